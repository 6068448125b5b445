#!/usr/bin/env python3
"""MPS seismograms of a Lamb's-problem run against the exact solution (seed 000 §3, eq. 27; issue 6).

Reads RUN/case.resolved.yaml (material, sources, receivers, the block whose top edge is the free
surface) and RUN/receivers.csv (written by `mpsfsi run`), computes the analytic seismograms with
lamb2d.py for the same source time function and geometry (Cagniard-de Hoop for receivers on the
surface, the wavenumber integration for buried ones), and prints the misfit
    misfit = sum_t (S_num - S_ana)^2 / sum_t S_ana^2          (seed 000 eq. 27)
per receiver and component over the receiver's window [0, t_end(x)],
    t_end(x) = t0 + |x| / c_R + 1.5 / f0
(the Rayleigh pulse, the latest arrival, has passed; the cases' blocks are sized so that no reflection
from the block's sides or bottom reaches the receiver before t_end, cases/lamb/README.md), or over a
common window (--window T).

  /usr/bin/python3 scripts/lamb/compare.py out/lamb_a [--plot docs/img/lamb_a_300hz.png]
      [--csv misfit.csv] [--depth Z] [--window T] [--max-misfit 0.1] [--max-misfit-ux X]
      [--max-misfit-uy Y] [--label TEXT]

Exit status 1 when a misfit exceeds a --max-misfit bound (for the ctest), 2 on bad input.
The plot follows seed 000 fig. 1: analytic solid, MPS dashed, their difference x 5 dotted, one trace
per receiver (offset on the vertical axis), misfit of each trace written at its end.
"""
from __future__ import annotations

import argparse
import math
import os
import sys

import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import lamb2d  # noqa: E402


class InputError(Exception):
    pass


def load_yaml(path):
    import yaml
    with open(path, encoding="utf-8") as f:
        return yaml.safe_load(f)


def stf_of(wavelet: dict, case_dir: str) -> lamb2d.SourceTimeFunction:
    kind = wavelet["type"]
    if kind == "table":
        path = wavelet["file"]
        if not os.path.isabs(path):
            path = os.path.join(case_dir, path)
        return lamb2d.SourceTimeFunction("table", table=lamb2d.load_table(path))
    return lamb2d.SourceTimeFunction(kind, float(wavelet["frequency"]),
                                     float(wavelet["delay"]) if wavelet.get("delay") is not None else None)


def setup(run_dir: str, case_dir: str | None):
    """Medium, sources, receivers and surface of the run; raises InputError."""
    case_path = os.path.join(run_dir, "case.resolved.yaml")
    rec_path = os.path.join(run_dir, "receivers.csv")
    for p in (case_path, rec_path):
        if not os.path.isfile(p):
            raise InputError(f"{p}: no such file (run the case with `mpsfsi run CASE --output {run_dir}`)")
    case = load_yaml(case_path)
    case_dir = case_dir or os.getcwd()
    sources = case.get("sources") or []
    points = (case.get("receivers") or {}).get("points") or []
    if not sources or not points:
        raise InputError(f"{case_path}: expected a case with sources and receivers")
    body_name = points[0]["body"]
    body = next(b for b in case["bodies"] if b["name"] == body_name)
    mat = case["materials"][body["material"]]
    if "vp" not in mat:
        raise InputError(f"{case_path}: material '{body['material']}' has no vp/vs (expected wave speeds)")
    medium = lamb2d.Medium(float(mat["vp"]), float(mat["vs"]), float(mat["rho"]))
    surface = float(body["rectangle"]["max"][1])  # the block's top edge is the free surface
    srcs = []
    for s in sources:
        if s["body"] != body_name:
            raise InputError(f"source '{s['name']}' is on body '{s['body']}', the receivers on '{body_name}'")
        pos = [float(v) for v in s["position"]]
        srcs.append({"name": s["name"], "type": s["type"], "x": pos[0], "depth": surface - pos[1],
                     "direction": [float(v) for v in s.get("direction", [0, 1])],
                     "amplitude": float(s["amplitude"]), "stf": stf_of(s["wavelet"], case_dir)})
    recs = []
    for r in points:
        pos = [float(v) for v in r["position"]]
        recs.append({"name": r["name"], "x": pos[0], "depth": surface - pos[1]})
    data = np.genfromtxt(rec_path, delimiter=",", names=True)
    return case, medium, srcs, recs, data


def analytic(medium, srcs, rec, t):
    """(ux, uy) of one receiver, summed over the sources (linearity)."""
    ux = np.zeros_like(t)
    uy = np.zeros_like(t)
    for s in srcs:
        offset = rec["x"] - s["x"]
        parts = [("explosion", 1.0)] if s["type"] == "explosion" else \
            [("force_x", s["direction"][0]), ("force_y", s["direction"][1])]
        for kind, factor in parts:
            if factor == 0.0:
                continue
            if rec["depth"] == 0.0 and s["depth"] > 0.0:
                ax, ay = lamb2d.seismograms_cagniard(medium, kind, s["depth"], [offset], t, s["stf"],
                                                     amplitude=s["amplitude"] * factor)
            else:
                ax, ay = lamb2d.seismograms_wavenumber(medium, kind, s["depth"], [offset], t, s["stf"],
                                                       amplitude=s["amplitude"] * factor,
                                                       receiver_depth=rec["depth"])
            ux += ax[0]
            uy += ay[0]
    return ux, uy


def window_end(medium, srcs, rec, t_common):
    if t_common is not None:
        return t_common
    cr = lamb2d.rayleigh_speed(medium.vp, medium.vs)
    end = 0.0
    for s in srcs:
        stf = s["stf"]
        if stf.kind == "table":
            tail = float(stf.tab[-1, 0])
            end = max(end, tail + abs(rec["x"] - s["x"]) / cr)
        else:
            end = max(end, stf.t0 + abs(rec["x"] - s["x"]) / cr + 1.5 / stf.f0)
    return end


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("run", help="output folder of `mpsfsi run` (case.resolved.yaml, receivers.csv)")
    ap.add_argument("--case-dir", help="folder of the case file, for a wavelet table (default: .)")
    ap.add_argument("--window", type=float, help="common window end [s] instead of per-receiver windows")
    ap.add_argument("--depth", type=float, help="only the receivers at this depth below the surface [m]")
    ap.add_argument("--plot", help="write the seed-000-fig.-1-style figure (PNG)")
    ap.add_argument("--csv", help="write the misfit table as CSV")
    ap.add_argument("--label", default="", help="title prefix of the plot")
    ap.add_argument("--max-misfit", type=float, help="fail (exit 1) when any misfit exceeds this fraction")
    ap.add_argument("--max-misfit-ux", type=float, help="bound for the horizontal traces only")
    ap.add_argument("--max-misfit-uy", type=float, help="bound for the vertical traces only")
    args = ap.parse_args(argv)
    try:
        case, medium, srcs, recs, data = setup(args.run, args.case_dir)
    except (InputError, KeyError, StopIteration, ValueError, OSError) as e:
        print(f"compare: error: {e}", file=sys.stderr)
        return 2
    t = np.asarray(data["time"], dtype=float)
    dt = float(np.median(np.diff(t)))
    if np.max(np.abs(np.diff(t) - dt)) > 1e-6 * dt or abs(t[0]) > 1e-12:
        print("compare: error: receivers.csv needs uniform rows from t = 0 (every step or a fixed interval)",
              file=sys.stderr)
        return 2
    t = np.arange(len(t)) * dt  # exact grid for the analytic evaluation
    if args.depth is not None:
        recs = [r for r in recs if abs(r["depth"] - args.depth) < 1e-9]
        if not recs:
            print(f"compare: error: no receiver at depth {args.depth:g} m", file=sys.stderr)
            return 2
    rows = []
    traces = []
    for rec in recs:
        ana_x, ana_y = analytic(medium, srcs, rec, t)
        end = window_end(medium, srcs, rec, args.window)
        if end > t[-1] + 0.5 * dt:
            print(f"compare: warning: receiver {rec['name']}: window end {end * 1e3:.2f} ms is after the last row "
                  f"{t[-1] * 1e3:.2f} ms; using the rows available", file=sys.stderr)
        m = t <= end + 0.5 * dt
        num_x = np.asarray(data[rec["name"] + "_ux"], dtype=float)
        num_y = np.asarray(data[rec["name"] + "_uy"], dtype=float)
        mx = lamb2d.misfit(num_x[m], ana_x[m])
        my = lamb2d.misfit(num_y[m], ana_y[m])
        px = np.max(np.abs(num_x[m])) / np.max(np.abs(ana_x[m]))
        py = np.max(np.abs(num_y[m])) / np.max(np.abs(ana_y[m]))
        rows.append((rec["name"], rec["x"] - srcs[0]["x"], rec["depth"], min(end, t[-1]), mx, my, px, py))
        traces.append((rec, t[m], num_x[m], ana_x[m], num_y[m], ana_y[m], mx, my))

    print(f"{'receiver':<10} {'offset m':>8} {'depth m':>7} {'window ms':>9} {'misfit ux':>10} {'misfit uy':>10} "
          f"{'peak ux':>8} {'peak uy':>8}")
    for name, x, z, end, mx, my, px, py in rows:
        print(f"{name:<10} {x:8.2f} {z:7.2f} {end * 1e3:9.2f} {100 * mx:9.2f}% {100 * my:9.2f}% {px:8.3f} {py:8.3f}")
    print("(misfit: seed 000 eq. 27 over [0, window]; peak: max|MPS| / max|analytic|)")
    if args.csv:
        with open(args.csv, "w", encoding="utf-8") as f:
            f.write("receiver,offset,depth,window_end,misfit_ux,misfit_uy,peak_ratio_ux,peak_ratio_uy\n")
            for r in rows:
                f.write("{},{:g},{:g},{:.6g},{:.6g},{:.6g},{:.6g},{:.6g}\n".format(*r))
    if args.plot:
        plot(args.plot, case, medium, srcs, traces, args.label)

    failed = []
    for name, x, z, end, mx, my, px, py in rows:
        for comp, value, bound in (("ux", mx, args.max_misfit_ux), ("uy", my, args.max_misfit_uy)):
            limit = bound if bound is not None else args.max_misfit
            if limit is not None and not value <= limit:
                failed.append(f"{name} {comp}: misfit {value:.4f} > {limit:.4f}")
    if failed:
        print("compare: FAILED: " + "; ".join(failed), file=sys.stderr)
        return 1
    return 0


def plot(path, case, medium, srcs, traces, label):
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, axes = plt.subplots(1, 2, figsize=(10, 6.2), sharey=True)
    spacing = np.min(np.diff([tr[0]["x"] for tr in traces])) if len(traces) > 1 else 1.0
    t_max = max(tr[1][-1] for tr in traces)
    for ax, comp, title in ((axes[0], 0, "horizontal $u_x$"), (axes[1], 1, "vertical $u_y$ (up)")):
        peak = max(np.max(np.abs(tr[3 + 2 * comp])) for tr in traces)
        scale = 0.45 * spacing / peak
        for rec, t, nx, ax_, ny, ay, mx, my in traces:
            num, ana, mis = (nx, ax_, mx) if comp == 0 else (ny, ay, my)
            y0 = rec["x"]
            ax.plot(t * 1e3, y0 + scale * ana, "k-", lw=1.0)
            ax.plot(t * 1e3, y0 + scale * num, "r--", lw=0.9)
            ax.plot(t * 1e3, y0 + 5 * scale * (num - ana), "b:", lw=0.9)
            ax.plot([t[-1] * 1e3], [y0], "ko", ms=3)
            ax.text(t_max * 1e3 * 1.025, y0, f"{100 * mis:.2f} %", va="center", fontsize=8)
        ax.set_title(f"{title}; peak {peak:.3g} m")
        ax.set_xlabel("t [ms]")
        ax.set_xlim(0, t_max * 1e3 * 1.15)
        ax.grid(alpha=0.3)
    axes[0].set_ylabel("offset [m]")
    handles = [plt.Line2D([], [], color="k", ls="-", label="analytic"),
               plt.Line2D([], [], color="r", ls="--", label="MPS"),
               plt.Line2D([], [], color="b", ls=":", label="difference x 5")]
    axes[0].legend(handles=handles, loc="upper left", fontsize=8)
    s = srcs[0]
    f0 = s["stf"].f0
    re = (case.get("solid") or {}).get("re", 2.1)
    fig.suptitle(f"{label + ': ' if label else ''}Vp {medium.vp:g}, Vs {medium.vs:g} m/s, "
                 f"{s['type']} {s['depth']:g} m deep, {f0:g} Hz, dx {case['dp']:g} m, re {re:g} dx; "
                 "misfit (eq. 27) at the right", fontsize=10)
    fig.tight_layout()
    os.makedirs(os.path.dirname(os.path.abspath(path)), exist_ok=True)
    fig.savefig(path, dpi=80)
    plt.close(fig)
    print(f"wrote {path}")


if __name__ == "__main__":
    sys.exit(main())
