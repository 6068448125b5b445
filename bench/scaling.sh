#!/bin/bash
# Strong scaling of the fluid step (bench_fluid_dam_break, SSOR) on 1 and 2 ranks of this machine, alternating
# the rank counts in each round so that both see the same load; per dp the median and the best (smallest) total
# ms per step of each rank count over the rounds, and the speed-up of the medians and of the bests. The best of
# several rounds is the figure least touched by other work on a shared machine (that work only ever adds time).
# Results go to docs/performance.md (## Parallel runs).
# Usage: bench/scaling.sh [BUILD_DIR [ROUNDS [STEPS [DP...]]]]
set -euo pipefail
build=${1:-build}
rounds=${2:-3}
steps=${3:-30}
shift $(( $# > 3 ? 3 : $# ))
# dp 1.6 mm: 2.0e4 particles; 1.1 mm (l0 of the issue): 4.0e4; 0.65 mm: 1.1e5; 0.48 mm: 2.0e5
dps=("$@")
if [ ${#dps[@]} -eq 0 ]; then dps=(0.0016 0.0011 0.00065 0.00048); fi
bench="$build/bench/fluid/bench_fluid_dam_break"
cmake --build "$build" --target bench_fluid_dam_break >/dev/null  # not in the default build
mpi="mpirun --allow-run-as-root --oversubscribe -np"
stats() {  # median and smallest of the numbers on stdin
  sort -g | awk '{a[NR]=$1} END {printf "%s %s", (NR % 2) ? a[(NR+1)/2] : (a[NR/2]+a[NR/2+1])/2, a[1]}'
}
for dp in "${dps[@]}"; do
  declare -A totals=([1]="" [2]="")
  for r in $(seq "$rounds"); do
    for np in 1 2; do
      row=$($mpi $np $bench ssor "$steps" "$dp" | tail -1)
      echo "dp $dp round $r: $row"
      totals[$np]+="$(awk -F'|' '{print $(NF-5)}' <<< "$row" | tr -d ' ')"$'\n'
    done
  done
  read -r med1 best1 <<< "$(printf '%s' "${totals[1]}" | stats)"
  read -r med2 best2 <<< "$(printf '%s' "${totals[2]}" | stats)"
  awk -v dp="$dp" -v r="$rounds" -v m1="$med1" -v b1="$best1" -v m2="$med2" -v b2="$best2" 'BEGIN {
    printf "dp %s over %d rounds: 1 rank median %.2f best %.2f, 2 ranks median %.2f best %.2f ms/step; " \
           "speed-up of the medians %.2f, of the bests %.2f\n", dp, r, m1, b1, m2, b2, m1 / m2, b1 / b2 }'
  unset totals
done
