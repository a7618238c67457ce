#!/usr/bin/env python3
"""hermetic.py - the same inputs give the same bytes whatever the environment of the run.

A catalog of five types (the generated samples with a LOD and a shared palette, Quaternius' Cow
and Husky from the shared third-party models) is baked the one-step way and one type per run
with `bake --type` + `roster merge`, first as a baseline, then each time with one thing changed:

  - the absolute path (the same tree copied two folders deeper elsewhere),
  - the user (nobody, when this runs as root) and the umask (077),
  - TZ and LANG / LC_ALL,
  - the thread count (-j 1 against -j 7),
  - the CPU path: build/generic/crowdbake (`make generic`: no AVX2 clones) against the normal
    build, which takes AVX2 where the CPU has it.

Every palette, manifest and fragment must be byte-identical to the baseline's, and none may hold
an absolute path. Also checks `roster merge`'s refusals: a missing, repeated or damaged fragment.
"""
import argparse
import os
import shutil
import subprocess
import sys

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
FAILURES = []

CATALOG = '''[bake]
out_dir = "out"
root_motion = "in-place"
[animal.goat]
model = "models/quadruped.glb"
lods = ["models/quadruped_lod1.glb"]
states = { idle = ["idle"], wander = ["walk"] }
[animal.sheep]
model = "models/quadruped.glb"
lods = ["models/quadruped_lod1.glb"]
states = { idle = ["idle"], wander = ["walk"] }
[animal.fish]
model = "models/fish.glb"
[animal.cow]
model = "models/Cow.glb"
[animal.husky]
model = "models/Husky.glb"
'''
TYPES = ['cow', 'fish', 'goat', 'husky', 'sheep']


def check(ok, what):
    print(('ok   ' if ok else 'FAIL ') + what, flush=True)
    if not ok:
        FAILURES.append(what)


def make_tree(top, build, shared):
    shutil.rmtree(top, ignore_errors=True)
    models = os.path.join(top, 'models')
    os.makedirs(models)
    for f in ('quadruped.glb', 'quadruped_lod1.glb', 'fish.glb'):
        shutil.copyfile(os.path.join(build, 'samples', f), os.path.join(models, f))
    for f in ('quaternius-cow/Cow.glb', 'quaternius-husky/Husky.glb'):
        shutil.copyfile(os.path.join(shared, 'assets', f), os.path.join(models, os.path.basename(f)))
    with open(os.path.join(top, 'catalog.toml'), 'w') as f:
        f.write(CATALOG)
    os.chmod(top, 0o777)
    for d, dirs, files in os.walk(top):
        for x in dirs:
            os.chmod(os.path.join(d, x), 0o777)


def bake(crowdbake, top, env=None, jobs='1', preexec=None):
    """Both ways: out/ (one step) and split/ (one run per type, then the merge)."""
    def run(args):
        p = subprocess.run([crowdbake] + args, cwd=top, env=env, preexec_fn=preexec, capture_output=True, text=True)
        if p.returncode:
            sys.stderr.write(p.stdout + p.stderr)
        return p.returncode
    rc = run(['bake', 'catalog.toml', '-q', '-j', jobs, '--force'])
    for t in TYPES:
        rc |= run(['bake', 'catalog.toml', '--type', t, '--out-dir', 'split', '-q', '-j', jobs, '--force'])
    rc |= run(['roster', 'merge', '-q', '-o', 'split/roster.json'] + ['split/%s.fragment' % t for t in TYPES])
    return rc


def outputs(top):
    got = {}
    for sub in ('out', 'split'):
        for name in sorted(os.listdir(os.path.join(top, sub))):
            if not name.startswith('.'):
                got[sub + '/' + name] = open(os.path.join(top, sub, name), 'rb').read()
    return got


def compare(what, base, got, top):
    check(rc_ok(got) and base == got, what + ': every output byte-identical (%d files)' % len(base))
    leaks = [n for n, v in got.items() if top.encode() in v or b'/work/' in v or b'/tmp/' in v]
    check(not leaks, what + ': no absolute path in the outputs %s' % (leaks or ''))


def rc_ok(got):
    return bool(got)


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument('--build', default='build')
    ap.add_argument('--shared', default='../shared')
    a = ap.parse_args()
    build, shared = os.path.abspath(a.build), os.path.abspath(a.shared)
    crowdbake, generic = os.path.join(build, 'crowdbake'), os.path.join(build, 'generic', 'crowdbake')
    work = os.path.join(build, 'hermetic')
    base_top = os.path.join(work, 'a')
    make_tree(base_top, build, shared)
    env = dict(os.environ, TZ='UTC', LANG='C', LC_ALL='C')
    check(bake(crowdbake, base_top, env) == 0, 'baseline bake (one step and per type + merge)')
    base = outputs(base_top)
    check(base.get('out/roster.json') == base.get('split/roster.json'),
          'the merged manifest equals the one-step manifest')
    check(all(base.get('out/%s.pal' % t) == base.get('split/%s.pal' % t) for t in ('cow', 'fish', 'goat', 'husky')),
          'the per-type palettes equal the one-step palettes')
    check('out/sheep.pal' not in base and b'"shares_palette_of": "goat"' in base.get('split/roster.json', b''),
          'sheep shares goat\'s palette in both manifests')

    def again(what, top=base_top, binary=crowdbake, env=env, jobs='1', preexec=None):
        if top != base_top:
            make_tree(top, build, shared)
        else:
            for sub in ('out', 'split'):
                shutil.rmtree(os.path.join(top, sub), ignore_errors=True)
        rc = bake(binary, top, env, jobs, preexec)
        compare(what, base, outputs(top) if rc == 0 else {}, top)

    again('another absolute path', top=os.path.join(work, 'elsewhere', 'deeper', 'b'))
    again('TZ=Pacific/Chatham LANG=de_DE.UTF-8', env=dict(env, TZ='Pacific/Chatham', LANG='de_DE.UTF-8',
                                                            LC_ALL='de_DE.UTF-8'))
    again('-j 7', jobs='7')

    def nobody_umask():
        os.umask(0o077)
        if os.getuid() == 0:
            os.setgid(65534)
            os.setuid(65534)
    again('umask 077' + (' as user nobody' if os.getuid() == 0 else ''), preexec=nobody_umask)
    if os.path.exists(generic):
        again('generic CPU path (make generic: no AVX2 clones)', binary=generic)
    else:
        check(False, 'build/generic/crowdbake exists (make generic)')

    # samples/catalog.toml itself (states, a LOD, a shared rig, per-animal overrides): the merge of its
    # per-type bakes writes the one-step manifest, byte for byte.
    sample_out = os.path.join(work, 'samples')
    shutil.rmtree(sample_out, ignore_errors=True)
    one, two = os.path.join(sample_out, 'one'), os.path.join(sample_out, 'two')
    rc = subprocess.run([crowdbake, 'bake', 'samples/catalog.toml', '--out-dir', one, '-q'], cwd=ROOT).returncode
    for t in ('bird', 'fish', 'goat', 'sheep'):
        rc |= subprocess.run([crowdbake, 'bake', 'samples/catalog.toml', '--type', t, '--out-dir', two, '-q'],
                             cwd=ROOT).returncode
    rc |= subprocess.run([crowdbake, 'roster', 'merge', '-q', '-o', os.path.join(two, 'roster.json')] +
                         [os.path.join(two, t + '.fragment') for t in ('bird', 'fish', 'goat', 'sheep')]).returncode
    same = rc == 0 and all(open(os.path.join(one, f), 'rb').read() == open(os.path.join(two, f), 'rb').read()
                           for f in ('roster.json', 'bird.pal', 'fish.pal', 'goat.pal'))
    check(same, 'samples/catalog.toml: merged manifest and palettes equal the one-step bake\'s')

    # The merge's refusals, each one line naming the file and the fix.
    def merge(args):
        return subprocess.run([crowdbake, 'roster', 'merge', '-o', 'bad.json'] + args, cwd=base_top,
                              capture_output=True, text=True)
    frags = ['split/%s.fragment' % t for t in TYPES]
    p = merge(frags[1:])
    check(p.returncode == 4 and 'no fragment for type cow' in p.stderr, 'a missing fragment is named: ' + p.stderr.strip())
    p = merge(frags + frags[:1])
    check(p.returncode == 4 and 'two fragments' in p.stderr, 'a repeated fragment is refused: ' + p.stderr.strip())
    damaged = os.path.join(base_top, 'split', 'damaged.fragment')
    data = open(os.path.join(base_top, frags[0]), 'rb').read()
    open(damaged, 'wb').write(data[:len(data) // 2])
    p = merge(['split/damaged.fragment'] + frags[1:])
    check(p.returncode == 4 and 'damaged' in p.stderr and not os.path.exists(os.path.join(base_top, 'bad.json')),
          'a damaged fragment is refused, nothing written: ' + p.stderr.strip())
    if FAILURES:
        print('hermetic: %d check(s) failed' % len(FAILURES), file=sys.stderr)
        return 1
    print('hermetic: all checks passed')
    return 0


if __name__ == '__main__':
    sys.exit(main())
