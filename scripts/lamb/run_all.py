#!/usr/bin/env python3
"""The full Lamb's-problem validation (seed 000 §3, issue 6): models A and B x 300 / 400 Hz x
re = 1.9 / 2.1 dx, one MPS run each (one after the other), then the misfit tables.

Every run has the cases' eight surface receivers (r10 ... r38, the issue's setup) and, added with
--set, eight receivers 1 m deep (d10 ... d38, the seed's literal text "source and eight receivers
are set at 1 m depth"); both sets are compared with the exact solution (scripts/lamb/compare.py:
Cagniard-de Hoop at the surface, wavenumber integration at depth). A 400 Hz run ends at its last
window end (t0 + 38 m / c_R + 1.5 / f0), shorter than the 300 Hz run of the case file.

  /usr/bin/python3 scripts/lamb/run_all.py [--mpsfsi build/mpsfsi] [--out out/lamb]
      [--only a300_19,b300_19] [--skip-existing] [--no-run] [--set KEY=VALUE ...] [--markdown table.md]

The runs use the case files as they are (solid.volumetric_strain: corrected); docs/validation.md's
`n0` rows come from `--set solid.volumetric_strain=n0 --out out/lamb_n0`.

Writes OUT/<run>/ (the run, receivers.csv, misfit_surface.csv, misfit_depth1.csv, PNGs) and prints
the tables (markdown) with particles, steps, wall and CPU time of each run (from OUT/<run>/run.jsonl
and the process's rusage).
"""
from __future__ import annotations

import argparse
import csv
import json
import os
import resource
import subprocess
import sys
import time

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(os.path.dirname(HERE))
sys.path.insert(0, HERE)
import lamb2d  # noqa: E402

MODELS = {"a": ("cases/lamb_a.yaml", 2611.0), "b": ("cases/lamb_b.yaml", 4522.0)}
VS = 1846.0
OFFSETS = [10, 14, 18, 22, 26, 30, 34, 38]


def configs():
    for model in ("a", "b"):
        for f0 in (300, 400):
            for re in (1.9, 2.1):
                yield f"{model}{f0}_{str(re).replace('.', '')}", model, f0, re


def run_one(args, name, model, f0, re):
    case, vp = MODELS[model]
    out = os.path.join(args.out, name)
    end = 1.5 / f0 + max(OFFSETS) / lamb2d.rayleigh_speed(vp, VS) + 1.5 / f0
    end = round(end + 5e-5, 4)  # a few steps past the last window end
    buried = ", ".join(f"{{name: d{x}, body: ground, position: [{x}, -1]}}" for x in OFFSETS)
    surface = ", ".join(f"{{name: r{x}, body: ground, position: [{x}, 0]}}" for x in OFFSETS)
    cmd = [args.mpsfsi, "run", os.path.join(ROOT, case), "--quiet", "--overwrite", "--output", out,
           "--end-time", f"{end:g}", "--set", f"sources.blast.wavelet.frequency={f0}", "--set", f"solid.re={re}",
           "--set", f"receivers.points=[{surface}, {buried}]"]
    for extra in args.set or []:
        cmd += ["--set", extra]
    done = os.path.join(out, "run.jsonl")
    if args.skip_existing and os.path.isfile(done) and '"summary"' in open(done, encoding="utf-8").read():
        print(f"{name}: exists, skipped", flush=True)
        return
    print(f"{name}: {' '.join(cmd)}", flush=True)
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    t0 = time.time()
    subprocess.run(["nice"] + cmd, check=True)
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    with open(os.path.join(out, "cpu.json"), "w", encoding="utf-8") as f:
        json.dump({"wall": time.time() - t0, "user": after.ru_utime - before.ru_utime,
                   "system": after.ru_stime - before.ru_stime}, f)


def compare(args, name, model, f0, re):
    out = os.path.join(args.out, name)
    rows = {}
    for label, depth in (("surface", 0.0), ("depth1", 1.0)):
        csv_path = os.path.join(out, f"misfit_{label}.csv")
        cmd = [sys.executable, os.path.join(HERE, "compare.py"), out, "--depth", str(depth), "--csv", csv_path,
               "--plot", os.path.join(out, f"{name}_{label}.png"),
               "--label", f"model {model.upper()}, receivers {'at the surface' if depth == 0 else '1 m deep'}"]
        subprocess.run(cmd, check=True, stdout=subprocess.DEVNULL)
        with open(csv_path, encoding="utf-8") as f:
            rows[label] = list(csv.DictReader(f))
    return rows


def run_info(args, name):
    out = os.path.join(args.out, name)
    info = {}
    with open(os.path.join(out, "run.jsonl"), encoding="utf-8") as f:
        for line in f:
            e = json.loads(line)
            if e.get("event") == "summary":
                info.update(steps=e["steps"], wall=e["wall"], solid=e["solid"])
    cpu = os.path.join(out, "cpu.json")
    if os.path.isfile(cpu):
        with open(cpu, encoding="utf-8") as f:
            info["cpu"] = json.load(f)["user"]
    with open(os.path.join(out, "case.resolved.yaml"), encoding="utf-8") as f:
        import yaml
        case = yaml.safe_load(f)
    r = case["bodies"][0]["rectangle"]
    dx = float(case["dp"])
    info["particles"] = round((r["max"][0] - r["min"][0]) / dx) * round((r["max"][1] - r["min"][1]) / dx)
    info["block"] = f"{r['max'][0] - r['min'][0]:g} x {r['max'][1] - r['min'][1]:g} m"
    return info


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--mpsfsi", default=os.path.join(ROOT, "build", "mpsfsi"))
    ap.add_argument("--out", default=os.path.join(ROOT, "out", "lamb"))
    ap.add_argument("--only", help="comma-separated run names (a300_19, a300_21, a400_19, ..., b400_21)")
    ap.add_argument("--skip-existing", action="store_true", help="do not rerun a finished run")
    ap.add_argument("--no-run", action="store_true", help="only compare existing runs")
    ap.add_argument("--markdown", help="also write the tables to this file")
    ap.add_argument("--set", action="append", help="an extra --set override for every run (repeatable)")
    args = ap.parse_args(argv)
    only = set(args.only.split(",")) if args.only else None
    selected = [c for c in configs() if only is None or c[0] in only]
    for c in selected:
        if not args.no_run:
            run_one(args, *c)
    lines = []
    for label, title in (("surface", "receivers at the surface (issue 6)"),
                         ("depth1", "receivers 1 m deep (seed 000 text)")):
        lines += [f"Misfit (seed 000 eq. 27, %), {title}: ux / uy", "",
                  "| run | model | f0 | re | " + " | ".join(f"{x} m" for x in OFFSETS) + " |",
                  "|---|---|---|---|" + "---|" * len(OFFSETS)]
        for name, model, f0, re in selected:
            if not os.path.isfile(os.path.join(args.out, name, "receivers.csv")):
                continue
            rows = compare(args, name, model, f0, re)[label]
            cells = [f"{100 * float(r['misfit_ux']):.2f} / {100 * float(r['misfit_uy']):.2f}" for r in rows]
            lines.append(f"| {name} | {model.upper()} | {f0} | {re} | " + " | ".join(cells) + " |")
        lines.append("")
    lines += ["| run | block | particles | steps | wall [s] | solid [s] | CPU [s] |", "|---|---|---|---|---|---|---|"]
    for name, *_ in selected:
        if not os.path.isfile(os.path.join(args.out, name, "run.jsonl")):
            continue
        i = run_info(args, name)
        lines.append(f"| {name} | {i['block']} | {i['particles']} | {i.get('steps', '?')} | {i.get('wall', 0):.0f} | "
                     f"{i.get('solid', 0):.0f} | {i.get('cpu', float('nan')):.0f} |")
    text = "\n".join(lines)
    print(text)
    if args.markdown:
        with open(args.markdown, "w", encoding="utf-8") as f:
            f.write(text + "\n")
    return 0


if __name__ == "__main__":
    sys.exit(main())
