"""The named checks of the command-line test scripts (run_output_test.py, reliability_test.py): each check
prints `ok: NAME` or `FAIL: NAME` with its detail; finish() prints the tally and exits 1 if any failed."""
import subprocess
import sys

failures = []
passed = 0


def check(name, ok, detail=""):
    global passed
    if ok:
        passed += 1
        print(f"ok: {name}")
    else:
        failures.append(name)
        print(f"FAIL: {name}\n{detail}")


def run_program(program, args, timeout=300, **kw):
    """`program args`, stdout and stderr together as text."""
    return subprocess.run([program] + args, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True,
                          timeout=timeout, **kw)


def finish():
    print(f"{passed} passed, {len(failures)} failed")
    sys.exit(1 if failures else 0)
