//! Progress bars with ETA per bake phase (indicatif), drawn on stderr only when it is a
//! terminal and progress is wanted.

use std::io::IsTerminal;
use std::time::Duration;

use indicatif::{ProgressBar, ProgressDrawTarget, ProgressStyle};

/// Makes one progress bar per phase.
#[derive(Debug, Clone, Copy)]
pub struct Progress {
    enabled: bool,
}

impl Progress {
    /// Bars drawn when `wanted` and stderr is a terminal.
    pub fn new(wanted: bool) -> Self {
        Self {
            enabled: wanted && std::io::stderr().is_terminal(),
        }
    }

    /// No bars at all.
    pub fn hidden() -> Self {
        Self { enabled: false }
    }

    /// Whether bars are drawn.
    pub fn enabled(&self) -> bool {
        self.enabled
    }

    /// A bar for phase `name` with `len` steps (0: a spinner).
    pub fn phase(&self, name: &str, len: u64) -> ProgressBar {
        if !self.enabled {
            return ProgressBar::hidden();
        }
        let bar = if len == 0 {
            let b = ProgressBar::new_spinner();
            b.enable_steady_tick(Duration::from_millis(120));
            b
        } else {
            ProgressBar::new(len)
        };
        bar.set_draw_target(ProgressDrawTarget::stderr());
        let template = if len == 0 {
            "{prefix:>14} {spinner} {elapsed_precise} {msg}"
        } else {
            "{prefix:>14} [{bar:32}] {pos}/{len} {elapsed_precise} ETA {eta_precise} {msg}"
        };
        if let Ok(style) = ProgressStyle::with_template(template) {
            bar.set_style(style.progress_chars("=> "));
        }
        bar.set_prefix(name.to_owned());
        bar
    }
}
