//! `update` for the recipe editor and the fill preview. Pure: every change to the manifest
//! text is validated with the manifest parser before it is kept, and saving, previewing and
//! filling are effects run by workers.

use super::edit;
use super::message::Effect;
use super::model::{Editor, FillView, Model, Screen};
use crate::io::manifest;
use crate::volume::Axis;
use std::path::Path;

/// Open the editor on the selected exemplar; the text arrives with `EditorReady`.
pub fn open_editor(model: &mut Model) -> Vec<Effect> {
    let Some(item) = model.items.get(model.selected) else { return Vec::new() };
    model.screen = Screen::Editor(Editor { name: item.name.clone(), ..Editor::default() });
    model.status = format!("editing {}: enter edits a value, s saves, u undoes, r redoes", item.name);
    vec![Effect::ReadManifest]
}

/// The manifest text arrived: the first time, or again after Ctrl-R (then the editor's
/// edits of its entry are applied to the new text, or the designer chooses).
pub fn editor_ready(model: &mut Model, result: Result<String, String>) -> Vec<Effect> {
    let Screen::Editor(editor) = &mut model.screen else { return Vec::new() };
    match result {
        Ok(theirs) if editor.text.is_some() => {
            model.outside = false;
            rebased(model, theirs, false)
        }
        Ok(text) => {
            model.outside = false;
            let folder = model.manifest.parent().unwrap_or(Path::new(".")).to_path_buf();
            if let Err(e) = check(&text, &folder, &editor.name) {
                model.status = format!("{} has a mistake: {e}", editor.name);
            }
            editor.saved = text.clone();
            editor.text = Some(text);
            preview(editor)
        }
        Err(e) => {
            model.status = format!("cannot edit: {e}");
            model.screen = Screen::Library;
            Vec::new()
        }
    }
}

fn preview(editor: &mut Editor) -> Vec<Effect> {
    let Some(text) = &editor.text else { return Vec::new() };
    editor.generation += 1;
    editor.previewing = true;
    vec![Effect::Preview { name: editor.name.clone(), text: text.clone(), generation: editor.generation }]
}

/// Enter: start editing the selected value, or commit the typed one.
pub fn commit(model: &mut Model) -> Vec<Effect> {
    let folder = model.manifest.parent().unwrap_or(Path::new(".")).to_path_buf();
    let Screen::Editor(editor) = &mut model.screen else { return Vec::new() };
    let Some(text) = editor.text.clone() else { return Vec::new() };
    let fields = edit::fields(&text, &editor.name).unwrap_or_default();
    let Some(field) = fields.get(editor.selected) else { return Vec::new() };
    let Some(input) = editor.input.as_ref().map(|i| i.value().to_string()) else {
        editor.input = Some(field.value.as_str().into());
        editor.error = None;
        return Vec::new();
    };
    if field.key == "name" {
        editor.error = Some("the name is the exemplar's identity: rename it in the file".into());
        return Vec::new();
    }
    let edited = edit::set(&text, &editor.name, &field.key, &input);
    keep(model, &folder, edited, format!("{} = {input}; previewing", field.key))
}

/// Keeps an edit of the editor's text (for undo, then previewed) when the manifest parser
/// accepts the entry after it. A valid entry keeps only edits that leave it valid; an entry
/// that already has a mistake keeps every well-formed edit, so its mistakes can be fixed one
/// at a time. Otherwise the reason shows under the fields.
fn keep(model: &mut Model, folder: &Path, edited: Result<String, String>, status: String) -> Vec<Effect> {
    let Screen::Editor(editor) = &mut model.screen else { return Vec::new() };
    let Some(text) = editor.text.clone() else { return Vec::new() };
    let name = editor.name.clone();
    let verdict = edited.map(|t| {
        let still = check(&t, folder, &name).err();
        (t, still)
    });
    match verdict {
        Ok((new_text, still)) if still.is_none() || check(&text, folder, &name).is_err() => {
            editor.undo.push(text);
            editor.redo.clear();
            editor.text = Some(new_text);
            editor.input = None;
            editor.error = still.map(|e| format!("kept; the entry still has a mistake: {e}"));
            model.status = status;
            let Screen::Editor(editor) = &mut model.screen else { return Vec::new() };
            preview(editor)
        }
        Ok((_, still)) => {
            editor.error = still;
            Vec::new()
        }
        Err(e) => {
            editor.error = Some(e);
            Vec::new()
        }
    }
}

/// `a` appends a blur step at the centre of the entry's volume (radius an eighth of its
/// smallest side) and selects it, for `Enter` to place and size it.
pub fn add_blur(model: &mut Model) -> Vec<Effect> {
    let folder = model.manifest.parent().unwrap_or(Path::new(".")).to_path_buf();
    let Screen::Editor(editor) = &mut model.screen else { return Vec::new() };
    let Some(text) = editor.text.clone() else { return Vec::new() };
    let fields = edit::fields(&text, &editor.name).unwrap_or_default();
    let size = fields.iter().find(|f| f.key == "size").map(|f| sides(&f.value)).unwrap_or_default();
    let Some(size) = size else {
        model.status = "the entry has no size to centre a blur on: add the step in the file".into();
        return Vec::new();
    };
    let at = size.map(|s| (s / 2.0).floor());
    let radius = (size.iter().copied().fold(f32::INFINITY, f32::min) / 8.0).round().max(1.0);
    let name = editor.name.clone();
    let status = format!("added a blur at {},{},{} radius {radius}; previewing", at[0], at[1], at[2]);
    let effects = keep(model, &folder, edit::append_blur(&text, &name, at, radius), status);
    reselect(model, |fields, _| fields.len().saturating_sub(2));
    effects
}

/// The mesh of a new stamp or scatter step arrived (as the manifest names it): the step is
/// appended, a stamp at the volume's centre, a scatter of ten seeds, checked and previewed.
pub fn add_mesh_step(model: &mut Model, mesh: Result<String, String>, stamp: bool) -> Vec<Effect> {
    let folder = model.manifest.parent().unwrap_or(Path::new(".")).to_path_buf();
    let Screen::Editor(editor) = &mut model.screen else { return Vec::new() };
    let Some(text) = editor.text.clone() else { return Vec::new() };
    let mesh = match mesh {
        Ok(mesh) => mesh,
        Err(e) => {
            model.status = format!("no step added: {e}");
            return Vec::new();
        }
    };
    let fields = edit::fields(&text, &editor.name).unwrap_or_default();
    let Some(size) = fields.iter().find(|f| f.key == "size").and_then(|f| sides(&f.value)) else {
        model.status = "the entry has no size to place the step in: add the step in the file".into();
        return Vec::new();
    };
    let smallest = size.iter().copied().fold(f32::INFINITY, f32::min);
    let step = if stamp {
        let at = glam::Vec3::from(size.map(|s| (s / 2.0).floor()));
        let scale = glam::Vec3::splat((smallest / 10.0).max(1.0));
        super::model::StampStep::Stamp(crate::stamp::Placement { at, rotation: glam::Quat::IDENTITY, scale })
    } else {
        super::model::StampStep::Scatter {
            count: 10,
            scale: ((smallest / 20.0).max(1.0), (smallest / 12.0).max(1.5)),
            seed: 1,
        }
    };
    let name = editor.name.clone();
    let what = if stamp { "a stamp" } else { "a scatter of 10" };
    let status = format!("added {what} of {mesh}; previewing");
    let effects = keep(model, &folder, edit::append_steps(&text, &name, &[step], &mesh), status);
    reselect(model, |fields, _| fields.len().saturating_sub(1));
    effects
}

/// After a kept edit, selects the field `pick` chooses from the new fields and the old
/// selection (clamped to the list).
fn reselect(model: &mut Model, pick: impl FnOnce(&[edit::Field], usize) -> usize) {
    if let Screen::Editor(editor) = &mut model.screen
        && editor.error.is_none()
        && let Some(t) = &editor.text
    {
        let fields = edit::fields(t, &editor.name).unwrap_or_default();
        editor.selected = pick(&fields, editor.selected).min(fields.len().saturating_sub(1));
    }
}

/// The sides of a `size` value: `64` or `[64, 64, 128]`.
fn sides(value: &str) -> Option<[f32; 3]> {
    let numbers: Vec<f32> = value
        .trim_matches(['[', ']', ' '])
        .split(',')
        .map(|n| n.trim().parse::<f32>())
        .collect::<Result<_, _>>()
        .ok()?;
    match numbers.as_slice() {
        [s] => Some([*s; 3]),
        [x, y, z] => Some([*x, *y, *z]),
        _ => None,
    }
}

/// `x` removes the step the selected field belongs to; `K` / `J` (`earlier` or not) move
/// it before the previous step or after the next, the selection following it.
pub fn step(model: &mut Model, remove: bool, earlier: bool) -> Vec<Effect> {
    let folder = model.manifest.parent().unwrap_or(Path::new(".")).to_path_buf();
    let Screen::Editor(editor) = &mut model.screen else { return Vec::new() };
    let Some(text) = editor.text.clone() else { return Vec::new() };
    let fields = edit::fields(&text, &editor.name).unwrap_or_default();
    let Some(index) = fields.get(editor.selected).and_then(|f| edit::step_of(&f.key)) else {
        model.status = "select a field of a step (steps[i].…) first".into();
        return Vec::new();
    };
    let name = editor.name.clone();
    if remove {
        return keep(
            model,
            &folder,
            edit::remove_step(&text, &name, index),
            format!("removed step {}; previewing", index + 1),
        );
    }
    let moved = edit::move_step(&text, &name, index, earlier);
    let to = moved.as_ref().map(|m| m.1).unwrap_or(index);
    let offset = fields[editor.selected..].iter().take_while(|f| edit::step_of(&f.key) == Some(index)).count();
    let effects =
        keep(model, &folder, moved.map(|m| m.0), format!("moved step {} to {}; previewing", index + 1, to + 1));
    // the same field of the moved step stays selected
    reselect(model, |fields, selected| {
        let end = fields.iter().rposition(|f| edit::step_of(&f.key) == Some(to)).map_or(selected, |e| e + 1);
        end.saturating_sub(offset)
    });
    effects
}

/// The entry's recipe and the fields it can add (the manifest's table of fields, less
/// those set).
fn addable(text: &str, name: &str) -> (String, Vec<manifest::FieldRule>) {
    let fields = edit::fields(text, name).unwrap_or_default();
    let recipe = recipe_of(&fields);
    let mut rules = manifest::fields_of(&recipe);
    rules.retain(|r| !fields.iter().any(|f| f.key == r.key));
    rules.dedup_by(|a, b| a.key == b.key);
    (recipe, rules)
}

/// The entry's recipe, as its `recipe` field reads (without quotes).
fn recipe_of(fields: &[edit::Field]) -> String {
    fields.iter().find(|f| f.key == "recipe").map_or(String::new(), |f| f.value.trim_matches('"').to_string())
}

/// `+`: the picker of fields the entry's recipe takes and it does not set.
pub fn pick_field(model: &mut Model) {
    let Screen::Editor(editor) = &mut model.screen else { return };
    let Some(text) = &editor.text else { return };
    let (recipe, rules) = addable(text, &editor.name);
    if rules.is_empty() {
        model.status = format!("{} sets every field recipe {recipe:?} takes", editor.name);
        return;
    }
    editor.picker = Some(0);
    model.status = "choose a field to add: enter adds it with the value shown, esc closes".into();
}

/// The picker's rows (key, what it allows, the value it starts with), for the view.
pub fn picker_rows(editor: &Editor) -> Vec<manifest::FieldRule> {
    editor.text.as_deref().map(|t| addable(t, &editor.name).1).unwrap_or_default()
}

/// Move the picker's choice by `rows`.
pub fn picker_move(model: &mut Model, rows: i64) {
    let Screen::Editor(editor) = &mut model.screen else { return };
    let count = picker_rows(editor).len() as i64;
    if let Some(row) = &mut editor.picker {
        *row = (*row as i64).saturating_add(rows).clamp(0, (count - 1).max(0)) as usize;
    }
}

/// Enter in the picker: the chosen field is added with its start value (a file field starts
/// as the entry's image), selected, and its value opened for typing.
pub fn picker_add(model: &mut Model) -> Vec<Effect> {
    let folder = model.manifest.parent().unwrap_or(Path::new(".")).to_path_buf();
    let Screen::Editor(editor) = &mut model.screen else { return Vec::new() };
    let (Some(row), Some(text)) = (editor.picker.take(), editor.text.clone()) else { return Vec::new() };
    let Some(rule) = picker_rows(editor).into_iter().nth(row) else { return Vec::new() };
    let image = edit::fields(&text, &editor.name).unwrap_or_default().into_iter().find(|f| f.key == "image");
    let start = match image {
        Some(image) if rule.start == "\"\"" => image.value,
        _ => rule.start.clone(),
    };
    let name = editor.name.clone();
    let effects =
        keep(model, &folder, edit::set(&text, &name, rule.key, &start), format!("added {} = {start}", rule.key));
    let Screen::Editor(editor) = &mut model.screen else { return effects };
    let fields = editor.text.as_deref().map(|t| edit::fields(t, &name).unwrap_or_default()).unwrap_or_default();
    if let Some(at) = fields.iter().position(|f| f.key == rule.key) {
        editor.selected = at;
        editor.input = Some(fields[at].value.as_str().into());
        model.status = format!("{} = {start} added: type its value ({}), enter keeps it", rule.key, rule.allowed);
    }
    effects
}

/// `-`: remove the selected field, unless the entry needs it.
pub fn remove_field(model: &mut Model) -> Vec<Effect> {
    let folder = model.manifest.parent().unwrap_or(Path::new(".")).to_path_buf();
    let Screen::Editor(editor) = &mut model.screen else { return Vec::new() };
    let Some(text) = editor.text.clone() else { return Vec::new() };
    let fields = edit::fields(&text, &editor.name).unwrap_or_default();
    let Some(field) = fields.get(editor.selected) else { return Vec::new() };
    let needed = manifest::fields_of(&recipe_of(&fields)).into_iter().any(|r| r.key == field.key && r.required);
    let refusal = match field.key.as_str() {
        "name" | "recipe" => Some("the name and the recipe make the entry (d on the library deletes it)".to_string()),
        key if edit::step_of(key).is_some() => Some("a step's fields go with their step: x removes the step".into()),
        key if needed => Some(format!("{key} is needed by this recipe: change its value instead")),
        _ => None,
    };
    if let Some(why) = refusal {
        model.status = why;
        return Vec::new();
    }
    let (name, key) = (editor.name.clone(), field.key.clone());
    let effects = keep(model, &folder, edit::unset(&text, &name, &key), format!("removed {key}; previewing"));
    if let Screen::Editor(editor) = &mut model.screen {
        editor.selected = editor.selected.min(fields.len().saturating_sub(2));
    }
    effects
}

/// `o`: the manifest in an outside editor at the entry's line, once the editor's edits are
/// saved (it opens the file as it is on disk).
pub fn outside(model: &mut Model) -> Vec<Effect> {
    let Screen::Editor(editor) = &model.screen else { return Vec::new() };
    let Some(text) = &editor.text else { return Vec::new() };
    if *text != editor.saved {
        model.status = "save your edits first (s): the outside editor opens the file as it is on disk".into();
        return Vec::new();
    }
    vec![Effect::EditOutside(edit::line_of(text, &editor.name))]
}

/// Back from the outside editor: the manifest is read again, checked, and the list too.
pub fn outside_edited(model: &mut Model, result: Result<(), String>) -> Vec<Effect> {
    let Screen::Editor(editor) = &mut model.screen else { return Vec::new() };
    editor.text = None;
    editor.undo.clear();
    editor.redo.clear();
    let name = editor.name.clone();
    model.status = match result {
        Ok(()) => format!("read the manifest as the outside editor left it ({name})"),
        Err(e) => e,
    };
    vec![Effect::ReadManifest, Effect::Reload(name)]
}

/// The manifest parser's verdict on entry `name` of `text` (other entries' mistakes are
/// theirs: they do not block editing this one).
fn check(text: &str, folder: &Path, name: &str) -> Result<(), String> {
    manifest::parse_entry(text, folder, name).map(|_| ()).map_err(|e| e.to_string())
}

/// Editing the value being typed.
pub fn input(model: &mut Model, request: tui_input::InputRequest) {
    if let Screen::Editor(Editor { input: Some(value), .. }) = &mut model.screen {
        value.handle(request);
    }
}

/// Esc while typing: drop the value. Returns false when there was nothing to cancel.
pub fn cancel(model: &mut Model) -> bool {
    match &mut model.screen {
        Screen::Editor(editor) if editor.conflict.is_some() => {
            editor.conflict = None;
            model.status = "not saved: the entry differs on disk (s asks again, Ctrl-R reads the file)".into();
            true
        }
        Screen::Editor(editor) if editor.input.is_some() || editor.error.is_some() => {
            editor.input = None;
            editor.error = None;
            true
        }
        _ => false,
    }
}

/// Undo (or redo, with `redo`) one edit.
pub fn undo(model: &mut Model, redo: bool) -> Vec<Effect> {
    let Screen::Editor(editor) = &mut model.screen else { return Vec::new() };
    let Some(current) = editor.text.clone() else { return Vec::new() };
    let (from, to) = if redo { (&mut editor.redo, &mut editor.undo) } else { (&mut editor.undo, &mut editor.redo) };
    let Some(previous) = from.pop() else {
        model.status = format!("nothing to {}", if redo { "redo" } else { "undo" });
        return Vec::new();
    };
    to.push(current);
    editor.text = Some(previous);
    editor.input = None;
    model.status = if redo { "redone".into() } else { "undone".into() };
    let Screen::Editor(editor) = &mut model.screen else { return Vec::new() };
    preview(editor)
}

/// Save the edited text (the worker applies it to the manifest as it reads then).
pub fn save(model: &mut Model) -> Vec<Effect> {
    let Screen::Editor(editor) = &model.screen else { return Vec::new() };
    match &editor.text {
        Some(text) if *text != editor.saved => {
            vec![Effect::Save { name: editor.name.clone(), base: editor.saved.clone(), text: text.clone() }]
        }
        _ => {
            model.status = "nothing to save".into();
            Vec::new()
        }
    }
}

/// The editor's text becomes `theirs` (the manifest as it reads now) with the editor's
/// entry in it; undo and redo follow onto it. After a save, `theirs` is what was written.
fn onto(editor: &mut Editor, theirs: &str, mine: String) {
    let follow = |texts: &mut Vec<String>| {
        *texts = texts.iter().filter_map(|t| edit::with_entry_of(t, theirs, &editor.name)).collect();
    };
    follow(&mut editor.undo);
    follow(&mut editor.redo);
    editor.text = Some(mine);
    editor.conflict = None;
}

/// The manifest read again (`saving`: by a save) is `theirs`: the editor's edits go onto
/// it, or the designer is asked when the entry changed there too.
fn rebased(model: &mut Model, theirs: String, saving: bool) -> Vec<Effect> {
    let Screen::Editor(editor) = &mut model.screen else { return Vec::new() };
    if let Err(e) = edit::readable(&theirs) {
        model.status = format!("the manifest on disk does not read ({e}); your edits are kept: fix the file, then s");
        return Vec::new();
    }
    let mine = editor.text.clone().unwrap_or_default();
    match edit::rebase(&editor.saved, &mine, &theirs, &editor.name) {
        Some(merged) => {
            onto(editor, &theirs, merged);
            editor.saved = theirs;
            model.status = "read the manifest again; your edits of this entry are kept (s saves them)".into();
            preview(editor)
        }
        None => {
            editor.conflict = Some(Box::new(super::model::Conflict { theirs, saving, both: false }));
            model.status = "changed on disk: m keeps yours, t takes the file's, b both".to_string();
            Vec::new()
        }
    }
}

/// A save found the entry changed on disk too.
pub fn save_conflict(model: &mut Model, theirs: String) -> Vec<Effect> {
    model.outside = false;
    rebased(model, theirs, true)
}

/// `m`, `t` or `b` while the entry conflicts: keep mine (saved at once when a save found
/// the conflict), take the file's (`u` brings mine back), or show both side by side.
pub fn resolve(model: &mut Model, choice: char) -> Vec<Effect> {
    let Screen::Editor(editor) = &mut model.screen else { return Vec::new() };
    let Some(conflict) = editor.conflict.as_mut() else { return Vec::new() };
    let mine = editor.text.clone().unwrap_or_default();
    let theirs = conflict.theirs.clone();
    match choice {
        'b' => {
            conflict.both = !conflict.both;
            return Vec::new();
        }
        'm' => {
            let saving = conflict.saving;
            let kept = edit::with_entry_of(&mine, &theirs, &editor.name).unwrap_or(mine);
            onto(editor, &theirs, kept.clone());
            editor.saved = theirs.clone();
            model.status = format!("kept your {}; the rest of the file is as it reads now", editor.name);
            if saving {
                return vec![Effect::Save { name: editor.name.clone(), base: theirs, text: kept }];
            }
        }
        't' => {
            let yours = edit::with_entry_of(&mine, &theirs, &editor.name);
            onto(editor, &theirs, theirs.clone());
            editor.undo.extend(yours);
            editor.redo.clear();
            editor.saved = theirs;
            model.status = format!("took the file's {}; u brings your version back", editor.name);
        }
        _ => return Vec::new(),
    }
    let Screen::Editor(editor) = &mut model.screen else { return Vec::new() };
    preview(editor)
}

/// `S` in the editor: a prompt for a new file beside the manifest to save it as (for a
/// manifest that cannot be written), filled in with a free-looking name.
pub fn ask_save_as(model: &mut Model) {
    let Screen::Editor(editor) = &model.screen else { return };
    if editor.text.is_none() {
        return;
    }
    let stem = model.manifest.file_stem().map_or("library".into(), |s| s.to_string_lossy().into_owned());
    let path = model.manifest.with_file_name(format!("{stem}-2.toml"));
    model.prompt = Some(super::model::Prompt {
        purpose: super::model::Purpose::SaveAs,
        input: path.display().to_string().as_str().into(),
        note: String::new(),
    });
    model.status = "save the manifest as a new file beside it (an existing file is never replaced)".into();
}

/// Enter in the save-as prompt.
pub fn save_as(model: &mut Model) -> Vec<Effect> {
    let typed = model.prompt.take().map(|p| p.input.value().to_string()).unwrap_or_default();
    let Screen::Editor(editor) = &model.screen else { return Vec::new() };
    let Some(text) = editor.text.clone() else { return Vec::new() };
    if typed.trim().is_empty() {
        model.status = "not saved: no file named".into();
        return Vec::new();
    }
    model.status = format!("saving as {typed}");
    vec![Effect::SaveAs(std::path::PathBuf::from(typed.trim()), text)]
}

/// The manifest was saved as another file: the UI goes on with that file.
pub fn saved_as(model: &mut Model, result: Result<(std::path::PathBuf, String), String>) {
    match result {
        Ok((path, text)) => {
            let old = std::mem::replace(&mut model.manifest, path);
            model.read_only.clear();
            if let Screen::Editor(editor) = &mut model.screen {
                editor.saved = text;
            }
            model.status = format!(
                "saved as {}; the UI goes on with it ({} is unchanged; solidtex tui {} opens it later)",
                model.manifest.display(),
                old.display(),
                model.manifest.display()
            );
        }
        Err(e) => model.status = format!("not saved: {e}"),
    }
}

/// The save finished.
pub fn saved(model: &mut Model, result: Result<String, String>) {
    if result.is_ok() {
        model.outside = false;
    }
    match (result, &mut model.screen) {
        (Ok(written), Screen::Editor(editor)) => {
            let merged = editor.text.as_deref() != Some(written.as_str());
            if merged {
                onto(editor, &written, written.clone());
            }
            let (name, valid) = (editor.name.clone(), editor.error.is_none());
            // the row shows the size the manifest now asks for
            let folder = model.manifest.parent().unwrap_or(Path::new("."));
            let (entries, _) = crate::io::manifest::parse_plan_lenient(&written, folder);
            let asked = entries.iter().find(|e| e.name == name).and_then(|e| e.dims);
            editor.saved = written;
            super::update::mark_changed(model, &name, valid);
            for item in model.items.iter_mut().filter(|i| i.name == name && asked.is_some()) {
                item.size = asked;
            }
            let kept = if merged { " with the file's other changes kept" } else { "" };
            model.status = format!("saved{kept}; b on the library builds {name} as it is now");
        }
        (Ok(_), Screen::Exemplar(view)) => {
            if let Some(stamp) = &mut view.stamp {
                stamp.steps.clear();
                stamp.undo.clear();
            }
            let name = view.name.clone();
            super::update::mark_changed(model, &name, true);
            model.status = format!("saved the steps into {}", model.manifest.display());
        }
        (Ok(_), _) => model.status = format!("saved {}", model.manifest.display()),
        // the manifest's path is in the title: the reason comes first
        (Err(e), Screen::Editor(_)) => {
            let e = e.replace(&format!("{}: ", model.manifest.display()), "");
            model.status = format!("not saved (S saves under another name): {e}")
        }
        (Err(e), _) => model.status = format!("not saved: {e}"),
    }
}

/// A preview arrived; older generations are dropped. Its build's warnings go to the status
/// line (never to the terminal under the screen).
pub fn previewed(
    model: &mut Model,
    generation: u64,
    result: Result<std::sync::Arc<crate::Volume>, String>,
    warnings: Vec<String>,
) {
    let Screen::Editor(editor) = &mut model.screen else { return };
    if generation != editor.generation {
        return;
    }
    editor.previewing = false;
    editor.preview_error = result.as_ref().err().cloned();
    match result {
        Ok(volume) => {
            editor.preview = Some(volume);
            if !warnings.is_empty() {
                model.status = format!("preview: {}", warnings.join("; "));
            }
        }
        Err(e) => model.status = format!("preview failed: {e}"),
    }
}

/// Open the fill preview of the exemplar on screen.
pub fn open_fill(model: &mut Model) -> Vec<Effect> {
    let Screen::Exemplar(view) = &model.screen else { return Vec::new() };
    let name = view.name.clone();
    let from = Some(Box::new(view.clone()));
    model.screen =
        Screen::Fill(FillView { name: name.clone(), filled: None, axis: Axis::X, offset: 0.0, from, edit: None });
    model.status = format!("filling a shape with {name}...");
    vec![Effect::Fill(name)]
}

/// A fill preview arrived.
pub fn filled(model: &mut Model, name: &str, result: Result<std::sync::Arc<super::model::FillPreview>, String>) {
    let Screen::Fill(view) = &mut model.screen else { return };
    if view.name != name {
        return;
    }
    match result {
        Ok(preview) => {
            model.status = format!("{}; x/y/z choose the cut, arrows move it", preview.summary);
            if view.edit.is_none() {
                view.edit = Some(super::model::FillEdit {
                    spec: preview.spec.clone(),
                    shape: preview.shape.clone(),
                    cursor: [0.5, 0.5],
                    stroke: Vec::new(),
                    depth: 1.0,
                    show_depth: false,
                    undo: Vec::new(),
                    saved: Box::new(preview.spec.clone()),
                    dragging: false,
                    refilling: false,
                    overlay: None,
                    picture: None,
                    pending: false,
                });
            }
            if let Some(edit) = &mut view.edit {
                edit.refilling = false;
            }
            view.filled = Some(preview);
        }
        Err(e) => match &mut view.edit {
            // a refill with the constraints failed: the fill and the constraints stay
            Some(edit) if view.filled.is_some() => {
                edit.refilling = false;
                model.status = format!("the refill failed: {e}; u undoes the last constraint");
            }
            _ => {
                model.status = format!("cannot fill with {name}: {e}");
                model.screen = Screen::Library;
            }
        },
    }
}

/// Move or turn the cut plane.
pub fn plane(model: &mut Model, axis: Option<Axis>, step: f32) {
    if let Screen::Fill(view) = &mut model.screen {
        if let Some(axis) = axis.filter(|a| *a != view.axis) {
            // A new axis starts with the plane through the model's centre.
            view.axis = axis;
            view.offset = 0.0;
        }
        view.offset = (view.offset + step).clamp(-0.98, 0.98);
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::tui::message::Message;
    use crate::tui::model::Item;
    use crate::tui::update;
    use std::path::PathBuf;

    const TEXT: &str =
        "# my library\n[[exemplar]]\nname = \"m\"\nrecipe = \"procedural:marble\"  # veins\nsize = 16\nseed = 3\n";

    fn editing() -> Model {
        let item = Item {
            name: "m".into(),
            declared: None,
            size: None,
            state: crate::tui::BuildState::NotBuilt,
            quality: None,
            previous: false,
        };
        let mut m = Model::new(PathBuf::from("lib/library.toml"), PathBuf::from("out"), vec![item], Vec::new());
        assert_eq!(update(&mut m, Message::Edit), vec![Effect::ReadManifest]);
        let effects = update(&mut m, Message::EditorReady(Ok(TEXT.into())));
        assert!(matches!(&effects[..], [Effect::Preview { generation: 1, .. }]));
        m
    }

    fn editor(m: &Model) -> &Editor {
        let Screen::Editor(e) = &m.screen else { panic!("the editor is open") };
        e
    }

    fn type_value(m: &mut Model, value: &str) -> Vec<Effect> {
        update(m, Message::Commit);
        for _ in 0..10 {
            update(m, Message::Input(tui_input::InputRequest::DeletePrevChar));
        }
        value.chars().for_each(|c| {
            update(m, Message::Input(tui_input::InputRequest::InsertChar(c)));
        });
        update(m, Message::Commit)
    }

    /// The value is a text field: the cursor moves, deletes and inserts anywhere, and Ctrl-U
    /// clears it (it only appended and removed at the end).
    #[test]
    fn a_value_is_edited_anywhere_in_it() {
        use tui_input::InputRequest::{DeleteLine, DeleteNextChar, GoToEnd, GoToStart, InsertChar};
        let mut m = editing();
        update(&mut m, Message::Down);
        update(&mut m, Message::Down);
        update(&mut m, Message::Commit);
        let value = |m: &Model| editor(m).input.as_ref().map(|i| i.value().to_string());
        assert_eq!(value(&m).as_deref(), Some("16"));
        for request in [GoToStart, DeleteNextChar, InsertChar('2'), GoToEnd, InsertChar('0')] {
            update(&mut m, Message::Input(request));
        }
        assert_eq!(value(&m).as_deref(), Some("260"));
        update(&mut m, Message::Input(DeleteLine));
        assert_eq!(value(&m).as_deref(), Some(""));
        for c in "24".chars() {
            update(&mut m, Message::Input(InsertChar(c)));
        }
        update(&mut m, Message::Commit);
        assert!(editor(&m).text.as_deref().unwrap().contains("size = 24"), "{:?}", editor(&m).text);
    }

    /// `K`/`J` move the selected step with the selection, `x` removes it, `u` brings it
    /// back; each kept change is previewed; outside a step the keys only say what they need.
    #[test]
    fn steps_are_moved_and_removed_in_the_editor() {
        const STEPS: &str = "[[exemplar]]\nname = \"m\"\nrecipe = \"procedural:marble\"\nsize = 16\n  [[exemplar.steps]]\n  blur = \"1,1,1\"\n  radius = 2\n  [[exemplar.steps]]\n  blur = \"8,8,8\"\n  radius = 3\n";
        let mut m = editing_in(STEPS, "m");
        assert!(update(&mut m, Message::RemoveStep).is_empty());
        assert!(m.status.contains("select a field of a step"), "{}", m.status);
        let selected = |m: &Model| {
            let e = editor(m);
            edit::fields(e.text.as_deref().unwrap(), "m").unwrap()[e.selected].clone()
        };
        for _ in 0..6 {
            update(&mut m, Message::Down);
        }
        assert_eq!((selected(&m).key.as_str(), selected(&m).value.as_str()), ("steps[1].radius", "3"));
        let effects = update(&mut m, Message::MoveStep(true));
        assert!(matches!(effects.as_slice(), [Effect::Preview { .. }]), "{effects:?}");
        assert_eq!((selected(&m).key.as_str(), selected(&m).value.as_str()), ("steps[0].radius", "3"));
        let text = editor(&m).text.clone().unwrap();
        assert!(text.find("8,8,8").unwrap() < text.find("1,1,1").unwrap(), "{text}");
        assert!(update(&mut m, Message::MoveStep(true)).is_empty());
        assert!(editor(&m).error.as_deref().unwrap().contains("already the first"));
        update(&mut m, Message::RemoveStep);
        assert!(!editor(&m).text.as_deref().unwrap().contains("8,8,8"));
        update(&mut m, Message::Undo);
        update(&mut m, Message::Undo);
        assert_eq!(editor(&m).text.as_deref(), Some(STEPS), "two undos give the text back");
        // a: a blur step at the centre, selected, accepted by the manifest's rules
        let effects = update(&mut m, Message::AddBlur);
        assert!(matches!(effects.as_slice(), [Effect::Preview { .. }]), "{effects:?}");
        assert_eq!((selected(&m).key.as_str(), selected(&m).value.as_str()), ("steps[2].blur", "\"8,8,8\""));
        let text = editor(&m).text.clone().unwrap();
        assert!(text.ends_with("  [[exemplar.steps]]\n  blur = \"8,8,8\"\n  radius = 2\n"), "{text}");
        assert!(check(&text, Path::new("lib"), "m").is_ok());
        assert_eq!(sides("[16, 24, 40]"), Some([16.0, 24.0, 40.0]));
        assert_eq!(sides("\"big\""), None);
    }

    /// `t` and `n` pick a mesh in the file picker and append a stamp at the centre or a
    /// scatter of ten, checked by the manifest's rules; esc in the picker adds nothing.
    #[test]
    fn t_and_n_append_stamp_and_scatter_steps_of_a_picked_mesh() {
        use crate::tui::new_entry::{FileKind, FileRow};
        let dir = tempfile::tempdir().unwrap();
        let ball = crate::mesh::shapes::ellipsoid(glam::Vec3::ONE, 6, 8);
        crate::io::mesh_file::write_mesh(&dir.path().join("seed.obj"), &ball).unwrap();
        let mut m = editing_in(TEXT, "m");
        m.manifest = dir.path().join("library.toml");
        let folder = dir.path().to_path_buf();
        assert_eq!(update(&mut m, Message::AddMeshStep(true)), vec![Effect::List(folder.clone(), FileKind::Mesh)]);
        update(&mut m, Message::Back);
        assert!(matches!(m.screen, Screen::Editor(_)) && m.status == "no step added", "{}", m.status);
        for stamp in [true, false] {
            update(&mut m, Message::AddMeshStep(stamp));
            let rows =
                vec![FileRow { name: "..".into(), folder: true }, FileRow { name: "seed.obj".into(), folder: false }];
            update(&mut m, Message::Listed(folder.clone(), Ok((folder.clone(), rows))));
            update(&mut m, Message::Down);
            assert_eq!(update(&mut m, Message::Open), vec![Effect::StepMesh(folder.join("seed.obj"), stamp)]);
            let effects = update(&mut m, Message::StepMeshChosen(Ok("seed.obj".into()), stamp));
            assert!(matches!(effects.as_slice(), [Effect::Preview { .. }]), "{effects:?} {:?}", editor(&m).error);
        }
        let text = editor(&m).text.clone().unwrap();
        assert!(text.contains("stamp = \"seed.obj\"") && text.contains("at = \"8.0,8.0,8.0\""), "{text}");
        assert!(text.contains("scatter = \"seed.obj\"") && text.contains("count = 10"), "{text}");
        assert!(check(&text, dir.path(), "m").is_ok());
        update(&mut m, Message::StepMeshChosen(Err("no such mesh".into()), true));
        assert!(m.status.contains("no step added: no such mesh"), "{}", m.status);
    }

    /// A manifest whose entry "bad" has two mistakes (size 0, an unknown recipe).
    const TWO: &str = "[[exemplar]]\nname = \"m\"\nrecipe = \"procedural:marble\"\nsize = 16\n\n[[exemplar]]\nname = \"bad\"\nrecipe = \"weave\"\nsize = 0\n";

    fn editing_in(text: &str, name: &str) -> Model {
        let item = Item {
            name: name.into(),
            declared: None,
            size: None,
            state: crate::tui::BuildState::NotBuilt,
            quality: None,
            previous: false,
        };
        let mut m = Model::new(PathBuf::from("lib/library.toml"), PathBuf::from("out"), vec![item], Vec::new());
        update(&mut m, Message::Edit);
        update(&mut m, Message::EditorReady(Ok(text.into())));
        m
    }

    /// Another entry's mistakes do not block editing a valid one; a broken entry keeps each
    /// well-formed edit, so its mistakes are fixed one at a time.
    #[test]
    fn mistakes_elsewhere_do_not_block_edits_and_a_broken_entry_is_fixed_step_by_step() {
        let mut m = editing_in(TWO, "m");
        update(&mut m, Message::Down);
        update(&mut m, Message::Down);
        type_value(&mut m, "24");
        assert!(editor(&m).error.is_none(), "{:?}", editor(&m).error);
        assert!(editor(&m).text.as_deref().unwrap().contains("size = 24"));
        let mut m = editing_in(TWO, "bad");
        update(&mut m, Message::Down);
        update(&mut m, Message::Down);
        type_value(&mut m, "16");
        let e = editor(&m);
        assert!(e.text.as_deref().unwrap().contains("size = 16"), "the fix is kept");
        assert!(e.error.as_deref().unwrap_or("").contains("still has a mistake"), "{:?}", e.error);
        update(&mut m, Message::Up);
        type_value(&mut m, "\"procedural:marble\"");
        assert!(editor(&m).error.is_none(), "both fixed: {:?}", editor(&m).error);
    }

    #[test]
    fn an_edit_is_validated_kept_with_its_comments_and_previewed() {
        let mut m = editing();
        update(&mut m, Message::Down);
        update(&mut m, Message::Down);
        let effects = type_value(&mut m, "24");
        let text = editor(&m).text.clone().unwrap();
        assert_eq!(text, TEXT.replace("size = 16", "size = 24"));
        assert!(matches!(&effects[..], [Effect::Preview { generation: 2, .. }]));
        // size 0 is refused by the manifest rules, in place, and nothing changes
        assert!(type_value(&mut m, "0").is_empty());
        let e = editor(&m);
        assert!(e.error.as_deref().unwrap_or("").contains("size"), "{:?}", e.error);
        assert_eq!(e.text.as_deref(), Some(text.as_str()));
        assert!(e.input.is_some(), "the value stays open for a fix");
        update(&mut m, Message::Cancel);
        assert!(editor(&m).input.is_none() && matches!(m.screen, Screen::Editor(_)));
    }

    #[test]
    fn undo_redo_save_and_stale_previews() {
        let mut m = editing();
        update(&mut m, Message::Down);
        update(&mut m, Message::Down);
        type_value(&mut m, "32");
        update(&mut m, Message::Undo);
        assert_eq!(editor(&m).text.as_deref(), Some(TEXT));
        assert!(update(&mut m, Message::Save).is_empty(), "nothing to save after undoing");
        update(&mut m, Message::Redo);
        let edited = TEXT.replace("size = 16", "size = 32");
        let save = Effect::Save { name: editor(&m).name.clone(), base: TEXT.into(), text: edited.clone() };
        assert_eq!(update(&mut m, Message::Save), vec![save]);
        update(&mut m, Message::Saved(Ok(edited)));
        assert!(m.status.starts_with("saved"));
        let name = editor(&m).name.clone();
        let row = m.items.iter().find(|i| i.name == name).unwrap();
        assert_eq!(row.size, Some([32; 3]), "the list shows the size just saved");
        let stale = std::sync::Arc::new(crate::Volume::new([2; 3], crate::Channel::rgb()).unwrap());
        update(&mut m, Message::Previewed(1, Ok(stale.clone()), Vec::new()));
        assert!(editor(&m).preview.is_none(), "an old generation is dropped");
        let current = editor(&m).generation;
        update(&mut m, Message::Previewed(current, Ok(stale), vec!["placed 59 of 60 seeds".into()]));
        assert!(editor(&m).preview.is_some() && m.status.contains("placed 59 of 60 seeds"), "{}", m.status);
        // the name is not edited here
        update(&mut m, Message::Up);
        update(&mut m, Message::Up);
        type_value(&mut m, "\"x\"");
        assert!(editor(&m).error.as_deref().unwrap_or("").contains("name"));
    }

    #[test]
    fn leaving_with_unsaved_changes_asks_first() {
        let mut m = editing();
        update(&mut m, Message::Down);
        update(&mut m, Message::Down);
        type_value(&mut m, "20");
        update(&mut m, Message::Back);
        assert!(
            matches!(m.screen, Screen::Editor(_)) && m.status.starts_with("esc again leaves without saving; unsaved")
        );
        update(&mut m, Message::Back);
        assert!(matches!(m.screen, Screen::Library));
    }

    /// `+` lists the fields the recipe takes that the entry does not set, with what each
    /// allows; enter adds the chosen one and opens it for typing; `-` removes a field, but
    /// not one the entry needs.
    #[test]
    fn fields_are_added_from_the_table_and_removed() {
        let mut m = editing();
        update(&mut m, Message::PickField);
        let rows = picker_rows(editor(&m));
        let keys: Vec<&str> = rows.iter().map(|r| r.key).collect();
        assert_eq!(keys, ["type", "masks", "mask_falloff", "exports"], "marble takes these, and sets size and seed");
        assert!(rows[1].allowed.contains("splotch") && rows[1].start == "[\"splotch\"]", "{:?}", rows[1]);
        update(&mut m, Message::Jump(1));
        update(&mut m, Message::Commit);
        let e = editor(&m);
        assert!(e.picker.is_none() && e.text.as_deref().unwrap().contains("masks = [\"splotch\"]"), "{:?}", e.text);
        let fields = edit::fields(e.text.as_deref().unwrap(), "m").unwrap();
        assert_eq!(fields[e.selected].key, "masks");
        assert_eq!(e.input.as_ref().map(|i| i.value()), Some("[\"splotch\"]"), "its value opens for typing");
        update(&mut m, Message::Cancel);
        // size is needed by a procedural recipe; seed is not
        let at = |m: &Model, key: &str| {
            edit::fields(editor(m).text.as_deref().unwrap(), "m").unwrap().iter().position(|f| f.key == key).unwrap()
        };
        let row = at(&m, "size");
        let Screen::Editor(e) = &mut m.screen else { panic!() };
        e.selected = row;
        update(&mut m, Message::RemoveField);
        assert!(m.status.contains("size is needed"), "{}", m.status);
        let row = at(&m, "seed");
        let Screen::Editor(e) = &mut m.screen else { panic!() };
        e.selected = row;
        update(&mut m, Message::RemoveField);
        assert!(!editor(&m).text.as_deref().unwrap().contains("seed"), "{:?}", editor(&m).text);
        assert!(editor(&m).text.as_deref().unwrap().starts_with("# my library"), "comments stay");
        // the outside editor opens the file as saved
        assert!(update(&mut m, Message::OutsideEditor).is_empty());
        assert!(m.status.contains("save your edits first"), "{}", m.status);
    }

    /// `o` opens the saved manifest at the entry's line; back from it, the manifest and the
    /// list are read again and the entry checked.
    #[test]
    fn the_outside_editor_opens_at_the_entry_and_its_result_is_read() {
        let mut m = editing();
        assert_eq!(update(&mut m, Message::OutsideEditor), vec![Effect::EditOutside(3)]);
        let effects = update(&mut m, Message::OutsideEdited(Ok(())));
        assert_eq!(effects, vec![Effect::ReadManifest, Effect::Reload("m".into())]);
        assert!(editor(&m).text.is_none(), "the editor waits for the file as it is now");
        let broken = TEXT.replace("size = 16", "size = 0");
        update(&mut m, Message::EditorReady(Ok(broken)));
        assert!(m.status.starts_with("m has a mistake") && m.status.contains("size"), "{}", m.status);
    }
}
