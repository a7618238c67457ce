#!/usr/bin/env python3
"""bazel_rules.py - the Bazel rules (bazel/crowdbake.bzl) with Debian's bazel-bootstrap, offline.

A 3-type roster (cow and cow2 on Quaternius' Cow, which share a palette; husky on Quaternius'
Husky, from the shared third-party models) built by Bazel from `make bundle`'s crowdbake:

  1. equals, byte for byte, the one-step `crowdbake bake CATALOG` a Makefile runs (the same
     relative output folder depth, so the manifest's relative paths agree), palettes and manifest;
  2. after `bazel clean`, a rebuild with --disk_cache runs no bake or merge action;
  3. a second workspace at another path, sharing only a loopback HTTP remote cache (GET/PUT of
     /ac/HASH and /cas/HASH, served by this script on 127.0.0.1), runs none either and writes
     the same bytes;
  4. changing one model's bytes re-runs exactly that type's action and the merge.

Actions are counted from --execution_log_json_file (spawns that were not cache hits). Bazel's
output user root is under BUILD/bazel_test, so nothing is written outside the tree but what
Bazel insists on. One server per workspace, shut down at the end.
"""
import argparse
import http.server
import json
import os
import shutil
import struct
import subprocess
import sys
import threading

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
FAILURES = []


def check(ok, what):
    print(('ok   ' if ok else 'FAIL ') + what, flush=True)
    if not ok:
        FAILURES.append(what)


class CacheHandler(http.server.BaseHTTPRequestHandler):
    """Bazel's HTTP cache protocol: GET and PUT of /ac/HASH and /cas/HASH, kept in a folder."""
    store = None
    protocol_version = 'HTTP/1.1'  # every response has a Content-Length: Bazel keeps its connections

    def log_message(self, fmt, *args):
        with open(self.store + '.log', 'a') as f:
            f.write((fmt % args) + '\n')

    def path_on_disk(self):
        parts = self.path.strip('/').split('/')
        if len(parts) != 2 or parts[0] not in ('ac', 'cas') or not parts[1].isalnum():
            return None
        return os.path.join(self.store, parts[0] + '-' + parts[1])

    def do_GET(self):
        p = self.path_on_disk()
        if not p or not os.path.exists(p):
            self.send_response(404)
            self.send_header('Content-Length', '0')
            self.end_headers()
            return
        data = open(p, 'rb').read()
        self.send_response(200)
        self.send_header('Content-Length', str(len(data)))
        self.end_headers()
        self.wfile.write(data)

    def do_PUT(self):
        p = self.path_on_disk()
        n = int(self.headers.get('Content-Length', '0'))
        data = self.rfile.read(n)
        if p:
            with open(p + '.tmp', 'wb') as f:
                f.write(data)
            os.replace(p + '.tmp', p)
        self.send_response(200 if p else 400)
        self.send_header('Content-Length', '0')
        self.end_headers()


def start_cache(store):
    os.makedirs(store, exist_ok=True)
    handler = type('Handler', (CacheHandler,), {'store': store})
    server = http.server.ThreadingHTTPServer(('127.0.0.1', 0), handler)
    threading.Thread(target=server.serve_forever, daemon=True).start()
    return server


def write(path, text):
    os.makedirs(os.path.dirname(path), exist_ok=True)
    with open(path, 'w') as f:
        f.write(text)


CATALOG = '''# The test roster: cow and cow2 share one palette (same rig, bind pose and clips).
[bake]
out_dir = "out"
[animal.cow]
model = "models/Cow.glb"
[animal.cow2]
model = "models/Cow.glb"
[animal.husky]
model = "models/Husky.glb"
'''

ROSTER_BUILD = '''load("//bazel:crowdbake.bzl", "crowdbake_bake", "crowdbake_roster")

crowdbake_roster(
    name = "zoo",
    catalog = "catalog.toml",
    models = {
        "cow": ["models/Cow.glb"],
        "cow2": ["models/Cow.glb"],
        "husky": ["models/Husky.glb"],
    },
    crowdbake = "//tools/crowdbake",
)

crowdbake_bake(
    name = "husky_alone",
    model = "models/Husky.glb",
    crowdbake = "//tools/crowdbake",
)
'''


def make_workspace(ws, bundle, shared):
    shutil.rmtree(ws, ignore_errors=True)
    write(os.path.join(ws, 'WORKSPACE'), 'workspace(name = "crowdbake_bazel_test")\n')
    for f in ('BUILD.bazel', 'crowdbake.bzl'):
        write(os.path.join(ws, 'bazel', f), open(os.path.join(ROOT, 'bazel', f)).read())
    shutil.copytree(bundle, os.path.join(ws, 'tools', 'crowdbake'), symlinks=False,
                    ignore=shutil.ignore_patterns('.done'))
    write(os.path.join(ws, 'tools', 'crowdbake', 'BUILD.bazel'),
          'filegroup(name = "crowdbake", srcs = ["bin/crowdbake"] + glob(["lib/*"]), '
          'visibility = ["//visibility:public"])\n')
    write(os.path.join(ws, 'roster', 'catalog.toml'), CATALOG)
    write(os.path.join(ws, 'roster', 'BUILD.bazel'), ROSTER_BUILD)
    os.makedirs(os.path.join(ws, 'roster', 'models'))
    for src in ('quaternius-cow/Cow.glb', 'quaternius-husky/Husky.glb'):
        shutil.copyfile(os.path.join(shared, 'assets', src), os.path.join(ws, 'roster', 'models', os.path.basename(src)))


def bazel(ws, user_root, args, log=None):
    # Debian's /etc/bazel/bazelrc is read: it names the install base and the local JDK.
    startup = ['bazel', '--nohome_rc', '--noworkspace_rc', '--output_user_root=' + user_root,
               '--max_idle_secs=300']
    cmd = startup + args[:1] + ['--noshow_progress', '--color=no'] + args[1:]
    if log:
        cmd.append('--execution_log_json_file=' + log)
    p = subprocess.run(cmd, cwd=ws, capture_output=True, text=True)
    if p.returncode:
        sys.stderr.write(p.stdout + p.stderr)
    return p.returncode


def executed(log):
    """Mnemonics of the spawns in a JSON execution log that ran (not answered from a cache)."""
    text = open(log).read()
    ran = []
    dec = json.JSONDecoder()
    i = 0
    while True:
        while i < len(text) and text[i].isspace():
            i += 1
        if i >= len(text):
            break
        entry, i = dec.raw_decode(text, i)
        if not entry.get('remoteCacheHit'):
            ran.append(entry.get('mnemonic') or entry.get('progressMessage', ''))
    return sorted(m for m in ran if m.startswith('Crowdbake') or m.startswith('crowdbake'))


def roster_files(folder):
    out = {}
    for name in sorted(os.listdir(folder)):
        if name.endswith('.pal') or name.endswith('.json'):
            out[name] = open(os.path.join(folder, name), 'rb').read()
    return out


def touch_glb(path):
    """New bytes, same model: four spaces more at the end of the JSON chunk (lengths fixed up)."""
    data = bytearray(open(path, 'rb').read())
    magic, version, length = struct.unpack_from('<III', data, 0)
    chunk_len, chunk_type = struct.unpack_from('<II', data, 12)
    assert magic == 0x46546C67 and chunk_type == 0x4E4F534A
    data[20 + chunk_len:20 + chunk_len] = b'    '
    struct.pack_into('<I', data, 12, chunk_len + 4)
    struct.pack_into('<I', data, 8, length + 4)
    os.chmod(path, 0o644)
    open(path, 'wb').write(bytes(data))


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument('--build', default='build')
    ap.add_argument('--shared', default='../shared')
    a = ap.parse_args()
    if not shutil.which('bazel'):
        print('bazel_rules: no bazel on PATH; `make deps` installs bazel-bootstrap', file=sys.stderr)
        return 1
    build = os.path.abspath(a.build)
    top = os.path.join(build, 'bazel_test')
    bundle = os.path.join(build, 'bundle')
    crowdbake = os.path.join(bundle, 'bin', 'crowdbake')
    user_root = os.path.join(top, 'user_root')
    ws1, ws2 = os.path.join(top, 'ws1'), os.path.join(top, 'elsewhere', 'second', 'ws2')
    for ws in (ws1, ws2):
        make_workspace(ws, bundle, os.path.abspath(a.shared))
    shutil.rmtree(os.path.join(top, 'http_cache'), ignore_errors=True)
    server = start_cache(os.path.join(top, 'http_cache'))
    remote = '--remote_cache=http://127.0.0.1:%d' % server.server_address[1]
    disk = '--disk_cache=' + os.path.join(top, 'disk_cache')
    shutil.rmtree(os.path.join(top, 'disk_cache'), ignore_errors=True)
    log = os.path.join(top, 'exec.json')
    targets = ['//roster:zoo', '//roster:zoo_report', '//roster:husky_alone']
    try:
        # A clean start: earlier runs' outputs and action caches (the workspaces' paths are the same).
        for ws in (ws1, ws2):
            check(bazel(ws, user_root, ['clean']) == 0, 'bazel clean in ' + os.path.relpath(ws, top))
        # 1. The first build runs every action; its bytes equal the one-step bake's.
        rc = bazel(ws1, user_root, ['build', disk, remote] + targets, log)
        check(rc == 0, 'bazel build of the 3-type roster, its report and a single bake')
        first = executed(log)
        check(first.count('CrowdbakeType') == 3 and first.count('CrowdbakeMerge') == 1,
              'first build: 3 type actions and the merge ran (%s)' % first)
        bin_roster = os.path.join(ws1, 'bazel-bin', 'roster', 'zoo')
        # The one-step bake, as a Makefile rule runs it: the same relative depth as bazel-out/k8-fastbuild/bin.
        mk = 'mkout/k8-fastbuild/bin/roster/zoo'
        p = subprocess.run([crowdbake, 'bake', 'roster/catalog.toml', '--out-dir', mk, '-q', '-j', '2'], cwd=ws1)
        check(p.returncode == 0, 'the one-step bake of the same catalog')
        by_bazel, by_make = roster_files(bin_roster), roster_files(os.path.join(ws1, mk))
        check(sorted(by_make) == ['cow.pal', 'husky.pal', 'roster.json'], 'one-step bake: cow.pal, husky.pal, roster.json')
        check(all(by_bazel.get(n) == by_make[n] for n in by_make),
              'Bazel\'s roster.json, cow.pal and husky.pal equal the one-step bake byte for byte')
        manifest = json.loads(by_bazel.get('roster.json', b'{}'))
        check(manifest.get('types', {}).get('cow2', {}).get('shares_palette_of') == 'cow',
              'cow2 shares cow\'s palette in the merged manifest')
        check(not any(b'/work/' in v or build.encode() in v for v in by_bazel.values()),
              'no absolute path in the outputs')
        report = json.load(open(os.path.join(ws1, 'bazel-bin', 'roster', 'zoo_report.json')))
        check(report.get('schema') == 'crowdbake-report/1', 'the VRAM report action wrote a report')
        alone = open(os.path.join(ws1, 'bazel-bin', 'roster', 'husky_alone.pal'), 'rb').read()
        p = subprocess.run([crowdbake, 'bake', 'roster/models/Husky.glb', '-o', os.path.join(top, 'husky.pal'), '-q'],
                           cwd=ws1)
        check(p.returncode == 0 and open(os.path.join(top, 'husky.pal'), 'rb').read() == alone,
              'crowdbake_bake equals crowdbake bake MODEL')

        # 2. bazel clean, then the disk cache answers every action.
        check(bazel(ws1, user_root, ['clean']) == 0, 'bazel clean')
        rc = bazel(ws1, user_root, ['build', disk] + targets, log)
        again = executed(log)
        check(rc == 0 and again == [], 'after bazel clean, --disk_cache: no crowdbake action ran (%s)' % again)
        check(roster_files(bin_roster) == by_bazel, 'the disk cache gave the same bytes')

        # 3. Another workspace at another path, the HTTP cache only.
        rc = bazel(ws2, user_root, ['build', remote] + targets, log)
        other = executed(log)
        check(rc == 0 and other == [], 'second workspace, HTTP remote cache: no crowdbake action ran (%s)' % other)
        check(roster_files(os.path.join(ws2, 'bazel-bin', 'roster', 'zoo')) == by_bazel,
              'the second workspace has the same bytes')

        # 4. One model changes: its type's action and the merge run, nothing else.
        touch_glb(os.path.join(ws1, 'roster', 'models', 'Husky.glb'))
        rc = bazel(ws1, user_root, ['build', disk, remote, '//roster:zoo'], log)
        changed = executed(log)
        check(rc == 0 and changed == ['CrowdbakeMerge', 'CrowdbakeType'],
              'Husky.glb changed: exactly the husky action and the merge ran (%s)' % changed)
    finally:
        for ws in (ws1, ws2):
            bazel(ws, user_root, ['shutdown'])
        server.shutdown()
    if FAILURES:
        print('bazel_rules: %d check(s) failed' % len(FAILURES), file=sys.stderr)
        return 1
    print('bazel_rules: all checks passed')
    return 0


if __name__ == '__main__':
    sys.exit(main())
