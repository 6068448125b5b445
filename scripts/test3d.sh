#!/usr/bin/env bash
# Builds the 3D toolkit (MPSFSI_DIM=3, in build3d/: the program build3d/mpsfsi runs 3D cases) and runs
# its tests: the core tests and tests/dim3. Called by .ci/run after the 2D suite; developers can run it by hand.
# MPSFSI_JOBS sets the parallel jobs (default: nproc).
set -euo pipefail
cd "$(dirname "$0")/.."

jobs=${MPSFSI_JOBS:-$(nproc)}
cmake -S . -B build3d -DCMAKE_BUILD_TYPE=Release -DMPSFSI_DIM=3
cmake --build build3d -j "$jobs"
ctest --test-dir build3d --output-on-failure -j "$jobs" -LE long
