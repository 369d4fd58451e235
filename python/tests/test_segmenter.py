"""moslam.Segmenter: masks from a model card (needs the shared ONNX model, skipped without)."""
import os

import cv2
import numpy as np
import pytest

import moslam

CARD = "configs/models/deeplabv3_mnv2_voc.yaml"


@pytest.fixture(scope="module")
def segmenter():
    shared = os.environ.get("MOSLAM_SHARED", "../shared")
    if not os.path.exists(os.path.join(shared, "models/deeplabv3_mnv2_voc")):
        pytest.skip("the shared model deeplabv3_mnv2_voc is absent (set MOSLAM_SHARED)")
    return moslam.Segmenter(CARD)


def test_segment_gives_probabilities_and_a_mask(segmenter, sequence):
    frame = moslam.read_sequence(sequence)["frames"][10]
    image = cv2.imread(frame["image"], cv2.IMREAD_COLOR)
    probabilities, mask = segmenter.segment(image)
    assert probabilities.dtype == np.float32 and probabilities.ndim == 3
    assert probabilities.shape[0] == len(segmenter.classes)
    np.testing.assert_allclose(probabilities.sum(axis=0), 1.0, atol=1e-3)
    assert mask.shape == image.shape[:2] and mask.dtype == np.uint8
    assert set(np.unique(mask)) <= {0, 255}
    with pytest.raises(TypeError, match="image: expected dtype uint8"):
        segmenter.segment(image.astype(np.float32))


def test_system_with_a_model_card_masks_frames(segmenter, sequence):
    del segmenter  # only for the skip
    seq = moslam.read_sequence(sequence)
    system = moslam.System(os.path.join(sequence, "settings.yaml"), model_card=CARD,
                           deterministic=True)
    for frame in seq["frames"][:3]:
        image = cv2.imread(frame["image"], cv2.IMREAD_COLOR)
        depth = cv2.imread(frame["depth"], cv2.IMREAD_UNCHANGED)
        system.track(frame["timestamp"], image, depth=depth)
    assert system.frames == 3
