"""Class 12 of the hostile campaign (scripts/hostile_campaign.py)."""
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


def class12():
    """Issue 35, the third pass (2026-12-06, as root): read-only outputs, PNG
    chunk bombs, frames of another size, ground-truth pair bombs, NUL in a
    list, lsgd match's skips, many skipped frames."""
    print('\n=== class 12: read-only as root, PNG chunks, pair bombs', flush=True)
    root = fresh(os.path.join(WORK, 'c12'))
    corr = os.path.join(BASE, 'corr')
    names = corr_list(corr)

    def among_good(label, ext, data, expect, budget_mb=256):
        cwd = fresh(os.path.join(root, label.replace(' ', '-')))
        c = Case(12, 'a %s among good frames' % label,
                 'skipped naming it (%s); under %d MB and 5 s' % (expect, budget_mb))
        for i, n in enumerate(names[:6]):
            shutil.copy(os.path.join(corr, n), os.path.join(cwd, '%02d.jpg' % (2 * i)))
        write(os.path.join(cwd, '05' + ext), data)
        r = c.run(['run', '--sequence', cwd, '--output', os.path.join(root, label.replace(' ', '-') + '.csv')], root)
        msg(12, c.name, r)
        c.check(r.rc == 0, 'rc=%s' % r.rc, r)
        c.check(expect in r.stderr and '05' + ext in r.stderr, 'not skipped with "%s"' % expect, r)
        c.check(r.maxrss_kb < budget_mb * 1024, 'used %d MB' % (r.maxrss_kb // 1024), r)
        c.check(r.elapsed < 5, 'took %.1f s' % r.elapsed, r)
        c.done()

    png = make_png(160, 120)
    among_good('PNG whose tEXt claims 2 GB', '.png',
               png[:33] + struct.pack('>I', 0x7FFFFFF0) + b'tEXt' + b'a' * 100, "chunk 'tEXt'")
    rows = b''.join(b'\0' + bytes(160) for _ in range(120))
    surplus = zlib.compressobj(1)
    idat = surplus.compress(rows)
    zeros = bytes(1 << 20)
    for _ in range(400):  # 400 MB of zeros after the rows, ~400 KB compressed
        idat += surplus.compress(zeros)
    idat += surplus.flush()
    among_good('PNG whose IDAT inflates to 400 MB', '.png',
               png[:33] + png_chunk(b'IDAT', idat) + png_chunk(b'IEND', b''), 'IDAT')
    # 8192 x 6144 (the most pixels lsgd reads), in a run of 160 x 120 frames.
    big = b'\x89PNG\r\n\x1a\n' + png_chunk(b'IHDR', struct.pack('>IIBBBBB', 8192, 6144, 8, 0, 0, 0, 0))
    big += png_chunk(b'IDAT', zlib.compress(b''.join(b'\0' + bytes(8192) for _ in range(6144)), 9))
    big += png_chunk(b'IEND', b'')
    among_good('PNG of 8192 x 6144 in a run of 160 x 120', '.png', big, 'nothing was decoded')

    # Read-only outputs and databases: refused by their mode, also for root.
    cwd = fresh(os.path.join(root, 'readonly'))
    c = Case(12, 'a read-only output, output folder and database (the campaign runs as %s)' %
             ('root' if os.geteuid() == 0 else 'a user'), 'refused naming it; nothing changed')
    seq = os.path.join(corr, 'sequence.txt')
    write(os.path.join(cwd, 'ro.csv'), b'keep\n')
    os.chmod(os.path.join(cwd, 'ro.csv'), 0o444)
    os.makedirs(os.path.join(cwd, 'locked'))
    os.chmod(os.path.join(cwd, 'locked'), 0o555)
    for args in (['run', '--sequence', seq, '--last', '5', '--output', 'ro.csv'],
                 ['run', '--sequence', seq, '--last', '5', '--output', 'locked/o.csv'],
                 ['gt', 'stats', os.path.join(corr, 'groundtruth.txt'), '--json', 'ro.csv']):
        r = c.run(args, cwd)
        msg(12, c.name, r)
        c.check(r.rc != 0 and 'read-only' in r.stderr, '%s: not refused' % ' '.join(args[-2:]), r)
    c.check(read(os.path.join(cwd, 'ro.csv')) == b'keep\n', 'ro.csv was changed')
    c.check(not os.path.exists(os.path.join(cwd, 'locked', 'o.csv')), 'written into the read-only folder')
    r = c.run(['run', '--sequence', seq, '--last', '5', '--database', 'd.db', '--output', '/dev/null'], cwd)
    if c.check(r.rc == 0, 'the database was not made', r):
        os.chmod(os.path.join(cwd, 'd.db'), 0o444)
        before = read(os.path.join(cwd, 'd.db'))
        r = c.run(['run', '--sequence', seq, '--first', '6', '--last', '9', '--database', 'd.db',
                   '--output', '/dev/null'], cwd)
        c.check(r.rc != 0 and 'read-only' in r.stderr, 'a read-only database was appended to', r)
        c.check(read(os.path.join(cwd, 'd.db')) == before, 'the database was changed')
        os.chmod(os.path.join(cwd, 'd.db'), 0o644)
    os.chmod(os.path.join(cwd, 'locked'), 0o755)
    c.done()

    # Poses of a robot standing still: every pair, refused while read.
    cwd = fresh(os.path.join(root, 'poses'))
    c = Case(12, 'KITTI poses of a robot standing still (10,000 lines, 240 KB)',
             'refused naming the file; under 256 MB and 5 s')
    write(os.path.join(cwd, 'p.txt'), b'1 0 0 0 0 1 0 0 0 0 1 0\n' * 10000)
    r = c.run(['gt', 'stats', 'p.txt', '--format', 'kitti-poses', '--min-gap', '0'], cwd)
    msg(12, c.name, r)
    c.check(r.rc != 0 and 'p.txt' in r.stderr and 'pairs' in r.stderr, 'not refused naming the file', r)
    c.check(r.maxrss_kb < 256 * 1024, 'used %d MB' % (r.maxrss_kb // 1024), r)
    c.check(r.elapsed < 5, 'took %.1f s' % r.elapsed, r)
    c.done()

    # A NUL inside a list line; lsgd match skipping what it cannot read.
    cwd = fresh(os.path.join(root, 'lists'))
    c = Case(12, 'a list line with a NUL; lsgd match with a missing query image',
             'the list refused naming the line; match skips the image and keeps the others')
    good = [os.path.join(corr, n) for n in names[:8]]
    write(os.path.join(cwd, 'nul.txt'), (good[0] + '\n' + good[1] + '\0junk\n').encode())
    r = c.run(['run', '--sequence', 'nul.txt', '--output', 'n.csv'], cwd)
    msg(12, c.name, r)
    c.check(r.rc != 0 and 'line 2' in r.stderr and 'NUL' in r.stderr, 'not refused naming line 2', r)
    write(os.path.join(cwd, 'ref.txt'), ''.join(g + '\n' for g in good[:4]).encode())
    write(os.path.join(cwd, 'q.txt'), ''.join(g + '\n' for g in [good[4], '/nonexistent.jpg', good[5]]).encode())
    r = c.run(['match', '--reference', 'ref.txt', '--query', 'q.txt', '--output', 'm.csv'], cwd)
    msg(12, c.name, r)
    c.check(r.rc == 0 and 'skipping --query image 1' in r.stderr, 'match did not skip the missing image', r)
    if r.rc == 0:
        queries = sorted(set(int(row[0]) for row in read_csv_rows(os.path.join(cwd, 'm.csv')) if row[0].isdigit()))
        c.check(queries == [4, 6], 'query ids %s, not [4, 6]' % queries)
    c.done()

    # Many missing files: the first 100 listed, the rest counted.
    cwd = fresh(os.path.join(root, 'many'))
    c = Case(12, '5,000 missing files then one image', 'the first 100 skips listed, the rest counted')
    write(os.path.join(cwd, 'l.txt'), (''.join('m%d.png\n' % i for i in range(5000)) + good[0] + '\n').encode())
    r = c.run(['run', '--sequence', 'l.txt', '--output', 'l.csv'], cwd)
    c.check(r.rc == 0 and r.stderr.count('skipped frame ') == 100 and '5000 skipped' in r.stderr,
            'rc %s, %d skip lines' % (r.rc, r.stderr.count('skipped frame ')), r)
    c.done()
