#!/usr/bin/python3
"""Hostile-user test campaign of the lsgd command line (issue 15; counts in
docs/reliability.md, "The hostile-user campaign").

Run:  /usr/bin/python3 scripts/hostile_campaign.py [CLASS ...]
      (no argument: every class; e.g. `hostile_campaign.py 2 5` runs only classes 2 and 5)
Environment: LSGD (the binary, default build/tools/lsgd/lsgd), WORK (scratch
folder, default /tmp/lsgd-campaign; wiped at start), SHARED (the shared
datasets' parent, default ../shared), DEMO (a `lsgd demo --output` folder;
made in WORK when unset). Takes about 13 minutes on 2 cores; needs
../shared/datasets/corridor.

The classes are scripts/hostile/classN.py (one module each, a function
classN()), on the helpers of scripts/hostile/run.py (settings, inputs,
running lsgd), report.py (cases, the report) and files.py; a new class is a
module and an entry in CLASSES and report.CLASS_NAMES.

Everything is written under WORK.  Deterministic:
one fixed random seed per class.  At most one lsgd process runs at a time,
except in the concurrent-writer cases of class 10.

Generic checks on EVERY lsgd invocation (a failure of any fails the case):
  * finishes within its timeout (60 s default; a hang is a failure),
  * not killed by a signal (unless the case kills it),
  * stderr free of: std::bad_alloc, std::out_of_range, terminate called,
    what():, Sanitizer, Segmentation,
  * peak RSS (os.wait4 ru_maxrss, and /proc polling which kills at the
    limit) below 1.5 GB,
  * every input file byte-identical afterwards (md5 before and after; files
    above 256 MB: size, mtime and md5 of the first and last MiB).
"""
import importlib
import os
import shutil
import subprocess
import sys
import time

# The classes and their helpers are modules of scripts/hostile/ (one per
# class: hostile/classN.py); a class module is imported once the demo folder
# is known (hostile.run.DEMO_SRC).
from hostile import run
from hostile.run import CORR_SRC, LSGD, WORK, _hash_cache, _spawner, fingerprint
from hostile.report import Case, print_report
from hostile.files import fresh, setup_base

CLASSES = {1: 'class1', 2: 'class2', 3: 'class3', 4: 'class4', 5: 'class5', 6: 'class6',
           7: 'class7', 8: 'class8', 10: 'class10', 11: 'class11', 12: 'class12', 13: 'class13', 14: 'class14',
           15: 'class15', 16: 'class16'}


def main():
    _spawner()   # fork the spawner while this interpreter is small
    t0 = time.monotonic()
    usage = 'usage: hostile_campaign.py [CLASS ...] (classes %s; none: every class)' % (
        ' '.join(str(k) for k in sorted(CLASSES)))
    if any(a in ('-h', '--help') for a in sys.argv[1:]):
        print(usage + '\n' + __doc__)
        return
    bad = [a for a in sys.argv[1:] if not a.isdigit() or int(a) not in CLASSES]
    if bad:
        sys.exit('hostile_campaign.py: %s is not a class\n%s' % (', '.join(bad), usage))
    want = [int(a) for a in sys.argv[1:]] or sorted(CLASSES)
    os.makedirs(WORK, exist_ok=True)
    for n in os.listdir(WORK):
        if n.startswith('c') or n == 'base':
            fresh(os.path.join(WORK, n))
            shutil.rmtree(os.path.join(WORK, n))
    if not run.DEMO_SRC:  # the synthetic street, written by lsgd demo
        run.DEMO_SRC = os.path.join(WORK, 'demo')
        if not os.path.exists(os.path.join(run.DEMO_SRC, 'sequence.txt')):
            shutil.rmtree(run.DEMO_SRC, ignore_errors=True)
            subprocess.run([LSGD, 'demo', '--output', run.DEMO_SRC], check=True,
                           stdout=subprocess.DEVNULL)
    shared_before = {}
    for d in (CORR_SRC, run.DEMO_SRC):
        for dirpath, dirs, files in os.walk(d):
            for f in files:
                p = os.path.join(dirpath, f)
                shared_before[p] = fingerprint(p)
    setup_base()
    for k in want:
        fn = getattr(importlib.import_module('hostile.' + CLASSES[k]), CLASSES[k])
        t = time.monotonic()
        try:
            fn()
        except Exception as e:   # a harness bug must not hide the other classes
            import traceback
            traceback.print_exc()
            c = Case(k, 'HARNESS ERROR in class %d: %r' % (k, e), 'the class runs to the end')
            c.fail('harness exception (not an lsgd verdict): %r' % e)
            c.done()
        print('class %d took %.0f s' % (k, time.monotonic() - t), flush=True)
    _hash_cache.clear()
    changed = [p for p, fp in shared_before.items() if fingerprint(p) != fp]
    if changed:
        c = Case(1, 'shared datasets unchanged at the end', 'byte-identical')
        c.fail('shared files changed: %s' % changed[:10])
        c.done()
    print_report(time.monotonic() - t0)


if __name__ == '__main__':
    main()
