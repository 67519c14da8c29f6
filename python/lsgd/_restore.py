"""How pickle rebuilds lsgd's values: their __reduce__ names these functions,
which rebuild a value from its state. Never through __new__: an lsgd class
refuses a bare __new__ (an instance without its C++ object crashed the
interpreter), and a pybind11 function cannot be pickled by name itself."""

from . import _lsgd


def frame_description(data):
    """A FrameDescription from FrameDescription.to_bytes()."""
    return _lsgd._restore_frame_description(data)


def pr_point(state):
    """A PrPoint from its pickled state."""
    return _lsgd._restore_pr_point(state)


def metrics(state):
    """A Metrics from its pickled state."""
    return _lsgd._restore_metrics(state)
