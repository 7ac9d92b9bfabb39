#!/usr/bin/env python3
"""Issue 18's long-run figures for `beslam run` folders (scripts/long-run.sh makes them).

  scripts/long-run-figures.py RUN [RUN ...]

Per run, from RUN/timing.csv (total_ms and rss_mb per frame) and RUN/summary.json: frames tracked,
keyframes, loop closures, relocalisations; the per-frame time medians of the first --window (500) frames
after initialisation (the first frame tracked against a local map) and of the last --window frames, and
their ratio (target: within 20 %); medians per --step (500) frames; the resident memory at the end of each
step and the peak (summary.json, else RUN.time from /usr/bin/time -v; target: under 2 GB). Markdown."""
import argparse
import csv
import json
import os
import statistics
import sys


def read_timing(path):
    rows = []
    with open(path) as f:
        for row in csv.DictReader(f):
            rows.append(row)
    if not rows:
        raise SystemExit(f"long-run-figures: {path}: no frames")
    for col in ("total_ms", "rss_mb"):
        if col not in rows[0]:
            raise SystemExit(f"long-run-figures: {path}: no {col} column (a run from before rss_mb was written?)")
    return rows


def peak_from_time(path):
    if not os.path.exists(path):
        return None
    for line in open(path):
        if "Maximum resident set size (kbytes)" in line:
            return int(line.split(":")[1]) / 1024.0
    return None


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("runs", nargs="+")
    ap.add_argument("--window", type=int, default=500)
    ap.add_argument("--step", type=int, default=500)
    a = ap.parse_args()
    print("| run | tracked | keyframes | loops | reloc. | first %d ms | last %d ms | last/first | peak RSS MiB |"
          % (a.window, a.window))
    print("|---|---|---|---|---|---|---|---|---|")
    steps = []
    for run in a.runs:
        summary_path = os.path.join(run, "summary.json")
        if not os.path.exists(summary_path):
            print(f"long-run-figures: {run}: no summary.json (run failed or unfinished)", file=sys.stderr)
            continue
        s = json.load(open(summary_path))
        rows = read_timing(os.path.join(run, "timing.csv"))
        start = next((k for k, r in enumerate(rows) if r.get("backend.track_local_map_ms")), 0)
        total = [float(r["total_ms"]) for r in rows]
        first = total[start:start + a.window]
        last = total[-a.window:]
        f_med, l_med = statistics.median(first), statistics.median(last)
        peak = s.get("peak_rss_mb") or peak_from_time(run.rstrip("/") + ".time")
        c = s.get("backend_counters", {})
        print(f"| {os.path.basename(run.rstrip('/'))} | {s['tracked']}/{s['frames']} | {s['keyframes']} "
              f"| {int(c.get('loop_closures', 0))} | {int(c.get('relocalisations', 0))} | {f_med:.1f} "
              f"| {l_med:.1f} | {l_med / f_med:.2f} | {peak:.0f} |")
        per = []
        for b in range(0, len(rows), a.step):
            chunk = rows[b:b + a.step]
            per.append((int(chunk[0]["frame"]), int(chunk[-1]["frame"]),
                        statistics.median(float(r["total_ms"]) for r in chunk), float(chunk[-1]["rss_mb"])))
        steps.append((os.path.basename(run.rstrip("/")), per))
    for name, per in steps:
        print(f"\n{name}: frames, median ms per frame, resident MiB at the last frame")
        for lo, hi, ms, rss in per:
            print(f"  {lo:5d}-{hi:5d}  {ms:6.1f} ms  {rss:7.1f} MiB")


if __name__ == "__main__":
    main()
