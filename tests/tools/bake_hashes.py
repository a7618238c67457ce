#!/usr/bin/env python3
"""bake_hashes.py [--write] [--build DIR] [--shared DIR]: the bytes every bake writes, pinned.

Bakes every bundled sample and every shared asset in several formats (.pal, .pal with zstd,
.exr, mat4/half, affine/float; the default bake (local rows) and its global rows, kept and in place; .pal +
.exr + .ktx2 on the samples and Fox; .bvat.json on the samples, Fox and Cow; local rows at 30 fps on the samples,
Fox, Cow and Husky), `inspect --json` of each
default and local .pal, and the sample catalog (palettes, roster.json, depfile, with a --format pal,exr and a --format pal,babylon
override too), then compares the sha256 of every file with tests/bake_hashes.txt. A model that
does not bake is recorded by its exit code. `make check` runs this (normal build only), so a
refactoring that changes one output byte fails.

When an output changes ON PURPOSE (a new header field, a better encoder), regenerate the list
with `make bake-hashes` (this script with --write), read the diff of tests/bake_hashes.txt (only
the outputs you meant to change should move) and commit it with the change."""
import hashlib, os, re, shutil, subprocess, sys

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(os.path.dirname(HERE))
LIST = os.path.join(ROOT, 'tests', 'bake_hashes.txt')

# Every model bakes in these; the name is the key in the list. They bake at a fixed 30 fps, the
# default before bakes were error-bounded, and global rows, the default before local rows were:
# their bytes are the ones pinned before (the proof that --fps 30 --bone-space global keeps them).
VARIANTS = [
    ('default.pal', ['-o', '{out}.pal', '--fps', '30', '--bone-space', 'global']),
    ('default.exr', ['-o', '{out}.exr', '--fps', '30']),
    ('zstd-inplace', ['-o', '{out}.pal', '--format', 'pal,exr', '--zstd', '--root-motion', 'in-place', '--fps', '30',
                      '--bone-space', 'global']),
    ('mat4-half.pal', ['-o', '{out}.pal', '--layout', 'mat4', '--precision', 'half', '--fps', '30']),
    ('affine-float.exr', ['-o', '{out}.exr', '--layout', 'affine', '--precision', 'float', '--exr-compression', 'zip',
                          '--fps', '30']),
]
KTX2 = ('pal-exr-ktx2', ['-o', '{out}.pal', '--format', 'pal,exr,ktx2', '--precision', 'half', '--fps', '30'])
BABYLON = ('babylon', ['-o', '{out}.bvat.json', '--fps', '30'])  # Babylon.js's baked vertex animation data
LOCAL = ('local.pal', ['-o', '{out}.pal', '--fps', '30', '--bone-space', 'local'])  # local rows, .pal version 6
# The default bake (no --fps: error-bounded within 1 mm/m; local rows, sampled), and its global rows (fitted or
# sampled per clip, the default before local rows) kept and in place; a model whose clips cannot meet the budget is
# recorded by its exit code (6), and the other variants still run.
ERROR_BOUNDED = [('auto-local.pal', ['-o', '{out}.pal', '-q']),
                 ('auto.pal', ['-o', '{out}.pal', '-q', '--bone-space', 'global']),
                 ('auto-inplace.pal', ['-o', '{out}.pal', '-q', '--root-motion', 'in-place', '--bone-space', 'global'])]


def sha(path):
    with open(path, 'rb') as f:
        return hashlib.sha256(f.read()).hexdigest()


def models(build, shared):
    found = [os.path.join(build, 'samples', n) for n in sorted(os.listdir(os.path.join(build, 'samples')))
             if n.endswith('.glb')]
    for d, _, files in sorted(os.walk(os.path.join(shared, 'assets'))):
        found += [os.path.join(d, n) for n in sorted(files) if n.endswith(('.glb', '.gltf'))]
    return found


def key_of(model, shared):
    rel = os.path.relpath(model, os.path.join(shared, 'assets'))
    return ('shared/' + rel) if not rel.startswith('..') else 'samples/' + os.path.basename(model)


def run(cmd, **kw):
    return subprocess.run(cmd, stdout=subprocess.PIPE, stderr=subprocess.PIPE, **kw)


def bake_models(crowdbake, build, shared, tmp, out):
    for model in models(build, shared):
        key = key_of(model, shared)
        variants = VARIANTS + ([KTX2] if key.startswith('samples/') or key.endswith('fox-bevy/Fox.glb') else [])
        variants += [BABYLON] if key.startswith('samples/') or key.endswith(('Fox.glb', 'Cow.glb')) else []
        variants += [LOCAL] if key.startswith('samples/') or key.endswith(('Fox.glb', 'Cow.glb', 'Husky.glb')) else []
        for name, args in variants + ERROR_BOUNDED:
            d = os.path.join(tmp, key.replace('/', '_'), name)
            os.makedirs(d)
            stem = os.path.join(d, 'out')
            p = run([crowdbake, 'bake', model, '-j', '2'] + [a.format(out=stem) for a in args])
            if p.returncode:
                out.append('%s %s exit %d' % (key, name, p.returncode))
                if (name, args) in ERROR_BOUNDED:
                    continue  # over its budget: the fixed-rate variants baked
                break  # a model that does not bake fails the same way in every variant
            for f in sorted(os.listdir(d)):
                out.append('%s %s %s %s' % (key, name, f, sha(os.path.join(d, f))))
            if name in ('default.pal', 'local.pal'):
                p = run([crowdbake, 'inspect', 'out.pal', '--json'], cwd=d)  # no absolute path in what is hashed
                out.append('%s %s inspect-json %s' % (key, name, hashlib.sha256(p.stdout).hexdigest()))


def bake_catalog(crowdbake, build, tmp, out):
    samples = os.path.abspath(os.path.join(build, 'samples'))
    text = open(os.path.join(ROOT, 'samples', 'catalog.toml')).read()
    # The catalog names its models through a link beside it, so that no absolute path (which
    # differs between checkouts) reaches the outputs.
    text = text.replace('../build/samples', 'samples').replace('"../build/roster"', '"roster"')
    variants = (('catalog', []), ('catalog-pal-exr', ['--format', 'pal,exr', '--precision', 'half', '--zstd']),
                ('catalog-babylon', ['--format', 'pal,babylon']))
    for name, extra in variants:
        d = os.path.join(tmp, name)
        os.makedirs(d)
        os.symlink(samples, os.path.join(d, 'samples'))
        with open(os.path.join(d, 'catalog.toml'), 'w') as f:
            f.write(text)
        p = run([crowdbake, 'bake', 'catalog.toml', '-j', '2', '-q', '--depfile', 'roster.d'] + extra, cwd=d)
        if p.returncode:
            out.append('%s exit %d' % (name, p.returncode))
            continue
        for root, _, files in sorted(os.walk(d)):  # (os.walk does not enter the link)
            for f in sorted(files):
                path = os.path.join(root, f)
                rel = os.path.relpath(path, d)
                if rel == 'catalog.toml' or (f.startswith('.') and f.endswith('.prep')):
                    continue  # the input; the prep records (cli/roster/roster_cache.h), a cache in this machine's byte order
                data = open(path, 'rb').read()
                if f == 'roster.d':  # it names the executable (a new crowdbake re-runs the build), wherever it is
                    data = data.replace(os.path.realpath(crowdbake).encode(), b'CROWDBAKE')
                out.append('%s %s %s' % (name, rel, hashlib.sha256(data).hexdigest()))


def main():
    args = sys.argv[1:]
    build = args[args.index('--build') + 1] if '--build' in args else 'build'
    shared = args[args.index('--shared') + 1] if '--shared' in args else os.environ.get('CROWDBAKE_SHARED', '../shared')
    crowdbake = os.path.abspath(os.path.join(build, 'crowdbake'))
    tmp = os.path.abspath(os.path.join(build, 'tmp-tests', 'bake_hashes'))
    shutil.rmtree(tmp, ignore_errors=True)
    os.makedirs(tmp)
    out = []
    bake_models(crowdbake, build, shared, tmp, out)
    bake_catalog(crowdbake, build, tmp, out)
    text = '\n'.join(out) + '\n'
    if '--write' in args:
        with open(LIST, 'w') as f:
            f.write(text)
        print('bake_hashes: %d outputs recorded in %s' % (len(out), os.path.relpath(LIST, ROOT)))
        return 0
    want = open(LIST).read().splitlines()
    got = text.splitlines()
    if got == want:
        print('bake_hashes: %d outputs byte-identical with tests/bake_hashes.txt' % len(got))
        return 0
    import difflib
    sys.stdout.writelines(l + '\n' for l in difflib.unified_diff(want, got, 'tests/bake_hashes.txt', 'now', lineterm=''))
    print('bake_hashes: outputs differ from tests/bake_hashes.txt (if on purpose: `make bake-hashes`, check the diff, '
          'commit it)')
    return 1


if __name__ == '__main__':
    sys.exit(main())
