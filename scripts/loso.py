#!/usr/bin/python3
# Leave-one-sequence-out choice of defaults from the CSV of `lsgd sweep` (one
# row per dataset and grid point). docs/results.md runs it.
#
#   scripts/loso.py SWEEP.csv KEY1,KEY2,... [DEFAULT1,DEFAULT2,...]
#   scripts/loso.py --suite KEY1,... DEFAULT1,... RUN.json RUN.json ...
#
# With --suite the grid comes from runs of scripts/eval_suite.py (--json),
# one per grid point, its values read from the run's --option KEY=VALUE (a
# key not given is at its DEFAULT). The sequences are those issue 32 chose
# defaults on: every sequence of the suite but the synthetic streets 2-6 and
# the +-2-frame ground truths (their false loops are 3+ frames off).
#
# For each held-out sequence: among the grid points that declare no false loop
# on any other sequence, the one with the highest mean declared-loop recall
# over the others; ties keep the most shipped values, then the most
# conservative (smaller bonuses, tolerance and gap, larger min_inliers and
# continuity_inliers). The held-out sequence is reported at that point. Then
# the same rule on all sequences (the default), and a stricter "margin" rule
# (the point and its grid neighbours all free of false loops) for comparison.
# Standard library only (/usr/bin/python3).
import csv, sys, collections, json
def suite_rows(keys, default, paths):
    rows = []
    for path in paths:
        with open(path) as f:
            run = json.load(f)
        given = dict(o.split('=', 1) for o in run['options'])
        point = {k: given.get(k, d) for k, d in zip(keys, default)}
        for name, r in run['results'].items():
            if name.startswith('street-s') and name != 'street-s1' or 'strict' in name:
                continue
            rows.append(dict(point, dataset=name, **{k: r[k] for k in
                        ('declared_loops', 'declared_true', 'declared_false', 'recall_at_decision',
                         'recall_at_100_precision')}))
    return rows
if sys.argv[1] == '--suite':
    keys = sys.argv[2].split(',')
    default = tuple(sys.argv[3].split(','))
    rows = suite_rows(keys, default, sys.argv[4:])
else:
    path = sys.argv[1]
    keys = sys.argv[2].split(',')          # grid columns
    default = tuple(sys.argv[3].split(',')) if len(sys.argv) > 3 else None  # shipped values: ties keep them
    rows = list(csv.DictReader(open(path)))
grid = collections.defaultdict(dict)
for r in rows:
    g = tuple(r[k] for k in keys)
    grid[g][r['dataset']] = r
seqs = sorted({r['dataset'] for r in rows})
def fp(g, s): return int(grid[g][s]['declared_false'])
def rec(g, s): return float(grid[g][s]['recall_at_decision'])
def conservative(g):
    d = dict(zip(keys, g)); out = []
    if default is not None:
        out.append(sum(float(a) == float(b) for a, b in zip(g, default)))
    for k in keys:
        v = float(d[k])
        # larger is more conservative for min_inliers / continuity_inliers; smaller for
        # bonuses, tolerance and gap
        out.append(-v if ('bonus' in k or 'tolerance' in k or 'gap' in k) else v)
    return tuple(out)
values = [sorted({g[i] for g in grid}, key=float) for i in range(len(keys))]
def neighbours(g):
    """The grid points one step away from g in one parameter."""
    out = []
    for i in range(len(keys)):
        k = values[i].index(g[i])
        for d in (-1, 1):
            if 0 <= k + d < len(values[i]):
                out.append(g[:i] + (values[i][k + d],) + g[i + 1:])
    return out
def choose(train, margin=False):
    """The rule; with margin, every grid neighbour must be free of false loops too."""
    def safe(g):
        points = [g] + [x for x in neighbours(g) if x in grid] if margin else [g]
        return all(s in grid[x] and fp(x, s) == 0 for x in points for s in train)
    ok = [g for g in grid if safe(g)]
    if not ok: return None
    return max(ok, key=lambda g: (sum(rec(g, s) for s in train) / len(train), conservative(g)))
def folds(margin):
    print('| held out | chosen (' + ', '.join(keys) + ') | declared on the held-out sequence (TP / FP) | recall at decision | R@100P |')
    print('|---|---|---|---|---|')
    for held in seqs:
        g = choose([s for s in seqs if s != held], margin)
        if g is None:
            print(f'| {held} | no grid point is safe |  |  |  |'); continue
        r = grid[g][held]
        print(f"| {held} | {', '.join(g)} | {r['declared_loops']} ({r['declared_true']} / {r['declared_false']}) | {float(r['recall_at_decision']):.3f} | {float(r['recall_at_100_precision']):.3f} |")
folds(False)
g = choose(seqs)
print('\nall sequences:', dict(zip(keys, g)))
for s in seqs:
    r = grid[g][s]
    print(f"  {s}: {r['declared_loops']} ({r['declared_true']} / {r['declared_false']}) recall {float(r['recall_at_decision']):.3f} R@100P {float(r['recall_at_100_precision']):.3f}")
print('\ngrid points with no false loop anywhere:', sum(1 for x in grid if all(fp(x, s) == 0 for s in seqs)), 'of', len(grid))
print('\nmargin rule (the point and its grid neighbours free of false loops)')
folds(True)
print('all:', choose(seqs, True))
