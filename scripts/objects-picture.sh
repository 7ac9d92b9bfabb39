#!/usr/bin/env bash
# A picture of a run's reconstructed objects as the project's own viewer draws them: `beslam report`
# of the run, opened at index.html#objects (the 3D view alone, framed on the first object and its
# neighbours) in headless Chromium.
#   scripts/objects-picture.sh RUN_DIR OUT.png [WIDTHxHEIGHT (default 1200x700)]
# BESLAM_BUILD_DIR picks the build (default build). docs/images/objects.png was made this way from a
# run of configs/demo.yaml.
set -euo pipefail
cd "$(dirname "$0")/.."
run="${1:?usage: scripts/objects-picture.sh RUN_DIR OUT.png [WxH]}"
out="${2:?usage: scripts/objects-picture.sh RUN_DIR OUT.png [WxH]}"
size="${3:-1200x700}"
bin="${BESLAM_BUILD_DIR:-build}/bin/beslam"
[ -f "$run/objects.json" ] || { echo "objects-picture: $run/objects.json: no such file (a run with a reconstructor?)" >&2; exit 1; }
command -v chromium >/dev/null || { echo "objects-picture: chromium is not installed (scripts/install-deps.sh --test installs it)" >&2; exit 1; }
tmp="$(mktemp -d)"
trap 'rm -rf "$tmp"' EXIT
"$bin" report "$run" --out "$tmp/report" > "$tmp/report.log" 2>&1 || { cat "$tmp/report.log" >&2; exit 1; }
chromium --headless --no-sandbox --disable-gpu --enable-unsafe-swiftshader --disable-quic --no-first-run \
  --disable-background-networking --disable-component-update --disable-sync --hide-scrollbars \
  --window-size="${size/x/,}" --virtual-time-budget=15000 --user-data-dir="$tmp/profile" \
  --screenshot="$tmp/shot.png" "file://$(realpath "$tmp/report/index.html")#objects" > "$tmp/chromium.log" 2>&1 \
  || { cat "$tmp/chromium.log" >&2; exit 1; }
mkdir -p "$(dirname "$out")"
cp "$tmp/shot.png" "$out"
echo "objects-picture: $out"
