#!/usr/bin/env bash
# Reproduces backend_orb's default ORB vocabulary (plugins/backend_orb/data/orb_vocabulary.bvoc) from
# the project's own synthetic renders only (docs/place-recognition.md): renders the five synthetic
# sequences of configs/synth/ (grey camera only), then trains with a fixed seed.
#   scripts/train-vocabulary.sh [BUILD_DIR] [OUT_FILE]
# Needs a build with the simulator (build/bin/beslam synth) and build/bin/beslam-vocab.
set -euo pipefail
cd "$(dirname "$0")/.."
build="${1:-build}"
out="${2:-plugins/backend_orb/data/orb_vocabulary.bvoc}"
work="$(mktemp -d)"
trap 'rm -rf "$work"' EXIT
dirs=()
for seq in urban_loop static_loop static_street dynamic_street highway; do
  "$build/bin/beslam" synth --config "configs/synth/$seq.yaml" --out "$work/$seq" \
    --set frames=120 --set camera.colour=false --set lidar.enabled=false >/dev/null
  dirs+=(--images "$work/$seq/sequences/00/image_0")
done
"$build/bin/beslam" vocab train "${dirs[@]}" --out "$out" --k 10 --levels 6 --seed 1 --max-images 100 \
  --features 1000
