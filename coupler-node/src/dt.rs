//! Time-step agreement (DESIGN §3 step 1): the minimum of the nodes' proposals, the scene's cap,
//! and what is left to the next output time.
//!
//! The step travels as one named type on each leg: a node's model gives its
//! `protocol::session::StepLimit`, which goes on the wire as a `DtProposal` and becomes a
//! [`Proposal`] in the coupler, [`agree`] turns the proposals into an [`Agreed`] step, the
//! coupler keeps that until the step is done and announces it as a `StepPlan`. The end of the
//! step is [`Agreed::end`] on the coupler's side and `StepPlan::t_end` on the nodes'.

use protocol::wire::{DtProposal, NodeKind};
use serde::{Deserialize, Serialize};

/// One node's proposal for the next step, as the coupler collects it.
#[derive(Clone, Debug, PartialEq)]
pub struct Proposal {
    /// The node that proposes.
    pub node: NodeKind,
    /// Largest stable step \[s\]; `f64::INFINITY` when the node sets no limit.
    pub dt_max: f64,
    /// What limits it (`"cfl"`, `"elastic"`, ...).
    pub limiter: String,
}

impl Proposal {
    /// The proposal `node` sent.
    pub fn from_wire(node: NodeKind, proposal: DtProposal) -> Proposal {
        Proposal {
            node,
            dt_max: proposal.dt_max,
            limiter: proposal.limiter,
        }
    }
}

/// The proposals as an error message shows them: `[("fluid", 0.001, "cfl"), ...]`.
pub fn describe(proposals: &[Proposal]) -> String {
    let listed: Vec<(&str, f64, &str)> = proposals
        .iter()
        .map(|p| (p.node.name(), p.dt_max, p.limiter.as_str()))
        .collect();
    format!("{listed:?}")
}

/// The step the coupler announces.
///
/// Part of the coupler's checkpoint: its `bincode` layout (`dt`, `output`, `limiter`, in this
/// order) is that of the tuple `(f64, Option<u32>, String)` earlier records hold.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Agreed {
    /// Step size \[s\].
    pub dt: f64,
    /// `Some(k)` when the step ends exactly at output time `k`.
    pub output: Option<u32>,
    /// Who limited the step: `"fluid:cfl"`, `"solid:elastic"`, `"scene"`, `"output"`.
    pub limiter: String,
}

impl Agreed {
    /// Time at the end of the step that starts at `t` \[s\]: the output time itself when the
    /// step ends on one (`outputs` as given to [`agree`]), `t + dt` otherwise.
    ///
    /// NOTE: the nodes take `t + dt` for every step (`StepPlan::t_end`). On an output step
    /// `dt = t_out - t`, and `t + dt` can differ from `t_out` in the last bit when `t < t_out / 2`
    /// (the subtraction then rounds); both are kept as the records have them.
    pub fn end(&self, t: f64, outputs: &[f64]) -> f64 {
        match self.output {
            Some(k) => outputs[k as usize],
            None => t + self.dt,
        }
    }
}

/// Agrees on the step from time `t`.
///
/// `proposals` are the nodes' (in the order they arrived); `outputs` the output times (increasing, the
/// last one is `t_end`); `next_output` the index of the first output time not yet written.
/// Returns `None` when no finite positive step can be agreed (every proposal infinite and no
/// cap), which the caller reports.
pub fn agree(
    t: f64,
    proposals: &[Proposal],
    scene_cap: Option<f64>,
    outputs: &[f64],
    next_output: usize,
) -> Option<Agreed> {
    let mut dt = f64::INFINITY;
    let mut limiter = String::new();
    for proposal in proposals {
        if proposal.dt_max < dt {
            dt = proposal.dt_max;
            limiter = format!("{}:{}", proposal.node.name(), proposal.limiter);
        }
    }
    if let Some(cap) = scene_cap
        && cap < dt
    {
        dt = cap;
        limiter = "scene".to_string();
    }
    let t_out = *outputs.get(next_output)?;
    let left = t_out - t;
    let mut output = None;
    // NOTE: a step that would end within a millionth of a step of the output time ends on it,
    // so no sliver step is left before the output.
    if dt.is_infinite() || dt >= left * (1.0 - 1e-6) {
        if dt.is_infinite() && left <= 0.0 {
            return None;
        }
        dt = left;
        output = Some(next_output as u32);
        limiter = "output".to_string();
    }
    (dt.is_finite() && dt > 0.0).then_some(Agreed {
        dt,
        output,
        limiter,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn fluid(dt_max: f64, limiter: &str) -> Proposal {
        Proposal {
            node: NodeKind::Fluid,
            dt_max,
            limiter: limiter.into(),
        }
    }

    fn solid(dt_max: f64, limiter: &str) -> Proposal {
        Proposal {
            node: NodeKind::Solid,
            dt_max,
            limiter: limiter.into(),
        }
    }

    #[test]
    fn minimum_of_proposals_and_cap() {
        let outputs = [1.0];
        let a = agree(
            0.0,
            &[fluid(0.2, "cfl"), solid(0.1, "elastic")],
            None,
            &outputs,
            0,
        )
        .expect("a step");
        assert_eq!(a.dt, 0.1);
        assert_eq!(a.limiter, "solid:elastic");
        assert_eq!(a.output, None);
        let a = agree(0.0, &[fluid(0.2, "cfl")], Some(0.05), &outputs, 0).expect("a step");
        assert_eq!((a.dt, a.limiter.as_str()), (0.05, "scene"));
    }

    #[test]
    fn lands_exactly_on_output_times() {
        let outputs = [0.25, 1.0];
        let a = agree(0.2, &[fluid(0.1, "cfl")], None, &outputs, 0).expect("a step");
        assert_eq!(a.output, Some(0));
        assert_eq!(0.2 + a.dt, 0.25);
        let a = agree(0.25, &[fluid(0.1, "cfl")], None, &outputs, 1).expect("a step");
        assert_eq!((a.dt, a.output), (0.1, None));
    }

    #[test]
    fn refuses_an_unbounded_step_past_the_end() {
        assert_eq!(
            agree(1.0, &[solid(f64::INFINITY, "none")], None, &[1.0], 0),
            None
        );
        assert_eq!(agree(1.0, &[], None, &[1.0], 1), None);
    }

    #[test]
    fn the_agreed_step_is_checkpointed_as_the_tuple_it_replaces() {
        let agreed = Agreed {
            dt: 0.1,
            output: Some(3),
            limiter: "fluid:cfl".into(),
        };
        let tuple = (0.1, Some(3u32), "fluid:cfl".to_string());
        assert_eq!(
            protocol::codec::encode_blob(&Some(agreed)),
            protocol::codec::encode_blob(&Some(tuple))
        );
    }

    #[test]
    fn proposals_are_described_as_before() {
        assert_eq!(
            describe(&[fluid(0.5, "cfl"), solid(f64::INFINITY, "none")]),
            r#"[("fluid", 0.5, "cfl"), ("solid", inf, "none")]"#
        );
    }

    #[test]
    fn the_end_of_an_output_step_is_the_output_time() {
        let outputs = [0.25, 1.0];
        let a = agree(0.2, &[fluid(0.1, "cfl")], None, &outputs, 0).expect("a step");
        assert_eq!(a.end(0.2, &outputs), 0.25);
        let a = agree(0.25, &[fluid(0.1, "cfl")], None, &outputs, 1).expect("a step");
        assert_eq!(a.end(0.25, &outputs), 0.25 + 0.1);
    }
}
