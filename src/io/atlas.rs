//! The flipbook atlas: the z-slices of a volume tiled left to right, top to bottom,
//! in a grid of `columns = ceil(sqrt(depth))` by `rows = ceil(depth / columns)`.
//!
//! ```text
//!  +------+------+------+
//!  | z=0  | z=1  | z=2  |     a 4x4x5 volume: 3 columns, 2 rows,
//!  +------+------+------+     atlas 12x8 pixels; unused tiles are 0
//!  | z=3  | z=4  |      |
//!  +------+------+------+
//! ```

use crate::error::{Error, Result};
use crate::volume::{Channel, Volume};

/// Columns and rows of the atlas for `depth` slices.
pub fn layout(depth: usize) -> [usize; 2] {
    let columns = (depth as f64).sqrt().ceil().max(1.0) as usize;
    [columns, depth.div_ceil(columns)]
}

/// The atlas of `volume`: (width, height, interleaved samples).
pub fn to_atlas(volume: &Volume) -> (usize, usize, Vec<f32>) {
    let [dx, dy, dz] = volume.dims();
    let [columns, rows] = layout(dz);
    let n = volume.channel_count();
    let (width, height) = (columns * dx, rows * dy);
    let mut out = vec![0.0; width * height * n];
    for z in 0..dz {
        let (ox, oy) = ((z % columns) * dx, (z / columns) * dy);
        for y in 0..dy {
            let row = volume.index(0, y, z) * n;
            let at = ((oy + y) * width + ox) * n;
            out[at..at + dx * n].copy_from_slice(&volume.data()[row..row + dx * n]);
        }
    }
    (width, height, out)
}

/// A volume from its atlas; the atlas size must match the layout of `dims`.
pub fn from_atlas(
    dims: [usize; 3],
    channels: Vec<Channel>,
    width: usize,
    height: usize,
    atlas: &[f32],
) -> Result<Volume> {
    let [dx, dy, dz] = dims;
    let [columns, rows] = layout(dz);
    if width != columns * dx || height != rows * dy {
        return Err(Error::invalid(format!(
            "atlas is {width}x{height} pixels but dims {dx}x{dy}x{dz} need {columns}x{rows} tiles of {dx}x{dy} = {}x{} pixels",
            columns * dx,
            rows * dy
        )));
    }
    let mut volume = Volume::new(dims, channels)?;
    let n = volume.channel_count();
    for z in 0..dz {
        let (ox, oy) = ((z % columns) * dx, (z / columns) * dy);
        for y in 0..dy {
            let row = volume.index(0, y, z) * n;
            let at = ((oy + y) * width + ox) * n;
            volume.data_mut()[row..row + dx * n].copy_from_slice(&atlas[at..at + dx * n]);
        }
    }
    Ok(volume)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn layout_is_near_square() {
        assert_eq!(layout(1), [1, 1]);
        assert_eq!(layout(5), [3, 2]);
        assert_eq!(layout(64), [8, 8]);
        assert_eq!(layout(65), [9, 8]);
    }

    #[test]
    fn atlas_round_trips_and_places_slices() {
        let v = Volume::from_fn([4, 3, 5], Channel::grey(), |x, y, z, o| o[0] = (x + 10 * y + 100 * z) as f32).unwrap();
        let (w, h, data) = to_atlas(&v);
        assert_eq!((w, h), (12, 6));
        assert_eq!(data[3 * 12 + 1], 301.0); // z=3 is tile (0, 1): pixel (1, 3) -> voxel (1, 0, 3)
        assert_eq!(data[3 * 12 + 4], 400.0); // z=4 is tile (1, 1)
        let back = from_atlas([4, 3, 5], Channel::grey(), w, h, &data).unwrap();
        assert_eq!(back, v);
        let err = from_atlas([4, 3, 7], Channel::grey(), w, h, &data).unwrap_err().to_string();
        assert!(err.contains("12x6") && err.contains("4x3x7"), "{err}");
    }
}
