#!/usr/bin/env bash
# The sanitised build (issue 17): clang with AddressSanitizer + UndefinedBehaviorSanitizer (any UB is an
# error) and libFuzzer coverage, into build-sanitize/. Two sets (docs/testing.md):
#   BESLAM_SANITIZE_SET=ci (default; what test.sh and CI run, within CI's 30 minutes): builds only the
#     parsers, the host's core modules, the motion checker and mask cores and the replay plugins with
#     their unit tests (LeakSanitizer on), then every fuzz target for BESLAM_FUZZ_RUNS executions
#     (default 10000) from its seed corpus in tests/fuzz/corpus/;
#   BESLAM_SANITIZE_SET=full: everything, every unit test with LeakSanitizer, the end-to-end runs
#     (`beslam run` as a child process) without the leak check (the host unloads its plugins at exit and
#     the static caches of the libraries they pulled in are then reported as leaks of an unknown module),
#     and the fuzz targets. Left out even there (minutes under ASan, nothing memory-specific): the SLAM
#     accuracy runs on KITTI and synthetic sequences, the bench, the report's browser test and the
#     out-of-tree SDK builds.
# BESLAM_SANITIZE_ONLY=fuzz runs only the fuzz targets (scripts/fuzz-nightly.sh).
# backend_orb in the CI set: its unit tests and the SLAM core end to end on the rendered corridor (tracking,
# inline, threaded and concurrent mapping, frames prepared ahead, map files, relocalisation), without the
# KITTI runs, the vocabulary training tests and the slowest corridor runs (orb_slow below: all 94 took 14
# minutes under ASan on the shared machine; the full set runs them, the vocabulary loader is fuzzed); its
# plugin through the C ABI (tracking, a map saved and localised in).
#
# scripts/sanitize.sh --tsan: ThreadSanitizer instead, in build-tsan/ (not in CI: its build is most of the
# tree again, and one corridor run takes minutes under TSan; docs/testing.md): the threaded paths end to
# end, clean or it fails —
# backend_orb's threaded and concurrent mapping and prepared frames on the rendered corridor, then
# `beslam run configs/demo.yaml` on the first BESLAM_TSAN_FRAMES (default 40) frames of urban_loop (frames
# loaded, detected and masked ahead on the prefetch thread, threaded mapping, the reconstructor's fits on
# OpenCV's thread pool) and the same with concurrent mapping. Suppressions (tests/tsan.supp) only for
# third-party code TSan cannot see into, each with its reason.
set -euo pipefail
cd "$(dirname "$0")/.."
jobs=${BESLAM_BUILD_JOBS:-2}
if [ "${1:-}" = --tsan ]; then
  frames=${BESLAM_TSAN_FRAMES:-40}
  tsan_targets="backend_orb_test;beslam;backend_orb;detector_oracle;motion_bev_tracker;mask_box;reconstructor_sdf"
  cmake -S . -B build-tsan -DBESLAM_SELECTED_TARGETS="$tsan_targets" -DCMAKE_BUILD_TYPE=Debug -DCMAKE_C_COMPILER=clang \
    -DCMAKE_CXX_COMPILER=clang++ -DCMAKE_CXX_FLAGS="-O1 -gline-tables-only" -DCMAKE_C_FLAGS="-O1 -gline-tables-only" \
    -DBESLAM_TSAN=ON -DBESLAM_PYTHON=OFF -DBESLAM_BUILD_BENCHMARKS=OFF > /dev/null
  cmake --build build-tsan -j"$jobs" --target beslam_selected
  export TSAN_OPTIONS="halt_on_error=1 second_deadlock_stack=1 suppressions=$PWD/tests/tsan.supp ${TSAN_OPTIONS:-}"
  export BESLAM_PLUGIN_PATH=$PWD/build-tsan/lib/beslam/plugins
  start=$SECONDS
  filter='SlamSynthetic.ThreadedMappingGivesTheSameTrajectory:SlamSynthetic.FramesPreparedAheadGiveTheSameTrajectory'
  filter+=':SlamSynthetic.ConcurrentMappingTracksTheCorridorAccurately'
  if build-tsan/tests/backend_orb_test --gtest_filter="$filter" > build-tsan/backend_orb_test.log 2>&1; then
    echo "tsan: backend_orb_test $(grep -E '^\[  PASSED  \]' build-tsan/backend_orb_test.log | head -1) ($((SECONDS - start)) s)"
  else
    echo "tsan: backend_orb_test FAILED:"; tail -n 80 build-tsan/backend_orb_test.log; exit 1
  fi
  for mapping in threaded_mapping concurrent_mapping; do
    start=$SECONDS
    if build-tsan/bin/beslam run configs/demo.yaml --set dataset.root="$PWD/build-tsan/synth-cache" \
      --set "dataset.synth_set=lidar.enabled=false,camera.colour=false,frames=$frames" --set "backend.$mapping=true" \
      --set output.samples=0 --overwrite --out "build-tsan/demo_$mapping" > "build-tsan/demo_$mapping.log" 2>&1; then
      echo "tsan: demo ($frames frames, prefetch, $mapping, reconstructor): clean ($((SECONDS - start)) s);" \
        "$(grep -E '^objects reconstructed' "build-tsan/demo_$mapping.log" || echo 'no objects reconstructed')"
    else
      echo "tsan: demo with $mapping FAILED:"; tail -n 80 "build-tsan/demo_$mapping.log"; exit 1
    fi
  done
  exit 0
fi
runs=${BESLAM_FUZZ_RUNS:-10000}
set_name=${BESLAM_SANITIZE_SET:-ci}
only=${BESLAM_SANITIZE_ONLY:-}
unit_tests=(abi_layout_test common_test formats_test datasets_test eval_test pipeline_spec_test pipeline_samples_test
  static_map_test motion_score_test object_score_test mask_common_test motion_bev_tracker_test detector_replay_test
  registry_test)
# backend_orb_test runs with a filter (ORB_FILTER below); backend_orb_plugin_test loads the plugin.
orb_tests=(backend_orb_test backend_orb_plugin_test)
fuzzers=(pipeline_yaml label_rows detection_rows nuscenes calibration image ply_mesh trajectory times_poses bench_matrix
  velodyne map_file vocabulary)
selected=("${unit_tests[@]}" "${orb_tests[@]}" backend_orb "${fuzzers[@]}")
[ "$only" = fuzz ] && selected=("${fuzzers[@]}")
[ "$set_name" = full ] && selected=()
selected_list=$(IFS=';'; echo "${selected[*]}")
cmake -S . -B build-sanitize -DBESLAM_SELECTED_TARGETS="$selected_list" -DCMAKE_BUILD_TYPE=Debug -DCMAKE_C_COMPILER=clang -DCMAKE_CXX_COMPILER=clang++ \
  -DCMAKE_CXX_FLAGS="-O1 -gline-tables-only" -DCMAKE_C_FLAGS="-O1 -gline-tables-only" -DBESLAM_SANITIZE=ON \
  -DBESLAM_FUZZ=ON -DBESLAM_FUZZ_RUNS="$runs" -DBESLAM_BUILD_BENCHMARKS=OFF > /dev/null
export UBSAN_OPTIONS=${UBSAN_OPTIONS:-print_stacktrace=1:halt_on_error=1}
export BESLAM_PLUGIN_PATH=$PWD/build-sanitize/lib/beslam/plugins
if [ "$set_name" = full ]; then
  cmake --build build-sanitize -j"$jobs"
  cd build-sanitize
  end_to_end='^(RunTest|Demo|ShippedConfigs|TemplateBuild)\.|^sdk_template_test$'
  slow='Kitti|KITTI|Demo|SlamSynthetic|^Synth\.|SyntheticStreets|BenchCommand|ReportBrowser|TemplateBuild|sdk_template_test'
  if [ "$only" != fuzz ]; then
    ASAN_OPTIONS=detect_leaks=1 ctest --output-on-failure -j"$jobs" --timeout 900 -E "^fuzz\.|$end_to_end|$slow"
    ASAN_OPTIONS=detect_leaks=0 ctest --output-on-failure -j"$jobs" --timeout 900 -R "$end_to_end" -E "$slow"
  fi
  ASAN_OPTIONS=detect_leaks=1 ctest --output-on-failure -j"$jobs" --timeout 3600 -R '^fuzz\.'
  exit 0
fi
cmake --build build-sanitize -j"$jobs" --target beslam_selected  # all at once (see CMakeLists.txt)
if [ "$only" != fuzz ]; then
  failed=()
  # IouFloors: mask accuracy floors on rendered scenes, a minute under ASan and nothing memory-specific
  # (the full set runs them). backend_orb: what the header says.
  orb_slow='Kitti00.*:Kitti06.*:Vocabulary.*:Relocalisation.*:MapMemory.*:ObjectLandmarks.EnterLocalBaOfAMetricCorridorRun'
  orb_slow+=':ObjectLandmarks.OffAndNonMetricRunsAreByteIdenticalToNoObjects:SlamSynthetic.TracksTheCorridorAccurately'
  orb_slow+=':SlamSynthetic.TheMapsMovesUnderTheCameraAreReportedAndFollowingThemSteadiesThePoses:SlamSynthetic.SameSeed*'
  orb_slow+=':SlamSynthetic.WithAScanKeyframesMakeMapPointsWhereTheRangesPutThem:SlamSynthetic.DynamicMasked*'
  orb_slow+=':SlamSynthetic.LidarRangesMakeTheMapMetricSoonAfterInitialisationAndHoldIt'
  orb_slow+=':BundleAdjustment.GlobalBaSparseSchurLmAndCeresReachTheSameMinimum'
  for t in "${unit_tests[@]}" "${orb_tests[@]}"; do  # from the source folder, as ctest runs them
    filter=-IouFloors.*
    [ "$t" = backend_orb_test ] && filter=-$orb_slow
    if ASAN_OPTIONS=detect_leaks=1 build-sanitize/tests/"$t" --gtest_filter="$filter" > "build-sanitize/$t.log" 2>&1; then
      echo "sanitize: $t $(grep -E '^\[  PASSED  \]' "build-sanitize/$t.log" | head -1)"
    else
      echo "sanitize: $t FAILED:"; tail -n 60 "build-sanitize/$t.log"; failed+=("$t")
    fi
  done
  if [ ${#failed[@]} -gt 0 ]; then echo "sanitize: failed: ${failed[*]}"; exit 1; fi
fi
for f in "${fuzzers[@]}"; do
  echo "sanitize: fuzz $f, $runs executions"
  ASAN_OPTIONS=detect_leaks=1 tests/fuzz/run_fuzzer.sh "$PWD/build-sanitize/fuzz/$f" "$PWD/tests/fuzz/corpus/$f" "$runs"
done
