#!/usr/bin/env python3
"""Reference text says what the code does now (ctest docs:reference).

README.md, docs/*.md, include/vpm/*.hpp and workflow/*.yaml hold no session words ("the tenth
session", "this session"), no commit hashes ("commit 0abb4d1") and, in Markdown, no dated
headings ("## Bad surfaces (2026-11-23)"); the config files hold no dates at all. Measurements of
the past, with their dates and commits, belong to bench/results/ (LEDGER.md and the folders it
points to) and CHANGELOG.md. The ledger itself keeps its preamble and its table's header (a
row written with `>` instead of `>>` once replaced the whole ledger).

PENDING names the pages still written as a lab notebook: they are reported, not failed, and a
pending page that has become clean fails until it leaves the list, so the list only shrinks.

Usage: check_reference.py SOURCE_DIR | --self-test
"""
import glob
import os
import re
import sys

PENDING: set = set()

ORDINAL = (r"first|second|third|fourth|fifth|sixth|seventh|eighth|ninth|tenth|eleventh|twelfth|"
           r"thirteenth|fourteenth|fifteenth|\d+(?:st|nd|rd|th)|this|previous|next|last")
SESSION = re.compile(rf"\b(?:{ORDINAL}) session\b", re.I)
COMMIT = re.compile(r"\bcommits? [0-9a-f]{7,40}\b")
DATE = re.compile(r"\b20\d\d-[01]\d-[0-3]\d\b")
HEADING = re.compile(r"^#+ ")


def problems(path, text):
    """(line, what) for each line of `text` (the file at `path`) that breaks the rule."""
    markdown, config = path.endswith(".md"), path.endswith((".yaml", ".yml"))
    out, fenced = [], False
    for n, line in enumerate(text.splitlines(), 1):
        if markdown and line.startswith("```"):
            fenced = not fenced
        if SESSION.search(line):
            out.append((n, "a session word: " + SESSION.search(line).group(0)))
        if COMMIT.search(line):
            out.append((n, "a commit hash: " + COMMIT.search(line).group(0)))
        if markdown and not fenced and HEADING.match(line) and DATE.search(line):
            out.append((n, "a dated heading"))
        if config and DATE.search(line):
            out.append((n, "a date in a config file: " + DATE.search(line).group(0)))
    return out


def files(root):
    names = ["README.md"]
    for pattern in ("docs/*.md", "include/vpm/*.hpp", "workflow/*.yaml"):
        names += sorted(os.path.relpath(p, root) for p in glob.glob(os.path.join(root, pattern)))
    return names


LEDGER = "bench/results/LEDGER.md"
LEDGER_HEAD = ("# Results ledger", "| date | what | measured on | result | decision |")


def ledger_problems(text):
    """What is wrong with the ledger's text: its title or its table's header gone."""
    lines = text.splitlines()
    out = []
    if not lines or lines[0] != LEDGER_HEAD[0]:
        out.append("its first line is not " + repr(LEDGER_HEAD[0]) + ": was it overwritten?")
    if LEDGER_HEAD[1] not in lines:
        out.append("its table's header " + repr(LEDGER_HEAD[1]) + " is gone")
    return out


def check(root):
    failed = False
    ledger = os.path.join(root, LEDGER)
    for what in ledger_problems(open(ledger, encoding="utf-8").read() if os.path.exists(ledger) else ""):
        print(f"{LEDGER}: {what}")
        failed = True
    for name in files(root):
        found = problems(name, open(os.path.join(root, name), encoding="utf-8").read())
        if name in PENDING:
            if not found:
                print(f"{name}: reads as reference now: take it off PENDING in tests/arch/check_reference.py")
                failed = True
            else:
                print(f"{name}: pending, {len(found)} lines of history")
            continue
        for n, what in found:
            print(f"{name}:{n}: {what} (history goes to bench/results/LEDGER.md or CHANGELOG.md)")
            failed = True
    missing = sorted(p for p in PENDING if not os.path.exists(os.path.join(root, p)))
    for p in missing:
        print(f"{p}: on PENDING but not there")
    return 1 if failed or missing else 0


def self_test():
    bad = {
        "x.md": "Measured in the tenth session.\n",
        "y.md": "## Bad surfaces (2026-11-23)\n",
        "z.hpp": "/// as of commit 0abb4d1\n",
        "c.yaml": "level: 6  # since 2026-11-29\n",
    }
    good = {
        "x.md": "Measured on 2026-11-29 on the 2-core VM (one run).\n\n## Bad surfaces\n",
        "y.md": "```\n# 2026-11-23 is a date in a code block\n```\n",
        "z.hpp": "/// A session of the browser view keeps its state.\n",
        "c.yaml": "level: 6  # canonical elements\n",
    }
    if not ledger_problems("| 2026-12-05 | a row | m | r | d |\n") or ledger_problems(
            LEDGER_HEAD[0] + "\n\nText.\n\n" + LEDGER_HEAD[1] + "\n|---|\n"):
        print("self-test: the ledger's check")
        return 1
    for name, text in bad.items():
        if not problems(name, text):
            print(f"self-test: {name!r} {text!r} passed but should not")
            return 1
    for name, text in good.items():
        if problems(name, text):
            print(f"self-test: {name!r} {text!r} failed: {problems(name, text)}")
            return 1
    return 0


if __name__ == "__main__":
    if sys.argv[1:] == ["--self-test"]:
        sys.exit(self_test())
    sys.exit(check(sys.argv[1]))
