"""Issue 43, item 1: where the default (error-bounded) bake's bytes go, against a fixed --fps 30 bake of
the same layout and precision, and what each lever would save, on the shared animals, the fish and the robot.

Every number here is a byte count or an error the bake measures: deterministic, one run. For each model:
- the texture bytes (the header's payload_raw_size) of the default bake (local rows at their auto rates, timed
  where that costs fewer rows) and of --fps 30, and their ratio (issue 43's goal: <= 1.0x on Cow, Husky and Fox,
  <= 1.5x on the fish); the same for --bone-space global (global rows, the default before), with its visible
  error, and for the global rows of --timed-rows on (rows on the keys where fewer, asked for);
- the budget's split: the encoding error at the rows (u16 quantisation, one box for the file), measured on the
  --fps 30 bake (sampled rows, so it is the quantisation alone), against the float bake's;
- the levers, from bench_rows (bench/bench_rows.c): the rows a per-clip time -> row map would need (rows placed
  per key interval, each interval split as its own motion needs, sampled rows; and an estimate for fitted rows,
  which halve the blend's error), and the joints that skin no vertex (rows only for the joints that skin
  would leave out their texels)."""
import json
import os
import struct
import subprocess

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
BUILD = os.path.join(ROOT, 'build')
SHARED = os.environ.get('CROWDBAKE_SHARED', os.path.join(ROOT, '..', 'shared'))
EXE = os.environ.get('CROWDBAKE', os.path.join(BUILD, 'crowdbake'))

GOALS = {'Cow': 1.0, 'Husky': 1.0, 'Fox': 1.0, 'fish': 1.5}


def models(smoke):
    fish = ('fish', os.path.join(BUILD, 'samples', 'fish.glb'))
    if smoke:
        return [fish]
    a = os.path.join(SHARED, 'assets')
    return [('Cow', os.path.join(a, 'quaternius-cow', 'Cow.glb')), ('Husky', os.path.join(a, 'quaternius-husky', 'Husky.glb')),
            ('Fox', os.path.join(a, 'fox-bevy', 'Fox.glb')), fish,
            ('robot', os.path.join(a, 'robot-quaternius-raylib', 'robot.glb'))]


def header(path):
    """The .pal header's sizes and errors (docs/pal-format.md)."""
    with open(path, 'rb') as f:
        d = f.read(256)
    rows, = struct.unpack_from('<I', d, 40)
    max_error, height, visible = struct.unpack_from('<3f', d, 100)
    raw, = struct.unpack_from('<Q', d, 168)
    mm = lambda e: e / height * 1000 if height > 0 else 0
    return {'rows': rows, 'texture_bytes': raw, 'encoding_mm': mm(max_error), 'visible_mm': mm(visible)}


def bake(model, out, extra):
    subprocess.run([EXE, 'bake', model, '-o', out, '-q'] + extra, check=True, stderr=subprocess.DEVNULL)
    return header(out)


def one_model(name, model):
    out = os.path.join(BUILD, 'bench', 'bytes.pal')
    os.makedirs(os.path.dirname(out), exist_ok=True)
    auto, fixed = bake(model, out, []), bake(model, out, ['--fps', '30'])
    fixed_float = bake(model, out, ['--fps', '30', '--precision', 'float'])
    glob = bake(model, out, ['--bone-space', 'global'])
    timed = bake(model, out, ['--timed-rows', 'on', '--bone-space', 'global'])
    lines = subprocess.run([os.path.join(BUILD, 'bench_rows'), model], check=True, capture_output=True, text=True).stdout
    rows = [json.loads(line) for line in lines.splitlines() if line.strip()]
    skin, clips = rows[0], rows[1:]
    total = lambda key: sum(c[key] for c in clips)
    return {'model': name, 'auto': auto, 'fixed': fixed, 'ratio': auto['texture_bytes'] / fixed['texture_bytes'],
            'global': glob, 'global_ratio': glob['texture_bytes'] / fixed['texture_bytes'],
            'timed': timed, 'timed_ratio': timed['texture_bytes'] / fixed['texture_bytes'],
            'goal': GOALS.get(name), 'quantisation_mm': fixed['encoding_mm'] - fixed_float['encoding_mm'],
            'bones': skin['bones'], 'bones_skinning_nothing': skin['bones_skinning_nothing'],
            'map_rows': total('map_rows'), 'map_rows_fitted_estimate': total('map_rows_fitted_estimate'),
            'rows_30fps': total('rows_30fps'), 'clips': clips,
            'blends': {kind: {'uniform_rows': total(prefix + 'uniform_rows'), 'map_rows': total(prefix + 'map_rows')}
                       for kind, prefix in (('chord', ''), ('dual', 'dual_'), ('local', 'local_'))}}


def bytes_bench(smoke):
    return [one_model(name, path) for name, path in models(smoke)]


def print_bytes(results):
    print('\nbytes (issue 43, item 1): the default bake (1 mm/m, a goal; local rows) against --fps 30, same layout and '
          'precision; texture bytes, one run (deterministic)')
    print('%-6s %9s %9s %6s %6s  %15s %6s  %15s %6s  %6s %6s  %8s  %9s %9s  %8s' % (
        'model', 'default', '--fps 30', 'ratio', 'goal', 'global (ratio)', 'mm/m', 'timed (ratio)', 'mm/m', 'enc', 'quant',
        'rows', 'map rows', 'fitted~', 'unskinned'))
    for r in results:
        a, f = r['auto'], r['fixed']
        keep = 1 - r['bones_skinning_nothing'] / r['bones']
        loc, tim = r['global'], r['timed']
        print('%-6s %9d %9d %5.2fx %6s  %8d (%4.2fx) %6.3f  %8d (%4.2fx) %6.3f  %6.3f %6.3f  %4d/%-4d %5d %4.2fx %5d %4.2fx  '
              '%2d/%-2d %4.2fx' % (
            r['model'], a['texture_bytes'], f['texture_bytes'], r['ratio'], '<=%.1fx' % r['goal'] if r['goal'] else '-',
            loc['texture_bytes'], r['global_ratio'], loc['visible_mm'], tim['texture_bytes'], r['timed_ratio'], tim['visible_mm'],
            a['encoding_mm'], r['quantisation_mm'], a['rows'], f['rows'],
            r['map_rows'], r['map_rows'] / r['rows_30fps'], r['map_rows_fitted_estimate'],
            r['map_rows_fitted_estimate'] / r['rows_30fps'], r['bones_skinning_nothing'], r['bones'],
            r['map_rows_fitted_estimate'] / r['rows_30fps'] * keep))
    print('  default: local rows (.pal version 6, 7 with timed rows) at their auto rates, every clip within 1 mm/m; the '
          'runtimes compose them, at global rows\' cost through a bone pass; global: --bone-space global, each bone\'s '
          'skinning transform (the default before local rows), mm/m its visible error; timed: --timed-rows on '
          '--bone-space global, global rows on their keys where that takes fewer rows (asked for: weighing them costs '
          'the default bake\'s time)')
    print('  enc: the default bake\'s encoding error at its rows (mm/m); '
          'quant: what u16 adds over float at --fps 30\'s sampled rows (the most a per-clip quantisation box could win '
          'back of the 1 mm/m budget); map rows: a time -> row map, rows per key interval as its motion needs '
          '(sampled; fitted~ estimated at twice the blend budget), and its ratio to --fps 30\'s rows; unskinned: joints '
          'no vertex is weighted to, and the fitted map\'s ratio with their texels left out too')
    print('\nthe blend between two rows, weighed (bench_rows, sampled rows, every clip within 1 mm/m): rows at one '
          'key-aligned rate per clip | placed per key interval, against --fps 30\'s rows')
    print('%-6s %15s %15s %15s' % ('model', 'global (today)', 'dual quat', 'local composed'))
    for r in results:
        b, n = r['blends'], r['rows_30fps']
        print('%-6s %s' % (r['model'], ' '.join('%6.2fx |%5.2fx' % (b[k]['uniform_rows'] / n, b[k]['map_rows'] / n)
                                                 for k in ('chord', 'dual', 'local'))))
    print('  global: the rows hold each joint\'s global rotation and pivot, blended as they are (the shipped runtimes); '
          'dual quat: the same rows blended as dual quaternions (a screw between them); local composed: the rows hold '
          'each joint\'s transform in its parent joint\'s frame, blended joint by joint (nlerp, lerp) and composed down '
          'the skeleton, as a bone pass could: at rows on the keys, the glTF\'s own interpolation')
    for r in results:
        worst = sorted(r['clips'], key=lambda c: c['map_rows'] / max(1, c['key_intervals']), reverse=True)[:3]
        print('  %s, rows a map needs per key interval, most first: %s' % (r['model'], ', '.join(
            '%s %d/%d' % (c['clip'].split('|')[-1], c['map_rows'], c['key_intervals']) for c in worst)))
