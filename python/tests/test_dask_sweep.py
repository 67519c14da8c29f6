"""lsgd.sweep(client=...): the cells of a sweep as tasks on a Dask cluster
(issue 34, item 7). A LocalCluster of two worker processes gives the rows a
local sweep gives (every metric but the times), errors name their cell as a
local sweep's do, and a row's Metrics cross processes whole (pickle)."""
import os
import pickle

import pytest

import lsgd

from test_eval_tools import route  # noqa: F401 (the fixture: 30 places visited 3 times)

distributed = pytest.importorskip(
    "distributed", reason="Dask distributed is absent (Debian python3-distributed, scripts/install-deps.sh)")

TIMES = {"ms_per_frame_median", "ms_per_frame_p95", "ms_per_frame_mean", "prt",
         "load_ms_median", "convert_ms_median", "segment_ms_median", "describe_ms_median",
         "search_ms_median", "verify_ms_median"}


@pytest.fixture(scope="module")
def client():
    # Worker processes (not threads): each imports lsgd on its own, as on a
    # cluster of machines; they inherit PYTHONPATH from this process.
    with distributed.LocalCluster(n_workers=2, threads_per_worker=1, processes=True,
                                  dashboard_address=":0", silence_logs=40) as cluster:
        with distributed.Client(cluster) as c:
            yield c


def plain(rows):
    out = []
    for row in rows:
        row = dict(row)
        metrics = row.pop("metrics").to_dict()
        row["metrics"] = {k: v for k, v in metrics.items() if k not in TIMES}
        out.append(row)
    return out


def test_metrics_pickle_whole(route):  # noqa: F811
    images = lsgd.open_sequence(os.path.join(route, "sequence.txt"))
    gt = lsgd.load_groundtruth(os.path.join(route, "groundtruth.txt"), frames=len(images))
    m = lsgd.evaluate(lsgd.run(lsgd.Detector({"search.min_gap": 10}), images), gt, min_gap=10)
    back = pickle.loads(pickle.dumps(m))
    assert back.to_dict() == m.to_dict()
    assert len(back.curve) == len(m.curve) > 0
    assert back.ms_per_frame_median == m.ms_per_frame_median > 0
    point = pickle.loads(pickle.dumps(m.curve[0]))
    assert (point.threshold, point.precision, point.recall, point.confirmed) == (
        m.curve[0].threshold, m.curve[0].precision, m.curve[0].recall, m.curve[0].confirmed)


def test_rows_on_a_cluster_equal_the_local_sweep(route, client):  # noqa: F811
    sets = ["search.mode=exhaustive,nodes,index", "segmentation.superpixel_size=30,40"]
    datasets = ["route=%s,10" % route, "again=%s,12" % route]
    local = lsgd.sweep(datasets, sets, jobs=2)
    with distributed.get_task_stream(client) as stream:
        remote = lsgd.sweep(datasets, sets, client=client)
    assert len(remote) == len(local) == 12
    assert plain(remote) == plain(local)
    assert [r["values"]["search.mode"] for r in remote[:6]] == ["exhaustive"] * 2 + ["nodes"] * 2 + ["index"] * 2
    assert remote[0]["metrics"].recall_at_1 > 0.5
    assert isinstance(remote[0]["metrics"], lsgd.Metrics)
    # Each cell ran as a task on the workers.
    tasks = [t for t in stream.data if t["key"].startswith("lsgd-sweep-")]
    assert len(tasks) == 12 and {t["worker"] for t in tasks} <= set(client.scheduler_info()["workers"])
    # Without sets: one evaluation per dataset (lsgd eval's), on the cluster.
    evaluations = lsgd.sweep(datasets, client=client)
    assert [r["dataset"] for r in evaluations] == ["route", "again"]
    assert plain(evaluations) == plain(lsgd.sweep(datasets))


def test_the_grid_is_checked_before_any_task(route, client):  # noqa: F811
    before = client.run_on_scheduler(lambda dask_scheduler: len(dask_scheduler.tasks))
    with pytest.raises(lsgd.InvalidArgument, match="superpixel_size"):
        lsgd.sweep(["route=%s,10" % route], ["segmentation.superpixel_size=0,30"], client=client)
    with pytest.raises(lsgd.IoError):
        lsgd.sweep(["route=/no/such/folder,10"], client=client)
    with pytest.raises(lsgd.InvalidArgument, match="jobs"):
        lsgd.sweep(["route=%s,10" % route], client=client, jobs=0)
    assert client.run_on_scheduler(lambda dask_scheduler: len(dask_scheduler.tasks)) == before


def test_a_failing_cell_is_named_with_its_worker(route, client, tmp_path):  # noqa: F811
    # Every image removed after the grid was checked: the cells fail on the
    # workers, and the error names the cell (as a local sweep's) and the worker.
    folder = tmp_path / "gone"
    folder.mkdir()
    names = []
    for k in range(3):
        path = folder / ("%d.pgm" % k)
        path.write_bytes(b"P5\n4 4\n255\n" + bytes(16))
        names.append(str(path))
    (folder / "sequence.txt").write_text("\n".join(names) + "\n")
    (folder / "groundtruth.txt").write_text("2 0\n")
    for name in names:
        os.remove(name)
    # The cells run at once on the two workers: the first to fail is raised.
    with pytest.raises(lsgd.Error, match=r"\[[12]/2\] gone search.mode=(exhaustive|nodes): .*skipped.*on worker"):
        lsgd.sweep(["gone=%s,1" % folder], ["search.mode=exhaustive,nodes"], client=client)
    local = None
    with pytest.raises(lsgd.Error) as local:
        lsgd.sweep(["gone=%s,1" % folder], ["search.mode=exhaustive,nodes"])
    assert "[1/2] gone search.mode=exhaustive" in str(local.value)


def test_a_worker_with_another_build_is_refused(route):  # noqa: F811
    from lsgd import _dask
    cell = lsgd._lsgd._sweep_plan(["route=%s,10" % route], [], None, 1)[0]
    with pytest.raises(lsgd.Error, match="commit .* the client's 0123abc: run the same build everywhere"):
        _dask._run_cell(cell["dataset_spec"], cell["options"], cell["label"], False, "0123abc")
    row = _dask._run_cell(cell["dataset_spec"], cell["options"], cell["label"], False, lsgd.__commit__)
    assert row["metrics"].recall_at_1 == lsgd.sweep(["route=%s,10" % route])[0]["metrics"].recall_at_1


def _describe(options, path):
    """A robot: describes one of its frames (on a worker)."""
    return lsgd.Detector(options).describe_frame(lsgd.read_image(path))


def test_robots_describe_on_workers_and_the_map_stores(route, client):  # noqa: F811
    # Frames described in the workers' processes travel back pickled, and the
    # map here gives the Results of the images (issue 34: robots describe
    # their frames locally and send the compact descriptor).
    import sys
    import cloudpickle
    cloudpickle.register_pickle_by_value(sys.modules[__name__])  # workers cannot import this file
    options = {"search.min_gap": 10, "descriptor.storage": "compact"}
    images = lsgd.open_sequence(os.path.join(route, "sequence.txt"))
    with distributed.get_task_stream(client) as stream:
        described = client.gather(client.map(_describe, [options] * len(images), images))
    assert len([t for t in stream.data if t["key"].startswith("_describe")]) == len(images)
    reference, map_ = lsgd.Detector(options), lsgd.Detector(options)
    for path, d in zip(images, described):
        expected = reference.process(lsgd.read_image(path))
        got = map_.process(d)
        assert (got.loop, got.best.frame, [c.frame for c in got.candidates]) == (
            expected.loop, expected.best.frame, [c.frame for c in expected.candidates])
    assert reference.size == map_.size == len(images)


def test_a_cluster_without_a_worker_is_an_error_not_a_hang(route, monkeypatch):  # noqa: F811
    import lsgd._dask
    monkeypatch.setattr(lsgd._dask, "WORKER_WAIT_S", 1)
    with distributed.LocalCluster(n_workers=0, processes=False, dashboard_address=":0",
                                  silence_logs=40) as cluster:
        with distributed.Client(cluster) as c:
            with pytest.raises(lsgd.Error, match="has had no worker for 1 s"):
                lsgd.sweep(["route=%s,10" % route], client=c)
