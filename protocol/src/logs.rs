//! The binaries' logs: one `tracing` subscriber writing to stderr, its level from `RUST_LOG`
//! when that is set and from `-v`/`-q` otherwise, every line prefixed with the process's node
//! name (`fluid`, `solid`, `coupler`), so the three processes of a run, which share one stderr,
//! can be told apart.
//!
//! A line reads `coupler  INFO sod: completed in 400 steps ...`; at debug and trace the event's
//! module follows the level (`fluid   DEBUG protocol::session: greeted the coupler ...`), which
//! is the name a `RUST_LOG` directive selects it by. Each line is written whole with one
//! `write`, so the lines of the three processes do not interleave; on a terminal each starts by
//! clearing the line, so that it does not land on the end of the coupler's progress bar.
//!
//! The libraries only emit events; nothing is written unless a binary installs the subscriber
//! ([`init`]). Final error reports are not events: the binaries print them as plain text, so
//! they keep their exact wording whatever the level.

use std::io::{IsTerminal, Write};

use tracing::level_filters::LevelFilter;
use tracing::{Event, Level, Subscriber};
use tracing_subscriber::EnvFilter;
use tracing_subscriber::fmt::format::Writer;
use tracing_subscriber::fmt::{FmtContext, FormatEvent, FormatFields, MakeWriter};
use tracing_subscriber::registry::LookupSpan;

/// What a terminal line starts with to clear what is on it (a progress bar): carriage return,
/// then erase to the end of the line.
pub const CLEAR_LINE: &str = "\r\x1b[K";

/// How much a process logs when `RUST_LOG` is not set: the counts of `-v` and `-q`, the flags
/// of all three binaries (`#[command(flatten)]`).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, clap::Args)]
pub struct Verbosity {
    /// More log lines on stderr: -v debug, -vv trace (`RUST_LOG`, when set, decides instead, in
    /// every process; `coupler-node run` passes -v/-q on to the nodes).
    #[arg(short, long, action = clap::ArgAction::Count, global = true, help_heading = "Logs")]
    pub verbose: u8,
    /// Fewer log lines on stderr: -q warnings and errors only, -qq errors only; errors are
    /// printed at any level (`coupler-node run -q` also drops the progress line).
    #[arg(
        short,
        long,
        action = clap::ArgAction::Count,
        global = true,
        conflicts_with = "verbose",
        help_heading = "Logs"
    )]
    pub quiet: u8,
}

impl Verbosity {
    /// The level: info by default; `-v` debug, `-vv` trace; `-q` warn, `-qq` error. More of
    /// either change nothing more, and each `-q` takes one `-v` back.
    pub fn level(self) -> LevelFilter {
        match i16::from(self.verbose) - i16::from(self.quiet) {
            ..=-2 => LevelFilter::ERROR,
            -1 => LevelFilter::WARN,
            0 => LevelFilter::INFO,
            1 => LevelFilter::DEBUG,
            2.. => LevelFilter::TRACE,
        }
    }

    /// The flags that give a child process this verbosity: `-v` or `-q` once per count, none
    /// by default.
    pub fn to_args(self) -> Vec<String> {
        let mut args = vec!["-v".to_string(); usize::from(self.verbose)];
        args.extend(vec!["-q".to_string(); usize::from(self.quiet)]);
        args
    }
}

/// The filter of a process: the directives of `rust_log` (the value of `RUST_LOG`) when it is
/// set and not blank, that level alone otherwise. Directives that all name a module keep
/// `verbosity`'s level for the other modules (`RUST_LOG=coupler_node=trace` leaves the nodes'
/// warnings in); a bare level among them (`RUST_LOG=debug`) sets it instead. A value that does
/// not parse is refused with the parser's reason.
pub fn filter(rust_log: Option<&str>, verbosity: Verbosity) -> Result<EnvFilter, String> {
    let level = verbosity.level();
    let builder = EnvFilter::builder().with_default_directive(level.into());
    let Some(directives) = rust_log.map(str::trim).filter(|s| !s.is_empty()) else {
        return Ok(builder.parse_lossy(""));
    };
    let bare_level = directives
        .split(',')
        .any(|d| d.trim().parse::<LevelFilter>().is_ok());
    let all = if bare_level {
        directives.to_string()
    } else {
        format!("{level},{directives}")
    };
    builder
        .parse(all)
        .map_err(|err| format!("RUST_LOG={directives:?} is not a filter: {err}"))
}

/// Installs the stderr subscriber of node `node` ([`StderrLines`]); see [`init_with_writer`].
pub fn init(node: &'static str, verbosity: Verbosity) {
    init_with_writer(node, verbosity, StderrLines::new());
}

/// Installs the subscriber of node `node`: [`NodeLine`] lines into `writer`, filtered by
/// `RUST_LOG` or `verbosity` ([`filter`]). A `RUST_LOG` that does not parse is reported as a
/// warning and `verbosity` decides instead. A second call changes nothing.
pub fn init_with_writer<W>(node: &'static str, verbosity: Verbosity, writer: W)
where
    W: for<'w> MakeWriter<'w> + Send + Sync + 'static,
{
    let rust_log = std::env::var(EnvFilter::DEFAULT_ENV).ok();
    let (filter, refused) = match filter(rust_log.as_deref(), verbosity) {
        Ok(filter) => (filter, None),
        Err(reason) => (
            filter(None, verbosity).expect("a level alone is a filter"),
            Some(reason),
        ),
    };
    let subscriber = tracing_subscriber::fmt()
        .event_format(NodeLine { node })
        .with_env_filter(filter)
        .with_writer(writer)
        .finish();
    if tracing::subscriber::set_global_default(subscriber).is_ok()
        && let Some(reason) = refused
    {
        tracing::warn!("{reason}; using the -v/-q level");
    }
}

/// Prints a final report (an error) on stderr as a plain line, not a log event, so that its
/// text does not depend on the level: one `write`, so that no other process's line cuts into
/// it, after [`CLEAR_LINE`] on a terminal, so that it starts on a line of its own.
pub fn print_report(report: &str) {
    let start = if std::io::stderr().is_terminal() {
        CLEAR_LINE
    } else {
        ""
    };
    let _ = std::io::stderr()
        .lock()
        .write_all(format!("{start}{report}\n").as_bytes());
}

/// The line format: `NODE LEVEL [module: ]message fields`, the node name padded to 7 and the
/// level to 5 characters, the module at debug and trace only.
#[derive(Clone, Copy, Debug)]
pub struct NodeLine {
    /// `fluid`, `solid` or `coupler`.
    pub node: &'static str,
}

impl<S, N> FormatEvent<S, N> for NodeLine
where
    S: Subscriber + for<'a> LookupSpan<'a>,
    N: for<'a> FormatFields<'a> + 'static,
{
    fn format_event(
        &self,
        ctx: &FmtContext<'_, S, N>,
        mut writer: Writer<'_>,
        event: &Event<'_>,
    ) -> std::fmt::Result {
        let meta = event.metadata();
        write_prefix(&mut writer, self.node, *meta.level(), meta.target())?;
        ctx.format_fields(writer.by_ref(), event)?;
        writeln!(writer)
    }
}

/// Stderr, one whole line per event: the event is formatted into a buffer that is written with
/// one `write_all` when it is dropped, after [`CLEAR_LINE`] on a terminal.
#[derive(Clone, Copy, Debug)]
pub struct StderrLines {
    terminal: bool,
}

impl StderrLines {
    /// Stderr as it is now (a terminal or not).
    pub fn new() -> StderrLines {
        StderrLines {
            terminal: std::io::stderr().is_terminal(),
        }
    }
}

impl Default for StderrLines {
    fn default() -> StderrLines {
        StderrLines::new()
    }
}

impl<'w> MakeWriter<'w> for StderrLines {
    type Writer = LineBuffer;

    fn make_writer(&'w self) -> LineBuffer {
        let mut bytes = Vec::with_capacity(128);
        if self.terminal {
            bytes.extend_from_slice(CLEAR_LINE.as_bytes());
        }
        LineBuffer { bytes }
    }
}

/// One event's line on its way to stderr ([`StderrLines`]).
#[derive(Debug)]
pub struct LineBuffer {
    bytes: Vec<u8>,
}

impl Write for LineBuffer {
    fn write(&mut self, buf: &[u8]) -> std::io::Result<usize> {
        self.bytes.extend_from_slice(buf);
        Ok(buf.len())
    }

    fn flush(&mut self) -> std::io::Result<()> {
        Ok(())
    }
}

impl Drop for LineBuffer {
    fn drop(&mut self) {
        // A closed stderr loses the line; a log line is no reason to fail.
        let _ = std::io::stderr().lock().write_all(&self.bytes);
    }
}

/// The start of a [`NodeLine`]: node, level and (debug, trace) module.
fn write_prefix(
    w: &mut impl std::fmt::Write,
    node: &str,
    level: Level,
    target: &str,
) -> std::fmt::Result {
    write!(w, "{node:<7} {level:>5} ")?;
    // NOTE: tracing orders levels by verbosity: TRACE > DEBUG > INFO.
    if level >= Level::DEBUG {
        write!(w, "{target}: ")?;
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    fn v(verbose: u8, quiet: u8) -> Verbosity {
        Verbosity { verbose, quiet }
    }

    #[test]
    fn the_counts_of_v_and_q_step_the_level_from_info() {
        assert_eq!(v(0, 0).level(), LevelFilter::INFO);
        assert_eq!(v(1, 0).level(), LevelFilter::DEBUG);
        assert_eq!(v(2, 0).level(), LevelFilter::TRACE);
        assert_eq!(v(9, 0).level(), LevelFilter::TRACE);
        assert_eq!(v(0, 1).level(), LevelFilter::WARN);
        assert_eq!(v(0, 2).level(), LevelFilter::ERROR);
        assert_eq!(v(0, 9).level(), LevelFilter::ERROR);
        assert_eq!(v(1, 1).level(), LevelFilter::INFO);
    }

    #[test]
    fn a_child_gets_the_same_flags() {
        assert!(v(0, 0).to_args().is_empty());
        assert_eq!(v(2, 0).to_args(), ["-v", "-v"]);
        assert_eq!(v(0, 1).to_args(), ["-q"]);
    }

    #[test]
    fn rust_log_decides_when_set_and_the_flags_fill_in_the_rest() {
        let quiet = v(0, 1);
        assert_eq!(filter(None, quiet).expect("filter").to_string(), "warn");
        assert_eq!(
            filter(Some("  "), quiet).expect("filter").to_string(),
            "warn"
        );
        let named = filter(Some("coupler_node=trace"), quiet).expect("filter");
        let text = named.to_string();
        assert!(
            text.contains("coupler_node=trace") && text.contains("warn"),
            "{text}"
        );
        let bare = filter(Some("debug,protocol=trace"), quiet).expect("filter");
        let text = bare.to_string();
        assert!(
            text.contains("debug") && text.contains("protocol=trace") && !text.contains("warn"),
            "{text}"
        );
        let err = filter(Some("coupler_node=loud"), quiet).expect_err("refused");
        assert!(err.starts_with("RUST_LOG=\"coupler_node=loud\""), "{err}");
    }

    #[test]
    fn lines_start_with_the_node_and_the_level() {
        let prefix = |node, level, target| {
            let mut line = String::new();
            write_prefix(&mut line, node, level, target).expect("a String takes it");
            line
        };
        assert_eq!(
            prefix("coupler", Level::INFO, "coupler_node::cli"),
            "coupler  INFO "
        );
        assert_eq!(
            prefix("fluid", Level::DEBUG, "protocol::session"),
            "fluid   DEBUG protocol::session: "
        );
        assert_eq!(
            prefix("solid", Level::TRACE, "solid_node::node"),
            "solid   TRACE solid_node::node: "
        );
    }
}
