#!/usr/bin/env bash
# The measurements behind issue 15 (docs/reconstruction.md), rerunnable by anyone: parked cars
# reconstructed by reconstructor_sdf on the synthetic sequences, monocular (map points) with objects in
# local BA off and on, and with LiDAR; plus the true motion states as the coverage a perfect motion
# checker would give. Every run is an ordinary `beslam run` into OUT/<row>/<sequence>/seed<N> (finished
# runs are skipped on a rerun) scored by `beslam eval-objects`; the table (medians over seeds, min-max)
# goes to OUT/table.md and stdout.
#   scripts/reconstruction-bench.sh [OUT (default out/reconstruction)] [SEEDS (default "1 2 3 4 5")]
# BESLAM_BUILD_DIR picks the build (default build).
set -euo pipefail
cd "$(dirname "$0")/.."
out="${1:-out/reconstruction}"
seeds="${2:-1 2 3 4 5}"
source scripts/lib/run-matrix.sh  # bin, run_once

run() {  # run DIR CONFIG [--set k=v]...: the run (once), then its objects scored
  local dir="$1"
  run_once "$@"
  "$bin" eval-objects --run "$dir" --json "$dir/objects_score.json" > /dev/null
}

for s in $seeds; do
  for seq in urban_loop dynamic_street; do
    run "$out/mono/$seq/seed$s" configs/reconstruction/mono.yaml --set dataset.sequence="$seq" --set backend.seed="$s"
    run "$out/mono_objects_in_ba/$seq/seed$s" configs/reconstruction/mono.yaml --set dataset.sequence="$seq" \
      --set backend.seed="$s" --set backend.object_landmarks=ba
    run "$out/mono_true_states/$seq/seed$s" configs/reconstruction/mono.yaml --set dataset.sequence="$seq" \
      --set backend.seed="$s" --set motion_checker.plugin=none --set detector.true_motion=true \
      --set detector.pass_track_ids=true
  done
  for seq in dynamic_street urban_loop; do
    run "$out/lidar/$seq/seed$s" configs/reconstruction/lidar.yaml --set dataset.sequence="$seq" --set backend.seed="$s"
    run "$out/lidar_objects_in_ba/$seq/seed$s" configs/reconstruction/lidar.yaml --set dataset.sequence="$seq" \
      --set backend.seed="$s" --set backend.object_landmarks=ba
  done
done

python3 - "$out" <<'PY'
import os, statistics, sys
sys.path.insert(0, "scripts/lib")
from run_table import collect
out = sys.argv[1]
def stat(v, fmt="%.3f"):
    v = [x for x in v if x is not None and x >= 0]
    if not v: return "-"
    return (fmt + " (" + fmt + "-" + fmt + ")") % (statistics.median(v), min(v), max(v))
lines = ["| row | sequence | seeds | APE Sim(3) m | APE SE(3) m | objects | parked <=15 m correct | false | centre error m | heading <=10 deg | Chamfer m | shape-only Chamfer m |",
         "|---|---|---|---|---|---|---|---|---|---|---|---|"]
names = ["summary.json", "objects_score.json"]
for row, seq, runs in collect(out, names, required=names):
    ape = [j.get("ape", {}) for j, _ in runs]
    share = lambda o: o["parked_in_view_correct"] / o["parked_in_view"] if o["parked_in_view"] else None
    false = lambda o: o["false"] / o["reconstructed"] if o["reconstructed"] else None
    yaw10 = lambda o: (sum(1 for x in o["objects"] if x["parked"] and 0 <= x["yaw_error_deg"] <= 10) /
                       max(1, sum(1 for x in o["objects"] if x["parked"] and x["yaw_error_deg"] >= 0)))
    lines.append("| %s | %s | %d | %s | %s | %s | %s | %s | %s | %s | %s | %s |" % (
        row, seq, len(runs), stat([a.get("sim3_rmse") for a in ape]), stat([a.get("se3_rmse") for a in ape]),
        stat([o["reconstructed"] for _, o in runs], "%d"), stat([share(o) for _, o in runs]),
        stat([false(o) for _, o in runs]), stat([o["median_centre_error_m"] for _, o in runs]),
        stat([yaw10(o) for _, o in runs]), stat([o["median_chamfer_m"] for _, o in runs]),
        stat([o["median_shape_chamfer_m"] for _, o in runs])))
text = "\n".join(lines) + "\n"
open(os.path.join(out, "table.md"), "w").write(text)
print(text)
PY
