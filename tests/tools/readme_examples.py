#!/usr/bin/env python3
"""readme_examples.py [--write] [--build DIR] [FILE...]: the documentation's example outputs come
from real runs. FILE defaults to README.md, docs/*.md and every README.md under runtimes/ and cli/.
Each example sits between

    <!-- begin output: COMMAND -->
    ...
    <!-- end output -->

(add `(markdown)` after `output` to insert the output as quoted Markdown rather than as an
indented code block). COMMAND runs from the repository root with DIR (default build) first on PATH, so
`crowdbake` is the built one. Without --write, exits 1 with a diff when an example differs from
what its command prints now; times (`7 ms`, `1.2 s`) are not compared, everything else is.
`make check` runs this; `make readme` rewrites the examples."""
import difflib, glob, os, re, subprocess, sys

BLOCK = re.compile(r'(<!-- begin output( \(markdown\))?: (.*?) -->\n)(.*?)(<!-- end output -->)', re.S)
TIME = re.compile(r'\b\d+(\.\d+)? (ms|s)\b')


def run(command, build):
    env = dict(os.environ, PATH=os.path.abspath(build) + os.pathsep + os.environ['PATH'])
    p = subprocess.run(command, shell=True, env=env, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True)
    if p.returncode not in (0, 3):  # 3: a report over budget is still an example worth showing
        sys.exit('readme_examples: `%s` exited %d:\n%s' % (command, p.returncode, p.stdout))
    return p.stdout


def render(markdown, output):
    if markdown:  # quoted, so its headings and tables read as an example, not as the README's own
        return '\n'.join(('> ' + line).rstrip() for line in output.rstrip('\n').split('\n')) + '\n\n'
    return '\n'.join(('    ' + line).rstrip() for line in output.rstrip('\n').split('\n')) + '\n\n'


def main():
    args = sys.argv[1:]
    write = '--write' in args
    build = args[args.index('--build') + 1] if '--build' in args else 'build'
    paths = [a for a in args if not a.startswith('--') and a != build] or default_pages()
    stale, count = [], 0
    for path in paths:
        count += check_page(path, build, write, stale)
    if write:
        print('readme_examples: %d examples regenerated in %d pages' % (count, len(paths)))
        return 0
    for command, old, new in stale:
        sys.stdout.writelines(difflib.unified_diff(old.splitlines(True), new.splitlines(True),
                                                   'docs: ' + command, 'now'))
    print('readme_examples: %d of %d examples in %d pages are stale%s' % (
        len(stale), count, len(paths), ' (run `make readme`)' if stale else ''))
    return 1 if stale else 0


def default_pages():
    pages = ['README.md'] + sorted(glob.glob('docs/*.md'))
    pages += sorted(glob.glob('runtimes/**/README.md', recursive=True) + glob.glob('cli/**/README.md', recursive=True))
    return [p for p in pages if 'node_modules' not in p]


def check_page(path, build, write, stale):
    """Regenerates the examples of one page; adds the stale ones to `stale`; returns how many it has."""
    text = open(path).read()

    def regenerate(m):
        head, markdown, command, old, tail = m.group(1), bool(m.group(2)), m.group(3), m.group(4), m.group(5)
        new = '\n' + render(markdown, run(command, build))
        if TIME.sub('<time>', new) != TIME.sub('<time>', old):
            stale.append((command, old, new))
        return head + new + tail

    updated = BLOCK.sub(regenerate, text)
    if write and updated != text:
        open(path, 'w').write(updated)
    return len(BLOCK.findall(text))


if __name__ == '__main__':
    sys.exit(main())
