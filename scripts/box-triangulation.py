#!/usr/bin/env python3
"""Whether a 2D detector's boxes hold a parked car still enough for a static test by triangulation.

  scripts/box-triangulation.py --poses POSES --calib CALIB [--camera-height H] [--range M]
                               [--min-detections N] RUN

RUN is a `beslam run` output folder with track ids in RUN/objects.txt, made on the true poses POSES (KITTI
odometry format, T_world_cam per frame; `configs/kitti_detector_image_true_poses.yaml`); CALIB the sequence's
calib.txt (its P0 row gives the focal length and principal point).

For each car track with at least N detections within M metres (boxes touching the image border left out), one
fixed world point is fitted (Gauss-Newton) to the bottom centres of its 2D boxes, (x1 + x2) / 2 and y2, seen
from the true poses: where a parked car's road contact would be if its boxes held it still. The script prints
the fit's reprojection error and the point's depth below the camera at the nearest place the ego passes,
divided by the camera height: 1 for a box bottom on the road under a parked car. A car driving at v along the
ego's line of travel is triangulated at v_ego / (v_ego - v) times its range, so its contact point sits that
factor lower (1.12 for 1 m/s at 9 m/s): the test that would resolve the epipolar ambiguity with physics needs
parked cars well inside that."""
import collections
import math
import os
import statistics
import sys

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "lib"))
import run_files  # noqa: E402
from run_files import fail  # noqa: E402


def read_intrinsics(path):
    for n, line in enumerate(run_files.lines(path), 1):
        if line.startswith("P0:"):
            p = run_files.numbers(path, n, line[3:], 12)
            if not all(math.isfinite(x) for x in p) or p[0] <= 0 or p[5] <= 0:
                fail(path, n, "P0 needs a positive, finite focal length")
            return p[0], p[5], p[2], p[6]
    fail(path, 0, "no P0 row")


def solve3(a, b):
    """x with a x = b for a 3x3 matrix (Cramer's rule); None when a is singular."""
    def det(m):
        return (m[0][0] * (m[1][1] * m[2][2] - m[1][2] * m[2][1]) - m[0][1] * (m[1][0] * m[2][2] - m[1][2] * m[2][0])
                + m[0][2] * (m[1][0] * m[2][1] - m[1][1] * m[2][0]))
    d = det(a)
    if abs(d) < 1e-12:
        return None
    out = []
    for i in range(3):
        m = [row[:] for row in a]
        for r in range(3):
            m[r][i] = b[r]
        out.append(det(m) / d)
    return out


def to_cam(pose, p):
    """T_cam_world p for a 3x4 T_world_cam row: R^T (p - t)."""
    d = [p[0] - pose[3], p[1] - pose[7], p[2] - pose[11]]
    return [pose[0] * d[0] + pose[4] * d[1] + pose[8] * d[2],
            pose[1] * d[0] + pose[5] * d[1] + pose[9] * d[2],
            pose[2] * d[0] + pose[6] * d[1] + pose[10] * d[2]]


def triangulate(obs, poses, k):
    """The world point whose projections best match the observations (frame, u, v); its RMS error in pixels."""
    fx, fy, cx, cy = k
    frame, u, v = min(obs, key=lambda o: -o[2])  # start from the nearest box: the one lowest in the image
    depth = fy * 1.65 / max(v - cy, 1.0)
    pc = [(u - cx) * depth / fx, 1.65, depth]
    pose = poses[frame]
    p = [pose[0] * pc[0] + pose[1] * pc[1] + pose[2] * pc[2] + pose[3],
         pose[4] * pc[0] + pose[5] * pc[1] + pose[6] * pc[2] + pose[7],
         pose[8] * pc[0] + pose[9] * pc[1] + pose[10] * pc[2] + pose[11]]
    rms = float("inf")
    for _ in range(30):
        jtj = [[0.0] * 3 for _ in range(3)]
        jtr = [0.0] * 3
        sq = 0.0
        for frame, u, v in obs:
            pose = poses[frame]
            x, y, z = to_cam(pose, p)
            if z < 0.5:
                return None, rms
            r = [u - (fx * x / z + cx), v - (fy * y / z + cy)]
            sq += r[0] ** 2 + r[1] ** 2
            # d(u, v)/d(p_cam), then through R^T to the world point.
            du = [fx / z, 0.0, -fx * x / z ** 2]
            dv = [0.0, fy / z, -fy * y / z ** 2]
            for row, res in ((du, r[0]), (dv, r[1])):
                j = [row[0] * pose[0] + row[1] * pose[1] + row[2] * pose[2],
                     row[0] * pose[4] + row[1] * pose[5] + row[2] * pose[6],
                     row[0] * pose[8] + row[1] * pose[9] + row[2] * pose[10]]
                for a in range(3):
                    jtr[a] += j[a] * res
                    for b in range(3):
                        jtj[a][b] += j[a] * j[b]
        rms = math.sqrt(sq / (2 * len(obs)))
        step = solve3(jtj, jtr)
        if step is None:
            return None, rms
        p = [p[i] + step[i] for i in range(3)]
        if math.sqrt(sum(s * s for s in step)) < 1e-7:
            break
    return p, rms


def main():
    ap = run_files.track_parser(__doc__, 6)
    ap.add_argument("--poses", required=True, help="true poses, KITTI odometry format")
    ap.add_argument("--calib", required=True, help="the sequence's calib.txt")
    ap.add_argument("--camera-height", type=float, default=1.65, help="metres over the road (KITTI: 1.65)")
    a = ap.parse_args()
    poses = run_files.rows(a.poses, 12)
    k = read_intrinsics(a.calib)
    width, height = 2 * k[2], 2 * k[3]  # KITTI's principal point is near the image centre
    tracks = collections.defaultdict(list)
    for car in run_files.cars(a.run, a.range, unclipped=True):
        x1, y1, x2, y2 = car.box2d
        if x1 < 3 or x2 > width - 3 or y2 > height - 3:
            continue
        if car.frame < 0 or car.frame >= len(poses):
            fail(a.run + "/objects.txt", 0, "frame %d has no pose (%d poses)" % (car.frame, len(poses)))
        tracks[car.track].append((car.frame, 0.5 * (x1 + x2), y2))
    ratios = []
    print("track  boxes  frames    rms px  depth under the camera / camera height")
    for track, obs in sorted(tracks.items(), key=lambda kv: kv[1][0][0]):
        if len(obs) < a.min_detections:
            continue
        p, rms = triangulate(obs, poses, k)
        if p is None:
            print("%5s  %5d  %3d-%3d   no fit" % (track, len(obs), obs[0][0], obs[-1][0]))
            continue
        # The camera the ego passes the point closest with: the road under it is camera_height below.
        near = min(poses, key=lambda q: math.hypot(q[3] - p[0], q[11] - p[2]))
        below = (p[0] - near[3]) * near[1] + (p[1] - near[7]) * near[5] + (p[2] - near[11]) * near[9]
        ratio = below / a.camera_height
        ratios.append(ratio)
        print("%5s  %5d  %3d-%3d  %6.2f   %.3f" % (track, len(obs), obs[0][0], obs[-1][0], rms, ratio))
    if not ratios:
        sys.exit("no track with %d detections within %g m" % (a.min_detections, a.range))
    q = statistics.quantiles(ratios, n=10) if len(ratios) >= 2 else ratios * 9
    print("%d tracks: depth ratio median %.3f, 10th-90th percentile %.3f-%.3f, range %.3f-%.3f" % (
        len(ratios), statistics.median(ratios), q[0], q[-1], min(ratios), max(ratios)))


if __name__ == "__main__":
    main()
