#!/usr/bin/env python3
"""interrupt_mid_write.py SIGNAL POINT OUT CMD...: runs CMD with CROWDBAKE_TEST_STOP=POINT, so it
stops itself (SIGSTOP) at that point of writing OUT (mid-write: half of its first write done;
before-rename: complete but not renamed). Once it has stopped, sends SIGNAL and lets it go on
(SIGCONT). Nothing is timed or polled: waitpid reports the stop. Prints the temporary files
that existed while it was stopped, the exit status and the program's message."""
import os, signal, subprocess, sys

sig, point, out, cmd = getattr(signal, sys.argv[1]), sys.argv[2], sys.argv[3], sys.argv[4:]
d, prefix = os.path.dirname(out) or '.', '.' + os.path.basename(out) + '.tmp.'
p = subprocess.Popen(cmd, stderr=subprocess.PIPE, env=dict(os.environ, CROWDBAKE_TEST_STOP=point))
_, status = os.waitpid(p.pid, os.WUNTRACED)
if not os.WIFSTOPPED(status):
    sys.exit('%s: never stopped at %s (exit status %d)' % (cmd[0], point, os.waitstatus_to_exitcode(status)))
temporaries = [(n, os.path.getsize(os.path.join(d, n))) for n in os.listdir(d) if n.startswith(prefix)]
os.kill(p.pid, sig)
os.kill(p.pid, signal.SIGCONT)
_, err = p.communicate()
print('stopped with %s; status %d; message %s' % (
    ', '.join('%s (%d bytes)' % t for t in temporaries) or 'no temporary', p.returncode, err.decode().strip()))
