#!/usr/bin/env python3
"""The linear standing wave in a closed tank (cases/standing_wave.yaml): its initial water polygon, and its period
and decay against linear theory.

Water of depth h in a tank of length B starts at rest with its surface at eta = a cos(k x), k = pi / B (the first
sloshing mode). Linear theory (Dean & Dalrymple 1991, §4; docs/references.md): the surface oscillates as
eta = a cos(k x) cos(omega t) with omega^2 = g k tanh(kh); an inviscid fluid keeps its amplitude.

Usage
  cases/standing_wave/analyse.py polygon cases/standing_wave/water.txt --length 0.6 --depth 0.2 --amplitude 0.01
  mpsfsi run cases/standing_wave.yaml --output out/standing_wave
  cases/standing_wave/analyse.py analyse out/standing_wave [more runs] [--until 3] [--check 0.02] [--converging]

polygon writes the water's outline (x y lines: the floor, then the surface from x = B back to 0 at --points
points). analyse fits (left - right) / 2 of the two wave gauges (the first and last wave_gauge probes, near the
end walls) with a exp(-delta t) cos(omega t + phi) over t <= --until and prints the period against theory, and the
decay rate delta with the amplitude lost per period, 1 - exp(-delta T). B is the tank's (box wall's) inner length from
the case, h is --depth (default 0.2 m). With --check TOL it exits 1 unless the period of the last run is within
TOL of the theory (relative); with --converging, unless each run's period error is smaller in magnitude than the
run's before it (give the runs from the coarsest to the finest).
"""
import argparse
import math
import os
import sys

import numpy as np
from scipy.optimize import curve_fit

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "..", "scripts"))
from run_output import read_case, read_probes  # noqa: E402

PROG = "standing_wave/analyse.py"


def polygon(a):
    xs = np.linspace(a.length, 0, a.points)
    rows = [(0.0, 0.0), (a.length, 0.0)] + [(x, a.depth + a.amplitude * math.cos(math.pi * x / a.length)) for x in xs]
    with open(a.file, "w") as f:
        f.write(f"# water of depth {a.depth:g} m under eta = {a.amplitude:g} cos(pi x / {a.length:g}), written by "
                f"cases/standing_wave/analyse.py\n")
        for x, y in rows:
            f.write(f"{x:.6f} {y:.6f}\n")
    print(f"wrote {a.file}: {len(rows)} points")


def analyse_run(run, a):
    case = read_case(run, PROG)
    g = -float(case["gravity"][-1])
    tanks = [w for w in case.get("walls", []) if w.get("type") == "box"]
    if not tanks:
        sys.exit(f"{PROG}: {run}: no box wall (the tank) in case.resolved.yaml")
    lo, hi = tanks[0]["rectangle"]["min"], tanks[0]["rectangle"]["max"]
    length = float(hi[0]) - float(lo[0])
    depth = a.depth
    gauges = [p["name"] for p in case.get("probes", []) if p.get("type") == "wave_gauge"]
    if len(gauges) < 2:
        sys.exit(f"{PROG}: {run}: fewer than 2 wave_gauge probes")
    probes = read_probes(run, PROG)
    t = np.array(probes["time"])
    e = (np.array(probes[gauges[0]]) - np.array(probes[gauges[-1]])) / 2
    k = math.pi / length
    omega = math.sqrt(g * k * math.tanh(k * depth))
    sel = t <= a.until
    if sel.sum() < 20:
        sys.exit(f"{PROG}: {run}: fewer than 20 probe rows up to t = {a.until:g} s")

    def model(tt, amp, w, d, ph):
        return amp * np.exp(-d * tt) * np.cos(w * tt + ph)

    p, _ = curve_fit(model, t[sel], e[sel], p0=[e[0] if e[0] != 0 else 0.01, omega, 0.1, 0.0])
    period, period_th = 2 * math.pi / p[1], 2 * math.pi / omega
    rms = float(np.sqrt(np.mean((model(t[sel], *p) - e[sel]) ** 2)))
    return dict(run=run, dp=float(case["dp"]), length=length, depth=depth, kh=k * depth, T=period, T_th=period_th,
                decay=p[2], amp=p[0], rms=rms)


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    sub = ap.add_subparsers(dest="command", required=True)
    pp = sub.add_parser("polygon", help="write the water's initial outline")
    pp.add_argument("file")
    pp.add_argument("--length", type=float, required=True, help="the tank's inner length B [m]")
    pp.add_argument("--depth", type=float, required=True, help="the still water depth h [m]")
    pp.add_argument("--amplitude", type=float, required=True, help="the initial amplitude a [m]")
    pp.add_argument("--points", type=int, default=121, help="points along the surface")
    pa = sub.add_parser("analyse", help="the period and decay of runs against linear theory")
    pa.add_argument("runs", nargs="+")
    pa.add_argument("--depth", type=float, default=0.2, help="the still water depth h [m] (default 0.2)")
    pa.add_argument("--until", type=float, default=3.0, help="fit over t <= this [s]")
    pa.add_argument("--check", type=float, metavar="TOL", help="exit 1 unless the last run's period is within TOL (relative)")
    pa.add_argument("--converging", action="store_true",
                    help="exit 1 unless each run's period error is smaller than the one before (coarsest run first)")
    a = ap.parse_args()
    if a.command == "polygon":
        polygon(a)
        return
    failed = False
    errors = []
    for run in a.runs:
        r = analyse_run(run, a)
        err = r["T"] / r["T_th"] - 1
        loss = 1 - math.exp(-r["decay"] * r["T"])
        print(f"{run}: dp {r['dp']:g} m (h/dp {r['depth'] / r['dp']:.0f}), B {r['length']:g} m, h {r['depth']:g} m, "
              f"kh {r['kh']:.4f}: period {r['T']:.4f} s against {r['T_th']:.4f} s ({err * 100:+.2f} %); decay "
              f"{r['decay']:.4f} 1/s ({loss * 100:.1f} % of the amplitude per period); fit rms {r['rms'] * 1000:.2f} mm")
        if a.converging and errors and not abs(err) < abs(errors[-1]):
            print(f"  FAIL: a period error smaller than the coarser run's ({errors[-1] * 100:+.2f} %) expected")
            failed = True
        errors.append(err)
    if a.check is not None and abs(errors[-1]) > a.check:
        print(f"  FAIL: the last run's period within {a.check * 100:g} % expected")
        failed = True
    sys.exit(1 if failed else 0)


if __name__ == "__main__":
    main()
