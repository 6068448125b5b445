#!/usr/bin/python3
"""Water at rest, measured against the criteria of the fluid scheme (docs/validation.md, ## Fluid): in a frame
of an mpsfsi run of cases/hydrostatic.yaml (or any still-water case), the largest and the 99th-percentile
fluid speed as a share of sqrt(g h), the largest pressure error |p - rho g (h - y)| / (rho g (h - y)) over the
fluid particles more than 3 dp below the surface, the fluid particle count, and the volume the fluid takes:
the mean height of its top (the highest particle of each column of width dp, plus dp/2) against h.

h is the depth of the water as the case file builds it (the top of the fluid body), y the particle's height
above the bottom of that body.

Usage
  mpsfsi run cases/hydrostatic.yaml --end-time 2 --output out/hs
  scripts/hydrostatic_check.py out/hs                    # the last frame
  scripts/hydrostatic_check.py out/hs --frames 0,20,-1   # frame numbers, negative from the end
  scripts/hydrostatic_check.py out/hs --map 8             # and where the water moves: 8 x 8 blocks of the body

--map N: for each frame, the body's rectangle cut into N x N blocks (2D; top row first), each block's mean fluid
velocity (x, y) and the rms of the velocities about it, in mm/s: where motion in still water starts and spreads.
"""
import argparse
import os
import sys

import numpy as np

from run_output import frame_files, pick_frames, read_case, read_frame

FLUID = 0  # ParticleKind::fluid in the `kind` field


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("run", help="output folder of a run (holding case.resolved.yaml and particles_*.vtu)")
    ap.add_argument("--frames", default="-1", help="comma-separated frame numbers (default: the last)")
    ap.add_argument("--body", default=None, help="the fluid body (default: the first fluid body of the case)")
    ap.add_argument("--map", type=int, default=0, metavar="N", help="print N x N blocks of the velocity (see above)")
    args = ap.parse_args()
    prog = "hydrostatic_check.py"
    all_files = frame_files(args.run, prog)
    files = pick_frames(all_files, args.frames, prog)
    case = read_case(args.run, prog)
    fluids = [b for b in case["bodies"] if b.get("kind") == "fluid" and (args.body is None or b["name"] == args.body)]
    if not fluids:
        sys.exit(f"{prog}: no fluid body{' ' + args.body if args.body else ''} in {args.run}/case.resolved.yaml")
    body = fluids[0]
    rho = float(case["materials"][body["material"]]["rho"])
    g = float(np.linalg.norm(case["gravity"]))
    dp = float(case["dp"])
    y0, y1 = float(body["rectangle"]["min"][1]), float(body["rectangle"]["max"][1])
    h = y1 - y0
    _, first_f = read_frame(all_files[0])
    n_first = int(np.sum(first_f["kind"] == FLUID))
    print(f"{body['name']}: h = {h:g} m, rho g h = {rho * g * h:.1f} Pa, sqrt(g h) = {np.sqrt(g * h):.4f} m/s, "
          f"{n_first} fluid particles in the first frame")
    print("| frame | fluid | top / h | max speed % sqrt(gh) | 99th pct % | median % | pressure error % (depth > 3 dp): max / median |")
    print("|---|---|---|---|---|---|---|")
    for path in files:
        x, f = read_frame(path)
        fluid = f["kind"] == FLUID
        v = np.linalg.norm(f["velocity"][fluid], axis=1) / np.sqrt(g * h) * 100
        depth = y1 - x[fluid, 1]
        p = f["pressure"][fluid]
        deep = depth > 3 * dp
        p_ref = rho * g * depth[deep]
        rel = np.abs(p[deep] - p_ref) / p_ref * 100
        err, err_median = (rel.max(), np.median(rel)) if np.any(deep) else (float("nan"), float("nan"))
        n = int(np.sum(fluid))
        column = np.floor(x[fluid, 0] / dp).astype(int)
        tops = [x[fluid, 1][column == c].max() for c in np.unique(column)]
        top = (np.mean(tops) + dp / 2 - y0) / h
        print(f"| {os.path.basename(path)} | {n} | {top:.4f} | {v.max():.3f} | {np.percentile(v, 99):.3f} | "
              f"{np.median(v):.3f} | {err:.2f} / {err_median:.2f} |")
    if args.map > 0:
        lo = np.array(body["rectangle"]["min"][:2], float)
        hi = np.array(body["rectangle"]["max"][:2], float)
        for path in files:
            x, f = read_frame(path)
            fluid = f["kind"] == FLUID
            print_map(os.path.basename(path), x[fluid, :2], f["velocity"][fluid, :2], lo, hi, args.map)
    return 0


def print_map(name, x, v, lo, hi, n):
    """The N x N blocks of the rectangle lo-hi (top row first): mean velocity (x, y) | rms about it, mm/s."""
    block = np.floor((x - lo) / (hi - lo) * n).astype(int).clip(0, n - 1)
    print(f"{name}: mean velocity x, y | rms about it [mm/s] in {n} x {n} blocks, top row first")
    for row in range(n - 1, -1, -1):
        cells = []
        for col in range(n):
            inside = (block[:, 0] == col) & (block[:, 1] == row)
            if not np.any(inside):
                cells.append(" " * 17)
                continue
            mean = v[inside].mean(axis=0)
            rms = np.sqrt(((v[inside] - mean) ** 2).sum(axis=1).mean())
            cells.append(f"{mean[0] * 1e3:+5.1f},{mean[1] * 1e3:+5.1f}|{rms * 1e3:4.1f}")
        print("  ".join(cells))


if __name__ == "__main__":
    sys.exit(main())
