#!/usr/bin/python3
# Offline study (docs/results.md, "A cut cannot be detected from blocks of
# frames either"): can a map find where one place ends and another begins
# from its own frames? For every frame i, the block contrast
#   (within - cross) / (1 - within)
# where within is the mean similarity among the k frames before i and among
# the k frames from i on (averaged), and cross the mean similarity between the
# two blocks (the detector's own descriptors, lsgd.similarity). A true cut
# (a mixed map's part boundary, from its parts.txt) should stand above every
# frame inside a real sequence.
#
#   PYTHONPATH=build/python scripts/cut_study.py [--k 8] [--descriptor gradient] SEQUENCE_FOLDER...
#
# --descriptor gradient replaces the detector's gray-level histograms by a
# gradient-orientation histogram (4 x 4 cells of the frame at 160 x 120, 8
# orientations weighted by gradient magnitude, each cell normalised; the
# similarity is 1 - half the mean L1 distance of the cells): does a
# descriptor of structure rather than brightness find the places?
#
# --descriptor signature: the same, computed by the library
# (lsgd.place_signature, lsgd/places.h), as verification.temporal.place_cut
# finds the places.
#
# SEQUENCE_FOLDER holds sequence.txt (scripts/eval_suite.py's work folders,
# ../shared/datasets/<name>); a mixed map's parts.txt gives its cuts.
import argparse, os

import numpy as np
import lsgd

ap = argparse.ArgumentParser()
ap.add_argument('--k', type=int, default=8)
ap.add_argument('--descriptor', choices=['lsgd', 'gradient', 'signature'], default='lsgd')
ap.add_argument('folders', nargs='+')
args = ap.parse_args()
k = args.k


def gradient_descriptor(path, grid=4, bins=8):
    from PIL import Image
    g = np.asarray(Image.open(path).convert('L').resize((160, 120)), dtype=np.float32)
    gy, gx = np.gradient(g)
    magnitude = np.hypot(gx, gy)
    b = np.minimum(((np.arctan2(gy, gx) % np.pi) / np.pi * bins).astype(int), bins - 1)
    rows, cols = g.shape
    cells = []
    for r in range(grid):
        for c in range(grid):
            part = (slice(r * rows // grid, (r + 1) * rows // grid),
                    slice(c * cols // grid, (c + 1) * cols // grid))
            h = np.bincount(b[part].ravel(), weights=magnitude[part].ravel(), minlength=bins)
            cells.append(h / (h.sum() + 1e-9))
    return np.array(cells)


def gradient_similarity(a, b):
    return 1 - 0.5 * float(np.abs(a - b).sum()) / len(a)


for folder in args.folders:
    images = lsgd.open_sequence(os.path.join(folder, 'sequence.txt'))
    if args.descriptor == 'gradient':
        D = [gradient_descriptor(p) for p in images]
        similarity = gradient_similarity
    elif args.descriptor == 'signature':  # the library's own (verification.temporal.place_cut)
        D = [lsgd.place_signature(lsgd.read_image(p)) for p in images]
        similarity = lsgd.signature_similarity
    else:
        detector = lsgd.Detector()
        D = [detector.describe(lsgd.read_image(p)) for p in images]
        similarity = lsgd.similarity
    n = len(D)
    near = {}

    def s(a, b):
        key = (max(a, b), abs(a - b))
        if key not in near:
            near[key] = similarity(D[a], D[b])
        return near[key]

    r = np.full(n, -np.inf)
    for i in range(k, n - k):
        before = np.mean([s(a, b) for a in range(i - k, i) for b in range(i - k, a)])
        after = np.mean([s(a, b) for a in range(i, i + k) for b in range(i, a)])
        cross = np.mean([s(a, b) for a in range(i, i + k) for b in range(i - k, i)])
        within = (before + after) / 2
        r[i] = (within - cross) / max(1 - within, 1e-9)
    cuts = []
    parts = os.path.join(folder, 'parts.txt')
    if os.path.isfile(parts):
        for line in open(parts):  # "first count folder" a part
            fields = line.split()
            if fields and 0 < int(fields[0]) < n:
                cuts.append(int(fields[0]))
    inside = r.copy()
    for c in cuts:
        inside[max(0, c - k):c + k] = -np.inf
    top = np.argsort(-inside)[:3]
    print(f'{os.path.basename(folder.rstrip("/"))}: {n} frames, at the cuts '
          f'{[round(float(r[c]), 3) for c in cuts]}, elsewhere highest '
          f'{[round(float(inside[t]), 3) for t in top]} at frames {list(map(int, top))}')
