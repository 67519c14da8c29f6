#!/usr/bin/python3
# A map of two environments from two real sequences: the first N frames of
# FIRST, converted to gray and resized to SECOND's frame size, then every
# frame of SECOND; with both ground truths, SECOND's shifted by N. What a
# robot that maps one place and then another stores (docs/results.md, "A map
# of two environments").
#
#   scripts/mixed_map.py FIRST_DATASET FIRST_GT N SECOND_DATASET SECOND_GT OUT_DIR
#
# Datasets are folders with sequence.txt (../shared/datasets). Writes
# OUT_DIR/images/ (FIRST's frames, resized), OUT_DIR/sequence.txt (absolute
# paths) and OUT_DIR/groundtruth.txt; then
#   lsgd eval --sequence OUT_DIR --gt OUT_DIR/groundtruth.txt --min-gap 50 --json F
# Needs Pillow (Debian python3-pil, which python3-matplotlib of
# scripts/install-deps.sh brings).
import os, sys
from PIL import Image

if len(sys.argv) != 7:
    sys.exit("usage: scripts/mixed_map.py FIRST_DATASET FIRST_GT N SECOND_DATASET SECOND_GT OUT_DIR")
first, first_gt, n, second, second_gt, out = sys.argv[1:]
try:
    n = int(n)
except ValueError:
    sys.exit(f'N = {n!r}: not a whole number of frames')

def frames(dataset):
    with open(os.path.join(dataset, 'sequence.txt')) as f:
        return [os.path.abspath(os.path.join(dataset, line.strip())) for line in f if line.strip()]

def pairs(path):
    with open(path) as f:
        return [tuple(map(int, line.split()[:2])) for line in f if line.strip() and not line.startswith('#')]

for path in (first_gt, second_gt, os.path.join(first, 'sequence.txt'), os.path.join(second, 'sequence.txt')):
    if not os.path.isfile(path):
        sys.exit(f'{path}: no such file')
a, b = frames(first), frames(second)
if not 0 < n <= len(a):
    sys.exit(f'N = {n}: {first} has {len(a)} frames')
if not b:
    sys.exit(f'{second}/sequence.txt lists no frame')
# No output may land on an input (OUT_DIR a dataset folder, or holding one's images).
targets = [os.path.join(out, 'sequence.txt'), os.path.join(out, 'groundtruth.txt')] + \
          [os.path.join(out, 'images', f'{k:06d}.png') for k in range(n)]
inputs = {os.path.realpath(p) for p in a[:n] + b + [first_gt, second_gt,
          os.path.join(first, 'sequence.txt'), os.path.join(second, 'sequence.txt')]}
for t in targets:
    if os.path.realpath(t) in inputs:
        sys.exit(f'{t} is an input: choose another OUT_DIR')
size = Image.open(b[0]).size
os.makedirs(os.path.join(out, 'images'), exist_ok=True)
listed = []
for k, path in enumerate(a[:n]):
    target = os.path.abspath(targets[2 + k])
    Image.open(path).convert('L').resize(size, Image.BOX).save(target)
    listed.append(target)
listed += b
with open(os.path.join(out, 'sequence.txt'), 'w') as f:
    f.write('\n'.join(listed) + '\n')
with open(os.path.join(out, 'groundtruth.txt'), 'w') as f:
    for q, m in pairs(first_gt):
        if q < n and m < n:
            f.write(f'{q} {m}\n')
    for q, m in pairs(second_gt):
        f.write(f'{q + n} {m + n}\n')
print(f'{out}: {n} frames of {first} at {size[0]}x{size[1]}, then {len(b)} of {second}')
