#!/usr/bin/env bash
# The README's main job: installs what is missing, builds, renders the embedded synthetic default
# sequence on first use (cached in build/synth-cache), runs the whole BE-SLAM pipeline on it
# (configs/demo.yaml) and prints the APE against the rendered ground truth. Output: out/demo/ (replaced on
# every run: --overwrite).
set -euo pipefail
cd "$(dirname "$0")/.."
scripts/install-deps.sh
scripts/build.sh
build/bin/beslam run configs/demo.yaml --out out/demo --overwrite "$@"
