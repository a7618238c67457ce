#!/usr/bin/env python3
"""campaign.py - runs each fuzz target in turn for a while (make fuzz MINUTES=N), one process at a
time, from its kept corpus (build/fuzz/corpus/T, grown run by run) and its seeds (seeds.py:
with the regression inputs), and prints one line per target: executions, coverage, findings.

A finding (a crash, leak, timeout or out-of-memory input) is copied into
tests/fuzz/regressions/T/, where `make check` replays it (replay_T, or for the web reader
runtimes/web/test/fuzz_regressions.test.mjs) until it is fixed; the target then starts again for the
rest of its time, so one bug does not end the campaign.

Usage: campaign.py --fuzz-build DIR --seconds N [--smoke] TARGET...   (TARGET: gltf pal exr ktx2 catalog web)

--smoke (make check's short run of every target): findings stay in DIR/artifacts, are named and fail the
run; nothing is written under tests/.
"""
import argparse
import os
import re
import shutil
import subprocess
import sys
import time

KINDS = ('crash-', 'leak-', 'timeout-', 'oom-', 'slow-unit-')
MAX_RESTARTS = 20


def command(target, build, corpus, seeds, seconds, artifacts):
    libfuzzer = [f'-max_total_time={seconds}', '-timeout=10', '-rss_limit_mb=2048', '-max_len=400000',
                 f'-artifact_prefix={artifacts}/', '-print_final_stats=1']
    inputs = [corpus, seeds]  # new inputs go to the first; the seeds hold the regression inputs too
    if target == 'web':
        web = 'tests/fuzz/web'
        preload = subprocess.run([sys.executable, f'{web}/glibc_compat.py',
                                  f'{web}/node_modules/@jazzer.js/fuzzer/prebuilds/fuzzer-linux-x64.node',
                                  f'{web}/node_modules/.crowdbake-compat'], capture_output=True, text=True, check=True)
        env = dict(os.environ, LD_PRELOAD=preload.stdout.strip()) if preload.stdout.strip() else dict(os.environ)
        return [f'{web}/node_modules/.bin/jazzer', f'{web}/fuzz_web.mjs', *inputs, '--sync', '--', *libfuzzer,
                f'-dict={web}/web.dict'], env
    return [f'{build}/fuzz_{target}', *libfuzzer, *inputs], dict(os.environ)


def run_target(target, build, seconds, smoke=False):
    corpus, seeds = f'{build}/corpus/{target}', f'{build}/seeds/{target}'
    artifacts = f'{build}/artifacts/{target}'
    for d in (corpus, artifacts):
        os.makedirs(d, exist_ok=True)
    log_path = f'{build}/fuzz-{target}.log'
    executions, coverage, features, findings, restarts = 0, 0, 0, [], 0
    deadline = time.monotonic() + seconds
    open(log_path, 'w').close()  # each run appends as it goes (tail -f it) and is read back when it ends
    while True:
        left = int(deadline - time.monotonic())
        if left < 5 or restarts > MAX_RESTARTS:
            break
        before = set(os.listdir(artifacts))
        cmd, env = command(target, build, corpus, seeds, left, artifacts)
        with open(log_path, 'a') as log:
            start = log.tell()
            subprocess.run(cmd, env=env, stdout=log, stderr=subprocess.STDOUT)
        with open(log_path, errors='replace') as log:
            log.seek(start)
            out = log.read()
        units = re.findall(r'stat::number_of_executed_units:\s*(\d+)', out)
        if units:
            executions += int(units[-1])
        else:  # no final stats (a crash): the last status line's count
            counts = re.findall(r'^#(\d+)\s', out, re.M)
            executions += int(counts[-1]) if counts else 0
        cov = re.findall(r'cov: (\d+) ft: (\d+)', out)
        if cov:
            coverage, features = max(coverage, int(cov[-1][0])), max(features, int(cov[-1][1]))
        new = sorted(set(os.listdir(artifacts)) - before)
        new = [n for n in new if n.startswith(KINDS)]
        if not new:
            if 'Done ' not in out and 'DONE' not in out:
                print(f'fuzz {target}: the fuzzer stopped without finishing; see {log_path}', file=sys.stderr)
                print(out[-2000:], file=sys.stderr)
                findings.append('(stopped: see the log)')
            break
        for name in new:
            if smoke:
                findings.append(f'{artifacts}/{name}')
                continue
            os.makedirs(f'tests/fuzz/regressions/{target}', exist_ok=True)
            shutil.copy(f'{artifacts}/{name}', f'tests/fuzz/regressions/{target}/{name}')
            findings.append(f'tests/fuzz/regressions/{target}/{name}')
        if smoke:
            break
        restarts += 1
    corpus_size = len(os.listdir(corpus))
    print(f'fuzz {target}: {seconds} s, {executions:,} executions, coverage {coverage} edges ({features} features), '
          f'corpus {corpus_size} inputs, {len(findings)} findings' + (': ' + ', '.join(findings) if findings else ''),
          flush=True)
    return not findings


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument('--fuzz-build', required=True)
    ap.add_argument('--seconds', type=int, required=True)
    ap.add_argument('--smoke', action='store_true')
    ap.add_argument('targets', nargs='+')
    a = ap.parse_args()
    ok = True
    for t in a.targets:
        ok = run_target(t, a.fuzz_build, a.seconds, a.smoke) and ok
    sys.exit(0 if ok else 1)


if __name__ == '__main__':
    main()
