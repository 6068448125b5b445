#!/usr/bin/python3
"""Runs one case at a list of particle spacings and tabulates, per dp, what a resolution study needs: the exit
code, steps and wall time, the smallest dt and the limit that set it (run.jsonl's summary), the fluid particles
removed and put back out of a wall, and from the frames (scripts/flow_check.py's figures) the largest fluid speed and 99.9th percentile
pressure up to --until and the most fluid particles ever inside a wall. --measure adds a column per command:
the last line of its output, with {run} replaced by the run's folder (e.g. an analyse.py of the case).

Usage
  scripts/sweep.py cases/dam_break.yaml --dp 0.004,0.002,0.0016 --out out/sweep -- --end-time 1.0
  scripts/sweep.py cases/dam_break.yaml --dp 0.0008,0.00065 --ranks 2 --until 0.15 --out out/sweep_fine \\
      -- --end-time 0.3 --set output.interval=0.01
  scripts/sweep.py cases/hydrostatic.yaml --dp 0.005,0.0025 --out out/hs \\
      --measure "scripts/hydrostatic_check.py {run} --frames -1" -- --end-time 2

Everything after -- goes to `mpsfsi run` unchanged. The table is printed as Markdown and written to OUT/sweep.csv.
"""
import argparse
import csv
import json
import math
import os
import shlex
import subprocess
import sys
import time

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from flow_check import frame_health, tank_boxes  # noqa: E402
from run_output import frame_files, frame_times, read_case, read_frame  # noqa: E402

PROG = "sweep.py"
ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))


def summary_of(run):
    """The last summary event of the run's run.jsonl, or {}."""
    found = {}
    try:
        with open(os.path.join(run, "run.jsonl")) as f:
            for line in f:
                try:
                    event = json.loads(line)
                except ValueError:
                    continue
                if event.get("event") == "summary":
                    found = event
    except OSError:
        pass
    return found


def frames_of(run, until):
    """Largest speed and 99.9th percentile pressure over the frames at t <= until, most particles ever inside a wall."""
    files = frame_files(run, PROG)
    times = frame_times(run, files)
    boxes = tank_boxes(read_case(run, PROG))
    speed = p999 = 0.0
    out = None
    for f, t in zip(files, times):
        h = frame_health(*read_frame(f), boxes)
        if until is None or not t > until:
            speed = max(speed, h["speed"])
            p999 = max(p999, h["p999"])
        if h["outside"] is not None:
            out = max(out or 0, h["outside"])
    return speed, p999, out


def main():
    argv = sys.argv[1:]
    extra = []
    if "--" in argv:
        k = argv.index("--")
        argv, extra = argv[:k], argv[k + 1:]
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("case", help="case file")
    ap.add_argument("--dp", required=True, help="comma-separated particle spacings [m]")
    ap.add_argument("--out", required=True, help="folder of the runs (OUT/dp_<dp>) and of sweep.csv")
    ap.add_argument("--mpsfsi", default=os.path.join(ROOT, "build", "mpsfsi"), help="the program (default build/mpsfsi)")
    ap.add_argument("--ranks", type=int, default=1, help="MPI ranks of each run (default 1)")
    ap.add_argument("--until", type=float, default=None, help="speed and pressure over the frames at t <= this [s]")
    ap.add_argument("--measure", action="append", default=[], help="a command with {run}; its last output line is a column")
    args = ap.parse_args(argv)
    try:
        dps = [float(v) for v in args.dp.split(",")]
        assert dps and all(d > 0 and math.isfinite(d) for d in dps)
    except (ValueError, AssertionError):
        sys.exit(f"{PROG}: --dp '{args.dp}': expected positive spacings in metres separated by commas")
    if args.ranks < 1:
        sys.exit(f"{PROG}: --ranks {args.ranks}: expected at least 1")
    os.makedirs(args.out, exist_ok=True)
    head = ["dp [m]", "exit", "steps", "wall [s]", "smallest dt [s]", "its limit", "at t [s]", "removed",
            "put back", "max speed [m/s]", "p99.9 max [Pa]", "in a wall max"] + [f"measure {i + 1}" for i in range(len(args.measure))]
    rows = []
    for dp in dps:
        run = os.path.join(args.out, f"dp_{dp:g}")
        cmd = [args.mpsfsi, "run", args.case, "--dp", repr(dp), "--output", run, "--overwrite", "--quiet"] + extra
        if args.ranks > 1:
            cmd = ["mpirun", "--allow-run-as-root", "--oversubscribe", "-n", str(args.ranks)] + cmd
        print(" ".join(shlex.quote(c) for c in cmd), file=sys.stderr, flush=True)
        t0 = time.time()
        code = subprocess.call(cmd, stdout=subprocess.DEVNULL)
        wall = time.time() - t0
        s = summary_of(run)
        speed, p999, out = frames_of(run, args.until) if os.path.isdir(run) else (float("nan"),) * 3
        row = [f"{dp:g}", code, s.get("steps", "-"), f"{wall:.0f}", f"{s['dt_min']:.3g}" if "dt_min" in s else "-",
               s.get("limit_of_dt_min", "-"), f"{s['t_of_dt_min']:.4g}" if "t_of_dt_min" in s else "-",
               s.get("removed", "-"), s.get("put_back", "-"), f"{speed:.4g}", f"{p999:.4g}", "-" if out is None else out]
        for m in args.measure:
            r = subprocess.run(m.replace("{run}", shlex.quote(run)), shell=True, stdout=subprocess.PIPE,
                               stderr=subprocess.STDOUT, text=True, cwd=ROOT)
            lines = [x for x in r.stdout.splitlines() if x.strip()]
            row.append(lines[-1].strip() if lines else f"(exit {r.returncode})")
        rows.append(row)
    with open(os.path.join(args.out, "sweep.csv"), "w", newline="") as f:
        csv.writer(f).writerows([head] + rows)
    print("| " + " | ".join(head) + " |")
    print("|" + "---|" * len(head))
    for row in rows:
        print("| " + " | ".join(str(v) for v in row) + " |")
    return 0 if all(r[1] == 0 for r in rows) else 1


if __name__ == "__main__":
    sys.exit(main())
