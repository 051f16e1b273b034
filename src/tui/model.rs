//! The terminal UI's state: plain data, changed only by `update`.

use super::message::EntryChange;
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
    /// Asked to build, waiting for the build before it to finish.
    Queued,
    /// Built; the classified type from the build record.
    Built(String),
    /// Built (the classified type), but its recipe or inputs changed since (why): the
    /// output is stale.
    Changed(String, String),
    /// The last build failed with this message; true when an earlier build is still there
    /// to open.
    Failed(String, bool),
    /// The manifest entry has a mistake (this message): `e` opens it to fix.
    Broken(String),
}

impl BuildState {
    /// Whether a build of it runs or waits to run.
    pub fn busy(&self) -> bool {
        matches!(self, BuildState::Building | BuildState::Queued)
    }
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
    /// For synthesized entries, the figures of the last build against the photos.
    pub quality: Option<crate::quality::Glance>,
    /// Whether the build before the last one is kept for comparing (accept or discard).
    pub previous: bool,
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
    /// Stamp mode, when on.
    pub stamp: Option<StampMode>,
    /// Magnification of the slices: 1, 2 or 4 (around each slice's centre).
    pub zoom: usize,
    /// The exemplar and its masks once loaded (`a` cycles through them), and which shows.
    pub layers: Vec<(String, Arc<Volume>)>,
    /// Index into `layers` of the volume on screen.
    pub layer: usize,
    /// The photos it was made from, one per slice axis (`p` loads them), or why not.
    pub photos: Option<Result<Arc<Photos>, String>>,
    /// Whether the photo of the slice axis is shown beside its slice.
    pub beside_photo: bool,
    /// Whether the volume is an earlier build kept after the latest build failed.
    pub older: bool,
}

/// The images an exemplar was made from, for the slices across x, y and z (None: no image
/// for that axis).
pub type Photos = [Option<crate::volume::Image2d>; 3];

impl ExemplarView {
    /// The view of exemplar `name` before its volume has loaded.
    pub fn new(name: &str) -> ExemplarView {
        ExemplarView {
            name: name.to_string(),
            volume: None,
            index: [0; 3],
            axis: Axis::Z,
            channel: 0,
            stamp: None,
            zoom: 1,
            layers: Vec::new(),
            layer: 0,
            photos: None,
            beside_photo: false,
            older: false,
        }
    }
}

/// A seed mesh placed over the slices, stamped with Enter.
#[derive(Debug, Clone)]
pub struct StampMode {
    /// The seed mesh.
    pub mesh: Arc<crate::mesh::Mesh>,
    /// Its file, relative to the manifest's folder (None: the built-in seed, not saveable).
    pub file: Option<String>,
    /// Where it goes next.
    pub placement: crate::stamp::Placement,
    /// Its coverage at that placement (the outline on the slices).
    pub outline: Arc<crate::mesh::Coverage>,
    /// Volumes before each stamp or scatter, newest last.
    pub undo: Vec<Arc<Volume>>,
    /// The stamps and scatters made, as manifest steps (in order).
    pub steps: Vec<StampStep>,
    /// Seed of the next scatter.
    pub next_seed: u64,
}

/// One stamp-mode action, to be saved as a manifest step.
#[derive(Debug, Clone, PartialEq)]
pub enum StampStep {
    /// One seed at a placement.
    Stamp(crate::stamp::Placement),
    /// `count` seeds scattered with `seed` at scales `scale`.
    Scatter {
        /// How many.
        count: usize,
        /// Scale range.
        scale: (f32, f32),
        /// Seed.
        seed: u64,
    },
}

/// The recipe editor of one exemplar: the manifest text being edited, with undo and redo.
#[derive(Debug, Clone, Default)]
pub struct Editor {
    /// Exemplar name.
    pub name: String,
    /// The manifest text as edited (None while it loads).
    pub text: Option<String>,
    /// The text as last read or saved.
    pub saved: String,
    /// Selected field row.
    pub selected: usize,
    /// The value being typed, when editing.
    pub input: Option<tui_input::Input>,
    /// Why the last edit was refused.
    pub error: Option<String>,
    /// Earlier texts, newest last.
    pub undo: Vec<String>,
    /// Undone texts, newest last.
    pub redo: Vec<String>,
    /// The field picker, when open: the row chosen among the fields the entry can add.
    pub picker: Option<usize>,
    /// The low-resolution preview of the current text.
    pub preview: Option<Arc<Volume>>,
    /// Counts edits, so a late preview of an older text is dropped.
    pub generation: u64,
    /// A preview is being made.
    pub previewing: bool,
    /// Why the newest preview failed (the panel then shows the last good one, marked stale).
    pub preview_error: Option<String>,
    /// The manifest as it reads now, when it and this entry changed on disk since the
    /// editor read it: the designer keeps theirs or mine (see [`Conflict`]).
    pub conflict: Option<Box<Conflict>>,
}

/// The entry being edited changed both here and on disk.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Conflict {
    /// The manifest as it reads now.
    pub theirs: String,
    /// Whether it was found by a save (keeping mine then saves).
    pub saving: bool,
    /// Whether both versions of the entry are shown side by side.
    pub both: bool,
}

pub use crate::fill::FillPreview;

/// The fill preview: a drawn shape filled with the exemplar, and a cut plane.
#[derive(Debug, Clone)]
pub struct FillView {
    /// Exemplar name.
    pub name: String,
    /// The filled model (None while filling).
    pub filled: Option<Arc<FillPreview>>,
    /// The axis the cut plane is across.
    pub axis: Axis,
    /// Where the plane sits between the model's bounds, -1 to 1.
    pub offset: f32,
    /// The exemplar view the preview was opened from, where Esc goes back to.
    pub from: Option<Box<ExemplarView>>,
    /// The constraints being placed on the cut (the fill spec), once the first fill arrives.
    pub edit: Option<FillEdit>,
}

/// Constraints placed on the fill preview's cut (thesis ch. 5): direction strokes, depth
/// points, face groups and manual pastes, kept as the fill spec they make.
#[derive(Debug, Clone)]
pub struct FillEdit {
    /// The spec with every constraint placed so far.
    pub spec: crate::fill::spec::FillSpec,
    /// The drawn shape filled (`fruit`, `block`).
    pub shape: String,
    /// Where the cursor is on the cut: 0 to 1 across and down.
    pub cursor: [f32; 2],
    /// The points of the stroke being drawn.
    pub stroke: Vec<glam::Vec3>,
    /// The depth new points and face groups get, 0 (surface) to 1 (innermost).
    pub depth: f32,
    /// Whether the cut shows the depth field as a colour map instead of the texture.
    pub show_depth: bool,
    /// Earlier specs, newest last (`u`).
    pub undo: Vec<crate::fill::spec::FillSpec>,
    /// The spec as the preview opened, or as last written (`w`) or loaded (`o`): leaving
    /// with another asks first.
    pub saved: Box<crate::fill::spec::FillSpec>,
    /// Whether a stroke is being dragged with the mouse.
    pub dragging: bool,
    /// Whether a refill with the spec runs (the fill shown stays until it ends).
    pub refilling: bool,
    /// What the cut shows over the texture (`v`): the frame field of the spec as it is, or
    /// a cut synthesized along it; `None`: the texture.
    pub overlay: Option<crate::library::guided::Overlay>,
    /// The last overlay picture made, and what it shows.
    pub picture: Option<(Box<OverlayKey>, std::sync::Arc<crate::library::guided::Picture>)>,
    /// Whether an overlay picture is being made.
    pub pending: bool,
}

/// What an overlay picture shows: which overlay, on which cut, of which spec.
#[derive(Debug, Clone, PartialEq)]
pub struct OverlayKey {
    /// Field or guided cut.
    pub overlay: crate::library::guided::Overlay,
    /// The cut's axis.
    pub axis: crate::volume::Axis,
    /// The cut's offset, -1 to 1.
    pub offset: f32,
    /// The spec whose strokes and depth give the field.
    pub spec: crate::fill::spec::FillSpec,
}

/// An action that loses unsaved work, asked for once and done on the second press.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Confirm {
    /// Quit the program.
    Quit,
    /// Go back to the library.
    Leave,
    /// Leave stamp mode.
    StampOff,
    /// Delete the selected entry.
    Delete,
}

/// The screen on top.
#[derive(Debug, Clone)]
pub enum Screen {
    /// The library list.
    Library,
    /// One exemplar's slices.
    Exemplar(ExemplarView),
    /// The recipe editor.
    Editor(Editor),
    /// The fill preview.
    Fill(FillView),
    /// A new entry: its kind, then its file.
    New(super::new_entry::NewEntry),
    /// Two volumes side by side.
    Compare(CompareView),
}

/// One side of a comparison.
#[derive(Debug, Clone)]
pub struct Side {
    /// What it is: an exemplar's name, `NAME before` or `NAME after`.
    pub label: String,
    /// The volume (None while loading), or why it cannot be read.
    pub volume: Option<Result<Arc<Volume>, String>>,
    /// Its quality figures, when it is synthesized.
    pub quality: Option<crate::quality::Glance>,
}

/// Two exemplars side by side, or an entry's previous build beside its new one.
#[derive(Debug, Clone)]
pub struct CompareView {
    /// Left and right.
    pub sides: [Side; 2],
    /// The axis both slices are across.
    pub axis: Axis,
    /// Where both slices sit along the axis, 0 to 1 (each volume's own voxels).
    pub position: f32,
    /// The entry whose previous (left) and new (right) builds are compared, which `a`
    /// accepts and `d` discards.
    pub before_after: Option<String>,
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
    /// Manifest errors, listed under the exemplars that are valid.
    pub errors: Vec<String>,
    /// First line of the error list shown (page up/down scroll it).
    pub error_scroll: usize,
    /// Selected row of the library list.
    pub selected: usize,
    /// The screen on top.
    pub screen: Screen,
    /// The help overlay, when shown.
    pub help: Option<Help>,
    /// A line being typed: a library entry's new name, or the file to save the manifest as.
    pub prompt: Option<Prompt>,
    /// The entry `v` marked to compare with the next one `v` is pressed on.
    pub mark: Option<String>,
    /// One line of status at the bottom (cut to the screen's width; whole in the log).
    pub status: String,
    /// Seconds the status has been shown; it clears after [`STATUS_SECONDS`].
    pub status_age: u32,
    /// Every status shown, oldest first (at most [`LOG_LINES`]).
    pub log: Vec<String>,
    /// The message log overlay, when shown: the first line on screen.
    pub log_view: Option<usize>,
    /// The library list shows only entries whose name holds this (any case).
    pub filter: String,
    /// Time since the UI started, as the last tick said.
    pub now: std::time::Duration,
    /// The builds asked for since the queue was last empty, for `done/total`, elapsed time and
    /// an estimate.
    pub batch: Option<Batch>,
    /// No manifest at [`Model::manifest`] yet: the library screen offers to start one.
    pub first_run: bool,
    /// The terminal's columns and rows.
    pub size: (u16, u16),
    /// A rename sent to the manifest: its prompt comes back, as typed, if it is refused.
    pub renaming: Option<Prompt>,
    /// Leave the program.
    pub quit: bool,
    /// The manifest changed on disk since this UI last read or wrote it (Ctrl-R reloads).
    pub outside: bool,
    /// Library operations done here, newest last, each as the change that undoes it
    /// (applied to the manifest as it reads then) and what it undoes.
    pub undo: Vec<(EntryChange, String)>,
    /// Why files cannot be written (a read-only manifest or output folder), said at start.
    pub read_only: Vec<String>,
    /// The action a second press of the same key confirms (unsaved work would be lost).
    pub confirm: Option<Confirm>,
    /// Progress of running builds: exemplar -> (stage, fraction).
    pub progress: std::collections::BTreeMap<String, (String, f32)>,
    /// The latest pyramid level a synthesis build finished: exemplar -> (`2/3`, volume).
    pub previews: std::collections::BTreeMap<String, (String, Arc<Volume>)>,
}

/// How long a status stays in the status row.
pub const STATUS_SECONDS: u32 = 12;

/// The most lines the message log keeps.
pub const LOG_LINES: usize = 500;

/// Builds asked for together (one `b`, `B` or `R`, and those queued while they run).
#[derive(Debug, Clone, PartialEq)]
pub struct Batch {
    /// The entries asked for.
    pub total: usize,
    /// Those finished (built, failed or cancelled).
    pub done: usize,
    /// When the first was asked for ([`Model::now`]).
    pub started: std::time::Duration,
}

/// A line typed at the bottom of the screen.
#[derive(Debug, Clone)]
pub struct Prompt {
    /// What it is for.
    pub purpose: Purpose,
    /// What is typed.
    pub input: tui_input::Input,
    /// Why the last value typed was refused (shown before the prompt).
    pub note: String,
}

/// What a prompt is for.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Purpose {
    /// The selected library entry's new name.
    Rename,
    /// The file the editor saves the manifest as (when the manifest cannot be written).
    SaveAs,
    /// The library list's filter (the list narrows as it is typed).
    Filter,
}

/// The help overlay: the keys of every screen, the one on top first, filtered by a query.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Help {
    /// Only keys whose text holds this (any case) are shown.
    pub query: String,
    /// Whether keys type into the query (after `/`).
    pub typing: bool,
    /// The first line on screen.
    pub scroll: usize,
}

impl Model {
    /// A model over `items`.
    pub fn new(manifest: PathBuf, output: PathBuf, items: Vec<Item>, errors: Vec<String>) -> Model {
        // what needs doing first: the status row cuts a long line at its end
        let mut status = format!("{} exemplar(s) in {}", items.len(), manifest.display());
        let changed = items.iter().filter(|i| matches!(i.state, BuildState::Changed(..))).count();
        if changed > 0 {
            status = format!("{changed} changed since their last build (select one to see why); {status}");
        }
        Model {
            manifest,
            output,
            items,
            errors,
            error_scroll: 0,
            selected: 0,
            mark: None,
            screen: Screen::Library,
            help: None,
            prompt: None,
            log: vec![status.clone()],
            status,
            status_age: 0,
            log_view: None,
            filter: String::new(),
            now: Default::default(),
            batch: None,
            first_run: false,
            size: (80, 24),
            renaming: None,
            quit: false,
            outside: false,
            undo: Vec::new(),
            read_only: Vec::new(),
            confirm: None,
            progress: Default::default(),
            previews: Default::default(),
        }
    }

    /// The rows of the library list: indices into `items` of the entries the filter keeps.
    pub fn visible(&self) -> Vec<usize> {
        let filter = self.filter.to_lowercase();
        (0..self.items.len()).filter(|&i| self.items[i].name.to_lowercase().contains(&filter)).collect()
    }
}
