#!/usr/bin/env bash
# Rebuilds reconstructor_sdf's shipped car shape prior byte for byte (docs/reconstruction.md):
#   scripts/train-shape-prior.sh BUILD_DIR OUT     e.g. scripts/train-shape-prior.sh build /tmp/prior.bsdf
# then `cmp OUT plugins/reconstructor_sdf/data/car_shape_prior.bsdf`.
set -euo pipefail
build="${1:?usage: scripts/train-shape-prior.sh BUILD_DIR OUT}"
out="${2:?usage: scripts/train-shape-prior.sh BUILD_DIR OUT}"
"$build/bin/beslam-shape-prior" train --out "$out" --cars 200 --seed 1 --grid 44,22,22 --margin 0.15 --dims 0
