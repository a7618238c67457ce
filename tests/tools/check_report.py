#!/usr/bin/env python3
"""check_report.py CROWDBAKE REPORT.json MAX_TEXTURE FPS NAME=MODEL[@OWNER] ...

Recomputes a `crowdbake report --json` from the formulas of docs/budget.md, written again here
from that document, with the facts `crowdbake info --json` gives for each model (bones,
vertices, indices, frames per clip). Every number must match byte for byte. Prints what it
checked; exits 1 on the first mismatch."""
import json, math, struct, subprocess, sys

exe, report_path, max_tex, fps = sys.argv[1], sys.argv[2], int(sys.argv[3]), sys.argv[4]
types = {}
for arg in sys.argv[5:]:
    name, rest = arg.split('=', 1)
    model, _, owner = rest.partition('@')
    types[name] = (model, owner or None)
report = json.load(open(report_path))
checks = 0


def gltf_json(path):
    data = open(path, 'rb').read()
    if data[:4] == b'glTF':  # GLB: 12-byte header, then the JSON chunk
        length, kind = struct.unpack_from('<II', data, 12)
        assert kind == 0x4E4F534A, path
        return json.loads(data[20:20 + length])
    return json.loads(data)


COMPONENTS = {'SCALAR': 1, 'VEC2': 2, 'VEC3': 3, 'VEC4': 4, 'MAT2': 4, 'MAT3': 9, 'MAT4': 16}
COMPONENT_BYTES = {5120: 1, 5121: 1, 5122: 2, 5123: 2, 5125: 4, 5126: 4}


def mesh_bytes(path, skin):
    """The skinned primitives' buffers in the file's own vertex format: every attribute as its
    accessor types it, padded to 4 bytes; indices as stored, 8-bit ones widened to 16."""
    g = gltf_json(path)
    acc = g['accessors']
    total = 0
    for node in g['nodes']:
        if node.get('skin') != skin or 'mesh' not in node:
            continue
        for prim in g['meshes'][node['mesh']]['primitives']:
            attrs = prim['attributes']
            if not all(k in attrs for k in ('POSITION', 'JOINTS_0', 'WEIGHTS_0')):
                continue
            vertex = sum(-(-COMPONENTS[acc[i]['type']] * COMPONENT_BYTES[acc[i]['componentType']] // 4) * 4
                         for i in attrs.values())
            total += acc[attrs['POSITION']]['count'] * vertex
            if 'indices' in prim:
                a = acc[prim['indices']]
                total += a['count'] * (4 if a['componentType'] == 5125 else 2)
    return total


def expect(what, got, want):
    global checks
    if got != want:
        sys.exit('MISMATCH %s: report %r, formula %r' % (what, got, want))
    checks += 1


def wrap(row_texels, rows, m):
    if row_texels > m or rows < 1:
        return None
    blocks = -(-rows // m)
    if blocks > m // row_texels:
        return None
    return blocks * row_texels, -(-rows // blocks), blocks


TEXELS = {'mat4': 4, 'affine': 3, 'qpos': 2}
BYTES = {'float': 16, 'half': 8, 'u16': 8}
VAT = {'position RGBA16F + normal RGBA8': 12, 'position + normal RGBA16F': 16, 'position + normal RGBA32F': 32}
totals = {'palettes': 0, 'meshes': 0, 'vat': {k: 0 for k in VAT}}
meshes_counted = {}  # model path -> the first type on it: a model's mesh is on the GPU once, however many types use it
by_name = {t['name']: t for t in report['types']}
for name, (model, owner) in sorted(types.items()):
    info = json.loads(subprocess.run([exe, 'info', model, '--json', '--fps', fps], capture_output=True, check=True).stdout)
    skin = info['baked_skin']
    bones = info['skins'][skin]['joints']
    prims = [p for p in info['mesh_primitives'] if p['skin'] == skin]
    vertices = sum(p['vertices'] for p in prims)
    indices = sum(p['indices'] for p in prims)
    frames = sum(c['frames'] for c in info['clips'])
    t = by_name[name]
    expect(name + ' bones', t['bones'], bones)
    expect(name + ' vertices', t['vertices'], vertices)
    expect(name + ' indices', t['indices'], indices)
    expect(name + ' rows', t['rows'], frames)
    for key, b in t['encodings'].items():
        layout, precision = key.split('/')
        g = wrap(bones * TEXELS[layout], frames, max_tex)
        expect(name + ' ' + key, b, g[0] * g[1] * BYTES[precision] if g else 0)
    pal = t['palette']
    g = wrap(bones * TEXELS[pal['layout']], frames, 16384)  # as baked, at the catalog's default limit
    expect(name + ' palette geometry', (pal['width'], pal['height'], pal['blocks']), g)
    expect(name + ' palette bytes', pal['bytes'], g[0] * g[1] * BYTES[pal['precision']])
    w = min(vertices, max_tex)
    vg = wrap(w, frames * -(-vertices // w), max_tex)
    expect(name + ' vat fits', t['vat']['fits_texture_limit'], vg is not None)
    for enc, per in VAT.items():
        want = vg[0] * vg[1] * per if vg else vertices * frames * per
        expect(name + ' vat ' + enc, t['vat'][enc], want)
        totals['vat'][enc] += want
    mesh = mesh_bytes(model, skin)
    expect(name + ' mesh bytes', t['mesh_bytes'], mesh)
    if model in meshes_counted:
        expect(name + ' mesh counted with', t.get('mesh_counted_with'), meshes_counted[model])
    else:
        meshes_counted[model] = name
        expect(name + ' mesh counted here', t.get('mesh_counted_with'), None)
        totals['meshes'] += mesh
    if owner:
        expect(name + ' shares', t.get('shares_palette_of'), owner)
    else:
        totals['palettes'] += pal['bytes']
expect('totals palettes', report['totals']['palettes'], totals['palettes'])
expect('totals meshes', report['totals']['meshes'], totals['meshes'])
expect('totals roster', report['totals']['roster'], totals['palettes'] + totals['meshes'])
expect('totals vat', report['totals']['vat'], totals['vat'])
if 'budget' in report:
    b = report['budget']
    expect('budget bytes', b['budget_bytes'], round(b['vram_bytes'] * b['crowd_share']))
    expect('over budget', report['totals']['over_budget'], totals['palettes'] + totals['meshes'] > b['budget_bytes'])
    # the herd the budget left holds: 64 B an instance (a_instance + a 3x4 transform), palettes and meshes in the total
    left = b['budget_bytes'] - totals['palettes'] - totals['meshes']
    # the vertex rate: only the Steam Deck's maker states a figure (1.6 TFLOPS FP32, over 300 FLOP a skinned vertex)
    rate = b.get('vertex_rate')
    if b['target'] == 'Steam Deck':
        expect('vertex rate (relative error under 1e-9)', [abs(rate['vertices_per_second'] / (1.6e12 / 300) - 1) < 1e-9,
               abs(rate['vertices_per_frame'] / (1.6e12 / 300 / 60) - 1) < 1e-9, rate['estimate']], [True, True, True])
    else:
        expect('no vertex rate', rate, None)
    for name, (model, owner) in sorted(types.items()):
        t = by_name[name]
        herd = left // 64 if left > 0 else 0
        expect(name + ' herd instances', t['herd']['instances'], herd)
        expect(name + ' herd vertices a frame', t['herd']['vertices_per_frame'], herd * t['vertices'])
        if rate:
            share = t['herd']['vertices_per_frame'] / (rate['vertices_per_second'] / 60)
            expect(name + ' herd share of the vertex rate', abs(t['herd']['share_of_vertex_rate'] - share) <= 1e-8 * share, True)  # %.9g
            expect(name + ' herd instances at the vertex rate', t['herd']['instances_at_vertex_rate'],
                   int(rate['vertices_per_second'] / 60 // t['vertices']))
        else:
            expect(name + ' herd share of no vertex rate', t['herd'].get('share_of_vertex_rate'), None)
print('%d numbers match the formulas' % checks)
