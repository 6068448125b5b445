#!/usr/bin/env python3
"""Command-line tests of how `mpsfsi run` behaves towards an operator (issue 29), through the program:

- SIGINT and SIGTERM stop the run at the end of the current step: exit 130 / 143, a message that says how
  to continue, an `interrupted` event in run.jsonl, a frame and a checkpoint of the state reached (the last
  frame's time is the checkpoint's); `run --restart FOLDER` then continues to the end with exit 0;
- a second SIGINT stops at once (the process ends by the signal);
- under mpirun (when given), SIGINT to the ranks stops both after the same step with a checkpoint, exit 130;
- the output folder is locked: a second run into it is refused with exit 2 naming the holder's pid and host,
  and is accepted again once the first has ended (also by SIGKILL);
- a folder removed while the run writes into it stops the run with exit 4 and a message;
- a restart from an earlier checkpoint of a folder removes the later frames and checkpoints of the old
  trajectory and says so; the folder can then be continued with `--restart FOLDER`;
- `--restart` on a FIFO is refused with exit 2 at once (no hang);
- a case without `description:` and `source:` (a user's own) is accepted;
- a clamped particle driven faster than its P-wave speed by the tank motion names that motion as the cause,
  and the failed run's series does not list time 0 twice.

Usage: reliability_test.py MPSFSI CASES_DIR WORK_DIR [MPIRUN ...]
"""
import json
import os
import re
import shutil
import signal
import socket
import subprocess
import sys
import time

from checks import check, finish, run_program

MPSFSI, CASES, WORK = sys.argv[1], sys.argv[2], sys.argv[3]
MPIRUN = sys.argv[4:]
DAM_BREAK = os.path.join(CASES, "dam_break.yaml")
def folder(name):
    path = os.path.join(WORK, name)
    shutil.rmtree(path, ignore_errors=True)
    return path


def run(args, timeout=300):
    return run_program(MPSFSI, args, timeout=timeout)


def start(args, prefix=()):
    return subprocess.Popen(list(prefix) + [MPSFSI] + args, stdout=subprocess.PIPE, stderr=subprocess.STDOUT,
                            text=True, start_new_session=True)


def wait_for_steps(out, n, timeout=120):
    """Waits until run.jsonl in `out` logs step n (the run is then inside its loop)."""
    end = time.time() + timeout
    while time.time() < end:
        try:
            with open(os.path.join(out, "run.jsonl")) as f:
                steps = [json.loads(line).get("step", 0) for line in f if '"event":"step"' in line]
            if steps and max(steps) >= n:
                return True
        except (OSError, ValueError):
            pass
        time.sleep(0.05)
    return False


def events(out):
    with open(os.path.join(out, "run.jsonl")) as f:
        return [json.loads(line) for line in f if line.strip()]


def frame_times(out):
    with open(os.path.join(out, "particles.pvd")) as f:
        return [float(t) for t in re.findall(r'timestep="([^"]+)"', f.read())]


def checkpoints(out):
    return sorted(f for f in os.listdir(out) if f.startswith("checkpoint_") and f.endswith(".chk"))


# A dam break long enough to be stopped in its loop (dp 6 mm: steps of a few ms of wall time).
LONG = [DAM_BREAK, "--dp", "0.006", "--end-time", "2", "--set", "output.interval=0.05", "--quiet"]


def interrupted_run(signo, code, name):
    out = folder(name)
    p = start(["run"] + LONG + ["--output", out])
    started = wait_for_steps(out, 30)
    os.kill(p.pid, signo)
    text = p.communicate(timeout=120)[0]
    check(f"{name}: exit {code}", started and p.returncode == code, f"exit {p.returncode}\n{text}")
    sig = signal.Signals(signo).name
    check(f"{name}: message names the signal and how to continue",
          f"interrupted by {sig}" in text and f"mpsfsi run --restart {out}" in text, text)
    ev = events(out)
    stop = [e for e in ev if e.get("event") == "interrupted"]
    check(f"{name}: run.jsonl logs the interruption", len(stop) == 1 and stop[0].get("signal") == sig, str(ev[-3:]))
    cks = checkpoints(out)
    t_stop = stop[0]["t"] if stop else -1
    check(f"{name}: a checkpoint and a frame of the state reached",
          len(cks) == 1 and abs(float(cks[0][len("checkpoint_"):-4]) - t_stop) < 1e-9
          and abs(frame_times(out)[-1] - t_stop) < 1e-9, f"{cks} {frame_times(out)[-3:]} t {t_stop}")
    return out, t_stop


def signals():
    out, t_stop = interrupted_run(signal.SIGINT, 130, "sigint")
    r = run(["run", "--restart", out, "--end-time", f"{t_stop + 0.02:.6f}", "--quiet"])
    check("sigint: run --restart FOLDER continues", r.returncode == 0 and frame_times(out)[-1] > t_stop,
          f"exit {r.returncode}\n{r.stdout}")
    interrupted_run(signal.SIGTERM, 143, "sigterm")

    # A second Ctrl-C stops at once: a run whose steps take long (dp 1.5 mm), two signals 0.1 s apart.
    out = folder("sigint_twice")
    p = start(["run", DAM_BREAK, "--dp", "0.0015", "--end-time", "1", "--quiet", "--output", out])
    started = wait_for_steps(out, 2)
    os.kill(p.pid, signal.SIGINT)
    time.sleep(0.1)
    t0 = time.time()
    os.kill(p.pid, signal.SIGINT)
    text = p.communicate(timeout=60)[0]
    check("second SIGINT: the process ends by the signal, at once",
          started and p.returncode == -signal.SIGINT and time.time() - t0 < 5, f"exit {p.returncode}\n{text}")

    if MPIRUN:
        out = folder("sigint_mpirun")
        p = start(["run"] + LONG + ["--output", out], prefix=MPIRUN)
        started = wait_for_steps(out, 30)
        # The ranks are mpirun's children (a signal to mpirun itself makes it SIGTERM and soon SIGKILL them).
        subprocess.run(["pkill", "-INT", "-P", str(p.pid), "-x", os.path.basename(MPSFSI)])
        text = p.communicate(timeout=120)[0]
        ev = events(out)
        stop = [e for e in ev if e.get("event") == "interrupted"]
        check("mpirun: SIGINT to the ranks: exit 130, one interruption, a checkpoint",
              started and p.returncode == 130 and len(stop) == 1 and len(checkpoints(out)) == 1,
              f"exit {p.returncode}\n{text}\n{ev[-3:]}")


def lock():
    out = folder("locked")
    first = start(["run"] + LONG + ["--output", out])
    started = wait_for_steps(out, 5)
    r = run(["run", os.path.join(CASES, "hydrostatic.yaml"), "--output", out, "--overwrite", "--quiet",
             "--end-time", "0.01"])
    check("lock: a second run into the folder is refused with exit 2 naming pid and host",
          started and r.returncode == 2 and f"pid {first.pid}" in r.stdout and socket.gethostname() in r.stdout,
          f"exit {r.returncode}\n{r.stdout}")
    check("lock: the second run wrote nothing", "hydrostatic" not in open(os.path.join(out, "case.resolved.yaml")).read())
    first.send_signal(signal.SIGKILL)
    first.communicate(timeout=60)
    r = run(["run", DAM_BREAK, "--dp", "0.01", "--end-time", "0.01", "--output", out, "--overwrite", "--quiet"])
    check("lock: released by the kernel when the holder is killed", r.returncode == 0, f"exit {r.returncode}\n{r.stdout}")
    out = folder("foreign")
    os.makedirs(out)
    open(os.path.join(out, "notes.txt"), "w").close()
    r = run(["run", DAM_BREAK, "--dp", "0.01", "--end-time", "0.01", "--output", out, "--quiet"])
    check("lock: a run refused for a non-empty folder leaves no lock file in it",
          r.returncode == 2 and os.listdir(out) == ["notes.txt"], f"exit {r.returncode}\n{r.stdout}\n{os.listdir(out)}")
    out = folder("lock_only")
    os.makedirs(out)
    open(os.path.join(out, ".mpsfsi.lock"), "w").close()
    r = run(["run", DAM_BREAK, "--dp", "0.01", "--end-time", "0.01", "--output", out, "--quiet"])
    check("lock: a folder holding only a released lock file counts as empty", r.returncode == 0,
          f"exit {r.returncode}\n{r.stdout}")


def removed_folder():
    out = folder("removed")
    p = start(["run"] + LONG + ["--output", out, "--set", "output.interval=0.005"])
    started = wait_for_steps(out, 30)
    # `rm -rf`: the run may write a file while the folder is emptied, so go on until the folder is gone.
    for _ in range(20):
        shutil.rmtree(out, ignore_errors=True)
        if not os.path.exists(out):
            break
    text = p.communicate(timeout=120)[0]
    check("folder removed mid-run: exit 4 with a message", started and p.returncode == 4 and "was removed" in text,
          f"exit {p.returncode}\n{text}")


def branching_restart():
    out = folder("branch")
    r = run(["run", DAM_BREAK, "--dp", "0.01", "--end-time", "0.3", "--checkpoint-every", "0.1", "--set",
             "output.interval=0.02", "--output", out, "--quiet"])
    cks = checkpoints(out)
    first = os.path.join(out, cks[0]) if cks else ""
    r2 = run(["run", "--restart", first, "--set", "fluid.tolerance=1e-3", "--end-time", "0.25", "--quiet"])
    later = [c for c in checkpoints(out) if float(c[len("checkpoint_"):-4]) > 0.25 + 1e-9]
    frames = sorted(f for f in os.listdir(out) if re.fullmatch(r"particles_\d+\.vtu", f))
    check("branching restart: the old trajectory's later checkpoints and frames are removed, and it says so",
          r.returncode == 0 and r2.returncode == 0 and not later and len(frames) == len(frame_times(out))
          and "later file(s) of the earlier trajectory were removed" in r2.stdout,
          f"exit {r.returncode} {r2.returncode}\n{r2.stdout}\n{checkpoints(out)}\n{frames}")
    r3 = run(["run", "--restart", out, "--end-time", "0.35", "--quiet"])
    check("branching restart: the folder is continued by --restart FOLDER", r3.returncode == 0,
          f"exit {r3.returncode}\n{r3.stdout}")


def fifo_and_source():
    fifo = os.path.join(folder("fifo"), "checkpoint_0.1.chk")
    os.makedirs(os.path.dirname(fifo))
    os.mkfifo(fifo)
    try:
        r = run(["run", "--restart", fifo], timeout=30)
        check("--restart FIFO: refused with exit 2", r.returncode == 2 and "not a regular file" in r.stdout,
              f"exit {r.returncode}\n{r.stdout}")
        r = run(["run", "--restart", os.path.dirname(fifo)], timeout=30)
        check("--restart FOLDER holding a FIFO checkpoint: refused with exit 2", r.returncode == 2,
              f"exit {r.returncode}\n{r.stdout}")
    except subprocess.TimeoutExpired:
        check("--restart FIFO: no hang", False)
    own = os.path.join(WORK, "own_case.yaml")
    with open(DAM_BREAK) as f:
        text = "".join(line for line in f if not re.match(r"(description|source):", line))
    with open(own, "w") as f:
        f.write(text)
    r = run(["check", own])
    check("a case without description and source is accepted", r.returncode == 0 and "case OK" in r.stdout,
          f"exit {r.returncode}\n{r.stdout}")


def prescribed_motion():
    out = folder("violent_roll")
    r = run(["run", os.path.join(CASES, "dam_break_elastic_plate.yaml"), "--dp", "0.006", "--output", out, "--quiet",
             "--set", "tank_motion={type: sine_roll, pivot: [0.292,0], amplitude_deg: 89, period: 0.001}"])
    check("a clamped particle too fast: exit 3 naming the prescribed tank motion, not the solid dt",
          r.returncode == 3 and "prescribed tank motion" in r.stdout and "reduce the solid dt" not in r.stdout,
          f"exit {r.returncode}\n{r.stdout}")
    times = frame_times(out)
    check("a failed run's series never repeats a time", len(times) == len(set(times)), str(times))


def main():
    os.makedirs(WORK, exist_ok=True)
    signals()
    lock()
    removed_folder()
    branching_restart()
    fifo_and_source()
    prescribed_motion()
    finish()


if __name__ == "__main__":
    main()
