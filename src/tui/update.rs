//! `update`: the only place the model changes. Pure: returns the work to start.

use super::message::{Effect, EntryChange, Message, SharedFill, WebSubject};
use super::model::{
    Batch, BuildState, Confirm, ExemplarView, LOG_LINES, Model, Prompt, Purpose, STATUS_SECONDS, Screen,
};
use super::{compare, editing, fill_edit, new_entry, stamping};
use crate::volume::Axis;

/// Apply `message` to `model`; returns the effects to run.
pub fn update(model: &mut Model, message: Message) -> Vec<Effect> {
    let before = model.status.clone();
    let mut effects = handle(model, message);
    effects.extend(fill_edit::overlay_due(model));
    if model.status != before {
        noted(model);
    }
    effects
}

/// Whether the editor's field picker is open.
fn picking(model: &Model) -> bool {
    matches!(&model.screen, Screen::Editor(e) if e.picker.is_some())
}

/// A new status: shown afresh, and kept in the log with the time it came.
fn noted(model: &mut Model) {
    model.status_age = 0;
    if model.status.is_empty() {
        return;
    }
    let seconds = model.now.as_secs();
    model.log.push(format!("{:02}:{:02} {}", seconds / 60, seconds % 60, model.status));
    if model.log.len() > LOG_LINES {
        model.log.drain(..model.log.len() - LOG_LINES);
    }
}

/// A second passed: the status clears once it has been up [`STATUS_SECONDS`] (a question
/// waiting for its answer stays).
fn tick(model: &mut Model, now: std::time::Duration) {
    model.now = now;
    model.status_age = model.status_age.saturating_add(1);
    if model.status_age >= STATUS_SECONDS && model.confirm.is_none() && model.prompt.is_none() {
        model.status.clear();
    }
}

/// Scroll the help or the message log by `rows`, within its lines.
fn scroll(model: &mut Model, rows: i64) {
    // a page key moves by what the overlay shows
    let page = (i64::from(model.size.1) - 5).max(1);
    let rows = if rows.abs() == super::keymap::PAGE { rows.signum() * page } else { rows };
    let moved = |at: usize, most: usize| (at as i64).saturating_add(rows).clamp(0, most as i64) as usize;
    if let Some(help) = &mut model.help {
        let most = super::view::help_scroll_most(&model.screen, &help.query, model.size);
        help.scroll = moved(help.scroll.min(most), most);
    } else if let Some(first) = model.log_view {
        let most = super::view::log_scroll_most(&model.log, model.size);
        model.log_view = Some(moved(first.min(most), most));
    }
}

fn handle(model: &mut Model, message: Message) -> Vec<Effect> {
    // A confirmation holds for the very next key only; results from workers leave it.
    let asked = if from_key(&message) { model.confirm.take() } else { model.confirm };
    match message {
        Message::Quit => quit(model, asked),
        Message::Help => model.help = if model.help.is_some() { None } else { Some(Default::default()) },
        Message::ShowLog => {
            model.log_view = match model.log_view {
                Some(_) => None,
                None => Some(super::view::log_scroll_most(&model.log, model.size)),
            }
        }
        Message::Scroll(rows) => scroll(model, rows),
        Message::Jump(rows) if matches!(model.screen, Screen::Library) => select(model, rows),
        Message::Jump(rows) => editing::picker_move(model, rows),
        Message::PickField => editing::pick_field(model),
        Message::RemoveField => return editing::remove_field(model),
        Message::OutsideEditor => return editing::outside(model),
        Message::OutsideEdited(result) => return editing::outside_edited(model, result),
        Message::Filter if matches!(model.screen, Screen::Library) => {
            model.prompt =
                Some(Prompt { purpose: Purpose::Filter, input: model.filter.as_str().into(), note: String::new() });
        }
        Message::Filter => {}
        Message::Say(text) => model.status = text,
        Message::Tick(now) => tick(model, now),
        Message::Resized(w, h) => model.size = (w, h),
        Message::HelpSearch => {
            if let Some(help) = &mut model.help {
                help.typing = !help.typing;
            }
        }
        Message::HelpType(c) => {
            if let Some(help) = model.help.as_mut().filter(|h| h.typing) {
                match c {
                    Some(c) => help.query.push(c),
                    None => _ = help.query.pop(),
                }
                help.scroll = 0;
            }
        }
        Message::Back => return back(model, asked),
        Message::Up | Message::Down | Message::Open | Message::Parent if matches!(model.screen, Screen::New(_)) => {
            return match message {
                Message::Up => new_entry::select(model, -1),
                Message::Down => new_entry::select(model, 1),
                Message::Open => new_entry::open(model),
                _ => new_entry::parent(model),
            };
        }
        Message::Select(row) if matches!(model.screen, Screen::New(_)) => return new_entry::pick(model, row),
        Message::Select(row) => return click(model, row),
        Message::PointAt(axis, a, b) => with_view(model, |v| point_at(v, axis, a, b)),
        Message::MoveSliceOf(axis, step) => with_view(model, |v| {
            v.axis = axis;
            move_slice(v, step)
        }),
        Message::Up => select(model, -1),
        Message::Down => select(model, 1),
        Message::Open => return open(model),
        Message::New if model.first_run => model.status = "no library here yet: enter starts one".into(),
        Message::New if matches!(model.screen, Screen::Library) => new_entry::start(model),
        Message::New | Message::Parent => {}
        Message::Listed(folder, result) => return new_entry::listed(model, &folder, result),
        Message::Peeked(path, result) => new_entry::peeked(model, path, result),
        Message::Build => return build(model, false),
        Message::BuildAll => return build(model, true),
        Message::BuildChanged => return build_changed(model),
        Message::BuildStarted(names) => {
            for item in model.items.iter_mut().filter(|i| i.state == BuildState::Queued && names.contains(&i.name)) {
                item.state = BuildState::Building;
            }
        }
        Message::Duplicate => return change_entry(model, false, asked),
        Message::Delete => return change_entry(model, true, asked),
        Message::EntriesChanged(result) => {
            model.first_run &= result.is_err();
            // a refused rename: the prompt again, with the name as typed
            if let (Some(mut retry), Err(why)) = (model.renaming.take(), &result) {
                retry.note = why.clone();
                model.prompt = Some(retry);
            }
            new_entry::added(model, result.is_ok());
            entries_changed(model, result)
        }
        Message::ScrollErrors(lines) => {
            // The view stops at the last line; here only a bound that never overflows.
            let most = model.errors.iter().map(|e| e.len()).sum::<usize>();
            model.error_scroll = model.error_scroll.saturating_add_signed(lines as isize).min(most);
        }
        Message::SelectAxis(axis) if compare::axis(model, axis) => {}
        Message::MoveSlice(step) if compare::move_slice(model, step) => {}
        Message::Compare if matches!(model.screen, Screen::Library) => return compare::compare(model),
        Message::BeforeAfter if matches!(model.screen, Screen::Library) => return compare::before_after(model),
        Message::Compare | Message::BeforeAfter => {}
        Message::SideLoaded(side, label, result) => compare::loaded(model, side, &label, result),
        Message::Accept => return compare::settle(model, true),
        Message::Discard => return compare::settle(model, false),
        Message::SelectAxis(axis) => {
            with_view(model, |v| v.axis = axis);
            editing::plane(model, Some(axis), 0.0);
        }
        Message::MoveSlice(step) => with_view(model, |v| move_slice(v, step)),
        Message::NextChannel => with_view(model, |v| {
            let n = v.volume.as_ref().map_or(1, |vol| vol.channel_count() + 1);
            v.channel = (v.channel + 1) % n;
        }),
        Message::Loaded(name, result) => loaded(model, &name, result),
        Message::Built(name, result) => built(model, &name, result),
        Message::BuildCancelled(name, row) => cancelled(model, &name, row),
        Message::Edit => return editing::open_editor(model),
        Message::EditorReady(result) => return editing::editor_ready(model, result),
        Message::Rename => start_rename(model),
        Message::Export => return export(model),
        Message::WebView => return web_view(model),
        Message::WebWritten(result) => model.status = result.unwrap_or_else(|e| format!("no 3D view: {e}")),
        Message::Exported(result) => model.status = exported(result),
        Message::SpecWritten(spec, result) => {
            if result.is_ok() {
                fill_edit::written(model, &spec);
            }
            model.status = exported(result);
        }
        Message::OpenSpec => return new_entry::pick_spec(model),
        Message::SpecLoaded(path, result) => fill_edit::spec_loaded(model, &path, result),
        Message::Commit if model.prompt.as_ref().is_some_and(|p| p.purpose == Purpose::SaveAs) => {
            return editing::save_as(model);
        }
        Message::Commit if model.prompt.as_ref().is_some_and(|p| p.purpose == Purpose::Filter) => {
            model.prompt = None;
            filtered(model);
        }
        Message::Commit if model.prompt.is_some() => return finish_rename(model),
        Message::Commit if picking(model) => return editing::picker_add(model),
        Message::Cancel if picking(model) => {
            if let Screen::Editor(e) = &mut model.screen {
                e.picker = None;
            }
        }
        Message::Input(request) if model.prompt.is_some() => {
            let prompt = model.prompt.as_mut().expect("checked");
            prompt.input.handle(request);
            if prompt.purpose == Purpose::Filter {
                model.filter = prompt.input.value().to_string();
                filtered(model);
            }
        }
        Message::Cancel if model.prompt.is_some() => {
            let purpose = model.prompt.take().expect("checked").purpose;
            model.status = match purpose {
                Purpose::Rename => "the name stays".into(),
                Purpose::SaveAs => "not saved".into(),
                Purpose::Filter => {
                    model.filter.clear();
                    format!("every entry shown ({})", model.items.len())
                }
            };
        }
        Message::SaveAs => editing::ask_save_as(model),
        Message::SavedAs(result) => editing::saved_as(model, result),
        Message::Commit => return editing::commit(model),
        Message::Input(request) => editing::input(model, request),
        Message::Cancel => {
            if !editing::cancel(model) {
                return back(model, asked);
            }
        }
        Message::Undo if matches!(model.screen, Screen::Exemplar(_)) => stamping::undo(model),
        Message::Undo if matches!(model.screen, Screen::Fill(_)) => fill_edit::undo(model),
        Message::Undo if matches!(model.screen, Screen::Library) => return undo_entry(model),
        Message::Undo => return editing::undo(model, false),
        Message::Redo => return editing::undo(model, true),
        Message::Save => return editing::save(model),
        Message::AddBlur => return editing::add_blur(model),
        Message::AddMeshStep(stamp) => return new_entry::pick_step_mesh(model, stamp),
        Message::StepMeshChosen(result, stamp) => return editing::add_mesh_step(model, result, stamp),
        Message::RemoveStep => return editing::step(model, true, false),
        Message::MoveStep(earlier) => return editing::step(model, false, earlier),
        Message::Saved(result) => editing::saved(model, result),
        Message::SaveConflict(theirs) => return editing::save_conflict(model, theirs),
        Message::Resolve(choice) => return editing::resolve(model, choice),
        Message::Reload => return reload(model),
        Message::ChangedOnDisk => {
            model.outside = true;
            model.status = "the manifest changed on disk: Ctrl-R reloads".into();
        }
        Message::Previewed(generation, result, warnings) => editing::previewed(model, generation, result, warnings),
        Message::FillPreview => return editing::open_fill(model),
        Message::Filled(name, result) => editing::filled(model, &name, result),
        Message::MovePlane(step) => editing::plane(model, None, step),
        Message::MoveCursor(right, down) => fill_edit::move_cursor(model, right, down),
        Message::CursorAt(across, down) => fill_edit::cursor_at(model, across, down),
        Message::StrokePoint => fill_edit::stroke_point(model),
        Message::DragStroke(across, down) => fill_edit::drag(model, across, down),
        Message::EndDrag => fill_edit::end_drag(model),
        Message::FinishStroke => fill_edit::finish_stroke(model),
        Message::DepthPoint => fill_edit::depth_point(model),
        Message::DepthValue(step) => fill_edit::depth_value(model, step),
        Message::FaceGroup => fill_edit::face_group(model),
        Message::Paste => {
            let size = if let Screen::Fill(v) = &model.screen { fill_edit::model_size(v) } else { 1.0 };
            fill_edit::paste(model, size)
        }
        Message::WarpPaste(degrees, factor) => fill_edit::warp_paste(model, degrees, factor),
        Message::ShowDepth => fill_edit::toggle_depth(model),
        Message::NextOverlay => fill_edit::next_overlay(model),
        Message::OverlayMade(name, key, result) => fill_edit::overlay_made(model, &name, *key, result),
        Message::Refill => return fill_edit::refill(model),
        Message::WriteSpec => return fill_edit::write(model),
        Message::Zoom(closer) => {
            with_view(model, |v| v.zoom = if closer { (v.zoom * 2).min(4) } else { (v.zoom / 2).max(1) })
        }
        Message::NextLayer => return next_layer(model),
        Message::Photo => return photo(model),
        Message::PhotosLoaded(name, result) => {
            if let Screen::Exemplar(v) = &mut model.screen
                && v.name == name
            {
                match &result {
                    Err(e) => {
                        model.status = format!("no photo to compare with: {e}");
                        v.beside_photo = false;
                    }
                    Ok(_) => model.status = COMPARING.into(),
                }
                v.photos = Some(result);
            }
        }
        Message::MasksLoaded(name, result) => masks_loaded(model, &name, result),
        Message::StampMode if showing_mask(model) => {
            model.status = "stamping works on the exemplar, not on a mask: press a".into()
        }
        Message::StampMode if stamps_unsaved(model) && asked != Some(Confirm::StampOff) => {
            model.confirm = Some(Confirm::StampOff);
            model.status = "m again leaves stamp mode without saving; unsaved stamps: s saves them as steps".into();
        }
        Message::StampMode => return stamping::toggle(model),
        Message::SeedLoaded(result) => stamping::seed_loaded(model, result),
        Message::MoveSeed(step) => stamping::move_seed(model, step),
        Message::TurnSeed(degrees) => stamping::turn(model, degrees),
        Message::ScaleSeed(factor) => stamping::scale(model, factor),
        Message::Stamp => stamping::stamp_seed(model),
        Message::Scatter => stamping::scatter(model),
        Message::SaveSteps => return stamping::save(model),
        Message::PickSeed => return new_entry::pick_seed(model),
        Message::BuildPreview(name, level, volume) => {
            model.previews.insert(name, (level, volume));
        }
        Message::BuildProgress(name, stage, fraction) => {
            if model.items.iter().any(|i| i.name == name && i.state == BuildState::Building) {
                model.progress.insert(name, (stage, fraction));
            }
        }
        Message::BuildWarning(name, warning) => model.status = format!("warning: {name}: {warning}"),
        Message::WorkerFailed(why) => model.status = format!("{why}; nothing else is lost, the UI goes on"),
    }
    Vec::new()
}

/// What an export wrote, or why nothing.
fn exported(result: Result<(String, Vec<String>, Vec<String>), String>) -> String {
    match result {
        Ok((folder, files, skipped)) => {
            // the files first: a long folder is what the status row cuts (M shows it whole)
            let mut text = match &files[..] {
                [one] => format!("exported {one}"),
                _ => format!("exported {} files: {}", files.len(), files.join(", ")),
            };
            if !skipped.is_empty() {
                text += &format!("; not {}", skipped.join(", not "));
            }
            text + &format!(" into {folder}")
        }
        Err(e) => format!("nothing exported: {e}"),
    }
}

/// Whether `message` comes from a key (not from a worker's result or the clock).
fn from_key(message: &Message) -> bool {
    !matches!(
        message,
        Message::Tick(_)
            | Message::Loaded(..)
            | Message::EntriesChanged(_)
            | Message::Built(..)
            | Message::BuildCancelled(..)
            | Message::EditorReady(_)
            | Message::Saved(_)
            | Message::SaveConflict(_)
            | Message::SavedAs(_)
            | Message::ChangedOnDisk
            | Message::Previewed(..)
            | Message::Filled(..)
            | Message::OverlayMade(..)
            | Message::MasksLoaded(..)
            | Message::SeedLoaded(_)
            | Message::BuildPreview(..)
            | Message::BuildProgress(..)
            | Message::BuildStarted(_)
            | Message::Exported(_)
            | Message::WebWritten(_)
            | Message::BuildWarning(..)
            | Message::WorkerFailed(_)
            | Message::SpecWritten(..)
            | Message::SpecLoaded(..)
            | Message::Listed(..)
            | Message::Peeked(..)
            | Message::PhotosLoaded(..)
            | Message::SideLoaded(..)
            | Message::StepMeshChosen(..)
    )
}

/// `c` copies the selected entry in the manifest; `d` deletes it, asking first (a second
/// `d`). Its built files stay in the output folder.
fn change_entry(model: &mut Model, delete: bool, asked: Option<Confirm>) -> Vec<Effect> {
    let Some(name) = model.items.get(model.selected).map(|i| i.name.clone()) else {
        model.status = "the library has no entry to copy or delete".into();
        return Vec::new();
    };
    if !delete {
        model.status = format!("copying {name}");
        return vec![Effect::ChangeEntry(EntryChange::Duplicate(name))];
    }
    if asked != Some(Confirm::Delete) {
        model.confirm = Some(Confirm::Delete);
        model.status =
            format!("d again deletes {name} from the manifest (its built files stay); any other key keeps it");
        return Vec::new();
    }
    model.status = format!("deleting {name}");
    vec![Effect::ChangeEntry(EntryChange::Delete(name))]
}

/// `E`: on the slices, export the volume on screen (once it has loaded); in the fill
/// preview, its cut.
fn export(model: &mut Model) -> Vec<Effect> {
    if let Screen::Fill(view) = &model.screen {
        let Some(filled) = view.filled.clone() else {
            model.status = "the fill is still running".into();
            return Vec::new();
        };
        model.status = format!("exporting the cut of {}", view.name);
        return vec![Effect::ExportCut(view.name.clone(), SharedFill(filled), view.axis, view.offset)];
    }
    let Screen::Exemplar(view) = &model.screen else { return Vec::new() };
    let Some(volume) = view.volume.clone() else {
        model.status = "the volume is still loading".into();
        return Vec::new();
    };
    let index = view.index[view.axis.index()];
    model.status = format!("exporting {}", view.name);
    vec![Effect::Export(view.name.clone(), volume, view.axis, index)]
}

/// `W`: the 3D view of the exemplar or fill preview on screen, once it is there.
fn web_view(model: &mut Model) -> Vec<Effect> {
    let (name, subject) = match &model.screen {
        Screen::Fill(view) => match view.filled.clone() {
            Some(filled) => (view.name.clone(), WebSubject::Fill(SharedFill(filled))),
            None => return waiting(model, "the fill is still running"),
        },
        Screen::Exemplar(view) => match view.volume.clone() {
            Some(volume) => (view.name.clone(), WebSubject::Volume(volume)),
            None => return waiting(model, "the volume is still loading"),
        },
        _ => return Vec::new(),
    };
    model.status = format!("writing the 3D view of {name}");
    vec![Effect::WebView(name, subject)]
}

fn waiting(model: &mut Model, why: &str) -> Vec<Effect> {
    model.status = why.into();
    Vec::new()
}

/// `r` on the library: a prompt for the selected entry's new name, its name filled in.
fn start_rename(model: &mut Model) {
    let Some(name) = model.items.get(model.selected).map(|i| i.name.clone()) else {
        model.status = "the library has no entry to rename".into();
        return;
    };
    model.status = format!("new name for {name} (enter renames, esc keeps it)");
    model.prompt = Some(Prompt { purpose: Purpose::Rename, input: name.as_str().into(), note: String::new() });
}

/// Enter in the rename prompt: rename the entry in the manifest (the worker refuses a name
/// the manifest does not allow or one taken, and says why).
fn finish_rename(model: &mut Model) -> Vec<Effect> {
    model.renaming = model.prompt.take();
    let new = model.renaming.as_ref().map(|p| p.input.value().to_string()).unwrap_or_default();
    let Some(name) = model.items.get(model.selected).map(|i| i.name.clone()) else { return Vec::new() };
    if new == name {
        model.status = "the name stays".into();
        return Vec::new();
    }
    model.status = format!("renaming {name} to {new}");
    vec![Effect::ChangeEntry(EntryChange::Rename(name, new))]
}

/// The manifest's entries changed: the new list, the row of `select` chosen; a library
/// operation can be undone.
fn entries_changed(model: &mut Model, result: super::message::Changed) {
    match result {
        Ok(change) => {
            let row = change.items.iter().position(|i| i.name == change.select).unwrap_or(model.selected);
            model.selected = row.min(change.items.len().saturating_sub(1));
            (model.items, model.errors, model.status) = (change.items, change.errors, change.status);
            // the selection stays among the entries the filter shows
            let shown = model.visible();
            if !shown.contains(&model.selected)
                && let Some(&first) = shown.first()
            {
                model.selected = first;
            }
            model.undo.extend(change.inverse);
            model.outside = false;
        }
        Err(e) => model.status = format!("the manifest is unchanged: {e}"),
    }
}

/// `u` on the library: undo the last library operation, applied to the manifest as it
/// reads now (an edit made outside since stays).
fn undo_entry(model: &mut Model) -> Vec<Effect> {
    let Some((change, what)) = model.undo.pop() else {
        model.status = "no library operation to undo".into();
        return Vec::new();
    };
    model.status = format!("undoing {what}");
    vec![Effect::UndoEntry(change, what)]
}

/// Ctrl-R: read the manifest again (the editor keeps its edits of its entry).
fn reload(model: &mut Model) -> Vec<Effect> {
    if matches!(model.screen, Screen::Editor(_)) {
        return vec![Effect::ReadManifest];
    }
    let select = model.items.get(model.selected).map(|i| i.name.clone()).unwrap_or_default();
    vec![Effect::Reload(select)]
}

/// `q` or Ctrl-C: quit, asking first when recipe edits or stamps are unsaved or builds run
/// (quitting cancels them; their previous outputs are kept).
fn quit(model: &mut Model, asked: Option<Confirm>) {
    let building = model.items.iter().filter(|i| i.state.busy()).count();
    match unsaved(model) {
        _ if asked == Some(Confirm::Quit) => model.quit = true,
        Some((what, how)) => {
            model.confirm = Some(Confirm::Quit);
            model.status = format!("q again quits without saving; unsaved {what}: {how}");
        }
        None if building > 0 => {
            model.confirm = Some(Confirm::Quit);
            model.status =
                format!("q again quits and cancels the {building} build(s) running (their previous outputs are kept)");
        }
        None => model.quit = true,
    }
}

/// Esc: clear the help's search or close the help, cancel running builds, or go back to
/// the library (asking first when work is unsaved). The library is the first screen: Esc
/// there never quits.
fn back(model: &mut Model, asked: Option<Confirm>) -> Vec<Effect> {
    let on_library = matches!(model.screen, Screen::Library);
    if model.help.is_none() && new_entry::back(model) {
        return Vec::new();
    }
    if let Some(help) = &mut model.help {
        if help.typing || !help.query.is_empty() {
            *help = Default::default();
        } else {
            model.help = None;
        }
    } else if on_library && !model.filter.is_empty() {
        model.filter.clear();
        model.status = format!("every entry shown ({})", model.items.len());
    } else if on_library && model.items.iter().any(|i| i.state.busy()) {
        model.status = "cancelling the running builds; their previous outputs are kept".into();
        return vec![Effect::CancelBuilds];
    } else if on_library {
        model.status = "this is the library, the first screen: q quits".into();
    } else if let Some((what, how)) = unsaved(model).filter(|_| asked != Some(Confirm::Leave)) {
        model.confirm = Some(Confirm::Leave);
        model.status = format!("esc again leaves without saving; unsaved {what}: {how}");
    } else if let Screen::Fill(super::model::FillView { from: Some(view), .. }) = &mut model.screen {
        let view = std::mem::replace(view, Box::new(ExemplarView::new("")));
        model.status = format!("back to {}", view.name);
        model.screen = Screen::Exemplar(*view);
    } else {
        // The left screen's messages do not follow onto the library.
        model.screen = Screen::Library;
        model.status =
            format!("{} exemplar(s): enter opens, b builds, e edits, c copies, d deletes", model.items.len());
    }
    Vec::new()
}

fn select(model: &mut Model, step: i64) {
    if let Screen::Editor(e) = &mut model.screen {
        let count = e.text.as_deref().and_then(|t| super::edit::fields(t, &e.name).ok()).map_or(0, |f| f.len());
        e.selected = (e.selected as i64).saturating_add(step).clamp(0, count.saturating_sub(1) as i64) as usize;
        return;
    }
    let rows = model.visible();
    let Some(&last) = rows.last() else { return };
    let at = rows.iter().position(|&i| i >= model.selected).unwrap_or(rows.len() - 1) as i64;
    let to = at.saturating_add(step).clamp(0, rows.len() as i64 - 1) as usize;
    let before = model.selected;
    model.selected = rows.get(to).copied().unwrap_or(last);
    if model.selected != before {
        model.status = about(&model.items[model.selected]);
    }
}

/// What the status row says when an entry is selected: why it needs a build or why it
/// failed, else nothing (a message about the entry left would be stale).
fn about(item: &super::model::Item) -> String {
    match &item.state {
        BuildState::Changed(_, why) => format!("{} changed since its last build ({why}): b rebuilds it", item.name),
        BuildState::Failed(e, _) => format!("{} failed: {e}", item.name),
        BuildState::Broken(e) => format!("{} has a mistake (e opens it): {e}", item.name),
        _ => String::new(),
    }
}

/// The filter changed: the selection moves onto the first entry it keeps when the selected
/// one is hidden, and the status says how many are shown.
fn filtered(model: &mut Model) {
    let rows = model.visible();
    if !rows.contains(&model.selected)
        && let Some(&first) = rows.first()
    {
        model.selected = first;
    }
    model.status = if model.filter.is_empty() {
        format!("every entry shown ({})", model.items.len())
    } else {
        format!(
            "{} of {} entries hold {:?} (/ changes it, esc in it clears it)",
            rows.len(),
            model.items.len(),
            model.filter
        )
    };
}

fn showing_mask(model: &Model) -> bool {
    matches!(&model.screen, Screen::Exemplar(v) if v.layer > 0)
}

const COMPARING: &str = "the photo and the slice at the same pixel scale: x/y/z and arrows choose the slice";

/// `p`: the photo of the slice axis beside the slice (read the first time), or back to
/// the three slices.
fn photo(model: &mut Model) -> Vec<Effect> {
    let Screen::Exemplar(v) = &mut model.screen else { return Vec::new() };
    if v.stamp.is_some() {
        model.status = "leave stamp mode (m) to compare with the photo".into();
        return Vec::new();
    }
    v.beside_photo = !v.beside_photo;
    if !v.beside_photo {
        model.status = "the three slices".into();
        return Vec::new();
    }
    match &v.photos {
        None => {
            model.status = format!("reading the photos of {}", v.name);
            vec![Effect::LoadPhotos(v.name.clone())]
        }
        Some(Err(e)) => {
            model.status = format!("no photo to compare with: {e}");
            v.beside_photo = false;
            Vec::new()
        }
        Some(Ok(_)) => {
            model.status = COMPARING.into();
            Vec::new()
        }
    }
}

/// `a`: load the masks the first time, then cycle exemplar -> masks -> exemplar.
fn next_layer(model: &mut Model) -> Vec<Effect> {
    let Screen::Exemplar(v) = &mut model.screen else { return Vec::new() };
    let Some(volume) = v.volume.clone() else { return Vec::new() };
    if v.stamp.is_some() {
        model.status = "leave stamp mode (m) to look at the masks".into();
        return Vec::new();
    }
    if v.layers.is_empty() {
        v.layers.push(("exemplar".into(), volume));
        return vec![Effect::LoadMasks(v.name.clone())];
    }
    if v.layers.len() == 1 {
        model.status =
            format!("{} has no built masks (add masks = [\"splotch\"] or [\"layered\"] to its entry)", v.name);
        return Vec::new();
    }
    v.layer = (v.layer + 1) % v.layers.len();
    v.volume = Some(v.layers[v.layer].1.clone());
    v.channel = 0;
    model.status = format!("showing {} of {} (a: next)", v.layers[v.layer].0, v.name);
    Vec::new()
}

fn masks_loaded(
    model: &mut Model,
    name: &str,
    result: Result<Vec<(String, std::sync::Arc<crate::volume::Volume>)>, String>,
) {
    let Screen::Exemplar(v) = &mut model.screen else { return };
    if v.name != name {
        return;
    }
    match result {
        Ok(masks) => {
            v.layers.extend(masks);
            next_layer(model);
        }
        Err(e) => model.status = format!("cannot load the masks: {e}"),
    }
}

/// What would be lost by leaving the screen (recipe edits, stamps or fill constraints not
/// yet saved, also under a file picker opened from them, or a new entry half made), and
/// how to keep it.
fn unsaved(model: &Model) -> Option<(&'static str, &'static str)> {
    use super::new_entry::{NewEntry, PickFor};
    let (edits, stamps, constraints) =
        (("recipe edits", "s saves them"), ("stamps", "s saves them"), ("fill constraints", "w writes them"));
    let under = |what: (&'static str, &'static str)| (what.0, "esc goes back to them");
    match &model.screen {
        Screen::Editor(e) if edits_unsaved(e) => Some(edits),
        Screen::Exemplar(v) if stamped(v) => Some(stamps),
        Screen::Fill(v) if constrained(v) => Some(constraints),
        Screen::New(NewEntry { pick_for: Some(PickFor::Step(e, _)), .. }) if edits_unsaved(e) => Some(under(edits)),
        Screen::New(NewEntry { pick_for: Some(PickFor::Seed(v)), .. }) if stamped(v) => Some(under(stamps)),
        Screen::New(NewEntry { pick_for: Some(PickFor::Spec(v)), .. }) if constrained(v) => Some(under(constraints)),
        Screen::New(NewEntry { pick_for: None, picker: Some(_), .. }) => {
            Some(("new entry (no file chosen yet)", "enter on a file adds it"))
        }
        _ => None,
    }
}

fn edits_unsaved(editor: &super::model::Editor) -> bool {
    editor.text.as_ref().is_some_and(|t| *t != editor.saved)
}

fn stamped(view: &ExemplarView) -> bool {
    view.stamp.as_ref().is_some_and(|s| !s.steps.is_empty())
}

fn constrained(view: &super::model::FillView) -> bool {
    view.edit.as_ref().is_some_and(|e| e.spec != *e.saved || !e.stroke.is_empty())
}

fn stamps_unsaved(model: &Model) -> bool {
    matches!(&model.screen, Screen::Exemplar(v) if stamped(v))
}

fn with_view(model: &mut Model, f: impl FnOnce(&mut ExemplarView)) {
    if let Screen::Exemplar(view) = &mut model.screen {
        f(view);
    }
}

/// A click on row `row` of the library or the editor's fields: select it; a click on the
/// selected row opens it (the library) or edits it (the editor).
fn click(model: &mut Model, row: usize) -> Vec<Effect> {
    if matches!(model.screen, Screen::Library) {
        let Some(&item) = model.visible().get(row) else { return Vec::new() };
        if item == model.selected {
            return update(model, Message::Open);
        }
        model.selected = item;
        model.status = about(&model.items[item]);
        return Vec::new();
    }
    let current = match &model.screen {
        Screen::Editor(e) if e.input.is_none() => e.selected,
        _ => return Vec::new(),
    };
    if row == current {
        let again = if matches!(model.screen, Screen::Library) { Message::Open } else { Message::Commit };
        return update(model, again);
    }
    select(model, row as i64 - current as i64);
    Vec::new()
}

/// The other two slices through the voxel at (`a`, `b`) of the slice across `axis`.
fn point_at(view: &mut ExemplarView, axis: Axis, a: usize, b: usize) {
    let Some(volume) = &view.volume else { return };
    let d = volume.dims();
    let (pa, pb) = axis.plane_axes();
    view.index[pa] = a.min(d[pa] - 1);
    view.index[pb] = b.min(d[pb] - 1);
}

fn move_slice(view: &mut ExemplarView, step: i64) {
    let Some(volume) = &view.volume else { return };
    let k = view.axis.index();
    let last = volume.dims()[k] as i64 - 1;
    view.index[k] = (view.index[k] as i64 + step).clamp(0, last) as usize;
}

fn open(model: &mut Model) -> Vec<Effect> {
    if model.first_run {
        return vec![Effect::StartLibrary];
    }
    let Some(item) = model.items.get(model.selected) else { return Vec::new() };
    if let BuildState::Broken(reason) = &item.state {
        model.status = format!("{} has a mistake (e opens it to fix): {reason}", item.name);
        return Vec::new();
    }
    let older = matches!(item.state, BuildState::Failed(_, true));
    if !older && !matches!(item.state, BuildState::Built(_) | BuildState::Changed(..)) {
        model.status = format!("{} is not built yet: press b to build it", item.name);
        return Vec::new();
    }
    let name = item.name.clone();
    model.screen = Screen::Exemplar(ExemplarView { older, ..ExemplarView::new(&name) });
    model.status = if older {
        format!("loading the earlier build of {name} (its latest build failed)")
    } else {
        format!("loading {name}")
    };
    vec![Effect::Load(name)]
}

fn build(model: &mut Model, all: bool) -> Vec<Effect> {
    let selected = model.selected;
    let names = wanted(model, |i, _| all || i == selected);
    if names.is_empty() {
        if let Some(BuildState::Broken(reason)) = model.items.get(model.selected).map(|i| &i.state)
            && !all
        {
            model.status = format!("this entry has a mistake (e opens it to fix): {reason}");
        }
        return Vec::new();
    }
    queue(model, names)
}

/// `R`: build the entries changed since their last build and those never built.
fn build_changed(model: &mut Model) -> Vec<Effect> {
    let names = wanted(model, |_, state| matches!(state, BuildState::Changed(..) | BuildState::NotBuilt));
    if names.is_empty() {
        model.status = "every entry is built and none changed since".into();
        return Vec::new();
    }
    queue(model, names)
}

/// The names of the entries `pick` chooses (by row and state) that can build now.
fn wanted(model: &Model, pick: impl Fn(usize, &BuildState) -> bool) -> Vec<String> {
    let rows = model.items.iter().enumerate().filter(|(i, item)| pick(*i, &item.state));
    rows.filter(|(_, item)| !item.state.busy() && !matches!(item.state, BuildState::Broken(_)))
        .map(|(_, item)| item.name.clone())
        .collect()
}

/// Marks `names` waiting for their turn (the worker says when it starts) and starts it.
fn queue(model: &mut Model, names: Vec<String>) -> Vec<Effect> {
    let waiting = model.items.iter().any(|i| i.state.busy());
    match &mut model.batch {
        Some(batch) if waiting => batch.total += names.len(),
        _ => model.batch = Some(Batch { total: names.len(), done: 0, started: model.now }),
    }
    for item in model.items.iter_mut().filter(|i| names.contains(&i.name)) {
        item.state = BuildState::Queued;
    }
    model.status = if waiting {
        format!("{} wait(s) for the build before them (esc cancels all)", names.join(", "))
    } else {
        format!("building {} (esc cancels)", names.join(", "))
    };
    vec![Effect::Build(names)]
}

fn loaded(model: &mut Model, name: &str, result: Result<std::sync::Arc<crate::volume::Volume>, String>) {
    match result {
        Ok(volume) => {
            let d = volume.dims();
            model.status = format!("{name}: {}x{}x{}; x/y/z choose the axis, arrows move the slice", d[0], d[1], d[2]);
            with_view(model, |v| {
                if v.name == name {
                    v.index = [d[0] / 2, d[1] / 2, d[2] / 2];
                    v.volume = Some(volume);
                }
            });
        }
        Err(e) => {
            model.status = format!("cannot open {name}: {e}");
            model.screen = Screen::Library;
        }
    }
}

fn built(model: &mut Model, name: &str, result: Result<crate::tui::model::Item, String>) {
    model.progress.remove(name);
    finished_one(model);
    if let Some(item) = model.items.iter_mut().find(|i| i.name == name) {
        match result {
            Ok(row) => {
                match &row.state {
                    BuildState::Built(kind) => model.status = format!("built {name} (measured type {kind})"),
                    BuildState::Failed(e, true) => {
                        model.status = format!("{name} failed; its earlier build stays (enter opens it): {e}")
                    }
                    BuildState::Failed(e, false) => model.status = format!("{name} failed: {e}"),
                    _ => {}
                }
                *item = row;
            }
            Err(e) => {
                model.status = format!("{name} failed: {e}");
                item.state = BuildState::Failed(e, false);
            }
        }
    }
}

/// A build was cancelled before it finished: `row` is the entry as its previous output
/// left it (that output is kept).
fn cancelled(model: &mut Model, name: &str, row: crate::tui::model::Item) {
    model.progress.remove(name);
    finished_one(model);
    model.previews.remove(name);
    let kept = matches!(row.state, BuildState::Built(_) | BuildState::Changed(..));
    if let Some(item) = model.items.iter_mut().find(|i| i.name == name) {
        *item = row;
    }
    model.status = if kept {
        format!("cancelled {name}: its previous output is kept")
    } else {
        format!("cancelled {name}: it has no output yet")
    };
}

/// One build of the batch ended; the batch ends with the last.
fn finished_one(model: &mut Model) {
    if let Some(batch) = &mut model.batch {
        batch.done = (batch.done + 1).min(batch.total);
        if batch.done == batch.total {
            model.batch = None;
        }
    }
}

/// Mark exemplar `name` as changed since its last build (its recipe was saved; `valid`:
/// the saved entry passed the manifest rules, so a broken one is now buildable).
pub fn mark_changed(model: &mut Model, name: &str, valid: bool) {
    if valid {
        // its mistake is fixed: the list of the manifest's mistakes drops it
        let own = format!("({name})");
        model.errors.retain(|e| !e.contains(&own));
    }
    for item in model.items.iter_mut().filter(|i| i.name == name) {
        match &item.state {
            BuildState::Built(kind) => item.state = BuildState::Changed(kind.clone(), "its recipe was saved".into()),
            BuildState::Broken(_) if valid => item.state = BuildState::NotBuilt,
            _ => {}
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::tui::model::Item;
    use crate::volume::{Axis, Channel, Volume};
    use std::path::PathBuf;
    use std::sync::Arc;

    fn model() -> Model {
        let item = |n: &str, state| Item {
            name: n.into(),
            declared: Some("0".into()),
            size: Some([8; 3]),
            state,
            quality: None,
            previous: false,
        };
        let items = vec![item("a", BuildState::Built("0".into())), item("b", BuildState::NotBuilt)];
        Model::new(PathBuf::from("lib.toml"), PathBuf::from("out"), items, Vec::new())
    }

    /// `p` reads the photos once and toggles them beside the slice; an entry made without
    /// one says why and stays on its three slices.
    /// The status belongs to what is on screen: selecting another entry replaces a message
    /// about the last one, a message clears after its time, and the log keeps them all.
    #[test]
    fn the_status_follows_the_selection_times_out_and_is_logged() {
        let mut m = model();
        update(&mut m, Message::Built("a".into(), Err("no such photo".into())));
        assert!(m.status.starts_with("a failed"), "{}", m.status);
        update(&mut m, Message::Jump(1));
        assert_eq!((m.selected, m.status.as_str()), (1, ""), "the message about a left with it");
        update(&mut m, Message::Jump(-1));
        assert!(m.status.starts_with("a failed: no such photo"), "the failed entry says why: {}", m.status);
        for s in 1..STATUS_SECONDS {
            update(&mut m, Message::Tick(std::time::Duration::from_secs(u64::from(s))));
        }
        assert!(!m.status.is_empty(), "shown {} s", STATUS_SECONDS - 1);
        update(&mut m, Message::Tick(std::time::Duration::from_secs(99)));
        assert!(m.status.is_empty(), "cleared after {STATUS_SECONDS} s");
        let logged: Vec<_> = m.log.iter().filter(|l| l.contains("a failed")).collect();
        assert_eq!(logged.len(), 2, "{:?}", m.log);
        assert!(logged[0].starts_with("00:00 "), "{:?}", logged);
        update(&mut m, Message::ShowLog);
        assert!(m.log_view.is_some());
        update(&mut m, Message::ShowLog);
        assert!(m.log_view.is_none());
    }

    /// g/G, pgup/pgdn and the filter move the selection among the entries shown; esc in the
    /// filter shows them all again.
    #[test]
    fn the_list_jumps_and_filters() {
        let mut m = model();
        let names = ["c", "kiwi", "kiwi-2", "marble", "oak"];
        for n in names {
            m.items.push(Item { name: n.into(), ..m.items[0].clone() });
        }
        update(&mut m, Message::Jump(crate::tui::keymap::END));
        assert_eq!(m.selected, 6);
        update(&mut m, Message::Jump(-crate::tui::keymap::PAGE));
        assert_eq!(m.selected, 0);
        update(&mut m, Message::Filter);
        for c in "KIWI".chars() {
            update(&mut m, Message::Input(tui_input::InputRequest::InsertChar(c)));
        }
        assert_eq!(m.visible(), [3, 4]);
        assert_eq!(m.selected, 3, "the selection moves onto the first entry shown");
        update(&mut m, Message::Commit);
        assert!(m.prompt.is_none() && m.filter == "KIWI" && m.status.contains("2 of 7"), "{}", m.status);
        update(&mut m, Message::Jump(crate::tui::keymap::END));
        assert_eq!(m.selected, 4);
        update(&mut m, Message::Select(0));
        assert_eq!(m.selected, 3, "a click picks the row as shown");
        update(&mut m, Message::Filter);
        update(&mut m, Message::Cancel);
        assert_eq!((m.filter.as_str(), m.visible().len()), ("", 7));
    }

    /// Builds asked together count done/total, and a refused rename gives its prompt back.
    #[test]
    fn a_batch_counts_its_builds_and_a_refused_rename_keeps_the_name_typed() {
        let mut m = model();
        update(&mut m, Message::Tick(std::time::Duration::from_secs(5)));
        update(&mut m, Message::BuildAll);
        assert_eq!(m.batch, Some(Batch { total: 2, done: 0, started: std::time::Duration::from_secs(5) }));
        update(&mut m, Message::Built("a".into(), Err("x".into())));
        assert_eq!(m.batch.as_ref().map(|b| b.done), Some(1));
        update(&mut m, Message::Built("b".into(), Err("x".into())));
        assert_eq!(m.batch, None);
        update(&mut m, Message::Rename);
        update(&mut m, Message::Input(tui_input::InputRequest::InsertChar('x')));
        let effects = update(&mut m, Message::Commit);
        assert_eq!(effects, vec![Effect::ChangeEntry(EntryChange::Rename("a".into(), "ax".into()))]);
        update(&mut m, Message::EntriesChanged(Err("the name \"ax\" is taken".into())));
        assert_eq!(m.prompt.as_ref().map(|p| p.input.value()), Some("ax"));
        assert!(m.prompt.as_ref().is_some_and(|p| p.note.contains("is taken")));
        // a mistake fixed and saved leaves the list of the manifest's mistakes
        m.errors = vec!["lib.toml: line 9: entry 2 (b): size is missing".into(), "line 1: entry 3 (c): x".into()];
        mark_changed(&mut m, "b", true);
        assert_eq!(m.errors, ["line 1: entry 3 (c): x"]);
    }

    #[test]
    fn p_shows_the_photo_beside_the_slice() {
        let mut m = model();
        update(&mut m, Message::Open);
        assert_eq!(update(&mut m, Message::Photo), vec![Effect::LoadPhotos("a".into())]);
        let photo = crate::volume::Image2d::from_data(1, 1, crate::volume::Channel::grey(), vec![0.5]).unwrap();
        update(&mut m, Message::PhotosLoaded("a".into(), Ok(Arc::new([Some(photo), None, None]))));
        let Screen::Exemplar(v) = &m.screen else { panic!("the slices") };
        assert!(v.beside_photo && m.status.contains("same pixel scale"), "{}", m.status);
        assert!(update(&mut m, Message::Photo).is_empty(), "read once");
        assert!(update(&mut m, Message::Photo).is_empty());
        let Screen::Exemplar(v) = &mut m.screen else { panic!("the slices") };
        assert!(v.beside_photo);
        v.photos = None;
        update(&mut m, Message::Photo);
        update(&mut m, Message::Photo);
        update(&mut m, Message::PhotosLoaded("a".into(), Err("a is not made from an image".into())));
        let Screen::Exemplar(v) = &m.screen else { panic!("the slices") };
        assert!(!v.beside_photo && m.status.contains("not made from an image"), "{}", m.status);
    }

    /// The help's search: `/` starts it, keys type it (keys of the screen below do
    /// nothing), esc clears it, esc again closes the help.
    #[test]
    fn the_help_is_searched_and_closed_with_esc() {
        use crate::tui::keymap::{help_key, help_rows};
        use crossterm::event::{KeyCode, KeyEvent, KeyModifiers};
        let press = |m: &Model, code| help_key(m.help.as_ref().unwrap(), KeyEvent::new(code, KeyModifiers::NONE));
        let mut m = model();
        update(&mut m, Message::Help);
        assert!(press(&m, KeyCode::Char('b')).is_none(), "b does not build under the help");
        for code in [KeyCode::Char('/'), KeyCode::Char('b'), KeyCode::Char('l'), KeyCode::Char('x'), KeyCode::Backspace]
        {
            let message = press(&m, code).expect("a help key");
            assert!(update(&mut m, message).is_empty());
        }
        for code in "ur".chars().map(KeyCode::Char).chain([KeyCode::Enter]) {
            let message = press(&m, code).unwrap();
            update(&mut m, message);
        }
        let help = m.help.clone().unwrap();
        assert_eq!((help.query.as_str(), help.typing), ("blur", false));
        let rows = help_rows(&m.screen, &help.query);
        assert_eq!(rows.iter().map(|r| r.0).collect::<Vec<_>>(), ["recipe editor"], "{rows:?}");
        assert!(m.items.iter().all(|i| i.state != BuildState::Building), "nothing was built");
        let esc = press(&m, KeyCode::Esc).unwrap();
        update(&mut m, esc.clone());
        assert_eq!(m.help, Some(Default::default()), "esc clears the search");
        update(&mut m, esc);
        assert_eq!(m.help, None, "esc again closes the help");
    }

    #[test]
    fn selection_stays_in_the_list_and_builds_mark_the_rows() {
        let mut m = model();
        update(&mut m, Message::Up);
        assert_eq!(m.selected, 0);
        update(&mut m, Message::Down);
        update(&mut m, Message::Down);
        assert_eq!(m.selected, 1);
        assert!(update(&mut m, Message::Open).is_empty(), "b is not built");
        assert!(m.status.contains("press b"));
        assert_eq!(update(&mut m, Message::Build), vec![Effect::Build(vec!["b".into()])]);
        assert_eq!(m.items[1].state, BuildState::Queued, "until the worker takes its turn");
        update(&mut m, Message::BuildStarted(vec!["b".into()]));
        assert_eq!(m.items[1].state, BuildState::Building);
        assert!(update(&mut m, Message::Build).is_empty(), "no second build while one runs");
        let row = Item {
            name: "b".into(),
            declared: Some("1-b".into()),
            size: Some([8; 3]),
            state: BuildState::Built("1-b".into()),
            quality: None,
            previous: false,
        };
        update(&mut m, Message::Built("b".into(), Ok(row)));
        assert_eq!(m.items[1].state, BuildState::Built("1-b".into()));
    }

    #[test]
    fn opening_loads_and_the_slice_keys_stay_inside_the_volume() {
        let mut m = model();
        assert_eq!(update(&mut m, Message::Open), vec![Effect::Load("a".into())]);
        let v = Arc::new(Volume::new([8, 6, 4], Channel::rgb()).unwrap());
        update(&mut m, Message::Loaded("a".into(), Ok(v)));
        update(&mut m, Message::MoveSlice(100));
        update(&mut m, Message::SelectAxis(Axis::X));
        update(&mut m, Message::MoveSlice(-100));
        let Screen::Exemplar(view) = &m.screen else { panic!("the exemplar view is open") };
        assert_eq!(view.index, [0, 3, 3]);
        m.status = "z = 3 of the exemplar view".into();
        update(&mut m, Message::Back);
        assert!(matches!(m.screen, Screen::Library));
        assert!(m.status.contains("exemplar(s)"), "the exemplar view's message stays behind: {}", m.status);
        update(&mut m, Message::Back);
        assert!(!m.quit && m.status.contains("q quits"), "esc on the library goes nowhere: {}", m.status);
        update(&mut m, Message::Quit);
        assert!(m.quit);
        // with a build running, q asks first and says the build is cancelled
        let mut m = model();
        m.items[0].state = BuildState::Building;
        update(&mut m, Message::Quit);
        assert!(!m.quit && m.status.contains("cancels the 1 build(s) running"), "{}", m.status);
        update(&mut m, Message::Quit);
        assert!(m.quit);
    }

    /// R builds the entries changed since their last build and those never built; a build
    /// asked while another runs waits its turn, and says so.
    #[test]
    fn r_rebuilds_the_changed_entries_and_later_builds_wait_their_turn() {
        let mut m = model();
        m.items[1].state = BuildState::Built("0".into());
        assert!(update(&mut m, Message::BuildChanged).is_empty());
        assert!(m.status.contains("every entry is built and none changed"), "{}", m.status);
        m.items[1].state = BuildState::NotBuilt;
        assert_eq!(update(&mut m, Message::BuildChanged), vec![Effect::Build(vec!["b".into()])]);
        m = model();
        m.items[0].state = BuildState::Changed("0".into(), "the recipe changed".into());
        update(&mut m, Message::Down);
        assert_eq!(update(&mut m, Message::Build), vec![Effect::Build(vec!["b".into()])]);
        update(&mut m, Message::BuildStarted(vec!["b".into()]));
        assert_eq!(update(&mut m, Message::BuildChanged), vec![Effect::Build(vec!["a".into()])]);
        assert_eq!((&m.items[0].state, &m.items[1].state), (&BuildState::Queued, &BuildState::Building));
        assert!(m.status.contains("a wait(s) for the build before them"), "{}", m.status);
        assert!(update(&mut m, Message::BuildChanged).is_empty(), "a is already queued");
        update(&mut m, Message::BuildStarted(vec!["a".into()]));
        assert_eq!(m.items[0].state, BuildState::Building);
    }

    #[test]
    fn build_progress_shows_and_esc_cancels_running_builds() {
        let mut m = model();
        update(&mut m, Message::Down);
        update(&mut m, Message::Build);
        update(&mut m, Message::BuildStarted(vec!["b".into()]));
        update(&mut m, Message::BuildProgress("b".into(), "level 2/3, iteration 1: searched".into(), 0.4));
        update(&mut m, Message::BuildProgress("a".into(), "level 1/3".into(), 0.1));
        assert_eq!(m.progress.len(), 1, "only running builds report");
        assert_eq!(update(&mut m, Message::Back), vec![Effect::CancelBuilds]);
        assert!(!m.quit && m.status.contains("cancelling"));
        // b had been built before: the cancelled build keeps that output and says so.
        let before = Item {
            name: "b".into(),
            declared: None,
            size: Some([8; 3]),
            state: BuildState::Built("0".into()),
            quality: None,
            previous: false,
        };
        update(&mut m, Message::BuildCancelled("b".into(), before));
        assert!(m.progress.is_empty());
        assert_eq!(m.items[1].state, BuildState::Built("0".into()));
        assert!(m.status.contains("cancelled b") && m.status.contains("previous output is kept"), "{}", m.status);
        assert!(!m.status.contains("built b"));
    }

    /// The editor with one unsaved edit of exemplar a.
    fn edited() -> Model {
        let mut m = model();
        update(&mut m, Message::Edit);
        update(
            &mut m,
            Message::EditorReady(Ok("[[exemplar]]\nname = \"a\"\nrecipe = \"procedural:marble\"\nsize = 8\n".into())),
        );
        let Screen::Editor(e) = &mut m.screen else { panic!("the editor") };
        e.text = Some(e.saved.replace("size = 8", "size = 16"));
        m
    }

    #[test]
    fn quitting_or_leaving_with_unsaved_edits_asks_first() {
        let mut m = edited();
        update(&mut m, Message::Quit);
        assert!(!m.quit && m.status.contains("unsaved recipe edits"), "{}", m.status);
        update(&mut m, Message::Down);
        update(&mut m, Message::Quit);
        assert!(!m.quit, "another key in between asks again");
        update(&mut m, Message::Previewed(99, Err("late".into()), Vec::new()));
        update(&mut m, Message::Tick(std::time::Duration::from_secs(5)));
        update(&mut m, Message::Quit);
        assert!(m.quit, "the second q quits; a worker's result or the clock in between does not reset the question");
        let mut m = edited();
        update(&mut m, Message::Cancel);
        assert!(matches!(m.screen, Screen::Editor(_)) && m.status.contains("esc again"), "{}", m.status);
        update(&mut m, Message::Cancel);
        assert!(matches!(m.screen, Screen::Library));
        // a mesh picker opened from unsaved edits still asks; esc goes back to them
        let mut m = edited();
        update(&mut m, Message::AddMeshStep(true));
        assert!(matches!(m.screen, Screen::New(_)));
        update(&mut m, Message::Quit);
        assert!(!m.quit && m.status.contains("unsaved recipe edits: esc goes back to them"), "{}", m.status);
        update(&mut m, Message::Back);
        assert!(matches!(m.screen, Screen::Editor(_)), "esc in the picker goes back to the editor");
        // a new entry whose file is not chosen yet asks too
        let mut m = model();
        update(&mut m, Message::New);
        update(&mut m, Message::Open);
        update(&mut m, Message::Quit);
        assert!(!m.quit && m.status.contains("unsaved new entry"), "{}", m.status);
    }

    #[test]
    fn the_fill_preview_centres_each_new_axis_and_esc_goes_back_to_the_exemplar() {
        let mut m = model();
        update(&mut m, Message::Open);
        let v = Arc::new(Volume::new([8, 8, 8], Channel::rgb()).unwrap());
        update(&mut m, Message::Loaded("a".into(), Ok(v)));
        update(&mut m, Message::SelectAxis(Axis::Y));
        assert_eq!(update(&mut m, Message::FillPreview), vec![Effect::Fill("a".into())]);
        update(&mut m, Message::MovePlane(0.25));
        update(&mut m, Message::SelectAxis(Axis::Z));
        let Screen::Fill(f) = &m.screen else { panic!("the fill preview") };
        assert_eq!((f.axis, f.offset), (Axis::Z, 0.0), "a new axis cuts through the centre");
        update(&mut m, Message::MovePlane(0.05));
        update(&mut m, Message::SelectAxis(Axis::Z));
        let Screen::Fill(f) = &m.screen else { panic!("the fill preview") };
        assert_eq!(f.offset, 0.05, "the same axis keeps its cut");
        update(&mut m, Message::Back);
        let Screen::Exemplar(view) = &m.screen else { panic!("back to the exemplar view, not the library") };
        assert_eq!((view.name.as_str(), view.axis), ("a", Axis::Y));
        assert!(view.volume.is_some(), "its volume is still loaded");
    }

    #[test]
    fn a_saved_edit_marks_the_entry_changed_since_its_build() {
        let mut m = edited();
        let Screen::Editor(e) = &m.screen else { panic!("the editor") };
        let text = e.text.clone().unwrap();
        update(&mut m, Message::Saved(Ok(text)));
        assert!(matches!(&m.items[0].state, BuildState::Changed(t, _) if t == "0"));
        update(&mut m, Message::Quit);
        assert!(m.quit, "nothing unsaved after saving");
        let mut m = model();
        m.items[0].state = BuildState::Changed("0".into(), "the input p.png changed".into());
        update(&mut m, Message::Down);
        update(&mut m, Message::Up);
        assert!(m.status.contains("a changed since its last build (the input p.png changed)"), "{}", m.status);
        assert_eq!(update(&mut m, Message::Open), vec![Effect::Load("a".into())], "its previous output opens");
    }

    #[test]
    fn zoom_is_bounded_and_a_cycles_through_the_masks() {
        let mut m = model();
        update(&mut m, Message::Open);
        let v = Arc::new(Volume::new([8, 8, 8], Channel::rgb()).unwrap());
        update(&mut m, Message::Loaded("a".into(), Ok(v.clone())));
        for _ in 0..3 {
            update(&mut m, Message::Zoom(true));
        }
        update(&mut m, Message::Zoom(false));
        assert_eq!(update(&mut m, Message::NextLayer), vec![Effect::LoadMasks("a".into())]);
        let mask = Arc::new(Volume::new([8, 8, 8], Channel::grey()).unwrap());
        update(&mut m, Message::MasksLoaded("a".into(), Ok(vec![("splotch mask".into(), mask.clone())])));
        let Screen::Exemplar(view) = &m.screen else { panic!("the exemplar view") };
        assert_eq!(view.zoom, 2);
        assert!(Arc::ptr_eq(view.volume.as_ref().unwrap(), &mask) && m.status.contains("splotch mask"));
        assert!(update(&mut m, Message::StampMode).is_empty() && m.status.contains("not on a mask"));
        update(&mut m, Message::NextLayer);
        let Screen::Exemplar(view) = &m.screen else { panic!("the exemplar view") };
        assert!(Arc::ptr_eq(view.volume.as_ref().unwrap(), &v), "back to the exemplar");
    }
    /// A save that finds the entry changed on disk asks; m keeps mine (saved again onto the
    /// file as it reads), t takes theirs (u brings mine back), esc leaves it unsaved.
    #[test]
    fn an_entry_changed_on_disk_too_is_never_saved_over_silently() {
        let mut m = edited();
        let Screen::Editor(e) = &m.screen else { panic!("the editor") };
        let (base, mine) = (e.saved.clone(), e.text.clone().unwrap());
        let save = Effect::Save { name: "a".into(), base: base.clone(), text: mine.clone() };
        assert_eq!(update(&mut m, Message::Save), vec![save]);
        let theirs = format!("# noted\n{}", base.replace("size = 8", "size = 12"));
        update(&mut m, Message::SaveConflict(theirs.clone()));
        assert!(m.status.contains("changed on disk: m keeps yours"), "{}", m.status);
        update(&mut m, Message::Resolve('b'));
        let Screen::Editor(e) = &m.screen else { panic!("the editor") };
        assert!(e.conflict.as_ref().is_some_and(|c| c.both));
        let effects = update(&mut m, Message::Resolve('m'));
        let kept = format!("# noted\n{}", mine);
        assert_eq!(effects[0], Effect::Save { name: "a".into(), base: theirs.clone(), text: kept.clone() });
        let mut m = edited();
        update(&mut m, Message::SaveConflict(theirs.clone()));
        update(&mut m, Message::Resolve('t'));
        let Screen::Editor(e) = &m.screen else { panic!("the editor") };
        assert_eq!((e.text.as_deref(), e.saved.as_str()), (Some(theirs.as_str()), theirs.as_str()));
        update(&mut m, Message::Undo);
        let Screen::Editor(e) = &m.screen else { panic!("the editor") };
        assert_eq!(e.text.as_deref(), Some(kept.as_str()), "u brings mine back onto their file");
        let mut m = edited();
        update(&mut m, Message::SaveConflict(theirs));
        update(&mut m, Message::Cancel);
        let Screen::Editor(e) = &m.screen else { panic!("the editor") };
        assert!(e.conflict.is_none() && e.text.as_deref() == Some(mine.as_str()) && m.status.contains("not saved"));
        update(&mut m, Message::ChangedOnDisk);
        assert!(m.outside && m.status.contains("Ctrl-R reloads"));
        assert_eq!(update(&mut m, Message::Reload), vec![Effect::ReadManifest]);
    }

    /// `u` on the library undoes the last library operation by its inverse change; a failed
    /// rebuild whose earlier build is there still opens it.
    #[test]
    fn library_operations_undo_and_a_failed_build_keeps_its_earlier_one() {
        let mut m = model();
        update(&mut m, Message::Undo);
        assert!(m.status.contains("no library operation to undo"));
        let change = crate::tui::Change {
            items: m.items.clone(),
            errors: Vec::new(),
            select: "a-2".into(),
            status: "copied a as a-2".into(),
            inverse: Some((EntryChange::Delete("a-2".into()), "the copy a-2".into())),
        };
        update(&mut m, Message::EntriesChanged(Ok(change)));
        let undo = EntryChange::Delete("a-2".into());
        assert_eq!(update(&mut m, Message::Undo), vec![Effect::UndoEntry(undo, "the copy a-2".into())]);
        assert!(m.undo.is_empty());
        let row = Item { state: BuildState::Failed("no image".into(), true), ..m.items[0].clone() };
        update(&mut m, Message::Built("a".into(), Ok(row)));
        assert!(m.status.contains("a failed; its earlier build stays (enter opens it): no image"), "{}", m.status);
        assert_eq!(update(&mut m, Message::Open), vec![Effect::Load("a".into())]);
        assert!(matches!(&m.screen, Screen::Exemplar(v) if v.older));
        let mut m = model();
        m.items[1].state = BuildState::Failed("no image".into(), false);
        m.selected = 1;
        assert!(update(&mut m, Message::Open).is_empty() && m.status.contains("not built yet"));
    }
}
