#!/usr/bin/env python3
"""Command-line tests of a run's outputs (issue 13), through the mpsfsi program:

- disk full while frames are written: exit 4 with a message naming the file, every frame the .pvd lists is
  complete, no .tmp file is left (a 2 MiB tmpfs; skipped when this user may not mount one);
- the progress lines reach a pipe as they are printed (not in 4 KB chunks at the end);
- fragments.csv only for cases whose solids can break;
- empty command-line values (--output '', --subcycles '') are refused with exit 2;
- run.jsonl logs every step once (a run that ends on a logged step, a run that fails).

Usage: run_output_test.py MPSFSI CASES_DIR WORK_DIR
"""
import os
import shutil
import subprocess
import sys
import time

from checks import check, finish, run_program

MPSFSI, CASES, WORK = sys.argv[1], sys.argv[2], sys.argv[3]


def run(args, **kw):
    return run_program(MPSFSI, args, **kw)


def full_disk():
    folder = os.path.join(WORK, "full")
    os.makedirs(folder, exist_ok=True)
    subprocess.run(["umount", folder], stderr=subprocess.DEVNULL)
    mounted = subprocess.run(["mount", "-t", "tmpfs", "-o", "size=2m", "tmpfs", folder],
                             stderr=subprocess.DEVNULL).returncode == 0
    if not mounted:  # a file-size limit would be the other way, but it breaks MPI's start-up files
        print("skipped: full disk (this user cannot mount a tmpfs)")
        return
    out = os.path.join(folder, "db")
    try:
        r = run(["run", os.path.join(CASES, "dam_break.yaml"), "--dp", "0.006", "--end-time", "1", "--set",
                 "output.interval=0.002", "--output", out, "--overwrite", "--quiet"])
        check("full disk: exit 4", r.returncode == 4, f"exit {r.returncode}\n{r.stdout}")
        check("full disk: message names the file", "output error: cannot write" in r.stdout and out in r.stdout,
              r.stdout)
        pvd = os.path.join(out, "particles.pvd")
        text = open(pvd).read() if os.path.exists(pvd) else ""
        listed = [line.split('file="')[1].split('"')[0] for line in text.splitlines() if "<DataSet" in line]
        complete = [f for f in listed
                    if open(os.path.join(out, f), "rb").read().rstrip().endswith(b"</VTKFile>")]
        check("full disk: the .pvd lists complete frames only", listed and len(complete) == len(listed),
              f"{len(listed)} listed, {len(complete)} complete")
        check("full disk: the message counts the listed frames", f"lists the {len(listed)} complete frame(s)" in r.stdout,
              r.stdout)
        tmp = [f for f in os.listdir(out) if f.endswith(".tmp")]
        check("full disk: no .tmp file left", not tmp, str(tmp))
    finally:
        subprocess.run(["umount", folder])


def progress_is_flushed():
    """The first progress line arrives while the run is still going (a pipe is block-buffered by default)."""
    out = os.path.join(WORK, "flush")
    p = subprocess.Popen([MPSFSI, "run", os.path.join(CASES, "hydrostatic.yaml"), "--end-time", "3", "--output", out,
                          "--overwrite"], stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True)
    try:
        first = ""
        t0 = time.time()
        while time.time() - t0 < 60:
            line = p.stdout.readline()
            if not line or line.startswith("t = "):
                first = line
                break
        running = p.poll() is None
        check("progress line reaches a pipe while the run goes on", first.startswith("t = ") and running,
              f"first line {first!r}, running {running}")
    finally:
        p.kill()
        p.wait()


def fragments_only_when_breakable():
    out = os.path.join(WORK, "cantilever")
    r = run(["run", os.path.join(CASES, "cantilever.yaml"), "--end-time", "2e-4", "--output", out, "--overwrite",
             "--quiet"])
    check("cantilever runs", r.returncode == 0, r.stdout)
    check("no fragments.csv without fracture", not os.path.exists(os.path.join(out, "fragments.csv")))
    out = os.path.join(WORK, "collision")
    r = run(["run", os.path.join(CASES, "collision_fracture.yaml"), "--end-time", "2e-4", "--output", out,
             "--overwrite", "--quiet"])
    check("fragments.csv with fracture", r.returncode == 0 and os.path.exists(os.path.join(out, "fragments.csv")),
          r.stdout)


def empty_values_refused():
    for option in ["--output", "--subcycles"]:
        r = run(["run", os.path.join(CASES, "dam_break.yaml"), option, ""])
        check(f"{option} '' refused", r.returncode == 2 and f"{option}: expected a non-empty value" in r.stdout,
              f"exit {r.returncode}\n{r.stdout}")


def run_log_lines_once():
    import json
    hydro = os.path.join(CASES, "hydrostatic.yaml")
    runs = {"ends on step 100": (["--end-time", "0.1", "--set", "time.cfl=~", "--set", "time.dt_max=~", "--set",
                                  "time.dt=1e-3"], 0),
            "fails": (["--end-time", "0.35", "--set", "gravity=[0,9.81]", "--set",
                       "domain={min: [-0.05, -0.05], max: [0.25, 0.32]}"], 3)}
    for what, (args, code) in runs.items():
        out = os.path.join(WORK, "jsonl_" + what.replace(" ", "_"))
        r = run(["run", hydro, "--output", out, "--overwrite", "--quiet"] + args)
        events = [json.loads(line) for line in open(os.path.join(out, "run.jsonl"))]
        steps = [e["step"] for e in events if e["event"] == "step"]
        ok = r.returncode == code and steps == sorted(set(steps))
        ok = ok and sum(e["event"] in ("summary", "failure") for e in events) == 1
        check(f"run.jsonl logs each step once ({what})", ok, f"exit {r.returncode}; steps {steps}")


os.makedirs(WORK, exist_ok=True)
full_disk()
progress_is_flushed()
fragments_only_when_breakable()
empty_values_refused()
run_log_lines_once()
finish()
