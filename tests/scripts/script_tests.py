"""Driver of the ctest tests of scripts/plot_probes.py, scripts/render.py, scripts/sweep.py with
scripts/flow_check.py, scripts/hydrostatic_check.py and cases/dam_break_lobovsky/analyse.py (see tests/scripts/CMakeLists.txt; render-3d:
tests/dim3/CMakeLists.txt, the 3D build)."""
import os
import re
import shutil
import struct
import subprocess
import sys


def fail(msg):
    print(f"FAIL: {msg}")
    sys.exit(1)


def run(cmd, env=None):
    print("+ " + " ".join(cmd), flush=True)
    r = subprocess.run(cmd, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True, env=env)
    print(r.stdout, end="", flush=True)
    return r.returncode, r.stdout


def png_size(path):
    if not os.path.isfile(path) or os.path.getsize(path) == 0:
        fail(f"{path}: missing or empty")
    with open(path, "rb") as f:
        head = f.read(24)
    if head[:8] != b"\x89PNG\r\n\x1a\n" or head[12:16] != b"IHDR":
        fail(f"{path}: not a PNG file")
    return struct.unpack(">II", head[16:24])


def expect_error(cmd, code, words):
    rc, out = run(cmd)
    if rc != code:
        fail(f"exit code {rc}, expected {code}")
    for w in words:
        if w not in out:
            fail(f"message does not name '{w}'")


def test_plot(python, script, work):
    os.makedirs(work, exist_ok=True)
    probes = os.path.join(work, "probes.csv")
    ref = os.path.join(work, "reference.tsv")
    with open(probes, "w") as f:
        f.write("time,front,height,p_bottom_right\n")
        for i in range(81):
            t = 0.005 * i
            f.write(f"{t:.9g},{0.146 + 0.9 * t * t:.9g},{0.292 - 0.5 * t * t:.9g},{2800 - 1500 * t:.9g}\n")
    with open(ref, "w") as f:
        f.write("# synthetic reference: Z = x/L against T = t sqrt(2g/L)\n# second comment line\n")
        f.write("T\tZ\n1.0\t1.3\n2.0\t2.2\n3.0\t3.4\n")
    out = os.path.join(work, "probes_vs_reference.png")
    if os.path.exists(out):
        os.remove(out)
    rc, _ = run([python, script, probes, "--output", out, "--reference", ref, "--ref-columns", "T,Z",
                 "--x-expr", "time*sqrt(2*g/L)", "--y-expr", "y/L", "--const", "L=0.146", "g=9.81",
                 "--ref-target", "front"])
    if rc != 0:
        fail(f"plot_probes.py exited {rc}")
    w, h = png_size(out)
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    img = plt.imread(out)
    if img.shape[0] != h or img.shape[1] != w:
        fail(f"{out}: decoded size {img.shape} differs from the header {w}x{h}")
    dark = (img[:, :, :3].sum(axis=2) < 1.5).mean()
    if dark < 0.002:
        fail(f"{out}: the picture is (almost) blank ({dark:.4%} dark pixels)")
    print(f"{out}: {w}x{h} PNG, {dark:.2%} dark pixels")
    out2 = os.path.join(work, "all_columns.png")
    rc, _ = run([python, script, probes, "--output", out2])
    if rc != 0:
        fail(f"plot_probes.py exited {rc}")
    png_size(out2)

    missing = os.path.join(work, "no_such_probes.csv")
    expect_error([python, script, missing, "--output", out2], 2, ["no_such_probes.csv"])
    expect_error([python, script, probes, "--columns", "front,bogus_column", "--output", out2], 2, ["bogus_column"])
    expect_error([python, script, probes, "--reference", ref, "--ref-columns", "T,nosuch", "--output", out2], 2,
                 ["nosuch", "reference.tsv"])
    expect_error([python, script, probes, "--reference", os.path.join(work, "no_ref.tsv"), "--output", out2], 2,
                 ["no_ref.tsv"])
    expect_error([python, script, probes, "--y-expr", "__import__('os')", "--output", out2], 2, ["not allowed"])
    print("OK")


def test_render(python, script, mpsfsi, case, work):
    if os.path.exists(work):
        shutil.rmtree(work)
    # A real (short) run: the last frame has pressures.
    rc, _ = run([mpsfsi, "run", case, "--end-time", "0.04", "--quiet", "--output", work])
    if rc != 0:
        fail(f"mpsfsi run exited {rc}")
    pvd = os.path.join(work, "particles.pvd")
    out = os.path.join(work, "frame0.png")
    rc, _ = run([python, script, "--pvd", pvd, "--frames", "-1", "--output", out, "--size", "640x480"])
    if rc == 77:
        print("SKIP: render.py found no X display and no xvfb-run (install Debian's xvfb and xauth)")
        sys.exit(77)
    if rc != 0:
        fail(f"render.py exited {rc}")
    w, h = png_size(out)
    if (w, h) != (640, 480):
        fail(f"{out}: size {w}x{h}, expected 640x480")
    import numpy as np
    import vtk
    from vtk.util.numpy_support import vtk_to_numpy
    reader = vtk.vtkPNGReader()
    reader.SetFileName(out)
    reader.Update()
    img = vtk_to_numpy(reader.GetOutput().GetPointData().GetScalars()).astype(int)[:, :3]
    background = (img >= 250).all(axis=1)
    share = 1.0 - background.mean()
    blue = ((img[:, 2] - img[:, 0]) > 60).mean()   # fluid particles (plain blue without a pressure field)
    grey = ((abs(img[:, 0] - img[:, 2]) < 8) & (img[:, 0] < 235) & (img[:, 0] > 60)).mean()  # walls
    print(f"{out}: {w}x{h} PNG, {share:.2%} non-background, {blue:.2%} blue, {grey:.2%} grey pixels")
    if share < 0.02 or blue < 0.01 or grey < 0.002:
        fail(f"{out}: too few particle pixels")
    expect_error([python, script, "--pvd", os.path.join(work, "none.pvd"), "--output", out], 2, ["none.pvd"])
    expect_error([python, script, "--pvd", pvd, "--frames", "5", "--output", out], 2, ["frame 5"])
    print("OK")


def test_render_3d(python, script, mpsfsi, case, work):
    """A 3D run (the 3D build) is drawn as a slice: by default across y through the middle, or the plane of --slice."""
    if os.path.exists(work):
        shutil.rmtree(work)
    rc, _ = run([mpsfsi, "run", case, "--end-time", "0.02", "--quiet", "--output", work])
    if rc != 0:
        fail(f"mpsfsi run exited {rc}")
    pvd = os.path.join(work, "particles.pvd")
    out = os.path.join(work, "slice.png")
    rc, text = run([python, script, "--pvd", pvd, "--output", out, "--size", "640x480"])
    if rc == 77:
        print("SKIP: render.py found no X display and no xvfb-run (install Debian's xvfb and xauth)")
        sys.exit(77)
    if rc != 0:
        fail(f"render.py exited {rc}")
    if (w_h := png_size(out)) != (640, 480):
        fail(f"{out}: size {w_h}, expected 640x480")
    if "in the slice" not in text:
        fail("render.py does not say it drew a slice")
    out_x = os.path.join(work, "slice_x.png")
    rc, _ = run([python, script, "--pvd", pvd, "--slice", "x=0.05", "--output", out_x, "--size", "640x480"])
    if rc != 0:
        fail(f"render.py --slice x=0.05 exited {rc}")
    png_size(out_x)
    expect_error([python, script, "--pvd", pvd, "--slice", "y=5", "--output", out], 2, ["y=5", "no particle"])
    expect_error([python, script, "--pvd", pvd, "--slice", "w=5", "--output", out], 2, ["--slice 'w=5'"])
    print("OK")


def test_render_no_display(python, script, work):
    os.makedirs(work, exist_ok=True)
    env = {k: v for k, v in os.environ.items() if k not in ("DISPLAY", "WAYLAND_DISPLAY")}
    env["PATH"] = os.path.join(work, "empty_path")  # no xvfb-run to be found
    pvd = os.path.join(work, "one.pvd")
    with open(pvd, "w") as f:
        f.write('<?xml version="1.0"?>\n<VTKFile type="Collection" version="0.1"><Collection>\n'
                '<DataSet timestep="0" file="one_000000.vtu"/></Collection></VTKFile>\n')
    open(os.path.join(work, "one_000000.vtu"), "w").close()
    rc, out = run([python, script, "--pvd", pvd, "--output", os.path.join(work, "x.png")], env=env)
    if rc != 77 or "xvfb-run" not in out:
        fail(f"exit code {rc}, expected 77 and a message naming xvfb-run")
    print("OK")


def test_sweep(python, scripts, mpsfsi, case, work):
    """sweep.py runs a case at two dp and tabulates them; flow_check.py on one of the runs passes a bound that holds
    and fails one that does not, naming it; bad arguments are refused."""
    shutil.rmtree(work, ignore_errors=True)
    sweep, check = os.path.join(scripts, "sweep.py"), os.path.join(scripts, "flow_check.py")
    rc, out = run([python, sweep, case, "--dp", "0.008,0.006", "--out", work, "--mpsfsi", mpsfsi, "--until", "0.01",
                   "--measure", "echo measured {run}", "--", "--end-time", "0.02", "--set", "output.interval=0.01"])
    if rc != 0:
        fail(f"sweep.py exited {rc}")
    with open(os.path.join(work, "sweep.csv")) as f:
        rows = [line.rstrip("\n").split(",") for line in f]
    if len(rows) != 3 or [r[0] for r in rows[1:]] != ["0.008", "0.006"] or any(r[1] != "0" for r in rows[1:]):
        fail(f"sweep.csv: expected two runs that exited 0, got {rows}")
    if not all(r[-1].startswith("measured ") for r in rows[1:]) or "| 0.006 | 0 |" not in out:
        fail("the table lacks the runs or the measure column")
    run_dir = os.path.join(work, "dp_0.006")
    rc, _ = run([python, check, run_dir, "--max-speed", "10", "--max-p999", "1e5"])
    if rc != 0:
        fail(f"flow_check.py exited {rc} on bounds that hold")
    expect_error([python, check, run_dir, "--frames", "-1", "--max-speed", "1e-6"], 1, ["largest fluid speed"])
    expect_error([python, check, run_dir, "--frames", "-1", "--min-pressure-at", "0.003,0.003,1e9"], 1, ["pressure"])
    expect_error([python, check, run_dir, "--min-pressure-at", "1,2"], 1, ["--min-pressure-at", "X,Y,P"])
    expect_error([python, sweep, case, "--dp", "0.004,-1", "--out", work], 1, ["--dp", "positive spacings"])


def test_lobovsky(python, script, work):
    """analyse.py on probes.csv files made from known signals: the experiment's own record in the program's
    units (the same figures as the experiment's row), and a step with a 1 kHz ripple of amplitude 0.1 rho g H
    (noise figure 0.1 / sqrt(2): the 5 ms average spans five periods)."""
    import math

    os.makedirs(work, exist_ok=True)
    H, rho, g = 0.3, 1000.0, 9.81
    record = os.path.join(os.path.dirname(script), "lobovsky_2014_h300_event5.csv")
    rows = [line.split(",") for line in open(record) if line[0].isdigit()]
    same = os.path.join(work, "same.csv")
    with open(same, "w") as f:
        f.write("time,front,p1,p2,p3,p4\n")
        for r in rows:
            t = float(r[0]) / math.sqrt(g / H)
            f.write(f"{t!r},0," + ",".join(repr(float(v) * rho * g * H) for v in r[1:5]) + "\n")
    ripple = os.path.join(work, "ripple.csv")
    with open(ripple, "w") as f:
        f.write("time,front,p1,p2,p3,p4\n")
        for k in range(15000):
            t = k * 1e-4
            p = (1.0 + 0.1 * math.sin(2 * math.pi * 1000 * t + 0.3)) if t * math.sqrt(g / H) > 1.5 else 0.0
            f.write(f"{t!r},0," + ",".join([repr(p * rho * g * H)] * 4) + "\n")
    rc, out = run([python, script, same, ripple, "--label", "same", "ripple"])
    if rc != 0:
        fail(f"exit code {rc}")
    lines = [line for line in out.splitlines() if line.startswith("| ")]
    experiment = [line.split("|")[2:] for line in lines if line.startswith("| experiment")]
    copy = [line.split("|")[2:] for line in lines if line.startswith("| same")]
    if len(experiment) != 4 or experiment != copy:
        fail(f"the record in the program's units does not give the experiment's figures: {experiment} vs {copy}")
    for line in (line for line in lines if line.startswith("| ripple")):
        cells = [c.strip() for c in line.split("|")]
        noise = float(cells[-2])
        if abs(noise - 0.1 / math.sqrt(2)) > 0.002:
            fail(f"ripple noise {noise}, expected {0.1 / math.sqrt(2):.4f}")
        if abs(float(cells[3]) - 1.1) > 0.002:
            fail(f"ripple first peak {cells[3]}, expected 1.1")
    print("OK")


def test_hydrostatic(python, script, work):
    """hydrostatic_check.py on a frame made by hand: water 0.1 m deep on a 10 x 10 lattice (dp 0.01 m) at the exact
    hydrostatic pressure but one particle 10 % over it, still but the block of the top right corner (the 2 x 2 map's
    top right block, 25 particles) moving at (1, -2) mm/s and one particle of it at (1, -2) + (3, 4) mm/s."""
    import math

    import numpy as np
    import vtk
    from vtk.util.numpy_support import numpy_to_vtk

    shutil.rmtree(work, ignore_errors=True)
    os.makedirs(work)
    rho, g, dp, h = 1000.0, 9.81, 0.01, 0.1
    with open(os.path.join(work, "case.resolved.yaml"), "w") as f:
        f.write(f"dp: {dp}\ngravity: [0, -{g}]\nmaterials:\n  water: {{rho: {rho}}}\n"
                f"bodies:\n  - name: water\n    kind: fluid\n    material: water\n"
                f"    rectangle: {{min: [0, 0], max: [{h}, {h}]}}\n")
    c = (np.arange(10) + 0.5) * dp
    x = np.array([[a, b, 0.0] for b in c for a in c])
    p = rho * g * (h - x[:, 1])
    v = np.zeros_like(x)
    corner = (x[:, 0] > h / 2) & (x[:, 1] > h / 2)
    v[corner, :2] = [1e-3, -2e-3]
    odd = int(np.flatnonzero(corner)[0])
    v[odd, :2] += [3e-3, 4e-3]
    deep = 12  # 1.25 dp above the floor: deeper than 3 dp below the surface
    p[deep] *= 1.1
    grid = vtk.vtkUnstructuredGrid()
    points = vtk.vtkPoints()
    points.SetData(numpy_to_vtk(x, deep=True))
    grid.SetPoints(points)
    for name, values in (("kind", np.zeros(len(x), np.int32)), ("pressure", p), ("velocity", v)):
        array = numpy_to_vtk(values, deep=True)
        array.SetName(name)
        grid.GetPointData().AddArray(array)
    writer = vtk.vtkXMLUnstructuredGridWriter()
    writer.SetFileName(os.path.join(work, "particles_000000.vtu"))
    writer.SetInputData(grid)
    if writer.Write() != 1:
        fail("cannot write the frame")
    rc, out = run([python, script, work, "--map", "2"])
    if rc != 0:
        fail(f"exit code {rc}")
    row = [line for line in out.splitlines() if line.startswith("| particles_000000.vtu")]
    if len(row) != 1:
        fail("no table row for the frame")
    cells = [cell.strip() for cell in row[0].split("|")[1:-1]]
    fastest = math.hypot(4e-3, 2e-3) / math.sqrt(g * h) * 100
    if cells[1] != "100" or cells[2] != "1.0000" or abs(float(cells[3]) - fastest) > 1e-3:
        fail(f"count, top or largest speed wrong: {cells}, expected 100, 1.0000, {fastest:.3f}")
    if cells[6] != "10.00 / 0.00":
        fail(f"pressure error {cells[6]}, expected 10.00 / 0.00")
    rms = math.sqrt(24 * (0.12e-3 ** 2 + 0.16e-3 ** 2) + (2.88e-3 ** 2 + 3.84e-3 ** 2)) / 5 * 1e3  # mm/s
    lines = out.splitlines()
    at = [k for k, line in enumerate(lines) if line.startswith("particles_000000.vtu: mean velocity")]
    if len(at) != 1:
        fail("no map for the frame")
    top, bottom = ([float(v) for v in re.findall(r"[-+]?\d+\.\d", lines[at[0] + k])] for k in (1, 2))
    if top != [0.0, 0.0, 0.0, 1.1, -1.8, round(rms, 1)] or bottom != [0.0] * 6:
        fail(f"the map's rows {top} and {bottom}, expected one block at 1.1, -1.8 mm/s, rms {rms:.1f}, the rest still")
    print("OK")


if __name__ == "__main__":
    what = sys.argv[1]
    if what == "plot":
        test_plot(*sys.argv[2:5])
    elif what == "render":
        test_render(*sys.argv[2:7])
    elif what == "render-3d":
        test_render_3d(*sys.argv[2:7])
    elif what == "render-no-display":
        test_render_no_display(*sys.argv[2:5])
    elif what == "lobovsky":
        test_lobovsky(*sys.argv[2:5])
    elif what == "hydrostatic":
        test_hydrostatic(*sys.argv[2:5])
    elif what == "sweep":
        test_sweep(*sys.argv[2:7])
    else:
        fail(f"unknown test {what}")
