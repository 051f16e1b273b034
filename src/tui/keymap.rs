//! Keys to messages, per screen: a pure function, unit-tested.

use super::message::Message;
use super::model::Screen;
use crate::volume::Axis;
use crossterm::event::{KeyCode, KeyEvent, KeyModifiers};

/// The message a key means on `screen`, if any.
pub fn key(screen: &Screen, event: KeyEvent) -> Option<Message> {
    if event.modifiers.contains(KeyModifiers::CONTROL) && event.code == KeyCode::Char('c') {
        return Some(Message::Quit);
    }
    let common = match event.code {
        KeyCode::Char('?') => Some(Message::Help),
        KeyCode::Char('q') => Some(Message::Quit),
        KeyCode::Esc => Some(Message::Back),
        _ => None,
    };
    common.or(match screen {
        Screen::Library => library(event.code),
        Screen::Exemplar(_) => exemplar(event.code),
    })
}

fn library(code: KeyCode) -> Option<Message> {
    match code {
        KeyCode::Up | KeyCode::Char('k') => Some(Message::Up),
        KeyCode::Down | KeyCode::Char('j') => Some(Message::Down),
        KeyCode::Enter => Some(Message::Open),
        KeyCode::Char('b') => Some(Message::Build),
        KeyCode::Char('B') => Some(Message::BuildAll),
        _ => None,
    }
}

fn exemplar(code: KeyCode) -> Option<Message> {
    match code {
        KeyCode::Char('x') => Some(Message::SelectAxis(Axis::X)),
        KeyCode::Char('y') => Some(Message::SelectAxis(Axis::Y)),
        KeyCode::Char('z') => Some(Message::SelectAxis(Axis::Z)),
        KeyCode::Right | KeyCode::Up | KeyCode::Char('l') => Some(Message::MoveSlice(1)),
        KeyCode::Left | KeyCode::Down | KeyCode::Char('h') => Some(Message::MoveSlice(-1)),
        KeyCode::PageUp => Some(Message::MoveSlice(8)),
        KeyCode::PageDown => Some(Message::MoveSlice(-8)),
        KeyCode::Char('c') => Some(Message::NextChannel),
        KeyCode::Backspace => Some(Message::Back),
        _ => None,
    }
}

/// The help text: one line per key.
pub const HELP: [&str; 12] = [
    "up/down, j/k   choose an exemplar",
    "enter          open its slices",
    "b / B          build it / build all",
    "x, y, z        choose the slice axis",
    "left/right     move the slice (page up/down: 8)",
    "c              cycle colour and single channels",
    "esc            back",
    "?              this help",
    "q, ctrl-c      quit",
    "",
    "builds run in the background: the list shows",
    "their state and the type the build measured",
];

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
    fn keys_mean_different_things_per_screen() {
        assert!(matches!(key(&Screen::Library, press(KeyCode::Char('b'))), Some(Message::Build)));
        assert!(matches!(key(&Screen::Library, press(KeyCode::Down)), Some(Message::Down)));
        assert!(key(&Screen::Library, press(KeyCode::Char('x'))).is_none());
        let view = Screen::Exemplar(super::super::model::ExemplarView {
            name: "a".into(),
            volume: None,
            index: [0; 3],
            axis: Axis::Z,
            channel: 0,
        });
        assert!(matches!(key(&view, press(KeyCode::Char('x'))), Some(Message::SelectAxis(Axis::X))));
        assert!(matches!(key(&view, press(KeyCode::PageUp)), Some(Message::MoveSlice(8))));
        assert!(matches!(key(&view, press(KeyCode::Char('?'))), Some(Message::Help)));
        let ctrl_c = KeyEvent { modifiers: KeyModifiers::CONTROL, ..press(KeyCode::Char('c')) };
        assert!(matches!(key(&view, ctrl_c), Some(Message::Quit)));
    }
}
