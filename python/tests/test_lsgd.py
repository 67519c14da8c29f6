"""Tests of the Python module (pytest; run by ctest as python.pytest).

The module must give what the C++ library gives: the same results frame for
frame as `lsgd run` on the same images, the same metrics as `lsgd eval`, the
library's errors as Python exceptions with the same messages.
"""
import csv
import json
import os
import subprocess
import threading

import numpy as np
import pytest

import lsgd
from frames import CLI, SHARED, SOURCE, place, route, write_pgm


def test_version_and_options():
    assert lsgd.__version__
    defaults = lsgd.default_options()
    assert defaults["search.min_gap"] == "50"
    assert defaults["verification.stages"] == "temporal,geometric"
    o = lsgd.options({"search": {"min_gap": 10, "mode": "nodes"}}, verification={"stages": ["temporal"]})
    assert (o["search.min_gap"], o["search.mode"], o["verification.stages"]) == ("10", "nodes", "temporal")
    assert lsgd.options({"search.nodes.beta": 1.1})["search.nodes.beta"] == "1.1"
    assert lsgd.Detector(search={"min_gap": 7}).options["search.min_gap"] == "7"


def test_option_errors_are_the_librarys():
    with pytest.raises(lsgd.InvalidArgument, match="unknown option 'search.min_gapp'"):
        lsgd.Detector({"search.min_gapp": 3})
    with pytest.raises(ValueError, match="search.min_gap"):  # InvalidArgument is a ValueError
        lsgd.Detector(search={"min_gap": -1})
    with pytest.raises(lsgd.Error, match="verification stage 'sift' is unknown"):
        lsgd.Detector(verification={"stages": "sift"})
    with pytest.raises(lsgd.InvalidArgument, match="bool"):
        lsgd.Detector(search={"min_gap": True})
    # A value that is no value is refused, naming the option (issue 35, fifth
    # pass: {} was taken as an empty section and ignored, [] read as 'none',
    # a lone surrogate gave pybind11's bare "Unable to cast").
    with pytest.raises(lsgd.InvalidArgument, match="option decision.threshold: the value is a dict"):
        lsgd.options({"decision.threshold": {}})
    with pytest.raises(lsgd.InvalidArgument, match="option decision.threshold: the value is a list"):
        lsgd.options({"decision": {"threshold": []}})
    with pytest.raises(lsgd.InvalidArgument, match="search mode 'nodes.*' is unknown"):
        lsgd.options({"search.mode": "nodes\udcff"})
    with pytest.raises(lsgd.InvalidArgument, match="unknown option 'sea.*rch.mode'"):
        lsgd.options({"sea\udcffrch.mode": "nodes"})
    assert lsgd.options({"verification.stages": []})["verification.stages"] == "none"
    assert lsgd.options({"search": {}}) == lsgd.default_options()


def test_the_descriptor_is_an_option_with_its_own_options():
    """descriptor.type (issue 36's seam): gradient orientations instead of gray levels."""
    assert lsgd.default_options()["descriptor.type"] == "intensity"
    d = lsgd.Detector(descriptor={"type": "gradient", "gradient": {"orientations": 16}})
    assert (d.options["descriptor.type"], d.options["descriptor.gradient.orientations"]) == ("gradient", "16")
    i = lsgd.Detector()
    frame = place(3)
    brighter = (frame // 2) * 2  # the same edges at a lower and a higher gain
    darker = frame // 2
    for detector in (d, i):
        detector.process(darker)
        detector.process(brighter)
    assert d.similarity(0, 1) > i.similarity(0, 1)
    with pytest.raises(lsgd.Error, match="descriptor 'sift' is unknown"):
        lsgd.Detector(descriptor={"type": "sift"})
    with pytest.raises(ValueError, match="descriptor.gradient.orientations"):
        lsgd.Detector(descriptor={"type": "gradient", "gradient": {"orientations": 500}})

    # A descriptor knows what it counts: those of other descriptors (or other
    # options of one) are never compared (they scored 0.77 against each other).
    x, y = d.describe(frame), i.describe(frame)
    assert (x.type, y.type) == ("gradient (threshold 1.5, orientations 16)", "intensity")
    g32 = lsgd.Detector(descriptor={"type": "gradient"}).describe(frame)
    for a, b in [(x, y), (x, g32)]:
        with pytest.raises(lsgd.InvalidArgument, match="the descriptors count different things"):
            lsgd.similarity(a, b)
        with pytest.raises(lsgd.InvalidArgument, match="count different things"):
            lsgd.match([a, a], [b])
    assert lsgd.similarity(x, d.describe(frame)) == lsgd.similarity(x, x)
    arrays = lsgd.Descriptor.from_arrays(y.histograms, y.pixels, grid=y.grid)
    assert arrays.type == "" and lsgd.similarity(arrays, y) == lsgd.similarity(y, y)
    c = lsgd.Detector(descriptor={"type": "gradient", "storage": "compact"}).describe(frame)
    assert c.type.startswith("gradient")


def test_images_gray_bgr_and_strided_give_the_same_results():
    gray = route(20, 2)
    a = lsgd.Detector(search={"min_gap": 5}, verification={"stages": "temporal"})
    b = lsgd.Detector(search={"min_gap": 5}, verification={"stages": "temporal"})
    c = lsgd.Detector(search={"min_gap": 5}, verification={"stages": "temporal"})
    for g in gray:
        bgr = np.repeat(g[:, :, None], 3, axis=2)
        wide = np.zeros((g.shape[0], g.shape[1] * 2), np.uint8)
        wide[:, ::2] = g  # a strided view: copied once, same pixels
        ra, rb, rc = a.process(g), b.process(bgr), c.process(wide[:, ::2])
        assert (ra.frame, ra.best.frame, ra.loop) == (rb.frame, rb.best.frame, rb.loop)
        assert (ra.best.frame, ra.best.score) == (rc.best.frame, rc.best.score)
    assert len(a) == a.size == 40


def test_bad_images_are_errors_and_change_nothing():
    d = lsgd.Detector(search={"min_gap": 5})
    d.process(place(0))
    with pytest.raises(lsgd.InvalidArgument, match="uint8"):
        d.process(place(1).astype(np.float32))
    with pytest.raises(lsgd.InvalidArgument, match="shape"):
        d.process(np.zeros((4, 4, 2), np.uint8))
    with pytest.raises(lsgd.InvalidArgument, match="same size"):
        d.process(np.zeros((60, 80), np.uint8))
    assert d.size == 1
    with pytest.raises(lsgd.IoError, match="no-such-image.png"):
        lsgd.read_image("no-such-image.png")
    with pytest.raises(OSError):
        lsgd.open_sequence("no-such-folder")


def test_paths_that_are_not_utf8_name_their_files(tmp_path):
    # bytes, or a str with surrogate escapes (os.fsdecode): the file itself,
    # not pybind11's bare "Unable to cast Python instance to C++ type".
    folder = os.fsencode(tmp_path) + b"/\xff-frames"
    os.mkdir(folder)
    for i in range(3):
        write_pgm(folder + b"/%d.pgm" % i, place(i))
    image = folder + b"/0.pgm"
    assert lsgd.read_image(image).shape == (120, 160)
    assert lsgd.read_image(os.fsdecode(image)).shape == (120, 160)
    assert len(lsgd.open_sequence(folder)) == 3
    with pytest.raises(lsgd.IoError, match="no-such"):
        lsgd.read_image(folder + b"/no-such.png")


def test_results_match_lsgd_run_frame_for_frame(tmp_path):
    if not CLI:
        pytest.skip("LSGD_CLI (the lsgd tool) not given: run through ctest")
    frames = route(30, 4)
    folder = tmp_path / "route"
    folder.mkdir()
    for i, f in enumerate(frames):
        write_pgm(folder / ("%03d.pgm" % i), f)
    out = tmp_path / "run.csv"
    subprocess.run([CLI, "run", "--sequence", str(folder), "--min-gap", "10", "--output", str(out)],
                   check=True, capture_output=True)
    rows = list(csv.DictReader(open(out)))
    d = lsgd.Detector(search={"min_gap": 10})
    # One path or one image where a sequence is expected: refused, nothing processed (a str
    # would have been read character by character).
    for one in (str(folder / "000.pgm"), folder / "000.pgm", frames[0]):
        with pytest.raises(lsgd.InvalidArgument, match="where a sequence of paths or arrays"):
            lsgd.run(d, one)
    assert len(d) == 0
    results = lsgd.run(d, [str(folder / ("%03d.pgm" % i)) for i in range(len(frames))])
    assert len(rows) == len(results)
    loops = 0
    for row, r in zip(rows, results):
        assert int(row["frame"]) == r.frame
        assert int(row["loop_frame"]) == (r.best.frame if r.loop else -1)
        assert int(row["candidate_frame"]) == r.best.frame
        if r.best.frame >= 0:
            assert float(row["score"]) == pytest.approx(r.best.score, rel=1e-5)
        loops += r.loop
    assert loops > 10
    # lsgd.write_csv writes the tool's CSV: the same code, the same rows but for the milliseconds.
    mine = tmp_path / "python.csv"
    assert lsgd.write_csv(results, [str(folder / ("%03d.pgm" % i)) for i in range(len(frames))], mine) == loops
    theirs = list(csv.DictReader(open(mine)))
    assert list(theirs[0].keys()) == list(rows[0].keys())
    for a, b in zip(rows, theirs):
        assert {k: v for k, v in a.items() if k != "ms"} == {k: v for k, v in b.items() if k != "ms"}
    with pytest.raises(lsgd.InvalidArgument, match="one per result"):
        lsgd.write_csv(results, [], mine)
    image = folder / "000.pgm"
    before = image.read_bytes()
    with pytest.raises(lsgd.InvalidArgument, match="is the input image"):
        lsgd.write_csv(results, [str(folder / ("%03d.pgm" % i)) for i in range(len(frames))], image)
    assert image.read_bytes() == before
    # Results twice or reversed would pair frames with the wrong images; a subset is fine.
    names = [str(folder / ("%03d.pgm" % i)) for i in range(10)]
    with pytest.raises(lsgd.InvalidArgument, match="in the order process\\(\\) returned them, each once"):
        lsgd.write_csv(results[:5] + results[:5], names, mine)
    with pytest.raises(lsgd.InvalidArgument, match="each once"):
        lsgd.write_csv(results[::-1][:10], names, mine)
    assert lsgd.write_csv(results[::2][:10], names, mine) >= 0


def test_cut_ends_the_loop_it_follows():
    """Detector.cut(): the frame after it continues no loop; without it, the same frame does."""
    frames = route(30, 3)
    plain = lsgd.Detector(search={"min_gap": 10})
    cut = lsgd.Detector(search={"min_gap": 10})
    checked = 0
    previous_cut = False
    for i, f in enumerate(frames):
        a, b = plain.process(f), cut.process(f)
        if i > 0 and a.evidence.continues and previous_cut:
            assert not b.evidence.continues
            checked += 1
        previous_cut = a.loop and i % 5 == 0
        if previous_cut:
            cut.cut()
    assert checked > 0


def test_evaluation_in_ten_lines_matches_lsgd_eval(tmp_path):
    corridor = os.path.join(SHARED, "corridor")
    if not os.path.isdir(corridor) or not CLI:
        pytest.skip("../shared/datasets/corridor or the lsgd tool is absent")
    images = lsgd.open_sequence(os.path.join(corridor, "sequence.txt"))
    gt = lsgd.load_groundtruth(os.path.join(corridor, "groundtruth.txt"), frames=len(images))
    detector = lsgd.Detector(search={"min_gap": 50})
    results = lsgd.run(detector, images)
    m = lsgd.evaluate(results, gt, min_gap=50)
    out = tmp_path / "eval.json"
    subprocess.run([CLI, "eval", "--sequence", os.path.join(corridor, "sequence.txt"), "--gt",
                    os.path.join(corridor, "groundtruth.txt"), "--min-gap", "50", "--json", str(out)],
                   check=True, capture_output=True)
    j = json.load(open(out))
    assert m.declared_loops == j["declared_loops"] and m.declared_false == j["declared_false"]
    for key in ["recall_at_100_precision", "average_precision", "recall_at_1", "recall_at_5",
                "decision_recall_at_100_precision", "decision_average_precision"]:
        assert getattr(m, key) == pytest.approx(j[key], abs=1e-12), key
    assert [p.confirmed for p in m.curve] == [p[3] for p in j["pr_curve"]["points"]]
    assert m.declared_false == 0 and m.declared_loops > 0


def test_process_releases_the_gil():
    frames = route(20, 2)
    alone = [r.best.frame for r in lsgd.run(lsgd.Detector(search={"min_gap": 5}), frames)]
    out = {}

    def work(k):
        out[k] = [r.best.frame for r in lsgd.run(lsgd.Detector(search={"min_gap": 5}), frames)]

    threads = [threading.Thread(target=work, args=(k,)) for k in range(2)]
    for t in threads:
        t.start()
    for t in threads:
        t.join()
    assert out[0] == alone and out[1] == alone


def test_result_fields():
    d = lsgd.Detector(search={"min_gap": 5})
    results = [d.process(f) for f in route(20, 2)]
    r = max(results, key=lambda r: r.best.score)
    assert r.candidates and r.candidates[0].frame >= 0
    assert r.timings.total_ms > 0
    # The search's parts: index insertion (none in exhaustive mode) and the evidence.
    assert r.timings.insert_ms == 0
    assert 0 < r.timings.evidence_ms <= r.timings.search_ms
    assert all(v.stage in ("temporal", "geometric") for x in results for v in x.verification)
    assert r.evidence.inliers >= -1
    assert "Result(frame=" in repr(r)
    # The ranking: the best candidate, examined on every query.
    for x in results:
        if x.candidates:
            assert (x.ranking.best.frame, x.ranking.best.score) in [(c.frame, c.score) for c in x.candidates]
    assert isinstance(r.ranking, lsgd.Ranking) and "Ranking(best=" in repr(r.ranking)
    # Why there is a loop or none: an enum a program branches on.
    assert [x.status for x in results[:6]] == [lsgd.LoopStatus.TOO_FEW_FRAMES] * 6
    assert all((x.status == lsgd.LoopStatus.LOOP) == x.loop for x in results)
    assert str(lsgd.LoopStatus.NOT_CONFIRMED) == "not_confirmed"
    assert "status=" in repr(r)
    # A confirmed report carries its geometry: the matches and the model, as numpy arrays.
    confirmed = [x for x in results if x.evidence.confirmed]
    assert confirmed
    for x in confirmed:
        g = x.geometry
        assert g.model in ("fundamental", "homography") and "LoopGeometry(" in repr(g)
        assert g.matrix.shape == (3, 3) and g.matrix.dtype == np.float64
        n = len(g.inliers)
        assert g.query_points.shape == (n, 2) and g.candidate_points.shape == (n, 2)
        assert g.query_points.dtype == np.float32 and g.inliers.dtype == np.bool_
        assert int(g.inliers.sum()) == x.evidence.inliers
    assert lsgd.Detector(search={"min_gap": 5}, verification={"stages": "temporal"}).process(route(1, 1)[0]).geometry is None


def test_example_script_evaluates_and_plots(tmp_path):
    places, laps = 30, 4
    frames = route(places, laps)
    for i, f in enumerate(frames):
        write_pgm(tmp_path / ("%03d.pgm" % i), f)
    with open(tmp_path / "gt.txt", "w") as gt:
        for q in range(places, len(frames)):
            for m in range(q % places, q, places):
                gt.write("%d %d\n" % (q, m))
    figure = tmp_path / "pr.png"
    script = os.path.join(SOURCE, "python", "examples", "evaluate.py")
    out = subprocess.run(["/usr/bin/python3", script, str(tmp_path), str(tmp_path / "gt.txt"), "10",
                          str(figure)], check=True, capture_output=True, text=True,
                         env=dict(os.environ, MPLCONFIGDIR=str(tmp_path))).stdout
    assert "declared" in out and "R@100P" in out
    assert figure.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"


def test_paths_shapes_and_options_a_hostile_user_tries(tmp_path):
    import pathlib
    frames = route(6, 1)
    write_pgm(tmp_path / "0.pgm", frames[0])
    # pathlib.Path and bytes wherever a path is taken; a NUL inside is refused.
    image = lsgd.read_image(tmp_path / "0.pgm")
    assert np.array_equal(image, lsgd.read_image(os.fsencode(str(tmp_path / "0.pgm"))))
    assert lsgd.open_sequence(tmp_path) == [str(tmp_path / "0.pgm")]
    with lsgd.Database.create(tmp_path / "p.db") as db:
        assert db.frames == 0
    assert lsgd.Database.open(pathlib.Path(tmp_path / "p.db"), writable=False).frames == 0
    assert lsgd.run(lsgd.Detector(), [tmp_path / "0.pgm"])[0].frame == 0
    with pytest.raises(lsgd.InvalidArgument, match="has a NUL character inside"):
        lsgd.read_image(str(tmp_path / "0.pgm") + "\0.txt")
    with pytest.raises(lsgd.InvalidArgument, match="int is not a path"):
        lsgd.open_sequence(5)
    # Options are a dict or a config's path: anything else is told both.
    for call in (lambda: lsgd.options(lsgd.Detector()), lambda: lsgd.Detector([("a", 1)]),
                 lambda: lsgd.Database.create(tmp_path / "o.db", 5)):
        with pytest.raises(lsgd.InvalidArgument, match=r"options: \w+ is neither a dict of options .* nor the path"):
            call()
    assert not os.path.exists(tmp_path / "o.db")
    # (H, W, 1) is gray; an empty image or a side above 16384 is refused before any copy.
    a, b = lsgd.Detector(), lsgd.Detector()
    for f in frames:
        x, y = a.process(f), b.process(f[:, :, None])
        assert (x.frame, x.best.frame, x.best.score) == (y.frame, y.best.frame, y.best.score)
    with pytest.raises(lsgd.InvalidArgument, match="0 x 160 pixels: empty"):
        a.process(np.zeros((0, 160), np.uint8))
    huge = np.lib.stride_tricks.as_strided(np.zeros(1, np.uint8), shape=(1, 2**32 + 160), strides=(0, 0))
    with pytest.raises(lsgd.InvalidArgument, match="a side above 16384"):
        a.process(huge)
    assert len(a) == len(frames)
    # An option given twice, nested and dotted, is refused.
    with pytest.raises(lsgd.InvalidArgument, match="option search.min_gap is given twice"):
        lsgd.Detector({"search": {"min_gap": 5}, "search.min_gap": 7})
    # Options that hold themselves (the process died of a stack overflow) or nest without end.
    looped = {}
    looped["search"] = looped
    with pytest.raises(lsgd.InvalidArgument, match="nested more than 16 dicts deep"):
        lsgd.Detector(looped)
    with pytest.raises(lsgd.InvalidArgument, match="nested more than 16 dicts deep"):
        lsgd.Detector(search=looped)
    # A negative frame id other than -1 is refused by Database.append.
    db = lsgd.Database.create(tmp_path / "q.db")
    d = lsgd.Detector(db.options)
    r = d.process(frames[0])
    with pytest.raises(lsgd.InvalidArgument, match="frame id -5 is negative"):
        db.append(d, r, session=0, frame=-5)
    # A name no image has (a NUL inside) or longer than a list line is refused, nothing stored.
    with pytest.raises(lsgd.InvalidArgument, match="NUL character"):
        db.append(d, r, 0, "a\0b")
    with pytest.raises(lsgd.InvalidArgument, match="more than 65536"):
        db.append(d, r, 0, "x" * 65537)
    assert db.frames == 0
    db.append(d, r, session=0)
    assert db.frames == 1


def test_evaluate_counts_frames_without_a_result_as_missed():
    frames = route(10, 3)
    gt = lsgd.GroundTruth(len(frames))
    for i in range(10, 30):
        for j in range(i % 10, i, 10):
            gt.add(i, j)
    everything = lsgd.Detector(search={"min_gap": 5})
    full = lsgd.evaluate([everything.process(f, id=i) for i, f in enumerate(frames)], gt, min_gap=5)
    kept = [i for i in range(30) if not (i >= 20 and i % 2)]  # the camera dropped half a lap
    d = lsgd.Detector(search={"min_gap": 5})
    part = [d.process(frames[i], id=i) for i in kept]
    m = lsgd.evaluate(part, gt, min_gap=5)
    dropped = sum(1 for i in range(30) if i not in kept and gt.has_loop(i, 5))
    assert dropped == 5 and m.frames == 30 and m.positives == full.positives
    assert m.recall_at_1 <= (m.positives - dropped) / m.positives
    assert all(r.loop_id in kept for r in part if r.loop)
    with pytest.raises(lsgd.InvalidArgument, match="give every Result of one detector"):
        lsgd.evaluate(part[1:], gt, min_gap=5)


def test_match_one_traverse_against_another(tmp_path):
    places = 12
    reference = [place(p, 0) for p in range(places)]
    query = [place(p, 3) for p in range(places)]  # the same places, moved
    d = lsgd.Detector()
    refs = [d.describe(f) for f in reference]
    queries = [d.describe(f) for f in query]
    out = tmp_path / "pairs.csv"
    m = lsgd.match(refs, queries, top_k=3, query_offset=places, output=str(out))
    assert m["query"].dtype == np.int64 and m["score"].dtype == np.float64
    assert list(m["rank"]) == [1, 2, 3] * places
    assert list(m["query"][::3]) == list(range(places, 2 * places))
    assert list(m["match"][::3]) == list(range(places))  # each place finds itself first
    assert np.all(m["similarity"][::3] >= m["similarity"][1::3])
    gt = tmp_path / "gt.txt"
    gt.write_text("".join(f"{places + p} {p}\n" for p in range(places)))
    metrics = lsgd.evaluate_detections(str(out), lsgd.load_groundtruth(str(gt), frames=2 * places), min_gap=0)
    assert metrics.recall_at_1 == 1.0
    # A match to the query itself is a false loop, and said (lsgd eval's warning).
    selfmatch = tmp_path / "self.csv"
    selfmatch.write_text("query,match,score\n12,0,1\n13,13,1\n")
    with pytest.warns(UserWarning, match=r"reports 1 match to the query itself or a later frame"):
        m2 = lsgd.evaluate_detections(str(selfmatch), lsgd.load_groundtruth(str(gt), frames=2 * places), min_gap=0)
    assert m2.declared_false == 1
    if CLI:  # lsgd match writes the same file from the images
        for name, frames in (("r", reference), ("q", query)):
            (tmp_path / name).mkdir()
            for i, f in enumerate(frames):
                write_pgm(tmp_path / name / f"{i:03d}.pgm", f)
        cli = tmp_path / "cli.csv"
        subprocess.run([CLI, "match", "--reference", str(tmp_path / "r"), "--query", str(tmp_path / "q"),
                        "--top-k", "3", "--output", str(cli)], check=True, capture_output=True)
        assert cli.read_text() == out.read_text()
    with pytest.raises(lsgd.InvalidArgument, match="top_k 0 must be in"):
        lsgd.match(refs, queries, top_k=0)
    # Query ids are frame ids: never negative, never beyond 2^53 - 1 (lsgd match's range).
    for offset in (-5, 2**53 - 1, 2**62):
        with pytest.raises(lsgd.InvalidArgument, match="query_offset"):
            lsgd.match(refs, queries, query_offset=offset)
    with pytest.raises(lsgd.InvalidArgument, match="the reference holds no frame"):
        lsgd.match([], queries)
    # A read-only file (or folder) is never replaced, also when run as root.
    ro = tmp_path / "ro.csv"
    ro.write_text("keep\n")
    ro.chmod(0o444)
    with pytest.raises(lsgd.IoError, match="read-only"):
        lsgd.match(refs, queries, output=str(ro))
    assert ro.read_text() == "keep\n"
    locked = tmp_path / "locked"
    locked.mkdir()
    locked.chmod(0o555)
    with pytest.raises(lsgd.IoError, match="read-only"):
        lsgd.match(refs, queries, output=str(locked / "m.csv"))
    assert not (locked / "m.csv").exists()
    locked.chmod(0o755)
    # An output that cannot be written is refused before the matching (a
    # folder, or a missing folder, lost the results after the work).
    for bad, message in [(tmp_path, "it is a folder"), (tmp_path / "no" / "m.csv", "does not exist")]:
        with pytest.raises(lsgd.IoError, match=message):
            lsgd.match(refs, queries, output=str(bad))


def test_describe_to_numpy_and_back():
    frames = route(5, 1)
    d = lsgd.Detector(search={"min_gap": 5})
    x = d.describe(frames[0])
    assert len(d) == 0
    assert x.histograms.dtype == np.uint16 and x.histograms.shape == (x.grid[0] * x.grid[1], 256)
    assert x.pixels.dtype == np.uint32 and int(x.pixels.sum()) == frames[0].size
    y = lsgd.Descriptor.from_arrays(x.histograms, x.pixels, grid=x.grid)
    assert lsgd.similarity(x, y) == lsgd.similarity(x, x)
    assert lsgd.similarity(x, d.describe(frames[1])) < lsgd.similarity(x, x)
    c = lsgd.Detector(descriptor={"storage": "compact"}).describe(frames[0])
    assert c.storage == "compact" and c.histograms.dtype == np.uint8 and c.cell_pixels > 0
    back = lsgd.Descriptor.from_arrays(c.histograms, grid=c.grid, cell_pixels=c.cell_pixels)
    assert lsgd.similarity(c, back) == lsgd.similarity(c, c)
    with pytest.raises(lsgd.InvalidArgument):
        lsgd.Descriptor.from_arrays(x.histograms[:-1], x.pixels, grid=x.grid)
    with pytest.raises(lsgd.InvalidArgument, match="differ in grid or storage"):
        lsgd.similarity(x, c)
    # Counts of another dtype, or beyond the counts' type, are refused (they
    # were cast: -1 became 65535, 1e12 and NaN 0, and compared as if real);
    # integer counts in range are taken whatever their dtype.
    for histograms, pixels, message in [
            (-x.histograms.astype(np.int32), x.pixels, "histograms value -"),
            (np.full(x.histograms.shape, 1e12), x.pixels, "histograms has dtype float64"),
            (x.histograms.astype(bool), x.pixels, "histograms has dtype bool"),
            (x.histograms.astype(np.int64) + 70000, x.pixels, "outside 0 .. 65535"),
            (x.histograms, -x.pixels.astype(np.int64), "pixels value -")]:
        with pytest.raises(lsgd.InvalidArgument, match=message):
            lsgd.Descriptor.from_arrays(histograms, pixels, grid=x.grid)
    # Bins that do not add up to their cell's pixels are no histogram: an
    # all-zero and an all-full descriptor compared 0.996 alike (l1).
    zeros, full = np.zeros_like(x.histograms), np.full_like(x.histograms, 100)
    for histograms in (zeros, full):
        with pytest.raises(lsgd.InvalidArgument, match="cell 0's bins add up to"):
            lsgd.Descriptor.from_arrays(histograms, x.pixels, grid=x.grid)
    with pytest.raises(lsgd.InvalidArgument, match="compact bins add up to"):
        lsgd.Descriptor.from_arrays(np.full_like(c.histograms, 200), grid=c.grid, cell_pixels=c.cell_pixels)
    same = lsgd.Descriptor.from_arrays(x.histograms.astype(np.int64), x.pixels.astype(np.int64), grid=x.grid)
    assert lsgd.similarity(x, same) == lsgd.similarity(x, x)
    for grid in [(2 ** 31, 2 ** 31), (1.5, 2)]:
        with pytest.raises(lsgd.InvalidArgument, match="grid"):
            lsgd.Descriptor.from_arrays(x.histograms, x.pixels, grid=grid)


def test_bare_new_is_refused_and_values_pickle_by_reduce():
    # Issue 35: lsgd.X.__new__(lsgd.X) (or object.__new__) without __init__
    # gave an instance with no C++ object, whose methods read garbage or
    # crashed the interpreter (Detector.nodes, Database.__repr__,
    # GroundTruth.queries, Result.geometry). Every lsgd class refuses it.
    import copy
    import pickle
    classes = [c for c in vars(lsgd._lsgd).values()
               if isinstance(c, type) and not issubclass(c, BaseException)]
    assert {"Detector", "Database", "GroundTruth", "Result", "LoopStatus"} <= {c.__name__ for c in classes}
    for cls in classes:
        for new in (cls.__new__, object.__new__):
            with pytest.raises(TypeError, match="is not safe"):
                new(cls)

    # Python subclasses still work, and must still call __init__.
    class Mine(lsgd.Detector):
        def __init__(self):
            super().__init__(search={"min_gap": 5})
            self.tag = "mine"
    mine = Mine()
    assert mine.size == 0 and mine.tag == "mine"
    with pytest.raises(TypeError, match="is not safe"):
        Mine.__new__(Mine)

    class Forgot(lsgd.Detector):
        def __init__(self):
            pass
    with pytest.raises(TypeError, match="__init__"):
        Forgot()

    # What pickles (and copies) rebuilds from its state, not through __new__.
    rng = np.random.default_rng(3)
    described = lsgd.Detector().describe_frame(rng.integers(0, 255, (96, 128), dtype=np.uint8))
    for back in (pickle.loads(pickle.dumps(described)), copy.deepcopy(described), copy.copy(described)):
        assert back.to_bytes() == described.to_bytes()
    for status in lsgd.LoopStatus.__members__.values():
        assert pickle.loads(pickle.dumps(status)) == status and copy.copy(status) == status
    # Values without a state to pickle are refused clearly, never half-made.
    result = lsgd.Detector().process(rng.integers(0, 255, (96, 128), dtype=np.uint8))
    with pytest.raises(TypeError, match="cannot pickle"):
        copy.copy(result)
