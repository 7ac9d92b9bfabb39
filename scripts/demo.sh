#!/usr/bin/env bash
# The README's main job: installs what the build needs, builds the CLI and the plugins the demo loads (not the tests:
# scripts/test.sh builds those), renders the embedded synthetic default sequence on first use (cached in
# build/synth-cache), runs the whole BE-SLAM pipeline on it (configs/demo.yaml) and prints the APE against
# the rendered ground truth. Output: out/demo/ (replaced on every run: --overwrite).
set -euo pipefail
cd "$(dirname "$0")/.."
scripts/install-deps.sh
# Only what the demo loads (the command and the plugins configs/demo.yaml names: target beslam_demo; the
# other plugins: target beslam_runtime). A build folder the tests already configured keeps its tests for
# scripts/test.sh; a fresh one is configured without them.
tests=OFF
if [ -f build/CMakeCache.txt ] && grep -q '^BESLAM_BUILD_TESTS:BOOL=ON' build/CMakeCache.txt &&
  dpkg-query -W -f='${Status}' libgtest-dev 2>/dev/null | grep -q "install ok installed"; then
  tests=ON
fi
cmake -S . -B build -DCMAKE_BUILD_TYPE="${BESLAM_BUILD_TYPE:-Release}" -DBESLAM_BUILD_TESTS=$tests
cmake --build build -j"${BESLAM_JOBS:-$(nproc 2>/dev/null || echo 2)}" --target beslam_demo
build/bin/beslam run configs/demo.yaml --out out/demo --overwrite "$@"
echo "demo: built only the demo's plugins; every other plugin (KITTI, replay pipelines):" \
  "cmake --build build -j2 --target beslam_runtime; the LiDAR detector needs PCL first: scripts/install-deps.sh --lidar"
