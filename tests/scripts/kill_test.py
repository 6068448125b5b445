"""A run killed with SIGKILL (several times, at different moments) leaves a .pvd whose every listed frame
VTK's reader opens completely: frames and the series are written to temporary names and renamed.
Usage: kill_test.py MPSFSI CASE WORKDIR"""
import os
import shutil
import signal
import subprocess
import sys
import time
import xml.etree.ElementTree as ET

import vtk


def fail(msg):
    print(f"FAIL: {msg}")
    sys.exit(1)


def check_series(out):
    pvd = os.path.join(out, "particles.pvd")
    if not os.path.exists(pvd):
        return 0
    root = ET.parse(pvd).getroot()  # raises on a half-written .pvd
    entries = root.findall("./Collection/DataSet")
    for e in entries:
        path = os.path.join(out, e.get("file"))
        reader = (vtk.vtkXMLPUnstructuredGridReader() if path.endswith(".pvtu")  # pieces of a run on several ranks
                else vtk.vtkXMLUnstructuredGridReader())
        reader.SetFileName(path)
        errors = vtk.vtkStringOutputWindow()
        vtk.vtkOutputWindow.SetInstance(errors)
        reader.Update()
        grid = reader.GetOutput()
        if reader.GetErrorCode() != 0 or errors.GetOutput().strip():
            fail(f"{path}: VTK reader error: {errors.GetOutput().strip()}")
        n = grid.GetNumberOfPoints()
        if n == 0 or grid.GetPointData().GetArray("velocity") is None:
            fail(f"{path}: incomplete frame ({n} points)")
        if grid.GetPointData().GetArray("velocity").GetNumberOfTuples() != n:
            fail(f"{path}: array length differs from the point count")
    return len(entries)


def main():
    mpsfsi, case, work = sys.argv[1:4]
    total = 0
    for k, delay in enumerate([0.4, 0.9, 1.7, 2.6]):
        out = os.path.join(work, f"killed_{k}")
        if os.path.exists(out):
            shutil.rmtree(out)
        proc = subprocess.Popen([mpsfsi, "run", case, "--quiet", "--output", out, "--end-time", "1",
                                 "--set", "output.interval=0.002"],
                                stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
        time.sleep(delay)
        if proc.poll() is not None:
            fail(f"the run ended before it could be killed (after {delay} s)")
        os.kill(proc.pid, signal.SIGKILL)
        proc.wait()
        n = check_series(out)
        print(f"killed after {delay} s: {n} complete frames listed")
        total += n
    if total == 0:
        fail("no frame was written before any kill: the test proved nothing")
    print("OK")


if __name__ == "__main__":
    main()
