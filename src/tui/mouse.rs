//! The mouse: clicks select list rows and fields, the wheel scrolls lists and moves slices,
//! a click or drag on a slice puts the other two slices through that voxel. `view` records
//! where it drew the lists and the slices ([`Regions`]); [`message`] is pure.

use super::message::Message;
use super::model::Screen;
use crate::volume::Axis;
use crossterm::event::{MouseButton, MouseEvent, MouseEventKind};
use ratatui::layout::{Position, Rect};

/// A list on screen: the area of its rows and the index of the first row shown.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct List {
    /// Where the rows are, one per terminal line.
    pub area: Rect,
    /// Index of the row on the area's first line.
    pub first: usize,
}

/// A slice on screen: where its pixels are and which voxels they show.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Panel {
    /// The area the picture is drawn in (from its top-left corner).
    pub area: Rect,
    /// The axis the slice is across.
    pub axis: Axis,
    /// Terminal columns per pixel (a line holds two pixel rows).
    pub scale: f32,
    /// The picture's size in pixels.
    pub size: (usize, usize),
    /// Where the picture starts in the full slice (zoom crops it).
    pub origin: (usize, usize),
    /// The full slice's height, and whether it is drawn upside down (+z up).
    pub rows: usize,
    /// Whether row 0 of the slice is drawn at the bottom.
    pub up: bool,
}

/// Where the last frame drew what the mouse can point at.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Regions {
    /// The list of the screen on top (library rows, editor fields, kinds or files).
    pub list: Option<List>,
    /// The slices of the exemplar view.
    pub panels: Vec<Panel>,
    /// The fill preview's cut (one pixel per column, two per line).
    pub cut: Option<Rect>,
}

/// The message a mouse event means on `screen`, given where things were drawn.
pub fn message(screen: &Screen, regions: &Regions, event: MouseEvent) -> Option<Message> {
    let at = Position::new(event.column, event.row);
    let wheel = match event.kind {
        MouseEventKind::ScrollUp => Some(1),
        MouseEventKind::ScrollDown => Some(-1),
        _ => None,
    };
    let press = matches!(event.kind, MouseEventKind::Down(MouseButton::Left) | MouseEventKind::Drag(MouseButton::Left));
    match screen {
        Screen::Exemplar(_) => {
            let panel = regions.panels.iter().find(|p| p.area.contains(at))?;
            match (wheel, press) {
                (Some(step), _) => Some(Message::MoveSliceOf(panel.axis, step)),
                (None, true) => voxel(panel, at).map(|(a, b)| Message::PointAt(panel.axis, a, b)),
                _ => None,
            }
        }
        Screen::Fill(_) => {
            if let Some(s) = wheel {
                return Some(Message::MovePlane(0.05 * s as f32));
            }
            if matches!(event.kind, MouseEventKind::Up(MouseButton::Left)) {
                return Some(Message::EndDrag);
            }
            let cut = regions.cut.filter(|c| c.contains(at))?;
            let across = (f32::from(at.x - cut.x) + 0.5) / f32::from(cut.width.max(1));
            let down = (f32::from(at.y - cut.y) + 0.5) / f32::from(cut.height.max(1));
            match event.kind {
                MouseEventKind::Down(MouseButton::Left) => Some(Message::CursorAt(across, down)),
                MouseEventKind::Drag(MouseButton::Left) => Some(Message::DragStroke(across, down)),
                _ => None,
            }
        }
        Screen::Compare(_) => wheel.map(Message::MoveSlice),
        _ => {
            if let Some(step) = wheel {
                return Some(if step > 0 { Message::Up } else { Message::Down });
            }
            let list = regions.list.filter(|l| l.area.contains(at))?;
            let row = list.first + usize::from(at.y - list.area.y);
            matches!(event.kind, MouseEventKind::Down(MouseButton::Left)).then_some(Message::Select(row))
        }
    }
}

/// The voxel of `panel`'s slice under `at`: its coordinates along the slice's two axes.
fn voxel(panel: &Panel, at: Position) -> Option<(usize, usize)> {
    if panel.scale <= 0.0 {
        return None;
    }
    let px = (f32::from(at.x - panel.area.x) / panel.scale) as usize;
    let py = (2.0 * f32::from(at.y - panel.area.y) / panel.scale) as usize;
    if px >= panel.size.0 || py >= panel.size.1 {
        return None;
    }
    let row = py + panel.origin.1;
    let row = if panel.up { panel.rows.checked_sub(1 + row)? } else { row };
    Some((px + panel.origin.0, row))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::tui::model::ExemplarView;
    use crossterm::event::KeyModifiers;

    fn event(kind: MouseEventKind, column: u16, row: u16) -> MouseEvent {
        MouseEvent { kind, column, row, modifiers: KeyModifiers::NONE }
    }

    #[test]
    fn clicks_pick_rows_and_the_wheel_scrolls() {
        let regions = Regions { list: Some(List { area: Rect::new(1, 2, 40, 10), first: 3 }), ..Default::default() };
        let click = |x, y| message(&Screen::Library, &regions, event(MouseEventKind::Down(MouseButton::Left), x, y));
        assert!(matches!(click(5, 4), Some(Message::Select(5))));
        assert!(click(5, 1).is_none() && click(50, 4).is_none(), "outside the rows");
        let wheel = message(&Screen::Library, &regions, event(MouseEventKind::ScrollDown, 0, 0));
        assert!(matches!(wheel, Some(Message::Down)));
    }

    #[test]
    fn a_click_on_a_slice_points_at_its_voxel_and_the_wheel_moves_it() {
        // a 16x16 slice across y drawn with +z up at 2 columns per pixel from (10, 5)
        let panel = Panel {
            area: Rect::new(10, 5, 32, 16),
            axis: Axis::Y,
            scale: 2.0,
            size: (16, 16),
            origin: (0, 0),
            rows: 16,
            up: true,
        };
        let regions = Regions { panels: vec![panel], ..Default::default() };
        let screen = Screen::Exemplar(ExemplarView::new("a"));
        let at = |kind, x, y| message(&screen, &regions, event(kind, x, y));
        // column 14 = pixel 2; line 5 = pixel rows 0..1 from the top, so z = 15
        assert!(matches!(at(MouseEventKind::Down(MouseButton::Left), 14, 5), Some(Message::PointAt(Axis::Y, 2, 15))));
        assert!(matches!(at(MouseEventKind::Drag(MouseButton::Left), 41, 20), Some(Message::PointAt(Axis::Y, 15, 0))));
        assert!(matches!(at(MouseEventKind::ScrollUp, 20, 8), Some(Message::MoveSliceOf(Axis::Y, 1))));
        assert!(at(MouseEventKind::Down(MouseButton::Left), 9, 8).is_none(), "outside the panel");
        // zoomed in: the picture starts at (4, 4) of the full slice
        let zoomed = Panel { origin: (4, 4), size: (8, 8), scale: 4.0, ..panel };
        let regions = Regions { panels: vec![zoomed], ..Default::default() };
        let at = message(&screen, &regions, event(MouseEventKind::Down(MouseButton::Left), 10, 5));
        assert!(matches!(at, Some(Message::PointAt(Axis::Y, 4, 11))), "{at:?}");
    }
}
