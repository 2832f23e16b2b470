"""Opens a run's VTK series in ParaView, coloured and laid out (issue 39 item 1).

    pvpython docs/paraview/open_run.py out/clamped-beam-2d            # opens, renders
    pvpython docs/paraview/open_run.py out/clamped-beam-2d shot.png   # and saves the last time

In the ParaView GUI: View > Python Shell > Run Script, after setting the run folder in
COSIM_RUN (the GUI passes no arguments).

What it shows: the fluid (`fluid.pvd`, density `rho` by cell, the "Viridis" map, its colour bar;
the cells the solid covers are hidden by their `vtkGhostType`), the solid's particles
(`solid.pvd`, light grey) and the wet surface (`wet.pvd`, white lines). A 2-D run lies in the
plane z = 0 and gets a 2-D camera looking down z.
"""

import os
import sys

from paraview.simple import (
    ColorBy,
    GetActiveViewOrCreate,
    GetAnimationScene,
    GetColorTransferFunction,
    PVDReader,
    Render,
    ResetCamera,
    SaveScreenshot,
    Show,
)

run = sys.argv[1] if len(sys.argv) > 1 else os.environ.get("COSIM_RUN", "out/clamped-beam-2d")
shot = sys.argv[2] if len(sys.argv) > 2 else None
view = GetActiveViewOrCreate("RenderView")


def series(name):
    path = os.path.join(run, f"{name}.pvd")
    return PVDReader(registrationName=name, FileName=path) if os.path.exists(path) else None


fluid = series("fluid")
if fluid is not None:
    shown = Show(fluid, view)
    ColorBy(shown, ("CELLS", "rho"))
    rho = GetColorTransferFunction("rho")
    rho.ApplyPreset("Viridis (matplotlib)", True)
    shown.RescaleTransferFunctionToDataRange(True, False)
    shown.SetScalarBarVisibility(view, True)
    bounds = fluid.GetDataInformation().GetBounds()
    if bounds[4] == bounds[5]:
        view.InteractionMode = "2D"
        view.CameraPosition = [0.5 * (bounds[0] + bounds[1]), 0.5 * (bounds[2] + bounds[3]), 1.0]
        view.CameraFocalPoint = [0.5 * (bounds[0] + bounds[1]), 0.5 * (bounds[2] + bounds[3]), 0.0]
        view.CameraViewUp = [0.0, 1.0, 0.0]

solid = series("solid")
if solid is not None:
    shown = Show(solid, view)
    ColorBy(shown, None)
    shown.AmbientColor = shown.DiffuseColor = [0.8, 0.8, 0.8]

wet = series("wet")
if wet is not None:
    shown = Show(wet, view)
    ColorBy(shown, None)
    shown.AmbientColor = shown.DiffuseColor = [1.0, 1.0, 1.0]
    shown.LineWidth = 2.0

scene = GetAnimationScene()
scene.UpdateAnimationUsingDataTimeSteps()
scene.AnimationTime = scene.EndTime
ResetCamera(view)
Render(view)
if shot:
    SaveScreenshot(shot, view, ImageResolution=[1600, 900])
