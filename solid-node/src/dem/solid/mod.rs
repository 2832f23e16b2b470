//! [`Solid`]: the DEM state and its splittable step (`begin_step`, `trial`…, `commit`).
//!
//! Translation: velocity Verlet (003 eq. (4), (5), (8)); rotation: RATTLE (eq. (6), (7), (9))
//! through [`crate::dem::rattle`] in 3-D, the same kick–drift–kick on the angle in 2-D (rotation
//! about a fixed axis, where RATTLE is exactly Verlet). External loads are held fixed over the
//! step (003 eq. (14)–(17)): they enter both half kicks.
//!
//! Files, by concept: `state` (what a solid holds), `build` (from the scene), `query` (what it
//! answers about the committed state), `evaluate` (forces and wet surface at the committed
//! configuration), `forces` (the link-force kernel), `limits` (time-step bounds), `step`
//! (`begin_step`, `trial`), `substep` (K sub-steps per step), `commit`, `checkpoint`, `orientation` (stored rotations).

mod build;
mod checkpoint;
mod commit;
mod evaluate;
mod forces;
mod limits;
mod orientation;
mod query;
mod state;
mod step;
mod substep;

pub use build::SetupError;
pub use checkpoint::CheckpointError;
pub use limits::{ELASTIC_SAFETY, MAX_ROTATION};
pub use state::{Solid, Trial};
