#!/usr/bin/env bash
# The ablation behind issue 14 ("does trusting parked cars help?"), rerunnable by anyone:
#   no semantics / every car masked (DynaSLAM-style) / BE-SLAM with our motion checker / BE-SLAM with the
#   true motion states, and BE-SLAM with reconstructed parked cars in local BA (issue 15), on synthetic
#   urban_loop and dynamic_street (5 backend seeds each), all with the metric ORB backend, and on dynamic_street BE-SLAM with the LiDAR detector; then the real KITTI 00 and
#   06 excerpts (../shared/data) with the image detector.
# Every run is an ordinary `beslam run` into OUT/<pipeline>/<sequence>/seed<N> (a finished run is skipped
# when the script is run again); the table (medians over seeds, min-max) goes to OUT/table.md and stdout.
#   scripts/ablation.sh [OUT (default out/ablation)] [SEEDS (default "42 1 2 3 4")] [SEQUENCES]
# BESLAM_BUILD_DIR picks the build (default build); BESLAM_ABLATION_REAL=0 skips the KITTI rows;
# BESLAM_ABLATION_LIDAR=1 renders the synthetic sequences with their LiDAR scans, which backend_orb then
# uses for the metric scale (lidar_scale; the boxes stay the oracle's), so the rows compare on a map whose
# scale does not drift (docs/metric-scale.md "With a LiDAR").
set -euo pipefail
cd "$(dirname "$0")/.."
out="${1:-out/ablation}"
seeds="${2:-42 1 2 3 4}"
sequences="${3:-urban_loop dynamic_street}"
source scripts/lib/run-matrix.sh  # bin, run_once
lidar_args=()
[ "${BESLAM_ABLATION_LIDAR:-0}" = 1 ] && lidar_args=(--set dataset.synth_set=camera.colour=false --set dataset.lidar=true)
run() { run_once "$@"; }
synth() { run_once "$@" "${lidar_args[@]}"; }

mkdir -p "$out"
for s in $seeds; do  # seeds outermost: a partial sweep still compares every pipeline
  for seq in $sequences; do
    for p in synth_no_semantics synth_mask_all_cars synth_beslam synth_beslam_true_states; do
      mkdir -p "$out/$p/$seq"
      synth "$out/$p/$seq/seed$s" "configs/ablation/$p.yaml" --set dataset.sequence="$seq" --set backend.seed="$s"
      [ "$p" = synth_no_semantics ] || "$bin" eval-motion --run "$out/$p/$seq/seed$s" --json "$out/$p/$seq/seed$s/motion.json" > /dev/null
    done
    # The paper's whole loop: BE-SLAM with parked cars reconstructed from the map points on them
    # (reconstructor_sdf) and the objects in local BA (configs/reconstruction/mono.yaml is synth_beslam
    # plus the reconstructor).
    p=synth_beslam_objects_in_ba
    mkdir -p "$out/$p/$seq"
    synth "$out/$p/$seq/seed$s" configs/reconstruction/mono.yaml --set dataset.sequence="$seq" --set backend.seed="$s" \
      --set backend.object_landmarks=ba
    "$bin" eval-motion --run "$out/$p/$seq/seed$s" --json "$out/$p/$seq/seed$s/motion.json" > /dev/null
    if [ "$seq" = dynamic_street ]; then  # the LiDAR detector instead of the oracle (the scans are there)
      p=synth_beslam_lidar
      mkdir -p "$out/$p/$seq"
      run "$out/$p/$seq/seed$s" "configs/ablation/$p.yaml" --set dataset.sequence="$seq" --set backend.seed="$s"
      "$bin" eval-motion --run "$out/$p/$seq/seed$s" --json "$out/$p/$seq/seed$s/motion.json" > /dev/null
    fi
  done
done

if [ "${BESLAM_ABLATION_REAL:-1}" = 0 ]; then
  echo "ablation: BESLAM_ABLATION_REAL=0: real-data rows skipped" >&2
elif [ -d ../shared/data/kitti/odometry ] && [ -f ../shared/models/yolo-fastest-1.1/yolo-fastest-1.1.weights ]; then
  for seq in 00 06; do
    for s in $seeds; do
      for p in kitti_no_semantics kitti_mask_all_cars kitti_beslam; do mkdir -p "$out/$p/$seq"; done
      run "$out/kitti_no_semantics/$seq/seed$s" configs/kitti_mono_orb_metric.yaml \
        --set dataset.sequence="$seq" --set backend.seed="$s"
      run "$out/kitti_mask_all_cars/$seq/seed$s" configs/kitti_detector_image_metric.yaml \
        --set dataset.sequence="$seq" --set backend.seed="$s" --set motion_checker.plugin=none
      run "$out/kitti_beslam/$seq/seed$s" configs/kitti_detector_image_metric.yaml \
        --set dataset.sequence="$seq" --set backend.seed="$s"
    done
  done
else
  echo "ablation: ../shared/data (KITTI) or ../shared/models (Yolo-Fastest) absent: real-data rows skipped" >&2
fi

python3 - "$out" <<'PY'
import os, statistics, sys
sys.path.insert(0, "scripts/lib")
from run_table import collect
out = sys.argv[1]
rows = collect(out, ["summary.json", "motion.json"], required=["summary.json"])
def stat(v):
    v = [x for x in v if x is not None]
    if not v: return "-"
    return "%.3f (%.3f-%.3f)" % (statistics.median(v), min(v), max(v)) if max(v) < 1000 else "%d (%d-%d)" % (statistics.median(v), min(v), max(v))
lines = ["| pipeline | sequence | seeds | frames tracked | APE Sim(3) m | APE SE(3) m | Sim(3) scale | metric from frame | detections static/dynamic/unknown (median) | F1 dyn | parked <=30 m called static |",
         "|---|---|---|---|---|---|---|---|---|---|---|"]
for p, seq, runs in rows:
    ape = [j.get("ape", {}) for j, _ in runs]
    det = [j.get("detections", {}) for j, _ in runs]
    mot = [m for _, m in runs if m]
    med = lambda k: int(statistics.median([d.get(k, 0) for d in det]))
    f1 = stat([m["f1_dynamic"] for m in mot]) if mot else "-"
    near = stat([m["standing_near_static"] / m["standing_near"] if m["standing_near"] else None for m in mot]) if mot else "-"
    mf = [j.get("world", {}).get("metric_from_frame") for j, _ in runs]
    tracked = [j.get("tracked", 0) for j, _ in runs]
    lines.append("| %s | %s | %d | %d (%d-%d) of %d | %s | %s | %s | %s | %d/%d/%d | %s | %s |" % (
        p, seq, len(runs), statistics.median(tracked), min(tracked), max(tracked), runs[0][0].get("frames", 0),
        stat([a.get("sim3_rmse") for a in ape]), stat([a.get("se3_rmse") for a in ape]),
        stat([a.get("sim3_scale") for a in ape]), stat([x for x in mf if x is not None]),
        med("static"), med("dynamic"), med("unknown"), f1, near))
text = "\n".join(lines) + "\n"
open(os.path.join(out, "table.md"), "w").write(text)
print(text)
PY
