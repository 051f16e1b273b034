//! Layered synthesis picks exemplar pixels by depth (the last channel): the random init
//! starts every voxel from pixels of its slice's depth, and the histogram transfer matches
//! every slice to them. Both use these helpers, so "the pixels of a depth" means one thing.

use std::ops::Range;

/// The ideal depth of z-slice `z` of `slices`: 0 at the first, 1 at the last.
pub fn slice_depth(z: usize, slices: usize) -> f32 {
    if slices > 1 { z as f32 / (slices - 1) as f32 } else { 0.5 }
}

/// The mean distance of a layered volume's Depth channel from each z-slice's ideal depth
/// ([`slice_depth`]); `None` without a Depth channel.
pub fn depth_error(volume: &crate::volume::Volume) -> Option<f64> {
    let depth = volume.channel_index(&crate::volume::Channel::Depth)?;
    let [dx, dy, dz] = volume.dims();
    let mut error = 0.0;
    for z in 0..dz {
        let ideal = slice_depth(z, dz) as f64;
        for y in 0..dy {
            for x in 0..dx {
                error += (volume.get(x, y, z, depth) as f64 - ideal).abs();
            }
        }
    }
    Some(error / volume.voxel_count().max(1) as f64)
}

/// `(depth, pixel)` pairs sorted by depth, ties by pixel index (so results are deterministic).
pub fn sorted_by_depth(mut order: Vec<(f32, u32)>) -> Vec<(f32, u32)> {
    order.sort_by(|a, b| a.0.total_cmp(&b.0).then(a.1.cmp(&b.1)));
    order
}

/// The `width` entries of a depth-sorted list whose depths are nearest to `target`
/// (`width` is at most the list's length).
pub fn band(order: &[(f32, u32)], target: f32, width: usize) -> Range<usize> {
    let at = order.partition_point(|e| e.0 < target);
    let start = at.saturating_sub(width / 2).min(order.len() - width);
    start..start + width
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_band_is_centred_on_the_target_and_stays_inside() {
        let order = sorted_by_depth((0..10).rev().map(|i| (i as f32 / 9.0, i)).collect());
        assert_eq!(order[0], (0.0, 0));
        assert_eq!(band(&order, 0.5, 4), 3..7);
        assert_eq!(band(&order, 0.0, 4), 0..4);
        assert_eq!(band(&order, 1.0, 4), 6..10);
        assert_eq!((slice_depth(0, 5), slice_depth(4, 5), slice_depth(0, 1)), (0.0, 1.0, 0.5));
    }
}
