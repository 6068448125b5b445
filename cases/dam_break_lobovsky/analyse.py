#!/usr/bin/env python3
"""Impact pressures of the dam_break_lobovsky case (cases/dam_break_lobovsky.yaml) against the experiment of
Lobovsky et al. 2014 (H = 300 mm; lobovsky_2014_h300_event5.csv, one repetition of the experiment, sampled
at 20 kHz). For each sensor p1-p4 (3, 15, 30, 80 mm above the floor), in units of rho g H and
t* = t sqrt(g/H):
  - the first peak: the largest pressure within 1 (t* units) of the first arrival (p > 0.1 rho g H),
    its time, and the arrival time;
  - the history: the mean pressure over the windows t* in [3, 4], [4, 5], [5, 6], [6, 7];
  - the noise figure: the RMS of the signal minus its 5 ms centred moving average over t* in [2, 7], as a
    fraction of rho g H (the experiment's own figure is printed too: it holds the sensors' noise and the
    flow's real fluctuations).
Usage: analyse.py probes.csv [more probes.csv ...] [--label NAME ...]
The probes need rows every ~0.1 ms (output.probe_interval of the case)."""
import argparse
import csv
import math
import os

import numpy as np

H, RHO, G = 0.3, 1000.0, 9.81
T_SCALE = math.sqrt(G / H)  # t* = t T_SCALE
P_SCALE = RHO * G * H
HERE = os.path.dirname(os.path.abspath(__file__))
SENSORS = ["p1", "p2", "p3", "p4"]
WINDOWS = [(3, 4), (4, 5), (5, 6), (6, 7)]


def experiment():
    rows = np.loadtxt(os.path.join(HERE, "lobovsky_2014_h300_event5.csv"), delimiter=",", comments="#", skiprows=6)
    return rows[:, 0], {s: rows[:, k + 1] for k, s in enumerate(SENSORS)}


def simulation(path):
    with open(path) as f:
        rows = list(csv.DictReader(f))
    t = np.array([float(r["time"]) for r in rows]) * T_SCALE
    return t, {s: np.array([float(r[s]) for r in rows]) / P_SCALE for s in SENSORS}


def moving_average(t, p, width):
    """Centred moving average over `width` (t* units) on a uniform grid of the signal."""
    dt = np.median(np.diff(t))
    n = max(1, int(round(width / dt)))
    kernel = np.ones(n) / n
    return np.convolve(p, kernel, mode="same"), n


def figures(t, p):
    arrive = np.argmax(p > 0.1) if np.any(p > 0.1) else None
    out = {}
    if arrive is None:
        out["arrival"] = out["peak_t"] = out["peak"] = float("nan")
    else:
        w = (t >= t[arrive]) & (t <= t[arrive] + 1.0)
        k = np.argmax(np.where(w, p, -np.inf))
        out["arrival"], out["peak_t"], out["peak"] = t[arrive], t[k], p[k]
    out["means"] = [float(np.mean(p[(t >= a) & (t < b)])) if np.any((t >= a) & (t < b)) else float("nan") for a, b in WINDOWS]
    avg, n = moving_average(t, p, 0.005 * T_SCALE)
    w = (t >= 2) & (t <= 7)
    w[: n // 2 + 1] = False
    w[len(w) - n // 2 - 1:] = False
    out["noise"] = float(np.sqrt(np.mean((p[w] - avg[w]) ** 2))) if np.any(w) else float("nan")
    return out


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("probes", nargs="+")
    ap.add_argument("--label", nargs="*", default=[])
    a = ap.parse_args()
    labels = a.label + [os.path.basename(os.path.dirname(os.path.abspath(p))) for p in a.probes[len(a.label):]]
    series = [("experiment (event 5)",) + experiment()] + [(l,) + simulation(p) for l, p in zip(labels, a.probes)]
    print("p* = p / (rho g H), t* = t sqrt(g / H), H = 0.3 m; first peak within 1 of the arrival (p* > 0.1);")
    print("history: mean p* over t* windows; noise: RMS of p* minus its 5 ms moving average over t* in [2, 7]")
    for s in SENSORS:
        print(f"\n{s}:")
        print("| series | arrival t* | first peak p* | at t* | " + " | ".join(f"mean [{a}, {b}]" for a, b in WINDOWS) + " | noise |")
        print("|---|---|---|---|" + "---|" * len(WINDOWS) + "---|")
        for label, t, p in series:
            f = figures(t, p[s])
            print(f"| {label} | {f['arrival']:.3f} | {f['peak']:.3f} | {f['peak_t']:.3f} | " +
                  " | ".join(f"{m:.3f}" for m in f["means"]) + f" | {f['noise']:.4f} |")


if __name__ == "__main__":
    main()
