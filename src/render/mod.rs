//! Pictures of volumes for people: 8-bit RGB canvases, slices, a cut-away view and
//! the labelled contact sheet. Pure: it makes pixels, `io` writes them.

mod cutaway;
mod font;
mod sheet;

pub use cutaway::cutaway;
pub use sheet::sheet;

use crate::volume::{Channel, Image2d};

/// An 8-bit RGB picture, rows top to bottom.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Rgb8 {
    /// Width in pixels.
    pub width: usize,
    /// Height in pixels.
    pub height: usize,
    /// `width * height * 3` bytes.
    pub data: Vec<u8>,
}

/// Sheet background.
pub const BACKGROUND: [u8; 3] = [34, 36, 40];
/// Label ink.
pub const INK: [u8; 3] = [228, 230, 235];

impl Rgb8 {
    /// A canvas filled with `colour`.
    pub fn new(width: usize, height: usize, colour: [u8; 3]) -> Rgb8 {
        let data = colour.iter().copied().cycle().take(width * height * 3).collect();
        Rgb8 { width, height, data }
    }

    /// Set one pixel; outside the canvas nothing happens.
    pub fn put(&mut self, x: usize, y: usize, colour: [u8; 3]) {
        if x < self.width && y < self.height {
            let i = (x + y * self.width) * 3;
            self.data[i..i + 3].copy_from_slice(&colour);
        }
    }

    /// The colour at (x, y).
    pub fn at(&self, x: usize, y: usize) -> [u8; 3] {
        let i = (x + y * self.width) * 3;
        [self.data[i], self.data[i + 1], self.data[i + 2]]
    }

    /// Copy `other` with its top-left corner at (x, y).
    pub fn blit(&mut self, other: &Rgb8, x: usize, y: usize) {
        for j in 0..other.height {
            for i in 0..other.width {
                self.put(x + i, y + j, other.at(i, j));
            }
        }
    }

    /// Write `text` with its top-left corner at (x, y), each font pixel `scale` pixels wide.
    pub fn text(&mut self, text: &str, x: usize, y: usize, scale: usize, colour: [u8; 3]) {
        for (k, c) in text.chars().enumerate() {
            let rows = font::glyph(c);
            let left = x + k * 6 * scale;
            for (r, bits) in rows.iter().enumerate() {
                for b in 0..5 {
                    if bits & (1 << (4 - b)) != 0 {
                        self.fill(left + b * scale, y + r * scale, scale, scale, colour);
                    }
                }
            }
        }
    }

    /// The same picture upside down (row 0 becomes the last row).
    pub fn flipped(&self) -> Rgb8 {
        let row = self.width * 3;
        let data = self.data.chunks_exact(row.max(1)).rev().flatten().copied().collect();
        Rgb8 { data, ..*self }
    }

    /// Fill a rectangle.
    pub fn fill(&mut self, x: usize, y: usize, w: usize, h: usize, colour: [u8; 3]) {
        for j in y..y + h {
            for i in x..x + w {
                self.put(i, j, colour);
            }
        }
    }
}

/// Width in pixels of `text` written at `scale`.
pub fn text_width(text: &str, scale: usize) -> usize {
    text.chars().count() * 6 * scale
}

/// How to show samples as a colour: the R, G, B roles if all three are there,
/// otherwise the first channel as grey.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum ColourMap {
    /// Take these three channel positions as red, green, blue.
    Rgb([usize; 3]),
    /// Show this channel position as grey.
    Grey(usize),
}

impl ColourMap {
    /// The natural display of a channel list.
    pub fn for_channels(channels: &[Channel]) -> ColourMap {
        let find = |c: Channel| channels.iter().position(|x| *x == c);
        match (find(Channel::R), find(Channel::G), find(Channel::B)) {
            (Some(r), Some(g), Some(b)) => ColourMap::Rgb([r, g, b]),
            _ => ColourMap::Grey(0),
        }
    }

    /// The 8-bit colour of one voxel's samples.
    pub fn colour(self, samples: &[f32]) -> [u8; 3] {
        match self {
            ColourMap::Rgb(idx) => idx.map(|i| to_u8(samples[i])),
            ColourMap::Grey(i) => [to_u8(samples[i]); 3],
        }
    }
}

/// A [0, 1] sample as a byte, rounding to nearest; NaN shows as 0.
pub fn to_u8(v: f32) -> u8 {
    (v.clamp(0.0, 1.0) * 255.0).round() as u8
}

/// An image shown with `map`, each pixel `scale` x `scale` (nearest neighbour: voxels stay crisp).
pub fn picture(image: &Image2d, map: ColourMap, scale: usize) -> Rgb8 {
    let mut out = Rgb8::new(image.width() * scale, image.height() * scale, BACKGROUND);
    for y in 0..image.height() {
        for x in 0..image.width() {
            out.fill(x * scale, y * scale, scale, scale, map.colour(image.pixel(x, y)));
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn colour_map_prefers_rgb_roles() {
        let list = vec![Channel::Depth, Channel::B, Channel::G, Channel::R];
        let map = ColourMap::for_channels(&list);
        assert_eq!(map, ColourMap::Rgb([3, 2, 1]));
        assert_eq!(map.colour(&[0.5, 1.0, 0.0, 0.2]), [51, 0, 255]);
        assert_eq!(ColourMap::for_channels(&[Channel::Depth]), ColourMap::Grey(0));
    }

    #[test]
    fn text_draws_ink_inside_its_box() {
        let mut c = Rgb8::new(40, 10, BACKGROUND);
        c.text("X1", 1, 1, 1, INK);
        let inked = (0..40 * 10).filter(|i| c.at(i % 40, i / 40) == INK).count();
        assert!(inked > 10);
        assert_eq!(c.at(14, 1), BACKGROUND);
        assert_eq!(text_width("X1", 2), 24);
    }
}
