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


def test_file_masks_and_recorded_options_are_refused_live(moslam_bin, tmp_path):
    done = run(moslam_bin, tmp_path / "a", "--dataset", "camera", "/dev/null", "--mask-source",
               "synth-gt")
    assert done.returncode == 2 and "needs image files" in done.stderr, done.stderr


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
