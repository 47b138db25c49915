#!/usr/bin/python3
"""Makes examples/cohort_in_python.ipynb from examples/cohort_in_python.py: one cell per
"# %%" block ("# %% [markdown]" blocks become markdown cells, their "# " prefixes removed).
With --check, exits 1 when the notebook differs from what the script makes (CI)."""
import os
import sys

import nbformat

HERE = os.path.dirname(os.path.abspath(__file__))


def cells(source):
    blocks, current = [], None
    for line in source.splitlines():
        if line.startswith("# %%"):
            current = ["markdown" if "[markdown]" in line else "code", []]
            blocks.append(current)
        elif current is not None:
            current[1].append(line)
    for kind, lines in blocks:
        text = "\n".join(lines).strip("\n")
        if kind == "markdown":
            yield nbformat.v4.new_markdown_cell("\n".join(l[2:] if l.startswith("# ") else l.lstrip("#") for l in text.splitlines()))
        else:
            yield nbformat.v4.new_code_cell(text)


def notebook():
    nb = nbformat.v4.new_notebook()
    nb.cells = list(cells(open(os.path.join(HERE, "cohort_in_python.py")).read()))
    for i, cell in enumerate(nb.cells):
        cell["id"] = f"cell-{i}"  # fixed ids: the same script makes the same notebook
    nb.metadata["kernelspec"] = {"name": "python3", "display_name": "Python 3", "language": "python"}
    return nbformat.writes(nb) + "\n"


if __name__ == "__main__":
    path = os.path.join(HERE, "cohort_in_python.ipynb")
    text = notebook()
    if "--check" in sys.argv:
        same = os.path.exists(path) and open(path).read() == text
        print("notebook up to date" if same else f"{path} differs from the script: run examples/make_notebook.py")
        sys.exit(0 if same else 1)
    open(path, "w").write(text)
    print("wrote", path)
