//! A progress line on stderr. On a terminal it is redrawn in place (`\r`) at most five times a
//! second; elsewhere (a CI log, `2> file`) a redraw would pile up as one endless line of
//! carriage returns, so a whole line is written at most every `LOG_EVERY` instead, and the last.

use std::io::{IsTerminal, Write};
use std::time::{Duration, Instant};

const REDRAW_EVERY: Duration = Duration::from_millis(200);
const LOG_EVERY: Duration = Duration::from_secs(10);

pub struct Progress {
    terminal: bool,
    last: Option<Instant>,
    drawn: bool,
    /// The last line has been shown: callers that report "done" more than once (replay does,
    /// as its final frames come in) printed it twice.
    done: bool,
}

impl Progress {
    pub fn new() -> Progress {
        Progress::to(std::io::stderr().is_terminal())
    }

    fn to(terminal: bool) -> Progress {
        Progress {
            terminal,
            last: None,
            drawn: false,
            done: false,
        }
    }

    /// Shows `line` if it is time to, or always when `last` (the work is done).
    pub fn show(&mut self, line: impl std::fmt::Display, last: bool) {
        if let Some(text) = self.render(&line, last, Instant::now()) {
            let mut err = std::io::stderr().lock();
            // A progress line that cannot be written is no reason to stop the work.
            let _ = err.write_all(text.as_bytes());
            let _ = err.flush();
        }
    }

    /// Ends the line on a terminal (the next output starts on a line of its own).
    pub fn finish(&mut self) {
        if self.terminal && self.drawn {
            eprintln!();
        }
        self.drawn = false;
    }

    /// What to write for `line` at `now`, if anything.
    fn render(&mut self, line: &dyn std::fmt::Display, last: bool, now: Instant) -> Option<String> {
        let every = if self.terminal {
            REDRAW_EVERY
        } else {
            LOG_EVERY
        };
        if self.done || (!last && self.last.is_some_and(|t| now.duration_since(t) < every)) {
            return None;
        }
        self.last = Some(now);
        self.drawn = true;
        self.done = last;
        Some(if self.terminal {
            format!("\r{line}")
        } else {
            format!("{line}\n")
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_log_gets_whole_lines_now_and_then_and_a_terminal_redraws_in_place() {
        let t0 = Instant::now();
        let mut log = Progress::to(false);
        let at = |s: f64| t0 + Duration::from_secs_f64(s);
        assert_eq!(
            log.render(&"1/40 s", false, at(0.0)).as_deref(),
            Some("1/40 s\n")
        );
        // Nothing until LOG_EVERY has passed, except the last.
        assert_eq!(log.render(&"2/40 s", false, at(1.0)), None);
        assert_eq!(
            log.render(&"11/40 s", false, at(10.0)).as_deref(),
            Some("11/40 s\n")
        );
        assert_eq!(log.render(&"12/40 s", false, at(11.0)), None);
        assert_eq!(
            log.render(&"40/40 s", true, at(12.0)).as_deref(),
            Some("40/40 s\n")
        );
        assert_eq!(
            log.render(&"40/40 s", true, at(12.1)),
            None,
            "done is said once"
        );
        let mut tty = Progress::to(true);
        assert_eq!(tty.render(&"a", false, at(0.0)).as_deref(), Some("\ra"));
        assert_eq!(tty.render(&"b", false, at(0.1)), None);
        assert_eq!(tty.render(&"c", false, at(0.3)).as_deref(), Some("\rc"));
    }
}
