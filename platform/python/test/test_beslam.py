"""The Python package against the host: trajectories read as the C++ readers read them, scores equal to
`beslam eval --json`'s and to evo's reference figures, a run folder opened, a pipeline run with progress,
and bad input as one ValueError naming the file. Needs the build tree (ctest sets PYTHONPATH and
BESLAM_BINARY_DIR); the evo test skips without ../shared/data."""
import json
import math
import os
import subprocess

import numpy as np
import pytest

import beslam

BUILD = os.environ.get("BESLAM_BINARY_DIR", "build")
SHARED = os.environ.get("BESLAM_SHARED_DATA", "../shared/data")
COMMAND = os.path.join(BUILD, "bin", "beslam")


def write_kitti(path, positions):
    with open(path, "w") as f:
        for x, y, z in positions:
            f.write("1 0 0 %r 0 1 0 %r 0 0 1 %r\n" % (x, y, z))


def test_evaluate_equals_the_command_and_knows_a_shifted_trajectory(tmp_path):
    ref = [(0.1 * i, 0.0, 0.5 * i + 0.01 * i * i) for i in range(30)]
    est = [(x + 0.2, y, z) for x, y, z in ref]  # shifted by 0.2 m: SE(3) alignment takes it all out
    write_kitti(tmp_path / "ref.txt", ref)
    write_kitti(tmp_path / "est.txt", est)
    none = beslam.evaluate(tmp_path / "ref.txt", tmp_path / "est.txt", align="none")
    assert none["pairs"] == 30
    assert math.isclose(none["ape"]["trans"]["rmse"], 0.2, rel_tol=1e-9)
    se3 = beslam.evaluate(tmp_path / "ref.txt", tmp_path / "est.txt", align="se3")
    assert se3["ape"]["trans"]["rmse"] < 1e-9
    subprocess.run([COMMAND, "eval", "--ref", str(tmp_path / "ref.txt"), "--est", str(tmp_path / "est.txt"),
                    "--align", "none", "--json", str(tmp_path / "cli.json")], check=True, capture_output=True)
    with open(tmp_path / "cli.json") as f:
        assert json.load(f) == none


def test_evaluate_reproduces_evo_on_kitti_00():
    ref, est = os.path.join(SHARED, "evo", "KITTI_00_gt.txt"), os.path.join(SHARED, "evo", "KITTI_00_ORB.txt")
    if not os.path.exists(ref):
        pytest.skip("evo's test trajectories not found under %s (shared data absent)" % SHARED)
    score = beslam.evaluate(ref, est, format="kitti", align="sim3")
    assert math.isclose(score["ape"]["trans"]["rmse"], 0.937709074, rel_tol=1e-6)
    assert math.isclose(score["rpe"]["trans"]["rmse"], 0.027822453, rel_tol=1e-6)


def test_read_trajectory_gives_4x4_poses_and_names_a_bad_file(tmp_path):
    write_kitti(tmp_path / "t.txt", [(1.0, 2.0, 3.0), (4.0, 5.0, 6.0)])
    stamps, poses = beslam.read_trajectory(str(tmp_path / "t.txt"))
    assert poses.shape == (2, 4, 4) and stamps.shape == (2,)
    assert np.allclose(poses[1][:3, 3], [4, 5, 6]) and np.allclose(poses[0][3], [0, 0, 0, 1])
    (tmp_path / "bad.txt").write_text("1 0 0 nan-ish 0 1 0 0 0 0 1 0\n")
    with pytest.raises(ValueError, match="bad.txt"):
        beslam.read_trajectory(str(tmp_path / "bad.txt"))
    with pytest.raises(ValueError, match="align"):
        beslam.evaluate(tmp_path / "t.txt", tmp_path / "t.txt", align="affine")


def tiny_sequence(root):
    """A KITTI-layout sequence of 8 noise frames and its poses, and a pipeline that replays the poses."""
    import zlib
    import struct
    seq = root / "data" / "sequences" / "00"
    (seq / "image_0").mkdir(parents=True)
    (root / "data" / "poses").mkdir(parents=True)
    rng = np.random.default_rng(7)
    for i in range(8):  # an 8-bit grey PNG written by hand (no imaging package needed)
        pixels = rng.integers(0, 256, size=(48, 64), dtype=np.uint8)
        raw = b"".join(b"\x00" + row.tobytes() for row in pixels)

        def chunk(kind, data):
            return struct.pack(">I", len(data)) + kind + data + struct.pack(">I", zlib.crc32(kind + data))
        png = b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", struct.pack(">IIBBBBB", 64, 48, 8, 0, 0, 0, 0)) + \
            chunk(b"IDAT", zlib.compress(raw)) + chunk(b"IEND", b"")
        (seq / "image_0" / ("%06d.png" % i)).write_bytes(png)
    (seq / "times.txt").write_text("".join("%g\n" % (0.1 * i) for i in range(8)))
    (seq / "calib.txt").write_text("P0: 50 0 32 0 0 50 24 0 0 0 1 0\n")
    write_kitti(root / "data" / "poses" / "00.txt", [(0.5 * i, 0.0, 0.1 * i * i) for i in range(8)])
    pipeline = root / "pipeline.yaml"
    pipeline.write_text('dataset: {type: kitti_odometry, root: data, sequence: "00"}\n'
                        "backend: {plugin: backend_pose_replay, poses: data/poses/00.txt}\n")
    return pipeline


def test_run_reports_progress_and_opens_its_folder(tmp_path):
    pipeline = tiny_sequence(tmp_path)
    seen = []
    run = beslam.run(pipeline, tmp_path / "out", progress=lambda stage, done, total: seen.append((stage, done, total)))
    assert ("frames", 8, 8) in seen
    assert run.poses.shape == (8, 4, 4) and run.stamps.shape == (8,)
    assert np.allclose(run.poses[7][:3, 3], [3.5, 0.0, 4.9])
    assert run.summary["frames"] == 8
    assert "total_ms" in run.timing and run.timing["total_ms"].shape == (8,)
    assert run.objects == []
    score = run.evaluate(tmp_path / "data" / "poses" / "00.txt", align="none")
    assert score["ape"]["trans"]["rmse"] < 1e-9
    again = beslam.open_run(tmp_path / "out")
    assert np.array_equal(again.poses, run.poses)
    with pytest.raises(RuntimeError, match="overwrite"):  # a used folder is refused without it
        beslam.run(pipeline, tmp_path / "out")
    assert beslam.run(pipeline, tmp_path / "out", overwrite=True).summary["frames"] == 8


def test_a_failed_run_and_a_missing_folder_are_one_clear_error(tmp_path):
    (tmp_path / "broken.yaml").write_text("dataset: {type: kitti_odometry, root: nowhere}\n")
    with pytest.raises(RuntimeError, match="broken.yaml"):
        beslam.run(tmp_path / "broken.yaml", tmp_path / "out")
    with pytest.raises(ValueError, match="no such folder"):
        beslam.open_run(tmp_path / "absent")
