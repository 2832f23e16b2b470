#!/usr/bin/env python3
"""Reads a run's folder with the Python reader `fsi_cosim` (python/, on PYTHONPATH or
installed with `pip install ./python`) and prints, as one JSON object, numbers the Rust test
compares with what the run wrote (tests/it/issue_39_python.rs). Floats are printed as their
shortest round-trip text in quotes (`repr`), which Rust's `str::parse::<f64>` reads back to
the same bits (a JSON number would go through serde_json's faster, inexact parser).

usage: check_reader.py RUN_DIR STEP   (COSIM_COUPLER names the coupler-node binary)
"""

import json
import sys

import numpy as np

import fsi_cosim


def x(value):
    """A float as text that reads back to the same bits."""
    return repr(float(value))


def main(path, step):
    run = fsi_cosim.open_run(path)
    ledger = run.ledger
    diagnostics = run.diagnostics()
    k = int(run.outputs["k"][-1])
    fluid = run.fluid(k)
    p = fluid.grid("p")
    solid = run.solid(k)
    exchange = run.exchange(step, whole=False)
    # The solid's trials put back whole: every one as long as the step's first.
    whole = [m for m in run.exchange(step) if m["kind"] == "SolidState"]
    state = [m for m in exchange if m["kind"] == "SolidState"]
    out = {
        "steps": int(run.summary["steps"]),
        "ledger_rows": int(len(ledger)),
        "ledger_steps": [int(ledger["step"][0]), int(ledger["step"][-1])],
        "max_mass_rel_err": x(np.abs(ledger["mass_rel_err"]).max()),
        "last_energy_rel_err": x(ledger["energy_rel_err"][-1]),
        "diagnostics": len(diagnostics),
        "diagnostics_last_energy_rel_err": x(diagnostics[-1]["ledger"]["energy_rel_err"]),
        "outputs": int(len(run.outputs)),
        "output_k": k,
        "output_t": x(run.outputs["t"][-1]),
        "fluid_shape": list(p.shape),
        "fluid_hidden": int((fluid["vtkGhostType"] & 32 != 0).sum()),
        "fluid_p": [x(v) for v in fluid["p"][[0, len(fluid["p"]) // 2, -1]]],
        "fluid_p_grid_row1_col2": x(p[1, 2]),
        "particles": int(len(solid.points)),
        "particle_last_x": x(solid.points[-1, 0]),
        "particle_last_sigma_n": x(solid["sigma_n"][-1]),
        "exchange_messages": len(exchange),
        "whole_state_lengths": sorted({int(len(m["fields"]["position"])) for m in whole
                                       if m["topic"] == "/solid-to-coupler"}),
        "whole_states_changed_only": sum(bool(m["fields"]["changed_only"]) for m in whole),
        # Each SolidState: topic, sequence, its positions' length and first value.
        "exchange_states": sorted(
            [m["topic"], m["sequence"], int(len(m["fields"]["position"])), x(m["fields"]["position"][0])]
            for m in state
        ),
    }
    print(json.dumps(out))


if __name__ == "__main__":
    main(sys.argv[1], int(sys.argv[2]))
