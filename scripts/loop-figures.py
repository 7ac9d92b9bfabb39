#!/usr/bin/env python3
"""Issue 18's loop figures for `beslam run` folders on a synthetic sequence (docs/place-recognition.md).

  scripts/loop-figures.py [--gt POSES.txt] RUN [RUN ...]

Each RUN is an output folder with summary.json; the closures are read from RUN.log, the run's stderr with
BESLAM_ORB_DEBUG=1 ("frame F: loop closed, keyframe of frame K with frame L ..."). The ground truth is
the whole sequence's pose file (default: poses/SEQ.txt beside the first run's dataset_path in summary.json). The revisit start is
taken from the ground truth: the first frame whose camera centre is within --radius m (3) of the centre of
a frame at least --min-path m (100) of driving earlier, looking the same way (within 30 degrees). Prints
one Markdown row per run: tracked frames, APE Sim(3) / SE(3) (m and % of the distance the ground truth
travels over the run's frames), relocalisations, the closures (keyframe's frame with the loop frame) and
how many frames after the revisit start the first one was detected.

With --black FIRST-LAST (the run's dataset.black_frames) it prints, per run, the relocalisation figures
instead: the first frame tracked after LAST (trajectory_online.tum: the pose tracking gave that frame) and
the error of its pose relative to the last frame tracked before FIRST, against the same relative pose in
the ground truth (metres, degrees): how far off the recovered pose is from where the camera went dark."""
import argparse
import json
import math
import os
import re
import sys


def read_kitti(path):
    poses = []
    for line in open(path):
        v = [float(x) for x in line.split()]
        if len(v) == 12:
            poses.append(((v[3], v[7], v[11]), (v[2], v[6], v[10])))  # centre, optical axis (world)
    return poses


def read_kitti_matrices(path):
    out = []
    for line in open(path):
        v = [float(x) for x in line.split()]
        if len(v) == 12:
            out.append([v[0:4], v[4:8], v[8:12], [0.0, 0.0, 0.0, 1.0]])
    return out


def from_tum(v):
    t, (qx, qy, qz, qw) = v[1:4], v[4:8]
    n = math.sqrt(qx * qx + qy * qy + qz * qz + qw * qw)
    qx, qy, qz, qw = qx / n, qy / n, qz / n, qw / n
    r = [[1 - 2 * (qy * qy + qz * qz), 2 * (qx * qy - qz * qw), 2 * (qx * qz + qy * qw)],
         [2 * (qx * qy + qz * qw), 1 - 2 * (qx * qx + qz * qz), 2 * (qy * qz - qx * qw)],
         [2 * (qx * qz - qy * qw), 2 * (qy * qz + qx * qw), 1 - 2 * (qx * qx + qy * qy)]]
    return [r[0] + [t[0]], r[1] + [t[1]], r[2] + [t[2]], [0.0, 0.0, 0.0, 1.0]]


def mul(a, b):
    return [[sum(a[i][k] * b[k][j] for k in range(4)) for j in range(4)] for i in range(4)]


def inv(a):  # a rigid transform
    r = [[a[j][i] for j in range(3)] for i in range(3)]
    t = [-sum(r[i][k] * a[k][3] for k in range(3)) for i in range(3)]
    return [r[0] + [t[0]], r[1] + [t[1]], r[2] + [t[2]], [0.0, 0.0, 0.0, 1.0]]


def pose_error(e):  # metres, degrees of a rigid transform that should be the identity
    c = max(-1.0, min(1.0, (e[0][0] + e[1][1] + e[2][2] - 1) / 2))
    return math.sqrt(e[0][3] ** 2 + e[1][3] ** 2 + e[2][3] ** 2), math.degrees(math.acos(c))


def blackout_rows(runs, gt_path, first_black, last_black):
    gt = read_kitti_matrices(gt_path)
    print(f"ground truth {gt_path}; black frames {first_black}-{last_black}")
    print("| run | tracked | relocalisations | first frame tracked after the blackout | frames after the images "
          "returned | its pose against the truth, relative to the last frame before the blackout |")
    print("|---|---|---|---|---|---|")
    for run in runs:
        summary = json.load(open(os.path.join(run, "summary.json")))
        times = [float(x) for x in open(os.path.join(summary["dataset_path"], "times.txt"))]
        index = {round(t, 6): i for i, t in enumerate(times)}
        online = {}
        for line in open(os.path.join(run, "trajectory_online.tum")):
            if line.startswith("#") or not line.strip():
                continue
            v = [float(x) for x in line.split()]
            online[index[round(v[0], 6)]] = from_tum(v)
        untracked = set(summary.get("untracked_frames", []))
        before = max((f for f in online if f < first_black and f not in untracked), default=None)
        after = min((f for f in online if f > last_black and f not in untracked), default=None)
        reloc = int(summary.get("backend_counters", {}).get("relocalisations", 0))
        name = os.path.basename(run.rstrip("/"))
        if before is None or after is None:
            print(f"| {name} | {summary.get('tracked')}/{summary.get('frames')} | {reloc} | never | - | - |")
            continue
        rel_est = mul(inv(online[before]), online[after])
        rel_gt = mul(inv(gt[before]), gt[after])
        m, deg = pose_error(mul(inv(rel_gt), rel_est))
        print(f"| {name} | {summary.get('tracked')}/{summary.get('frames')} | {reloc} | {after} | "
              f"{after - last_black} | {m:.3f} m / {deg:.2f} deg (from frame {before}) |")


def revisit_start(poses, radius, min_path, first=0):
    s = [0.0]
    for a, b in zip(poses, poses[1:]):
        s.append(s[-1] + math.dist(a[0], b[0]))
    for i in range(first, len(poses)):
        c, f = poses[i]
        for j in range(first, i):
            if s[i] - s[j] < min_path:
                break
            cj, fj = poses[j]
            if math.dist(c, cj) < radius and sum(x * y for x, y in zip(f, fj)) > math.cos(math.radians(30)):
                return i, j, s
    return None, None, s


CLOSED = re.compile(r"frame (\d+): loop closed, keyframe of frame (\d+) with frame (\d+) \((\d+) matches\), "
                    r"moved ([\d.]+) / ([\d.]+) deg")


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--gt", help="KITTI-format ground truth of the whole sequence")
    ap.add_argument("--radius", type=float, default=3.0)
    ap.add_argument("--min-path", type=float, default=100.0)
    ap.add_argument("--first", type=int, default=0, help="the runs' first frame (dataset.first)")
    ap.add_argument("--black", help="FIRST-LAST: the relocalisation figures of runs with these black frames")
    ap.add_argument("runs", nargs="+")
    a = ap.parse_args()
    if not a.gt:
        first = json.load(open(os.path.join(a.runs[0], "summary.json")))
        seq_dir = first["dataset_path"]
        a.gt = os.path.join(os.path.dirname(os.path.dirname(seq_dir)), "poses", first["dataset_sequence"] + ".txt")
    if a.black:
        first_black, last_black = (int(x) for x in a.black.split("-"))
        blackout_rows(a.runs, a.gt, first_black, last_black)
        return 0
    poses = read_kitti(a.gt)
    start, seen, s = revisit_start(poses, a.radius, a.min_path, a.first)
    print(f"ground truth {a.gt}: {len(poses)} frames; revisit starts at frame {start} "
          f"(within {a.radius} m of frame {seen})")
    print("| run | tracked | APE Sim(3) / SE(3) | share of distance (Sim(3) / SE(3)) | relocalisations | "
          "loops closed (keyframe's frame with frame, matches, correction) | first closure after the revisit start |")
    print("|---|---|---|---|---|---|---|")
    for run in a.runs:
        summary = json.load(open(os.path.join(run, "summary.json")))
        frames = summary.get("frames", 0)
        last = a.first + frames - 1
        dist = s[min(last, len(s) - 1)] - s[a.first]
        ape = summary.get("ape", {})
        # se3_rmse is null for a map that never became metric
        sim3 = ape.get("sim3_rmse", float("nan"))
        se3 = ape.get("se3_rmse") if ape.get("se3_rmse") is not None else float("nan")
        counters = summary.get("backend_counters", {})
        closures = []
        log = run.rstrip("/") + ".log"
        if os.path.isfile(log):
            for line in open(log):
                m = CLOSED.search(line)
                if m:
                    closures.append(tuple(float(x) if "." in x else int(x) for x in m.groups()))
        text = "; ".join(f"{k} with {l}, {n}, {c:.2f} m / {d:.2f} deg" for _, k, l, n, c, d in closures) or "none"
        after = f"{closures[0][1] - start:+d} frames" if closures and start is not None else "-"
        tracked = summary.get("tracked", frames)
        print(f"| {os.path.basename(run.rstrip('/'))} | {tracked}/{frames} | {sim3:.3f} / {se3:.3f} m | "
              f"{100 * sim3 / dist:.3f} / {100 * se3 / dist:.3f} % of {dist:.0f} m | "
              f"{int(counters.get('relocalisations', 0))} | {text} | {after} |")
    return 0


if __name__ == "__main__":
    sys.exit(main())
