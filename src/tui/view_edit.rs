//! Drawing the recipe editor and the fill preview.

use super::edit;
use super::model::{Editor, FillView};
use super::view::HalfBlocks;
use crate::fill::render;
use crate::render::to_u8;
use crate::volume::Axis;
use glam::Vec3;
use ratatui::Frame;
use ratatui::buffer::Buffer;
use ratatui::layout::{Constraint, Layout, Rect};
use ratatui::style::{Color, Modifier, Style};
use ratatui::text::{Line, Span};
use ratatui::widgets::{Block, Borders, Paragraph, Widget, Wrap};

/// The editor: the entry's fields on the left, the live preview on the right.
pub fn editor(frame: &mut Frame, editor: &Editor, area: Rect, regions: &mut super::mouse::Regions) {
    let modified = editor.text.as_ref().is_some_and(|t| *t != editor.saved);
    let title = format!(" recipe: {}{} ", editor.name, if modified { " [modified]" } else { "" });
    if let (Some(conflict), Some(mine)) = (editor.conflict.as_ref().filter(|c| c.both), &editor.text) {
        both(frame, &editor.name, mine, &conflict.theirs, area);
        return;
    }
    let block = Block::default().borders(Borders::ALL).title(super::view::fitted(&title, area.width));
    let inner = block.inner(area);
    frame.render_widget(block, area);
    let Some(text) = &editor.text else {
        frame.render_widget(Paragraph::new("reading the manifest..."), inner);
        return;
    };
    let [left, right] = Layout::horizontal([Constraint::Percentage(45), Constraint::Percentage(55)]).areas(inner);
    let (fields, error) = match &editor.error {
        Some(e) => {
            // The whole reason, up to half the column (word wrap needs a little more room).
            let needed = super::view::wrapped_lines(e, left.width.saturating_sub(4)) + 2;
            let lines = needed.clamp(3, (left.height / 2).max(3));
            let [f, e_area] = Layout::vertical([Constraint::Min(3), Constraint::Length(lines)]).areas(left);
            let message = Paragraph::new(e.as_str()).style(Style::new().fg(Color::Red)).wrap(Wrap { trim: true });
            (f, Some((e_area, message)))
        }
        None => (left, None),
    };
    // keep the selected field in view
    let offset = (editor.selected + 2).saturating_sub(fields.height as usize) as u16;
    regions.list = Some(super::mouse::List { area: fields, first: usize::from(offset) });
    frame.render_widget(Paragraph::new(field_lines(editor, text)).scroll((offset, 0)), fields);
    if let Some((area, message)) = error {
        frame.render_widget(message.block(Block::default().borders(Borders::TOP)), area);
    }
    preview(frame, editor, right);
    if let Some(row) = editor.picker {
        picker(frame, editor, row, area);
    }
}

/// The field picker over the editor: the fields the entry can add, what each allows and the
/// value it starts with.
fn picker(frame: &mut Frame, editor: &Editor, row: usize, area: Rect) {
    let rules = super::editing::picker_rows(editor);
    let lines: Vec<Line> = rules
        .iter()
        .enumerate()
        .map(|(i, r)| {
            let text = format!("{:<13} {} (starts as {})", r.key, r.allowed, r.start);
            let text = super::view::cut(&text, area.width.saturating_sub(2));
            let style = if i == row { Style::new().add_modifier(Modifier::REVERSED) } else { Style::new() };
            Line::styled(text, style)
        })
        .collect();
    let h = (lines.len() as u16 + 2).min(area.height);
    let rect = Rect::new(area.x, area.y + (area.height - h) / 2, area.width, h);
    let offset = (row + 3).saturating_sub(usize::from(h.saturating_sub(2))) as u16;
    let title = super::view::fitted(" add a field: enter adds it, esc closes ", rect.width);
    frame.render_widget(ratatui::widgets::Clear, rect);
    let block = Block::default().borders(Borders::ALL).title(title);
    frame.render_widget(Paragraph::new(lines).scroll((offset, 0)).block(block), rect);
}

/// The entry as the editor has it beside the entry as the file has it now.
fn both(frame: &mut Frame, name: &str, mine: &str, theirs: &str, area: Rect) {
    let [left, right] = Layout::horizontal([Constraint::Percentage(50), Constraint::Percentage(50)]).areas(area);
    let gone = "(not in the file)".to_string();
    for (rect, text, label) in [(left, mine, "yours (m keeps it)"), (right, theirs, "the file's (t takes it)")] {
        let entry = edit::entry_text(text, name).unwrap_or_else(|| gone.clone());
        let block = Block::default().borders(Borders::ALL).title(format!(" {name}: {label} ")).title_bottom(" b back ");
        frame.render_widget(Paragraph::new(entry).block(block).wrap(Wrap { trim: false }), rect);
    }
}

fn field_lines(editor: &Editor, text: &str) -> Vec<Line<'static>> {
    let fields = edit::fields(text, &editor.name).unwrap_or_default();
    fields
        .iter()
        .enumerate()
        .map(|(i, f)| {
            let selected = i == editor.selected;
            match (&editor.input, selected) {
                (Some(input), true) => {
                    // The cursor: the character under it reversed, or `_` past the end.
                    let style = Style::new().fg(Color::Yellow).add_modifier(Modifier::BOLD);
                    let chars: Vec<char> = input.value().chars().collect();
                    let at = input.cursor().min(chars.len());
                    let before: String = chars[..at].iter().collect();
                    let under = chars.get(at).map_or("_".to_string(), char::to_string);
                    let after: String = chars.get(at + 1..).unwrap_or_default().iter().collect();
                    Line::from(vec![
                        Span::styled(format!("{} = {before}", f.key), style),
                        Span::styled(under, style.add_modifier(Modifier::REVERSED)),
                        Span::styled(after, style),
                    ])
                }
                (_, true) => {
                    Line::styled(format!("{} = {}", f.key, f.value), Style::new().add_modifier(Modifier::REVERSED))
                }
                _ => Line::from(format!("{} = {}", f.key, f.value)),
            }
        })
        .collect()
}

fn preview(frame: &mut Frame, editor: &Editor, area: Rect) {
    let label = match (&editor.preview_error, editor.previewing) {
        (_, true) => " preview (updating...) ",
        (Some(_), false) => " preview FAILED: the last good one, stale ",
        (None, false) => " preview (low resolution) ",
    };
    let block = Block::default().borders(Borders::LEFT).title(label);
    let mut inner = block.inner(area);
    frame.render_widget(block, area);
    if let Some(error) = &editor.preview_error {
        let lines = 3.min(inner.height);
        let [pictures, reason] = Layout::vertical([Constraint::Min(0), Constraint::Length(lines)]).areas(inner);
        let text = Paragraph::new(error.as_str()).style(Style::new().fg(Color::Red)).wrap(Wrap { trim: true });
        frame.render_widget(text, reason);
        inner = pictures;
    }
    let Some(volume) = &editor.preview else { return };
    let panels = Layout::vertical([Constraint::Ratio(1, 2); 2]).split(inner);
    let top = Layout::horizontal([Constraint::Ratio(1, 2); 2]).split(panels[0]);
    let d = volume.dims();
    for (panel, axis) in [top[0], top[1], panels[1]].iter().zip([Axis::Z, Axis::Y, Axis::X]) {
        let [label, picture] = Layout::vertical([Constraint::Length(1), Constraint::Min(0)]).areas(*panel);
        let text = format!("{axis} = {} of {}", d[axis.index()] / 2, d[axis.index()]);
        frame.render_widget(Paragraph::new(text).style(Style::new().fg(Color::DarkGray)), label);
        if let Ok(image) = volume.slice(axis, d[axis.index()] / 2) {
            frame.render_widget(HalfBlocks { image: &image, channel: 0, overlay: None, scale: None }, picture);
        }
    }
}

/// The fill preview: a cut through the filled shape, with the constraints placed on it.
pub fn fill(frame: &mut Frame, view: &FillView, area: Rect, regions: &mut super::mouse::Regions) {
    let placed = view.edit.as_ref().map_or(String::new(), |e| {
        let changed = view.filled.as_ref().is_some_and(|f| f.spec != e.spec);
        let counts = [
            (e.spec.directions.len(), "stroke(s)"),
            (e.spec.depth.points.len(), "depth pt(s)"),
            (e.spec.depth.faces.len(), "group(s)"),
            (e.spec.pastes.len(), "paste(s)"),
        ];
        let placed: String = counts.iter().filter(|(n, _)| *n > 0).map(|(n, what)| format!(", {n} {what}")).collect();
        let state = if e.pending {
            " [making the field or guided cut...]"
        } else if e.refilling {
            " [filling again...]"
        } else if changed {
            " [r refills]"
        } else {
            ""
        };
        format!("{placed}, depth {:.2}{state}", e.depth)
    });
    let title = format!(" fill: {}, cut {} {:+.2}{placed} ", view.name, view.axis, view.offset);
    let block = Block::default().borders(Borders::ALL).title(super::view::fitted(&title, area.width));
    let inner = block.inner(area);
    frame.render_widget(block, area);
    let Some(filled) = &view.filled else {
        frame.render_widget(Paragraph::new("filling (tet mesh, field, patches)..."), inner);
        return;
    };
    let size = (inner.width as usize).min(2 * inner.height as usize).clamp(8, 4096);
    let x0 = inner.x + (inner.width.saturating_sub(size as u16)) / 2;
    regions.cut = Some(Rect::new(x0, inner.y, size as u16, (size / 2) as u16));
    frame.render_widget(CutWidget { view, filled, size }, Rect::new(x0, inner.y, size as u16, inner.height));
}

/// The cut of a fill preview across `axis` at `offset` (-1 to 1 across the model), `size`
/// pixels square.
pub fn cut_of(
    filled: &super::model::FillPreview,
    axis: crate::volume::Axis,
    offset: f32,
    size: usize,
) -> crate::error::Result<render::Cut> {
    let models = [(&filled.model, &filled.textures)];
    Ok(render::cut_many(&models, &super::fill_edit::plane_view(filled, axis, offset, size)))
}

struct CutWidget<'a> {
    view: &'a FillView,
    filled: &'a super::model::FillPreview,
    size: usize,
}

/// The colour of depth `d`: dark blue at 0 (the surface) to yellow at 1 (innermost).
fn depth_colour(d: f32) -> Color {
    let t = d.clamp(0.0, 1.0);
    let mix = |a: f32, b: f32| to_u8(a + (b - a) * t);
    Color::Rgb(mix(0.08, 1.0), mix(0.1, 0.88), mix(0.45, 0.15))
}

impl Widget for CutWidget<'_> {
    fn render(self, area: Rect, buf: &mut Buffer) {
        let size = self.size;
        let edit = self.view.edit.as_ref();
        let plane = super::fill_edit::plane_view(self.filled, self.view.axis, self.view.offset, size);
        let depth = match (edit.is_some_and(|e| e.show_depth), &self.filled.depth) {
            (true, Some(values)) => Some(render::field_cut(&self.filled.model.mesh, values, &plane)),
            _ => None,
        };
        let overlay = super::fill_edit::overlay_shown(self.view);
        let cut = (depth.is_none() && overlay.is_none())
            .then(|| render::cut_many(&[(&self.filled.model, &self.filled.textures)], &plane));
        let px = |x: usize, y: usize| match (&depth, &cut) {
            (Some(d), _) => d[y * size + x].map(depth_colour),
            (None, None) if let Some(o) = overlay => {
                o.pixels[(y * o.size / size) * o.size + x * o.size / size].map(|[r, g, b]| Color::Rgb(r, g, b))
            }
            (None, Some(cut)) => {
                let p = cut.pixels[y * size + x];
                (p[3] > 0.0).then(|| Color::Rgb(to_u8(p[0]), to_u8(p[1]), to_u8(p[2])))
            }
            _ => None,
        };
        for cy in 0..(size / 2).min(area.height as usize) {
            for cx in 0..size.min(area.width as usize) {
                let Some(cell) = buf.cell_mut((area.x + cx as u16, area.y + cy as u16)) else { continue };
                // A half outside the shape is the background: drawn with the other half's
                // block, so the terminal's default foreground never shows at the rim.
                match (px(cx, 2 * cy), px(cx, 2 * cy + 1)) {
                    (Some(top), Some(bottom)) => cell.set_symbol("▀").set_fg(top).set_bg(bottom),
                    (Some(top), None) => cell.set_symbol("▀").set_fg(top).set_bg(Color::Reset),
                    (None, Some(bottom)) => cell.set_symbol("▄").set_fg(bottom).set_bg(Color::Reset),
                    (None, None) => continue,
                };
            }
        }
        let Some(edit) = edit else { return };
        // the cell a point near the plane (within 8 pixels of it) falls in
        let cell_of = |p: Vec3| -> Option<(f32, f32)> {
            let (normal, rel) = (plane.right.cross(plane.down).normalize(), p - plane.origin);
            if normal.dot(rel).abs() > 8.0 * plane.right.length() {
                return None;
            }
            let x = plane.right.dot(rel) / plane.right.length_squared();
            let y = plane.down.dot(rel) / plane.down.length_squared() / 2.0;
            (x >= 0.0 && y >= 0.0 && (x as usize) < size && (y as usize) < size / 2).then_some((x, y))
        };
        let mut marked: Vec<(u16, u16)> = Vec::new();
        let mut mark = |p: Vec3, symbol: &str, colour: Color| {
            if let Some((x, y)) = cell_of(p) {
                let at = (area.x + x as u16, area.y + y as u16);
                if let Some(cell) = buf.cell_mut(at) {
                    cell.set_symbol(symbol).set_fg(colour).set_bg(Color::Black);
                    marked.push(at);
                }
            }
        };
        let spec = &edit.spec;
        let strokes = spec.directions.iter().map(|s| (s, Color::Yellow)).chain([(&edit.stroke, Color::LightRed)]);
        for (stroke, colour) in strokes {
            // a stroke is a line of dots ending in an arrow the way it was drawn
            for pair in stroke.windows(2) {
                for k in 1..8 {
                    mark(pair[0].lerp(pair[1], k as f32 / 8.0), "·", colour);
                }
            }
            stroke.iter().for_each(|p| mark(*p, "•", colour));
            if let [.., from, to] = &stroke[..]
                && let (Some(a), Some(b)) = (cell_of(*from), cell_of(*to))
            {
                mark(*to, arrow(b.0 - a.0, b.1 - a.1), colour);
            }
        }
        spec.depth.points.iter().for_each(|(p, _)| mark(*p, "◆", Color::Cyan));
        spec.depth.faces.iter().for_each(|f| mark(f.at, "■", Color::Green));
        spec.pastes.iter().for_each(|p| mark(p.at, "✚", Color::Magenta));
        let (cx, cy) = ((edit.cursor[0] * size as f32) as u16, (edit.cursor[1] * size as f32 / 2.0) as u16);
        let at = (area.x + cx.min(size as u16 - 1), area.y + cy.min((size / 2) as u16 - 1));
        // on a mark the cursor lights the mark's cell instead of hiding it
        let on_mark = marked.contains(&at);
        if let Some(cell) = buf.cell_mut(at) {
            if on_mark {
                cell.set_bg(Color::White);
            } else {
                cell.set_symbol("+").set_fg(Color::White).set_bg(Color::Black);
            }
        }
    }
}

/// The arrow nearest the direction (`dx` right, `dy` down, in cells; a cell is twice as
/// tall as wide).
fn arrow(dx: f32, dy: f32) -> &'static str {
    const ARROWS: [&str; 8] = ["→", "↘", "↓", "↙", "←", "↖", "↑", "↗"];
    let angle = (2.0 * dy).atan2(dx).rem_euclid(std::f32::consts::TAU);
    ARROWS[((angle / std::f32::consts::FRAC_PI_4).round() as usize) % 8]
}
