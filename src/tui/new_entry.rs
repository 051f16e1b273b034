//! The new-entry screen: choose what makes the volume (a recipe kind), then, for kinds that
//! read a file, the file, in a picker that browses folders and previews photos. Pure: the
//! folder listing and the photo arrive as messages from workers.

use super::message::{Effect, EntryChange};
use super::model::{Editor, ExemplarView, FillView, Model, Screen};
use crate::volume::Image2d;
use std::path::{Path, PathBuf};
use std::sync::Arc;

/// What a recipe kind reads.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum FileKind {
    /// A 2D image (PNG, JPEG, EXR, TIFF, HDR).
    Image,
    /// A volume file.
    Volume,
    /// A mesh (a seed for stamp mode).
    Mesh,
    /// A fill spec (`solidtex fill --spec`).
    FillSpec,
}

impl FileKind {
    /// The file extensions (lower case) the picker lists.
    pub fn extensions(self) -> &'static [&'static str] {
        match self {
            FileKind::Image => &["png", "jpg", "jpeg", "exr", "tif", "tiff", "hdr"],
            FileKind::Volume => &["exr", "nrrd", "vol", "png", "vdb", "dds"],
            FileKind::Mesh => &["obj", "stl", "ply"],
            FileKind::FillSpec => &["toml"],
        }
    }
}

/// One kind of entry the screen makes.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Kind {
    /// The manifest's `recipe` value.
    pub recipe: &'static str,
    /// What it makes.
    pub what: &'static str,
    /// The file it reads, if any.
    pub file: Option<FileKind>,
}

const fn kind(recipe: &'static str, what: &'static str, file: Option<FileKind>) -> Kind {
    Kind { recipe, what, file }
}

/// The kinds offered, in order.
pub const KINDS: [Kind; 10] = [
    kind("synth", "a solid synthesized from a photo (Kopf 2007)", Some(FileKind::Image)),
    kind("synth-layered", "layers along z synthesized from a photo (type 1-b)", Some(FileKind::Image)),
    kind("sweep", "a cross-section image swept along x", Some(FileKind::Image)),
    kind("load", "a volume file (exr, nrrd, vol, vdb, dds, png atlas)", Some(FileKind::Volume)),
    kind("procedural:marble", "veined marble from noise (type 0)", None),
    kind("procedural:strata", "rock strata (type 1-b)", None),
    kind("procedural:wood", "wood rings (type 2-a)", None),
    kind("procedural:sponge", "sponge cake crumb (type 0)", None),
    kind("procedural:cream", "whipped cream (type 0)", None),
    kind("procedural:chocolate", "chocolate glaze (type 0)", None),
];

/// One row of the file picker.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct FileRow {
    /// File or folder name (`..` for the folder above).
    pub name: String,
    /// Whether it is a folder.
    pub folder: bool,
}

/// The file picker of a kind that reads a file.
#[derive(Debug, Clone)]
pub struct Picker {
    /// What it lists.
    pub file: FileKind,
    /// The folder shown.
    pub folder: PathBuf,
    /// Its folders and the files the kind reads (None while listing), or why not.
    pub rows: Option<Result<Vec<FileRow>, String>>,
    /// Selected row.
    pub selected: usize,
    /// The selected photo, once read (or why it cannot be).
    pub peek: Option<(PathBuf, Result<Arc<Image2d>, String>)>,
    /// The folder just left by going up, selected once the listing arrives.
    pub came_from: Option<String>,
}

impl Picker {
    /// A picker of `file`s in `folder`, nothing listed yet.
    pub fn new(file: FileKind, folder: PathBuf) -> Picker {
        Picker { file, folder, rows: None, selected: 0, peek: None, came_from: None }
    }
}

/// The new-entry screen.
#[derive(Debug, Clone)]
pub struct NewEntry {
    /// Index into [`KINDS`].
    pub kind: usize,
    /// The file picker, once the kind is chosen (kinds that read a file).
    pub picker: Option<Picker>,
    /// When it picks a file for another screen instead of making an entry: for what, and
    /// the screen to go back to.
    pub pick_for: Option<PickFor>,
}

/// What a file is picked for.
#[derive(Debug, Clone)]
pub enum PickFor {
    /// The seed mesh of stamp mode in this exemplar view.
    Seed(Box<ExemplarView>),
    /// The mesh of a stamp (true) or scatter step appended in this recipe editor.
    Step(Box<Editor>, bool),
    /// A written fill spec whose constraints this fill preview loads.
    Spec(Box<FillView>),
}

/// `n` on the library: the list of kinds.
pub fn start(model: &mut Model) {
    model.screen = Screen::New(NewEntry { kind: 0, picker: None, pick_for: None });
    model.status = "new exemplar: choose what makes it (enter), esc goes back".into();
}

fn screen(model: &mut Model) -> Option<&mut NewEntry> {
    match &mut model.screen {
        Screen::New(entry) => Some(entry),
        _ => None,
    }
}

/// Up/down: the next kind, or the next file (its photo is read).
pub fn select(model: &mut Model, step: i64) -> Vec<Effect> {
    let Some(entry) = screen(model) else { return Vec::new() };
    let Some(picker) = &mut entry.picker else {
        entry.kind = (entry.kind as i64 + step).clamp(0, KINDS.len() as i64 - 1) as usize;
        return Vec::new();
    };
    let count = picker.rows.as_ref().and_then(|r| r.as_ref().ok()).map_or(0, Vec::len);
    picker.selected = (picker.selected as i64 + step).clamp(0, count.saturating_sub(1) as i64) as usize;
    peek(picker)
}

/// A click on row `row` (a kind or a file): select it; a click on the selected row takes it.
pub fn pick(model: &mut Model, row: usize) -> Vec<Effect> {
    let Some(entry) = screen(model) else { return Vec::new() };
    let current = entry.picker.as_ref().map_or(entry.kind, |p| p.selected);
    if row == current {
        return open(model);
    }
    select(model, row as i64 - current as i64)
}

/// The photo under the cursor is read, when it is one and not read yet.
fn peek(picker: &mut Picker) -> Vec<Effect> {
    let Some(row) = selected_row(picker) else { return Vec::new() };
    let path = picker.folder.join(&row.name);
    let image = picker.file == FileKind::Image || has_extension(&path, &["png", "jpg", "jpeg", "tif", "tiff"]);
    if row.folder || !image || picker.peek.as_ref().is_some_and(|(p, _)| *p == path) {
        return Vec::new();
    }
    picker.peek = None;
    vec![Effect::Peek(path)]
}

fn selected_row(picker: &Picker) -> Option<FileRow> {
    picker.rows.as_ref()?.as_ref().ok()?.get(picker.selected).cloned()
}

fn has_extension(path: &Path, extensions: &[&str]) -> bool {
    path.extension().is_some_and(|e| extensions.contains(&e.to_string_lossy().to_ascii_lowercase().as_str()))
}

/// Enter: choose the kind (a procedural entry is added at once; the others open the file
/// picker in the manifest's folder); in the picker, enter a folder or choose the file.
pub fn open(model: &mut Model) -> Vec<Effect> {
    let folder = manifest_folder(&model.manifest);
    let Some(entry) = screen(model) else { return Vec::new() };
    let kind = KINDS[entry.kind];
    let Some(picker) = &mut entry.picker else {
        let Some(file) = kind.file else { return add(model, kind, None) };
        entry.picker = Some(Picker::new(file, folder.clone()));
        let what = if file == FileKind::Image { "an image" } else { "a volume file" };
        model.status = format!("{}: choose {what} (enter), backspace goes up a folder", kind.recipe);
        return vec![Effect::List(folder, file)];
    };
    let Some(row) = selected_row(picker) else { return Vec::new() };
    if row.folder {
        let target = if row.name == ".." {
            picker.folder.parent().map_or_else(|| picker.folder.clone(), Path::to_path_buf)
        } else {
            picker.folder.join(&row.name)
        };
        return go_to(picker, target);
    }
    let path = picker.folder.join(&row.name);
    match entry.pick_for.take() {
        Some(PickFor::Seed(view)) => {
            model.screen = Screen::Exemplar(*view);
            model.status = format!("loading the seed {}", path.display());
            return vec![Effect::LoadSeedFile(path)];
        }
        Some(PickFor::Step(editor, stamp)) => {
            model.screen = Screen::Editor(*editor);
            return vec![Effect::StepMesh(path, stamp)];
        }
        Some(PickFor::Spec(view)) => {
            model.screen = Screen::Fill(*view);
            model.status = format!("reading {}", path.display());
            return vec![Effect::LoadSpec(path)];
        }
        None => {}
    }
    add(model, kind, Some(path))
}

/// `o` in stamp mode: a picker for another seed mesh (in the manifest's folder), unless
/// stamps are unsaved (saved steps name the mesh they used).
pub fn pick_seed(model: &mut Model) -> Vec<Effect> {
    let folder = manifest_folder(&model.manifest);
    let Screen::Exemplar(view) = &model.screen else { return Vec::new() };
    let Some(stamp) = &view.stamp else { return Vec::new() };
    if !stamp.steps.is_empty() {
        model.status = "save (s) or undo (u) the stamps first: each saved step names the mesh it used".into();
        return Vec::new();
    }
    let view = Box::new(view.clone());
    let picker = Picker::new(FileKind::Mesh, folder.clone());
    model.screen = Screen::New(NewEntry { kind: 0, picker: Some(picker), pick_for: Some(PickFor::Seed(view)) });
    model.status = "choose a seed mesh (obj, stl, ply): enter takes it, esc keeps the one in use".into();
    vec![Effect::List(folder, FileKind::Mesh)]
}

/// `t` / `n` in the recipe editor: a picker for the mesh of a new stamp (true) or scatter
/// step, starting in the manifest's folder.
pub fn pick_step_mesh(model: &mut Model, stamp: bool) -> Vec<Effect> {
    let folder = manifest_folder(&model.manifest);
    let Screen::Editor(editor) = &model.screen else { return Vec::new() };
    if editor.text.is_none() {
        return Vec::new();
    }
    let editor = Box::new(editor.clone());
    let picker = Picker::new(FileKind::Mesh, folder.clone());
    model.screen =
        Screen::New(NewEntry { kind: 0, picker: Some(picker), pick_for: Some(PickFor::Step(editor, stamp)) });
    let what = if stamp { "stamp" } else { "scatter" };
    model.status = format!("choose the mesh to {what} (obj, stl, ply): enter takes it, esc goes back");
    vec![Effect::List(folder, FileKind::Mesh)]
}

/// `o` in the fill preview: a picker for a written fill spec, starting in the folder `w`
/// writes them to (`OUTPUT/exports/`; backspace goes up when it does not exist yet).
pub fn pick_spec(model: &mut Model) -> Vec<Effect> {
    let Screen::Fill(view) = &model.screen else { return Vec::new() };
    if view.edit.is_none() {
        model.status = "the fill is still running".into();
        return Vec::new();
    }
    let folder = model.output.join("exports");
    let view = Box::new(view.clone());
    let picker = Picker::new(FileKind::FillSpec, folder.clone());
    model.screen = Screen::New(NewEntry { kind: 0, picker: Some(picker), pick_for: Some(PickFor::Spec(view)) });
    model.status = "choose a fill spec (toml) to load its constraints: enter loads it, esc goes back".into();
    vec![Effect::List(folder, FileKind::FillSpec)]
}

/// Backspace or left in the picker: the folder above.
pub fn parent(model: &mut Model) -> Vec<Effect> {
    let Some(picker) = screen(model).and_then(|e| e.picker.as_mut()) else { return Vec::new() };
    let Some(up) = picker.folder.parent().map(Path::to_path_buf) else { return Vec::new() };
    go_to(picker, up)
}

/// List `folder`; when it is the one above, the folder left is selected once listed.
fn go_to(picker: &mut Picker, folder: PathBuf) -> Vec<Effect> {
    let left = picker.folder.file_name().filter(|_| picker.folder.parent() == Some(folder.as_path()));
    let came_from = left.map(|n| n.to_string_lossy().into_owned());
    *picker = Picker { came_from, ..Picker::new(picker.file, folder.clone()) };
    vec![Effect::List(folder, picker.file)]
}

/// The entry is asked for; the screen goes to the library once it is added (a refused file
/// leaves the picker open, see [`added`]).
fn add(model: &mut Model, kind: Kind, file: Option<PathBuf>) -> Vec<Effect> {
    if file.is_none() {
        model.screen = Screen::Library;
    }
    model.status = format!("adding a {} entry", kind.recipe);
    vec![Effect::ChangeEntry(EntryChange::New(kind.recipe.to_string(), file))]
}

/// The manifest changed (or not) after a new entry was asked for: on success the library
/// shows it; a refusal leaves the picker open with the reason.
pub fn added(model: &mut Model, ok: bool) {
    if ok && matches!(model.screen, Screen::New(NewEntry { pick_for: None, .. })) {
        model.screen = Screen::Library;
    }
}

/// Esc: the picker goes back to the kinds; the kinds to the library. False when the
/// screen is not this one.
pub fn back(model: &mut Model) -> bool {
    let Some(entry) = screen(model) else { return false };
    if let Some(back) = entry.pick_for.take() {
        (model.screen, model.status) = match back {
            PickFor::Seed(view) => (Screen::Exemplar(*view), "the seed mesh stays".into()),
            PickFor::Step(editor, _) => (Screen::Editor(*editor), "no step added".into()),
            PickFor::Spec(view) => (Screen::Fill(*view), "no fill spec loaded".into()),
        };
    } else if entry.picker.take().is_none() {
        model.screen = Screen::Library;
        model.status = "no entry added".into();
    } else {
        model.status = "new exemplar: choose what makes it (enter)".into();
    }
    true
}

/// A folder listing arrived: `asked` is the folder asked for, then (the folder as a
/// canonical path, its rows).
pub fn listed(model: &mut Model, asked: &Path, result: Result<(PathBuf, Vec<FileRow>), String>) -> Vec<Effect> {
    let Some(entry) = screen(model) else { return Vec::new() };
    let Some(picker) = entry.picker.as_mut().filter(|p| p.folder == asked) else { return Vec::new() };
    match result {
        Ok((folder, rows)) => {
            picker.selected = picker.came_from.take().and_then(|n| rows.iter().position(|r| r.name == n)).unwrap_or(0);
            picker.folder = folder;
            picker.rows = Some(Ok(rows));
            peek(picker)
        }
        Err(e) => {
            picker.rows = Some(Err(e));
            Vec::new()
        }
    }
}

/// A photo arrived; kept when it is still the one under the cursor.
pub fn peeked(model: &mut Model, path: PathBuf, result: Result<Arc<Image2d>, String>) {
    let Some(picker) = screen(model).and_then(|e| e.picker.as_mut()) else { return };
    if selected_row(picker).is_some_and(|row| picker.folder.join(row.name) == path) {
        picker.peek = Some((path, result));
    }
}

/// The folder relative paths in the manifest start from.
pub fn manifest_folder(manifest: &Path) -> PathBuf {
    match manifest.parent() {
        Some(p) if !p.as_os_str().is_empty() => p.to_path_buf(),
        _ => PathBuf::from("."),
    }
}

/// The rows of a folder listing: `..` (unless at the root), its folders, then the files
/// with one of `extensions`, each group by name; hidden entries left out.
pub fn rows(at_root: bool, entries: Vec<(String, bool)>, extensions: &[&str]) -> Vec<FileRow> {
    let mut kept: Vec<FileRow> = entries
        .into_iter()
        .filter(|(name, folder)| !name.starts_with('.') && (*folder || has_extension(Path::new(name), extensions)))
        .map(|(name, folder)| FileRow { name, folder })
        .collect();
    kept.sort_by(|a, b| b.folder.cmp(&a.folder).then_with(|| a.name.to_lowercase().cmp(&b.name.to_lowercase())));
    let up = (!at_root).then(|| FileRow { name: "..".into(), folder: true });
    up.into_iter().chain(kept).collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::tui::{Message, update};

    fn model() -> Model {
        Model::new(PathBuf::from("lib/library.toml"), PathBuf::from("out"), Vec::new(), Vec::new())
    }

    fn rows_of(names: &[(&str, bool)]) -> Vec<FileRow> {
        names.iter().map(|(n, f)| FileRow { name: n.to_string(), folder: *f }).collect()
    }

    #[test]
    fn a_procedural_kind_is_added_at_once_and_a_photo_kind_opens_the_picker() {
        let mut m = model();
        update(&mut m, Message::New);
        assert!(matches!(m.screen, Screen::New(_)));
        for _ in 0..4 {
            update(&mut m, Message::Down);
        }
        let effects = update(&mut m, Message::Open);
        assert_eq!(effects, vec![Effect::ChangeEntry(EntryChange::New("procedural:marble".into(), None))]);
        assert!(matches!(m.screen, Screen::Library));
        update(&mut m, Message::New);
        let effects = update(&mut m, Message::Open);
        assert_eq!(effects, vec![Effect::List(PathBuf::from("lib"), FileKind::Image)]);
        assert!(matches!(&m.screen, Screen::New(NewEntry { picker: Some(p), .. }) if p.file == FileKind::Image));
        // esc closes the picker first, then the screen
        assert!(matches!(update(&mut m, Message::Back)[..], []) && matches!(m.screen, Screen::New(_)));
        update(&mut m, Message::Back);
        assert!(matches!(m.screen, Screen::Library) && m.status == "no entry added", "{}", m.status);
    }

    #[test]
    fn the_picker_walks_folders_previews_photos_and_adds_the_chosen_one() {
        let mut m = model();
        update(&mut m, Message::New);
        update(&mut m, Message::Open);
        let listing = rows_of(&[("..", true), ("photos", true), ("a.png", false), ("b.jpg", false)]);
        // a listing of another folder (an older request) is dropped
        let late = update(&mut m, Message::Listed(PathBuf::from("elsewhere"), Ok((PathBuf::from("/x"), vec![]))));
        assert!(late.is_empty());
        let effects = update(&mut m, Message::Listed(PathBuf::from("lib"), Ok((PathBuf::from("/w/lib"), listing))));
        assert!(effects.is_empty(), "`..` is not a photo: {effects:?}");
        assert_eq!(update(&mut m, Message::Down), vec![]);
        assert_eq!(update(&mut m, Message::Down), vec![Effect::Peek(PathBuf::from("/w/lib/a.png"))]);
        let photo = Arc::new(Image2d::from_data(2, 1, crate::volume::Channel::rgb(), vec![0.5; 6]).unwrap());
        update(&mut m, Message::Peeked(PathBuf::from("/w/lib/b.jpg"), Ok(photo.clone())));
        let Screen::New(NewEntry { picker: Some(p), .. }) = &m.screen else { panic!("the picker") };
        assert!(p.peek.is_none(), "a photo no longer under the cursor is dropped");
        update(&mut m, Message::Peeked(PathBuf::from("/w/lib/a.png"), Ok(photo)));
        let Screen::New(NewEntry { picker: Some(p), .. }) = &m.screen else { panic!("the picker") };
        assert!(p.peek.as_ref().is_some_and(|(_, r)| r.is_ok()));
        // up goes to the folder above, the folder left selected; enter on a folder goes into it
        assert_eq!(update(&mut m, Message::Parent), vec![Effect::List(PathBuf::from("/w"), FileKind::Image)]);
        let listing = rows_of(&[("..", true), ("a", true), ("lib", true)]);
        update(&mut m, Message::Listed(PathBuf::from("/w"), Ok((PathBuf::from("/w"), listing))));
        assert_eq!(update(&mut m, Message::Open), vec![Effect::List(PathBuf::from("/w/lib"), FileKind::Image)]);
        let listing = rows_of(&[("..", true), ("a.png", false)]);
        update(&mut m, Message::Listed(PathBuf::from("/w/lib"), Ok((PathBuf::from("/w/lib"), listing))));
        update(&mut m, Message::Down);
        let effects = update(&mut m, Message::Open);
        let chosen = EntryChange::New("synth".into(), Some(PathBuf::from("/w/lib/a.png")));
        assert_eq!(effects, vec![Effect::ChangeEntry(chosen)]);
        // a refused file leaves the picker open; an added entry shows on the library
        update(&mut m, Message::EntriesChanged(Err("a.png: cannot decode it as an image".into())));
        assert!(matches!(m.screen, Screen::New(_)) && m.status.contains("cannot decode"), "{}", m.status);
        let change = crate::tui::Change {
            items: Vec::new(),
            errors: Vec::new(),
            select: "a".into(),
            status: "added a".into(),
            inverse: None,
        };
        update(&mut m, Message::EntriesChanged(Ok(change)));
        assert!(matches!(m.screen, Screen::Library));
    }

    #[test]
    fn listings_keep_folders_and_the_files_a_kind_reads() {
        let entries = vec![
            ("Zebra.PNG".to_string(), false),
            ("notes.txt".to_string(), false),
            (".hidden.png".to_string(), false),
            ("meshes".to_string(), true),
            ("a.jpg".to_string(), false),
            ("scan.nrrd".to_string(), false),
        ];
        let names = |rows: Vec<FileRow>| rows.into_iter().map(|r| r.name).collect::<Vec<_>>();
        assert_eq!(
            names(rows(false, entries.clone(), FileKind::Image.extensions())),
            ["..", "meshes", "a.jpg", "Zebra.PNG"]
        );
        assert_eq!(names(rows(true, entries, FileKind::Volume.extensions())), ["meshes", "scan.nrrd", "Zebra.PNG"]);
    }
}
