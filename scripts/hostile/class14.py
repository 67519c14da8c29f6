"""Class 14 of the hostile campaign (scripts/hostile_campaign.py)."""
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


def class14():
    """Issue 35, the fourth pass (2026-12-07): a database through a symbolic
    link, a log older than its file, names SQLite reads as special, another
    program's WAL database, image names with a newline, empty flag values, a
    config of a million nodes, a top-k file of one query's 85,000 ranks, match
    with no readable query."""
    print('\n=== class 14: links, old logs, special names, newlines, empty flags, bombs', flush=True)
    root = fresh(os.path.join(WORK, 'c14'))

    def got(path):  # a file's bytes; a file lsgd removed reads as such
        return read(path) if os.path.exists(path) else b'<removed>'
    corr = os.path.join(BASE, 'corr')
    seq = os.path.join(corr, 'sequence.txt')
    names = corr_list(corr)

    cwd = fresh(os.path.join(root, 'link'))
    c = Case(14, "another database's log beside a database opened through a symbolic link",
             "refused naming the target's log (lsgd looked for LINK-wal); nothing changed")
    os.makedirs(os.path.join(cwd, 'a'))
    os.makedirs(os.path.join(cwd, 'b'))
    for name, first in (('a', '0'), ('b', '60')):
        c.run(['run', '--sequence', seq, '--database', name + '/d.db', '--output', name + '.csv',
               '--min-gap', '20', '--first', first], cwd, timeout=120,
              kill_when=wait_rows(os.path.join(cwd, name + '.csv'), 45))
    logs = [os.path.join(cwd, n, 'd.db-wal') for n in ('a', 'b')]
    if c.check(all(os.path.isfile(w) and os.path.getsize(w) > 0 for w in logs),
               'a killed writer left no log (harness)'):
        shutil.copyfile(logs[1], logs[0])
        if os.path.exists(os.path.join(cwd, 'a', 'd.db-shm')):
            os.remove(os.path.join(cwd, 'a', 'd.db-shm'))
        os.symlink(os.path.join('a', 'd.db'), os.path.join(cwd, 'link.db'))
        before = got(os.path.join(cwd, 'a', 'd.db')) + got(logs[0])
        r = c.run(['run', '--sequence', seq, '--database', 'link.db', '--output', 'l.csv', '--min-gap', '20'],
                  cwd, skip_inputs=['link.db'])
        msg(14, c.name, r)
        c.check(r.rc != 0 and 'another database' in r.stderr and 'a/d.db-wal' in r.stderr,
                'not refused naming the target\'s log', r)
        c.check(got(os.path.join(cwd, 'a', 'd.db')) + got(logs[0]) == before, 'the database was changed')
    c.done()

    cwd = fresh(os.path.join(root, 'older'))
    c = Case(14, 'a log copied before its file (older than the file)',
             'refused by readers and writers naming the log; nothing changed')
    args = ['run', '--sequence', seq, '--database', 'd.db', '--output', 'c.csv', '--min-gap', '20']
    c.run(args, cwd, timeout=120, kill_when=wait_rows(os.path.join(cwd, 'c.csv'), 45))
    log = os.path.join(cwd, 'd.db-wal')
    if c.check(os.path.isfile(log) and os.path.getsize(log) > 0, 'a killed writer left no log (harness)'):
        old = read(log)
        r = c.run(args, cwd, timeout=120)   # resumed to the end and closed: the file holds every frame
        write(log, old)
        if os.path.exists(os.path.join(cwd, 'd.db-shm')):
            os.remove(os.path.join(cwd, 'd.db-shm'))
        before = read(os.path.join(cwd, 'd.db'))
        for a in (['db', 'info', 'd.db'], args[:-6] + ['--database', 'd.db', '--output', 'c2.csv']):
            r = c.run(a, cwd, skip_inputs=['d.db-wal'])
            msg(14, c.name, r)
            c.check(r.rc != 0 and 'older than the file' in r.stderr, '%s: not refused' % a[0], r)
        c.check(got(os.path.join(cwd, 'd.db')) == before, 'the file was changed')
    c.done()

    cwd = fresh(os.path.join(root, 'names'))
    c = Case(14, "databases named ':memory:' and 'file:a.db' (names SQLite reads as special)",
             'files of those names, read back with their frames')
    for name in (':memory:', 'file:a.db'):
        r = c.run(['run', '--sequence', seq, '--database', name, '--output', 'n.csv', '--last', '9'], cwd)
        c.check(r.rc == 0 and os.path.isfile(os.path.join(cwd, name)), '%s: not created as a file' % name, r)
        r = c.run(['db', 'info', name], cwd)
        c.check(r.rc == 0 and 'frames: 10' in r.stdout, '%s: not read back' % name, r)
        if os.path.exists(os.path.join(cwd, 'n.csv')):
            os.remove(os.path.join(cwd, 'n.csv'))
    c.check(not os.path.exists(os.path.join(cwd, 'a.db')), 'SQLite opened a.db (a URI)')
    c.done()

    cwd = fresh(os.path.join(root, 'other'))
    c = Case(14, "another program's SQLite database in WAL mode as --database",
             'refused as not an lsgd database; its file and log unchanged')
    import sqlite3
    con = sqlite3.connect(os.path.join(cwd, 'live.db'))
    con.execute('pragma journal_mode=wal')
    con.execute('pragma wal_autocheckpoint=0')
    con.execute('create table t(a)')
    con.commit()
    for i in range(30):
        con.execute('insert into t values (?)', (i,))
        con.commit()
    shutil.copyfile(os.path.join(cwd, 'live.db'), os.path.join(cwd, 'app.db'))
    shutil.copyfile(os.path.join(cwd, 'live.db-wal'), os.path.join(cwd, 'app.db-wal'))
    con.close()
    before = read(os.path.join(cwd, 'app.db')) + read(os.path.join(cwd, 'app.db-wal'))
    r = c.run(['run', '--sequence', seq, '--database', 'app.db', '--output', 'o.csv'], cwd,
              skip_inputs=['app.db', 'app.db-wal'])
    c.check(r.rc != 0 and 'not an lsgd database' in r.stderr, 'not refused', r)
    c.check(os.path.exists(os.path.join(cwd, 'app.db-wal')) and
            got(os.path.join(cwd, 'app.db')) + got(os.path.join(cwd, 'app.db-wal')) == before,
            'the other program\'s database was changed')
    c.done()

    cwd = fresh(os.path.join(root, 'newline'))
    c = Case(14, 'image names with a newline and a lone CR; a run killed and resumed',
             "one row per frame after the resume (the resume cut the rows of stored frames); "
             "eval --detections reads the run's own CSV")
    os.makedirs(os.path.join(cwd, 'f'))
    for i in range(60):
        n = '%03d' % i + ('\nx' if i == 10 else '\r' if i == 11 else '')
        shutil.copyfile(os.path.join(corr, names[i]), os.path.join(cwd, 'f', n + '.jpg'))
    args = ['run', '--sequence', 'f', '--output', 'c.csv', '--database', 'd.db', '--min-gap', '5']
    c.run(args, cwd, timeout=120, kill_when=wait_rows(os.path.join(cwd, 'c.csv'), 45))
    r = c.run(args, cwd, timeout=120)
    rows = [l for l in csv.reader(open(os.path.join(cwd, 'c.csv'), newline=''))][1:]
    c.check(r.rc == 0 and [int(x[0]) for x in rows] == list(range(60)),
            'rows %s' % [x[0] for x in rows][:70], r)
    write(os.path.join(cwd, 'gt.txt'), b'40 3\n')
    r = c.run(['eval', '--detections', 'c.csv', '--gt', 'gt.txt', '--min-gap', '5', '--json', 'j.json'], cwd)
    c.check(r.rc == 0, 'lsgd eval cannot read lsgd run\'s CSV', r)
    c.done()

    cwd = fresh(os.path.join(root, 'empty'))
    c = Case(14, "empty flag values ('' from an unset variable)", 'refused naming the flag')
    write(os.path.join(cwd, 'gt.txt'), b'40 3\n')
    write(os.path.join(cwd, 'd.csv'), b'40,3,0.5\n')
    for a in (['eval', '--detections', 'd.csv', '--gt', 'gt.txt', '--min-gap', ''],
              ['run', '--sequence', seq, '--output', 'o.csv', '--last', ''],
              ['options', '--threshold', '']):
        r = c.run(a, cwd)
        flag = [x for x in a if x.startswith('--')][-1]
        c.check(r.rc != 0 and flag + ': an empty value' in r.stderr, '%s: not refused' % ' '.join(a), r)
    c.done()

    cwd = fresh(os.path.join(root, 'bombs'))
    c = Case(14, "a 1 MB config '[,,,...]', a 64 KiB one, and a top-k file of one query's 85,000 ranks",
             'refused (the configs) or read (the ranks) within 256 MB and 1 s of CPU each')
    write(os.path.join(cwd, 'big.yaml'), ('[' + ',' * 1048000 + ']').encode())
    write(os.path.join(cwd, 'small.yaml'), ('[' + ',' * 65000 + ']').encode())
    for f in ('big.yaml', 'small.yaml'):
        r = c.run(['options', '--config', f], cwd)
        c.check(r.rc != 0 and f in r.stderr, '%s: not refused' % f, r)
        c.check(r.maxrss_kb < 256 * 1024 and r.cpu_s < 1, '%s: %d MB, %.2f s of CPU' % (f, r.maxrss_kb // 1024, r.cpu_s), r)
    write(os.path.join(cwd, 'topk.csv'), ('query,match,score,similarity,rank\n' +
          ''.join('100,%d,0.5,0.5,%d\n' % (k % 90, k + 1) for k in range(85000))).encode())
    write(os.path.join(cwd, 'gt.txt'), b'100 3\n')
    r = c.run(['eval', '--detections', 'topk.csv', '--gt', 'gt.txt', '--min-gap', '5', '--json', 't.json'], cwd)
    c.check(r.rc == 0 and r.cpu_s < 1 and r.maxrss_kb < 256 * 1024,
            'rc %s, %.2f s of CPU, %d MB' % (r.rc, r.cpu_s, r.maxrss_kb // 1024), r)
    c.done()

    cwd = fresh(os.path.join(root, 'match'))
    c = Case(14, 'lsgd match with 5,000 query images, none readable',
             'an error, no CSV, the first 100 skips listed then counted')
    write(os.path.join(cwd, 'q.txt'), ''.join('m/%d.png\n' % i for i in range(5000)).encode())
    r = c.run(['match', '--reference', seq, '--query', 'q.txt', '--output', 'm.csv'], cwd)
    c.check(r.rc != 0 and 'no image could be read' in r.stderr and r.stderr.count('\n') <= 103,
            'rc %s, %d stderr lines' % (r.rc, r.stderr.count('\n')), r)
    c.check(not os.path.exists(os.path.join(cwd, 'm.csv')), 'a CSV was written')
    c.done()
