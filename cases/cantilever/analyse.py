#!/usr/bin/env python3
"""Tip deflection of the cantilever case (cases/cantilever.yaml): peak deflection and first-mode
frequency from probes.csv (column tip_dy), compared with the analytic values of seed 004 eq. 53-54
(peak 47.09 cm = twice the static deflection, f = 1.27 Hz).
Usage: analyse.py probes.csv [--max-peak-error PCT] [--max-frequency-error PCT]
Exit code 1 when a given tolerance is exceeded."""
import argparse
import csv
import math
import sys

RHO, E, L, B, G = 1000.0, 1.0e8, 2.0, 0.1, 9.81
A, I = B * B, B ** 4 / 12
PEAK = 2 * RHO * G * A * L ** 4 / (8 * E * I)            # eq. 53, dynamic (released from rest)
FREQ = 1.875 ** 2 / (2 * math.pi) * math.sqrt(E * I / (RHO * A * L ** 4))   # eq. 54


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("probes")
    ap.add_argument("--max-peak-error", type=float)
    ap.add_argument("--max-frequency-error", type=float)
    args = ap.parse_args()
    t, y = [], []
    with open(args.probes) as f:
        for row in csv.DictReader(f):
            t.append(float(row["time"]))
            y.append(-float(row["tip_dy"]))   # downward deflection, positive
    # First peak: first local maximum, refined by a parabola through three samples.
    k = next(i for i in range(1, len(y) - 1) if y[i] >= y[i - 1] and y[i] > y[i + 1] and y[i] > 0.5 * max(y))
    den = y[k - 1] - 2 * y[k] + y[k + 1]
    s = 0.5 * (y[k - 1] - y[k + 1]) / den if den != 0 else 0.0
    peak = y[k] - 0.25 * (y[k - 1] - y[k + 1]) * s
    # Period: crossings of the mid line peak/2 (linear interpolation), least-squares slope vs index.
    mid = 0.5 * peak
    xs = [t[i] + (mid - y[i]) / (y[i + 1] - y[i]) * (t[i + 1] - t[i])
          for i in range(len(y) - 1) if (y[i] - mid) * (y[i + 1] - mid) < 0]
    n = len(xs)
    if n < 3:
        print("not enough crossings for a frequency; run longer", file=sys.stderr)
        return 1
    mi, mx = (n - 1) / 2, sum(xs) / n
    half_period = sum((i - mi) * (x - mx) for i, x in enumerate(xs)) / sum((i - mi) ** 2 for i in range(n))
    freq = 1 / (2 * half_period)
    e_peak = 100 * (peak / PEAK - 1)
    e_freq = 100 * (freq / FREQ - 1)
    print(f"peak tip deflection {100 * peak:.2f} cm (analytic {100 * PEAK:.2f} cm, {e_peak:+.2f} %) at t = {t[k]:.3f} s")
    print(f"first-mode frequency {freq:.4f} Hz (analytic {FREQ:.4f} Hz, {e_freq:+.2f} %) from {n} crossings")
    ok = True
    if args.max_peak_error is not None and abs(e_peak) > args.max_peak_error:
        print(f"FAIL: peak error {e_peak:.2f} % exceeds {args.max_peak_error} %")
        ok = False
    if args.max_frequency_error is not None and abs(e_freq) > args.max_frequency_error:
        print(f"FAIL: frequency error {e_freq:.2f} % exceeds {args.max_frequency_error} %")
        ok = False
    return 0 if ok else 1


if __name__ == "__main__":
    sys.exit(main())
