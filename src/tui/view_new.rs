//! Drawing the new-entry screen: the recipe kinds, then the file picker with the photo
//! under the cursor beside it.

use super::graphics::Graphics;
use super::mouse::{List, Regions};
use super::new_entry::{KINDS, NewEntry, PickFor, Picker};
use super::view::HalfBlocks;
use ratatui::Frame;
use ratatui::layout::{Constraint, Layout, Rect};
use ratatui::style::{Color, Modifier, Style};
use ratatui::text::Line;
use ratatui::widgets::{Block, Borders, Paragraph, Wrap};

/// The kinds, or the picker of the chosen kind.
pub fn new_entry(
    frame: &mut Frame,
    entry: &NewEntry,
    area: Rect,
    regions: &mut Regions,
    graphics: Option<&mut Graphics>,
) {
    let what = match &entry.pick_for {
        Some(PickFor::Seed(view)) => format!("seed mesh for {}", view.name),
        Some(PickFor::Step(editor, true)) => format!("mesh to stamp into {}", editor.name),
        Some(PickFor::Step(editor, false)) => format!("mesh to scatter in {}", editor.name),
        Some(PickFor::Spec(view)) => format!("fill spec to load into the preview of {}", view.name),
        None => format!("new {} exemplar", KINDS[entry.kind].recipe),
    };
    match &entry.picker {
        None => kinds(frame, entry.kind, area, regions),
        Some(picker) => files(frame, &what, picker, area, regions, graphics),
    }
}

fn row_style(selected: bool) -> Style {
    if selected { Style::new().add_modifier(Modifier::REVERSED) } else { Style::new() }
}

fn kinds(frame: &mut Frame, chosen: usize, area: Rect, regions: &mut Regions) {
    let block = Block::default().borders(Borders::ALL).title(" new exemplar: what makes it? ");
    regions.list = Some(List { area: block.inner(area), first: 0 });
    let lines: Vec<Line> = KINDS
        .iter()
        .enumerate()
        .map(|(i, k)| Line::styled(format!(" {:<22} {}", k.recipe, k.what), row_style(i == chosen)))
        .collect();
    frame.render_widget(Paragraph::new(lines).block(block), area);
}

fn files(
    frame: &mut Frame,
    what: &str,
    picker: &Picker,
    area: Rect,
    regions: &mut Regions,
    graphics: Option<&mut Graphics>,
) {
    let title = format!(" {what}: {} ", picker.folder.display());
    let block = Block::default().borders(Borders::ALL).title(super::view::fitted(&title, area.width));
    let inner = block.inner(area);
    frame.render_widget(block, area);
    let [list, photo] = Layout::horizontal([Constraint::Percentage(40), Constraint::Percentage(60)]).areas(inner);
    let rows = match &picker.rows {
        None => {
            frame.render_widget(Paragraph::new("reading the folder..."), list);
            return;
        }
        Some(Err(e)) => {
            let text = Paragraph::new(format!("cannot list it: {e}")).style(Style::new().fg(Color::Red));
            frame.render_widget(text.wrap(Wrap { trim: true }), list);
            return;
        }
        Some(Ok(rows)) => rows,
    };
    // keep the selected row in view
    let offset = (picker.selected + 1).saturating_sub(list.height as usize) as u16;
    regions.list = Some(List { area: list, first: usize::from(offset) });
    let lines: Vec<Line> = rows
        .iter()
        .enumerate()
        .map(|(i, r)| {
            let name = if r.folder { format!("{}/", r.name) } else { r.name.clone() };
            let colour = if r.folder { Color::Cyan } else { Color::Reset };
            Line::styled(format!(" {name}"), row_style(i == picker.selected).fg(colour))
        })
        .collect();
    let mut text = lines;
    if rows.iter().all(|r| r.folder) {
        text.push(Line::styled(" (no file of this kind here)", Style::new().fg(Color::DarkGray)));
    }
    frame.render_widget(Paragraph::new(text).scroll((offset, 0)), list);
    let Some((path, peek)) = &picker.peek else { return };
    let name = path.file_name().map(|n| n.to_string_lossy().to_string()).unwrap_or_default();
    match peek {
        Ok(image) => {
            let label = format!(" {name} (shown {}x{}) ", image.width(), image.height());
            let block = Block::default().borders(Borders::LEFT).title(label);
            let inside = block.inner(photo);
            frame.render_widget(block, photo);
            match graphics {
                Some(g) => g.draw(frame, inside, format!("peek:{}", path.display()), image, 0),
                None => frame.render_widget(HalfBlocks { image, channel: 0, overlay: None, scale: None }, inside),
            }
        }
        Err(e) => {
            let text = Paragraph::new(format!("{name}: {e}")).style(Style::new().fg(Color::Red));
            frame.render_widget(text.wrap(Wrap { trim: true }).block(Block::default().borders(Borders::LEFT)), photo);
        }
    }
}
