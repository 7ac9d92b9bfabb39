#!/usr/bin/env bash
# The README's main job: installs what the build needs, builds the CLI and the plugins (not the tests:
# scripts/test.sh builds those), renders the embedded synthetic default sequence on first use (cached in
# build/synth-cache), runs the whole BE-SLAM pipeline on it (configs/demo.yaml) and prints the APE against
# the rendered ground truth. Output: out/demo/ (replaced on every run: --overwrite).
set -euo pipefail
cd "$(dirname "$0")/.."
scripts/install-deps.sh
# A build folder the tests already configured keeps its tests (and builds them too); a fresh one has none.
if [ -f build/CMakeCache.txt ] && grep -q '^BESLAM_BUILD_TESTS:BOOL=ON' build/CMakeCache.txt &&
  dpkg-query -W -f='${Status}' libgtest-dev 2>/dev/null | grep -q "install ok installed"; then
  scripts/build.sh
else
  scripts/build.sh -DBESLAM_BUILD_TESTS=OFF
fi
build/bin/beslam run configs/demo.yaml --out out/demo --overwrite "$@"
