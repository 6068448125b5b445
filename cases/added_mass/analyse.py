#!/usr/bin/env python3
"""Period of the block's axial oscillation in cases/added_mass.yaml against the analytic one.

The block (height h above its clamp, density rho_s, E, nu = 0) and the water column above it (height L,
density rho_f) form a rod clamped at one end with a tip mass: beta h tan(beta h) = rho_s h / (rho_f L),
omega = beta c_s, c_s = sqrt(E / rho_s). With the water's sound speed c the column is itself a rod with a free
end, and the frequency solves rho_s c_s cot(omega h / c_s) = rho_f c tan(omega L / c) (the same equation as
c -> infinity); both periods are printed, the error is against the incompressible one.
The measured period is the mean spacing of the successive upward and of the successive downward crossings of
the mean by the top's vertical displacement (probes.csv column top_dy) after --t0 (default: the end of the case's gravity ramp).
The case is read from each run's case.resolved.yaml (dp, densities, E, c, the block's and the column's
rectangles).
Usage: analyse.py RUN [RUN ...] [--t0 S] [--check PCT] [--plot PNG]
  --t0 S       start of the measured window [s] (default: the case's gravity_ramp)
  --check PCT  exit code 1 when a run's period differs from the analytic one by more than PCT %
  --plot PNG   the top's vertical displacement of every run against time, with the analytic period marked"""
import argparse
import csv
import math
import os
import sys

import yaml
from scipy.optimize import brentq


def analytic_periods(case):
    """(mass ratio, incompressible period, period with the water's sound speed, static shortening / h)."""
    mats = case["materials"]
    bodies = {b["name"]: b for b in case["bodies"]}
    block, column = bodies["block"], bodies["column"]
    solid, fluid = mats[block["material"]], mats[column["material"]]
    h = block["rectangle"]["max"][1] - block["clamp"]["max"][1]
    length = column["rectangle"]["max"][1] - column["rectangle"]["min"][1]
    rho_s, e, rho_f, c = (float(v) for v in (solid["rho"], solid["E"], fluid["rho"], fluid["c"]))
    cs = math.sqrt(e / rho_s)
    ratio = rho_s * h / (rho_f * length)
    x = brentq(lambda b: b * math.tan(b) - ratio, 1e-12, math.pi / 2 - 1e-12, xtol=1e-15)
    t_inc = 2 * math.pi * h / (x * cs)
    w_max = min(math.pi / 2 * cs / h, math.pi / 2 * c / length) * (1 - 1e-12)
    w = brentq(lambda w: rho_s * cs / math.tan(w * h / cs) - rho_f * c * math.tan(w * length / c), 1e-9, w_max, xtol=1e-13)
    g = abs(float(case.get("gravity", [0, 0])[-1]))
    shortening = g * (rho_f * length * h + rho_s * h * h / 2) / e / h
    return ratio, t_inc, 2 * math.pi / w, shortening


def crossings(t, y, level, band, sign):
    """Times at which sign * (y - level) passes 0 upwards, each after the signal was below -band (hysteresis:
    particle-scale wiggles near the level do not count), linearly interpolated."""
    out, armed = [], False
    for k in range(1, len(y)):
        a, b = sign * (y[k - 1] - level), sign * (y[k] - level)
        if b < -band:
            armed = True
        if armed and a < 0 <= b:
            out.append(t[k - 1] + (t[k] - t[k - 1]) * (-a) / (b - a))
            armed = False
    return out


def measured_period(probes, t0):
    """Mean spacing of the upward and of the downward crossings of the mean displacement after t0."""
    t, y = [], []
    with open(probes) as f:
        for row in csv.DictReader(f):
            if float(row["time"]) >= t0:
                t.append(float(row["time"]))
                y.append(float(row["top_dy"]))
    if len(y) < 3:
        return float("nan"), 0
    level = sum(y) / len(y)
    band = 0.3 * math.sqrt(sum((v - level) ** 2 for v in y) / len(y))
    spacings = []
    for sign in (1, -1):
        c = crossings(t, y, level, band, sign)
        spacings += [b - a for a, b in zip(c, c[1:])]
    if not spacings:
        return float("nan"), 0
    return sum(spacings) / len(spacings), len(spacings)


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("runs", nargs="+")
    ap.add_argument("--t0", type=float, default=None, help="start of the window [s] (default: the case's gravity_ramp)")
    ap.add_argument("--check", type=float, default=None)
    ap.add_argument("--plot", default=None)
    args = ap.parse_args()
    ok = True
    print("| run | dp | mass ratio | analytic period (with c) | measured period (periods) | error | static shortening |")
    print("|---|---|---|---|---|---|---|")
    for run in args.runs:
        with open(os.path.join(run, "case.resolved.yaml")) as f:
            case = yaml.safe_load(f)
        ratio, t_inc, t_c, short = analytic_periods(case)
        t0 = args.t0 if args.t0 is not None else float(case.get("gravity_ramp", 0))
        t_m, n = measured_period(os.path.join(run, "probes.csv"), t0)
        err = 100 * (t_m - t_inc) / t_inc
        if args.check is not None and not abs(err) <= args.check:
            ok = False
        print(f"| {run} | {1000 * float(case['dp']):g} mm | {ratio:g} | {t_inc:.5f} s ({t_c:.5f} s) | {t_m:.5f} s ({n}) | "
              f"{err:+.2f} % | {100 * short:.2f} % |")
    if args.plot:
        plot(args.runs, args.plot)
    return 0 if ok else 1


def plot(runs, png):
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    fig, ax = plt.subplots(len(runs), 1, figsize=(9, 1.9 * len(runs) + 0.6), sharex=True, squeeze=False)
    for a, run in zip(ax[:, 0], runs):
        with open(os.path.join(run, "case.resolved.yaml")) as f:
            case = yaml.safe_load(f)
        ratio, t_inc, _, _ = analytic_periods(case)
        with open(os.path.join(run, "probes.csv")) as f:
            rows = list(csv.DictReader(f))
        t = [float(r["time"]) for r in rows]
        y = [1e6 * float(r["top_dy"]) for r in rows]
        scheme = case.get("coupling", {}).get("scheme", "explicit")
        a.plot(t, y, lw=0.8)
        ramp = float(case.get("gravity_ramp", 0))
        k = 0
        while ramp + k * t_inc <= t[-1]:
            a.axvline(ramp + k * t_inc, color="0.7", lw=0.5, ls="--")
            k += 1
        a.set_ylabel("top [um]")
        a.set_title(f"mass ratio {ratio:g}, dp {1000 * float(case['dp']):g} mm, {scheme} "
                    "(dashed: analytic period from the end of the ramp)", fontsize=9)
    ax[-1, 0].set_xlabel("t [s]")
    fig.tight_layout()
    fig.savefig(png, dpi=90)


if __name__ == "__main__":
    sys.exit(main())
