"""The campaign's settings, the inputs each command reads (hashed before and
after), and running lsgd with the generic checks (the spawner, RSS, timeouts)."""
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


REPO = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))  # scripts/hostile/run.py


LSGD = os.path.abspath(os.environ.get('LSGD', os.path.join(REPO, 'build/tools/lsgd/lsgd')))


WORK = os.path.abspath(os.environ.get('WORK', '/tmp/lsgd-campaign'))


SEED = 20261201


RSS_LIMIT_KB = int(1.5 * 1024 * 1024)          # 1.5 GB in KiB


BAD_STDERR = ['std::bad_alloc', 'std::out_of_range', 'terminate called',
              'what():', 'Sanitizer', 'Segmentation']


DEMO_SRC = os.environ.get('DEMO', '')  # set by main() when unset: read it as run.DEMO_SRC, never through a star import


def find_shared():
    for c in [os.environ.get('SHARED', ''), os.path.join(os.path.dirname(REPO), 'shared')]:
        if os.path.isdir(os.path.join(c, 'datasets', 'corridor')):
            return c
    sys.exit('no shared datasets found')


SHARED = find_shared()


CORR_SRC = os.path.join(SHARED, 'datasets', 'corridor')


# --------------------------------------------------------------------------
# hashing of inputs
# --------------------------------------------------------------------------
_hash_cache = {}


def fingerprint(path):
    """Content fingerprint of a regular file (None for anything else)."""
    try:
        st = os.stat(path)
    except OSError:
        return ('missing',)
    if not stat.S_ISREG(st.st_mode):
        return ('special', stat.S_IFMT(st.st_mode))
    key = (st.st_dev, st.st_ino, st.st_size, st.st_mtime_ns, st.st_ctime_ns)
    if key in _hash_cache:
        return _hash_cache[key]
    h = hashlib.md5()
    if st.st_size > 256 * 1024 * 1024:
        with open(path, 'rb') as f:
            h.update(f.read(1 << 20))
            f.seek(max(0, st.st_size - (1 << 20)))
            h.update(f.read(1 << 20))
        fp = ('big', st.st_size, st.st_mtime_ns, h.hexdigest())
    else:
        with open(path, 'rb') as f:
            while True:
                b = f.read(1 << 22)
                if not b:
                    break
                h.update(b)
        fp = ('reg', st.st_size, h.hexdigest())
    _hash_cache[key] = fp
    return fp


IMG_EXT = ('.png', '.jpg', '.jpeg', '.bmp', '.pgm', '.ppm', '.tif', '.tiff')


def sequence_files(seq, cwd):
    """The files a --sequence argument names: the list file and its images,
    or the images of a folder.  Special files are left out (not hashable)."""
    p = seq if os.path.isabs(seq) else os.path.join(cwd, seq)
    out = []
    try:
        st = os.stat(p)
    except OSError:
        return out
    if stat.S_ISDIR(st.st_mode):
        for n in sorted(os.listdir(p)):
            q = os.path.join(p, n)
            if os.path.isfile(q):
                out.append(q)
        return out
    if not stat.S_ISREG(st.st_mode) or st.st_size > 50 * 1024 * 1024:
        return out
    out.append(p)
    base = os.path.dirname(p)
    try:
        with open(p, 'rb') as f:
            data = f.read()
        for line in data.decode('utf-8', 'replace').splitlines():
            line = line.strip().lstrip('\ufeff')
            if not line or line.startswith('#'):
                continue
            q = line if os.path.isabs(line) else os.path.join(base, line)
            if os.path.isfile(q) and os.path.getsize(q) < 2 * 1024 ** 3:
                out.append(q)
    except OSError:
        pass
    return out


def collect_inputs(args, cwd):
    """Input files named by an lsgd command line (for the identity check)."""
    ins = []
    a = list(args)
    sub = a[0] if a else ''
    for i, x in enumerate(a):
        nxt = a[i + 1] if i + 1 < len(a) else None
        if nxt is None:
            continue
        if x == '--sequence':
            ins += sequence_files(nxt, cwd)
        elif x in ('--config', '--gt', '--poses', '--detections'):
            ins.append(nxt)
        elif x == '--dataset':
            m = re.match(r'^[^=]*=(.*)$', nxt)
            if m:
                parts = m.group(1).split(',')
                if len(parts) == 3:
                    ins += sequence_files(parts[0], cwd)
                    ins.append(parts[1])
                elif len(parts) == 2:
                    d = parts[0]
                    ins += sequence_files(os.path.join(d, 'sequence.txt'), cwd)
                    ins.append(os.path.join(d, 'groundtruth.txt'))
    if sub == 'gt' and len(a) > 2:
        ins.append(a[2])
    if sub == 'db' and len(a) > 2:
        src = [x for x in a[2:] if not x.startswith('--')]
        if src:
            ins.append(src[0])
            ins.append(src[0] + '-wal')
    res = []
    for p in ins:
        if not p:
            continue
        q = p if os.path.isabs(p) else os.path.join(cwd, p)
        if os.path.isfile(q):
            res.append(os.path.abspath(q))
    return sorted(set(res))


# --------------------------------------------------------------------------
# running lsgd
# --------------------------------------------------------------------------
class Res:
    pass


def proc_rss_kb(pid):
    try:
        with open('/proc/%d/status' % pid) as f:
            for line in f:
                if line.startswith('VmRSS:'):
                    return int(line.split()[1])
    except OSError:
        pass
    return 0


RUN_COUNT = [0]


# --------------------------------------------------------------------------
# The spawner: a small process forked at start-up, while this interpreter is
# still small, that starts lsgd, polls it and reaps it with wait4.  Linux
# carries the parent's peak RSS into a child's ru_maxrss across fork/exec, so
# spawning from the (large) harness would inflate every measurement.
# --------------------------------------------------------------------------
import pickle


_SPAWNER = {}


def _send(fd, obj):
    b = pickle.dumps(obj)
    os.write(fd, struct.pack('>I', len(b)))
    view = memoryview(b)
    while view:
        n = os.write(fd, view)
        view = view[n:]


def _recv(fd):
    def exact(n):
        buf = b''
        while len(buf) < n:
            chunk = os.read(fd, n - len(buf))
            if not chunk:
                raise EOFError
            buf += chunk
        return buf
    n = struct.unpack('>I', exact(4))[0]
    return pickle.loads(exact(n))


def _rows_at_least(path, n):
    try:
        with open(path, 'rb') as f:
            return f.read().count(b'\n') - 1 >= n
    except OSError:
        return False


def _spawner_loop(rfd, wfd):
    procs = {}
    while True:
        try:
            req = _recv(rfd)
        except EOFError:
            os._exit(0)
        op = req['op']
        if op == 'start':
            outf = open(req['stdout'], 'wb')
            errf = open(req['stderr'], 'wb')
            p = subprocess.Popen(req['argv'], cwd=req['cwd'], stdout=outf, stderr=errf,
                                 stdin=subprocess.DEVNULL, env=req.get('env'))
            outf.close()
            errf.close()
            procs[p.pid] = (p, time.monotonic())
            _send(wfd, {'pid': p.pid})
        elif op == 'finish':
            p, t0 = procs.pop(req['pid'])
            res = {'timed_out': False, 'killed': False, 'mem_killed': False, 'kill_time': None}
            poll_rss = 0
            fast = req.get('kill_after') is not None or req.get('kill_rows') is not None
            while True:
                pid, status, ru = os.wait4(p.pid, os.WNOHANG)
                if pid:
                    break
                el = time.monotonic() - t0
                if not res['killed'] and ((req.get('kill_after') is not None and el >= req['kill_after']) or
                                          (req.get('kill_rows') is not None and _rows_at_least(*req['kill_rows']))):
                    os.kill(p.pid, signal.SIGKILL)
                    res['killed'] = True
                    res['kill_time'] = el
                rss = proc_rss_kb(p.pid)
                poll_rss = max(poll_rss, rss)
                if rss > req['rss_limit_kb'] and not res['killed']:
                    os.kill(p.pid, signal.SIGKILL)
                    res['mem_killed'] = res['killed'] = True
                if el > req['timeout'] and not res['killed']:
                    os.kill(p.pid, signal.SIGKILL)
                    res['timed_out'] = res['killed'] = True
                time.sleep(0.001 if fast else 0.003)
            p.returncode = 0
            res.update(elapsed=time.monotonic() - t0, cpu_s=ru.ru_utime + ru.ru_stime,
                       maxrss_kb=max(ru.ru_maxrss, poll_rss), poll_rss=poll_rss,
                       rc=os.WEXITSTATUS(status) if os.WIFEXITED(status) else None,
                       sig=os.WTERMSIG(status) if os.WIFSIGNALED(status) else None)
            _send(wfd, res)


def _spawner():
    if not _SPAWNER:
        r1, w1 = os.pipe()
        r2, w2 = os.pipe()
        pid = os.fork()
        if pid == 0:
            os.close(w1)
            os.close(r2)
            _spawner_loop(r1, w2)
        os.close(r1)
        os.close(w2)
        _SPAWNER.update(pid=pid, w=w1, r=r2)
    return _SPAWNER


def _call(req):
    sp = _spawner()
    _send(sp['w'], req)
    return _recv(sp['r'])


class Started:
    """An lsgd process started without waiting (the concurrent-writer cases)."""

    def __init__(self, args, cwd, tag):
        self.args, self.cwd, self.tag = list(args), cwd, tag
        self.out = os.path.join(WORK, '.stdout-' + tag)
        self.err = os.path.join(WORK, '.stderr-' + tag)
        self.pid = _call({'op': 'start', 'argv': [LSGD] + self.args, 'cwd': cwd, 'stdout': self.out,
                          'stderr': self.err})['pid']
        RUN_COUNT[0] += 1

    def finish(self, timeout=60.0):
        d = _call({'op': 'finish', 'pid': self.pid, 'timeout': timeout, 'rss_limit_kb': RSS_LIMIT_KB})
        r = Res()
        r.__dict__.update(d)
        r.args, r.cwd = self.args, self.cwd
        r.cmd = 'cd %s && %s' % (shlex.quote(self.cwd), shlex.join([LSGD] + self.args))
        r.stdout, r.stdout_size = read_capped(self.out)
        r.stderr, r.stderr_size = read_capped(self.err)
        r.changed = []
        r.generic = generic_problems(r, timeout)
        return r


def read_capped(path, cap=1 << 20):
    """First and last CAP bytes of a (possibly huge) output file, and its size."""
    size = os.path.getsize(path)
    with open(path, 'rb') as f:
        if size <= 2 * cap:
            return f.read().decode('utf-8', 'replace'), size
        head = f.read(cap)
        f.seek(size - cap)
        tail = f.read(cap)
    return (head.decode('utf-8', 'replace') + '\n...[%d bytes left out]...\n' % (size - 2 * cap) +
            tail.decode('utf-8', 'replace')), size


def generic_problems(r, timeout):
    gen = []
    if r.timed_out:
        gen.append('HANG: still running after %.0f s (killed)' % timeout)
    if r.mem_killed:
        gen.append('MEMORY: RSS above 1.5 GB (killed at %d MB after %.1f s)' % (r.poll_rss // 1024, r.elapsed))
    if r.sig is not None and not r.timed_out and not r.mem_killed and not (r.killed and r.sig == signal.SIGKILL):
        gen.append('died by signal %d' % r.sig)
    for b in BAD_STDERR:
        if b in r.stderr:
            gen.append('stderr contains %r' % b)
    if r.maxrss_kb > RSS_LIMIT_KB and not r.mem_killed:
        gen.append('peak RSS %d MB > 1.5 GB' % (r.maxrss_kb // 1024))
    if r.changed:
        gen.append('INPUT MODIFIED: %s' % ', '.join(r.changed))
    return gen


def file_contains(path, needle):
    """Stream a (possibly huge) file looking for needle."""
    nb = needle.encode()
    tail = b''
    with open(path, 'rb') as f:
        while True:
            b = f.read(1 << 22)
            if not b:
                return False
            if nb in tail + b:
                return True
            tail = b[-len(nb):]


def lsgd(args, cwd, timeout=60.0, extra_inputs=(), skip_inputs=(),
         kill_after=None, kill_rows=None, env=None, kill_when=None, needles=()):
    """Run lsgd once (through the spawner); apply the generic checks.
    kill_after: seconds after the spawn at which SIGKILL is sent;
    kill_rows: (csv path, n): SIGKILL once the CSV holds n data rows."""
    if kill_when is not None:
        kill_rows = kill_when
    RUN_COUNT[0] += 1
    os.makedirs(cwd, exist_ok=True)
    inputs = collect_inputs(args, cwd)
    for p in extra_inputs:
        q = p if os.path.isabs(p) else os.path.join(cwd, p)
        if os.path.isfile(q):
            inputs.append(os.path.abspath(q))
    skip = set(os.path.abspath(p if os.path.isabs(p) else os.path.join(cwd, p)) for p in skip_inputs)
    inputs = sorted(set(i for i in inputs if i not in skip))
    before = {p: fingerprint(p) for p in inputs}
    outp, errp = os.path.join(WORK, '.stdout'), os.path.join(WORK, '.stderr')
    pid = _call({'op': 'start', 'argv': [LSGD] + list(args), 'cwd': cwd, 'stdout': outp, 'stderr': errp,
                 'env': env})['pid']
    d = _call({'op': 'finish', 'pid': pid, 'timeout': timeout, 'rss_limit_kb': RSS_LIMIT_KB,
               'kill_after': kill_after, 'kill_rows': kill_rows})
    r = Res()
    r.__dict__.update(d)
    r.pid = pid
    r.args = list(args)
    r.cwd = cwd
    r.cmd = 'cd %s && %s' % (shlex.quote(cwd), shlex.join([LSGD] + list(args)))
    r.stdout, r.stdout_size = read_capped(outp)
    r.stderr, r.stderr_size = read_capped(errp)
    # whether the whole stderr (not only its first and last MiB) holds each needle
    r.stderr_has = {n: (n in r.stderr) or (r.stderr_size > 2 * (1 << 20) and file_contains(errp, n)) for n in needles}
    r.changed = [p for p in inputs if fingerprint(p) != before[p]]
    r.generic = generic_problems(r, timeout)
    return r
