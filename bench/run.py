#!/usr/bin/env python3
"""crowdbake benchmark: crowdbake against its peer (three.js GLTFLoader + AnimationMixer, bench/peer.mjs)
measured in the same run on the same inputs.

  python3 bench/run.py [--repeat N] [--json] [--smoke] [--instructions] [--crowd-only] [--gl-only] [--gl-counts N,...]

Inputs: ../shared/assets Fox.glb and robot.glb, and rigs from the sample generator: 200 joints x
{8, 15, 30, 60} clips x 10 s at 30 fps (the 30-clip rig is 9,000 frames, 1.8 M joint matrices).
For each: whole-process wall time, peak RSS and page faults of `crowdbake bake` to a .pal (with
its own load/sample/encode/measure/write split), and the peer's in-process load + sampling and
whole process. Median of N runs, with the spread (min..max); Fox and the 30-clip rig, whose ratios
to the peer are goals, run 3N pairs (a bake and a peer run one right after the other) and are
judged on the median of the pairs' ratios. Then, each as a ratio measured in this run: the load
against the floor (read + RapidJSON parse of the same file, bench_floor), a no-op rebuild of a
32-type catalog against its cold bake, the catalog's cold bake on -j 1 against -j N (parallel
efficiency T1 / (N x TN), N = 2 and the machine's cores), --fps auto against a fixed-fps bake, 60
against 30 clips and 800 against 200 joints; then issue 21's goals, each as measured, its target
and whether it is met. --smoke runs every part once on tiny inputs (4-type catalog, 20/40-joint
rigs, the fish sample), so `make check` keeps the script working.

The crowd benchmark (tests/runtimes/browser/bench_crowd.mjs, headless Chromium): frame time of a herd drawn
from its palette against the same herd drawn from a VAT of the same frames (crowdbake vat), one
instanced draw each, alternating in one page, for 10 to 100,000 instances of the fish sample and
100 and 1,000 Cows, each drawn three ways: palette (per-vertex blending), bones (the bone pass: each
instance's bones blended once a frame, runtimes/web/crowdbake_bones.mjs) and VAT. --crowd-only runs only it.
Without a GPU, Chromium renders with SwiftShader (software: its absolute times say little about a
GPU; the ratio is measured in the same run).

The native benchmark (bench/bench_gl.c): the same three methods with the shipped GLSL in OpenGL 3.3
through EGL without a window, frames timed with GL timer queries: Mesa's llvmpipe here, a GPU's
driver where there is one (--gl-only runs only it; --gl-counts sets the herd sizes).

Last, the default bake's bytes against --fps 30 and what each lever would save (bench/bytes_bench.py,
bench/bench_rows.c; --bytes-only runs only it).
"""
import argparse, json, math, os, resource, statistics, subprocess, sys, time
sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import auto_speed  # noqa: E402  (issue 43 item 2: default / fixed 30 fps on Cow, Husky, Fox)
from bytes_bench import bytes_bench, print_bytes  # noqa: E402  (issue 43 item 1: the default bake's bytes)

from common import BUILD, EXE, ROOT, SHARED, run
from crowd import crowd_bench, gl_bench, print_crowd, print_gl


def run_rss(cmd, faults=None, cpu=None):
    start = time.perf_counter()
    proc = subprocess.Popen(cmd, stdout=subprocess.PIPE, stderr=subprocess.DEVNULL)
    out = proc.stdout.read()
    _, status, usage = os.wait4(proc.pid, 0)
    wall = time.perf_counter() - start
    if status != 0:
        sys.exit('bench: %s failed' % ' '.join(cmd))
    if faults is not None:
        faults.append(usage.ru_minflt + usage.ru_majflt)
    if cpu is not None:
        cpu.append(usage.ru_utime + usage.ru_stime)
    return wall, usage.ru_maxrss * 1024, out.decode()


def timed(cmd):
    """Wall seconds of one run of cmd (its output discarded)."""
    return run_rss(cmd)[0]


def stats(values):
    return {'median': statistics.median(values), 'min': min(values), 'max': max(values)}


def ensure_peer():
    if not os.path.isdir(os.path.join(ROOT, 'bench', 'node_modules', 'three')):
        subprocess.run(['npm', 'ci', '--no-audit', '--no-fund', '--silent'], cwd=os.path.join(ROOT, 'bench'), check=True)


# The sampler's benchmarks (against three.js, which samples global joint matrices; clips and joints scaling) bake a
# fixed 30 fps of global rows: the same work as before local rows became the default, and the peer's. The default's
# local rows on the 200-joint rig are counted beside them (bench_instructions' rig_30clips_local).
FIXED_GLOBAL = ['--fps', '30', '--bone-space', 'global']


def gen_rig(joints, clips, seconds):
    out = os.path.join(BUILD, 'bench')
    os.makedirs(out, exist_ok=True)
    path = os.path.join(out, 'bench_j%d_c%d_s%g.glb' % (joints, clips, seconds))
    if not os.path.exists(path):
        subprocess.run([os.path.join(BUILD, 'gen_samples'), '--bench', out, str(joints), str(clips), str(seconds)],
                       check=True, stdout=subprocess.DEVNULL)
    return path


def bench_input(name, path, repeat, peer=True):
    """crowdbake and the peer in turns (in_turns), so a change in the machine's load hits both alike. Each
    bake writes a new .pal: the previous one is removed first, outside the timing (replacing a
    just-written 29 MB palette adds the file system's cost of freeing it, ~20 ms here)."""
    out_pal = os.path.join(BUILD, 'bench', name + '.pal')
    walls, rss, phases, faults = [], [], [], []
    peer_walls, peer_load, peer_sample, peer_matrices = [], [], [], 0

    def bake():
        if os.path.exists(out_pal):
            os.remove(out_pal)
        wall, peak, out = run_rss([EXE, 'bake', path, '-o', out_pal, '--json'] + FIXED_GLOBAL, faults)
        walls.append(wall)
        rss.append(peak)
        phases.append(json.loads(out)['outputs'][0])

    def peer_run():
        nonlocal peer_matrices
        if not peer:
            peer_walls.append(0), peer_load.append(0), peer_sample.append(1)
            return
        wall, out = run(['node', os.path.join(ROOT, 'bench', 'peer.mjs'), path, '30'])
        r = json.loads(out)
        peer_walls.append(wall)
        peer_load.append(r['load'])
        peer_sample.append(r['sample'])
        peer_matrices = r['matrices']

    in_turns(bake, peer_run, repeat)
    last = phases[-1]
    matrices = last['rows'] * last['bones']
    sample = [p['phases']['sample'] for p in phases]
    result = {
        'input': name, 'input_bytes': os.path.getsize(path), 'output_bytes': os.path.getsize(out_pal),
        'bones': last['bones'], 'frames': last['rows'], 'matrices': matrices, 'runs': repeat,
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
    # Pair i is bake i and peer run i, run one right after the other (in_turns): both see the
    # machine as it was then. Their ratio, pair by pair, leaves out what changes between pairs.
    pairs = [(l + s) / w for l, s, w in zip(peer_load, peer_sample, walls)]
    result['ratios'] = {
        'sampling_throughput': c['matrices_per_second'] / p['matrices_per_second'],
        'end_to_end_vs_peer_load_plus_sample': (p['load']['median'] + p['sample']['median']) / c['wall']['median'],
        'end_to_end_pairs': stats(pairs),
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


GOAL_INPUTS, GOAL_PAIRS = ('Fox', 'rig_200j_30clips'), 3


def in_turns(a, b, repeat):
    """Calls a() and b() `repeat` times each, in turns (a change in the machine's load hits both
    alike) and in the order a b, b a, a b, ...: each runs after the other as often as after
    itself. A process that starts right after a larger one exits runs slower on this kind of VM
    (a Fox bake 7.1 ms after three.js's Node process, 5.9 ms after another bake, medians of 15),
    so a fixed order would favour whichever runs second."""
    for i in range(repeat):
        if i % 2:
            b(), a()
        else:
            a(), b()


def paired(a, b, repeat):
    """Median wall seconds of commands a and b, run in turns (in_turns)."""
    ta, tb = [], []
    in_turns(lambda: ta.append(a() if callable(a) else timed(a)), lambda: tb.append(b() if callable(b) else timed(b)),
             repeat)
    return statistics.median(ta), statistics.median(tb)


def catalog_n(types=32, samples_only=False):
    """A catalog of `types` types: eight models (shared assets and samples) at four rates each;
    samples_only: the three samples (the smoke run)."""
    S = os.path.join(SHARED, 'assets')
    models = [os.path.join(BUILD, 'samples', n + '.glb') for n in ('quadruped', 'fish', 'bird')]
    if not samples_only:
        models = [os.path.join(S, 'fox-bevy', 'Fox.glb'), os.path.join(S, 'quaternius-cow', 'Cow.glb'),
                  os.path.join(S, 'robot-quaternius-raylib', 'robot.glb'),
                  os.path.join(S, 'spider-animated-luanti', 'gltf_spider_animated.gltf'),
                  os.path.join(S, 'riggedfigure-raylib', 'rigged_figure.glb')] + models
    d = os.path.join(BUILD, 'bench', 'cat%d' % types)
    os.makedirs(d, exist_ok=True)
    text = '[bake]\nout_dir = "out"\n'
    for i in range(types):
        text += '\n[animal.t%02d]\nmodel = "%s"\nfps = %d\n' % (
            i, os.path.abspath(models[i % len(models)]), (15, 20, 24, 30)[i * 4 // types])
    path = os.path.join(d, 'catalog.toml')
    with open(path, 'w') as f:
        f.write(text)
    return path


def catalog_32():
    return catalog_n(32)


def bench_catalog(repeat, path, types):
    """A no-op rebuild of up-to-date types against the cold bake of the same catalog; and the cold
    bake on -j 1 against -j N in turns (N = 2 and the machine's cores): parallel efficiency
    T1 / (N x TN), 1.0 when N threads bake N times as fast."""
    cold = [timed([EXE, 'bake', path, '-q', '--force']) for _ in range(max(1, repeat // 2))]
    noop = [timed([EXE, 'bake', path, '-q']) for _ in range(repeat)]
    jobs = {}
    for n in sorted({2, os.cpu_count() or 2}):
        c1, cn = [], []  # CPU seconds (user + sys): threads that add work show here, whatever the load
        t1, tn = paired(lambda: run_rss([EXE, 'bake', path, '-q', '--force', '-j', '1'], cpu=c1)[0],
                        lambda: run_rss([EXE, 'bake', path, '-q', '--force', '-j', str(n)], cpu=cn)[0], repeat)
        jobs[n] = {'t1': t1, 'tn': tn, 'efficiency': t1 / (n * tn),
                   'cpu_1': statistics.median(c1), 'cpu_n': statistics.median(cn)}
    return {'types': types, 'cold': statistics.median(cold), 'noop': statistics.median(noop), 'jobs': jobs}


def bench_clips(repeat, joints=200, clips=(30, 60), seconds=10):
    """60 against 30 clips of the 200-joint rig, in turns (the series above runs each input's
    repeats together, so a change in load between two inputs skews their ratio)."""
    small, big = gen_rig(joints, clips[0], seconds), gen_rig(joints, clips[1], seconds)
    out = os.path.join(BUILD, 'bench', 'clips.pal')
    t_small, t_big = paired([EXE, 'bake', small, '-o', out, '-q'] + FIXED_GLOBAL, [EXE, 'bake', big, '-o', out, '-q'] + FIXED_GLOBAL,
                            repeat)
    return {'small': clips[0], 'big': clips[1], 't_small': t_small, 't_big': t_big}


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
        'cow_fixed': instructions([EXE, 'bake', cow, '-o', out, '-q', '-j', '1', '--root-motion', 'in-place', '--fps', '30']),
        'cow_auto': instructions([EXE, 'bake', cow, '-o', out, '-q', '-j', '1', '--root-motion', 'in-place']),
        'rig_30clips': instructions([EXE, 'bake', gen_rig(200, 30, 10), '-o', out, '-q', '-j', '1'] + FIXED_GLOBAL),
        'rig_30clips_local': instructions([EXE, 'bake', gen_rig(200, 30, 10), '-o', out, '-q', '-j', '1', '--fps', '30']),
        'catalog_noop': instructions([EXE, 'bake', cat, '-q', '-j', '1']),
        'joints_200': instructions([EXE, 'bake', gen_rig(200, 8, 10), '-o', out, '-q', '-j', '1'] + FIXED_GLOBAL),
        'joints_800': instructions([EXE, 'bake', gen_rig(800, 8, 10), '-o', out, '-q', '-j', '1'] + FIXED_GLOBAL),
    }


def bench_joints(repeat, joints=(200, 800), clips=8, seconds=10):
    """4x the joints: 800 against 200, 8 clips x 10 s each, in turns (crowdbake only)."""
    small, big = gen_rig(joints[0], clips, seconds), gen_rig(joints[1], clips, seconds)
    out = os.path.join(BUILD, 'bench', 'joints.pal')
    t_small, t_big = paired([EXE, 'bake', small, '-o', out, '-q'] + FIXED_GLOBAL, [EXE, 'bake', big, '-o', out, '-q'] + FIXED_GLOBAL,
                            repeat)
    return {'small': joints[0], 'big': joints[1], 'clips': clips, 'seconds': seconds, 't_small': t_small, 't_big': t_big}


def goals(x, big, fox):
    """Issue 21's goals: (what, measured, target, met); met is None where the issue sets no number."""
    fl, c, a, j, cl = x['floor'], x['catalog'], x['auto'], x['joints'], x['clips']
    # The load and the floor each in a fresh process, in turns (bench_floor). The goal is held
    # against the strictest floor: a read into memory already mapped (no page faults) + parse.
    load = fl['load'] / (fl['read_warm'] + fl['parse'])
    rows = [
        ('big rig end to end vs three.js load + sample', big['ratios']['end_to_end_pairs']['median'], '>= 12x', 12, 1),
        ('%d / %d clips' % (cl['big'], cl['small']), cl['t_big'] / cl['t_small'], '<= 2.2x', 2.2, -1),
        ('%d / %d joints' % (j['big'], j['small']), j['t_big'] / j['t_small'], '<= 4.4x', 4.4, -1),
        ('no-op rebuild, %d types (ms)' % c['types'], c['noop'] * 1000, '< 50 ms', 50, -1),
    ] + [('default (error-bounded) / --fps 30 (%s; %.2fx the --fps 30 bake without its warning search)' % (
        m, r['auto_vs_naive']), r['auto_vs_fixed'], '<= 1.5x', auto_speed.GOAL, -1) for m, r in a.items()] + [
        ('%s end to end vs three.js' % fox['input'], fox['ratios']['end_to_end_pairs']['median'], '>= 6x', 6, 1),
        ('load / (warm read + RapidJSON parse)', load, '<= 1.5x', 1.5, -1),
        ('peak RSS / (input + output), big rig', big['ratios']['peak_rss_vs_input_plus_output'], '<= 1.2x', 1.2, -1),
    ]
    out = [{'goal': g, 'measured': v, 'target': t, 'met': v * sign >= limit * sign} for g, v, t, limit, sign in rows]
    for n, e in sorted(c['jobs'].items()):
        out.append({'goal': 'catalog cold bake, -j %d efficiency T1 / (%d x T%d)' % (n, n, n), 'measured': e['efficiency'],
                    'target': 'reported', 'met': None})
    return out


def core_numbers(model, pal, exr):
    _, out = run([os.path.join(BUILD, 'bench_core'), model, pal] + ([exr] if exr else []))
    return json.loads(out)


def ms(s):
    return '%.1f' % (s * 1000)


def print_table(report):
    print('crowdbake %s vs three.js %s (peer), %d runs each (%s: %d, whose ratios are goals), median [min..max]; %s' % (
        report['crowdbake_version'], report['three_version'], report['repeat'], ' and '.join(GOAL_INPUTS),
        report['repeat'] * GOAL_PAIRS, report['machine']))
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
            r['ratios']['end_to_end_pairs']['median']))
    print('(e2e x: the median over the pairs of peer load + sample / crowdbake wall, each pair a bake and a peer run '
          'one right after the other)')
    print()
    for r in report['results']:
        ph = r['crowdbake']['phases']
        print('%-22s phases ms: load %s, sample %s, encode %s, measure %s, write %s; RSS / (in + out) = %.2f; %d page faults' % (
            r['input'], ms(ph['load']), ms(ph['sample']), ms(ph['encode']), ms(ph['measure']), ms(ph['write']),
            r['ratios']['peak_rss_vs_input_plus_output'], r['crowdbake']['page_faults']))
    by_input = {r['input']: r for r in report['results']}
    x = report.get('extra')
    if x:
        fl, big = x['floor'], x['floor_input']
        print('\nfloor (%s, %.1f MB, JSON %.2f MB; each in a fresh process, in turns): read %s ms (into memory already '
              'mapped: %s ms), map+touch %s ms, RapidJSON parse %s ms (plain %s ms); crowdbake load %s ms = %.2fx warm '
              'read + parse, %.2fx read + parse (in the bake: %s ms)' % (
            big['input'], fl['bytes'] / 1e6, fl['json_bytes'] / 1e6, ms(fl['read']), ms(fl['read_warm']), ms(fl['map_touch']),
            ms(fl['parse']), ms(fl['parse_plain']), ms(fl['load']), fl['load'] / (fl['read_warm'] + fl['parse']),
            fl['load'] / (fl['read'] + fl['parse']), ms(big['crowdbake']['phases']['load'])))
        c = x['catalog']
        print('catalog of %d types: cold bake %s ms, no-op rebuild %s ms (%.1f%% of cold)' % (
            c['types'], ms(c['cold']), ms(c['noop']), 100 * c['noop'] / c['cold']))
        for n, e in sorted(c['jobs'].items()):
            print('catalog cold bake -j 1 %s ms, -j %d %s ms (in turns): speed-up %.2fx, efficiency T1 / (%d x T%d) = %.2f; '
                  'CPU time -j %d / -j 1 = %.2f' % (ms(e['t1']), n, ms(e['tn']), e['t1'] / e['tn'], n, n, e['efficiency'], n,
                                                  e['cpu_n'] / e['cpu_1']))
        auto_speed.print_table(x['auto'])
        j = x['joints']
        print('%d joints %s ms vs %d joints %s ms (%d clips x %g s, in turns): %.2fx' % (
            j['big'], ms(j['t_big']), j['small'], ms(j['t_small']), j['clips'], j['seconds'], j['t_big'] / j['t_small']))
        cl = x['clips']
        print('%d clips vs %d clips (in turns): %s vs %s ms: %.2fx' % (
            cl['big'], cl['small'], ms(cl['t_big']), ms(cl['t_small']), cl['t_big'] / cl['t_small']))
        ins = x.get('instructions')
        if ins:
            print('instructions (callgrind, 1 thread): Cow --fps 30 %.0f M, default (error-bounded) %.0f M (%.2fx); 200-joint 30-clip rig %.0f M '
                  '(global rows; its default local rows %.0f M, %.2fx); 32-type catalog no-op %.1f M; 800 / 200 joints %.0f / %.0f M (%.2fx)' % (
                      ins['cow_fixed'] / 1e6, ins['cow_auto'] / 1e6, ins['cow_auto'] / ins['cow_fixed'],
                      ins['rig_30clips'] / 1e6, ins['rig_30clips_local'] / 1e6, ins['rig_30clips_local'] / ins['rig_30clips'],
                      ins['catalog_noop'] / 1e6, ins['joints_800'] / 1e6, ins['joints_200'] / 1e6,
                      ins['joints_800'] / ins['joints_200']))
        print('\ngoals of issue 21 (each measured in this run%s):' % (
            '; SMOKE RUN: tiny inputs, the numbers mean nothing' if report.get('smoke') else ''))
        for g in report['goals']:
            print('  %-56s %9.2f   %-9s %s' % (g['goal'], g['measured'], g['target'],
                                               'met' if g['met'] else '-' if g['met'] is None else 'NOT met'))
        for r in (by_input[n] for n in GOAL_INPUTS if n in by_input):
            pr, c, p = r['ratios']['end_to_end_pairs'], r['crowdbake']['wall'], r['peer']
            print('  %s vs three.js: median of %d pairs %.2fx, pairs %.2f..%.2fx; the two medians apart: %s / %s ms = %.2fx' % (
                r['input'], r['runs'], pr['median'], pr['min'], pr['max'],
                ms(p['load']['median'] + p['sample']['median']), ms(c['median']),
                r['ratios']['end_to_end_vs_peer_load_plus_sample']))
    if report.get('exponent') is not None:
        print('\ncost ~ (joints x frames)^%.2f over the size series' % report['exponent'])
    for name, core in report.get('core', {}).items():
        similar = core.get('similarity_matrices_per_second')
        print('%s: single-thread sampling %.2f M matrices/s as 4x4%s; .pal open %.1f us (%d bytes), checksum %.1f GB/s%s' % (
            name, core['matrices_per_second'] / 1e6,
            ', %.2f M/s as similarities (the qpos path)' % (similar / 1e6) if similar else '',
            core['pal_open_us'], core['pal_bytes'], core['pal_verify_gb_per_s'],
            ', same palette from EXR via OpenEXR %.1f ms' % (core['exr_read_us'] / 1000) if 'exr_read_us' in core else ''))


# crowdbake's qpos palettes against Unreal's AnimToTexture bone mode, written from its documented
# rules (bench/bench_att.c says which and how): bytes and visible error at the same frames.
ATT_MODELS = (('Cow', ('quaternius-cow', 'Cow.glb')), ('Husky', ('quaternius-husky', 'Husky.glb')))


def att_bench(smoke):
    models = [('fish', os.path.join(BUILD, 'samples', 'fish.glb'))] if smoke else \
        [(name, os.path.join(SHARED, 'assets', *rel)) for name, rel in ATT_MODELS]
    results = []
    for name, path in models:
        _, out = run([os.path.join(BUILD, 'bench_att'), path, '30'])
        for line in out.strip().split('\n'):
            r = json.loads(line)
            r['input'] = name
            results.append(r)
    return results


def print_att(results):
    print('\nagainst AnimToTexture (Unreal, bone mode; its encoding written from its documented rules, bench/bench_att.c):'
          '\nevery clip at 30 fps, the same rows; error = |skinned - the glTF\'s own skinning| over every vertex of every row,'
          '\nmm per metre of the model\'s height')
    print('%-7s %-27s %10s %9s %12s %11s' % ('model', 'encoding', 'bytes', 'vs u16', 'worst mm/m', 'mean mm/m'))
    base = {r['input']: r['bytes'] for r in results if r['encoding'] == 'crowdbake qpos/u16'}
    for r in results:
        print('%-7s %-27s %10d %8.2fx %12.4f %11.4f' % (r['input'], r['encoding'], r['bytes'], r['bytes'] / base[r['input']],
                                                      r['worst_mm_per_m'], r['mean_mm_per_m']))


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument('--repeat', type=int, default=5)
    ap.add_argument('--json', action='store_true')
    ap.add_argument('--smoke', action='store_true')
    ap.add_argument('--instructions', action='store_true', help='also count instructions with valgrind (slow)')
    ap.add_argument('--crowd-only', action='store_true')
    ap.add_argument('--gl-only', action='store_true', help='only the native benchmark (bench_gl)')
    ap.add_argument('--bytes-only', action='store_true', help='only the bytes of the default bake against --fps 30 (issue 43)')
    ap.add_argument('--gl-counts', help='herd sizes for the native benchmark, e.g. 1000,10000,100000')
    args = ap.parse_args()
    if args.bytes_only:
        r = bytes_bench(args.smoke)
        json.dump({'bytes': r}, sys.stdout, indent=2) if args.json else print_bytes(r)
        return
    if args.gl_only:
        gl = gl_bench(args.smoke, args.gl_counts)
        if args.json:
            json.dump({'gl': gl}, sys.stdout, indent=2)
            print()
        else:
            print_gl(gl)
        return
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
    # The two inputs whose ratio to three.js is a goal run three times the pairs: on a shared VM the
    # big rig's pairs of one run spread from about half to 1.4 times their median (bench/RESULTS.txt),
    # and the goal is judged on that median.
    results = [bench_input(name, path, args.repeat * (GOAL_PAIRS if name in GOAL_INPUTS else 1)) for name, path in inputs]
    three = json.load(open(os.path.join(ROOT, 'bench', 'node_modules', 'three', 'package.json')))['version']
    report = {
        'crowdbake_version': subprocess.run([EXE, '--version'], capture_output=True, text=True).stdout.split()[-1],
        'three_version': three, 'repeat': args.repeat, 'smoke': args.smoke, 'machine': '%d cores' % os.cpu_count(), 'results': results,
        'exponent': fit_exponent([r for r in results if r['input'].startswith('rig_200j')]),
        'core': {},
    }
    big = [p for n, p in inputs if n == 'rig_200j_30clips'] or [inputs[-1][1]]
    exr = os.path.join(BUILD, 'bench', 'core.exr')
    subprocess.run([EXE, 'bake', big[0], '-o', exr, '-q', '--precision', 'half', '--format', 'pal,exr', '--fps', '30'], check=True)
    report['core']['large'] = core_numbers(big[0], exr[:-4] + '.pal', exr)
    by_name = {r['input']: r for r in results}
    if args.smoke:  # every part once, on tiny inputs: the numbers mean nothing, the script keeps working
        big_r = fox_r = results[0]
        report['extra'] = {
            'floor': floor_numbers(big[0]), 'catalog': bench_catalog(1, catalog_n(4, True), 4),
            'auto': {'fish': auto_speed.measure(EXE, os.path.join(BUILD, 'samples', 'fish.glb'),
                                                os.path.join(BUILD, 'bench', 'auto.pal'), 1)},
            'joints': bench_joints(1, (20, 40), 1, 1), 'clips': bench_clips(1, 20, (1, 2), 1),
        }
    else:
        small = os.path.join(BUILD, 'bench', 'Fox.pal')
        report['core']['Fox'] = core_numbers(inputs[0][1], small, None)
        big_r, fox_r = by_name['rig_200j_30clips'], by_name['Fox']
        report['extra'] = {
            'floor': floor_numbers(big[0]), 'catalog': bench_catalog(args.repeat, catalog_32(), 32),
            'auto': auto_speed.run_all(EXE, SHARED, 2 * args.repeat),  # Cow, Husky, Fox (issue 43, item 2)
            'joints': bench_joints(args.repeat), 'clips': bench_clips(args.repeat),
        }
        if args.instructions:
            report['extra']['instructions'] = bench_instructions()
    report['extra']['floor_input'] = big_r
    report['goals'] = goals(report['extra'], big_r, fox_r)
    report['crowd'] = crowd_bench(args.smoke)
    report['gl'] = gl_bench(args.smoke, args.gl_counts)
    report['att'] = att_bench(args.smoke)
    report['bytes'] = bytes_bench(args.smoke)
    if args.json:
        json.dump(report, sys.stdout, indent=2)
        print()
    else:
        print_table(report)
        print_crowd(report['crowd'])
        print_gl(report['gl'])
        print_att(report['att'])
        print_bytes(report['bytes'])


if __name__ == '__main__':
    main()
