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
    GetScalarBar,
    PVDReader,
    Render,
    ResetCamera,
    SaveScreenshot,
    Text,
    Show,
)

run = sys.argv[1] if len(sys.argv) > 1 else os.environ.get("COSIM_RUN", "out/clamped-beam-2d")
shot = sys.argv[2] if len(sys.argv) > 2 else None
view = GetActiveViewOrCreate("RenderView")
if shot:
    # The picture's own size, so that fonts are not scaled up with it.
    view.ViewSize = [1400, 620]


def series(name):
    path = os.path.join(run, f"{name}.pvd")
    return PVDReader(registrationName=name, FileName=path) if os.path.exists(path) else None


fluid = series("fluid")
if fluid is not None:
    shown = Show(fluid, view)
    # "Surface", not the default "Slice" of an image: ParaView 5.11 (Debian 12) draws the slice
    # blank in screenshots larger than about 1000 pixels; the surface honours vtkGhostType too.
    shown.Representation = "Surface"
    ColorBy(shown, ("CELLS", "rho"))
    rho = GetColorTransferFunction("rho")
    rho.ApplyPreset("Viridis (matplotlib)", True)
    shown.RescaleTransferFunctionToDataRange(True, False)
    shown.SetScalarBarVisibility(view, True)
    bar = GetScalarBar(rho, view)
    bar.Title = "rho [kg/m^3]"
    bar.ComponentTitle = ""
    bar.WindowLocation = "Any Location"
    bar.Position = [0.85, 0.12]
    bar.ScalarBarLength = 0.7
    bar.ScalarBarThickness = 16
    bar.TitleFontSize = 18
    bar.LabelFontSize = 16
    bar.RangeLabelFormat = "%-#.1f"
    bounds = fluid.GetDataInformation().GetBounds()
    if bounds[4] == bounds[5]:
        view.InteractionMode = "2D"
        view.CameraPosition = [0.5 * (bounds[0] + bounds[1]), 0.5 * (bounds[2] + bounds[3]), 1.0]
        view.CameraFocalPoint = [0.5 * (bounds[0] + bounds[1]), 0.5 * (bounds[2] + bounds[3]), 0.0]
        view.CameraViewUp = [0.0, 1.0, 0.0]

solid = series("solid")
if solid is not None:
    shown = Show(solid, view)
    # (Not `ColorBy(shown, None)`: ParaView 5.11, Debian 12's, refuses the association None.)
    shown.ColorArrayName = ["POINTS", ""]
    shown.AmbientColor = shown.DiffuseColor = [0.8, 0.8, 0.8]

wet = series("wet")
if wet is not None:
    shown = Show(wet, view)
    shown.ColorArrayName = ["POINTS", ""]
    shown.AmbientColor = shown.DiffuseColor = [1.0, 1.0, 1.0]
    shown.LineWidth = 2.0

scene = GetAnimationScene()
scene.UpdateAnimationUsingDataTimeSteps()
scene.AnimationTime = scene.EndTime
label = Show(Text(Text=f"{os.path.basename(os.path.normpath(run))}, t = {scene.AnimationTime:g} s"), view)
label.WindowLocation = "Upper Left Corner"
label.FontSize = 16
ResetCamera(view)
if fluid is not None and view.InteractionMode == "2D":
    # The fluid's box fills the picture, with room on the right for the colour bar.
    view.CameraParallelScale = 0.6 * (bounds[3] - bounds[2])
    view.CameraPosition[0] = view.CameraFocalPoint[0] = 0.5 * (bounds[0] + bounds[1]) + 0.13 * (
        bounds[1] - bounds[0]
    )
view.OrientationAxesVisibility = 0
Render(view)
if shot:
    SaveScreenshot(shot, view, ImageResolution=[1400, 620])
