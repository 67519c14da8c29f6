"""The Python module's Database: sessions resumed as `lsgd run --database` resumes
them, queries that store nothing, frames forgotten, the index saved with the
map, and callers' ids and stamps kept."""
import json
import os
import pathlib
import subprocess

import numpy as np
import pytest

import lsgd
from frames import CLI, route, write_pgm


def test_database_resumes_a_session_as_lsgd_run_does(tmp_path):
    """Database.plan_session: the tool's resume policy. lsgd run stores the first 40 images, Python
    continues the session at image 40 with the same ids, and the tool then finds nothing to do."""
    if not CLI:
        pytest.skip("LSGD_CLI (the lsgd tool) not given: run through ctest")
    frames = route(20, 4)
    folder = tmp_path / "route"
    folder.mkdir()
    images = []
    for i, f in enumerate(frames):
        images.append(str(folder / ("%03d.pgm" % i)))
        write_pgm(images[-1], f)
    path = str(tmp_path / "map.db")
    subprocess.run([CLI, "run", "--sequence", str(folder), "--last", "39", "--min-gap", "10",
                    "--database", path, "--output", str(tmp_path / "a.csv")], check=True, capture_output=True)
    uninterrupted = lsgd.Detector(search={"min_gap": 10})
    expected = [uninterrupted.process(f) for f in frames]
    with lsgd.Database.open(path) as db:
        d = db.detector()
        plan = db.plan_session(d, images)
        assert (plan.session, plan.first_id, plan.first, plan.resume, plan.last_stored) == (0, 0, 40, True, 39)
        for i in range(plan.first, len(images)):
            r = d.process(lsgd.read_image(images[i]), id=plan.first_id + i)
            db.append(d, r, plan.session, lsgd.stored_image_name(images[i]), r.id)
            e = expected[i]
            assert (r.frame, r.best.frame, r.loop) == (e.frame, e.best.frame, e.loop)
        assert db.frame_ids() == list(range(len(images)))
        # Other images are a new session, numbered after the stored frames; stored images are one
        # only when asked for.
        others = [str(tmp_path / ("other-%d.pgm" % k)) for k in range(5)]
        for k, name in enumerate(others):
            write_pgm(name, frames[k])
        # The new session's first image is where the route starts again, within the window of
        # the last stored frame's loop: a detector cut for the new session continues nothing.
        restored = db.detector()
        assert restored.process(lsgd.read_image(others[0])).evidence.continues
        other = db.plan_session(d, others)
        assert (other.session, other.first_id, other.first, other.resume) == (1, 80, 0, False)
        r = d.process(lsgd.read_image(others[0]), id=other.first_id)
        assert not r.evidence.continues
        # d now holds a frame the database does not: it plans nothing, nor does a detector that
        # is not the database's, nor a session id out of range (all refused before any frame).
        with pytest.raises(lsgd.InvalidArgument, match="holds 80 frames, the detector 81"):
            db.plan_session(d, others)
        with pytest.raises(lsgd.InvalidArgument, match="the detector 0"):
            db.plan_session(lsgd.Detector(search={"min_gap": 10}), others, session=3)
        d = db.detector()
        for bad in (-1, 2**53):
            with pytest.raises(lsgd.InvalidArgument, match="out of range"):
                db.plan_session(d, others, session=bad)
        # Any sequence of paths (a tuple, pathlib paths), never one path.
        assert db.plan_session(d, tuple(pathlib.Path(o) for o in others)).first_id == 80
        with pytest.raises(lsgd.InvalidArgument, match="a list of paths is expected"):
            db.plan_session(d, others[0])
        with pytest.raises(lsgd.InvalidArgument, match="already stored in session 0"):
            db.plan_session(d, images[::2])
        assert db.plan_session(d, images[::2], session=7).session == 7
    done = subprocess.run([CLI, "run", "--sequence", str(folder), "--min-gap", "10", "--database", path],
                          capture_output=True, text=True)
    assert done.returncode == 0 and "nothing to do" in done.stderr, done.stderr
    assert lsgd.stored_image_name(os.path.relpath(images[0])) == images[0]


def test_database_resumes_where_it_stopped(tmp_path):
    path = str(tmp_path / "places.db")
    frames = route(20, 3)
    uninterrupted = lsgd.Detector(search={"min_gap": 5})
    expected = [uninterrupted.process(f) for f in frames]
    db = lsgd.Database.create(path, search={"min_gap": 5})
    d = lsgd.Detector(db.options)
    for f in frames[:30]:
        db.append(d, d.process(f), session=0)
    del db, d  # the robot stops
    db = lsgd.Database.open(path)
    assert db.frames == 30
    d = db.detector()
    assert d.size == 30
    for f, e in zip(frames[30:], expected[30:]):
        r = d.process(f)
        db.append(d, r, session=1)
        assert (r.frame, r.best.frame, r.loop, r.best.score) == (e.frame, e.best.frame, e.loop, e.best.score)
    assert lsgd.Database.open(path, writable=False).frames == 60
    with pytest.raises(lsgd.IoError, match="already exists"):
        lsgd.Database.create(path)
    for call in (lambda: lsgd.Database.create(""), lambda: lsgd.Database.open("")):
        with pytest.raises(lsgd.InvalidArgument, match="the database path is empty"):
            call()


def test_query_answers_as_process_and_stores_nothing(tmp_path):
    frames = route(20, 3)
    d = lsgd.Detector(search={"min_gap": 5})
    reference = lsgd.Detector(search={"min_gap": 5})
    for i, f in enumerate(frames):
        e = reference.process(f)
        other = d.query(frames[(i + 17) % len(frames)])  # a frame that is not the next
        q = d.query(f)
        assert d.size == i and other.frame == i
        r = d.process(f)
        for x in (q, r):
            assert (x.frame, x.best.frame, x.loop, x.best.score, x.ranking.best.frame) == \
                (e.frame, e.best.frame, e.loop, e.best.score, e.ranking.best.frame)
    # A map opened read-only: queried, never grown, the file unchanged.
    path = str(tmp_path / "map.db")
    db = lsgd.Database.create(path, search={"min_gap": 5})
    writer = lsgd.Detector(db.options)
    for f in frames[:40]:
        db.append(writer, writer.process(f), session=0)
    del db
    before = open(path, "rb").read()
    m = lsgd.Database.open(path, writable=False).detector()
    expected = writer.process(frames[40])
    q = m.query(frames[40])
    assert (q.frame, q.best.frame, q.loop, q.best.score) == \
        (expected.frame, expected.best.frame, expected.loop, expected.best.score)
    assert m.size == 40
    assert open(path, "rb").read() == before
    with pytest.raises(lsgd.InvalidArgument, match="every frame must have the same size"):
        m.query(np.zeros((10, 10), np.uint8))


def test_forget_a_session_and_frames(tmp_path):
    frames = route(20, 3)
    path = str(tmp_path / "forget.db")
    db = lsgd.Database.create(path, search={"min_gap": 5})
    d = lsgd.Detector(db.options)
    for i, f in enumerate(frames):
        db.append(d, d.process(f, id=100 + i), session=i // 20)
    assert db.forget_session(2) == 20
    assert d.forget(140, 159) == 20
    assert db.forget(105, 109) == 5 and d.forget(105, 109) == 5
    assert db.forget(0, 99) == 0
    assert d.size == db.frames == 35
    assert db.frame_ids() == [i for i in range(100, 140) if not 105 <= i <= 109]
    restored = db.detector()
    for i, f in enumerate(frames[:20]):  # the first lap again: its places are kept
        r, e = restored.process(f, id=200 + i), d.process(f, id=200 + i)
        assert (r.frame, r.best.frame, r.loop, r.loop_id, r.best.score) == \
            (e.frame, e.best.frame, e.loop, e.loop_id, e.best.score)
        assert not 105 <= r.loop_id <= 109
    with pytest.raises(lsgd.InvalidArgument, match=r"session 2 has no frames \(sessions: 0, 1\)"):
        db.forget_session(2)
    with pytest.raises(lsgd.InvalidArgument, match="the first id 9 is above the last 1"):
        d.forget(9, 1)
    # Negative ids name no frame: refused as lsgd db forget --frames refuses them.
    with pytest.raises(lsgd.InvalidArgument, match="outside the frame ids"):
        d.forget(-5, -1)
    with pytest.raises(lsgd.InvalidArgument, match="outside the frame ids"):
        db.forget(-5, 3)
    assert db.frames == 35


def test_index_mode_graph_saved_and_restored(tmp_path):
    path = str(tmp_path / "index.db")
    frames = route(20, 3)
    options = {"search": {"min_gap": 5, "mode": "index"}}
    uninterrupted = lsgd.Detector(**options)
    expected = [uninterrupted.process(f) for f in frames]
    db = lsgd.Database.create(path, **options)
    d = lsgd.Detector(db.options)
    for f in frames[:30]:
        db.append(d, d.process(f), session=0)
    assert db.save_index(d) == 30 - 5 - 1  # the frames that left the temporal window
    del db, d
    for rebuild in (False, True):
        d = lsgd.Database.open(path, writable=False).detector(rebuild_index=rebuild)
        for f, e in zip(frames[30:], expected[30:]):
            r = d.process(f)
            assert (r.frame, r.best.frame, r.loop, r.best.score) == (e.frame, e.best.frame, e.loop, e.best.score)


def test_readable_objects_closable_database_and_did_you_mean(tmp_path):
    frames = route(20, 3)
    d = lsgd.Detector(search={"min_gap": 5})
    results = [d.process(f) for f in frames]
    gt = lsgd.GroundTruth(len(frames))
    for q in range(20, len(frames)):
        gt.add(q, q % 20)
    m = lsgd.evaluate(results, gt, min_gap=5)
    assert repr(m).startswith("Metrics(declared_loops=") and "0x" not in repr(m)
    for r in results:
        assert "0x" not in repr(r.evidence) + repr(r.timings) + "".join(repr(v) for v in r.verification)
    as_dict = m.to_dict()
    assert as_dict["declared_loops"] == m.declared_loops and isinstance(as_dict["curve"], list)
    json.dumps(as_dict)
    loop = next(r for r in results if r.loop)
    row = loop.to_dict()
    assert row["status"] == "loop" and row["best"]["frame"] == loop.best.frame
    assert len(row["geometry"]["inliers"]) == len(loop.geometry.inliers)
    json.dumps([r.to_dict() for r in results])

    # A database closes when asked (or at the end of a with block); a second
    # writer on it in this process is told so while the first is open.
    path = str(tmp_path / "map.db")
    with lsgd.Database.create(path, search={"min_gap": 5}) as db:
        w = lsgd.Detector(db.options)
        for f in frames[:10]:
            db.append(w, w.process(f), session=0)
        with pytest.raises(lsgd.IoError, match="already open for writing in this process"):
            lsgd.Database.open(path)
        assert repr(db) == f"Database('{path}', 10 frames)"
    assert db.closed and repr(db) == f"Database('{path}', closed)"
    with pytest.raises(lsgd.InvalidArgument, match="is closed"):
        db.frames
    again = lsgd.Database.open(path)
    assert again.frames == 10
    again.close()
    again.close()  # twice: nothing

    # A name whose __fspath__ closes the database: the name is read first, so
    # append is told the database is closed (it used a freed database before).
    db = lsgd.Database.open(path)
    w = lsgd.Detector(db.options)

    class Closing(os.PathLike):
        def __fspath__(self):
            db.close()
            return "x.pgm"

    r = w.process(frames[0])
    with pytest.raises(lsgd.InvalidArgument, match="is closed"):
        db.append(w, r, 1, Closing())

    with pytest.raises(lsgd.InvalidArgument, match="did you mean 'search.min_gap'"):
        lsgd.Detector(serch={"min_gap": 5})
    with pytest.raises(lsgd.InvalidArgument, match="did you mean 'search.min_gap'"):
        lsgd.Detector(search={"min_gapp": 5})


def test_close_says_the_file_was_replaced_under_the_writer(tmp_path):
    # mv other.db map.db while a writer has map.db open: its frames are in a
    # file no name reaches. close() (and the end of a with block) says so; an
    # exception already leaving the block is the one raised.
    frames = route(20, 1)
    path, other = str(tmp_path / "map.db"), str(tmp_path / "other.db")
    lsgd.Database.create(other).close()
    db = lsgd.Database.create(path)
    d = lsgd.Detector(db.options)
    for f in frames[:3]:
        db.append(d, d.process(f), session=0)
    os.replace(other, path)
    with pytest.raises(lsgd.IoError, match="was replaced while this writer had it open"):
        db.close()
    assert db.closed
    db.close()  # twice: nothing
    with pytest.raises(lsgd.IoError, match="was replaced"):
        with lsgd.Database.open(path):
            os.replace(path, path + ".moved")
            lsgd.Database.create(path).close()
    with pytest.raises(KeyError):
        with lsgd.Database.open(path):
            os.replace(path, path + ".moved")
            raise KeyError("the block's own error")


def test_callers_ids_and_stamps(tmp_path):
    frames = route(20, 3)
    d = lsgd.Detector(search={"min_gap": 5})
    results = [d.process(f, id=100 + 2 * i, stamp=0.5 * i) for i, f in enumerate(frames)]
    assert [r.id for r in results] == [100 + 2 * i for i in range(len(frames))]
    assert results[3].stamp == 1.5
    assert all(r.loop_id == (d.id_of(r.best.frame) if r.best.frame >= 0 else -1) for r in results)
    assert d.frame_of(104) == 2 and d.frame_of(105) == -1 and d.stamp_of(2) == 1.0
    with pytest.raises(lsgd.InvalidArgument, match="must be above the last frame's id"):
        d.process(frames[0], id=100)
    assert d.process(frames[0]).id == 100 + 2 * (len(frames) - 1) + 1
    path = str(tmp_path / "ids.db")
    with lsgd.Database.create(path, search={"min_gap": 5}) as db:
        w = lsgd.Detector(db.options)
        for i, f in enumerate(frames[:10]):
            db.append(w, w.process(f, id=50 + 10 * i, stamp=float(i)), session=0)
    with lsgd.Database.open(path, writable=False) as db:
        assert db.frame_ids() == [50 + 10 * i for i in range(10)]
        r = db.detector()
        assert [r.id_of(k) for k in range(10)] == db.frame_ids() and r.stamp_of(9) == 9.0


def test_names_that_are_not_utf8(tmp_path):
    """A database and images whose names are not UTF-8 (issue 35, fifth pass:
    Database.path and repr raised UnicodeDecodeError, and append refused the
    name open_sequence itself returned, after process() had taken the frame)."""
    folder = os.fsencode(tmp_path) + b"/d\xff"
    os.mkdir(folder)
    for i, image in enumerate(route(3, 1)):
        write_pgm(folder + b"/%d.pgm" % i, image)
    path = os.fsencode(tmp_path) + b"/m\xfe.db"
    with lsgd.Database.create(path) as db:
        assert os.fsencode(db.path) == path
        assert "m\\udcfe.db" in repr(db)
        images = lsgd.open_sequence(folder)
        detector = db.detector()
        for k, image in enumerate(images):
            db.append(detector, detector.process(lsgd.read_image(image)), 0, image)
        db.append(detector, detector.process(lsgd.read_image(images[0])), 0, pathlib.Path(os.fsdecode(images[0])))
        with pytest.raises(lsgd.InvalidArgument, match="append: name: int is not a path"):
            db.append(detector, detector.process(lsgd.read_image(images[0])), 0, 7)
    assert lsgd.Database.open(path, writable=False).frames == 4  # the refused one is not stored
