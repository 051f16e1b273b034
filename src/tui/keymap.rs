//! Keys to messages, per screen: a pure function, unit-tested.

use super::message::Message;
use super::model::{Editor, Help, Screen};
use crate::volume::Axis;
use crossterm::event::{KeyCode, KeyEvent, KeyModifiers};

/// The message a key means on `screen`, if any.
pub fn key(screen: &Screen, event: KeyEvent) -> Option<Message> {
    if event.modifiers.contains(KeyModifiers::CONTROL) && event.code == KeyCode::Char('c') {
        return Some(Message::Quit);
    }
    if event.modifiers.contains(KeyModifiers::CONTROL) && event.code == KeyCode::Char('r') {
        return Some(Message::Reload);
    }
    if let Screen::Editor(Editor { input: Some(_), .. }) = screen {
        return typing(event);
    }
    if let Screen::Editor(Editor { picker: Some(_), .. }) = screen {
        return match event.code {
            KeyCode::Enter => Some(Message::Commit),
            KeyCode::Esc => Some(Message::Cancel),
            code => scrolling(code, -1).map(Message::Jump),
        };
    }
    if let (Screen::Editor(Editor { conflict: Some(_), .. }), KeyCode::Char(c @ ('m' | 't' | 'b'))) =
        (screen, event.code)
    {
        return Some(Message::Resolve(c));
    }
    let common = match event.code {
        KeyCode::Char('?') => Some(Message::Help),
        KeyCode::Char('M') => Some(Message::ShowLog),
        KeyCode::Char('q') => Some(Message::Quit),
        KeyCode::Esc => Some(Message::Back),
        _ => None,
    };
    let esc = |m: Option<Message>| if event.code == KeyCode::Esc { Some(Message::Cancel) } else { m };
    match screen {
        Screen::Library => common.or(library(event.code)),
        Screen::Exemplar(v) if v.stamp.is_some() => common.or(stamping(event.code)).or(exemplar(event.code)),
        Screen::Exemplar(_) => common.or(exemplar(event.code)),
        Screen::Editor(_) => esc(common).or(editor(event.code)),
        Screen::Fill(_) => common.or(fill(event.code)),
        Screen::New(_) => common.or(new_entry(event.code)),
        Screen::Compare(_) => common.or(comparing(event.code)),
    }
}

/// The keys that choose the slice axis and move the slice (slices, comparisons).
fn slice_keys(code: KeyCode) -> Option<Message> {
    match code {
        KeyCode::Char('x') => Some(Message::SelectAxis(Axis::X)),
        KeyCode::Char('y') => Some(Message::SelectAxis(Axis::Y)),
        KeyCode::Char('z') => Some(Message::SelectAxis(Axis::Z)),
        KeyCode::Right | KeyCode::Up | KeyCode::Char('l') | KeyCode::Char('k') => Some(Message::MoveSlice(1)),
        KeyCode::Left | KeyCode::Down | KeyCode::Char('h') | KeyCode::Char('j') => Some(Message::MoveSlice(-1)),
        KeyCode::PageUp => Some(Message::MoveSlice(8)),
        KeyCode::PageDown => Some(Message::MoveSlice(-8)),
        _ => None,
    }
}

fn comparing(code: KeyCode) -> Option<Message> {
    slice_keys(code).or(match code {
        KeyCode::Char('a') => Some(Message::Accept),
        KeyCode::Char('d') => Some(Message::Discard),
        KeyCode::Backspace => Some(Message::Back),
        _ => None,
    })
}

fn new_entry(code: KeyCode) -> Option<Message> {
    match code {
        KeyCode::Up | KeyCode::Char('k') => Some(Message::Up),
        KeyCode::Down | KeyCode::Char('j') => Some(Message::Down),
        KeyCode::Enter | KeyCode::Right | KeyCode::Char('l') => Some(Message::Open),
        KeyCode::Backspace | KeyCode::Left | KeyCode::Char('h') => Some(Message::Parent),
        _ => None,
    }
}

/// A key's name as the key bar writes it (`b`, `enter`, `esc`), for keys the bar can show.
pub fn key_name(code: KeyCode) -> Option<String> {
    match code {
        KeyCode::Char(c) => Some(c.to_string()),
        KeyCode::Enter => Some("enter".into()),
        KeyCode::Esc => Some("esc".into()),
        KeyCode::Backspace => Some("backspace".into()),
        _ => None,
    }
}

/// Rows a page key moves in lists and overlays.
pub const PAGE: i64 = 10;

/// Rows that take a list or an overlay to its end.
pub const END: i64 = 1 << 40;

/// Keys that scroll an overlay or move a list: arrows and j/k a row, pgup/pgdn a page,
/// g/G and home/end to an end; `up` is what moving up means.
fn scrolling(code: KeyCode, up: i64) -> Option<i64> {
    match code {
        KeyCode::Up | KeyCode::Char('k') => Some(up),
        KeyCode::Down | KeyCode::Char('j') => Some(-up),
        KeyCode::PageUp => Some(up * PAGE),
        KeyCode::PageDown => Some(-up * PAGE),
        KeyCode::Home | KeyCode::Char('g') => Some(up * END),
        KeyCode::End | KeyCode::Char('G') => Some(-up * END),
        _ => None,
    }
}

/// The message a key means while the help is shown: `/` searches, typed keys edit the
/// search, esc clears it (or closes the help), `?` closes it, the scrolling keys scroll it;
/// other keys do nothing.
pub fn help_key(help: &Help, event: KeyEvent) -> Option<Message> {
    if event.modifiers.contains(KeyModifiers::CONTROL) && event.code == KeyCode::Char('c') {
        return Some(Message::Quit);
    }
    match (help.typing, event.code) {
        (_, KeyCode::Esc) => Some(Message::Back),
        (true, KeyCode::Enter) | (false, KeyCode::Char('/')) => Some(Message::HelpSearch),
        (true, KeyCode::Backspace) => Some(Message::HelpType(None)),
        (true, KeyCode::Char(c)) => Some(Message::HelpType(Some(c))),
        (false, KeyCode::Char('?')) => Some(Message::Help),
        (false, KeyCode::Char('q')) => Some(Message::Quit),
        (_, code) => scrolling(code, -1).map(Message::Scroll),
    }
}

/// The message a key means while the message log is shown: it scrolls, `M` or esc closes it.
pub fn log_key(event: KeyEvent) -> Option<Message> {
    if event.modifiers.contains(KeyModifiers::CONTROL) && event.code == KeyCode::Char('c') {
        return Some(Message::Quit);
    }
    match event.code {
        KeyCode::Esc | KeyCode::Char('M') => Some(Message::ShowLog),
        KeyCode::Char('q') => Some(Message::Quit),
        code => scrolling(code, -1).map(Message::Scroll),
    }
}

fn library(code: KeyCode) -> Option<Message> {
    if let Some(rows) = scrolling(code, -1) {
        return Some(Message::Jump(rows));
    }
    match code {
        KeyCode::Enter => Some(Message::Open),
        KeyCode::Char('b') => Some(Message::Build),
        KeyCode::Char('B') => Some(Message::BuildAll),
        KeyCode::Char('R') => Some(Message::BuildChanged),
        KeyCode::Char('e') => Some(Message::Edit),
        KeyCode::Char('c') => Some(Message::Duplicate),
        KeyCode::Char('d') => Some(Message::Delete),
        KeyCode::Char('r') => Some(Message::Rename),
        KeyCode::Char('n') => Some(Message::New),
        KeyCode::Char('v') => Some(Message::Compare),
        KeyCode::Char('V') => Some(Message::BeforeAfter),
        KeyCode::Char('u') => Some(Message::Undo),
        KeyCode::Char(']') => Some(Message::ScrollErrors(3)),
        KeyCode::Char('[') => Some(Message::ScrollErrors(-3)),
        KeyCode::Char('/') => Some(Message::Filter),
        _ => None,
    }
}

fn stamping(code: KeyCode) -> Option<Message> {
    match code {
        KeyCode::Right | KeyCode::Char('l') => Some(Message::MoveSeed([1, 0, 0])),
        KeyCode::Left | KeyCode::Char('h') => Some(Message::MoveSeed([-1, 0, 0])),
        KeyCode::Up | KeyCode::Char('k') => Some(Message::MoveSeed([0, 1, 0])),
        KeyCode::Down | KeyCode::Char('j') => Some(Message::MoveSeed([0, -1, 0])),
        KeyCode::PageUp => Some(Message::MoveSeed([0, 0, 1])),
        KeyCode::PageDown => Some(Message::MoveSeed([0, 0, -1])),
        KeyCode::Char('r') => Some(Message::TurnSeed(15.0)),
        KeyCode::Char('R') => Some(Message::TurnSeed(-15.0)),
        KeyCode::Char('+') | KeyCode::Char('=') => Some(Message::ScaleSeed(1.15)),
        KeyCode::Char('-') => Some(Message::ScaleSeed(1.0 / 1.15)),
        KeyCode::Enter => Some(Message::Stamp),
        KeyCode::Char('n') => Some(Message::Scatter),
        KeyCode::Char('o') => Some(Message::PickSeed),
        KeyCode::Char('u') => Some(Message::Undo),
        KeyCode::Char('s') => Some(Message::SaveSteps),
        _ => None,
    }
}

/// Keys while a value is typed: Enter commits, Esc drops it, the rest edit it as a text
/// field (tui-input: arrows, Home, End, Backspace, Delete, Ctrl-U, Ctrl-W, Ctrl-A, Ctrl-E).
pub fn typing(event: KeyEvent) -> Option<Message> {
    match event.code {
        KeyCode::Enter => Some(Message::Commit),
        KeyCode::Esc => Some(Message::Cancel),
        _ => tui_input::backend::crossterm::to_input_request(&crossterm::event::Event::Key(event)).map(Message::Input),
    }
}

fn editor(code: KeyCode) -> Option<Message> {
    match code {
        KeyCode::Up | KeyCode::Char('k') => Some(Message::Up),
        KeyCode::Down | KeyCode::Char('j') => Some(Message::Down),
        KeyCode::Enter => Some(Message::Commit),
        KeyCode::Char('u') => Some(Message::Undo),
        KeyCode::Char('r') => Some(Message::Redo),
        KeyCode::Char('s') => Some(Message::Save),
        KeyCode::Char('S') => Some(Message::SaveAs),
        KeyCode::Char('a') => Some(Message::AddBlur),
        KeyCode::Char('t') => Some(Message::AddMeshStep(true)),
        KeyCode::Char('n') => Some(Message::AddMeshStep(false)),
        KeyCode::Char('x') => Some(Message::RemoveStep),
        KeyCode::Char('K') => Some(Message::MoveStep(true)),
        KeyCode::Char('J') => Some(Message::MoveStep(false)),
        KeyCode::Char('+') => Some(Message::PickField),
        KeyCode::Char('-') => Some(Message::RemoveField),
        KeyCode::Char('o') => Some(Message::OutsideEditor),
        _ => None,
    }
}

fn fill(code: KeyCode) -> Option<Message> {
    match code {
        KeyCode::Char('x') => Some(Message::SelectAxis(Axis::X)),
        KeyCode::Char('y') => Some(Message::SelectAxis(Axis::Y)),
        KeyCode::Char('z') => Some(Message::SelectAxis(Axis::Z)),
        KeyCode::Right | KeyCode::Up | KeyCode::Char('l') | KeyCode::Char('k') => Some(Message::MovePlane(0.05)),
        KeyCode::Left | KeyCode::Down | KeyCode::Char('h') | KeyCode::Char('j') => Some(Message::MovePlane(-0.05)),
        KeyCode::PageUp => Some(Message::MovePlane(0.25)),
        KeyCode::PageDown => Some(Message::MovePlane(-0.25)),
        KeyCode::Char('E') => Some(Message::Export),
        KeyCode::Char('W') => Some(Message::WebView),
        KeyCode::Backspace => Some(Message::Back),
        KeyCode::Char('H') => Some(Message::MoveCursor(-1.0, 0.0)),
        KeyCode::Char('L') => Some(Message::MoveCursor(1.0, 0.0)),
        KeyCode::Char('K') => Some(Message::MoveCursor(0.0, -1.0)),
        KeyCode::Char('J') => Some(Message::MoveCursor(0.0, 1.0)),
        KeyCode::Char('s') => Some(Message::StrokePoint),
        KeyCode::Char('S') => Some(Message::FinishStroke),
        KeyCode::Char('d') => Some(Message::DepthPoint),
        KeyCode::Char('[') => Some(Message::DepthValue(-super::fill_edit::DEPTH_STEP)),
        KeyCode::Char(']') => Some(Message::DepthValue(super::fill_edit::DEPTH_STEP)),
        KeyCode::Char('g') => Some(Message::FaceGroup),
        KeyCode::Char('p') => Some(Message::Paste),
        KeyCode::Char('t') => Some(Message::WarpPaste(15.0, 1.0)),
        KeyCode::Char('+') | KeyCode::Char('=') => Some(Message::WarpPaste(0.0, 1.25)),
        KeyCode::Char('-') => Some(Message::WarpPaste(0.0, 0.8)),
        KeyCode::Char('u') => Some(Message::Undo),
        KeyCode::Char('c') => Some(Message::ShowDepth),
        KeyCode::Char('v') => Some(Message::NextOverlay),
        KeyCode::Char('r') => Some(Message::Refill),
        KeyCode::Char('w') => Some(Message::WriteSpec),
        KeyCode::Char('o') => Some(Message::OpenSpec),
        _ => None,
    }
}

fn exemplar(code: KeyCode) -> Option<Message> {
    slice_keys(code).or(match code {
        KeyCode::Char('c') => Some(Message::NextChannel),
        KeyCode::Char('f') => Some(Message::FillPreview),
        KeyCode::Char('m') => Some(Message::StampMode),
        KeyCode::Char('+') | KeyCode::Char('=') => Some(Message::Zoom(true)),
        KeyCode::Char('-') => Some(Message::Zoom(false)),
        KeyCode::Char('a') => Some(Message::NextLayer),
        KeyCode::Char('p') => Some(Message::Photo),
        KeyCode::Char('E') => Some(Message::Export),
        KeyCode::Char('W') => Some(Message::WebView),
        KeyCode::Backspace => Some(Message::Back),
        _ => None,
    })
}

/// One screen's keys for the help: its title and (keys, what they do) rows.
pub type Section = (&'static str, &'static [(&'static str, &'static str)]);

/// The keys of every screen, for the help.
pub const SECTIONS: [Section; 9] = [
    (
        "library",
        &[
            ("up/down, j/k", "choose an exemplar"),
            ("g/G, home/end", "the first / the last exemplar"),
            ("pgup/pgdn", "a page up / down"),
            ("/", "filter the list by name (esc in it clears)"),
            ("enter", "open its slices"),
            ("b / B", "build it / build all"),
            ("R", "build those changed since their last build or never built"),
            ("c", "copy the entry (right after it, NAME-2)"),
            ("d d", "delete the entry (built files stay)"),
            ("r", "rename the entry (enter keeps, esc drops)"),
            ("n", "new entry: choose its recipe, then its photo or file"),
            ("v", "mark for comparing; v on another shows both"),
            ("V", "its previous build beside the new one"),
            ("e", "edit its recipe"),
            ("u", "undo the last copy, delete, rename or new entry"),
            ("[ / ]", "scroll the manifest's mistakes"),
        ],
    ),
    (
        "slices",
        &[
            ("x, y, z", "choose the slice axis"),
            ("arrows, hjkl, pgup/pgdn", "move the slice (pgup/pgdn: 8 at a time)"),
            ("c", "cycle colour and single channels"),
            ("+/-, =", "zoom in / out (= as +)"),
            ("a", "show the masks in turn"),
            ("p", "its photo beside the slice, same pixel scale, with quality figures"),
            ("f", "fill a shape with it"),
            ("m", "stamp mode"),
            ("E", "export: every format, contact sheet, this slice"),
            ("W", "a 3D view in the browser (exports/NAME.view/view.html)"),
            ("backspace", "back to the library"),
        ],
    ),
    (
        "stamp mode",
        &[
            ("arrows, hjkl", "move the seed (pgup/pgdn: in depth)"),
            ("r / R", "turn it 15 degrees"),
            ("+/-", "scale it"),
            ("enter", "stamp it"),
            ("n", "scatter copies of it"),
            ("o", "another seed mesh, from a file picker"),
            ("u", "undo the last stamp"),
            ("s", "save the steps into the manifest"),
            ("m", "leave stamp mode"),
        ],
    ),
    (
        "recipe editor",
        &[
            ("up/down, j/k", "choose a value"),
            ("enter", "edit it (enter keeps, esc drops)"),
            ("s", "save the manifest (changes made to it meanwhile are kept)"),
            ("S", "save it as a new file beside it"),
            ("+", "add a field: its range and first value shown"),
            ("-", "remove the field under the cursor"),
            ("o", "the manifest in $VISUAL / $EDITOR at this entry"),
            ("m / t / b", "entry changed on disk too: keep mine / take the file's / show both"),
            ("u / r", "undo / redo"),
            ("a", "add a blur step"),
            ("t / n", "add a stamp / scatter step: pick its mesh"),
            ("x", "remove the step under the cursor"),
            ("K / J", "move that step up / down"),
        ],
    ),
    (
        "fill preview",
        &[
            ("x, y, z", "choose the cut axis"),
            ("arrows, hjkl, pgup/pgdn", "move the cut (pgup/pgdn: 5 at a time)"),
            ("E", "export the cut as a 512x512 PNG"),
            ("W", "the fill in 3D in the browser (exports/NAME.fill-view/view.html)"),
            ("H J K L", "move the cursor on the cut (or click)"),
            ("s / S", "add the cursor to a stroke / end the stroke"),
            ("d", "a depth point at the cursor"),
            ("[ / ]", "lower / raise the depth new points get"),
            ("g", "the faces nearest the cursor get that depth"),
            ("p", "a manual paste at the cursor"),
            ("t, +/-, =", "turn / scale the last paste (= as +)"),
            ("u", "undo the last constraint"),
            ("c", "the depth field as a colour map"),
            ("v", "the texture, the frame field, a guided cut"),
            ("r", "fill again with the constraints"),
            ("w", "write the fill spec and the shape"),
            ("o", "load the constraints of a written fill spec"),
            ("backspace", "back to the slices"),
        ],
    ),
    (
        "new exemplar",
        &[
            ("up/down, j/k", "choose a recipe kind, or a file (or a seed mesh)"),
            ("enter, l, right", "take it; in the picker, open the folder"),
            ("backspace, h, left", "the folder above"),
        ],
    ),
    (
        "compare",
        &[
            ("x, y, z", "choose the axis of both slices"),
            ("arrows, hjkl, pgup/pgdn", "move both slices (pgup/pgdn: 8 at a time)"),
            ("a", "keep the new build (before/after)"),
            ("d", "discard it: the previous build comes back"),
            ("backspace", "back to the library"),
        ],
    ),
    (
        "mouse",
        &[
            ("click", "select a row, field, kind or file; again opens or edits it"),
            ("click/drag a slice", "the other two slices go through that voxel"),
            ("wheel", "scroll lists; move the slice under it; move the cut"),
            ("click the fill's cut", "put the cursor there"),
            ("drag on the fill's cut", "draw a direction stroke"),
        ],
    ),
    (
        "everywhere",
        &[
            ("esc", "back (asks if work is unsaved)"),
            ("ctrl-r", "read the manifest again after a change on disk"),
            ("?", "this help; / searches it, arrows and pgup/pgdn scroll it"),
            ("M", "the message log: every status shown"),
            ("q, ctrl-c", "quit (asks if work is unsaved)"),
        ],
    ),
];

/// The help's section for `screen` (it is shown first).
pub fn section_of(screen: &Screen) -> &'static str {
    match screen {
        Screen::Library => "library",
        Screen::Exemplar(v) if v.stamp.is_some() => "stamp mode",
        Screen::Exemplar(_) => "slices",
        Screen::Editor(_) => "recipe editor",
        Screen::Fill(_) => "fill preview",
        Screen::New(_) => "new exemplar",
        Screen::Compare(_) => "compare",
    }
}

/// Rows of the help: (keys, what they do).
pub type Rows = Vec<(&'static str, &'static str)>;

/// The help's sections in the order shown for `screen` (its own first, `everywhere` last),
/// each with the rows whose keys or action hold `query` (any case); sections left empty
/// are dropped.
pub fn help_rows(screen: &Screen, query: &str) -> Vec<(&'static str, Rows)> {
    let query = query.to_lowercase();
    let own = section_of(screen);
    let order = SECTIONS.iter().filter(|s| s.0 == own).chain(SECTIONS.iter().filter(|s| s.0 != own));
    order
        .filter_map(|&(title, rows)| {
            let kept: Rows = rows
                .iter()
                .copied()
                .filter(|(k, a)| k.to_lowercase().contains(&query) || a.to_lowercase().contains(&query))
                .collect();
            (!kept.is_empty()).then_some((title, kept))
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crossterm::event::KeyEventKind;

    fn press(code: KeyCode) -> KeyEvent {
        KeyEvent {
            code,
            modifiers: KeyModifiers::NONE,
            kind: KeyEventKind::Press,
            state: crossterm::event::KeyEventState::NONE,
        }
    }

    #[test]
    fn the_help_shows_the_screen_on_top_first_and_finds_keys_in_any_case() {
        let editor = Screen::Editor(Editor::default());
        let titles = |screen: &Screen, q: &str| help_rows(screen, q).iter().map(|r| r.0).collect::<Vec<_>>();
        assert_eq!(titles(&editor, "")[0], "recipe editor");
        assert_eq!(titles(&Screen::Library, "").last(), Some(&"everywhere"));
        assert_eq!(titles(&Screen::Library, "").len(), SECTIONS.len());
        assert_eq!(titles(&Screen::Library, "STAMP"), ["slices", "stamp mode", "recipe editor"]);
        let stamp_rows = &help_rows(&Screen::Library, "stamp")[1].1;
        assert!(stamp_rows.iter().all(|(k, a)| k.contains("stamp") || a.contains("stamp")), "{stamp_rows:?}");
        assert!(help_rows(&editor, "no such key").is_empty());
        // every key the library screen answers to is in its section
        let library = &SECTIONS[0].1;
        for key in ["enter", "b / B", "c", "d d", "e"] {
            assert!(library.iter().any(|(k, _)| *k == key), "{key}");
        }
    }

    /// docs/tui.md lists every key of the help in its table, screen by screen.
    #[test]
    fn the_docs_list_the_keys_the_help_shows() {
        let docs = include_str!("../../docs/tui.md");
        for (title, rows) in SECTIONS {
            let at = docs.find(&format!("**{title}**")).unwrap_or_else(|| panic!("no table for {title}"));
            for (keys, action) in rows {
                assert!(docs[at..].contains(&format!("| `{keys}` | {action} |")), "{title}: {keys}");
            }
        }
    }

    #[test]
    fn keys_mean_different_things_per_screen() {
        assert!(matches!(key(&Screen::Library, press(KeyCode::Char('b'))), Some(Message::Build)));
        assert!(matches!(key(&Screen::Library, press(KeyCode::Down)), Some(Message::Jump(1))));
        assert!(matches!(key(&Screen::Library, press(KeyCode::Char('G'))), Some(Message::Jump(n)) if n == END));
        assert!(matches!(key(&Screen::Library, press(KeyCode::PageUp)), Some(Message::Jump(n)) if n == -PAGE));
        assert!(key(&Screen::Library, press(KeyCode::Char('x'))).is_none());
        assert!(matches!(key(&Screen::Library, press(KeyCode::Char('c'))), Some(Message::Duplicate)));
        assert!(matches!(key(&Screen::Library, press(KeyCode::Char('d'))), Some(Message::Delete)));
        let view = Screen::Exemplar(super::super::model::ExemplarView::new("a"));
        assert!(matches!(key(&view, press(KeyCode::Char('x'))), Some(Message::SelectAxis(Axis::X))));
        assert!(matches!(key(&view, press(KeyCode::PageUp)), Some(Message::MoveSlice(8))));
        assert!(matches!(key(&view, press(KeyCode::Char('k'))), Some(Message::MoveSlice(1))));
        assert!(matches!(key(&view, press(KeyCode::Char('j'))), Some(Message::MoveSlice(-1))));
        assert!(matches!(key(&view, press(KeyCode::Char('?'))), Some(Message::Help)));
        let ctrl_c = KeyEvent { modifiers: KeyModifiers::CONTROL, ..press(KeyCode::Char('c')) };
        assert!(matches!(key(&view, ctrl_c), Some(Message::Quit)));
        assert!(matches!(key(&view, press(KeyCode::Char('f'))), Some(Message::FillPreview)));
        let editing =
            |input: Option<&str>| Screen::Editor(Editor { input: input.map(Into::into), ..Editor::default() });
        assert!(matches!(key(&editing(None), press(KeyCode::Char('u'))), Some(Message::Undo)));
        assert!(matches!(key(&editing(None), press(KeyCode::Esc)), Some(Message::Cancel)));
        // while a value is typed, every letter is text, even q and ?
        use tui_input::InputRequest::{DeleteLine, DeletePrevWord, GoToEnd, GoToPrevChar, GoToStart, InsertChar};
        let typed = |code, modifiers| key(&editing(Some("")), KeyEvent { modifiers, ..press(code) });
        assert!(matches!(typed(KeyCode::Char('q'), KeyModifiers::NONE), Some(Message::Input(InsertChar('q')))));
        assert!(matches!(typed(KeyCode::Char('?'), KeyModifiers::NONE), Some(Message::Input(InsertChar('?')))));
        assert!(matches!(typed(KeyCode::Left, KeyModifiers::NONE), Some(Message::Input(GoToPrevChar))));
        assert!(matches!(typed(KeyCode::Home, KeyModifiers::NONE), Some(Message::Input(GoToStart))));
        assert!(matches!(typed(KeyCode::End, KeyModifiers::NONE), Some(Message::Input(GoToEnd))));
        assert!(matches!(typed(KeyCode::Char('u'), KeyModifiers::CONTROL), Some(Message::Input(DeleteLine))));
        assert!(matches!(typed(KeyCode::Char('w'), KeyModifiers::CONTROL), Some(Message::Input(DeletePrevWord))));
        assert!(matches!(key(&editing(Some("")), press(KeyCode::Enter)), Some(Message::Commit)));
    }

    /// The key names a help row's keys stand for: `arrows` for the four arrows, `hjkl` for
    /// its letters, `H J K L`, `x, y, z`, `a / b` and `a/b` for each.
    fn named(keys: &str) -> Vec<String> {
        if keys == "/" {
            return vec![keys.to_string()];
        }
        keys.split([',', ' ', '/'])
            .filter(|k| !k.is_empty())
            .flat_map(|k| match k {
                "arrows" => ["up", "down", "left", "right"].map(String::from).to_vec(),
                "hjkl" => ["h", "j", "k", "l"].map(String::from).to_vec(),
                "ctrl-c" | "ctrl-r" => vec![k.to_string()],
                _ => vec![k.to_lowercase().replace("pgup", "pageup").replace("pgdn", "pagedown"), k.to_string()],
            })
            .collect()
    }

    /// Every key a screen answers to is in its help section (or `everywhere`), so the help
    /// and docs/tui.md's tables (checked against the help above) match the keymap.
    #[test]
    fn every_key_a_screen_answers_to_is_in_its_help() {
        use super::super::model::ExemplarView;
        let mut codes: Vec<(KeyCode, String)> =
            (b'!'..=b'~').map(|c| (KeyCode::Char(c as char), (c as char).to_string())).collect();
        for (code, name) in [
            (KeyCode::Enter, "enter"),
            (KeyCode::Esc, "esc"),
            (KeyCode::Backspace, "backspace"),
            (KeyCode::Up, "up"),
            (KeyCode::Down, "down"),
            (KeyCode::Left, "left"),
            (KeyCode::Right, "right"),
            (KeyCode::PageUp, "pageup"),
            (KeyCode::PageDown, "pagedown"),
            (KeyCode::Home, "home"),
            (KeyCode::End, "end"),
        ] {
            codes.push((code, name.to_string()));
        }
        let screens = [
            Screen::Library,
            Screen::Exemplar(ExemplarView::new("a")),
            Screen::Editor(Editor::default()),
            Screen::Fill(super::super::model::FillView {
                name: "a".into(),
                filled: None,
                axis: Axis::Z,
                offset: 0.0,
                from: None,
                edit: None,
            }),
            Screen::New(super::super::new_entry::NewEntry { kind: 0, picker: None, pick_for: None }),
            Screen::Compare(super::super::model::CompareView {
                sides: [0, 1].map(|_| super::super::model::Side { label: "a".into(), volume: None, quality: None }),
                axis: Axis::Z,
                position: 0.5,
                before_after: None,
            }),
        ];
        let mut unlisted = Vec::new();
        for screen in &screens {
            let section = section_of(screen);
            let listed: Vec<String> = SECTIONS
                .iter()
                .filter(|s| s.0 == section || s.0 == "everywhere")
                .flat_map(|s| s.1.iter().flat_map(|(keys, _)| named(keys)))
                .collect();
            let missing: Vec<&String> = codes
                .iter()
                .filter(|(code, name)| key(screen, press(*code)).is_some() && !listed.contains(name))
                .map(|(_, n)| n)
                .collect();
            unlisted.extend(missing.into_iter().map(|n| format!("{section}: {n}")));
        }
        assert!(unlisted.is_empty(), "keys that act but the help does not list: {unlisted:?}");
    }
}
