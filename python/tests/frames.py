"""Frames and paths the Python tests share: synthetic places (a route of
them, as arrays or PGM files) and where the sources, the CLI and ../shared are."""
import os

import numpy as np

SOURCE = os.environ.get("LSGD_SOURCE_DIR", os.path.join(os.path.dirname(__file__), "..", ".."))
CLI = os.environ.get("LSGD_CLI", "")
SHARED = os.path.join(SOURCE, "..", "shared", "datasets")


def place(p, shift=0, width=160, height=120):
    """Frame of place p: noise over the place's own 8 gray levels, moved by `shift` pixels."""
    rng = np.random.default_rng(1000 + p)
    levels = np.random.default_rng(7000 + p).integers(0, 256, 8, dtype=np.uint8)
    index = rng.integers(0, 8, (height, width + 8))
    return levels[index[:, shift:shift + width]]


def route(places=30, laps=3):
    return [place(p, lap) for lap in range(laps) for p in range(places)]


def write_pgm(path, image):
    with open(path, "wb") as f:
        f.write(b"P5\n%d %d\n255\n" % (image.shape[1], image.shape[0]))
        f.write(np.ascontiguousarray(image).tobytes())
