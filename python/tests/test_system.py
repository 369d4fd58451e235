"""moslam.System against `moslam run --deterministic` on the same frames."""
import json
import os
import subprocess

import cv2
import numpy as np
import pytest

import moslam
from conftest import VOCABULARY


def track_sequence(path, **kwargs):
    seq = moslam.read_sequence(path)
    system = moslam.System(os.path.join(path, "settings.yaml"), vocabulary=VOCABULARY,
                           sensor="rgbd", deterministic=True, **kwargs)
    states = []
    for frame in seq["frames"]:
        image = cv2.imread(frame["image"], cv2.IMREAD_COLOR)
        depth = cv2.imread(frame["depth"], cv2.IMREAD_UNCHANGED)
        pose, state = system.track(frame["timestamp"], image, depth=depth)
        assert (pose is None) == (state != "ok")
        if pose is not None:
            assert pose.shape == (4, 4) and pose.dtype == np.float64
        states.append(state)
    system.finish()
    return seq, system, states


def test_matches_moslam_run_exactly(sequence, moslam_bin, tmp_path):
    out = tmp_path / "run"
    subprocess.run([moslam_bin, "run", "--dataset", "tum", sequence, "--settings",
                    os.path.join(sequence, "settings.yaml"), "--deterministic", "--quiet",
                    "--vocabulary", VOCABULARY, "--out", str(out)],
                   check=True, capture_output=True)
    with open(out / "summary.json") as f:
        cli_rmse = json.load(f)["ate"]["translation_m"]["rmse"]

    seq, system, states = track_sequence(sequence)
    assert states.count("ok") >= 25
    times, poses = system.trajectory()
    assert times.shape == (len(poses),) and poses.shape[1:] == (4, 4)

    # `moslam run` writes CameraTrajectory.txt with 6 decimals for stamps and 9 for positions and
    # computes its ATE from that file: the same numbers, printed the same way.
    rows = [f"{t:.6f} {p[0, 3]:.9f} {p[1, 3]:.9f} {p[2, 3]:.9f}" for t, p in zip(times, poses)]
    with open(out / "CameraTrajectory.txt") as f:
        cli_rows = [" ".join(line.split()[:4]) for line in f if not line.startswith("#")]
    assert rows == cli_rows

    printed = poses.copy()
    printed[:, :3, 3] = [[float(f"{x:.9f}") for x in p[:3, 3]] for p in poses]
    printed_times = np.array([float(f"{t:.6f}") for t in times])
    gt_times, gt_poses = moslam.eval.read_trajectory(seq["ground_truth"])
    ate = moslam.eval.ate(gt_times, gt_poses, printed_times, printed)
    assert ate["rmse"] == cli_rmse
    # Unrounded, the difference is the printing's.
    assert abs(moslam.eval.ate(gt_times, gt_poses, times, poses)["rmse"] - cli_rmse) < 1e-8


def test_results_on_request(sequence):
    _, system, _ = track_sequence(sequence)
    points = system.map_points()
    assert points.ndim == 2 and points.shape[1] == 3 and len(points) > 100
    kf_times, kf_poses = system.keyframe_trajectory()
    assert len(kf_times) >= 1 and kf_poses.shape == (len(kf_times), 4, 4)
    summary = system.summary()
    assert summary["frames"] == 30 and summary["keyframes"] == len(kf_times)
    with pytest.raises(moslam.InputError, match="after Finish"):
        image = np.zeros((240, 320, 3), np.uint8)
        system.track(100.0, image, depth=np.zeros((240, 320), np.uint16))


def test_views_of_other_layouts_track_the_same(sequence):
    """A frame that is a slice of a larger array (rows apart) or a flipped copy is accepted."""
    seq = moslam.read_sequence(sequence)
    system = moslam.System(os.path.join(sequence, "settings.yaml"), deterministic=True)
    frame = seq["frames"][0]
    image = cv2.imread(frame["image"], cv2.IMREAD_COLOR)
    depth = cv2.imread(frame["depth"], cv2.IMREAD_UNCHANGED)
    wide = np.zeros((240, 400, 3), np.uint8)
    wide[:, :320] = image
    _, state = system.track(0.0, wide[:, :320], depth=np.asfortranarray(depth))
    assert state in ("ok", "not_initialized")
    _, state = system.track(0.1, image[::-1, ::-1][::-1, ::-1], depth=depth.astype(np.float32) / 5000)
    assert state in ("ok", "not_initialized", "lost")
    assert system.frames == 2
