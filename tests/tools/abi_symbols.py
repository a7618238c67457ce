#!/usr/bin/env python3
"""The shared library's dynamic symbols against its installed headers.

    abi_symbols.py LIBRARY HEADER_DIR...

Reads LIBRARY's defined dynamic symbols (nm -D --defined-only) and every function and object the
headers under HEADER_DIR declare (a cb_/cbpal_ name followed by '(' or declared extern), and
fails, naming them, on a symbol no header declares (an internal leaking into the ABI) and on a
declared function the library does not export (a declaration missing CROWDBAKE_API). Symbol
versions (name@@CROWDBAKE_3) must be the one node the version script names."""
import glob
import os
import re
import subprocess
import sys

DECLARED_FUNCTION = re.compile(r'\b((?:cb|cbpal)_[A-Za-z0-9_]+)\s*\(')
DECLARED_OBJECT = re.compile(r'^\s*(?:CROWDBAKE_API\s+)?extern\s+const\s+[A-Za-z0-9_ ]+?\b((?:cb|cbpal)_[A-Za-z0-9_]+)\s*[\[;]',
                             re.M)
VERSION_NODE = 'CROWDBAKE_3'


def strip_comments(text):
    text = re.sub(r'/\*.*?\*/', ' ', text, flags=re.S)
    return re.sub(r'//[^\n]*', ' ', text)


def declarations(dirs):
    """(functions that must be exported, every name a header declares)."""
    exported, named = set(), set()
    paths = []
    for d in dirs:
        paths += glob.glob(os.path.join(d, '*.h')) if os.path.isdir(d) else [d]
    for path in paths:
        text = strip_comments(open(path, encoding='utf-8').read())
        # A header-only implementation section (crowdbake_pal.h's) defines, it does not declare.
        text = text.split('#ifdef CROWDBAKE_PAL_IMPLEMENTATION')[0]
        for stmt in re.split(r'[;{}]', text):
            s = ' '.join(stmt.split())
            for m in DECLARED_FUNCTION.finditer(s):
                named.add(m.group(1))
                inline = 'static inline' in s[:m.start()] or s.startswith('static ')
                pointer = re.search(r'\(\s*\*\s*$', s[:m.start()]) is not None or s.startswith('typedef')
                macro = s.startswith('#')
                first = m.start() == DECLARED_FUNCTION.search(s).start()
                if first and not (inline or pointer or macro):
                    exported.add(m.group(1))
        for m in DECLARED_OBJECT.finditer(text):
            named.add(m.group(1))
            exported.add(m.group(1))
    return exported, named


def dynamic_symbols(library):
    out = subprocess.run(['nm', '-D', '--defined-only', library], check=True, capture_output=True, text=True).stdout
    symbols = {}
    for line in out.splitlines():
        parts = line.split()
        if len(parts) < 3:
            continue
        kind, name = parts[1], parts[2]
        if kind == 'A':  # the version node itself
            continue
        base, _, version = name.partition('@')
        symbols[base] = version.lstrip('@')
    return symbols


def main():
    if len(sys.argv) < 3:
        sys.exit(__doc__)
    library, dirs = sys.argv[1], sys.argv[2:]
    exported, named = declarations(dirs)
    symbols = dynamic_symbols(library)
    problems = []
    undeclared = sorted(s for s in symbols if s not in named)
    if undeclared:
        problems.append(f'{len(undeclared)} exported symbols no installed header declares (give them hidden '
                        f'visibility or declare them): ' + ' '.join(undeclared[:40]) + (' ...' if len(undeclared) > 40 else ''))
    missing = sorted(n for n in exported if n not in symbols)
    if missing:
        problems.append(f'{len(missing)} declared functions the library does not export (CROWDBAKE_API missing?): '
                        + ' '.join(missing))
    unversioned = sorted(s for s, v in symbols.items() if s in named and v != VERSION_NODE)
    if unversioned:
        problems.append(f'{len(unversioned)} symbols outside the version node {VERSION_NODE}: ' + ' '.join(unversioned[:20]))
    for p in problems:
        print(f'{library}: {p}', file=sys.stderr)
    if problems:
        sys.exit(1)
    print(f'{library}: {len(symbols)} exported symbols, each declared in {" ".join(dirs)}')


if __name__ == '__main__':
    main()
