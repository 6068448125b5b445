#!/usr/bin/env python3
"""The time step of a run against a reference run's, step by step: from the probe tables of two runs written
every step (`--set output.probe_interval=1e-6`), dt(t) of each, and the smallest ratio dt / dt_ref over
t <= --until, dt_ref taken at the same time (the reference step that contains t).

Usage
  mpsfsi run cases/dam_break.yaml --dp 0.001 --end-time 0.3 --set output.probe_interval=1e-6 --output out/a
  mpsfsi run cases/dam_break.yaml --dp 0.001 --end-time 0.3 --set output.probe_interval=1e-6 \\
      --set fluid.scheme=standard --output out/b
  scripts/dt_ratio.py out/a out/b --until 0.3

Prints the steps of each run up to --until and the smallest ratio with its time; with --min R it exits 1 when
the smallest ratio is below R.
"""
import argparse
import bisect
import csv
import os
import sys


def step_times(run):
    path = os.path.join(run, "probes.csv")
    with open(path, newline="") as f:
        times = [float(row["time"]) for row in csv.DictReader(f)]
    if len(times) < 2:
        sys.exit(f"dt_ratio.py: {path} holds fewer than two rows")
    return times


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("run", help="the run's output folder (probes.csv written every step)")
    ap.add_argument("reference", help="the reference run's output folder (the same)")
    ap.add_argument("--until", type=float, default=float("inf"), help="compare the steps that end at t <= this [s]")
    ap.add_argument("--min", type=float, help="exit 1 when the smallest ratio is below this")
    a = ap.parse_args()
    t, t_ref = step_times(a.run), step_times(a.reference)
    worst, worst_t, n, n_ref = float("inf"), 0.0, 0, sum(1 for x in t_ref[1:] if x <= a.until)
    for k in range(1, len(t) - 1):  # (the last step, cut at the end time, is left out)
        if t[k] > a.until or t[k] > t_ref[-1]:
            break
        n += 1
        dt = t[k] - t[k - 1]
        # the reference step that contains the middle of this one
        m = min(max(bisect.bisect_left(t_ref, 0.5 * (t[k] + t[k - 1])), 1), len(t_ref) - 1)
        ratio = dt / (t_ref[m] - t_ref[m - 1])
        if ratio < worst:
            worst, worst_t = ratio, t[k]
    print(f"steps to {min(a.until, t[-1]):g} s: {n} (reference {n_ref}); smallest dt / dt_ref {worst:.3f} at t = {worst_t:.5g} s")
    if a.min is not None and worst < a.min:
        sys.exit(1)


if __name__ == "__main__":
    main()
