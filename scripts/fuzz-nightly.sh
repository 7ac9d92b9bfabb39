#!/usr/bin/env bash
# The long fuzz run (issue 17): every libFuzzer target in tests/fuzz for BESLAM_FUZZ_RUNS executions
# (default 1,000,000; CI runs 10,000), in the sanitised build. A finding fails with libFuzzer's report
# and the input in base64; add the input to tests/fuzz/corpus/<target>/ once fixed.
set -euo pipefail
cd "$(dirname "$0")/.."
BESLAM_FUZZ_RUNS=${BESLAM_FUZZ_RUNS:-1000000} BESLAM_SANITIZE_ONLY=fuzz exec scripts/sanitize.sh
