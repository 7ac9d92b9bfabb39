"""BE-SLAM's results from Python: open a `beslam run` output folder and score trajectories exactly as
`beslam eval` does (the evaluator is the host's own C++ code, through the `_beslam` extension).

    import beslam
    run = beslam.open_run("out/demo")
    print(run.summary["ape"]["sim3_rmse"], run.poses.shape)          # (N, 4, 4) T_world_cam
    score = beslam.evaluate("gt.txt", "out/demo/trajectory.kitti", align="sim3")
    print(score["ape"]["trans"]["rmse"])
    run = beslam.run("configs/demo.yaml", out="out/py", overrides={"backend.seed": 2},
                     progress=lambda stage, done, total: print(stage, done, total))

Bad input raises ValueError with one line naming the file.
"""
import csv
import json
import os
import pty
import re
import select
import shutil
import subprocess

import numpy as np

from ._beslam import detect_format
from ._beslam import evaluate as _evaluate
from ._beslam import read_trajectory

__all__ = ["Run", "detect_format", "evaluate", "open_run", "read_trajectory", "run"]


def evaluate(ref, est, format="", align="none", align_first=0, max_diff=0.01, offset=0.0, delta=1,
             all_pairs=False):
    """APE and RPE of the trajectory file `est` against `ref`, as `beslam eval --json` writes them: a dict
    with "pairs", "alignment" ({"type", "scale", "rotation", "translation"}) and "ape" / "rpe", each with
    "trans" (m), "rot" (degrees) and "full", each {"rmse", "mean", "median", "std", "min", "max"}.
    format: "kitti", "tum" or "" (detected from `ref`); align: "none", "se3" or "sim3"; the rest as the
    command's options (--align-first, --max-diff, --offset, --delta, --all-pairs)."""
    return json.loads(_evaluate(os.fspath(ref), os.fspath(est), format, align, int(align_first), float(max_diff),
                                float(offset), int(delta), bool(all_pairs)))


def _fail(path, problem):
    raise ValueError("%s: %s" % (path, problem))


class Run:
    """A `beslam run` output folder. Attributes (read when the folder is opened):
    folder; summary (summary.json as a dict); stamps (N,) and poses (N, 4, 4): the final trajectory
    (trajectory.tum, T_world_cam; frames the backend did not track are absent, summary["untracked_frames"]
    lists them); online_stamps / online_poses (the pose
    each frame got when it was tracked, trajectory_online.tum, where present); keyframe_stamps /
    keyframe_poses (keyframes.tum, where present); timing (timing.csv as {column: array}); objects (the
    rows of objects.txt as dicts, empty without a detector)."""

    def __init__(self, folder):
        self.folder = os.fspath(folder)
        if not os.path.isdir(self.folder):
            _fail(self.folder, "not a folder" if os.path.exists(self.folder) else "no such folder")
        summary = os.path.join(self.folder, "summary.json")
        try:
            with open(summary) as f:
                self.summary = json.load(f)
        except OSError as e:
            _fail(summary, e.strerror)
        except ValueError as e:
            _fail(summary, "not JSON: %s" % e)
        self.stamps, self.poses = read_trajectory(os.path.join(self.folder, "trajectory.tum"), "tum")
        self.online_stamps, self.online_poses = self._optional("trajectory_online.tum")
        self.keyframe_stamps, self.keyframe_poses = self._optional("keyframes.tum")
        self.timing = self._timing()
        self.objects = self._objects()

    def _optional(self, name):
        path = os.path.join(self.folder, name)
        if not os.path.exists(path):
            return np.zeros(0), np.zeros((0, 4, 4))
        return read_trajectory(path, "tum")

    def _timing(self):
        path = os.path.join(self.folder, "timing.csv")
        if not os.path.exists(path):
            return {}
        with open(path, newline="") as f:
            rows = list(csv.reader(f))
        if not rows:
            _fail(path, "empty")
        header, columns = rows[0], {name: [] for name in rows[0]}
        for n, row in enumerate(rows[1:], 2):
            if len(row) != len(header):
                _fail("%s:%d" % (path, n), "expected %d fields, got %d" % (len(header), len(row)))
            for name, value in zip(header, row):
                try:
                    columns[name].append(float(value) if value != "" else np.nan)
                except ValueError:
                    _fail("%s:%d" % (path, n), "'%s' in column %s is not a number" % (value, name))
        return {name: np.array(values) for name, values in columns.items()}

    def _objects(self):
        path = os.path.join(self.folder, "objects.txt")
        if not os.path.exists(path):
            return []
        names = ("frame", "track_id", "type", "truncated", "occluded", "alpha", "x1", "y1", "x2", "y2", "height",
                 "width", "length", "x", "y", "z", "rotation_y", "score")
        out = []
        with open(path) as f:
            for n, line in enumerate(f, 1):
                v = line.split()
                if not v:
                    continue
                if len(v) != len(names) + 1:
                    _fail("%s:%d" % (path, n), "expected %d fields (a KITTI tracking row and a motion state), got %d"
                          % (len(names) + 1, len(v)))
                row = {"type": v[2], "motion_state": v[-1]}
                try:
                    row["frame"], row["track_id"] = int(v[0]), int(v[1])
                    for k in range(3, len(names)):
                        row[names[k]] = float(v[k])
                except ValueError:
                    _fail("%s:%d" % (path, n), "a number field is not a number")
                out.append(row)
        return out

    def evaluate(self, reference, align="se3", **options):
        """This run's final trajectory (trajectory.kitti for a KITTI-format reference, else trajectory.tum)
        scored against `reference` as `beslam eval` does; options as beslam.evaluate's."""
        reference = os.fspath(reference)
        fmt = options.pop("format", "") or detect_format(reference)
        est = os.path.join(self.folder, "trajectory.kitti" if fmt == "kitti" else "trajectory.tum")
        return evaluate(reference, est, format=fmt, align=align, **options)


def open_run(folder):
    """The `beslam run` output folder `folder` as a Run (see Run)."""
    return Run(folder)


def _binary():
    """The `beslam` command: $BESLAM_COMMAND, else the one beside this package (the build tree's bin/, or the
    install prefix's bin/), else the first on PATH."""
    if os.environ.get("BESLAM_COMMAND"):
        return os.environ["BESLAM_COMMAND"]
    here = os.path.dirname(os.path.abspath(__file__))
    for up in (2, 4):  # build/python/beslam -> build/bin; PREFIX/lib/python3.X/dist-packages/beslam -> PREFIX/bin
        candidate = os.path.join(here, *([os.pardir] * up), "bin", "beslam")
        if os.access(candidate, os.X_OK):
            return os.path.normpath(candidate)
    found = shutil.which("beslam")
    if not found:
        raise RuntimeError("the beslam command was not found beside the package or on PATH (set BESLAM_COMMAND)")
    return found


_PROGRESS = re.compile(rb"(beslam synth: frame|frame) (\d+)/(\d+)")


def run(pipeline, out, overrides=None, progress=None, overwrite=False, extra_args=()):
    """Runs `beslam run PIPELINE --out OUT --set KEY=VALUE...` (the command itself, so the run is exactly the
    command line's) and returns the finished run as a Run. overrides: {key: value} or ["key=value", ...];
    progress: called as progress(stage, done, total) with stage "render" (a synthetic sequence being made)
    or "frames", while the run goes on; overwrite: replace an earlier run in `out` (the command refuses a used
    folder otherwise). Raises RuntimeError with the command's error lines when it fails."""
    args = [_binary(), "run", os.fspath(pipeline), "--out", os.fspath(out)] + (["--overwrite"] if overwrite else [])
    items = overrides.items() if isinstance(overrides, dict) else [tuple(o.split("=", 1)) for o in overrides or []]
    for key, value in items:
        if isinstance(value, bool):
            value = "true" if value else "false"
        args += ["--set", "%s=%s" % (key, value)]
    args += list(extra_args)
    # The command draws its progress on a terminal only: give its stderr one (a pseudo-terminal) and read it.
    # The slave end stays open here until the command has ended, so no hang-up can drop what it last wrote.
    master, slave = pty.openpty()
    err = bytearray()
    pending = [b""]  # the line being written: the command writes a progress line a few bytes at a time

    def drain(timeout):
        """Reads what the command wrote within `timeout` seconds; False when nothing came."""
        ready, _, _ = select.select([master], [], [], timeout)
        if not ready:
            return False
        chunk = os.read(master, 65536)
        err.extend(chunk)
        *lines, pending[0] = re.split(rb"[\r\n]", pending[0] + chunk)
        for line in lines if progress else ():
            m = _PROGRESS.search(line)
            if m:
                progress("render" if m.group(1).startswith(b"beslam") else "frames", int(m.group(2)), int(m.group(3)))
        return bool(chunk)

    try:
        proc = subprocess.Popen(args, stdin=subprocess.DEVNULL, stdout=subprocess.PIPE, stderr=slave)
        try:
            while proc.poll() is None:
                drain(0.2)
            while drain(0):
                pass
        finally:
            stdout = proc.communicate()[0]
    finally:
        os.close(slave)
        os.close(master)
    err = bytes(err)
    if proc.returncode != 0:
        lines = [l for l in re.split(r"[\r\n]", err.decode(errors="replace")) if l.strip() and
                 not _PROGRESS.search(l.encode())]
        raise RuntimeError("beslam run %s failed (exit %d): %s" % (pipeline, proc.returncode,
                                                                   " / ".join(lines[-3:]) or stdout.decode()))
    return Run(out)
