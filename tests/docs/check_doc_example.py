#!/usr/bin/env python3
"""Checks that a case shown in a doc is the case shipped in cases/, and that it passes `mpsfsi check`.

Usage: check_doc_example.py MPSFSI DOC HEADING CASE WORK_DIR [--whole]

Takes the first ```yaml block after the Markdown heading HEADING (a line equal to it) in DOC and
  1. compares it with the case file CASE without its opening comment lines (the header that says what
     the case is, its sample runs and its source), or with the whole file (--whole): they must be equal,
     line for line;
  2. writes the block to WORK_DIR/<case name> and runs `mpsfsi check` on it: exit 0 and "case OK".
Prints a unified diff or the program's output when a check fails; exit 0 when both hold, else 1
(2 for bad usage or a missing heading or block).
Registered in ctest by tests/docs/CMakeLists.txt (label unit).
"""

import difflib
import os
import subprocess
import sys


def doc_block(doc_path, heading):
    with open(doc_path, encoding="utf-8") as f:
        lines = f.read().split("\n")
    if heading not in lines:
        sys.exit("check_doc_example.py: %s: no heading line '%s'" % (doc_path, heading))
    i = lines.index(heading) + 1
    while i < len(lines) and lines[i].strip() != "```yaml":
        if lines[i].startswith("## "):
            break
        i += 1
    if i >= len(lines) or lines[i].strip() != "```yaml":
        sys.exit("check_doc_example.py: %s: no ```yaml block under '%s'" % (doc_path, heading))
    end = lines.index("```", i + 1)
    return [line + "\n" for line in lines[i + 1:end]]


def case_body(case_path):
    with open(case_path, encoding="utf-8") as f:
        lines = f.readlines()
    i = 0
    while i < len(lines) and lines[i].startswith("#"):
        i += 1
    return lines[i:]


def main():
    whole = sys.argv[6:] == ["--whole"]
    if len(sys.argv) != 6 + whole:
        print(__doc__, file=sys.stderr)
        return 2
    mpsfsi, doc, heading, case, work = sys.argv[1:6]
    block = doc_block(doc, heading)
    body = open(case, encoding="utf-8").readlines() if whole else case_body(case)
    ok = True
    if block != body:
        ok = False
        print("%s (under '%s') differs from %s after its header comments:" % (doc, heading, case))
        sys.stdout.writelines(difflib.unified_diff(body, block, case, doc))
    os.makedirs(work, exist_ok=True)
    path = os.path.join(work, os.path.basename(case))
    with open(path, "w", encoding="utf-8") as f:
        f.writelines(block)
    result = subprocess.run([mpsfsi, "check", path], capture_output=True, text=True, timeout=120)
    if result.returncode != 0 or "case OK" not in result.stdout:
        ok = False
        print("mpsfsi check %s (the block of %s): exit %d" % (path, doc, result.returncode))
        print(result.stdout + result.stderr)
    print("%s: the example %s" % (doc, "equals %s and passes mpsfsi check" % case if ok else "FAILED"))
    return 0 if ok else 1


if __name__ == "__main__":
    sys.exit(main())
