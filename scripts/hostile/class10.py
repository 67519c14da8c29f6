"""Class 10 of the hostile campaign (scripts/hostile_campaign.py)."""
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
from hostile.run import _rows_at_least


# ==========================================================================
# class 10: messages
# ==========================================================================
DAMAGE_WORDS = ('damag', 'corrupt', 'truncat', 'lost', 'held 7', 'but the database held')


def class10():
    print('\n=== class 10: messages', flush=True)
    root = fresh(os.path.join(WORK, 'c10'))
    corr = os.path.join(BASE, 'corr')
    cseq = os.path.join(corr, 'sequence.txt')
    dseq = os.path.join(BASE, 'demo640.txt')
    args = ['run', '--sequence', dseq, '--database', 'd.db', '--output', 'a.csv', '--min-gap', '20']
    ref = c4_reference(fresh(os.path.join(root, 'ref')), ['run', '--sequence', dseq, '--database', 'd.db', '--output',
                                                         'c.csv', '--min-gap', '20'])

    # ---- a second writer while one runs ----
    seconds = [
        ('the same sequence, another --output', lambda: ['run', '--sequence', dseq, '--database', 'd.db', '--output', 'b.csv',
                                                          '--min-gap', '20'], 20),
        ('the identical command (same --output a.csv)', lambda: list(args), 20),
        ('--session 5', lambda: ['run', '--sequence', dseq, '--database', 'd.db', '--output', 'b.csv', '--min-gap', '20',
                                 '--session', '5'], 40),
        ('another sequence (corridor, another size)', lambda: ['run', '--sequence', cseq, '--database', 'd.db', '--output',
                                                                'b.csv', '--min-gap', '20'], 60),
        ('a different spelling of the database (./x/../d.db)', lambda: ['run', '--sequence', dseq, '--database',
                                                                        './sub/../d.db', '--output', 'b.csv', '--min-gap', '20'], 80),
        ('the database through a symlink', lambda: ['run', '--sequence', dseq, '--database', 'link.db', '--output', 'b.csv',
                                                    '--min-gap', '20'], 100),
        ('the identical command, near the end of the first', lambda: list(args), 560),
    ]
    for i, (label, mk, at_rows) in enumerate(seconds):
        cwd = fresh(os.path.join(root, 'w%d' % i))
        os.makedirs(os.path.join(cwd, 'sub'))
        os.symlink('d.db', os.path.join(cwd, 'link.db'))
        c = Case(10, 'second writer (%s) while a run writes d.db' % label,
                 'the second exits non-zero saying another process is writing (no claim of damage), touches neither '
                 'the database nor the first run\'s CSV; the first run ends equal to an uninterrupted run')
        A = Started(args, cwd, 'A')
        t0 = time.monotonic()
        while not _rows_at_least(os.path.join(cwd, 'a.csv'), at_rows) and time.monotonic() - t0 < 60:
            time.sleep(0.005)
        a_rows_at_start = len(read_csv_rows(os.path.join(cwd, 'a.csv')) or [])
        B = c.run(mk(), cwd, timeout=60)
        ra = A.finish(timeout=120)
        if B.rc == 0 and 'nothing to do' in B.stderr + B.stdout:
            info(10, c.name, 'the first writer was near its end (%d CSV rows when the second started); the second '
                 'waited for the writer lock, then found every frame stored and said "nothing to do" '
                 '(timing; not counted)' % a_rows_at_start, B)
            c4_compare(c, cwd, ref, csvname='a.csv', label='first writer')
            c.done()
            continue
        c.runs.append(ra)
        for g in ra.generic:
            c.fail('first writer: ' + g, ra)
        if not _rows_at_least(os.path.join(cwd, 'a.csv'), 640) or ra.rc != 0:
            c.check(ra.rc == 0, 'the first writer failed rc=%s' % ra.rc, ra)
        c.check(B.rc not in (0, None), 'the second writer exit %s' % B.rc, B)
        c.check('another process' in B.stderr, 'the second writer does not say another process is writing', B)
        c.check(not any(w in B.stderr for w in DAMAGE_WORDS), 'the second writer claims damage/loss', B)
        c.check('d.db' in B.stderr or 'link.db' in B.stderr, 'the message does not name the database', B)
        ref_a = {'csv': ref['csv'], 'db': ref['db'], 'info': ref['info']}
        c4_compare(c, cwd, ref_a, csvname='a.csv', label='first writer')
        msg(10, c.name, B)
        c.done()
    # two writers starting together on a database that does not exist yet
    for i, delay in enumerate((0.0, 0.02, 0.1)):
        cwd = fresh(os.path.join(root, 'race%d' % i))
        c = Case(10, 'two writers create the same new database (second %.2f s after the first)' % delay,
                 'one creates and runs, the other exits non-zero with a clear message; the database and the '
                 'winner\'s CSV equal an uninterrupted run')
        A = Started(args, cwd, 'A')
        time.sleep(delay)
        B = c.run(['run', '--sequence', dseq, '--database', 'd.db', '--output', 'b.csv', '--min-gap', '20'], cwd, timeout=120)
        ra = A.finish(timeout=120)
        c.runs.append(ra)
        for g in ra.generic:
            c.fail('first writer: ' + g, ra)
        ok = [x for x, r in (('a.csv', ra), ('b.csv', B)) if r.rc == 0]
        c.check(len(ok) >= 1, 'neither writer succeeded (rc %s / %s)' % (ra.rc, B.rc), B)
        if len(ok) == 2:
            # both exited 0: one must have continued the other's session (sequential), never a double store
            pass
        for r in (ra, B):
            if r.rc not in (0, None):
                c.check(not any(w in r.stderr for w in DAMAGE_WORDS), 'the loser claims damage: %s' % r.stderr.strip()[:200], r)
        try:
            dd = db_dump(os.path.join(cwd, 'd.db'))
            diffs = compare_db(dd, ref['db'])
            c.check(not diffs, 'database differs from an uninterrupted run: %s' % '; '.join(diffs[:4]), B)
        except Exception as e:
            c.fail('database unreadable: %s' % e, B)
        if len(ok) == 1:
            got = csv_no_ms(read_csv_rows(os.path.join(cwd, ok[0])))
            c.check(got == ref['csv'], 'the winner\'s CSV differs from the uninterrupted run', B)
        left = [f for f in os.listdir(cwd) if '.tmp' in f]
        c.check(not left, 'temporary files left: %s' % left, B)
        msg(10, c.name + ' [first]', ra)
        msg(10, c.name + ' [second]', B)
        c.done()
    # a reader beside the writer
    cwd = fresh(os.path.join(root, 'reader'))
    c = Case(10, 'db info while a run writes', 'exit 0 with a consistent count (<= CSV rows), no damage claimed')
    A = Started(args, cwd, 'A')
    t0 = time.monotonic()
    while not _rows_at_least(os.path.join(cwd, 'a.csv'), 100) and time.monotonic() - t0 < 60:
        time.sleep(0.005)
    for k in range(3):
        r = c.run(['db', 'info', 'd.db', '--json'], cwd, skip_inputs=['d.db', 'd.db-wal'])  # a writer is running
        nrows = len(read_csv_rows(os.path.join(cwd, 'a.csv')) or [])
        c.check(r.rc == 0, 'db info beside a writer exit %s' % r.rc, r)
        try:
            j = json.loads(r.stdout)
            c.check(j['frames'] <= nrows, 'db info reports %d frames but the CSV has %d rows' % (j['frames'], nrows), r)
            c.check(not j.get('damage'), 'db info reports damage beside a writer: %r' % j.get('damage'), r)
        except (ValueError, KeyError):
            c.fail('db info --json unreadable', r)
        time.sleep(0.3)
    ra = A.finish(timeout=120)
    c.check(ra.rc == 0, 'the writer failed rc=%s' % ra.rc, ra)
    msg(10, c.name, r)
    c.done()

    # ---- empty names ----
    gt = os.path.join(corr, 'groundtruth.txt')
    empties = [
        ("--database ''", ['run', '--sequence', cseq, '--database', '', '--output', 'o.csv'], '--database'),
        ("--output ''", ['run', '--sequence', cseq, '--output', ''], '--output'),
        ("--sequence ''", ['run', '--sequence', '', '--output', 'o.csv'], '--sequence'),
        ("--config ''", ['run', '--sequence', cseq, '--config', '', '--output', 'o.csv'], '--config'),
        ("eval --json ''", ['eval', '--sequence', cseq, '--gt', gt, '--min-gap', '20', '--json', ''], '--json'),
        ("eval --gt ''", ['eval', '--sequence', cseq, '--gt', '', '--min-gap', '20', '--json', 'o.json'], '--gt'),
        ("eval --output ''", ['eval', '--sequence', cseq, '--gt', gt, '--min-gap', '20', '--json', 'o.json', '--output', ''], '--output'),
        ("eval --report ''", ['eval', '--sequence', cseq, '--gt', gt, '--min-gap', '20', '--json', 'o.json', '--report', ''], '--report'),
        ("eval --detections ''", ['eval', '--detections', '', '--gt', gt, '--min-gap', '20', '--json', 'o.json'], '--detections'),
        ("db info ''", ['db', 'info', ''], 'FILE'),
        ("gt convert '' --output x", ['gt', 'convert', '', '--output', 'x.txt'], 'SOURCE'),
        ("gt stats X --json ''", ['gt', 'stats', gt, '--json', ''], '--json'),
        ("sweep --csv ''", ['sweep', '--dataset', 'c=%s,20' % corr, '--csv', ''], '--csv'),
        ("demo --output ''", ['demo', '--output', ''], '--output'),
        ("bench --json ''", ['bench', '--frames', '5', '--warmup', '0', '--width', '64', '--height', '48', '--opencv-frames', '0',
                             '--json', ''], '--json'),
    ]
    cwd = fresh(os.path.join(root, 'empty'))
    for label, a, flag in empties:
        c = Case(10, label, 'exit non-zero before any work, the message names %s' % flag)
        r = c.run(a, cwd, timeout=120)
        c.check(r.rc not in (0, None), 'exit %s' % r.rc, r)
        c.check('processed' not in r.stdout + r.stderr, 'work was done', r)
        c.check(flag in r.stderr or (flag == 'FILE' and ('FILE' in r.stderr or 'database' in r.stderr)) or
                (flag == 'SOURCE' and ('SOURCE' in r.stderr or 'ground truth' in r.stderr)),
                'the message does not name %s' % flag, r)
        c.check(not os.listdir(cwd), 'files were written: %s' % os.listdir(cwd), r)
        for f in os.listdir(cwd):
            p = os.path.join(cwd, f)
            shutil.rmtree(p) if os.path.isdir(p) else os.remove(p)
        msg(10, c.name, r)
        c.done()

    # ---- --session 2^53 - 1 ----
    cwd = fresh(os.path.join(root, 'session'))
    shutil.copytree(corr, os.path.join(cwd, 'corr2'))
    big = '9007199254740991'
    sargs = ['run', '--sequence', cseq, '--database', 's.db', '--output', 's.csv', '--min-gap', '20', '--session', big]
    c = Case(10, '--session %s on a new database' % big, 'exit 0; db info shows the session id exactly')
    r = c.run(sargs, cwd)
    c.check(r.rc == 0, 'rc=%s' % r.rc, r)
    rj, j = info_json(cwd, 's.db')
    c.runs.append(rj)
    c.check(j is not None and [s['session'] for s in j.get('sessions', [])] == [int(big)],
            'db info --json sessions %s' % (j.get('sessions') if j else None), rj)
    rt = c.run(['db', 'info', 's.db'], cwd)
    c.check(('session %s' % big) in rt.stdout, 'db info text does not print session %s' % big, rt)
    rows = read_csv_rows(os.path.join(cwd, 's.csv')) or []
    c.check([int(x[0]) for x in rows] == list(range(len(rows))), 'frame ids are not 0.. in session %s' % big, r)
    msg(10, c.name, r)
    c.done()
    c = Case(10, '--session %s: kill -9, then the same command resumes' % big, 'the session continues; equal to uninterrupted')
    cwd2 = fresh(os.path.join(root, 'session-kill'))
    refrows = csv_no_ms(read_csv_rows(os.path.join(cwd, 's.csv')))
    refdb = db_dump(os.path.join(cwd, 's.db'))
    r = c.run(sargs, cwd2, kill_rows=(os.path.join(cwd2, 's.csv'), 90))
    r2 = c.run(sargs, cwd2)
    c.check(r2.rc == 0, 'resume rc=%s' % r2.rc, r2)
    c.check(csv_no_ms(read_csv_rows(os.path.join(cwd2, 's.csv'))) == refrows, 'CSV differs from the uninterrupted run', r2)
    c.check(not compare_db(db_dump(os.path.join(cwd2, 's.db')), refdb), 'database differs', r2)
    msg(10, c.name, r2)
    c.done()
    c = Case(10, '--session %s: the same command again' % big, 'exit 0, "nothing to do", nothing changed')
    before = db_dump(os.path.join(cwd, 's.db'))
    r = c.run(sargs, cwd)
    c.check(r.rc == 0, 'rc=%s' % r.rc, r)
    c.check(not compare_db(db_dump(os.path.join(cwd, 's.db')), before), 'the database changed', r)
    msg(10, c.name, r)
    c.done()
    c = Case(10, 'after session %s, a new sequence without --session (last session + 1 overflows)' % big,
             'refused (exit non-zero) naming the session limit; nothing stored')
    before = db_dump(os.path.join(cwd, 's.db'))
    r = c.run(['run', '--sequence', 'corr2/sequence.txt', '--database', 's.db', '--output', 's2.csv', '--min-gap', '20'], cwd)
    after = db_dump(os.path.join(cwd, 's.db'))
    if r.rc == 0:
        sess = sorted(set(x[1] for x in after['frames']))
        c.fail('accepted: sessions now %s' % sess, r)
    else:
        c.check(not compare_db(after, before), 'the database changed', r)
        c.check(big in r.stderr or '2^53' in r.stderr or 'session' in r.stderr, 'the message does not mention the session limit', r)
    msg(10, c.name, r)
    c.done()
    for bad in ('9007199254740992', '-1', '1e3', '18446744073709551616'):
        c = Case(10, '--session %s' % bad, 'rejected, naming --session and the value')
        r = c.run(['run', '--sequence', cseq, '--database', 'x.db', '--output', 'x.csv', '--session', bad], cwd)
        c.check(r.rc not in (0, None), 'exit %s' % r.rc, r)
        c.check('--session' in r.stderr or 'session' in r.stderr, 'the message does not name --session', r)
        c.check(not os.path.exists(os.path.join(cwd, 'x.db')), 'a database was created', r)
        msg(10, c.name, r)
        c.done()

    # ---- resuming with images of another size ----
    cwd = fresh(os.path.join(root, 'size'))
    with open(dseq) as f:
        demo = [l.strip() for l in f if l.strip()]
    write(os.path.join(cwd, 'demo50.txt'), ('\n'.join(demo[:50]) + '\n').encode())
    r0 = lsgd(['run', '--sequence', cseq, '--database', 'd.db', '--output', 'c.csv', '--min-gap', '20'], cwd)
    for label, extra in (('automatic session', []), ('--session 1', ['--session', '1'])):
        c = Case(10, 'resume a 160x120 database with 320x240 images (%s)' % label,
                 'exit 1 "no frame was processed" naming the size; no claim that frames were processed; database unchanged')
        before = db_dump(os.path.join(cwd, 'd.db'))
        r = c.run(['run', '--sequence', 'demo50.txt', '--database', 'd.db', '--output', 'o.csv', '--min-gap', '20'] + extra, cwd)
        c.check(r.rc == 1, 'rc=%s' % r.rc, r)
        m = re.search(r'processed (\d+) frames', r.stdout + r.stderr)
        c.check(not (m and int(m.group(1)) > 0), 'claims %s frames were processed' % (m.group(1) if m else ''), r)
        c.check('320x240' in r.stderr or '160x120' in r.stderr, 'the message does not name the sizes', r)
        c.check(not compare_db(db_dump(os.path.join(cwd, 'd.db')), before), 'the database changed', r)
        msg(10, c.name, r)
        c.done()
    mixed = [os.path.join(corr, n) for n in corr_list(corr)[:30]] + demo[:5] + [os.path.join(corr, n) for n in corr_list(corr)[30:40]]
    write(os.path.join(cwd, 'mixed.txt'), ('\n'.join(mixed) + '\n').encode())
    c = Case(10, 'a sequence with 5 images of another size in the middle', 'each reported skipped with its index and both sizes; ids keep their place')
    r = c.run(['run', '--sequence', 'mixed.txt', '--output', 'm.csv', '--min-gap', '20'], cwd)
    c.check(r.rc == 0, 'rc=%s' % r.rc, r)
    for k in range(30, 35):
        c.check(('skipped frame %d ' % k) in r.stderr, 'no "skipped frame %d"' % k, r)
    rows = read_csv_rows(os.path.join(cwd, 'm.csv')) or []
    c.check([int(x[0]) for x in rows] == list(range(30)) + list(range(35, 45)), 'frame ids moved', r)
    msg(10, c.name, r)
    c.done()
    c = Case(10, 'resume with other options (--mode nodes on an exhaustive database)',
             'refused naming the key and both values; database unchanged')
    before = db_dump(os.path.join(cwd, 'd.db'))
    r = c.run(['run', '--sequence', cseq, '--database', 'd.db', '--output', 'o.csv', '--min-gap', '20', '--mode', 'nodes',
               '--session', '7'], cwd)
    c.check(r.rc not in (0, None), 'rc=%s' % r.rc, r)
    c.check('search.mode' in r.stderr and 'nodes' in r.stderr and 'exhaustive' in r.stderr,
            'the message does not name search.mode and both values', r)
    c.check(not compare_db(db_dump(os.path.join(cwd, 'd.db')), before), 'the database changed', r)
    msg(10, c.name, r)
    c.done()
    c = Case(10, 'resume with another --min-gap', 'refused naming search.min_gap and both values')
    r = c.run(['run', '--sequence', cseq, '--database', 'd.db', '--output', 'o.csv', '--min-gap', '30', '--session', '7'], cwd)
    c.check(r.rc not in (0, None) and 'min_gap' in r.stderr and '30' in r.stderr and '20' in r.stderr,
            'rc=%s; message should name min_gap, 30 and 20' % r.rc, r)
    msg(10, c.name, r)
    c.done()

    # ---- foreign files as --database ----
    cwd = fresh(os.path.join(root, 'foreign'))
    con = sqlite3.connect(os.path.join(cwd, 'other.db'))
    con.execute('CREATE TABLE t(x)')
    con.execute('INSERT INTO t VALUES (1)')
    con.commit()
    con.close()
    write(os.path.join(cwd, 'notes.db'), b'my notes, not a database\n')
    for f in ('other.db', 'notes.db'):
        c = Case(10, 'another program\'s file as --database (%s)' % f, 'refused naming the file; the file unchanged')
        r = c.run(['run', '--sequence', cseq, '--database', f, '--output', 'o.csv', '--min-gap', '20'], cwd, extra_inputs=[f])
        c.check(r.rc not in (0, None) and f in r.stderr, 'rc=%s' % r.rc, r)
        msg(10, c.name, r)
        c.done()
        c = Case(10, 'db info of another program\'s file (%s)' % f, 'exit 1 naming the file; unchanged')
        r = c.run(['db', 'info', f], cwd)
        c.check(r.rc == 1 and f in r.stderr, 'rc=%s' % r.rc, r)
        msg(10, c.name, r)
        c.done()
    c = Case(10, 'db info of a missing file', 'exit 1 naming the file, saying it does not exist')
    r = c.run(['db', 'info', 'nope.db'], cwd)
    c.check(r.rc == 1 and 'nope.db' in r.stderr, 'rc=%s' % r.rc, r)
    c.check(not os.path.exists(os.path.join(cwd, 'nope.db')), 'db info created the file', r)
    msg(10, c.name, r)
    c.done()

    # ---- UTF-8 byte-order marks ----
    cwd = fresh(os.path.join(root, 'bom'))
    BOM = b'\xef\xbb\xbf'
    gtb = read(gt)
    write(os.path.join(cwd, 'gt_bom.txt'), BOM + gtb)
    write(os.path.join(cwd, 'gt_bom_comment.txt'), BOM + b'# pairs\n' + gtb)
    write(os.path.join(cwd, 'gt_bom_crlf.txt'), BOM + gtb.replace(b'\n', b'\r\n'))
    r = lsgd(['gt', 'stats', gt, '--json', 'plain.json'], cwd)
    plain = json.load(open(os.path.join(cwd, 'plain.json')))
    for f in ('gt_bom.txt', 'gt_bom_comment.txt', 'gt_bom_crlf.txt'):
        c = Case(10, 'pairs file with a UTF-8 BOM (%s): gt stats, eval' % f, 'the same pairs as without the BOM')
        r = c.run(['gt', 'stats', f, '--json', 'b.json'], cwd)
        c.check(r.rc == 0, 'gt stats rc=%s' % r.rc, r)
        if r.rc == 0:
            j = json.load(open(os.path.join(cwd, 'b.json')))
            c.check(j.get('pairs') == plain.get('pairs') and j.get('frames') == plain.get('frames'),
                    'pairs %s frames %s vs %s %s without BOM' % (j.get('pairs'), j.get('frames'), plain.get('pairs'),
                                                                  plain.get('frames')), r)
        r = c.run(['eval', '--detections', os.path.join(BASE, 'det.csv'), '--gt', f, '--min-gap', '20', '--json', 'e.json'], cwd)
        c.check(r.rc == 0, 'eval rc=%s' % r.rc, r)
        msg(10, c.name, r)
        c.done()
    names = corr_list(corr)
    write(os.path.join(corr, '..', 'c10_bomlist.txt'), b'')  # placeholder removed below
    os.remove(os.path.join(corr, '..', 'c10_bomlist.txt'))
    write(os.path.join(cwd, 'list_bom.txt'), BOM + ('\n'.join(os.path.join(corr, n) for n in names) + '\n').encode())
    c = Case(10, 'list file with a UTF-8 BOM', 'all 222 frames, image 0 not skipped')
    r = c.run(['run', '--sequence', 'list_bom.txt', '--output', 'lb.csv', '--min-gap', '20'], cwd)
    rows = read_csv_rows(os.path.join(cwd, 'lb.csv')) or []
    c.check(r.rc == 0 and len(rows) == 222 and 'skipped' not in r.stderr, 'rc=%s rows=%d' % (r.rc, len(rows)), r)
    msg(10, c.name, r)
    c.done()
    detb = read(os.path.join(BASE, 'det.csv'))
    write(os.path.join(cwd, 'det_bom.csv'), BOM + detb)
    simple = b'query,match,score\n' + b''.join(b'%d,-1,0\n' % i for i in range(150)) + b'150,39,9\n'
    write(os.path.join(cwd, 'det_simple_bom.csv'), BOM + simple)
    write(os.path.join(cwd, 'det_simple_bom_noheader.csv'), BOM + simple.split(b'\n', 1)[1])
    for f in ('det_bom.csv', 'det_simple_bom.csv', 'det_simple_bom_noheader.csv'):
        c = Case(10, 'detections with a UTF-8 BOM (%s)' % f, 'read as without the BOM')
        r = c.run(['eval', '--detections', f, '--gt', gt, '--min-gap', '20', '--json', 'd.json'], cwd)
        c.check(r.rc == 0, 'rc=%s' % r.rc, r)
        msg(10, c.name, r)
        c.done()
    write(os.path.join(cwd, 'cfg_bom.yaml'), BOM + read(os.path.join(BASE, 'cfg.yaml')))
    c = Case(10, 'config with a UTF-8 BOM', 'read as without the BOM')
    r = c.run(['run', '--sequence', cseq, '--config', 'cfg_bom.yaml', '--output', 'cb.csv', '--min-gap', '20'], cwd)
    c.check(r.rc == 0, 'rc=%s' % r.rc, r)
    msg(10, c.name, r)
    c.done()
    write(os.path.join(cwd, 'poses_bom.txt'), BOM + read(os.path.join(BASE, 'poses.txt')))
    c = Case(10, 'poses with a UTF-8 BOM', 'read as without the BOM')
    r = c.run(['eval', '--sequence', cseq, '--gt', gt, '--min-gap', '20', '--json', 'p.json', '--report', 'p.html',
               '--poses', 'poses_bom.txt'], cwd)
    c.check(r.rc == 0, 'rc=%s' % r.rc, r)
    msg(10, c.name, r)
    c.done()
    write(os.path.join(cwd, 'gt_2bom.txt'), BOM + BOM + gtb)
    c = Case(10, 'pairs file with two BOMs', 'an error naming file:line (only one BOM is a BOM)')
    r = c.run(['gt', 'stats', 'gt_2bom.txt'], cwd)
    c.check(r.rc not in (0, None) and 'gt_2bom.txt' in r.stderr, 'rc=%s' % r.rc, r)
    msg(10, c.name, r)
    c.done()

    # ---- output devices ----
    cwd = fresh(os.path.join(root, 'dev'))
    c = Case(10, 'run --output /dev/full', 'exit non-zero naming /dev/full and the frame ("disk full")')
    r = c.run(['run', '--sequence', cseq, '--output', '/dev/full', '--min-gap', '20'], cwd)
    c.check(r.rc not in (0, None) and '/dev/full' in r.stderr, 'rc=%s' % r.rc, r)
    msg(10, c.name, r)
    c.done()
    c = Case(10, 'run --database d.db --output /dev/full', 'exit non-zero naming /dev/full; the database holds no frame without its row')
    r = c.run(['run', '--sequence', cseq, '--output', '/dev/full', '--min-gap', '20', '--database', 'd.db'], cwd)
    c.check(r.rc not in (0, None) and '/dev/full' in r.stderr, 'rc=%s' % r.rc, r)
    if os.path.exists(os.path.join(cwd, 'd.db')):
        n = len(db_dump(os.path.join(cwd, 'd.db'))['frames'])
        c.check(n == 0, 'the database stored %d frames whose CSV rows could not be written' % n, r)
    msg(10, c.name, r)
    c.done()
    for a, label in ((['eval', '--sequence', cseq, '--gt', gt, '--min-gap', '20', '--json', '/dev/full'], 'eval --json /dev/full'),
                     (['gt', 'convert', gt, '--output', '/dev/full'], 'gt convert --output /dev/full'),
                     (['gt', 'stats', gt, '--json', '/dev/full'], 'gt stats --json /dev/full')):
        c = Case(10, label, 'exit non-zero naming /dev/full')
        r = c.run(a, cwd)
        c.check(r.rc not in (0, None) and '/dev/full' in r.stderr, 'rc=%s' % r.rc, r)
        msg(10, c.name, r)
        c.done()
    c = Case(10, 'run --output /dev/null', 'accepted (a character device)')
    r = c.run(['run', '--sequence', cseq, '--output', '/dev/null', '--min-gap', '20'], cwd)
    c.check(r.rc == 0, 'rc=%s' % r.rc, r)
    c.done()
