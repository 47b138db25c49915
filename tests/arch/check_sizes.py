#!/usr/bin/env python3
"""Lists source files over 400 lines and functions over 80 lines in host/, apps/, bench/,
include/ and python/src (C++), the limits of docs/architecture.md. A function may stay longer
when the line before its signature (or its template line) carries a comment starting with
"// long:" that says why.

Functions are found by reading each file's statements at namespace level (comments and string
literals left out): a "{" that ends a statement whose text ends with a parameter list (an
optional const / noexcept / override / trailing return type / constructor initialiser list
after it) opens a function body; struct, class, enum, union and namespace heads do not. A
signature may wrap over several lines; its first line counts as the function's start.
Exits 1 when something is over a limit.
Usage: check_sizes.py [ROOT] | check_sizes.py --self-test
"""
import pathlib
import re
import sys

FILE_LIMIT, FUNC_LIMIT = 400, 80
FOLDERS = ("host", "apps", "bench", "include", "python/src")


def clean(line, state):
    """The line without comments, string and char literals (braces in them do not count);
    state['block'] tracks /* */ comments across lines."""
    out, i, n = [], 0, len(line)
    while i < n:
        if state["block"]:
            j = line.find("*/", i)
            if j < 0:
                return "".join(out)
            state["block"], i = False, j + 2
            continue
        c = line[i]
        if line.startswith("//", i):
            break
        if line.startswith("/*", i):
            state["block"], i = True, i + 2
            continue
        if c in "\"'":
            if c == '"' and i > 0 and line[i - 1] == "R":  # raw string: skip to )"
                j = line.find(')"', i)
                i = n if j < 0 else j + 2
                continue
            j = i + 1
            while j < n and line[j] != c:
                j += 2 if line[j] == "\\" else 1
            out.append(c + c)
            i = j + 1
            continue
        out.append(c)
        i += 1
    return "".join(out)

HEAD = re.compile(r"^\s*(struct|class|enum|union|namespace|extern|template\s*<[^>]*>\s*(struct|class))\b")

def functions(lines):
    state = {"block": False}
    out, depth, ns = [], 0, [0]  # ns: depths at which we are at "namespace level"
    pending, pending_text = None, ""
    body = None  # (start, name, open depth)
    for idx, raw in enumerate(lines):
        line = clean(raw, state)
        if body is None and depth in ns and line.strip() and not line.strip().startswith("#"):
            if pending is None:
                pending, pending_text = idx, ""
            pending_text += " " + line
        for ch in line:
            if ch == "{":
                if body is None and depth in ns and pending is not None:
                    text = pending_text.split("{")[0]
                    if HEAD.match(text) or re.match(r"^\s*namespace\b", text):
                        if re.match(r"^\s*(namespace|extern)\b", text):
                            ns.append(depth + 1)
                        pending = None
                    elif re.search(r"\)\s*(const)?\s*(noexcept)?\s*(override)?\s*(->\s*[\w:<>,\s]+)?\s*(:.*)?$", text) and "=" not in text.split("(")[0]:
                        name = re.search(r"([\w:~]+)\s*\(", text)
                        body = (pending, name.group(1) if name else "?", depth)
                        pending = None
                    else:
                        pending = None
                depth += 1
            elif ch == "}":
                depth -= 1
                if depth + 1 in ns and depth + 1 != 0:
                    ns.remove(depth + 1)
                if body is not None and depth == body[2]:
                    start, name, _ = body
                    allowed = start > 0 and lines[start - 1].strip().startswith("// long:")
                    out.append((start + 1, idx - start + 1, name, allowed))
                    body = None
                pending = None
            elif ch == ";" and body is None and depth in ns:
                pending = None
    return out


def self_test():
    """The finder on made-up code: one-line and wrapped signatures, templates, constructors
    with initialiser lists, methods in classes are not namespace-level, braces in strings."""
    filler = ["  x += 1;"] * 81
    code = (["namespace a {", "int one(int x) {"] + filler + ["}",
             "template <class T>", "static std::vector<T> wrapped(", "    const T& a,", "    int b) const {"] + filler +
            ["}", "Foo::Foo(int n)", "    : n_(n) {", '  s = "{{{";'] + ["  ;"] * 3 + ["}",
             "struct S {", "  void m() {"] + filler + ["  }", "};", "}  // namespace a"])
    found = {name: length for _, length, name, _ in functions(code)}
    assert found.get("one") == 83, found
    assert found.get("wrapped") == 86, found  # template line through the closing brace
    assert found.get("Foo::Foo") == 7, found
    assert "m" not in found, found
    print("self-test: ok")
    return 0


def main():
    if sys.argv[1:] == ["--self-test"]:
        return self_test()
    root = pathlib.Path(sys.argv[1] if len(sys.argv) > 1 else ".")
    problems = []
    for folder in FOLDERS:
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
