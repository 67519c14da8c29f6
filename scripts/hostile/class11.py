"""Class 11 of the hostile campaign (scripts/hostile_campaign.py)."""
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


def class11():
    """Issue 35: a dead database's leftovers, decompression bombs, companions
    that are not files, line endings of other systems."""
    print('\n=== class 11: leftovers, bombs, line ends', flush=True)
    root = fresh(os.path.join(WORK, 'c11'))
    corr = os.path.join(BASE, 'corr')
    seq = os.path.join(corr, 'sequence.txt')

    # A writer killed, its file deleted, its log left: a new database there refuses it.
    cwd = fresh(os.path.join(root, 'stale'))
    c = Case(11, 'a database deleted after its writer was killed; a new one at its path',
             'refused naming the -wal left beside it; no database created; the log untouched')
    c.run(['run', '--sequence', seq, '--database', 'd.db', '--output', 'c.csv', '--min-gap', '20'],
          cwd, timeout=120, kill_when=wait_rows(os.path.join(cwd, 'c.csv'), 45))
    wal = os.path.join(cwd, 'd.db-wal')
    if c.check(os.path.isfile(wal) and os.path.getsize(wal) > 0, 'the killed writer left no log (harness)'):
        before = read(wal)
        os.remove(os.path.join(cwd, 'd.db'))
        r = c.run(['run', '--sequence', seq, '--database', 'd.db', '--output', 'c2.csv', '--min-gap', '20'], cwd)
        msg(11, c.name, r)
        c.check(r.rc != 0, 'accepted (rc 0): the new database may hold the dead one\'s frames', r)
        c.check('d.db-wal' in r.stderr, 'the message does not name the log', r)
        c.check(not os.path.exists(os.path.join(cwd, 'd.db')), 'a database was created', r)
        c.check(read(wal) == before, 'the log was changed', r)
    c.done()

    # Another SQLite database's hot rollback journal (a transaction cut off by
    # a kill) at the path: a new database there, and a database beside one,
    # refuse it (SQLite would roll its pages back into the file).
    cwd = fresh(os.path.join(root, 'journal'))
    c = Case(11, "a killed SQLite writer's rollback journal at a new database's path, then beside a database",
             'refused naming the -journal; no database created; the journal and the file untouched')
    jpath = os.path.join(cwd, 'd.db')
    code = ("import os, sqlite3, sys\n"
            "c = sqlite3.connect(sys.argv[1], isolation_level=None)\n"
            "c.execute('PRAGMA journal_mode=DELETE'); c.execute('CREATE TABLE t(x BLOB)')\n"
            "for i in range(50): c.execute('INSERT INTO t VALUES (randomblob(3000))')\n"
            "c.execute('PRAGMA cache_size=1'); c.execute('BEGIN'); c.execute('UPDATE t SET x = randomblob(3000)')\n"
            "for i in range(50): c.execute('INSERT INTO t VALUES (randomblob(3000))')\n"
            "os._exit(0)\n")
    subprocess.run(['/usr/bin/python3', '-c', code, jpath], check=True)
    journal = jpath + '-journal'
    if c.check(os.path.isfile(journal) and os.path.getsize(journal) > 0, 'no hot journal was left (harness)'):
        os.remove(jpath)
        before = read(journal)
        r = c.run(['run', '--sequence', seq, '--database', 'd.db', '--output', 'c.csv', '--min-gap', '20'], cwd)
        msg(11, c.name, r)
        c.check(r.rc != 0 and 'd.db-journal' in r.stderr, 'a new database was not refused naming the journal', r)
        c.check(not os.path.exists(jpath), 'a database was created', r)
        c.check(read(journal) == before, 'the journal was changed', r)
        os.rename(journal, journal + '.old')
        r = c.run(['run', '--sequence', seq, '--database', 'd.db', '--output', 'c.csv', '--min-gap', '20',
                   '--last', '30'], cwd)
        c.check(r.rc == 0, 'without the journal no database is made', r)
        shutil.copyfile(journal + '.old', journal)
        file_before = read(jpath)
        for args in (['db', 'info', 'd.db'],
                     ['run', '--sequence', seq, '--database', 'd.db', '--output', 'c2.csv', '--min-gap', '20']):
            r = c.run(args, cwd, skip_inputs=['d.db-journal'])
            msg(11, c.name, r)
            c.check(r.rc != 0 and 'd.db-journal' in r.stderr, '%s: not refused naming the journal' % args[0], r)
        c.check(read(jpath) == file_before, 'the database was changed')
        c.check(read(journal) == before, 'the journal was changed')
    c.done()

    # Another database's log beside a file (two killed writers of the same
    # options, other images): it would replay without damage; refused.
    cwd = fresh(os.path.join(root, 'foreign'))
    c = Case(11, "a killed writer's file beside another killed writer's log (same options)",
             'refused by readers and writers naming the log; nothing changed; moved away, the file opens')
    for name, first in (('a', '0'), ('b', '60')):
        c.run(['run', '--sequence', seq, '--database', name + '.db', '--output', name + '.csv',
               '--min-gap', '20', '--first', first], cwd, timeout=120,
              kill_when=wait_rows(os.path.join(cwd, name + '.csv'), 45))
    logs = [os.path.join(cwd, n + '.db-wal') for n in ('a', 'b')]
    if c.check(all(os.path.isfile(w) and os.path.getsize(w) > 0 for w in logs),
               'a killed writer left no log (harness)'):
        shutil.copyfile(logs[1], logs[0])
        for f in ('a.db-shm',):
            if os.path.exists(os.path.join(cwd, f)):
                os.remove(os.path.join(cwd, f))
        before = read(os.path.join(cwd, 'a.db'))
        for args in (['db', 'info', 'a.db'],
                     ['run', '--sequence', seq, '--database', 'a.db', '--output', 'a2.csv', '--min-gap', '20']):
            r = c.run(args, cwd, skip_inputs=['a.db-wal'])
            msg(11, c.name, r)
            c.check(r.rc != 0 and 'a.db-wal' in r.stderr and 'another database' in r.stderr,
                    '%s: not refused naming the log' % args[0], r)
        c.check(read(os.path.join(cwd, 'a.db')) == before, 'the file was changed')
        if os.path.exists(logs[0]):  # a writer that took the log in has emptied it
            os.rename(logs[0], logs[0] + '.b')
        r = c.run(['db', 'info', 'a.db'], cwd)
        c.check(r.rc == 0, 'the file alone does not open', r)
    c.done()

    # A database on a read-only file system (a mount namespace; skipped where
    # the machine allows none): readable, exactly.
    cwd = fresh(os.path.join(root, 'readonly'))
    c = Case(11, 'db info and run --localize on a database on a read-only file system',
             'read (the file as immutable), the same frames as where it was written')
    r = c.run(['run', '--sequence', seq, '--database', 'd.db', '--output', 'c.csv', '--last', '30'], cwd)
    probe = subprocess.run(['unshare', '-m', 'true'], capture_output=True)
    if probe.returncode != 0:
        print('  (skipped: no mount namespace here)', flush=True)
    else:
        script = ('mount --bind "$0" "$0" && mount -o remount,ro,bind "$0" && '
                  '"$1" db info "$0/d.db" && "$1" run --database "$0/d.db" --localize --sequence "$2" '
                  '--output "$3" --last 5')
        p2 = subprocess.run(['unshare', '-m', 'sh', '-c', script, cwd, LSGD, seq, os.path.join(root, 'loc.csv')],
                            capture_output=True, text=True, timeout=120)
        c.check(p2.returncode == 0 and 'frames: 31' in p2.stdout,
                'not read: rc %d, %s' % (p2.returncode, (p2.stderr or p2.stdout)[-300:]))
    c.done()

    # A companion that is a folder.
    cwd = fresh(os.path.join(root, 'walfolder'))
    c = Case(11, 'db info with d.db-wal a folder', 'refused naming d.db-wal')
    c.run(['run', '--sequence', seq, '--database', 'd.db', '--output', 'c.csv', '--last', '30'], cwd)
    os.makedirs(os.path.join(cwd, 'd.db-wal'))
    r = c.run(['db', 'info', 'd.db'], cwd)
    msg(11, c.name, r)
    c.check(r.rc != 0 and 'd.db-wal\' is a directory' in r.stderr, 'not refused naming the folder', r)
    c.done()

    # Decompression bombs beside good images: skipped from the header, cheaply.
    def sof_resized(data, w, h):
        at = jpeg_sof_offset(data)
        return data[:at + 5] + struct.pack('>HH', h, w) + data[at + 9:]
    good = read(os.path.join(corr, corr_list(corr)[0]))
    bombs = {
        'progressive JPEG 30000 x 30000': None,
        'baseline JPEG 65500 x 65500': sof_resized(good, 65500, 65500),
        'PNG 30000 x 30000': make_png(8, 8)[:16] + struct.pack('>II', 30000, 30000) + make_png(8, 8)[24:],
        'PGM 30000 x 30000': b'P5\n30000 30000\n255\n' + bytes(512),
    }
    # A progressive JPEG: the good frame's header with SOF2 in place of SOF0
    # (its scans then fail, after the size is read).
    at = jpeg_sof_offset(good)
    bombs['progressive JPEG 30000 x 30000'] = sof_resized(good[:at + 1] + b'\xC2' + good[at + 2:], 30000, 30000)
    for label, data in bombs.items():
        cwd = fresh(os.path.join(root, 'bomb-' + label.split()[0].lower() + label.split()[1].lower()))
        c = Case(11, 'a %s among good frames' % label,
                 'skipped from its header naming it; under 256 MB and 1 s for it')
        names = corr_list(corr)[:6]
        for i, n in enumerate(names):
            shutil.copy(os.path.join(corr, n), os.path.join(cwd, '%02d.jpg' % (2 * i)))
        ext = '.png' if label.startswith('PNG') else '.pgm' if label.startswith('PGM') else '.jpg'
        write(os.path.join(cwd, '05' + ext), data)
        r = c.run(['run', '--sequence', cwd, '--output', os.path.join(root, label.split()[0] + '.csv')], root)
        msg(11, c.name, r)
        c.check(r.rc == 0, 'rc=%s' % r.rc, r)
        c.check('declares' in r.stderr and '05' + ext in r.stderr, 'not skipped from its header', r)
        c.check(r.maxrss_kb < 256 * 1024, 'used %d MB' % (r.maxrss_kb // 1024), r)
        c.check(r.elapsed < 5, 'took %.1f s' % r.elapsed, r)
        c.done()

    # Detections with CR-only (classic Mac) and CRLF line endings score as with LF.
    cwd = fresh(os.path.join(root, 'ends'))
    c = Case(11, 'a detections file with CR-only or CRLF line endings', 'the same metrics as with LF')
    rows = ['query,match,score'] + ['%d,%d,0.9' % (q, q - 1) for q in range(5, 40)]
    write(os.path.join(cwd, 'gt.txt'), ''.join('%d %d\n' % (q, q - 1) for q in range(5, 40)).encode())
    got = {}
    for name, end in (('lf', '\n'), ('cr', '\r'), ('crlf', '\r\n')):
        write(os.path.join(cwd, name + '.csv'), (end.join(rows) + end).encode())
        r = c.run(['eval', '--detections', name + '.csv', '--gt', 'gt.txt', '--min-gap', '0', '--json',
                   name + '.json'], cwd)
        if c.check(r.rc == 0, '%s: rc=%s' % (name, r.rc), r):
            with open(os.path.join(cwd, name + '.json')) as f:
                got[name] = json.load(f)['recall_at_1']
    c.check(len(set(got.values())) == 1 and got.get('lf', 0) > 0, 'recall differs: %s' % got)
    c.done()
