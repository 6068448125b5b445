#!/usr/bin/env python3
"""Runs cases/added_mass.yaml at a list of mass ratios rho_s h / (rho_f L) and particle spacings and prints
analyse.py's table: the block's density is 2000 times the ratio, and gravity rises over one analytic period
(gravity_ramp), which leaves an oscillation of a third of the static displacement (the response of an
oscillator to the ramp (1 - cos(pi t / T_r)) / 2 has the amplitude |cos(pi x / 2)| / |1 - x^2| of the static
one, x = 2 T_r / T), so that the interface pressure stays well above zero and the water never separates.
Usage: sweep.py --out DIR [--ratios 10,3,1,0.3,0.1] [--dp 0.005,0.0025] [--coupling implicit]
                [--mpsfsi build/mpsfsi] [--ranks N] [-- extra mpsfsi arguments]"""
import argparse
import math
import os
import subprocess
import sys

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, HERE)
import analyse  # noqa: E402

CASE = os.path.join(HERE, "..", "added_mass.yaml")


def main():
    argv = sys.argv[1:]
    extra = []
    if "--" in argv:
        extra = argv[argv.index("--") + 1:]
        argv = argv[:argv.index("--")]
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--out", required=True)
    ap.add_argument("--ratios", default="10,3,1,0.3,0.1")
    ap.add_argument("--dp", default="0.005")
    ap.add_argument("--coupling", default="implicit")
    ap.add_argument("--mpsfsi", default=os.path.join(HERE, "..", "..", "build", "mpsfsi"))
    ap.add_argument("--ranks", type=int, default=1)
    args = ap.parse_args(argv)
    import yaml
    with open(CASE) as f:
        case = yaml.safe_load(f)
    runs = []
    for dp in args.dp.split(","):
        for ratio in args.ratios.split(","):
            rho = 2000 * float(ratio)
            case["materials"]["block"]["rho"] = rho
            _, period, _, _ = analyse.analytic_periods(case)
            out = os.path.join(args.out, f"dp_{dp}_ratio_{ratio}_{args.coupling}")
            cmd = [args.mpsfsi, "run", CASE, "--dp", dp, "--output", out, "--overwrite", "--coupling", args.coupling,
                   "--set", f"materials.block.rho={rho:g}", "--set", f"gravity_ramp={period:.6g}"] + extra
            if args.ranks > 1:
                cmd = ["mpirun", "--allow-run-as-root", "--oversubscribe", "-np", str(args.ranks)] + cmd
            os.makedirs(args.out, exist_ok=True)
            with open(out + ".log", "w") as log:
                rc = subprocess.call(cmd, stdout=log, stderr=subprocess.STDOUT)
            print(f"dp {dp} ratio {ratio} {args.coupling}: exit {rc} ({out}.log)", file=sys.stderr)
            if os.path.exists(os.path.join(out, "case.resolved.yaml")):
                runs.append(out)
    sys.argv = ["analyse.py"] + runs
    return analyse.main()


if __name__ == "__main__":
    sys.exit(main())
