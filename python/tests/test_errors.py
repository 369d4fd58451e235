"""Bad input raises a Python exception naming what was wrong; the interpreter lives on."""
import os

import numpy as np
import pytest

import moslam

SETTINGS = "configs/Synthetic_RGBD.yaml"  # 640x480, RGB-D


@pytest.fixture
def system():
    return moslam.System(SETTINGS, sensor="rgbd")


def frame(dtype=np.uint8, shape=(480, 640, 3)):
    return np.zeros(shape, dtype)


DEPTH = np.zeros((480, 640), np.uint16)


def test_wrong_dtypes_are_type_errors(system):
    with pytest.raises(TypeError, match="image: expected dtype uint8, got float32"):
        system.track(0.0, frame(np.float32), depth=DEPTH)
    with pytest.raises(TypeError, match="depth: expected dtype uint16 .* or float32 .*float64"):
        system.track(0.0, frame(), depth=np.zeros((480, 640)))
    with pytest.raises(TypeError, match="mask: expected dtype uint8 or bool"):
        system.track(0.0, frame(), depth=DEPTH, mask=np.zeros((480, 640), np.int32))
    with pytest.raises(TypeError, match="image: expected a numpy.ndarray, got list"):
        system.track(0.0, [[0]], depth=DEPTH)
    assert system.frames == 0


def test_wrong_shapes_are_value_errors(system):
    for bad in [frame(shape=(480, 640, 2)), frame(shape=(480,)), frame(shape=(0, 640))]:
        with pytest.raises(ValueError, match="image: expected shape") as error:
            system.track(0.0, bad, depth=DEPTH)
        assert error.type is ValueError
    with pytest.raises(ValueError, match="depth: expected shape"):
        system.track(0.0, frame(), depth=np.zeros((480, 640, 1), np.uint16))
    with pytest.raises(ValueError, match="needs depth="):
        system.track(0.0, frame())
    with pytest.raises(ValueError, match="takes no right="):
        system.track(0.0, frame(), depth=DEPTH, right=frame())


def test_sizes_that_disagree_with_the_settings_are_input_errors(system):
    with pytest.raises(moslam.InputError, match="is not the size of the settings"):
        system.track(0.0, frame(shape=(240, 320, 3)), depth=np.zeros((240, 320), np.uint16))
    with pytest.raises(moslam.InputError, match="depth: .* is not the image's size"):
        system.track(0.0, frame(), depth=np.zeros((240, 320), np.uint16))
    with pytest.raises(moslam.InputError, match="mask: expected 8-bit single-channel"):
        system.track(0.0, frame(), depth=DEPTH, mask=np.zeros((10, 10), np.uint8))
    _, state = system.track(0.0, frame(), depth=DEPTH)  # still usable
    assert state == "not_initialized"
    with pytest.raises(moslam.InputError, match="goes back"):
        system.track(-1.0, frame(), depth=DEPTH)


def test_bad_settings_and_files(tmp_path):
    with pytest.raises(FileNotFoundError, match="settings: no file 'nowhere.yaml'"):
        moslam.System("nowhere.yaml")
    with pytest.raises(FileNotFoundError, match="vocabulary"):
        moslam.System(SETTINGS, vocabulary="nowhere.mvoc")
    with pytest.raises(ValueError, match="sensor: 'kinect' is none of"):
        moslam.System(SETTINGS, sensor="kinect")
    bad = tmp_path / "bad.yaml"
    bad.write_text("%YAML:1.0\nCamera.fx: -5.0\n")
    with pytest.raises(moslam.InputError, match=str(bad)):
        moslam.System(str(bad))
    not_yaml = tmp_path / "garbage.yaml"
    not_yaml.write_bytes(b"\x00\xff not yaml {{{")
    with pytest.raises(moslam.InputError):
        moslam.System(str(not_yaml))
    with pytest.raises(FileNotFoundError):
        moslam.System("")
    with pytest.raises(moslam.InputError, match="no_such_card.yaml"):
        moslam.Segmenter("no_such_card.yaml")
    assert issubclass(moslam.InputError, ValueError)


def test_eval_checks_its_arrays():
    times = np.arange(10) * 0.1
    poses = np.tile(np.eye(4), (10, 1, 1))
    with pytest.raises(ValueError, match=r"shape \(N, 4, 4\)"):
        moslam.eval.ate(times, poses[:, :3], times, poses)
    with pytest.raises(ValueError, match="shape"):
        moslam.eval.ate(times, poses[:5], times, poses)
    rotated = poses.copy()
    rotated[3, 0, 0] = 2.0
    with pytest.raises(ValueError, match="pose 3 is not a rigid transform"):
        moslam.eval.ate(times, rotated, times, poses)
    with pytest.raises(TypeError):
        moslam.eval.ate("a", poses, times, poses)
    with pytest.raises(moslam.InputError):
        moslam.eval.ate(times, poses, times + 100.0, poses)  # nothing associates


def test_eval_on_arrays():
    times = np.arange(20) * 0.1
    gt = np.tile(np.eye(4), (20, 1, 1))
    gt[:, 0, 3] = np.linspace(0, 2, 20)
    est = gt.copy()
    est[:, 1, 3] += 0.01 * (-1) ** np.arange(20)  # +-1 cm zigzag
    ate = moslam.eval.ate(times, gt, times, est, alignment="none")
    assert ate["count"] == 20
    assert ate["rmse"] == pytest.approx(0.01, abs=1e-12)
    rpe = moslam.eval.rpe(times, gt, times, est, delta=1, delta_unit="f", convention="evo")
    assert rpe["rmse"] == pytest.approx(0.02, abs=1e-9)
    assert ate["alignment"].shape == (4, 4)
