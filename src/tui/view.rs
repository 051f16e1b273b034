//! `view`: draws the model, nothing else. Slices are truecolour half-blocks: each terminal
//! cell shows two voxels, the upper as the foreground of '▀' and the lower as its background.

use super::model::{BuildState, ExemplarView, Help, Model, Screen};
use super::mouse::{List, Panel, Regions};
use crate::render::ColourMap;
use crate::volume::{Axis, Image2d};
use ratatui::Frame;
use ratatui::buffer::Buffer;
use ratatui::layout::{Constraint, Layout, Rect};
use ratatui::style::{Color, Modifier, Style};
use ratatui::text::{Line, Span};
use ratatui::widgets::{Block, Borders, Clear, Paragraph, Row, Table, Widget, Wrap};

/// Smallest usable terminal.
pub const MIN_SIZE: (u16, u16) = (60, 16);

/// Draw the whole screen with half-block pictures.
pub fn draw(frame: &mut Frame, model: &Model) {
    draw_with(frame, model, None, &mut Regions::default());
}

/// Draw the whole screen; slices use `graphics` (sixel, kitty, iTerm2) when given; where
/// the lists and slices went is kept in `regions` for the mouse.
pub fn draw_with(
    frame: &mut Frame,
    model: &Model,
    graphics: Option<&mut super::graphics::Graphics>,
    regions: &mut Regions,
) {
    *regions = Regions::default();
    let area = frame.area();
    if area.width < MIN_SIZE.0 || area.height < MIN_SIZE.1 {
        let text = format!(
            "terminal too small: {}x{}, solidtex needs at least {}x{}",
            area.width, area.height, MIN_SIZE.0, MIN_SIZE.1
        );
        frame.render_widget(Paragraph::new(text), area);
        return;
    }
    let status_text = match &model.prompt {
        Some(p) if p.purpose == super::model::Purpose::Rename && !p.note.is_empty() => {
            format!("new name: {}_  refused: {}", p.input.value(), p.note)
        }
        Some(p) if p.purpose == super::model::Purpose::Rename => {
            format!("new name: {}_  (enter renames, esc keeps the name)", p.input.value())
        }
        Some(p) if p.purpose == super::model::Purpose::Filter => {
            format!("filter: {}_  (enter keeps it, esc shows every entry)", p.input.value())
        }
        Some(p) => format!("save as: {}_  (enter saves, esc does not)", p.input.value()),
        None => model.status.clone(),
    };
    let [main, bar, status] =
        Layout::vertical([Constraint::Min(3), Constraint::Length(1), Constraint::Length(1)]).areas(area);
    frame.render_widget(Paragraph::new(Line::from(key_bar(model, bar.width))), bar);
    match &model.screen {
        Screen::Library => library(frame, model, main, regions),
        Screen::Exemplar(view) if view.beside_photo => {
            let quality = model.items.iter().find(|i| i.name == view.name).and_then(|i| i.quality.as_ref());
            beside_photo(frame, view, quality, main)
        }
        Screen::Exemplar(view) => exemplar(frame, view, main, graphics, regions),
        Screen::Editor(editor) => super::view_edit::editor(frame, editor, main, regions),
        Screen::Fill(view) => super::view_edit::fill(frame, view, main, regions),
        Screen::New(entry) => super::view_new::new_entry(frame, entry, main, regions, graphics),
        Screen::Compare(view) => super::view_compare::compare(frame, view, main),
    }
    let [left, right] =
        Layout::horizontal([Constraint::Min(10), Constraint::Length(OVERLAY_KEYS.len() as u16)]).areas(status);
    let shown = cut(status_text.lines().next().unwrap_or_default(), left.width);
    frame.render_widget(Paragraph::new(shown).style(Style::new().fg(Color::Gray)), left);
    frame.render_widget(Paragraph::new(OVERLAY_KEYS).style(Style::new().fg(Color::DarkGray)), right);
    if let Some(h) = &model.help {
        help(frame, area, &model.screen, h);
    } else if let Some(first) = model.log_view {
        log(frame, area, &model.log, first);
    }
}

/// The keys at the right of the status row, on every screen.
const OVERLAY_KEYS: &str = " ? help  M log  q quit";

/// `text` in at most `width` columns: cut at the end with `…` when longer (the message log
/// keeps it whole).
pub fn cut(text: &str, width: u16) -> String {
    let width = usize::from(width);
    if text.chars().count() <= width {
        return text.to_string();
    }
    let kept: String = text.chars().take(width.saturating_sub(1)).collect();
    format!("{kept}…")
}

/// A title in at most `width` columns (a box's width less its corners): shortened in the
/// middle with `…`, so its start and its end (a file's name, a state) both stay.
pub fn fitted(title: &str, width: u16) -> String {
    let most = usize::from(width.saturating_sub(2));
    let count = title.chars().count();
    if count <= most {
        return title.to_string();
    }
    let head = most.saturating_sub(1) / 3;
    let tail = most.saturating_sub(1) - head;
    let start: String = title.chars().take(head).collect();
    let end: String = title.chars().skip(count - tail).collect();
    format!("{start}…{end}")
}

/// The screen's keys in one row of `width` columns, most used first: a key that cannot
/// act now is dimmed (pressing it says why), and `…` ends the row when keys are left out
/// (the help lists them all).
fn key_bar(model: &Model, width: u16) -> Vec<Span<'static>> {
    let mut spans: Vec<Span> = Vec::new();
    let mut used = 0;
    let hints = super::keybar::hints(model);
    let count = hints.len();
    for (k, h) in hints.into_iter().enumerate() {
        let action = format!(" {} ", h.action);
        let wide = 1 + h.keys.chars().count() + action.chars().count();
        let room = usize::from(width).saturating_sub(if k + 1 < count { 2 } else { 0 });
        if used + wide > room {
            spans.push(Span::styled(" …", Style::new().fg(Color::DarkGray)));
            break;
        }
        used += wide;
        spans.push(Span::raw(" "));
        let (key, text) = match h.why_not {
            None => (Style::new().fg(Color::Yellow), Style::new().fg(Color::Gray)),
            Some(_) => (Style::new().fg(Color::DarkGray), Style::new().fg(Color::DarkGray)),
        };
        spans.push(Span::styled(h.keys, key));
        spans.push(Span::styled(action, text));
    }
    spans
}

fn library(frame: &mut Frame, model: &Model, area: Rect, regions: &mut Regions) {
    let rows = model.visible();
    let mut title = format!(" solidtex library: {} ", model.manifest.display());
    if model.outside {
        title += "(changed on disk: Ctrl-R reloads) ";
    }
    if !model.read_only.is_empty() {
        title += "(read-only) ";
    }
    if let Some(at) = rows.iter().position(|&i| i == model.selected) {
        title += &format!("{}/{} ", at + 1, rows.len());
    }
    if !model.filter.is_empty() {
        title += &format!("filter {:?} ({} of {}) ", model.filter, rows.len(), model.items.len());
    }
    let area = if model.errors.is_empty() { area } else { manifest_errors(frame, model, area) };
    if model.first_run || model.items.is_empty() {
        return first_run(frame, model, area, &title);
    }
    let block = Block::default().borders(Borders::ALL).title(fitted(&title, area.width));
    let block = match &model.batch {
        Some(batch) => {
            block.title_bottom(Line::styled(batch_line(model, batch), Style::new().fg(Color::Yellow)).right_aligned())
        }
        None => block,
    };
    let table_rows = rows.iter().map(|&i| {
        let item = &model.items[i];
        let size = item.size.map(|[x, y, z]| format!("{x}x{y}x{z}")).unwrap_or_else(|| "-".into());
        let declared = item.declared.clone().unwrap_or_else(|| "-".into());
        let (state, measured) = match &item.state {
            BuildState::NotBuilt => ("not built".to_string(), "-".to_string()),
            BuildState::Building => (gauge(model.progress.get(&item.name)), "-".to_string()),
            BuildState::Queued => ("waiting (queued)".to_string(), "-".to_string()),
            BuildState::Built(t) if item.previous => ("built; previous kept".to_string(), t.clone()),
            BuildState::Built(t) => ("built".to_string(), t.clone()),
            BuildState::Changed(t, _) => ("changed since built".to_string(), t.clone()),
            BuildState::Failed(e, true) => (format!("failed (earlier build kept): {e}"), "-".to_string()),
            BuildState::Failed(e, false) => (format!("failed: {e}"), "-".to_string()),
            BuildState::Broken(_) => ("mistake: e fixes it".to_string(), "-".to_string()),
        };
        let badge = if measured != "-" && measured != declared { format!("{measured} (differs)") } else { measured };
        let style = if i == model.selected { Style::new().add_modifier(Modifier::REVERSED) } else { Style::new() };
        let quality = item.quality.as_ref().map_or("-", |q| q.verdict()).to_string();
        let marked = model.mark.as_deref() == Some(item.name.as_str());
        let name = if marked { format!("{} (v)", item.name) } else { item.name.clone() };
        Row::new(vec![name, size, declared, badge, quality, state]).style(style)
    });
    // names as wide as the longest (with room for the compare mark), up to 28 columns
    let mark = |i: &super::model::Item| if model.mark.as_deref() == Some(i.name.as_str()) { 4 } else { 0 };
    let longest = model.items.iter().map(|i| i.name.chars().count() + mark(i)).max().unwrap_or(8);
    let widths = [
        Constraint::Length(longest.clamp(10, 28) as u16),
        Constraint::Length(11),
        Constraint::Length(8),
        Constraint::Length(13),
        Constraint::Length(7),
        Constraint::Min(10),
    ];
    // while builds run their count takes the bottom line
    let quality = model.items.get(model.selected).filter(|_| model.batch.is_none());
    let block = match quality.and_then(|i| Some((i, i.quality.as_ref()?))) {
        Some((item, q)) => {
            let colour = if q.in_range() { Color::Green } else { Color::Red };
            let verdict = if q.in_range() { "in range".to_string() } else { format!("out of range: {}", q.verdict()) };
            let line = format!(" {}: {} ({verdict}) ", item.name, q.summary());
            block.title_bottom(Line::styled(line, Style::new().fg(colour)))
        }
        None => block,
    };
    let header = Row::new(vec!["exemplar", "size", "declared", "measured", "quality", "state"])
        .style(Style::new().add_modifier(Modifier::BOLD));
    let selected = model.items.get(model.selected).and_then(|i| model.previews.get(&i.name));
    let (table, side) = match selected {
        Some(preview) if area.width >= 100 => {
            let [t, s] = Layout::horizontal([Constraint::Min(60), Constraint::Length(34)]).areas(area);
            (t, Some((s, preview)))
        }
        _ => (area, None),
    };
    let inner = block.inner(table);
    let rows_area = Rect { y: inner.y + 1, height: inner.height.saturating_sub(1), ..inner };
    // the table scrolls to keep the selected row in view
    let at = rows.iter().position(|&i| i == model.selected);
    let mut state = ratatui::widgets::TableState::default().with_selected(at);
    frame.render_stateful_widget(Table::new(table_rows, widths).header(header).block(block), table, &mut state);
    regions.list = Some(List { area: rows_area, first: state.offset() });
    if let Some((rect, (level, volume))) = side {
        let block = Block::default().borders(Borders::ALL).title(format!(" level {level} (z middle) "));
        let inner = block.inner(rect);
        frame.render_widget(block, rect);
        if let Ok(image) = volume.slice(Axis::Z, volume.dims()[2] / 2) {
            frame.render_widget(HalfBlocks { image: &image, channel: 0, overlay: None, scale: None }, inner);
        }
    }
}

/// The manifest's mistakes in red below the list, wrapped, up to half of `area` (scrolled
/// by `[` and `]`); the area left for the list.
fn manifest_errors(frame: &mut Frame, model: &Model, area: Rect) -> Rect {
    let wrapped: u16 = model.errors.iter().map(|e| wrapped_lines(e, area.width.saturating_sub(2))).sum();
    let lines = (wrapped + 2).min(area.height / 2).max(3);
    let [list, errors] = Layout::vertical([Constraint::Min(3), Constraint::Length(lines)]).areas(area);
    let text: Vec<Line> = model.errors.iter().map(|e| Line::styled(e.as_str(), Style::new().fg(Color::Red))).collect();
    let hidden = wrapped.saturating_sub(lines - 2);
    let scroll = (model.error_scroll as u16).min(hidden);
    let more = if hidden > 0 {
        format!("lines {}-{} of {wrapped}, [ ] scroll; ", scroll + 1, scroll + lines - 2)
    } else {
        String::new()
    };
    let working = model.items.iter().any(|i| !matches!(i.state, BuildState::Broken(_)));
    let rest = if working { "the other exemplars work" } else { "fix the file, then Ctrl-R reads it again" };
    let title = format!(" the manifest has {} error(s) ({more}{rest}) ", model.errors.len());
    let box_ = Block::default().borders(Borders::ALL).title(fitted(&title, errors.width));
    let paragraph = Paragraph::new(text).wrap(ratatui::widgets::Wrap { trim: false }).scroll((scroll, 0));
    frame.render_widget(paragraph.block(box_), errors);
    list
}

/// The library when it has no entry yet: how to start one.
fn first_run(frame: &mut Frame, model: &Model, area: Rect, title: &str) {
    let text = if model.first_run {
        vec![
            Line::from(format!("There is no library at {} yet.", model.manifest.display())),
            Line::from(""),
            Line::from("Press enter to start one there (an empty manifest with a comment on its format),"),
            Line::from("then n to add your first exemplar from a photo, a cross-section or a recipe."),
            Line::from("q quits and writes nothing."),
        ]
    } else if !model.errors.is_empty() {
        vec![
            Line::from("No exemplar can be read from this manifest: its mistakes are listed below."),
            Line::from(""),
            Line::from("Fix them in the file (in a text editor), then press Ctrl-R to read it again."),
        ]
    } else {
        vec![
            Line::from("This library has no exemplar yet."),
            Line::from(""),
            Line::from("Press n to add your first exemplar: a photo to synthesize a solid from,"),
            Line::from("a cross-section to sweep, a volume file, or a procedural recipe."),
        ]
    };
    let block = Block::default().borders(Borders::ALL).title(fitted(title, area.width));
    frame.render_widget(Paragraph::new(text).wrap(Wrap { trim: false }).block(block), area);
}

/// Builds asked for together: `building 2/5 · 0:45 · about 1:10 left`.
fn batch_line(model: &Model, batch: &super::model::Batch) -> String {
    let running: f32 = model.progress.values().map(|(_, f)| f.clamp(0.0, 1.0)).sum();
    let share = ((batch.done as f32 + running) / batch.total.max(1) as f32).clamp(0.0, 1.0);
    let elapsed = model.now.saturating_sub(batch.started).as_secs_f32();
    let clock = |s: f32| format!("{}:{:02}", s as u64 / 60, s as u64 % 60);
    let mut line = format!(" building {}/{} · {}", batch.done + 1, batch.total, clock(elapsed));
    if share > 0.02 && elapsed >= 2.0 {
        line += &format!(" · about {} left", clock(elapsed * (1.0 - share) / share));
    }
    line + " "
}

/// A build's state as a one-line gauge: `level 2/3 ####---- 48%`.
fn gauge(progress: Option<&(String, f32)>) -> String {
    let Some((stage, fraction)) = progress else { return "building...".into() };
    let filled = (fraction.clamp(0.0, 1.0) * 8.0).round() as usize;
    let level = stage.split(',').next().unwrap_or(stage);
    format!("{level} {}{} {:.0}%", "#".repeat(filled), "-".repeat(8 - filled), fraction * 100.0)
}

/// Where the seed is: position (voxels), rotation (degrees about an axis), scale (voxels
/// per mesh unit).
fn readout(p: &crate::stamp::Placement) -> String {
    let (axis, angle) = p.rotation.to_axis_angle();
    let degrees = angle.to_degrees().round();
    let turned = if degrees == 0.0 || degrees == 360.0 {
        "not turned".to_string()
    } else {
        format!("turned {degrees}° about {:.2},{:.2},{:.2}", axis.x, axis.y, axis.z)
    };
    let s = p.scale;
    let scale =
        if s.x == s.y && s.y == s.z { format!("{:.2}", s.x) } else { format!("{:.2},{:.2},{:.2}", s.x, s.y, s.z) };
    format!("at {:.0},{:.0},{:.0}, {turned}, scale {scale}", p.at.x, p.at.y, p.at.z)
}

fn exemplar(
    frame: &mut Frame,
    view: &ExemplarView,
    area: Rect,
    mut graphics: Option<&mut super::graphics::Graphics>,
    regions: &mut Regions,
) {
    let title = match &view.stamp {
        Some(s) => format!(
            " {}  STAMP MODE: {}; {} step(s) unsaved; m leaves ",
            view.name,
            readout(&s.placement),
            s.steps.len()
        ),
        None => {
            let shown = view.layers.get(view.layer).map_or("exemplar", |l| l.0.as_str());
            let zoom = if view.zoom > 1 { format!(" x{}", view.zoom) } else { String::new() };
            let older = if view.older { " (earlier build: the latest failed)" } else { "" };
            format!(" {}{older} {shown}{zoom} ", view.name)
        }
    };
    let block = Block::default().borders(Borders::ALL).title(fitted(&title, area.width));
    let inner = block.inner(area);
    frame.render_widget(block, area);
    let Some(volume) = &view.volume else {
        frame.render_widget(Paragraph::new("loading..."), inner);
        return;
    };
    let panels = Layout::horizontal([Constraint::Ratio(1, 3); 3]).split(inner);
    let d = volume.dims();
    let channel_name = match view.channel {
        0 => "colour".to_string(),
        k => volume.channels()[k - 1].to_string(),
    };
    for (panel, axis) in panels.iter().zip([Axis::Z, Axis::Y, Axis::X]) {
        let k = axis.index();
        let active = axis == view.axis;
        let (a, b) = axis.plane_axes();
        let label = format!(
            " {}{} {axis}={}/{} {channel_name} ",
            ["X", "Y", "Z"][a],
            ["X", "Y", "Z"][b],
            view.index[k],
            d[k] - 1
        );
        let style = if active { Style::new().fg(Color::Yellow) } else { Style::new() };
        let block = Block::default().borders(Borders::ALL).title(fitted(&label, panel.width)).border_style(style);
        let slice_area = block.inner(*panel);
        frame.render_widget(block, *panel);
        let Ok(full) = volume.slice(axis, view.index[k]) else { continue };
        // Slices containing z are drawn with +z up, as on the contact sheet.
        let up = axis != Axis::Z;
        let full = if up { flipped(&full) } else { full };
        let rows = full.height();
        let (image, ox, oy) = crop(&full, view.zoom);
        let (w, h) = (image.width(), image.height());
        regions.panels.push(Panel {
            area: slice_area,
            axis,
            scale: (slice_area.width as f32 / w as f32).min(2.0 * slice_area.height as f32 / h as f32),
            size: (w, h),
            origin: (ox, oy),
            rows,
            up,
        });
        if let (Some(g), None) = (graphics.as_deref_mut(), &view.stamp) {
            let key = format!(
                "{}:{axis}:{}:{}:{}:{:p}",
                view.name,
                view.index[k],
                view.channel,
                view.zoom,
                std::sync::Arc::as_ptr(volume)
            );
            g.draw(frame, slice_area, key, &image, view.channel);
            continue;
        }
        {
            let outline = view.stamp.as_ref().map(|s| s.outline.clone());
            let index = view.index[k];
            let seed = move |px: usize, py: usize| {
                let mut v = [0usize; 3];
                let row = if up { rows - 1 - (py + oy) } else { py + oy };
                (v[k], v[a], v[b]) = (index, px + ox, row);
                outline.as_ref().is_some_and(|o| o.at(v[0], v[1], v[2]) > 0.5)
            };
            let overlay: Option<&dyn Fn(usize, usize) -> bool> =
                view.stamp.as_ref().map(|_| &seed as &dyn Fn(usize, usize) -> bool);
            frame.render_widget(HalfBlocks { image: &image, channel: view.channel, overlay, scale: None }, slice_area);
        }
    }
}

/// The photo of the slice axis beside the slice, both at one pixel scale (the largest at
/// which both fit their half), with the quality figures of the last build.
fn beside_photo(frame: &mut Frame, view: &ExemplarView, quality: Option<&crate::quality::Glance>, area: Rect) {
    let k = view.axis.index();
    let figures = quality.and_then(|q| q.axes.iter().find(|a| a.0 == k).map(|a| (a, q.histogram)));
    let title = match figures {
        Some(((_, g, l), h)) => {
            format!(" {} across {}: sharp {g:.2}  size {l:.2}  hist {h:.2}  (p: three slices) ", view.name, view.axis)
        }
        None => format!(
            " {} across {}: no figures (built before they were kept, or not synthesized)  (p: three slices) ",
            view.name, view.axis
        ),
    };
    let colour = match quality {
        Some(q) if q.in_range() => Color::Green,
        Some(_) => Color::Red,
        None => Color::Reset,
    };
    let block =
        Block::default().borders(Borders::ALL).title(Line::styled(fitted(&title, area.width), Style::new().fg(colour)));
    let inner = block.inner(area);
    frame.render_widget(block, area);
    let (Some(volume), Some(Ok(photos))) = (&view.volume, &view.photos) else {
        frame.render_widget(Paragraph::new("reading the photo..."), inner);
        return;
    };
    let [left, right] = Layout::horizontal([Constraint::Ratio(1, 2); 2]).areas(inner);
    let Some(photo) = &photos[k] else {
        let text = format!("no photo for the slices across {} (x, y or z chooses another axis)", view.axis);
        frame.render_widget(Paragraph::new(text).wrap(Wrap { trim: true }), left);
        return;
    };
    let Ok(slice) = volume.slice(view.axis, view.index[k]) else { return };
    let slice = if view.axis != Axis::Z { flipped(&slice) } else { slice };
    let pblock = Block::default().borders(Borders::ALL).title(format!(" photo {}x{} ", photo.width(), photo.height()));
    let d = volume.dims();
    let sblock = Block::default()
        .borders(Borders::ALL)
        .title(format!(" slice {}={}/{} ", view.axis, view.index[k], d[k] - 1))
        .border_style(Style::new().fg(Color::Yellow));
    let (pa, sa) = (pblock.inner(left), sblock.inner(right));
    let fit = |a: Rect, i: &Image2d| (a.width as f32 / i.width() as f32).min(2.0 * a.height as f32 / i.height() as f32);
    let scale = fit(pa, photo).min(fit(sa, &slice));
    frame.render_widget(pblock, left);
    frame.render_widget(sblock, right);
    frame.render_widget(HalfBlocks { image: photo, channel: 0, overlay: None, scale: Some(scale) }, pa);
    frame.render_widget(HalfBlocks { image: &slice, channel: 0, overlay: None, scale: Some(scale) }, sa);
}

/// `image` upside down (row 0 last).
pub fn flipped(image: &Image2d) -> Image2d {
    let data = (0..image.height()).rev().flat_map(|y| (0..image.width()).flat_map(move |x| image.pixel(x, y).to_vec()));
    Image2d::from_data(image.width(), image.height(), image.channels().to_vec(), data.collect())
        .unwrap_or_else(|_| image.clone())
}

/// The middle `1/zoom` of `image` in each direction, and where it starts.
fn crop(image: &Image2d, zoom: usize) -> (Image2d, usize, usize) {
    let (w, h) = (image.width(), image.height());
    let (cw, ch) = ((w / zoom.max(1)).max(1), (h / zoom.max(1)).max(1));
    let (ox, oy) = ((w - cw) / 2, (h - ch) / 2);
    let data = (oy..oy + ch).flat_map(|y| (ox..ox + cw).flat_map(move |x| image.pixel(x, y).to_vec())).collect();
    let cropped = Image2d::from_data(cw, ch, image.channels().to_vec(), data).unwrap_or_else(|_| image.clone());
    (cropped, ox, oy)
}

/// A 2D image drawn with half-block characters, scaled to fit: grown by repeating pixels,
/// shrunk by averaging the pixels each half cell covers (point samples of a fine pattern
/// such as marble veins alias into noise).
pub struct HalfBlocks<'a> {
    /// The image.
    pub image: &'a Image2d,
    /// 0: natural colours; k: channel k - 1 as grey.
    pub channel: usize,
    /// Pixels to tint yellow (the seed in stamp mode).
    pub overlay: Option<&'a dyn Fn(usize, usize) -> bool>,
    /// Terminal columns per pixel (None: as large as fits).
    pub scale: Option<f32>,
}

impl Widget for HalfBlocks<'_> {
    fn render(self, area: Rect, buf: &mut Buffer) {
        let (w, h) = (self.image.width() as f32, self.image.height() as f32);
        let scale = self.scale.unwrap_or((area.width as f32 / w).min(2.0 * area.height as f32 / h));
        if scale <= 0.0 {
            return;
        }
        let map = match self.channel {
            0 => ColourMap::for_channels(self.image.channels()),
            k => ColourMap::Grey(k - 1),
        };
        let (iw, ih) = (self.image.width(), self.image.height());
        let colour = |x: f32, y: f32| -> Option<Color> {
            let (px, py) = ((x / scale) as usize, (y / scale) as usize);
            if px >= iw || py >= ih {
                return None;
            }
            // The pixels under this half cell: one when growing, a block when shrinking.
            let (x1, y1) =
                ((((x + 1.0) / scale) as usize).clamp(px + 1, iw), (((y + 1.0) / scale) as usize).clamp(py + 1, ih));
            let (mut sum, mut seeded) = ([0u32; 3], false);
            for (qx, qy) in (py..y1).flat_map(|qy| (px..x1).map(move |qx| (qx, qy))) {
                let c = map.colour(self.image.pixel(qx, qy));
                sum.iter_mut().zip(c).for_each(|(s, v)| *s += u32::from(v));
                seeded |= self.overlay.is_some_and(|seed| seed(qx, qy));
            }
            let n = ((x1 - px) * (y1 - py)) as u32;
            let [r, g, b] = sum.map(|s| (s / n) as u8);
            if seeded {
                let tint = |c: u8, t: u8| ((c as u16 * 2 + t as u16 * 3) / 5) as u8;
                return Some(Color::Rgb(tint(r, 255), tint(g, 220), tint(b, 0)));
            }
            Some(Color::Rgb(r, g, b))
        };
        for cy in 0..area.height {
            for cx in 0..area.width {
                let (top, bottom) = (colour(cx as f32, 2.0 * cy as f32), colour(cx as f32, 2.0 * cy as f32 + 1.0));
                let Some(top) = top else { continue };
                if let Some(cell) = buf.cell_mut((area.x + cx, area.y + cy)) {
                    cell.set_symbol("▀").set_fg(top).set_bg(bottom.unwrap_or(Color::Reset));
                }
            }
        }
    }
}

/// How many lines `text` takes wrapped at `width` columns (counting characters; a close
/// enough estimate of the word wrap for choosing a height).
pub fn wrapped_lines(text: &str, width: u16) -> u16 {
    let width = usize::from(width.max(1));
    text.lines().map(|l| l.chars().count().div_ceil(width).max(1)).sum::<usize>().min(u16::MAX as usize) as u16
}

/// The help's lines: the keys of the screen on top first, then the others, those matching
/// the search with the match highlighted.
fn help_text(screen: &Screen, query: &str) -> (Vec<Line<'static>>, usize) {
    let sections = super::keymap::help_rows(screen, query);
    let keys_wide = sections.iter().flat_map(|(_, rows)| rows.iter()).map(|(k, _)| k.chars().count()).max();
    let wide = keys_wide.unwrap_or(0) + 2;
    let mut text: Vec<Line> = Vec::new();
    for (title, rows) in &sections {
        text.push(Line::from(Span::styled(*title, Style::new().add_modifier(Modifier::BOLD))));
        for (keys, action) in rows {
            let mut spans = vec![Span::raw("  ")];
            spans.extend(marked(&format!("{keys:<wide$}"), query));
            spans.extend(marked(action, query));
            text.push(Line::from(spans));
        }
    }
    if sections.is_empty() {
        text.push(Line::from(format!("no key matches '{query}'")));
    }
    let widest = sections.iter().flat_map(|(_, rows)| rows.iter()).map(|(_, a)| a.chars().count() + wide + 4).max();
    (text, widest.unwrap_or(40))
}

/// Rows of an overlay of `lines` lines in a terminal `height` rows high that show lines
/// (its borders and its bottom line take three).
fn overlay_rows(lines: usize, height: u16) -> usize {
    (lines + 3).min(usize::from(height)).saturating_sub(3)
}

/// The furthest the help scrolls on a terminal of `size`.
pub fn help_scroll_most(screen: &Screen, query: &str, size: (u16, u16)) -> usize {
    let lines = help_text(screen, query).0.len();
    lines.saturating_sub(overlay_rows(lines, size.1))
}

/// The furthest the message log scrolls on a terminal of `size`.
pub fn log_scroll_most(log: &[String], size: (u16, u16)) -> usize {
    log_rows(log, size.0).len().saturating_sub(usize::from(size.1).saturating_sub(3))
}

/// The message log's rows on a terminal `width` columns wide: each message whole, its
/// continuation rows indented under its text.
fn log_rows(log: &[String], width: u16) -> Vec<String> {
    let wide = usize::from(width.saturating_sub(2)).max(12);
    let mut rows = Vec::new();
    for message in log {
        let chars: Vec<char> = message.chars().collect();
        rows.push(chars.iter().take(wide).collect());
        for chunk in chars.get(wide..).unwrap_or_default().chunks(wide - 6) {
            rows.push(format!("      {}", chunk.iter().collect::<String>()));
        }
    }
    rows
}

/// The help overlay, scrolled to `state.scroll`; the search and where the view is at the
/// bottom.
fn help(frame: &mut Frame, area: Rect, screen: &Screen, state: &Help) {
    let (text, widest) = help_text(screen, &state.query);
    let search = match (state.typing, state.query.is_empty()) {
        (true, _) => format!("/{}_  (enter keeps it, esc clears)", state.query),
        (false, false) => format!("/{}  (/ changes it, esc clears)", state.query),
        (false, true) => "/ search  esc close".to_string(),
    };
    let rows = overlay_rows(text.len(), area.height);
    let first = state.scroll.min(text.len().saturating_sub(rows));
    let w = (widest.max(60) as u16).min(area.width);
    let h = (rows + 3) as u16;
    let rect = Rect::new(area.x + (area.width - w) / 2, area.y + (area.height - h) / 2, w, h);
    let title = format!(" keys: {} ", super::keymap::section_of(screen));
    overlay(frame, rect, &title, text, first, &search);
}

/// The message log: every status shown, newest last, scrolled to `first`.
fn log(frame: &mut Frame, area: Rect, log: &[String], first: usize) {
    let rows = usize::from(area.height).saturating_sub(3);
    let lines = log_rows(log, area.width);
    let first = first.min(lines.len().saturating_sub(rows));
    let text: Vec<Line> = lines.into_iter().map(Line::from).collect();
    overlay(frame, area, " messages (newest last) ", text, first, "M or esc closes");
}

/// An overlay box: `text` from line `first`, and a bottom line with `note` and, when the
/// text is longer than the box, which lines show and how to scroll.
fn overlay(frame: &mut Frame, rect: Rect, title: &str, text: Vec<Line>, first: usize, note: &str) {
    let inner = Rect::new(rect.x + 1, rect.y + 1, rect.width.saturating_sub(2), rect.height.saturating_sub(2));
    let [body, bottom] = Layout::vertical([Constraint::Min(1), Constraint::Length(1)]).areas(inner);
    let total = text.len();
    let shown = usize::from(body.height).min(total);
    let mut line = note.to_string();
    if shown < total {
        line += &format!("  lines {}-{} of {total}: up/down, pgup/pgdn, g/G scroll", first + 1, first + shown);
    }
    frame.render_widget(Clear, rect);
    frame.render_widget(Block::default().borders(Borders::ALL).title(fitted(title, rect.width)), rect);
    frame.render_widget(Paragraph::new(text).scroll((first as u16, 0)), body);
    frame.render_widget(Paragraph::new(cut(&line, bottom.width)).style(Style::new().fg(Color::Yellow)), bottom);
}

/// `text` as spans, the first match of `query` (any case) highlighted.
fn marked<'a>(text: &str, query: &str) -> Vec<Span<'a>> {
    let found = (!query.is_empty()).then(|| text.to_lowercase().find(&query.to_lowercase())).flatten();
    match found {
        // lower-casing keeps byte offsets for the ASCII the help is written in
        Some(at) if text.is_char_boundary(at) && text.is_char_boundary(at + query.len()) => vec![
            Span::raw(text[..at].to_string()),
            Span::styled(text[at..at + query.len()].to_string(), Style::new().fg(Color::Black).bg(Color::Yellow)),
            Span::raw(text[at + query.len()..].to_string()),
        ],
        _ => vec![Span::raw(text.to_string())],
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::tui::model::{ExemplarView, Item};
    use crate::volume::{Channel, Volume};
    use ratatui::Terminal;
    use ratatui::backend::TestBackend;
    use std::path::PathBuf;
    use std::sync::Arc;

    fn screen(model: &Model, w: u16, h: u16) -> (String, Buffer) {
        let mut terminal = Terminal::new(TestBackend::new(w, h)).unwrap();
        terminal.draw(|f| draw(f, model)).unwrap();
        let buffer = terminal.backend().buffer().clone();
        let text = (0..h)
            .map(|y| (0..w).map(|x| buffer[(x, y)].symbol().to_string()).collect::<String>())
            .collect::<Vec<_>>()
            .join("\n");
        (text, buffer)
    }

    fn model() -> Model {
        let items = vec![
            Item {
                name: "kiwi".into(),
                declared: Some("2-b".into()),
                size: Some([64; 3]),
                state: BuildState::Built("1-b".into()),
                quality: None,
                previous: false,
            },
            Item {
                name: "marble".into(),
                declared: Some("0".into()),
                size: Some([64; 3]),
                state: BuildState::NotBuilt,
                quality: None,
                previous: false,
            },
        ];
        Model::new(PathBuf::from("lib.toml"), PathBuf::from("out"), items, Vec::new())
    }

    #[test]
    fn the_library_screen_lists_types_and_states_at_80x24() {
        let (text, _) = screen(&model(), 80, 24);
        assert!(text.contains("solidtex library: lib.toml"), "{text}");
        assert!(text.contains("kiwi") && text.contains("64x64x64") && text.contains("1-b (differs)"), "{text}");
        assert!(text.contains("marble") && text.contains("not built"), "{text}");
        assert!(text.contains("? help"), "{text}");
        let mut m = model();
        m.items[1].state = BuildState::Building;
        m.progress.insert("marble".into(), ("level 2/3, iteration 1: searched".into(), 0.48));
        m.items[0].state = BuildState::Queued;
        let (text, _) = screen(&m, 80, 24);
        assert!(text.contains("level 2/3 ####---- 48%") && text.contains("waiting (queued)"), "{text}");
        let (text, _) = screen(&m, 140, 24);
        assert!(text.contains("esc cancel builds") && text.contains("R build changed"), "{text}");
        m.items[0].state = BuildState::Built("1-b".into());
        m.selected = 1;
        let level =
            Volume::from_fn([8, 8, 8], Channel::rgb(), |_, _, _, o| o.copy_from_slice(&[0.0, 0.0, 1.0])).unwrap();
        m.previews.insert("marble".into(), ("2/3".into(), Arc::new(level)));
        let (text, buffer) = screen(&m, 110, 24);
        assert!(text.contains("level 2/3 (z middle)"), "{text}");
        let blue = (0..110u16)
            .flat_map(|x| (0..24u16).map(move |y| (x, y)))
            .filter(|p| buffer[*p].fg == Color::Rgb(0, 0, 255))
            .count();
        assert!(blue > 50, "{blue} cells of the level preview");
    }

    /// A manifest that does not load shows its mistakes, not an empty library inviting a
    /// first entry.
    #[test]
    fn a_manifest_that_does_not_load_shows_why() {
        let error = "lib.toml: invalid manifest at line 5: duplicate key `size`".to_string();
        let m = Model::new(PathBuf::from("lib.toml"), PathBuf::from("out"), Vec::new(), vec![error]);
        let (text, _) = screen(&m, 80, 24);
        assert!(text.contains("duplicate key `size`") && text.contains("1 error(s)"), "{text}");
        assert!(text.contains("No exemplar can be read") && text.contains("Ctrl-R"), "{text}");
        assert!(!text.contains("has no exemplar yet"), "{text}");
    }

    #[test]
    fn a_small_terminal_gets_a_message_and_help_overlays() {
        let (text, _) = screen(&model(), 40, 10);
        assert!(text.contains("terminal too small: 40x10"), "{text}");
        let mut m = model();
        m.help = Some(Help::default());
        let (text, _) = screen(&m, 80, 40);
        assert!(text.contains("keys: library") && text.contains("cycle colour"), "{text}");
        assert!(text.contains("/ search  esc close"), "{text}");
        // a search keeps the matching keys, highlighted, and says how to change it
        m.help = Some(Help { query: "Zoom".into(), typing: false, scroll: 0 });
        let (text, buffer) = screen(&m, 80, 40);
        assert!(text.contains("zoom") && !text.contains("cycle colour"), "{text}");
        assert!(text.contains("/Zoom  (/ changes it, esc clears)"), "{text}");
        let highlighted =
            buffer.content().iter().filter(|c| c.bg == Color::Yellow).map(|c| c.symbol()).collect::<String>();
        assert_eq!(highlighted, "zoom");
        m.help = Some(Help { query: "qqq".into(), typing: true, scroll: 0 });
        let (text, _) = screen(&m, 80, 40);
        assert!(text.contains("no key matches 'qqq'") && text.contains("/qqq_"), "{text}");
        // the rename prompt shows what is typed, and the key bar its keys
        m.help = None;
        m.prompt = Some(crate::tui::model::Prompt {
            purpose: crate::tui::model::Purpose::Rename,
            input: "ab".into(),
            note: String::new(),
        });
        let (text, _) = screen(&m, 80, 24);
        assert!(text.contains("new name: ab_") && text.contains("keep the name"), "{text}");
    }

    /// The exemplar view of `volume`, its central slices shown.
    fn viewing(volume: Volume) -> Model {
        let index = volume.dims().map(|d| d / 2);
        Model {
            screen: Screen::Exemplar(ExemplarView {
                volume: Some(Arc::new(volume)),
                index,
                ..ExemplarView::new("kiwi")
            }),
            ..model()
        }
    }

    #[test]
    fn the_exemplar_view_draws_slices_in_colour() {
        let volume =
            Volume::from_fn([8, 8, 8], Channel::rgb(), |_, _, _, o| o.copy_from_slice(&[1.0, 0.0, 0.0])).unwrap();
        let (text, buffer) = screen(&viewing(volume), 80, 24);
        assert!(text.contains("XY z=4/7") && text.contains("XZ y=4/7") && text.contains("YZ x=4/7"), "{text}");
        let ramp =
            Image2d::from_data(8, 1, crate::volume::Channel::grey(), (0..8).map(|x| x as f32).collect()).unwrap();
        let (zoomed, ox, _) = crop(&ramp, 4);
        assert_eq!((zoomed.width(), ox, zoomed.data()), (2, 3, &[3.0, 4.0][..]), "zoom 4 keeps the middle quarter");
        let red = (0..80u16)
            .flat_map(|x| (0..24u16).map(move |y| (x, y)))
            .filter(|p| buffer[*p].fg == Color::Rgb(255, 0, 0))
            .count();
        assert!(red > 100, "{red} red half-blocks");
        let m2 = Model { errors: vec!["lib.toml: line 9: entry 3 (a): size is missing".into()], ..model() };
        let (text, _) = screen(&m2, 80, 24);
        assert!(text.contains("size is missing") && text.contains("the manifest has 1 error(s)"), "{text}");
        assert!(text.contains("kiwi") && text.contains("marble"), "the valid exemplars stay listed: {text}");
        // when every listed entry is broken, none is said to work
        let mut m4 = Model { errors: m2.errors.clone(), ..model() };
        m4.items.iter_mut().for_each(|i| i.state = BuildState::Broken("size is missing".into()));
        let (text, _) = screen(&m4, 80, 24);
        assert!(text.contains("fix the file") && !text.contains("the other exemplars work"), "{text}");
        let many = (1..=12).map(|i| format!("lib.toml: line {i}: exemplar[{i}] (e{i}): size is missing")).collect();
        let mut m3 = Model { errors: many, ..model() };
        let (text, _) = screen(&m3, 80, 24);
        assert!(text.contains("[ ] scroll") && text.contains("(e1)") && !text.contains("(e12)"), "{text}");
        crate::tui::update(&mut m3, crate::tui::Message::ScrollErrors(30));
        let (text, _) = screen(&m3, 80, 24);
        assert!(text.contains("(e12)") && !text.contains("(e1)"), "scrolled to the last error: {text}");
    }

    /// Slices containing z have +z up, as on the contact sheet; a slice wider than its
    /// panel is shrunk by averaging, so a fine checkerboard reads as grey, not as noise.
    #[test]
    fn slices_have_z_up_and_shrink_by_averaging() {
        let volume = Volume::from_fn([64, 64, 64], Channel::rgb(), |x, y, z, o| {
            let check = ((x + y) % 2) as f32;
            o.copy_from_slice(&[z as f32 / 63.0, check, 1.0 - z as f32 / 63.0]);
        })
        .unwrap();
        let (_, buffer) = screen(&viewing(volume), 80, 24);
        let rgb = |c: Color| match c {
            Color::Rgb(r, g, b) => Some((r, g, b)),
            _ => None,
        };
        // The XY panel (left third): green is the checkerboard, averaged to about half.
        let greens: Vec<u8> = (1..26u16)
            .flat_map(|x| (0..24u16).map(move |y| (x, y)))
            .filter_map(|p| rgb(buffer[p].fg))
            .map(|c| c.1)
            .collect();
        assert!(greens.len() > 100, "{} cells", greens.len());
        let grey = greens.iter().filter(|g| (60..=195).contains(*g)).count();
        assert!(grey * 10 >= greens.len() * 9, "{grey} of {} cells averaged", greens.len());
        // The XZ and YZ panels (right two thirds): red (high z) on top, blue (low z) below.
        let rows: Vec<u16> = (0..24u16).filter(|&y| (30..80u16).any(|x| rgb(buffer[(x, y)].fg).is_some())).collect();
        let (top, bottom) = (rows[0], rows[rows.len() - 1]);
        let (tr, _, tb) = rgb(buffer[(40, top)].fg).unwrap();
        let (br, _, bb) = rgb(buffer[(40, bottom)].fg).unwrap();
        assert!(tr > tb && bb > br, "top ({tr}, {tb}) is high z, bottom ({br}, {bb}) low z");
    }

    /// A long status takes one row, cut with `…` (the log keeps it whole), beside the keys
    /// every screen has.
    #[test]
    fn a_long_status_is_one_row_cut_and_whole_in_the_log() {
        let mut m = model();
        let reason =
            "line 43: step 1: count = 4000 is out of range; allowed: 1 to 2000 (the most seeds one scatter places)";
        crate::tui::update(&mut m, crate::tui::Message::Say(format!("not saved: {reason}")));
        let (text, _) = screen(&m, 80, 24);
        let last = text.lines().last().unwrap();
        assert!(last.starts_with("not saved: line 43") && last.contains('…'), "{last}");
        assert!(last.ends_with(OVERLAY_KEYS), "{last}");
        assert!(!text.contains("scatter places"), "{text}");
        assert!(m.log.last().unwrap().ends_with("scatter places)"), "{:?}", m.log);
        // the log shows it whole, wrapped under its text
        crate::tui::update(&mut m, crate::tui::Message::ShowLog);
        let (text, _) = screen(&m, 80, 24);
        assert!(text.contains("messages (newest last)") && text.contains("scatter places)"), "{text}");
        assert!(text.contains("│      "), "continuation rows are indented: {text}");
    }

    /// Every screen the designer can reach, with enough in it to fill its key bar.
    fn every_screen() -> Vec<(&'static str, Model)> {
        use crate::tui::model::{CompareView, Editor, FillView, Side};
        let volume = Arc::new(Volume::from_fn([8; 3], Channel::rgb(), |x, _, _, o| o.fill(x as f32 / 8.0)).unwrap());
        let long_name = "a_very_long_exemplar_name_that_will_not_fit_in_a_narrow_title_bar_at_all";
        let mut library = model();
        library.manifest = PathBuf::from(format!("/home/designer/projects/solids/{long_name}/exemplars/library.toml"));
        library.errors = vec!["lib.toml: line 9: entry 3 (a): size is missing".into()];
        let view = ExemplarView { volume: Some(volume.clone()), index: [4; 3], ..ExemplarView::new(long_name) };
        let mut stamp = Model { screen: Screen::Exemplar(view.clone()), ..model() };
        let seed = Arc::new(crate::sections::seed_mesh(32, 32).unwrap());
        crate::tui::update(&mut stamp, crate::tui::Message::SeedLoaded(Ok((seed, None))));
        let text = "[[exemplar]]\nname = \"m\"\nrecipe = \"procedural:marble\"\nsize = 16\n".to_string();
        let editor = Editor { name: "m".into(), text: Some(text.clone()), saved: text, ..Editor::default() };
        let picker = Editor { picker: Some(1), ..editor.clone() };
        let fill = FillView {
            name: long_name.into(),
            filled: Some(Arc::new(crate::tui::fill_edit::tests::filled_cube(None))),
            axis: Axis::Z,
            offset: 0.0,
            from: None,
            edit: None,
        };
        let side = |label: &str| Side { label: label.into(), volume: Some(Ok(volume.clone())), quality: None };
        let compare = CompareView {
            sides: [side("kiwi before"), side("kiwi after")],
            axis: Axis::Z,
            position: 0.5,
            before_after: Some("kiwi".into()),
        };
        let on = |screen: Screen| Model { screen, ..model() };
        let mut help = model();
        help.help = Some(Help::default());
        let mut empty = model();
        empty.items.clear();
        let mut first = empty.clone();
        first.first_run = true;
        vec![
            ("library", library),
            ("exemplar", on(Screen::Exemplar(view))),
            ("stamp", stamp),
            ("editor", on(Screen::Editor(editor))),
            ("picker", on(Screen::Editor(picker))),
            ("fill", on(Screen::Fill(fill))),
            ("new", on(Screen::New(crate::tui::new_entry::NewEntry { kind: 0, picker: None, pick_for: None }))),
            ("compare", on(Screen::Compare(compare))),
            ("help", help),
            ("empty", empty),
            ("first run", first),
        ]
    }

    /// At 80, 100 and 200 columns every screen keeps its key bar to one row holding the
    /// screen's first keys, the status to one row (a long one cut with `…`) with the keys
    /// every screen has, and box titles within their boxes.
    #[test]
    fn every_screen_fits_80_100_and_200_columns() {
        let status = "building marble: level 3/3, iteration 2 of 2, searching the exemplar for the best matching neighbourhoods of every voxel";
        for (name, mut m) in every_screen().into_iter().filter(|(name, _)| *name != "help") {
            m.status = status.into();
            for w in [80u16, 100, 200] {
                let (text, _) = screen(&m, w, 24);
                let rows: Vec<&str> = text.lines().collect();
                let (bar, last) = (rows[22], rows[23]);
                let first = crate::tui::keybar::hints(&m)[0].keys;
                assert!(bar.trim_start().starts_with(first), "{name} at {w}: key bar {bar:?}");
                assert!(!bar.contains('│') && !bar.contains('─'), "{name} at {w}: the bar overlaps a box: {bar:?}");
                assert!(
                    rows[21].contains('─') || rows[21].trim().is_empty() || name == "help",
                    "{name} at {w}: {text}"
                );
                assert!(last.ends_with(OVERLAY_KEYS), "{name} at {w}: status row {last:?}");
                let cut = status.chars().count() + OVERLAY_KEYS.len() > usize::from(w);
                assert_eq!(last.contains('…'), cut, "{name} at {w}: status row {last:?}");
                for row in &rows {
                    let corners = row.chars().filter(|c| matches!(c, '┌' | '┐')).count();
                    assert!(corners % 2 == 0, "{name} at {w}: a title ran over its box's corner: {row:?}");
                }
            }
        }
    }

    /// At 80x24 the help scrolls to its last section; the bottom line says where it is.
    #[test]
    fn the_help_scrolls_to_its_last_section_at_80x24() {
        let mut m = model();
        crate::tui::update(&mut m, crate::tui::Message::Resized(80, 24));
        crate::tui::update(&mut m, crate::tui::Message::Help);
        let (text, _) = screen(&m, 80, 24);
        assert!(!text.contains("quit (asks if work is unsaved)") && text.contains("lines 1-"), "{text}");
        crate::tui::update(&mut m, crate::tui::Message::Scroll(crate::tui::keymap::END));
        let (text, _) = screen(&m, 80, 24);
        assert!(text.contains("everywhere") && text.contains("quit (asks if work is unsaved)"), "{text}");
        // one row up from the end shows one row less of it
        crate::tui::update(&mut m, crate::tui::Message::Scroll(-1));
        let (up, _) = screen(&m, 80, 24);
        assert!(!up.contains("quit (asks if work is unsaved)") && up.contains("everywhere"), "{up}");
    }

    #[test]
    fn the_editor_shows_fields_the_value_being_typed_and_errors() {
        let text = "[[exemplar]]\nname = \"m\"\nrecipe = \"procedural:marble\"\nsize = 16\n";
        let mut m = model();
        m.screen = Screen::Editor(crate::tui::model::Editor {
            name: "m".into(),
            text: Some(text.replace("16", "20")),
            saved: text.into(),
            selected: 2,
            input: Some("0".into()),
            error: Some("size 0 is not allowed".into()),
            ..Default::default()
        });
        let (text, _) = screen(&m, 80, 24);
        assert!(text.contains("recipe: m [modified]"), "{text}");
        assert!(text.contains("recipe = \"procedural:marble\"") && text.contains("size = 0_"), "{text}");
        assert!(text.contains("size 0 is not allowed") && text.contains("enter keep the value"), "{text}");
        // A failed preview says so beside the last good picture.
        let Screen::Editor(e) = &mut m.screen else { panic!("the editor") };
        e.preview = Some(Arc::new(Volume::new([8; 3], Channel::rgb()).unwrap()));
        e.preview_error = Some("stamp: outside the volume".into());
        let (text, _) = screen(&m, 100, 30);
        assert!(text.contains("preview FAILED") && text.contains("stale"), "{text}");
        assert!(text.contains("stamp: outside the volume"), "{text}");
    }

    #[test]
    fn the_fill_preview_draws_a_cut_of_the_model() {
        let filled = crate::tui::fill_edit::tests::filled_cube(None);
        let mut m = model();
        m.screen = Screen::Fill(crate::tui::model::FillView {
            name: "marble".into(),
            filled: Some(Arc::new(filled)),
            axis: Axis::Z,
            offset: 0.0,
            from: None,
            edit: None,
        });
        let (text, buffer) = screen(&m, 80, 24);
        assert!(text.contains("fill: marble, cut z +0.00"), "{text}");
        let cells: Vec<(u16, u16)> = (0..80u16).flat_map(|x| (0..24u16).map(move |y| (x, y))).collect();
        let painted = cells.iter().filter(|p| matches!(buffer[**p].fg, Color::Rgb(..))).count();
        assert!(painted > 300, "{painted} cells of the cut");
        // Half-blocks at the rim draw their inside half; the default colour never fills a half.
        let rim = cells.iter().filter(|p| matches!(buffer[**p].symbol(), "▀" | "▄") && buffer[**p].fg == Color::Reset);
        assert_eq!(rim.count(), 0, "a half-block whose coloured half is the terminal's default");
    }

    /// A synthesized entry's figures show as a word in the list and in full under it; its
    /// photo is drawn beside the slice at the same pixel scale.
    #[test]
    fn quality_figures_show_at_a_glance_and_the_photo_beside_the_slice() {
        let mut m = model();
        let glance =
            crate::quality::Glance { axes: vec![(0, 0.5, 1.0), (1, 0.9, 1.0), (2, 0.95, 1.1)], histogram: 0.01 };
        m.items[1].quality = Some(glance.clone());
        m.selected = 1;
        let (text, buffer) = screen(&m, 100, 24);
        assert!(text.contains("quality") && text.contains("blurred"), "{text}");
        assert!(text.contains("marble: sharp 0.50-0.95  size 1.00-1.10  hist 0.01"), "{text}");
        let red = buffer.content().iter().filter(|c| c.fg == Color::Red).count();
        assert!(red > 20, "figures out of range are red: {red}");
        // the photo (16 px) is drawn twice as wide as the slice (8 px): one pixel scale
        let volume =
            Volume::from_fn([8, 8, 8], Channel::rgb(), |_, _, _, o| o.copy_from_slice(&[1.0, 0.0, 0.0])).unwrap();
        let photo = Image2d::from_data(16, 16, Channel::rgb(), [0.0, 0.0, 1.0].repeat(256)).unwrap();
        let mut m = viewing(volume);
        m.items[0].name = "kiwi".into();
        m.items[0].quality = Some(glance);
        let Screen::Exemplar(v) = &mut m.screen else { panic!("the slices") };
        (v.beside_photo, v.axis) = (true, Axis::X);
        v.photos = Some(Ok(Arc::new([Some(photo), None, None])));
        let (text, buffer) = screen(&m, 100, 30);
        assert!(text.contains("kiwi across x: sharp 0.50  size 1.00  hist 0.01"), "{text}");
        assert!(text.contains("photo 16x16") && text.contains("slice x=4/7"), "{text}");
        let count = |colour: Color| buffer.content().iter().filter(|c| c.fg == colour && c.symbol() == "▀").count();
        let (blue, red) = (count(Color::Rgb(0, 0, 255)), count(Color::Rgb(255, 0, 0)));
        let ratio = blue as f32 / red as f32;
        assert!(red > 10 && (3.6..4.4).contains(&ratio), "photo {blue} cells, slice {red} cells");
        let Screen::Exemplar(v) = &mut m.screen else { panic!("the slices") };
        v.axis = Axis::Y;
        let (text, _) = screen(&m, 100, 30);
        assert!(text.contains("no photo for the slices across y"), "{text}");
    }

    #[test]
    fn the_new_entry_screen_lists_kinds_then_files_with_the_photo() {
        use crate::tui::new_entry::{FileRow, NewEntry, Picker};
        let mut m = model();
        m.screen = Screen::New(NewEntry { kind: 2, picker: None, pick_for: None });
        let (text, buffer) = screen(&m, 100, 24);
        assert!(text.contains("new exemplar: what makes it?") && text.contains("procedural:chocolate"), "{text}");
        let chosen = (0..100u16).map(|x| buffer[(x, 3)].symbol().to_string()).collect::<String>();
        assert!(chosen.contains("sweep") && buffer[(2, 3)].modifier.contains(Modifier::REVERSED), "{chosen}");
        let photo = Image2d::from_data(4, 4, Channel::rgb(), [0.0, 1.0, 0.0].repeat(16)).unwrap();
        let rows =
            ["..", "photos", "a.png"].iter().map(|n| FileRow { name: n.to_string(), folder: !n.ends_with(".png") });
        m.screen = Screen::New(NewEntry {
            kind: 0,
            pick_for: None,
            picker: Some(Picker {
                file: crate::tui::new_entry::FileKind::Image,
                folder: PathBuf::from("/w/lib"),
                rows: Some(Ok(rows.collect())),
                selected: 2,
                peek: Some((PathBuf::from("/w/lib/a.png"), Ok(Arc::new(photo)))),
                came_from: None,
            }),
        });
        let (text, buffer) = screen(&m, 100, 24);
        assert!(
            text.contains("new synth exemplar: /w/lib")
                && text.contains("photos/")
                && text.contains("a.png (shown 4x4)"),
            "{text}"
        );
        let green = buffer.content().iter().filter(|c| c.fg == Color::Rgb(0, 255, 0)).count();
        assert!(green > 50, "{green} cells of the photo");
    }

    /// Two volumes side by side at one pixel scale, each with its figures; a before/after
    /// comparison says what a and d do.
    #[test]
    fn a_comparison_draws_both_slices_at_one_scale() {
        use crate::tui::model::{CompareView, Side};
        let solid = |dims, rgb: [f32; 3]| {
            Some(Ok(Arc::new(Volume::from_fn(dims, Channel::rgb(), |_, _, _, o| o.copy_from_slice(&rgb)).unwrap())))
        };
        let glance = crate::quality::Glance { axes: vec![(2, 1.0, 1.0)], histogram: 0.0 };
        let mut m = model();
        m.screen = Screen::Compare(CompareView {
            sides: [
                Side { label: "kiwi before".into(), volume: solid([8, 8, 8], [1.0, 0.0, 0.0]), quality: Some(glance) },
                Side { label: "kiwi after".into(), volume: solid([16, 16, 16], [0.0, 0.0, 1.0]), quality: None },
            ],
            axis: Axis::Z,
            position: 0.5,
            before_after: Some("kiwi".into()),
        });
        let (text, buffer) = screen(&m, 100, 30);
        assert!(
            text.contains("kiwi before | kiwi after  across z") && text.contains("kiwi before z=4/7 8x8"),
            "{text}"
        );
        assert!(
            text.contains("kiwi after z=8/15 16x16") && text.contains("sharp 1.00  size 1.00  hist 0.00"),
            "{text}"
        );
        assert!(text.contains("a keeps the new build, d discards it"), "{text}");
        let count = |colour: Color| buffer.content().iter().filter(|c| c.fg == colour && c.symbol() == "▀").count();
        let (red, blue) = (count(Color::Rgb(255, 0, 0)), count(Color::Rgb(0, 0, 255)));
        let ratio = blue as f32 / red as f32;
        assert!(red > 10 && (3.5..4.5).contains(&ratio), "8x8 in {red} cells, 16x16 in {blue}");
    }

    /// A click on a library row selects it (a second click opens it); a click on a slice
    /// moves the other slices through the voxel drawn under the mouse.
    #[test]
    fn the_mouse_points_at_what_was_drawn() {
        use crate::tui::mouse::{Regions, message};
        use crossterm::event::{KeyModifiers, MouseButton, MouseEvent, MouseEventKind};
        let draw_at = |m: &Model, regions: &mut Regions| {
            let mut terminal = Terminal::new(TestBackend::new(100, 30)).unwrap();
            terminal.draw(|f| draw_with(f, m, None, regions)).unwrap();
            terminal.backend().buffer().clone()
        };
        let click = |column, row| MouseEvent {
            kind: MouseEventKind::Down(MouseButton::Left),
            column,
            row,
            modifiers: KeyModifiers::NONE,
        };
        let mut m = model();
        let mut regions = Regions::default();
        let buffer = draw_at(&m, &mut regions);
        let marble_line = (0..30u16).find(|&y| buffer[(1, y)].symbol() == "m").unwrap();
        let row = message(&m.screen, &regions, click(3, marble_line)).unwrap();
        crate::tui::update(&mut m, row);
        assert_eq!(m.selected, 1);
        // x, y, z in red, green, blue: the colour under the mouse names the voxel
        let volume = Volume::from_fn([16, 12, 10], Channel::rgb(), |x, y, z, o| {
            o.copy_from_slice(&[x as f32 / 15.0, y as f32 / 11.0, z as f32 / 9.0])
        })
        .unwrap();
        let mut m = viewing(volume);
        let mut pointed = 0;
        for (column, line) in [(5u16, 4u16), (20, 9), (38, 20), (45, 6), (80, 12)] {
            let buffer = draw_at(&m, &mut regions);
            let Some(message) = message(&m.screen, &regions, click(column, line)) else { continue };
            pointed += 1;
            let Color::Rgb(r, g, b) = buffer[(column, line)].fg else { panic!("no pixel at {column},{line}") };
            crate::tui::update(&mut m, message);
            let Screen::Exemplar(v) = &m.screen else { panic!("the slices") };
            let voxel =
                [r as f32 / 255.0 * 15.0, g as f32 / 255.0 * 11.0, b as f32 / 255.0 * 9.0].map(|c| c.round() as usize);
            let moved: Vec<usize> = (0..3).filter(|&k| v.index[k] == voxel[k]).collect();
            assert!(
                moved.len() >= 2,
                "at {column},{line} the voxel {voxel:?} is drawn; the slices are at {:?}",
                v.index
            );
        }
        assert!(pointed >= 4, "{pointed} clicks landed on slices");
    }

    /// The depth field shows as a colour map, dark blue at depth 0 to yellow at 1; the
    /// constraints placed show as marks on the cut, the cursor as a cross.
    #[test]
    fn the_fill_preview_shows_the_depth_field_and_the_constraints() {
        use crate::tui::fill_edit::tests::{filled_cube, filling};
        let mut m = filling(filled_cube(Some(Vec::new())));
        crate::tui::update(&mut m, crate::tui::Message::DepthPoint);
        crate::tui::update(&mut m, crate::tui::Message::MoveCursor(4.0, 0.0));
        crate::tui::update(&mut m, crate::tui::Message::ShowDepth);
        let (text, buffer) = screen(&m, 80, 24);
        assert!(text.contains("1 depth pt(s)") && text.contains("◆") && text.contains("+"), "{text}");
        // depth = x: the left of the cut is blue, the right yellow
        let rgb = |x: u16, y: u16| match buffer[(x, y)].fg {
            Color::Rgb(r, g, b) => Some((r, g, b)),
            _ => None,
        };
        let row: Vec<(u16, (u8, u8, u8))> = (0..80u16).filter_map(|x| rgb(x, 6).map(|c| (x, c))).collect();
        let (left, right) = (row[1].1, row[row.len() - 2].1);
        assert!(left.2 > left.0 && right.0 > right.2 && right.1 > 150, "left {left:?} right {right:?}");
    }

    #[test]
    fn stamp_mode_reads_out_where_the_seed_is() {
        use glam::{Quat, Vec3};
        let mut p = crate::stamp::Placement {
            at: Vec3::new(12.0, 30.4, 40.0),
            rotation: Quat::IDENTITY,
            scale: Vec3::splat(3.0),
        };
        assert_eq!(readout(&p), "at 12,30,40, not turned, scale 3.00");
        p.rotation = Quat::from_axis_angle(Vec3::Y, 15f32.to_radians());
        p.scale = Vec3::new(2.0, 2.0, 3.0);
        assert_eq!(readout(&p), "at 12,30,40, turned 15° about 0.00,1.00,0.00, scale 2.00,2.00,3.00");
    }
}
