#!/usr/bin/env python3
"""interrupt_mid_write.py SIGNAL OUT CMD...: runs CMD, waits until its temporary output file
(.OUT.tmp.*) exists, freezes the process (SIGSTOP), sends SIGNAL, lets it go on (SIGCONT).
Prints the exit status and whether the temporary was caught."""
import os, signal, subprocess, sys, time

sig = getattr(signal, sys.argv[1])
out = sys.argv[2]
d, base = os.path.dirname(out) or '.', '.' + os.path.basename(out) + '.tmp.'
p = subprocess.Popen(sys.argv[3:], stderr=subprocess.PIPE)
caught = False
deadline = time.time() + 60
while p.poll() is None and time.time() < deadline:
    if any(n.startswith(base) for n in os.listdir(d)):
        os.kill(p.pid, signal.SIGSTOP)
        caught = True
        os.kill(p.pid, sig)
        os.kill(p.pid, signal.SIGCONT)
        break
    time.sleep(0.0001)
_, err = p.communicate()
print('status %d caught %s message %s' % (p.returncode, caught, err.decode().strip()))
