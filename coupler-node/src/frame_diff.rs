//! What a replay found, and the first difference between a recorded and a replayed frame, with
//! the channel, step, iteration, field, index and both values. Shared by the replays of a node
//! ([`crate::replay`]) and of the coupler ([`crate::coupler_replay`]).

use protocol::codec;
use serde_json::Value;

/// What the replay found.
#[derive(Clone, Debug, PartialEq)]
pub enum Outcome {
    /// Every compared message matched.
    Identical {
        /// Messages compared.
        compared: usize,
        /// Step the comparison started at (a checkpoint, or 0).
        from_step: u64,
    },
    /// The first difference.
    Differs(String),
}

/// `None` when equal; otherwise where the first difference is (`channel` names the frames).
pub(crate) fn compare(channel: &str, recorded: &[u8], replayed: &[u8]) -> Option<String> {
    if recorded == replayed {
        return None;
    }
    let (rh, rm) = match codec::decode(recorded) {
        Ok(x) => x,
        Err(e) => {
            return Some(format!(
                "{channel}: the recorded frame does not decode: {e}"
            ));
        }
    };
    let (ph, pm) = match codec::decode(replayed) {
        Ok(x) => x,
        Err(e) => {
            return Some(format!(
                "{channel}: the replayed frame does not decode: {e}"
            ));
        }
    };
    let head = format!(
        "{channel} step {} iteration {}",
        rh.stamp.step, rh.stamp.iteration
    );
    if rh.kind != ph.kind || rh.stamp != ph.stamp {
        return Some(format!(
            "{head}: recorded {:?} (step {}, iteration {}), replayed {:?} (step {}, iteration {})",
            rh.kind, rh.stamp.step, rh.stamp.iteration, ph.kind, ph.stamp.step, ph.stamp.iteration
        ));
    }
    let a = serde_json::to_value(&rm).unwrap_or(Value::Null);
    let b = serde_json::to_value(&pm).unwrap_or(Value::Null);
    let (path, va, vb) = first_difference(&a, &b, String::new()).unwrap_or((
        "(bytes)".into(),
        Value::Null,
        Value::Null,
    ));
    Some(format!(
        "{head}: field {path}: recorded {va}, replayed {vb}"
    ))
}

fn first_difference(a: &Value, b: &Value, path: String) -> Option<(String, Value, Value)> {
    match (a, b) {
        (Value::Object(x), Value::Object(y)) => {
            for (k, va) in x {
                let vb = y.get(k).unwrap_or(&Value::Null);
                let sub = if path.is_empty() {
                    k.clone()
                } else {
                    format!("{path}.{k}")
                };
                if let Some(d) = first_difference(va, vb, sub) {
                    return Some(d);
                }
            }
            None
        }
        (Value::Array(x), Value::Array(y)) => {
            for i in 0..x.len().max(y.len()) {
                let va = x.get(i).unwrap_or(&Value::Null);
                let vb = y.get(i).unwrap_or(&Value::Null);
                if let Some(d) = first_difference(va, vb, format!("{path}[{i}]")) {
                    return Some(d);
                }
            }
            None
        }
        // NOTE: numbers are compared by their bits through the JSON text, which prints the
        // shortest representation that round-trips, so different bits print differently.
        _ if a == b => None,
        _ => Some((path, a.clone(), b.clone())),
    }
}
