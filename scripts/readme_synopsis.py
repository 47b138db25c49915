#!/usr/bin/env python3
"""Prints the command synopsis block of docs/cli.md from `vpm --help` (BINARY, default build/vpm),
wrapped at 100 columns between options; with --check docs/cli.md, exits 1 when the page's block
differs (tests/test_cli.cpp runs it that way).

Usage: readme_synopsis.py [BINARY] [--check docs/cli.md | --check --write]  (--write: rewrite docs/cli.md's block)
"""
import subprocess
import sys


def items(synopsis):
    """Splits a synopsis at spaces outside brackets, keeping "A | B" groups whole."""
    out, depth, cur = [], 0, ""
    for ch in synopsis:
        depth += ch in "[("
        depth -= ch in "])"
        if ch == " " and depth == 0:
            out.append(cur)
            cur = ""
        else:
            cur += ch
    out.append(cur)
    return out


def block(binary):
    text = subprocess.run([binary, "--help"], capture_output=True, text=True, check=True).stdout
    lines = []
    for syn in (l.strip() for l in text.splitlines() if l.startswith("  vpm ")):
        cur = ""
        for tok in items(syn):
            if cur and tok[:1] in "[(" and len(cur) + 1 + len(tok) > 100:
                lines.append(cur)
                cur = "    " + tok
            else:
                cur = cur + " " + tok if cur else tok
        lines.append(cur)
    return "\n".join(lines) + "\n"


def readme_block(path):
    text = open(path).read()
    start = text.index("## Commands\n\n```\n") + len("## Commands\n\n```\n")
    return text, start, text.index("```", start)


def main():
    args = sys.argv[1:]
    check = None
    if "--check" in args:
        i = args.index("--check")
        check = args[i + 1]
        del args[i:i + 2]
    want = block(args[0] if args else "build/vpm")
    if check is None:
        sys.stdout.write(want)
        return 0
    if check == "--write":
        text, start, end = readme_block("docs/cli.md")
        open("docs/cli.md", "w").write(text[:start] + want + text[end:])
        return 0
    text, start, end = readme_block(check)
    if text[start:end] == want:
        return 0
    sys.stderr.write(f"{check}: the command synopsis differs from `vpm --help`; expected:\n{want}")
    return 1


if __name__ == "__main__":
    sys.exit(main())
