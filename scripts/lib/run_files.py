"""Reads the files the diagnostic scripts take: rows of numbers (poses, times, trajectories) and a `beslam run`
folder's objects.txt (KITTI tracking rows: frame, track id, class, truncation, occlusion, alpha, 2D box x1 y1 x2
y2, height width length, x y z of the box's bottom centre in the camera frame, yaw, score; with the motion state
appended). Bad input ends the script with one line naming the file and line."""
import argparse
import collections
import math
import sys

Car = collections.namedtuple("Car", "frame track truncation box2d bottom_cam state")


def track_parser(doc, min_detections):
    """The argument parser of a script that reads a run's car tracks: doc (its docstring) as the description,
    --range, --min-detections and RUN; the script adds its own options."""
    ap = argparse.ArgumentParser(description=doc, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--range", type=float, default=25.0, help="metres from the camera (default 25)")
    ap.add_argument("--min-detections", type=int, default=min_detections,
                    help="detections a track needs (default %d)" % min_detections)
    ap.add_argument("run", help="a `beslam run` output folder")
    return ap


def fail(path, line, problem):
    """Exits with 'PATH[:LINE]: PROBLEM'."""
    sys.exit("%s: %s" % ("%s:%d" % (path, line) if line else path, problem))


def lines(path):
    """The file's lines."""
    try:
        with open(path) as f:
            return f.read().splitlines()
    except OSError as e:
        fail(path, 0, e.strerror)


def numbers(path, n, text, width=None):
    """The numbers of line n's text, exactly width of them when width is given."""
    try:
        v = [float(x) for x in text.split()]
    except ValueError:
        fail(path, n, "expected numbers")
    if width is not None and len(v) != width:
        fail(path, n, "expected %d numbers, got %d" % (width, len(v)))
    return v


def rows(path, width, comments=False):
    """Every non-empty line as width numbers; comments: lines starting with # are skipped (TUM files)."""
    return [numbers(path, n, line, width) for n, line in enumerate(lines(path), 1)
            if line.strip() and not (comments and line.startswith("#"))]


def cars(run, max_range=None, unclipped=False):
    """The car rows of RUN/objects.txt in file order; max_range: only boxes within that horizontal distance of
    the camera; unclipped: only boxes the image border does not cut (truncation 0)."""
    path = run + "/objects.txt"
    out = []
    for n, line in enumerate(lines(path), 1):
        v = line.split()
        if not v:
            continue
        if len(v) < 17:
            fail(path, n, "expected a KITTI tracking row with a motion state, got %d fields" % len(v))
        if v[2] != "Car":
            continue
        try:
            car = Car(int(v[0]), v[1], float(v[3]), tuple(float(x) for x in v[6:10]),
                      (float(v[13]), float(v[14]), float(v[15])), v[-1])
        except ValueError:
            fail(path, n, "the frame, truncation, 2D box or box position is not a number")
        if unclipped and car.truncation > 0:
            continue
        if max_range is not None and math.hypot(car.bottom_cam[0], car.bottom_cam[2]) > max_range:
            continue
        out.append(car)
    return out
