#!/usr/bin/env python3
"""A case whose first body and first wall (a box tank) are given as closed surfaces runs as the case itself: the
body and the tank are written as surfaces (2D: polygons in the case file; 3D: STL files made by
scripts/extrude_polygon_stl.py), both cases run their first steps, and the probe series and the last frame must
be the same, bit for bit (the surfaces give the built-in shapes' particles, point for point and in their order).

Usage: surface_case_test.py --mpsfsi BIN --case CASE --work DIR --steps N [-- run args]
"""
import argparse
import os
import shutil
import sys

import numpy as np
import vtk
import yaml
from vtk.util.numpy_support import vtk_to_numpy

HERE = os.path.dirname(os.path.abspath(__file__))
EXTRUDE = os.path.join(HERE, "..", "..", "scripts", "extrude_polygon_stl.py")


sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "support"))
from run_checks import fail, run  # noqa: E402


def corners(rect):
    (x0, y0), (x1, y1) = rect["min"][:2], rect["max"][:2]
    return [[x0, y0], [x1, y0], [x1, y1], [x0, y1]]


def as_surface(rect, dim, work, name):
    """The rectangle (box) as a polygon (2D) or an STL file (3D), in a case's shape form."""
    if dim == 2:
        return {"points": corners(rect)}
    path = os.path.join(work, name + ".stl")
    pts = [f"{x!r},{y!r}" for x, y in corners(rect)]
    run([sys.executable, EXTRUDE, path, "--points", *pts, "--z0", repr(rect["min"][2]), "--z1", repr(rect["max"][2])])
    return {"file": path}


def last_frame(folder):
    import xml.etree.ElementTree as ET
    root = ET.parse(os.path.join(folder, "particles.pvd")).getroot()
    entry = root.findall("./Collection/DataSet")[-1]
    reader = vtk.vtkXMLUnstructuredGridReader()
    reader.SetFileName(os.path.join(folder, entry.get("file")))
    reader.Update()
    grid = reader.GetOutput()
    pd = grid.GetPointData()
    return {"points": vtk_to_numpy(grid.GetPoints().GetData()), "pressure": vtk_to_numpy(pd.GetArray("pressure")),
            "velocity": vtk_to_numpy(pd.GetArray("velocity")), "time": entry.get("timestep")}


def main():
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--mpsfsi", required=True)
    parser.add_argument("--case", required=True)
    parser.add_argument("--work", required=True)
    parser.add_argument("--steps", type=int, default=20)
    parser.add_argument("extra", nargs="*", help="after --: arguments for both runs (e.g. --dp)")
    args = parser.parse_args()
    shutil.rmtree(args.work, ignore_errors=True)
    os.makedirs(args.work)
    with open(args.case) as f:
        case = yaml.safe_load(f)
    dim = int(case.get("dimension", 2))
    key = "polygon" if dim == 2 else "surface"
    body, tank = case["bodies"][0], case["walls"][0]
    if "rectangle" not in body or tank.get("type") != "box":
        fail("the case's first body must be a rectangle and its first wall a box")
    body[key] = as_surface(body.pop("rectangle"), dim, args.work, "body")
    open_top = tank.get("open_top", True)
    tank.update({"type": key, key: as_surface(tank.pop("rectangle"), dim, args.work, "tank"), "fluid": "inside",
                 "open_top": open_top})
    surface_case = os.path.join(args.work, "surface_case.yaml")
    with open(surface_case, "w") as f:
        yaml.safe_dump(case, f)
    outs = {}
    for name, path in (("built-in", os.path.abspath(args.case)), ("surfaces", surface_case)):
        outs[name] = os.path.join(args.work, name)
        run([args.mpsfsi, "run", path, "--quiet", "--output", outs[name], "--max-steps", str(args.steps), *args.extra])
    with open(os.path.join(outs["built-in"], "probes.csv")) as a, open(os.path.join(outs["surfaces"], "probes.csv")) as b:
        pa, pb = a.read(), b.read()
    if pa != pb:
        fail(f"the probe series differ:\n{pa[-600:]}\n---\n{pb[-600:]}")
    fa, fb = last_frame(outs["built-in"]), last_frame(outs["surfaces"])
    for k in ("time", "points", "pressure", "velocity"):
        if not np.array_equal(fa[k], fb[k]):
            fail(f"the last frames' {k} differ")
    n_rows = pa.count("\n") - 1
    print(f"OK: {len(fa['points'])} particles, {n_rows} probe rows and the last frame (t = {fa['time']} s) bit for bit "
          f"the same with the {'polygons' if dim == 2 else 'STL surfaces'}")


if __name__ == "__main__":
    main()
