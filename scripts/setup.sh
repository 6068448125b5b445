#!/usr/bin/env bash
# One-step setup for mpsfsi on Debian 12: installs the missing Debian packages (as root),
# configures and builds in Release into build/ (the 2D program, and the 3D one in build/3d). Safe to run
# again: it only installs what is missing.
set -euo pipefail
cd "$(dirname "$0")/.."

packages=(build-essential cmake git pkg-config
  trilinos-all-dev libptscotch-dev libeigen3-dev libopenmpi-dev openmpi-bin
  libvtk9-dev libgtest-dev libyaml-cpp-dev libcli11-dev libfmt-dev libbenchmark-dev
  python3 python3-matplotlib python3-numpy python3-scipy python3-vtk9 python3-yaml xvfb xauth
  valgrind)  # valgrind: bench/scheme_instructions.sh
missing=()
for p in "${packages[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done
if [ ${#missing[@]} -gt 0 ]; then
  echo "setup: installing ${missing[*]}"
  if [ "$(id -u)" -ne 0 ]; then
    echo "setup: missing packages and not root; run as root or install: ${missing[*]}" >&2
    exit 1
  fi
  export DEBIAN_FRONTEND=noninteractive
  apt-get update -qq
  apt-get install -y -qq "${missing[@]}"
fi

jobs=${MPSFSI_JOBS:-$(nproc)}
cmake -S . -B build -DCMAKE_BUILD_TYPE=Release
cmake --build build -j "$jobs"
