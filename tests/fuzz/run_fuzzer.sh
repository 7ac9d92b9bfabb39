#!/usr/bin/env bash
# run_fuzzer.sh FUZZER SEED_CORPUS RUNS: RUNS executions of a libFuzzer target, seeded (-seed=1) from
# SEED_CORPUS, new inputs kept in a scratch folder (the repo's corpus is not touched). A finding (crash,
# sanitizer report, leak, an exception escaping) fails with libFuzzer's report and the input saved.
set -euo pipefail
fuzzer=$1 seeds=$2 runs=$3
scratch=$(mktemp -d)
trap 'rm -rf "$scratch"' EXIT
cd "$scratch"
"$fuzzer" -seed=1 -runs="$runs" -max_len=4096 -rss_limit_mb=2048 -artifact_prefix="$scratch/" \
  "$scratch" "$seeds" 2>&1 | tail -n 25
status=${PIPESTATUS[0]}
if ls "$scratch"/crash-* "$scratch"/leak-* "$scratch"/oom-* "$scratch"/timeout-* >/dev/null 2>&1; then
  for f in "$scratch"/crash-* "$scratch"/leak-* "$scratch"/oom-* "$scratch"/timeout-*; do
    [ -e "$f" ] && { echo "finding: $(basename "$f") (base64):"; base64 -w0 "$f"; echo; }
  done
fi
exit "$status"
