#!/usr/bin/env python3
"""The first step of a 2D dam break against the exact start of the flow.

At t = 0+ the pressure in a water column of width L and height H against a wall at x = 0 (floor y = 0, free
top y = H and free front x = L) solves Laplace's equation with dp/dx = 0 at the wall, dp/dy = -rho g at the
floor and p = 0 on the free faces; as a series in k_n = (2n + 1) pi / (2H):

    p = rho g (H - y) - rho g sum_n 2 cosh(k_n x) cos(k_n y) / (H k_n^2 cosh(k_n L)),
    a_x = g sum_n 2 sinh(k_n x) cos(k_n y) / (H k_n cosh(k_n L)),
    a_y = -g sum_n 2 cosh(k_n x) sin(k_n y) / (H k_n cosh(k_n L))

(the flow starts from rest, so a = -grad p / rho + g). The acceleration is singular at the toe (x = L,
y = 0) like log(1 / y): a fluid particle half a spacing from the floor and from the front accelerates the
faster the finer the lattice. This script reads the frame a run wrote after its first step (frame 1: run
with output.interval equal to that step's dt, the case's dt_max) and compares the fluid particles' pressure with p and their velocity / t
with a.

    mpsfsi run cases/dam_break.yaml --dp 0.0016 --end-time 0.001 --set output.interval=0.001 --output out/start_16
    scripts/dam_break_start.py out/start_16 [more runs] [--max-error 2 --max-pressure-rms 0.01]

Prints per run: the pressure error (RMS and 99th percentile over the fluid particles, in rho g H), the
acceleration error (median and 90th percentile, in g), and the acceleration of the toe particle (half a
spacing from the floor and the front) and of the fastest particle against the exact ones at their positions.
The column is the one the lattice filled: its faces half a spacing beyond the outermost particles.
"""
import argparse
import os
import sys

import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from run_output import frame_files, frame_times, read_case, read_frame  # noqa: E402

PROG = "dam_break_start.py"
TOE_RADIUS = 5  # [dp] the particles nearer the toe than this are left out of the largest error


def exact_start(x, y, L, H, g, dp):
    """Pressure / rho (p / rho) and acceleration (a_x, a_y) at t = 0+ at the points (x, y), which lie at least
    dp / 2 inside the free faces: the terms fall as exp(-k_n (L - x)), taken down to 1e-12."""
    out = [np.empty(len(x)) for _ in range(3)]
    order = np.argsort(x)[::-1]  # from the front inwards: the farther from x = L, the fewer terms
    for b in range(0, len(x), 512):  # in blocks of points: the series is a points x terms array
        idx = order[b:b + 512]
        gap = max(L - x[idx].max(), dp / 2)
        n_terms = int(np.ceil(28 / (np.pi / (2 * H) * gap)))
        for o, v in zip(out, exact_block(x[idx], y[idx], L, H, g, n_terms)):
            o[idx] = v
    return out


def exact_block(x, y, L, H, g, n_terms):
    n = np.arange(n_terms)
    k = (2 * n + 1) * np.pi / (2 * H)
    # cosh(k x) / cosh(k L) and sinh(k x) / cosh(k L) without overflow: e^{k (x - L)} (1 +- e^{-2 k x}) / (1 + e^{-2 k L})
    xs = x[:, None]
    ys = y[:, None]
    den = 1 + np.exp(-2 * k * L)
    ch = np.exp(k * (xs - L)) * (1 + np.exp(-2 * k * xs)) / den
    sh = np.exp(k * (xs - L)) * (1 - np.exp(-2 * k * xs)) / den
    c = 2 / (H * k)
    p = g * (H - y) - g * np.sum(c / k * ch * np.cos(k * ys), axis=1)
    ax = g * np.sum(c * sh * np.cos(k * ys), axis=1)
    ay = -g * np.sum(c * ch * np.sin(k * ys), axis=1)
    return p, ax, ay


def column(case):
    """The fluid column's rectangle (x0, y0, x1, y1) of the case (its wall at x0, its floor at y0)."""
    fluids = [b for b in case.get("bodies", []) if b.get("kind") == "fluid" and "rectangle" in b]
    if len(fluids) != 1:
        sys.exit(f"{PROG}: expected one fluid rectangle in the case, found {len(fluids)}")
    r = fluids[0]["rectangle"]
    return r["min"][0], r["min"][1], r["max"][0], r["max"][1]


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("runs", nargs="+", help="output folders of runs that stopped after their first step")
    ap.add_argument("--max-error", type=float, default=None,
                    help=f"fail (exit 1) if a particle farther than {TOE_RADIUS} dp from the toe has an acceleration "
                         "error above this [g]")
    ap.add_argument("--max-pressure-rms", type=float, default=None,
                    help="fail (exit 1) if the RMS pressure error is above this [rho g H]")
    args = ap.parse_args()
    failures = []
    print("| run | dp | t | pressure error RMS / 99th pct (rho g H) | acceleration error median / 90th pct (g) "
          f"| largest acceleration error farther than {TOE_RADIUS} dp from the toe, at ((x - L) / dp, y / dp) "
          "| toe particle: a (exact) | fastest particle: a (exact) at ((x - L) / dp, y / dp) |")
    print("|---|---|---|---|---|---|---|---|")
    for run in args.runs:
        case = read_case(run, PROG)
        files = frame_files(run, PROG)
        if len(files) < 2:
            sys.exit(f"{PROG}: '{run}' has no frame after the start; run with output.interval equal to the first step")
        t = frame_times(run, files)[1]
        x, f = read_frame(files[1])
        fluid = f["kind"] == 0
        x0, y0, _, _ = column(case)
        body = next(b for b in case["bodies"] if b.get("kind") == "fluid")
        rho = float(case["materials"][body["material"]]["rho"])
        g = abs(float(case.get("gravity", [0, -9.81])[1]))
        dp = float(case["dp"])
        # The column the lattice filled (its faces half a spacing beyond the outermost particles of frame 0).
        x_start, f_start = read_frame(files[0])
        start = x_start[f_start["kind"] == 0]
        L = start[:, 0].max() + dp / 2 - x0
        H = start[:, 1].max() + dp / 2 - y0
        px, py = x[fluid, 0] - x0, x[fluid, 1] - y0
        p_exact, ax, ay = exact_start(px, py, L, H, g, dp)
        p = f["pressure"][fluid] / rho
        v = f["velocity"][fluid][:, :2]
        a = v / t
        p_err = np.abs(p - p_exact) / (g * H)
        a_err = np.hypot(a[:, 0] - ax, a[:, 1] - ay) / g
        far = np.hypot(px - L, py) > TOE_RADIUS * dp  # away from the singular toe
        worst = np.flatnonzero(far)[int(np.argmax(a_err[far]))]
        fast = int(np.argmax(np.hypot(a[:, 0], a[:, 1])))
        toe = int(np.argmin(np.hypot(px - (L - dp / 2), py - dp / 2)))
        print(f"| {os.path.basename(os.path.normpath(run))} | {dp * 1e3:g} mm ({L:.4g} x {H:.4g} m) | {t:.3g} s "
              f"| {np.sqrt(np.mean(p_err ** 2)):.4f} / {np.percentile(p_err, 99):.4f} "
              f"| {np.median(a_err):.3f} / {np.percentile(a_err, 90):.3f} "
              f"| {a_err[worst]:.2f} g at ({(px[worst] - L) / dp:.1f}, {py[worst] / dp:.1f}) "
              f"| {np.hypot(*a[toe]) / g:.2f} g ({np.hypot(ax[toe], ay[toe]) / g:.2f} g) "
              f"| {np.hypot(*a[fast]) / g:.2f} g ({np.hypot(ax[fast], ay[fast]) / g:.2f} g) at "
              f"({(px[fast] - L) / dp:.1f}, {py[fast] / dp:.1f}) |")
        if args.max_error is not None and a_err[worst] > args.max_error:
            failures.append(f"{run}: acceleration error {a_err[worst]:.2f} g at ({px[worst]:.5f}, {py[worst]:.5f}) m "
                            f"> {args.max_error} g")
        p_rms = np.sqrt(np.mean(p_err ** 2))
        if args.max_pressure_rms is not None and p_rms > args.max_pressure_rms:
            failures.append(f"{run}: RMS pressure error {p_rms:.4f} rho g H > {args.max_pressure_rms}")
    for f in failures:
        print(f"{PROG}: {f}", file=sys.stderr)
    sys.exit(1 if failures else 0)


if __name__ == "__main__":
    main()
