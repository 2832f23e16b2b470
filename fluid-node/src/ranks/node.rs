//! The fluid node on K ranks (issue 16): rank 0 runs the usual node loop over the bus with a
//! [`Leader`] model, which tells the other ranks before each model call which call comes next;
//! the other ranks ([`follow`]) make the same call on their slab. Every call of
//! [`RealFluid`] is collective, so the ranks meet inside it; results (totals, outputs,
//! checkpoints) end on rank 0, which alone writes files and talks to the coupler.
//!
//! A call's errors are deterministic, so every rank meets the same error: rank 0 reports it to
//! the coupler, the others go on waiting for the next call. Rank 0 sends [`Call::Stop`] when its
//! loop ends, however it ends; a rank that dies takes the whole MPI job down (`mpirun` ends
//! the others), which the coupler sees as the fluid's exit.

use std::path::{Path, PathBuf};

use protocol::session::{NodeModel, StepLimit};
use protocol::wire::{ConservedTotals, InterfaceLoads, SolidState, Stamp, StepPlan};

use crate::Error;
use crate::exchange::RealFluid;
use crate::fv::comm::Comm;
use crate::model::FluidModel;

/// What rank 0 asks the other ranks to do next.
#[derive(Debug, serde::Serialize, serde::Deserialize)]
pub enum Call {
    /// [`NodeModel::dt_max`].
    DtMax,
    /// [`NodeModel::totals`].
    Totals(Stamp, f64),
    /// [`NodeModel::checkpoint`].
    Checkpoint,
    /// [`NodeModel::restore`] with these bytes.
    Restore(Vec<u8>),
    /// [`NodeModel::write_output`].
    WriteOutput(u32, f64, PathBuf),
    /// [`NodeModel::record_probes`].
    RecordProbes(f64),
    /// [`FluidModel::set_initial_surface`].
    InitialSurface(Box<SolidState>),
    /// [`FluidModel::predict`].
    Predict(StepPlan),
    /// [`FluidModel::loads`] on this trial solid state.
    Loads(StepPlan, Box<SolidState>),
    /// [`FluidModel::correct`], with the accepted solid state in a coupled scene.
    Correct(StepPlan, Option<Box<SolidState>>),
    /// The end of the run.
    Stop,
}

/// Rank 0's model: announces each call on `calls`, then makes it.
pub struct Leader<'c> {
    /// Rank 0's slab of the fluid.
    pub inner: RealFluid,
    /// Where the calls go (a communicator of its own, so that they never meet the solver's
    /// collectives).
    pub calls: &'c dyn Comm,
}

impl Leader<'_> {
    fn announce(&self, call: &Call) {
        let mut bytes = protocol::codec::encode_blob(call);
        self.calls.broadcast(0, &mut bytes);
    }
}

/// Tells the other ranks the run is over (rank 0, after its loop, whatever its outcome).
pub fn stop(calls: &dyn Comm) {
    let mut bytes = protocol::codec::encode_blob(&Call::Stop);
    calls.broadcast(0, &mut bytes);
}

impl NodeModel for Leader<'_> {
    fn implementation(&self) -> &'static str {
        self.inner.implementation()
    }

    fn dt_max(&self) -> StepLimit {
        self.announce(&Call::DtMax);
        self.inner.dt_max()
    }

    fn totals(&self, stamp: Stamp, t: f64) -> ConservedTotals {
        self.announce(&Call::Totals(stamp, t));
        self.inner.totals(stamp, t)
    }

    fn checkpoint(&self) -> Vec<u8> {
        self.announce(&Call::Checkpoint);
        self.inner.checkpoint()
    }

    fn restore(&mut self, bytes: &[u8]) -> Result<(), String> {
        self.announce(&Call::Restore(bytes.to_vec()));
        self.inner.restore(bytes)
    }

    fn write_output(&mut self, k: u32, t: f64, out: &Path) -> std::io::Result<()> {
        self.announce(&Call::WriteOutput(k, t, out.to_path_buf()));
        self.inner.write_output(k, t, out)
    }

    fn record_probes(&mut self, t: f64) {
        self.announce(&Call::RecordProbes(t));
        self.inner.record_probes(t);
    }

    fn write_probes(&mut self, out: &Path, end: bool) -> std::io::Result<()> {
        // Rank 0 holds every probe's rows: nothing to ask of the others.
        self.inner.write_probes(out, end)
    }
}

impl FluidModel for Leader<'_> {
    fn dim(&self) -> usize {
        self.inner.dim()
    }

    fn set_initial_surface(&mut self, state: &SolidState) -> Result<(), Error> {
        self.announce(&Call::InitialSurface(Box::new(state.clone())));
        self.inner.set_initial_surface(state)
    }

    fn predict(&mut self, plan: &StepPlan) -> Result<(), Error> {
        self.announce(&Call::Predict(plan.clone()));
        self.inner.predict(plan)
    }

    fn loads(&mut self, plan: &StepPlan, state: &SolidState) -> Result<InterfaceLoads, Error> {
        // Collective: every rank takes the sub-faces of its own block, the terms of all are
        // gathered on every rank and added as one rank adds them (`Embedded::loads`), so every
        // rank has the loads of one rank; rank 0's go to the coupler.
        self.announce(&Call::Loads(plan.clone(), Box::new(state.clone())));
        self.inner.loads(plan, state)
    }

    fn correct(&mut self, plan: &StepPlan, state: Option<&SolidState>) -> Result<(), Error> {
        self.announce(&Call::Correct(
            plan.clone(),
            state.map(|s| Box::new(s.clone())),
        ));
        self.inner.correct(plan, state)
    }
}

/// Why a rank other than 0 stopped with an error.
#[derive(Debug, thiserror::Error)]
pub enum FollowError {
    /// Building this rank's model failed (rank 0 met the same error and reported it).
    #[error(transparent)]
    Model(#[from] Error),
    /// Rank 0 asked a call of this rank after building its model failed.
    #[error("rank 0 asked {call} of a rank that failed")]
    AskedFailed {
        /// The call, as `Debug` writes it.
        call: String,
    },
    /// A broadcast from rank 0 does not decode as a call (the codec's reason).
    #[error("a call from rank 0: {0}")]
    Decode(String),
}

/// A rank other than 0: makes rank 0's calls on its block until [`Call::Stop`]. `model` is
/// `Err` when building it failed; rank 0 meets the same error and stops, and the error is
/// returned then. `wait` receives the next call (a broadcast from rank 0 that may wait long).
pub fn follow(
    model: Result<RealFluid, Error>,
    mut wait: impl FnMut() -> Vec<u8>,
) -> Result<(), FollowError> {
    let mut model = model;
    loop {
        let bytes = wait();
        let call: Call = protocol::codec::decode_blob(&bytes).map_err(FollowError::Decode)?;
        let Ok(m) = model.as_mut() else {
            match call {
                Call::Stop => return Ok(model.map(|_| ())?),
                other => {
                    return Err(FollowError::AskedFailed {
                        call: format!("{other:?}"),
                    });
                }
            }
        };
        // Results and errors are rank 0's to report: the other ranks only take part.
        match call {
            Call::Stop => return Ok(()),
            Call::DtMax => {
                m.dt_max();
            }
            Call::Totals(stamp, t) => {
                m.totals(stamp, t);
            }
            Call::Checkpoint => {
                m.checkpoint();
            }
            Call::Restore(bytes) => {
                let _ = m.restore(&bytes);
            }
            Call::WriteOutput(k, t, out) => {
                let _ = m.write_output(k, t, &out);
            }
            Call::RecordProbes(t) => m.record_probes(t),
            Call::InitialSurface(state) => {
                let _ = m.set_initial_surface(&state);
            }
            Call::Predict(plan) => {
                let _ = m.predict(&plan);
            }
            Call::Loads(plan, state) => {
                let _ = m.loads(&plan, &state);
            }
            Call::Correct(plan, state) => {
                let _ = m.correct(&plan, state.as_deref());
            }
        }
    }
}
