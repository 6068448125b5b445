#!/bin/bash
# What this machine allows two ranks to gain on the fluid step, and how much of it the 2-rank run takes. In each
# round, in turn: one rank on the dam break at DP; two independent one-rank runs started together at DP sqrt(2)
# (half the particles each, no exchange between them at all); and the real 2-rank run at DP. The ratio of the
# one-rank time to the slower of the two halves is the speed-up two ranks would reach with no parallel overhead;
# below 2 it is what the two cores share (memory bandwidth, caches). The 2-rank speed-up is given beside it and
# as a fraction of it. Per round and, over the rounds, of the medians and of the bests.
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
mpi="mpirun --allow-run-as-root --oversubscribe -np 2"
total() { tail -1 | awk -F'|' '{print $(NF-5)}' | tr -d ' '; }
stats() { sort -g | awk '{a[NR]=$1} END {printf "%s %s", (NR % 2) ? a[(NR+1)/2] : (a[NR/2]+a[NR/2+1])/2, a[1]}'; }
scratch="${TMPDIR:-/tmp}/scaling_bound.$$.a"
ones="" pairs="" twos=""
for r in $(seq "$rounds"); do
  one=$("$bench" ssor "$steps" "$dp" | total)
  "$bench" ssor "$steps" "$half" | total > "$scratch" &
  b=$("$bench" ssor "$steps" "$half" | total)
  wait
  a=$(cat "$scratch")
  slower=$(awk -v a="$a" -v b="$b" 'BEGIN {print (a > b) ? a : b}')
  two=$($mpi "$bench" ssor "$steps" "$dp" | total)
  ones+="$one"$'\n' pairs+="$slower"$'\n' twos+="$two"$'\n'
  echo "round $r: 1 rank at dp $dp $one ms/step; two runs at dp $half together: $a and $b ms/step; 2 ranks" \
       "$two ms/step; bound $(awk -v o="$one" -v s="$slower" 'BEGIN {printf "%.2f", o / s}')," \
       "2 ranks $(awk -v o="$one" -v t="$two" 'BEGIN {printf "%.2f", o / t}')"
done
rm -f "$scratch"
read -r m1 b1 <<< "$(printf '%s' "$ones" | stats)"
read -r mh bh <<< "$(printf '%s' "$pairs" | stats)"
read -r m2 b2 <<< "$(printf '%s' "$twos" | stats)"
awk -v m1="$m1" -v b1="$b1" -v mh="$mh" -v bh="$bh" -v m2="$m2" -v b2="$b2" -v r="$rounds" 'BEGIN {
  printf "over %d rounds (ms/step, median and best): 1 rank %.2f %.2f; two halves together (slower) %.2f %.2f; " \
         "2 ranks %.2f %.2f\n", r, m1, b1, mh, bh, m2, b2
  printf "bound of the medians %.2f, of the bests %.2f; 2-rank speed-up of the medians %.2f (%.0f %% of the " \
         "bound), of the bests %.2f (%.0f %%)\n", m1 / mh, b1 / bh, m1 / m2, 100 * mh / m2, b1 / b2, 100 * bh / b2 }'
