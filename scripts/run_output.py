"""Reading the output folder of an mpsfsi run, shared by the analysis scripts (hydrostatic_check.py,
density_error.py, flow_check.py): its frames (particles_NNNNNN.vtu on one rank, particles_NNNNNN.pvtu with
their pieces on several), one frame's points and point fields, the frames a --frames option picks, their
times (particles.pvd), the resolved case (case.resolved.yaml) and the probe table (probes.csv). Errors exit with a message that names the
calling script.
"""
import csv
import glob
import os
import re
import sys
import xml.etree.ElementTree as ET

import vtk
import yaml
from vtk.util.numpy_support import vtk_to_numpy


def read_frame(path):
    """Points (n x 3) and a dict of point fields of one .vtu or .pvtu frame."""
    r = vtk.vtkXMLPUnstructuredGridReader() if path.endswith(".pvtu") else vtk.vtkXMLUnstructuredGridReader()
    r.SetFileName(path)
    r.Update()
    g = r.GetOutput()
    pd = g.GetPointData()
    x = vtk_to_numpy(g.GetPoints().GetData())
    fields = {pd.GetArrayName(i): vtk_to_numpy(pd.GetArray(i)) for i in range(pd.GetNumberOfArrays())}
    return x, fields


def frame_files(run, prog):
    """The run's frames in order; exits if it has none."""
    files = sorted(f for f in glob.glob(os.path.join(run, "particles_*.*vtu"))
                   if re.fullmatch(r"particles_\d+\.p?vtu", os.path.basename(f)))
    if not files:
        sys.exit(f"{prog}: no particles_NNNNNN.vtu or .pvtu in '{run}'")
    return files


def frame_times(run, files):
    """The time of each of these frame files from the run's particles.pvd (nan where it does not say)."""
    times = {}
    try:
        for ds in ET.parse(os.path.join(run, "particles.pvd")).getroot().iter("DataSet"):
            times[os.path.basename(ds.get("file"))] = float(ds.get("timestep"))
    except (OSError, ET.ParseError):
        pass
    return [times.get(os.path.basename(f), float("nan")) for f in files]


def pick_frames(files, frames, prog):
    """The files named by a comma-separated list of frame numbers (negative from the end); all if frames is None."""
    if frames is None:
        return files
    try:
        return [files[int(k)] for k in frames.split(",")]
    except (ValueError, IndexError):
        sys.exit(f"{prog}: --frames '{frames}': expected frame numbers in [-{len(files)}, {len(files) - 1}] "
                 "separated by commas")


def read_case(run, prog):
    """The run's case.resolved.yaml as a dict."""
    path = os.path.join(run, "case.resolved.yaml")
    try:
        with open(path) as f:
            return yaml.safe_load(f)
    except OSError as e:
        sys.exit(f"{prog}: cannot read {path}: {e}")


def read_probes(run, prog):
    """The run's probes.csv as a dict of columns (lists of floats, "time" among them); exits if it is unreadable."""
    path = os.path.join(run, "probes.csv")
    try:
        with open(path, newline="") as f:
            rows = list(csv.DictReader(f))
    except OSError as e:
        sys.exit(f"{prog}: cannot read {path}: {e}")
    if not rows:
        sys.exit(f"{prog}: {path} holds no rows")
    return {k: [float(r[k]) for r in rows] for k in rows[0]}
