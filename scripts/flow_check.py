#!/usr/bin/python3
"""The health of a fluid run, frame by frame (.vtu or .pvtu frames): the largest fluid speed and where it is,
the 99.9th percentile and the largest fluid pressure, the fluid particles inside a wall (in a `box` wall or
a `block` of the resolved case, its faces on the lattice, or inside a `sphere`, `cylinder`, `polygon` or `surface`
obstacle, with a margin of 1e-9 m (walls that move on their own are not checked); "-" for a case without walls
or with tank_motion) and the fluid particle count. With bounds it is a check: it exits 1 naming the first frame and quantity that breaks one.

Usage
  scripts/flow_check.py out/db                                   # a table, every frame
  scripts/flow_check.py out/db --frames -1 --max-speed 0.5 --max-p999 4300 --min-pressure-at 0.0005,0.0005,900
  scripts/flow_check.py out/db --until 0.15 --max-speed 3.4      # the frames with t <= 0.15 s only

--min-pressure-at X,Y,P: the pressure of the fluid particle nearest (X, Y) is at least P [Pa]. Every frame is
checked for particles inside a wall unless --allow-outside. A polygon's or surface's file is read relative to
--case-dir (the folder of the run's case file; default: where the resolved case's name is found under cases/).
"""
import argparse
import os
import sys

import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from run_output import frame_files, frame_times, pick_frames, read_case, read_frame  # noqa: E402

PROG = "flow_check.py"
FLUID = 0  # ParticleKind::fluid in the `kind` field


WALL_LAYERS = 3  # a wall's layer and its two dummy layers (core/geometry.hpp: box_walls, block_walls)


def surface_distance(shape, dim, case_dir):
    """The signed distance (negative inside) of a case's polygon (2D) or STL / OBJ surface (3D), scaled, rotated and
    translated as io/surface.hpp does, as a function of an (n, dim) array of points."""
    import vtk
    scale = shape.get("scale", 1.0)
    scale = [float(scale)] * dim if not isinstance(scale, list) else [float(v) for v in scale]
    translate = [float(v) for v in shape.get("translate", [0.0] * dim)]
    transform = vtk.vtkTransform()
    transform.PostMultiply()
    transform.Scale(*(scale + [1.0] * (3 - dim)))
    if dim == 2:
        transform.RotateZ(float(shape.get("rotate", 0.0)))
    else:
        rx, ry, rz = (float(v) for v in shape.get("rotate", [0, 0, 0]))
        transform.RotateX(rx), transform.RotateY(ry), transform.RotateZ(rz)
    transform.Translate(*(translate + [0.0] * (3 - dim)))
    if dim == 2:
        if "points" in shape:
            pts = np.array(shape["points"], float)
        else:
            rows = []
            with open(os.path.join(case_dir, shape["file"])) as f:
                for line in f:
                    line = line.split("#")[0].replace(",", " ").split()
                    if line:
                        rows.append([float(line[0]), float(line[1])])
            pts = np.array(rows)
        pts = np.array([transform.TransformPoint(x, y, 0.0)[:2] for x, y in pts])
        from matplotlib.path import Path
        path = Path(pts)

        def distance(x):
            d = np.full(len(x), np.inf)
            for a, b in zip(pts, np.roll(pts, -1, axis=0)):
                t = np.clip(((x - a) @ (b - a)) / ((b - a) @ (b - a)), 0, 1)
                d = np.minimum(d, np.linalg.norm(x - (a + np.outer(t, b - a)), axis=1))
            return np.where(path.contains_points(x), -d, d)
        return distance
    path = os.path.join(case_dir, shape["file"])
    reader = vtk.vtkSTLReader() if path.lower().endswith(".stl") else vtk.vtkOBJReader()
    reader.SetFileName(path)
    moved = vtk.vtkTransformPolyDataFilter()
    moved.SetInputConnection(reader.GetOutputPort())
    moved.SetTransform(transform)
    moved.Update()
    implicit = vtk.vtkImplicitPolyDataDistance()
    implicit.SetInput(moved.GetOutput())
    return lambda x: np.array([implicit.EvaluateFunction(*p) for p in x])


def find_case_dir(case):
    """The folder under cases/ that holds a file named like the case (its name without a _3d suffix)."""
    root = os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "cases")
    name = str(case.get("name", ""))
    for stem in (name, name[:-3] if name.endswith("_3d") else name):
        for sub in ("", "3d"):
            if os.path.exists(os.path.join(root, sub, stem + ".yaml")):
                return os.path.join(root, sub)
    return "."


def lattice_origin(case):
    """The corner of the case's lattice, as io/scene.cpp takes it: the first box wall's low corner, else the first
    rectangle body's, else the origin."""
    dim = int(case.get("dimension", 2))
    for w in case.get("walls", []) or []:
        if w.get("type", "box") == "box" and "rectangle" in w:
            return np.array(w["rectangle"]["min"], float)
    for b in case.get("bodies", []) or []:
        if "rectangle" in b and not any(k in b for k in ("sphere", "cylinder", "polygon", "surface")):
            return np.array(b["rectangle"]["min"], float)
    return np.zeros(dim)


def lattice_rect(lo, hi, origin, dp):
    """core/geometry.cpp's lattice_rect: the faces of the lattice cells (faces at origin + k dp) whose centres c
    satisfy lo < c <= hi on each axis; one cell from lo on an axis that holds none."""
    tol = 1e-9
    rlo, rhi = np.array(lo, float), np.array(hi, float)
    for a in range(len(lo)):
        f_lo, f_hi = (lo[a] - origin[a]) / dp, (hi[a] - origin[a]) / dp
        first, last = np.floor(f_lo - 0.5 + tol) + 1, np.floor(f_hi - 0.5 + tol)
        if last < first:
            rlo[a], rhi[a] = lo[a], lo[a] + dp
            continue
        rlo[a] = lo[a] if abs(f_lo - round(f_lo)) < tol else origin[a] + first * dp
        rhi[a] = rlo[a] + (last - first + 1) * dp
    return rlo, rhi


def tank_boxes(case, case_dir="."):
    """The walls of the case as (lo, hi, kind, open_top): kind "box" with its inner faces, "block" with its outer
    ones; None for a moving tank (its walls are not where the case puts them), whose particles are then not
    checked. The faces are the lattice's, as the program builds them (core/geometry.cpp, lattice_rect: every box
    and block on the case's one lattice)."""
    if case.get("tank_motion"):
        return None
    dp = float(case["dp"])
    boxes = []
    dim = int(case.get("dimension", 2))
    origin = lattice_origin(case)
    for w in case.get("walls", []) or []:
        if w.get("motion"):
            continue  # a wall that moves on its own is not where the case puts it: not checked
        if w.get("type") in ("polygon", "surface") and w.get("fluid", "outside") == "outside":
            boxes.append((np.zeros(dim), None, "surface", surface_distance(w[w["type"]], dim, case_dir), dp))
            continue
        if w.get("type") in ("polygon", "surface"):
            continue  # a container: not checked
        if w.get("type") == "sphere":
            s = w["sphere"]
            boxes.append((np.array(s["centre"], float), None, "sphere", float(s["radius"]), dp))
            continue
        if w.get("type") == "cylinder":
            c = w["cylinder"]
            boxes.append((np.array(c["base"], float), np.array(c["axis"], float), "cylinder", float(c["radius"]), dp))
            continue
        r = w["rectangle"]
        lo, hi = lattice_rect(np.array(r["min"], float), np.array(r["max"], float), origin, dp)
        boxes.append((lo, hi, w.get("type", "box"), bool(w.get("open_top", False)), dp))
    return boxes


def outside(x, boxes):
    """How many points lie inside a wall: in a box wall (between the inner faces and the outer faces of its
    dummy layers, below the top of the walls when the top is open) or in a block. Spray that leaves the tank over
    the top of its walls has crossed no wall and is not counted. None without walls."""
    if not boxes:
        return None
    in_wall = np.zeros(len(x), bool)
    eps = 1e-9
    x = x[:, :len(boxes[0][0])]  # 2D frames have z = 0
    for lo, hi, kind, open_top, dp in boxes:
        if kind == "surface":  # (-, -, "surface", signed distance, dp)
            in_wall |= open_top(x) < -eps
            continue
        if kind == "sphere":  # (centre, -, "sphere", radius, dp)
            in_wall |= np.linalg.norm(x - lo, axis=1) < open_top - eps
            continue
        if kind == "cylinder":  # (base, axis, "cylinder", radius, dp)
            length = np.linalg.norm(hi)
            e = hi / length
            s = (x - lo) @ e
            rho = np.linalg.norm(x - lo - np.outer(s, e), axis=1)
            in_wall |= (s > eps) & (s < length - eps) & (rho < open_top - eps)
            continue
        if kind == "block":
            in_wall |= np.all((x > lo + eps) & (x < hi - eps), axis=1)
            continue
        top = len(lo) - 1
        shell_hi, inner_hi = hi + WALL_LAYERS * dp, hi + eps
        if open_top:
            shell_hi[top], inner_hi[top] = hi[top], np.inf
        in_shell = np.all((x > lo - WALL_LAYERS * dp) & (x < shell_hi), axis=1)
        in_inner = np.all((x >= lo - eps) & (x <= inner_hi), axis=1)
        in_wall |= in_shell & ~in_inner
    return int(in_wall.sum())


def frame_health(x, fields, boxes):
    """One frame's figures: fluid count, largest fluid speed and its position, 99.9th percentile and largest
    fluid pressure, fluid particles inside a wall."""
    fluid = fields["kind"] == FLUID
    if not fluid.any():
        return {"n": 0, "speed": 0.0, "at": (0.0, 0.0), "p999": 0.0, "pmax": 0.0, "outside": outside(x[fluid], boxes)}
    speed = np.linalg.norm(fields["velocity"][fluid], axis=1)
    p = fields["pressure"][fluid]
    k = int(np.argmax(speed))
    return {"n": int(fluid.sum()), "speed": float(speed[k]), "at": tuple(x[fluid][k]),
            "p999": float(np.percentile(p, 99.9)), "pmax": float(p.max()), "outside": outside(x[fluid], boxes)}


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("run", help="output folder of a run on one rank")
    ap.add_argument("--frames", default=None, help="comma-separated frame numbers (default: all)")
    ap.add_argument("--until", type=float, default=None, help="only the frames at t <= this [s]")
    ap.add_argument("--max-speed", type=float, default=None, help="bound on the largest fluid speed [m/s]")
    ap.add_argument("--max-p999", type=float, default=None, help="bound on the 99.9th percentile fluid pressure [Pa]")
    ap.add_argument("--min-pressure-at", default=None, help="X,Y,P: the fluid particle nearest (X, Y) has p >= P [Pa]")
    ap.add_argument("--allow-outside", action="store_true", help="do not fail on particles inside a wall")
    ap.add_argument("--case-dir", default=None, help="the folder of the run's case file (for its surfaces' files)")
    args = ap.parse_args()

    files = frame_files(args.run, PROG)
    times = dict(zip(files, frame_times(args.run, files)))
    files = pick_frames(files, args.frames, PROG)
    if args.until is not None:
        files = [f for f in files if not times[f] > args.until]
    case = read_case(args.run, PROG)
    boxes = tank_boxes(case, args.case_dir or find_case_dir(case))
    probe = None
    if args.min_pressure_at:
        try:
            probe = [float(v) for v in args.min_pressure_at.split(",")]
            assert len(probe) >= 3
        except (ValueError, AssertionError):
            sys.exit(f"{PROG}: --min-pressure-at '{args.min_pressure_at}': expected X,Y,P (or X,Y,Z,P in 3D)")
    failures = []
    print("frame, t [s], fluid particles, max speed [m/s], x, y of max, p99.9 [Pa], p max [Pa], inside a wall")
    for f in files:
        x, fields = read_frame(f)
        h = frame_health(x, fields, boxes)
        name = os.path.basename(f)
        print(f"{name}, {times[f]:.5g}, {h['n']}, {h['speed']:.4g}, {h['at'][0]:.5f}, {h['at'][1]:.5f}, "
              f"{h['p999']:.4g}, {h['pmax']:.4g}, {'-' if h['outside'] is None else h['outside']}")
        if args.max_speed is not None and h["speed"] > args.max_speed:
            failures.append(f"{name}: largest fluid speed {h['speed']:.4g} m/s > {args.max_speed}")
        if args.max_p999 is not None and h["p999"] > args.max_p999:
            failures.append(f"{name}: 99.9th percentile pressure {h['p999']:.4g} Pa > {args.max_p999}")
        if h["outside"] and not args.allow_outside:
            failures.append(f"{name}: {h['outside']} fluid particle(s) inside a wall")
        if probe is not None and h["n"]:
            fluid = fields["kind"] == FLUID
            d = len(probe) - 1
            j = int(np.argmin(np.linalg.norm(x[fluid, :d] - np.array(probe[:d]), axis=1)))
            p_j = fields["pressure"][fluid][j]
            if p_j < probe[-1]:
                failures.append(f"{name}: pressure {p_j:.4g} Pa at the fluid particle nearest {probe[:d]} < {probe[-1]}")
    if failures:
        print("\n".join(f"{PROG}: FAIL {m}" for m in failures), file=sys.stderr)
        sys.exit(1)


if __name__ == "__main__":
    main()
