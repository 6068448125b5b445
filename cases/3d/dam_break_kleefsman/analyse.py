#!/usr/bin/python3
"""Water heights and box pressures of the 3D dam_break_kleefsman case (cases/3d/dam_break_kleefsman.yaml)
against the MARIN experiment of Kleefsman et al. 2005 (kleefsman_2005_marin.csv, 1 kHz).

  - pressures P1-P8: the run's probes p1-p8 (probes.csv);
  - water heights H1-H4 at (x, y) = (0.496, 0.5), (0.992, 0.5), (1.488, 0.5), (2.638, 0.5): from each frame
    (particles.pvd, .vtu or .pvtu frames), the water depth over the gauge: dp times the sum over the fluid
    particles of the tent weights (1 - |x - x_g|/dp)+ (1 - |y - y_g|/dp)+, which sum to 1 per column of a lattice
    of spacing dp wherever the gauge is. Spray thrown up over the gauge adds its (small) volume, not its height;
    dp is the run's (case.resolved.yaml).

The experiment is interpolated linearly to the run's times. For each sensor, over t in [0, T] with
T = --t-end (default 2 s) or the run's last time if shorter, it prints the RMS of run - experiment, the arrival
(first time above 0.1 rho g H = 540 Pa for pressures, 0.05 m for heights; H4, in the reservoir, is wet from
the start) and the first peak: the largest value within 0.25 s of the arrival, with its time.
The measured pressures keep their sensors' offsets (-50 to +6 Pa before the water arrives).

Usage: analyse.py RUN_FOLDER [--t-end 2.0] [--plot out.png]
Needs numpy, vtk and PyYAML (Debian's python3-*; run with /usr/bin/python3), matplotlib for --plot."""
import argparse
import csv
import os
import sys
import xml.etree.ElementTree as ET

import numpy as np

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, os.path.join(HERE, "..", "..", "..", "scripts"))
import run_output  # noqa: E402  (read_frame, read_case)

PROG = "analyse.py"
GAUGES = {"H1": (0.496, 0.5), "H2": (0.992, 0.5), "H3": (1.488, 0.5), "H4": (2.638, 0.5)}
PRESSURES = [f"P{k}" for k in range(1, 9)]  # probes p1-p8 of the case
FLUID = 0  # ParticleKind::fluid in the frames' "kind" array
ARRIVAL = {"P": 0.1 * 1000 * 9.81 * 0.55, "H": 0.05}  # [Pa], [m]
PEAK_WINDOW = 0.25  # [s] after the arrival


def read_table(path):
    """Columns of a CSV file with '#' comment lines and one header line."""
    with open(path) as f:
        rows = list(csv.reader(line for line in f if not line.startswith("#")))
    data = np.array(rows[1:], dtype=float)
    return {name: data[:, k] for k, name in enumerate(rows[0])}


def experiment():
    e = read_table(os.path.join(HERE, "kleefsman_2005_marin.csv"))
    return e["time_s"], {**{h: e[f"{h}_m"] for h in GAUGES}, **{p: e[f"{p}_Pa"] for p in PRESSURES}}


def frame(path):
    """Points and point fields of a .vtu or .pvtu frame."""
    if path.endswith(".vtu"):
        return run_output.read_frame(path)
    import vtk
    from vtk.util.numpy_support import vtk_to_numpy
    r = vtk.vtkXMLPUnstructuredGridReader()  # the pieces of a run on several ranks
    r.SetFileName(path)
    r.Update()
    g = r.GetOutput()
    pd = g.GetPointData()
    return vtk_to_numpy(g.GetPoints().GetData()), {pd.GetArrayName(i): vtk_to_numpy(pd.GetArray(i))
                                                   for i in range(pd.GetNumberOfArrays())}


def water_heights(run, dp):
    """Frame times and the heights at the gauges from the frames listed in particles.pvd."""
    pvd = os.path.join(run, "particles.pvd")
    if not os.path.isfile(pvd):
        sys.exit(f"{PROG}: no particles.pvd in '{run}'")
    sets = [(float(d.get("timestep")), os.path.join(run, d.get("file")))
            for d in ET.parse(pvd).getroot().iter("DataSet")]
    t, h = [], {g: [] for g in GAUGES}
    for time, path in sets:
        x, fields = frame(path)
        fluid = x[fields["kind"] == FLUID]
        for g, (gx, gy) in GAUGES.items():
            w = np.clip(1 - np.abs(fluid[:, 0] - gx) / dp, 0, None) * np.clip(1 - np.abs(fluid[:, 1] - gy) / dp, 0, None)
            h[g].append(dp * w.sum())
        t.append(time)
    return np.array(t), {g: np.array(v) for g, v in h.items()}


def figures(t, v, name, t_end):
    """Arrival, first peak and its time over t <= t_end (nan when the signal never arrives)."""
    w = t <= t_end
    t, v = t[w], v[w]
    above = np.nonzero(v > ARRIVAL[name[0]])[0]
    if above.size == 0:
        return np.nan, np.nan, np.nan
    arrival = t[above[0]]
    k = np.argmax(np.where((t >= arrival) & (t <= arrival + PEAK_WINDOW), v, -np.inf))
    return arrival, v[k], t[k]


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("run", help="the run's output folder (probes.csv, particles.pvd, case.resolved.yaml)")
    ap.add_argument("--t-end", type=float, default=2.0, help="end of the compared interval [s] (default 2)")
    ap.add_argument("--plot", help="write a figure of all sensors, run and experiment, to this PNG")
    a = ap.parse_args()

    dp = float(run_output.read_case(a.run, PROG)["dp"])
    te, exp = experiment()
    run = {}  # name -> (times, values)
    th, heights = water_heights(a.run, dp)
    run.update({g: (th, heights[g]) for g in GAUGES})
    probes = os.path.join(a.run, "probes.csv")
    if os.path.isfile(probes):
        p = read_table(probes)
        run.update({n: (p["time"], p[n.lower()]) for n in PRESSURES if n.lower() in p})
    else:
        print(f"{PROG}: no probes.csv in '{a.run}': pressures skipped")

    print(f"run {a.run} (dp = {dp:g} m) against Kleefsman et al. 2005 (MARIN); arrival: first value above "
          f"{ARRIVAL['P']:.0f} Pa / {ARRIVAL['H']} m, first peak: largest value within {PEAK_WINDOW} s of it")
    print("| sensor | t in | RMS run - exp | arrival run / exp [s] | first peak run | at [s] | first peak exp "
          "| at [s] |")
    print("|---|---|---|---|---|---|---|---|")
    for name, (t, v) in run.items():
        t_end = min(a.t_end, t[-1], te[-1])
        w = t <= t_end
        rms = np.sqrt(np.mean((v[w] - np.interp(t[w], te, exp[name])) ** 2))
        ar, pr, tr = figures(t, v, name, t_end)
        ae, pe, tpe = figures(te, exp[name], name, t_end)
        unit, fmt = ("m", "{:.3f}") if name[0] == "H" else ("Pa", "{:.0f}")
        print(f"| {name} | [0, {t_end:.2f}] | {fmt.format(rms)} {unit} | {ar:.3f} / {ae:.3f} | "
              f"{fmt.format(pr)} {unit} | {tr:.3f} | {fmt.format(pe)} {unit} | {tpe:.3f} |")

    if a.plot:
        import matplotlib
        matplotlib.use("Agg")
        import matplotlib.pyplot as plt
        names = list(GAUGES) + PRESSURES
        fig, axes = plt.subplots(4, 3, figsize=(15, 12), sharex=True)
        t_max = max(t[-1] for t, _ in run.values())
        for ax, name in zip(axes.T.ravel(), names):
            w = te <= t_max
            ax.plot(te[w], exp[name][w], "r-", lw=0.8, label="experiment")
            if name in run:
                ax.plot(*run[name], "k-", lw=0.8, label="run")
            ax.set_title(name)
            ax.set_ylabel("h [m]" if name[0] == "H" else "p [Pa]")
            ax.grid(True, lw=0.3)
        axes[0, 0].legend()
        for ax in axes[-1]:
            ax.set_xlabel("t [s]")
        fig.tight_layout()
        fig.savefig(a.plot, dpi=100)
        print(f"wrote {a.plot}")


if __name__ == "__main__":
    main()
