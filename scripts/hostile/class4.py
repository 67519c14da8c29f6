"""Class 4 of the hostile campaign (scripts/hostile_campaign.py)."""
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


def c4_killed_state(cwd, dbname='d.db', csvname='c.csv'):
    rows = read_csv_rows(os.path.join(cwd, csvname))
    nrows = len(rows) if rows is not None else None
    frames = None
    if os.path.exists(os.path.join(cwd, dbname)):
        try:
            frames = len(db_dump_copy(os.path.join(cwd, dbname), os.path.join(cwd, '.peek'))['frames'])
        except Exception as e:
            frames = 'unreadable (%s)' % e
        shutil.rmtree(os.path.join(cwd, '.peek'), ignore_errors=True)
    return 'killed with %s CSV rows, %s committed frames' % (nrows, frames)


def class4():
    print('\n=== class 4: kill -9 and re-run', flush=True)
    rng = random.Random(SEED + 4)
    root = fresh(os.path.join(WORK, 'c4'))
    seq = os.path.join(BASE, 'demo640.txt')
    args = ['run', '--sequence', seq, '--database', 'd.db', '--output', 'c.csv', '--min-gap', '20']
    ref = c4_reference(fresh(os.path.join(root, 'ref')), args)
    T = ref['T']
    print('  uninterrupted run: %.2f s, %d rows' % (T, len(ref['csv'])))
    kills = [('time', t) for t in (0.0, 0.002, 0.01, 0.03, 0.06, 0.1, 0.2)]
    kills += [('time', round(rng.uniform(0.25, 0.9 * T), 3)) for _ in range(9)]
    kills += [('time', round(T * f, 3)) for f in (0.95, 0.98)] + [('time', round(T - 0.05, 3)), ('time', round(T - 0.01, 3))]
    kills += [('rows', n) for n in (1, 31, 32, 33, 64, 320, 638, 639, 640)]

    def kill_kw(kind, v, cwd, csvname='c.csv'):
        return {'kill_after': v} if kind == 'time' else {'kill_when': wait_rows(os.path.join(cwd, csvname), v)}

    for i, (kind, v) in enumerate(kills):
        cwd = fresh(os.path.join(root, 'k%02d' % i))
        c = Case(4, 'kill -9 at %s, then the same command' % ('%.3f s' % v if kind == 'time' else '%d CSV rows' % v),
                 'final CSV (but ms) and database equal the uninterrupted run row for row')
        r = c.run(args, cwd, timeout=120, **kill_kw(kind, v, cwd))
        state = c4_killed_state(cwd) if r.killed else 'finished before the kill (rc=%s)' % r.rc
        ri = c.run(['db', 'info', 'd.db'], cwd)
        r2 = c.run(args, cwd, timeout=120)
        c.check(r2.rc == 0, 're-run failed rc=%s (%s)' % (r2.rc, state), r2)
        c4_compare(c, cwd, ref, label='after re-run (%s)' % state)
        msg(4, c.name + ' [%s] db info' % state, ri)
        msg(4, c.name + ' [%s] re-run' % state, r2)
        if not c.done():
            c.problems = []
        # a third run must change nothing
        if i % 4 == 0 and r2.rc == 0:
            c = Case(4, 'kill -9 at %s: a third run changes nothing' % ('%.3f s' % v if kind == 'time' else '%d rows' % v),
                     'exit 0, "nothing to do", CSV and database unchanged')
            before = (read(os.path.join(cwd, 'c.csv')), db_dump(os.path.join(cwd, 'd.db')))
            r3 = c.run(args, cwd)
            c.check(r3.rc == 0, 'rc=%s' % r3.rc, r3)
            c.check(read(os.path.join(cwd, 'c.csv')) == before[0], 'the CSV changed', r3)
            c.check(not compare_db(db_dump(os.path.join(cwd, 'd.db')), before[1]), 'the database changed', r3)
            c.done()

    # kill twice in a row (the second kill during the resume)
    doubles = [(('rows', 100), ('rows', 300)), (('rows', 50), ('time', 0.01)), (('rows', 400), ('rows', 401)),
               (('time', round(T * 0.5, 3)), ('time', 0.2)), (('rows', 639), ('time', 0.005)),
               (('rows', 32), ('rows', 33)), (('time', 0.05), ('time', 0.05))]
    for i, (k1, k2) in enumerate(doubles):
        cwd = fresh(os.path.join(root, 'd%02d' % i))
        c = Case(4, 'kill -9 at %s, kill -9 the resume at %s, then the same command' % (k1, k2),
                 'final CSV and database equal the uninterrupted run')
        r = c.run(args, cwd, timeout=120, **kill_kw(k1[0], k1[1], cwd))
        s1 = c4_killed_state(cwd)
        r = c.run(args, cwd, timeout=120, **kill_kw(k2[0], k2[1], cwd))
        s2 = c4_killed_state(cwd) if r.killed else 'resume finished before the 2nd kill'
        r3 = c.run(args, cwd, timeout=120)
        c.check(r3.rc == 0, 'final re-run rc=%s' % r3.rc, r3)
        c4_compare(c, cwd, ref, label='after 2 kills (%s; %s)' % (s1, s2))
        c.done()

    # kill, then re-run with another --output name
    for i, n in enumerate((100, 333, 639)):
        cwd = fresh(os.path.join(root, 'o%02d' % i))
        c = Case(4, 'kill -9 at %d CSV rows, re-run with --output c2.csv' % n,
                 'database equals the uninterrupted run; c.csv untouched by the re-run; c2.csv holds the rows of '
                 'the frames not yet committed; committed rows of c.csv + c2.csv = the uninterrupted CSV')
        r = c.run(args, cwd, timeout=120, kill_when=wait_rows(os.path.join(cwd, 'c.csv'), n))
        st = c4_killed_state(cwd)
        old = read(os.path.join(cwd, 'c.csv'))
        dd = db_dump_copy(os.path.join(cwd, 'd.db'), os.path.join(cwd, '.peek'))
        committed = len(dd['frames'])
        args2 = [a if a != 'c.csv' else 'c2.csv' for a in args]
        r2 = c.run(args2, cwd, timeout=120)
        msg(4, c.name + ' [%s]' % st, r2)
        c.check(r2.rc == 0, 're-run rc=%s' % r2.rc, r2)
        c.check(read(os.path.join(cwd, 'c.csv')) == old, 'the old CSV c.csv was modified by the re-run', r2)
        new = csv_no_ms(read_csv_rows(os.path.join(cwd, 'c2.csv'))) or []
        c.check(new == ref['csv'][committed:],
                'c2.csv holds %d rows (frames %s..%s); expected the %d rows of frames %d..%d' % (
                    len(new), new[0][0] if new else None, new[-1][0] if new else None,
                    len(ref['csv']) - committed, committed, len(ref['csv']) - 1), r2)
        dd2 = db_dump(os.path.join(cwd, 'd.db'))
        diffs = compare_db(dd2, ref['db'])
        c.check(not diffs, 'database differs: %s' % '; '.join(diffs[:4]), r2)
        c.done()

    # nodes mode on the corridor (node restoration across kills)
    seqc = os.path.join(BASE, 'corr', 'sequence.txt')
    argsn = ['run', '--sequence', seqc, '--database', 'd.db', '--output', 'c.csv', '--min-gap', '20', '--mode', 'nodes']
    refn = c4_reference(fresh(os.path.join(root, 'refn')), argsn)
    for i, n in enumerate((1, 5, 40, 100, 150, 200, 221, 222)):
        cwd = fresh(os.path.join(root, 'n%02d' % i))
        c = Case(4, 'nodes mode (corridor): kill -9 at %d CSV rows, then the same command' % n,
                 'final CSV and database equal the uninterrupted run')
        r = c.run(argsn, cwd, kill_when=wait_rows(os.path.join(cwd, 'c.csv'), n))
        st = c4_killed_state(cwd) if r.killed else 'finished before the kill'
        r2 = c.run(argsn, cwd)
        c.check(r2.rc == 0, 're-run rc=%s' % r2.rc, r2)
        c4_compare(c, cwd, refn, label='after re-run (%s)' % st)
        c.done()
