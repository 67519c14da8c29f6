"""Class 1 of the hostile campaign (scripts/hostile_campaign.py)."""
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
from hostile import run as _run  # DEMO_SRC as main() sets it (a star import holds the value at import)


def c1_expect_refused(c, r, new_outputs, cwd):
    c.check(r.rc not in (0, None), 'expected a non-zero exit (refusal), got rc=%s' % r.rc, r)
    c.check('processed' not in r.stdout + r.stderr and 'report:' not in r.stdout,
            'work was done before the refusal (output mentions processing)', r)
    for o in new_outputs:
        q = o if os.path.isabs(o) else os.path.join(cwd, o)
        if os.path.lexists(q) and not os.path.islink(q):
            c.fail('output %s was created although the command was refused' % o, r)
    if r.rc not in (0, None) and 'nothing was run' not in r.stderr:
        c.tags.add('no "nothing was run"')


def class1():
    print('\n=== class 1: outputs vs inputs', flush=True)
    root = fresh(os.path.join(WORK, 'c1'))
    pristine = os.path.join(root, 'pristine')
    copy_corridor(os.path.join(pristine, 'corr'))
    for n in ('cfg.yaml', 'poses.txt', 'det.csv'):
        shutil.copyfile(os.path.join(BASE, n), os.path.join(pristine, n))
    r = lsgd(['run', '--sequence', 'corr/sequence.txt', '--database', 'd.db', '--output', 'dbrun.csv',
              '--min-gap', '20'], pristine)
    assert r.rc == 0, r.stderr
    data = os.path.join(root, 'data')

    def restore():
        """Put every file of data/ back to its pristine content, in place (the
        inodes stay, so hard links made for later cases stay valid)."""
        if not os.path.exists(data):
            shutil.copytree(pristine, data)
        for dirpath, dirs, files in os.walk(pristine):
            for f in files:
                src = os.path.join(dirpath, f)
                dst = os.path.join(data, os.path.relpath(src, pristine))
                if os.path.islink(dst) or (os.path.exists(dst) and not os.path.isfile(dst)):
                    if os.path.isdir(dst) and not os.path.islink(dst):
                        shutil.rmtree(dst)
                    else:
                        os.remove(dst)
                if not os.path.exists(dst) or read(src) != read(dst):
                    with open(dst, 'wb') as g:
                        g.write(read(src))
        for dirpath, dirs, files in os.walk(data):
            for f in files:
                q = os.path.join(dirpath, f)
                if not os.path.exists(os.path.join(pristine, os.path.relpath(q, data))) and not f.startswith('d.db'):
                    os.remove(q)
        # SQLite companions must exist as files for the tests
        for s in ('-wal', '-shm'):
            if not os.path.exists(os.path.join(data, 'd.db' + s)):
                open(os.path.join(data, 'd.db' + s), 'wb').close()
    restore()
    D = lambda *p: os.path.join(data, *p)
    seq, img, cfg, gt = D('corr', 'sequence.txt'), D('corr', 'images', '0003.jpg'), D('cfg.yaml'), D('corr', 'groundtruth.txt')
    poses, det, db = D('poses.txt'), D('det.csv'), D('d.db')

    # command specs: name -> (builder(outputs)->args, inputs{label:path}, output flags, extra fixed)
    def rel(cwd, p):
        return os.path.relpath(p, cwd)

    specs = []
    specs.append(('run', lambda o, cw: ['run', '--sequence', rel(cw, seq), '--config', rel(cw, cfg), '--min-gap', '20',
                                        '--database', o.get('--database', rel(cw, db)),
                                        '--output', o.get('--output', 'out.csv')],
                  {'list': seq, 'image': img, 'config': cfg, 'database': db, 'database-wal': db + '-wal',
                   'database-shm': db + '-shm'},
                  ['--output'], {'--output': 'out.csv'}))
    specs.append(('run-newdb', lambda o, cw: ['run', '--sequence', rel(cw, seq), '--config', rel(cw, cfg), '--min-gap', '20',
                                              '--database', o.get('--database', 'new.db'),
                                              '--output', o.get('--output', 'out.csv')],
                  {'list': seq, 'image': img, 'config': cfg},
                  ['--database', '--output'], {'--output': 'out.csv', '--database': 'new.db'}))
    specs.append(('eval', lambda o, cw: ['eval', '--sequence', rel(cw, seq), '--gt', rel(cw, gt), '--min-gap', '20',
                                         '--config', rel(cw, cfg), '--poses', rel(cw, poses),
                                         '--json', o.get('--json', 'm.json'), '--output', o.get('--output', 'e.csv'),
                                         '--report', o.get('--report', 'r.html')],
                  {'list': seq, 'image': img, 'config': cfg, 'gt': gt, 'poses': poses},
                  ['--json', '--output', '--report'], {'--json': 'm.json', '--output': 'e.csv', '--report': 'r.html'}))
    specs.append(('eval-detections', lambda o, cw: ['eval', '--detections', rel(cw, det), '--gt', rel(cw, gt),
                                                    '--min-gap', '20', '--json', o.get('--json', 'm.json'),
                                                    '--report', o.get('--report', 'r.html')],
                  {'detections': det, 'gt': gt}, ['--json', '--report'], {'--json': 'm.json', '--report': 'r.html'}))
    specs.append(('gt-convert', lambda o, cw: ['gt', 'convert', rel(cw, gt), '--output', o.get('--output', 'p.txt')],
                  {'source': gt}, ['--output'], {'--output': 'p.txt'}))
    specs.append(('gt-stats', lambda o, cw: ['gt', 'stats', rel(cw, gt), '--min-gap', '20', '--json', o.get('--json', 's.json')],
                  {'source': gt}, ['--json'], {'--json': 's.json'}))
    specs.append(('sweep', lambda o, cw: ['sweep', '--dataset', 'c=%s,%s,20' % (rel(cw, seq), rel(cw, gt)),
                                          '--config', rel(cw, cfg), '--set', 'verification.max_candidates=3',
                                          '--csv', o.get('--csv', 's.csv'), '--markdown', o.get('--markdown', 's.md'),
                                          '--json', o.get('--json', 's.json')],
                  {'list': seq, 'image': img, 'config': cfg, 'gt': gt},
                  ['--csv', '--markdown', '--json'], {'--csv': 's.csv', '--markdown': 's.md', '--json': 's.json'}))
    specs.append(('bench', lambda o, cw: ['bench', '--frames', '20', '--width', '64', '--height', '48', '--warmup', '0',
                                          '--opencv-frames', '0', '--block', '10', '--config', rel(cw, cfg),
                                          '--json', o.get('--json', 'b.json')],
                  {'config': cfg}, ['--json'], {'--json': 'b.json'}))

    n = 0
    for name, build, inputs, oflags, defaults in specs:
        cwd = fresh(os.path.join(root, 'w_' + name))
        # (a) each output flag given each input, in every spelling
        for of in oflags:
            for ilabel, ipath in inputs.items():
                for slabel, sp in spellings(ipath, cwd, '%s_%s' % (name, ilabel)):
                    n += 1
                    outs = dict(defaults)
                    outs[of] = sp
                    c = Case(1, '%s: %s = %s (%s)' % (name, of, ilabel, slabel),
                             'non-zero exit before any work, inputs unchanged')
                    args = build(outs, cwd)
                    new_outs = [v for k, v in outs.items() if k != of]
                    new_outs = [v for v in new_outs if not os.path.lexists(os.path.join(cwd, v))]
                    r = c.run(args, cwd, timeout=120, extra_inputs=[ipath, db, db + '-wal'] if 'database' in ilabel else [ipath])
                    c1_expect_refused(c, r, new_outs, cwd)
                    if c.done():
                        msg(1, c.name, r) if slabel == 'symlink' else None
                    if r.changed or r.rc == 0:
                        restore()
                        # remove outputs the run wrote
                        for k, v in defaults.items():
                            q = os.path.join(cwd, v)
                            if os.path.isfile(q):
                                os.remove(q)
        # (b) two outputs of the same command, one spelled differently
        for i, of1 in enumerate(oflags):
            for of2 in oflags[i + 1:]:
                for exists in (False, True):
                    tgt = os.path.join(cwd, 'both_' + of1.strip('-'))
                    if os.path.exists(tgt):
                        os.remove(tgt)
                    if exists:
                        write(tgt, b'old\n')
                    for slabel, sp in spellings(tgt, cwd, '%s_both_%s_%s_%d' % (name, of1.strip('-'), of2.strip('-'), exists)):
                        n += 1
                        outs = dict(defaults)
                        outs[of1] = os.path.relpath(tgt, cwd)
                        outs[of2] = sp
                        c = Case(1, '%s: %s and %s the same %s file (%s)' % (
                            name, of1, of2, 'existing' if exists else 'new', slabel),
                            'non-zero exit before any work')
                        others = [v for k, v in outs.items() if k not in (of1, of2)]
                        others = [v for v in others if not os.path.lexists(os.path.join(cwd, v))]
                        r = c.run(build(outs, cwd), cwd, timeout=120,
                                  extra_inputs=[tgt] if exists else [])
                        c1_expect_refused(c, r, others + ([] if exists else [os.path.relpath(tgt, cwd)]), cwd)
                        if r.rc == 0:
                            q = os.path.join(cwd, sp)
                            st = ('still a symlink to %s' % os.readlink(q)) if os.path.islink(q) else (
                                'replaced by a regular file' if os.path.isfile(q) else 'absent')
                            head = read(tgt)[:40] if os.path.isfile(tgt) else b''
                            c.fail('consequence: %s given to %s is %s after the run; the target %s holds %r...: %s' % (
                                sp, of2, st, os.path.basename(tgt), head,
                                'ONE OUTPUT WAS OVERWRITTEN BY THE OTHER' if os.path.islink(q) or slabel == 'hardlink'
                                else 'both outputs survive (the writer replaced the link)'), r)
                        c.done()
                        for k, v in defaults.items():
                            q = os.path.join(cwd, v)
                            if os.path.isfile(q):
                                os.remove(q)
                        if os.path.exists(tgt) and not exists:
                            os.remove(tgt)
                        if exists:
                            write(tgt, b'old\n')
                        if r.changed:
                            restore()
        # (c) a missing folder, a folder, a read-only folder, a read-only file, a dangling link into a missing folder
        os.makedirs(os.path.join(cwd, 'adir'), exist_ok=True)
        rod = os.path.join(cwd, 'rodir')
        os.makedirs(rod, exist_ok=True)
        os.chmod(rod, 0o555)
        rof = os.path.join(cwd, 'ro.out')
        write(rof, b'read-only\n')
        os.chmod(rof, 0o444)
        if not os.path.lexists(os.path.join(cwd, 'dangling_missing')):
            os.symlink(os.path.join(cwd, 'nodir', 'x'), os.path.join(cwd, 'dangling_missing'))
        for of in oflags:
            for label, p in (('missing folder', 'nodir/x.out'), ('missing nested folder', 'nodir/a/b/x.out'),
                             ('a directory', 'adir'), ('a directory with slash', 'adir/'),
                             ('dangling link into a missing folder', 'dangling_missing'),
                             ('existing folder path + trailing slash file', 'ro.out/'),
                             ('/ (root)', '/'), ('a block device', '/dev/loop0' if os.path.exists('/dev/loop0') else None)):
                if p is None:
                    continue
                n += 1
                outs = dict(defaults)
                outs[of] = p
                c = Case(1, '%s: %s is %s (%s)' % (name, of, label, p), 'refused before the run')
                others = [v for k, v in outs.items() if k != of and not os.path.lexists(os.path.join(cwd, v))]
                if p == 'dangling_missing':
                    q = os.path.join(cwd, p)
                    if os.path.lexists(q):
                        os.remove(q)
                    os.symlink(os.path.join(cwd, 'nodir', 'x'), q)
                r = c.run(build(outs, cwd), cwd, timeout=120)
                if p == 'dangling_missing' and r.rc == 0 and os.path.isfile(os.path.join(cwd, p)) \
                        and not os.path.islink(os.path.join(cwd, p)):
                    # the writer replaced the dangling link by the output: nothing lost
                    info(1, c.name, 'accepted: the output replaced the dangling symlink (nothing lost; counted as pass)', r)
                    os.remove(os.path.join(cwd, p))
                else:
                    c1_expect_refused(c, r, others, cwd)
                if 'adir' in p:
                    c.check(os.listdir(os.path.join(cwd, 'adir')) == [], 'something was written inside adir/', r)
                c.done()
                msg(1, c.name, r)
                for k, v in defaults.items():
                    q = os.path.join(cwd, v)
                    if os.path.isfile(q):
                        os.remove(q)
                if r.changed:
                    restore()
            # informational: read-only folder / file (we run as root)
            for label, p in (('read-only folder (0555)', 'rodir/x.out'), ('read-only file (0444)', 'ro.out')):
                outs = dict(defaults)
                outs[of] = p
                before = fingerprint(rof)
                r = lsgd(build(outs, cwd), cwd, timeout=120)
                refused = r.rc not in (0, None) and 'nothing was run' in r.stderr
                info(1, '%s: %s is a %s' % (name, of, label),
                     ('refused: ' + r.stderr.strip().splitlines()[0]) if refused else
                     ('not refused before the run (rc=%s%s) -- we run as root, so permission bits do not bite; '
                      'not counted%s' % (r.rc, ', stderr: ' + r.stderr.strip().splitlines()[-1] if r.stderr.strip() else '',
                                         '; the 0444 file was overwritten' if fingerprint(rof) != before else '')), r)
                if os.path.exists(rof):
                    os.chmod(rof, 0o644)
                    write(rof, b'read-only\n')
                    os.chmod(rof, 0o444)
                for k, v in defaults.items():
                    q = os.path.join(cwd, v)
                    if os.path.isfile(q):
                        os.remove(q)
                q = os.path.join(rod, 'x.out')
                if os.path.exists(q):
                    os.remove(q)
                if r.changed:
                    restore()
        os.chmod(rod, 0o755)

    # (d) run --database new.db with --output new.db-wal/-shm/-journal (new database companions)
    cwd = fresh(os.path.join(root, 'w_newdb_companions'))
    for comp in ('-wal', '-shm', '-journal'):
        tgt = os.path.join(cwd, 'new.db' + comp)
        for slabel, sp in [('same', 'new.db' + comp), ('dotdot', '../w_newdb_companions/new.db' + comp),
                           ('absolute', tgt)]:
            c = Case(1, 'run-newdb: --output = --database new.db + %s (%s)' % (comp, slabel),
                     'non-zero exit before any work, no database created')
            r = c.run(['run', '--sequence', os.path.relpath(seq, cwd), '--min-gap', '20', '--database', 'new.db',
                       '--output', sp], cwd)
            c1_expect_refused(c, r, ['new.db', 'new.db' + comp], cwd)
            c.done()
            for f in os.listdir(cwd):
                if f.startswith('new.db'):
                    os.remove(os.path.join(cwd, f))
        # --database given through a symlink; output the real file's companion
        os.symlink(db, os.path.join(cwd, 'link.db'))
        c = Case(1, 'run: --database link.db (symlink to d.db), --output d.db%s (real companion)' % comp,
                 'non-zero exit before any work')
        r = c.run(['run', '--sequence', os.path.relpath(seq, cwd), '--min-gap', '20', '--database', 'link.db',
                   '--output', os.path.relpath(db + comp, cwd)], cwd,
                  extra_inputs=[db + comp] if os.path.exists(db + comp) else [])
        c1_expect_refused(c, r, [], cwd)
        c.done()
        os.remove(os.path.join(cwd, 'link.db'))
        if r.rc == 0 or r.changed:
            restore()
    # a dangling symlink output pointing at another (new) output
    cwd = fresh(os.path.join(root, 'w_dangling'))
    os.symlink('m.json', os.path.join(cwd, 'alias.csv'))
    c = Case(1, 'eval: --output alias.csv is a dangling symlink to --json m.json (both new)',
             'non-zero exit before any work')
    r = c.run(['eval', '--sequence', os.path.relpath(seq, cwd), '--gt', os.path.relpath(gt, cwd), '--min-gap', '20',
               '--json', 'm.json', '--output', 'alias.csv'], cwd)
    c1_expect_refused(c, r, ['m.json'], cwd)
    c.done()
    # the list names an image through another spelling: output the image by its plain path
    cwd = fresh(os.path.join(root, 'w_listspelling'))
    write(os.path.join(cwd, 'odd.txt'), ('\n'.join(['%s/images/../images/%04d.jpg' % (os.path.join(data, 'corr'), i)
                                                     for i in range(40)]) + '\n').encode())
    c = Case(1, 'run: list names images as DIR/images/../images/N.jpg; --output DIR/images/0005.jpg',
             'non-zero exit before any work')
    r = c.run(['run', '--sequence', 'odd.txt', '--output', D('corr', 'images', '0005.jpg')], cwd)
    c1_expect_refused(c, r, [], cwd)
    c.done()
    if r.changed or r.rc == 0:
        restore()
    # folder sequence: output an image of the folder
    c = Case(1, 'run: --sequence FOLDER, --output FOLDER/0007.jpg', 'non-zero exit before any work')
    r = c.run(['run', '--sequence', D('corr', 'images'), '--output', D('corr', 'images', '0007.jpg')], cwd)
    c1_expect_refused(c, r, [], cwd)
    c.done()
    if r.changed or r.rc == 0:
        restore()
    # --output the list file via a hard link made in another folder and a relative ../ spelling
    # demo: output DIR = config / a folder holding the config / earlier-demo folder holding config
    cwd = fresh(os.path.join(root, 'w_demo'))
    shutil.copyfile(cfg, os.path.join(cwd, 'cfg.yaml'))
    fakedemo = os.path.join(cwd, 'earlier')
    os.makedirs(fakedemo)
    for f in ('metrics.json', 'sequence.txt', 'groundtruth.txt', 'results-exhaustive.csv', 'results-nodes.csv'):
        shutil.copyfile(os.path.join(_run.DEMO_SRC, f), os.path.join(fakedemo, f))
    shutil.copyfile(cfg, os.path.join(fakedemo, 'cfg.yaml'))
    os.symlink(cwd, os.path.join(cwd, 'selflink'))
    for label, cfgp, outp in (('DIR = the config file', 'cfg.yaml', 'cfg.yaml'),
                              ('DIR = the config file (./x/../)', 'cfg.yaml', './../w_demo/cfg.yaml'),
                              ('DIR = the config file (absolute)', 'cfg.yaml', os.path.join(cwd, 'cfg.yaml')),
                              ('DIR = the folder holding the config', 'cfg.yaml', '.'),
                              ('DIR = symlink to the folder holding the config', 'cfg.yaml', 'selflink'),
                              ('DIR = an earlier demo folder that also holds --config', 'earlier/cfg.yaml', 'earlier'),
                              ('DIR = a missing nested folder', 'cfg.yaml', 'no/such/dir'),
                              ('DIR = an existing regular file (not an input)', 'cfg.yaml', 'earlier/metrics.json')):
        c = Case(1, 'demo: --output %s' % label, 'non-zero exit before any work, nothing written')
        before = sorted(os.listdir(cwd)) + sorted(os.listdir(fakedemo))
        r = c.run(['demo', '--config', cfgp, '--output', outp], cwd, timeout=180,
                  extra_inputs=[os.path.join(fakedemo, f) for f in os.listdir(fakedemo)])
        c1_expect_refused(c, r, [], cwd)
        after = sorted(os.listdir(cwd)) + sorted(os.listdir(fakedemo))
        c.check(before == after, 'files appeared: %s' % sorted(set(after) - set(before)), r)
        c.done()
        msg(1, c.name, r)
    print('class 1: %d cases' % len(RESULTS.get(1, [])))
