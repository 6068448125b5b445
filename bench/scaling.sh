#!/bin/bash
# Strong scaling of the fluid step (bench_fluid_dam_break, SSOR) on 1 and 2 ranks of this machine, alternating
# the rank counts in each round so that both see the same load; then the one-rank cost per particle over the
# resolutions. Results go to docs/performance.md (## Parallel runs).
# Usage: bench/scaling.sh [BUILD_DIR [ROUNDS [STEPS]]]
set -euo pipefail
build=${1:-build}
rounds=${2:-3}
steps=${3:-30}
bench="$build/bench/fluid/bench_fluid_dam_break"
mpi="mpirun --allow-run-as-root --oversubscribe -np"
# dp 1.6 mm: 2.0e4 particles; 1.1 mm (l0 of the issue): 4.0e4; 0.65 mm: 1.1e5; 0.48 mm: 2.0e5
for dp in 0.0016 0.0011 0.00065 0.00048; do
  for r in $(seq "$rounds"); do
    for np in 1 2; do
      echo "dp $dp round $r: $($mpi $np $bench ssor "$steps" $dp | tail -1)"
    done
  done
done
