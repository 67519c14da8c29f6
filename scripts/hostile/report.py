"""Cases, their verdicts and the final report."""
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


# --------------------------------------------------------------------------
# cases and reporting
# --------------------------------------------------------------------------
RESULTS = {}       # class -> list of case dicts


MESSAGES = []      # (class, label, command, rc, message) verbatim


INFO = []          # informational (not counted) observations


CLASS_NAMES = {
    1: 'outputs vs inputs', 2: 'truncated/corrupt images', 3: 'frame ids',
    4: 'kill -9 and re-run', 5: 'WAL / database damage', 6: 'hangs, unbounded reads',
    7: 'MAT files', 8: 'zero-frame runs, broken links', 10: 'messages',
    11: 'leftovers, bombs, line ends', 12: 'read-only, PNG chunks, pair bombs',
    13: 'MAT cells, match sizes, missing lists, bare __new__',
    14: 'links, old logs, special names, newlines, empty flags',
    15: 'lists inside folders, one writer per output, cut pairs, sweep values',
    16: 'decimal numbers, demo folders, deep and tiled images, configs',
}


def short(s, n=1500):
    s = s.rstrip('\n')
    if len(s) > n:
        return s[:n] + ' ...[%d more chars]' % (len(s) - n)
    return s


class Case:
    def __init__(self, cls, name, expected=''):
        self.cls = cls
        self.name = name
        self.expected = expected
        self.problems = []   # (text, Res or None)
        self.runs = []
        self.tags = set()

    def run(self, args, cwd, **kw):
        r = lsgd(args, cwd, **kw)
        self.runs.append(r)
        for g in r.generic:
            self.problems.append((g, r))
        return r

    def fail(self, text, r=None):
        self.problems.append((text, r))

    def check(self, cond, text, r=None):
        if not cond:
            self.fail(text, r)
        return cond

    def done(self):
        ok = not self.problems
        d = {'name': self.name, 'ok': ok, 'expected': self.expected, 'tags': sorted(self.tags),
             'problems': [], 'commands': [r.cmd for r in self.runs]}
        for text, r in self.problems:
            e = {'what': text}
            if r is not None:
                e.update(cmd=r.cmd, rc=r.rc, sig=r.sig, elapsed=round(r.elapsed, 2),
                         rss_mb=r.maxrss_kb // 1024, stderr=short(r.stderr),
                         stdout=short(r.stdout, 400))
            d['problems'].append(e)
        RESULTS.setdefault(self.cls, []).append(d)
        mark = 'ok  ' if ok else 'FAIL'
        print('  [%s] %s' % (mark, self.name), flush=True)
        if not ok:
            for e in d['problems']:
                print('        - %s' % e['what'])
        return ok


def msg(cls, label, r):
    MESSAGES.append({'cls': cls, 'label': label, 'cmd': r.cmd, 'rc': r.rc,
                     'stderr': short(r.stderr, 3000), 'stdout': short(r.stdout, 600)})


def info(cls, label, text, r=None):
    e = {'cls': cls, 'label': label, 'text': text}
    if r is not None:
        e.update(cmd=r.cmd, rc=r.rc, stderr=short(r.stderr, 800))
    INFO.append(e)
    print('  [info] %s: %s' % (label, text), flush=True)


# ==========================================================================
# main: run the classes, print failures and the summary table
# ==========================================================================
def print_report(total_time):
    print('\n' + '=' * 78)
    print('FAILURES (command, expected, observed, verbatim stderr)')
    print('=' * 78)
    for cls in sorted(RESULTS):
        fails = [d for d in RESULTS[cls] if not d['ok']]
        if not fails:
            continue
        print('\n--- class %d (%s): %d failed' % (cls, CLASS_NAMES[cls], len(fails)))
        for d in fails:
            print('\n* %s' % d['name'])
            print('  expected: %s' % d['expected'])
            for e in d['problems']:
                print('  observed: %s' % e['what'])
                if 'cmd' in e:
                    print('  command:  %s' % e['cmd'])
                    print('  rc=%s signal=%s %.2fs rss=%dMB' % (e['rc'], e['sig'], e['elapsed'], e['rss_mb']))
                    if e['stderr']:
                        print('  stderr:   ' + e['stderr'].replace('\n', '\n            '))
    print('\n' + '=' * 78)
    print('MESSAGES (verbatim, for judging)')
    print('=' * 78)
    for m in MESSAGES:
        if m['cls'] == 10 or m['cls'] == 5:
            print('\n[%d] %s\n  %s\n  rc=%s\n  stderr: %s' % (m['cls'], m['label'], m['cmd'], m['rc'],
                                                          m['stderr'].replace('\n', '\n          ')))
            if m['stdout'].strip():
                print('  stdout: ' + m['stdout'].replace('\n', '\n          '))
    print('\n' + '=' * 78)
    print('INFORMATIONAL (not counted)')
    print('=' * 78)
    for e in INFO:
        print('- [%d] %s: %s' % (e['cls'], e['label'], e['text']))
    print('\n' + '=' * 78)
    print('SUMMARY  (%d lsgd invocations, %.0f s)' % (RUN_COUNT[0], total_time))
    print('=' * 78)
    print('%-5s %-32s %6s %6s %6s' % ('class', 'name', 'tried', 'passed', 'failed'))
    T = P = 0
    for cls in sorted(RESULTS):
        t = len(RESULTS[cls])
        p = sum(1 for d in RESULTS[cls] if d['ok'])
        T += t
        P += p
        print('%-5d %-32s %6d %6d %6d' % (cls, CLASS_NAMES[cls], t, p, t - p))
    print('%-5s %-32s %6d %6d %6d' % ('all', '', T, P, T - P))
    with open(os.path.join(WORK, 'results.json'), 'w') as f:
        json.dump({'results': {str(k): v for k, v in RESULTS.items()}, 'messages': MESSAGES, 'info': INFO,
                   'seconds': total_time, 'invocations': RUN_COUNT[0]}, f, indent=1)
    print('details: %s' % os.path.join(WORK, 'results.json'))
