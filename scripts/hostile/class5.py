"""Class 5 of the hostile campaign (scripts/hostile_campaign.py)."""
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
# class 5: write-ahead-log damage, damaged database file
# ==========================================================================
LOSS_WORDS = ('lost', 'replayed', 'stopped before closing', 'never closed', 'missing')


def class5():
    print('\n=== class 5: WAL damage and database damage', flush=True)
    rng = random.Random(SEED + 5)
    root = fresh(os.path.join(WORK, 'c5'))
    seq = os.path.join(BASE, 'corr', 'sequence.txt')
    args = ['run', '--sequence', seq, '--database', 'd.db', '--output', 'c.csv', '--min-gap', '20']
    ref = c4_reference(fresh(os.path.join(root, 'ref')), args)
    # the snapshot: a run killed with recent frames in d.db-wal
    snap = None
    for attempt, n in enumerate((150, 152, 156, 148, 170)):
        sd = fresh(os.path.join(root, 'snap'))
        r = lsgd(args, sd, kill_when=wait_rows(os.path.join(sd, 'c.csv'), n))
        wal = os.path.join(sd, 'd.db-wal')
        if r.killed and os.path.exists(wal) and os.path.getsize(wal) > 32 + 4096 * 4:
            S = len(db_dump_copy(os.path.join(sd, 'd.db'), os.path.join(root, 'peek'))['frames'])
            base_frames = len(db_dump_copy(os.path.join(sd, 'd.db'), os.path.join(root, 'peek2'))['frames']) if False else None
            snap = sd
            break
    if snap is None:
        c = Case(5, 'set-up: a killed run leaving frames in the WAL', 'a WAL with frames')
        c.fail('could not produce a killed run with a non-empty WAL')
        c.done()
        return
    wal_bytes = read(os.path.join(snap, 'd.db-wal'))
    # committed frames in the main file alone (the last checkpoint)
    pk = fresh(os.path.join(root, 'peek3'))
    shutil.copyfile(os.path.join(snap, 'd.db'), os.path.join(pk, 'x.db'))
    S0 = len(db_dump(os.path.join(pk, 'x.db'))['frames'])
    nrows = len(read_csv_rows(os.path.join(snap, 'c.csv')))
    W = len(wal_bytes)
    pgsz = struct.unpack('>I', wal_bytes[8:12])[0]
    fsz = 24 + pgsz
    nfr = (W - 32) // fsz
    print('  snapshot: %d CSV rows, %d committed frames (%d in the main file), WAL %d bytes = %d log frames of %d' % (
        nrows, S, S0, W, nfr, pgsz))
    info(5, 'snapshot', '%d CSV rows, %d committed frames (%d checkpointed in the main file), WAL %d bytes, %d log frames' % (
        nrows, S, S0, W, nfr))

    damages = [('WAL deleted', lambda p: os.remove(p))]
    # the -shm deleted (harmless control) and both deleted
    damages.append(('-shm deleted (control)', lambda p: os.remove(p[:-4] + '-shm')))
    damages.append(('WAL and -shm deleted', lambda p: (os.remove(p), os.remove(p[:-4] + '-shm'))))
    cuts = sorted(set([0, 16, 31, 32, 32 + 10, 32 + 24, 32 + fsz - 1, 32 + fsz, 32 + fsz + 100, 32 + 2 * fsz,
                       32 + (nfr // 3) * fsz, 32 + (nfr // 2) * fsz + 7, 32 + (nfr - 1) * fsz, W - 1, W - 100]))
    for L in cuts:
        if 0 <= L < W:
            damages.append(('WAL truncated to %d of %d bytes' % (L, W),
                            (lambda L: lambda p: os.truncate(p, L))(L)))
    offs = [0, 3, 8, 12, 16, 20, 24, 28, 32, 36, 40, 44, 48, 52, 56, 32 + fsz + 4, W - 1]
    last_commit = None
    for i in range(nfr):
        o = 32 + i * fsz
        if struct.unpack('>I', wal_bytes[o + 4:o + 8])[0] != 0:
            last_commit = o
    if last_commit is not None:
        offs += [last_commit + 4, last_commit + 7, last_commit + 24 + 100]
    offs += sorted(rng.sample(range(W), 20))
    for o in offs:
        def flip(p, o=o):
            b = bytearray(read(p))
            b[o] ^= 0xFF
            write(p, bytes(b))
        where = 'WAL header' if o < 32 else ('log frame %d %s' % ((o - 32) // fsz, 'header' if (o - 32) % fsz < 24 else 'page'))
        damages.append(('WAL byte %d flipped (%s)' % (o, where), flip))

    for i, (label, dmg) in enumerate(damages):
        cwd = fresh(os.path.join(root, 'w%02d' % i))
        for f in os.listdir(snap):
            shutil.copyfile(os.path.join(snap, f), os.path.join(cwd, f))
        dmg(os.path.join(cwd, 'd.db-wal'))
        c = Case(5, '%s, then db info and the same command' % label,
                 'db info refuses naming the database or says frames were lost/replayed; the re-run ends equal '
                 'to the uninterrupted run; no silent loss')
        ri = c.run(['db', 'info', 'd.db', '--json'], cwd)
        rt = c.run(['db', 'info', 'd.db'], cwd)
        msg(5, label + ': db info', rt)
        F = None
        note = ''
        if ri.rc == 0:
            try:
                j = json.loads(ri.stdout)
                F = j.get('frames')
                note = j.get('note') or ''
            except ValueError:
                c.fail('db info --json exit 0 but not JSON', ri)
            if F is not None and F < S and not any(w in note for w in LOSS_WORDS):
                c.fail('SILENT LOSS in db info: %d frames reported, %d were committed, note %r' % (F, S, note), ri)
            if F is not None and F > S:
                c.fail('db info reports %d frames, more than the %d committed' % (F, S), ri)
        else:
            c.check('d.db' in rt.stderr, 'db info refused without naming the database', rt)
            c.check(not any(x in rt.stderr for x in ('another process',)), 'db info claims another process', rt)
        r2 = c.run(args, cwd)
        msg(5, label + ': re-run', r2)
        said = ri.stderr + rt.stdout + rt.stderr + r2.stderr + r2.stdout
        if r2.rc != 0:
            c.check('d.db' in r2.stderr, 're-run refused without naming the database', r2)
            if os.path.exists(os.path.join(cwd, 'd.db-wal')):
                os.rename(os.path.join(cwd, 'd.db-wal'), os.path.join(cwd, 'moved-away.wal'))
            r3 = c.run(args, cwd)
            msg(5, label + ': re-run after moving d.db-wal away', r3)
            said += r3.stderr + r3.stdout
            c.check(r3.rc == 0, 're-run after moving the WAL away failed rc=%s' % r3.rc, r3)
            fin = r3
        else:
            fin = r2
        # frames the re-run found in the database before it continued
        m = re.search(r'resumed d\.db: (\d+) frames stored', said)
        found = int(m.group(1)) if m else None
        if found is not None and found < S and 'lost' not in said:
            if found == S - 1 and any(w in said for w in LOSS_WORDS):
                # only the last commit is gone: indistinguishable from a kill while it was being written
                # (a torn last log frame); the tool said it replayed the log and re-processes the frame
                info(5, label, 'the last committed frame (%d) was dropped with only a "replayed" note, not "lost"; '
                     'the re-run processed it again (end state equal). Indistinguishable from a torn last write.' % (S - 1))
                c.tags.add('last commit dropped, said as replayed')
            else:
                c.fail('SILENT LOSS on re-run: the database held %d of the %d committed frames and no message said '
                       'frames were lost' % (found, S), fin)
        c4_compare(c, cwd, ref, label='after re-run')
        c.done()

    # --- byte flips and truncation in the main database file (clean, closed) ---
    refdb = os.path.join(root, 'ref', 'd.db')
    orig = read(refdb)
    orig_dump = db_dump(refdb)
    n = len(orig)
    pg = struct.unpack('>H', orig[16:18])[0]
    pg = 65536 if pg == 1 else pg
    offs = [0, 5, 15, 16, 17, 18, 19, 20, 21, 24, 28, 29, 30, 31, 32, 36, 40, 44, 47, 48, 52, 56, 60, 64, 68, 92,
            96, 99, 100, 101, 103, 105, 107, pg, pg + 1, pg + 8, 2 * pg + 3, n - 1, n - pg]
    offs += sorted(rng.sample(range(n), 30))
    for k, o in enumerate(offs):
        cwd = fresh(os.path.join(root, 'f%02d' % k))
        b = bytearray(orig)
        b[o] ^= 0xFF
        write(os.path.join(cwd, 'd.db'), bytes(b))
        c = Case(5, 'main database byte %d of %d flipped (page %d): db info' % (o, n, o // pg + 1),
                 'db info exits 1 naming the file and the damage, unless the flip changed nothing SQLite reads')
        r = c.run(['db', 'info', 'd.db'], cwd)
        try:
            same = db_dump(os.path.join(cwd, 'd.db')) == orig_dump
        except Exception as e:
            same = False
        if r.rc == 0:
            if not same:
                c.fail('DAMAGED FILE REPORTED FINE: db info exit 0 but the content SQLite reads differs '
                       'from the original (or SQLite cannot read it)', r)
            else:
                c.tags.add('flip in unused/ignored bytes: content identical')
        else:
            c.check(r.rc == 1, 'expected exit 1, got %s' % r.rc, r)
            c.check('d.db' in r.stderr, 'the error does not name the file', r)
        if k % 3 == 0:
            r2 = c.run(args, cwd)
            if r2.rc == 0 and not same:
                c.fail('lsgd run resumed a damaged database (exit 0)', r2)
            if r2.rc != 0:
                c.check('d.db' in r2.stderr, 'run refused the damaged file without naming it', r2)
        c.done()
    for L in (0, 1, 50, 99, 100, 101, pg - 1, pg, pg + 1, 3 * pg, n // 2, n - pg, n - 1):
        cwd = fresh(os.path.join(root, 't%06d' % L))
        write(os.path.join(cwd, 'd.db'), orig[:L])
        c = Case(5, 'main database truncated to %d of %d bytes: db info' % (L, n), 'exit 1 naming the file')
        r = c.run(['db', 'info', 'd.db'], cwd)
        c.check(r.rc == 1 and 'd.db' in r.stderr, 'expected exit 1 naming d.db, got rc=%s' % r.rc, r)
        c.done()
