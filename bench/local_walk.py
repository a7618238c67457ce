#!/usr/bin/env python3
"""Issue 43 item 1, weighed at draw time: local rows (the shipped GLSL's CB_LOCAL_ROWS, bench_gl --local-rows: the
bone pass and the direct path each walking a bone's chain) against global rows, on llvmpipe through EGL.

    python3 bench/local_walk.py [--rounds R] [--frames K] [--count N] [--models Cow,Husky]

Each round runs, per model, bench_gl N --lod with global and with local rows in turns (the order alternating round
by round), and the same two with --pass-only (the pass alone). Reported: medians over the rounds of each run's VAT /
lod frame-time ratio (bench_gl pairs each frame's VAT with the same moment's lod frame: a change of load hits both),
wall and CPU, of the frame CPU ms (palette: the direct path), and of the pass's own CPU ms; the load average."""
import argparse
import json
import os
import statistics

from common import BUILD, SHARED, run

MODELS = {'Cow': os.path.join(SHARED, 'assets', 'quaternius-cow', 'Cow.glb'),
          'Husky': os.path.join(SHARED, 'assets', 'quaternius-husky', 'Husky.glb'),
          'fish': os.path.join(BUILD, 'samples', 'fish.glb')}
VARIANTS = ('global', 'local')


def bench(model, variant, count, frames, pass_only):
    env = dict(os.environ, EGL_PLATFORM=os.environ.get('EGL_PLATFORM', 'surfaceless'))
    args = [os.path.join(BUILD, 'bench_gl'), MODELS[model], str(count), '--frames', str(frames), '--lod']
    if variant != 'global':
        args.append('--local-rows')
    if pass_only:
        args.append('--pass-only')
    _, out = run(args, env=env)
    return json.loads(out.strip().split('\n')[-1])['counts'][str(count)]


def main():
    ap = argparse.ArgumentParser(description=__doc__.split('\n')[0])
    ap.add_argument('--rounds', type=int, default=5)
    ap.add_argument('--frames', type=int, default=5)
    ap.add_argument('--count', type=int, default=1000)
    ap.add_argument('--models', default='Cow,Husky')
    a = ap.parse_args()
    keys = ('vat_over_lod', 'cpu_vat_over_lod', 'lod_cpu_ms', 'vat_cpu_ms', 'palette_cpu_ms', 'pass_cpu_ms')
    got = {}
    loads = []
    variants = VARIANTS
    for m, v in [(m, v) for m in a.models.split(',') for v in variants]:
        got[(m, v)] = {k: [] for k in keys}
    for r in range(a.rounds):
        for m in a.models.split(','):
            for v in (variants if r % 2 == 0 else variants[::-1]):
                loads.append(os.getloadavg()[0])
                frame = bench(m, v, a.count, a.frames, False)
                for k in keys[:5]:
                    got[(m, v)][k].append(frame[k])
                got[(m, v)]['pass_cpu_ms'].append(bench(m, v, a.count, 3, True)['lod_cpu_ms'])
        print('round %d done, load %.2f' % (r + 1, loads[-1]), flush=True)
    print('%d instances a model (--lod), %d rounds of %d frames, load average %.2f-%.2f' % (
        a.count, a.rounds, a.frames, min(loads), max(loads)))
    print('model  pass     vat/lod wall  vat/lod cpu  lod cpu ms  vat cpu ms  palette cpu ms  pass alone cpu ms')
    for (m, v), d in got.items():
        med = {k: statistics.median(x) if x else float('nan') for k, x in d.items()}
        print('%-6s %-8s %12.3f %12.3f %11.1f %11.1f %15.1f %18.1f   (vat/lod cpu per round: %s)' % (
            m, v, med['vat_over_lod'], med['cpu_vat_over_lod'], med['lod_cpu_ms'], med['vat_cpu_ms'],
            med['palette_cpu_ms'], med['pass_cpu_ms'], ' '.join('%.3f' % x for x in d['cpu_vat_over_lod'])))


if __name__ == '__main__':
    main()
