#!/usr/bin/env bash
# run_fuzzer.sh FUZZER SEED_CORPUS RUNS: RUNS executions of a libFuzzer target, seeded (-seed=1) from
# SEED_CORPUS (which may be absent) and the seeds the target writes itself, new inputs kept in a scratch folder (the repo's corpus is not touched). A finding (crash,
# sanitizer report, leak, an exception escaping) fails with the end of libFuzzer's report and the input
# in base64 (to add to the corpus once fixed). An input that runs longer than BESLAM_FUZZ_TIMEOUT seconds
# (default 25) is a finding too: a hang (the alias bomb that hung the YAML loader) is a bug.
set -uo pipefail
fuzzer=$1 seeds=$2 runs=$3
scratch=$(mktemp -d)
trap 'rm -rf "$scratch"' EXIT
cd "$scratch"
# A target that writes its own seeds (binary inputs are made, not kept in the repo) is asked for them first.
corpora=("$seeds")
if grep -q BESLAM_FUZZ_WRITE_SEEDS "$fuzzer"; then
  mkdir -p "$scratch/made" && BESLAM_FUZZ_WRITE_SEEDS="$scratch/made" "$fuzzer" > /dev/null 2>&1
  corpora+=("$scratch/made")
fi
[ -d "$seeds" ] || corpora=("${corpora[@]:1}")
"$fuzzer" -seed=1 -runs="$runs" -max_len=4096 -rss_limit_mb=2048 -timeout="${BESLAM_FUZZ_TIMEOUT:-25}" \
  -artifact_prefix="$scratch/" \
  "$scratch" "${corpora[@]}" > "$scratch/fuzz.log" 2>&1
status=$?
tail -n 25 "$scratch/fuzz.log"
for f in "$scratch"/crash-* "$scratch"/leak-* "$scratch"/oom-* "$scratch"/timeout-*; do
  [ -e "$f" ] && { echo "finding: $(basename "$f") (base64):"; base64 -w0 "$f"; echo; }
done
exit "$status"
