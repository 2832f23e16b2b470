"""Opens every VTK XML file of a run with VTK's own readers (issue 39 item 1).

    check_vtk.py OUT_DIR

For each `.pvd` series: every file it lists exists and loads with vtkXMLImageDataReader
(`.vti`) or vtkXMLPolyDataReader (`.vtp`) without a VTK error or warning, and holds cells.
A `.vti` with a `vtkGhostType` array has exactly its covered cells (alpha <= 1e-12) hidden
(32), and a 2-D fluid lies in the plane z = 0. Prints one line per file; exits 1 on any
failure.
"""

import sys
import xml.etree.ElementTree as ET
from pathlib import Path

import vtk
from vtk.util.numpy_support import vtk_to_numpy


class Errors:
    """Collects VTK's error and warning events (a reader reports damage through them)."""

    def __init__(self):
        self.messages = []

    def __call__(self, obj, event):
        self.messages.append(f"{event}")


def load(path):
    reader = (
        vtk.vtkXMLImageDataReader() if path.suffix == ".vti" else vtk.vtkXMLPolyDataReader()
    )
    errors = Errors()
    reader.AddObserver("ErrorEvent", errors)
    reader.AddObserver("WarningEvent", errors)
    reader.GetExecutive().AddObserver("ErrorEvent", errors)
    reader.SetFileName(str(path))
    reader.Update()
    if errors.messages or reader.GetErrorCode() != 0:
        raise SystemExit(f"{path}: VTK reported {errors.messages} (code {reader.GetErrorCode()})")
    return reader.GetOutput()


def check_image(path, data):
    cells = data.GetCellData()
    alpha = cells.GetArray("alpha")
    ghost = cells.GetArray("vtkGhostType")
    if alpha is None:
        raise SystemExit(f"{path}: no alpha")
    hidden = 0
    if ghost is not None:
        a, g = vtk_to_numpy(alpha), vtk_to_numpy(ghost)
        expected = (a <= 1e-12) * 32
        if not (g == expected).all():
            raise SystemExit(f"{path}: vtkGhostType does not hide exactly the covered cells")
        hidden = int((g == 32).sum())
    dims = data.GetDimensions()
    bounds = data.GetBounds()
    if dims[2] == 1 and (bounds[4], bounds[5]) != (0.0, 0.0):
        raise SystemExit(f"{path}: a 2-D image outside the plane z = 0: {bounds}")
    return f"{data.GetNumberOfCells()} cells, {hidden} hidden, dimensions {dims}"


def main():
    out = Path(sys.argv[1])
    series = sorted(out.glob("*.pvd"))
    if not series:
        raise SystemExit(f"{out}: no .pvd series")
    n = 0
    for pvd in series:
        for ds in ET.parse(pvd).getroot().iter("DataSet"):
            path = out / ds.get("file")
            data = load(path)
            if data.GetNumberOfCells() == 0:
                raise SystemExit(f"{path}: no cells")
            what = check_image(path, data) if path.suffix == ".vti" else (
                f"{data.GetNumberOfPoints()} points, {data.GetNumberOfCells()} cells"
            )
            print(f"{pvd.name} t={ds.get('timestep')} {path.name}: {what}")
            n += 1
    loose = {p.name for p in out.glob("*.vt[ip]")} - {
        ds.get("file") for pvd in series for ds in ET.parse(pvd).getroot().iter("DataSet")
    }
    if loose:
        raise SystemExit(f"files in no series: {sorted(loose)}")
    print(f"{n} files in {len(series)} series load")


main()
