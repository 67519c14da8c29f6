"""Class 15 of the hostile campaign (scripts/hostile_campaign.py)."""
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


def class15():
    """Issue 35, the seventh pass (2026-12-07): an output over the list of a
    dataset folder given as the sequence, two runs given one --output, an
    interrupted sweep's --json, a pairs file cut short under its lsgd header,
    a sweep value given twice."""
    print('\n=== class 15: lists inside folders, one writer per output, cut pairs, sweep values', flush=True)
    root = fresh(os.path.join(WORK, 'c15'))

    cwd = fresh(os.path.join(root, 'list'))
    corr = copy_corridor(os.path.join(cwd, 'corr'))
    c = Case(15, "--output over the sequence.txt of the dataset folder given (run, match)",
             'refused, the list unchanged')
    before = read(os.path.join(corr, 'sequence.txt'))
    for args in (['run', '--sequence', 'corr', '--output', 'corr/sequence.txt'],
                 ['match', '--reference', 'corr', '--query', 'corr/images', '--output', 'corr/sequence.txt']):
        r = c.run(args, cwd, extra_inputs=['corr/sequence.txt'])
        msg(15, c.name, r)
        c.check(r.rc != 0 and 'was read from' in r.stderr, '%s: not refused' % args[0], r)
    c.check(read(os.path.join(corr, 'sequence.txt')) == before, 'the list was replaced')
    c.done()

    cwd = fresh(os.path.join(root, 'two'))
    c = Case(15, 'a second lsgd run given the --output another run is writing',
             "refused ('another process is writing it'); the first run's CSV holds its own rows only")
    seq = os.path.join(BASE, 'corr', 'sequence.txt')
    first = subprocess.Popen([LSGD, 'run', '--sequence', os.path.join(BASE, 'demo330.txt'), '--output', 'same.csv'],
                             cwd=cwd, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    deadline = time.monotonic() + 30
    while time.monotonic() < deadline and (read_csv_rows(os.path.join(cwd, 'same.csv')) or []) == []:
        time.sleep(0.05)
    r = c.run(['run', '--sequence', seq, '--output', 'same.csv'], cwd, skip_inputs=['same.csv'])
    msg(15, c.name, r)
    first.wait(timeout=120)
    c.check(r.rc != 0 and 'another process is writing it' in r.stderr, 'the second run was not refused', r)
    rows = read_csv_rows(os.path.join(cwd, 'same.csv')) or []
    c.check(first.returncode == 0 and len(rows) == 330 and all('corr' not in row[1] for row in rows),
            "the first run's CSV is not its 330 rows (%d rows)" % len(rows))
    c.done()

    cwd = fresh(os.path.join(root, 'sweep'))
    c = Case(15, "an interrupted lsgd sweep leaves the --json of the previous sweep",
             'the JSON unchanged (it was emptied as the sweep started)')
    write(os.path.join(cwd, 'old.json'), b'{"earlier": 1}\n')
    c.run(['sweep', '--dataset', 's=%s,%s,20' % (seq, os.path.join(BASE, 'corr', 'groundtruth.txt')),
           '--set', 'decision.threshold=1:30:1', '--csv', 't.csv', '--json', 'old.json'], cwd, timeout=120,
          kill_when=wait_rows(os.path.join(cwd, 't.csv'), 1), skip_inputs=['old.json'])
    c.check(read(os.path.join(cwd, 'old.json')) == b'{"earlier": 1}\n', 'the JSON was changed')
    c.done()

    cwd = fresh(os.path.join(root, 'pairs'))
    c = Case(15, 'a pairs file lsgd wrote, cut short at a line end, scored by eval --detections',
             'refused naming the file and both pair counts (it scored true loops as false, exit 0)')
    r = c.run(['gt', 'convert', os.path.join(BASE, 'corr', 'groundtruth.txt'), '--output', 'g.txt'], cwd)
    lines = read(os.path.join(cwd, 'g.txt')).split(b'\n')
    write(os.path.join(cwd, 'cut.txt'), b'\n'.join(lines[:len(lines) // 2]) + b'\n')
    r = c.run(['eval', '--detections', os.path.join(BASE, 'det.csv'), '--gt', 'cut.txt', '--min-gap', '20',
               '--json', 'e.json'], cwd)
    msg(15, c.name, r)
    c.check(r.rc != 0 and 'but its header says pairs=' in r.stderr and 'cut.txt' in r.stderr, 'not refused', r)
    c.check(not os.path.exists(os.path.join(cwd, 'e.json')), 'a JSON was written')
    c.done()

    cwd = fresh(os.path.join(root, 'twice'))
    c = Case(15, "lsgd sweep --set decision.threshold=5,5.0 (one value spelt twice)",
             'refused naming both values (it ran one configuration twice)')
    r = c.run(['sweep', '--dataset', 's=%s,%s,20' % (seq, os.path.join(BASE, 'corr', 'groundtruth.txt')),
               '--set', 'decision.threshold=5,5.0', '--csv', 't.csv'], cwd)
    msg(15, c.name, r)
    c.check(r.rc != 0 and "the values '5' and '5.0'" in r.stderr, 'not refused', r)
    c.done()
