//! The command line's progress bar: one that appears only once work has
//! run for over a second.

use std::sync::atomic::{AtomicBool, Ordering};
use std::time::{Duration, Instant};

use indicatif::{ProgressDrawTarget, ProgressStyle};
use lambert::progress::{ProgressBar, ProgressSink};

/// Draws each render pass's bar, and jobs' lines, on stderr.
pub struct StderrBar;

impl ProgressSink for StderrBar {
    /// A bar over `total` units (tiles, rows), drawn on stderr after 1 s.
    fn start(&self, total: u64, unit: &str) -> Box<dyn ProgressBar> {
        let bar =
            indicatif::ProgressBar::with_draw_target(Some(total), ProgressDrawTarget::hidden());
        bar.set_style(
            ProgressStyle::with_template(&format!(
                "{{spinner}} [{{elapsed_precise}}] {{bar:40}} {{pos}}/{{len}} {unit} (eta {{eta}})"
            ))
            .expect("static template"),
        );
        Box::new(DelayedBar {
            bar,
            start: Instant::now(),
            shown: AtomicBool::new(false),
        })
    }

    fn line(&self, text: &str) {
        eprintln!("{text}");
    }
}

struct DelayedBar {
    bar: indicatif::ProgressBar,
    start: Instant,
    shown: AtomicBool,
}

impl ProgressBar for DelayedBar {
    fn inc(&self, units: u64) {
        self.bar.inc(units);
        if !self.shown.load(Ordering::Relaxed) && self.start.elapsed() > Duration::from_secs(1) {
            self.shown.store(true, Ordering::Relaxed);
            self.bar.set_draw_target(ProgressDrawTarget::stderr());
        }
    }

    fn finish(&self) {
        self.bar.finish_and_clear();
    }
}

/// The bar, unless the user asked for quiet.
pub fn unless_quiet(quiet: bool) -> Option<&'static dyn ProgressSink> {
    (!quiet).then_some(&StderrBar as &dyn ProgressSink)
}
