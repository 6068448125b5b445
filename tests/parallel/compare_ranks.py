#!/usr/bin/env python3
"""The same case on 1 and on N MPI ranks (label mpi): the probe series and the last frame, particle by
particle matched by global id, agree within the bounds given; with --restart, a checkpoint written on N ranks
restarts on each of the --restart-ranks counts and ends where the uninterrupted 1-rank run ends, within the
same bounds.

Usage: compare_ranks.py --mpsfsi BIN --mpirun "mpiexec ... -n" --case CASE --end T --ranks N --work DIR
       [--pressure-tol R] [--position-tol M] [--probe-tol R] [--restart T_CK --restart-ranks 1,3] [-- run args]
"""
import argparse
import glob
import os
import shlex
import shutil
import sys
import xml.etree.ElementTree as ET

import numpy as np
import vtk
from vtk.util.numpy_support import vtk_to_numpy


sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "support"))
from run_checks import fail, run  # noqa: E402


def last_frame(folder):
    root = ET.parse(os.path.join(folder, "particles.pvd")).getroot()
    entries = root.findall("./Collection/DataSet")
    path = os.path.join(folder, entries[-1].get("file"))
    reader = (vtk.vtkXMLPUnstructuredGridReader() if path.endswith(".pvtu") else vtk.vtkXMLUnstructuredGridReader())
    reader.SetFileName(path)
    reader.Update()
    grid = reader.GetOutput()
    pd = grid.GetPointData()
    ids = vtk_to_numpy(pd.GetArray("global_id")).astype(np.int64)
    order = np.argsort(ids)
    out = {"global_id": ids[order], "points": vtk_to_numpy(grid.GetPoints().GetData())[order],
           "time": float(entries[-1].get("timestep"))}
    for name in ("pressure", "velocity"):
        if pd.GetArray(name) is not None:
            out[name] = vtk_to_numpy(pd.GetArray(name))[order]
    return out


def probes(folder):
    path = os.path.join(folder, "probes.csv")
    if not os.path.exists(path):
        return None
    return np.genfromtxt(path, delimiter=",", names=True)


def compare(ref, got, what, a, with_probes=True):
    """Largest differences of `got` against `ref` (folders); fails beyond the bounds."""
    fa, fb = last_frame(ref), last_frame(got)
    if fa["time"] != fb["time"]:
        fail(f"{what}: last frame at t = {fb['time']}, expected {fa['time']}")
    if not np.array_equal(fa["global_id"], fb["global_id"]):
        fail(f"{what}: the last frame holds {len(fb['global_id'])} particles, not the same global ids as the "
             f"1-rank run's {len(fa['global_id'])}")
    dx = float(np.max(np.linalg.norm(fa["points"] - fb["points"], axis=1))) if len(fa["points"]) else 0.0
    dp = 0.0
    if "pressure" in fa:
        scale = max(float(np.max(np.abs(fa["pressure"]))), 1e-300)
        dp = float(np.max(np.abs(fa["pressure"] - fb["pressure"]))) / scale
    pa, pb = (probes(ref), probes(got)) if with_probes else (None, None)
    dprobe = 0.0
    if pa is not None:
        if pb is None or pa.shape != pb.shape:
            fail(f"{what}: probes.csv has another shape than the 1-rank run's")
        for name in pa.dtype.names:
            x, y = np.atleast_1d(pa[name]), np.atleast_1d(pb[name])
            scale = max(float(np.nanmax(np.abs(x))), 1e-300)
            dprobe = max(dprobe, float(np.nanmax(np.abs(x - y))) / scale)
    print(f"{what}: last frame t = {fa['time']:.6g} s, {len(fa['global_id'])} particles; max |x_1 - x_N| = {dx:.3e} m, "
          f"max |p_1 - p_N| / max |p| = {dp:.3e}, probes max relative difference {dprobe:.3e}")
    if dx > a.position_tol or dp > a.pressure_tol or dprobe > a.probe_tol:
        fail(f"{what}: beyond the bounds (position {a.position_tol:g} m, pressure {a.pressure_tol:g}, probes "
             f"{a.probe_tol:g})")


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--mpsfsi", required=True)
    ap.add_argument("--mpirun", required=True, help="the launcher up to the rank count, e.g. 'mpiexec -n'")
    ap.add_argument("--case", required=True)
    ap.add_argument("--end", required=True)
    ap.add_argument("--ranks", type=int, required=True)
    ap.add_argument("--work", required=True)
    ap.add_argument("--pressure-tol", type=float, default=1e-6)
    ap.add_argument("--position-tol", type=float, default=1e-9)
    ap.add_argument("--probe-tol", type=float, default=1e-6)
    ap.add_argument("--restart", help="checkpoint time of the N-rank run to restart from")
    ap.add_argument("--restart-ranks", default="1")
    ap.add_argument("--same-file", action="append", default=[],
                    help="an output file that must be the same byte for byte (e.g. fragments.csv: fracture at the same step)")
    ap.add_argument("run_args", nargs="*")
    a = ap.parse_args()
    if os.path.exists(a.work):
        shutil.rmtree(a.work)
    os.makedirs(a.work)
    mp = shlex.split(a.mpirun)
    base = [a.mpsfsi, "run", a.case, "--quiet", "--end-time", a.end] + a.run_args
    one = os.path.join(a.work, "np1")
    many = os.path.join(a.work, f"np{a.ranks}")
    run(mp + ["1"] + base + ["--output", one])
    extra = ["--checkpoint-every", a.restart] if a.restart else []
    run(mp + [str(a.ranks)] + base + ["--output", many] + extra)
    compare(one, many, f"{a.ranks} ranks against 1", a)
    for name in a.same_file:
        with open(os.path.join(one, name), "rb") as f1, open(os.path.join(many, name), "rb") as fn:
            if f1.read() != fn.read():
                fail(f"{name} differs between 1 and {a.ranks} ranks")
        print(f"{name}: the same on 1 and {a.ranks} ranks")
    if not a.restart:
        return
    times = sorted((float(os.path.basename(c)[len("checkpoint_"):-len(".chk")]), c)
                   for c in glob.glob(os.path.join(many, "checkpoint_*.chk")))
    first = [c for t, c in times if float(a.restart) - 1e-9 <= t < float(a.end) - 1e-9]
    if not first:
        fail(f"no checkpoint between t = {a.restart} and the end in {many}: {times}")
    for m in [int(x) for x in a.restart_ranks.split(",")]:
        out = os.path.join(a.work, f"restart_np{m}")
        run(mp + [str(m), a.mpsfsi, "run", "--restart", first[0], "--quiet", "--output", out])
        compare(one, out, f"a checkpoint of {a.ranks} ranks ({os.path.basename(first[0])}) restarted on {m} rank(s)", a,
                with_probes=False)  # (the new folder's probes.csv starts at the restart)


if __name__ == "__main__":
    main()
