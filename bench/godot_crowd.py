"""The Godot herd's frame times (bench/run.py's godot_crowd): CrowdbakeHerd (runtimes/godot/addons/crowdbake) in
Godot 4.6's web build in headless Chromium on SwiftShader (tests/runtimes/godot/run_godot.mjs running
tests/runtimes/godot/bench_herd.gd), a herd of walking Cows drawn per vertex, through the bone pass, with the
herd's "auto" choice, and from a VAT of the same frames (crowdbake vat --like the palette).

    python3 bench/godot_crowd.py [N1,N2,...] [cow|husky]   (default 10,100,1000 Cows; prints a table and the JSON)
"""
import json
import os
import re
import struct
import subprocess
import sys

from common import BUILD, EXE, ROOT, SHARED

HALF, FLOAT = 1, 2
ANIMALS = {'cow': ('quaternius-cow/Cow.glb', 'AnimalArmature|Walk'), 'husky': ('quaternius-husky/Husky.glb', 'Walk')}


def read_vat(path):
    """The uncompressed scanline EXR crowdbake vat writes (runtimes/web/crowdbake_vat.mjs's readVat): its
    dimensions and the position.* and normal.* layers as RGBA half-float bytes."""
    data = open(path, 'rb').read()
    assert struct.unpack_from('<I', data, 0)[0] == 20000630, path + ': not an OpenEXR file'
    at, attrs = 8, {}

    def cstring():
        nonlocal at
        end = data.index(b'\0', at)
        s = data[at:end].decode()
        at = end + 1
        return s
    while True:
        name = cstring()
        if not name:
            break
        kind = cstring()
        size = struct.unpack_from('<i', data, at)[0]
        at += 4
        v = data[at:at + size]
        if kind == 'int':
            attrs[name] = struct.unpack_from('<i', v)[0]
        elif kind == 'compression':
            attrs[name] = v[0]
        elif kind == 'box2i':
            attrs[name] = struct.unpack_from('<4i', v)
        elif kind == 'chlist':
            channels, o = [], 0
            while v[o] != 0:
                end = v.index(b'\0', o)
                channels.append((v[o:end].decode(), struct.unpack_from('<i', v, end + 1)[0]))
                o = end + 1 + 16
            attrs[name] = channels
        at += size
    assert attrs['compression'] == 0, path + ': bake the VAT with --exr-compression none'
    x0, y0, x1, y1 = attrs['dataWindow']
    width, height = x1 - x0 + 1, y1 - y0 + 1
    layers = {'position': bytearray(width * height * 8), 'normal': bytearray(width * height * 8)}
    for y in range(height):
        o = struct.unpack_from('<Q', data, at + y * 8)[0] + 8
        for name, kind in attrs['channels']:
            layer, comp = name.split('.')
            if layer in layers and comp in 'RGBA' and kind == HALF:
                k = 'RGBA'.index(comp)
                for x in range(width):
                    i = ((y * width + x) * 4 + k) * 2
                    layers[layer][i:i + 2] = data[o + x * 2:o + x * 2 + 2]
            o += width * (2 if kind == HALF else 4)
    meta = {'width': width, 'height': height, 'frameWidth': attrs['crowdbake.frameWidth'],
            'rowsPerFrame': attrs['crowdbake.rowsPerFrame'], 'vertices': attrs['crowdbake.vertices']}
    return meta, layers


def godot_input(name='cow'):
    """build/bench/godot-NAME: model.glb, roster/ (a catalog of one walking state), the VAT of its palette's rows."""
    asset, walk = ANIMALS[name]
    model = os.path.join(SHARED, 'assets', asset)
    out = os.path.join(BUILD, 'bench', 'godot-' + name)
    os.makedirs(out, exist_ok=True)
    subprocess.run(['cp', model, os.path.join(out, 'model.glb')], check=True)
    with open(os.path.join(out, 'catalog.toml'), 'w') as f:
        f.write('[bake]\nout_dir = "roster"\nfps = 30\n\n[animal.%s]\nmodel = "model.glb"\n'
                'states = { wander = ["%s"] }\n' % (name, walk))
    subprocess.run([EXE, 'bake', 'catalog.toml', '-q'], check=True, cwd=out)
    exr = os.path.join(out, 'vat.exr')
    subprocess.run([EXE, 'vat', 'model.glb', '-o', exr, '--like', 'roster/%s.pal' % name, '--exr-compression', 'none', '-q'],
                   check=True, cwd=out, stdout=subprocess.DEVNULL)
    meta, layers = read_vat(exr)
    os.remove(exr) # run_godot.mjs hands Godot every file of the folder
    with open(os.path.join(out, 'vat.json'), 'w') as f:
        json.dump(meta, f)
    for layer, blob in layers.items():
        with open(os.path.join(out, 'vat_%ss.bin' % layer), 'wb') as f:
            f.write(blob)
    return out


def godot_crowd_bench(counts=(10, 100, 1000), methods=('palette', 'bones', 'vat'), animal='cow'):
    out = godot_input(animal)
    with open(os.path.join(out, 'bench.json'), 'w') as f:
        json.dump({'counts': list(counts), 'methods': list(methods), 'animal': animal}, f)
    log = os.path.join(BUILD, 'bench', 'godot-crowd.log')
    # Not check=True: the results line is what counts (run_godot.mjs ends a benchmark once it prints done; its 600 s
    # guard against a hung engine can still end a slow run of 1,000 Cows, seconds a frame on two busy cores).
    subprocess.run(['node', os.path.join(ROOT, 'tests', 'runtimes', 'godot', 'run_godot.mjs'), out, log,
                    os.path.join(ROOT, 'tests', 'runtimes', 'godot', 'bench_herd.gd')])
    lines = [l for l in open(log) if l.startswith('crowdbake-bench: ')]
    if not lines:
        sys.exit('bench_herd.gd printed no results; see ' + log)
    result = json.loads(lines[-1][len('crowdbake-bench: '):])
    # CPU seconds a frame (run_godot.mjs's count of the browser's process tree between each block's marks): the work a
    # frame takes whatever else shares the cores, where the wall-clock medians move with the machine's load.
    herd = open(os.path.join(ROOT, 'tests', 'runtimes', 'godot', 'bench_herd.gd')).read()
    measured = int(re.search(r'^const BLOCK := (\d+)', herd, re.M).group(1)) - 1  # frames between a block's marks
    cpu, begun = {}, {}
    for l in open(log):
        if l.startswith('crowdbake-bench-cpu: '):
            n, method, edge, seconds = l.split()[1:]
            if edge == 'begin':
                begun[(n, method)] = float(seconds)
            elif (n, method) in begun:
                c = cpu.setdefault(str(float(n)), {}).setdefault(method, [0.0, 0])
                c[0] += float(seconds) - begun.pop((n, method))
                c[1] += measured
    for n, methods_cpu in cpu.items():
        for method, (seconds, frames) in methods_cpu.items():
            if n in result['counts']:
                result['counts'][n][method + '_cpu_ms'] = 1000.0 * seconds / frames
    return result


def print_table(r, methods=('palette', 'bones', 'vat'), animal='cow'):
    print('Godot 4.6 web build (Compatibility, SwiftShader), walking %s (%d bones, %d vertices), frame ms (median):'
          % (animal, r['bones'], r['vertices']))
    print('%10s' % 'instances' + ''.join('%12s' % (m + ' ms') for m in methods) + '   auto chose')
    for n, c in sorted(r['counts'].items(), key=lambda kv: float(kv[0])):
        print("%10d" % float(n) + ''.join('%12.1f' % c[m + '_ms'] for m in methods) + '   ' + ('bones' if c['auto_bone_pass'] else 'palette'))
        if all(m + '_cpu_ms' in c for m in methods):
            print('%10s' % 'CPU ms' + ''.join('%12.1f' % c[m + '_cpu_ms'] for m in methods) + "   (the browser's CPU a frame)")
    print('bytes per instance beside its MultiMesh row: ' + ', '.join('%s %d' % kv for kv in r['bytes_per_instance'].items()))


if __name__ == '__main__':
    counts = [int(n) for n in sys.argv[1].split(',')] if len(sys.argv) > 1 else [10, 100, 1000]
    animal = sys.argv[2] if len(sys.argv) > 2 else 'cow'
    result = godot_crowd_bench(counts, animal=animal)
    print_table(result, animal=animal)
    print(json.dumps(result))
