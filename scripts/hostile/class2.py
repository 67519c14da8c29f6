"""Class 2 of the hostile campaign (scripts/hostile_campaign.py)."""
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
# class 2: truncated / corrupt images inside a sequence
# ==========================================================================
SILENT = {'cut': [], 'flip': [], 'other': []}


def c2_check(c, r, csvp, k, imgs, strict, kind, label):
    """imgs: the image strings of the list (for the frame/image check)."""
    rows = read_csv_rows(csvp) or []
    by_frame = {}
    for row in rows:
        try:
            by_frame[int(row[0])] = row
        except (ValueError, IndexError):
            c.fail('unparsable CSV row %r' % row, r)
    skip_re = re.compile(r'skipped frame %d \(' % k)
    said = bool(skip_re.search(r.stderr))
    row = by_frame.get(k)
    if strict:
        c.check(r.rc == 1, 'under --strict the run must exit 1, got rc=%s' % r.rc, r)
        c.check(('frame %d' % k) in r.stderr and os.path.basename(imgs[k]) in r.stderr,
                'the --strict error must name frame %d and its file' % k, r)
        c.check(sorted(by_frame) == list(range(k)),
                'under --strict the CSV must keep rows 0..%d and nothing after; has %d rows, frames %s..%s' % (
                    k - 1, len(by_frame), min(by_frame) if by_frame else None, max(by_frame) if by_frame else None), r)
        return
    c.check(r.rc == 0, 'a skipped frame must not fail the run (rc=%s)' % r.rc, r)
    if not said:
        if row is not None and (row[2] != '-1' or row[3] != '-1'):
            c.fail('SILENTLY ACCEPTED: no "skipped frame %d" on stderr and frame %d has a row with loop=%s candidate=%s' % (
                k, k, row[2], row[3]), r)
            SILENT[kind].append(label)
            c.tags.add('silently-accepted')
        elif row is not None:
            c.fail('no "skipped frame %d" on stderr; frame %d was processed as a real frame (row without a candidate)' % (k, k), r)
            SILENT[kind].append(label + ' (row, no candidate)')
            c.tags.add('silently-accepted')
        else:
            c.fail('no "skipped frame %d" message, and no row', r)
    else:
        c.check(os.path.basename(imgs[k]) in r.stderr, 'the skip message must name the file', r)
        if row is not None:
            c.check(row[2] == '-1', 'the skipped frame has a CSV row declaring loop %s' % row[2], r)
    for f, rw in by_frame.items():
        if f < len(imgs) and not rw[1].endswith(imgs[f].split('/')[-1]):
            c.fail('frame %d row names image %s, expected %s' % (f, rw[1], imgs[f]), r)
            break
    c.check(len(by_frame) in (len(imgs) - 1, len(imgs)), 'expected %d rows, got %d' % (len(imgs) - 1, len(by_frame)), r)


def class2():
    print('\n=== class 2: truncated / corrupt images', flush=True)
    rng = random.Random(SEED + 2)
    root = fresh(os.path.join(WORK, 'c2'))
    corr = copy_corridor(os.path.join(root, 'corr'))
    names = corr_list(corr)

    def variants_jpeg(data, full):
        n = len(data)
        v = []
        for f in (0.01, 0.05, 0.10, 0.20, 0.30, 0.50, 0.70, 0.90, 0.95, 0.99):
            v.append(('cut', 'cut at %d%% (%d of %d bytes)' % (round(f * 100), int(n * f), n), data[:int(n * f)]))
        for d in (1, 2, 3):
            v.append(('cut', 'cut %d byte(s) short' % d, data[:n - d]))
        if not full:
            return v
        ss = jpeg_scan_start(data)
        v.append(('cut', 'cut right at the scan data (%d bytes: headers only)' % ss, data[:ss]))
        v.append(('cut', 'cut one byte into the scan data', data[:ss + 1]))
        for f in (0.3, 0.5, 0.9, 0.99):
            v.append(('cut', 'cut at %d%% + an end-of-image marker appended' % round(f * 100),
                      data[:int(n * f)] + b'\xff\xd9'))
        for f in (0.3, 0.5, 0.9):
            v.append(('cut', 'cut at %d%% then zero-filled to full length (crash after size update)' % round(f * 100),
                      data[:int(n * f)] + b'\0' * (n - int(n * f))))
        mid = ss + (n - ss) // 2
        v.append(('flip', 'a 1 KiB block zeroed in the middle of the scan, end marker intact (torn write)',
                  data[:mid] + b'\0' * 1024 + data[mid + 1024:]))
        v.append(('other', 'zero-byte file', b''))
        v.append(('other', 'a text file named .jpg', b'this is not an image\n' * 20))
        v.append(('other', 'two JPEGs concatenated, the first cut at 50%', data[:n // 2] + data))
        sof = jpeg_sof_offset(data)
        for off, what in ((0, 'SOI byte 0'), (1, 'SOI byte 1'), (sof + 5, 'SOF height high byte'),
                          (sof + 6, 'SOF height low byte'), (sof + 7, 'SOF width high byte'),
                          (sof + 9, 'SOF component count'), (ss - 1, 'last SOS header byte')):
            b = bytearray(data)
            b[off] ^= 0xFF
            v.append(('flip', 'byte %d flipped (%s)' % (off, what), bytes(b)))
        for off in sorted(rng.sample(range(n), 20)):
            b = bytearray(data)
            b[off] ^= 0xFF
            where = 'header' if off < ss else ('end marker' if off >= n - 2 else 'entropy-coded data')
            v.append(('flip', 'byte %d of %d flipped (%s)' % (off, n, where), bytes(b)))
        return v

    # --- JPEG sequence (corridor) ---
    for k in (120, 160, 200):
        path = os.path.join(corr, names[k])
        orig = read(path)
        for kind, label, data in variants_jpeg(orig, k == 160):
            for strict in ((False, True) if (k == 160 and kind == 'cut') or (k == 120 and 'cut at 50%' in label) else (False,)):
                c = Case(2, 'JPEG frame %d: %s%s' % (k, label, ' --strict' if strict else ''),
                         'frame %d reported skipped on stderr with its index; no loop in its row; --strict: exit 1, '
                         'rows 0..%d kept' % (k, k - 1))
                write(path, data)
                csvp = os.path.join(root, 'out.csv')
                if os.path.exists(csvp):
                    os.remove(csvp)
                args = ['run', '--sequence', 'corr/sequence.txt', '--output', 'out.csv', '--min-gap', '20']
                if strict:
                    args.append('--strict')
                r = c.run(args, root)
                c2_check(c, r, csvp, k, names, strict, kind, 'JPEG %d %s' % (k, label))
                if kind == 'flip' and 'silently-accepted' in c.tags:
                    c.tags.add('debatable: JPEG has no checksum' if 'entropy' in label or 'zeroed' in label
                               else 'header flip accepted')
                c.done()
                write(path, orig)

    # --- PNG sequence (demo-s1, first 330 frames) ---
    with open(os.path.join(BASE, 'demo330.txt')) as f:
        demo = [l.strip() for l in f if l.strip()]
    pdir = fresh(os.path.join(root, 'png'))
    for k in (310, 320):
        orig = read(demo[k])
        n = len(orig)
        lst = list(demo)
        local = os.path.join(pdir, os.path.basename(demo[k]))
        lst[k] = local
        write(os.path.join(pdir, 'seq.txt'), ('\n'.join(lst) + '\n').encode())
        v = []
        for fr in (0.01, 0.05, 0.10, 0.30, 0.50, 0.90, 0.99):
            v.append(('cut', 'cut at %d%% (%d of %d bytes)' % (round(fr * 100), int(n * fr), n), orig[:int(n * fr)]))
        for d in (1, 4, 12, 13):
            v.append(('cut', 'cut %d byte(s) short%s' % (d, ' (IEND gone)' if d == 12 else ''), orig[:n - d]))
        if k == 310:
            iend = png_chunk(b'IEND', b'')
            v.append(('cut', 'cut at 50% + a valid IEND chunk appended', orig[:n // 2] + iend))
            v.append(('cut', 'cut at 90% then zero-filled to full length', orig[:int(n * .9)] + b'\0' * (n - int(n * .9))))
            for off in sorted(rng.sample(range(8, n), 20)) + [0, 3, 8, 16, 20, n - 5]:
                b = bytearray(orig)
                b[off] ^= 0xFF
                v.append(('flip', 'byte %d of %d flipped' % (off, n), bytes(b)))
        for kind, label, data in v:
            for strict in ((False, True) if kind == 'cut' and k == 310 else (False,)):
                c = Case(2, 'PNG frame %d: %s%s' % (k, label, ' --strict' if strict else ''),
                         'frame %d reported skipped with its index; no loop in its row; --strict: exit 1' % k)
                write(local, data)
                csvp = os.path.join(pdir, 'out.csv')
                if os.path.exists(csvp):
                    os.remove(csvp)
                args = ['run', '--sequence', 'seq.txt', '--output', 'out.csv', '--min-gap', '20']
                if strict:
                    args.append('--strict')
                r = c.run(args, pdir, timeout=90)
                c2_check(c, r, csvp, k, lst, strict, kind, 'PNG %d %s' % (k, label))
                c.done()
    info(2, 'silently accepted cut lengths', '%d: %s' % (len(SILENT['cut']), SILENT['cut']))
    info(2, 'silently accepted byte flips', '%d: %s' % (len(SILENT['flip']), SILENT['flip']))
    info(2, 'silently accepted other', '%d: %s' % (len(SILENT['other']), SILENT['other']))
