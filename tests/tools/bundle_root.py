#!/usr/bin/env python3
"""bundle_root.py - `make bundle`'s crowdbake runs in a root holding glibc and nothing else.

The root: the bundle (bin/crowdbake, lib/*), glibc's loader, libc and libm (the files of Debian's
libc6 that the command links), /proc (the loader reads /proc/self/exe to find $ORIGIN) and the
models. The command runs there through a user and mount namespace (unshare -rm, then chroot),
bakes Quaternius' Husky and the generated fish, and must write the bytes the normal build does.
Where namespaces are not allowed, it checks instead that ldd resolves every library but glibc's
inside the bundle and runs the bundle from another folder with LD_LIBRARY_PATH cleared.
"""
import argparse
import os
import shutil
import subprocess
import sys

GLIBC = ('ld-linux', 'libc.so', 'libm.so', 'libpthread.so', 'libdl.so', 'librt.so')
FAILURES = []


def check(ok, what):
    print(('ok   ' if ok else 'FAIL ') + what, flush=True)
    if not ok:
        FAILURES.append(what)


def glibc_files(binary):
    """The glibc libraries the bundle's command resolves (paths on this machine)."""
    out = subprocess.run(['ldd', binary], capture_output=True, text=True).stdout
    files = []
    for line in out.splitlines():
        parts = line.split()
        path = parts[2] if len(parts) > 2 and parts[1] == '=>' else parts[0] if parts and parts[0].startswith('/') else None
        if path and os.path.basename(path).startswith(GLIBC):
            files.append(path)
    return files, out


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument('--build', default='build')
    ap.add_argument('--shared', default='../shared')
    a = ap.parse_args()
    build, shared = os.path.abspath(a.build), os.path.abspath(a.shared)
    bundle = os.path.join(build, 'bundle')
    root = os.path.join(build, 'bundle_root')
    shutil.rmtree(root, ignore_errors=True)
    shutil.copytree(bundle, os.path.join(root, 'bundle'), ignore=shutil.ignore_patterns('.done'))
    binary = os.path.join(root, 'bundle', 'bin', 'crowdbake')
    libc, listing = glibc_files(binary)
    outside = [l for l in listing.splitlines() if '=>' in l and not os.path.basename(l.split()[0]).startswith(GLIBC)
               and os.path.join(root, 'bundle') not in os.path.realpath(l.split()[2])]
    check(not outside, 'ldd: every library but glibc\'s resolves inside the bundle %s' % (outside or ''))
    for path in libc:
        dest = os.path.join(root, path.lstrip('/'))
        os.makedirs(os.path.dirname(dest), exist_ok=True)
        shutil.copyfile(os.path.realpath(path), dest)
        os.chmod(dest, 0o755)
    os.makedirs(os.path.join(root, 'proc'))
    os.makedirs(os.path.join(root, 'm'))
    models = {'Husky.glb': os.path.join(shared, 'assets', 'quaternius-husky', 'Husky.glb'),
              'fish.glb': os.path.join(build, 'samples', 'fish.glb')}
    for name, src in models.items():
        shutil.copyfile(src, os.path.join(root, 'm', name))
    everything = sorted(os.path.relpath(os.path.join(d, f), root) for d, _, fs in os.walk(root) for f in fs)
    print('the root holds: ' + ', '.join(everything))
    isolated = subprocess.run(['unshare', '-rm', 'true'], capture_output=True).returncode == 0
    for name in models:
        out = name.replace('.glb', '.pal')
        args = ['bake', '/m/' + name, '-o', '/m/' + out, '-q', '--root-motion', 'in-place']
        if isolated:
            cmd = ['unshare', '-rm', 'bash', '-c',
                   'root=$1; shift; mount --rbind /proc "$root/proc" && exec chroot "$root" /bundle/bin/crowdbake "$@"',
                   'bash', root] + args
            where = 'in a root with only glibc'
        else:
            cmd = ['env', '-u', 'LD_LIBRARY_PATH', binary] + [x.replace('/m/', os.path.join(root, 'm') + '/') for x in args]
            where = 'from another folder, LD_LIBRARY_PATH cleared (no namespaces here)'
        p = subprocess.run(cmd, capture_output=True, text=True, cwd='/')
        ref = os.path.join(root, 'ref-' + out)
        q = subprocess.run([os.path.join(build, 'crowdbake'), 'bake', os.path.join(root, 'm', name), '-o', ref, '-q',
                            '--root-motion', 'in-place'], capture_output=True, text=True)
        same = p.returncode == 0 and q.returncode == 0 and \
            open(os.path.join(root, 'm', out), 'rb').read() == open(ref, 'rb').read()
        check(same, 'the bundle bakes %s %s, the same bytes as build/crowdbake %s' % (name, where, p.stderr.strip()))
    if FAILURES:
        print('bundle_root: %d check(s) failed' % len(FAILURES), file=sys.stderr)
        return 1
    print('bundle_root: all checks passed')
    return 0


if __name__ == '__main__':
    sys.exit(main())
