#!/usr/bin/python3
"""Runs `MPSFSI ARGS --output WORK --overwrite`, then `PYTHON CHECKER WORK CHECK_ARGS`; exits with the first
non-zero code (the run's, else the checker's). ARGS and CHECK_ARGS are '|'-separated (CMake lists).
Usage: run_and_check.py MPSFSI WORK ARGS PYTHON CHECKER CHECK_ARGS
"""
import subprocess
import sys


def main():
    if len(sys.argv) != 7:
        sys.exit(__doc__)
    mpsfsi, work, args, python, checker, check_args = sys.argv[1:]
    run = [mpsfsi] + args.split("|") + ["--output", work, "--overwrite"]
    print(" ".join(run), flush=True)
    code = subprocess.call(run)
    if code != 0:
        sys.exit(f"run_and_check.py: the run exited {code}")
    check = [python, checker, work] + check_args.split("|")
    print(" ".join(check), flush=True)
    sys.exit(subprocess.call(check))


if __name__ == "__main__":
    main()
