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
n = int(n)

def frames(dataset):
    with open(os.path.join(dataset, 'sequence.txt')) as f:
        return [os.path.abspath(os.path.join(dataset, line.strip())) for line in f if line.strip()]

def pairs(path):
    with open(path) as f:
        return [tuple(map(int, line.split()[:2])) for line in f if line.strip() and not line.startswith('#')]

a, b = frames(first), frames(second)
if not 0 < n <= len(a):
    sys.exit(f'N = {n}: {first} has {len(a)} frames')
size = Image.open(b[0]).size
os.makedirs(os.path.join(out, 'images'), exist_ok=True)
listed = []
for k, path in enumerate(a[:n]):
    target = os.path.abspath(os.path.join(out, 'images', f'{k:06d}.png'))
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
