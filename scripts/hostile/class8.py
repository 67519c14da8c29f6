"""Class 8 of the hostile campaign (scripts/hostile_campaign.py)."""
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
# class 8: zero-frame runs; dangling and looping links
# ==========================================================================
def class8():
    print('\n=== class 8: zero-frame runs, broken links', flush=True)
    rng = random.Random(SEED + 8)
    root = fresh(os.path.join(WORK, 'c8'))
    corr = os.path.join(BASE, 'corr')
    names = corr_list(corr)
    write(os.path.join(root, 'gt.txt'), b'5 0\n6 1\n')
    # sequences that can give no frame
    seqs = {}
    junk = []
    for i in range(12):
        junk.append(''.join(rng.choice('abcdefghij klmnop%$&*()[]{}:;,.<>?') for _ in range(rng.randint(3, 40))).strip() or 'x')
    write(os.path.join(root, 'garbage.txt'), ('\n'.join(junk) + '\n').encode())
    seqs['a garbage list file'] = 'garbage.txt'
    write(os.path.join(root, 'binary.txt'), bytes(rng.randrange(256) for _ in range(4000)))
    seqs['a binary file as list'] = 'binary.txt'
    seqs['the ground truth as --sequence'] = os.path.join(corr, 'groundtruth.txt')
    d16 = os.path.join(root, 'png16')
    os.makedirs(d16)
    for i in range(12):
        write(os.path.join(d16, '%03d.png' % i), make_png(64, 48, 16, 0, seed=i))
    seqs['a folder of 16-bit gray PNGs'] = 'png16'
    d16c = os.path.join(root, 'png16rgb')
    os.makedirs(d16c)
    for i in range(12):
        write(os.path.join(d16c, '%03d.png' % i), make_png(64, 48, 16, 2, seed=i))
    seqs['a folder of 16-bit RGB PNGs'] = 'png16rgb'
    os.makedirs(os.path.join(root, 'empty'))
    seqs['an empty folder'] = 'empty'
    os.makedirs(os.path.join(root, 'txtonly'))
    for i in range(5):
        write(os.path.join(root, 'txtonly', '%d.txt' % i), b'x\n')
    seqs['a folder without images'] = 'txtonly'
    write(os.path.join(root, 'missing.txt'), ('\n'.join('nowhere/%04d.jpg' % i for i in range(12)) + '\n').encode())
    seqs['a list whose images are all missing'] = 'missing.txt'
    write(os.path.join(root, 'emptylist.txt'), b'')
    seqs['an empty list file'] = 'emptylist.txt'
    write(os.path.join(root, 'comments.txt'), b'# nothing\n\n   \n# more\n')
    seqs['a list of comments and blank lines'] = 'comments.txt'
    dl = os.path.join(root, 'alldangling')
    os.makedirs(dl)
    for i in range(12):
        os.symlink('/nonexistent/%d.jpg' % i, os.path.join(dl, '%03d.jpg' % i))
    seqs['a folder of dangling symlinks only'] = 'alldangling'
    zl = os.path.join(root, 'zerobytes')
    os.makedirs(zl)
    for i in range(12):
        write(os.path.join(zl, '%03d.jpg' % i), b'')
    seqs['a folder of zero-byte .jpg files'] = 'zerobytes'

    for label, sq in seqs.items():
        for cmd in ('run', 'eval', 'sweep', 'run --database'):
            for f in ('o.csv', 'o.json', 'new.db'):
                if os.path.exists(os.path.join(root, f)):
                    os.remove(os.path.join(root, f))
            c = Case(8, '%s: %s' % (cmd, label), 'exit non-zero ("no frame was processed" or a clear error); no metrics; '
                                                 'a database it created is removed')
            if cmd == 'run':
                args = ['run', '--sequence', sq, '--output', 'o.csv', '--min-gap', '1']
            elif cmd == 'eval':
                args = ['eval', '--sequence', sq, '--gt', 'gt.txt', '--min-gap', '1', '--json', 'o.json']
            elif cmd == 'sweep':
                args = ['sweep', '--dataset', 'x=%s,gt.txt,1' % sq, '--json', 'o.json']
            else:
                args = ['run', '--sequence', sq, '--output', 'o.csv', '--min-gap', '1', '--database', 'new.db']
            r = c.run(args, root)
            c.check(r.rc not in (0, None), 'expected a non-zero exit, got rc=%s' % r.rc, r)
            if cmd == 'eval':
                c.check(not os.path.exists(os.path.join(root, 'o.json')), 'eval wrote metrics for a run without frames', r)
            if cmd == 'sweep' and os.path.exists(os.path.join(root, 'o.json')):
                try:
                    j = json.load(open(os.path.join(root, 'o.json')))
                    info(8, c.name, 'sweep exit %s but left a --json with %d rows (not counted: the brief asks only '
                         'for a non-zero exit)' % (r.rc, len(j.get('rows', []))))
                except ValueError:
                    pass
            if cmd == 'run --database':
                left = [f for f in os.listdir(root) if f.startswith('new.db')]
                c.check(not left, 'database files left behind: %s' % left, r)
            if r.rc not in (0, None):
                c.check(len(r.stderr.strip().splitlines()) >= 1, 'no message', r)
                if 'folder' in label or 'list' in label:
                    pass
            msg(8, c.name, r)
            c.done()
    # an existing database and a sequence of 16-bit images: nothing stored, database unchanged
    cwd = fresh(os.path.join(root, 'existing'))
    r0 = lsgd(['run', '--sequence', os.path.join(corr, 'sequence.txt'), '--database', 'd.db', '--output', 'c.csv',
               '--min-gap', '20'], cwd)
    dump0 = db_dump(os.path.join(cwd, 'd.db'))
    c = Case(8, 'run --database EXISTING with a folder of 16-bit PNGs', 'exit 1, nothing stored, database content unchanged')
    r = c.run(['run', '--sequence', d16, '--database', 'd.db', '--output', 'c2.csv', '--min-gap', '20'], cwd)
    c.check(r.rc == 1, 'rc=%s' % r.rc, r)
    c.check(not compare_db(db_dump(os.path.join(cwd, 'd.db')), dump0), 'the database changed', r)
    c.check('processed 0' not in r.stdout + r.stderr or 'no frame' in r.stderr, 'says it processed frames', r)
    msg(8, c.name, r)
    c.done()
    # control: the same encoder at 8 bit gives frames
    d8 = os.path.join(root, 'png8')
    os.makedirs(d8)
    for i in range(12):
        write(os.path.join(d8, '%03d.png' % i), make_png(64, 48, 8, 0, seed=i))
    c = Case(8, 'control: a folder of 8-bit PNGs from the same encoder is processed', 'exit 0, 12 rows')
    r = c.run(['run', '--sequence', 'png8', '--output', 'o8.csv', '--min-gap', '1'], root)
    c.check(r.rc == 0 and len(read_csv_rows(os.path.join(root, 'o8.csv')) or []) == 12, 'rc=%s' % r.rc, r)
    c.done()

    # ---- dangling / looping links keep their place ----
    link_setups = [
        ('dangling 0050, looping 0060, good link 0080', {50: 'dangling', 60: 'loop', 80: 'goodlink'}),
        ('0070.jpg a symlink to a folder', {70: 'dirlink'}),
        ('0090.jpg a folder (not a link)', {90: 'dir'}),
        ('dangling first image 0000', {0: 'dangling'}),
        ('looping last image 0221', {221: 'loop'}),
        ('dangling 0100 and 0101, self-link 0102', {100: 'dangling', 101: 'dangling', 102: 'self'}),
        ('link chain 0030 -> a -> b -> missing', {30: 'chain'}),
    ]
    for si, (label, links) in enumerate(link_setups):
        cwd = fresh(os.path.join(root, 'links%d' % si))
        imgs = os.path.join(cwd, 'imgs')
        shutil.copytree(os.path.join(corr, 'images'), imgs)
        for i, how in links.items():
            p = os.path.join(imgs, '%04d.jpg' % i)
            os.remove(p)
            if how == 'dangling':
                os.symlink('/nonexistent/x%d.jpg' % i, p)
            elif how == 'loop':
                os.symlink('%04d.lnk' % i, p)
                os.symlink('%04d.jpg' % i, os.path.join(imgs, '%04d.lnk' % i))
            elif how == 'self':
                os.symlink('%04d.jpg' % i, p)
            elif how == 'dirlink':
                os.symlink(cwd, p)
            elif how == 'dir':
                os.makedirs(p)
            elif how == 'goodlink':
                os.symlink(os.path.join(corr, 'images', '%04d.jpg' % i), p)
            elif how == 'chain':
                os.symlink('c1.lnk', p)
                os.symlink('c2.lnk', os.path.join(imgs, 'c1.lnk'))
                os.symlink('/nonexistent/c3', os.path.join(imgs, 'c2.lnk'))
        bad = sorted(i for i, h in links.items() if h != 'goodlink')
        for cmd in ('run', 'run --strict', 'eval', 'run --database'):
            c = Case(8, '%s, folder with %s' % (cmd, label),
                     'each broken link reported with its index; image i stays frame i; --strict stops at the first')
            for f in ('o.csv', 'o.json', 'd.db', 'd.db-wal', 'd.db-shm'):
                if os.path.exists(os.path.join(cwd, f)):
                    os.remove(os.path.join(cwd, f))
            if cmd.startswith('run'):
                args = ['run', '--sequence', 'imgs', '--output', 'o.csv', '--min-gap', '20']
                if 'strict' in cmd:
                    args.append('--strict')
                if 'database' in cmd:
                    args += ['--database', 'd.db']
            else:
                args = ['eval', '--sequence', 'imgs', '--gt', os.path.join(corr, 'groundtruth.txt'), '--min-gap', '20',
                        '--json', 'o.json', '--output', 'o.csv']
            r = c.run(args, cwd)
            rows = read_csv_rows(os.path.join(cwd, 'o.csv')) or []
            if 'strict' in cmd:
                c.check(r.rc == 1, '--strict: rc=%s' % r.rc, r)
                c.check(('frame %d' % bad[0]) in r.stderr, '--strict error does not name frame %d' % bad[0], r)
                c.check([int(x[0]) for x in rows] == list(range(bad[0])), '--strict kept rows %s..' % (
                    [x[0] for x in rows[:1]]), r)
            else:
                c.check(r.rc == 0, 'rc=%s' % r.rc, r)
                for b in bad:
                    c.check(re.search(r'skipped frame %d \(' % b, r.stderr) is not None,
                            'no "skipped frame %d" for the broken link %04d.jpg' % (b, b), r)
                wrong = [(x[0], os.path.basename(x[1])) for x in rows if os.path.basename(x[1]) != '%04d.jpg' % int(x[0])]
                c.check(not wrong, 'frame ids moved: %s' % wrong[:4], r)
                c.check(len(rows) == 222 - len(bad), '%d rows, expected %d' % (len(rows), 222 - len(bad)), r)
                if cmd == 'eval' and os.path.exists(os.path.join(cwd, 'o.json')):
                    j = json.load(open(os.path.join(cwd, 'o.json')))
                    c.check(j.get('frames') == 222 and j.get('skipped_frames') == len(bad),
                            'eval JSON frames=%s skipped=%s' % (j.get('frames'), j.get('skipped_frames')), r)
                if 'database' in cmd and r.rc == 0:
                    d = db_dump(os.path.join(cwd, 'd.db'))
                    fr = sorted(x[11] for x in d['frames'])
                    c.check(fr == sorted(int(x[0]) for x in rows), 'database ids differ from the CSV', r)
            msg(8, c.name, r)
            c.done()
