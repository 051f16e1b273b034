//! Drawing a comparison: two slices across one axis at the same relative place, side by
//! side at one pixel scale, each titled with its quality figures.

use super::compare::index;
use super::model::{CompareView, Side};
use super::view::HalfBlocks;
use crate::volume::{Axis, Image2d};
use ratatui::Frame;
use ratatui::layout::{Constraint, Layout, Rect};
use ratatui::style::{Color, Style};
use ratatui::text::Line;
use ratatui::widgets::{Block, Borders, Paragraph, Wrap};

/// Both sides, and what `a` and `d` do when it compares an entry's builds.
pub fn compare(frame: &mut Frame, view: &CompareView, area: Rect) {
    let title = format!(" {} | {}  across {} ", view.sides[0].label, view.sides[1].label, view.axis);
    let mut block = Block::default().borders(Borders::ALL).title(super::view::fitted(&title, area.width));
    if view.before_after.is_some() {
        let note = " a keeps the new build, d discards it (the previous comes back) ";
        block = block.title_bottom(super::view::fitted(note, area.width));
    }
    let half = area.width.saturating_sub(2) / 2;
    let inner = block.inner(area);
    frame.render_widget(block, area);
    let halves = Layout::horizontal([Constraint::Ratio(1, 2); 2]).split(inner);
    let slices: Vec<Option<Image2d>> = view.sides.iter().map(|s| slice(s, view)).collect();
    let boxes: Vec<Block> =
        view.sides.iter().zip(&slices).map(|(s, i)| side_block(s, i.as_ref(), view, half)).collect();
    let areas: Vec<Rect> = boxes.iter().zip(halves.iter()).map(|(b, h)| b.inner(*h)).collect();
    let fit = |a: Rect, i: &Image2d| (a.width as f32 / i.width() as f32).min(2.0 * a.height as f32 / i.height() as f32);
    let scale = slices.iter().zip(&areas).filter_map(|(i, a)| i.as_ref().map(|i| fit(*a, i))).reduce(f32::min);
    for (((side, image), block), (half, inside)) in
        view.sides.iter().zip(&slices).zip(boxes).zip(halves.iter().zip(&areas))
    {
        frame.render_widget(block, *half);
        match (image, &side.volume) {
            (Some(image), _) => frame.render_widget(HalfBlocks { image, channel: 0, overlay: None, scale }, *inside),
            (None, Some(Err(e))) => {
                let text = Paragraph::new(e.as_str()).style(Style::new().fg(Color::Red)).wrap(Wrap { trim: true });
                frame.render_widget(text, *inside);
            }
            (None, _) => frame.render_widget(Paragraph::new("loading..."), *inside),
        }
    }
}

/// The side's slice at the view's place, +z up as on the slices screen.
fn slice(side: &Side, view: &CompareView) -> Option<Image2d> {
    let volume = side.volume.as_ref()?.as_ref().ok()?;
    let k = view.axis.index();
    let image = volume.slice(view.axis, index(view.position, volume.dims()[k])).ok()?;
    Some(if view.axis != Axis::Z { super::view::flipped(&image) } else { image })
}

fn side_block<'a>(side: &Side, image: Option<&Image2d>, view: &CompareView, width: u16) -> Block<'a> {
    let at = side.volume.as_ref().and_then(|r| r.as_ref().ok()).map(|v| {
        let d = v.dims()[view.axis.index()];
        format!(" {}={}/{}", view.axis, index(view.position, d), d - 1)
    });
    let size = image.map(|i| format!(" {}x{}", i.width(), i.height())).unwrap_or_default();
    let title = format!(" {}{}{size} ", side.label, at.unwrap_or_default());
    let mut block = Block::default().borders(Borders::ALL).title(super::view::fitted(&title, width));
    if let Some(q) = &side.quality {
        let colour = if q.in_range() { Color::Green } else { Color::Red };
        let caption = super::view::fitted(&format!(" {} ", q.summary()), width);
        block = block.title_bottom(Line::styled(caption, Style::new().fg(colour)));
    }
    block
}
