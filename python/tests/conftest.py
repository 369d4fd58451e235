"""Shared fixtures of the Python module's tests (run by ctest as python/pytest from the
repository root, with PYTHONPATH at the built module and MOSLAM_BIN at the `moslam` program)."""
import os

import pytest

import moslam

VOCABULARY = "data/vocab/moslam_orb.mvoc"


@pytest.fixture(scope="session")
def sequence(tmp_path_factory):
    """A short synthetic RGB-D sequence (w_xyz: a walking person, a moving camera)."""
    out = tmp_path_factory.mktemp("synth") / "w_xyz"
    moslam.synth(str(out), preset="w_xyz", frames=30, seed=3, width=320, height=240)
    return str(out)


@pytest.fixture(scope="session")
def moslam_bin():
    path = os.environ.get("MOSLAM_BIN")
    if not path or not os.path.exists(path):
        pytest.skip("MOSLAM_BIN is not set to the moslam program (ctest sets it)")
    return path
