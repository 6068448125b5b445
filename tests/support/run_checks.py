"""What the Python tests that run the program share: a failure that says what is wrong and exits 1, a command run
with its output kept (the test fails on a non-zero exit code, printing that output), and the arguments and run of
the tests that run one case (--mpsfsi BIN --case CASE --work DIR --end T [-- run args])."""
import argparse
import os
import shutil
import subprocess
import sys

import yaml


def fail(msg):
    print("FAIL: " + msg)
    sys.exit(1)


def run(cmd):
    """Runs cmd (printed first); its standard output and error together, or a failure on a non-zero exit code."""
    print("$ " + " ".join(cmd), flush=True)
    r = subprocess.run(cmd, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True)
    if r.returncode != 0:
        fail(f"exit code {r.returncode}; output:\n{r.stdout}")
    return r.stdout


def case_run_parser(description):
    """The arguments of a test that runs one case: --mpsfsi, --case, --work, --end and the run's extra arguments."""
    ap = argparse.ArgumentParser(description=description)
    ap.add_argument("--mpsfsi", required=True)
    ap.add_argument("--case", required=True)
    ap.add_argument("--work", required=True)
    ap.add_argument("--end", type=float, required=True)
    ap.add_argument("extra", nargs="*")
    return ap


def run_case(args, out):
    """Runs args.case to args.end into the new folder `out` (with args.extra); the resolved case it wrote."""
    shutil.rmtree(out, ignore_errors=True)
    run([args.mpsfsi, "run", args.case, "--quiet", "--output", out, "--end-time", str(args.end), *args.extra])
    with open(os.path.join(out, "case.resolved.yaml")) as f:
        return yaml.safe_load(f)
