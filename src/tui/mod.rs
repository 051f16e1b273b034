//! The terminal UI for texture designers (ratatui + crossterm), Model / Message / update /
//! view: `keymap` and `update` are pure and unit-tested, `view` only draws, and long work
//! (loading a volume, building exemplars) runs in worker threads that send messages back.
//!
//! Screens: the library list with declared and measured types and build state (building
//! one or all in the background); the exemplar view with three orthogonal slices as
//! truecolour half-blocks, moved with keys, per channel; the recipe editor (format-preserving
//! edits validated in place, undo/redo, live low-resolution preview, save); and the fill
//! preview (a shape filled with the exemplar, a cut plane moved with keys).

mod compare;
mod edit;
mod editing;
mod fill_edit;
mod graphics;
mod keybar;
mod keymap;
mod message;
mod model;
mod mouse;
mod new_entry;
mod stamping;
mod update;
mod view;
mod view_compare;
mod view_edit;
mod view_new;

pub use message::{Change, Changed, Effect, EntryChange, Message};
pub use model::{BuildState, FillPreview, Item, Model, Screen};
pub use update::update;
pub use view::draw;

use crate::error::{Error, Result};
use crate::io;
use crate::library::{self, Freshness, Observer, Outcome};
use crate::volume::{Axis, Volume};
use crossterm::event::{self, Event, KeyEventKind, KeyModifiers};
use std::collections::HashMap;
use std::path::{Path, PathBuf};
use std::sync::Arc;
use std::sync::Mutex;
use std::sync::atomic::{AtomicBool, AtomicU64, AtomicUsize, Ordering};
use std::sync::mpsc::{Receiver, Sender, channel};
use std::time::Duration;

/// The library items of a manifest, with their build state read from `output`.
pub fn load_items(manifest: &Path, output: &Path) -> (Vec<Item>, Vec<String>) {
    let text = match read_manifest(manifest) {
        Ok(text) => text,
        Err(e) => return (Vec::new(), vec![e.to_string()]),
    };
    let folder = manifest.parent().unwrap_or(Path::new("."));
    let (entries, errors) = io::manifest::parse_plan_lenient(&text, folder);
    let shown = manifest.display();
    // Every entry in manifest order; a broken one is listed too, so it can be opened and fixed.
    let items = entry_names_of(&text)
        .into_iter()
        .map(|name| match entries.iter().find(|e| e.name == name) {
            Some(entry) => item(entry, folder, output),
            None => {
                let own = errors.iter().find(|e| e.contains(&format!("({name})")));
                let reason = own.cloned().unwrap_or_else(|| "a mistake in this entry (see below)".to_string());
                Item {
                    name,
                    declared: None,
                    size: None,
                    state: BuildState::Broken(reason),
                    quality: None,
                    previous: false,
                }
            }
        })
        .collect();
    (items, errors.into_iter().map(|e| format!("{shown}: {e}")).collect())
}

/// The names of a manifest's entries in order, valid or not (entries without a name, or
/// with a repeated one, are left out: the editor finds entries by name).
fn entry_names_of(text: &str) -> Vec<String> {
    let Ok(doc) = text.parse::<toml::Table>() else { return Vec::new() };
    let mut names: Vec<String> = Vec::new();
    let list = doc.get("exemplar").and_then(|v| v.as_array()).map(Vec::as_slice).unwrap_or_default();
    for name in list.iter().filter_map(|e| e.get("name").and_then(|n| n.as_str())) {
        if !names.iter().any(|n| n == name) {
            names.push(name.to_string());
        }
    }
    names
}

/// A valid entry's row: its build state from the cache's plan (not built, built, or
/// changed since its last build).
fn item(entry: &io::manifest::Entry, folder: &Path, output: &Path) -> Item {
    let (record, state) = match library::cache::freshness(entry, folder, output) {
        Freshness::NotBuilt => (None, BuildState::NotBuilt),
        Freshness::UpToDate(r) => (Some(r.clone()), BuildState::Built(r.classified)),
        Freshness::Stale(r, why) => (Some(r.clone()), BuildState::Changed(r.classified, why)),
    };
    Item {
        name: entry.name.clone(),
        declared: entry
            .texture_type
            .map(|t| t.to_string())
            .or_else(|| record.as_ref().and_then(|r| r.declared.clone())),
        size: record.as_ref().map(|r| r.dims).or(entry.dims),
        quality: record.and_then(|r| r.quality),
        previous: library::previous::record(output, &entry.name).is_some(),
        state,
    }
}

/// Open the UI on `manifest`, with builds going to `output`.
pub fn run(manifest: &Path, output: &Path) -> Result<()> {
    use std::io::IsTerminal;
    if !(std::io::stdin().is_terminal() && std::io::stdout().is_terminal()) {
        return Err(Error::usage(
            "the terminal UI needs a terminal (its input and output are not one here); \
             build the library without it with `solidtex build`, or see `solidtex --help`",
        ));
    }
    let first_run = !manifest.exists();
    let (items, errors) = if first_run { Default::default() } else { load_items(manifest, output) };
    let mut model = Model::new(manifest.to_path_buf(), output.to_path_buf(), items, errors);
    if first_run {
        model.first_run = true;
        model.status = format!("no library at {} yet: enter starts one", manifest.display());
    }
    model.read_only = read_only(manifest, output);
    if !model.read_only.is_empty() {
        model.status = model.read_only.join("; ");
    }
    let (send, receive) = channel();
    let mut terminal = ratatui::init();
    let mut graphics = graphics::Graphics::detect();
    if let Some(g) = &graphics {
        model.status = format!("{} (pictures: {})", model.status, g.name());
    }
    // SOLIDTEX_MOUSE=0 leaves the mouse to the terminal (its own selection and copy).
    let mouse = std::env::var("SOLIDTEX_MOUSE").map_or(true, |v| v != "0");
    if mouse {
        let _ = crossterm::execute!(std::io::stdout(), crossterm::event::EnableMouseCapture);
    }
    MOUSE.store(mouse, Ordering::SeqCst);
    OPEN.store(true, Ordering::SeqCst);
    // A panic of the UI's own thread leaves the terminal as it found it (ratatui's hook
    // restores it, then reports); a worker's panic is caught and becomes its job's error in
    // the status line, so nothing is printed over the screen.
    let ui = std::thread::current().id();
    let report = std::panic::take_hook();
    std::panic::set_hook(Box::new(move |info| {
        if std::thread::current().id() == ui {
            restore_terminal();
            report(info);
        }
    }));
    let result = event_loop(&mut terminal, &mut model, &send, &receive, graphics.as_mut());
    restore_terminal();
    stop_builds();
    result
}

/// Build workers running (each counts itself while it runs).
static BUILDS: AtomicUsize = AtomicUsize::new(0);

/// How long quitting waits for cancelled builds to stop.
const STOP_WAIT: Duration = Duration::from_secs(60);

/// On quitting: cancel the builds still running and wait (up to [`STOP_WAIT`]) until they
/// have stopped, so none is cut off half-way through writing a file.
fn stop_builds() {
    if BUILDS.load(Ordering::SeqCst) == 0 {
        return;
    }
    CANCELS.fetch_add(1, Ordering::SeqCst);
    eprintln!("cancelling the running builds; their previous outputs are kept");
    let asked = std::time::Instant::now();
    while BUILDS.load(Ordering::SeqCst) > 0 && asked.elapsed() < STOP_WAIT {
        std::thread::sleep(Duration::from_millis(50));
    }
}

/// A build worker counted in [`BUILDS`] while it lives.
struct Counted;

impl Counted {
    fn new() -> Counted {
        BUILDS.fetch_add(1, Ordering::SeqCst);
        Counted
    }
}

impl Drop for Counted {
    fn drop(&mut self) {
        BUILDS.fetch_sub(1, Ordering::SeqCst);
    }
}

/// What cannot be written, said when the library opens: a read-only manifest or output
/// folder.
fn read_only(manifest: &Path, output: &Path) -> Vec<String> {
    let mut notes = Vec::new();
    if io::atomic::read_only(manifest) {
        notes.push(format!(
            "{} is read-only: saves are refused (the editor's S saves under another name)",
            manifest.display()
        ));
    }
    if output.is_dir() && io::atomic::read_only(output) {
        notes.push(format!("the output folder {} is read-only: builds and exports will fail", output.display()));
    }
    notes
}

/// Whether the UI has the terminal (raw mode, alternate screen), and whether it asked for
/// mouse reports.
static OPEN: AtomicBool = AtomicBool::new(false);
static MOUSE: AtomicBool = AtomicBool::new(false);

/// Give the terminal back as the UI found it, once, from whichever thread gets here first:
/// a normal exit, a panic of the UI thread, or a signal (SIGTERM, SIGHUP) handled by the
/// binary. Errors are ignored, never printed: after SIGHUP the terminal is gone.
pub fn restore_terminal() {
    if OPEN.swap(false, Ordering::SeqCst) {
        if MOUSE.load(Ordering::SeqCst) {
            let _ = crossterm::execute!(std::io::stdout(), crossterm::event::DisableMouseCapture);
        }
        let _ = ratatui::try_restore();
    }
}

fn event_loop(
    terminal: &mut ratatui::DefaultTerminal,
    model: &mut Model,
    send: &Sender<Message>,
    receive: &Receiver<Message>,
    mut graphics: Option<&mut graphics::Graphics>,
) -> Result<()> {
    let fail = |e: std::io::Error| Error::io("terminal", e);
    let mut regions = mouse::Regions::default();
    let mut looked = std::time::Instant::now();
    let opened = looked;
    if let Ok(size) = terminal.size() {
        dispatch(terminal, update(model, Message::Resized(size.width, size.height)), model, send)?;
    }
    while !model.quit {
        // Once a second: the clock moves on; has someone else changed the manifest?
        if looked.elapsed() >= Duration::from_secs(1) {
            looked = std::time::Instant::now();
            dispatch(terminal, update(model, Message::Tick(opened.elapsed())), model, send)?;
            if !model.outside && changed_outside(&model.manifest) {
                dispatch(terminal, update(model, Message::ChangedOnDisk), model, send)?;
            }
        }
        terminal.draw(|f| view::draw_with(f, model, graphics.as_deref_mut(), &mut regions)).map_err(fail)?;
        let mut dimmed = None;
        let message = if event::poll(Duration::from_millis(100)).map_err(fail)? {
            match event::read().map_err(fail)? {
                Event::Key(key) if key.kind == KeyEventKind::Press => match (&model.help, &model.prompt) {
                    (Some(help), _) => keymap::help_key(help, key),
                    (None, Some(_)) => keymap::typing(key),
                    (None, None) if model.log_view.is_some() => keymap::log_key(key),
                    (None, None) => {
                        // a dimmed key says why it did nothing (when it did nothing)
                        dimmed = keymap::key_name(key.code)
                            .filter(|_| key.modifiers.difference(KeyModifiers::SHIFT).is_empty())
                            .and_then(|name| keybar::why_dimmed(model, &name));
                        keymap::key(&model.screen, key)
                    }
                },
                Event::Resize(w, h) => {
                    // a full redraw: nothing of the old layout stays on screen
                    terminal.clear().map_err(fail)?;
                    Some(Message::Resized(w, h))
                }
                Event::Mouse(m) if model.help.is_none() && model.prompt.is_none() => {
                    mouse::message(&model.screen, &regions, m)
                }
                _ => None,
            }
        } else {
            None
        };
        let before = model.status.clone();
        if let Some(message) = message {
            dispatch(terminal, update(model, message), model, send)?;
        }
        if let Some(why) = dimmed.take().filter(|_| model.status == before) {
            dispatch(terminal, update(model, Message::Say(why)), model, send)?;
        }
        while let Ok(message) = receive.try_recv() {
            dispatch(terminal, update(model, message), model, send)?;
        }
    }
    Ok(())
}

/// Run effects: editing the manifest outside on this thread (it owns the terminal), the
/// others in workers.
fn dispatch(
    terminal: &mut ratatui::DefaultTerminal,
    effects: Vec<Effect>,
    model: &mut Model,
    send: &Sender<Message>,
) -> Result<()> {
    let (outside, rest): (Vec<Effect>, Vec<Effect>) =
        effects.into_iter().partition(|e| matches!(e, Effect::EditOutside(_)));
    start(rest, model, send);
    for effect in outside {
        if let Effect::EditOutside(line) = effect {
            let result = edit_outside(terminal, &model.manifest, line);
            dispatch(terminal, update(model, Message::OutsideEdited(result)), model, send)?;
        }
    }
    Ok(())
}

/// Suspend the UI, edit `manifest` at `line` in `$VISUAL` or `$EDITOR` (vi when neither is
/// set), and take the terminal back.
fn edit_outside(
    terminal: &mut ratatui::DefaultTerminal,
    manifest: &Path,
    line: usize,
) -> std::result::Result<(), String> {
    let editor = ["VISUAL", "EDITOR"]
        .iter()
        .filter_map(|v| std::env::var(v).ok())
        .find(|e| !e.trim().is_empty())
        .unwrap_or_else(|| "vi".into());
    restore_terminal();
    // through the shell, so an editor given with its options (`code -w`) runs as written
    let status = std::process::Command::new("sh")
        .arg("-c")
        .arg(format!("{editor} +{line} \"$1\""))
        .arg("solidtex")
        .arg(manifest)
        .status();
    *terminal = ratatui::init();
    OPEN.store(true, Ordering::SeqCst);
    if MOUSE.load(Ordering::SeqCst) {
        let _ = crossterm::execute!(std::io::stdout(), crossterm::event::EnableMouseCapture);
    }
    let _ = terminal.clear();
    match status {
        Ok(s) if s.success() => Ok(()),
        Ok(s) => Err(format!("{editor} ended with {s}; the manifest is read as it is now")),
        Err(e) => Err(format!("cannot run {editor} ($VISUAL / $EDITOR): {e}")),
    }
}

/// Run effects in worker threads that report back through `send`. A worker that panics
/// says so in the status line (a build fails its entries) and the UI goes on.
fn start(effects: Vec<Effect>, model: &Model, send: &Sender<Message>) {
    for effect in effects {
        let (send, manifest, output) = (send.clone(), model.manifest.clone(), model.output.clone());
        let counted = matches!(effect, Effect::Build(_)).then(Counted::new);
        std::thread::spawn(move || {
            let _counted = counted;
            let building = if let Effect::Build(names) = &effect { names.clone() } else { Vec::new() };
            let run = || {
                work(effect, &send, &manifest, &output);
                Ok(())
            };
            if let Err(e) = library::build::caught(run) {
                for name in building {
                    let _ = send.send(Message::Built(name, Err(e.to_string())));
                }
                let _ = send.send(Message::WorkerFailed(e.to_string()));
            }
        });
    }
}

/// Do one effect's work and send its result.
fn work(effect: Effect, send: &Sender<Message>, manifest: &Path, output: &Path) {
    let (manifest, output) = (manifest.to_path_buf(), output.to_path_buf());
    match effect {
        Effect::Load(name) => {
            let result =
                io::read_volume(&library::files::volume(&output, &name), io::budget_from_env().unwrap_or(u64::MAX))
                    .map(Arc::new)
                    .map_err(|e| e.to_string());
            let _ = send.send(Message::Loaded(name, result));
        }
        Effect::Build(names) => build(&manifest, &output, names, send),
        Effect::EditOutside(_) => {}
        Effect::StartLibrary => {
            let _ = send.send(Message::EntriesChanged(start_library(&manifest)));
        }
        Effect::ReadManifest => {
            let text = read_manifest(&manifest).map_err(|e| e.to_string());
            let _ = send.send(Message::EditorReady(text));
        }
        Effect::Save { name, base, text } => {
            let _ = send.send(save_editor(&manifest, &name, &base, &text));
        }
        Effect::SaveAs(path, text) => {
            let result = save_as(&manifest, &path, &text).map(|_| (path, text)).map_err(|e| e.to_string());
            let _ = send.send(Message::SavedAs(result));
        }
        Effect::Reload(select) => {
            let (items, errors) = load_items(&manifest, &output);
            let status = format!("read {} again: {} exemplar(s)", manifest.display(), items.len());
            let change = message::Change { items, errors, select, status, inverse: None };
            let _ = send.send(Message::EntriesChanged(Ok(change)));
        }
        Effect::UndoEntry(change, what) => {
            let result = change_entry(&manifest, &output, &change).map(|c| message::Change {
                status: format!("undid {what}: {}", c.status.trim_end_matches(" (u undoes)")),
                inverse: None,
                ..c
            });
            let _ = send.send(Message::EntriesChanged(result));
        }
        Effect::Preview { name, text, generation } => {
            let (result, warnings) = match library::recipe::preview(&manifest, &name, &text) {
                Ok((volume, warnings)) => (Ok(Arc::new(volume)), warnings),
                Err(e) => (Err(e.to_string()), Vec::new()),
            };
            let _ = send.send(Message::Previewed(generation, result, warnings));
        }
        Effect::CancelBuilds => {
            CANCELS.fetch_add(1, Ordering::SeqCst);
        }
        Effect::LoadMasks(name) => {
            let _ = send.send(Message::MasksLoaded(name.clone(), load_masks(&output, &name)));
        }
        Effect::LoadSeed(name) => {
            let _ = send.send(Message::SeedLoaded(find_seed(&manifest, &name).map_err(|e| e.to_string())));
        }
        Effect::SaveSteps(name, steps, file) => {
            let _ = send.send(Message::Saved(save_steps(&manifest, &name, &steps, &file)));
        }
        Effect::ChangeEntry(change) => {
            let _ = send.send(Message::EntriesChanged(change_entry(&manifest, &output, &change)));
        }
        Effect::Export(name, volume, axis, index) => {
            let result = export(&output, &name, &volume, axis, index).map_err(|e| e.to_string());
            let _ = send.send(Message::Exported(result));
        }
        Effect::ExportCut(name, filled, axis, offset) => {
            let result = export_cut(&output, &name, &filled.0, axis, offset).map_err(|e| e.to_string());
            let _ = send.send(Message::Exported(result));
        }
        Effect::WebView(name, subject) => {
            let browser = std::env::var("BROWSER").ok();
            let result = web_view(&output, &name, &subject, browser.as_deref()).map_err(|e| e.to_string());
            let _ = send.send(Message::WebWritten(result));
        }
        Effect::List(folder, kind) => {
            let _ = send.send(Message::Listed(folder.clone(), list_folder(&folder, kind)));
        }
        Effect::Peek(path) => {
            let result = io::read_image_fit(&path, Some(256)).map(Arc::new).map_err(|e| e.to_string());
            let _ = send.send(Message::Peeked(path, result));
        }
        Effect::LoadSide(side, label, name, previous) => {
            let result = side_of(&output, &name, previous).map_err(|e| e.to_string());
            let _ = send.send(Message::SideLoaded(side, label, result));
        }
        Effect::Settle(name, accept) => {
            let _ = send.send(Message::EntriesChanged(settle(&manifest, &output, &name, accept)));
        }
        Effect::Refill(name, spec, shape) => {
            let result = library::fill::preview_with(&spec, &shape, &crate::progress::NoProgress)
                .map(Arc::new)
                .map_err(|e| e.to_string());
            let _ = send.send(Message::Filled(name, result));
        }
        Effect::Overlay(name, filled, key) => {
            let view = fill_edit::plane_view(&filled.0, key.axis, key.offset, fill_edit::OVERLAY_SIZE);
            let result =
                library::guided::picture(&filled.0, &key.spec, key.overlay, &view, &crate::progress::NoProgress)
                    .map(Arc::new)
                    .map_err(|e| e.to_string());
            let _ = send.send(Message::OverlayMade(name, key, result));
        }
        Effect::WriteSpec(name, spec, shape) => {
            let result = write_spec(&output, &name, &spec, &shape).map_err(|e| e.to_string());
            let _ = send.send(Message::SpecWritten(spec, result));
        }
        Effect::LoadSpec(path) => {
            let result = io::fill_spec::read_fill_spec(&path).map(Box::new).map_err(|e| e.to_string());
            let _ = send.send(Message::SpecLoaded(path, result));
        }
        Effect::StepMesh(path, stamp) => {
            let named = seed_file(&manifest, &path).map(|(_, name)| name.unwrap_or_default());
            let _ = send.send(Message::StepMeshChosen(named.map_err(|e| e.to_string()), stamp));
        }
        Effect::LoadSeedFile(path) => {
            let _ = send.send(Message::SeedLoaded(seed_file(&manifest, &path).map_err(|e| e.to_string())));
        }
        Effect::LoadPhotos(name) => {
            let result = photos_of(&manifest, &name).map(Arc::new).map_err(|e| e.to_string());
            let _ = send.send(Message::PhotosLoaded(name, result));
        }
        Effect::Fill(name) => {
            let result = library::fill::preview(&manifest, &output, &name, &crate::progress::NoProgress)
                .map(Arc::new)
                .map_err(|e| e.to_string());
            let _ = send.send(Message::Filled(name, result));
        }
    }
}

/// Copies, deletes, renames, adds or restores an entry of the manifest as it reads now,
/// saves it and reloads the list; with the change that undoes it.
fn change_entry(manifest: &Path, output: &Path, change: &EntryChange) -> Changed {
    let text = read_manifest(manifest).map_err(|e| e.to_string())?;
    let (new_text, select, status, inverse) = match change {
        EntryChange::Duplicate(name) => {
            let (t, copy) = edit::duplicate(&text, name)?;
            let status = format!("copied {name} as {copy} (e edits it, b builds it; u undoes)");
            (t, copy.clone(), status, (EntryChange::Delete(copy.clone()), format!("the copy {copy}")))
        }
        EntryChange::Delete(name) => {
            let t = edit::delete(&text, name)?;
            let restore = EntryChange::Restore(Box::new(edit::removed(&text, &t, name)));
            let status = format!("deleted {name} from {}; its built files stay (u undoes)", manifest.display());
            (t, String::new(), status, (restore, format!("the deletion of {name}")))
        }
        EntryChange::Rename(name, new) => {
            let t = edit::rename(&text, name, new)?;
            let status = format!("renamed {name} to {new}; the files built as {name} stay (b builds {new}; u undoes)");
            let back = EntryChange::Rename(new.clone(), name.clone());
            (t, new.clone(), status, (back, format!("the rename of {name} to {new}")))
        }
        EntryChange::New(recipe, file) => {
            let (t, name, status) = added(manifest, &text, recipe, file.as_deref())?;
            let what = format!("the new entry {name}");
            (t, name.clone(), status, (EntryChange::Delete(name), what))
        }
        EntryChange::Restore(removed) => {
            let t = edit::restore(&text, removed)?;
            let name = removed.name.clone();
            let status = format!("{name} is back in {}", manifest.display());
            (t, name.clone(), status, (EntryChange::Delete(name.clone()), format!("the return of {name}")))
        }
    };
    write_manifest(manifest, &new_text).map_err(|e| e.to_string())?;
    // A kept previous build belongs to the name it was built under: it goes with the entry.
    if let EntryChange::Delete(name) | EntryChange::Rename(name, _) = change {
        let _ = library::previous::drop_kept(output, name);
    }
    let (items, errors) = load_items(manifest, output);
    Ok(message::Change { items, errors, select, status, inverse: Some(inverse) })
}

/// The first lines of a library started in the UI.
const NEW_MANIFEST: &str = "# A solidtex library: one [[exemplar]] table per solid texture (docs/manifest.md).\n\
# `solidtex build` builds them into the output folder; in `solidtex tui`, n adds one.\n";

/// Write an empty manifest at `manifest` (its folder made if missing); a file there is
/// never replaced.
fn start_library(manifest: &Path) -> Changed {
    let folder = new_entry::manifest_folder(manifest);
    std::fs::create_dir_all(&folder).map_err(|e| format!("cannot make the folder {}: {e}", folder.display()))?;
    let mut file = std::fs::File::options()
        .write(true)
        .create_new(true)
        .open(manifest)
        .map_err(|e| format!("cannot start a library at {}: {e}", manifest.display()))?;
    std::io::Write::write_all(&mut file, NEW_MANIFEST.as_bytes())
        .map_err(|e| format!("cannot write {}: {e}", manifest.display()))?;
    *KNOWN.lock().unwrap_or_else(|e| e.into_inner()) = Some(NEW_MANIFEST.to_string());
    Ok(message::Change {
        items: Vec::new(),
        errors: Vec::new(),
        select: String::new(),
        status: format!("started a library at {}: n adds your first exemplar", manifest.display()),
        inverse: None,
    })
}

/// The manifest text the UI last read or wrote, to tell a change made outside from its
/// own: reads and writes of the manifest go through [`read_manifest`] and
/// [`write_manifest`], which hold it while they touch the file.
static KNOWN: Mutex<Option<String>> = Mutex::new(None);

/// Read the manifest, remembering its text.
fn read_manifest(manifest: &Path) -> Result<String> {
    let mut known = KNOWN.lock().unwrap_or_else(|e| e.into_inner());
    let text = io::read_text(manifest, "manifest")?;
    *known = Some(text.clone());
    Ok(text)
}

/// Write the manifest (refused when it is read-only), remembering its text.
fn write_manifest(manifest: &Path, text: &str) -> Result<()> {
    let mut known = KNOWN.lock().unwrap_or_else(|e| e.into_inner());
    io::atomic::write_document(manifest, text.as_bytes())?;
    *known = Some(text.to_string());
    Ok(())
}

/// Whether the manifest reads otherwise than the UI last read or wrote it.
fn changed_outside(manifest: &Path) -> bool {
    let known = KNOWN.lock().unwrap_or_else(|e| e.into_inner());
    let now = io::read_text(manifest, "manifest").ok();
    known.is_some() && now.is_some() && *known != now
}

/// Write `text` as a new manifest at `path`, beside `manifest` (its relative paths start
/// from that folder); an existing file is never replaced.
fn save_as(manifest: &Path, path: &Path, text: &str) -> Result<()> {
    let folder = |p: &Path| new_entry::manifest_folder(p).canonicalize().ok();
    if folder(path).is_none() || folder(path) != folder(manifest) {
        return Err(Error::file(
            path,
            format!(
                "save-as writes beside the manifest, in {} (its image and mesh paths are relative to that folder)",
                new_entry::manifest_folder(manifest).display()
            ),
        ));
    }
    if path.exists() {
        return Err(Error::file(path, "exists; save-as never replaces a file: name a new one"));
    }
    let mut known = KNOWN.lock().unwrap_or_else(|e| e.into_inner());
    io::write_bytes(path, text.as_bytes())?;
    *known = Some(text.to_string());
    Ok(())
}

/// Save the editor's text of entry `name` (edited from `base`) onto the manifest as it
/// reads now: written when their changes and mine do not meet, else the text as it reads
/// now for the designer to choose.
fn save_editor(manifest: &Path, name: &str, base: &str, text: &str) -> Message {
    let theirs = match read_manifest(manifest) {
        Ok(theirs) => theirs,
        Err(e) => return Message::Saved(Err(e.to_string())),
    };
    if let Err(e) = edit::readable(&theirs) {
        return Message::Saved(Err(format!(
            "{} on disk does not read ({e}); fix it there, then s saves (your edits are kept)",
            manifest.display()
        )));
    }
    match edit::rebase(base, text, &theirs, name) {
        Some(merged) => Message::Saved(write_manifest(manifest, &merged).map(|_| merged).map_err(|e| e.to_string())),
        None => Message::SaveConflict(theirs),
    }
}

/// The manifest with a new entry of `recipe` reading `file` (written relative to the
/// manifest's folder), checked like the manifest; its name and a status line.
fn added(manifest: &Path, text: &str, recipe: &str, file: Option<&Path>) -> Result<(String, String, String), String> {
    let folder = new_entry::manifest_folder(manifest);
    let written = file.map(|f| io::written_relative(f, &folder));
    match file {
        Some(f) if recipe == "load" => {
            io::read_volume(f, io::budget_from_env().unwrap_or(u64::MAX))
                .map_err(|e| format!("cannot load it as a volume: {e}"))?;
        }
        Some(f) => {
            image::image_dimensions(f).map_err(|e| format!("{}: cannot decode it as an image: {e}", f.display()))?;
        }
        None => {}
    }
    let (text, name) = edit::new_entry(text, recipe, written.as_deref())?;
    io::manifest::parse_entry(&text, &folder, &name)
        .map_err(|e| format!("a new {recipe} entry does not fit this manifest: {e}"))?;
    let from = file.map(|f| format!(" from {}", f.display())).unwrap_or_default();
    let status = format!("added {name} ({recipe}{from}): b builds it, e edits its settings");
    Ok((text, name, status))
}

/// A volume to compare and its quality figures: exemplar `name`'s build, or the previous
/// build kept beside it.
fn side_of(output: &Path, name: &str, previous: bool) -> Result<(Arc<Volume>, Option<crate::quality::Glance>)> {
    let (path, record) = if previous {
        let path = library::previous::volume(output, name)
            .ok_or_else(|| Error::invalid(format!("no previous build of {name} is kept")))?;
        (path, library::previous::record(output, name))
    } else {
        (library::files::volume(output, name), library::cache::read_record(output, name))
    };
    let volume = io::read_volume(&path, io::budget_from_env().unwrap_or(u64::MAX))?;
    Ok((Arc::new(volume), record.and_then(|r| r.quality)))
}

/// Accept exemplar `name`'s new build (its kept previous build goes) or discard it (the
/// previous comes back); the reloaded list.
fn settle(manifest: &Path, output: &Path, name: &str, accept: bool) -> Changed {
    let done = if accept {
        library::previous::drop_kept(output, name).map(|_| format!("kept the new build of {name}"))
    } else {
        library::previous::restore(output, name).map(|_| {
            format!("{name} is its previous build again; the manifest keeps the new recipe (b builds it again)")
        })
    };
    let status = done.map_err(|e| e.to_string())?;
    let (items, errors) = load_items(manifest, output);
    Ok(message::Change { items, errors, select: name.to_string(), status, inverse: None })
}

/// The images exemplar `name` was made from, per slice axis: a synthesis' photos (shrunk as
/// for the synthesis), a sweep's cross-section across its axis.
fn photos_of(manifest: &Path, name: &str) -> Result<model::Photos> {
    let text = io::read_text(manifest, "manifest")?;
    let folder = new_entry::manifest_folder(manifest);
    let entry = io::manifest::parse_entry(&text, &folder, name)?;
    match &entry.source {
        io::manifest::Source::Synth(spec) => {
            let [x, y, z] = library::recipe::photos(spec)?;
            Ok([Some(x), Some(y), (!spec.layered).then_some(z)])
        }
        io::manifest::Source::Sweep(spec) => {
            let mut out: model::Photos = Default::default();
            out[spec.axis.index()] = Some(io::read_image(&spec.image)?);
            Ok(out)
        }
        _ => Err(Error::invalid(format!(
            "{name} is not made from an image (p compares synthesized and swept exemplars with theirs)"
        ))),
    }
}

/// A folder's rows for the picker (see [`new_entry::rows`]), and the folder as a canonical
/// path.
fn list_folder(
    folder: &Path,
    kind: new_entry::FileKind,
) -> std::result::Result<(PathBuf, Vec<new_entry::FileRow>), String> {
    let folder = folder.canonicalize().map_err(|e| Error::io(folder, e).to_string())?;
    let read = std::fs::read_dir(&folder).map_err(|e| Error::io(&folder, e).to_string())?;
    let entries =
        read.filter_map(|e| e.ok()).map(|e| (e.file_name().to_string_lossy().to_string(), e.path().is_dir())).collect();
    let rows = new_entry::rows(folder.parent().is_none(), entries, kind.extensions());
    Ok((folder, rows))
}

/// The formats `E` writes an exemplar in (by extension), besides its contact sheet and the
/// slice on screen.
const EXPORTS: [&str; 6] = ["exr", "nrrd", "vol", "vdb", "dds", "png"];

/// `OUTPUT/exports/`, made if missing: where `E` writes.
fn exports(output: &Path) -> Result<PathBuf> {
    let folder = output.join("exports");
    std::fs::create_dir_all(&folder).map_err(|e| Error::io(&folder, e))?;
    Ok(folder)
}

/// What an export wrote: the folder, the files written, and the formats that cannot hold
/// this volume with the reason.
type Exported = (String, Vec<String>, Vec<String>);

/// Writes `volume` in every format of [`EXPORTS`] that can hold it (the PNG as an atlas),
/// its contact sheet and its slice `index` across `axis` into the folder
/// `OUTPUT/exports/NAME/`, replaced as a whole (a folder there that holds files solidtex
/// did not write is refused).
fn export(output: &Path, name: &str, volume: &Volume, axis: Axis, index: usize) -> Result<Exported> {
    let folder = exports(output)?.join(name);
    let (mut written, mut skipped) = (Vec::new(), Vec::new());
    io::write_folder(&folder, |dir| {
        for ext in EXPORTS {
            let file = format!("{name}.{ext}");
            match io::write_volume(&dir.join(&file), volume) {
                Ok(()) => written.push(file),
                Err(Error::File { message, .. }) => skipped.push(format!("{file} ({message})")),
                Err(e) => return Err(e),
            }
        }
        let sheet = format!("{name}.sheet.png");
        io::write_rgb8(&dir.join(&sheet), &crate::render::sheet(volume, name))?;
        let slice = format!("{name}.slice-{axis}{index}.png");
        let image = volume.slice(axis, index)?;
        let picture = crate::render::picture(&image, crate::render::ColourMap::for_channels(volume.channels()), 1);
        io::write_rgb8(&dir.join(&slice), &picture)?;
        written.extend([sheet, slice]);
        Ok(())
    })?;
    Ok((folder.display().to_string(), written, skipped))
}

/// Writes the fill preview's cut across `axis` at `offset` as a 512² PNG into
/// `OUTPUT/exports/`, named after the exemplar and the plane; an existing file of that name
/// is never replaced: the first free `-2`, `-3` ... name is taken.
fn export_cut(output: &Path, name: &str, filled: &FillPreview, axis: Axis, offset: f32) -> Result<Exported> {
    let folder = exports(output)?;
    let file = free_name(&folder, &format!("{name}.fill-cut-{axis}{offset:+.2}"), "png");
    let cut = view_edit::cut_of(filled, axis, offset, 512)?;
    io::write_rgb8(&folder.join(&file), &cut.picture())?;
    Ok((folder.display().to_string(), vec![file], Vec::new()))
}

/// Writes the 3D view of `subject` as `view.html` in `OUTPUT/exports/NAME.view/` (a fill's
/// in `NAME.fill-view/`), a folder solidtex replaces only as a whole and only while it holds
/// just what solidtex wrote there, and opens it in `browser` (`$BROWSER`) or `xdg-open`:
/// what to tell.
fn web_view(output: &Path, name: &str, subject: &message::WebSubject, browser: Option<&str>) -> Result<String> {
    let (folder, page) = match subject {
        message::WebSubject::Volume(volume) => (format!("{name}.view"), io::web::preview_page(name, volume)?),
        message::WebSubject::Fill(filled) => {
            let model = [(name, &filled.0.model, &filled.0.textures)];
            let budget = io::budget_from_env()?;
            (format!("{name}.fill-view"), io::web::fill_page(name, &model, io::web::FILL_RES, budget)?.0)
        }
    };
    let folder = exports(output)?.join(folder);
    io::write_folder(&folder, |dir| io::write_bytes(&dir.join("view.html"), page.as_bytes()))?;
    let path = folder.join("view.html");
    Ok(match open_in_browser(&path, browser) {
        Some(program) => format!("wrote {}; opened it with {program}", path.display()),
        None => format!("wrote {}; open it in a browser (no $BROWSER or xdg-open here)", path.display()),
    })
}

/// Hands `path` to `browser` (a command; `%s` stands for the path, else it comes last) or
/// else to `xdg-open`, detached and silent: the program that started, if one did.
fn open_in_browser(path: &Path, browser: Option<&str>) -> Option<String> {
    let given = browser.and_then(|b| b.split(':').next()).filter(|b| !b.trim().is_empty());
    for command in given.into_iter().chain(["xdg-open"]) {
        let mut words = command.split_whitespace();
        let program = words.next()?;
        let mut args: Vec<std::ffi::OsString> =
            words.map(|w| w.replace("%s", &path.to_string_lossy()).into()).collect();
        if !command.contains("%s") {
            args.push(path.into());
        }
        let started = std::process::Command::new(program)
            .args(&args)
            .stdin(std::process::Stdio::null())
            .stdout(std::process::Stdio::null())
            .stderr(std::process::Stdio::null())
            .spawn();
        if let Ok(mut child) = started
            && !failed_at_once(&mut child)
        {
            std::thread::spawn(move || child.wait());
            return Some(program.to_string());
        }
    }
    None
}

/// Whether a program just started ended within a second with a failure (no browser
/// there, or it could not open the page); one still running or done well did not fail.
fn failed_at_once(child: &mut std::process::Child) -> bool {
    let started = std::time::Instant::now();
    while started.elapsed() < Duration::from_secs(1) {
        match child.try_wait() {
            Ok(Some(status)) => return !status.success(),
            Ok(None) => std::thread::sleep(Duration::from_millis(20)),
            Err(_) => return false,
        }
    }
    false
}

/// `STEM.EXT` in `folder`, or the first of `STEM-2.EXT`, `STEM-3.EXT` ... that is free: an
/// export never replaces a file.
fn free_name(folder: &Path, stem: &str, ext: &str) -> String {
    std::iter::once(format!("{stem}.{ext}"))
        .chain((2..).map(|k| format!("{stem}-{k}.{ext}")))
        .find(|f| !folder.join(f).exists())
        .expect("a free name")
}

/// Writes the fill spec placed in the fill preview and the drawn shape it fills into
/// `OUTPUT/exports/` as `NAME.fill.toml` and `NAME.fill-SHAPE.obj` (taking `-2`, `-3` ...
/// rather than replacing a file), the spec naming the shape's file in its header so
/// `solidtex fill` runs it from that folder.
fn write_spec(output: &Path, name: &str, spec: &crate::fill::spec::FillSpec, shape: &str) -> Result<Exported> {
    let folder = exports(output)?;
    let spec_file = free_name(&folder, &format!("{name}.fill"), "toml");
    let mesh_file = free_name(&folder, &format!("{name}.fill-{shape}"), "obj");
    let surface = crate::mesh::shapes::named(shape)
        .ok_or_else(|| Error::invalid(format!("no drawn shape named {shape}")))?
        .canonical();
    io::mesh_file::write_mesh(&folder.join(&mesh_file), &surface)?;
    let rel = |p: &Path| io::written_relative(p, &folder);
    let header = format!(
        "Placed in the solidtex terminal UI's fill preview of {name}. Run it from this folder:\n  solidtex fill {mesh_file} --spec {spec_file} -o {name}.lst"
    );
    let text = io::fill_spec::spec_text(spec, &rel(&spec.library), &rel(&spec.built), &header);
    io::write_bytes(&folder.join(&spec_file), text.as_bytes())?;
    Ok((folder.display().to_string(), vec![spec_file, mesh_file], Vec::new()))
}

/// Counts cancellations: a build stops when the count moves past the one it started with,
/// so a cancel stops the builds running then, not the ones started after it.
static CANCELS: AtomicU64 = AtomicU64::new(0);

/// One build at a time writes into the output folder; later ones wait their turn.
static BUILDING: Mutex<()> = Mutex::new(());

/// Build in this process on a worker thread; progress, level previews and warnings
/// become messages, and each entry's end becomes `Built` or `BuildCancelled`.
fn build(manifest: &Path, output: &Path, names: Vec<String>, send: &Sender<Message>) {
    let cancels = CANCELS.load(Ordering::SeqCst);
    let _turn = BUILDING.lock().unwrap_or_else(|e| e.into_inner());
    let _ = send.send(Message::BuildStarted(names.clone()));
    // The build before this one stays beside it until the designer accepts or discards it.
    let kept: Vec<String> =
        names.iter().filter(|n| library::previous::keep(output, n).unwrap_or(false)).cloned().collect();
    let request = library::Request {
        manifest: manifest.to_path_buf(),
        output: output.to_path_buf(),
        force: false,
        only: names.clone(),
        shard: None,
    };
    let observer = Messages { send: send.clone(), cancels, percent: Mutex::new(HashMap::new()) };
    let outcomes =
        library::build::select(&request).and_then(|entries| library::build::build(&request, &entries, &observer));
    let rebuilt =
        |n: &str| outcomes.as_ref().is_ok_and(|o| o.iter().any(|o| o.name() == n && matches!(o, Outcome::Built(_))));
    for name in kept.iter().filter(|n| !rebuilt(n)) {
        let _ = library::previous::drop_kept(output, name);
    }
    let (items, _) = load_items(manifest, output);
    let row = |name: &str| items.iter().find(|i| i.name == name).cloned();
    let messages: Vec<Message> = match outcomes {
        Ok(outcomes) => outcomes.iter().map(|o| finished(o, row(o.name()))).collect(),
        Err(e) => names.iter().map(|n| failed(n, &e.to_string(), row(n))).collect(),
    };
    for message in messages {
        let _ = send.send(message);
    }
}

/// The message for one finished entry, given its list row as the build left it.
fn finished(outcome: &Outcome, row: Option<Item>) -> Message {
    let name = outcome.name().to_string();
    match (outcome, row) {
        (Outcome::Cancelled(_), Some(row)) => Message::BuildCancelled(name, row),
        (Outcome::Built(_) | Outcome::Cached(_), Some(row)) => Message::Built(name, Ok(row)),
        (Outcome::Failed(_, why), row) => failed(&name, why, row),
        (_, None) => Message::Built(name, Err("the entry is no longer in the manifest".to_string())),
    }
}

/// The message for an entry whose build failed, given its row as the files on disk leave
/// it: an earlier build there stays openable.
fn failed(name: &str, why: &str, row: Option<Item>) -> Message {
    match row {
        Some(row) => {
            let older = matches!(row.state, BuildState::Built(_) | BuildState::Changed(..));
            Message::Built(name.to_string(), Ok(Item { state: BuildState::Failed(why.to_string(), older), ..row }))
        }
        None => Message::Built(name.to_string(), Err(why.to_string())),
    }
}

/// A build's observer that sends messages to the UI (progress at most once per percent).
struct Messages {
    send: Sender<Message>,
    cancels: u64,
    percent: Mutex<HashMap<String, i32>>,
}

impl Observer for Messages {
    fn progress(&self, name: &str, stage: &str, fraction: f32) {
        let percent = (fraction.clamp(0.0, 1.0) * 100.0) as i32;
        let mut last = self.percent.lock().unwrap_or_else(|e| e.into_inner());
        if last.insert(name.to_string(), percent) != Some(percent) {
            let _ = self.send.send(Message::BuildProgress(name.to_string(), stage.to_string(), fraction));
        }
    }

    fn warn(&self, name: &str, message: &str) {
        let _ = self.send.send(Message::BuildWarning(name.to_string(), message.to_string()));
    }

    fn level_done(&self, name: &str, level: usize, levels: usize, dims: [usize; 3], channels: usize, data: &[f32]) {
        let roles = if channels >= 3 { crate::Channel::rgb() } else { crate::Channel::grey() };
        let keep = roles.len();
        let samples: Vec<f32> = data.chunks_exact(channels).flat_map(|v| v[..keep].iter().copied()).collect();
        if let Ok(volume) = crate::Volume::from_data(dims, roles, samples) {
            let _ =
                self.send.send(Message::BuildPreview(name.to_string(), format!("{level}/{levels}"), Arc::new(volume)));
        }
    }

    fn cancelled(&self) -> bool {
        CANCELS.load(Ordering::SeqCst) != self.cancels
    }
}

/// The seed mesh for stamping into `name`: the mesh its steps already use, else the first
/// mesh file beside the manifest, else the built-in seed (which has no file).
fn find_seed(manifest: &Path, name: &str) -> Result<(Arc<crate::mesh::Mesh>, Option<String>)> {
    let folder = manifest.parent().unwrap_or(Path::new("."));
    let plan = io::manifest::read_plan(manifest)?;
    let used = plan.entries.iter().filter(|e| e.name == name).flat_map(|e| e.steps.iter()).find_map(|s| match s {
        io::manifest::Step::Stamp { mesh, .. } | io::manifest::Step::Scatter { mesh, .. } => Some(mesh.clone()),
        _ => None,
    });
    let beside = || {
        let mut files: Vec<PathBuf> =
            std::fs::read_dir(folder).ok()?.filter_map(|e| e.ok().map(|e| e.path())).collect();
        files.sort();
        files.into_iter().find(|p| matches!(p.extension().and_then(|e| e.to_str()), Some("obj" | "stl" | "ply")))
    };
    match used.or_else(beside) {
        Some(path) => {
            let mesh = io::mesh_file::read_mesh(&path)?;
            let relative = path.strip_prefix(folder).unwrap_or(&path).to_string_lossy().into_owned();
            Ok((Arc::new(mesh), Some(relative)))
        }
        None => Ok((Arc::new(crate::sections::seed_mesh(32, 32)?), None)),
    }
}

/// The seed mesh in `path`, and its path as the manifest's steps write it (relative to
/// the manifest's folder).
fn seed_file(manifest: &Path, path: &Path) -> Result<(Arc<crate::mesh::Mesh>, Option<String>)> {
    let mesh = io::mesh_file::read_mesh(path)?;
    Ok((Arc::new(mesh), Some(io::written_relative(path, &new_entry::manifest_folder(manifest)))))
}

/// Appends stamp steps to the manifest, checks it and writes it atomically.
fn save_steps(
    manifest: &Path,
    name: &str,
    steps: &[model::StampStep],
    file: &str,
) -> std::result::Result<String, String> {
    let text = read_manifest(manifest).map_err(|e| e.to_string())?;
    let text = edit::append_steps(&text, name, steps, file)?;
    let folder = manifest.parent().unwrap_or(Path::new("."));
    io::manifest::parse_entry(&text, folder, name).map_err(|e| e.to_string())?;
    write_manifest(manifest, &text).map_err(|e| e.to_string())?;
    Ok(text)
}

/// The built masks of `name`: `NAME.mask.exr` and `NAME.masks/{outer,middle,inner}.exr`.
fn load_masks(output: &Path, name: &str) -> std::result::Result<Vec<(String, Arc<crate::volume::Volume>)>, String> {
    let budget = io::budget_from_env().unwrap_or(u64::MAX);
    let mut files = vec![("splotch mask".to_string(), library::files::splotch_mask(output, name))];
    for layer in crate::mask::Layer::ALL {
        files.push((format!("{} mask", layer.name()), library::files::layer_mask(output, name, layer)));
    }
    files
        .into_iter()
        .filter(|(_, f)| f.exists())
        .map(|(label, f)| io::read_volume(&f, budget).map(|v| (label, Arc::new(v))).map_err(|e| e.to_string()))
        .collect()
}

#[cfg(test)]
mod tests {
    use super::{
        BuildState, Effect, EntryChange, Message, change_entry, finished, list_folder, load_items, message, new_entry,
        photos_of, read_only, save_as, save_editor, settle, side_of, update,
    };

    /// `E` on the slices writes every format, the contact sheet and the slice on screen
    /// into OUTPUT/exports/NAME/, replacing its own export; a folder there holding a file
    /// solidtex did not write is refused, and that file stays.
    #[test]
    fn w_writes_the_3d_view_and_hands_it_to_the_browser() {
        use crate::tui::model::{ExemplarView, Model, Screen};
        use crate::volume::{Channel, Volume};
        let dir = tempfile::tempdir().unwrap();
        let volume = Volume::from_fn([6, 5, 4], Channel::rgb(), |x, _, _, o| o.fill(x as f32 / 5.0)).unwrap();
        let mut m = Model::new(dir.path().join("lib.toml"), dir.path().join("out"), Vec::new(), Vec::new());
        let mut view = ExemplarView::new("ramp");
        m.screen = Screen::Exemplar(view.clone());
        assert!(update(&mut m, Message::WebView).is_empty() && m.status.contains("loading"), "{}", m.status);
        view.volume = Some(std::sync::Arc::new(volume));
        m.screen = Screen::Exemplar(view);
        let effects = update(&mut m, Message::WebView);
        let [Effect::WebView(name, subject)] = &effects[..] else { panic!("{effects:?}") };
        let page = m.output.join("exports/ramp.view/view.html");
        let told = super::web_view(&m.output, name, subject, Some("true")).unwrap();
        assert!(told.contains(&page.display().to_string()) && told.contains("opened it with true"), "{told}");
        let text = std::fs::read_to_string(&page).unwrap();
        assert!(text.starts_with("<!doctype html>") && text.contains("\"dims\":[6,5,4]"));
        let told = super::web_view(&m.output, name, subject, Some("no-such-browser-here")).unwrap();
        assert!(told.contains("opened it with xdg-open") || told.contains("open it in a browser"), "{told}");
        let told = super::web_view(&m.output, name, subject, Some("false")).unwrap();
        assert!(!told.contains("opened it with false") && told.contains(&page.display().to_string()), "{told}");
        std::fs::write(page.with_file_name("notes.txt"), "mine").unwrap();
        let refused = super::web_view(&m.output, name, subject, Some("true")).unwrap_err().to_string();
        assert!(refused.contains("ramp.view"), "a folder holding a person's file is left alone: {refused}");
        assert_eq!(std::fs::read_to_string(page.with_file_name("notes.txt")).unwrap(), "mine");
    }

    #[test]
    fn e_exports_the_volume_in_every_format_beside_the_slice_on_screen() {
        use crate::tui::model::{ExemplarView, Model, Screen};
        use crate::volume::{Axis, Channel, Volume};
        let dir = tempfile::tempdir().unwrap();
        let volume = Volume::from_fn([6, 5, 4], Channel::rgb(), |x, y, z, o| {
            o.copy_from_slice(&[x as f32 / 5.0, y as f32 / 4.0, z as f32 / 3.0])
        })
        .unwrap();
        let mut m = Model::new(dir.path().join("lib.toml"), dir.path().join("out"), Vec::new(), Vec::new());
        let mut view = ExemplarView::new("ramp");
        assert!(update(&mut m, Message::Export).is_empty(), "not on the slices");
        (view.axis, view.index) = (Axis::Y, [3, 2, 1]);
        m.screen = Screen::Exemplar(view.clone());
        assert!(update(&mut m, Message::Export).is_empty() && m.status.contains("loading"), "{}", m.status);
        view.volume = Some(std::sync::Arc::new(volume.clone()));
        m.screen = Screen::Exemplar(view);
        let effects = update(&mut m, Message::Export);
        let [Effect::Export(name, v, axis, index)] = &effects[..] else { panic!("{effects:?}") };
        assert_eq!((name.as_str(), *axis, *index), ("ramp", Axis::Y, 2));
        for _ in 0..2 {
            let exported = super::export(&m.output, name, v, *axis, *index).unwrap();
            update(&mut m, Message::Exported(Ok(exported)));
        }
        assert!(
            m.status.contains("exported 7 files: ")
                && m.status.contains("ramp.slice-y2.png")
                && m.status.contains(" into "),
            "{}",
            m.status
        );
        assert!(m.status.contains("not ramp.vol (") && m.status.contains("cubes only"), "{}", m.status);
        let folder = m.output.join("exports/ramp");
        assert!(!folder.join("ramp.vol").exists());
        for ext in ["exr", "nrrd", "vdb", "dds", "png"] {
            let back = crate::io::read_volume(&folder.join(format!("ramp.{ext}")), u64::MAX).unwrap();
            assert_eq!(back.dims(), [6, 5, 4], "{ext}");
        }
        let slice = image::open(folder.join("ramp.slice-y2.png")).unwrap();
        assert_eq!((slice.width(), slice.height()), (6, 4), "an x-z slice");
        std::fs::write(folder.join("notes.txt"), "mine").unwrap();
        let refused = super::export(&m.output, "ramp", &volume, Axis::Z, 0).unwrap_err().to_string();
        assert!(refused.contains("exports/ramp"), "{refused}");
        assert_eq!(std::fs::read_to_string(folder.join("notes.txt")).unwrap(), "mine");
    }

    /// A temporary copy of tests/manifests/two-broken.toml (valid a, b; broken1, broken2).
    fn two_broken() -> (tempfile::TempDir, std::path::PathBuf) {
        let dir = tempfile::tempdir().unwrap();
        let manifest = dir.path().join("lib.toml");
        let fixture = concat!(env!("CARGO_MANIFEST_DIR"), "/tests/manifests/two-broken.toml");
        std::fs::copy(fixture, &manifest).unwrap();
        (dir, manifest)
    }

    /// Broken entries are listed in manifest order (so they can be opened and fixed) with
    /// every error below; `B` builds the valid ones, `b` on a broken one says why not.
    #[test]
    fn broken_entries_are_listed_and_only_valid_ones_build() {
        let (dir, manifest) = two_broken();
        let (items, errors) = load_items(&manifest, &dir.path().join("out"));
        let names: Vec<&str> = items.iter().map(|i| i.name.as_str()).collect();
        assert_eq!(names, ["a", "broken1", "b", "broken2"]);
        assert!(matches!(&items[1].state, BuildState::Broken(e) if e.contains("size")), "{:?}", items[1].state);
        assert!(matches!(&items[3].state, BuildState::Broken(e) if e.contains("weave")), "{:?}", items[3].state);
        assert_eq!(errors.len(), 2, "{errors:?}");
        let mut m = super::Model::new(manifest, dir.path().join("out"), items, errors);
        assert_eq!(update(&mut m, Message::BuildAll), vec![Effect::Build(vec!["a".into(), "b".into()])]);
        let mut m = super::Model { selected: 3, ..m };
        m.items[3].state = BuildState::Broken("weave".into());
        assert!(update(&mut m, Message::Build).is_empty());
        assert!(m.status.contains("mistake") && m.status.contains("e opens it"), "{}", m.status);
        assert_eq!(update(&mut m, Message::Edit), vec![Effect::ReadManifest], "a broken entry opens in the editor");
    }

    /// Each finished entry becomes one message: a cancelled one keeps its row as the
    /// previous output left it, a failed one says why and whether its earlier build stays.
    #[test]
    fn each_outcome_becomes_its_message() {
        let row = super::Item {
            name: "m".into(),
            declared: None,
            size: Some([8; 3]),
            state: BuildState::Built("0".into()),
            quality: None,
            previous: false,
        };
        let cancelled = finished(&super::Outcome::Cancelled("m".into()), Some(row.clone()));
        assert!(matches!(cancelled, Message::BuildCancelled(n, r) if n == "m" && r == row));
        let failed = finished(&super::Outcome::Failed("m".into(), "no image".into()), Some(row.clone()));
        let kept = BuildState::Failed("no image".into(), true);
        assert!(matches!(failed, Message::Built(n, Ok(r)) if n == "m" && r.state == kept), "the earlier build stays");
        let never = super::Item { state: BuildState::NotBuilt, ..row };
        let failed = finished(&super::Outcome::Failed("m".into(), "no image".into()), Some(never));
        assert!(matches!(failed, Message::Built(_, Ok(r)) if r.state == BuildState::Failed("no image".into(), false)));
    }

    /// A photo that would decode past the memory budget (a 32,000² 1-bit PNG of 128 KB)
    /// fails its entry with the reason, in this process, and the other entry builds: the UI
    /// is never taken down.
    #[test]
    fn a_decompression_bomb_fails_its_entry_not_the_ui() {
        let dir = tempfile::tempdir().unwrap();
        let bomb = dir.path().join("bomb.png");
        let mut encoder = png::Encoder::new(std::fs::File::create(&bomb).unwrap(), 32_000, 32_000);
        encoder.set_color(png::ColorType::Grayscale);
        encoder.set_depth(png::BitDepth::One);
        let mut writer = encoder.write_header().unwrap();
        let mut stream = writer.stream_writer().unwrap();
        for _ in 0..32_000 {
            std::io::Write::write_all(&mut stream, &[0u8; 4000]).unwrap();
        }
        stream.finish().unwrap();
        let (manifest, out) = (dir.path().join("lib.toml"), dir.path().join("out"));
        let text = "[[exemplar]]\nname = \"m\"\nrecipe = \"procedural:marble\"\nsize = 8\n\
                    [[exemplar]]\nname = \"boom\"\nrecipe = \"synth\"\nimage = \"bomb.png\"\nsize = 8\n";
        std::fs::write(&manifest, text).unwrap();
        let (send, receive) = std::sync::mpsc::channel();
        super::build(&manifest, &out, vec!["m".into(), "boom".into()], &send);
        drop(send);
        let built: Vec<Message> = receive.iter().filter(|m| matches!(m, Message::Built(..))).collect();
        assert!(built.iter().any(|m| matches!(m, Message::Built(n, Ok(_)) if n == "m")));
        let failed = built.iter().find_map(|m| match m {
            Message::Built(n, Ok(super::Item { state: BuildState::Failed(e, false), .. })) if n == "boom" => {
                Some(e.clone())
            }
            _ => None,
        });
        assert!(failed.as_deref().is_some_and(|e| e.contains("bomb.png") && e.contains("too large")), "{failed:?}");
    }

    /// `c` copies the selected entry into the manifest, `d` twice deletes it: the file keeps
    /// its comments and the other entries byte for byte, and the list follows.
    #[test]
    fn entries_are_copied_and_deleted_in_the_manifest() {
        let (dir, manifest) = two_broken();
        let original = std::fs::read_to_string(&manifest).unwrap();
        let out = dir.path().join("out");
        let (items, errors) = load_items(&manifest, &out);
        let mut m = super::Model::new(manifest.clone(), out.clone(), items, errors);
        let run = |m: &mut super::Model, message: Message| {
            for effect in update(m, message) {
                let Effect::ChangeEntry(change) = effect else { panic!("{effect:?}") };
                update(m, Message::EntriesChanged(change_entry(&manifest, &out, &change)));
            }
        };
        run(&mut m, Message::Duplicate);
        let names: Vec<&str> = m.items.iter().map(|i| i.name.as_str()).collect();
        assert_eq!(names, ["a", "a-2", "broken1", "b", "broken2"]);
        assert_eq!((m.selected, m.status.contains("copied a as a-2")), (1, true), "{}", m.status);
        // d asks; another key keeps the entry; d twice deletes the copy
        run(&mut m, Message::Delete);
        assert!(m.status.contains("d again deletes a-2"), "{}", m.status);
        run(&mut m, Message::Down);
        run(&mut m, Message::Up);
        run(&mut m, Message::Delete);
        assert_eq!(m.items.len(), 5, "the Down in between dropped the question");
        run(&mut m, Message::Delete);
        assert_eq!(m.items.len(), 4);
        assert_eq!(std::fs::read_to_string(&manifest).unwrap(), original, "copy then delete gives the file back");
        assert!(m.status.contains("deleted a-2") && m.status.contains("built files stay"), "{}", m.status);
        // r renames the selected entry; a taken name is refused with the reason
        let type_name = |m: &mut super::Model, name: &str| {
            run(m, Message::Rename);
            run(m, Message::Input(tui_input::InputRequest::DeleteLine));
            name.chars().for_each(|c| run(m, Message::Input(tui_input::InputRequest::InsertChar(c))));
            run(m, Message::Commit);
        };
        m.selected = 0;
        type_name(&mut m, "b");
        assert!(m.status.contains("already has an exemplar named \"b\""), "{}", m.status);
        assert_eq!(std::fs::read_to_string(&manifest).unwrap(), original);
        type_name(&mut m, "apple");
        assert_eq!(m.items[m.selected].name, "apple");
        assert!(m.status.contains("renamed a to apple"), "{}", m.status);
        assert!(std::fs::read_to_string(&manifest).unwrap().contains("name = \"apple\""));
        type_name(&mut m, "a");
        assert_eq!(std::fs::read_to_string(&manifest).unwrap(), original, "renaming back gives the file back");
        // esc drops the prompt and keeps the name
        run(&mut m, Message::Rename);
        run(&mut m, Message::Cancel);
        assert!(m.prompt.is_none() && m.status.contains("the name stays"));
    }

    /// An entry made from a photo in another folder is written with a relative path, the
    /// manifest checks it, and `p` finds the photo again; a file that is no image is
    /// refused and the manifest stays as it was.
    #[test]
    fn a_new_entry_from_a_photo_is_added_checked_and_compared() {
        let dir = tempfile::tempdir().unwrap();
        let (lib, photos) = (dir.path().join("lib"), dir.path().join("photos"));
        std::fs::create_dir_all(&lib).unwrap();
        std::fs::create_dir_all(photos.join("sub")).unwrap();
        let manifest = lib.join("library.toml");
        let original = "# mine\n\n[[exemplar]]\nname = \"m\"\nrecipe = \"procedural:marble\"\nsize = 8\n";
        std::fs::write(&manifest, original).unwrap();
        image::RgbImage::from_fn(40, 20, |x, _| image::Rgb([x as u8 * 6, 90, 30]))
            .save(photos.join("bark.png"))
            .unwrap();
        std::fs::write(photos.join("notes.png"), b"not a picture").unwrap();
        std::fs::write(photos.join("notes.txt"), b"text").unwrap();
        let (rows_dir, rows) = list_folder(&photos, new_entry::FileKind::Image).unwrap();
        let names: Vec<&str> = rows.iter().map(|r| r.name.as_str()).collect();
        assert_eq!((rows_dir, names), (photos.canonicalize().unwrap(), vec!["..", "sub", "bark.png", "notes.png"]));
        let bad = EntryChange::New("synth".into(), Some(photos.join("notes.png")));
        let e = change_entry(&manifest, &dir.path().join("out"), &bad).unwrap_err();
        assert!(e.contains("notes.png") && e.contains("decode"), "{e}");
        assert_eq!(std::fs::read_to_string(&manifest).unwrap(), original);
        let plain = EntryChange::New("load".into(), Some(photos.join("bark.png")));
        let e = change_entry(&manifest, &dir.path().join("out"), &plain).unwrap_err();
        assert!(e.contains("cannot load it as a volume"), "{e}");
        assert_eq!(std::fs::read_to_string(&manifest).unwrap(), original);
        let good = EntryChange::New("synth".into(), Some(photos.join("bark.png")));
        let message::Change { items, errors, select, status, .. } =
            change_entry(&manifest, &dir.path().join("out"), &good).unwrap();
        assert!(errors.is_empty() && select == "bark" && items.len() == 2, "{errors:?} {select}");
        assert!(status.contains("added bark (synth from"), "{status}");
        let text = std::fs::read_to_string(&manifest).unwrap();
        assert!(text.starts_with(original) && text.contains("image = \"../photos/bark.png\""), "{text}");
        let [x, y, z] = photos_of(&manifest, "bark").unwrap();
        assert_eq!([x.unwrap().width(), y.unwrap().height(), z.unwrap().width()], [40, 20, 40]);
        let e = photos_of(&manifest, "m").unwrap_err().to_string();
        assert!(e.contains("m is not made from an image"), "{e}");
    }

    /// A rebuild in the UI keeps the build before it: both can be read for comparing;
    /// discarding gives the previous build back (and the entry reads as changed, since its
    /// recipe is the new one), accepting drops the copy; an unchanged rebuild keeps none.
    #[test]
    fn a_rebuild_keeps_the_previous_build_until_it_is_settled() {
        let dir = tempfile::tempdir().unwrap();
        let (manifest, out) = (dir.path().join("lib.toml"), dir.path().join("out"));
        let text = "[[exemplar]]\nname = \"m\"\nrecipe = \"procedural:marble\"\nsize = 8\nseed = 1\n";
        std::fs::write(&manifest, text).unwrap();
        let (send, receive) = std::sync::mpsc::channel();
        super::build(&manifest, &out, vec!["m".into()], &send);
        super::build(&manifest, &out, vec!["m".into()], &send);
        assert!(!load_items(&manifest, &out).0[0].previous, "an up-to-date entry keeps no copy");
        std::fs::write(&manifest, text.replace("seed = 1", "seed = 2")).unwrap();
        super::build(&manifest, &out, vec!["m".into()], &send);
        drop(send);
        let built: Vec<Message> = receive.iter().filter(|m| matches!(m, Message::Built(..))).collect();
        assert_eq!(built.len(), 3);
        let (items, _) = load_items(&manifest, &out);
        assert!(items[0].previous && matches!(items[0].state, BuildState::Built(_)));
        let (before, _) = side_of(&out, "m", true).unwrap();
        let (after, _) = side_of(&out, "m", false).unwrap();
        assert_ne!(before.data(), after.data(), "seed 1 beside seed 2");
        let message::Change { items, select, status, .. } = settle(&manifest, &out, "m", false).unwrap();
        assert!(select == "m" && status.contains("previous build again"), "{status}");
        assert!(!items[0].previous && matches!(items[0].state, BuildState::Changed(..)), "{:?}", items[0]);
        assert_eq!(side_of(&out, "m", false).unwrap().0.data(), before.data());
        assert!(side_of(&out, "m", true).unwrap_err().to_string().contains("no previous build of m"));
        super::build(&manifest, &out, vec!["m".into()], &std::sync::mpsc::channel().0);
        let message::Change { items, status, .. } = settle(&manifest, &out, "m", true).unwrap();
        assert!(!items[0].previous && status.contains("kept the new build"), "{status}");
        assert_eq!(side_of(&out, "m", false).unwrap().0.data(), after.data());
        // a kept copy goes with its entry when the entry is renamed
        std::fs::write(&manifest, text.replace("seed = 1", "seed = 3")).unwrap();
        super::build(&manifest, &out, vec!["m".into()], &std::sync::mpsc::channel().0);
        assert!(load_items(&manifest, &out).0[0].previous);
        let items = change_entry(&manifest, &out, &EntryChange::Rename("m".into(), "n".into())).unwrap().items;
        assert!(!items[0].previous && !crate::library::previous::folder(&out, "m").exists());
    }

    /// `w` in the fill preview writes a spec `solidtex fill` reads back (its library and
    /// build folder found from the exports folder) beside the shape; a second write never
    /// replaces the first.
    #[test]
    fn the_fill_spec_placed_in_the_preview_is_written_beside_its_shape() {
        let dir = tempfile::tempdir().unwrap();
        let (manifest, out) = (dir.path().join("lib").join("library.toml"), dir.path().join("out"));
        std::fs::create_dir_all(manifest.parent().unwrap()).unwrap();
        std::fs::write(&manifest, "").unwrap();
        let mut spec = crate::fill::spec::FillSpec::new("kiwi");
        (spec.library, spec.built) = (manifest.clone(), out.clone());
        spec.depth.points = vec![(glam::Vec3::new(0.1, 0.2, 0.0), 0.5)];
        let (folder, files, _) = super::write_spec(&out, "kiwi", &spec, "fruit").unwrap();
        assert_eq!(files, ["kiwi.fill.toml", "kiwi.fill-fruit.obj"]);
        let exports = std::path::PathBuf::from(folder);
        let back = crate::io::fill_spec::read_fill_spec(&exports.join("kiwi.fill.toml")).unwrap();
        assert_eq!(back.depth.points, spec.depth.points);
        assert_eq!(back.library.canonicalize().unwrap(), manifest.canonicalize().unwrap());
        assert_eq!(back.built.canonicalize().unwrap(), out.canonicalize().unwrap());
        let shape = crate::io::mesh_file::read_mesh(&exports.join("kiwi.fill-fruit.obj")).unwrap();
        assert!(shape.triangles.len() > 100);
        let (_, again, _) = super::write_spec(&out, "kiwi", &spec, "fruit").unwrap();
        assert_eq!(again, ["kiwi.fill-2.toml", "kiwi.fill-fruit-2.obj"]);
    }
    /// Each library operation returns its inverse; applied to the manifest as it reads
    /// later, it undoes the operation and keeps an edit made outside meanwhile.
    #[test]
    fn library_operations_are_undone_onto_the_file_as_it_reads() {
        let (dir, manifest) = two_broken();
        let original = std::fs::read_to_string(&manifest).unwrap();
        let out = dir.path().join("out");
        let undo = |change: &EntryChange| change_entry(&manifest, &out, change).unwrap().inverse.unwrap();
        for change in [
            EntryChange::Delete("b".into()),
            EntryChange::Delete("a".into()),
            EntryChange::Duplicate("a".into()),
            EntryChange::Rename("a".into(), "apple".into()),
        ] {
            let (inverse, what) = undo(&change);
            undo(&inverse);
            assert_eq!(std::fs::read_to_string(&manifest).unwrap(), original, "{what} undone byte for byte");
            let (inverse, what) = undo(&change);
            let outside = std::fs::read_to_string(&manifest).unwrap() + "# noted outside\n";
            std::fs::write(&manifest, &outside).unwrap();
            change_entry(&manifest, &out, &inverse).unwrap();
            let back = std::fs::read_to_string(&manifest).unwrap();
            assert_eq!(back, original.clone() + "# noted outside\n", "{what}");
            std::fs::write(&manifest, &original).unwrap();
        }
    }

    /// A save onto a manifest that no longer reads as TOML (a half-typed entry outside) is
    /// refused with where the file breaks, and the file is left as it is: applied to it,
    /// the edit found no entry of its name and added a second one.
    #[test]
    fn a_save_onto_a_manifest_that_does_not_read_is_refused() {
        let (dir, manifest) = two_broken();
        let original = std::fs::read_to_string(&manifest).unwrap();
        let broken = format!("{original}\n[[exemplar]]\nname = \"new-one\n");
        std::fs::write(&manifest, &broken).unwrap();
        let e = save_editor(&manifest, "a", &original, &original.replace("size = 8", "size = 9"));
        assert!(matches!(&e, Message::Saved(Err(e)) if e.contains("does not read") && e.contains("line")), "{e:?}");
        assert_eq!(std::fs::read_to_string(&manifest).unwrap(), broken);
        drop(dir);
    }

    /// A read-only manifest is flagged, never written (its edits are refused with the
    /// reason), and can be saved as a new file beside it, never over an existing one.
    #[test]
    fn a_read_only_manifest_is_flagged_and_saved_under_another_name() {
        use std::os::unix::fs::PermissionsExt;
        let (dir, manifest) = two_broken();
        let original = std::fs::read_to_string(&manifest).unwrap();
        std::fs::set_permissions(&manifest, std::fs::Permissions::from_mode(0o444)).unwrap();
        let notes = read_only(&manifest, &dir.path().join("out"));
        assert!(notes.len() == 1 && notes[0].contains("is read-only"), "{notes:?}");
        let e = change_entry(&manifest, &dir.path().join("out"), &EntryChange::Delete("a".into())).unwrap_err();
        assert!(e.contains("is read-only") && e.contains("another name"), "{e}");
        let e = save_editor(&manifest, "a", &original, &original.replace("size = 8", "size = 9"));
        assert!(matches!(&e, Message::Saved(Err(e)) if e.contains("is read-only")), "{e:?}");
        assert_eq!(std::fs::read_to_string(&manifest).unwrap(), original);
        let copy = dir.path().join("lib-2.toml");
        save_as(&manifest, &copy, "[[exemplar]]\n").unwrap();
        assert_eq!(std::fs::read_to_string(&copy).unwrap(), "[[exemplar]]\n");
        assert!(save_as(&manifest, &copy, "x").unwrap_err().to_string().contains("never replaces"));
        let elsewhere = tempfile::tempdir().unwrap();
        let e = save_as(&manifest, &elsewhere.path().join("lib.toml"), "x").unwrap_err().to_string();
        assert!(e.contains("beside the manifest"), "{e}");
    }
}
