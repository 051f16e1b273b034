//! Resolution changes: 2x Gaussian downsampling and linear upsampling, one axis at a time.
//!
//! Both are separable: each axis is resampled with a short list of (source, weight)
//! taps per output position, so the same helper serves both.

use super::{Edge, Volume};
use crate::error::Result;

/// The 5-tap binomial kernel, a close Gaussian (sigma about 1).
const GAUSS5: [f32; 5] = [1.0 / 16.0, 4.0 / 16.0, 6.0 / 16.0, 4.0 / 16.0, 1.0 / 16.0];

/// Blur with a 5-tap Gaussian and keep every second voxel; each side becomes
/// `ceil(side / 2)` (a side of 1 stays 1).
pub fn downsample(volume: &Volume, edge: Edge) -> Result<Volume> {
    let mut out = volume.clone();
    for axis in 0..3 {
        let len = out.dims()[axis];
        if len == 1 {
            continue;
        }
        let taps: Vec<Vec<(i64, f32)>> =
            (0..len.div_ceil(2)).map(|i| (0..5).map(|k| (2 * i as i64 + k as i64 - 2, GAUSS5[k])).collect()).collect();
        out = resample_axis(&out, axis, &taps, edge)?;
    }
    Ok(out.with_meta(volume.meta.clone()))
}

/// Linear interpolation to `dims` (voxel centres aligned, as for image resizing).
pub fn upsample(volume: &Volume, dims: [usize; 3], edge: Edge) -> Result<Volume> {
    resize(volume, dims, edge, |i, len, target| {
        let s = (i as f32 + 0.5) * len as f32 / target as f32 - 0.5;
        let (base, t) = (s.floor(), s - s.floor());
        vec![(base as i64, 1.0 - t), (base as i64 + 1, t)]
    })
}

/// Double each side's resolution on the grid [`downsample`] keeps: fine voxel 2i lies on
/// coarse voxel i, fine voxel 2i + 1 halfway between i and i + 1 (their mean). `dims`
/// is at most twice the volume's size per axis; sides already at their size stay.
pub fn upsample_on_samples(volume: &Volume, dims: [usize; 3], edge: Edge) -> Result<Volume> {
    resize(volume, dims, edge, |i, _, _| {
        let i = i as i64;
        if i % 2 == 0 { vec![(i / 2, 1.0)] } else { vec![(i / 2, 0.5), (i / 2 + 1, 0.5)] }
    })
}

/// Resample every axis whose size differs from `dims`; `taps(i, len, target)` gives output
/// position i's (source, weight) list along an axis of `len` voxels resized to `target`.
fn resize(
    volume: &Volume,
    dims: [usize; 3],
    edge: Edge,
    taps: impl Fn(usize, usize, usize) -> Vec<(i64, f32)>,
) -> Result<Volume> {
    let mut out = volume.clone();
    for (axis, &target) in dims.iter().enumerate() {
        let len = out.dims()[axis];
        if len != target {
            let list: Vec<Vec<(i64, f32)>> = (0..target).map(|i| taps(i, len, target)).collect();
            out = resample_axis(&out, axis, &list, edge)?;
        }
    }
    Ok(out.with_meta(volume.meta.clone()))
}

/// Resample one axis: output position i along `axis` is the weighted sum of `taps[i]`.
fn resample_axis(volume: &Volume, axis: usize, taps: &[Vec<(i64, f32)>], edge: Edge) -> Result<Volume> {
    let src = volume.dims();
    let mut dims = src;
    dims[axis] = taps.len();
    let n = volume.channel_count();
    let stride = [1, src[0], src[0] * src[1]][axis];
    let mut out = Volume::new(dims, volume.channels().to_vec())?;
    let data = volume.data();
    for (voxel, dst) in out.data_mut().chunks_exact_mut(n).enumerate() {
        let mut p = super::unindex(dims, voxel);
        let i = p[axis];
        p[axis] = 0;
        let row = p[0] + src[0] * (p[1] + src[1] * p[2]);
        for &(s, w) in &taps[i] {
            let at = (row + edge.fold(s, src[axis]) * stride) * n;
            for (d, v) in dst.iter_mut().zip(&data[at..at + n]) {
                *d += w * v;
            }
        }
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::volume::Channel;

    #[test]
    fn downsample_keeps_constants_and_the_mean() {
        let v = Volume::from_fn([8, 6, 5], Channel::grey(), |x, y, z, o| {
            o[0] = ((x * 7 + y * 3 + z * 5) % 11) as f32 / 10.0;
        })
        .unwrap();
        let d = downsample(&v, Edge::Wrap).unwrap();
        assert_eq!(d.dims(), [4, 3, 3]);
        let flat = Volume::from_fn([6, 6, 6], Channel::rgb(), |_, _, _, o| o.fill(0.25)).unwrap();
        let d = downsample(&flat, Edge::Clamp).unwrap();
        assert!(d.data().iter().all(|v| (v - 0.25).abs() < 1e-6));
    }

    #[test]
    fn downsample_removes_the_finest_checkerboard() {
        let v = Volume::from_fn([8, 8, 8], Channel::grey(), |x, y, z, o| {
            o[0] = ((x + y + z) % 2) as f32;
        })
        .unwrap();
        let d = downsample(&v, Edge::Wrap).unwrap();
        assert!(d.data().iter().all(|v| (v - 0.5).abs() < 1e-6));
    }

    /// Upsampling on the kept samples inverts the sampling of `downsample`: even voxels
    /// take the coarse values, odd ones the mean of their two coarse neighbours.
    #[test]
    fn upsampling_on_samples_puts_coarse_voxels_on_even_positions() {
        let v = Volume::from_fn([3, 1, 1], Channel::grey(), |x, _, _, o| o[0] = [0.0, 1.0, 4.0][x]).unwrap();
        let wrapped = upsample_on_samples(&v, [6, 1, 1], Edge::Wrap).unwrap();
        assert_eq!(wrapped.data(), &[0.0, 0.5, 1.0, 2.5, 4.0, 2.0]);
        let clamped = upsample_on_samples(&v, [5, 1, 1], Edge::Clamp).unwrap();
        assert_eq!(clamped.data(), &[0.0, 0.5, 1.0, 2.5, 4.0]);
    }

    #[test]
    fn upsample_interpolates_and_reaches_the_dims() {
        let v = Volume::from_fn([2, 1, 1], Channel::grey(), |x, _, _, o| o[0] = x as f32).unwrap();
        let u = upsample(&v, [4, 2, 1], Edge::Clamp).unwrap();
        assert_eq!(u.dims(), [4, 2, 1]);
        assert_eq!(&u.data()[..4], &[0.0, 0.25, 0.75, 1.0]);
    }
}
