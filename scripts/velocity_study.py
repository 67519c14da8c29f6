#!/usr/bin/python3
# Offline study (docs/results.md, "Sequences along other slopes"): would a
# sequence score taken along slopes other than 1 (SeqSLAM's velocities: a
# revisit driven slower or faster) rank places better than the detector's
# diagonals? Every similarity of the detector's descriptors (lsgd.match, the
# 1000 best of each query, the rest set to the query's lowest), each query's
# z over its candidates j < i - W (queries with 32 candidates or more), the
# sequence score A(i, j) = 1/L sum_{t<L} z(i - t, j - round(v t)) (terms
# outside the map count 0), its best over the slopes v, standardised over the
# query's candidates. R@1: the best candidate is a pair of the ground truth;
# R@100P: the queries by best score, until the first wrong one.
#
#   PYTHONPATH=build/python scripts/velocity_study.py SEQUENCE_LIST GROUND_TRUTH W
import sys, os, numpy as np, lsgd
from PIL import Image
seq, gtfile, w = sys.argv[1], sys.argv[2], int(sys.argv[3])
base = os.path.dirname(seq)
paths = [os.path.join(base, l.strip()) for l in open(seq) if l.strip()]
cache = os.path.join(os.environ.get('TMPDIR', '/tmp'), f'velocity-{os.path.basename(base)}.npy')
if os.path.exists(cache):
    S = np.load(cache)
else:
    d = lsgd.Detector()
    descs = [d.describe(np.array(Image.open(p).convert('L'))) for p in paths]
    n = len(descs)
    S = np.full((n, n), np.nan)
    m = lsgd.match(descs, descs, top_k=min(1000, n))
    S[m['query'], m['match']] = m['similarity']
    for i in range(n):
        row = S[i]; row[np.isnan(row)] = np.nanmin(row)
    np.save(cache, S)
n = len(S)
gt = {}
for l in open(gtfile):
    if l.strip() and not l.startswith('#'):
        a, b = map(int, l.split()[:2]); q, m_ = max(a, b), min(a, b)
        gt.setdefault(q, set()).add(m_)
# z of query i over candidates j < i - w
Z = np.zeros((n, n))
for i in range(n):
    c = i - w
    if c >= 32:
        v = S[i, :c]; Z[i, :c] = (v - v.mean()) / (v.std() + 1e-12)
def seq_scores(i, L, slope):
    # A(i, j) = 1/L sum_t z(i - t, j - round(slope * t)) for every j < i - w
    c = i - w
    js = np.arange(c)
    acc = np.zeros(c)
    for t in range(L):
        a = i - t
        if a < 0: break
        jj = js - int(round(slope * t))
        ok = (jj >= 0) & (jj < a - w)
        acc[ok] += Z[a, jj[ok]]
    return acc / L
def evaluate(slopes, L, tol=2):
    best = []
    for i in range(n):
        if i - w < 32: continue
        sc = np.max([seq_scores(i, L, s) for s in slopes], axis=0)
        # standardise like level 2
        r = (sc - sc.mean()) / (sc.std() + 1e-12)
        j = int(np.argmax(r)); best.append((i, j, r[j]))
    pos = [b for b in best if b[0] in gt]
    r1 = np.mean([any(abs(b[1] - m) <= 0 for m in gt[b[0]]) for b in pos])
    # R@100P over queries ranked by score: true when j in gt[i]
    ranked = sorted(best, key=lambda b: -b[2])
    tp = 0; r100 = 0
    for b in ranked:
        if b[0] in gt and b[1] in gt[b[0]]: tp += 1
        else: break
    return r1, tp / len(gt)
for L in (16, 48):
    for name, slopes in (('1', [1.0]), ('0.8..1.25', [0.8, 0.9, 1.0, 1.1, 1.25]), ('0.67..1.5', [0.67, 0.8, 0.9, 1.0, 1.1, 1.25, 1.5])):
        r1, r100 = evaluate(slopes, L)
        print(f'{os.path.basename(base)} L={L} slopes {name}: R@1 {r1:.3f}  R@100P {r100:.3f}', flush=True)
