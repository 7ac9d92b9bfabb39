#!/usr/bin/env bash
# The byte-identity check for refactors: seeded runs of the shipped pipelines whose outputs must not change,
# then one sha256 line per output file (timing.csv, summary.json, the resolved pipeline and logs left out: they
# carry timings and paths). Run it on the build before a change and after, and diff the two listings:
#   scripts/outputs-checksum.sh build /tmp/before > before.sha   # ... change, rebuild ...
#   scripts/outputs-checksum.sh build /tmp/after > after.sha
#   diff <(sed 's|/tmp/before|X|' before.sha) <(sed 's|/tmp/after|X|' after.sha)
# Covers the demo (motion, masks, 34 reconstructed cars), KITTI 00 and 06 (monocular core), KITTI 00 with
# kitti_beslam.yaml (real images), urban_loop with a loop closure, its global BA and objects in BA, and a map
# saved and loaded for localisation. About 75 s on an idle 2-core machine; needs ../shared/data for KITTI.
set -uo pipefail
cd "$(dirname "$0")/.."
[ $# -eq 2 ] || { echo "usage: scripts/outputs-checksum.sh BUILD_DIR OUT_DIR" >&2; exit 2; }
build=$(realpath "$1") out=$2
[ -x "$build/bin/beslam" ] || { echo "outputs-checksum: $build/bin/beslam not found (build first)" >&2; exit 2; }
rm -rf "$out" && mkdir -p "$out"
status=0
run() {
  local name=$1
  shift
  "$build/bin/beslam" run "$@" --quiet --out "$out/$name" > "$out/$name.log" 2>&1 ||
    { echo "outputs-checksum: run $name failed (see $out/$name.log)" >&2; status=1; }
}
run demo configs/demo.yaml
run k00 configs/kitti_mono_orb.yaml --set dataset.sequence=00 --set backend.seed=42
run k06 configs/kitti_mono_orb.yaml --set dataset.sequence=06 --set backend.seed=3
run k00beslam configs/kitti_beslam.yaml --set dataset.sequence=00 --set backend.seed=42
run loopmono configs/reconstruction/mono.yaml --set dataset.sequence=urban_loop --set backend.seed=1 \
  --set backend.object_landmarks=ba
run k06save configs/kitti_mono_orb.yaml --set dataset.sequence=06 --set backend.seed=5 --save-map "$out/k06.map"
run k06load configs/kitti_mono_orb.yaml --set dataset.sequence=06 --set backend.seed=5 --load-map "$out/k06.map" \
  --localise-only
(cd "$out" && find . -type f ! -name '*.log' ! -name timing.csv ! -name summary.json ! -name pipeline.resolved.yaml \
  ! -name '*.lock' | sort | xargs sha256sum)
exit $status
