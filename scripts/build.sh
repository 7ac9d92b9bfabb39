#!/usr/bin/env bash
# Configures and builds BE-SLAM into build/ (Release, tests on). Extra arguments go to cmake's
# configure step, e.g. scripts/build.sh -DBESLAM_SANITIZE=ON.
set -euo pipefail
cd "$(dirname "$0")/.."
jobs="${BESLAM_JOBS:-$(nproc 2>/dev/null || echo 2)}"
cmake -S . -B build -DCMAKE_BUILD_TYPE="${BESLAM_BUILD_TYPE:-Release}" "$@"
cmake --build build -j"$jobs"
