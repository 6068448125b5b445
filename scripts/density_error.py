#!/usr/bin/python3
"""The numerical compressibility of a run: in frames of an mpsfsi run (one rank), the largest and the
99th-percentile |n_i - n0| / n0 over the interior fluid particles (fluid particles not flagged free surface and more than
--depth dp, default 3, from every flagged one; frames without free-surface flags, the initial one, are
skipped), and the largest compression (n_i - n0) / n0,
n_i the number density over all particles (fluid, walls, dummies, solids) and n0 its value on the square
lattice of the case's dp. Two kernels: the projection's (Wendland's C2 at fluid.projection_radius, default 2.0
dp) and the MPS weight of eq. 7 at fluid.re_gradient (default 2.1 dp), whichever scheme ran.

Usage
  mpsfsi run cases/hydrostatic.yaml --end-time 2 --output out/hs
  scripts/density_error.py out/hs                       # every frame
  scripts/density_error.py out/hs --frames 0,20,-1      # frame numbers, negative from the end
  scripts/density_error.py out/db --summary             # one line: the largest over the frames
"""
import argparse
import os

import numpy as np
from scipy.spatial import cKDTree

from run_output import frame_files, pick_frames, read_case, read_frame

FLUID = 0  # ParticleKind::fluid in the `kind` field


def wendland(r, re):
    q = np.clip(r / re, 0.0, 1.0)
    return (1 - q) ** 4 * (1 + 4 * q)


def mps(r, re):
    r = np.maximum(r, 1e-300)
    return np.where(r < re, re / r - 1.0, 0.0)


def lattice_n0(w, dp, re, dim):
    k = int(np.ceil(re / dp)) + 1
    axes = [np.arange(-k, k + 1) * dp] * dim
    pts = np.stack(np.meshgrid(*axes, indexing="ij"), -1).reshape(-1, dim)
    r = np.linalg.norm(pts, axis=1)
    r = r[(r > 0) & (r < re)]
    return float(np.sum(w(r, re)))


def densities(x, at, w, re):
    tree = cKDTree(x)
    n = np.zeros(len(at))
    for k, i in enumerate(at):
        js = tree.query_ball_point(x[i], re)
        r = np.linalg.norm(x[js] - x[i], axis=1)
        r = r[r > 0]
        n[k] = np.sum(w(r, re))
    return n


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("run", help="output folder of a run (holding case.resolved.yaml and particles_*.vtu)")
    ap.add_argument("--frames", default=None, help="comma-separated frame numbers (default: all)")
    ap.add_argument("--depth", type=float, default=3.0,
                    help="interior: more than this many dp from every free-surface particle (default 3; 0: not flagged)")
    ap.add_argument("--summary", action="store_true", help="print only the largest values over the frames")
    args = ap.parse_args()
    prog = "density_error.py"
    files = pick_frames(frame_files(args.run, prog), args.frames, prog)
    case = read_case(args.run, prog)
    dp = float(case["dp"])
    fluid = case.get("fluid") or {}
    kernels = [("wendland", wendland, float(fluid.get("projection_radius", 2.0)) * dp),
               ("mps", mps, float(fluid.get("re_gradient", 2.1)) * dp)]
    worst = {name: (0.0, 0.0, "") for name, _, _ in kernels}
    if not args.summary:
        print("| frame | interior particles | " + " | ".join(f"{n} max / 99th / largest compression %" for n, _, _ in kernels) + " |")
        print("|---|---|" + "---|" * len(kernels))
    for f in files:
        x, fields = read_frame(f)
        dim = 3 if np.ptp(x[:, 2]) > 0 else 2
        x = x[:, :dim]
        if not np.any(fields["free_surface"] != 0):
            continue  # the initial frame: no step has flagged the free surface yet
        fluid = fields["kind"] == FLUID
        surface = fluid & (fields["free_surface"] != 0)
        interior = np.where(fluid & ~surface)[0]
        if args.depth > 0 and np.any(surface):
            d, _ = cKDTree(x[surface]).query(x[interior])
            interior = interior[d > args.depth * dp]
        cells = []
        for name, w, radius in kernels:
            if len(interior) == 0:
                cells.append("-")
                continue
            n0 = lattice_n0(w, dp, radius, dim)
            signed = 100 * (densities(x, interior, w, radius) - n0) / n0
            err = np.abs(signed)
            e_max, e_99 = float(err.max()), float(np.percentile(err, 99))
            cells.append(f"{e_max:.2f} / {e_99:.2f} / {signed.max():+.2f}")
            if e_max > worst[name][0]:
                worst[name] = (e_max, e_99, os.path.basename(f))
        if not args.summary:
            print(f"| {os.path.basename(f)} | {len(interior)} | " + " | ".join(cells) + " |")
    if args.summary:
        for name, (e_max, e_99, frame) in worst.items():
            print(f"{name}: largest interior |n - n0| / n0 {e_max:.2f} % (99th percentile {e_99:.2f} %) in {frame}")


if __name__ == "__main__":
    main()
