//! Message types exchanged between the coupler and the two nodes (DESIGN §3–4).
//!
//! Arrays travel flat (`Vec<f64>`, `Vec<u32>`) so that encoding is a copy, not a walk. Counts and
//! ids are `u32`/`u64`, never `usize`. The spatial dimension `dim` (1, 2 or 3) fixes the stride of
//! every flattened array: positions and forces have `dim` components per particle, rotations have
//! `n_rot(dim)` components (1 in 2-D: the angle about z; 3 in 3-D).

use serde::{Deserialize, Serialize};

mod changes;

/// Bumped on any change to the layout or meaning of a message.
pub const PROTOCOL_VERSION: u32 = 7;

/// Number of rotational degrees of freedom for a spatial dimension: 0 in 1-D, 1 in 2-D, 3 in 3-D.
pub const fn n_rot(dim: u32) -> usize {
    match dim {
        2 => 1,
        3 => 3,
        _ => 0,
    }
}

/// Number of components of an orientation for a spatial dimension: the angle in 2-D, the unit
/// quaternion `(w, x, y, z)` in 3-D.
pub const fn n_orientation(dim: u32) -> usize {
    match dim {
        2 => 1,
        3 => 4,
        _ => 0,
    }
}

/// Which process a message comes from or is meant for.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Serialize, Deserialize)]
pub enum NodeKind {
    /// The coupler: time loop, handshake, record.
    Coupler,
    /// The fluid node (real or double).
    Fluid,
    /// The solid node (real or double).
    Solid,
}

impl NodeKind {
    /// Lower-case name used in service names, logs and file names.
    pub const fn name(self) -> &'static str {
        match self {
            NodeKind::Coupler => "coupler",
            NodeKind::Fluid => "fluid",
            NodeKind::Solid => "solid",
        }
    }

    /// Wire code of the sender in the message header.
    pub const fn code(self) -> u8 {
        match self {
            NodeKind::Coupler => 0,
            NodeKind::Fluid => 1,
            NodeKind::Solid => 2,
        }
    }

    /// Inverse of [`NodeKind::code`].
    pub const fn from_code(code: u8) -> Option<NodeKind> {
        match code {
            0 => Some(NodeKind::Coupler),
            1 => Some(NodeKind::Fluid),
            2 => Some(NodeKind::Solid),
            _ => None,
        }
    }
}

impl std::fmt::Display for NodeKind {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.name())
    }
}

/// Coupling step and fixed-point iteration a message belongs to.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash, Serialize, Deserialize)]
pub struct Stamp {
    /// Coupling step `n` (the step that goes from `t^n` to `t^{n+1}`).
    pub step: u64,
    /// Fixed-point iteration within the step, from 0.
    pub iteration: u32,
}

impl Stamp {
    /// A stamp for iteration 0 of `step`.
    pub const fn step(step: u64) -> Stamp {
        Stamp { step, iteration: 0 }
    }
}

/// Time-coupling scheme (DESIGN §3 step 4).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub enum Scheme {
    /// One pass of loads and solid motion per step (loads on `F^n`).
    Explicit,
    /// Fixed point on the wet-surface position until criterion (22) of paper 003 holds.
    SemiImplicit,
}

/// First message of a node: who it is and what it was built for.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Hello {
    /// The sender's role.
    pub node: NodeKind,
    /// The sender's [`PROTOCOL_VERSION`].
    pub protocol_version: u32,
    /// Hash of the resolved scene the node read ([`crate::scene::Scene::hash`]).
    pub scene_hash: u64,
    /// Which implementation answers: `"real"`, `"prescribed"`, `"pressure"`, `"replay"`.
    pub implementation: String,
    /// Optional features the node offers (for example `"checkpoint"`, `"fracture"`).
    pub capabilities: Vec<String>,
}

/// The coupler's answer to a [`Hello`].
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Welcome {
    /// `true` when the node may go on; otherwise `reason` says why it is refused.
    pub accepted: bool,
    /// Why the node was refused (empty when accepted).
    pub reason: String,
}

/// The largest step a node allows for the coming step (DESIGN §3 step 1).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct DtProposal {
    /// The step this proposal is for.
    pub stamp: Stamp,
    /// Largest stable time step \[s\]; `f64::INFINITY` when the node sets no limit.
    pub dt_max: f64,
    /// What limits it (for example `"cfl"`, `"elastic"`, `"ghost states beside the moving body ..."`), for the diagnostics.
    pub limiter: String,
}

/// The coupler's decision for a step: time, step size and scheme.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct StepPlan {
    /// The step (iteration 0).
    pub stamp: Stamp,
    /// Time at the start of the step `t^n` \[s\].
    pub t: f64,
    /// Step size `dt` \[s\].
    pub dt: f64,
    /// Coupling scheme of this step.
    pub scheme: Scheme,
    /// `Some(k)`: the step ends exactly at the k-th output time; the nodes write output `k`.
    pub output: Option<u32>,
    /// Semi-implicit with `run.predictor = "linear"`: right after this plan the coupler sends
    /// the fluid a predicted `SolidState` (this step, iteration 0), and the fluid computes the
    /// iteration-0 loads on it instead of on the accepted surface `F^n`.
    pub predicted: bool,
}

impl StepPlan {
    /// Time at the end of the step, `t + dt` \[s\]: where the nodes' outputs, probes and
    /// totals of the step stand.
    ///
    /// NOTE: the coupler's own clock lands on the output time itself at the end of an output
    /// step (`coupler-node`'s `dt::Agreed::end`); the two can differ in the last bit.
    pub fn t_end(&self) -> f64 {
        self.t + self.dt
    }
}

/// Pressure loads the fluid applies to the solid, one entry per particle.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct InterfaceLoads {
    /// Coupling step and fixed-point iteration these loads belong to.
    pub stamp: Stamp,
    /// Spatial dimension (stride of `force`).
    pub dim: u32,
    /// Impulse-averaged force on each particle over the step \[N\] (2-D: per unit depth), flattened.
    pub force: Vec<f64>,
    /// Torque on each particle about its centre of mass [N m], flattened (`n_rot(dim)` each).
    pub torque: Vec<f64>,
    /// The solid's numbers of the particles the arrays hold, ascending, when they hold only
    /// some: those of the [`SolidState`] the loads were computed on ([`SolidState::particles`];
    /// the others have none); empty: every particle, in order.
    pub particles: Vec<u32>,
}

/// The wet surface as the solid sends it (DESIGN §3): 3-D triangles, 2-D segments.
///
/// Internal faces of a body that may fracture are carried too, flagged dry until their link
/// breaks, so that fracture changes which elements are wet, not the shape of the message.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct WetSurface {
    /// Incremented each time the connectivity or the wet flags change.
    pub revision: u64,
    /// Spatial dimension: 3 (triangles) or 2 (segments).
    pub dim: u32,
    /// Vertex coordinates \[m\], flattened (`dim` each).
    pub vertices: Vec<f64>,
    /// Element connectivity, `dim` vertex indices per element, oriented as
    /// [`WetSurface::ORIENTATION`] says (closed 2-D loops run counter-clockwise around the solid).
    pub elements: Vec<u32>,
    /// The particle each element belongs to.
    pub element_particle: Vec<u32>,
    /// Whether each element touches the fluid (`false`: an internal face whose link holds).
    pub wet: Vec<bool>,
}

impl WetSurface {
    /// Orientation convention: element normals, from the right-hand rule on the vertex order
    /// (3-D) or the segment direction rotated by −90° (2-D: `(dy, −dx)`), point out of the solid
    /// into the fluid.
    pub const ORIENTATION: &'static str = "normals point out of the solid into the fluid";

    /// Number of vertices.
    pub fn n_vertices(&self) -> usize {
        if self.dim == 0 {
            0
        } else {
            self.vertices.len() / self.dim as usize
        }
    }

    /// Number of elements (triangles or segments).
    pub fn n_elements(&self) -> usize {
        self.element_particle.len()
    }
}

/// Kinematics of the solid particles and the trial (or final) wet surface (DESIGN §3 step 4).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct SolidState {
    /// Coupling step and fixed-point iteration of this trial.
    pub stamp: Stamp,
    /// Spatial dimension (stride of the arrays).
    pub dim: u32,
    /// Centre of mass of each particle at the end of the step `X^{n+1}` \[m\], flattened.
    pub position: Vec<f64>,
    /// Orientation of each particle at the end of the step `Q^{n+1}`: angle \[rad\] in 2-D, unit
    /// quaternion `(w, x, y, z)` in 3-D.
    pub orientation: Vec<f64>,
    /// Mid-step velocity `V^{n+1/2}` [m/s], flattened.
    pub velocity: Vec<f64>,
    /// Mid-step angular velocity `Ω^{n+1/2}` in the global frame [rad/s], `n_rot(dim)` each.
    pub angular_velocity: Vec<f64>,
    /// Diameter `h_s` of each particle \[m\] (weights the rotation term of criterion (22)).
    pub diameter: Vec<f64>,
    /// Wet surface at the end of the step `F^{n+1}`.
    pub surface: WetSurface,
    /// The solid's numbers of the particles the arrays above describe, ascending, when they
    /// describe only some (`surface.element_particle` then counts among these); empty: every
    /// particle, in order. The solid sends all of them; the coupler sends the fluid only those
    /// the elements belong to (issue 39 item 4: in `clamped-beam-2d` 124 of 728, the rest
    /// inside the beam), and spreads the fluid's loads back onto all of them for the solid.
    /// With [`SolidState::changed_only`]: the particles whose kinematics differ from the step's
    /// first trial.
    pub particles: Vec<u32>,
    /// `true`: a trial after the step's first that carries only the particles whose kinematics
    /// differ, bit for bit, from that first trial's (listed in `particles`); every other particle
    /// is as in the first trial, and `surface` is whole, its `element_particle` counting among
    /// every particle. The solid sends its trials after the first so (issue 39 item 4: in the
    /// semi-implicit scheme the internal forces are held, so only the particles the fluid pushes
    /// move differently from one trial to the next: 124 of 728 in `clamped-beam-2d`), and the
    /// coupler puts them back onto the first trial ([`SolidState::merged_onto`]) before anything
    /// reads them. Never sent to the fluid.
    pub changed_only: bool,
}

impl SolidState {
    /// The solid's number of particle `i` of the arrays (see [`SolidState::particles`]).
    pub fn particle_id(&self, i: usize) -> u32 {
        self.particles.get(i).copied().unwrap_or(i as u32)
    }

    /// Number of particles.
    pub fn n_particles(&self) -> usize {
        if self.dim == 0 {
            0
        } else {
            self.position.len() / self.dim as usize
        }
    }
}

/// Outcome of one fixed-point iteration, decided by the coupler.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub enum Decision {
    /// Not converged: the fluid computes loads on the trial surface and the solid tries again.
    Iterate,
    /// Converged (or explicit scheme): the trial is final; the fluid corrects, both commit.
    Accept,
}

/// The fixed-point residual of one iteration and what the coupler decided.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct FixedPointDecision {
    /// Step and iteration the residual was measured at.
    pub stamp: Stamp,
    /// Residual of criterion (22) of paper 003 (relative change of the solid positions).
    pub residual: f64,
    /// The decision.
    pub decision: Decision,
}

/// Conserved totals of one node at the end of a step, for the ledger (DESIGN §3 step 6).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct ConservedTotals {
    /// Step just completed.
    pub stamp: Stamp,
    /// The reporting node.
    pub node: NodeKind,
    /// Time at the end of the step \[s\].
    pub t: f64,
    /// Mass \[kg\] (2-D: per unit depth).
    pub mass: f64,
    /// Linear momentum [kg m/s], `dim` components.
    pub momentum: Vec<f64>,
    /// Total energy \[J\]: fluid total energy, or solid kinetic + elastic energy.
    pub energy: f64,
    /// Energy taken out of the node since the start \[J\]: dissipated (broken links, contact
    /// dashpots and friction), less the work its prescribed motions put in (solid: a particle
    /// driven at a set velocity takes whatever work holds it there).
    pub dissipated: f64,
    /// Work done by the interface loads on this node since the start \[J\] (solid: work received;
    /// fluid: work given, counted positive when the fluid loses energy).
    pub interface_work: f64,
    /// Momentum given through the interface since the start [kg m/s], `dim` components.
    pub interface_impulse: Vec<f64>,
    /// Mass that left or entered through the open domain boundaries since the start \[kg\]
    /// (positive: left), so the ledger can separate boundary flux from conservation error.
    pub boundary_mass_out: f64,
    /// Energy that left through the open domain boundaries since the start \[J\].
    pub boundary_energy_out: f64,
    /// Links broken since the start (solid only).
    pub links_broken: u64,
    /// Particle ids `a, b` of each link broken in this step, two per link, in the order they
    /// broke (solid only; empty in the initial totals and from the doubles). Breaking is decided
    /// when a step is accepted, never on a rejected fixed-point trial.
    pub broken_pairs: Vec<u32>,
    /// For each link of `broken_pairs`, the solid sub-step `j` (1 to K, `run.solid_substeps`;
    /// 1 without sub-steps) at whose end it broke: the coupler gives it the time
    /// `tⁿ + j dt/K` (`links_broken.csv`), the step's end for `j = K` (solid only).
    pub broken_substeps: Vec<u32>,
    /// Fluid mass the solid's motion displaced since the start \[kg\] (2-D: per unit depth):
    /// `Σ_n Σ_cells ρⁿ max(0, Λ^{n+1} − Λⁿ) V`, the fluid that was, at the start of each step,
    /// in the volume the solid newly covers during it (fluid only; 0 from the doubles).
    pub swept_mass: f64,
    /// Cells holding fluid (not covered by the solid) whose density or pressure is below the
    /// `fluid.vacuum` thresholds at the end of the step (fluid only).
    pub vacuum_cells: u64,
    /// Kinetic part of `energy` \[J\] (solid: translation + rotation; the fluid reports 0, its
    /// energy is not split). The rest of a solid's `energy` is potential (elastic links,
    /// contacts, gravity).
    pub kinetic: f64,
    /// Magnitude of the energies involved \[J\]: the sum of the absolute values of the parts of
    /// `energy` (kinetic, elastic, gravity, internal ...), so the ledger can state an energy
    /// error relative to something even when the parts cancel.
    pub energy_scale: f64,
}

/// A node's full state, opaque to the coupler (node-private bincode).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Checkpoint {
    /// State at the start of this step (`stamp.step`, iteration 0).
    pub stamp: Stamp,
    /// Whose state it is.
    pub node: NodeKind,
    /// The node's bytes.
    ///
    /// NOTE: encoded through serde's bytes methods (`serde_bytes`): bincode writes the same
    /// wire bytes as for a sequence of `u8` (the length, then the bytes) but copies them whole,
    /// where a sequence went a byte at a time (about 1 ns a byte each way: a fluid checkpoint of
    /// 2.6 MB took 2.6 ms to encode and 4 ms to decode, 0.26 and 0.23 ms now; issue 39 item 4).
    #[serde(with = "serde_bytes")]
    pub bytes: Vec<u8>,
}

/// The coupler asks a node to write a checkpoint of its state at the start of a step.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct CheckpointRequest {
    /// The step the checkpoint is for.
    pub stamp: Stamp,
}

/// Why the run ends.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub enum ShutdownReason {
    /// `t_end` was reached.
    Completed,
    /// A user asked (Ctrl-C, SIGTERM).
    Interrupted,
    /// A node failed or stopped answering; the text says which and why.
    Failure(String),
}

/// End of the run, sent by the coupler to the nodes (and by a node that must stop).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Shutdown {
    /// The last step reached.
    pub stamp: Stamp,
    /// Why.
    pub reason: ShutdownReason,
}

/// Numerical trouble in a node (NaN, ρ ≤ 0, p ≤ 0, CFL violated ...): the run must stop.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Failure {
    /// Where it happened.
    pub stamp: Stamp,
    /// The failing node.
    pub node: NodeKind,
    /// Human-readable report naming cell or particle and the values.
    pub report: String,
}

/// Every message that crosses a process boundary.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub enum Message {
    /// Node → coupler, first message.
    Hello(Hello),
    /// Coupler → node, answer to hello.
    Welcome(Welcome),
    /// Node → coupler, before each step.
    DtProposal(DtProposal),
    /// Coupler → nodes, start of a step.
    StepPlan(StepPlan),
    /// Fluid → coupler → solid, once per iteration.
    InterfaceLoads(InterfaceLoads),
    /// Solid → coupler → fluid, once per iteration (and once before step 0 with `F^0`).
    SolidState(SolidState),
    /// Coupler → nodes, after each solid trial.
    FixedPointDecision(FixedPointDecision),
    /// Node → coupler, end of each step.
    ConservedTotals(ConservedTotals),
    /// Coupler → node: write a checkpoint.
    CheckpointRequest(CheckpointRequest),
    /// Node → coupler (record), or coupler → node (restore, in replay).
    Checkpoint(Checkpoint),
    /// Either way: the run ends.
    Shutdown(Shutdown),
    /// Node → coupler: numerical trouble.
    Failure(Failure),
}

/// Compact code of each message kind, written in the header.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
#[repr(u16)]
pub enum MessageKind {
    /// [`Message::Hello`].
    Hello = 1,
    /// [`Message::Welcome`].
    Welcome = 2,
    /// [`Message::DtProposal`].
    DtProposal = 3,
    /// [`Message::StepPlan`].
    StepPlan = 4,
    /// [`Message::InterfaceLoads`].
    InterfaceLoads = 5,
    /// [`Message::SolidState`].
    SolidState = 6,
    /// [`Message::FixedPointDecision`].
    FixedPointDecision = 7,
    /// [`Message::ConservedTotals`].
    ConservedTotals = 8,
    /// [`Message::CheckpointRequest`].
    CheckpointRequest = 9,
    /// [`Message::Checkpoint`].
    Checkpoint = 10,
    /// [`Message::Shutdown`].
    Shutdown = 11,
    /// [`Message::Failure`].
    Failure = 12,
}

impl MessageKind {
    /// All kinds, in code order.
    pub const ALL: [MessageKind; 12] = [
        MessageKind::Hello,
        MessageKind::Welcome,
        MessageKind::DtProposal,
        MessageKind::StepPlan,
        MessageKind::InterfaceLoads,
        MessageKind::SolidState,
        MessageKind::FixedPointDecision,
        MessageKind::ConservedTotals,
        MessageKind::CheckpointRequest,
        MessageKind::Checkpoint,
        MessageKind::Shutdown,
        MessageKind::Failure,
    ];

    /// Inverse of `kind as u16`.
    pub fn from_code(code: u16) -> Option<MessageKind> {
        MessageKind::ALL.into_iter().find(|k| *k as u16 == code)
    }

    /// Rust type name of the payload, used in MCAP schema records.
    pub const fn type_name(self) -> &'static str {
        match self {
            MessageKind::Hello => "protocol::wire::Hello",
            MessageKind::Welcome => "protocol::wire::Welcome",
            MessageKind::DtProposal => "protocol::wire::DtProposal",
            MessageKind::StepPlan => "protocol::wire::StepPlan",
            MessageKind::InterfaceLoads => "protocol::wire::InterfaceLoads",
            MessageKind::SolidState => "protocol::wire::SolidState",
            MessageKind::FixedPointDecision => "protocol::wire::FixedPointDecision",
            MessageKind::ConservedTotals => "protocol::wire::ConservedTotals",
            MessageKind::CheckpointRequest => "protocol::wire::CheckpointRequest",
            MessageKind::Checkpoint => "protocol::wire::Checkpoint",
            MessageKind::Shutdown => "protocol::wire::Shutdown",
            MessageKind::Failure => "protocol::wire::Failure",
        }
    }
}

impl Message {
    /// The kind code of this message.
    pub fn kind(&self) -> MessageKind {
        match self {
            Message::Hello(_) => MessageKind::Hello,
            Message::Welcome(_) => MessageKind::Welcome,
            Message::DtProposal(_) => MessageKind::DtProposal,
            Message::StepPlan(_) => MessageKind::StepPlan,
            Message::InterfaceLoads(_) => MessageKind::InterfaceLoads,
            Message::SolidState(_) => MessageKind::SolidState,
            Message::FixedPointDecision(_) => MessageKind::FixedPointDecision,
            Message::ConservedTotals(_) => MessageKind::ConservedTotals,
            Message::CheckpointRequest(_) => MessageKind::CheckpointRequest,
            Message::Checkpoint(_) => MessageKind::Checkpoint,
            Message::Shutdown(_) => MessageKind::Shutdown,
            Message::Failure(_) => MessageKind::Failure,
        }
    }

    /// Step and iteration the message belongs to (hello and welcome: step 0).
    pub fn stamp(&self) -> Stamp {
        match self {
            Message::Hello(_) | Message::Welcome(_) => Stamp::default(),
            Message::DtProposal(m) => m.stamp,
            Message::StepPlan(m) => m.stamp,
            Message::InterfaceLoads(m) => m.stamp,
            Message::SolidState(m) => m.stamp,
            Message::FixedPointDecision(m) => m.stamp,
            Message::ConservedTotals(m) => m.stamp,
            Message::CheckpointRequest(m) => m.stamp,
            Message::Checkpoint(m) => m.stamp,
            Message::Shutdown(m) => m.stamp,
            Message::Failure(m) => m.stamp,
        }
    }
}
