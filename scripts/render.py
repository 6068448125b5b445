#!/usr/bin/python3
"""Render frames of an mpsfsi run (.pvd series of .vtu particle files) to PNG with VTK's Python bindings.

Fluid particles are coloured by pressure, solid particles by von Mises stress, each with its own colour map
and scalar bar; wall particles are dark grey and dummy particles light grey. Particles are drawn as discs
of diameter dp (from --dp, else the run's case.resolved.yaml, else the median nearest-neighbour distance).
When a field is missing (e.g. a frame written by `mpsfsi check`), that kind is drawn in a plain colour.

3D runs (the resolved case says `dimension: 3`, or the points have a z extent) are drawn as a slice: the
particles within half a slab width (--slice-width, default 1 dp) of a plane normal to one axis, drawn in
the plane's other two axes (y: x right, z up; x: y right, z up; z: x right, y up). The default is the plane
across y through the middle of the particles' y extent (moved to the nearest layer of wall particles of the
first chosen frame, or of any particles without walls), i.e. a vertical section along the tank; --slice y=0.03 (or x=..., z=..., or just an axis
for its middle) chooses another. The title gives the plane.

Usage
  scripts/render.py --pvd out/dam_break/particles.pvd --frames -1 --output last.png
  scripts/render.py --pvd out/dam_break --frames 0,10,-1 --output 'frame_{frame:04d}.png'
  scripts/render.py --pvd out/dam_break --frames all --output movie/f_{index:04d}.png --size 1280x720
  scripts/render.py --pvd out/dam_break_3d --slice x=0.3 --output section.png     (3D: the y-z plane at x = 0.3 m)

--frames: comma-separated frame numbers (negative counts from the end), ranges a:b or a:b:step
(Python slices, end excluded), or `all`. --output: a PNG name; with several frames it may hold
{frame} (frame number in the .pvd), {index} (position among the chosen frames) or {time}, e.g.
out_{frame:04d}.png; without a placeholder, _<frame> is added before .png.
Colour ranges are common to all chosen frames (robust 0.5-99.5 percentiles) unless --pressure-range /
--stress-range is given.

Needs an X display for VTK's OpenGL window: without $DISPLAY the script re-runs itself under
`xvfb-run -a` (Debian packages xvfb, xauth); if that is not available it exits with code 77.
Exit codes: 0 success, 2 bad input, 77 no display available.
Needs Debian's python3-vtk9 (run with /usr/bin/python3 if another python3 comes first in PATH).
"""

import argparse
import math
import os
import re
import shutil
import sys
import xml.etree.ElementTree as ET

PROG = "render.py"
REEXEC_MARK = "MPSFSI_RENDER_UNDER_XVFB"


def fail(msg, code=2):
    print(f"{PROG}: error: {msg}", file=sys.stderr)
    sys.exit(code)


def ensure_display(size):
    """Re-execute under xvfb-run when there is no X display; exit 77 when that is impossible."""
    if os.environ.get("DISPLAY") or sys.platform != "linux":
        return
    if os.environ.get(REEXEC_MARK):
        fail("still no DISPLAY under xvfb-run", 77)
    xvfb = shutil.which("xvfb-run")
    missing = [p for p, found in (("xvfb-run (Debian package xvfb)", xvfb), ("xauth", shutil.which("xauth")))
               if not found]
    if missing:
        print(f"{PROG}: no X display (DISPLAY is not set) and {' and '.join(missing)} not found; "
              f"cannot render. Install them (apt-get install xvfb xauth) or run with a display.", file=sys.stderr)
        sys.exit(77)
    w, h = max(size[0], 1280), max(size[1], 1024)
    env = dict(os.environ, **{REEXEC_MARK: "1"})
    cmd = [xvfb, "-a", "-s", f"-screen 0 {w}x{h}x24", sys.executable, os.path.abspath(__file__)] + sys.argv[1:]
    sys.stdout.flush()
    sys.stderr.flush()
    os.execve(xvfb, cmd, env)


# ---------------------------------------------------------------------------------------------------
# The .pvd collection and the run folder.

def read_pvd(path):
    """Return [(time, vtu path)] in file order from a .pvd collection."""
    if os.path.isdir(path):
        path = os.path.join(path, "particles.pvd")
    if not os.path.isfile(path):
        fail(f"{path}: no such file")
    try:
        root = ET.parse(path).getroot()
    except ET.ParseError as exc:
        fail(f"{path}: not a valid .pvd (XML) file: {exc}")
    base = os.path.dirname(os.path.abspath(path))
    frames = []
    for ds in root.iter("DataSet"):
        f = ds.get("file")
        if f is None:
            continue
        try:
            t = float(ds.get("timestep", "nan"))
        except ValueError:
            t = math.nan
        frames.append((t, os.path.join(base, f)))
    if not frames:
        fail(f"{path}: the collection lists no DataSet")
    return path, frames


def select_frames(spec, n, pvd):
    """Frame numbers from e.g. '0,-1', '2:10:2', 'all'."""
    chosen = []
    for part in spec.split(","):
        part = part.strip()
        if not part:
            continue
        try:
            if part == "all":
                chosen.extend(range(n))
            elif ":" in part:
                bits = [int(b) if b.strip() else None for b in part.split(":")]
                if len(bits) > 3:
                    raise ValueError
                chosen.extend(range(n)[slice(*bits)])
            else:
                i = int(part)
                if not -n <= i < n:
                    fail(f"--frames: frame {i} does not exist; {pvd} has {n} frame{'s' if n != 1 else ''} "
                         f"(0..{n - 1}, or -1 for the last)")
                chosen.append(i % n)
        except ValueError:
            fail(f"--frames '{spec}': expected frame numbers, ranges a:b[:step] or 'all', comma-separated")
    if not chosen:
        fail(f"--frames '{spec}' selects no frame; {pvd} has {n}")
    return chosen


def run_info(pvd_dir):
    """(case name, dp, dimension) from the run's case.resolved.yaml if present (top-level keys only)."""
    name, dp, dimension = None, None, None
    path = os.path.join(pvd_dir, "case.resolved.yaml")
    if os.path.isfile(path):
        with open(path, encoding="utf-8", errors="replace") as f:
            for line in f:
                m = re.match(r"^(name|dp|dimension)\s*:\s*['\"]?([^'\"#\s]+)", line)
                if m and m.group(1) == "name":
                    name = m.group(2)
                elif m:
                    try:
                        value = float(m.group(2))
                    except ValueError:
                        continue
                    if m.group(1) == "dp":
                        dp = value
                    else:
                        dimension = int(value)
    return name, dp, dimension


def parse_slice(text):
    """(axis 0-2, value or None) from 'y=0.03' or 'y'."""
    m = re.fullmatch(r"\s*([xyz])\s*(?:=\s*(\S+)\s*)?", text or "")
    if not m:
        fail(f"--slice '{text}': expected an axis and a coordinate, e.g. y=0.03, or an axis alone (x, y or z)")
    value = None
    if m.group(2) is not None:
        try:
            value = float(m.group(2))
        except ValueError:
            fail(f"--slice '{text}': '{m.group(2)}' is not a number")
        if not math.isfinite(value):
            fail(f"--slice '{text}': expected a finite coordinate")
    return "xyz".index(m.group(1)), value


# ---------------------------------------------------------------------------------------------------

FLUID, WALL, DUMMY, SOLID = 0, 1, 2, 3
PRESSURE_NAMES = ["pressure", "p", "fluid_pressure"]
STRESS_NAMES = ["von_mises", "von_mises_stress", "vonMises", "mises", "equivalent_stress", "stress"]

# Colour maps (control points from ColorBrewer YlGnBu and YlOrRd, without their palest ends so that
# low values stay visible on a white background).
FLUID_CMAP = ["#c7e9b4", "#7fcdbb", "#41b6c4", "#1d91c0", "#225ea8", "#253494", "#081d58"]
SOLID_CMAP = ["#fed976", "#feb24c", "#fd8d3c", "#fc4e2a", "#e31a1c", "#bd0026", "#800026"]
FLUID_PLAIN = "#4a90d9"
SOLID_PLAIN = "#e8702a"
WALL_GREY = "#8c8c8c"
DUMMY_GREY = "#cfcfcf"


def rgb(hexcolor):
    h = hexcolor.lstrip("#")
    return tuple(int(h[i:i + 2], 16) / 255.0 for i in (0, 2, 4))


def parse_args(argv):
    p = argparse.ArgumentParser(description="Render frames of an mpsfsi run to PNG (VTK, off-screen).",
                                epilog="See the head of this file for details.")
    p.add_argument("--pvd", required=True, help="the run's particles.pvd (or the run folder)")
    p.add_argument("--frames", default="-1", help="frames to render: e.g. 0,-1 or 0:20:5 or all (default: -1)")
    p.add_argument("--output", "-o", required=True,
                   help="PNG file; with several frames may contain {frame}, {index}, {time}")
    p.add_argument("--size", default="1600x900", help="image size WxH in pixels (default 1600x900)")
    p.add_argument("--dp", type=float, help="particle spacing (disc diameter); default: from the run")
    p.add_argument("--point-scale", type=float, default=1.0, help="disc diameter as a multiple of dp")
    p.add_argument("--pressure-field", help="array colouring the fluid (default: pressure)")
    p.add_argument("--stress-field", help="array colouring the solid (default: von_mises)")
    p.add_argument("--pressure-range", help="fluid colour range lo,hi (default: from the data)")
    p.add_argument("--stress-range", help="solid colour range lo,hi (default: from the data)")
    p.add_argument("--supersample", type=int, choices=[1, 2, 3, 4],
                   help="render N times larger and average down (anti-aliasing; default 3, less for huge images)")
    p.add_argument("--no-dummy", action="store_true", help="do not draw dummy particles")
    p.add_argument("--title", help="title prefix (default: case name); the time is appended")
    p.add_argument("--bounds", help="view xmin,xmax,ymin,ymax (3D: in the slice's two axes; default: all particles "
                                    "of the chosen frames)")
    p.add_argument("--slice", help="3D runs: the plane drawn, AXIS=VALUE normal to axis x, y or z, e.g. y=0.03, or "
                                   "an axis alone for the middle of the particles along it (default: y through the "
                                   "middle, a vertical section along x). 3D runs are always drawn as a slice")
    p.add_argument("--slice-width", type=float, default=1.0,
                   help="3D runs: thickness of the slab around the plane whose particles are drawn, in dp (default 1: "
                        "one particle layer)")
    return p.parse_args(argv)


def parse_range(text, what):
    try:
        lo, hi = (float(v) for v in text.split(","))
    except ValueError:
        fail(f"{what} '{text}': expected lo,hi")
    if not hi > lo:
        fail(f"{what} '{text}': expected lo < hi")
    return lo, hi


def median_spacing(pts):
    """Median distance from a particle to its nearest neighbour, over up to 4000 particles (the particle size
    when neither --dp nor the run's case gives it). Points are 3D (z = 0 in 2D)."""
    import numpy as np  # imported where main() imports them, after the display is set up
    import vtk
    from vtk.util.numpy_support import numpy_to_vtk

    sample = pts if len(pts) <= 4000 else pts[np.linspace(0, len(pts) - 1, 4000).astype(int)]
    locator_pts = vtk.vtkPoints()
    locator_pts.SetData(numpy_to_vtk(np.ascontiguousarray(pts), deep=True))
    poly = vtk.vtkPolyData()
    poly.SetPoints(locator_pts)
    loc = vtk.vtkStaticPointLocator()
    loc.SetDataSet(poly)
    loc.BuildLocator()
    ids = vtk.vtkIdList()
    d = []
    for p in sample:
        loc.FindClosestNPoints(2, tuple(p), ids)
        if ids.GetNumberOfIds() == 2:
            dist = float(np.linalg.norm(pts[ids.GetId(1)] - p))
            if dist > 0:
                d.append(dist)
    return float(np.median(d)) if d else 1.0

def main(argv=None):
    args = parse_args(argv)
    m = re.fullmatch(r"\s*(\d+)\s*[xX,]\s*(\d+)\s*", args.size)
    if not m or int(m.group(1)) < 64 or int(m.group(2)) < 64:
        fail(f"--size '{args.size}': expected WxH in pixels, e.g. 1600x900")
    size = (int(m.group(1)), int(m.group(2)))
    if args.dp is not None and not args.dp > 0:
        fail(f"--dp {args.dp}: expected a positive number")
    p_range = parse_range(args.pressure_range, "--pressure-range") if args.pressure_range else None
    s_range = parse_range(args.stress_range, "--stress-range") if args.stress_range else None
    plane = parse_slice(args.slice) if args.slice is not None else None
    if not args.slice_width > 0 or not math.isfinite(args.slice_width):
        fail(f"--slice-width {args.slice_width}: expected a positive number of dp")
    view = None
    if args.bounds:
        try:
            view = [float(v) for v in args.bounds.split(",")]
            assert len(view) == 4 and view[1] > view[0] and view[3] > view[2]
        except (ValueError, AssertionError):
            fail(f"--bounds '{args.bounds}': expected xmin,xmax,ymin,ymax")

    pvd, frames = read_pvd(args.pvd)
    chosen = select_frames(args.frames, len(frames), pvd)
    for i in chosen:
        if not os.path.isfile(frames[i][1]):
            fail(f"{frames[i][1]}: no such file (frame {i} of {pvd})")
    outputs = output_names(args.output, chosen, frames)
    for out in set(outputs):
        d = os.path.dirname(os.path.abspath(out))
        if not os.path.isdir(d):
            fail(f"{out}: the folder {d} does not exist")

    ensure_display(size)  # may re-exec under xvfb-run; all input checks are done before

    try:
        import numpy as np
        import vtk
        from vtk.util.numpy_support import numpy_to_vtk, vtk_to_numpy
    except ImportError as exc:
        fail(f"{exc}; install Debian's python3-vtk9 and run with /usr/bin/python3")

    vtk.vtkObject.GlobalWarningDisplayOff()
    case_name, run_dp, run_dimension = run_info(os.path.dirname(os.path.abspath(pvd)))

    def load(path):
        reader = (vtk.vtkXMLPUnstructuredGridReader() if path.endswith(".pvtu")  # pieces of a run on several ranks
                else vtk.vtkXMLUnstructuredGridReader())
        reader.SetFileName(path)
        reader.Update()
        grid = reader.GetOutput()
        if grid is None or grid.GetNumberOfPoints() == 0 or reader.GetErrorCode() != 0:
            fail(f"{path}: cannot read particles (not a valid .vtu or no points)")
        pts = vtk_to_numpy(grid.GetPoints().GetData()).astype(float)
        pd = grid.GetPointData()
        arrays = {}
        for k in range(pd.GetNumberOfArrays()):
            a = pd.GetArray(k)
            if a is not None and a.GetName():
                v = vtk_to_numpy(a).astype(float)
                if v.ndim == 2:
                    v = np.linalg.norm(v, axis=1)  # vectors: magnitude
                arrays[a.GetName()] = v
        if "kind" not in arrays:
            fail(f"{path}: no 'kind' point array; is this an mpsfsi particle file?")
        return pts, arrays

    def pick(arrays, wanted, defaults, what, path):
        if wanted:
            if wanted not in arrays:
                fail(f"{path}: no point array '{wanted}' ({what}); arrays: {', '.join(sorted(arrays))}")
            return wanted
        return next((n for n in defaults if n in arrays), None)

    data = [load(frames[i][1]) for i in chosen]
    is_3d = run_dimension == 3 or any(np.ptp(pts[:, 2]) > 0 for pts, _ in data)
    if plane is not None and not is_3d:
        fail(f"--slice {args.slice}: {pvd} is a 2D run (drawn whole); --slice is for 3D runs")

    # Particle size.
    dp = args.dp or run_dp
    if dp is None:
        dp = median_spacing(data[0][0])
    radius = 0.5 * dp * args.point_scale

    # 3D: the particles of the slab around the plane, in the plane's two axes (right, up) and the normal.
    slice_note = ""
    if is_3d:
        axis, value = plane if plane is not None else (1, None)
        right, up = [a for a in range(3) if a != axis]
        if value is None:  # the particle layer nearest to the middle of the first frame's extent (walls' if any)
            c = data[0][0][:, axis]
            mid = 0.5 * (c.min() + c.max())
            walls = (data[0][1]["kind"] == WALL) | (data[0][1]["kind"] == DUMMY)
            layers = c[walls] if walls.any() else c
            value = float(layers[np.argmin(np.abs(layers - mid))])
        half = 0.5 * args.slice_width * dp
        sliced = []
        for pts, arrays in data:
            sel = np.abs(pts[:, axis] - value) < half
            sliced.append((np.ascontiguousarray(pts[sel][:, [right, up, axis]]),
                           {k: a[sel] for k, a in arrays.items()}))
        if not any(len(pts) for pts, _ in sliced):
            extent = ", ".join(f"[{pts[:, axis].min():.4g}, {pts[:, axis].max():.4g}]" for pts, _ in data[:1])
            fail(f"--slice {'xyz'[axis]}={value:g}: no particle within {half:g} m of the plane (the first frame's "
                 f"particles span {'xyz'[axis]} in {extent})")
        data = sliced
        slice_note = f"    slice {'xyz'[axis]} = {value:.4g} m"

    # Fields and common colour ranges.
    first_path = frames[chosen[0]][1]
    p_name = pick(data[0][1], args.pressure_field, PRESSURE_NAMES, "--pressure-field", first_path)
    s_name = pick(data[0][1], args.stress_field, STRESS_NAMES, "--stress-field", first_path)
    has_fluid = any((a["kind"] == FLUID).any() for _, a in data)
    has_solid = any((a["kind"] == SOLID).any() for _, a in data)

    def auto_range(name, kind, lo_zero):
        vals = [a[name][a["kind"] == kind] for _, a in data if name in a]
        vals = np.concatenate(vals) if vals else np.zeros(0)
        vals = vals[np.isfinite(vals)]
        if vals.size == 0:
            return 0.0, 1.0
        lo, hi = np.percentile(vals, [0.5, 99.5])
        if lo_zero and lo > -0.02 * abs(hi):  # start at 0 unless clearly negative values matter
            lo = 0.0
        if not hi > lo:
            hi = lo + max(abs(lo) * 1e-3, 1e-12) if hi == lo and lo != 0 else lo + 1.0
        return float(lo), float(hi)

    if p_name and has_fluid:
        p_range = p_range or auto_range(p_name, FLUID, True)
    else:
        if has_fluid:
            print(f"{PROG}: note: no pressure array in {first_path}; fluid drawn in plain blue", file=sys.stderr)
        p_name = None
    if s_name and has_solid:
        s_range = s_range or auto_range(s_name, SOLID, True)
    else:
        if has_solid:
            print(f"{PROG}: note: no von Mises stress array in {first_path}; solid drawn in plain orange",
                  file=sys.stderr)
        s_name = None

    # View bounds: all particles of all chosen frames (fixed for a sequence).
    if view is None:
        lo = np.min([pts[:, :2].min(axis=0) for pts, _ in data], axis=0) - radius
        hi = np.max([pts[:, :2].max(axis=0) for pts, _ in data], axis=0) + radius
        view = [lo[0], hi[0], lo[1], hi[1]]

    def make_lut(colors, rng):
        ctf = vtk.vtkColorTransferFunction()
        for k, c in enumerate(colors):
            ctf.AddRGBPoint(rng[0] + (rng[1] - rng[0]) * k / (len(colors) - 1), *rgb(c))
        lut = vtk.vtkLookupTable()
        lut.SetNumberOfTableValues(256)
        lut.SetRange(*rng)
        for k in range(256):
            lut.SetTableValue(k, *ctf.GetColor(rng[0] + (rng[1] - rng[0]) * k / 255.0), 1.0)
        lut.SetBelowRangeColor(*rgb(colors[0]), 1.0)
        lut.SetAboveRangeColor(*rgb(colors[-1]), 1.0)
        lut.UseBelowRangeColorOn()
        lut.UseAboveRangeColorOn()
        lut.Build()
        return lut

    fluid_lut = make_lut(FLUID_CMAP, p_range) if p_name else None
    solid_lut = make_lut(SOLID_CMAP, s_range) if s_name else None

    disc = vtk.vtkRegularPolygonSource()
    disc.SetNumberOfSides(24)
    disc.SetRadius(radius)
    disc.SetCenter(0, 0, 0)
    disc.SetNormal(0, 0, 1)
    disc.GeneratePolylineOff()

    # Layout: scene on the left, scalar bars on the right, title on top.
    n_bars = int(bool(p_name)) + int(bool(s_name))
    w, h = size
    title_h = min(0.1, max(0.06, 56.0 / h))
    bar_w = min(0.34, 170.0 * n_bars / w) if n_bars else 0.0
    # The scene gets the width the particles need at full height (equal aspect), and scene + bars are
    # centred; a wide picture uses the whole width left of the bars.
    need_w = (view[1] - view[0]) / (view[3] - view[2]) * (1.0 - title_h) * h * 1.04 / w
    scene_w = min(1.0 - bar_w, need_w)
    left = 0.5 * (1.0 - bar_w - scene_w)
    scene_vp = (left, 0.0, left + scene_w, 1.0 - title_h)

    win = vtk.vtkRenderWindow()
    win.SetOffScreenRendering(1)
    ss = args.supersample or max(1, min(3, 8192 // max(w, h)))  # render larger, then average down
    win.SetSize(w * ss, h * ss)
    win.SetMultiSamples(0)
    white = (1.0, 1.0, 1.0)

    backdrop = vtk.vtkRenderer()  # clears the whole window to white
    backdrop.SetBackground(*white)
    win.AddRenderer(backdrop)
    scene = vtk.vtkRenderer()
    scene.SetViewport(*scene_vp)
    scene.SetBackground(*white)
    win.AddRenderer(scene)
    top = vtk.vtkRenderer()
    top.SetViewport(0.0, 1.0 - title_h, 1.0, 1.0)
    top.SetBackground(*white)
    win.AddRenderer(top)
    side = None
    if n_bars:
        side = vtk.vtkRenderer()
        side.SetViewport(scene_vp[2], 0.0, scene_vp[2] + bar_w, 1.0 - title_h)
        side.SetBackground(*white)
        win.AddRenderer(side)

    title = vtk.vtkTextActor()
    tp = title.GetTextProperty()
    tp.SetFontSize(ss * max(14, int(round(0.5 * title_h * h))))
    tp.SetColor(0.1, 0.1, 0.1)
    tp.SetJustificationToCentered()
    tp.SetVerticalJustificationToCentered()
    title.GetPositionCoordinate().SetCoordinateSystemToNormalizedViewport()
    title.SetPosition(0.5, 0.45)
    top.AddActor2D(title)

    def unit_scale(rng):
        """(factor, unit) so that the labels of a range in Pa read well."""
        m = max(abs(rng[0]), abs(rng[1]))
        return (1e-6, "MPa") if m >= 1e6 else (1e-3, "kPa") if m >= 1e3 else (1.0, "Pa")

    def scalar_bar(lut, label, slot):
        bar = vtk.vtkScalarBarActor()
        bar.SetLookupTable(lut)
        bar.SetTitle(label)
        bar.SetNumberOfLabels(6)
        bar.SetLabelFormat("%-#.3g")
        bar.SetBarRatio(0.28)
        bar.SetUnconstrainedFontSize(True)
        bar.DrawTickLabelsOn()
        for prop, fs in ((bar.GetTitleTextProperty(), 18), (bar.GetLabelTextProperty(), 17)):
            prop.SetColor(0.1, 0.1, 0.1)
            prop.SetFontSize(int(ss * fs * max(0.8, min(1.6, h / 900.0))))
            prop.BoldOff()
            prop.ItalicOff()
            prop.ShadowOff()
        bar.GetPositionCoordinate().SetCoordinateSystemToNormalizedViewport()
        bar.SetPosition((slot + 0.1) / n_bars, 0.05)
        bar.SetWidth(0.85 / n_bars)
        bar.SetHeight(0.86)
        side.AddActor2D(bar)

    # Scalar bars show values in Pa, kPa or MPa (the lookup tables are rescaled for display only).
    def display_lut(colors, rng, name, known, what):
        if name in known:
            f, unit = unit_scale(rng)
            return make_lut(colors, (rng[0] * f, rng[1] * f)), f"{what}\n[{unit}]"
        return make_lut(colors, rng), f"{what}\n{name}"

    slot = 0
    if p_name:
        scalar_bar(*display_lut(FLUID_CMAP, p_range, p_name, PRESSURE_NAMES, "fluid\npressure"), slot)
        slot += 1
    if s_name:
        scalar_bar(*display_lut(SOLID_CMAP, s_range, s_name, STRESS_NAMES, "solid\nvon Mises"), slot)

    # Camera: parallel projection, equal aspect, fit `view` into the scene viewport.
    cx, cy = 0.5 * (view[0] + view[1]), 0.5 * (view[2] + view[3])
    vw_px = (scene_vp[2] - scene_vp[0]) * w
    vh_px = (scene_vp[3] - scene_vp[1]) * h
    half_h = 0.5 * max(view[3] - view[2], (view[1] - view[0]) * vh_px / vw_px) * 1.04
    cam = scene.GetActiveCamera()
    cam.ParallelProjectionOn()
    cam.SetFocalPoint(cx, cy, 0.0)
    cam.SetPosition(cx, cy, 10.0 * half_h + 1.0)
    cam.SetViewUp(0, 1, 0)
    cam.SetParallelScale(half_h)
    scene.ResetCameraClippingRange(view[0], view[1], view[2], view[3], -1.0, 1.0)

    group_actors = []

    def add_group(pts, values, lut, color, z):
        if len(pts) == 0:
            return
        poly = vtk.vtkPolyData()
        p3 = np.ascontiguousarray(np.column_stack([pts[:, 0], pts[:, 1], np.full(len(pts), z)]))
        vp = vtk.vtkPoints()
        vp.SetData(numpy_to_vtk(p3, deep=True))
        poly.SetPoints(vp)
        mapper = vtk.vtkGlyph3DMapper()
        mapper.SetInputData(poly)
        mapper.SetSourceConnection(disc.GetOutputPort())
        mapper.ScalingOff()
        mapper.OrientOff()
        actor = vtk.vtkActor()
        actor.SetMapper(mapper)
        prop = actor.GetProperty()
        prop.SetAmbient(1.0)
        prop.SetDiffuse(0.0)
        prop.SetSpecular(0.0)
        if lut is not None:
            arr = numpy_to_vtk(np.ascontiguousarray(values, dtype=float), deep=True)
            arr.SetName("colour")
            poly.GetPointData().SetScalars(arr)
            mapper.SetLookupTable(lut)
            mapper.SetScalarModeToUsePointData()
            mapper.SetColorModeToMapScalars()
            mapper.UseLookupTableScalarRangeOn()
            mapper.ScalarVisibilityOn()
        else:
            mapper.ScalarVisibilityOff()
            prop.SetColor(*rgb(color))
        scene.AddActor(actor)
        group_actors.append(actor)

    png = vtk.vtkPNGWriter()
    for index, (i, (pts, arrays)) in enumerate(zip(chosen, data)):
        for a in group_actors:
            scene.RemoveActor(a)
        group_actors.clear()
        kind = arrays["kind"]
        if not args.no_dummy:
            add_group(pts[kind == DUMMY], None, None, DUMMY_GREY, -0.3)
        add_group(pts[kind == WALL], None, None, WALL_GREY, -0.2)
        sel = kind == FLUID
        add_group(pts[sel], arrays[p_name][sel] if p_name and p_name in arrays else None,
                  fluid_lut if p_name and p_name in arrays else None, FLUID_PLAIN, 0.0)
        sel = kind == SOLID
        add_group(pts[sel], arrays[s_name][sel] if s_name and s_name in arrays else None,
                  solid_lut if s_name and s_name in arrays else None, SOLID_PLAIN, 0.1)

        t = frames[i][0]
        prefix = args.title if args.title is not None else (case_name or os.path.basename(os.path.dirname(
            os.path.abspath(pvd))))
        tstr = f"t = {t:.4g} s" if math.isfinite(t) else "t = ?"
        title.SetInput((f"{prefix}    {tstr}    (frame {i} of {len(frames) - 1})" if prefix else tstr) + slice_note)

        win.Render()
        grab = vtk.vtkWindowToImageFilter()
        grab.SetInput(win)
        grab.SetInputBufferTypeToRGB()
        grab.ReadFrontBufferOff()
        grab.Update()
        png.SetFileName(outputs[index])
        if ss > 1:
            shrink = vtk.vtkImageShrink3D()
            shrink.SetInputConnection(grab.GetOutputPort())
            shrink.SetShrinkFactors(ss, ss, 1)
            shrink.AveragingOn()
            shrink.Update()
            png.SetInputConnection(shrink.GetOutputPort())
        else:
            png.SetInputConnection(grab.GetOutputPort())
        png.Write()
        if png.GetErrorCode() != 0 or not os.path.isfile(outputs[index]):
            fail(f"{outputs[index]}: cannot write the PNG")
        print(f"{PROG}: wrote {outputs[index]} (frame {i}, {tstr}, {len(pts)} particles{slice_note and ' in the slice'})")
    win.Finalize()
    return 0


def output_names(pattern, chosen, frames):
    if not pattern.lower().endswith(".png"):
        fail(f"--output '{pattern}': expected a .png file name")
    has_field = re.search(r"\{(frame|index|time)(:[^}]*)?\}", pattern) is not None
    if len(chosen) > 1 and not has_field:
        pattern = pattern[:-4] + "_{frame:06d}" + pattern[-4:]
    names = []
    for index, i in enumerate(chosen):
        try:
            names.append(pattern.format(frame=i, index=index, time=frames[i][0]))
        except (KeyError, IndexError, ValueError) as exc:
            fail(f"--output '{pattern}': bad placeholder ({exc}); use {{frame}}, {{index}} or {{time}}")
    if len(set(names)) != len(names):
        fail(f"--output '{pattern}': several frames would be written to the same file")
    return names


if __name__ == "__main__":
    sys.exit(main())
