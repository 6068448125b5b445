#!/bin/bash
# Instructions per fluid step on 1 rank and on each of 2 ranks (bench_fluid_dam_break, SSOR, the default scheme),
# counted by valgrind's callgrind inside FluidSolver::advance only (--toggle-collect): runs of N1 and N2 steps and
# the difference per step, so that the set-up and the first steps drop out. On 2 ranks the instructions a rank
# spends in MPI calls within the step (every PMPI_ function, inclusive: the waits, which under valgrind spin as long
# as the other rank works, and the messages' copies) are given apart: they measure the wait, not work. Waits outside
# the step (MPI_Finalize, the benchmark's own reductions) are not collected. What the 2 ranks do
# beyond the 1-rank count is the parallel overhead that no machine removes (ghosts, the block preconditioner's
# extra iterations, the exchanges); the count does not see the memory's speed. Results go to docs/performance.md
# ("Parallel runs").
# Usage: bench/scaling_instructions.sh [BUILD_DIR [DP [N1 N2 [OVERRIDE...]]]] (the overrides go to the benchmark,
# e.g. the 3D box of docs/performance.md with BUILD_DIR build/3d)
set -euo pipefail
build=${1:-build}
dp=${2:-0.00065}
n1=${3:-2}
n2=${4:-4}
shift $(( $# < 4 ? $# : 4 ))
command -v valgrind > /dev/null || { echo "scaling_instructions.sh: valgrind is not installed" >&2; exit 2; }
cmake --build "$build" --target bench_fluid_dam_break >/dev/null  # not in the default build
bench="$build/bench/fluid/bench_fluid_dam_break"
[ -x "$bench" ] || bench="$build/bench/bench_fluid_dam_break"  # the 3D build's place
mpi="mpirun --allow-run-as-root --oversubscribe -np"
dir=$(mktemp -d)
trap 'rm -rf "$dir"' EXIT
inclusive() {  # file function-pattern: the inclusive instruction count of the first function that matches
  callgrind_annotate --inclusive=yes "$1" 2> /dev/null | grep -E "$2" | head -1 | awk '{gsub(",", "", $1); print $1}'
}
in_mpi() {  # file: the inclusive instruction count of every MPI call (MPI calls do not nest)
  callgrind_annotate --inclusive=yes --threshold=100 "$1" 2> /dev/null | grep -E '\?\?\?:PMPI_' |
    awk '{gsub(",", "", $1); s += $1} END {print s + 0}'
}
for np in 1 2; do
  for n in "$n1" "$n2"; do
    $mpi "$np" valgrind --tool=callgrind --toggle-collect='mpsfsi::FluidSolver::advance(double, double)' \
      --callgrind-out-file="$dir/cg.$np.$n.%q{OMPI_COMM_WORLD_RANK}" \
      "$bench" ssor "$n" "$dp" "$@" > "$dir/log.$np.$n" 2>&1
  done
done
per_step() { awk -v a="$1" -v b="$2" -v d="$((n2 - n1))" 'BEGIN {printf "%.1f", (b - a) / d / 1e6}'; }
one=$(per_step "$(inclusive "$dir/cg.1.$n1.0" 'FluidSolver::advance')" "$(inclusive "$dir/cg.1.$n2.0" 'FluidSolver::advance')")
echo "dp $dp, 1 rank: $one M instructions per step in FluidSolver::advance (steps $n1 to $n2)"
work_total=0
for r in 0 1; do
  adv=$(per_step "$(inclusive "$dir/cg.2.$n1.$r" 'FluidSolver::advance')" "$(inclusive "$dir/cg.2.$n2.$r" 'FluidSolver::advance')")
  wait=$(per_step "$(in_mpi "$dir/cg.2.$n1.$r")" "$(in_mpi "$dir/cg.2.$n2.$r")")
  work=$(awk -v a="$adv" -v w="$wait" 'BEGIN {printf "%.1f", a - w}')
  work_total=$(awk -v s="$work_total" -v w="$work" 'BEGIN {print s + w}')
  echo "dp $dp, 2 ranks, rank $r: $work M of work per step (FluidSolver::advance, $adv M, less its MPI calls; their waits vary from run to run)"
done
awk -v one="$one" -v two="$work_total" 'BEGIN {
  printf "2 ranks do %.3f times the work of 1 (%.1f M); a speed-up of at most %.2f with the work split evenly\n",
         two / one, two, 2 * one / two }'
