#!/usr/bin/env python3
"""Plate-tip amplitude and period of a sloshing run (cases/sloshing_*.yaml) from its probes.csv, as seed 004
§5.4 evaluates them: the crest-to-valley amplitude averaged over a window of the steady part (crests and
valleys are the local extrema of the tip's horizontal displacement in the tank's frame, column tip_dx;
each extremum refined by a parabola through three samples), the period from the times of the crests and of
the valleys, and the relative error against the experiment's amplitude.

Usage: analyse.py probes.csv --window T0 T1 --experiment CM [--period S] [--max-error PCT]
       [--max-period-error PCT]
  high filling: --window 2.44 9.08 --experiment 14.65 --period 1.20 (seed 004 §5.4.2)
  low filling:  --window 1.72 6.76 --experiment 1.44 (seed 004 §5.4.1)
Exit code 1 when a given tolerance is exceeded or the window holds no full oscillation."""
import argparse
import csv
import sys


def extrema(t, y, t0, t1):
    """Crests and valleys of y in [t0, t1] as (time, value, +1 crest / -1 valley): the signal is cut into
    half-cycles where it crosses its mean over the window with a hysteresis of 10 % of its range over the
    window (so ripples do not count), and the largest / smallest sample of each complete half-cycle is
    refined by a parabola through it and its two neighbours."""
    idx = [i for i in range(len(t)) if t0 <= t[i] <= t1]
    if len(idx) < 3:
        return []
    mean = sum(y[i] for i in idx) / len(idx)
    band = 0.1 * (max(y[i] for i in idx) - min(y[i] for i in idx))
    # Half-cycles over the whole record (so one that begins before t0 is still seen whole); the extrema of
    # the complete ones that fall inside [t0, t1] are kept.
    sign, cuts = 0, []
    for i in range(len(t)):  # indices where the signal settles on the other side of the mean
        s = 1 if y[i] > mean + band else -1 if y[i] < mean - band else 0
        if s != 0 and s != sign:
            cuts.append((i, s))
            sign = s
    out = []
    for (a, s), (b, _) in zip(cuts[1:], cuts[2:]):  # complete half-cycles: the first one may have begun before the record
        lo = a
        while lo > 0 and (y[lo - 1] - mean) * s > 0:  # back to the mean crossing
            lo -= 1
        k = max(range(lo, b), key=lambda i: s * y[i])
        if k == 0 or k == len(y) - 1 or not t0 <= t[k] <= t1:
            continue
        den = y[k - 1] - 2 * y[k] + y[k + 1]
        f = 0.5 * (y[k - 1] - y[k + 1]) / den if den != 0 else 0.0
        out.append((t[k] + f * (t[k + 1] - t[k]), y[k] - 0.25 * (y[k - 1] - y[k + 1]) * f, s))
    return out


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("probes")
    ap.add_argument("--window", nargs=2, type=float, required=True, metavar=("T0", "T1"))
    ap.add_argument("--experiment", type=float, required=True, help="experimental crest-to-valley amplitude [cm]")
    ap.add_argument("--period", type=float, help="experimental period [s]")
    ap.add_argument("--max-error", type=float, help="largest allowed amplitude error [%%]")
    ap.add_argument("--max-period-error", type=float, help="largest allowed period error [%%]")
    ap.add_argument("--column", default="tip_dx")
    args = ap.parse_args()
    t, y = [], []
    with open(args.probes) as f:
        for row in csv.DictReader(f):
            t.append(float(row["time"]))
            y.append(100 * float(row[args.column]))  # cm
    t0, t1 = args.window
    if t[-1] < t1:
        print(f"note: the run ends at t = {t[-1]:.2f} s, before the window's end {t1} s; window cut to {t0}-{t[-1]:.2f} s")
        t1 = t[-1]
    ex = extrema(t, y, t0, t1)
    crests = [e for e in ex if e[2] > 0]
    valleys = [e for e in ex if e[2] < 0]
    if len(crests) < 2 or len(valleys) < 2:
        print("FAIL: fewer than two crests and two valleys in the window")
        return 1
    crest, valley = sum(e[1] for e in crests) / len(crests), sum(e[1] for e in valleys) / len(valleys)
    amplitude = crest - valley
    period = 0.5 * ((crests[-1][0] - crests[0][0]) / (len(crests) - 1) + (valleys[-1][0] - valleys[0][0]) / (len(valleys) - 1))
    err = 100 * (amplitude / args.experiment - 1)
    print(f"window {t0:.2f}-{t1:.2f} s: {len(crests)} crests (mean {crest:+.2f} cm), {len(valleys)} valleys (mean {valley:+.2f} cm)")
    print(f"crest-to-valley amplitude {amplitude:.2f} cm (experiment {args.experiment:.2f} cm, {err:+.1f} %)")
    line = f"period {period:.3f} s"
    perr = None
    if args.period:
        perr = 100 * (period / args.period - 1)
        line += f" (experiment {args.period:.3f} s, {perr:+.1f} %)"
    print(line)
    ok = True
    if args.max_error is not None and abs(err) > args.max_error:
        print(f"FAIL: amplitude error {err:+.1f} % exceeds {args.max_error} %")
        ok = False
    if args.max_period_error is not None and perr is not None and abs(perr) > args.max_period_error:
        print(f"FAIL: period error {perr:+.1f} % exceeds {args.max_period_error} %")
        ok = False
    return 0 if ok else 1


if __name__ == "__main__":
    sys.exit(main())
