#!/bin/bash
# Cost per step of the default pressure scheme (projection) against the standard scheme: the fluid step of the
# dam break (bench_fluid_dam_break, SSOR, one rank) alternating the two schemes in each round, the order flipped
# from round to round so that neither always runs first; each round's ratio of the two totals, the median of the
# ratios, and the ratio of each scheme's best (smallest) total over the rounds: the figure least touched by other
# work on a shared machine, which only ever adds time. Results go to docs/performance.md ("Cost per step: the
# projection against the standard scheme").
# Usage: bench/scheme_cost.sh [BUILD_DIR [ROUNDS [DP STEPS]...]]
set -euo pipefail
build=${1:-build}
rounds=${2:-5}
shift $(( $# > 2 ? 2 : $# ))
runs=("$@")
if [ ${#runs[@]} -eq 0 ]; then runs=(0.0016 100 0.00065 20); fi
bench="$build/bench/fluid/bench_fluid_dam_break"
cmake --build "$build" --target bench_fluid_dam_break >/dev/null  # not in the default build
total() {  # the total ms per step of one run (the "total ms/step" column of the table's last row)
  "$bench" ssor "$2" "$1" "fluid.scheme=$3" | tail -1 | awk -F'|' '{print $(NF-5)}' | tr -d ' '
}
for ((k = 0; k < ${#runs[@]}; k += 2)); do
  dp=${runs[k]} steps=${runs[k+1]}
  ratios=()
  best_standard="" best_projection=""
  for r in $(seq "$rounds"); do
    if (( r % 2 )); then order=(standard projection); else order=(projection standard); fi
    declare -A ms=()
    for s in "${order[@]}"; do ms[$s]=$(total "$dp" "$steps" "$s"); done
    ratio=$(awk -v a="${ms[projection]}" -v b="${ms[standard]}" 'BEGIN {printf "%.3f", a / b}')
    ratios+=("$ratio")
    best_standard=$(awk -v a="${ms[standard]}" -v b="$best_standard" 'BEGIN {print (b == "" || a < b) ? a : b}')
    best_projection=$(awk -v a="${ms[projection]}" -v b="$best_projection" 'BEGIN {print (b == "" || a < b) ? a : b}')
    echo "dp $dp round $r: standard ${ms[standard]} ms, projection ${ms[projection]} ms per step, ratio $ratio"
    unset ms
  done
  median=$(printf '%s\n' "${ratios[@]}" | sort -g | awk '{a[NR]=$1} END {print (NR % 2) ? a[(NR+1)/2] : (a[NR/2]+a[NR/2+1])/2}')
  echo "dp $dp over $rounds rounds: median ratio $median; best standard $best_standard ms, best projection" \
       "$best_projection ms, ratio of the bests $(awk -v a="$best_projection" -v b="$best_standard" 'BEGIN {printf "%.3f", a / b}')"
done
