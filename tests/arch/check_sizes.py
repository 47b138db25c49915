#!/usr/bin/env python3
"""Lists source files over 400 lines and functions over 80 lines in host/, apps/, bench/ and
include/ (C++), the limits of docs/architecture.md. A function may stay longer when the line
before its signature carries a comment starting with "// long:" that says why.

Functions are found heuristically: a line at brace depth 0 (or 1 inside a namespace) that ends
a signature with "{". Exits 1 when something is over a limit.
Usage: check_sizes.py [ROOT]
"""
import pathlib
import re
import sys

FILE_LIMIT, FUNC_LIMIT = 400, 80
SIG = re.compile(r"^[\w:<>,*&~\s\[\]]+\([^;]*\)\s*(const)?\s*(noexcept)?\s*(->\s*[\w:<>]+)?\s*\{\s*$")


def functions(lines):
    """(start line, length, name) of function bodies at namespace level."""
    out, depth, ns_depth, i = [], 0, 0, 0
    while i < len(lines):
        line = lines[i]
        stripped = line.strip()
        if re.match(r"^namespace\b.*\{\s*$", stripped) or stripped.startswith('extern "C"'):
            ns_depth += 1
            depth += 1
            i += 1
            continue
        if depth == ns_depth and SIG.match(line) and not stripped.startswith(("struct", "class", "enum")):
            start, d = i, 0
            for j in range(i, len(lines)):
                d += lines[j].count("{") - lines[j].count("}")
                if d == 0:
                    name = re.search(r"([\w:~]+)\s*\(", line)
                    allowed = i > 0 and lines[i - 1].strip().startswith("// long:")
                    out.append((start + 1, j - start + 1, name.group(1) if name else "?", allowed))
                    i = j + 1
                    break
            else:
                i += 1
            continue
        depth += line.count("{") - line.count("}")
        ns_depth = min(ns_depth, depth)
        i += 1
    return out


def main():
    root = pathlib.Path(sys.argv[1] if len(sys.argv) > 1 else ".")
    problems = []
    for folder in ("host", "apps", "bench", "include"):
        for path in sorted((root / folder).rglob("*.[ch]pp")):
            lines = path.read_text().splitlines()
            if len(lines) > FILE_LIMIT:
                problems.append(f"{path.relative_to(root)}: {len(lines)} lines (limit {FILE_LIMIT})")
            for start, length, name, allowed in functions(lines):
                if length > FUNC_LIMIT and not allowed:
                    problems.append(f"{path.relative_to(root)}:{start}: {name} is {length} lines (limit {FUNC_LIMIT})")
    for p in problems:
        print(p)
    print(f"{len(problems)} over the limits")
    return 1 if problems else 0


if __name__ == "__main__":
    sys.exit(main())
