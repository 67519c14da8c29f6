"""Class 16 of the hostile campaign (scripts/hostile_campaign.py)."""
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


def tiff_tiled(tile_w, tile_h, side=64):
    """A little-endian 8-bit gray TIFF of SIDE x SIDE pixels in tiles of TILE_W x TILE_H, 64 bytes of data."""
    data = bytes(64)
    entries = [(256, 4, side), (257, 4, side), (258, 3, 8), (259, 3, 1), (262, 3, 1), (277, 3, 1),
               (322, 4, tile_w), (323, 4, tile_h), (324, 4, 8), (325, 4, len(data))]
    ifd = struct.pack('<H', len(entries))
    for tag, typ, val in entries:
        ifd += struct.pack('<HHIHH', tag, typ, 1, val, 0) if typ == 3 else struct.pack('<HHII', tag, typ, 1, val)
    return b'II*\0' + struct.pack('<I', 8 + len(data)) + data + ifd + struct.pack('<I', 0)


def class16():
    """Issue 35, the eighth pass (2026-12-07): numbers with leading zeros,
    lsgd demo --output through a folder that does not exist yet, 16-bit,
    large-tile and many-scan images under 1 MB, db forget --frames as typed,
    scores and poses whose span overflows, a NUL byte in a config, a flag
    given twice."""
    print('\n=== class 16: decimal numbers, demo folders, deep and tiled images, configs', flush=True)
    root = fresh(os.path.join(WORK, 'c16'))
    corr = copy_corridor(os.path.join(root, 'corr'))
    names = corr_list(corr)

    cwd = fresh(os.path.join(root, 'padded'))
    c = Case(16, 'lsgd run --first 010 --last 011 on images 000.jpg .. 011.jpg',
             'frames 10 and 11, images 010.jpg and 011.jpg (CLI11 read 010 as octal 8)')
    for i in range(12):
        shutil.copy(os.path.join(corr, names[i]), os.path.join(cwd, '%03d.jpg' % i))
    r = c.run(['run', '--sequence', '.', '--first', '010', '--last', '011', '--output', os.path.join(root, 'p.csv')], cwd)
    rows = read_csv_rows(os.path.join(root, 'p.csv')) or []
    c.check(r.rc == 0 and [os.path.basename(row[1]) for row in rows] == ['010.jpg', '011.jpg'],
            'rows name %s' % [row[1] for row in rows], r)
    c.done()

    cwd = fresh(os.path.join(root, 'demo'))
    c = Case(16, 'lsgd demo --output new/.. where the folder holds notes.txt and a sequence.txt',
             'refused as the folder itself is (it wrote its files there, replacing sequence.txt)')
    write(os.path.join(cwd, 'sequence.txt'), b'mine.png\n')
    write(os.path.join(cwd, 'notes.txt'), b'mine\n')
    r = c.run(['demo', '--mode', 'exhaustive', '--output', 'new/..'], cwd, timeout=120,
              extra_inputs=['sequence.txt', 'notes.txt'])
    msg(16, c.name, r)
    c.check(r.rc != 0 and "it holds 'notes.txt'" in r.stderr, 'not refused', r)
    c.check(not os.path.exists(os.path.join(cwd, 'images')), 'images were written')
    c.done()

    big16 = b'\x89PNG\r\n\x1a\n' + png_chunk(b'IHDR', struct.pack('>IIBBBBB', 8192, 6144, 16, 6, 0, 0, 0))
    big16 += png_chunk(b'IDAT', zlib.compress(b''.join(b'\0' + bytes(8192 * 8) for _ in range(6144)), 9))
    big16 += png_chunk(b'IEND', b'')
    for label, ext, data, needle in (('a 16-bit RGBA PNG of 8192 x 6144 pixels (391 KB)', '.png', big16, '16-bit samples'),
                                     ('a TIFF of 64 x 64 pixels in tiles of 32768 x 32752 (180 bytes)', '.tiff',
                                      tiff_tiled(32768, 32752), 'declares tiles of 32768 x 32752')):
        cwd = fresh(os.path.join(root, 'deep' + ext[1:]))
        c = Case(16, '%s among good frames' % label,
                 'skipped from its header naming it; under 256 MB and 1 s (458 MB and 2.3 s; 4.3 GB and 12 s)')
        for i, n in enumerate(names[:6]):
            shutil.copy(os.path.join(corr, n), os.path.join(cwd, '%02d.jpg' % (2 * i)))
        write(os.path.join(cwd, '05' + ext), data)
        r = c.run(['run', '--sequence', cwd, '--output', os.path.join(root, ext[1:] + '.csv')], root)
        msg(16, c.name, r)
        c.check(r.rc == 0 and needle in r.stderr and 'nothing was decoded' in r.stderr, 'not skipped from its header', r)
        c.check(r.maxrss_kb < 256 * 1024 and r.elapsed < 1, 'used %d MB, %.1f s' % (r.maxrss_kb // 1024, r.elapsed), r)
        c.done()

    cwd = fresh(os.path.join(root, 'scans'))
    c = Case(16, 'a progressive JPEG of 4096 x 4096 pixels repeating its last scan 1000 times (99 KB)',
             'skipped naming the damage; under 256 MB and 1 s (14 s before)')
    try:
        from PIL import Image   # the progressive encoder; the case is skipped without it
        buf = io.BytesIO()
        Image.new('L', (4096, 4096), 128).save(buf, 'JPEG', progressive=True, quality=90)
        jpeg = buf.getvalue()
        eoi, last = jpeg.rindex(b'\xff\xd9'), jpeg.rindex(b'\xff\xda')
        write(os.path.join(cwd, 'scans.jpg'), jpeg[:eoi] + jpeg[last:eoi] * 1000 + jpeg[eoi:])
        write(os.path.join(cwd, 'list.txt'), b'scans.jpg\n')
        r = c.run(['run', '--sequence', 'list.txt', '--output', 's.csv'], cwd)
        msg(16, c.name, r)
        c.check('damaged JPEG' in r.stderr and 'scans.jpg' in r.stderr, 'not refused as damaged', r)
        c.check(r.maxrss_kb < 256 * 1024 and r.elapsed < 1, 'used %d MB, %.1f s' % (r.maxrss_kb // 1024, r.elapsed), r)
    except ImportError:
        info(16, c.name, 'skipped: no PIL to write a progressive JPEG')
    c.done()

    cwd = fresh(os.path.join(root, 'forget'))
    c = Case(16, "lsgd db forget --frames ' 5:' (a space before the id)",
             'refused naming the value before the database is opened; the database unchanged')
    r = c.run(['run', '--sequence', os.path.join(corr, 'sequence.txt'), '--last', '20', '--database', 'd.db'], cwd)
    before = db_dump(os.path.join(cwd, 'd.db'))
    r = c.run(['db', 'forget', 'd.db', '--frames', ' 5:'], cwd)
    msg(16, c.name, r)
    c.check(r.rc != 0 and "' 5' is not a frame id" in r.stderr, 'not refused', r)
    c.check(db_dump(os.path.join(cwd, 'd.db')) == before, 'the database changed')
    c.done()

    cwd = fresh(os.path.join(root, 'span'))
    c = Case(16, 'detections scored +-1e308, and --poses at x = +-1e308, under eval --report',
             "refused naming the line or the file (the report's charts were '-nan', exit 0)")
    write(os.path.join(cwd, 'g.txt'), b'4 0\n5 1\n7 3\n')
    write(os.path.join(cwd, 'd.csv'), b'query,match,score\n4,0,1e308\n5,1,-1e308\n7,3,1\n')
    r = c.run(['eval', '--detections', 'd.csv', '--gt', 'g.txt', '--min-gap', '1', '--frames', '8',
               '--json', 'd.json', '--report', 'd.html'], cwd)
    msg(16, c.name, r)
    c.check(r.rc != 0 and 'd.csv:2: score 1e308 is beyond' in r.stderr, 'the scores were not refused', r)
    seq = os.path.join(BASE, 'corr', 'sequence.txt')
    n = len(corr_list(os.path.join(BASE, 'corr')))
    write(os.path.join(cwd, 'poses.txt'), ''.join('1 0 0 %s 0 1 0 0 0 0 1 0\n' % ('1e308' if i % 2 else '-1e308')
                                                  for i in range(n)).encode())
    r = c.run(['eval', '--sequence', seq, '--gt', os.path.join(BASE, 'corr', 'groundtruth.txt'), '--min-gap', '20',
               '--json', 'p.json', '--report', 'p.html', '--poses', 'poses.txt'], cwd)
    msg(16, c.name, r)
    c.check(r.rc != 0 and 'more than a double holds' in r.stderr and 'poses.txt' in r.stderr,
            'the poses were not refused', r)
    c.check(not os.path.exists(os.path.join(cwd, 'p.json')), 'the run went on')
    c.done()

    cwd = fresh(os.path.join(root, 'config'))
    c = Case(16, 'a config with a NUL byte; a flag given twice',
             "'a NUL byte on line 2'; '--min-gap is given more than once' (yaml-cpp: 'unknown escape "
             "character'; CLI11: 'At Most 1 required')")
    write(os.path.join(cwd, 'nul.yaml'), b'search:\n  mode: nodes\0\n')
    r = c.run(['options', '--config', 'nul.yaml'], cwd)
    msg(16, c.name, r)
    c.check(r.rc != 0 and 'a NUL byte on line 2' in r.stderr, 'the NUL byte not said', r)
    r = c.run(['options', '--min-gap', '5', '--min-gap', '6'], cwd)
    msg(16, c.name, r)
    c.check(r.rc != 0 and '--min-gap is given more than once' in r.stderr, 'the flag given twice not said', r)
    c.done()
