#!/usr/bin/env python3
"""seeds.py - the fuzzers' seed corpora (make fuzz-seeds), one folder per target under OUT:

  gltf     every shared model under 400 kB, the samples; every .gltf that names files, with
           them appended (fuzz_gltf.c's FILE_MARKER), and the same with its uris led outside
           its folder ("../", absolute, missing), the named file put there
  pal      bakes of the samples in every layout x precision, plain and zstd, and local rows (u16, float)
  exr      bakes in both EXR precisions x every EXR compression
  ktx2     bakes of the samples in every layout x half and float, and one in place
  catalog  the catalogs
  web      the .pal seeds and roster.json manifests (the web reader reads both)
and each target's regression inputs (tests/fuzz/regressions/T).

Usage: seeds.py --build BUILD --shared SHARED --out OUT
       seeds.py --escape-regressions SAMPLE.glb DIR   (the gltf escape inputs make check replays)
"""
import argparse
import glob
import json
import os
import re
import shutil
import subprocess
import sys

FILE_MARKER = b'#%crowdbake-fuzz-file:'
LAYOUTS = ['mat4', 'affine', 'qpos']
PRECISIONS = ['float', 'half', 'u16']
EXR_COMPRESSIONS = ['none', 'rle', 'zips', 'zip', 'piz']


def bundle(model, files):
    """A model and the files it names, as one fuzz_gltf input."""
    out = bytearray(model)
    for name, data in files:
        out += FILE_MARKER + name.encode() + b'\n' + data
    return bytes(out)


def separate(glb, uri):
    """A GLB as a .gltf whose buffer is the file `uri`, and that file's bytes."""
    json_length = int.from_bytes(glb[12:16], 'little')
    doc = json.loads(glb[20:20 + json_length])
    bin_at = 20 + json_length
    data = glb[bin_at + 8:bin_at + 8 + int.from_bytes(glb[bin_at:bin_at + 4], 'little')]
    doc['buffers'][0]['uri'] = uri
    return json.dumps(doc).encode(), data


def escape_bundles(glb, stem):
    """{name: bundle} of a sample split into .gltf + .bin: the .bin beside it, and named through
    "../", percent-encoded "../" and an absolute path, or missing, with the file outside its folder."""
    text, data = separate(glb, f'{stem}.bin')
    out = {'separate': bundle(text, [(f'{stem}.bin', data)]), 'missing': bundle(text, [])}
    for name, uri in [('parent', f'../{stem}.bin'), ('escaped', f'%2E%2E/{stem}.bin'), ('absolute', f'/tmp/{stem}.bin')]:
        out[name] = bundle(separate(glb, uri)[0], [(f'../{stem}.bin', data)])
    return out


def gltf_seeds(shared, build, out):
    for path in sorted(glob.glob(f'{shared}/assets/**/*.gl[bt]*', recursive=True)):
        if os.path.getsize(path) < 400_000 and path.endswith(('.glb', '.gltf')):
            shutil.copy(path, os.path.join(out, path.replace(f'{shared}/assets/', '').replace('/', '_')))
    for path in glob.glob(f'{build}/samples/*.glb'):
        shutil.copy(path, out)
        stem = os.path.basename(path)[:-4]
        for name, data in escape_bundles(open(path, 'rb').read(), stem).items():
            open(os.path.join(out, f'{stem}-{name}.gltf-bundle'), 'wb').write(data)
    # .gltf files with external buffers: the buffer beside the model, and led outside its folder.
    for path in sorted(glob.glob(f'{shared}/assets/**/*.gltf', recursive=True)):
        text = open(path, 'rb').read()
        uris = [u for u in re.findall(rb'"uri"\s*:\s*"([^"]+)"', text)
                if not u.startswith(b'data:') and u.endswith(b'.bin')]
        if not uris:
            continue
        folder, stem = os.path.dirname(path), os.path.basename(path)[:-5]
        files = [(u.decode(), open(os.path.join(folder, u.decode()), 'rb').read()) for u in uris]
        write = lambda suffix, data: open(os.path.join(out, f'{stem}-{suffix}.gltf-bundle'), 'wb').write(data)
        write('separate', bundle(text, files))
        for u, data in zip(uris, (d for _, d in files)):
            name = u.decode()
            write('parent', bundle(text.replace(b'"' + u + b'"', b'"../' + u + b'"'), [(f'../{name}', data)]))
            write('escaped', bundle(text.replace(b'"' + u + b'"', b'"%2E%2E/' + u + b'"'), [(f'../{name}', data)]))
            write('absolute', bundle(text.replace(b'"' + u + b'"', b'"/tmp/' + u + b'"'), [(f'../{name}', data)]))
            write('missing', bundle(text, []))


def bake(build, model, out, args):
    # The samples travel: their loops are baked in place, as a crowd game bakes them, whatever the
    # default for root motion is.
    if '--root-motion' not in args:
        args = [*args, '--root-motion', 'in-place']
    subprocess.run([f'{build}/crowdbake', 'bake', model, '-o', out, '-q', *args], check=True)


def palette_seeds(build, pal, exr):
    for s in ['fish', 'bird']:
        model = f'{build}/samples/{s}.glb'
        for layout in LAYOUTS:
            for precision in PRECISIONS:
                bake(build, model, f'{pal}/{s}-{layout}-{precision}.pal', ['--layout', layout, '--precision', precision])
                bake(build, model, f'{pal}/{s}-{layout}-{precision}-zstd.pal',
                     ['--layout', layout, '--precision', precision, '--zstd'])
        for precision in ['float', 'u16']:  # local rows (.pal version 6): the range table and the parents
            bake(build, model, f'{pal}/{s}-local-{precision}.pal', ['--bone-space', 'local', '--precision', precision])
    for precision in ['float', 'half']:
        for compression in EXR_COMPRESSIONS:
            bake(build, f'{build}/samples/fish.glb', f'{exr}/fish-{precision}-{compression}.exr',
                 ['--precision', precision, '--exr-compression', compression])
    bake(build, f'{build}/samples/bird.glb', f'{exr}/bird-qpos-half.exr', ['--layout', 'qpos', '--precision', 'half'])


def ktx2_seeds(build, ktx2):
    for s in ['fish', 'bird']:
        for layout in LAYOUTS:
            for precision in ['float', 'half']:
                bake(build, f'{build}/samples/{s}.glb', f'{ktx2}/{s}-{layout}-{precision}.ktx2',
                     ['--layout', layout, '--precision', precision])
    bake(build, f'{build}/samples/fish.glb', f'{ktx2}/fish-in-place.ktx2', ['--precision', 'half', '--root-motion', 'in-place'])


def roster_seeds(build, web, scratch):
    """The sample catalog baked (its roster.json) and two variants of it."""
    os.makedirs(scratch, exist_ok=True)
    catalog = open('samples/catalog.toml').read().replace('out_dir = "../build/roster"', 'out_dir = "roster"')
    catalog = catalog.replace('"../build/samples/', f'"{os.path.abspath(build)}/samples/')
    open(f'{scratch}/catalog.toml', 'w').write(catalog)
    subprocess.run([f'{build}/crowdbake', 'bake', f'{scratch}/catalog.toml', '-q'], check=True)
    text = open(f'{scratch}/roster/roster.json').read()
    open(f'{web}/roster.json', 'w').write(text)
    doc = json.loads(text)
    doc['failed'] = {'cow': {'model': 'cow.glb', 'error': 'cow.glb: not found'}}
    open(f'{web}/roster-failed.json', 'w').write(json.dumps(doc))
    open(f'{web}/roster-compact.json', 'w').write(json.dumps(json.loads(text), separators=(',', ':')))


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument('--escape-regressions', nargs=2)
    ap.add_argument('--build')
    ap.add_argument('--shared')
    ap.add_argument('--out')
    if '--escape-regressions' in sys.argv:
        glb, folder = ap.parse_args().escape_regressions
        stem = os.path.basename(glb)[:-4]
        for name, data in escape_bundles(open(glb, 'rb').read(), stem).items():
            open(os.path.join(folder, f'external-{stem}-{name}.gltf-bundle'), 'wb').write(data)
        return
    a = ap.parse_args()
    dirs = {t: os.path.join(a.out, t) for t in ['gltf', 'pal', 'exr', 'ktx2', 'catalog', 'web']}
    for d in dirs.values():
        shutil.rmtree(d, ignore_errors=True)
        os.makedirs(d)
    gltf_seeds(a.shared, a.build, dirs['gltf'])
    palette_seeds(a.build, dirs['pal'], dirs['exr'])
    ktx2_seeds(a.build, dirs['ktx2'])
    for path in ['catalog.example.toml', 'samples/catalog.toml']:
        shutil.copy(path, dirs['catalog'])
    for path in glob.glob(f'{dirs["pal"]}/*.pal'):
        shutil.copy(path, dirs['web'])
    roster_seeds(a.build, dirs['web'], os.path.join(a.out, 'scratch'))
    for t, d in dirs.items():  # and what the fuzzers found before
        for path in glob.glob(f'tests/fuzz/regressions/{t}/*'):
            shutil.copy(path, d)
        print(f'seeds: {t}: {len(os.listdir(d))} files')


if __name__ == '__main__':
    main()
