#!/usr/bin/env python3
"""Surge front of the dam_break case (cases/dam_break.yaml) against the experiments: Z = front/L against
T = t sqrt(2g/L) from probes.csv (column front), compared over T in [1.5, 3.0] with
  - martin_moyce_1952_surge_front.csv (the issue's table, linearly extrapolated past its last point T = 2.70),
  - koshizuka_oka_1996_surge_front.csv (the same series with the points up to T = 3.096),
  - martin_moyce_1952_fig3_n2_2.csv (Martin & Moyce's own two series, a = 1.125 and 2.25 in).
For each it prints the smallest and largest relative error of Z, and the same with the simulation delayed by
--delays (in T units): a constant delay measures a start-up offset (the experiment's release), a wrong front
speed would not be removed by it.
With --at T [T ...] it prints instead one line: the relative error of Z against Martin & Moyce a = 2.25 in at
each T (a resolution sweep's column, scripts/sweep.py).
Usage: analyse.py probes.csv [--delays 0 0.1 0.2 0.3] [--max-error PCT] [--at 2 3]
Exit code 1 when --max-error is given and the error against the issue's table (no delay) exceeds it."""
import argparse
import csv
import math
import os
import sys

L, G = 0.146, 9.81
HERE = os.path.dirname(os.path.abspath(__file__))


def read(name, series=None):
    rows = [r for r in csv.DictReader(line for line in open(os.path.join(HERE, name)) if not line.startswith("#"))]
    if series is not None:
        rows = [r for r in rows if r["a_in"] == series]
    return [float(r["T"]) for r in rows], [float(r["Z"]) for r in rows]


def interp(x, xs, ys, extrapolate=False):
    if x <= xs[0]:
        return ys[0]
    for k in range(1, len(xs)):
        if x <= xs[k]:
            return ys[k - 1] + (ys[k] - ys[k - 1]) * (x - xs[k - 1]) / (xs[k] - xs[k - 1])
    if extrapolate:
        return ys[-1] + (ys[-1] - ys[-2]) * (x - xs[-1]) / (xs[-1] - xs[-2])
    return None


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("probes")
    ap.add_argument("--delays", type=float, nargs="+", default=[0.0, 0.1, 0.2, 0.3])
    ap.add_argument("--max-error", type=float)
    ap.add_argument("--at", type=float, nargs="+", help="T values: the error against Martin & Moyce a = 2.25 in")
    args = ap.parse_args()
    ts, zs = [], []
    with open(args.probes) as f:
        for row in csv.DictReader(f):
            ts.append(float(row["time"]) * math.sqrt(2 * G / L))
            zs.append(float(row["front"]) / L)
    if ts[-1] < 3.0:
        sys.exit(f"analyse.py: the run ends at T = {ts[-1]:.2f}; run to t >= {3.0 / math.sqrt(2 * G / L):.3f} s")
    if args.at:
        te, ze = read("martin_moyce_1952_fig3_n2_2.csv", "2.25")
        print(" ".join(f"T={T:g}: {100 * (interp(T, ts, zs) / interp(T, te, ze) - 1):+.1f} %" for T in args.at))
        return 0
    refs = [("issue table (K&O 1995/96, 5 points)", read("martin_moyce_1952_surge_front.csv"), True),
            ("Koshizuka & Oka 1996 (9 points)", read("koshizuka_oka_1996_surge_front.csv"), False),
            ("Martin & Moyce a = 1.125 in", read("martin_moyce_1952_fig3_n2_2.csv", "1.125"), False),
            ("Martin & Moyce a = 2.25 in", read("martin_moyce_1952_fig3_n2_2.csv", "2.25"), False)]
    grid = [1.5 + 0.025 * k for k in range(61)]
    worst_issue = None
    print(f"{'reference':38s} " + " ".join(f"{'delay ' + format(d, '.2f'):>17s}" for d in args.delays))
    for name, (te, ze), extrapolate in refs:
        cells = []
        for d in args.delays:
            errs = []
            for T in grid:
                z_exp = interp(T, te, ze, extrapolate)
                if z_exp is None or T - d < ts[0]:
                    continue
                errs.append(interp(T - d, ts, zs) / z_exp - 1)
            cells.append(f"{100 * min(errs):+6.1f}..{100 * max(errs):+5.1f} %")
            if extrapolate and d == 0:
                worst_issue = max(abs(e) for e in errs)
        print(f"{name:38s} " + " ".join(f"{c:>17s}" for c in cells))
    if args.max_error is not None and worst_issue is not None and 100 * worst_issue > args.max_error:
        print(f"FAIL: worst error against the issue table {100 * worst_issue:.1f} % > {args.max_error} %")
        return 1
    return 0


if __name__ == "__main__":
    sys.exit(main())
