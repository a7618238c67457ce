"""The crowd benchmarks of bench/run.py: frame time of a herd drawn from its palette (per vertex, the bone pass,
its animation LOD, the herd-size choice) against the same herd drawn from a VAT, in headless Chromium
(tests/runtimes/browser/bench_crowd.mjs) and natively through EGL (bench/bench_gl.c)."""
import json
import os
import subprocess

from common import BUILD, EXE, ROOT, SHARED, run


def crowd_input(name, model, local=False):
    """model.glb, model.pal (qpos/u16 global rows, --bone-space global) and model.exr (its VAT) in
    build/bench/crowd-NAME; local: also model-local.pal, the default bake (local rows, composed by the runtime)."""
    out = os.path.join(BUILD, 'bench', 'crowd-' + name)
    os.makedirs(out, exist_ok=True)
    subprocess.run(['cp', model, os.path.join(out, 'model.glb')], check=True)
    subprocess.run([EXE, 'bake', model, '-o', os.path.join(out, 'model.pal'), '-q', '--root-motion', 'in-place',
                    '--bone-space', 'global'], check=True)
    if local:
        subprocess.run([EXE, 'bake', model, '-o', os.path.join(out, 'model-local.pal'), '-q', '--root-motion', 'in-place'],
                       check=True)
    subprocess.run([EXE, 'vat', model, '-o', os.path.join(out, 'model.exr'), '--root-motion', 'in-place',
                    '--exr-compression', 'none'], check=True, stdout=subprocess.DEVNULL)
    return out


CROWD_METHODS = ('palette', 'bones', 'lod', 'auto', 'vat')
# Local rows (web43): the same herd drawn from the model baked --bone-space local, per vertex and through the bone pass,
# beside the global palette's and the VAT's frames in the same run (Cow and Husky).
LOCAL_METHODS = ('palette', 'bones', 'lod', 'auto', 'local_palette', 'local_bones', 'local_lod', 'local_auto', 'vat')


def crowd_bench(smoke):
    runs = [('fish', os.path.join(BUILD, 'samples', 'fish.glb'), '10' if smoke else '10,30,100,1000,10000,100000',
             1 if smoke else 3, CROWD_METHODS)]
    if not smoke:
        runs.append(('Cow', os.path.join(SHARED, 'assets', 'quaternius-cow', 'Cow.glb'), '100,1000', 5, LOCAL_METHODS))
        runs.append(('Husky', os.path.join(SHARED, 'assets', 'quaternius-husky', 'Husky.glb'), '1000', 5, LOCAL_METHODS))
    results = []
    for name, model, counts, frames, methods in runs:
        local = any(m.startswith('local_') for m in methods)
        _, out = run(['node', os.path.join(ROOT, 'tests', 'runtimes', 'browser', 'bench_crowd.mjs'), crowd_input(name, model, local),
                      counts, '--frames', str(frames), '--methods', ','.join(methods)])
        r = json.loads(out.strip().split('\n')[-1])
        r['input'] = name
        results.append(r)
    return results


def print_methods(r, title, key='_ms', methods=LOCAL_METHODS, pairs=True):
    """A crowd table: frame ms of each method (palette: per-vertex blending; bones: the bone pass, every influence;
    lod: the bone pass with animation LOD; auto: Crowd's default choice; vat) and the VAT's speed over each: the
    median of the pairs' ratios where each frame drew every method in turns, else the ratio of the medians."""
    methods = [m for m in methods if any(m + key in c for c in r['counts'].values())]
    others = [m for m in methods if m != 'vat']
    print(title)
    print('%10s' % 'instances' + ''.join('%12s' % (m + ' ms') for m in methods) + ''.join('%14s' % ('speed ' + m) for m in others))
    for n, c in sorted(r['counts'].items(), key=lambda kv: int(kv[0])):
        t = {m: max(c[m + key], 1e-3) for m in methods}
        ratio = {m: c['vat_over_' + m] if pairs and 'vat_over_' + m in c else t['vat'] / t[m] for m in others}
        print('%10s' % n + ''.join('%12.1f' % t[m] for m in methods) + ''.join('%14.2f' % ratio[m] for m in others))
    print('(speed X: the VAT\'s frame time over X\'s, X\'s frame speed in VATs; >= 1.0: X at least as fast as the VAT)')
    if pairs and any('cpu_vat_over_' + m in c for c in r['counts'].values() for m in others):
        print('the same pairs by CPU time (the renderer\'s processes\' user + system time: what the frame cost, whatever else '
              'the machine ran):')
        for n, c in sorted(r['counts'].items(), key=lambda kv: int(kv[0])):
            print('%10s' % n + ''.join('%12.1f' % c.get(m + '_cpu_ms', 0) for m in methods) +
                  ''.join('%14.2f' % c.get('cpu_vat_over_' + m, 0) for m in others))
    held = {m: [int(n) for n, c in r['counts'].items() if c[m + key] <= 1000 / 60] for m in methods}
    print('VRAM: palette %d bytes, VAT %d bytes (%.1fx); largest measured herd holding 60 fps: %s' % (
        r['palette_bytes'], r['vat_bytes'], r['vat_bytes'] / r['palette_bytes'],
        ', '.join('%s %s' % (m, max(h) if h else 'none') for m, h in held.items())))
    if r.get('bytes_per_instance'):
        print('memory per instance: ' + ', '.join('%s %d bytes' % (m, b) for m, b in r['bytes_per_instance'].items()
                                                  if m in methods) + ' (the VAT\'s: its instance row; the bone pass adds '
              '48 bytes a bone)')
    if r.get('local_palette_bytes'):
        print('local rows: palette %d bytes (global %d)' % (r['local_palette_bytes'], r['palette_bytes']))
    for n, c in sorted((r.get('local_auto_choice') or {}).items(), key=lambda kv: int(kv[0])):
        print('local auto at %s: %s (%s)' % (n, c['method'], c['reason']))
    if r.get('lod_choice'):
        print('animation LOD: ' + r['lod_choice'])
    for n, c in sorted((r.get('auto_choice') or {}).items(), key=lambda kv: int(kv[0])):
        print('auto at %s: %s (%s)' % (n, c['method'], c['reason']))


def print_crowd(results):
    for r in results:
        print_methods(r, '\ncrowd: %s (%d vertices), WebGL2 in headless Chromium on %s; median of %d frames (960x540, each to '
                      'a readPixels sync)' % (r['input'], r['vertices'], r['renderer'], r['frames']))


# The native benchmark (bench/bench_gl.c, OpenGL through EGL): llvmpipe here, where a whole frame of
# 100,000 Cows takes minutes; on a GPU: python3 bench/run.py --gl-only --gl-counts 1000,3000,10000,30000,100000,300000
# (model, counts, frames, --lod: the bone pass with the runtimes' default animation LOD, lod 'auto', in place of every influence)
GL_RUNS = (('Cow', '1000', 5, False), ('Cow', '1000', 5, True), ('Husky', '1000', 5, False), ('Husky', '1000', 5, True),
           ('fish', '100,1000,10000,100000', 3, False))
GL_METHODS = ('palette', 'bones', 'lod', 'vat')


def gl_bench(smoke, counts=None):
    models = {'Cow': os.path.join(SHARED, 'assets', 'quaternius-cow', 'Cow.glb'),
              'Husky': os.path.join(SHARED, 'assets', 'quaternius-husky', 'Husky.glb'),
              'fish': os.path.join(BUILD, 'samples', 'fish.glb')}
    runs = [('fish', '10', 1, True)] if smoke else [(name, counts or c, frames, lod) for name, c, frames, lod in GL_RUNS]
    results = []
    for name, c, frames, lod in runs:
        _, out = run([os.path.join(BUILD, 'bench_gl'), models[name], c, '--frames', str(frames)] + (['--lod'] if lod else []))
        r = json.loads(out.strip().split('\n')[-1])
        r['input'] = name
        results.append(r)
    return results


def print_gl(results):
    for r in results:
        head = '\nnative: %s (%d vertices), OpenGL %s on %s (EGL, no window); median of %d frames (960x540, ' % (
            r['input'], r['vertices'], r['version'], r['renderer'], r['frames'])
        print_methods(r, head + 'GL_TIME_ELAPSED)', methods=GL_METHODS, pairs=False)
        print_methods(r, head + 'wall time to glFinish)', '_wall_ms', methods=GL_METHODS)
        if r.get('lod_one_pixels'):
            print('lod (the runtimes\' lod \'auto\'): 2 influences under %.1f pixels tall, 1 under %.1f: there the worst vertex of '
                  '64 poses moves at most a pixel' % (r['lod_two_pixels'], r['lod_one_pixels']))
