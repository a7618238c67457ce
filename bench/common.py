"""What bench/run.py and bench/crowd.py share: where things are, and running a command."""
import os
import subprocess
import sys
import time

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
BUILD = os.path.join(ROOT, 'build')
SHARED = os.environ.get('CROWDBAKE_SHARED', os.path.join(ROOT, '..', 'shared'))
EXE = os.environ.get('CROWDBAKE', os.path.join(BUILD, 'crowdbake'))


def run(cmd, **kw):
    """Runs cmd; returns (wall seconds, peak RSS bytes of that child, stdout)."""
    start = time.perf_counter()
    proc = subprocess.Popen(cmd, stdout=subprocess.PIPE, stderr=subprocess.PIPE, **kw)
    out, err = proc.communicate()
    wall = time.perf_counter() - start
    # communicate() reaped it; RUSAGE_CHILDREN keeps the max over children, so take a fresh
    # measurement by running each command through wait4 instead when possible.
    if proc.returncode != 0:
        sys.exit('bench: %s failed: %s' % (' '.join(cmd), err.decode()[-500:]))
    return wall, out.decode()
