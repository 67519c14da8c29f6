#!/usr/bin/python3
"""The size bar of the code (issue 36): no source file over 600 lines and no
C++ function over 80, unless the reason is written beside it.

Run:  /usr/bin/python3 scripts/check_sizes.py [--list]
Exit status 1 when something is over its bar without a reason; --list also
prints the longest functions. ctest runs it (code.sizes).

Files: every C++ and Python source of the repository (src, include, tools,
python, tests, bench, fuzz, synthetic, examples, scripts). A file over 600
lines says why in its first 20 lines, in a comment holding "over 600 lines:"
followed by the reason.

Functions: every C++ function body (free functions, methods, lambdas count
with the function that holds them, TEST bodies too), from its signature's
line to its closing brace. A function over 80 lines says why in the comment
just above it, holding "(N lines:" followed by the reason (as
bench/stages_bench.cc's register_all does).
"""
import os
import re
import sys

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
FOLDERS = ['src', 'include', 'tools', 'python', 'tests', 'bench', 'fuzz', 'synthetic', 'examples', 'scripts']
CPP = ('.cc', '.h', '.cpp', '.hpp')
MAX_FILE = 600
MAX_FUNCTION = 80
FILE_REASON = re.compile(r'over 600 lines:\s*\S', re.IGNORECASE)
FUNCTION_REASON = re.compile(r'\(\d+ lines:\s*\S')
CONTAINER = re.compile(r'^\s*(?:template\s*<.*>\s*)?(?:namespace|class|struct|union|enum|extern\s+"C")\b')


def sources():
    for folder in FOLDERS:
        for base, dirs, files in os.walk(os.path.join(ROOT, folder)):
            dirs[:] = [d for d in dirs if d not in ('build', '__pycache__') and not d.startswith('.')]
            for name in sorted(files):
                if name.endswith(CPP) or name.endswith('.py'):
                    yield os.path.join(base, name)


def code_only(text):
    """The text with comments, string and character literals blanked (newlines
    kept), so that braces and parentheses can be counted."""
    out = []
    i, n = 0, len(text)
    while i < n:
        c = text[i]
        if text.startswith('//', i):
            j = text.find('\n', i)
            j = n if j < 0 else j
            out.append(' ' * (j - i))
            i = j
        elif text.startswith('/*', i):
            j = text.find('*/', i + 2)
            j = n if j < 0 else j + 2
            out.append(re.sub(r'[^\n]', ' ', text[i:j]))
            i = j
        elif c == 'R' and text.startswith('R"', i) and (i == 0 or not (text[i - 1].isalnum() or text[i - 1] == '_')):
            open_paren = text.find('(', i + 2)
            delim = text[i + 2:open_paren]
            j = text.find(')' + delim + '"', open_paren)
            j = n if j < 0 else j + len(delim) + 2
            out.append('""' + re.sub(r'[^\n]', ' ', text[i + 2:j]))
            i = j
        elif c in '"\'':
            j = i + 1
            while j < n and text[j] != c and text[j] != '\n':
                j += 2 if text[j] == '\\' else 1
            j = min(j + 1, n)
            out.append(c + ' ' * max(0, j - i - 2) + (c if j - i >= 2 else ''))
            i = j
        else:
            out.append(c)
            i += 1
    # Preprocessor lines (with their continuations) are no code here.
    lines = ''.join(out).split('\n')
    directive = False
    for k, l in enumerate(lines):
        if directive or l.lstrip().startswith('#'):
            directive = l.rstrip().endswith('\\')
            lines[k] = ' ' * len(l)
    return '\n'.join(lines)


def functions(path):
    """(first line, last line, name) of each outermost function body."""
    text = open(path, encoding='utf-8', errors='replace').read()
    code = code_only(text)
    stack = []  # per open brace: 'container', 'function' or 'other'
    found = []
    last_stop = 0  # where the statement before the current brace began
    line = 1
    start_line = {}
    for i, c in enumerate(code):
        if c == '\n':
            line += 1
        elif c in ';':
            last_stop = i + 1
        elif c == '{':
            head = code[last_stop:i]
            if all(kind == 'container' for kind in stack):
                flat = ' '.join(head.split())
                if CONTAINER.match(flat) and '(' not in flat.split('{')[0].split(':')[0]:
                    kind = 'container'
                elif '(' in flat and not re.search(r'=\s*$', flat) and not flat.startswith('='):
                    kind = 'function'
                else:
                    kind = 'other'
            else:
                kind = 'other'
            if kind == 'function':
                # the signature's first line (comments are blank in `head`)
                lead = len(head) - len(head.lstrip())
                first = line - head.count('\n') + head.count('\n', 0, lead)
                start_line[len(stack)] = (first, ' '.join(head.split())[:70])
            stack.append(kind)
            last_stop = i + 1
        elif c == '}':
            if stack:
                kind = stack.pop()
                if kind == 'function':
                    first, name = start_line.pop(len(stack))
                    found.append((first, line, name))
            last_stop = i + 1
    return found, text.split('\n')


def reason_above(lines, first):
    """The comment block just above line `first` (1-based) holds a reason."""
    k = first - 2
    block = []
    while k >= 0 and lines[k].strip().startswith('//'):
        block.append(lines[k])
        k -= 1
    return bool(FUNCTION_REASON.search(' '.join(reversed(block))))


def main():
    listing = '--list' in sys.argv[1:]
    problems, longest = [], []
    for path in sources():
        rel = os.path.relpath(path, ROOT)
        lines = open(path, encoding='utf-8', errors='replace').read().split('\n')
        count = len(lines) - (1 if lines and lines[-1] == '' else 0)
        if count > MAX_FILE and not any(FILE_REASON.search(l) for l in lines[:20]):
            problems.append(f'{rel}: {count} lines, over {MAX_FILE} without "over 600 lines: <reason>" in its first 20 lines')
        if not path.endswith(CPP):
            continue
        found, text_lines = functions(path)
        for first, last, name in found:
            length = last - first + 1
            longest.append((length, rel, first, name))
            if length > MAX_FUNCTION and not reason_above(text_lines, first):
                problems.append(f'{rel}:{first}: a function of {length} lines, over {MAX_FUNCTION} without '
                                f'"(N lines: <reason>)" in the comment above it: {name}')
    if listing:
        for length, rel, first, name in sorted(longest, reverse=True)[:25]:
            print(f'{length:5d}  {rel}:{first}  {name}')
    for p in problems:
        print(p)
    print(f'check_sizes: {len(problems)} over the bar without a reason')
    return 1 if problems else 0


if __name__ == '__main__':
    sys.exit(main())
