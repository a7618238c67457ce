#!/usr/bin/env python3
"""crowdbake benchmark: crowdbake against its peer (three.js GLTFLoader + AnimationMixer, bench/peer.mjs)
measured in the same run on the same inputs.

  python3 bench/run.py [--repeat N] [--json] [--smoke]

Inputs: ../shared/assets Fox.glb and robot.glb, and rigs from the sample generator: 200 joints x
{8, 15, 30, 60} clips x 10 s at 30 fps (the 30-clip rig is 9,000 frames, 1.8 M joint matrices).
For each: whole-process wall time and peak RSS of `crowdbake bake` to a .pal (with its own
load/sample/encode/measure/write split), and the peer's in-process load + sampling and whole
process. Median of N runs, with the spread (min..max). --smoke runs one tiny input once, so
`make check` keeps the script working.

The crowd benchmark (tests/browser/bench_crowd.mjs, headless Chromium): frame time of a herd drawn
from its palette against the same herd drawn from a VAT of the same frames (crowdbake vat), one
instanced draw each, alternating in one page, for 10 to 100,000 instances of the fish sample and
1,000 Cows. --crowd-only runs only it. Without a GPU, Chromium renders with SwiftShader (software:
its absolute times say little about a GPU; the ratio is measured in the same run).
"""
import argparse, json, math, os, resource, statistics, subprocess, sys, time

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
BUILD = os.path.join(ROOT, 'build')
SHARED = os.environ.get('CROWDBAKE_SHARED', os.path.join(ROOT, '..', 'shared'))
EXE = os.environ.get('CROWDBAKE', os.path.join(BUILD, 'crowdbake'))


def run(cmd, **kw):
    """Runs cmd; returns (wall seconds, peak RSS bytes of that child, stdout)."""
    start = time.perf_counter()
    proc = subprocess.Popen(cmd, stdout=subprocess.PIPE, stderr=subprocess.PIPE, **kw)
    out, err = proc.communicate()
    wall = time.perf_counter() - start
    # communicate() reaped it; RUSAGE_CHILDREN keeps the max over children, so take a fresh
    # measurement by running each command through wait4 instead when possible.
    if proc.returncode != 0:
        sys.exit('bench: %s failed: %s' % (' '.join(cmd), err.decode()[-500:]))
    return wall, out.decode()


def run_rss(cmd):
    start = time.perf_counter()
    proc = subprocess.Popen(cmd, stdout=subprocess.PIPE, stderr=subprocess.DEVNULL)
    out = proc.stdout.read()
    _, status, usage = os.wait4(proc.pid, 0)
    wall = time.perf_counter() - start
    if status != 0:
        sys.exit('bench: %s failed' % ' '.join(cmd))
    return wall, usage.ru_maxrss * 1024, out.decode()


def stats(values):
    return {'median': statistics.median(values), 'min': min(values), 'max': max(values)}


def ensure_peer():
    if not os.path.isdir(os.path.join(ROOT, 'bench', 'node_modules', 'three')):
        subprocess.run(['npm', 'ci', '--no-audit', '--no-fund', '--silent'], cwd=os.path.join(ROOT, 'bench'), check=True)


def gen_rig(joints, clips, seconds):
    out = os.path.join(BUILD, 'bench')
    os.makedirs(out, exist_ok=True)
    path = os.path.join(out, 'bench_j%d_c%d_s%g.glb' % (joints, clips, seconds))
    if not os.path.exists(path):
        subprocess.run([os.path.join(BUILD, 'gen_samples'), '--bench', out, str(joints), str(clips), str(seconds)],
                       check=True, stdout=subprocess.DEVNULL)
    return path


def bench_input(name, path, repeat):
    """crowdbake and the peer in turns, so a change in the machine's load hits both alike. Each
    bake writes a new .pal: the previous one is removed first, outside the timing (replacing a
    just-written 29 MB palette adds the file system's cost of freeing it, ~20 ms here)."""
    out_pal = os.path.join(BUILD, 'bench', name + '.pal')
    walls, rss, phases = [], [], []
    peer_walls, peer_load, peer_sample, peer_matrices = [], [], [], 0
    for _ in range(repeat):
        if os.path.exists(out_pal):
            os.remove(out_pal)
        wall, peak, out = run_rss([EXE, 'bake', path, '-o', out_pal, '--json'])
        walls.append(wall)
        rss.append(peak)
        phases.append(json.loads(out)['outputs'][0])
        wall, out = run(['node', os.path.join(ROOT, 'bench', 'peer.mjs'), path, '30'])
        r = json.loads(out)
        peer_walls.append(wall)
        peer_load.append(r['load'])
        peer_sample.append(r['sample'])
        peer_matrices = r['matrices']
    last = phases[-1]
    matrices = last['frames'] * last['bones']
    sample = [p['phases']['sample'] for p in phases]
    result = {
        'input': name, 'input_bytes': os.path.getsize(path), 'output_bytes': os.path.getsize(out_pal),
        'bones': last['bones'], 'frames': last['frames'], 'matrices': matrices,
        'crowdbake': {
            'wall': stats(walls), 'peak_rss': max(rss),
            'phases': {k: statistics.median(p['phases'][k] for p in phases) for k in last['phases']},
            'matrices_per_second': matrices / statistics.median(sample),
        },
        'peer': {
            'wall': stats(peer_walls), 'load': stats(peer_load), 'sample': stats(peer_sample),
            'matrices': peer_matrices, 'matrices_per_second': peer_matrices / statistics.median(peer_sample),
        },
    }
    c, p = result['crowdbake'], result['peer']
    result['ratios'] = {
        'sampling_throughput': c['matrices_per_second'] / p['matrices_per_second'],
        'end_to_end_vs_peer_load_plus_sample': (p['load']['median'] + p['sample']['median']) / c['wall']['median'],
        'whole_process': p['wall']['median'] / c['wall']['median'],
        'peak_rss_vs_input_plus_output': c['peak_rss'] / (result['input_bytes'] + result['output_bytes']),
    }
    return result


def fit_exponent(results):
    pts = [(math.log(r['matrices']), math.log(r['crowdbake']['wall']['median'])) for r in results]
    n = len(pts)
    if n < 2:
        return None
    mx, my = sum(x for x, _ in pts) / n, sum(y for _, y in pts) / n
    return sum((x - mx) * (y - my) for x, y in pts) / sum((x - mx) ** 2 for x, _ in pts)


def core_numbers(model, pal, exr):
    _, out = run([os.path.join(BUILD, 'bench_core'), model, pal] + ([exr] if exr else []))
    return json.loads(out)


def ms(s):
    return '%.1f' % (s * 1000)


def print_table(report):
    print('crowdbake %s vs three.js %s (peer), %d runs each, median [min..max]; %s' % (
        report['crowdbake_version'], report['three_version'], report['repeat'], report['machine']))
    head = '%-22s %9s %8s %24s %9s %24s %10s %9s %9s' % ('input', 'matrices', 'MB in', 'crowdbake wall ms', 'peak MB',
                                                         'peer load+sample ms', 'cb Mmat/s', 'peer Mm/s', 'e2e x')
    print(head)
    print('-' * len(head))
    for r in report['results']:
        c, p = r['crowdbake'], r['peer']
        print('%-22s %9d %8.1f %24s %9.1f %24s %10.2f %9.2f %9.1f' % (
            r['input'], r['matrices'], r['input_bytes'] / 1e6,
            '%s [%s..%s]' % (ms(c['wall']['median']), ms(c['wall']['min']), ms(c['wall']['max'])),
            c['peak_rss'] / 1e6,
            '%s + %s' % (ms(p['load']['median']), ms(p['sample']['median'])),
            c['matrices_per_second'] / 1e6, p['matrices_per_second'] / 1e6,
            r['ratios']['end_to_end_vs_peer_load_plus_sample']))
    print()
    for r in report['results']:
        ph = r['crowdbake']['phases']
        print('%-22s phases ms: load %s, sample %s, encode %s, measure %s, write %s; RSS / (in + out) = %.2f' % (
            r['input'], ms(ph['load']), ms(ph['sample']), ms(ph['encode']), ms(ph['measure']), ms(ph['write']),
            r['ratios']['peak_rss_vs_input_plus_output']))
    if report.get('exponent') is not None:
        print('\ncost ~ (joints x frames)^%.2f over the size series' % report['exponent'])
    for name, core in report.get('core', {}).items():
        similar = core.get('similarity_matrices_per_second')
        print('%s: single-thread sampling %.2f M matrices/s as 4x4%s; .pal open %.1f us (%d bytes), checksum %.1f GB/s%s' % (
            name, core['matrices_per_second'] / 1e6,
            ', %.2f M/s as similarities (the qpos path)' % (similar / 1e6) if similar else '',
            core['pal_open_us'], core['pal_bytes'], core['pal_verify_gb_per_s'],
            ', same palette from EXR via OpenEXR %.1f ms' % (core['exr_read_us'] / 1000) if 'exr_read_us' in core else ''))


def crowd_input(name, model):
    """model.glb, model.pal (the default qpos/u16) and model.exr (its VAT) in build/bench/crowd-NAME."""
    out = os.path.join(BUILD, 'bench', 'crowd-' + name)
    os.makedirs(out, exist_ok=True)
    subprocess.run(['cp', model, os.path.join(out, 'model.glb')], check=True)
    subprocess.run([EXE, 'bake', model, '-o', os.path.join(out, 'model.pal'), '-q', '--root-motion', 'in-place'], check=True)
    subprocess.run([EXE, 'vat', model, '-o', os.path.join(out, 'model.exr'), '--root-motion', 'in-place',
                    '--exr-compression', 'none'], check=True, stdout=subprocess.DEVNULL)
    return out


def crowd_bench(smoke):
    runs = [('fish', os.path.join(BUILD, 'samples', 'fish.glb'), '10' if smoke else '10,30,100,1000,10000,100000',
             1 if smoke else 2)]
    if not smoke:
        runs.append(('Cow', os.path.join(SHARED, 'assets', 'quaternius-cow', 'Cow.glb'), '100,1000', 2))
    results = []
    for name, model, counts, frames in runs:
        _, out = run(['node', os.path.join(ROOT, 'tests', 'browser', 'bench_crowd.mjs'), crowd_input(name, model), counts,
                      '--frames', str(frames)])
        r = json.loads(out.strip().split('\n')[-1])
        r['input'] = name
        results.append(r)
    return results


def print_crowd(results):
    for r in results:
        print('\ncrowd: %s (%d vertices), WebGL2 in headless Chromium on %s; median of %d frames (960x540, each to a '
              'readPixels sync)' % (r['input'], r['vertices'], r['renderer'], r['frames']))
        print('%10s %12s %12s %12s %10s' % ('instances', 'palette ms', 'VAT ms', 'VAT/palette', 'fps (pal)'))
        for n, c in sorted(r['counts'].items(), key=lambda kv: int(kv[0])):
            print('%10s %12.1f %12.1f %12.2f %10.1f' % (n, c['palette_ms'], c['vat_ms'], c['vat_over_palette'],
                                                     1000 / c['palette_ms']))
        held = [int(n) for n, c in r['counts'].items() if c['palette_ms'] <= 1000 / 60]
        print('VRAM: palette %d bytes, VAT %d bytes (%.1fx); largest measured herd holding 60 fps from the palette: %s' % (
            r['palette_bytes'], r['vat_bytes'], r['vat_bytes'] / r['palette_bytes'], max(held) if held else 'none'))


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument('--repeat', type=int, default=5)
    ap.add_argument('--json', action='store_true')
    ap.add_argument('--smoke', action='store_true')
    ap.add_argument('--crowd-only', action='store_true')
    args = ap.parse_args()
    if args.crowd_only:
        crowd = crowd_bench(args.smoke)
        if args.json:
            json.dump({'crowd': crowd}, sys.stdout, indent=2)
            print()
        else:
            print_crowd(crowd)
        return
    ensure_peer()
    inputs = []
    if args.smoke:
        args.repeat = 1
        inputs.append(('rig_tiny', gen_rig(20, 1, 1)))
        series = []
    else:
        inputs.append(('Fox', os.path.join(SHARED, 'assets', 'fox-bevy', 'Fox.glb')))
        inputs.append(('robot', os.path.join(SHARED, 'assets', 'robot-quaternius-raylib', 'robot.glb')))
        series = [('rig_200j_%dclips' % c, gen_rig(200, c, 10)) for c in (8, 15, 30, 60)]
        inputs += series
    results = [bench_input(name, path, args.repeat) for name, path in inputs]
    three = json.load(open(os.path.join(ROOT, 'bench', 'node_modules', 'three', 'package.json')))['version']
    report = {
        'crowdbake_version': subprocess.run([EXE, '--version'], capture_output=True, text=True).stdout.split()[-1],
        'three_version': three, 'repeat': args.repeat, 'machine': '%d cores' % os.cpu_count(), 'results': results,
        'exponent': fit_exponent([r for r in results if r['input'].startswith('rig_200j')]),
        'core': {},
    }
    big = [p for n, p in inputs if n == 'rig_200j_30clips'] or [inputs[-1][1]]
    exr = os.path.join(BUILD, 'bench', 'core.exr')
    subprocess.run([EXE, 'bake', big[0], '-o', exr, '-q', '--precision', 'half', '--format', 'pal,exr'], check=True)
    report['core']['large'] = core_numbers(big[0], exr[:-4] + '.pal', exr)
    if not args.smoke:
        small = os.path.join(BUILD, 'bench', 'Fox.pal')
        report['core']['Fox'] = core_numbers(inputs[0][1], small, None)
    report['crowd'] = crowd_bench(args.smoke)
    if args.json:
        json.dump(report, sys.stdout, indent=2)
        print()
    else:
        print_table(report)
        print_crowd(report['crowd'])


if __name__ == '__main__':
    main()
