//! Progress and cancellation for long work, without tying the core to a terminal.

/// Receives progress from long-running work and may ask it to stop.
pub trait Progress: Sync {
    /// `stage` names the step (e.g. `level 2/3`), `fraction` is in [0, 1].
    fn update(&self, stage: &str, fraction: f32);

    /// Return true to ask the work to stop at the next check.
    fn cancelled(&self) -> bool {
        false
    }

    /// Something the user should know that does not stop the work (e.g. fewer seeds placed
    /// than asked). Front ends show it where they show messages. Default: ignore.
    fn warn(&self, _message: &str) {}

    /// A level of multi-resolution work finished: `level` of `levels` (from 1), its samples
    /// (`dims`, `channels` per voxel, x fastest), e.g. to show a preview. Default: ignore.
    fn level_done(&self, _level: usize, _levels: usize, _dims: [usize; 3], _channels: usize, _data: &[f32]) {}
}

/// A part of a longer job: the part's fractions land in `from..from + span` of the
/// whole's, under the whole's stage name; stopping and warnings pass through.
pub struct Part<'a> {
    /// The whole job's progress.
    pub whole: &'a dyn Progress,
    /// The stage the whole shows while the part runs.
    pub stage: String,
    /// The whole's fraction when the part starts.
    pub from: f32,
    /// The share of the whole the part is.
    pub span: f32,
}

impl Progress for Part<'_> {
    fn update(&self, _stage: &str, fraction: f32) {
        self.whole.update(&self.stage, self.from + fraction.clamp(0.0, 1.0) * self.span);
    }
    fn cancelled(&self) -> bool {
        self.whole.cancelled()
    }
    fn warn(&self, message: &str) {
        self.whole.warn(message)
    }
}

/// Progress that goes nowhere.
#[derive(Debug, Clone, Copy, Default)]
pub struct NoProgress;

impl Progress for NoProgress {
    fn update(&self, _stage: &str, _fraction: f32) {}
}
