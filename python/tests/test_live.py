"""`moslam run --dataset camera|kinect|rosbag`: a source that cannot be opened is an error naming
it, before any output is written (exit status 2, as any bad input). The live run loop itself is
tested with fake sources in C++ (runner/live_run), bags in sensors/rosbag and rosbag_run."""
import subprocess

SETTINGS = "configs/Synthetic_RGBD.yaml"


def run(moslam_bin, out, *args):
    return subprocess.run([moslam_bin, "run", *args, "--settings", SETTINGS, "--quiet",
                           "--vocabulary", "none", "--out", str(out)],
                          capture_output=True, text=True)


def test_missing_camera_is_named(moslam_bin, tmp_path):
    done = run(moslam_bin, tmp_path / "a", "--dataset", "camera", "/dev/video_moslam_absent")
    assert done.returncode == 2, done.stderr
    assert "/dev/video_moslam_absent: no such camera device" in done.stderr
    assert not (tmp_path / "a").exists()


def test_camera_that_is_no_camera_is_named(moslam_bin, tmp_path):
    text = tmp_path / "video0"
    text.write_text("not a device\n")
    done = run(moslam_bin, tmp_path / "a", "--dataset", "camera", str(text))
    assert done.returncode == 2 and f"{text}: is not a camera device" in done.stderr, done.stderr
    done = run(moslam_bin, tmp_path / "b", "--dataset", "camera", "/dev/null")
    assert done.returncode == 2, done.stderr
    assert "/dev/null: cannot be opened as a V4L2 camera" in done.stderr
    # A stereo pair names both devices; an empty one is refused before any is opened.
    done = run(moslam_bin, tmp_path / "c", "--dataset", "camera", "/dev/video_moslam_l,")
    assert done.returncode == 2 and "--dataset camera: an empty name" in done.stderr


def test_absent_kinect_is_named(moslam_bin, tmp_path):
    done = run(moslam_bin, tmp_path / "a", "--dataset", "kinect", "9")
    assert done.returncode == 2 and "kinect:9: " in done.stderr, done.stderr


def test_file_masks_are_refused_live(sequence, moslam_bin, tmp_path):
    done = run(moslam_bin, tmp_path / "a", "--dataset", "camera", "/dev/null", "--mask-source",
               "synth-gt")
    assert done.returncode == 2 and "needs image files" in done.stderr, done.stderr
    done = run(moslam_bin, tmp_path / "b", "--dataset", "tum", sequence, "--live",
               "--mask-source", "synth-gt")
    assert done.returncode == 2 and "a data set played live" in done.stderr, done.stderr


def test_bad_bags_are_named(moslam_bin, tmp_path):
    done = run(moslam_bin, tmp_path / "a", "--dataset", "rosbag", str(tmp_path / "none.bag"),
               "--topics", "/rgb,/depth")
    assert done.returncode == 2, done.stderr
    assert ("none.bag: no such bag file" in done.stderr
            or "built without librosbag" in done.stderr), done.stderr
    done = run(moslam_bin, tmp_path / "b", "--dataset", "rosbag", str(tmp_path / "none.bag"))
    assert done.returncode == 2 and "--topics" in done.stderr, done.stderr
    done = run(moslam_bin, tmp_path / "c", "--dataset", "tum", str(tmp_path), "--topics", "/rgb")
    assert done.returncode == 2 and "--topics: for --dataset rosbag" in done.stderr, done.stderr


def summary_of(out):
    import json
    with open(out / "summary.json") as f:
        return json.load(f)


def test_recorded_sequence_played_live(sequence, moslam_bin, tmp_path):
    """--live plays the folder as a camera at its frame rate: every frame is tracked or dropped,
    and the ATE against the ground truth still applies (the frames keep their stamps)."""
    done = subprocess.run([moslam_bin, "run", "--dataset", "tum", sequence, "--settings",
                           f"{sequence}/settings.yaml", "--live", "--quiet", "--vocabulary",
                           "none", "--out", str(tmp_path / "live")],
                          capture_output=True, text=True)
    assert done.returncode == 0, done.stderr
    summary = summary_of(tmp_path / "live")
    assert summary["live"]["captured"] == 30
    assert summary["frames"] + summary["dropped"] == 30
    assert summary["live"]["max_queued"] <= 2
    assert summary["end"]["status"] == "completed"


def test_ctrl_c_ends_a_live_run_with_every_output(sequence, moslam_bin, tmp_path):
    import signal
    out = tmp_path / "live"
    process = subprocess.Popen([moslam_bin, "run", "--dataset", "tum", sequence, "--settings",
                                f"{sequence}/settings.yaml", "--live", "--vocabulary", "none",
                                "--out", str(out)],
                               stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    # The run says when its handlers are in place; the replay then lasts 1 s (30 frames).
    for line in process.stderr:
        if "Ctrl-C ends the run" in line:
            break
    process.send_signal(signal.SIGINT)
    stdout, stderr = process.communicate(timeout=120)
    assert process.returncode == 130, stderr
    assert "interrupted by SIGINT" in stdout
    summary = summary_of(out)
    assert summary["end"]["status"] == "interrupted"
    assert summary["live"]["captured"] < 30
    for name in ["CameraTrajectory.txt", "KeyFrameTrajectory.txt", "frames.csv"]:
        assert (out / name).exists(), name
