"""Class 13 of the hostile campaign (scripts/hostile_campaign.py)."""
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


def mat5_with_cell(cells, compressed):
    """A little-endian v5 MAT file: a cell 'c' claiming `cells` elements (one
    stored), then a 4x4 double 'GT' with GT(3, 0) = GT(2, 1) = 1."""
    def el(t, b):
        return struct.pack('<II', t, len(b)) + b + bytes((8 - len(b) % 8) % 8)

    def matrix(cls, dims, name, data):
        body = el(6, struct.pack('<II', cls, 0)) + el(5, struct.pack('<%dI' % len(dims), *dims)) + el(1, name) + data
        return struct.pack('<II', 14, len(body)) + body
    gt = [0.0] * 16
    gt[3] = gt[6] = 1.0
    elements = [matrix(1, [cells, 1], b'c', matrix(6, [0, 0], b'', b'')),
                matrix(6, [4, 4], b'GT', el(9, struct.pack('<16d', *gt)))]
    if compressed:
        elements = [struct.pack('<II', 15, len(zlib.compress(e))) + zlib.compress(e) for e in elements]
    return b'MATLAB 5.0 MAT-file'.ljust(116, b' ') + bytes(8) + b'\x00\x01IM' + b''.join(elements)


def class13():
    """Issue 35, found after the third pass (2026-12-06): a MAT cell that
    claims 6 GB (CI's fuzz_gt), lsgd match decoding an image of another size,
    a list of 200,000 missing images, Python objects made by __new__ alone."""
    print('\n=== class 13: MAT cells, match sizes, missing lists, bare __new__', flush=True)
    root = fresh(os.path.join(WORK, 'c13'))
    corr = os.path.join(BASE, 'corr')
    names = corr_list(corr)

    cwd = fresh(os.path.join(root, 'mat'))
    c = Case(13, 'a MAT v5 cell claiming 0x30000004 elements beside the ground truth',
             'the ground truth read (2 pairs); the cell, named, refused as not square; under 256 MB')
    for z in (False, True):
        f = 'cell%s.mat' % ('-z' if z else '')
        write(os.path.join(cwd, f), mat5_with_cell(0x30000004, z))
        r = c.run(['gt', 'convert', f, '--output', f + '.txt'], cwd)
        msg(13, c.name, r)
        if c.check(r.rc == 0, '%s: rc %s' % (f, r.rc), r):
            pairs = [l for l in read(os.path.join(cwd, f + '.txt')).decode().splitlines() if l and l[0].isdigit()]
            c.check(sorted(pairs) == ['2 1', '3 0'], '%s: pairs %s' % (f, pairs))
        c.check(r.maxrss_kb < 256 * 1024, 'used %d MB' % (r.maxrss_kb // 1024), r)
        r = c.run(['gt', 'stats', f, '--variable', 'c'], cwd)
        c.check(r.rc != 0 and 'class 1 is not a square' in r.stderr, '%s: the cell was not refused' % f, r)
    c.done()

    cwd = fresh(os.path.join(root, 'match'))
    c = Case(13, 'lsgd match with an 8192 x 6144 PNG among 160 x 120 queries',
             'skipped from its header (nothing decoded); under 256 MB and 5 s')
    good = [os.path.join(corr, n) for n in names[:6]]
    big = b'\x89PNG\r\n\x1a\n' + png_chunk(b'IHDR', struct.pack('>IIBBBBB', 8192, 6144, 8, 0, 0, 0, 0))
    big += png_chunk(b'IDAT', zlib.compress(b''.join(b'\0' + bytes(8192) for _ in range(6144)), 9))
    big += png_chunk(b'IEND', b'')
    write(os.path.join(cwd, 'big.png'), big)
    write(os.path.join(cwd, 'ref.txt'), ''.join(g + '\n' for g in good[:3]).encode())
    write(os.path.join(cwd, 'q.txt'), (good[3] + '\nbig.png\n' + good[4] + '\n').encode())
    r = c.run(['match', '--reference', 'ref.txt', '--query', 'q.txt', '--output', 'm.csv'], cwd)
    msg(13, c.name, r)
    c.check(r.rc == 0 and 'skipping --query image 1' in r.stderr and 'nothing was decoded' in r.stderr,
            'not skipped from its header', r)
    c.check(r.maxrss_kb < 256 * 1024, 'used %d MB' % (r.maxrss_kb // 1024), r)
    c.check(r.elapsed < 5, 'took %.1f s' % r.elapsed, r)
    c.done()

    cwd = fresh(os.path.join(root, 'missing'))
    c = Case(13, 'a list of 200,000 missing images (1.1 MB)',
             '"no frame was processed", counting them; under 256 MB and 4 s of CPU (6.5 s before; '
             'CPU time, as a wall clock moves with whatever else runs)')
    write(os.path.join(cwd, 'l.txt'), ''.join('%x\n' % i for i in range(200000)).encode())
    r = c.run(['run', '--sequence', 'l.txt', '--output', 'l.csv'], cwd)
    c.check(r.rc != 0 and 'all 200000 images were skipped' in r.stderr, 'rc %s' % r.rc, r)
    c.check(r.maxrss_kb < 256 * 1024, 'used %d MB' % (r.maxrss_kb // 1024), r)
    c.check(r.cpu_s < 4, 'took %.1f s of CPU (%.1f s)' % (r.cpu_s, r.elapsed), r)
    c.done()

    c = Case(13, 'Python: every lsgd class made by X.__new__(X) or object.__new__(X), then used',
             'a TypeError each time; never a crash')
    pypath = os.environ.get('LSGD_PYTHONPATH', os.path.join(REPO, 'build', 'python'))
    code = (
        'import lsgd, sys\n'
        'made = []\n'
        'for c in vars(lsgd._lsgd).values():\n'
        '    if not isinstance(c, type) or issubclass(c, BaseException): continue\n'
        '    for new in (c.__new__, object.__new__):\n'
        '        try: o = new(c)\n'
        '        except TypeError: continue\n'
        '        made.append(c.__name__)\n'
        '        for a in dir(o):\n'
        '            try: getattr(o, a)\n'
        '            except Exception: pass\n'
        'print(" ".join(made) or "none")\n')
    if not os.path.isdir(os.path.join(pypath, 'lsgd')):
        info(13, c.name, 'skipped: no Python module at %s (LSGD_PYTHONPATH)' % pypath)
    else:
        p = subprocess.run(['/usr/bin/python3', '-c', code], env=dict(os.environ, PYTHONPATH=pypath),
                           capture_output=True, text=True, timeout=120)
        c.check(p.returncode == 0 and p.stdout.strip() == 'none',
                'rc %s, made without __init__: %s %s' % (p.returncode, p.stdout.strip(), p.stderr[-300:]))
    c.done()
