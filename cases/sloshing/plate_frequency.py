#!/usr/bin/env python3
"""First bending frequency of a clamped plate from a probes.csv (column tip_dy, or --column, e.g. tip_dz in 3D;
cases/sloshing/plate_in_air_*.yaml, cases/3d/sloshing/plate_in_air_high.yaml),
against Euler-Bernoulli f1 = 1.875^2 / (2 pi L^2) sqrt(E' t^2 / (12 rho)) with E' = E (plane stress) and
E / (1 - nu^2) (wide plate, cylindrical bending).
Usage: plate_frequency.py probes.csv --length L [--thickness 0.004] [--E 6e6] [--nu 0.49] [--rho 1100]
                          [--column tip_dy] [--max-error PCT --against plane_stress|wide_plate]   (exit 1 when exceeded)"""
import argparse
import csv
import math
import sys


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("probes")
    ap.add_argument("--length", type=float, required=True, help="free length [m]")
    ap.add_argument("--thickness", type=float, default=0.004)
    ap.add_argument("--E", type=float, default=6.0e6)
    ap.add_argument("--nu", type=float, default=0.49)
    ap.add_argument("--rho", type=float, default=1100.0)
    ap.add_argument("--column", default="tip_dy", help="the tip displacement across the plate")
    ap.add_argument("--max-error", type=float, help="largest allowed |error| [%%] against --against")
    ap.add_argument("--against", choices=["plane_stress", "wide_plate"], default="wide_plate")
    a = ap.parse_args()
    t, y = [], []
    with open(a.probes) as f:
        for row in csv.DictReader(f):
            t.append(float(row["time"]))
            y.append(float(row[a.column]))
    mean = sum(y) / len(y)
    y = [v - mean for v in y]
    xs = [t[i] - y[i] * (t[i + 1] - t[i]) / (y[i + 1] - y[i]) for i in range(len(y) - 1) if y[i] * y[i + 1] < 0]
    if len(xs) < 4:
        print("not enough zero crossings; run longer", file=sys.stderr)
        return 1
    freq = (len(xs) - 1) / (2 * (xs[-1] - xs[0]))
    print(f"first-mode frequency {freq:.3f} Hz from {len(xs)} zero crossings")
    ok = True
    for key, name, e in [("plane_stress", "plane stress, E", a.E), ("wide_plate", "wide plate, E / (1 - nu^2)", a.E / (1 - a.nu ** 2))]:
        f1 = 1.875 ** 2 / (2 * math.pi * a.length ** 2) * math.sqrt(e * a.thickness ** 2 / (12 * a.rho))
        err = 100 * (freq / f1 - 1)
        print(f"  Euler-Bernoulli, {name}: {f1:.3f} Hz (measured {err:+.1f} %)")
        if a.max_error is not None and key == a.against and abs(err) > a.max_error:
            print(f"FAIL: error {err:+.1f} % against {name} exceeds {a.max_error} %")
            ok = False
    return 0 if ok else 1


if __name__ == "__main__":
    sys.exit(main())
