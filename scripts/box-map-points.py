#!/usr/bin/env python3
"""The backend's map points inside a detector's car boxes, against the boxes themselves.

  scripts/box-map-points.py --calib CALIB [--camera-height H] [--range M] [--min-detections N] RUN

RUN is a `beslam run` output folder of a SLAM backend with the motion checker's track ids (objects.txt, KITTI
tracking rows with the 2D box and the bottom centre of the 3D box in the camera frame), its trajectory
(trajectory.kitti, one 3x4 row per tracked frame, and trajectory.tum for their times), keyframes.tum and the
final map (map_points.ply: x y z, colour, observations). CALIB is the KITTI calib.txt whose P0 row gives the
camera (fx, cx, cy). Boxes cut by the image border (truncation > 0) and beyond M metres are left out. A map
point counts when 3 or more keyframes observe it; "in a box" means projected with the frame's pose into the
middle 70 % of the 2D box, at a depth within 0.6-1.6 times the box's own.

Two things are printed:
- for every keyframe detection with 5 or more such points: the lowest fifth of their depths divided by the
  road distance of the box's bottom edge (fx * H / (y2 - cy), a flat road under a camera H metres up): where
  the map's own triangulation puts the car's near side against the flat-road lift (percentiles);
- for every car track with N or more detections (any frame): how far the median world position of the points
  in its boxes moves, across (x) and along (z) the world's bird's-eye view, against its lifted boxes.
The map's points on a parked car are static by construction; on a car driving along the camera's line of
travel they are triangulated as a parked car farther away (docs/motion.md "The floor under a static call")."""
import collections
import os
import sys

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "lib"))
import run_files  # noqa: E402
from run_files import fail, lines, numbers  # noqa: E402


def read_camera(path):
    for n, line in enumerate(lines(path), 1):
        if line.startswith("P0:"):
            p = numbers(path, n, line[3:], 12)
            return p[0], p[2], p[6]
    fail(path, 0, "no P0 row (a KITTI calib.txt)")


def read_map(path):
    text = lines(path)
    try:
        end = text.index("end_header")
    except ValueError:
        fail(path, 0, "no end_header (a PLY file written by beslam)")
    points = []
    for n, line in enumerate(text[end + 1:], end + 2):
        v = numbers(path, n, line)
        if len(v) < 7:
            fail(path, n, "expected x y z r g b observations")
        if v[6] >= 3:
            points.append((v[0], v[1], v[2]))
    return points


def read_run(run):
    poses = run_files.rows(run + "/trajectory.kitti", 12)
    times = [r[0] for r in run_files.rows(run + "/trajectory.tum", 8, comments=True)]
    if len(poses) != len(times):
        fail(run, 0, "trajectory.kitti has %d poses, trajectory.tum %d" % (len(poses), len(times)))
    keyframe_times = set(round(r[0], 4) for r in run_files.rows(run + "/keyframes.tum", 8, comments=True))
    return poses, times, keyframe_times


def read_boxes(run, max_range):
    boxes = collections.defaultdict(list)
    for car in run_files.cars(run, max_range, unclipped=True):
        boxes[car.frame].append((car.track, car.box2d, car.bottom_cam))
    return boxes


def percentile(values, q):
    s = sorted(values)
    return s[min(len(s) - 1, int(q * len(s)))]


def main():
    ap = run_files.track_parser(__doc__, 10)
    ap.add_argument("--calib", required=True, help="KITTI calib.txt (its P0 row)")
    ap.add_argument("--camera-height", type=float, default=1.65, help="metres over the road (KITTI: 1.65)")
    a = ap.parse_args()
    fx, cx, cy = read_camera(a.calib)
    poses, times, keyframe_times = read_run(a.run)
    points = read_map(a.run + "/map_points.ply")
    boxes = read_boxes(a.run, a.range)

    ratios = []
    tracks = collections.defaultdict(list)  # id -> (points' median x z, lifted x z)
    for frame, frame_boxes in sorted(boxes.items()):
        if frame >= len(poses):
            fail(a.run + "/objects.txt", 0, "frame %d has no pose (%d in trajectory.kitti)" % (frame, len(poses)))
        m = poses[frame]
        R = [[m[0], m[1], m[2]], [m[4], m[5], m[6]], [m[8], m[9], m[10]]]
        t = [m[3], m[7], m[11]]
        projected = []  # (u, v, depth, world point)
        for p in points:
            d = [p[i] - t[i] for i in range(3)]
            c = [sum(R[j][i] * d[j] for j in range(3)) for i in range(3)]  # R^T (p - t)
            if c[2] > 1:
                projected.append((fx * c[0] / c[2] + cx, fx * c[1] / c[2] + cy, c[2], p))
        keyframe = round(times[frame], 4) in keyframe_times
        for track_id, (x1, y1, x2, y2), (x, y, z) in frame_boxes:
            mx, my = 0.15 * (x2 - x1), 0.15 * (y2 - y1)
            inside = [q for q in projected if x1 + mx <= q[0] <= x2 - mx and y1 + my <= q[1] <= y2 - my and
                      0.6 * z < q[2] < 1.6 * z]
            lifted = [sum(R[i][j] * c for j, c in enumerate((x, y, z))) + t[i] for i in range(3)]
            if inside:
                xs = sorted(q[3][0] for q in inside)
                zs = sorted(q[3][2] for q in inside)
                tracks[track_id].append(((xs[len(xs) // 2], zs[len(zs) // 2]), (lifted[0], lifted[2])))
            if keyframe and len(inside) >= 5 and y2 > cy + 1:
                near = sorted(q[2] for q in inside)[len(inside) // 5]
                ratios.append(near / (fx * a.camera_height / (y2 - cy)))

    if ratios:
        print("keyframe detections with 5+ map points in the box: %d; near-side depth / flat-road distance of the "
              "bottom edge: 10th %.2f, median %.2f, 90th percentile %.2f" % (
                  len(ratios), percentile(ratios, 0.1), percentile(ratios, 0.5), percentile(ratios, 0.9)))
    else:
        print("no keyframe detection has 5 map points in its box")
    print()
    print("| track | detections with points | points' median moves over x, z (m) | lifted boxes move over x, z (m) |")
    print("|---|---|---|---|")
    for track_id, rows in sorted(tracks.items(), key=lambda kv: int(kv[0]) if kv[0].isdigit() else -1):
        if len(rows) < a.min_detections:
            continue
        spans = [max(r[k][i] for r in rows) - min(r[k][i] for r in rows) for k in (0, 1) for i in (0, 1)]
        print("| %s | %d | %.2f, %.2f | %.2f, %.2f |" % (track_id, len(rows), *spans))


if __name__ == "__main__":
    main()
