#!/usr/bin/python3
# A map of several environments from real sequences: the first N frames of
# each part but the last, converted to gray and resized to the last part's
# frame size, then every frame of the last part; with every part's ground
# truth, shifted to the part's place in the map. What a robot that maps one
# place and then another stores (docs/results.md, "A map of two
# environments"; scripts/eval_suite.py builds the maps it scores with it).
#
#   scripts/mixed_map.py FIRST_DATASET FIRST_GT N [DATASET GT N ...] LAST_DATASET LAST_GT OUT_DIR
#
# Datasets are folders with sequence.txt (../shared/datasets). Writes
# OUT_DIR/images/ (the resized frames), OUT_DIR/sequence.txt (absolute
# paths), OUT_DIR/groundtruth.txt and OUT_DIR/parts.txt (one line a part:
# first frame, frame count, dataset); then
#   lsgd eval --sequence OUT_DIR --gt OUT_DIR/groundtruth.txt --min-gap 50 --json F
# Needs Pillow (Debian python3-pil, which python3-matplotlib of
# scripts/install-deps.sh brings).
import os, sys
from PIL import Image


def frames(dataset):
    """The images of a dataset folder's sequence.txt, as absolute paths."""
    with open(os.path.join(dataset, 'sequence.txt')) as f:
        return [os.path.abspath(os.path.join(dataset, line.strip())) for line in f if line.strip()]


def pairs(path):
    """The (query, match) pairs of a ground-truth pairs file."""
    with open(path) as f:
        return [tuple(map(int, line.split()[:2])) for line in f if line.strip() and not line.startswith('#')]


def main():
    args = sys.argv[1:]
    if len(args) < 6 or (len(args) - 3) % 3 != 0:
        sys.exit("usage: scripts/mixed_map.py FIRST_DATASET FIRST_GT N [DATASET GT N ...] "
                 "LAST_DATASET LAST_GT OUT_DIR")
    out = args[-1]
    parts = []  # (dataset, gt, n or None for the whole last part)
    for k in range(0, len(args) - 3, 3):
        dataset, gt, n = args[k:k + 3]
        try:
            n = int(n)
        except ValueError:
            sys.exit(f'N = {n!r}: not a whole number of frames')
        parts.append((dataset, gt, n))
    parts.append((args[-3], args[-2], None))

    for dataset, gt, _ in parts:
        for path in (gt, os.path.join(dataset, 'sequence.txt')):
            if not os.path.isfile(path):
                sys.exit(f'{path}: no such file')
    lists = [frames(dataset) for dataset, _, _ in parts]
    for (dataset, _, n), images in zip(parts, lists):
        if n is not None and not 0 < n <= len(images):
            sys.exit(f'N = {n}: {dataset} has {len(images)} frames')
        if not images:
            sys.exit(f'{dataset}/sequence.txt lists no frame')
    counts = [n for _, _, n in parts[:-1]] + [len(lists[-1])]
    resized = sum(counts[:-1])
    # No output may land on an input (OUT_DIR a dataset folder, or holding one's images).
    targets = [os.path.join(out, name) for name in ('sequence.txt', 'groundtruth.txt', 'parts.txt')] + \
              [os.path.join(out, 'images', f'{k:06d}.png') for k in range(resized)]
    inputs = {os.path.realpath(p) for images in lists for p in images} | \
             {os.path.realpath(p) for dataset, gt, _ in parts for p in (gt, os.path.join(dataset, 'sequence.txt'))}
    for t in targets:
        if os.path.realpath(t) in inputs:
            sys.exit(f'{t} is an input: choose another OUT_DIR')
    size = Image.open(lists[-1][0]).size
    os.makedirs(os.path.join(out, 'images'), exist_ok=True)
    listed = []
    for images, n in zip(lists[:-1], counts[:-1]):
        for path in images[:n]:
            target = os.path.abspath(targets[3 + len(listed)])
            Image.open(path).convert('L').resize(size, Image.BOX).save(target)
            listed.append(target)
    listed += lists[-1]
    with open(os.path.join(out, 'sequence.txt'), 'w') as f:
        f.write('\n'.join(listed) + '\n')
    with open(os.path.join(out, 'groundtruth.txt'), 'w') as g, open(os.path.join(out, 'parts.txt'), 'w') as p:
        start = 0
        for (dataset, gt, _), n in zip(parts, counts):
            for q, m in pairs(gt):
                if q < n and m < n:
                    g.write(f'{q + start} {m + start}\n')
            p.write(f'{start} {n} {os.path.abspath(dataset)}\n')
            start += n
    described = ', then '.join(f'{n} frames of {dataset}' for (dataset, _, _), n in zip(parts, counts))
    print(f'{out}: {described}, at {size[0]}x{size[1]}')


if __name__ == '__main__':
    main()
