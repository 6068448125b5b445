#!/usr/bin/env python3
"""Regular waves from a wave maker against linear theory: from the wave gauges (probes of type wave_gauge) of one or
more runs of a flume (cases/wave_flume.yaml), the wave height, the wavelength and the reflection from the far end.

Theory (Dean & Dalrymple 1991, §6.2; docs/references.md), for still water depth h, paddle stroke S and period T:
  dispersion          omega^2 = g k tanh(kh)                            -> k, the wavelength L = 2 pi / k
  piston              H / S = 2 (cosh 2kh - 1) / (sinh 2kh + 2kh)
  flap (hinge at the floor)
                      H / S = 4 (sinh kh / kh) (kh sinh kh - cosh kh + 1) / (sinh 2kh + 2kh)
  group velocity      c_g = (omega / 2k) (1 + 2kh / sinh 2kh)

What is measured, per run:
  - at each gauge x, in the window after the full-height waves have arrived (t > start + ramp + x / c_g + T) and
    before anything reflected at the far end can (t < start + (2 x_end - x) / c_g, x_end the still water line):
    the first harmonic of the elevation, fitted by least squares with its mean and second harmonic; its height H
    (twice its amplitude) against the theory, and its phase;
  - the wavenumber: the slope of the phases along the gauges (least squares), against the dispersion relation;
  - the damping: the fit ln H = ln H_0 - delta x along the gauges, printed as the height lost per wavelength and
    H_0, the height extrapolated to the paddle (x = 0);
  - the reflection: in the last --reflection-window seconds of the run, each gauge's complex first harmonic fitted
    as an incident and a reflected wave that both decay as they travel, a_I exp(-i k_c u) + a_R exp(i k_c u),
    k_c = k - i delta, u = x - x_m (x_m the middle of the gauges), by least squares over the gauges;
    K_r = |a_R| / |a_I| at x_m.

Usage
  mpsfsi run cases/wave_flume.yaml --output out/wave_flume
  cases/wave_flume/analyse.py out/wave_flume [more runs] [--plot wave_flume.png] [--check 0.05 0.03]

h is the top of the fluid bodies (or --depth), x_end their largest x (or --end); S, T, start and ramp come from
the run's moving wall with a wave_maker (case.resolved.yaml). With --check H_TOL K_TOL it exits 1 unless every
gauge's H is within H_TOL of the theory (relative) and k within K_TOL.
"""
import argparse
import math
import os
import sys

import numpy as np
from scipy.optimize import brentq

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "..", "scripts"))
from run_output import read_case, read_probes  # noqa: E402

PROG = "wave_flume/analyse.py"


def wavenumber(omega, h, g):
    return brentq(lambda k: omega * omega - g * k * math.tanh(k * h), 1e-9, 10 * omega * omega / g + 100 / h)


def transfer(kind, kh):
    if kind == "piston":
        return 2 * (math.cosh(2 * kh) - 1) / (math.sinh(2 * kh) + 2 * kh)
    return 4 * (math.sinh(kh) / kh) * (kh * math.sinh(kh) - math.cosh(kh) + 1) / (math.sinh(2 * kh) + 2 * kh)


def harmonics(t, eta, omega):
    """Least-squares fit of eta(t) = c + sum_{n=1,2} (a_n cos n omega t + b_n sin n omega t): the complex first
    harmonic A = a_1 - i b_1 (eta_1 = Re(A exp(i omega t))) and the rms of the residual."""
    cols = [np.ones_like(t)]
    for n in (1, 2):
        cols += [np.cos(n * omega * t), np.sin(n * omega * t)]
    m = np.column_stack(cols)
    c, *_ = np.linalg.lstsq(m, eta, rcond=None)
    return complex(c[1], -c[2]), float(np.sqrt(np.mean((m @ c - eta) ** 2)))


def read_run(run, args):
    case = read_case(run, PROG)
    g = -float(case["gravity"][-1])
    maker = None
    for w in case.get("walls", []):
        wm = (w.get("motion") or {}).get("wave_maker")
        if wm:
            maker = dict(wm, start=float(w["motion"].get("start", 0)), ramp=float(w["motion"].get("ramp", 0)))
    if maker is None:
        sys.exit(f"{PROG}: {run}: no wall with motion.wave_maker in case.resolved.yaml")
    tops, ends = [], []
    for b in case.get("bodies", []):
        if b.get("kind") == "fluid" and "rectangle" in b:
            tops.append(float(b["rectangle"]["max"][-1]))
            ends.append(float(b["rectangle"]["max"][0]))
    h = args.depth if args.depth is not None else (max(tops) if tops else None)
    x_end = args.end if args.end is not None else (max(ends) if ends else None)
    if h is None or x_end is None:
        sys.exit(f"{PROG}: {run}: no fluid rectangle to take the depth and the end from; give --depth and --end")
    gauges = {p["name"]: float(p["position"][0]) for p in case.get("probes", []) if p.get("type") == "wave_gauge"}
    if len(gauges) < 3:
        sys.exit(f"{PROG}: {run}: fewer than 3 wave_gauge probes")
    probes = read_probes(run, PROG)
    t = np.array(probes["time"])
    series = {n: np.array(probes[n]) - h for n in gauges}
    return dict(run=run, dp=float(case["dp"]), g=g, h=h, x_end=x_end, maker=maker, gauges=gauges, t=t, eta=series)


def analyse(r, args):
    m = r["maker"]
    kind, S, T = m["type"], float(m["stroke"]), float(m["period"])
    omega = 2 * math.pi / T
    k = wavenumber(omega, r["h"], r["g"])
    kh = k * r["h"]
    H_th = S * transfer(kind, kh)
    cg = omega / k / 2 * (1 + 2 * kh / math.sinh(2 * kh))
    t = r["t"]
    rows = []
    for name, x in sorted(r["gauges"].items(), key=lambda p: p[1]):
        t0 = m["start"] + m["ramp"] + x / cg + T
        t1 = min(m["start"] + (2 * r["x_end"] - x) / cg, t[-1])
        sel = (t >= t0) & (t <= t1)
        if t1 - t0 < 2 * T or sel.sum() < 20:
            continue
        A, res = harmonics(t[sel], r["eta"][name][sel], omega)
        rows.append(dict(name=name, x=x, t0=t0, t1=t1, H=2 * abs(A), phase=-math.atan2(A.imag, A.real), res=res))
    if len(rows) < 3:
        sys.exit(f"{PROG}: {r['run']}: fewer than 3 gauges have 2 periods of incident waves before the reflection "
                 f"(run longer, or move the gauges nearer the paddle)")
    # The still water before anything from the paddle can arrive (the long-wave speed sqrt(g h)): its mean level.
    still = []
    for name, x in r["gauges"].items():
        sel = (t > 0) & (t < m["start"] + x / math.sqrt(r["g"] * r["h"]))
        if sel.sum() >= 5:
            still.append(float(np.mean(r["eta"][name][sel])))
    xs = np.array([q["x"] for q in rows])
    ph = np.unwrap(np.array([q["phase"] for q in rows]))
    k_meas = float(np.polyfit(xs, ph, 1)[0])
    slope, intercept = np.polyfit(xs, np.log([q["H"] for q in rows]), 1)  # H ~ H_0 exp(-damping x)
    damping, H_paddle = -float(slope), math.exp(intercept)
    # The reflection over all gauges in the last window of the run.
    sel = t >= t[-1] - args.reflection_window
    xr = np.array(sorted(r["gauges"].values()))
    names = sorted(r["gauges"], key=lambda n: r["gauges"][n])
    refl = None
    ready = m["start"] + m["ramp"] + (2 * r["x_end"] - xr.min()) / cg
    if t[-1] - args.reflection_window >= ready and sel.sum() >= 20:
        amps = np.array([harmonics(t[sel], r["eta"][n][sel], omega)[0] for n in names])
        # Both waves decay as they travel (the damping measured in the incident window): k - i damping.
        kc = k_meas - 1j * damping
        xm = 0.5 * (xr.min() + xr.max())
        mat = np.column_stack([np.exp(-1j * kc * (xr - xm)), np.exp(1j * kc * (xr - xm))])
        (aI, aR), *_ = np.linalg.lstsq(mat, amps, rcond=None)
        refl = dict(Kr=abs(aR) / abs(aI), HI=2 * abs(aI), HR=2 * abs(aR), x=xr, xm=xm, kc=kc, H=2 * np.abs(amps),
                    aI=aI, aR=aR, window=(t[-1] - args.reflection_window, t[-1]))
    return dict(kind=kind, S=S, T=T, k=k, kh=kh, H_th=H_th, cg=cg, k_meas=k_meas, damping=damping, H_paddle=H_paddle,
                rows=rows, refl=refl, still=still)


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("runs", nargs="+", help="output folders of flume runs")
    ap.add_argument("--depth", type=float, help="still water depth h [m] (default: the top of the fluid rectangles)")
    ap.add_argument("--end", type=float, help="x of the still water line at the far end [m] (default: their largest x)")
    ap.add_argument("--reflection-window", type=float, default=3.5, help="the last seconds of the run for K_r")
    ap.add_argument("--plot", help="write a figure here (png)")
    ap.add_argument("--check", nargs=2, type=float, metavar=("H_TOL", "K_TOL"),
                    help="exit 1 unless every gauge's H and the wavenumber are within these relative tolerances")
    a = ap.parse_args()
    results = []
    failed = False
    for run in a.runs:
        r = read_run(run, a)
        q = analyse(r, a)
        results.append((r, q))
        print(f"{run}: dp {r['dp']:g} m (h/dp {r['h'] / r['dp']:.0f}), {q['kind']} S {q['S']:g} m, T {q['T']:g} s, "
              f"h {r['h']:g} m: kh {q['kh']:.4f}, L {2 * math.pi / q['k']:.4f} m, H theory {q['H_th'] * 1000:.2f} mm "
              f"(H/S {q['H_th'] / q['S']:.4f}), c_g {q['cg']:.4f} m/s")
        if q["still"]:
            print(f"  the still water before the paddle's first long wave arrives: mean level {min(q['still']) * 1000:+.2f} "
                  f"to {max(q['still']) * 1000:+.2f} mm at the gauges")
        print("  gauge     x [m]   window [s]     H [mm]   H/H_th   rms residual [mm]")
        worst = 0.0
        for row in q["rows"]:
            e = row["H"] / q["H_th"] - 1
            worst = max(worst, abs(e))
            print(f"  {row['name']:8s} {row['x']:6.3f}  {row['t0']:5.2f}-{row['t1']:5.2f}  {row['H'] * 1000:8.3f}  "
                  f"{row['H'] / q['H_th']:7.4f}  {row['res'] * 1000:8.3f}")
        ek = q["k_meas"] / q["k"] - 1
        print(f"  wavenumber: {q['k_meas']:.4f} 1/m against {q['k']:.4f} ({ek * 100:+.2f} %); wavelength "
              f"{2 * math.pi / q['k_meas']:.4f} m against {2 * math.pi / q['k']:.4f} m")
        Hm = np.array([row["H"] for row in q["rows"]])
        print(f"  H/H_th over the gauges: mean {Hm.mean() / q['H_th']:.4f}, from {Hm.min() / q['H_th']:.4f} to "
              f"{Hm.max() / q['H_th']:.4f} (largest deviation {worst * 100:.1f} %); height lost per wavelength "
              f"{(1 - math.exp(-q['damping'] * 2 * math.pi / q['k_meas'])) * 100:.1f} %, H/H_th extrapolated along it to x = 0: "
              f"{q['H_paddle'] / q['H_th']:.3f}")
        if q["refl"]:
            f = q["refl"]
            print(f"  reflection over t = {f['window'][0]:.2f}-{f['window'][1]:.2f} s: K_r = {f['Kr']:.3f} "
                  f"(H_I {f['HI'] * 1000:.2f} mm, H_R {f['HR'] * 1000:.2f} mm at x = {f['xm']:.2f} m)")
        else:
            print(f"  reflection: the run ends before the reflected waves are at every gauge for "
                  f"{a.reflection_window:g} s")
        if a.check and (worst > a.check[0] or abs(ek) > a.check[1]):
            print(f"  FAIL: H within {a.check[0] * 100:g} % and k within {a.check[1] * 100:g} % expected")
            failed = True
    if a.plot:
        plot(results, a.plot)
    sys.exit(1 if failed else 0)


def plot(results, path):
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    fig, ax = plt.subplots(2, 2, figsize=(12, 8))
    r0, q0 = results[0]
    for r, q in results:
        lab = f"dp {r['dp'] * 1000:g} mm (h/dp {r['h'] / r['dp']:.0f})"
        xs = [row["x"] for row in q["rows"]]
        ax[0, 1].plot(xs, [row["H"] / q["S"] for row in q["rows"]], "o-", label=lab)
        ph = np.unwrap([row["phase"] for row in q["rows"]])
        ax[1, 0].plot(xs, ph - ph[0], "o", label=lab + f": k {q['k_meas']:.3f} 1/m")
        if q["refl"]:
            f = q["refl"]
            ax[1, 1].plot(f["x"], f["H"] / q["S"], "o", label=lab + f": K_r {f['Kr']:.3f}")
            xx = np.linspace(f["x"].min(), f["x"].max(), 200)
            u = xx - f["xm"]
            ax[1, 1].plot(xx, 2 * np.abs(f["aI"] * np.exp(-1j * f["kc"] * u) + f["aR"] * np.exp(1j * f["kc"] * u))
                          / q["S"], "-", lw=0.8)
    # the elevation at the nearest gauge to the first run's middle gauge
    mid = q0["rows"][len(q0["rows"]) // 2]
    for r, q in results:
        ax[0, 0].plot(r["t"], r["eta"][mid["name"]] * 1000, lw=0.8, label=f"dp {r['dp'] * 1000:g} mm")
    ax[0, 0].axhline(q0["H_th"] / 2 * 1000, color="k", ls="--", lw=0.8, label="linear theory, +-H/2")
    ax[0, 0].axhline(-q0["H_th"] / 2 * 1000, color="k", ls="--", lw=0.8)
    ax[0, 0].axvspan(mid["t0"], mid["t1"], color="0.9")
    ax[0, 0].set(xlabel="t [s]", ylabel="elevation [mm]", title=f"gauge {mid['name']} at x = {mid['x']:g} m "
                 "(shaded: the incident window)")
    ax[0, 1].axhline(q0["H_th"] / q0["S"], color="k", ls="--", label="linear theory")
    ax[0, 1].axhspan(0.95 * q0["H_th"] / q0["S"], 1.05 * q0["H_th"] / q0["S"], color="0.9", label="+-5 %")
    ax[0, 1].set(xlabel="x [m]", ylabel="H / S (first harmonic)", title="wave height in the incident window")
    xx = np.linspace(0, max(row["x"] for row in q0["rows"]), 2)
    ax[1, 0].plot(xx, q0["k"] * (xx - q0["rows"][0]["x"]), "k--", label=f"dispersion relation: k {q0['k']:.3f} 1/m")
    ax[1, 0].set(xlabel="x [m]", ylabel="phase [rad]", title="phase of the first harmonic along the flume")
    ax[1, 1].set(xlabel="x [m]", ylabel="H / S at the gauges", title="last window: incident + reflected fit")
    for a in ax.flat:
        a.legend(fontsize=7)
        a.grid(alpha=0.3)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    print(f"wrote {path}")


if __name__ == "__main__":
    main()
