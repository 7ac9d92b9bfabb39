#!/usr/bin/env python3
"""How fast a detector's boxes make parked cars seem to move: the floor under any static test.

  scripts/parked-drift.py --poses POSES --times TIMES [--range M] [--min-detections N] [--z Z]
                          [--static-speed V] [--near M] RUN

RUN is a `beslam run` output folder whose motion checker gave track ids (RUN/objects.txt: KITTI tracking
rows, frame, track id, class, truncation, ..., x y z of the box's bottom centre in the camera frame, ...).
POSES are the true camera poses (KITTI odometry format, one 3x4 row per frame: T_world_cam), TIMES the
frame times (KITTI times.txt). Run it on a pipeline that replayed those poses (`backend_pose_replay`), so
whatever moves is the boxes.

Every car track with at least N detections within M metres (horizontal distance from the camera; boxes
cut by the image border, truncation > 0, left out) is placed in the world bird's-eye view with the true
poses, and one straight line is fitted through all its positions: its velocity is how fast the boxes make
the car seem to move, its standard error how well its own scatter pins that down. For a parked car,
|v| + Z * se is the best bound any static test could reach on that track, with all of its detections in
one window; a test that must reject cars faster than V m/s (motion_bev_tracker's static_speed) can call it
static only when that bound is below V. The script also prints the bound with the tracks' median velocity
taken off every track: what a perfect calibration of the detector's systematic error, fitted on these very
tracks, would leave; and for both, the earliest detection from which a window growing from the track's
first detection is below V, and how many detections a static call from there would cover. On real KITTI
odometry nearly every car in view is parked (docs/motion.md).

--near M adds the boxes' range error as a share of the range: for each track with two or more detections
closer than M metres, the mean world position of those is taken as the car's place (a box's range error
shrinks with the square of its range), and every farther detection's range is compared with that place's
range from the same camera. The velocity a parked car seems to move at is about this share times the ego's
speed.

--state STATE keeps only the detections the motion checker gave that state: with `static`, what the boxes a
checker hands on as parked (to the mask generator, the backend and the reconstructor) make a parked car seem to
do."""
import collections
import math
import os
import sys

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "lib"))
import run_files  # noqa: E402
from run_files import fail  # noqa: E402


def read_tracks(run, poses, times, max_range, state=None):
    tracks = collections.defaultdict(list)
    for car in run_files.cars(run, max_range, unclipped=True):
        if state and car.state != state:
            continue
        if car.frame < 0 or car.frame >= len(poses) or car.frame >= len(times):
            fail(run + "/objects.txt", 0, "frame %d has no pose or time (%d poses, %d times)" % (
                car.frame, len(poses), len(times)))
        m = poses[car.frame]
        x, y, z = car.bottom_cam
        wx = m[0] * x + m[1] * y + m[2] * z + m[3]
        wz = m[8] * x + m[9] * y + m[10] * z + m[11]
        tracks[car.track].append((times[car.frame], wx, wz, math.hypot(x, z), car.frame))
    return tracks


def line_fit(track):
    """Velocity (vx, vz) of a least-squares line through the positions, and its standard error."""
    n = len(track)
    t_mean = sum(p[0] for p in track) / n
    s_tt = sum((p[0] - t_mean) ** 2 for p in track)
    if s_tt <= 0:
        return None
    velocity, residual = [], 0.0
    for axis in (1, 2):
        mean = sum(p[axis] for p in track) / n
        slope = sum((p[0] - t_mean) * (p[axis] - mean) for p in track) / s_tt
        velocity.append(slope)
        residual += sum((p[axis] - mean - slope * (p[0] - t_mean)) ** 2 for p in track)
    rms = math.sqrt(residual / max(2 * n - 4, 1))
    return velocity, rms / math.sqrt(s_tt), rms


def first_below(track, offset, z, speed):
    """1-based detection at which a window from the track's first detection first gives a bound below speed
    (the line's speed with offset taken off its velocity, plus z standard errors)."""
    for m in range(3, len(track) + 1):
        fit = line_fit(track[:m])
        if fit and math.hypot(fit[0][0] - offset[0], fit[0][1] - offset[1]) + z * fit[1] < speed:
            return m
    return None


def main():
    ap = run_files.track_parser(__doc__, 8)
    ap.add_argument("--poses", required=True, help="true poses, KITTI odometry format")
    ap.add_argument("--times", required=True, help="frame times, one per line")
    ap.add_argument("--z", type=float, default=2.0, help="standard errors of the bound (default 2, z_static)")
    ap.add_argument("--static-speed", type=float, default=1.0, help="m/s a static test rejects (default 1)")
    ap.add_argument("--near", type=float, default=0.0, help="range error against the near detections (m; 0: off)")
    ap.add_argument("--state", choices=["static", "dynamic", "unknown"],
                    help="only the detections the motion checker gave this state (default: all)")
    a = ap.parse_args()
    if a.min_detections < 3:
        sys.exit("--min-detections must be at least 3")
    poses = run_files.rows(a.poses, 12)
    times = [r[0] for r in run_files.rows(a.times, 1)]
    fits = []
    for track_id, track in read_tracks(a.run, poses, times, a.range, a.state).items():
        if len(track) < a.min_detections:
            continue
        fit = line_fit(track)
        if fit:
            fits.append((track_id, track, fit))
    if not fits:
        sys.exit("%s/objects.txt: no car track has %d detections within %g m" % (a.run, a.min_detections, a.range))
    for f in fits:
        f[1].sort()
    fits.sort(key=lambda f: f[1][0][0])
    median = [sorted(f[2][0][k] for f in fits)[len(fits) // 2] for k in (0, 1)]
    print("| track | detections | range (m) | velocity x, z (m/s) | speed (m/s) | se (m/s) | residual (m) | bound "
          "| from | bound, median velocity taken off | from |")
    print("|---|---|---|---|---|---|---|---|---|---|---|")
    bounds, calibrated, covered, covered_cal, detections = [], [], 0, 0, 0
    for track_id, track, (v, se, rms) in fits:
        b = math.hypot(v[0], v[1]) + a.z * se
        b_cal = math.hypot(v[0] - median[0], v[1] - median[1]) + a.z * se
        first = first_below(track, (0.0, 0.0), a.z, a.static_speed)
        first_cal = first_below(track, median, a.z, a.static_speed)
        bounds.append(b)
        calibrated.append(b_cal)
        detections += len(track)
        covered += len(track) - first + 1 if first else 0
        covered_cal += len(track) - first_cal + 1 if first_cal else 0
        print("| %s | %d | %.1f-%.1f | %.2f, %.2f | %.2f | %.2f | %.2f | %.2f | %s | %.2f | %s |" % (
            track_id, len(track), min(p[3] for p in track), max(p[3] for p in track), v[0], v[1],
            math.hypot(v[0], v[1]), se, rms, b, first or "-", b_cal, first_cal or "-"))
    speeds = sorted(math.hypot(*f[2][0]) for f in fits)
    print()
    print("%d tracks, %d detections; apparent speed median %.2f m/s; bound |v| + %g se median %.2f, lowest %.2f "
          "m/s: %d tracks below %g m/s, a growing window static on %d detections; with the median velocity (%.2f, "
          "%.2f) taken off: %d tracks below, static on %d detections" % (
              len(fits), detections, speeds[len(speeds) // 2], a.z, sorted(bounds)[len(bounds) // 2], min(bounds),
              sum(1 for b in bounds if b < a.static_speed), a.static_speed, covered, median[0], median[1],
              sum(1 for b in calibrated if b < a.static_speed), covered_cal))
    if a.near > 0:
        e = range_errors([f[1] for f in fits], poses, a.near)
        if not e:
            sys.exit("%s/objects.txt: no track has two detections closer than %g m" % (a.run, a.near))
        mean = sum(e) / len(e)
        sd = math.sqrt(sum((x - mean) ** 2 for x in e) / len(e))
        print("range error of %d detections beyond %g m against their track's place within it: median %+.3f, sd "
              "%.3f, 10th-90th percentile %+.3f to %+.3f" % (len(e), a.near, e[len(e) // 2], sd,
                                                              e[len(e) // 10], e[(9 * len(e)) // 10]))


def range_errors(tracks, poses, near):
    """Relative range errors of the detections farther than `near` against the track's near place."""
    errors = []
    for track in tracks:
        close = [p for p in track if p[3] < near]
        if len(close) < 2:
            continue
        place = (sum(p[1] for p in close) / len(close), sum(p[2] for p in close) / len(close))
        for t, wx, wz, rng, frame in track:
            if rng < near:
                continue
            m = poses[frame]
            errors.append(rng / math.hypot(place[0] - m[3], place[1] - m[11]) - 1)
    return sorted(errors)


if __name__ == "__main__":
    main()
