//! What can happen: keys turned into intents, and results coming back from workers.

use crate::volume::{Axis, Volume};
use std::path::PathBuf;
use std::sync::Arc;

/// The manifest's entries after a change, or why nothing changed.
pub type Changed = Result<Change, String>;

/// The manifest's entries after a change.
#[derive(Debug, Clone)]
pub struct Change {
    /// The reloaded list.
    pub items: Vec<super::model::Item>,
    /// Its errors.
    pub errors: Vec<String>,
    /// The entry to select.
    pub select: String,
    /// What happened.
    pub status: String,
    /// The change that undoes it and what it undoes (library operations).
    pub inverse: Option<(EntryChange, String)>,
}

/// A volume to compare and its quality figures, or why it cannot be read.
pub type SideResult = Result<(Arc<Volume>, Option<crate::quality::Glance>), String>;

/// One event for `update`.
#[derive(Debug, Clone)]
pub enum Message {
    /// Move the selection up.
    Up,
    /// Move the selection down.
    Down,
    /// Open the selected exemplar.
    Open,
    /// A click on row `.0` of the list on screen (a second click on the selected row opens it).
    Select(usize),
    /// A click or drag on the slice across `.0`: the other slices go through the voxel at
    /// these coordinates along its two axes.
    PointAt(Axis, usize, usize),
    /// The wheel over the slice across `.0`: move it by this many voxels.
    MoveSliceOf(Axis, i64),
    /// Back to the library (or quit from it).
    Back,
    /// Build the selected exemplar.
    Build,
    /// Build every exemplar.
    BuildAll,
    /// Build the exemplars changed since their last build.
    BuildChanged,
    /// A build took its turn: these exemplars build now (the others asked wait).
    BuildStarted(Vec<String>),
    /// Scroll the manifest's error list by this many lines.
    ScrollErrors(i32),
    /// Toggle the help overlay.
    Help,
    /// Toggle the message log.
    ShowLog,
    /// In the editor: open the picker of fields the entry can add.
    PickField,
    /// In the editor: remove the selected field.
    RemoveField,
    /// In the editor: open the manifest at the entry in `$VISUAL` / `$EDITOR`.
    OutsideEditor,
    /// The outside editor closed: its exit, or why it could not run.
    OutsideEdited(Result<(), String>),
    /// Scroll the help or the message log by this many lines (a large number: to an end).
    Scroll(i64),
    /// Move the library selection by this many rows (a large number: to an end).
    Jump(i64),
    /// Start typing the library list's filter.
    Filter,
    /// Show this in the status row (why a dimmed key does nothing now).
    Say(String),
    /// A second passed: the time since the UI started.
    Tick(std::time::Duration),
    /// The terminal has these many columns and rows.
    Resized(u16, u16),
    /// In the help: start typing a search (`/`), or stop typing and keep it (enter).
    HelpSearch,
    /// In the help: add a character to the search, or remove the last one (`None`).
    HelpType(Option<char>),
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
    /// A build was cancelled before this exemplar finished: the row as its previous output
    /// (kept) leaves it.
    BuildCancelled(String, super::model::Item),
    /// Open the recipe editor of the selected exemplar.
    Edit,
    /// Copy the selected entry in the manifest (right after it, named `NAME-2`).
    Duplicate,
    /// Delete the selected entry from the manifest (asks first).
    Delete,
    /// Start renaming the selected entry (a prompt with its name).
    Rename,
    /// Open the new-entry screen.
    New,
    /// On the library: mark the selected entry, or compare it with the marked one.
    Compare,
    /// On the library: the selected entry's previous build beside its new one.
    BeforeAfter,
    /// A side of the comparison arrived: side, its label, the volume and its figures.
    SideLoaded(usize, String, SideResult),
    /// Keep the new build being compared with the previous one.
    Accept,
    /// Discard the new build being compared: the previous one comes back.
    Discard,
    /// Show the photo the exemplar was made from beside its slice (or go back to three slices).
    Photo,
    /// The photos of exemplar `.0` arrived (or why there are none).
    PhotosLoaded(String, Result<Arc<super::model::Photos>, String>),
    /// In the file picker: the folder above.
    Parent,
    /// A folder listing for the picker arrived: the folder asked for, then (that folder as
    /// a canonical path, its rows) or why it cannot be listed.
    Listed(PathBuf, Result<(PathBuf, Vec<super::new_entry::FileRow>), String>),
    /// A photo for the picker's preview arrived (or why it cannot be read).
    Peeked(PathBuf, Result<Arc<crate::volume::Image2d>, String>),
    /// Export the exemplar on screen.
    Export,
    /// Write the 3D view (a `solidtex web` page) of the exemplar or fill on screen and open it.
    WebView,
    /// A 3D view was written: what to tell (its path, and whether a browser took it); or
    /// why it was not.
    WebWritten(Result<String, String>),
    /// An export finished: the folder, the files written and the formats that cannot hold
    /// the volume (with the reason); or why it failed.
    Exported(Result<(String, Vec<String>, Vec<String>), String>),
    /// The manifest's entries changed: the reloaded list, its errors, the entry to select
    /// and what happened; or why nothing changed.
    EntriesChanged(Changed),
    /// The manifest text for the editor arrived.
    EditorReady(Result<String, String>),
    /// Start editing the selected field, or commit the value being typed.
    Commit,
    /// Edit the value being typed: a character, a cursor move, a deletion (tui-input's
    /// requests: Left, Right, Home, End, Backspace, Delete, Ctrl-U, Ctrl-W, ...).
    Input(tui_input::InputRequest),
    /// Stop editing the value without changing it.
    Cancel,
    /// Undo the last edit.
    Undo,
    /// Redo the last undone edit.
    Redo,
    /// Save the manifest.
    Save,
    /// Append a blur step to the entry being edited.
    AddBlur,
    /// Append a stamp (true) or scatter step to the entry being edited: pick its mesh.
    AddMeshStep(bool),
    /// The mesh of a new stamp (true) or scatter step, as the manifest names it (or why not).
    StepMeshChosen(Result<String, String>, bool),
    /// Remove the step of the selected field (editor).
    RemoveStep,
    /// Move the step of the selected field before the previous one (true) or after the next.
    MoveStep(bool),
    /// The manifest was saved (or not): the text written.
    Saved(Result<String, String>),
    /// A save found the entry changed on disk too: the manifest as it reads now.
    SaveConflict(String),
    /// The manifest changed on disk, not by this UI.
    ChangedOnDisk,
    /// `S` in the editor: a prompt for another file to save the manifest as.
    SaveAs,
    /// The manifest was saved as another file (its path and text), or why not.
    SavedAs(Result<(PathBuf, String), String>),
    /// Ctrl-R: read the manifest again (the editor keeps its edits of the entry).
    Reload,
    /// While the entry being edited conflicts: keep mine (`m`), take theirs (`t`), or show
    /// both (`b`).
    Resolve(char),
    /// A preview finished: the edit generation it belongs to, the volume, and the
    /// warnings its build gave.
    Previewed(u64, Result<Arc<Volume>, String>, Vec<String>),
    /// Open the fill preview of the exemplar on screen.
    FillPreview,
    /// A fill preview finished.
    Filled(String, Result<Arc<super::model::FillPreview>, String>),
    /// `v`: the fill preview's cut shows the texture, the frame field, or a guided cut.
    NextOverlay,
    /// An overlay picture of fill `name` was made (or failed).
    OverlayMade(String, Box<super::model::OverlayKey>, Result<Arc<crate::library::guided::Picture>, String>),
    /// Move the cut plane by this share of the model.
    MovePlane(f32),
    /// Fill preview: move the cursor on the cut by (right, down) steps.
    MoveCursor(f32, f32),
    /// Fill preview: put the cursor at (across, down) of the cut, 0 to 1 (a click).
    CursorAt(f32, f32),
    /// Fill preview: add the cursor's point to the stroke being drawn.
    StrokePoint,
    /// Fill preview: a drag on the cut draws a stroke through (across, down), 0 to 1.
    DragStroke(f32, f32),
    /// Fill preview: the mouse button went up: a stroke dragged ends.
    EndDrag,
    /// Fill preview: the stroke drawn becomes a direction stroke.
    FinishStroke,
    /// Fill preview: a depth point at the cursor.
    DepthPoint,
    /// Fill preview: change the depth new points get by this much.
    DepthValue(f32),
    /// Fill preview: the faces nearest the cursor get the current depth.
    FaceGroup,
    /// Fill preview: a manual paste at the cursor.
    Paste,
    /// Fill preview: turn the last paste by degrees and scale it by a factor.
    WarpPaste(f32, f32),
    /// Fill preview: show the depth field, or the texture again.
    ShowDepth,
    /// Fill preview: fill again with the constraints placed.
    Refill,
    /// Fill preview: write the fill spec and the shape.
    WriteSpec,
    /// Fill preview: the spec written (the preview's constraints then count as saved), and
    /// what was written or why not.
    SpecWritten(Box<crate::fill::spec::FillSpec>, Result<(String, Vec<String>, Vec<String>), String>),
    /// Fill preview: choose a written fill spec to load its constraints.
    OpenSpec,
    /// A fill spec chosen with `o` was read (or why not).
    SpecLoaded(PathBuf, Result<Box<crate::fill::spec::FillSpec>, String>),
    /// Zoom the slices in (true) or out.
    Zoom(bool),
    /// Show the next of the exemplar and its masks.
    NextLayer,
    /// The masks of the exemplar on screen arrived: (label, volume) each.
    MasksLoaded(String, Result<Vec<(String, Arc<Volume>)>, String>),
    /// Enter or leave stamp mode.
    StampMode,
    /// The seed mesh for stamp mode arrived: mesh and its file.
    SeedLoaded(Result<(Arc<crate::mesh::Mesh>, Option<String>), String>),
    /// Move the seed by voxels along (the slice's right, up, the slice axis).
    MoveSeed([i32; 3]),
    /// Turn the seed by degrees about the slice axis.
    TurnSeed(f32),
    /// Scale the seed by a factor.
    ScaleSeed(f32),
    /// Stamp the seed.
    Stamp,
    /// Scatter ten seeds.
    Scatter,
    /// Save the stamps as manifest steps.
    SaveSteps,
    /// In stamp mode: choose another seed mesh in a file picker.
    PickSeed,
    /// A running synthesis finished a pyramid level: exemplar, `level/levels`, the level.
    BuildPreview(String, String, Arc<Volume>),
    /// A running build reported progress: exemplar, stage, fraction.
    BuildProgress(String, String, f32),
    /// A running build warned about exemplar `.0`: the message.
    BuildWarning(String, String),
    /// A worker stopped on an internal error (a panic): what it said.
    WorkerFailed(String),
}

/// Work `update` asks the runtime to start in a worker thread.
#[derive(Debug, Clone, PartialEq)]
pub enum Effect {
    /// Load the built volume of this exemplar.
    Load(String),
    /// Build these exemplars.
    Build(Vec<String>),
    /// Read the manifest text for the editor.
    ReadManifest,
    /// Start a library: write an empty manifest where none is.
    StartLibrary,
    /// Suspend the UI and edit the manifest in `$VISUAL` / `$EDITOR` at this line (run
    /// by the UI's own thread, which owns the terminal).
    EditOutside(usize),
    /// Build a low-resolution preview of exemplar `name` from manifest `text`.
    Preview {
        /// The exemplar.
        name: String,
        /// The manifest text.
        text: String,
        /// The edit generation.
        generation: u64,
    },
    /// Save the editor's text of entry `name`, edited from `base` (the manifest as read):
    /// applied to the manifest as it reads then (see [`super::edit::rebase`]).
    Save {
        /// The entry edited.
        name: String,
        /// The manifest as the editor read it.
        base: String,
        /// The editor's text.
        text: String,
    },
    /// Fill a drawn shape with this exemplar.
    Fill(String),
    /// Stop every running build.
    CancelBuilds,
    /// Load the built masks of exemplar `name`.
    LoadMasks(String),
    /// Find the seed mesh for stamping exemplar `name`.
    LoadSeed(String),
    /// Append stamp steps to exemplar `name` in the manifest and save it.
    SaveSteps(String, Vec<super::model::StampStep>, String),
    /// Copy or delete an entry of the manifest and save it.
    ChangeEntry(EntryChange),
    /// Undo a library operation by this change (and say what it undoes).
    UndoEntry(EntryChange, String),
    /// Write the editor's text as a new manifest file beside the manifest.
    SaveAs(PathBuf, String),
    /// Read the manifest's list again, selecting this entry.
    Reload(String),
    /// Write exemplar `name`'s volume in every interchange format, its contact sheet and
    /// the slice on screen (axis, index) into `OUTPUT/exports/NAME/`.
    Export(String, Arc<Volume>, Axis, usize),
    /// Write the fill preview's cut of exemplar `name` (across the axis, at the offset) as a
    /// 512² PNG into `OUTPUT/exports/`.
    ExportCut(String, SharedFill, Axis, f32),
    /// Write the 3D view of exemplar `name` (its volume or its fill preview) into
    /// `OUTPUT/exports/` and open it in a browser.
    WebView(String, WebSubject),
    /// List a folder's folders and the files of this kind, for the picker.
    List(PathBuf, super::new_entry::FileKind),
    /// Read a photo (shrunk) for the picker's preview.
    Peek(PathBuf),
    /// Read the photos exemplar `name` was made from.
    LoadPhotos(String),
    /// Read this mesh as the seed of stamp mode.
    LoadSeedFile(PathBuf),
    /// Find how the manifest names this mesh, for a new stamp (true) or scatter step.
    StepMesh(PathBuf, bool),
    /// Fill the drawn shape (third) with exemplar `name`'s spec (second).
    Refill(String, Box<crate::fill::spec::FillSpec>, String),
    /// Make the overlay picture `key` asks for over fill `name`'s preview.
    Overlay(String, SharedFill, Box<super::model::OverlayKey>),
    /// Write exemplar `name`'s fill spec and the drawn shape into `OUTPUT/exports/`.
    WriteSpec(String, Box<crate::fill::spec::FillSpec>, String),
    /// Read a fill spec for the fill preview.
    LoadSpec(PathBuf),
    /// Read a volume to compare: side, its label, the exemplar, and whether it is the
    /// previous build kept beside it.
    LoadSide(usize, String, String, bool),
    /// Accept (true) or discard exemplar `name`'s new build.
    Settle(String, bool),
}

/// A fill preview handed to a worker; two are equal when they are the same one.
#[derive(Debug, Clone)]
pub struct SharedFill(pub Arc<super::model::FillPreview>);

/// What a 3D view shows.
#[derive(Debug, Clone, PartialEq)]
pub enum WebSubject {
    /// An exemplar's volume.
    Volume(Arc<Volume>),
    /// A fill preview.
    Fill(SharedFill),
}

impl PartialEq for SharedFill {
    fn eq(&self, other: &SharedFill) -> bool {
        Arc::ptr_eq(&self.0, &other.0)
    }
}

/// A change to the manifest's list of entries.
#[derive(Debug, Clone, PartialEq)]
pub enum EntryChange {
    /// Copy exemplar `name`.
    Duplicate(String),
    /// Delete exemplar `name`.
    Delete(String),
    /// Rename exemplar `name` (first) to the second name.
    Rename(String, String),
    /// Add an entry of this recipe, reading this file (an image or a volume) if any.
    New(String, Option<PathBuf>),
    /// Put a deleted entry back where it was.
    Restore(Box<super::edit::Removed>),
}
