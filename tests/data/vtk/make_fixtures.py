#!/usr/bin/python3
"""Writes the .vtu fixtures of tests/test_io_vtk_binary.cpp with VTK's own writer (python3-vtk9):
one small tet mesh with fields (Float64 vectors, Float32 and Int32 scalars, an Int32 cell field)
in every data mode VTK writes: ascii (the reference), inline binary (UInt32 and UInt64 headers,
zlib), appended raw and base64 (zlib too). Run from this folder; the output is deterministic."""
import vtk

pts = vtk.vtkPoints()
pts.SetDataTypeToDouble()
n = 4
for k in range(n):
    for j in range(n):
        for i in range(n):
            pts.InsertNextPoint(i * 0.5 + 0.01 * j, j * 0.5, k * 0.5 + 0.003 * i * i)
grid = vtk.vtkUnstructuredGrid()
grid.SetPoints(pts)
cube = [(0, 0, 0), (1, 0, 0), (1, 1, 0), (0, 1, 0), (0, 0, 1), (1, 0, 1), (1, 1, 1), (0, 1, 1)]
split = [(0, 1, 3, 4), (1, 2, 3, 6), (1, 3, 4, 6), (1, 4, 5, 6), (3, 4, 6, 7)]
idx = lambda i, j, k: i + n * (j + n * k)
for k in range(n - 1):
    for j in range(n - 1):
        for i in range(n - 1):
            c = [idx(i + a, j + b, k + d) for a, b, d in cube]
            for t in split:
                grid.InsertNextCell(vtk.VTK_TETRA, 4, [c[q] for q in t])
vec = vtk.vtkDoubleArray(); vec.SetName("original_position"); vec.SetNumberOfComponents(3)
f32 = vtk.vtkFloatArray(); f32.SetName("ratio32")
i32 = vtk.vtkIntArray(); i32.SetName("vertex_label")
for p in range(grid.GetNumberOfPoints()):
    x = grid.GetPoint(p)
    vec.InsertNextTuple3(x[0] * 70 - 3.25, x[1] * 70 + 1e-9 * p, x[2] * 70)
    f32.InsertNextValue(1.0 + 0.001 * p)
    i32.InsertNextValue(p % 7 - 3)
lab = vtk.vtkIntArray(); lab.SetName("label")
for c in range(grid.GetNumberOfCells()):
    lab.InsertNextValue(c % 5 + 1)
for a in (vec, f32, i32):
    grid.GetPointData().AddArray(a)
grid.GetCellData().AddArray(lab)

modes = {
    "ascii": ("ascii", None, False, False),
    "binary": ("binary", None, False, False),
    "binary_u64": ("binary", None, True, False),
    "binary_zlib": ("binary", "zlib", False, False),
    "appended_raw": ("appended", None, False, True),
    "appended_raw_zlib_u64": ("appended", "zlib", True, True),
    "appended_base64": ("appended", None, False, False),
    "appended_base64_zlib": ("appended", "zlib", False, False),
}
for name, (mode, comp, h64, raw) in modes.items():
    w = vtk.vtkXMLUnstructuredGridWriter()
    w.SetInputData(grid)
    w.SetFileName(f"grid_{name}.vtu")
    {"ascii": w.SetDataModeToAscii, "binary": w.SetDataModeToBinary, "appended": w.SetDataModeToAppended}[mode]()
    if mode == "appended":
        w.SetEncodeAppendedData(0 if raw else 1)
    if comp:
        w.SetCompressorTypeToZLib()
        w.SetBlockSize(1024)  # several blocks per array
    else:
        w.SetCompressorTypeToNone()
    if h64:
        w.SetHeaderTypeToUInt64()
    w.Write()
