#!/usr/bin/env python3
"""Smallest block (finite half-space) for an MPS Lamb's-problem run: no wave reflected at the block's
sides or bottom may reach a receiver before the receiver's window ends (issue 6; cases/lamb/README.md).

Receiver at surface offset x (source at (0, -h), free surface y = 0), window end
    t_end(x) = t0 + |x| / c_R + 1.5 / f0      (the Rayleigh pulse, the last arrival, has passed;
                                                the same window as scripts/lamb/compare.py)
The earliest reflection is the P wave (Vp is the fastest speed). The wavelet's onset is taken at
t_on = t0 - 1 / f0 (6.3 sigma before its centre, relative amplitude 2e-9). A P wave leaving at t_on
reaches the receiver after the path lengths (image sources):
    right side at x = L_r:  2 L_r - x          left side at x = -L_l:  2 L_l + x
    bottom at y = -D:       sqrt(x^2 + (2 D - h)^2)
Each must exceed Vp (t_end(x) - t_on) for every receiver.

  /usr/bin/python3 scripts/lamb/block_size.py --vp 2611 --vs 1846 --f0 300 [--depth 1] \
      [--offsets 10,14,18,22,26,30,34,38] [--dx 0.1] [--dt 1e-5]
"""
from __future__ import annotations

import argparse
import math
import os
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import lamb2d  # noqa: E402


def block(vp, vs, f0, depth, offsets):
    """(t_end_max, L_left, L_right, D) in s and m."""
    cr = lamb2d.rayleigh_speed(vp, vs)
    t0 = 1.5 / f0
    t_on = t0 - 1.0 / f0
    left = right = bottom = t_max = 0.0
    for x in offsets:
        ax = abs(x)
        t_end = t0 + ax / cr + 1.5 / f0
        t_max = max(t_max, t_end)
        path = vp * (t_end - t_on)
        right = max(right, (path + x) / 2)
        left = max(left, (path - x) / 2)
        bottom = max(bottom, (math.sqrt(max(path * path - x * x, 0.0)) + depth) / 2)
    return t_max, left, right, bottom


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--vp", type=float, required=True)
    ap.add_argument("--vs", type=float, required=True)
    ap.add_argument("--f0", type=float, required=True, help="central frequency [Hz] (delay t0 = 1.5 / f0)")
    ap.add_argument("--depth", type=float, default=1.0, help="source depth h [m]")
    ap.add_argument("--offsets", default="10,14,18,22,26,30,34,38", help="receiver offsets x [m]")
    ap.add_argument("--dx", type=float, default=0.1)
    ap.add_argument("--dt", type=float, default=1e-5)
    args = ap.parse_args(argv)
    offsets = [float(v) for v in args.offsets.split(",") if v.strip()]
    t_max, left, right, bottom = block(args.vp, args.vs, args.f0, args.depth, offsets)
    n = (left + right) * bottom / args.dx**2
    steps = t_max / args.dt
    print(f"c_R = {lamb2d.rayleigh_speed(args.vp, args.vs):.1f} m/s; last window end {t_max * 1e3:.2f} ms "
          f"({steps:.0f} steps of {args.dt:g} s)")
    print(f"block at least x in [-{left:.1f}, {right:.1f}] m, depth {bottom:.1f} m: "
          f"{n / 1e3:.0f}k particles of {args.dx:g} m, {n * steps:.3g} particle-steps")
    return 0


if __name__ == "__main__":
    sys.exit(main())
