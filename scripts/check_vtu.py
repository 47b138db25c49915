#!/usr/bin/env python3
"""Opens a .vtu with VTK's own XML reader (Debian: python3-vtk9) and prints what it holds.

usage: check_vtu.py FILE.vtu [FIELD ...]

Prints the point and cell counts, the cell types, and each point/cell field with its number of
components. Exits 1 if VTK cannot read the file (or it has no points), if a FIELD named on the
command line is neither a point nor a cell field; 0 otherwise. On Debian run it with
/usr/bin/python3 (a pyenv/venv python3 may not see python3-vtk9).
"""
import os
import sys


def main(argv):
    if len(argv) < 2:
        print(__doc__.strip(), file=sys.stderr)
        return 2
    path, wanted = argv[1], argv[2:]
    try:
        import vtk  # noqa: F401  (python3-vtk9)
        from vtkmodules.vtkIOXML import vtkXMLUnstructuredGridReader
        from vtkmodules.vtkCommonCore import vtkCommand
    except ImportError as e:
        print(f"check_vtu: cannot import vtk ({e}); install python3-vtk9", file=sys.stderr)
        return 2
    if not os.path.isfile(path):
        print(f"check_vtu: {path}: no such file", file=sys.stderr)
        return 1

    errors = []

    def on_error(obj, event):
        errors.append(event)

    reader = vtkXMLUnstructuredGridReader()
    reader.AddObserver(vtkCommand.ErrorEvent, on_error)
    reader.GetExecutive().AddObserver(vtkCommand.ErrorEvent, on_error)
    reader.SetFileName(path)
    reader.Update()
    grid = reader.GetOutput()
    if errors or grid is None or grid.GetNumberOfPoints() == 0:
        print(f"check_vtu: {path}: VTK could not read the file", file=sys.stderr)
        return 1
    types = sorted({grid.GetCellType(i) for i in range(grid.GetNumberOfCells())})
    print(f"points {grid.GetNumberOfPoints()}")
    print(f"cells {grid.GetNumberOfCells()} types {types}")
    names = set()
    for kind, data in (("point", grid.GetPointData()), ("cell", grid.GetCellData())):
        for i in range(data.GetNumberOfArrays()):
            a = data.GetArray(i)
            names.add(a.GetName())
            print(f"{kind} field {a.GetName()} components {a.GetNumberOfComponents()} "
                  f"type {a.GetDataTypeAsString()} range {a.GetRange(-1 if a.GetNumberOfComponents() > 1 else 0)}")
    missing = [f for f in wanted if f not in names]
    if missing:
        print(f"check_vtu: {path}: missing field(s): {', '.join(missing)}", file=sys.stderr)
        return 1
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv))
