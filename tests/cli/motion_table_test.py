#!/usr/bin/env python3
"""A wall moved by a table runs as the same motion given by its formula. The piston of a case with a piston
`wave_maker` (cases/wave_flume.yaml) is run once by the formula, (S/2) r(tau) sin(2 pi tau / T). It is then run
again from the first run's case.resolved.yaml (which names the case's files by absolute paths, so it runs from
the work folder) with the wave maker replaced by `translation: {type: table}`, a table of (S/2) sin(2 pi tau / T)
sampled every 1.5 ms, with a half window of 1.5 ms. The piston's particles must be where the formula puts them in
every frame, to the linear interpolation's error (S/2) (2 pi / T)^2 dt^2 / 8, and move at its velocity to the
error of the centred difference, (S/2) (2 pi / T)^3 (h^2 / 6 + dt^2 / 8), twice over for the ramp's part. At the end, the water within --near
metres of the piston must be the same in both runs to 1e-3 dp. Further out, where the water meets the beach's
slope, round-off grows into differences of up to a dp by 1 s, whatever moves the piston.

Usage: motion_table_test.py --mpsfsi BIN --case CASE --work DIR --end T [--near D] [-- run args]
"""
import math
import os
import shutil
import sys

import numpy as np
import yaml

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, os.path.join(HERE, "..", "..", "scripts"))
sys.path.insert(0, os.path.join(HERE, "..", "support"))
from run_checks import case_run_parser, fail, run, run_case  # noqa: E402
from run_output import frame_files, read_frame  # noqa: E402

FLUID = 0  # ParticleKind (core/particles.hpp)
SAMPLE = 1.5e-3  # the table's row spacing [s]: frames fall between its rows


def frames(run_dir):
    """Positions, velocities and kinds of every frame, by global id."""
    out = []
    for path in frame_files(run_dir, "motion_table_test"):
        x, f = read_frame(path)
        order = np.argsort(f["global_id"])
        out.append((f["global_id"][order], x[order], f["kind"][order], f["velocity"][order]))
    return out


def main():
    ap = case_run_parser(__doc__)
    ap.add_argument("--near", type=float, default=2.0, help="compare the water this far from the piston [m]")
    args = ap.parse_args()
    shutil.rmtree(args.work, ignore_errors=True)
    os.makedirs(args.work)
    formula_dir, table_dir = os.path.join(args.work, "formula"), os.path.join(args.work, "table")
    case = run_case(args, formula_dir)
    pistons = [w for w in case["walls"] if w.get("motion", {}).get("wave_maker", {}).get("type") == "piston"]
    if len(pistons) != 1:
        fail("expected one piston wave maker in the case")
    motion = pistons[0]["motion"]
    maker = motion.pop("wave_maker")
    stroke, period = float(maker["stroke"]), float(maker["period"])
    direction = [float(c) for c in maker.get("direction", [1, 0])]
    tau = np.arange(0.0, args.end + 10 * SAMPLE, SAMPLE)
    table = os.path.join(args.work, "piston.csv")
    np.savetxt(table, np.c_[tau, 0.5 * stroke * np.sin(2 * math.pi * tau / period)], delimiter=",",
               header="time [s], displacement [m]", fmt="%.17g")
    motion["translation"] = {"type": "table", "file": "piston.csv", "direction": direction, "half_window": SAMPLE}
    case_path = os.path.join(args.work, "table_case.yaml")
    with open(case_path, "w") as f:
        yaml.safe_dump(case, f, sort_keys=False)
    # The resolved case's other files (a polygon, a surface) are absolute paths: it runs from the work folder.
    run([args.mpsfsi, "run", case_path, "--quiet", "--output", table_dir, "--end-time", str(args.end)])
    a, b = frames(formula_dir), frames(table_dir)
    if len(a) != len(b) or len(a) < 3:
        fail(f"{len(a)} frames by the formula, {len(b)} by the table")
    amplitude = 0.5 * stroke
    w = 2 * math.pi / period
    bound = amplitude * w ** 2 * SAMPLE ** 2 / 8 + 1e-12
    bound_v = 2 * amplitude * w ** 3 * (SAMPLE ** 2 / 6 + SAMPLE ** 2 / 8) + 1e-12
    worst_wall = worst_v = 0.0
    for (ia, xa, ka, va), (ib, xb, kb, vb) in zip(a, b):
        if not np.array_equal(ia, ib):
            fail("the two runs hold different particles")
        walls = ka != FLUID
        worst_wall = max(worst_wall, float(np.abs(xa[walls] - xb[walls]).max()))
        worst_v = max(worst_v, float(np.abs(va[walls] - vb[walls]).max()))
    if worst_wall > bound or worst_v > bound_v:
        fail(f"the walls of the two runs differ by {worst_wall:.3g} m and {worst_v:.3g} m/s, more than the interpolation's "
             f"{bound:.3g} m and {bound_v:.3g} m/s")
    if worst_wall < 1e-3 * bound:
        fail(f"the walls of the two runs agree to {worst_wall:.3g} m: the frames fall on the table's rows, where the "
             "interpolation is exact; the test does not see between them")
    ia, xa, ka, va = a[-1]
    dp = float(case["dp"])
    piston_x = float(pistons[0]["rectangle"]["max"][0])
    near = (ka == FLUID) & (np.abs(xa[:, 0] - piston_x) < args.near)
    if near.sum() < 100:
        fail(f"only {near.sum()} fluid particles within {args.near:g} m of the piston")
    worst_fluid = float(np.abs(xa[near] - b[-1][1][near]).max())
    if not worst_fluid < 1e-3 * dp:
        fail(f"the water within {args.near:g} m of the piston differs by {worst_fluid:.3g} m between the runs at the end "
             f"(dp {dp:g} m)")
    print(f"OK: {len(a)} frames to t = {args.end:g} s: the walls agree to {worst_wall:.2g} m and {worst_v:.2g} m/s (bounds "
          f"{bound:.2g}, {bound_v:.2g}), "
          f"the water within {args.near:g} m of the piston to {worst_fluid:.2g} m ({worst_fluid / dp:.2g} dp)")


if __name__ == "__main__":
    main()
