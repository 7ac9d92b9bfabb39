#!/usr/bin/env python3
"""Where two SLAM systems part, segment by segment, on one sequence with ground truth.

  scripts/compare-segments.py --gt POSES [--window N] TRAJECTORY [TRAJECTORY ...]

POSES is the ground truth in KITTI odometry format (one 3x4 row T_world_cam per frame). Each TRAJECTORY is a
KITTI-format file of one run: a `beslam run` folder's trajectory.kitti (row i is frame i; give the folder or the
file), or a file whose rows start with the frame index (ORB-SLAM2's runs in ../shared/peers/orbslam2-kitti00,
`runN_frames.kitti`; told apart by 13 numbers a row). For each window of N frames (default 20) it prints, per run:

  scale: the distance between the window's first and last camera centres against the truth's, divided by the
         run's median of that ratio over all windows (a monocular run's unit is arbitrary): 1.000 is a window
         in the run's typical unit, 1.05 one whose unit has grown 5 % since;
  dyaw:  the run's heading change over the window minus the truth's (degrees; positive: turned further left
         about the camera's y axis).

Alignment-free: neither figure depends on how the whole trajectory is fitted to the truth. A window where a
frame has no pose in a run shows '-'. The last lines give, per window, the median of each group of runs, grouped by
the folder two levels above each trajectory file (out/runs/seedK/trajectory.kitti: out; ORB-SLAM2's five
runs: ../shared/peers)."""
import argparse
import math
import os
import statistics
import sys

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "lib"))
import run_files  # noqa: E402
from run_files import fail  # noqa: E402


def read_run(path):
    """{frame: 12 numbers} of a KITTI-format trajectory, with or without a leading frame index."""
    if os.path.isdir(path):
        path = os.path.join(path, "trajectory.kitti")
    poses = {}
    for n, line in enumerate(run_files.lines(path), 1):
        if not line.strip() or line.startswith("#"):
            continue
        v = run_files.numbers(path, n, line)
        if len(v) == 13 and v[0] == int(v[0]) and v[0] >= 0:
            poses[int(v[0])] = v[1:]
        elif len(v) == 12:
            poses[len(poses)] = v
        else:
            fail(path, n, "expected 12 numbers (a 3x4 pose) or 13 (a frame index and a pose), got %d" % len(v))
    if not poses:
        fail(path, 0, "no pose")
    return path, poses


def relative(a, b):
    """Heading change (degrees, about the camera's y axis) and distance from pose a to pose b."""
    Ra = [[a[0], a[1], a[2]], [a[4], a[5], a[6]], [a[8], a[9], a[10]]]
    Rb = [[b[0], b[1], b[2]], [b[4], b[5], b[6]], [b[8], b[9], b[10]]]
    R = [[sum(Ra[k][i] * Rb[k][j] for k in range(3)) for j in range(3)] for i in range(3)]
    return math.degrees(math.atan2(R[0][2], R[2][2])), math.dist((a[3], a[7], a[11]), (b[3], b[7], b[11]))


def segments(gt, run, windows):
    """Per window (scale ratio before normalising, yaw error), None where the run lacks a pose."""
    out = []
    for a, b in windows:
        if a not in run or b not in run:
            out.append(None)
            continue
        yaw_gt, d_gt = relative(gt[a], gt[b])
        yaw_run, d_run = relative(run[a], run[b])
        out.append((d_run / d_gt if d_gt > 1e-6 else float("nan"), yaw_run - yaw_gt))
    return out


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--gt", required=True, help="ground truth, KITTI odometry format")
    ap.add_argument("--window", type=int, default=20, help="frames a window (default 20)")
    ap.add_argument("runs", nargs="+")
    a = ap.parse_args()
    if a.window < 2:
        sys.exit("--window must be at least 2")
    gt = dict(enumerate(run_files.rows(a.gt, 12)))
    windows = [(s, s + a.window - 1) for s in range(0, len(gt) - a.window + 1, a.window)]
    if not windows:
        sys.exit("%s: %d poses, fewer than one window of %d" % (a.gt, len(gt), a.window))
    print("| run | figure | " + " | ".join("%d-%d" % w for w in windows) + " |")
    print("|---|---|" + "---|" * len(windows))
    groups = {}
    for path in a.runs:
        name, run = read_run(path)
        seg = segments(gt, run, windows)
        ratios = sorted(s[0] for s in seg if s and s[0] == s[0])
        if not ratios:
            fail(name, 0, "no window has both of its end frames")
        unit = ratios[len(ratios) // 2]
        scale = [s[0] / unit if s else None for s in seg]
        yaw = [s[1] if s else None for s in seg]
        groups.setdefault(os.path.dirname(os.path.abspath(name)).rsplit(os.sep, 1)[0], []).append((scale, yaw))
        for label, values, fmt in (("scale", scale, "%.3f"), ("dyaw", yaw, "%+.2f")):
            print("| %s | %s | " % (name, label) + " | ".join(fmt % v if v is not None else "-" for v in values) + " |")
    for group, members in groups.items():
        for k, (label, fmt) in enumerate((("scale", "%.3f"), ("dyaw", "%+.2f"))):
            cells = []
            for w in range(len(windows)):
                v = [m[k][w] for m in members if m[k][w] is not None]
                cells.append(fmt % statistics.median(v) if v else "-")
            print("| median of %d runs in %s | %s | " % (len(members), group, label) + " | ".join(cells) + " |")


if __name__ == "__main__":
    main()
