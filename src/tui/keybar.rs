//! The key bar: the keys of the screen on top, one line, always shown; a key that cannot
//! act now is dimmed and says why (lazygit's rule). Pure: the model in, hints out.

use super::edit;
use super::model::{BuildState, Editor, Model, Screen};

/// One key (or group of keys) and what it does.
#[derive(Debug, Clone, PartialEq)]
pub struct Hint {
    /// The key as shown, e.g. `enter` or `x/y/z`.
    pub keys: &'static str,
    /// What it does.
    pub action: &'static str,
    /// Why it does nothing now, if it does not.
    pub why_not: Option<&'static str>,
}

fn hint(keys: &'static str, action: &'static str) -> Hint {
    Hint { keys, action, why_not: None }
}

fn unless(keys: &'static str, action: &'static str, why_not: Option<&'static str>) -> Hint {
    Hint { keys, action, why_not }
}

/// Why the key named `name` (as the bar writes keys: `b`, `enter`, `esc`) does nothing
/// now, when the bar shows it dimmed: its keys, action and reason.
pub fn why_dimmed(model: &Model, name: &str) -> Option<String> {
    hints(model).into_iter().find_map(|h| {
        let why = h.why_not?;
        h.keys.split(['/', ' ', ',']).any(|k| k == name).then(|| format!("{} {}: {why}", h.keys, h.action))
    })
}

/// The hints of the screen on top of `model`, most used first (`?` help and `q` quit stay
/// at the right of the status line).
pub fn hints(model: &Model) -> Vec<Hint> {
    if let Some(prompt) = &model.prompt {
        let (enter, esc) = match prompt.purpose {
            super::model::Purpose::Rename => ("rename", "keep the name"),
            super::model::Purpose::SaveAs => ("save as", "do not save"),
            super::model::Purpose::Filter => ("keep the filter", "show every entry"),
        };
        return vec![hint("enter", enter), hint("esc", esc), hint("ctrl-u", "clear")];
    }
    match &model.screen {
        Screen::Library => library(model),
        Screen::Exemplar(view) if view.stamp.is_some() => vec![
            hint("enter", "stamp"),
            hint("arrows/pgup/pgdn", "move"),
            hint("r/R", "turn"),
            hint("+/-", "scale"),
            hint("s", "save"),
            hint("m", "leave"),
            hint("n", "scatter"),
            hint("u", "undo"),
            hint("o", "seed mesh"),
        ],
        Screen::Exemplar(view) => {
            let loading = view.volume.is_none().then_some("loading");
            vec![
                hint("x/y/z", "axis"),
                hint("arrows", "slice"),
                unless("f", "fill", loading),
                unless("p", "photo", loading),
                unless("E", "export", loading),
                unless("W", "3D", loading),
                hint("esc", "back"),
                unless("a", "masks", view.layers.is_empty().then_some("no masks built")),
                unless("m", "stamp", loading),
                hint("c", "channel"),
                hint("+/-", "zoom"),
            ]
        }
        Screen::Editor(editor) if editor.picker.is_some() => {
            vec![hint("up/down", "field"), hint("enter", "add it"), hint("esc", "close")]
        }
        Screen::Editor(editor) if editor.input.is_some() => {
            vec![hint("enter", "keep the value"), hint("esc", "drop it"), hint("ctrl-u", "clear")]
        }
        Screen::Editor(editor) => editing(editor),
        Screen::New(entry) if entry.picker.is_some() => {
            vec![
                hint("up/down", "file"),
                hint("enter", "take it / open folder"),
                hint("backspace", "folder above"),
                hint("esc", "back"),
            ]
        }
        Screen::New(_) => vec![hint("up/down", "kind"), hint("enter", "take it"), hint("esc", "back")],
        Screen::Compare(view) => {
            let settle = view.before_after.is_none().then_some("only beside a previous build: V");
            vec![
                hint("x/y/z", "axis"),
                hint("arrows", "both slices"),
                unless("a", "keep new", settle),
                unless("d", "discard new", settle),
                hint("esc", "back"),
            ]
        }
        Screen::Fill(view) => {
            let filling = view.filled.is_none().then_some("filling");
            vec![
                unless("x/y/z", "cut", filling),
                unless("arrows", "move", filling),
                unless("s/S", "stroke", filling),
                unless("d", "depth", filling),
                unless("p", "paste", filling),
                unless("r", "refill", filling),
                unless("w", "write spec", filling),
                unless("v", "field/guided", filling),
                hint("esc", "back"),
                unless("u", "undo", filling),
                unless("E", "export", filling),
                unless("W", "3D", filling),
                unless("c", "depth map", filling),
                unless("o", "load spec", filling),
            ]
        }
    }
}

fn library(model: &Model) -> Vec<Hint> {
    if model.first_run {
        return vec![hint("enter", "start a library here"), hint("q", "quit")];
    }
    let item = model.items.get(model.selected);
    let state = item.map(|i| &i.state);
    let open = match state {
        None => Some("no entry"),
        Some(BuildState::NotBuilt) => Some("not built: b"),
        Some(BuildState::Broken(_)) => Some("a mistake: e"),
        _ => None,
    };
    let build = match state {
        None => Some("no entry"),
        Some(BuildState::Building) => Some("building"),
        Some(BuildState::Queued) => Some("waiting"),
        Some(BuildState::Broken(_)) => Some("a mistake: e"),
        _ => None,
    };
    let busy = model.items.iter().any(|i| i.state.busy());
    let none = item.is_none().then_some("no entry");
    let building_all = busy.then_some("building").or(none);
    let stale = model.items.iter().any(|i| matches!(i.state, BuildState::Changed(..) | BuildState::NotBuilt));
    let mut keys = vec![
        unless("enter", "open", open),
        unless("b", "build", build),
        unless("e", "edit", none),
        hint("n", "new"),
        unless("B", "build all", building_all),
        unless("R", "build changed", none.or((!stale).then_some("all built, none changed"))),
        hint("/", "filter"),
        unless("v", "compare", open.map(|_| "not built")),
        unless("c", "copy", none),
        unless("d", "delete", none),
        unless("r", "rename", none),
        unless("V", "before/after", (!item.is_some_and(|i| i.previous)).then_some("no previous build")),
    ];
    if busy {
        keys.insert(0, hint("esc", "cancel builds"));
    }
    if !model.errors.is_empty() {
        keys.insert(1, hint("[/]", "scroll mistakes"));
    }
    keys
}

fn editing(editor: &Editor) -> Vec<Hint> {
    let loading = editor.text.is_none().then_some("loading");
    let on_step = editor
        .text
        .as_deref()
        .and_then(|text| edit::fields(text, &editor.name).ok())
        .and_then(|fields| fields.get(editor.selected).and_then(|f| edit::step_of(&f.key)))
        .is_some();
    let not_step = (!on_step).then_some("not on a step");
    let unsaved = editor.text.as_deref().is_some_and(|t| t != editor.saved);
    vec![
        unless("enter", "edit", loading),
        unless("s", "save", (!unsaved).then_some("no changes")),
        unless("+", "add field", loading),
        unless("-", "remove field", loading),
        unless("o", "$EDITOR", loading.or(unsaved.then_some("save first"))),
        unless("u", "undo", editor.undo.is_empty().then_some("nothing to undo")),
        hint("esc", "back"),
        unless("r", "redo", editor.redo.is_empty().then_some("nothing to redo")),
        unless("a", "add blur", loading),
        unless("t/n", "add stamp/scatter", loading),
        unless("x", "remove step", not_step),
        unless("K/J", "move step", not_step),
    ]
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::tui::model::{ExemplarView, Item};
    use std::path::PathBuf;

    fn library_of(states: Vec<BuildState>) -> Model {
        let items = states
            .into_iter()
            .enumerate()
            .map(|(i, state)| Item {
                name: format!("e{i}"),
                declared: None,
                size: None,
                state,
                quality: None,
                previous: false,
            })
            .collect();
        Model::new(PathBuf::from("library.toml"), PathBuf::from("out"), items, Vec::new())
    }

    fn why(hints: &[Hint], keys: &str) -> Option<&'static str> {
        hints.iter().find(|h| h.keys == keys).unwrap_or_else(|| panic!("no {keys} in {hints:?}")).why_not
    }

    #[test]
    fn library_keys_say_why_they_cannot_act() {
        let mut m = library_of(vec![BuildState::NotBuilt, BuildState::Built("0".into()), BuildState::Building]);
        let h = hints(&m);
        assert_eq!(why(&h, "enter"), Some("not built: b"));
        assert_eq!(why(&h, "b"), None);
        assert_eq!(why(&h, "B"), Some("building"), "another entry is building");
        m.selected = 1;
        assert_eq!(why(&hints(&m), "enter"), None);
        m.selected = 2;
        assert_eq!(why(&hints(&m), "b"), Some("building"));
        let empty = library_of(Vec::new());
        assert_eq!(why(&hints(&empty), "e"), Some("no entry"));
    }

    #[test]
    fn each_screen_shows_its_own_keys() {
        let mut m = library_of(vec![BuildState::Built("0".into())]);
        m.screen = Screen::Exemplar(ExemplarView::new("e0"));
        let h = hints(&m);
        assert_eq!(why(&h, "f"), Some("loading"), "the volume is not loaded yet");
        assert!(h.iter().all(|h| h.keys != "b"), "no library keys on the exemplar screen");
        let text = "[[exemplar]]\nname = \"e0\"\nrecipe = \"procedural:marble\"\nsize = 8\n\n  \
                    [[exemplar.steps]]\n  blur = \"4,4,4\"\n  radius = 2\n";
        let editor = |selected: usize| Editor {
            name: "e0".into(),
            text: Some(text.into()),
            saved: text.into(),
            selected,
            ..Editor::default()
        };
        m.screen = Screen::Editor(editor(0));
        let h = hints(&m);
        assert_eq!(why(&h, "x"), Some("not on a step"));
        assert_eq!(why(&h, "s"), Some("no changes"));
        assert_eq!(why(&h, "u"), Some("nothing to undo"));
        m.screen = Screen::Editor(editor(3));
        assert_eq!(why(&hints(&m), "x"), None, "the blur step's field is selected");
        m.screen = Screen::Editor(Editor { input: Some("4".into()), ..editor(3) });
        assert_eq!(hints(&m)[0].action, "keep the value");
    }
}
