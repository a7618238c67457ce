#!/usr/bin/env python3
"""bench/auto_ab.py - two builds' default bakes against the same naive bake, interleaved (issue 43 item 2).

  python3 bench/auto_ab.py [--shared DIR] [--repeat N] BEFORE_EXE AFTER_EXE

bench/auto_speed.py times one build; on a VM shared with other work the load moves its ratios
between two runs more than a change does. Here, per model (Cow, Husky, Fox), each round runs
three commands, in every order as often as the others: BEFORE's default bake
(`bake MODEL -q --root-motion in-place`), AFTER's, and BEFORE's naive bake (`--fps 30
--max-error 1000`: the same rows with a budget nothing misses, so no search). Printed: the
medians of the per-round ratios default/naive for each build, and AFTER/BEFORE of the default
bakes, with the 1-minute load before and after.
"""
import argparse
import os
import statistics

from auto_speed import MODELS, ROOT, interleaved


def median_ratio(a, b):
    return statistics.median(x / y for x, y in zip(a, b))


def measure(before, after, model, out, repeat):
    base = ['bake', model, '-q', '--root-motion', 'in-place']
    cmds = {'before': [before] + base + ['-o', out + '.before.pal'], 'after': [after] + base + ['-o', out + '.after.pal'],
            'naive': [before] + base + ['-o', out + '.naive.pal', '--fps', '30', '--max-error', '1000']}
    return interleaved(cmds, repeat)


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument('--shared', default=os.path.join(ROOT, '..', 'shared'))
    ap.add_argument('--repeat', type=int, default=30)
    ap.add_argument('before')
    ap.add_argument('after')
    a = ap.parse_args()
    out = os.path.join(ROOT, 'build', 'bench', 'auto_ab')
    os.makedirs(os.path.dirname(out), exist_ok=True)
    print('load %.2f; %d rounds; medians of per-round ratios' % (os.getloadavg()[0], a.repeat))
    print('%-6s %9s %10s %10s %13s %13s %13s' % ('model', 'naive ms', 'before ms', 'after ms', 'before/naive',
                                                 'after/naive', 'after/before'))
    for name, rel in MODELS:
        t = measure(os.path.abspath(a.before), os.path.abspath(a.after), os.path.join(a.shared, 'assets', rel), out,
                    a.repeat)
        ms = {k: statistics.median(v) * 1e3 for k, v in t.items()}
        print('%-6s %9.1f %10.1f %10.1f %12.3fx %12.3fx %13.3f' % (
            name, ms['naive'], ms['before'], ms['after'], median_ratio(t['before'], t['naive']),
            median_ratio(t['after'], t['naive']), median_ratio(t['after'], t['before'])), flush=True)
    print('load %.2f' % os.getloadavg()[0])
    return 0


if __name__ == '__main__':
    raise SystemExit(main())
