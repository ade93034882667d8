//! How far a render has got: the library reports units (tiles, rows) done,
//! and whoever called it decides what to show. The `lambert` binary draws
//! a progress bar and prints jobs' lines; library callers, tests and
//! Python pass none.

/// One render pass's report, told of each unit as it is done (from any of
/// the render's threads).
pub trait ProgressBar: Send + Sync {
    fn inc(&self, units: u64);
    /// The pass is over (also when it failed).
    fn finish(&self);
}

/// Where a caller wants progress shown: it makes the bar of each pass, and
/// hears a render job's news as it happens (the device chosen, a frame
/// written), ahead of the job's report.
pub trait ProgressSink: Sync {
    /// A pass over `total` units named `unit` ("tiles", "rows") begins.
    fn start(&self, total: u64, unit: &str) -> Box<dyn ProgressBar>;

    /// A line for the user from a job under way; dropped unless shown.
    fn line(&self, _text: &str) {}
}

/// The report a render pass is given: a caller's bar, or nothing.
pub struct Progress {
    bar: Option<Box<dyn ProgressBar>>,
}

impl Progress {
    /// A pass over `total` units, shown by `sink` if there is one.
    pub fn start(sink: Option<&dyn ProgressSink>, total: u64, unit: &str) -> Progress {
        Progress {
            bar: sink.map(|sink| sink.start(total, unit)),
        }
    }

    /// No output at all: for library callers and tests.
    pub fn hidden() -> Progress {
        Progress { bar: None }
    }

    pub fn inc(&self, units: u64) {
        if let Some(bar) = &self.bar {
            bar.inc(units);
        }
    }

    pub fn finish(&self) {
        if let Some(bar) = &self.bar {
            bar.finish();
        }
    }
}
