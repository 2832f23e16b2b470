//! Time-step agreement (DESIGN §3 step 1): the minimum of the nodes' proposals, the scene's cap,
//! and what is left to the next output time.

/// The step the coupler announces.
#[derive(Clone, Debug, PartialEq)]
pub struct Agreed {
    /// Step size \[s\].
    pub dt: f64,
    /// `Some(k)` when the step ends exactly at output time `k`.
    pub output: Option<u32>,
    /// Who limited the step: `"fluid:cfl"`, `"solid:elastic"`, `"scene"`, `"output"`.
    pub limiter: String,
}

/// Agrees on the step from time `t`.
///
/// `proposals` are `(node name, dt_max, limiter)`; `outputs` the output times (increasing, the
/// last one is `t_end`); `next_output` the index of the first output time not yet written.
/// Returns `None` when no finite positive step can be agreed (every proposal infinite and no
/// cap), which the caller reports.
pub fn agree(
    t: f64,
    proposals: &[(&str, f64, &str)],
    scene_cap: Option<f64>,
    outputs: &[f64],
    next_output: usize,
) -> Option<Agreed> {
    let mut dt = f64::INFINITY;
    let mut limiter = String::new();
    for (node, dt_max, why) in proposals {
        if *dt_max < dt {
            dt = *dt_max;
            limiter = format!("{node}:{why}");
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

    #[test]
    fn minimum_of_proposals_and_cap() {
        let outputs = [1.0];
        let a = agree(
            0.0,
            &[("fluid", 0.2, "cfl"), ("solid", 0.1, "elastic")],
            None,
            &outputs,
            0,
        )
        .expect("a step");
        assert_eq!(a.dt, 0.1);
        assert_eq!(a.limiter, "solid:elastic");
        assert_eq!(a.output, None);
        let a = agree(0.0, &[("fluid", 0.2, "cfl")], Some(0.05), &outputs, 0).expect("a step");
        assert_eq!((a.dt, a.limiter.as_str()), (0.05, "scene"));
    }

    #[test]
    fn lands_exactly_on_output_times() {
        let outputs = [0.25, 1.0];
        let a = agree(0.2, &[("fluid", 0.1, "cfl")], None, &outputs, 0).expect("a step");
        assert_eq!(a.output, Some(0));
        assert_eq!(0.2 + a.dt, 0.25);
        let a = agree(0.25, &[("fluid", 0.1, "cfl")], None, &outputs, 1).expect("a step");
        assert_eq!((a.dt, a.output), (0.1, None));
    }

    #[test]
    fn refuses_an_unbounded_step_past_the_end() {
        assert_eq!(
            agree(1.0, &[("solid", f64::INFINITY, "none")], None, &[1.0], 0),
            None
        );
        assert_eq!(agree(1.0, &[], None, &[1.0], 1), None);
    }
}
