#!/usr/bin/env bash
# Quick start, step 1: install what is missing, configure, build (Release),
# and render the embedded default scene (the Cornell box) to
# out/cornell-box.png and out/cornell-box.pfm, printing per-stage timings.
set -euo pipefail
cd "$(dirname "$0")/.."
tools/install-deps.sh
cmake -S . -B build -DCMAKE_BUILD_TYPE=Release
cmake --build build -j "$(nproc)"
./build/softgi render "$@"
