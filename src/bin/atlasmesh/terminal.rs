//! Progress on the terminal: bars and spinners (indicatif) on a terminal, plain log lines on
//! stderr otherwise, nothing with `--quiet`.

use atlasmesh::study::Progress;
use indicatif::{ProgressBar, ProgressStyle};
use std::collections::HashMap;
use std::io::IsTerminal;
use std::sync::Mutex;
use std::sync::atomic::{AtomicU64, Ordering};
use std::time::Instant;

/// `s` as a terminal should show it: the characters a name may not show
/// ([`atlasmesh::geometry::hidden_char`]: escapes, carriage returns, bidirectional overrides)
/// as `�`, and every line after the first indented, so that nothing inside a message (a file
/// name holding a line break and `error: ...`) starts a line of its own.
pub fn safe(s: &str) -> String {
    let mut out = String::with_capacity(s.len());
    for c in s.trim_end_matches('\n').chars() {
        match c {
            '\n' => out.push_str("\n  "),
            c if atlasmesh::geometry::hidden_char(c) => out.push('\u{FFFD}'),
            c => out.push(c),
        }
    }
    out
}

/// The [`Progress`] of the command line.
pub struct Terminal {
    quiet: bool,
    tty: bool,
    bars: Mutex<HashMap<String, Bar>>,
    steps: Mutex<HashMap<String, (Option<ProgressBar>, Instant)>>,
}

/// A bar of counted items.
struct Bar {
    bar: ProgressBar,
    total: u64,
    done: AtomicU64,
}

impl Terminal {
    /// Progress on stderr, or none with `quiet`.
    pub fn new(quiet: bool) -> Self {
        Terminal {
            quiet,
            tty: std::io::stderr().is_terminal() && !quiet,
            bars: Mutex::default(),
            steps: Mutex::default(),
        }
    }
}

impl Progress for Terminal {
    fn step_started(&self, label: &str) {
        if self.quiet {
            return;
        }
        let bar = if self.tty {
            let b = ProgressBar::new_spinner();
            if let Ok(style) = ProgressStyle::with_template("{spinner} {msg} {elapsed}") {
                b.set_style(style);
            }
            b.set_message(label.to_string());
            b.enable_steady_tick(std::time::Duration::from_millis(120));
            Some(b)
        } else {
            eprintln!("{label} ...");
            None
        };
        if let Ok(mut s) = self.steps.lock() {
            s.insert(label.to_string(), (bar, Instant::now()));
        }
    }

    fn step_finished(&self, label: &str) {
        let Some((bar, start)) = self.steps.lock().ok().and_then(|mut s| s.remove(label)) else {
            return;
        };
        if let Some(b) = bar {
            b.finish_and_clear();
        }
        eprintln!("{label}: done in {:.1} s", start.elapsed().as_secs_f64());
    }

    fn items_started(&self, label: &str, total: usize) {
        if self.quiet {
            return;
        }
        let bar = if self.tty {
            ProgressBar::new(total as u64)
        } else {
            ProgressBar::hidden()
        };
        if let Ok(style) =
            ProgressStyle::with_template("{msg} [{bar:30}] {pos}/{len} {per_sec} eta {eta}")
        {
            bar.set_style(style.progress_chars("=> "));
        }
        bar.set_message(label.to_string());
        if let Ok(mut b) = self.bars.lock() {
            b.insert(
                label.to_string(),
                Bar {
                    bar,
                    total: total as u64,
                    done: AtomicU64::new(0),
                },
            );
        }
    }

    fn item_done(&self, label: &str, item: &str) {
        let Ok(bars) = self.bars.lock() else { return };
        let Some(b) = bars.get(label) else { return };
        let d = b.done.fetch_add(1, Ordering::Relaxed) + 1;
        if self.tty {
            b.bar.inc(1);
        } else {
            eprintln!("{label}: {d}/{} {item}", b.total);
        }
    }

    fn items_finished(&self, label: &str) {
        if let Some(b) = self.bars.lock().ok().and_then(|mut b| b.remove(label)) {
            b.bar.finish_and_clear();
        }
    }
}

impl Terminal {
    /// Whether `--quiet` was given.
    pub fn is_quiet(&self) -> bool {
        self.quiet
    }
}
