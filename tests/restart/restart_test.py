#!/usr/bin/python3
"""Checkpoint and restart of `mpsfsi run` (tests/restart/CMakeLists.txt registers the cases).

bitwise: a run to END without checkpoints (A) and the same run with --checkpoint-every EVERY (B) must
  write identical outputs (checkpoints do not perturb the run). Then, for the first and the last checkpoint
  before END, B is restarted in its own folder from that checkpoint (`mpsfsi run --restart FILE`, the
  case taken from the checkpoint): the folder must again equal A's exactly, i.e. every frame's point
  arrays bit for bit, the .pvd, probes.csv, interface.csv, fragments.csv and receivers.csv byte for byte. Finally a
  restart into a new folder (case file given) must write the frames after the checkpoint bit for bit and
  the CSV rows after the checkpoint time byte for byte.
cli: a checkpoint of another case, a truncated, a damaged and a non-checkpoint file, one of another
  program version, a checkpoint at the end time and a foreign non-empty output folder are refused with
  exit code 2 and a message that says what is wrong; --checkpoint-keep N keeps the newest N; --restart
  FOLDER takes the latest checkpoint of the folder.

Usage:
  restart_test.py bitwise --mpsfsi M --work DIR --case CASE --end T --every E [--mpirun CMD] [-- RUN ARGS]
  restart_test.py cli --mpsfsi M --work DIR --case CASE --other-case CASE2
"""
import argparse
import glob
import os
import re
import shlex
import shutil
import struct
import subprocess
import sys
import time
import xml.etree.ElementTree as ET

import numpy as np
import vtk
from vtk.util.numpy_support import vtk_to_numpy

CSV_FILES = ["probes.csv", "interface.csv", "fragments.csv", "receivers.csv"]


def fail(msg):
    print(f"FAIL: {msg}")
    sys.exit(1)


def run(cmd, expect=0, pattern=None):
    t0 = time.time()
    proc = subprocess.run(cmd, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True)
    print(f"$ {' '.join(shlex.quote(c) for c in cmd)}  -> exit {proc.returncode} in {time.time() - t0:.1f} s")
    if proc.returncode != expect:
        fail(f"exit code {proc.returncode}, expected {expect}; output:\n{proc.stdout}")
    if pattern and not re.search(pattern, proc.stdout, re.S):
        fail(f"output does not match '{pattern}':\n{proc.stdout}")
    return proc.stdout


def pvd_entries(folder):
    root = ET.parse(os.path.join(folder, "particles.pvd")).getroot()
    return [(e.get("timestep"), e.get("file")) for e in root.findall("./Collection/DataSet")]


def read_frame(path):
    reader = (vtk.vtkXMLPUnstructuredGridReader() if path.endswith(".pvtu")  # pieces of a run on several ranks
            else vtk.vtkXMLUnstructuredGridReader())
    reader.SetFileName(path)
    reader.Update()
    grid = reader.GetOutput()
    arrays = {"points": vtk_to_numpy(grid.GetPoints().GetData())}
    pd = grid.GetPointData()
    for k in range(pd.GetNumberOfArrays()):
        arrays[pd.GetArrayName(k)] = vtk_to_numpy(pd.GetArray(k))
    fd = grid.GetFieldData()
    for k in range(fd.GetNumberOfArrays()):
        arrays["field:" + fd.GetArrayName(k)] = vtk_to_numpy(fd.GetArray(k))
    return arrays


def compare_frames(ref_dir, ref_file, got_dir, got_file, what):
    a = read_frame(os.path.join(ref_dir, ref_file))
    b = read_frame(os.path.join(got_dir, got_file))
    if sorted(a) != sorted(b):
        fail(f"{what}: {got_file} has arrays {sorted(b)}, {ref_file} {sorted(a)}")
    for name in a:
        x, y = a[name], b[name]
        if x.shape != y.shape or x.dtype != y.dtype:
            fail(f"{what}: {got_file} array '{name}' is {y.dtype}{y.shape}, expected {x.dtype}{x.shape}")
        if x.tobytes() != y.tobytes():  # bit for bit (NaN-safe)
            diff = np.abs(x.astype(float) - y.astype(float))
            fail(f"{what}: {got_file} array '{name}' differs from {ref_file} in {np.count_nonzero(diff)} values "
                 f"(max {np.nanmax(diff):.3e})")


def compare_folders(ref, got, what):
    """got must equal ref: the series (entries and every frame's arrays) and the CSV files."""
    ea, eb = pvd_entries(ref), pvd_entries(got)
    if ea != eb:
        fail(f"{what}: {got}/particles.pvd lists {eb}, {ref}/particles.pvd {ea}")
    for _, f in ea:
        compare_frames(ref, f, got, f, what)
    for f in CSV_FILES:
        pa, pb = os.path.join(ref, f), os.path.join(got, f)
        if os.path.exists(pa) != os.path.exists(pb):
            fail(f"{what}: {f} exists in only one of {ref} and {got}")
        if os.path.exists(pa) and open(pa, "rb").read() != open(pb, "rb").read():
            fail(f"{what}: {got}/{f} differs from {ref}/{f}")
    return len(ea)


def checkpoints(folder):
    """(time, path) of the checkpoint files of a folder, by time."""
    out = []
    for p in glob.glob(os.path.join(folder, "checkpoint_*.chk")):
        out.append((float(os.path.basename(p)[len("checkpoint_"):-len(".chk")]), p))
    return sorted(out)


def fresh(path):
    if os.path.exists(path):
        shutil.rmtree(path)
    return path


def bitwise(a):
    mp = shlex.split(a.mpirun) if a.mpirun else []
    base = mp + [a.mpsfsi, "run", a.case, "--quiet", "--end-time", a.end] + a.run_args
    ref = fresh(os.path.join(a.work, "uninterrupted"))
    ck = fresh(os.path.join(a.work, "checkpointed"))
    run(base + ["--output", ref])
    run(base + ["--output", ck, "--checkpoint-every", a.every])
    n = compare_folders(ref, ck, "a run writing checkpoints")
    print(f"checkpoints do not perturb the run: {n} frames and the CSV files identical")
    cks = [(t, p) for t, p in checkpoints(ck) if t < float(a.end) - 1e-9]
    if not cks:
        fail(f"no checkpoint before the end time in {ck}")
    pristine = fresh(os.path.join(a.work, "checkpointed_copy"))
    shutil.copytree(ck, pristine)
    for t, path in sorted({cks[0], cks[-1]}):
        # As after a run killed at the end: the folder holds frames and rows after the checkpoint.
        fresh(ck)
        shutil.copytree(pristine, ck)
        out = run(mp + [a.mpsfsi, "run", "--restart", path], pattern="restart from .*continuing the folder's outputs")
        n = compare_folders(ref, ck, f"restart in place from t = {t}")
        print(f"restart in place from t = {t}: {n} frames and the CSV files bit for bit as the uninterrupted run")
    # A restart into a new folder: frames and rows after the checkpoint.
    t, path = cks[0]
    new = fresh(os.path.join(a.work, "restarted_elsewhere"))
    run(mp + [a.mpsfsi, "run", a.case, "--restart", path, "--output", new, "--quiet", "--end-time", a.end] + a.run_args)
    # The name holds the time to 9 digits; the frame at the checkpoint time is not written again.
    later = [(ts, f) for ts, f in pvd_entries(ref) if float(ts) > t + 1e-6]
    if pvd_entries(new) != later:
        fail(f"restart into {new}: the series lists {pvd_entries(new)}, expected the frames after t = {t}: {later}")
    for _, f in later:
        compare_frames(ref, f, new, f, "restart into a new folder")
    for f in CSV_FILES:
        pa, pb = os.path.join(ref, f), os.path.join(new, f)
        if not os.path.exists(pa):
            continue
        ra = open(pa).read().splitlines()
        rb = open(pb).read().splitlines()
        tail = [r for r in ra[1:] if float(r.split(",")[0]) > t + 1e-6]
        if rb[0] != ra[0] or rb[1:] != tail:
            fail(f"restart into {new}: {f} differs from the rows of {pa} after t = {t}")
    print(f"restart into a new folder from t = {t}: {len(later)} frames and the CSV rows bit for bit")
    print("OK")


def cli(a):
    src = fresh(os.path.join(a.work, "source"))
    run([a.mpsfsi, "run", a.case, "--quiet", "--output", src, "--end-time", "0.03", "--set", "dp=0.01",
         "--checkpoint-every", "0.01"])
    cks = checkpoints(src)
    ck = cks[0][1]
    other = os.path.join(a.work, "other")

    # Another case, another value of a key that must not change.
    run([a.mpsfsi, "run", a.other_case, "--restart", ck, "--output", fresh(other)], 2,
        r"checkpoint was written for case '\w+'.*differs.*name: \w+ vs \w+.*A restart may change only time.end")
    run([a.mpsfsi, "run", a.case, "--restart", ck, "--output", fresh(other), "--set", "dp=0.01", "--set",
         "gravity=[0,-9.8]", "--set", "time.cfl=0.1"], 2,
        r"differs \(checkpoint vs this run\):\s+gravity\[1\]: -9.81 vs -9.8\nA restart may change only")
    # A numerical control may change (the continuation is then another run), and is reported.
    run([a.mpsfsi, "run", a.case, "--restart", ck, "--output", fresh(other), "--set", "dp=0.01", "--set",
         "time.cfl=0.1", "--set", "fluid.preconditioner=jacobi"], 0,
        r"note: this restart changes numerical controls .*fluid.preconditioner: ssor vs jacobi\s+time.cfl: 0.2 vs 0.1")
    # Not a checkpoint, truncated, damaged.
    run([a.mpsfsi, "run", "--restart", a.case, "--output", fresh(other)], 2, r"is not an mpsfsi checkpoint")
    data = open(ck, "rb").read()
    bad = os.path.join(a.work, "bad.chk")
    open(bad, "wb").write(data[: len(data) * 2 // 3])
    run([a.mpsfsi, "run", "--restart", bad, "--output", fresh(other)], 2, r"bad.chk' is truncated: \d+ of its \d+ bytes")
    damaged = bytearray(data)
    damaged[len(data) // 2] ^= 0x01
    open(bad, "wb").write(damaged)
    run([a.mpsfsi, "run", "--restart", bad, "--output", fresh(other)], 2, r"is damaged: its checksum does not match")
    # Another program version: the version string changed (same length) and the checksum made valid again.
    (n,) = struct.unpack_from("<Q", data, 24)
    version = data[32:32 + n].decode()
    other_version = ("9" + version[1:]) if version[0] != "9" else ("8" + version[1:])
    forged = bytearray(data)
    forged[32:32 + n] = other_version.encode()
    h = 14695981039346656037
    for byte in bytes(forged[:-8]):
        h = ((h ^ byte) * 1099511628211) & 0xFFFFFFFFFFFFFFFF
    struct.pack_into("<Q", forged, len(forged) - 8, h)
    open(bad, "wb").write(forged)
    run([a.mpsfsi, "run", "--restart", bad, "--output", fresh(other)], 2,
        rf"was written by mpsfsi {re.escape(other_version)}; this is mpsfsi {re.escape(version)}")
    # At the end time of the case (the last checkpoint, written at the end).
    run([a.mpsfsi, "run", "--restart", cks[-1][1], "--output", fresh(other)], 2,
        r"not before the end time .*pass a later --end-time")
    # A non-empty folder of another run: refused, unless --overwrite.
    foreign = fresh(os.path.join(a.work, "foreign"))
    os.makedirs(foreign)
    open(os.path.join(foreign, "probes.csv"), "w").write("time,x\n0,1\n")
    run([a.mpsfsi, "run", "--restart", ck, "--output", foreign, "--quiet"], 2,
        r"is not empty and is not the run that wrote the checkpoint.*--overwrite")
    run([a.mpsfsi, "run", "--restart", ck, "--output", foreign, "--quiet", "--overwrite"], 0)
    # The refusals left the source folder alone: restarting in it (a folder: its latest checkpoint, here the
    # one at the end time 0.03) still works.
    run([a.mpsfsi, "run", "--restart", src, "--end-time", "0.04"], 0, r"restart from \S+checkpoint_0.03.chk \(t = 0.03 s")
    # --checkpoint-keep 2: the newest two.
    kept = fresh(os.path.join(a.work, "kept"))
    run([a.mpsfsi, "run", a.case, "--quiet", "--output", kept, "--end-time", "0.05", "--set", "dp=0.01",
         "--checkpoint-every", "0.01", "--checkpoint-keep", "2"])
    names = [os.path.basename(p) for _, p in checkpoints(kept)]
    if names != ["checkpoint_0.04.chk", "checkpoint_0.05.chk"]:
        fail(f"--checkpoint-keep 2 left {names}")
    print("OK")


def main():
    p = argparse.ArgumentParser()
    p.add_argument("mode", choices=["bitwise", "cli"])
    p.add_argument("--mpsfsi", required=True)
    p.add_argument("--work", required=True)
    p.add_argument("--case", required=True)
    p.add_argument("--other-case")
    p.add_argument("--end")
    p.add_argument("--every")
    p.add_argument("--mpirun", default="")
    argv = sys.argv[1:]
    cut = argv.index("--") if "--" in argv else len(argv)
    a = p.parse_args(argv[:cut])
    a.run_args = argv[cut + 1:]
    os.makedirs(a.work, exist_ok=True)
    bitwise(a) if a.mode == "bitwise" else cli(a)


if __name__ == "__main__":
    main()
