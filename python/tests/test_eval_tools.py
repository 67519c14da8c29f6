"""The evaluation tools from Python, through the library calls the CLI makes.

lsgd.sweep: lsgd sweep's grid (include/lsgd/eval/sweep.h): each row equals a
run of its configuration scored with lsgd.evaluate, and the table `lsgd sweep
--csv` writes. lsgd.make_distractor: lsgd bench --distractors' frames
(include/lsgd/eval/distractors.h)."""
import csv
import os
import subprocess

import numpy as np
import pytest

import lsgd
from frames import CLI, place


@pytest.fixture
def route(tmp_path):
    """30 places visited 3 times, as PGM files, with its loop ground truth."""
    folder = tmp_path / "route"
    folder.mkdir()
    names = []
    for k in range(90):
        path = folder / ("%03d.pgm" % k)
        image = place(k % 30, k // 30)
        with open(path, "wb") as f:
            f.write(b"P5\n160 120\n255\n" + np.ascontiguousarray(image).tobytes())
        names.append(str(path))
    (folder / "sequence.txt").write_text("\n".join(names) + "\n")
    (folder / "groundtruth.txt").write_text(
        "".join("%d %d\n" % (q, m) for q in range(30, 90) for m in range(q % 30, q - 29, 30)))
    return str(folder)


def test_rows_equal_runs_scored_alone(route):
    rows = lsgd.sweep(["route=%s,10" % route], ["segmentation.superpixel_size=30,40"],
                      options={"verification.stages": "temporal"}, jobs=2)
    assert [(r["dataset"], r["values"]) for r in rows] == [
        ("route", {"segmentation.superpixel_size": "30"}), ("route", {"segmentation.superpixel_size": "40"})]
    images = lsgd.open_sequence(os.path.join(route, "sequence.txt"))
    gt = lsgd.load_groundtruth(os.path.join(route, "groundtruth.txt"), frames=len(images))
    for row, size in zip(rows, [30, 40]):
        detector = lsgd.Detector({"verification.stages": "temporal", "search.min_gap": 10,
                                  "segmentation.superpixel_size": size})
        m = lsgd.evaluate(lsgd.run(detector, images), gt, min_gap=10)
        assert row["metrics"].declared_loops == m.declared_loops
        assert row["metrics"].recall_at_1 == m.recall_at_1
        assert row["metrics"].average_precision == m.average_precision
        assert row["nodes"] == detector.nodes and row["skipped_frames"] == 0
    assert rows[0]["metrics"].recall_at_1 > 0.5


def test_rows_equal_lsgd_sweep(route, tmp_path):
    if not CLI:
        pytest.skip("the lsgd tool is absent")
    out = tmp_path / "grid.csv"
    subprocess.run([CLI, "sweep", "--dataset", "route=%s,10" % route, "--set", "search.mode=exhaustive,nodes",
                    "--verify", "none", "--csv", str(out)], check=True, capture_output=True)
    table = list(csv.DictReader(open(out)))
    rows = lsgd.sweep(["route=%s,10" % route], ["search.mode=exhaustive,nodes"],
                      options={"verification.stages": "none"})
    assert len(rows) == len(table) == 2
    # One dataset and one set as strings: the same grid (a str was iterated character by character).
    one = lsgd.sweep("route=%s,10" % route, "search.mode=exhaustive,nodes",
                     options={"verification.stages": "none"})
    assert [r["metrics"].declared_loops for r in one] == [r["metrics"].declared_loops for r in rows]
    for row, line in zip(rows, table):
        assert row["values"]["search.mode"] == line["search.mode"]
        assert row["metrics"].declared_loops == int(line["declared_loops"])
        assert row["metrics"].recall_at_1 == pytest.approx(float(line["recall_at_1"]), abs=1e-12)
        assert row["nodes"] == int(line["nodes"])


def test_everything_is_checked_before_the_first_run(route):
    with pytest.raises(lsgd.InvalidArgument, match="superpixel_size"):
        lsgd.sweep(["route=%s,10" % route], ["segmentation.superpixel_size=0,30"])
    with pytest.raises(lsgd.InvalidArgument, match="per dataset"):
        lsgd.sweep(["route=%s,10" % route], ["search.min_gap=5,10"])
    # A window in the options would be replaced by each dataset's: refused.
    with pytest.raises(lsgd.InvalidArgument, match="options set search.min_gap = 3: the window is set per dataset"):
        lsgd.sweep(["route=%s,10" % route], options={"search.min_gap": 3})
    # A client that is not a distributed.Client: said so, before anything runs.
    with pytest.raises(lsgd.InvalidArgument, match="distributed.Client"):
        lsgd.sweep(["route=%s,10" % route], client="tcp://127.0.0.1:8786")
    with pytest.raises(lsgd.Error):
        lsgd.sweep(["route=/no/such/folder,10"])
    with pytest.raises(lsgd.InvalidArgument, match="used twice"):
        lsgd.sweep(["a=%s,10" % route, "a=%s,10" % route])
    with pytest.raises(lsgd.InvalidArgument, match="jobs"):
        lsgd.sweep(["route=%s,10" % route], jobs=0)


def test_distractors_are_the_benchs(route):
    """lsgd.make_distractor: what lsgd bench --distractors stores, from a real descriptor."""
    detector = lsgd.Detector()
    base = detector.describe(lsgd.read_image(os.path.join(route, "000.pgm")))
    a, b = lsgd.make_distractor(base, 0), lsgd.make_distractor(base, 1)
    assert lsgd.similarity(a, a) == pytest.approx(lsgd.similarity(base, base))
    assert lsgd.similarity(a, b) < lsgd.similarity(a, a)
    # A run of 5 distractors is one place: 10 .. 14 are equal, 15 another.
    run = [lsgd.make_distractor(base, k, run=5) for k in range(10, 16)]
    assert all(lsgd.similarity(run[0], d) == lsgd.similarity(run[0], run[0]) for d in run[1:5])
    assert lsgd.similarity(run[0], run[5]) < lsgd.similarity(run[0], run[0])
    compact = lsgd.make_distractor(base, 0, storage="compact")
    assert compact.storage == "compact"
    with pytest.raises(lsgd.InvalidArgument, match="at least 1"):
        lsgd.make_distractor(base, 0, run=0)
    with pytest.raises(lsgd.InvalidArgument, match="exact descriptor"):
        lsgd.make_distractor(compact, 0)
