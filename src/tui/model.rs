//! The terminal UI's state: plain data, changed only by `update`.

use crate::volume::{Axis, Volume};
use std::path::PathBuf;
use std::sync::Arc;

/// Whether an exemplar's outputs exist and are up to date.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum BuildState {
    /// No build output found.
    NotBuilt,
    /// A build is running.
    Building,
    /// Built; the classified type from the build record.
    Built(String),
    /// The last build failed with this message.
    Failed(String),
}

/// One exemplar of the library list.
#[derive(Debug, Clone, PartialEq)]
pub struct Item {
    /// Exemplar name.
    pub name: String,
    /// Declared type, if any.
    pub declared: Option<String>,
    /// Size, when known from the manifest or the build record.
    pub size: Option<[usize; 3]>,
    /// Build state.
    pub state: BuildState,
}

/// What the exemplar view shows.
#[derive(Debug, Clone)]
pub struct ExemplarView {
    /// Exemplar name.
    pub name: String,
    /// The loaded volume (None while loading).
    pub volume: Option<Arc<Volume>>,
    /// Slice index along x, y and z.
    pub index: [usize; 3],
    /// The axis the arrow keys move.
    pub axis: Axis,
    /// Which channel view: 0 = colour, then each channel alone.
    pub channel: usize,
}

/// The screen on top.
#[derive(Debug, Clone)]
pub enum Screen {
    /// The library list.
    Library,
    /// One exemplar's slices.
    Exemplar(ExemplarView),
}

/// The whole UI state.
#[derive(Debug, Clone)]
pub struct Model {
    /// The manifest being shown.
    pub manifest: PathBuf,
    /// Where builds go.
    pub output: PathBuf,
    /// The exemplars.
    pub items: Vec<Item>,
    /// Manifest errors, shown instead of the list when it cannot be read.
    pub errors: Vec<String>,
    /// Selected row of the library list.
    pub selected: usize,
    /// The screen on top.
    pub screen: Screen,
    /// Show the help overlay.
    pub help: bool,
    /// One line of status at the bottom.
    pub status: String,
    /// Leave the program.
    pub quit: bool,
}

impl Model {
    /// A model over `items`.
    pub fn new(manifest: PathBuf, output: PathBuf, items: Vec<Item>, errors: Vec<String>) -> Model {
        let status = format!("{} exemplar(s) in {}", items.len(), manifest.display());
        Model {
            manifest,
            output,
            items,
            errors,
            selected: 0,
            screen: Screen::Library,
            help: false,
            status,
            quit: false,
        }
    }
}
