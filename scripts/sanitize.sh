#!/usr/bin/env bash
# The sanitised build (issue 17): clang with AddressSanitizer + UndefinedBehaviorSanitizer (any UB is an
# error) and libFuzzer coverage, into build-sanitize/, then
#   1. every unit test (module and plugin tests) with LeakSanitizer on;
#   2. the end-to-end runs (`beslam run` as a child process: tests/integration, tests/sdk) with ASan and
#      UBSan but no leak check: the host unloads its plugins at exit, and the static caches of the libraries
#      they pulled in (OpenCV's among them) are then reported as leaks of an unknown module; the plugins'
#      own code is leak-checked by their unit tests in step 1;
#   3. every fuzz target for BESLAM_FUZZ_RUNS executions (default 10000 here; scripts/fuzz-nightly.sh runs
#      1,000,000) from its seed corpus in tests/fuzz/corpus/.
# Left to the Release suite (minutes under ASan, nothing memory-specific): the SLAM accuracy runs on KITTI
# and synthetic sequences, the bench, the browser test of the report and the out-of-tree SDK builds.
set -euo pipefail
cd "$(dirname "$0")/.."
jobs=${BESLAM_BUILD_JOBS:-2}
runs=${BESLAM_FUZZ_RUNS:-10000}
cmake -S . -B build-sanitize -DCMAKE_BUILD_TYPE=Debug -DCMAKE_C_COMPILER=clang -DCMAKE_CXX_COMPILER=clang++ \
  -DCMAKE_CXX_FLAGS="-O1 -g" -DCMAKE_C_FLAGS="-O1 -g" -DBESLAM_SANITIZE=ON -DBESLAM_FUZZ=ON \
  -DBESLAM_FUZZ_RUNS="$runs" -DBESLAM_BUILD_BENCHMARKS=OFF > /dev/null
cmake --build build-sanitize -j"$jobs"
cd build-sanitize
export UBSAN_OPTIONS=${UBSAN_OPTIONS:-print_stacktrace=1:halt_on_error=1}
end_to_end='^(RunTest|Demo|ShippedConfigs|TemplateBuild)\.'
slow='Kitti|KITTI|Demo|SlamSynthetic|^Synth\.|SyntheticStreets|BenchCommand|ReportBrowser|TemplateBuild'
if [ "${BESLAM_SANITIZE_ONLY:-}" != "fuzz" ]; then
  ASAN_OPTIONS=detect_leaks=1 ctest --output-on-failure -j"$jobs" --timeout 900 -E "^fuzz\.|$end_to_end|$slow"
  ASAN_OPTIONS=detect_leaks=0 ctest --output-on-failure -j"$jobs" --timeout 900 -R "$end_to_end" -E "$slow"
fi
ASAN_OPTIONS=detect_leaks=1 ctest --output-on-failure -j"$jobs" --timeout 3600 -R '^fuzz\.'
