//! A solid axis whose features are much thinner than the other two axes' is synthesized at
//! twice the sampling along it, then every other slice across it is kept.
//!
//! ```text
//!  lengths   per solid axis, the 1/e autocorrelation length of the two exemplars that hold
//!            it, read along it (x: Ey's and Ez's columns; y: Ex's columns, Ez's rows;
//!            z: Ex's and Ey's rows), averaged
//!  thin      an axis at most THIN times each other axis' length, with separate exemplars
//!  finer     those two exemplars with each pixel repeated along it, the solid twice as
//!            long along it, then its even slices across it
//! ```
//!
//! The core's levels halve every axis alike, so a feature three voxels thick along one axis
//! and fifteen along another is one coarse voxel thick where its length is laid out, and
//! comes out one or two voxels too thick (the channels truth's lenses: 1.5-2.4 times the
//! truth's correlation length along z, 1.1-1.4 along x and y; docs/synthesis.md, "Label
//! volumes against a larger truth"). Sampled twice as finely along the thin axis, each
//! coarse level holds it twice as thick in voxels; the even slices take nothing from
//! their neighbours (no blending: labels stay labels). One image for all three planes
//! describes no solid whose axes differ (its rows' and columns' lengths land on different
//! axes), so it is never made finer.

use crate::error::Result;
use crate::volume::Image2d;

/// An axis is thin when its feature length is at most this share of each other axis'
/// (the channels truth's slices: z 3.9 pixels against y 9.1 and x 14.7, 0.42; the foam
/// truth's 0.9-1.1).
pub const THIN: f64 = 0.5;

/// The provenance key naming the axis a solid was synthesized twice as finely along.
pub const FINER_KEY: &str = "finer_axis";

/// Longest side the finer axis may reach while synthesized (the longest side `synth`
/// makes), so the finer solid takes at most twice the memory of one it could make.
pub const MOST_SIDE: usize = 512;

/// The solid axis (0, 1, 2) to synthesize at twice the sampling for exemplars `images`
/// (orthogonal to x, y, z), or `None`: the exemplars are one image, or no axis is thin.
pub fn thin_axis(images: [&Image2d; 3]) -> Option<usize> {
    if std::ptr::eq(images[0], images[1]) && std::ptr::eq(images[1], images[2]) {
        return None;
    }
    let along = images.map(crate::sharpness::axis_lengths);
    let lengths: [f64; 3] = std::array::from_fn(|k| {
        let holding = (0..3).filter(|&a| a != k);
        holding.map(|a| along[a][image_axis(a, k)]).sum::<f64>() / 2.0
    });
    (0..3).find(|&k| (0..3).filter(|&o| o != k).all(|o| lengths[k] <= THIN * lengths[o]))
}

/// Which image axis of plane `a` (0: columns, 1: rows) runs along solid axis `k` (`k != a`):
/// a plane's columns run along the lower of its two solid axes, its rows along the higher.
fn image_axis(a: usize, k: usize) -> usize {
    let other = 3 - a - k;
    usize::from(k > other)
}

/// `images` with the two planes holding solid axis `k` repeating each pixel along it; the
/// plane across `k` as it is.
pub fn stretched(images: [&Image2d; 3], k: usize) -> Result<[Image2d; 3]> {
    let mut out = Vec::with_capacity(3);
    for (a, image) in images.iter().enumerate() {
        out.push(if a == k { (*image).clone() } else { doubled(image, image_axis(a, k))? });
    }
    Ok(out.try_into().unwrap_or_else(|_| unreachable!("three planes")))
}

/// `image` with each column (`axis` 0) or row (1) repeated.
fn doubled(image: &Image2d, axis: usize) -> Result<Image2d> {
    let (w, h, c) = (image.width(), image.height(), image.channel_count());
    let data = image.data();
    let mut out = Vec::with_capacity(data.len() * 2);
    if axis == 0 {
        for pixel in data.chunks_exact(c) {
            out.extend_from_slice(pixel);
            out.extend_from_slice(pixel);
        }
        return Image2d::from_data(w * 2, h, image.channels().to_vec(), out);
    }
    for row in data.chunks_exact(w * c) {
        out.extend_from_slice(row);
        out.extend_from_slice(row);
    }
    Image2d::from_data(w, h * 2, image.channels().to_vec(), out)
}

/// The even slices across axis `k` of `samples` (`dims` voxels of `channels`, x fastest).
pub fn even_slices(samples: &[f32], dims: [usize; 3], channels: usize, k: usize) -> Vec<f32> {
    let mut out = Vec::with_capacity(samples.len() / 2);
    for (v, voxel) in samples.chunks_exact(channels).enumerate() {
        let at = [v % dims[0], (v / dims[0]) % dims[1], v / (dims[0] * dims[1])];
        if at[k].is_multiple_of(2) {
            out.extend_from_slice(voxel);
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::volume::Channel;

    /// Stripes across an image axis: features of `period / 2` pixels along it.
    fn stripes(along_rows: bool, period: usize) -> Image2d {
        let data = (0..64 * 64)
            .map(|i| {
                let (x, y) = (i % 64, i / 64);
                let at = if along_rows { y } else { x };
                f32::from(u8::from(at % period < period / 2))
            })
            .collect();
        Image2d::from_data(64, 64, Channel::grey(), data).unwrap()
    }

    /// Blobs of the same size either way.
    fn blobs() -> Image2d {
        let data = (0..64 * 64).map(|i| f32::from(u8::from((i % 64) % 16 < 8 && (i / 64) % 16 < 8))).collect();
        Image2d::from_data(64, 64, Channel::grey(), data).unwrap()
    }

    /// Slabs thin along z: Ex and Ey show thin rows (z), Ez wide blobs; z is thin. The same
    /// blobs on every plane have no thin axis, nor does one image given for all three.
    #[test]
    fn the_axis_both_its_planes_read_thin_is_thin() {
        let (thin_rows, wide) = (stripes(true, 4), blobs());
        assert_eq!(thin_axis([&thin_rows, &thin_rows, &wide]), Some(2));
        let (a, b, c) = (blobs(), blobs(), blobs());
        assert_eq!(thin_axis([&a, &b, &c]), None);
        assert_eq!(thin_axis([&thin_rows, &thin_rows, &thin_rows]), None, "one image for all planes");
        // thin along x: Ey's and Ez's columns
        let thin_columns = stripes(false, 4);
        assert_eq!(thin_axis([&wide, &thin_columns, &thin_columns.clone()]), Some(0));
    }

    /// Stretching repeats pixels along the axis in the two planes holding it; the even
    /// slices of a doubled solid are the solid.
    #[test]
    fn stretching_and_even_slices_undo_each_other() {
        let (x, y, z) = (stripes(true, 4), stripes(false, 6), blobs());
        let [sx, sy, sz] = stretched([&x, &y, &z], 2).unwrap();
        assert_eq!((sx.width(), sx.height(), sy.width(), sy.height()), (64, 128, 64, 128));
        assert_eq!(sz, z);
        assert_eq!(sx.data()[..64], sx.data()[64..128], "row 0 repeated");
        assert_eq!(sx.data()[128..192], x.data()[64..128], "row 1 follows");
        let [_, _, wz] = stretched([&x, &y, &z], 0).unwrap();
        assert_eq!((wz.width(), wz.height()), (128, 64));
        assert_eq!(wz.data()[0], wz.data()[1]);
        let dims = [3, 2, 4];
        let solid: Vec<f32> = (0..24 * 2).map(|i| (i / 2) as f32).collect();
        let doubled: Vec<f32> = (0..2 * 24)
            .flat_map(|v| {
                let (x, y, z) = (v % 3, (v / 3) % 2, v / 6);
                let at = x + 3 * (y + 2 * (z / 2));
                [solid[2 * at], solid[2 * at + 1]]
            })
            .collect();
        assert_eq!(even_slices(&doubled, [dims[0], dims[1], dims[2] * 2], 2, 2), solid);
    }
}
