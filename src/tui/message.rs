//! What can happen: keys turned into intents, and results coming back from workers.

use crate::volume::{Axis, Volume};
use std::sync::Arc;

/// One event for `update`.
#[derive(Debug, Clone)]
pub enum Message {
    /// Move the selection up.
    Up,
    /// Move the selection down.
    Down,
    /// Open the selected exemplar.
    Open,
    /// Back to the library (or quit from it).
    Back,
    /// Build the selected exemplar.
    Build,
    /// Build every exemplar.
    BuildAll,
    /// Toggle the help overlay.
    Help,
    /// Leave.
    Quit,
    /// Choose the axis the slice keys move.
    SelectAxis(Axis),
    /// Move the current slice by this many voxels.
    MoveSlice(i64),
    /// Cycle the channel view.
    NextChannel,
    /// A volume finished loading (or failed).
    Loaded(String, Result<Arc<Volume>, String>),
    /// A build finished: name, and the rebuilt list row or the error.
    Built(String, Result<super::model::Item, String>),
}

/// Work `update` asks the runtime to start in a worker thread.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum Effect {
    /// Load the built volume of this exemplar.
    Load(String),
    /// Build these exemplars.
    Build(Vec<String>),
}
