//! Node-private checkpoints of the solver: the whole grid's state, step counter, time, outflow
//! and directional pressures.

use std::sync::OnceLock;

use crate::fv::euler::NQ;
use crate::fv::slab::take_block;
use crate::fv::solver::FluidSolver;

/// Checkpoint layout (node-private bytes, see [`FluidSolver::to_checkpoint`]).
#[derive(serde::Serialize, serde::Deserialize)]
struct Checkpoint {
    version: u32,
    cells: [u64; 3],
    step: u64,
    time: f64,
    u: Vec<f64>,
    outflow: [f64; NQ],
    pbar: Vec<Vec<f64>>,
}

const CHECKPOINT_VERSION: u32 = 1;

/// Why a checkpoint cannot be restored.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum CheckpointError {
    /// The bytes do not decode (the codec's reason).
    #[error("checkpoint: {0}")]
    Decode(String),
    /// Written by another version of the layout.
    #[error("checkpoint version {found} (expected {CHECKPOINT_VERSION})")]
    Version {
        /// The version found.
        found: u32,
    },
    /// Written for another grid (or with directional pressures of another shape).
    #[error(
        "checkpoint for grid {found_cells:?} with {found_values} values, this solver has \
         {cells:?} with {values}"
    )]
    Grid {
        /// Cells per axis of the checkpoint.
        found_cells: [u64; 3],
        /// Conserved values of the checkpoint.
        found_values: usize,
        /// Cells per axis of this solver's whole grid.
        cells: [u64; 3],
        /// Conserved values of this solver's whole grid.
        values: usize,
    },
}

impl FluidSolver {
    /// Node-private checkpoint bytes: state, step counter, time, outflow and directional
    /// pressures (encoded with `protocol::codec::encode_blob`). Collective: the whole grid is
    /// gathered on rank 0, which gets the bytes one rank would write; the other ranks get none.
    pub fn to_checkpoint(&self) -> Vec<u8> {
        let u = self.gather_cells(&self.state.u);
        let pbar: Vec<Option<Vec<f64>>> = self.pbar.iter().map(|p| self.gather_cells(p)).collect();
        let Some(u) = u else {
            return Vec::new();
        };
        let c = Checkpoint {
            version: CHECKPOINT_VERSION,
            cells: self.slab.global.cells.map(|n| n as u64),
            step: self.step,
            time: self.time,
            u,
            outflow: self.outflow,
            pbar: pbar.into_iter().flatten().collect(),
        };
        protocol::codec::encode_blob(&c)
    }

    /// Restores a checkpoint written by [`FluidSolver::to_checkpoint`] for the same grid (every
    /// rank passes the whole checkpoint and keeps its block, so any rank count restores it).
    pub fn restore_checkpoint(&mut self, bytes: &[u8]) -> Result<(), CheckpointError> {
        let c: Checkpoint = protocol::codec::decode_blob(bytes).map_err(CheckpointError::Decode)?;
        if c.version != CHECKPOINT_VERSION {
            return Err(CheckpointError::Version { found: c.version });
        }
        let global = &self.slab.global;
        let cells = global.cells.map(|n| n as u64);
        let nvar = self.state.nvar;
        if c.cells != cells
            || c.u.len() != nvar * global.n_cells()
            || (!c.pbar.is_empty() && c.pbar.len() != self.grid.dim)
            || c.pbar.iter().any(|p| p.len() != global.n_cells())
        {
            return Err(CheckpointError::Grid {
                found_cells: c.cells,
                found_values: c.u.len(),
                cells,
                values: nvar * global.n_cells(),
            });
        }
        let block = self.slab.block_of_rank(self.slab.rank);
        self.state
            .u
            .copy_from_slice(&take_block(global, block, nvar, &c.u));
        self.step = c.step;
        self.time = c.time;
        self.outflow = c.outflow;
        // Directional pressures come back only where this solver keeps them.
        if !self.pbar.is_empty() {
            if c.pbar.is_empty() {
                self.keep_directional_pressures(true);
            } else {
                self.pbar = c
                    .pbar
                    .iter()
                    .map(|p| take_block(&self.slab.global, block, 1, p))
                    .collect();
            }
        }
        self.dt_cache = OnceLock::new();
        self.sums_cache = OnceLock::new();
        Ok(())
    }
}
