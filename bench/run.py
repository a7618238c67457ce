#!/usr/bin/env python3
"""crowdbake benchmark: crowdbake against its peer (three.js GLTFLoader + AnimationMixer, bench/peer.mjs)
measured in the same run on the same inputs.

  python3 bench/run.py [--repeat N] [--json] [--smoke] [--instructions] [--crowd-only]

Inputs: ../shared/assets Fox.glb and robot.glb, and rigs from the sample generator: 200 joints x
{8, 15, 30, 60} clips x 10 s at 30 fps (the 30-clip rig is 9,000 frames, 1.8 M joint matrices).
For each: whole-process wall time, peak RSS and page faults of `crowdbake bake` to a .pal (with
its own load/sample/encode/measure/write split), and the peer's in-process load + sampling and
whole process. Median of N runs, with the spread (min..max). Then, each as a ratio measured in
this run: the load against the floor (read + RapidJSON parse of the same file, bench_floor), a
no-op rebuild of a 32-type catalog against its cold bake, --fps auto against a fixed-fps bake,
60 against 30 clips and 4x the joints (512 against 128). --smoke runs one tiny input once, so `make
check` keeps the script working.

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


def run_rss(cmd, faults=None):
    start = time.perf_counter()
    proc = subprocess.Popen(cmd, stdout=subprocess.PIPE, stderr=subprocess.DEVNULL)
    out = proc.stdout.read()
    _, status, usage = os.wait4(proc.pid, 0)
    wall = time.perf_counter() - start
    if status != 0:
        sys.exit('bench: %s failed' % ' '.join(cmd))
    if faults is not None:
        faults.append(usage.ru_minflt + usage.ru_majflt)
    return wall, usage.ru_maxrss * 1024, out.decode()


def timed(cmd):
    """Wall seconds of one run of cmd (its output discarded)."""
    return run_rss(cmd)[0]


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


def bench_input(name, path, repeat, peer=True):
    """crowdbake and the peer in turns, so a change in the machine's load hits both alike. Each
    bake writes a new .pal: the previous one is removed first, outside the timing (replacing a
    just-written 29 MB palette adds the file system's cost of freeing it, ~20 ms here)."""
    out_pal = os.path.join(BUILD, 'bench', name + '.pal')
    walls, rss, phases, faults = [], [], [], []
    peer_walls, peer_load, peer_sample, peer_matrices = [], [], [], 0
    for _ in range(repeat):
        if os.path.exists(out_pal):
            os.remove(out_pal)
        wall, peak, out = run_rss([EXE, 'bake', path, '-o', out_pal, '--json'], faults)
        walls.append(wall)
        rss.append(peak)
        phases.append(json.loads(out)['outputs'][0])
        if not peer:
            peer_walls.append(0), peer_load.append(0), peer_sample.append(1)
            continue
        wall, out = run(['node', os.path.join(ROOT, 'bench', 'peer.mjs'), path, '30'])
        r = json.loads(out)
        peer_walls.append(wall)
        peer_load.append(r['load'])
        peer_sample.append(r['sample'])
        peer_matrices = r['matrices']
    last = phases[-1]
    matrices = last['rows'] * last['bones']
    sample = [p['phases']['sample'] for p in phases]
    result = {
        'input': name, 'input_bytes': os.path.getsize(path), 'output_bytes': os.path.getsize(out_pal),
        'bones': last['bones'], 'frames': last['rows'], 'matrices': matrices,
        'crowdbake': {
            'wall': stats(walls), 'peak_rss': max(rss), 'page_faults': statistics.median(faults),
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


def floor_numbers(model):
    _, out = run([os.path.join(BUILD, 'bench_floor'), model])
    return json.loads(out)


def paired(a, b, repeat):
    """Median wall seconds of commands a and b, run in turns (load changes hit both alike)."""
    ta, tb = [], []
    for _ in range(repeat):
        ta.append(a() if callable(a) else timed(a))
        tb.append(b() if callable(b) else timed(b))
    return statistics.median(ta), statistics.median(tb)


def catalog_32():
    """A catalog of 32 types: eight models (shared assets and samples) at four rates each."""
    S = os.path.join(SHARED, 'assets')
    models = [os.path.join(S, 'fox-bevy', 'Fox.glb'), os.path.join(S, 'quaternius-cow', 'Cow.glb'),
              os.path.join(S, 'robot-quaternius-raylib', 'robot.glb'),
              os.path.join(S, 'spider-animated-luanti', 'gltf_spider_animated.gltf'),
              os.path.join(S, 'riggedfigure-raylib', 'rigged_figure.glb')] + \
             [os.path.join(BUILD, 'samples', n + '.glb') for n in ('quadruped', 'fish', 'bird')]
    d = os.path.join(BUILD, 'bench', 'cat32')
    os.makedirs(d, exist_ok=True)
    text = '[bake]\nout_dir = "out"\n'
    for i in range(32):
        text += '\n[animal.t%02d]\nmodel = "%s"\nfps = %d\n' % (i, os.path.abspath(models[i % 8]), (15, 20, 24, 30)[i // 8])
    path = os.path.join(d, 'catalog.toml')
    with open(path, 'w') as f:
        f.write(text)
    return path


def bench_catalog(repeat):
    """A no-op rebuild of 32 up-to-date types against the cold bake of the same catalog."""
    path = catalog_32()
    cold = [timed([EXE, 'bake', path, '-q', '--force']) for _ in range(max(1, repeat // 2))]
    noop = [timed([EXE, 'bake', path, '-q']) for _ in range(repeat)]
    return {'types': 32, 'cold': statistics.median(cold), 'noop': statistics.median(noop)}


def bench_auto(repeat):
    cow = os.path.join(SHARED, 'assets', 'quaternius-cow', 'Cow.glb')
    out = os.path.join(BUILD, 'bench', 'auto.pal')
    fixed, auto = paired([EXE, 'bake', cow, '-o', out, '-q'], [EXE, 'bake', cow, '-o', out, '-q', '--fps', 'auto'], repeat)
    return {'model': 'Cow.glb', 'fixed': fixed, 'auto': auto}


def bench_clips(repeat):
    """60 against 30 clips of the 200-joint rig, in turns (the series above runs each input's
    repeats together, so a change in load between two inputs skews their ratio)."""
    c30, c60 = gen_rig(200, 30, 10), gen_rig(200, 60, 10)
    out = os.path.join(BUILD, 'bench', 'clips.pal')
    return paired([EXE, 'bake', c30, '-o', out, '-q'], [EXE, 'bake', c60, '-o', out, '-q'], repeat)


def instructions(cmd):
    """Instructions one run of cmd executes (callgrind; independent of the machine's load)."""
    out = subprocess.run(['valgrind', '--tool=callgrind', '--callgrind-out-file=/dev/null'] + cmd,
                         capture_output=True, text=True).stderr
    refs = [line for line in out.splitlines() if 'refs:' in line]
    return int(refs[-1].split()[-1].replace(',', '')) if refs else None


def bench_instructions():
    """The same comparisons in instructions, single-threaded: what a busy machine cannot blur."""
    cow = os.path.join(SHARED, 'assets', 'quaternius-cow', 'Cow.glb')
    out = os.path.join(BUILD, 'bench', 'instr.pal')
    cat = catalog_32()
    subprocess.run([EXE, 'bake', cat, '-q'], check=True)
    return {
        'cow_fixed': instructions([EXE, 'bake', cow, '-o', out, '-q', '-j', '1']),
        'cow_auto': instructions([EXE, 'bake', cow, '-o', out, '-q', '-j', '1', '--fps', 'auto']),
        'rig_30clips': instructions([EXE, 'bake', gen_rig(200, 30, 10), '-o', out, '-q', '-j', '1']),
        'catalog_noop': instructions([EXE, 'bake', cat, '-q', '-j', '1']),
    }


def bench_joints(repeat):
    """4x the joints: 512 against 128, 8 clips x 10 s each (crowdbake only; the issue's 800 against
    200, scaled to the generator's limit of 512 joints)."""
    small, big = gen_rig(128, 8, 10), gen_rig(512, 8, 10)
    out = os.path.join(BUILD, 'bench', 'joints.pal')
    t_small, t_big = paired([EXE, 'bake', small, '-o', out, '-q'], [EXE, 'bake', big, '-o', out, '-q'], repeat)
    return {'small': 128, 'big': 512, 't_small': t_small, 't_big': t_big}


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
        print('%-22s phases ms: load %s, sample %s, encode %s, measure %s, write %s; RSS / (in + out) = %.2f; %d page faults' % (
            r['input'], ms(ph['load']), ms(ph['sample']), ms(ph['encode']), ms(ph['measure']), ms(ph['write']),
            r['ratios']['peak_rss_vs_input_plus_output'], r['crowdbake']['page_faults']))
    x = report.get('extra')
    if x:
        fl, big = x['floor'], x['floor_input']
        print('\nfloor (%s, %.1f MB, JSON %.2f MB): read %s ms, map+touch %s ms, RapidJSON parse %s ms; crowdbake load %s ms = %.1fx read + parse' % (
            big['input'], fl['bytes'] / 1e6, fl['json_bytes'] / 1e6, ms(fl['read']), ms(fl['map_touch']), ms(fl['parse']),
            ms(big['crowdbake']['phases']['load']), big['crowdbake']['phases']['load'] / (fl['read'] + fl['parse'])))
        c = x['catalog']
        print('catalog of %d types: cold bake %s ms, no-op rebuild %s ms (%.1f%% of cold)' % (
            c['types'], ms(c['cold']), ms(c['noop']), 100 * c['noop'] / c['cold']))
        a = x['auto']
        print('--fps auto on %s: %s ms, fixed 30 fps %s ms: %.2fx' % (a['model'], ms(a['auto']), ms(a['fixed']), a['auto'] / a['fixed']))
        j = x['joints']
        print('%d joints %s ms vs %d joints %s ms (8 clips x 10 s): %.2fx' % (
            j['big'], ms(j['t_big']), j['small'], ms(j['t_small']), j['t_big'] / j['t_small']))
        print('60 clips vs 30 clips (200 joints, in turns): %s vs %s ms: %.2fx' % (
            ms(x['clips'][1]), ms(x['clips'][0]), x['clips_60_vs_30']))
        ins = x.get('instructions')
        if ins:
            print('instructions (callgrind, 1 thread): Cow fixed %.0f M, --fps auto %.0f M (%.2fx); 200-joint 30-clip rig %.0f M; '
                  '32-type catalog no-op %.1f M' % (
                      ins['cow_fixed'] / 1e6, ins['cow_auto'] / 1e6, ins['cow_auto'] / ins['cow_fixed'],
                      ins['rig_30clips'] / 1e6, ins['catalog_noop'] / 1e6))
        print('goals: big rig e2e >= 12x three.js: %.1fx; 60/30 clips <= 2.2x: %.2fx; 4x joints (512/128) <= 4.4x: %.2fx; '
              'no-op 32 types < 50 ms: %s ms; auto <= 3x fixed: %.2fx; Fox e2e >= 6x: %.1fx' % (
                  big['ratios']['end_to_end_vs_peer_load_plus_sample'], x['clips_60_vs_30'], j['t_big'] / j['t_small'],
                  ms(c['noop']), a['auto'] / a['fixed'], x['fox_e2e']))
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
    ap.add_argument('--instructions', action='store_true', help='also count instructions with valgrind (slow)')
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
        by_name = {r['input']: r for r in results}
        big_r = by_name['rig_200j_30clips']
        report['extra'] = {
            'floor': floor_numbers(big[0]), 'floor_input': big_r,
            'catalog': bench_catalog(args.repeat), 'auto': bench_auto(args.repeat), 'joints': bench_joints(args.repeat),
            'clips': bench_clips(args.repeat),
            'fox_e2e': by_name['Fox']['ratios']['end_to_end_vs_peer_load_plus_sample'],
        }
        report['extra']['clips_60_vs_30'] = report['extra']['clips'][1] / report['extra']['clips'][0]
        if args.instructions:
            report['extra']['instructions'] = bench_instructions()
    else:
        report['floor'] = floor_numbers(inputs[0][1])
    report['crowd'] = crowd_bench(args.smoke)
    if args.json:
        json.dump(report, sys.stdout, indent=2)
        print()
    else:
        print_table(report)
        print_crowd(report['crowd'])


if __name__ == '__main__':
    main()
