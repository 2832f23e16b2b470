# %% [markdown]
# # The clamped beam's tip against time, redrawn from a run
#
# Paper 003 §5.1.1 (`scenes/clamped-beam-2d.toml`): a beam clamped at the bottom of a channel
# is hit by the waves of a double shock tube. This script redraws the tip's horizontal
# displacement against time (`docs/beam-2d/probe_tip_x.svg`, drawn by `coupler-node report
# figures`) from a run's folder with the Python reader `fsi_cosim` (`pip install ./python`).
# Run it as a script or cell by cell (`# %%`) in VS Code or Jupyter:
#
#     target/release/coupler-node run scenes/clamped-beam-2d.toml --out out/clamped-beam-2d
#     python docs/python/redraw_beam.py out/clamped-beam-2d
#
# With matplotlib it writes `tip_x.png` in the run's folder; without it, `tip_x.csv`.

# %%
import sys

import numpy as np

import fsi_cosim

path = sys.argv[1] if len(sys.argv) > 1 else "out/clamped-beam-2d"
run = fsi_cosim.open_run(path)
print(run.summary["scene"], run.summary["status"], run.summary["steps"], "steps")

# %% The tip probe: the particle at the beam's top (`[[output.probes]] name = "tip"`).
tip = run.probe("tip")
t = tip["t"]
dx = tip["x"] - tip["x"][0]
print(f"largest tip displacement {np.abs(dx).max():.4e} m at t = {t[np.abs(dx).argmax()]:.4f} s")

# %% The conservation ledger: the energy error of the same run, step by step.
print(f"energy error at the end {run.ledger['energy_rel_err'][-1]:.3e} (relative)")

# %% Draw it (or write the data).
try:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
except ImportError:
    plt = None
if plt is None:
    out = f"{path}/tip_x.csv"
    np.savetxt(out, np.column_stack([t, dx]), delimiter=",", header="t,dx", comments="")
else:
    out = f"{path}/tip_x.png"
    fig, ax = plt.subplots(figsize=(6, 3.5))
    ax.plot(t, dx * 1e3)
    ax.set_xlabel("t [s]")
    ax.set_ylabel("tip displacement x - x0 [mm]")
    ax.set_title(f"{run.summary['scene']}: beam tip")
    ax.grid(True, alpha=0.3)
    fig.tight_layout()
    fig.savefig(out, dpi=120)
print("wrote", out)
