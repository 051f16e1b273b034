//! Engine flipbooks: a volume's z-slices tiled into one RGBA image for game engines
//! (Unity's Texture3D import from a flipbook, Unreal's volume texture from a tiled
//! pseudo-volume texture, or a shader's own flipbook sampling), with a JSON sidecar
//! naming the layout.
//!
//! Slice `k` sits in column `k % columns`, row `k / columns` (row 0 at the top). Each tile
//! is `padding` pixels from its neighbours and the image edge on every side; the padding
//! repeats the tile's edge pixels, so bilinear filtering never bleeds one slice into the
//! next. With `pow2` the image is enlarged to powers of two (extra area transparent black).

use crate::error::{Error, Result};
use crate::volume::{Channel, Volume};
use serde::Serialize;

/// Largest padding, in pixels.
pub const MAX_PADDING: usize = 64;

/// Where every slice goes.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Layout {
    /// Slices (the volume's depth).
    pub slices: usize,
    /// Tiles across.
    pub columns: usize,
    /// Tiles down.
    pub rows: usize,
    /// Tile width (the volume's x size), in pixels.
    pub tile_width: usize,
    /// Tile height (the volume's y size), in pixels.
    pub tile_height: usize,
    /// Pixels of repeated edge around each tile.
    pub padding: usize,
    /// Image width.
    pub width: usize,
    /// Image height.
    pub height: usize,
}

impl Layout {
    /// The layout for a volume of `dims`: `columns` and `rows` as given (one of them derives
    /// from the other; neither: near square), `padding` pixels, powers of two if `pow2`.
    pub fn new(
        dims: [usize; 3],
        columns: Option<usize>,
        rows: Option<usize>,
        padding: usize,
        pow2: bool,
    ) -> Result<Layout> {
        let [tile_width, tile_height, slices] = dims;
        if padding > MAX_PADDING {
            return Err(Error::invalid(format!("--padding {padding} is out of range 0 to {MAX_PADDING}")));
        }
        for (flag, value) in [("--columns", columns), ("--rows", rows)] {
            if let Some(n) = value.filter(|n| !(1..=slices).contains(n)) {
                return Err(Error::invalid(format!(
                    "{flag} {n} is out of range; allowed: 1 to {slices} (the volume has {slices} slices, one tile each)"
                )));
            }
        }
        let [columns, rows] = match (columns, rows) {
            (Some(c), Some(r)) => [c, r],
            (Some(c), None) => [c, slices.div_ceil(c)],
            (None, Some(r)) => [slices.div_ceil(r), r],
            (None, None) => super::atlas::layout(slices),
        };
        if columns.saturating_mul(rows) < slices {
            return Err(Error::invalid(format!(
                "{columns} columns x {rows} rows hold {} tiles, fewer than the {slices} slices",
                columns * rows
            )));
        }
        let span = |tiles: usize, tile: usize| tiles.checked_mul(tile + 2 * padding);
        let (Some(mut width), Some(mut height)) = (span(columns, tile_width), span(rows, tile_height)) else {
            return Err(Error::invalid("the flipbook would be too large"));
        };
        if pow2 {
            (width, height) = (width.next_power_of_two(), height.next_power_of_two());
        }
        const MAX_SIDE: usize = 65536;
        if width > MAX_SIDE || height > MAX_SIDE {
            return Err(Error::invalid(format!(
                "the flipbook would be {width}x{height} pixels; engines take at most {MAX_SIDE} a side"
            )));
        }
        Ok(Layout { slices, columns, rows, tile_width, tile_height, padding, width, height })
    }

    /// The top-left pixel of slice `k`'s tile (inside its padding).
    pub fn origin(&self, k: usize) -> [usize; 2] {
        let (column, row) = (k % self.columns, k / self.columns);
        [
            column * (self.tile_width + 2 * self.padding) + self.padding,
            row * (self.tile_height + 2 * self.padding) + self.padding,
        ]
    }
}

/// The flipbook of `volume`: RGBA samples, `layout.width * layout.height * 4` of them (a
/// grey volume's channel three times; alpha 1 where the volume has none).
pub fn flipbook(volume: &Volume, layout: &Layout) -> Vec<f32> {
    let channels = volume.channels();
    let find = |role: Channel| channels.iter().position(|c| *c == role);
    let r = find(Channel::R).unwrap_or(0);
    let (g, b, a) = (find(Channel::G).unwrap_or(r), find(Channel::B).unwrap_or(r), find(Channel::A));
    let n = volume.channel_count();
    let mut out = vec![0.0; layout.width * layout.height * 4];
    let p = layout.padding as i64;
    let [dx, dy, _] = volume.dims();
    for k in 0..layout.slices {
        let [ox, oy] = layout.origin(k);
        for ty in -p..dy as i64 + p {
            for tx in -p..dx as i64 + p {
                // padding repeats the nearest edge pixel of the tile
                let (x, y) = (tx.clamp(0, dx as i64 - 1) as usize, ty.clamp(0, dy as i64 - 1) as usize);
                let v = &volume.data()[volume.index(x, y, k) * n..][..n];
                let at = (((oy as i64 + ty) as usize) * layout.width + (ox as i64 + tx) as usize) * 4;
                out[at..at + 4].copy_from_slice(&[v[r], v[g], v[b], a.map_or(1.0, |a| v[a])]);
            }
        }
    }
    out
}

/// The sidecar: the layout, and what to enter in Unity and Unreal; sealed, so a later run
/// replaces it only while nobody changed it.
pub fn sidecar(layout: &Layout, image: &str) -> String {
    // The engines' importers take the whole image as columns x rows slices, edge to edge.
    let engines_ready = layout.padding == 0
        && layout.width == layout.columns * layout.tile_width
        && layout.height == layout.rows * layout.tile_height
        && layout.columns * layout.rows == layout.slices;
    let json = serde_json::json!({
        "format": "solidtex flipbook 1",
        "written_by": super::guard::SEAL_MARK,
        "image": image,
        "layout": layout,
        "slice_order": "slice k (z = k) at column k % columns, row k / columns; row 0 at the top",
        "unity": {
            "texture_shape": "3D",
            "columns": layout.columns,
            "rows": layout.rows,
            "usable": engines_ready,
        },
        "unreal": {
            "tile_size_x": layout.tile_width,
            "tile_size_y": layout.tile_height,
            "num_frames": layout.slices,
            "usable": engines_ready,
        },
        "note": if engines_ready {
            "Unity and Unreal can import this image as a volume texture directly"
        } else {
            "padding or power-of-two margins: sample it with your own flipbook shader using the layout; \
             Unity's and Unreal's volume import need --padding 0, no --pow2, and columns x rows equal to the slices"
        },
    });
    super::guard::seal(&(serde_json::to_string_pretty(&json).expect("a layout always serializes") + "\n"))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn layouts_follow_the_options_and_refuse_too_few_tiles() {
        let near = Layout::new([4, 3, 5], None, None, 0, false).unwrap();
        assert_eq!((near.columns, near.rows, near.width, near.height), (3, 2, 12, 6));
        let strip = Layout::new([4, 3, 5], Some(5), None, 1, false).unwrap();
        assert_eq!((strip.columns, strip.rows, strip.width, strip.height), (5, 1, 30, 5));
        assert_eq!(strip.origin(2), [13, 1]);
        let pow2 = Layout::new([4, 3, 5], None, Some(1), 0, true).unwrap();
        assert_eq!((pow2.width, pow2.height), (32, 4));
        let err = Layout::new([4, 3, 5], Some(2), Some(2), 0, false).unwrap_err().to_string();
        assert!(err.contains("4 tiles, fewer than the 5 slices"), "{err}");
        assert!(Layout::new([4, 3, 5], Some(0), None, 0, false).is_err());
        let err = Layout::new([4, 3, 5], None, Some(6), 0, false).unwrap_err().to_string();
        assert!(err.contains("--rows 6 is out of range; allowed: 1 to 5"), "{err}");
        assert!(Layout::new([4, 3, 5], None, None, MAX_PADDING + 1, false).is_err());
    }

    /// Each slice lands in its tile; the padding repeats the tile's edge; the margin of a
    /// power-of-two image stays transparent.
    #[test]
    fn slices_land_in_their_tiles_with_repeated_edges() {
        let v =
            Volume::from_fn([2, 2, 3], Channel::grey(), |x, y, z, o| o[0] = (z * 4 + y * 2 + x) as f32 / 16.0).unwrap();
        let layout = Layout::new([2, 2, 3], Some(2), None, 1, true).unwrap();
        assert_eq!((layout.width, layout.height), (8, 8));
        let image = flipbook(&v, &layout);
        let pixel = |x: usize, y: usize| image[(y * 8 + x) * 4];
        let [ox, oy] = layout.origin(2); // slice 2: column 0, row 1
        assert_eq!([ox, oy], [1, 5]);
        assert_eq!(pixel(ox + 1, oy + 1), (2 * 4 + 3) as f32 / 16.0);
        assert_eq!(pixel(ox - 1, oy - 1), (2 * 4) as f32 / 16.0, "the corner padding repeats the tile's corner");
        assert_eq!(image[(7 * 8 + 7) * 4 + 3], 0.0, "the margin is transparent");
        assert_eq!(image[(oy * 8 + ox) * 4 + 3], 1.0, "a volume without alpha is opaque");
    }
}
