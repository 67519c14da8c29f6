"""A map's places (verification.temporal.place_cut, issue 32): the frames'
place signatures from Python, and a detector that finds where one
environment ends and another begins."""
import numpy as np
import pytest

import lsgd


def stripes(vertical, period, phase=0):
    y, x = np.mgrid[0:120, 0:160]
    v = (x if vertical else y) + phase
    return np.where((v // period) % 2 == 1, 200, 40).astype(np.uint8)


def test_signatures_tell_orientations_apart():
    a = lsgd.place_signature(stripes(True, 7))
    b = lsgd.place_signature(stripes(False, 7))
    assert len(a) == len(b) == 128
    assert lsgd.signature_similarity(a, a) == 1.0
    assert lsgd.signature_similarity(a, b) == 0.0
    with pytest.raises(lsgd.InvalidArgument, match="128"):
        lsgd.signature_similarity(a, b[:5])
    # Bytes whose cells do not sum to about 255 (or 0) are no signature (they scored -3).
    with pytest.raises(lsgd.InvalidArgument, match="not a place signature"):
        lsgd.signature_similarity(b"\xff" * 128, a)
    assert lsgd.signature_similarity(a, bytes(128)) == 0.5


def test_a_detector_finds_the_second_place():
    detector = lsgd.Detector({"search.min_gap": 10, "verification.temporal.place_cut": 1.45})
    rng = np.random.default_rng(3)
    for k in range(120):  # vertical structure, then horizontal from frame 60
        image = stripes(k < 60, 5 + k % 4, k)
        noisy = np.clip(image.astype(int) + rng.integers(-20, 20, image.shape), 0, 255).astype(np.uint8)
        detector.process(noisy)
        if k == 60 + 7:
            assert detector.place_starts == []  # found with the place's ninth frame
    assert detector.place_starts == [60]
    assert lsgd.Detector({"verification.temporal.place_cut": 0}).place_starts == []
