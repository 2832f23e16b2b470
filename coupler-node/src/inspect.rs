//! `coupler-node inspect`: pure functions over a [`Recording`]: a table of the recorded steps,
//! a dump of the arrays exchanged at one step (JSON), and a tidy CSV table of every number in
//! the record or one step ([`export_table`]).
//!
//! Step data come from the diagnostics JSON messages (see [`crate::record`]); a step without
//! them (level `exchange` runs cut short, older files) falls back to decoding the bincode frames
//! (`StepPlan` for t and dt, `FixedPointDecision` for the residuals, `ConservedTotals` for the
//! ledger).

use std::collections::BTreeMap;
use std::fmt::Write as _;

use protocol::codec;
use protocol::mcap_read::End;
use protocol::wire::Message;
use serde_json::{Value, json};

use crate::record::{DIAGNOSTICS_TOPIC, RecordError, Recorded, Recording};

/// Output format of [`export_step`].
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ExportFormat {
    /// One JSON document: `{"step": n, "messages": [{topic, sequence, kind, ...fields}]}`.
    Json,
    /// One tidy table ([`export_table`]): header `step,iteration,channel,field,index,value`,
    /// one row per numeric scalar.
    Csv,
}

/// Header of the tidy table of [`export_table`].
pub const TABLE_HEADER: &str = "step,iteration,channel,field,index,value";

/// What is known about one step.
#[derive(Default)]
struct StepRow {
    t: Option<f64>,
    dt: Option<f64>,
    iterations: Option<u64>,
    residuals: Vec<f64>,
    ledger: BTreeMap<String, f64>,
    from_diagnostics: bool,
    converged: bool,
}

/// A table of the recorded steps: step, t, dt, iterations, residual history and ledger totals.
pub fn list_steps(rec: &Recording) -> Result<String, RecordError> {
    let mut rows: BTreeMap<u64, StepRow> = BTreeMap::new();
    for m in rec.topic(DIAGNOSTICS_TOPIC) {
        let value: Value = serde_json::from_slice(&m.data).map_err(|e| decode_err(m, e))?;
        let row = rows.entry(m.step).or_default();
        row.from_diagnostics = true;
        row.converged = value.get("converged").and_then(Value::as_bool) == Some(true);
        row.t = value.get("t").and_then(Value::as_f64);
        row.dt = value.get("dt").and_then(Value::as_f64);
        row.iterations = value.get("iterations").and_then(Value::as_u64);
        row.residuals = value
            .get("residuals")
            .and_then(Value::as_array)
            .map(|a| a.iter().filter_map(Value::as_f64).collect())
            .unwrap_or_default();
        if let Some(ledger) = value.get("ledger").and_then(Value::as_object) {
            for (key, v) in ledger {
                if let Some(x) = v.as_f64() {
                    row.ledger.insert(key.clone(), x);
                }
            }
        }
    }
    // Fallback: decode the frames of steps the diagnostics do not cover.
    for m in rec.messages.iter().filter(|m| is_frame_topic(&m.topic)) {
        let (_, msg) = codec::decode(&m.data).map_err(|e| decode_err(m, e))?;
        // Only the messages of a step that started: a hello, the proposals of the step after
        // the last one, or the shutdown make no row (the count is the run's `steps`).
        if !matches!(
            msg,
            Message::StepPlan(_) | Message::FixedPointDecision(_) | Message::ConservedTotals(_)
        ) || rows.get(&m.step).is_some_and(|r| r.from_diagnostics)
        {
            continue;
        }
        let row = rows.entry(m.step).or_default();
        match msg {
            Message::StepPlan(plan) => {
                row.t = Some(plan.t);
                row.dt = Some(plan.dt);
            }
            Message::FixedPointDecision(d) => {
                row.residuals.push(d.residual);
                row.iterations = Some(u64::from(d.stamp.iteration) + 1);
            }
            Message::ConservedTotals(totals) => {
                let node = totals.node.name();
                row.ledger.insert(format!("{node}_mass"), totals.mass);
                row.ledger.insert(format!("{node}_energy"), totals.energy);
            }
            _ => {}
        }
    }
    let mut out = String::new();
    writeln!(
        out,
        "{:>8}  {:>12}  {:>11}  {:>5}  {:<40}  ledger",
        "step", "t", "dt", "iter", "residuals"
    )
    .expect("writing to a String");
    for (step, row) in &rows {
        let residuals = row
            .residuals
            .iter()
            .map(|r| format!("{r:.2e}"))
            .collect::<Vec<_>>()
            .join(" ");
        let ledger = row
            .ledger
            .iter()
            .map(|(k, v)| format!("{k}={v:.6e}"))
            .collect::<Vec<_>>()
            .join(" ");
        writeln!(
            out,
            "{:>8}  {:>12}  {:>11}  {:>5}  {:<40}  {}",
            step,
            opt(row.t, |t| format!("{t:.6e}")),
            opt(row.dt, |dt| format!("{dt:.4e}")),
            opt(row.iterations, |i| i.to_string()),
            if residuals.is_empty() {
                "-".to_string()
            } else {
                residuals
            },
            if ledger.is_empty() { "-" } else { &ledger },
        )
        .expect("writing to a String");
    }
    // Completed: the steps whose diagnostics say so (as many as the run's `summary.steps`);
    // a record without diagnostics counts the steps it lists.
    let completed = if rows.values().any(|r| r.from_diagnostics) {
        rows.values().filter(|r| r.converged).count()
    } else {
        rows.len()
    };
    let others = rows.len() - completed;
    writeln!(
        out,
        "{completed} steps completed{}, {} messages{}",
        if others > 0 {
            format!(" ({others} more listed: started, failed or without diagnostics)")
        } else {
            String::new()
        },
        rec.messages.len(),
        match describe_end(&rec.end) {
            Some(end) => format!(" ({end})"),
            None => String::new(),
        }
    )
    .expect("writing to a String");
    Ok(out)
}

/// How a record ends, in words, when it did not simply finish.
pub fn describe_end(end: &End) -> Option<String> {
    match end {
        End::Finished {
            summary_damage: None,
        } => None,
        End::Finished {
            summary_damage: Some(damage),
        } => Some(format!(
            "summary section damaged, not needed: {damage}; the data section was read in full"
        )),
        End::Unfinished => {
            Some("not finished: a killed run, readable up to its last completed step".to_string())
        }
        End::CutShort {
            offset,
            unreadable_bytes,
        } => Some(format!(
            "cut short at byte {offset}: {unreadable_bytes} bytes unreadable, a run killed while it wrote"
        )),
    }
}

/// Dumps what was exchanged at `step`: every recorded frame (decoded) and diagnostics message
/// of that coupling step.
pub fn export_step(
    rec: &Recording,
    step: u64,
    format: ExportFormat,
) -> Result<String, RecordError> {
    let at_step: Vec<&Recorded> = rec.messages.iter().filter(|m| m.step == step).collect();
    if at_step.is_empty() {
        return Err(no_such_step(rec, step));
    }
    if format == ExportFormat::Csv {
        return table(&at_step);
    }
    let mut entries = Vec::new();
    for m in at_step {
        let (kind, fields) = if m.topic == DIAGNOSTICS_TOPIC {
            let value: Value = serde_json::from_slice(&m.data).map_err(|e| decode_err(m, e))?;
            ("Diagnostics".to_string(), value)
        } else if is_frame_topic(&m.topic) {
            let (header, msg) = codec::decode(&m.data).map_err(|e| decode_err(m, e))?;
            let mut fields = message_fields(&msg).map_err(|e| decode_err(m, e))?;
            if let Value::Object(map) = &mut fields {
                map.insert("iteration".into(), json!(header.stamp.iteration));
                map.insert("sender".into(), json!(header.sender.name()));
            }
            (format!("{:?}", header.kind), fields)
        } else {
            continue;
        };
        entries.push(json!({
            "topic": m.topic,
            "sequence": m.sequence,
            "kind": kind,
            "fields": fields,
        }));
    }
    match format {
        ExportFormat::Json => {
            let doc = json!({"step": step, "messages": entries});
            serde_json::to_string_pretty(&doc).map_err(|e| RecordError::Decode {
                topic: "export".into(),
                step,
                reason: e.to_string(),
            })
        }
        ExportFormat::Csv => unreachable!("handled above"),
    }
}

fn no_such_step(rec: &Recording, step: u64) -> RecordError {
    let mut steps: Vec<u64> = rec.messages.iter().map(|m| m.step).collect();
    steps.sort_unstable();
    steps.dedup();
    RecordError::NoSuchStep {
        step,
        n_steps: steps.len(),
        first: steps.first().copied().unwrap_or(0),
        last: steps.last().copied().unwrap_or(0),
    }
}

/// The whole record (or one step of it) as one tidy table that `numpy.genfromtxt(names=True)`
/// or any CSV reader loads: header [`TABLE_HEADER`], then one row per numeric scalar of every
/// frame and diagnostics message, in record order.
///
/// - `step`: the coupling step; `iteration`: the frame's fixed-point iteration (0 for the
///   diagnostics, one message per step);
/// - `channel`: the topic (`/fluid-to-coupler`, `/diagnostics`, ...);
/// - `field`: the field's path, nested names joined with `.` (`surface.vertices`,
///   `ledger.fluid_mass`), elements of arrays of objects as `name[i]`;
/// - `index`: the element of an array field (0 for a scalar); `value`: the number (booleans as
///   1 and 0). Strings (limiter, sender, reasons) and checkpoint bytes are left out: the JSON
///   export has them.
pub fn export_table(rec: &Recording, step: Option<u64>) -> Result<String, RecordError> {
    let messages: Vec<&Recorded> = rec
        .messages
        .iter()
        .filter(|m| step.is_none_or(|s| m.step == s))
        .collect();
    if let Some(step) = step
        && messages.is_empty()
    {
        return Err(no_such_step(rec, step));
    }
    table(&messages)
}

fn table(messages: &[&Recorded]) -> Result<String, RecordError> {
    let io = |e: csv::Error| RecordError::Io(e.to_string());
    let mut out = csv::Writer::from_writer(Vec::new());
    out.write_record(TABLE_HEADER.split(',')).map_err(io)?;
    for m in messages {
        message_rows(&mut out, m).map_err(io)??;
    }
    let out = out
        .into_inner()
        .map_err(|e| RecordError::Io(e.to_string()))?;
    Ok(String::from_utf8(out).expect("the rows are UTF-8"))
}

/// Writes the rows of one message to `out` (outer error: writing; inner: decoding).
// NOTE: the rows go through a `csv` writer, which quotes a field name (a key of the
// diagnostics' JSON) holding a comma or a quote, and checks that every row has six fields.
fn message_rows<W: std::io::Write>(
    out: &mut csv::Writer<W>,
    m: &Recorded,
) -> csv::Result<Result<(), RecordError>> {
    match message_fields_of(m) {
        Ok(Some((iteration, fields))) => {
            let prefix = [m.step.to_string(), iteration.to_string(), m.topic.clone()];
            table_rows(out, &prefix, "", &fields).map(Ok)
        }
        Ok(None) => Ok(Ok(())),
        Err(e) => Ok(Err(e)),
    }
}

/// The iteration and fields of a frame or diagnostics message (`None` for another topic).
fn message_fields_of(m: &Recorded) -> Result<Option<(u32, Value)>, RecordError> {
    if m.topic == DIAGNOSTICS_TOPIC {
        let value: Value = serde_json::from_slice(&m.data).map_err(|e| decode_err(m, e))?;
        Ok(Some((0, value)))
    } else if is_frame_topic(&m.topic) {
        let (header, msg) = codec::decode(&m.data).map_err(|e| decode_err(m, e))?;
        let fields = message_fields(&msg).map_err(|e| decode_err(m, e))?;
        Ok(Some((header.stamp.iteration, fields)))
    } else {
        Ok(None)
    }
}

/// Which messages [`stream_table`] exports.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct TableFilter {
    /// Steps, both ends included.
    pub steps: std::ops::RangeInclusive<u64>,
    /// Topics (`/fluid-to-coupler`, `/diagnostics`, ...); empty: every one.
    pub channels: Vec<String>,
}

impl Default for TableFilter {
    fn default() -> TableFilter {
        TableFilter {
            steps: 0..=u64::MAX,
            channels: Vec::new(),
        }
    }
}

/// What [`stream_table`] read and wrote.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct TableSummary {
    /// Messages whose rows were written.
    pub messages: usize,
    /// Steps seen in the record (every message, filtered or not): first and last.
    pub steps: Option<(u64, u64)>,
    /// How the record ends.
    pub end: End,
}

/// [`export_table`] as a stream: reads the record from `input` piece by piece
/// ([`protocol::mcap_read::Stream`]) and writes each message's rows to `out` as it is read,
/// so a record of any size goes through in bounded memory (the largest chunk plus one
/// message's rows). Only the messages `filter` keeps; the same rows, in the same order, as
/// [`export_table`]. A read or write error of the streams is [`RecordError::Io`].
pub fn stream_table(
    mut input: impl std::io::Read,
    filter: &TableFilter,
    out: &mut impl std::io::Write,
) -> Result<TableSummary, RecordError> {
    let io = |what: &'static str| move |e: std::io::Error| RecordError::Io(format!("{what}: {e}"));
    let mut stream = protocol::mcap_read::Stream::new();
    let mut piece = vec![0u8; 1 << 20];
    let mut summary = TableSummary {
        messages: 0,
        steps: None,
        end: End::Unfinished,
    };
    let mut checked: Vec<u16> = Vec::new();
    let write = |e: csv::Error| RecordError::Io(format!("writing: {e}"));
    let mut out = csv::Writer::from_writer(out);
    out.write_record(TABLE_HEADER.split(',')).map_err(write)?;
    loop {
        let n = input.read(&mut piece).map_err(io("reading"))?;
        if n == 0 {
            break;
        }
        stream.feed(&piece[..n])?;
        for m in stream.take_messages() {
            let channel = &stream.channels()[&m.channel_id];
            if !checked.contains(&m.channel_id) {
                let version = stream
                    .metadata()
                    .iter()
                    .find(|(name, _)| name == "run")
                    .and_then(|(_, run)| run.get("protocol_version"))
                    .map(String::as_str);
                if let Some(why) =
                    protocol::topics::legacy_layout([channel.topic.as_str()], version)
                {
                    return Err(RecordError::Layout(why));
                }
                checked.push(m.channel_id);
            }
            let Some(m) = crate::record::recorded(channel, m)? else {
                continue;
            };
            summary.steps = Some(
                summary
                    .steps
                    .map_or((m.step, m.step), |(a, b)| (a.min(m.step), b.max(m.step))),
            );
            if !filter.steps.contains(&m.step)
                || !(filter.channels.is_empty() || filter.channels.contains(&m.topic))
            {
                continue;
            }
            message_rows(&mut out, &m).map_err(write)??;
            summary.messages += 1;
        }
    }
    out.flush().map_err(io("writing"))?;
    summary.end = stream.finish()?;
    Ok(summary)
}

/// Writes `prefix,field,index,value` rows for the numeric scalars in `value` (`prefix`: step,
/// iteration, channel).
fn table_rows<W: std::io::Write>(
    out: &mut csv::Writer<W>,
    prefix: &[String; 3],
    name: &str,
    value: &Value,
) -> csv::Result<()> {
    let number = |v: &Value| match v {
        Value::Number(n) => Some(n.to_string()),
        Value::Bool(b) => Some(u8::from(*b).to_string()),
        _ => None,
    };
    let mut row = |index: usize, x: String| {
        let fields = [name.to_string(), index.to_string(), x];
        out.write_record(prefix.iter().chain(&fields))
    };
    match value {
        Value::Object(map) => {
            for (key, v) in map {
                let child = if name.is_empty() {
                    key.clone()
                } else {
                    format!("{name}.{key}")
                };
                table_rows(out, prefix, &child, v)?;
            }
        }
        Value::Array(items) if items.iter().all(|v| !v.is_object() && !v.is_array()) => {
            for (i, v) in items.iter().enumerate() {
                if let Some(x) = number(v) {
                    row(i, x)?;
                }
            }
        }
        Value::Array(items) => {
            for (i, v) in items.iter().enumerate() {
                table_rows(out, prefix, &format!("{name}[{i}]"), v)?;
            }
        }
        scalar => {
            if let Some(x) = number(scalar) {
                row(0, x)?;
            }
        }
    }
    Ok(())
}

/// The fields of a message as JSON, with checkpoint bytes replaced by their length.
fn message_fields(msg: &Message) -> Result<Value, serde_json::Error> {
    // NOTE: a checkpoint's bytes never become JSON: as a `Value` each byte is a 32-byte number
    // (a fluid checkpoint of 2.8 MB held 88 MB, the peak of a streamed export; issue 39 item 5).
    if let Message::Checkpoint(cp) = msg {
        let mut fields = serde_json::Map::new();
        fields.insert("stamp".into(), serde_json::to_value(cp.stamp)?);
        fields.insert("node".into(), serde_json::to_value(cp.node)?);
        fields.insert("bytes".into(), json!(format!("<{} bytes>", cp.bytes.len())));
        return Ok(Value::Object(fields));
    }
    let mut value = serde_json::to_value(msg)?;
    // Externally tagged enum: {"Kind": {fields}}.
    let inner = match &mut value {
        Value::Object(map) if map.len() == 1 => map.values_mut().next().map(std::mem::take),
        _ => None,
    };
    Ok(inner.unwrap_or(value))
}

fn is_frame_topic(topic: &str) -> bool {
    topic != DIAGNOSTICS_TOPIC
}

fn opt<T>(value: Option<T>, show: impl Fn(T) -> String) -> String {
    value.map_or_else(|| "-".to_string(), show)
}

fn decode_err(m: &Recorded, err: impl std::fmt::Display) -> RecordError {
    RecordError::Decode {
        topic: m.topic.clone(),
        step: m.step,
        reason: err.to_string(),
    }
}
