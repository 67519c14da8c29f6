#!/usr/bin/python3
# Offline study of the appearance scores (docs/results.md, "Why corridor loses
# loops after lip6-outdoor"): the similarity matrix of a sequence from the
# detector's own descriptors, then the sequence score R of every query
# (exhaustive search, min gap w, sequences of 16 and 48 frames, terms before
# the map counting 0) under variants of the standardisation, and what each
# ranks: R@1 of the sequence score alone, R@100P of that ranking, the true
# places at 3.5 and 2 sigma, the best score of queries with no revisit.
# No geometry and no decision: a study of the ranking the decision starts from.
#
#   PYTHONPATH=build/python scripts/score_study.py SEQUENCE GROUNDTRUTH [--first Q] [--min-gap 50] [--level2]
#       [--parts PARTS | --cuts C1,C2]
#
# --level2: the shipped level 1, and variants of the second standardisation
# (R = (A - mean) / sd over the query's candidates) instead: robust or
# truncated estimates of the null of A.
# --parts PARTS: a mixed map's parts.txt (scripts/mixed_map.py): adds the
# variant "each candidate against its own part": s(i, j) standardised with
# the query's statistics over the candidates of j's part only, and A the
# same way at level 2 (a part with fewer than 32 candidates scores 0 there,
# as a young query: no null to stand out from), as a map that knew where its places begin would do,
# and the variants that take the lower of the place's score and the whole
# map's (the shipped one, verification.temporal.place_cut: "min at level 1,
# mean-max, sd floor at level 2", with sequences within a part).
# --cuts C1,C2: the places' first frames instead of --parts (the places a
# detector found, e.g. with one of them missed).
#
# SEQUENCE is anything `lsgd.open_sequence` reads; GROUNDTRUTH is pairs
# "query match" (scripts/eval_suite.py writes them); --first: queries before
# it are not counted (a mixed map's earlier parts). The matrix is kept in
# /tmp/score-study-<hash>.npy.
import argparse, hashlib, os, sys

import numpy as np
import lsgd

ap = argparse.ArgumentParser()
ap.add_argument('sequence')
ap.add_argument('groundtruth')
ap.add_argument('--first', type=int, default=0)
ap.add_argument('--min-gap', type=int, default=50)
ap.add_argument('--level2', action='store_true')
ap.add_argument('--parts')
ap.add_argument('--cuts', help='first frames of the places after the first, comma-separated '
                '(instead of the parts of --parts: the places a detector found)')
args = ap.parse_args()
w = args.min_gap

images = lsgd.open_sequence(args.sequence)
cache = '/tmp/score-study-' + hashlib.sha1('\n'.join(images).encode()).hexdigest()[:12] + '.npy'
if os.path.isfile(cache):
    S = np.load(cache)
else:
    detector = lsgd.Detector()
    D = [detector.describe(lsgd.read_image(p)) for p in images]
    S = np.zeros((len(D), len(D)))
    for i in range(len(D)):
        for j in range(i):
            S[i, j] = S[j, i] = lsgd.similarity(D[i], D[j])
    np.save(cache, S)
n = len(S)
gt = {}
with open(args.groundtruth) as f:
    for line in f:
        q, m = map(int, line.split()[:2])
        gt.setdefault(q, set()).add(m)


def z_global(c):
    return (c - c.mean()) / c.std()


def z_local(radius):
    """SeqSLAM's local contrast: each similarity against +-radius candidates."""
    def z(c):
        m = len(c)
        cs, cs2 = np.concatenate([[0], np.cumsum(c)]), np.concatenate([[0], np.cumsum(c * c)])
        lo, hi = np.clip(np.arange(m) - radius, 0, m), np.clip(np.arange(m) + radius + 1, 0, m)
        mu = (cs[hi] - cs[lo]) / (hi - lo)
        sd = np.sqrt(np.maximum((cs2[hi] - cs2[lo]) / (hi - lo) - mu * mu, 0))
        return (c - mu) / np.maximum(sd, 0.25 * c.std())
    return z


def otsu_upper(values):
    """Otsu's split of `values`: the share of their variance it separates, and its upper class."""
    v = np.sort(values)
    cs = np.cumsum(v)
    k = np.arange(1, len(v))
    w0 = k / len(v)
    between = w0 * (1 - w0) * ((cs[-1] - cs[k - 1]) / (len(v) - k) - cs[k - 1] / k) ** 2
    b = int(np.argmax(between))
    return between[b] / values.var(), v[k[b]:]


def z_otsu(eta0):
    """The upper class of Otsu's split when the split separates at least eta0 of the variance."""
    def z(c):
        eta, upper = otsu_upper(c)
        if eta >= eta0 and len(upper) >= 32:
            return (c - upper.mean()) / upper.std()
        return z_global(c)
    return z


def combine_mean(a, b):
    return (a + b) / 2


def l2_global(A):
    return A.mean(), A.std()


def l2_truncated(q):
    """A normal fitted to the values above the q-quantile (the truncated normal's moments)."""
    from statistics import NormalDist
    a = NormalDist().inv_cdf(q)
    lam = np.exp(-a * a / 2) / np.sqrt(2 * np.pi) / (1 - q)
    sd_factor = np.sqrt(1 + a * lam - lam * lam)

    def stats(A):
        upper = np.sort(A)[int(q * len(A)):]
        sd = upper.std() / sd_factor
        return upper.mean() - lam * sd, sd
    return stats


def l2_otsu(eta0):
    def stats(A):
        eta, upper = otsu_upper(A)
        if eta >= eta0 and len(upper) >= 32:
            return upper.mean(), upper.std()
        return l2_global(A)
    return stats


def l2_median_mad(A):
    median = np.median(A)
    return median, 1.4826 * np.median(np.abs(A - median))


def l2_quantiles(lo, hi):
    """A normal through the lo- and hi-quantiles of A."""
    from statistics import NormalDist
    zl, zh = NormalDist().inv_cdf(lo), NormalDist().inv_cdf(hi)

    def stats(A):
        a, b = np.percentile(A, [100 * lo, 100 * hi])
        sd = (b - a) / (zh - zl)
        return a - zl * sd, sd
    return stats


part = np.zeros(n, dtype=int)  # the part of every frame (one part without --parts)
if args.cuts:
    for c in args.cuts.split(','):
        part[int(c):] += 1
elif args.parts:
    for line in open(args.parts):
        fields = line.split()
        if fields:
            part[int(fields[0]):] += 1


def by_part(standardise_values):
    """A standardisation applied within each part of the candidates (>= 32 of them), else whole."""
    def z(c):
        out = standardise_values(c)
        for p in np.unique(part[:len(c)]):
            members = part[:len(c)] == p
            out[members] = standardise_values(c[members]) if members.sum() >= 32 else 0
        return out
    return z


def by_part_min(c):
    """The lower of the place's z and the whole map's: a candidate stands out from both."""
    return np.minimum(by_part(z_global)(c), z_global(c))


def l2_min(A):
    """The lower of the place's R and the whole map's, as (mean, sd) per candidate."""
    mean, sd = l2_by_part(A)
    m, s = A.mean(), A.std()
    use_map = (A - m) / s < (A - mean) / sd
    return np.where(use_map, m, mean), np.where(use_map, s, sd)


def l2_mean_max(A):
    """The place's sd, and the higher of the place's mean and the map's."""
    mean, sd = l2_by_part(A)
    return np.maximum(mean, A.mean()), sd


def l2_mean_max_floor(A):
    """mean-max with the place's sd at least half the map's."""
    mean, sd = l2_by_part(A)
    return np.maximum(mean, A.mean()), np.maximum(sd, 0.5 * A.std())


def l2_by_part(A):
    mean, sd = np.full(len(A), A.mean()), np.full(len(A), A.std())
    for p in np.unique(part[:len(A)]):
        members = part[:len(A)] == p
        if members.sum() >= 32:
            mean[members], sd[members] = A[members].mean(), A[members].std()
        else:  # too few candidates in the part for a null: no score there
            mean[members], sd[members] = A[members], 1
    return mean, sd


level2 = [('shipped', l2_global)]
if args.level2:
    level2 += [('truncated above the median', l2_truncated(0.5)),
               ('truncated above the 75th percentile', l2_truncated(0.75)),
               ('truncated above the 90th percentile', l2_truncated(0.9)),
               ("Otsu's upper class, eta >= 0.7", l2_otsu(0.7)),
               ("Otsu's upper class, eta >= 0.8", l2_otsu(0.8)),
               ('median and MAD', l2_median_mad),
               ('quantiles 50 and 75', l2_quantiles(0.5, 0.75)),
               ('quantiles 75 and 95', l2_quantiles(0.75, 0.95))]
variants = [('shipped: global z, mean of 16 and 48', z_global, combine_mean),
            ('local contrast +-10', z_local(10), combine_mean),
            ('local contrast +-20', z_local(20), combine_mean),
            ('Otsu upper class, eta >= 0.7', z_otsu(0.7), combine_mean),
            ('max(16, mean of 16 and 48)', z_global, lambda a, b: np.maximum(a, (a + b) / 2)),
            ('16 only', z_global, lambda a, b: a)]
if args.level2:
    variants = variants[:1]
if args.parts or args.cuts:
    variants = variants[:1] + [('each candidate against its own part', by_part(z_global), combine_mean),
                               ('... and sequences within a part', by_part(z_global), combine_mean),
                               ('the shipped z, level 2 against its own part', z_global, combine_mean),
                               ('min of place and map at level 1, place at level 2', by_part_min, combine_mean),
                               ('min of place and map at both levels', by_part_min, combine_mean),
                               ('place at level 1, min at level 2', by_part(z_global), combine_mean),
                               ('... and sequences within a part: min of place and map at both levels', by_part_min, combine_mean),
                               ('... and sequences within a part: place at level 1, min at level 2', by_part(z_global), combine_mean),
                               ('... and sequences within a part: min at level 1, mean-max at level 2', by_part_min, combine_mean),
                               ('... and sequences within a part: min at level 1, mean-max, sd floor at level 2', by_part_min, combine_mean)]
    level2_of = {variants[1][0]: l2_by_part, variants[2][0]: l2_by_part, variants[3][0]: l2_by_part,
                 variants[4][0]: l2_by_part, variants[5][0]: l2_min, variants[6][0]: l2_min,
                 variants[7][0]: l2_min, variants[8][0]: l2_min, variants[9][0]: l2_mean_max, variants[10][0]: l2_mean_max_floor}
queries = [i for i in range(max(args.first, w + 32), n)]
for name, standardise, combine in variants:
    Z = np.zeros((n, n))
    for i in range(w + 32, n):
        Z[i, :i - w] = standardise(S[i, :i - w])
    scores = []  # A of every query
    for i in queries:
        m = i - w
        sums = []
        for L in (16, 48):
            s = np.zeros(m)
            for t in range(L):
                j = np.arange(m) - t
                keep = j >= 0
                if name.startswith('... and sequences within'):
                    # A term whose pair crosses a cut counts 0, as one before the map.
                    keep &= (part[np.maximum(j, 0)] == part[np.arange(m)]) & (part[i - t] == part[i])
                s[keep] += Z[i - t, j[keep]]
            sums.append(s / L)
        scores.append(combine(*sums))
    for name2, second in ([(name, level2_of[name])] if (args.parts or args.cuts) and name in level2_of else level2):
        rows = []  # (best R, correct, has a revisit)
        for i, A in zip(queries, scores):
            mean, sd = second(A)
            R = (A - mean) / sd
            best = int(np.argmax(R))
            rows.append((R[best], best in gt.get(i, ()), i in gt, part[best] != part[i]))
        rows.sort(key=lambda r: -r[0])
        positives = sum(1 for r in rows if r[2])
        before_first_false = next((k for k, r in enumerate(rows) if not r[1]), len(rows))
        nulls = [r[0] for r in rows if not r[2]]
        label = name if not args.level2 else f'level 2: {name2}'
        print(f'{label}: R@1 {sum(r[1] for r in rows)}/{positives}, '
              f'R@100P {before_first_false / max(positives, 1):.3f}, '
              f'true at 3.5 sigma {sum(1 for r in rows if r[1] and r[0] >= 3.5)}, '
              f'at 2 {sum(1 for r in rows if r[1] and r[0] >= 2)}, '
              f'wrong at 3.5 {sum(1 for r in rows if not r[1] and r[0] >= 3.5)} '
              f'({sum(1 for r in rows if not r[1] and r[0] >= 3.5 and r[3])} in another part), '
              f'best of a query with no revisit {max(nulls) if nulls else float("nan"):.2f}')
