#!/usr/bin/env python3
"""A wall that moves on its own, through the program: the gate of cases/dam_break_gate.yaml (a translation at a
constant velocity after a smooth ramp, stopped) is run at a coarse dp; in every frame each of the gate's particles
is where the motion puts it, x0 + d(t), with the velocity d'(t) (to round-off), the tank's walls have not moved,
and no fluid particle is inside the lattice cell of a gate particle (the moving wall holds water).

d(t) for a ramp T and a velocity V (core/wall_motion.hpp): V (tau/2 - T sin(pi tau/T) / (2 pi)) within the ramp,
V (T/2 + tau - T) after it, tau = min(t, stop) - start.

Usage: moving_wall_test.py --mpsfsi BIN --case CASE --work DIR --end T [-- run args]
"""
import math
import os
import sys

import numpy as np

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, os.path.join(HERE, "..", "..", "scripts"))
sys.path.insert(0, os.path.join(HERE, "..", "support"))
from run_checks import case_run_parser, fail, run_case  # noqa: E402
from run_output import frame_files, frame_times, read_frame  # noqa: E402

FLUID, WALL, DUMMY = 0, 1, 2  # ParticleKind (core/particles.hpp)


def displacement(t, motion):
    v = np.array(motion["translation"]["velocity"], float)
    start, ramp, stop = motion.get("start", 0.0), motion.get("ramp", 0.0), motion.get("stop", math.inf)
    tau = max(0.0, min(t, stop) - start)
    if ramp > 0 and tau < ramp:
        return v * (tau / 2 - ramp * math.sin(math.pi * tau / ramp) / (2 * math.pi)), \
            (v * 0.5 * (1 - math.cos(math.pi * tau / ramp)) if start < t < stop else 0 * v)
    return v * (ramp / 2 + tau - ramp), (v if start < t < stop else 0 * v)


def main():
    args = case_run_parser(__doc__).parse_args()
    case = run_case(args, args.work)
    dp = float(case["dp"])
    moving = [w for w in case["walls"] if w.get("motion")]
    if len(moving) != 1 or moving[0]["type"] != "block":
        fail("expected one moving block wall in the case")
    gate = moving[0]
    lo, hi = np.array(gate["rectangle"]["min"], float), np.array(gate["rectangle"]["max"], float)
    files = frame_files(args.work, "moving_wall_test")
    times = frame_times(args.work, files)
    x0, f0 = read_frame(files[0])
    dim = len(lo)
    x0 = x0[:, :dim]
    walls0 = np.isin(f0["kind"], [WALL, DUMMY])
    in_gate = walls0 & np.all((x0 > lo) & (x0 < hi), axis=1)
    if not in_gate.any():
        fail("no gate particle found in the first frame")
    ref = {int(g): x for g, x in zip(f0["global_id"][walls0], x0[walls0])}
    gate_ids = set(int(g) for g in f0["global_id"][in_gate])
    worst_x = worst_v = 0.0
    checked = 0
    for path, t in zip(files, times):
        x, f = read_frame(path)
        x = x[:, :dim]
        d, v = displacement(t, gate["motion"])
        walls = np.isin(f["kind"], [WALL, DUMMY])
        gx = []
        for k in np.nonzero(walls)[0]:
            g = int(f["global_id"][k])
            if g in gate_ids:
                worst_x = max(worst_x, float(np.abs(x[k] - ref[g] - d).max()))
                worst_v = max(worst_v, float(np.abs(f["velocity"][k][:dim] - v).max()))
                gx.append(x[k])
            else:
                worst_x = max(worst_x, float(np.abs(x[k] - ref[g]).max()))
        gx = np.array(gx)
        fluid = x[f["kind"] == FLUID]
        inside = 0
        for p in gx:
            inside += int(np.all(np.abs(fluid - p) < 0.5 * dp - 1e-12, axis=1).sum())
        if inside:
            fail(f"t = {t:g} s: {inside} fluid particle(s) inside the gate's lattice cells")
        checked += 1
    if worst_x > 1e-12 or worst_v > 1e-12:
        fail(f"the walls are off their motion by up to {worst_x:.3g} m, {worst_v:.3g} m/s")
    print(f"OK: {checked} frames to t = {times[-1]:g} s: {len(gate_ids)} gate particles on their motion (to "
          f"{worst_x:.1e} m, {worst_v:.1e} m/s), the tank at rest, no fluid in the gate's cells")


if __name__ == "__main__":
    main()
