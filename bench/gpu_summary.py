#!/usr/bin/env python3
"""gpu_summary.py - bench/gpu.sh's table: bench_gl's JSON lines (one run per herd size) merged into
one JSON file, and per method the GPU frame time (median of the frames, GL timer queries) at each
size, the ratio against the VAT in the same run, and the largest herd drawn at 60 fps (16.7 ms):
the largest size measured within it, and between the last size within and the first past it the
size where the time reaches 16.7 ms, frame time taken as linear in the herd (a draw's cost is its
instances' vertices). LOD.jsonl (bench_gl --lod runs): the bone pass with the animation LOD beside
them, its ratio against the VAT of its own run.

    gpu_summary.py BENCH.jsonl BENCH.json [LOD.jsonl]
"""
import json
import sys

METHODS = ('palette', 'bones', 'lod', 'vat')
FRAME_60 = 1000 / 60


def largest_at_60(points):
    """points: [(count, ms)] ascending. (largest measured within 60 fps, the estimate) or Nones."""
    within = [(n, ms) for n, ms in points if ms <= FRAME_60]
    if not within:
        return None, None
    n0, ms0 = within[-1]
    past = [(n, ms) for n, ms in points if n > n0 and ms > FRAME_60]
    if not past:
        return n0, None  # every size measured is within: the largest is past the sizes tried
    n1, ms1 = past[0]
    estimate = n0 + (n1 - n0) * (FRAME_60 - ms0) / (ms1 - ms0)
    return n0, int(estimate)


def main():
    runs = [json.loads(line) for line in open(sys.argv[1]) if line.strip()]
    if not runs:
        print('no runs to summarise')
        return 1
    merged = dict(runs[0], counts={})
    for r in runs:
        merged['counts'].update(r['counts'])
    lod_runs = [json.loads(line) for line in open(sys.argv[3]) if line.strip()] if len(sys.argv) > 3 else []
    for r in lod_runs:  # the LOD pass's own figures, and its run's VAT as lod_run_vat_ms
        for c, m in r['counts'].items():
            if c in merged['counts']:
                merged['counts'][c].update({k: v for k, v in m.items() if k.startswith('lod_') or k.endswith('_lod')})
                merged['counts'][c]['lod_run_vat_ms'] = m['vat_ms']
    with open(sys.argv[2], 'w') as f:
        json.dump(merged, f, indent=1)
    counts = sorted(merged['counts'], key=int)
    print(f"{merged['renderer']} ({merged['version']}); {merged['vertices']} vertices an instance; palette "
          f"{merged['palette_bytes'] / 1e6:.2f} MB, VAT {merged['vat_bytes'] / 1e6:.1f} MB; median of "
          f"{merged['frames']} frames, GPU time (GL_TIME_ELAPSED)")
    print(f"{'instances':>10} {'palette ms':>11} {'bones ms':>9} {'LOD ms':>8} {'VAT ms':>8} {'VAT/palette':>12} "
          f"{'VAT/bones':>10} {'VAT/LOD':>8}   wall ms (palette, bones, LOD, VAT)")
    for c in counts:
        m = merged['counts'][c]
        lod = 'lod_ms' in m
        print(f"{int(c):>10} {m['palette_ms']:>11.3f} {m['bones_ms']:>9.3f} "
              f"{(format(m['lod_ms'], '.3f') if lod else '-'):>8} {m['vat_ms']:>8.3f} "
              f"{m['vat_ms'] / m['palette_ms']:>12.2f} {m['vat_ms'] / m['bones_ms']:>10.2f} "
              f"{(format(m['lod_run_vat_ms'] / m['lod_ms'], '.2f') if lod else '-'):>8}"
              f"   {m['palette_wall_ms']:.3f}, {m['bones_wall_ms']:.3f}, "
              f"{(format(m['lod_wall_ms'], '.3f') if lod else '-')}, {m['vat_wall_ms']:.3f}")
    for method in METHODS:
        points = [(int(c), merged['counts'][c][f'{method}_ms']) for c in counts if f'{method}_ms' in merged['counts'][c]]
        measured, estimate = largest_at_60(points)
        if not points:
            print(f'{method}: not measured')
        elif measured is None:
            print(f'{method}: no size measured draws at 60 fps')
        elif estimate is None:
            print(f'{method}: {measured} instances at 60 fps, the largest size tried (more would fit)')
        else:
            print(f'{method}: {measured} instances measured within 60 fps; about {estimate} at 16.7 ms (linear between sizes)')
    return 0


if __name__ == '__main__':
    sys.exit(main())
