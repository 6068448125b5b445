#!/bin/bash
# What this machine allows two ranks to gain on the fluid step, and how much of it the 2-rank run takes. In each
# round, in turn: one rank on the dam break at DP; two independent one-rank runs started together at DP sqrt(2)
# (half the particles each, no exchange between them at all); and the real 2-rank run at DP. The ratio of the
# one-rank time to the slower of the two halves is the speed-up two ranks would reach with no parallel overhead;
# below 2 it is what the two cores share (memory bandwidth, caches). The 2-rank speed-up is given beside it and
# as a fraction of it. Per round and, over the rounds, of the medians and of the bests; then the phases of each
# (medians over the rounds; of the slower half, and of 2 ranks each phase on its slower rank, as the benchmark
# reports it).
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
total() { awk -F'|' '{print $(NF-5)}' | tr -d ' '; }
row() { tail -1 | tr -d '()' ; }  # the benchmark's table row: | ranks | particles | phases ... | total | ...
stats() { sort -g | awk '{a[NR]=$1} END {printf "%s %s", (NR % 2) ? a[(NR+1)/2] : (a[NR/2]+a[NR/2+1])/2, a[1]}'; }
scratch="${TMPDIR:-/tmp}/scaling_bound.$$.a"
ones="" pairs="" twos="" rows1="" rowsh="" rows2=""
for r in $(seq "$rounds"); do
  row1=$("$bench" ssor "$steps" "$dp" | row)
  "$bench" ssor "$steps" "$half" | row > "$scratch" &
  rowb=$("$bench" ssor "$steps" "$half" | row)
  wait
  rowa=$(cat "$scratch")
  one=$(total <<< "$row1") a=$(total <<< "$rowa") b=$(total <<< "$rowb")
  slower=$(awk -v a="$a" -v b="$b" 'BEGIN {print (a > b) ? a : b}')
  if awk -v a="$a" -v b="$b" 'BEGIN {exit !(a > b)}'; then rowh=$rowa; else rowh=$rowb; fi
  row2=$($mpi "$bench" ssor "$steps" "$dp" | row)
  two=$(total <<< "$row2")
  ones+="$one"$'\n' pairs+="$slower"$'\n' twos+="$two"$'\n'
  rows1+="$row1"$'\n' rowsh+="$rowh"$'\n' rows2+="$row2"$'\n'
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
# The phases, medians over the rounds (ms per step; CG iterations per step in parentheses).
phases() {
  awk -F'|' '{for (c = 4; c <= 10; ++c) {split($c, f, " "); v[c, NR] = f[1]; if (c == 7) it[NR] = f[2]}}
    END {
      for (c = 4; c <= 11; ++c) {
        n = 0
        for (r = 1; r <= NR; ++r) {  # insertion sort (POSIX awk has no asort)
          x = (c == 11) ? it[r] : v[c, r]
          for (k = ++n; k > 1 && a[k - 1] > x; --k) a[k] = a[k - 1]
          a[k] = x
        }
        m[c] = (n % 2) ? a[(n + 1) / 2] : (a[n / 2] + a[n / 2 + 1]) / 2
      }
      printf "%.1f | %.1f | %.1f | %.1f (%.1f) | %.1f | %.1f | %.1f\n", m[4], m[5], m[6], m[7], m[11], m[8], m[9], m[10]
    }'
}
echo "phases, medians (neighbours | assembly | prec. setup | solve (CG iterations) | halo | rest | total, ms/step):"
printf '  1 rank: %s\n' "$(printf '%s' "$rows1" | phases)"
printf '  the slower half: %s\n' "$(printf '%s' "$rowsh" | phases)"
printf '  2 ranks (each phase on its slower rank): %s\n' "$(printf '%s' "$rows2" | phases)"
