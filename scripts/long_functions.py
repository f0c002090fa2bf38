#!/usr/bin/env python3
"""Lists functions longer than a limit in clang-formatted C++ files (Google style: a definition at
namespace scope starts in column 0 and its body ends with a '}' alone in column 0).

    scripts/long_functions.py [--limit 80] [--strict] FILE_OR_DIR...

A function may stay long when a comment on the line above its definition says why:
    // long-function: <reason>
--strict exits 1 when a long function has no such reason (tests/architecture runs it on the
workflow layer, the command line and the Python module)."""
import argparse
import os
import re
import sys

SKIP = re.compile(r'^(namespace|struct|class|enum|union|extern|template\s*<[^>]*>\s*(struct|class))\b')


def functions(path):
    lines = open(path, encoding='utf-8').read().split('\n')
    i = 0
    while i < len(lines):
        line = lines[i]
        head = line and not line[0].isspace() and not SKIP.match(line) \
            and not line.startswith(('#', '//', '}', ')')) and '(' in line \
            and '=' not in line.split('(')[0]
        if not head:
            i += 1
            continue
        # the signature may go on over a few lines; a '{' at the end of one opens the body
        k = i
        while k < len(lines) and k < i + 8 and not lines[k].rstrip().endswith(('{', ';')):
            k += 1
        if k >= len(lines) or not lines[k].rstrip().endswith('{'):
            i = k + 1
            continue
        start = i
        if start > 0 and lines[start - 1].startswith('template'):
            start -= 1
        j = k + 1
        while j < len(lines) and lines[j] != '}' and not lines[j].startswith('}  //'):
            j += 1
        name = line.split('(')[0].split()[-1] if line.split('(')[0].split() else line
        reason = None
        if start > 0 and '// long-function:' in lines[start - 1]:
            reason = lines[start - 1].split('// long-function:', 1)[1].strip()
        yield name, start + 1, j - start + 1, reason
        i = j + 1


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument('paths', nargs='+')
    ap.add_argument('--limit', type=int, default=80)
    ap.add_argument('--strict', action='store_true')
    args = ap.parse_args()
    files = []
    for p in args.paths:
        if os.path.isdir(p):
            for root, _, names in os.walk(p):
                files += [os.path.join(root, n) for n in sorted(names) if n.endswith(('.cpp', '.hpp'))]
        else:
            files.append(p)
    bad = 0
    for f in sorted(files):
        for name, line, length, reason in functions(f):
            if length > args.limit:
                print(f'{f}:{line}: {name}: {length} lines' + (f' (reason: {reason})' if reason else ''))
                bad += reason is None
    if args.strict and bad:
        print(f'{bad} function(s) over {args.limit} lines without a "// long-function:" reason', file=sys.stderr)
        return 1
    return 0


if __name__ == '__main__':
    sys.exit(main())
