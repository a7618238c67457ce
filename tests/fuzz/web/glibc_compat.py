#!/usr/bin/env python3
"""glibc_compat.py - lets Jazzer.js 4's prebuilt libFuzzer addon load on Debian 12.

The only Jazzer.js with a prebuilt addon that npm can install without network access to GitHub
(4.0.0; 2.1.0 downloads its addon from GitHub releases or builds it from sources the package does
not ship) was linked against glibc 2.38 and GCC 13's libstdc++. Debian 12 has glibc 2.36 and GCC
12, and the addon asks for four symbols the newer libraries added:

  __isoc23_strtol, __isoc23_strtoul    (GLIBC_2.38: strtol/strtoul that also take "0b" numbers)
  _ZSt21ios_base_library_initv         (GLIBCXX_3.4.32: makes sure std::cout is constructed)

This script (1) marks the addon's references to versions the system's libraries lack as weak
(VER_FLG_WEAK in .gnu.version_r), so the dynamic loader loads it instead of refusing, and (2)
builds compat.so, which defines the four symbols; `make fuzz` preloads it (LD_PRELOAD). On a
system whose libraries have the versions, it changes nothing and builds nothing.

Usage: glibc_compat.py ADDON.node OUT_DIR   (prints the LD_PRELOAD value, possibly empty)
"""
import os
import struct
import subprocess
import sys

VER_FLG_WEAK = 0x2
SHIM = r"""
#include <cstdlib>
#include <ios>
extern "C" long __isoc23_strtol(const char *s, char **end, int base) { return std::strtol(s, end, base); }
extern "C" unsigned long __isoc23_strtoul(const char *s, char **end, int base) { return std::strtoul(s, end, base); }
namespace std { void ios_base_library_init() { static ios_base::Init init; } }
"""


def sections(data):
    """{name: (offset, size, link)} of a little-endian ELF64 file."""
    shoff, = struct.unpack_from('<Q', data, 0x28)
    shentsize, shnum, shstrndx = struct.unpack_from('<HHH', data, 0x3A)
    heads = [struct.unpack_from('<IIQQQQIIQQ', data, shoff + i * shentsize) for i in range(shnum)]
    names_at = heads[shstrndx][4]
    out = {}
    for h in heads:
        name = data[names_at + h[0]:data.index(b'\0', names_at + h[0])].decode()
        out[name] = (h[4], h[5], h[6], heads)
    return out


def cstr(data, at):
    return data[at:data.index(b'\0', at)].decode()


def provided_versions(library):
    """Version names a system library defines (objdump -p's 'Version definitions')."""
    path = subprocess.run(['cc', f'-print-file-name={library}'], capture_output=True, text=True).stdout.strip()
    text = subprocess.run(['objdump', '-p', path], capture_output=True, text=True).stdout
    return {line.split()[-1] for line in text.split('Version definitions:')[-1].splitlines() if line.strip()[:1].isdigit()}


def weaken_missing(path):
    """Marks every version reference the system lacks as weak; returns those versions."""
    data = bytearray(open(path, 'rb').read())
    secs = sections(data)
    verneed_at, _, link, heads = secs['.gnu.version_r']
    strtab_at = heads[link][4]
    have = {lib: provided_versions(lib) for lib in ('libc.so.6', 'libstdc++.so.6', 'libm.so.6', 'libgcc_s.so.1')}
    marked, at = [], verneed_at
    while True:
        _, cnt, file_off, aux_off, next_off = struct.unpack_from('<HHIII', data, at)
        library = cstr(data, strtab_at + file_off)
        aux = at + aux_off
        for _ in range(cnt):
            _, flags, _, name_off, aux_next = struct.unpack_from('<IHHII', data, aux)
            version = cstr(data, strtab_at + name_off)
            if library in have and have[library] and version not in have[library]:
                struct.pack_into('<H', data, aux + 4, flags | VER_FLG_WEAK)
                marked.append(f'{library}:{version}')
            aux += aux_next
        if not next_off:
            break
        at += next_off
    if marked and bytes(data) != open(path, 'rb').read():
        with open(path + '.tmp', 'wb') as f:
            f.write(data)
        os.replace(path + '.tmp', path)
    return marked


def main():
    addon, out_dir = sys.argv[1], sys.argv[2]
    marked = weaken_missing(addon)
    shim = os.path.join(out_dir, 'compat.so')
    needs_shim = bool(marked)
    if needs_shim and not os.path.exists(shim):
        print(f'glibc_compat: {os.path.basename(addon)}: weak references to {", ".join(marked)}', file=sys.stderr)
        os.makedirs(out_dir, exist_ok=True)
        subprocess.run(['c++', '-shared', '-fPIC', '-O2', '-x', 'c++', '-', '-o', shim], input=SHIM, text=True, check=True)
    print(os.path.abspath(shim) if needs_shim else '')


if __name__ == '__main__':
    main()
