"""Class 7 of the hostile campaign (scripts/hostile_campaign.py)."""
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
# class 7: MAT files
# ==========================================================================
def mat_subelements(buf, start, end, le=True):
    """Sub-elements of a v5 matrix element's content buf[start:end]:
    list of dicts (type, nbytes, tag_off, data_off, small)."""
    E = '<' if le else '>'
    out = []
    i = start
    while i + 8 <= end:
        w = struct.unpack(E + 'I', buf[i:i + 4])[0]
        if w >> 16:   # small data element: nbytes in the upper 16 bits
            out.append({'type': w & 0xFFFF, 'nbytes': w >> 16, 'tag_off': i, 'data_off': i + 4, 'small': True})
            i += 8
        else:
            n = struct.unpack(E + 'I', buf[i + 4:i + 8])[0]
            out.append({'type': w, 'nbytes': n, 'tag_off': i, 'data_off': i + 8, 'small': False})
            i += 8 + ((n + 7) // 8) * 8
    return out


def mat_uncompressed_patch(data, fn):
    """Apply fn(buf, subelements) to the first matrix of an uncompressed v5 file."""
    b = bytearray(data)
    size = struct.unpack('<I', b[132:136])[0]
    subs = mat_subelements(b, 136, 136 + size)
    fn(b, subs)
    return bytes(b)


def mat_compressed_patch(data, fn, fix_outer=True):
    """Inflate the first miCOMPRESSED element, patch its matrix, deflate it again."""
    t, size = struct.unpack('<II', data[128:136])
    assert t == 15
    raw = bytearray(zlib.decompress(data[136:136 + size]))
    msize = struct.unpack('<I', raw[4:8])[0]
    subs = mat_subelements(raw, 8, 8 + msize)
    fn(raw, subs)
    z = zlib.compress(bytes(raw))
    return data[:128] + struct.pack('<II', 15, len(z)) + z + data[136 + size:]


def class7():
    print('\n=== class 7: MAT files', flush=True)
    import numpy as np
    import scipy.io
    import scipy.sparse
    root = fresh(os.path.join(WORK, 'c7'))
    N = 60
    pairs = sorted((q, q - 35) for q in range(40, 50))
    M = np.zeros((N, N))
    for q, m in pairs:
        M[q, m] = 1
    rows = ['query,match,score'] + ['%d,%d,%d' % (i, (i - 35) if 40 <= i < 50 else -1, 5) for i in range(N)]
    write(os.path.join(root, 'det.csv'), ('\n'.join(rows) + '\n').encode())
    corr_seq = os.path.join(BASE, 'corr', 'sequence.txt')
    variants = {
        'double': M, 'logical': M.astype(bool), 'uint8': M.astype(np.uint8),
        'sparse-double': scipy.sparse.csc_matrix(M), 'sparse-logical': scipy.sparse.csc_matrix(M.astype(bool)),
    }
    files = {}
    for vname, arr in variants.items():
        for comp in (False, True):
            fn = 'gt_%s%s.mat' % (vname, '_z' if comp else '')
            scipy.io.savemat(os.path.join(root, fn), {'truth': arr}, do_compression=comp)
            files[fn] = comp
    for vname in ('double', 'sparse-double'):
        fn = 'gt_%s_v4.mat' % vname
        scipy.io.savemat(os.path.join(root, fn), {'truth': variants[vname]}, format='4')
        files[fn] = 'v4'

    def valid_case(fn):
        c = Case(7, '%s (valid): gt convert / gt stats / eval read exactly the %d pairs' % (fn, len(pairs)),
                 'exit 0 and exactly the pairs written')
        r = c.run(['gt', 'convert', fn, '--output', 'p.txt'], root)
        got = []
        if r.rc == 0:
            for line in open(os.path.join(root, 'p.txt')):
                if line.strip() and not line.startswith('#'):
                    a, b = line.split()[:2]
                    got.append((int(a), int(b)))
        c.check(r.rc == 0 and sorted(got) == pairs, 'gt convert rc=%s pairs %s' % (r.rc, sorted(got)[:12]), r)
        r = c.run(['gt', 'stats', fn, '--json', 's.json'], root)
        c.check(r.rc == 0, 'gt stats rc=%s' % r.rc, r)
        if r.rc == 0:
            j = json.load(open(os.path.join(root, 's.json')))
            c.check(j.get('pairs') == len(pairs) and j.get('frames') == N,
                    'gt stats says frames=%s pairs=%s' % (j.get('frames'), j.get('pairs')), r)
        r = c.run(['eval', '--gt', fn, '--detections', 'det.csv', '--min-gap', '5', '--json', 'e.json'], root)
        c.check(r.rc == 0, 'eval --detections rc=%s' % r.rc, r)
        if r.rc == 0:
            j = json.load(open(os.path.join(root, 'e.json')))
            c.check(j.get('positives') == len(pairs) and j.get('declared_true') == len(pairs),
                    'eval positives=%s declared_true=%s' % (j.get('positives'), j.get('declared_true')), r)
        c.done()

    def bad_case(fn, label, data, light=False):
        write(os.path.join(root, 'bad.mat'), data)
        c = Case(7, '%s: %s' % (fn, label), 'non-zero exit naming bad.mat (FormatError), never made-up pairs')
        made_up = False
        for args in (['gt', 'convert', 'bad.mat', '--output', 'bp.txt'], ['gt', 'stats', 'bad.mat']) if light else (
                     ['gt', 'stats', 'bad.mat'],
                     ['gt', 'convert', 'bad.mat', '--output', 'bp.txt'],
                     ['eval', '--gt', 'bad.mat', '--detections', 'det.csv', '--min-gap', '5', '--json', 'be.json'],
                     ['eval', '--gt', 'bad.mat', '--sequence', corr_seq, '--last', str(N - 1), '--min-gap', '5',
                      '--json', 'be.json', '--verify', 'none']):
            for f in ('bp.txt', 'be.json'):
                if os.path.exists(os.path.join(root, f)):
                    os.remove(os.path.join(root, f))
            r = c.run(args, root)
            if r.rc == 0:
                extra = ''
                if args[1] == 'convert':
                    got = sorted(tuple(int(x) for x in l.split()[:2])
                                 for l in open(os.path.join(root, 'bp.txt')) if l.strip() and not l.startswith('#'))
                    if got == pairs:
                        extra = ' (the original %d pairs: data intact)' % len(got)
                    else:
                        made_up = True
                        extra = ' (MADE-UP PAIRS: %d pairs, e.g. %s)' % (len(got), got[:5])
                c.fail('ACCEPTED: %s exit 0%s' % (' '.join(args[:2]), extra), r)
            else:
                c.check('bad.mat' in r.stderr, 'the error does not name bad.mat', r)
        if c.problems:
            c.tags.add('made-up pairs' if made_up else 'accepted, data intact')
        c.done()
        return c

    for fn, comp in files.items():
        valid_case(fn)
    for fn, comp in files.items():
        data = read(os.path.join(root, fn))
        L = len(data)
        sparse = 'sparse' in fn
        if comp == 'v4':
            # v4: header mopt, mrows, ncols, imagf, namlen
            for label, rr, cc in (('dims %dx%d -> %dx%d' % (N, N, N + 1, N + 1), N + 1, N + 1),
                                  ('dims -> %dx%d' % (2 * N, 2 * N), 2 * N, 2 * N),
                                  ('dims -> 100000x100000', 100000, 100000),
                                  ('dims -> 2147483647x2147483647', 2147483647, 2147483647),
                                  ('dims -> %dx%d (smaller than the data)' % (N - 1, N - 1), N - 1, N - 1)):
                if sparse:
                    continue   # a v4 sparse matrix stores its size in the data
                b = bytearray(data)
                b[4:12] = struct.pack('<ii', rr, cc)
                bad_case(fn, label, bytes(b))
            for cut in (0, 4, 19, 20, 26, L // 2, L - 8, L - 1):
                bad_case(fn, 'truncated to %d of %d bytes' % (cut, L), data[:cut])
            continue
        patch = mat_compressed_patch if comp else mat_uncompressed_patch

        def set_dims(rr, cc):
            def f(b, subs):
                d = subs[1]
                struct.pack_into('<ii', b, d['data_off'], rr, cc)
            return f
        for label, rr, cc in (('dims %dx%d -> %dx%d' % (N, N, N + 1, N + 1), N + 1, N + 1),
                              ('dims -> %dx%d' % (2 * N, 2 * N), 2 * N, 2 * N),
                              ('dims -> 1000x1000', 1000, 1000),
                              ('dims -> 100000x100000', 100000, 100000),
                              ('dims -> 2147483647x2147483647', 2147483647, 2147483647),
                              ('dims -> -1x-1', -1, -1),
                              ('dims -> %dx%d (smaller than the data)' % (N - 1, N - 1), N - 1, N - 1)):
            bad_case(fn, label, patch(data, set_dims(rr, cc)))

        def data_size_plus(k):
            def f(b, subs):
                d = subs[-1]
                if d['small']:
                    w = struct.unpack('<I', b[d['tag_off']:d['tag_off'] + 4])[0]
                    struct.pack_into('<I', b, d['tag_off'], (w & 0xFFFF) | ((d['nbytes'] + k) << 16))
                else:
                    struct.pack_into('<I', b, d['tag_off'] + 4, d['nbytes'] + k)
            return f
        bad_case(fn, 'last data sub-element claims 8 more bytes', patch(data, data_size_plus(8)))
        bad_case(fn, 'last data sub-element claims 1 GB more', patch(data, data_size_plus(1 << 30)))
        if sparse:
            def sp(mod):
                def f(b, subs):
                    # subs: flags, dims, name, ir, jc, [pr]
                    ir, jc = subs[3], subs[4]
                    mod(b, ir, jc)
                return f
            bad_case(fn, 'sparse: a row index beyond the matrix',
                     patch(data, sp(lambda b, ir, jc: struct.pack_into('<i', b, ir['data_off'], N + 5))))
            bad_case(fn, 'sparse: a negative row index',
                     patch(data, sp(lambda b, ir, jc: struct.pack_into('<i', b, ir['data_off'], -3))))
            bad_case(fn, 'sparse: column index decreasing',
                     patch(data, sp(lambda b, ir, jc: struct.pack_into('<i', b, jc['data_off'] + 4 * 10, 999))))
            bad_case(fn, 'sparse: last column index counts more entries than stored',
                     patch(data, sp(lambda b, ir, jc: struct.pack_into('<i', b, jc['data_off'] + 4 * N, 10 ** 6))))
            bad_case(fn, 'sparse: first column index not 0',
                     patch(data, sp(lambda b, ir, jc: struct.pack_into('<i', b, jc['data_off'], 1))))
        if comp:
            cuts = (0, 100, 128, 130, 136, 140, 150, L // 2, L - 5, L - 1)
        else:
            cuts = (0, 10, 100, 127, 128, 130, 136, 150, 160, 168, 184, L // 2, L - 9, L - 8, L - 1)
        for cut in cuts:
            c = bad_case(fn, 'truncated to %d of %d bytes' % (cut, L), data[:cut])
            if not comp and cut >= L - 8 and not c.problems == []:
                tail = data[cut:]
                if tail.strip(b'\0') == b'':
                    c.tags.add('debatable: only padding bytes were cut')
        # a flipped byte in the zlib stream
        if comp:
            # bytes of the zlib stream (136 .. L-1): spread over the deflate data, and the Adler-32 trailer
            offs = sorted(set([136, 137, 138] + [136 + (L - 136) * k // 10 for k in range(1, 10)] +
                              [L - 4, L - 3, L - 2, L - 1]))
            for off in offs:
                b = bytearray(data)
                b[off] ^= 0xFF
                bad_case(fn, 'zlib stream byte %d of %d flipped%s' % (off, L, ' (Adler-32 trailer)' if off >= L - 4 else ''),
                         bytes(b), light=True)
