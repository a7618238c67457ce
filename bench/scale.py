#!/usr/bin/env python3
"""bench/scale.py - roster bakes as the type count grows (make bench-scale; issue 46).

  python3 bench/scale.py [--build DIR] [--shared DIR] [--counts 10,100,1000] [--bazel-types N] [--no-bazel]

1. Memory and time against the type count: catalogs of 10, 100 and 1,000 types, each type a
   variant of the generated samples (fish, bird, quadruped) under a new file name, the variants
   spread over 10 distinct palettes (model x layout). For each: peak RSS and wall time of the cold
   `bake` (-j 2), its no-op rerun, `report` and `report` again (report2: every type's record holds its
   VAT error, so nothing is loaded or sampled). Peak memory should be flat in the types beyond the
   distinct palettes; each count's ratio to the 10-type run is printed.
2. Scale out (unless --no-bazel): the same generated roster of --bazel-types types (default 1,000)
   as Bazel actions (bazel/crowdbake.bzl, bazel-bootstrap, sandboxed) against `make -j 2` running
   the same per-type commands (`bake --type` + `roster merge`): the action count, each's wall
   time, the peak memory of one type's action, the merge's time, and the incremental rebuild
   after one model changes, for both.

Prints a table; bench/RESULTS.txt keeps one run's numbers.
"""
import argparse
import os
import shutil
import struct
import subprocess
import sys
import time

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
sys.path.insert(0, os.path.join(ROOT, 'tests', 'tools'))
import bazel_rules  # noqa: E402  (the workspace helpers and the GLB touch)

MODELS = ['fish', 'bird', 'quadruped']
LAYOUTS = ['qpos', 'affine', 'mat4']
PALETTES = 10


def variant(i):
    """Type i's model and layout: PALETTES distinct (model, layout) pairs."""
    v = i % PALETTES
    return MODELS[v % 3], LAYOUTS[(v // 3) % 3], v


def make_roster(top, build, count):
    shutil.rmtree(top, ignore_errors=True)
    os.makedirs(os.path.join(top, 'models'))
    lines = ['[bake]', 'out_dir = "out"', 'root_motion = "in-place"', '']
    models = {}
    for i in range(count):
        model, layout, v = variant(i)
        name = 'm%04d.glb' % i  # every type its own file: variants under new names
        shutil.copyfile(os.path.join(build, 'samples', model + '.glb'), os.path.join(top, 'models', name))
        t = 't%04d' % i
        models[t] = 'models/' + name
        lines += ['[animal.%s]' % t, 'model = "models/%s"' % name, 'layout = "%s"' % layout, '']
    with open(os.path.join(top, 'catalog.toml'), 'w') as f:
        f.write('\n'.join(lines))
    return models


def timed(cmd, cwd):
    """(wall seconds, peak RSS in MB, exit code) of one command, by /usr/bin/time."""
    t0 = time.monotonic()
    p = subprocess.run(['/usr/bin/time', '-f', '%M'] + cmd, cwd=cwd, capture_output=True, text=True)
    wall = time.monotonic() - t0
    rss = int(p.stderr.strip().splitlines()[-1]) / 1024 if p.stderr.strip() else 0
    if p.returncode:
        sys.stderr.write(p.stderr[-2000:])
    return wall, rss, p.returncode


def memory_and_time(build, crowdbake, counts, work):
    print('== roster bake, no-op rerun and report against the type count (%d distinct palettes, -j 2)' % PALETTES)
    print('%6s  %-8s %9s %9s   %s' % ('types', 'step', 'wall s', 'peak MB', 'vs 10 types (wall, memory)'))
    base = {}
    for n in counts:
        top = os.path.join(work, 'roster%d' % n)
        make_roster(top, build, n)
        for step, cmd in (('bake', ['bake', 'catalog.toml', '-q', '-j', '2']),
                          ('rerun', ['bake', 'catalog.toml', '-q', '-j', '2']),
                          ('report', ['report', 'catalog.toml', '-q', '-j', '2', '--json', '--no-fail']),
                          ('report2', ['report', 'catalog.toml', '-q', '-j', '2', '--json', '--no-fail'])):
            wall, rss, rc = timed([crowdbake] + cmd, top)
            if step not in base:
                base[step] = (wall, rss)
            bw, br = base[step]
            print('%6d  %-8s %9.2f %9.1f   %.1fx, %.2fx%s' % (n, step, wall, rss, wall / bw if bw else 0,
                                                        rss / br if br else 0, '' if rc == 0 else '  (exit %d)' % rc),
                  flush=True)


def write_makefile(top, crowdbake, types):
    frags = ' '.join('split/%s.fragment' % t for t in types)
    rules = ['all: split/roster.json', 'split/roster.json: %s' % frags,
             '\t%s roster merge -q -o $@ $^' % crowdbake]
    for t, model in types.items():
        rules += ['split/%s.fragment: catalog.toml %s' % (t, model),
                  '\t%s bake catalog.toml --type %s --out-dir split -q -j 1' % (crowdbake, t)]
    with open(os.path.join(top, 'Makefile'), 'w') as f:
        f.write('\n'.join(rules) + '\n')


def scale_out(build, shared, crowdbake, count, work):
    print('\n== %d types as one action each: Bazel (sandboxed, --jobs 2) against make -j 2' % count)
    top = os.path.join(work, 'make%d' % count)
    types = make_roster(top, build, count)
    write_makefile(top, crowdbake, types)
    wall, _, rc = timed(['make', '-j', '2', '-s'], top)
    print('make -j 2: %d type commands + 1 merge, %.1f s%s' % (count, wall, '' if rc == 0 else ' (exit %d)' % rc))
    one = sorted(types)[0]
    w1, rss1, _ = timed([crowdbake, 'bake', 'catalog.toml', '--type', one, '--out-dir', 'one', '-q', '-j', '1'], top)
    print('one type\'s action: %.3f s, peak %.1f MB' % (w1, rss1))
    wm, rssm, _ = timed([crowdbake, 'roster', 'merge', '-q', '-o', 'merged.json'] +
                        ['split/%s.fragment' % t for t in sorted(types)], top)
    print('the merge of %d fragments: %.3f s, peak %.1f MB' % (count, wm, rssm))
    bazel_rules.touch_glb(os.path.join(top, types[one]))
    wi, _, _ = timed(['make', '-j', '2', '-s'], top)
    print('make -j 2 after one model changed: %.2f s' % wi)

    ws = os.path.join(work, 'bazel%d' % count)
    bazel_rules.make_workspace(ws, os.path.join(build, 'bundle'), shared)
    shutil.rmtree(os.path.join(ws, 'roster'))
    make_roster(os.path.join(ws, 'roster'), build, count)
    with open(os.path.join(ws, 'roster', 'BUILD.bazel'), 'w') as f:
        f.write('load("//bazel:crowdbake.bzl", "crowdbake_roster")\n\ncrowdbake_roster(\n    name = "zoo",\n'
                '    catalog = "catalog.toml",\n    models = {\n%s    },\n    crowdbake = "//tools/crowdbake",\n'
                '    report = False,\n)\n' % ''.join('        "%s": ["%s"],\n' % (t, m) for t, m in sorted(types.items())))
    user_root = os.path.join(work, 'bazel_user_root')
    log = os.path.join(work, 'exec.json')
    try:
        bazel_rules.bazel(ws, user_root, ['clean'])
        t0 = time.monotonic()
        rc = bazel_rules.bazel(ws, user_root, ['build', '--jobs=2', '//roster:zoo'], log)
        wb = time.monotonic() - t0
        ran = bazel_rules.executed(log)
        print('bazel build --jobs=2: %d actions (%d CrowdbakeType, %d merge), %.1f s (server warm)%s' % (
            len(ran), ran.count('CrowdbakeType'), ran.count('CrowdbakeMerge'), wb, '' if rc == 0 else ' (failed)'))
        bazel_rules.touch_glb(os.path.join(ws, 'roster', types[one]))
        t0 = time.monotonic()
        bazel_rules.bazel(ws, user_root, ['build', '--jobs=2', '//roster:zoo'], log)
        wi = time.monotonic() - t0
        ran = bazel_rules.executed(log)
        print('bazel after one model changed: %s, %.2f s' % (ran, wi))
    finally:
        bazel_rules.bazel(ws, user_root, ['shutdown'])


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument('--build', default=os.path.join(ROOT, 'build'))
    ap.add_argument('--shared', default=os.path.join(ROOT, '..', 'shared'))
    ap.add_argument('--counts', default='10,100,1000')
    ap.add_argument('--bazel-types', type=int, default=1000)
    ap.add_argument('--no-bazel', action='store_true')
    ap.add_argument('--crowdbake', help='the binary to measure (default BUILD/crowdbake): a baseline to compare')
    ap.add_argument('--work', help='where the rosters are made (default BUILD/bench_scale)')
    a = ap.parse_args()
    build = os.path.abspath(a.build)
    crowdbake = os.path.abspath(a.crowdbake) if a.crowdbake else os.path.join(build, 'crowdbake')
    work = os.path.abspath(a.work) if a.work else os.path.join(build, 'bench_scale')
    os.makedirs(work, exist_ok=True)
    memory_and_time(build, crowdbake, [int(c) for c in a.counts.split(',')], work)
    if not a.no_bazel:
        scale_out(build, os.path.abspath(a.shared), crowdbake, a.bazel_types, work)
    return 0


if __name__ == '__main__':
    sys.exit(main())
