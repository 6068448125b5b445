#!/bin/bash
# What this machine allows two ranks to gain on the fluid step, without any exchange between them: one rank on
# the dam break at DP against two independent one-rank runs started together at DP sqrt(2) (half the particles
# each), alternating in each round. The ratio of the one-rank time to the slower of the two halves is the
# speed-up two ranks would reach with no parallel overhead at all; below 2 it is what the two cores share
# (memory bandwidth, caches). Per round and, over the rounds, of the medians and of the bests.
# Results go to docs/performance.md ("Parallel runs").
# Usage: bench/scaling_bound.sh [BUILD_DIR [ROUNDS [STEPS [DP]]]]
set -euo pipefail
build=${1:-build}
rounds=${2:-5}
steps=${3:-20}
dp=${4:-0.00065}
half=$(awk -v d="$dp" 'BEGIN {printf "%.6g", d * sqrt(2)}')
bench="$build/bench/fluid/bench_fluid_dam_break"
cmake --build "$build" --target bench_fluid_dam_break >/dev/null  # not in the default build
total() { tail -1 | awk -F'|' '{print $(NF-5)}' | tr -d ' '; }
stats() { sort -g | awk '{a[NR]=$1} END {printf "%s %s", (NR % 2) ? a[(NR+1)/2] : (a[NR/2]+a[NR/2+1])/2, a[1]}'; }
ones="" pairs=""
for r in $(seq "$rounds"); do
  one=$("$bench" ssor "$steps" "$dp" | total)
  "$bench" ssor "$steps" "$half" | total > "${TMPDIR:-/tmp}/scaling_bound.$$.a" &
  b=$("$bench" ssor "$steps" "$half" | total)
  wait
  a=$(cat "${TMPDIR:-/tmp}/scaling_bound.$$.a")
  slower=$(awk -v a="$a" -v b="$b" 'BEGIN {print (a > b) ? a : b}')
  ones+="$one"$'\n' pairs+="$slower"$'\n'
  echo "round $r: 1 rank at dp $dp $one ms/step; two runs at dp $half together: $a and $b ms/step; ratio" \
       "$(awk -v o="$one" -v s="$slower" 'BEGIN {printf "%.2f", o / s}')"
done
rm -f "${TMPDIR:-/tmp}/scaling_bound.$$.a"
read -r m1 b1 <<< "$(printf '%s' "$ones" | stats)"
read -r m2 b2 <<< "$(printf '%s' "$pairs" | stats)"
awk -v m1="$m1" -v b1="$b1" -v m2="$m2" -v b2="$b2" -v r="$rounds" 'BEGIN {
  printf "over %d rounds: 1 rank median %.2f best %.2f, two halves together (slower) median %.2f best %.2f ms/step; " \
         "bound of the medians %.2f, of the bests %.2f\n", r, m1, b1, m2, b2, m1 / m2, b1 / b2 }'
