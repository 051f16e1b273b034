//! Sixel, kitty or iTerm2 pictures where the terminal supports them (ratatui-image), with
//! half-blocks everywhere else. The terminal is asked once at start; pictures are encoded
//! once per slice shown and kept until the slice changes.

use crate::render::ColourMap;
use crate::volume::Image2d;
use ratatui::Frame;
use ratatui::layout::Rect;
use ratatui_image::StatefulImage;
use ratatui_image::picker::{Picker, ProtocolType};
use ratatui_image::protocol::StatefulProtocol;
use std::collections::HashMap;

/// The terminal's picture protocol and the encoded slices.
pub struct Graphics {
    picker: Picker,
    cache: HashMap<String, StatefulProtocol>,
}

impl Graphics {
    /// The picture protocol to use (call after entering the alternate screen):
    /// `SOLIDTEX_GRAPHICS=sixel|kitty|iterm2` forces one, `halfblocks` none; otherwise the
    /// terminal is queried only when its environment says it is one that draws pictures
    /// (kitty, WezTerm, iTerm2, Ghostty, foot, mlterm, outside tmux), because the query's
    /// reader would swallow a key press in a terminal that never answers. `None` means
    /// half-blocks, which `view` draws itself.
    pub fn detect() -> Option<Graphics> {
        let forced = std::env::var("SOLIDTEX_GRAPHICS").unwrap_or_default();
        let protocol = match forced.as_str() {
            "halfblocks" => return None,
            "sixel" => Some(ProtocolType::Sixel),
            "kitty" => Some(ProtocolType::Kitty),
            "iterm2" => Some(ProtocolType::Iterm2),
            _ => None,
        };
        let picker = match protocol {
            Some(p) => return Some(Graphics::with(p)),
            None if graphics_terminal() => Picker::from_query_stdio().ok()?,
            None => return None,
        };
        (picker.protocol_type() != ProtocolType::Halfblocks).then(|| Graphics { picker, cache: HashMap::new() })
    }

    /// Graphics in `protocol` without asking the terminal (a guessed cell size).
    pub fn with(protocol: ProtocolType) -> Graphics {
        let mut picker = Picker::halfblocks();
        picker.set_protocol_type(protocol);
        Graphics { picker, cache: HashMap::new() }
    }

    /// The protocol's name, for the status line.
    pub fn name(&self) -> String {
        format!("{:?}", self.picker.protocol_type()).to_lowercase()
    }

    /// Draws `image` (channel view `channel`) into `area`; `key` names the slice so its
    /// encoding is reused while it does not change.
    pub fn draw(&mut self, frame: &mut Frame, area: Rect, key: String, image: &Image2d, channel: usize) {
        if !self.cache.contains_key(&key) {
            if self.cache.len() > 32 {
                self.cache.clear();
            }
            let protocol = self.picker.new_resize_protocol(to_dynamic(image, channel));
            self.cache.insert(key.clone(), protocol);
        }
        if let Some(state) = self.cache.get_mut(&key) {
            frame.render_stateful_widget(StatefulImage::<StatefulProtocol>::new(), area, state);
        }
    }
}

/// Whether the environment names a terminal known to draw pictures (and not tmux).
fn graphics_terminal() -> bool {
    let var = |k: &str| std::env::var(k).unwrap_or_default();
    if !var("TMUX").is_empty() {
        return false;
    }
    let program = var("TERM_PROGRAM");
    let term = var("TERM");
    !var("KITTY_WINDOW_ID").is_empty()
        || ["WezTerm", "iTerm.app", "ghostty"].contains(&program.as_str())
        || ["xterm-kitty", "foot", "mlterm", "xterm-ghostty"].iter().any(|t| term.starts_with(t))
}

/// An 8-bit RGB picture of a slice, one pixel per voxel.
fn to_dynamic(image: &Image2d, channel: usize) -> image::DynamicImage {
    let map = match channel {
        0 => ColourMap::for_channels(image.channels()),
        k => ColourMap::Grey(k - 1),
    };
    let rgb = image::RgbImage::from_fn(image.width() as u32, image.height() as u32, |x, y| {
        image::Rgb(map.colour(image.pixel(x as usize, y as usize)))
    });
    image::DynamicImage::ImageRgb8(rgb)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::volume::Channel;
    use ratatui::Terminal;
    use ratatui::backend::TestBackend;

    #[test]
    fn a_sixel_terminal_gets_sixel_data_and_the_encoding_is_reused() {
        let image = Image2d::from_data(4, 4, Channel::rgb(), vec![0.5; 48]).unwrap();
        let mut graphics = Graphics::with(ProtocolType::Sixel);
        let mut terminal = Terminal::new(TestBackend::new(20, 10)).unwrap();
        for _ in 0..2 {
            terminal.draw(|f| graphics.draw(f, Rect::new(0, 0, 20, 10), "a:z:1:0".into(), &image, 0)).unwrap();
        }
        assert_eq!(graphics.cache.len(), 1);
        let buffer = terminal.backend().buffer();
        let text: String =
            (0..10u16).flat_map(|y| (0..20u16).map(move |x| (x, y))).map(|p| buffer[p].symbol().to_string()).collect();
        assert!(text.contains("\u{1b}P"), "a sixel sequence starts with ESC P");
        assert_eq!(graphics.name(), "sixel");
    }
}
