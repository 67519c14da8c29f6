"""Files the classes write and read: scratch folders, the corridor copy, CSV
and database dumps, PNG and JPEG bytes, the base folder every class starts
from, and the shared steps of the kill -9 classes."""
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
from hostile import run as _run  # DEMO_SRC as main() sets it


# --------------------------------------------------------------------------
# helpers: files, CSV, databases, images
# --------------------------------------------------------------------------
def fresh(d):
    if os.path.lexists(d):
        subprocess.run(['chmod', '-R', 'u+rwx', d], stderr=subprocess.DEVNULL)
        shutil.rmtree(d)
    os.makedirs(d)
    return d


def write(path, data, mode='wb'):
    os.makedirs(os.path.dirname(path) or '.', exist_ok=True)
    with open(path, mode) as f:
        f.write(data)
    return path


def read(path):
    with open(path, 'rb') as f:
        return f.read()


def copy_corridor(dst):
    """A writable copy of the corridor dataset (sequence.txt, groundtruth.txt, images/)."""
    shutil.copytree(CORR_SRC, dst)
    subprocess.run(['chmod', '-R', 'u+w', dst])
    return dst


def corr_list(d):
    with open(os.path.join(d, 'sequence.txt')) as f:
        return [l.strip() for l in f if l.strip() and not l.startswith('#')]


def read_csv_rows(path):
    """Rows of an lsgd CSV as lists of strings (header dropped); None if missing."""
    if not os.path.isfile(path):
        return None
    with open(path, newline='') as f:
        rows = list(csv.reader(f))
    if rows and rows[0] and rows[0][0] == 'frame':
        rows = rows[1:]
    return rows


def csv_no_ms(rows):
    return [tuple(r[:5] + r[6:]) for r in rows] if rows is not None else None


def csv_text_lines(path):
    if not os.path.isfile(path):
        return None
    return read(path).decode('utf-8', 'replace').split('\n')


def db_dump(path):
    """All rows of frames and meta, read with sqlite3 read-only.  Raises on
    a file SQLite cannot read."""
    con = sqlite3.connect('file:%s?mode=ro' % path, uri=True, timeout=5)
    try:
        frames = con.execute('SELECT * FROM frames ORDER BY id').fetchall()
        meta = dict(con.execute('SELECT key, value FROM meta').fetchall())
    finally:
        con.close()
    return {'frames': frames, 'meta': meta}


def db_dump_copy(path, tmpdir):
    """Dump a copy of PATH (+ -wal) so the original stays untouched."""
    fresh(tmpdir)
    dst = os.path.join(tmpdir, 'x.db')
    shutil.copyfile(path, dst)
    if os.path.exists(path + '-wal'):
        shutil.copyfile(path + '-wal', dst + '-wal')
    return db_dump(dst)


def compare_db(a, b):
    """Differences between two dumps (list of text)."""
    out = []
    fa, fb = a['frames'], b['frames']
    if len(fa) != len(fb):
        out.append('frames rows %d vs %d' % (len(fa), len(fb)))
    for x, y in zip(fa, fb):
        if x != y:
            cols = ['id', 'session', 'name', 'histogram', 'pixels', 'node', 'place', 'features',
                    'crc32', 'loop', 'loop_inliers', 'frame']
            diff = [cols[i] if i < len(cols) else str(i) for i in range(len(x)) if x[i] != y[i]]
            out.append('row id %s differs in %s' % (x[0], ','.join(diff)))
            break
    ma, mb = a['meta'], b['meta']
    # Every database has its own random database_id (it names its log), and
    # the meta checksum covers it: two runs never agree on either. `db info`
    # checks the checksum of each. `checkpoints` counts the writer's
    # checkpoints, which a killed and resumed run takes at other frames.
    own = {'database_id', 'checksum', 'checkpoints'}
    for k in sorted((set(ma) | set(mb)) - own):
        if ma.get(k) != mb.get(k) and k != 'options':
            out.append('meta %s: %r vs %r' % (k, ma.get(k), mb.get(k)))
        elif k == 'options' and ma.get(k) != mb.get(k):
            out.append('meta options differ')
    return out


def png_chunk(tag, data):
    return struct.pack('>I', len(data)) + tag + data + struct.pack('>I', zlib.crc32(tag + data) & 0xffffffff)


def make_png(w, h, bitdepth=8, colortype=0, seed=0):
    """A tiny hand-written PNG encoder (gray or RGB, 8 or 16 bit)."""
    rng = random.Random(seed)
    ch = {0: 1, 2: 3}[colortype]
    bpp = ch * bitdepth // 8
    rows = []
    for y in range(h):
        row = bytearray([0])
        for x in range(w):
            v = (x * 7 + y * 3 + rng.randrange(40)) % 256
            for c in range(ch):
                if bitdepth == 16:
                    row += struct.pack('>H', v * 257)
                else:
                    row.append(v)
        rows.append(bytes(row))
    ihdr = struct.pack('>IIBBBBB', w, h, bitdepth, colortype, 0, 0, 0)
    return (b'\x89PNG\r\n\x1a\n' + png_chunk(b'IHDR', ihdr) +
            png_chunk(b'IDAT', zlib.compress(b''.join(rows))) + png_chunk(b'IEND', b''))


def jpeg_scan_start(data):
    """Offset of the first byte of entropy-coded data (after the first SOS header)."""
    i = 2
    while i + 4 <= len(data):
        if data[i] != 0xFF:
            return None
        m = data[i + 1]
        if m == 0xD8 or 0xD0 <= m <= 0xD7:
            i += 2
            continue
        ln = struct.unpack('>H', data[i + 2:i + 4])[0]
        if m == 0xDA:
            return i + 2 + ln
        i += 2 + ln
    return None


def jpeg_sof_offset(data):
    i = 2
    while i + 4 <= len(data):
        m = data[i + 1]
        ln = struct.unpack('>H', data[i + 2:i + 4])[0]
        if m in (0xC0, 0xC1, 0xC2):
            return i
        i += 2 + ln
    return None


def wait_rows(path, n):
    """kill condition: PATH holds at least n data rows (checked by the spawner)."""
    return (path, n)


# --------------------------------------------------------------------------
# shared base data
# --------------------------------------------------------------------------
BASE = os.path.join(WORK, 'base')


def setup_base():
    fresh(BASE)
    copy_corridor(os.path.join(BASE, 'corr'))
    write(os.path.join(BASE, 'cfg.yaml'), b'verification:\n  max_candidates: 3\n')
    lines = []
    for i in range(222):
        lines.append('1 0 0 %d 0 1 0 0 0 0 1 %d' % (i, i % 7))
    write(os.path.join(BASE, 'poses.txt'), ('\n'.join(lines) + '\n').encode())
    # the reference CSV of the corridor (used as --detections and as reference)
    r = lsgd(['run', '--sequence', 'corr/sequence.txt', '--output', 'ref.csv', '--min-gap', '20'], BASE)
    assert r.rc == 0, r.stderr
    shutil.copyfile(os.path.join(BASE, 'ref.csv'), os.path.join(BASE, 'det.csv'))
    with open(os.path.join(_run.DEMO_SRC, 'sequence.txt')) as f:
        demo = [os.path.join(_run.DEMO_SRC, l.strip()) for l in f if l.strip() and not l.startswith('#')]
    write(os.path.join(BASE, 'demo640.txt'), ('\n'.join(demo[:640]) + '\n').encode())
    write(os.path.join(BASE, 'demo330.txt'), ('\n'.join(demo[:330]) + '\n').encode())
    return demo


# ==========================================================================
# class 1: outputs vs inputs
# ==========================================================================
def spellings(target_abs, cwd, tag):
    """(label, spelling) of TARGET relative to CWD.  Links are created in
    CWD/links.  target need not exist (then no hard link)."""
    links = os.path.join(cwd, 'links')
    os.makedirs(links, exist_ok=True)
    rel = os.path.relpath(target_abs, cwd)
    d = os.path.dirname(rel)
    dd = os.path.basename(os.path.dirname(target_abs))
    out = [('same', rel),
           ('dotdot', os.path.join('.', d, '..', dd, os.path.basename(rel))),
           ('absolute', target_abs)]
    if os.path.exists(target_abs):
        hl = os.path.join(links, 'hl_' + tag)
        if not os.path.lexists(hl):
            os.link(target_abs, hl)
        out.append(('hardlink', os.path.relpath(hl, cwd)))
    sl = os.path.join(links, 'sl_' + tag)
    if not os.path.lexists(sl):
        os.symlink(target_abs, sl)
    out.append(('symlink', os.path.relpath(sl, cwd)))
    dl = os.path.join(links, 'dl_' + tag)
    if not os.path.lexists(dl):
        os.symlink(os.path.dirname(target_abs), dl)
    out.append(('dir-symlink', os.path.join(os.path.relpath(dl, cwd), os.path.basename(target_abs))))
    return out


# ==========================================================================
# class 4: kill -9 and re-run
# ==========================================================================
def info_json(cwd, dbp):
    r = lsgd(['db', 'info', dbp, '--json'], cwd)
    try:
        return r, json.loads(r.stdout)
    except ValueError:
        return r, None


def c4_compare(c, cwd, ref, csvname='c.csv', dbname='d.db', label='final'):
    rows = read_csv_rows(os.path.join(cwd, csvname))
    got = csv_no_ms(rows)
    if got != ref['csv']:
        if got is None:
            c.fail('%s CSV missing' % label)
        else:
            frames = [x[0] for x in got]
            dup = sorted(set(f for f in frames if frames.count(f) > 1), key=int)
            miss = sorted(set(x[0] for x in ref['csv']) - set(frames), key=int)
            first = next((i for i, (a, b) in enumerate(zip(got, ref['csv'])) if a != b), min(len(got), len(ref['csv'])))
            c.fail('%s CSV differs from the uninterrupted run: %d rows vs %d; doubled frames %s; missing frames %s; '
                   'first difference at row %d: %s vs %s' % (
                       label, len(got), len(ref['csv']), dup[:8], miss[:8], first,
                       got[first] if first < len(got) else None,
                       ref['csv'][first] if first < len(ref['csv']) else None))
    raw = read(os.path.join(cwd, csvname)) if os.path.exists(os.path.join(cwd, csvname)) else b''
    if raw.count(b'frame,image,') != 1:
        c.fail('%s CSV holds %d header lines' % (label, raw.count(b'frame,image,')))
    if raw and not raw.endswith(b'\n'):
        c.fail('%s CSV ends in a partial line' % label)
    try:
        dd = db_dump(os.path.join(cwd, dbname))
    except Exception as e:
        c.fail('%s database unreadable by sqlite3: %s' % (label, e))
        return
    diffs = compare_db(dd, ref['db'])
    if diffs:
        c.fail('%s database differs from the uninterrupted run: %s' % (label, '; '.join(diffs[:6])))
    ids = [x[11] for x in dd['frames']]
    if len(ids) != len(set(ids)):
        c.fail('%s database stores a frame twice' % label)
    names = [(x[1], x[2]) for x in dd['frames']]
    if len(names) != len(set(names)):
        c.fail('%s database stores an image twice in one session' % label)
    r, j = info_json(cwd, dbname)
    c.runs.append(r)
    for g in r.generic:
        c.fail(g, r)
    if j is None:
        c.fail('%s: db info --json failed' % label, r)
    else:
        for k in ('frames', 'sessions', 'nodes', 'format_version', 'damage', 'rows_verified'):
            if j.get(k) != ref['info'].get(k):
                c.fail('%s: db info %s = %r, uninterrupted run: %r' % (label, k, j.get(k), ref['info'].get(k)), r)
        if j.get('note'):
            c.fail('%s: db info still has a note after a clean re-run: %r' % (label, j.get('note')), r)
    left = [f for f in os.listdir(cwd) if '.tmp' in f]
    if left:
        c.fail('%s: temporary files left behind: %s' % (label, left))


def c4_reference(cwd, args, timeout=120):
    t = time.monotonic()
    r = lsgd(args, cwd, timeout=timeout)
    T = time.monotonic() - t
    assert r.rc == 0, r.stderr
    _, j = info_json(cwd, 'd.db')
    return {'csv': csv_no_ms(read_csv_rows(os.path.join(cwd, 'c.csv'))), 'db': db_dump(os.path.join(cwd, 'd.db')),
            'info': j, 'T': T}
