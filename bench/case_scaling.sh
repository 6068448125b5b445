#!/bin/bash
# Strong scaling of whole runs (`mpsfsi run`) with a solid on 1 and 2 ranks of this machine, alternating the
# rank counts in each round: dam_break_elastic_plate at dp 1 mm (fluid, solid and coupling) and the reduced
# Lamb problem of tests/lamb/lamb_reduced.py (a solid of 101,200 particles). Prints per run the steps, the
# phases of the run summary (rank 0's timers, ms per step) and rank 0's peak memory.
# Results go to docs/performance.md (## Parallel runs).
# Usage: bench/case_scaling.sh [BUILD_DIR [ROUNDS]]
set -euo pipefail
build=${1:-build}
rounds=${2:-2}
here=$(cd "$(dirname "$0")/.." && pwd)
mpsfsi="$build/mpsfsi"
mpi="mpirun --allow-run-as-root --oversubscribe -np"
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT

summary() {  # run.jsonl -> one table row
  /usr/bin/python3 - "$1" "$2" "$3" <<'EOF'
import json, sys
path, label, ranks = sys.argv[1:4]
s = [json.loads(l) for l in open(path) if '"summary"' in l][-1]
n = s["steps"]
ms = lambda k: 1000 * s[k] / n
print(f"| {label} | {ranks} | {n} | {ms('fluid'):.1f} | {ms('solid'):.1f} | {ms('coupling'):.1f} | "
      f"{1000 * s['wall'] / n:.1f} | {s['peak_memory_kib'] / 1024:.0f} |")
EOF
}

echo "| case | ranks | steps | fluid | solid | coupling | wall ms/step | peak MiB (rank 0) |"
echo "|---|---|---|---|---|---|---|---|"
for r in $(seq "$rounds"); do
  for np in 1 2; do
    out="$work/plate_np$np"
    $mpi "$np" "$mpsfsi" run "$here/cases/dam_break_elastic_plate.yaml" --dp 0.001 --end-time 0.05 --quiet \
      --overwrite --output "$out" --set output.interval=1 > /dev/null
    summary "$out/run.jsonl" "dam_break_elastic_plate dp 1 mm" "$np"
  done
  for np in 1 2; do
    out="$work/lamb_np$np"
    $mpi "$np" "$mpsfsi" run "$here/cases/lamb_a.yaml" --quiet --overwrite --output "$out" --end-time 0.0187 \
      --set "bodies.ground.rectangle={min: [-16, -22], max: [30, 0]}" \
      --set "receivers.points=[{name: r10, body: ground, position: [10, 0]}]" --set output.interval=1 > /dev/null
    summary "$out/run.jsonl" "lamb_a reduced (101,200 solid particles)" "$np"
  done
done
