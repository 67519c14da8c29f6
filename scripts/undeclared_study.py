#!/usr/bin/python3
# Offline study (docs/results.md, "Places in one map: three more ideas"):
# every query of a scripts/eval_suite.py run whose best-ranked candidate
# geometry confirms (ranked_confirmed 1) but which declared no loop, counted
# by its inliers and its appearance score, right or wrong place under the
# sequence's ground truth (strict: the exact pairs). It says what a lower bar
# for a first loop would add: loops and false loops.
#
#   scripts/undeclared_study.py [--work /tmp/lsgd-suite] [--runs DIR] [--shared ../shared/datasets]
#
# --runs: the folder of the suite's per-sequence CSVs (default WORK/runs).
import argparse, csv, glob, os

HERE = os.path.dirname(os.path.abspath(__file__))
ap = argparse.ArgumentParser()
ap.add_argument('--work', default='/tmp/lsgd-suite')
ap.add_argument('--runs')
ap.add_argument('--shared', default=os.path.join(HERE, '../../shared/datasets'))
args = ap.parse_args()
runs = args.runs or os.path.join(args.work, 'runs')
S = args.shared
gt_of = {'corridor': S + '/corridor/groundtruth.txt',
         'lip6-outdoor-wide': S + '/lip6-outdoor/groundtruth-wide.txt',
         'nordland-trimmed': S + '/nordland-trimmed/groundtruth.txt'}
rows = []  # (sequence, query, candidate, inliers, appearance, right)
for path in sorted(glob.glob(os.path.join(runs, '*.csv'))):
    name = os.path.basename(path)[:-4]
    if 'alone' in name or 'strict' in name:
        continue
    g = gt_of.get(name, os.path.join(args.work, name, 'groundtruth.txt'))
    if not os.path.exists(g):
        continue
    gt = {}
    for line in open(g):
        p = line.split()
        if len(p) >= 2 and not p[0].startswith('#'):
            gt.setdefault(int(p[0]), set()).add(int(p[1]))
    for r in csv.DictReader(open(path)):
        if r['ranked_confirmed'] != '1' or r['status'] == 'loop':
            continue
        q, c = int(r['frame']), int(r['ranked_frame'])
        rows.append((name, q, c, int(r['inliers']), float(r['ranked_score']), c in gt.get(q, ())))
print(f'{len(rows)} queries confirmed but not declared')
print('| inliers | appearance at least | right place | wrong place |')
print('|---|---|---|---|')
for lo, hi in [(20, 25), (25, 30), (30, 40), (40, 10 ** 9)]:
    for a in (3.0, 2.5, 2.0, 1.5):
        sel = [r for r in rows if lo <= r[3] < hi and r[4] >= a]
        span = f'{lo}-{hi - 1}' if hi < 10 ** 9 else f'{lo}+'
        print(f'| {span} | {a} | {sum(r[5] for r in sel)} | {sum(not r[5] for r in sel)} |')
