#!/usr/bin/env python3
"""Spalling of the Hopkinson bar (cases/hopkinson_bar*.yaml, seed 000 §4) from fragments.csv: the time
of the first fracture (first output with more than one fragment) and, at the last output, every
fragment other than the main one, with its length (particles / 11 rows x dp) and centroid.
Usage: analyse.py fragments.csv [more fragments.csv ...]"""
import csv
import sys

ROWS, DP = 11, 1.0e-3   # 301 x 11 particles, dp = 1 mm


def analyse(path):
    frames = {}
    with open(path) as f:
        for r in csv.DictReader(f):
            frames.setdefault(float(r["time"]), []).append(r)
    times = sorted(frames)
    first = next((t for t in times if int(frames[t][0]["n_fragments"]) > 1), None)
    last = frames[times[-1]]
    pieces = sorted((r for r in last if r["fragment"] != "0"), key=lambda r: -float(r["centroid_x"]))
    end_piece = pieces[0] if pieces else None
    print(f"{path}: first fracture at t = {first * 1e3:.3f} ms" if first is not None else f"{path}: no fracture")
    print(f"  at t = {times[-1] * 1e3:.3f} ms: {len(last)} fragments; pieces other than the main bar (largest x first):")
    for r in pieces:
        n = int(r["particles"])
        print(f"    fragment {r['fragment']}: {n} particles (length {1e3 * n / ROWS * DP:.1f} mm), centroid x = "
              f"{1e3 * float(r['centroid_x']):.1f} mm")
    if end_piece:
        print(f"  spalled end piece: {1e3 * int(end_piece['particles']) / ROWS * DP:.1f} mm long")
    return first, end_piece


if __name__ == "__main__":
    for p in sys.argv[1:]:
        analyse(p)
