"""`moslam run --dataset video`: a lossless video of a synthetic sequence gives the trajectory of
the same frames as an image folder (within 1 mm: monocular map units, ~1 m here); bad files are
clear errors."""
import os
import subprocess

import cv2
import numpy as np
import pytest

import moslam
from conftest import VOCABULARY


def run(moslam_bin, dataset, path, settings, out, *extra):
    return subprocess.run([moslam_bin, "run", "--dataset", dataset, path, "--settings", settings,
                           "--deterministic", "--quiet", "--vocabulary", VOCABULARY, "--out",
                           str(out), *extra], capture_output=True, text=True)


def positions(path):
    rows = [line.split() for line in open(path) if not line.startswith("#")]
    return np.array([[float(x) for x in row[:4]] for row in rows]).reshape(-1, 4)


@pytest.fixture(scope="module")
def grey_frames(tmp_path_factory):
    """40 grey frames of a synthetic street (a car driving forward: monocular SLAM initializes
    on it) as their PNG folder and an FFV1 (lossless) video at 10 frames/s."""
    root = tmp_path_factory.mktemp("video")
    seq_path = root / "seq"
    moslam.synth(str(seq_path), preset="kitti_cars", frames=40, seed=5)
    folder = seq_path / "image_0"
    images = sorted(folder.glob("*.png"))
    first = cv2.imread(str(images[0]), cv2.IMREAD_GRAYSCALE)
    video = str(root / "seq.mkv")
    writer = cv2.VideoWriter(video, cv2.CAP_FFMPEG, cv2.VideoWriter_fourcc(*"FFV1"), 10.0,
                             (first.shape[1], first.shape[0]), isColor=False)
    if not writer.isOpened():
        pytest.skip("this OpenCV cannot write FFV1 video")
    for image in images:
        writer.write(cv2.imread(str(image), cv2.IMREAD_GRAYSCALE))
    writer.release()
    return str(folder), video, str(seq_path / "settings.yaml")


def test_video_tracks_as_the_image_folder(grey_frames, moslam_bin, tmp_path):
    folder, video, settings = grey_frames
    for dataset, path in [("folder", folder), ("video", video)]:
        # The folder at 10 frames/s, the video with its container's times (0.1 s apart).
        extra = ["--rate", "10"] if dataset == "folder" else []
        done = run(moslam_bin, dataset, path, settings, tmp_path / dataset, *extra)
        assert done.returncode == 0, done.stderr
    from_folder = positions(tmp_path / "folder" / "CameraTrajectory.txt")
    from_video = positions(tmp_path / "video" / "CameraTrajectory.txt")
    assert len(from_folder) >= 30, "the monocular map did not initialize"
    assert from_video.shape == from_folder.shape
    np.testing.assert_allclose(from_video[:, 0], from_folder[:, 0], atol=1e-3)  # stamps
    assert np.abs(from_video[:, 1:] - from_folder[:, 1:]).max() < 1e-3  # metres (map units)
    # A video run has no depth: `moslam map export` says so instead of reading it as a data set.
    done = subprocess.run([moslam_bin, "map", "export", str(tmp_path / "video")],
                          capture_output=True, text=True)
    assert done.returncode != 0 and "a video run is monocular" in done.stderr, done.stderr


def test_bad_video_files_are_clear_errors(moslam_bin, tmp_path):
    settings = "configs/Synthetic_RGBD.yaml"
    done = run(moslam_bin, "video", str(tmp_path / "none.mkv"), settings, tmp_path / "a")
    assert done.returncode != 0 and "none.mkv: no such video file" in done.stderr
    text = tmp_path / "notes.mp4"
    text.write_text("not a video\n")
    done = run(moslam_bin, "video", str(text), settings, tmp_path / "b")
    assert done.returncode != 0 and "notes.mp4" in done.stderr
    done = run(moslam_bin, "video", str(text), settings, tmp_path / "c", "--mask-source",
               "synth-gt")
    assert done.returncode != 0 and "needs image files" in done.stderr
