#!/usr/bin/env python3
"""Fills the options tables of the stage pages from the command registry.

A page holds a table of a command's options between the lines
    <!-- options: vpm CMD -->
    <!-- /options -->
and this script writes it from `vpm CMD --help --expert` (BINARY, default build/vpm): one row per
option, its value and what it does, the expert options last and marked. With --check it exits 1
when a page's table differs from what it would write (tests/test_cli.cpp runs it that way).

Usage: doc_options.py [BINARY] [--check | --write] [PAGE.md ...]  (default: every docs/*.md)
"""
import glob
import os
import re
import subprocess
import sys

BLOCK = re.compile(r"(<!-- options: vpm ([\w-]+) -->\n)(.*?)(<!-- /options -->)", re.S)


def parse_help(text):
    """[(option, help, expert)] from `vpm CMD --help --expert`: option lines start with two
    spaces and a dash, continuation lines with more spaces."""
    rows, section = [], None
    for line in text.splitlines():
        if line == "options:":
            section = "plain"
        elif line.startswith("expert options"):
            section = "expert"
        elif section and line.startswith("  -"):
            parts = re.split(r"\s{2,}", line.strip(), maxsplit=1)
            rows.append([parts[0], parts[1] if len(parts) > 1 else "", section == "expert"])
        elif section and line.startswith("    ") and rows:
            rows[-1][1] += " " + line.strip()
        elif section and not line.startswith(" "):
            section = None if not line.startswith("expert options") else section
    return rows


def table(binary, command):
    text = subprocess.run([binary, command, "--help", "--expert"], capture_output=True, text=True,
                          check=True).stdout
    out = ["| option | what it does |", "|---|---|"]
    for option, what, expert in parse_help(text):
        option, what = option.replace("|", "\\|"), what.replace("|", "\\|")  # GFM: escaped in code too
        out.append(f"| `{option}` | {'(expert) ' if expert else ''}{what} |")
    out.append("")
    out.append(f"Generated from `vpm {command} --help --expert` (scripts/doc_options.py); every command"
               " also takes `--quiet` and `--verbose`.")
    return "\n".join(out) + "\n"


def rewrite(binary, text):
    return BLOCK.sub(lambda m: m.group(1) + table(binary, m.group(2)) + m.group(4), text)


def main():
    args = sys.argv[1:]
    mode = None
    for flag in ("--check", "--write"):
        if flag in args:
            mode = flag
            args.remove(flag)
    binary = args.pop(0) if args and not args[0].endswith(".md") else "build/vpm"
    root = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
    pages = args or sorted(glob.glob(os.path.join(root, "docs", "*.md")))
    stale = []
    for page in pages:
        text = open(page, encoding="utf-8").read()
        if not BLOCK.search(text):
            continue
        want = rewrite(binary, text)
        if want == text:
            continue
        if mode == "--write":
            open(page, "w", encoding="utf-8").write(want)
        elif mode == "--check":
            stale.append(page)
        else:
            sys.stdout.write(want)
    for page in stale:
        sys.stderr.write(f"{page}: an options table differs from the command's --help; "
                         "run scripts/doc_options.py --write\n")
    return 1 if stale else 0


if __name__ == "__main__":
    sys.exit(main())
