"""Frames described apart from the map (lsgd.FrameDescription, issue 34): a
robot's detector describes, the map's detector processes the description
and gets the Results of the images; descriptions travel as bytes or pickle."""
import math
import pickle

import pytest

import lsgd

from frames import place


def frames():
    return [place(k % 30, k // 30) for k in range(90)]


def same(a, b):
    assert (a.frame, a.loop, a.best.frame, a.status) == (b.frame, b.loop, b.best.frame, b.status)
    assert a.best.score == b.best.score or (math.isnan(a.best.score) and math.isnan(b.best.score))
    assert [c.frame for c in a.candidates] == [c.frame for c in b.candidates]


def test_the_map_gives_the_results_of_the_images():
    options = {"search.min_gap": 10}
    reference, robot, map_ = lsgd.Detector(options), lsgd.Detector(options), lsgd.Detector(options)
    loops = 0
    for k, image in enumerate(frames()):
        described = robot.describe_frame(image)
        sent = pickle.loads(pickle.dumps(described)) if k % 2 else lsgd.FrameDescription.from_bytes(
            described.to_bytes())
        if k % 9 == 4:
            same(map_.query(sent), reference.query(image))
        expected = reference.process(image, id=100 + k)
        got = map_.process(sent, id=100 + k)
        same(got, expected)
        assert got.id == 100 + k
        loops += expected.loop
    assert len(robot) == 0 and len(map_) == 90
    assert loops > 10


def test_a_description_shows_what_it_holds():
    d = lsgd.Detector().describe_frame(frames()[0])
    assert (d.width, d.height) == (160, 120)
    assert d.stages == ["temporal", "geometric"]
    assert d.descriptor.grid == lsgd.Detector().describe(frames()[0]).grid
    assert len(d.to_bytes()) > d.record_bytes > 0
    assert d.signature == lsgd.place_signature(frames()[0])  # the map finds its places by it
    assert lsgd.Detector({"verification.temporal.place_cut": 0}).describe_frame(frames()[0]).signature == b""


def test_what_does_not_fit_is_refused():
    robot = lsgd.Detector({"segmentation.superpixel_size": 25})
    map_ = lsgd.Detector()
    with pytest.raises(lsgd.InvalidArgument, match="other segmentation"):
        map_.process(robot.describe_frame(frames()[0]))
    assert len(map_) == 0
    data = lsgd.Detector().describe_frame(frames()[0]).to_bytes()
    with pytest.raises(lsgd.FormatError):
        lsgd.FrameDescription.from_bytes(data[:-3])
    with pytest.raises(lsgd.FormatError, match="mark"):
        lsgd.FrameDescription.from_bytes(b"x" + data[1:])
