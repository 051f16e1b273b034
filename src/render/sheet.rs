//! The contact sheet: a volume at a glance.
//!
//! ```text
//! +-------------------------------------------+
//! | title                                     |
//! | 64x64x64  R,G,B  type 1-b                 |
//! | XY at z=32          XZ at y=32            |
//! | [slice]             [slice]               |
//! | YZ at x=32          cut-away corner       |
//! | [slice]             [3D view]             |
//! +-------------------------------------------+
//! ```

use super::{BACKGROUND, ColourMap, INK, Rgb8, cutaway, picture};
use crate::volume::{Axis, Volume};

/// Side of one panel in pixels.
pub const PANEL: usize = 256;
const MARGIN: usize = 16;
const LABEL: usize = 24;
const HEADER: usize = 52;

/// The labelled sheet of `volume`: the three central slices and the cut-away view.
pub fn sheet(volume: &Volume, title: &str) -> Rgb8 {
    let width = 2 * PANEL + 3 * MARGIN;
    let height = HEADER + 2 * (LABEL + PANEL) + 2 * MARGIN;
    let mut out = Rgb8::new(width, height, BACKGROUND);
    out.text(title, MARGIN, 10, 2, INK);
    out.text(&summary(volume), MARGIN, 34, 1, [160, 166, 176]);
    let d = volume.dims();
    let panels = [
        (Axis::Z, format!("XY AT Z={}", d[2] / 2)),
        (Axis::Y, format!("XZ AT Y={}", d[1] / 2)),
        (Axis::X, format!("YZ AT X={}", d[0] / 2)),
    ];
    let map = ColourMap::for_channels(volume.channels());
    for (k, (axis, label)) in panels.iter().enumerate() {
        let mid = d[axis.index()] / 2;
        let slice = volume.slice(*axis, mid).expect("the central index is inside the volume");
        let scale = (PANEL / slice.width().max(slice.height())).max(1);
        // Slices containing z are drawn with +z up, as in the cut-away view.
        let pic = match axis {
            Axis::Z => picture(&slice, map, scale),
            _ => picture(&slice, map, scale).flipped(),
        };
        place(&mut out, k, label, &pic);
    }
    place(&mut out, 3, "CUT-AWAY CORNER", &cutaway(volume, PANEL));
    out
}

/// Draw panel `k` (row-major in a 2x2 grid) with its label, centred in its cell.
fn place(out: &mut Rgb8, k: usize, label: &str, pic: &Rgb8) {
    let x = MARGIN + (k % 2) * (PANEL + MARGIN);
    let y = HEADER + (k / 2) * (PANEL + LABEL + MARGIN);
    out.text(label, x, y + 4, 2, INK);
    let (w, h) = (pic.width.min(PANEL), pic.height.min(PANEL));
    let cropped = crop(pic, w, h);
    out.blit(&cropped, x + (PANEL - w) / 2, y + LABEL + (PANEL - h) / 2);
}

fn crop(pic: &Rgb8, w: usize, h: usize) -> Rgb8 {
    let mut out = Rgb8::new(w, h, BACKGROUND);
    out.blit(pic, 0, 0);
    out
}

/// `64X64X64  R,G,B  TYPE 1-B` (the font is upper case).
fn summary(volume: &Volume) -> String {
    let d = volume.dims();
    let channels: Vec<&str> = volume.channels().iter().map(|c| c.name()).collect();
    let kind = match volume.meta.texture_type {
        Some(t) => format!("TYPE {t}"),
        None => "TYPE NOT SET".to_string(),
    };
    format!("{}X{}X{}  {}  {}", d[0], d[1], d[2], channels.join(","), kind)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::volume::Channel;

    #[test]
    fn sheet_shows_the_central_slices() {
        let v = Volume::from_fn([32, 32, 32], Channel::rgb(), |x, y, z, o| {
            o.copy_from_slice(&[x as f32 / 31.0, y as f32 / 31.0, z as f32 / 31.0])
        })
        .unwrap();
        let s = sheet(&v, "RAMP");
        assert_eq!(s.width, 2 * PANEL + 3 * MARGIN);
        // The XY panel (z = 16) is 8x upscaled: its top-left voxel (0, 0, 16).
        let px = s.at(MARGIN + 2, HEADER + LABEL + 2);
        assert_eq!(px, [0, 0, (16.0f32 / 31.0 * 255.0).round() as u8]);
        // The XZ panel is drawn +z up: its top-right pixel is voxel (31, 16, 31).
        let px = s.at(2 * MARGIN + 2 * PANEL - 2, HEADER + LABEL + 2);
        assert_eq!(px, [255, (16.0f32 / 31.0 * 255.0).round() as u8, 255]);
    }
}
