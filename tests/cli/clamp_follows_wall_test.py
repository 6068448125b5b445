#!/usr/bin/env python3
"""A solid clamped into a wall that moves on its own moves with it. The case (tests/cli/cases/plate_on_paddle.yaml)
clamps an elastic plate into a paddle that moves. In every frame, the rigid motion of the paddle's particles (x0 ->
x, fitted by least squares: Kabsch) must carry the plate's clamped particles from their first places to their
places and velocities, to round-off. The plate's free tip must move with the paddle, beyond the clamp.

Usage: clamp_follows_wall_test.py --mpsfsi BIN --case CASE --work DIR --end T [-- run args]
"""
import os
import sys

import numpy as np

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, os.path.join(HERE, "..", "..", "scripts"))
sys.path.insert(0, os.path.join(HERE, "..", "support"))
from run_checks import case_run_parser, fail, run_case  # noqa: E402
from run_output import frame_files, frame_times, read_frame  # noqa: E402

FLUID, WALL, DUMMY, SOLID = 0, 1, 2, 3  # ParticleKind (core/particles.hpp)


def rigid_fit(x0, x):
    """R, d with x = R x0 + d in the least-squares sense (Kabsch)."""
    c0, c = x0.mean(axis=0), x.mean(axis=0)
    u, _, vt = np.linalg.svd((x0 - c0).T @ (x - c))
    s = np.eye(x0.shape[1])
    s[-1, -1] = np.sign(np.linalg.det(vt.T @ u.T))
    r = vt.T @ s @ u.T
    return r, c - r @ c0


def main():
    args = case_run_parser(__doc__).parse_args()
    case = run_case(args, args.work)
    moving = [w for w in case["walls"] if w.get("motion")]
    if len(moving) != 1:
        fail("expected one moving wall in the case")
    files = frame_files(args.work, "clamp_follows_wall_test")
    times = frame_times(args.work, files)
    x0, f0 = read_frame(files[0])
    dim = len(case["domain"]["min"])
    x0 = x0[:, :dim]
    body_names = [b["name"] for b in case["bodies"]] + [w["name"] for w in case["walls"]]
    paddle_body = body_names.index(moving[0]["name"])
    ids0 = f0["global_id"]
    paddle0 = {int(g): x for g, x, b, k in zip(ids0, x0, f0["body"], f0["kind"]) if b == paddle_body and k in (WALL, DUMMY)}
    clamped0 = {int(g): x for g, x, k, c in zip(ids0, x0, f0["kind"], f0["clamped"]) if k == SOLID and c}
    solid0 = {int(g): x for g, x, k in zip(ids0, x0, f0["kind"]) if k == SOLID}
    if len(paddle0) < 10 or len(clamped0) < 2:
        fail(f"expected a paddle and a clamped solid: {len(paddle0)} paddle particles, {len(clamped0)} clamped")
    tip_id = max(solid0, key=lambda g: solid0[g][dim - 1])
    worst_x = worst_v = 0.0
    paddle_travel = tip_travel = 0.0
    for path, t in zip(files, times):
        x, f = read_frame(path)
        x = x[:, :dim]
        v = f["velocity"][:, :dim]
        index = {int(g): k for k, g in enumerate(f["global_id"])}
        p_ids = list(paddle0)
        r, d = rigid_fit(np.array([paddle0[g] for g in p_ids]), np.array([x[index[g]] for g in p_ids]))
        # The paddle's velocity field: v(x) = v_c + Omega (x - c), fitted likewise (Omega skew in 2D and 3D).
        px = np.array([x[index[g]] for g in p_ids])
        pv = np.array([v[index[g]] for g in p_ids])
        a = np.c_[np.ones(len(p_ids)), px]
        coef, *_ = np.linalg.lstsq(a, pv, rcond=None)
        for g, y0 in clamped0.items():
            k = index[g]
            worst_x = max(worst_x, float(np.abs(x[k] - (r @ y0 + d)).max()))
            worst_v = max(worst_v, float(np.abs(v[k] - np.r_[1.0, x[k]] @ coef).max()))
        paddle_travel = max(paddle_travel, float(np.abs(d).max()))
        tip_travel = max(tip_travel, float(np.abs(x[index[tip_id]] - solid0[tip_id]).max()))
    if worst_x > 1e-12 or worst_v > 1e-9:
        fail(f"the clamped particles are off the paddle's rigid motion by up to {worst_x:.3g} m, {worst_v:.3g} m/s")
    if paddle_travel < 5 * float(case["dp"]):
        fail(f"the paddle moved only {paddle_travel:.3g} m: the test sees too little")
    if tip_travel < 0.5 * paddle_travel:
        fail(f"the plate's tip moved {tip_travel:.3g} m while the paddle moved {paddle_travel:.3g} m")
    print(f"OK: {len(files)} frames to t = {times[-1]:g} s: {len(clamped0)} clamped particles on the paddle's rigid "
          f"motion (to {worst_x:.1e} m, {worst_v:.1e} m/s); the paddle moved up to {paddle_travel:.3g} m, the plate's "
          f"tip {tip_travel:.3g} m")


if __name__ == "__main__":
    main()
