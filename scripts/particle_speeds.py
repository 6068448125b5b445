#!/usr/bin/python3
"""Median, 99th percentile and largest speed of the fluid particles in frames of an mpsfsi run (.vtu files of
its .pvd series), with the position of the fastest particle: how far a case is from rest (hydrostatic).

Usage
  scripts/particle_speeds.py out/hydrostatic                 # every frame
  scripts/particle_speeds.py out/hydrostatic --frames 10,-1  # frame numbers, negative from the end
"""
import argparse
import glob
import os
import sys

import numpy as np
import vtk
from vtk.util.numpy_support import vtk_to_numpy

FLUID = 0  # ParticleKind::fluid in the `kind` field


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("run", help="output folder of a run (holding particles_*.vtu)")
    ap.add_argument("--frames", default=None, help="comma-separated frame numbers (default: all)")
    args = ap.parse_args()
    files = sorted(glob.glob(os.path.join(args.run, "particles_*.vtu")))
    if not files:
        sys.exit(f"particle_speeds.py: no particles_*.vtu in '{args.run}'")
    if args.frames:
        try:
            files = [files[int(k)] for k in args.frames.split(",")]
        except (ValueError, IndexError):
            sys.exit(f"particle_speeds.py: --frames '{args.frames}': expected frame numbers in "
                     f"[-{len(files)}, {len(files) - 1}] separated by commas")
    print("frame, median [m/s], 99th percentile [m/s], max [m/s], x of max [m], y of max [m]")
    for f in files:
        reader = (vtk.vtkXMLPUnstructuredGridReader() if f.endswith(".pvtu")  # pieces of a run on several ranks
                else vtk.vtkXMLUnstructuredGridReader())
        reader.SetFileName(f)
        reader.Update()
        grid = reader.GetOutput()
        data = grid.GetPointData()
        x = vtk_to_numpy(grid.GetPoints().GetData())[:, :2]
        fluid = vtk_to_numpy(data.GetArray("kind")) == FLUID
        speed = np.linalg.norm(vtk_to_numpy(data.GetArray("velocity"))[:, :2], axis=1)[fluid]
        k = int(np.argmax(speed))
        print(f"{os.path.basename(f)}, {np.median(speed):.4f}, {np.percentile(speed, 99):.4f}, {speed[k]:.4f}, "
              f"{x[fluid][k, 0]:.3f}, {x[fluid][k, 1]:.3f}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
