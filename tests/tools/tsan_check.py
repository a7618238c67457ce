#!/usr/bin/env python3
"""tsan_check.py - the threaded paths under ThreadSanitizer: no data race, no lock-order inversion.

  python3 tests/tools/tsan_check.py --build build/tsan --samples build/samples --shared ../shared TEST...

`make test-tsan` (and `make check`) builds crowdbake and the named library tests with
-fsanitize=thread into --build, without the AVX2 clones (their ifunc resolvers run before the
sanitizer's runtime starts) and with tests/tools/tsan_threads.c preloaded (GCC 12's runtime does
not see glibc's C11 threads). Then, each a run of its own, every report fails it:

  - the library tests named (the pool, the bake job, the rate search's kept poses ...);
  - `crowdbake bake` of the shared Cow, Husky, Fox and robot at -j 2 and -j 4: the rate search
    with the speed reference beside it, the bake's workers, the per-row travel;
  - Fox with --bone-space local (the local rows' search) and --timed-rows on;
  - a catalog of Cow and Husky at -j 2, both types at once, into .pal, EXR and KTX2.
"""
import argparse
import os
import subprocess
import sys
import tempfile

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
MODELS = ('quaternius-cow/Cow.glb', 'quaternius-husky/Husky.glb', 'fox-bevy/Fox.glb',
          'robot-quaternius-raylib/robot.glb')
REPORT = 'WARNING: ThreadSanitizer'


def tsan_env(build, samples, exe):
    env = dict(os.environ, LD_PRELOAD=os.path.join(build, 'libtsan_threads.so'), CROWDBAKE=exe, SAMPLES=samples,
               TSAN_OPTIONS='halt_on_error=1:exitcode=66:second_deadlock_stack=1')
    return env


def run(name, cmd, env, cwd=None):
    """One run; False (its reports printed) where the sanitizer reported or the run failed."""
    p = subprocess.run(cmd, env=env, cwd=cwd, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True,
                       errors='replace')
    if p.returncode == 0 and REPORT not in p.stdout:
        print(f'ok   {name}')
        return True
    print(f'FAIL {name}: exit {p.returncode}' + (' (ThreadSanitizer reported)' if REPORT in p.stdout else ''))
    at = p.stdout.find('==================')
    print(p.stdout[at:at + 6000] if at >= 0 else p.stdout[-3000:])
    return False


def catalog(shared):
    return f'''[bake]
out_dir = "out"
root_motion = "in-place"
format = "pal,exr,ktx2"
[animal.cow]
model = "{shared}/assets/quaternius-cow/Cow.glb"
states = {{ idle = ["Idle"], walk = ["Walk"], gallop = ["Gallop"] }}
[animal.husky]
model = "{shared}/assets/quaternius-husky/Husky.glb"
states = {{ idle = ["Idle"], walk = ["Walk"], gallop = ["Gallop"] }}
'''


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument('--build', required=True, help='the ThreadSanitizer build (crowdbake, tests/, libtsan_threads.so)')
    ap.add_argument('--samples', required=True, help='the generated samples the tests read')
    ap.add_argument('--shared', required=True, help='../shared: the third-party models')
    ap.add_argument('tests', nargs='*', help='library tests built in --build/tests')
    a = ap.parse_args()
    build, shared = os.path.abspath(a.build), os.path.abspath(a.shared)
    exe = os.path.join(build, 'crowdbake')
    env = tsan_env(build, os.path.abspath(a.samples), exe)
    ok = True
    for t in a.tests:
        ok &= run(t, [os.path.join(build, 'tests', t)], env, cwd=ROOT)
    with tempfile.TemporaryDirectory(prefix='tsan_', dir=os.path.join(ROOT, 'build')) as tmp:
        out = os.path.join(tmp, 'x.pal')
        for model in MODELS:
            for j in ('2', '4'):
                ok &= run(f'bake {model} -j {j}', [exe, 'bake', os.path.join(shared, 'assets', model), '-o', out,
                                                   '-q', '-j', j], env)
        fox = os.path.join(shared, 'assets', 'fox-bevy/Fox.glb')
        ok &= run('bake Fox --bone-space local -j 2', [exe, 'bake', fox, '-o', out, '-q', '-j', '2',
                                                      '--bone-space', 'local'], env)
        ok &= run('bake Fox --timed-rows on -j 2', [exe, 'bake', fox, '-o', out, '-q', '-j', '2',
                                                   '--timed-rows', 'on'], env)
        with open(os.path.join(tmp, 'herd.toml'), 'w') as f:
            f.write(catalog(shared))
        ok &= run('bake catalog (Cow, Husky) -j 2', [exe, 'bake', 'herd.toml', '-q', '-j', '2'], env, cwd=tmp)
    print('tsan: no report' if ok else 'tsan: FAILED')
    return 0 if ok else 1


if __name__ == '__main__':
    sys.exit(main())
