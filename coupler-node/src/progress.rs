//! The progress line of `coupler-node run`: bar, simulated time, step, dt, iterations and ETA.
//!
//! The ETA is the simulated time left over the recent rate of simulated time per wall second,
//! measured between completed steps only: node start-up, the handshake and the first step (which
//! builds the solvers' scratch buffers) are not counted. On a terminal the line is redrawn in
//! place every 0.2 s; piped, it is a plain line (no `\r`) every 5 s. Either way the last line is
//! drawn when the run ends, so a run that reaches `t_end` ends on 100 %.
//!
//! The line is not a log event: `-v`/`-q` and `RUST_LOG` do not change it (`run -q` turns it
//! off). The coupler's log lines go through [`LogLines`], which knows whether a bar is drawn: it
//! clears the bar, writes the log line, and draws the bar again below it, so neither is cut into
//! the other. The nodes' log lines clear the line before they start ([`protocol::logs`]); the bar
//! comes back with the next step.

// NOTE: written by hand, not with `indicatif` (issue 39 item 8), which would not keep what
// docs/usage.md says: its stderr draw target hides the bar when stderr is not a terminal (a
// piped run shows a plain line every 5 s here); its ETA is an exponentially weighted rate with a
// 15 s weight that counts the time since the last update as no progress (here: simulated time
// per wall second between completed steps of the last 30 s, `--` until two steps); and the
// nodes, other processes, clear the line through `protocol::logs::CLEAR_LINE` before their log
// lines, which its redraws do not know of. Keeping all that would take a custom draw target,
// ETA and log bridge: more code than this file.

use std::collections::VecDeque;
use std::io::{IsTerminal, Write};
use std::sync::Mutex;
use std::time::Instant;

use protocol::logs::CLEAR_LINE;
use tracing_subscriber::fmt::MakeWriter;

use crate::scheme::StepReport;

/// Width of the bar, in characters.
const BAR_WIDTH: usize = 24;

/// Wall time the rate is measured over \[s\]: long enough to smooth step-to-step noise, short
/// enough to follow a run that slows down.
const RATE_WINDOW_S: f64 = 30.0;

/// At most this many samples are kept (a run of tiny steps does not grow the window).
const MAX_SAMPLES: usize = 256;

/// What one progress line shows.
#[derive(Clone, Debug, PartialEq)]
pub struct ProgressLine<'a> {
    /// Scene name.
    pub name: &'a str,
    /// Simulated time reached \[s\].
    pub t: f64,
    /// End time \[s\].
    pub t_end: f64,
    /// Steps completed.
    pub steps: u64,
    /// Last step's size \[s\].
    pub dt: f64,
    /// Last step's coupling iterations.
    pub iterations: u32,
    /// Wall time left \[s\]; `None` until two steps have completed.
    pub eta_s: Option<f64>,
}

/// Formats one progress line (pure): `NAME [####----] t = T/T_END s ( PCT%) step N dt DT it K
/// ETA E s`. The bar and the percentage are `t / t_end`, clamped to `[0, 1]`.
pub fn format_line(p: &ProgressLine<'_>) -> String {
    let frac = if p.t_end > 0.0 {
        (p.t / p.t_end).clamp(0.0, 1.0)
    } else {
        1.0
    };
    let filled = ((frac * BAR_WIDTH as f64).round() as usize).min(BAR_WIDTH);
    let bar = "#".repeat(filled) + &"-".repeat(BAR_WIDTH - filled);
    let eta = match p.eta_s {
        Some(eta) => format!("{eta:.0} s"),
        None => "--".to_string(),
    };
    format!(
        "{} [{bar}] t = {:.4e}/{:.4e} s ({:5.1}%) step {} dt {:.3e} it {} ETA {eta}",
        p.name,
        p.t,
        p.t_end,
        100.0 * frac,
        p.steps,
        p.dt,
        p.iterations,
    )
}

/// The wall time left (pure): `samples` are `(wall_s, t)` pairs of completed steps, oldest first;
/// the rate is simulated time per wall second between the first and the last. `None` with fewer
/// than two samples or no simulated time between them; `Some(0.0)` once `t_end` is reached.
pub fn eta_s(samples: &[(f64, f64)], t_end: f64) -> Option<f64> {
    let (&(wall_0, t_0), &(wall_1, t_1)) = (samples.first()?, samples.last()?);
    if t_1 >= t_end {
        return Some(0.0);
    }
    let (d_wall, d_t) = (wall_1 - wall_0, t_1 - t_0);
    if samples.len() < 2 || d_t <= 0.0 || d_wall <= 0.0 {
        return None;
    }
    Some((t_end - t_1) * d_wall / d_t)
}

/// The bar drawn on the terminal now, if any (redrawn in place, no newline after it).
static DRAWN: Mutex<Option<String>> = Mutex::new(None);

fn drawn() -> std::sync::MutexGuard<'static, Option<String>> {
    // A panic while the lock was held leaves a bar text that is still a bar text.
    DRAWN
        .lock()
        .unwrap_or_else(|poisoned| poisoned.into_inner())
}

/// The coupler's log writer: stderr, one whole line per event ([`protocol::logs::StderrLines`]),
/// around the progress bar when one is drawn.
#[derive(Clone, Copy, Debug)]
pub struct LogLines {
    terminal: bool,
}

impl LogLines {
    /// Stderr as it is now (a terminal or not).
    pub fn new() -> LogLines {
        LogLines {
            terminal: std::io::stderr().is_terminal(),
        }
    }
}

impl Default for LogLines {
    fn default() -> LogLines {
        LogLines::new()
    }
}

impl<'w> MakeWriter<'w> for LogLines {
    type Writer = LogLine;

    fn make_writer(&'w self) -> LogLine {
        LogLine {
            terminal: self.terminal,
            bytes: Vec::with_capacity(128),
        }
    }
}

/// One log line of the coupler on its way to stderr ([`LogLines`]).
#[derive(Debug)]
pub struct LogLine {
    terminal: bool,
    bytes: Vec<u8>,
}

impl Write for LogLine {
    fn write(&mut self, buf: &[u8]) -> std::io::Result<usize> {
        self.bytes.extend_from_slice(buf);
        Ok(buf.len())
    }

    fn flush(&mut self) -> std::io::Result<()> {
        Ok(())
    }
}

impl Drop for LogLine {
    fn drop(&mut self) {
        // NOTE: the bar's lock is taken before stderr's, as `Progress::print` does.
        let bar = drawn();
        let bytes = around_bar(self.terminal, bar.as_deref(), &self.bytes);
        // A closed stderr loses the line; a log line is no reason to fail.
        let _ = std::io::stderr().lock().write_all(&bytes);
    }
}

/// What a log line `line` (ending in a newline) is written as (pure): on a terminal, the line
/// is cleared first and the bar drawn, if any, is drawn again below the log line; piped, the
/// line as it is.
fn around_bar(terminal: bool, bar: Option<&str>, line: &[u8]) -> Vec<u8> {
    if !terminal {
        return line.to_vec();
    }
    let mut bytes = Vec::with_capacity(line.len() + 160);
    bytes.extend_from_slice(CLEAR_LINE.as_bytes());
    bytes.extend_from_slice(line);
    if let Some(bar) = bar {
        bytes.extend_from_slice(bar.as_bytes());
        bytes.extend_from_slice(b"\x1b[K");
    }
    bytes
}

/// The progress line's state: when it last printed and the recent steps' `(wall, t)`.
pub(crate) struct Progress {
    enabled: bool,
    tty: bool,
    origin: Instant,
    last_print: Option<Instant>,
    samples: VecDeque<(f64, f64)>,
    t_end: f64,
    name: String,
    last: Option<(u64, f64, f64, u32)>,
    /// Whether the last report was printed (so `finish` does not print it twice).
    current: bool,
}

impl Progress {
    /// A progress line for a run of `name` to `t_end`, printing only when `enabled`.
    pub(crate) fn new(enabled: bool, name: &str, t_end: f64) -> Progress {
        Progress {
            enabled,
            tty: std::io::stderr().is_terminal(),
            origin: Instant::now(),
            last_print: None,
            samples: VecDeque::new(),
            t_end,
            name: name.to_string(),
            last: None,
            current: false,
        }
    }

    /// A step completed: remember it; print if the last line is old enough.
    pub(crate) fn update(&mut self, r: &StepReport) {
        if !self.enabled {
            return;
        }
        let wall = self.origin.elapsed().as_secs_f64();
        self.samples.push_back((wall, r.t));
        while self.samples.len() > MAX_SAMPLES
            || (self.samples.len() > 2
                && self
                    .samples
                    .front()
                    .is_some_and(|s| wall - s.0 > RATE_WINDOW_S))
        {
            self.samples.pop_front();
        }
        self.last = Some((r.step + 1, r.t, r.dt, r.iterations));
        self.current = false;
        let every = if self.tty { 0.2 } else { 5.0 };
        if self
            .last_print
            .is_some_and(|l| l.elapsed().as_secs_f64() < every)
        {
            return;
        }
        self.print();
    }

    /// The run ended: draw its last step (100 % when it reached `t_end`) and end the line.
    pub(crate) fn finish(&mut self) {
        if !self.enabled || self.last.is_none() {
            return;
        }
        if !self.current {
            self.print();
        }
        if self.tty {
            let mut bar = drawn();
            eprintln!();
            *bar = None;
        }
    }

    fn print(&mut self) {
        let Some((steps, t, dt, iterations)) = self.last else {
            return;
        };
        let eta = eta_s(self.samples.make_contiguous(), self.t_end);
        let line = format_line(&ProgressLine {
            name: &self.name,
            t,
            t_end: self.t_end,
            steps,
            dt,
            iterations,
            eta_s: eta,
        });
        // NOTE: one `write` a line, so that no node's log line cuts into it.
        let mut bar = drawn();
        let bytes = if self.tty {
            format!("\r{line}\x1b[K")
        } else {
            format!("{line}\n")
        };
        let _ = std::io::stderr().lock().write_all(bytes.as_bytes());
        if self.tty {
            *bar = Some(line);
        }
        self.last_print = Some(Instant::now());
        self.current = true;
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn line(t: f64, eta_s: Option<f64>) -> String {
        format_line(&ProgressLine {
            name: "sod",
            t,
            t_end: 0.2,
            steps: 7,
            dt: 1.5e-3,
            iterations: 2,
            eta_s,
        })
    }

    #[test]
    fn a_log_line_clears_the_bar_and_draws_it_again_below_on_a_terminal_only() {
        let log = b"coupler  WARN a warning\n";
        assert_eq!(around_bar(false, Some("sod [##--]"), log), log);
        assert_eq!(
            around_bar(true, None, log),
            b"\r\x1b[Kcoupler  WARN a warning\n"
        );
        assert_eq!(
            around_bar(true, Some("sod [##--]"), log),
            b"\r\x1b[Kcoupler  WARN a warning\nsod [##--]\x1b[K"
        );
    }

    #[test]
    fn the_line_shows_the_fraction_of_t_end_and_the_eta() {
        assert_eq!(
            line(0.05, Some(12.4)),
            "sod [######------------------] t = 5.0000e-2/2.0000e-1 s ( 25.0%) step 7 dt 1.500e-3 it 2 ETA 12 s"
        );
    }

    #[test]
    fn the_bar_is_full_at_t_end_and_before_the_rate_is_known_the_eta_is_dashes() {
        assert_eq!(
            line(0.2, Some(0.0)),
            "sod [########################] t = 2.0000e-1/2.0000e-1 s (100.0%) step 7 dt 1.500e-3 it 2 ETA 0 s"
        );
        assert_eq!(
            line(0.0, None),
            "sod [------------------------] t = 0.0000e0/2.0000e-1 s (  0.0%) step 7 dt 1.500e-3 it 2 ETA --"
        );
        // A last step that overshoots `t_end` by rounding still draws a full bar, no more.
        assert!(line(0.2 + 1e-12, None).contains("[########################] "));
        assert!(line(0.2 + 1e-12, None).contains("(100.0%)"));
    }

    #[test]
    fn the_eta_is_the_time_left_over_the_recent_rate() {
        // 0.5 s of simulated time in 2 wall seconds; 1 s left: 4 s.
        assert_eq!(
            eta_s(&[(3.0, 0.5), (4.0, 0.625), (5.0, 1.0)], 2.0),
            Some(4.0)
        );
        // 0.25 s in 2 wall seconds; 1 s left: 8 s.
        assert_eq!(eta_s(&[(10.0, 0.75), (12.0, 1.0)], 2.0), Some(8.0));
    }

    #[test]
    fn start_up_is_not_counted_because_the_rate_starts_at_the_first_completed_step() {
        // The first step completes 60 s after launch (start-up); the next two take 1 s each.
        // The rate is 0.25 s per wall second, not 0.75 s over 62 s; 1 s left: 4 s, not 83 s.
        let samples = [(60.0, 0.25), (61.0, 0.5), (62.0, 0.75)];
        assert_eq!(eta_s(&samples, 1.75), Some(4.0));
    }

    #[test]
    fn no_eta_from_one_step_or_a_step_of_no_time_and_zero_at_the_end() {
        assert_eq!(eta_s(&[], 1.0), None);
        assert_eq!(eta_s(&[(1.0, 0.5)], 1.0), None);
        assert_eq!(eta_s(&[(1.0, 0.5), (2.0, 0.5)], 1.0), None);
        assert_eq!(eta_s(&[(1.0, 0.5), (2.0, 1.0)], 1.0), Some(0.0));
    }
}
