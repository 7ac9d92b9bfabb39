#!/usr/bin/env bash
# The README's test command: installs what is missing, builds, runs every test (2 in parallel).
# Tests that need ../shared/data skip with a message where it is absent.
set -euo pipefail
cd "$(dirname "$0")/.."
scripts/install-deps.sh
scripts/build.sh "$@"
cd build
ctest --output-on-failure -j"${BESLAM_TEST_JOBS:-2}" --timeout 900
