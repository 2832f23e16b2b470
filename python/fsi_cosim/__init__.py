"""Read the runs of the fluid-structure co-simulation into numpy.

    import fsi_cosim
    run = fsi_cosim.open_run("out/clamped-beam-2d")
    run.summary, run.ledger, run.outputs
    run.fluid(k), run.solid(k), run.diagnostics(), run.exchange(step), run.probe(name)
"""

from .run import Field, Run, open_run, read_csv
from .vtk import VtkFile, parse as parse_vtk, read as read_vtk

__all__ = ["Field", "Run", "VtkFile", "open_run", "parse_vtk", "read_csv", "read_vtk"]
__version__ = "0.1.0"
