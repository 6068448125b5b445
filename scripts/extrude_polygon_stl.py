#!/usr/bin/env python3
"""Writes a closed STL surface (ASCII): a convex polygon footprint in the x-y plane extruded along z from z0 to z1,
its triangles' normals outward. The shipped cases' STL obstacles are made with it, e.g.

  scripts/extrude_polygon_stl.py cases/3d/dam_break_wedge/wedge.stl \\
      --points 0.3285,0.073 0.4015,0.0365 0.4015,0.1095 --z0 0 --z1 0.219
"""
import argparse
import sys


def cross(o, a, b):
    return (a[0] - o[0]) * (b[1] - o[1]) - (a[1] - o[1]) * (b[0] - o[0])


def main():
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("out", help="the STL file to write")
    parser.add_argument("--points", nargs="+", required=True, help="the footprint's corners x,y in metres, in order")
    parser.add_argument("--z0", type=float, required=True, help="the bottom [m]")
    parser.add_argument("--z1", type=float, required=True, help="the top [m]")
    parser.add_argument("--name", default="prism", help="the solid's name in the file")
    args = parser.parse_args()
    try:
        pts = [tuple(float(v) for v in p.split(",")) for p in args.points]
    except ValueError:
        sys.exit("--points: expected x,y pairs such as 0.1,0.2")
    if len(pts) < 3 or any(len(p) != 2 for p in pts):
        sys.exit("--points: expected at least 3 points x,y")
    if not args.z1 > args.z0:
        sys.exit("--z1 must be above --z0")
    n = len(pts)
    turns = [cross(pts[k], pts[(k + 1) % n], pts[(k + 2) % n]) for k in range(n)]
    if all(t < 0 for t in turns):
        pts.reverse()  # counter-clockwise seen from above
    elif not all(t > 0 for t in turns):
        sys.exit("--points: expected a convex polygon with distinct corners")
    bottom = [(x, y, args.z0) for x, y in pts]
    top = [(x, y, args.z1) for x, y in pts]
    tris = []
    for k in range(1, n - 1):  # fans: the bottom seen from below is clockwise from above
        tris.append((bottom[0], bottom[k + 1], bottom[k]))
        tris.append((top[0], top[k], top[k + 1]))
    for k in range(n):  # the sides, outward for a counter-clockwise footprint
        a, b = k, (k + 1) % n
        tris.append((bottom[a], bottom[b], top[b]))
        tris.append((bottom[a], top[b], top[a]))
    with open(args.out, "w") as f:
        f.write(f"solid {args.name}\n")
        for t in tris:
            f.write(" facet normal 0 0 0\n  outer loop\n")
            for v in t:
                f.write(f"   vertex {v[0]:.9g} {v[1]:.9g} {v[2]:.9g}\n")
            f.write("  endloop\n endfacet\n")
        f.write(f"endsolid {args.name}\n")
    print(f"{args.out}: {len(tris)} triangles")


if __name__ == "__main__":
    main()
