//! [`EmbeddedError`]: why a step of the embedded solid stops, with the step, the cell and the
//! numbers; formatted once, where the node reports it.

use crate::fv::euler::NQ;

use super::NEAR_RADIUS;

/// A stop of the cut-cell method: the input is inconsistent, the solid moved farther than the
/// method allows, or the update produced a state that is not physical.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum EmbeddedError {
    /// The fluid and the solid have different dimensions.
    #[error("the fluid is {fluid}-D and the solid {solid}-D")]
    Dimensions {
        /// The fluid's dimension.
        fluid: usize,
        /// The solid's dimension.
        solid: usize,
    },
    /// A replacement surface has another dimension than the fluid.
    #[error("a {surface}-D surface for a {fluid}-D fluid")]
    SurfaceDimension {
        /// The surface's dimension.
        surface: usize,
        /// The fluid's dimension.
        fluid: usize,
    },
    /// The elements of the wet surface changed within a step (a step's prisms need the same
    /// elements at both ends).
    #[error(
        "{}the wet surface changed its elements ({before} to {after} indices): the swept volumes need the same elements at both ends of a step",
        at(*step)
    )]
    ElementsChanged {
        /// The step, where known.
        step: Option<u64>,
        /// Element indices at `t^n`.
        before: usize,
        /// Element indices at `t^{n+1}`.
        after: usize,
    },
    /// A vertex of the renumbered surface comes from two different vertices of the old one.
    #[error(
        "{}vertex {vertex} of the new wet surface comes from two different vertices of the old one",
        at(*step)
    )]
    VertexFromTwo {
        /// The step, where known.
        step: Option<u64>,
        /// The new vertex.
        vertex: usize,
    },
    /// Some geometry of the surface reaches a cell outside the near cells of `F^n`.
    #[error(
        "{}{what} reaches cell {cell:?} at {center:?}, more than {NEAR_RADIUS} cells from the wet surface at the start of the step (the solid moved too far in one step)",
        at(*step)
    )]
    OutsideNear {
        /// The step, where known.
        step: Option<u64>,
        /// What reached it.
        what: Reach,
        /// The cell's index triple.
        cell: [usize; 3],
        /// The cell's centre \[m\].
        center: [f64; 3],
    },
    /// The surface reaches a periodic side (the geometry does not wrap across it).
    #[error(
        "{}the wet surface reaches the periodic side {side} of the domain: particle {particle}, a vertex at {vertex:?}; a body must stay inside the domain at periodic sides (the geometry does not wrap across them)",
        at(*step)
    )]
    OutsideDomain {
        /// The step, where known (none: the surface at the start).
        step: Option<u64>,
        /// The side: `"x-"`, `"x+"`, … `"z+"`.
        side: &'static str,
        /// The particle of an element with that vertex.
        particle: u32,
        /// The vertex at or beyond the side \[m\].
        vertex: [f64; 3],
    },
    /// Sub-faces without a swept prism: the swept amounts would miss volume.
    #[error(
        "step {step}: {count} sub-faces of the wet surface have no swept prism (non-finite or inconsistent vertices)"
    )]
    NoSweptPrism {
        /// The step.
        step: u64,
        /// Sub-faces skipped.
        count: usize,
    },
    /// A near cell's face fluxes were not kept by the predict.
    #[error("step {step}: face fluxes of near cell {cell:?} were not kept (a bug)")]
    FluxNotKept {
        /// The step.
        step: u64,
        /// The cell's index triple.
        cell: [usize; 3],
    },
    /// Identity (3) broken beyond round-off: the accepted surface folds over itself.
    #[error(
        "step {step}: the accepted wet surface folds over itself in cell {cell:?} at {center:?}: its solid fraction went from {from} to {to} but the swept prisms give {swept:+e} (a defect of {defect:e} of the cell; an element turned inside out, e.g. particles rotated too far relative to their neighbours)"
    )]
    Folded {
        /// The step.
        step: u64,
        /// The cell's index triple.
        cell: [usize; 3],
        /// The cell's centre \[m\].
        center: [f64; 3],
        /// Solid fraction at `t^n`.
        from: f64,
        /// Solid fraction at `t^{n+1}`.
        to: f64,
        /// Swept volume over the cell's volume.
        swept: f64,
        /// Defect over the cell's volume.
        defect: f64,
    },
    /// A mixing group with no fluid volume.
    #[error(
        "no fluid volume to mix cell {cell:?} into (a closed pocket of covered cells holding {content:?})"
    )]
    ClosedPocket {
        /// The group's root cell.
        cell: [usize; 3],
        /// What the pocket holds.
        content: [f64; NQ],
    },
    /// A cut cell's state after the update (eq. 12 and the mixing) is not physical.
    #[error(
        "step {step}: cut cell {cell:?} at {center:?} (fluid fraction {fluid_fraction:e}) is non-physical after the cut-cell update: rho = {rho:e}, p = {p:e}, velocity = {velocity:?}"
    )]
    NonPhysical {
        /// The step.
        step: u64,
        /// The cell's index triple.
        cell: [usize; 3],
        /// The cell's centre \[m\].
        center: [f64; 3],
        /// Its fluid fraction `1 − Λ^{n+1}`.
        fluid_fraction: f64,
        /// Density [kg/m³].
        rho: f64,
        /// Pressure \[Pa\].
        p: f64,
        /// Velocity [m/s].
        velocity: [f64; 3],
    },
}

/// What reached a cell outside the near cells (see [`EmbeddedError::OutsideNear`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Reach {
    /// A sub-face of a trial surface (the loads of a fixed-point iteration).
    TrialSurface,
    /// A sub-face of the accepted surface.
    AcceptedSurface,
    /// A piece of a swept prism.
    SweptPrism,
}

impl std::fmt::Display for Reach {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(match self {
            Reach::TrialSurface => "the trial wet surface",
            Reach::AcceptedSurface => "the accepted wet surface",
            Reach::SweptPrism => "a swept prism",
        })
    }
}

impl EmbeddedError {
    /// The same error, naming `step` if it did not yet (the loads of a trial surface do not know
    /// the step; the exchange does).
    pub fn at_step(mut self, step: u64) -> EmbeddedError {
        match &mut self {
            EmbeddedError::ElementsChanged { step: s, .. }
            | EmbeddedError::VertexFromTwo { step: s, .. }
            | EmbeddedError::OutsideNear { step: s, .. }
            | EmbeddedError::OutsideDomain { step: s, .. } => {
                s.get_or_insert(step);
            }
            _ => {}
        }
        self
    }
}

/// `"step N: "` where the step is known.
fn at(step: Option<u64>) -> String {
    step.map(|s| format!("step {s}: ")).unwrap_or_default()
}
