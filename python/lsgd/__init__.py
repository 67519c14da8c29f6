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

from ._lsgd import (  # noqa: F401
    Candidate,
    Database,
    Detector,
    Error,
    FormatError,
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
    StageVerdict,
    Timings,
    __commit__,
    __version__,
    default_options,
    evaluate,
    load_groundtruth,
    open_sequence,
    options,
    read_image,
)


def run(detector, images):
    """Processes every image (paths or arrays) in order; returns the Results.

    A path that cannot be read raises lsgd.Error naming it.
    """
    return [detector.process(read_image(i) if isinstance(i, str) else i) for i in images]
