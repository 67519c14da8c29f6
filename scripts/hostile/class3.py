"""Class 3 of the hostile campaign (scripts/hostile_campaign.py)."""
import csv
import hashlib
import io
import json
import os
import random
import re
import resource
import shlex
import shutil
import signal
import sqlite3
import stat
import struct
import subprocess
import sys
import time
import zlib
from hostile.run import *  # noqa: F401,F403
from hostile.report import *  # noqa: F401,F403
from hostile.files import *  # noqa: F401,F403


# ==========================================================================
# class 3: frame ids
# ==========================================================================
def kept_indices(n, first=None, last=None, every=None):
    f = first or 0
    l = n - 1 if last is None else min(last, n - 1)
    e = every or 1
    return list(range(f, l + 1, e))


def c3_check_csv(c, r, rows, kept_paths, base_id, skipped_pos, label):
    """Every row's frame = base_id + position of its image among the kept
    images; skipped positions have no row (or a no-loop row)."""
    if rows is None:
        c.fail('%s: no CSV written' % label, r)
        return {}
    pos_of = {}
    for i, p in enumerate(kept_paths):
        pos_of.setdefault(os.path.basename(p), i)
    bad = []
    frames = {}
    for row in rows:
        f = int(row[0])
        name = os.path.basename(row[1])
        exp = base_id + pos_of.get(name, -10 ** 9)
        if f != exp:
            bad.append('frame %d is image %s (expected frame %d)' % (f, name, exp))
        if f in frames:
            bad.append('frame %d appears twice' % f)
        frames[f] = row
    if bad:
        c.fail('%s: frame column is not the image index: %s%s' % (label, '; '.join(bad[:4]),
                                                                   ' (%d bad rows)' % len(bad) if len(bad) > 4 else ''), r)
    for s in skipped_pos:
        row = frames.get(base_id + s)
        if row is not None and row[2] != '-1':
            c.fail('%s: skipped frame %d has a row declaring a loop' % (label, base_id + s), r)
        if r is not None and ('skipped frame %d ' % s) not in r.stderr and ('skipped frame %d ' % (base_id + s)) not in r.stderr:
            c.fail('%s: no "skipped frame %d" message' % (label, s), r)
    exp_n = len(kept_paths) - len(skipped_pos)
    c.check(len(frames) == exp_n, '%s: %d rows, expected %d' % (label, len(frames), exp_n), r)
    return frames


def c3_check_db(c, cwd, dbp, csv_frames, session, kept_paths, base_id, label):
    r = c.run(['db', 'info', dbp, '--json'], cwd)
    try:
        j = json.loads(r.stdout)
    except ValueError:
        c.fail('%s: db info --json is not JSON' % label, r)
        return
    ss = [s for s in j.get('sessions', []) if s.get('session') == session]
    if not ss:
        c.fail('%s: db info has no session %d: %s' % (label, session, j.get('sessions')), r)
        return
    s = ss[0]
    fs = sorted(csv_frames)
    c.check(s.get('frames') == len(fs), '%s: db info session %d holds %s frames, CSV has %d rows' % (
        label, session, s.get('frames'), len(fs)), r)
    if fs:
        c.check(s.get('first_frame') == fs[0] and s.get('last_frame') == fs[-1],
                '%s: db info session %d ids %s..%s, CSV frames %d..%d' % (
                    label, session, s.get('first_frame'), s.get('last_frame'), fs[0], fs[-1]), r)
    rt = lsgd(['db', 'info', dbp], cwd)
    c.runs.append(rt)
    if fs:
        c.check(('ids %d .. %d' % (fs[0], fs[-1])) in rt.stdout,
                '%s: db info text does not print "ids %d .. %d" for session %d' % (label, fs[0], fs[-1], session), rt)
    d = db_dump(os.path.join(cwd, dbp))
    rows = [x for x in d['frames'] if x[1] == session]
    got = {x[11]: x[2] for x in rows}
    if sorted(got) != fs:
        c.fail('%s: database frame ids of session %d (%d rows, %s..%s) differ from the CSV frames (%d rows)' % (
            label, session, len(got), min(got) if got else None, max(got) if got else None, len(fs)), r)
    for f, name in got.items():
        exp = os.path.abspath(os.path.join(cwd, kept_paths[f - base_id])) if 0 <= f - base_id < len(kept_paths) else None
        if name != exp:
            c.fail('%s: database frame %d is %s, expected %s' % (label, f, name, exp), r)
            break
    ids = [x[11] for x in d['frames']]
    c.check(len(ids) == len(set(ids)), '%s: a frame id is stored twice in the database' % label, r)


def class3():
    print('\n=== class 3: frame ids', flush=True)
    root = fresh(os.path.join(WORK, 'c3'))
    src = copy_corridor(os.path.join(root, 'src'))
    names = corr_list(src)
    N = len(names)
    scenarios = [
        ('image 7 missing', {7: 'missing'}, {}),
        ('image 0 missing (first)', {0: 'missing'}, {}),
        ('image 100 truncated', {100: 'cut'}, {}),
        ('image 221 missing (last)', {221: 'missing'}, {}),
        ('images 7 and 8 missing (consecutive)', {7: 'missing', 8: 'missing'}, {}),
        ('images 0,1,2 missing', {0: 'missing', 1: 'missing', 2: 'missing'}, {}),
        ('image 130 16-bit PNG in a JPEG list', {130: '16bit'}, {}),
        ('image 60 of another size', {60: 'size'}, {}),
        ('image 7 missing, --first 3 --every 2', {7: 'missing'}, {'first': 3, 'every': 2}),
        ('image 8 missing (not kept), --first 3 --every 2', {8: 'missing'}, {'first': 3, 'every': 2}),
        ('image 50 missing, --first 0 --last 100', {50: 'missing'}, {'first': 0, 'last': 100}),
        ('image 20 missing, --first 5 --last 150 --every 3', {20: 'missing'}, {'first': 5, 'last': 150, 'every': 3}),
        ('image 10 missing = --first 10', {10: 'missing'}, {'first': 10}),
        ('image 40 missing, --every 4', {40: 'missing'}, {'every': 4}),
        ('image 150 truncated, --first 100', {150: 'cut'}, {'first': 100}),
        ('no damage, --first 30 --last 200 --every 2', {}, {'first': 30, 'last': 200, 'every': 2}),
    ]
    for si, (label, damage, sub) in enumerate(scenarios):
        cwd = fresh(os.path.join(root, 's%02d' % si))
        d = os.path.join(cwd, 'corr')
        shutil.copytree(src, d)
        lst = list(names)
        for i, how in damage.items():
            p = os.path.join(d, names[i])
            if how == 'missing':
                os.remove(p)
            elif how == 'cut':
                data = read(p)
                write(p, data[:len(data) // 2])
            elif how == '16bit':
                os.remove(p)
                lst[i] = names[i].replace('.jpg', '.png')
                write(os.path.join(d, lst[i]), make_png(160, 120, 16, 0, seed=i))
            elif how == 'size':
                os.remove(p)
                lst[i] = names[i].replace('.jpg', '.png')
                write(os.path.join(d, lst[i]), make_png(80, 60, 8, 0, seed=i))
        write(os.path.join(d, 'sequence.txt'), ('\n'.join(lst) + '\n').encode())
        kidx = kept_indices(N, sub.get('first'), sub.get('last'), sub.get('every'))
        kept = [os.path.join('corr', lst[i]) for i in kidx]
        skipped = [kidx.index(i) for i in damage if i in kidx]
        subargs = []
        for k in ('first', 'last', 'every'):
            if k in sub:
                subargs += ['--%s' % k, str(sub[k])]
        base = ['--sequence', 'corr/sequence.txt', '--min-gap', '20'] + subargs

        c = Case(3, 'run, %s: frame = image index' % label, 'image i is frame i (after --first/--last/--every)')
        r = c.run(['run'] + base + ['--output', 'run.csv'], cwd)
        c.check(r.rc == 0, 'rc=%s' % r.rc, r)
        run_rows = read_csv_rows(os.path.join(cwd, 'run.csv'))
        c3_check_csv(c, r, run_rows, kept, 0, skipped, 'run CSV')
        c.done()

        c = Case(3, 'run --database, %s: CSV, db info and stored frame ids agree' % label,
                 'CSV frame = image index; db info ids and stored frame/name consistent with the CSV')
        r = c.run(['run'] + base + ['--output', 'db.csv', '--database', 'd.db'], cwd)
        c.check(r.rc == 0, 'rc=%s' % r.rc, r)
        rows = read_csv_rows(os.path.join(cwd, 'db.csv'))
        fr = c3_check_csv(c, r, rows, kept, 0, skipped, 'run --database CSV')
        c.check(csv_no_ms(rows) == csv_no_ms(run_rows), 'the CSV with --database differs from the one without', r)
        if r.rc == 0:
            c3_check_db(c, cwd, 'd.db', fr, 0, kept, 0, 'database')
        c.done()

        c = Case(3, 'eval --output, %s: same numbering and rows as run' % label,
                 'eval --output CSV equals the run CSV (but ms)')
        r = c.run(['eval'] + base + ['--gt', 'corr/groundtruth.txt', '--json', 'm.json', '--output', 'eval.csv'], cwd)
        c.check(r.rc == 0, 'rc=%s' % r.rc, r)
        erows = read_csv_rows(os.path.join(cwd, 'eval.csv'))
        c3_check_csv(c, r, erows, kept, 0, skipped, 'eval CSV')
        if erows is not None and run_rows is not None and csv_no_ms(erows) != csv_no_ms(run_rows):
            a = dict((x[0], x) for x in csv_no_ms(run_rows))
            b = dict((x[0], x) for x in csv_no_ms(erows))
            diff = [k for k in sorted(set(a) | set(b), key=int) if a.get(k) != b.get(k)]
            c.fail('eval --output differs from run at frames %s (e.g. run %s vs eval %s)' % (
                diff[:5], a.get(diff[0]), b.get(diff[0])), r)
        try:
            j = json.load(open(os.path.join(cwd, 'm.json')))
            c.check(j.get('frames') == len(kept), 'eval JSON frames=%s, expected %d' % (j.get('frames'), len(kept)), r)
            c.check(j.get('skipped_frames') == len(skipped), 'eval JSON skipped_frames=%s, expected %d' % (
                j.get('skipped_frames'), len(skipped)), r)
        except (OSError, ValueError) as e:
            c.fail('eval JSON unreadable: %s' % e, r)
        c.done()

        if si in (0, 4, 8):
            # a second session over the same images (--session 1) and over a copy in another folder
            c = Case(3, 'second session (--session 1, same images), %s: frames numbered from last id + 1' % label,
                     'frame = 1 + largest stored id + image index; db info agrees')
            dd = db_dump(os.path.join(cwd, 'd.db'))
            last = max(x[11] for x in dd['frames'])
            r = c.run(['run'] + base + ['--output', 's1.csv', '--database', 'd.db', '--session', '1'], cwd)
            c.check(r.rc == 0, 'rc=%s' % r.rc, r)
            rows = read_csv_rows(os.path.join(cwd, 's1.csv'))
            fr = c3_check_csv(c, r, rows, kept, last + 1, skipped, 'session 1 CSV') if rows is not None else {}
            if r.rc == 0:
                c3_check_db(c, cwd, 'd.db', fr, 1, kept, last + 1, 'database session 1')
            c.done()
            c = Case(3, 'new session from a copy of the folder (automatic), %s' % label,
                     'a new session (2) numbered from last id + 1')
            d2 = os.path.join(cwd, 'corr2')
            shutil.copytree(d, d2)
            dd = db_dump(os.path.join(cwd, 'd.db'))
            last = max(x[11] for x in dd['frames'])
            kept2 = [os.path.join('corr2', lst[i]) for i in kidx]
            r = c.run(['run', '--sequence', 'corr2/sequence.txt', '--min-gap', '20'] + subargs +
                      ['--output', 's2.csv', '--database', 'd.db'], cwd)
            c.check(r.rc == 0, 'rc=%s' % r.rc, r)
            rows = read_csv_rows(os.path.join(cwd, 's2.csv'))
            fr = c3_check_csv(c, r, rows, kept2, last + 1, skipped, 'session 2 CSV') if rows is not None else {}
            if r.rc == 0:
                c3_check_db(c, cwd, 'd.db', fr, 2, kept2, last + 1, 'database session 2')
            c.done()
    # folder layout with a gap in the names: frame ids follow the folder order
    cwd = fresh(os.path.join(root, 'folder'))
    shutil.copytree(os.path.join(src, 'images'), os.path.join(cwd, 'imgs'))
    os.remove(os.path.join(cwd, 'imgs', '0050.jpg'))
    files = sorted(os.listdir(os.path.join(cwd, 'imgs')))
    c = Case(3, 'folder sequence with 0050.jpg absent: frame i = i-th file in natural order',
             'frame ids follow the folder listing (no gap: the file does not exist)')
    r = c.run(['run', '--sequence', 'imgs', '--min-gap', '20', '--output', 'f.csv'], cwd)
    c3_check_csv(c, r, read_csv_rows(os.path.join(cwd, 'f.csv')), [os.path.join('imgs', f) for f in files], 0, [], 'folder CSV')
    c.done()
