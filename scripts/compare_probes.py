#!/usr/bin/env python3
"""Compare one column of two runs' probes.csv files, e.g. a 3D run against the 2D run it extends.

Usage: compare_probes.py A/probes.csv B/probes.csv --column NAME [--until VALUE] [--peak] [--max-error PCT]

Without --peak: B's column is interpolated to A's times, and the largest |b - a| / |a| over A's rows is printed
(only rows up to the first time A's value reaches --until, e.g. a surge front before it meets the far wall).
With --peak: the largest value of each run and its time, and their relative difference.
--max-error: exit 1 when the difference exceeds PCT percent. Missing files or columns exit 2.
"""
import argparse
import sys

import numpy as np


def read(path, column):
    try:
        with open(path) as f:
            lines = [line for line in f if not line.startswith("#")]  # a reference file may open with comments
        data = np.genfromtxt(lines, delimiter=",", names=True)
    except OSError as e:
        print(f"compare_probes.py: cannot read {path}: {e.strerror}", file=sys.stderr)
        sys.exit(2)
    if data.dtype.names is None or column not in data.dtype.names or "time" not in data.dtype.names:
        print(f"compare_probes.py: {path} has no column '{column}' (columns: {', '.join(data.dtype.names or [])})",
              file=sys.stderr)
        sys.exit(2)
    return np.atleast_1d(data["time"]), np.atleast_1d(data[column])


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("a")
    ap.add_argument("b")
    ap.add_argument("--column", required=True)
    ap.add_argument("--until", type=float, help="compare A's rows up to the first where A's value reaches this")
    ap.add_argument("--peak", action="store_true", help="compare the largest values instead")
    ap.add_argument("--max-error", type=float, help="exit 1 above this difference [%%]")
    args = ap.parse_args()
    ta, a = read(args.a, args.column)
    tb, b = read(args.b, args.column)
    if args.peak:
        ka, kb = int(np.argmax(a)), int(np.argmax(b))
        err = 100 * (b[kb] / a[ka] - 1)
        print(f"{args.column}: peak {a[ka]:.6g} at t = {ta[ka]:.4f} s (A), {b[kb]:.6g} at t = {tb[kb]:.4f} s (B): "
              f"B - A = {err:+.2f} %")
        err = abs(err)
    else:
        keep = np.ones_like(ta, dtype=bool)
        if args.until is not None:
            reached = np.nonzero(a >= args.until)[0]
            if reached.size:
                keep[reached[0] + 1:] = False
        keep &= (ta >= tb[0]) & (ta <= tb[-1]) & (a != 0)
        if not keep.any():
            print("compare_probes.py: no common rows to compare", file=sys.stderr)
            sys.exit(2)
        rel = np.abs(np.interp(ta[keep], tb, b) - a[keep]) / np.abs(a[keep])
        k = int(np.argmax(rel))
        print(f"{args.column}: {keep.sum()} rows up to t = {ta[keep][-1]:.4f} s; largest |B - A| / |A| = "
              f"{100 * rel[k]:.2f} % at t = {ta[keep][k]:.4f} s (A {a[keep][k]:.6g}, B {np.interp(ta[keep][k], tb, b):.6g}); "
              f"mean {100 * rel.mean():.2f} %")
        err = 100 * rel[k]
    if args.max_error is not None and err > args.max_error:
        print(f"FAIL: {err:.2f} % exceeds {args.max_error} %")
        return 1
    return 0


if __name__ == "__main__":
    sys.exit(main())
