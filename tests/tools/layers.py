#!/usr/bin/env python3
"""The layers look only down: src/core, formats/, src/bake, cli/ (lowest first).

    layers.py BUILD_DIR

No #include from a lower layer reaches a higher one's files (src/core includes no header of
src/bake, formats/ or cli/; formats/ none of src/bake or cli/; src/bake none of cli/), and no call
does: no undefined symbol of a src/core or formats/ object (BUILD_DIR/obj, nm) is defined only in
a src/bake or cli/ object. The public headers (include/) and the internal tier (src/internal/)
belong to no layer."""
import glob
import os
import re
import subprocess
import sys

LAYERS = ['src/core', 'formats', 'src/bake', 'cli']  # lowest first
INCLUDE = re.compile(r'^\s*#\s*include\s+"([^"]+)"', re.M)


def layer_of(path):
    path = os.path.normpath(path)
    for i, name in enumerate(LAYERS):
        if path == name or path.startswith(name + '/'):
            return i
    return None


def resolve(source, inc):
    """Where the compiler finds `inc` (quotes: beside the file, then -Iinclude -Isrc -Icli)."""
    for base in (os.path.dirname(source), 'include', 'src', 'cli'):
        path = os.path.normpath(os.path.join(base, inc))
        if os.path.exists(path):
            return path
    return None


def include_knots():
    knots = []
    for layer in LAYERS:
        for path in glob.glob(layer + '/**/*.[ch]', recursive=True) + glob.glob(layer + '/**/*.[ch]pp', recursive=True):
            mine = layer_of(path)
            for inc in INCLUDE.findall(open(path, encoding='utf-8').read()):
                target = resolve(path, inc)
                theirs = layer_of(target) if target else None
                if theirs is not None and theirs > mine:
                    knots.append(f'{path}: #include "{inc}" ({target}) is {LAYERS[theirs]}, above {LAYERS[mine]}')
    return knots


def symbols(objects, flag):
    out = subprocess.run(['nm', flag] + objects, check=True, capture_output=True, text=True).stdout
    found = {}
    current = None
    for line in out.splitlines():
        if line.endswith(':') and line[:-1] in objects:
            current = line[:-1]
            continue
        parts = line.split()
        if not parts:
            continue
        if flag == '-u':
            found.setdefault(parts[-1], set()).add(current)
        elif len(parts) == 3 and parts[1] in 'TDRBW':
            found.setdefault(parts[2], set()).add(current)
    return found


def call_knots(build):
    def objects(layer):
        return sorted(glob.glob(os.path.join(build, 'obj', layer, '**/*.o'), recursive=True))
    lower = objects('src/core') + objects('formats')
    upper = objects('src/bake') + [o for o in objects('cli') if '/gen/' not in o]
    if not lower or not upper:
        sys.exit(f'layers.py: no objects under {build}/obj: build first')
    defined_low = symbols(lower, '--defined-only')
    defined_up = symbols(upper, '--defined-only')
    knots = []
    for name, users in sorted(symbols(lower, '-u').items()):
        if name in defined_up and name not in defined_low:
            for user in sorted(users):
                knots.append(f'{user} calls {name}, defined only in {sorted(defined_up[name])[0]}')
    return knots


def main():
    build = sys.argv[1] if len(sys.argv) > 1 else 'build'
    knots = include_knots() + call_knots(build)
    for k in knots:
        print('layers:', k)
    if knots:
        sys.exit(1)
    print('layers: no include and no call runs up from src/core, formats, src/bake or cli')


main()
