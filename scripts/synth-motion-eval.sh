#!/usr/bin/env bash
# The motion benchmark on synthetic data, where truth is exact: renders a synth preset (default
# dynamic_street), turns its ground-truth labels into AB3DMOT detection rows (optionally with seeded
# Gaussian noise on the centre), lays them out like KITTI tracking (label_02, ego poses, detections) and
# runs build/bin/motion_bench on it — the same scoring as the real KITTI tracking benchmark.
#   scripts/synth-motion-eval.sh [PRESET] [POSITION_NOISE_M] [WORK_DIR]
set -euo pipefail
cd "$(dirname "$0")/.."
preset="${1:-dynamic_street}"
noise="${2:-0}"
work="${3:-build/synth-motion/$preset-noise$noise}"
synth="build/synth-motion/$preset"
bin="${BESLAM_BUILD_DIR:-build}/bin"
if [ ! -f "$synth/sequences/00/label_02/00.txt" ]; then
  "$bin/beslam" synth --config "$preset" --out "$synth" --set lidar.enabled=false --set camera.colour=false
fi
rm -rf "$work"
mkdir -p "$work/label_02" "$work/ego_poses_orbslam3" "$work/det_pointrcnn/Car" "$work/det_pointrcnn/Pedestrian" "$work/det_pointrcnn/Cyclist"
cp "$synth/sequences/00/label_02/00.txt" "$work/label_02/0000.txt"
cp "$synth/poses/00.txt" "$work/ego_poses_orbslam3/0000.txt"
# label row: frame id type trunc occ alpha x1 y1 x2 y2 h w l x y z ry
# AB3DMOT:   frame class x1 y1 x2 y2 score(logit) h w l x y z ry alpha
awk -v sigma="$noise" -v out="$work/det_pointrcnn" 'BEGIN { srand(12345) }
  function gauss() { u1 = rand(); if (u1 < 1e-12) u1 = 1e-12; return sqrt(-2 * log(u1)) * cos(6.283185307 * rand()) }
  $3 == "Car" || $3 == "Van" || $3 == "Pedestrian" {
    cls = ($3 == "Pedestrian") ? 1 : 2; file = (cls == 1) ? out "/Pedestrian/0000.txt" : out "/Car/0000.txt"
    x = $14 + sigma * gauss(); z = $16 + sigma * gauss()
    printf "%d,%d,%s,%s,%s,%s,5.0,%s,%s,%s,%.4f,%s,%.4f,%s,%s\n", $1, cls, $7, $8, $9, $10, $11, $12, $13, x, $15, z, $17, $6 > file
  }' "$synth/sequences/00/label_02/00.txt"
: > "$work/det_pointrcnn/Cyclist/0000.txt"
"$bin/motion_bench" --root "$work" --sequences 0000
