#!/usr/bin/env python3
"""Lists the functions longer than --max lines (default 120) in src/, tuning/ and bench/, and fails
(exit 1) when one is not in the allowance file or has grown past its allowance there, or when the
file still lists one that is no longer long. The house
style (CONTRIBUTING.md, "House style") keeps functions at most 120 lines; the allowance file lists
the ones written before the rule, each with the length it may not exceed, so the list only shrinks.

A function is a definition at namespace scope: clang-format puts its signature and its closing
brace at column 0, and it runs from the signature's first line to that brace (lambdas and local
classes inside count towards it). Functions defined inside a class body are not measured.

Usage: tools/function_lengths.py [--root DIR] [--max 120] [--allow tools/long_functions.txt] [--list]
Exit 0 within the rule and the allowances, 1 otherwise, 2 bad usage.
"""
import argparse
import pathlib
import re
import sys

FOLDERS = ("src", "tuning", "bench")
# A line that starts a definition at column 0: not a preprocessor line, comment, namespace, type,
# using-declaration or closing brace, and not a statement that ends there.
START = re.compile(r"^(?![#/ }]|namespace\b|using\b|struct\b|class\b|enum\b|template\b|static_assert\b|extern\b)\S")


def functions(path):
    """(name, first line, length) of each namespace-scope definition in the file."""
    lines = path.read_text(encoding="utf-8").split("\n")
    out, i = [], 0
    while i < len(lines):
        line = lines[i]
        if not START.match(line) or line.rstrip().endswith((";", "}")) or "(" not in line:
            i += 1
            continue
        j = i
        while j < len(lines) and not lines[j].rstrip().endswith(("{", ";", "}")):
            j += 1
        if j >= len(lines) or not lines[j].rstrip().endswith("{"):
            i = j + 1
            continue
        k = j + 1
        while k < len(lines) and lines[k] != "}":
            k += 1
        name = re.sub(r"\(.*", "", line).split()[-1].lstrip("*&")
        out.append((name, i + 1, k - i + 1))
        i = k + 1
    return out


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--root", default=str(pathlib.Path(__file__).resolve().parent.parent))
    ap.add_argument("--max", type=int, default=120)
    ap.add_argument("--allow", default="tools/long_functions.txt")
    ap.add_argument("--list", action="store_true", help="print every function over --max and exit 0")
    args = ap.parse_args()
    root = pathlib.Path(args.root)
    allowed = {}
    allow_file = root / args.allow
    if allow_file.exists():
        for number, text in enumerate(allow_file.read_text(encoding="utf-8").split("\n"), 1):
            text = text.split("#", 1)[0].strip()
            if not text:
                continue
            parts = text.split()
            if len(parts) != 3 or not parts[2].isdigit():
                print(f"{allow_file}: line {number}: '{text}' must be FILE FUNCTION LINES", file=sys.stderr)
                return 2
            allowed[(parts[0], parts[1])] = int(parts[2])
    long = []
    for folder in FOLDERS:
        for path in sorted((root / folder).rglob("*.cpp")):
            rel = path.relative_to(root).as_posix()
            for name, first, length in functions(path):
                if length > args.max:
                    long.append((rel, name, first, length))
    if args.list:
        for rel, name, first, length in sorted(long, key=lambda x: -x[3]):
            print(f"{rel} {name} {length}  # line {first}")
        return 0
    bad = []
    for rel, name, first, length in long:
        limit = allowed.get((rel, name))
        if limit is None:
            bad.append(f"{rel}:{first}: {name} has {length} lines (at most {args.max}; split it)")
        elif length > limit:
            bad.append(f"{rel}:{first}: {name} has {length} lines, more than its allowance of {limit} "
                       f"in {args.allow} (split it rather than raise the allowance)")
    found = {(rel, name) for rel, name, _, _ in long}
    for (rel, name), limit in sorted(allowed.items()):
        if (rel, name) not in found:
            bad.append(f"{args.allow}: {rel} {name} is no longer over {args.max} lines (or gone): "
                       "delete its line")
    for line in bad:
        print(line, file=sys.stderr)
    print(f"function lengths: {len(long)} over {args.max} lines, {len(bad)} beyond the rule and the allowances")
    return 1 if bad else 0


if __name__ == "__main__":
    sys.exit(main())
