"""lsgd: training-free visual loop closure detection (LSGDDN-LCD).

    import lsgd
    detector = lsgd.Detector(search={"min_gap": 50})
    result = detector.process(image)      # uint8 numpy array: gray, BGR or BGRA
    if result.loop:
        print(result.frame, "revisits", result.best.frame)

Options use the YAML's names (docs/options.md), nested or dotted:
``lsgd.Detector({"search.min_gap": 50})``, ``lsgd.Detector("config.yaml")``.
Errors are ``lsgd.Error`` (``InvalidArgument`` is also a ``ValueError``,
``IoError`` an ``OSError``, ``FormatError`` a ``ValueError``) with the
library's messages.
"""

import os

from . import _lsgd
from ._lsgd import (  # noqa: F401
    Candidate,
    Database,
    Descriptor,
    Detector,
    Error,
    FormatError,
    FrameDescription,
    GroundTruth,
    InvalidArgument,
    IoError,
    LoopEvidence,
    LoopGeometry,
    LoopStatus,
    Metrics,
    PrPoint,
    Ranking,
    Result,
    SessionPlan,
    StageVerdict,
    Timings,
    __commit__,
    __version__,
    default_options,
    evaluate,
    evaluate_detections,
    load_groundtruth,
    make_distractor,
    match,
    open_sequence,
    place_signature,
    options,
    read_image,
    signature_similarity,
    similarity,
    stored_image_name,
    write_csv,
)


def sweep(datasets, sets=(), options=None, jobs=1, strict=False, client=None):
    """Runs lsgd sweep's grid: every configuration of `sets` ("KEY=VALUES", as
    --set) on every dataset ("NAME=SEQUENCE,GT,MIN_GAP" or "NAME=DIR,MIN_GAP",
    as --dataset), on top of `options` (a dict or a YAML path); bad frames are
    skipped unless strict. A list of rows in grid order: dataset, values,
    metrics, nodes, bytes_per_frame, skipped_frames. Everything is checked
    before the first run.

    Without a client the cells run here on `jobs` threads. With `client` (a
    distributed.Client: a LocalCluster or a scheduler's address) each cell,
    its run and its evaluation, is a task on the cluster's workers, and the
    rows are the same (times aside); the workers must read the datasets at
    the same paths and import the same lsgd build (docs/evaluation.md,
    "Sweeps on a Dask cluster"). One dataset or one set may be given as a
    string rather than a list of one.
    """
    datasets = [datasets] if isinstance(datasets, str) else list(datasets)
    sets = [sets] if isinstance(sets, str) else list(sets)
    if client is None:
        return _lsgd.sweep(list(datasets), list(sets), options, jobs, strict)
    from . import _dask
    return _dask.sweep(client, datasets, sets, options, jobs, strict)


def run(detector, images):
    """Processes every image (paths or arrays) in order; returns the Results.

    A path that cannot be read raises lsgd.Error naming it; one path or one
    array where a sequence of them is expected raises lsgd.InvalidArgument.
    """
    if isinstance(images, (str, bytes, os.PathLike)):
        raise InvalidArgument("run: images: one path (%s), where a sequence of paths or arrays "
                              "is expected" % os.fsdecode(images))
    if getattr(images, "ndim", 0) == 2 or (getattr(images, "ndim", 0) == 3 and images.shape[-1] in (3, 4)):
        raise InvalidArgument("run: images: one image array (shape %s), where a sequence of "
                              "paths or arrays is expected" % (images.shape,))
    return [detector.process(read_image(i) if isinstance(i, (str, bytes, os.PathLike)) else i)
            for i in images]


def _plain(value):
    """A value of a result as plain Python (dicts, lists, numbers, strings)."""
    if hasattr(value, "to_dict"):
        return value.to_dict()
    if isinstance(value, LoopStatus):
        return str(value)
    if hasattr(value, "tolist"):  # numpy arrays
        return value.tolist()
    if isinstance(value, (list, tuple)):
        return [_plain(v) for v in value]
    return value


def _to_dict(self):
    """Every field as plain Python values (nested results too): json.dumps takes it."""
    kind = type(self)
    return {name: _plain(getattr(self, name)) for name in dir(kind)
            if not name.startswith("_") and isinstance(getattr(kind, name), property)}


def _repr(*shown):
    def __repr__(self):
        fields = ", ".join(f"{name}={getattr(self, name)!r}" for name in shown)
        return f"{type(self).__name__}({fields})"
    return __repr__


for _kind in (Candidate, LoopEvidence, LoopGeometry, Metrics, PrPoint, Ranking, Result, StageVerdict, Timings):
    _kind.to_dict = _to_dict
Metrics.__repr__ = _repr("declared_loops", "declared_true", "declared_false", "recall_at_decision",
                         "recall_at_100_precision", "average_precision", "recall_at_1")
LoopEvidence.__repr__ = _repr("appearance", "inliers", "confirmed", "continues")
StageVerdict.__repr__ = _repr("candidate", "stage", "accepted", "reason")
Timings.__repr__ = _repr("total_ms", "segment_ms", "search_ms", "verify_ms")
PrPoint.__repr__ = _repr("threshold", "precision", "recall")
