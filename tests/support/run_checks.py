"""What the Python tests that run the program share: a failure that says what is wrong and exits 1, and a command
run with its output kept (the test fails on a non-zero exit code, printing that output)."""
import subprocess
import sys


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
