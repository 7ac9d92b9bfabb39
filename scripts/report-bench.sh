#!/usr/bin/env bash
# Size of a run's HTML report and the time headless Chromium takes to load and draw it (issue 16 targets:
# under 20 MB for a 500-frame run, drawn in under 5 s). Not a test: it prints figures.
#   scripts/report-bench.sh RUN_DIR [REPEATS (default 3)]
# The time is wall time of `chromium --headless --dump-dom` until the page reports data-status="ready",
# minus the same for an empty page (browser start-up), best of REPEATS; and the page's own figure, from
# navigation start to drawn (body data-ready-ms, performance.now()).
set -euo pipefail
cd "$(dirname "$0")/.."
run="${1:?usage: scripts/report-bench.sh RUN_DIR [REPEATS]}"
repeats="${2:-3}"
bin="${BESLAM_BUILD_DIR:-build}/bin/beslam"
command -v chromium >/dev/null || { echo "report-bench: chromium is not installed (scripts/install-deps.sh --test)" >&2; exit 1; }
tmp="$(mktemp -d)"
trap 'rm -rf "$tmp"' EXIT
"$bin" report "$run" --out "$tmp/report" > /dev/null
echo "report size: $(du -sb "$tmp/report" | cut -f1) bytes ($(du -sh "$tmp/report" | cut -f1)), files: $(find "$tmp/report" -type f | wc -l)"
echo '<html><body data-status="ready"></body></html>' > "$tmp/empty.html"
chrome() {  # chrome URL: seconds until the DOM is dumped
  local t0 t1
  t0=$(date +%s.%N)
  chromium --headless --no-sandbox --disable-gpu --enable-unsafe-swiftshader --disable-quic --no-first-run \
    --disable-background-networking --disable-component-update --disable-sync --window-size=1280,2200 \
    --user-data-dir="$tmp/profile" --dump-dom "$1" 2>/dev/null > "$tmp/dom.html"
  t1=$(date +%s.%N)
  grep -q 'data-status="ready"' "$tmp/dom.html" || { echo "report-bench: the page did not finish drawing" >&2; exit 1; }
  awk -v a="$t0" -v b="$t1" 'BEGIN { printf "%.3f", b - a }'
}
best_page=999; best_empty=999
for _ in $(seq "$repeats"); do
  e=$(chrome "file://$tmp/empty.html"); p=$(chrome "file://$tmp/report/index.html")
  best_empty=$(awk -v a="$e" -v b="$best_empty" 'BEGIN { print (a < b ? a : b) }')
  best_page=$(awk -v a="$p" -v b="$best_page" 'BEGIN { print (a < b ? a : b) }')
done
ready_ms=$(grep -o 'data-ready-ms="[0-9]*"' "$tmp/dom.html" | grep -o '[0-9]*')
echo "chromium: the page itself, navigation start to drawn (last run): $ready_ms ms"
echo "chromium: report page $best_page s, empty page $best_empty s, the report's own load and draw $(awk -v a="$best_page" -v b="$best_empty" 'BEGIN { printf "%.3f", a - b }') s (best of $repeats)"
