#!/usr/bin/env bash
# Issue 18's long-run figures: the demo pipeline (configs/demo.yaml: BE-SLAM with loop closing, the
# reconstructor and relocalisation) on urban_loop rendered for FRAMES frames (default 3000: 6.5 laps,
# 2.5 km), one run per seed under /usr/bin/time -v, then scripts/long-run-figures.py's table: per-frame
# time of the first and last 500 frames after initialisation, resident memory against frame number
# (timing.csv's rss_mb) and the peak (summary.json's peak_rss_mb). Wall-clock figures: run it on an
# otherwise idle machine. Runs that finished (summary.json present) are not run again.
#
#   scripts/long-run.sh OUT [--frames N] [--seeds "42 1 2 3 4"] [--build DIR]
set -euo pipefail
cd "$(dirname "$0")/.."
[ $# -ge 1 ] || { sed -n '2,9p' "$0"; exit 2; }
out=$1
shift
frames=3000
seeds="42 1 2 3 4"
build=build
while (($#)); do
  case "$1" in
    --frames) frames="$2"; shift 2 ;;
    --seeds) seeds="$2"; shift 2 ;;
    --build) build="$2"; shift 2 ;;
    *) echo "long-run: unknown argument $1" >&2; exit 2 ;;
  esac
done
[ -x "$build/bin/beslam" ] || { echo "long-run: $build/bin/beslam not found (build first)" >&2; exit 1; }
mkdir -p "$out"
runs=()
for s in $seeds; do
  run="$out/urban_loop-f$frames-s$s"
  runs+=("$run")
  [ -f "$run/summary.json" ] && ! grep -q '"status": "failed\|"interrupted": true' "$run/summary.json" && continue
  echo "long-run: seed $s, $frames frames -> $run"
  /usr/bin/time -v -o "$run.time" "$build/bin/beslam" run configs/demo.yaml \
    --set "dataset.synth_set=lidar.enabled=false,camera.colour=false,frames=$frames" --set backend.seed="$s" \
    --out "$run" --overwrite > "$run.out" 2> "$run.log"
done
scripts/long-run-figures.py "${runs[@]}"
