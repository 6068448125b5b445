#!/usr/bin/env bash
# Runs the tests of the 3D build (MPSFSI_DIM=3), which scripts/setup.sh builds with the 2D one in build/3d
# (CMake option MPSFSI_WITH_3D): the core tests and tests/dim3. Called by .ci/run after the 2D suite;
# developers can run it by hand. MPSFSI_JOBS sets the parallel jobs (default: nproc).
set -euo pipefail
cd "$(dirname "$0")/.."

jobs=${MPSFSI_JOBS:-$(nproc)}
if [ ! -f build/3d/CTestTestfile.cmake ]; then
  echo "test3d.sh: no 3D build in build/3d; build with scripts/setup.sh (CMake option MPSFSI_WITH_3D=ON)" >&2
  exit 2
fi
ctest --test-dir build/3d --output-on-failure -j "$jobs" -LE long
