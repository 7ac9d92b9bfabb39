#!/usr/bin/env bash
# The README's test command: installs what is missing, checks the formatting, builds (Release) and runs
# every test (2 in parallel), then the sanitised build with its tests and the fuzz targets
# (scripts/sanitize.sh; BESLAM_SKIP_SANITIZE=1 leaves it out for a quick local run). docs/testing.md.
# Tests that need ../shared/data skip with a message where it is absent.
set -euo pipefail
cd "$(dirname "$0")/.."
scripts/install-deps.sh --test
scripts/check-format.sh
scripts/build.sh -DBESLAM_BUILD_TESTS=ON "$@"
(cd build && ctest --output-on-failure -j"${BESLAM_TEST_JOBS:-2}" --timeout 900)
if [ "${BESLAM_SKIP_SANITIZE:-}" != "1" ]; then
  scripts/sanitize.sh
fi
