#!/usr/bin/env python3
"""Motion states a run wrote for cars near the camera, where no truth of them exists (real KITTI odometry).

  scripts/motion-counts.py [--range M] RUN [RUN ...]

Each RUN is a `beslam run` output folder. Reads RUN/objects.txt (KITTI tracking rows with the motion state
appended: frame, track id, class, ..., x y z in the camera frame (bottom centre), ..., state) and prints one
Markdown row per run: car detections within --range metres (default 25, horizontal distance of the box from
the camera) called static / dynamic / unknown, how many tracks had a car within that range and how many of
them were called static in at least one frame, and every car detection's counts at any range. On the KITTI
00 excerpt nearly every car is parked (docs/motion.md, "Boxes that carry their own noise")."""
import argparse
import collections
import math
import os
import sys


def counts(run, max_range):
    near, every = collections.Counter(), collections.Counter()
    tracks = collections.defaultdict(collections.Counter)
    path = os.path.join(run, "objects.txt")
    with open(path) as f:
        for n, line in enumerate(f, 1):
            v = line.split()
            if not v:
                continue
            if len(v) < 17:
                sys.exit("%s:%d: expected a KITTI tracking row with a motion state, got %d fields" % (path, n, len(v)))
            if v[2] != "Car":
                continue
            try:
                x, z = float(v[13]), float(v[15])
            except ValueError:
                sys.exit("%s:%d: the box position is not a number" % (path, n))
            state = v[-1]
            every[state] += 1
            if math.hypot(x, z) <= max_range:
                near[state] += 1
                tracks[v[1]][state] += 1
    return near, every, len(tracks), sum(1 for c in tracks.values() if c["static"] > 0)


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--range", type=float, default=25.0, help="metres from the camera (default 25)")
    ap.add_argument("runs", nargs="+")
    a = ap.parse_args()
    print("| run | cars within %g m: static / dynamic / unknown | tracks within %g m (static at least once) | "
          "every car: static / dynamic / unknown |" % (a.range, a.range))
    print("|---|---|---|---|")
    for run in a.runs:
        try:
            near, every, n_tracks, n_static = counts(run, a.range)
        except OSError as e:
            sys.exit("%s: %s" % (e.filename, e.strerror))
        print("| %s | %d / %d / %d | %d (%d) | %d / %d / %d |" % (
            run, near["static"], near["dynamic"], near["unknown"], n_tracks, n_static,
            every["static"], every["dynamic"], every["unknown"]))


if __name__ == "__main__":
    main()
