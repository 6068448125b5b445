#!/bin/bash
# Instructions per fluid step of the two pressure schemes (projection, standard), counted by valgrind's
# callgrind: the dam break of bench_fluid_dam_break (SSOR, one rank) run for N1 and N2 steps, and the
# difference per step, so that the set-up and the first step drop out. Unlike the wall time, the count does not
# depend on what else the machine runs (it does not see the memory's speed either). Results go to
# docs/performance.md ("Cost per step: the projection against the standard scheme").
# Usage: bench/scheme_instructions.sh [BUILD_DIR [DP [N1 N2]]]
set -euo pipefail
build=${1:-build}
dp=${2:-0.0016}
n1=${3:-20}
n2=${4:-40}
command -v valgrind > /dev/null || { echo "scheme_instructions.sh: valgrind is not installed" >&2; exit 2; }
bench="$build/bench/fluid/bench_fluid_dam_break"
cmake --build "$build" --target bench_fluid_dam_break >/dev/null  # not in the default build
dir=$(mktemp -d)
trap 'rm -rf "$dir"' EXIT
count() {  # scheme steps: the program's instructions
  valgrind --tool=callgrind --callgrind-out-file="$dir/cg.$1.$2" "$bench" ssor "$2" "$dp" "fluid.scheme=$1" \
    > "$dir/log.$1.$2" 2>&1
  grep -o 'refs: *[0-9,]*' "$dir/log.$1.$2" | tr -d ', ' | cut -d: -f2
}
declare -A per_step
for s in standard projection; do
  a=$(count "$s" "$n1") b=$(count "$s" "$n2")
  per_step[$s]=$(( (b - a) / (n2 - n1) ))
  echo "dp $dp, $s: $(awk -v x="${per_step[$s]}" 'BEGIN {printf "%.1f", x / 1e6}') M instructions per step (steps $n1 to $n2)"
done
echo "ratio projection / standard: $(awk -v a="${per_step[projection]}" -v b="${per_step[standard]}" 'BEGIN {printf "%.3f", a / b}')"
