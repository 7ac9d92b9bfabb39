#!/usr/bin/env bash
# The throughput benchmark behind docs/performance.md: runs each case N times (default 5) and prints the
# medians over the runs of: whole-process wall time, frames per second (summary.json "fps"), the per-frame
# tracking median (backend.tracking_total), local mapping per keyframe (backend.mapping, inline mode) and
# the median of every stage in timing.csv. With --base DIR a second build (DIR/bin/beslam, e.g. the commit
# before a change) is run in alternation with build/, so both see the same machine load; the table then
# has one column per build; --base-cases LIST (one per case) lets the base build run another case in the
# same alternation, e.g. the old threaded mode against the new concurrent one. Timings are wall clock:
# run it on an otherwise idle machine, and compare builds only within one invocation.
#
#   scripts/bench-performance.sh                          # all cases, build/ only, 5 runs each
#   scripts/bench-performance.sh --n 3 --cases orb00_threaded --base build-base
#   scripts/bench-performance.sh --no-run --base build-base     # tables again from the last runs
#   scripts/bench-performance.sh --cases orb00_concurrent --base-cases orb00_threaded --base build-base
#
# Cases: orb00 (configs/kitti_mono_orb.yaml on KITTI 00, deterministic inline mapping), orb00_threaded
# (the same with backend.threaded_mapping=true), orb00_concurrent (backend.concurrent_mapping=true:
# tracking does not wait for mapping, not reproducible), detector06 (configs/kitti06_detector_image.yaml),
# beslam00 (configs/kitti_beslam.yaml on KITTI 00: YOLOX-Nano, the checker, masks, the metric backend),
# demo (configs/demo.yaml). KITTI cases need ../shared/data (skipped with a message when absent).
# Runs go to out/bench-performance/<build>/<case>/runN (overwritten).
set -euo pipefail
cd "$(dirname "$0")/.."

runs=5
cases="orb00,orb00_threaded,detector06,demo"
base=""
base_cases=""
run=1
while (($#)); do
  case "$1" in
    --n) runs="$2"; shift 2 ;;
    --cases) cases="$2"; shift 2 ;;
    --base) base="$2"; shift 2 ;;
    --no-run) run=0; shift ;;
    --base-cases) base_cases="$2"; shift 2 ;;
    -h | --help) sed -n '2,23p' "$0"; exit 0 ;;
    *) echo "bench-performance: unknown argument $1" >&2; exit 2 ;;
  esac
done

builds=(build)
[ -n "$base" ] && builds=("$base" build)
for b in "${builds[@]}"; do
  [ -x "$b/bin/beslam" ] || { echo "bench-performance: $b/bin/beslam not found (build first)" >&2; exit 1; }
done
if [ -n "$base" ] && [ "$(basename "$base")" = build ]; then
  echo "bench-performance: --base $base: its runs would go where build/'s go (out/bench-performance/build);" \
    "name the base build's folder otherwise, e.g. a symbolic link build-base -> $base" >&2
  exit 2
fi

case_args() {  # the `beslam run` arguments of a case
  case "$1" in
    orb00) echo "configs/kitti_mono_orb.yaml --set dataset.sequence=00" ;;
    orb00_threaded) echo "configs/kitti_mono_orb.yaml --set dataset.sequence=00 --set backend.threaded_mapping=true" ;;
    orb00_concurrent) echo "configs/kitti_mono_orb.yaml --set dataset.sequence=00 --set backend.concurrent_mapping=true" ;;
    detector06) echo "configs/kitti06_detector_image.yaml" ;;
    beslam00) echo "configs/kitti_beslam.yaml --set dataset.sequence=00" ;;
    demo) echo "configs/demo.yaml" ;;
    *) echo "bench-performance: unknown case $1" >&2; exit 2 ;;
  esac
}

median() {  # numbers on stdin, one a line -> their median ("-" when none)
  sort -g | awk '{v[NR] = $1} END {if (NR == 0) print "-"; else if (NR % 2) print v[(NR + 1) / 2]; else printf "%.3f\n", (v[NR / 2] + v[NR / 2 + 1]) / 2}'
}

column() {  # timing.csv column $2 of file $1, non-empty values
  awk -F, -v name="$2" 'NR == 1 {for (i = 1; i <= NF; i++) if ($i == name) c = i; next} c && $c != "" {print $c}' "$1"
}

json_number() {  # the number after "key": in summary.json (nothing when absent)
  sed -n "s/^ *\"$2\": \([-0-9.e+]*\),*$/\1/p" "$1" | head -1 || true
}

IFS=, read -r -a case_list <<<"$cases"
IFS=, read -r -a base_case_list <<<"$base_cases"
if [ -n "$base_cases" ] && [ "${#base_case_list[@]}" -ne "${#case_list[@]}" ]; then
  echo "bench-performance: --base-cases needs one case per case of --cases" >&2
  exit 2
fi
for i in "${!case_list[@]}"; do
  c=${case_list[$i]}
  bc=${base_case_list[$i]:-$c}
  args=$(case_args "$c")
  base_args=$(case_args "$bc")
  if [[ "$args" == *kitti* ]] && [ ! -d ../shared/data/kitti ]; then
    echo "== $c: skipped (no ../shared/data/kitti)"
    continue
  fi
  for ((r = 1; r <= runs * run; r++)); do
    for b in "${builds[@]}"; do
      out="out/bench-performance/$(basename "$b")/$c/run$r"
      a=$args
      [ "$b" = "$base" ] && a=$base_args
      rm -rf "$out"  # a fresh folder each time (a base build may not know --overwrite)
      t0=$(date +%s.%N)
      # shellcheck disable=SC2086
      "$b/bin/beslam" run $a --quiet --out "$out" >/dev/null
      t1=$(date +%s.%N)
      echo "$t0 $t1" | awk '{printf "%.3f\n", $2 - $1}' >"$out/wall_s.txt"
    done
  done
  [ "$bc" != "$c" ] && [ -n "$base" ] && echo "== $c: the base build $base runs $bc"
  echo "== $c: medians of $runs runs ($(nproc) cores, load average now $(cut -d' ' -f1-3 /proc/loadavg))"
  printf "%-34s" "metric"
  for b in "${builds[@]}"; do printf "%14s" "$(basename "$b")"; done
  echo
  first="out/bench-performance/$(basename "${builds[0]}")/$c/run1/timing.csv"
  stages=$(head -1 "$first" | tr , '\n' | grep -v '^frame$')
  for m in wall_s fps $stages; do
    printf "%-34s" "$m"
    for b in "${builds[@]}"; do
      dir="out/bench-performance/$(basename "$b")/$c"
      v=$(for ((r = 1; r <= runs; r++)); do
        case "$m" in
          wall_s) cat "$dir/run$r/wall_s.txt" ;;
          fps) json_number "$dir/run$r/summary.json" fps ;;
          *) column "$dir/run$r/timing.csv" "$m" | median ;;
        esac
      done | awk '$1 != "-" && $1 != ""' | median)
      if [ "$v" = "-" ]; then printf "%14s" "-"; else printf "%14.3f" "$v"; fi
    done
    echo
  done
done
