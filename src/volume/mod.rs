//! `Volume`: a small 3D grid of f32 samples with named channel roles.
//!
//! Samples are interleaved per voxel and stored x fastest, then y, then z:
//!
//! ```text
//! index(x, y, z) = x + dims[0] * (y + dims[1] * z)       (voxel index)
//! data[index * channels + c]                              (sample of channel c)
//! ```
//! Values are meant to lie in [0, 1]; nothing clamps them. Creating a volume checks
//! its size against a voxel budget first, so an absurd size is an error, never an
//! out-of-memory abort.

mod channel;
mod image2d;
mod pyramid;
mod sample;
mod slice;
mod stats;

pub use channel::{Channel, join as channel_names, luminance};
pub use image2d::Image2d;
pub use pyramid::{downsample, upsample, upsample_on_samples};
pub use sample::Edge;
pub use slice::{Axis, Plane};
pub use stats::{ChannelStats, stats_of};

use crate::error::{Error, Result};
use crate::texture_type::TextureType;

/// The default voxel budget: 4 GiB of samples.
pub const DEFAULT_BUDGET_BYTES: u64 = 4 << 30;

/// The provenance key of the longest exemplar side a volume was synthesized with
/// (`--max-exemplar`, a manifest's `max_exemplar`): `quality` shrinks the exemplars alike.
pub const MAX_EXEMPLAR_KEY: &str = "max_exemplar";

/// What a volume is, beyond its samples: its texture type and where it came from.
#[derive(Debug, Clone, Default, PartialEq, Eq)]
pub struct Meta {
    /// The declared or estimated LST type, if known.
    pub texture_type: Option<TextureType>,
    /// Provenance as ordered key/value pairs (recipe hash, seed, tool version ...).
    pub provenance: Vec<(String, String)>,
}

impl Meta {
    /// The provenance value stored under `key`.
    pub fn get(&self, key: &str) -> Option<&str> {
        self.provenance.iter().find(|(k, _)| k == key).map(|(_, v)| v.as_str())
    }

    /// Set (or replace) one provenance entry.
    pub fn set(&mut self, key: &str, value: impl Into<String>) {
        let value = value.into();
        match self.provenance.iter_mut().find(|(k, _)| k == key) {
            Some(entry) => entry.1 = value,
            None => self.provenance.push((key.to_string(), value)),
        }
    }
}

/// Where a volume sits in a model's space, axes along the model's: the model point at the
/// centre of voxel (0, 0, 0), and one voxel's side. Voxel (i, j, k) is centred at
/// `origin + (i, j, k) * voxel`; its cell reaches half a voxel either side.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize)]
pub struct ModelGrid {
    /// The model point at the centre of voxel (0, 0, 0).
    pub origin: [f32; 3],
    /// One voxel's side in model units (above 0).
    pub voxel: f32,
}

impl ModelGrid {
    /// The model-space box the voxels' cells cover: its lowest and highest corners.
    pub fn box_of(&self, dims: [usize; 3]) -> ([f32; 3], [f32; 3]) {
        let half = self.voxel / 2.0;
        let lo = self.origin.map(|o| o - half);
        let hi = [0, 1, 2].map(|a| self.origin[a] + (dims[a] as f32 - 0.5) * self.voxel);
        (lo, hi)
    }
}

/// A 3D grid of interleaved f32 samples, x fastest.
#[derive(Debug, Clone, PartialEq)]
pub struct Volume {
    dims: [usize; 3],
    channels: Vec<Channel>,
    data: Vec<f32>,
    /// Texture type and provenance; carried through every file format that can hold them.
    pub meta: Meta,
    /// Where the volume sits in model space (a bake's grid), when that is known. Kept by
    /// the formats that can hold it; a volume made anew from this one (resampled, cropped)
    /// starts without it.
    pub model_grid: Option<ModelGrid>,
}

/// The most channels a volume may have.
pub const MAX_CHANNELS: usize = 64;

/// Check dims and channel count against the voxel budget before any allocation; returns the sample count.
pub fn check_size(dims: [usize; 3], channels: usize, budget_bytes: u64) -> Result<usize> {
    if dims.contains(&0) {
        return Err(Error::invalid(format!(
            "volume dims {}x{}x{} contain a zero; every dimension must be at least 1",
            dims[0], dims[1], dims[2]
        )));
    }
    if channels == 0 {
        return Err(Error::invalid("a volume needs at least one channel"));
    }
    let needed = dims.iter().fold(channels as u128 * 4, |n, d| n.saturating_mul(*d as u128));
    if needed > budget_bytes as u128 {
        return Err(Error::Budget { dims, channels, needed, budget: budget_bytes as u128 });
    }
    if channels > MAX_CHANNELS {
        return Err(Error::invalid(format!("a volume has at most {MAX_CHANNELS} channels; {channels} were asked for")));
    }
    Ok((needed / 4) as usize)
}

impl Volume {
    /// A zero-filled volume within the default budget.
    pub fn new(dims: [usize; 3], channels: Vec<Channel>) -> Result<Volume> {
        Self::with_budget(dims, channels, DEFAULT_BUDGET_BYTES)
    }

    /// A zero-filled volume, refused before allocation if it would exceed `budget_bytes`.
    pub fn with_budget(dims: [usize; 3], channels: Vec<Channel>, budget_bytes: u64) -> Result<Volume> {
        Channel::check_list(&channels)?;
        let len = check_size(dims, channels.len(), budget_bytes)?;
        Ok(Volume { dims, channels, data: vec![0.0; len], meta: Meta::default(), model_grid: None })
    }

    /// Wrap existing samples; `data.len()` must equal voxels x channels.
    pub fn from_data(dims: [usize; 3], channels: Vec<Channel>, data: Vec<f32>) -> Result<Volume> {
        Channel::check_list(&channels)?;
        let len = check_size(dims, channels.len(), u64::MAX)?;
        if data.len() != len {
            return Err(Error::invalid(format!(
                "{} samples given for a {}x{}x{} volume with {} channel(s), which needs {len}",
                data.len(),
                dims[0],
                dims[1],
                dims[2],
                channels.len()
            )));
        }
        Ok(Volume { dims, channels, data, meta: Meta::default(), model_grid: None })
    }

    /// Build a volume by calling `f(x, y, z, out)` for every voxel, in storage order.
    pub fn from_fn(
        dims: [usize; 3],
        channels: Vec<Channel>,
        mut f: impl FnMut(usize, usize, usize, &mut [f32]),
    ) -> Result<Volume> {
        let mut volume = Volume::new(dims, channels)?;
        let n = volume.channels.len();
        for (i, voxel) in volume.data.chunks_exact_mut(n).enumerate() {
            let [x, y, z] = unindex(dims, i);
            f(x, y, z, voxel);
        }
        Ok(volume)
    }

    /// Like [`Volume::from_fn`], filling z-slices in parallel; `f` must depend only on its
    /// arguments, so the result is the same on any number of threads.
    pub fn from_fn_par(
        dims: [usize; 3],
        channels: Vec<Channel>,
        f: impl Fn(usize, usize, usize, &mut [f32]) + Sync,
    ) -> Result<Volume> {
        Volume::from_fn_par_with(dims, channels, f, &crate::progress::NoProgress)
    }

    /// [`Volume::from_fn_par`], telling `progress` the share of z-slices filled.
    pub fn from_fn_par_with(
        dims: [usize; 3],
        channels: Vec<Channel>,
        f: impl Fn(usize, usize, usize, &mut [f32]) + Sync,
        progress: &dyn crate::progress::Progress,
    ) -> Result<Volume> {
        use rayon::prelude::*;
        use std::sync::atomic::{AtomicUsize, Ordering};
        let mut volume = Volume::new(dims, channels)?;
        let n = volume.channels.len();
        let plane = dims[0] * dims[1];
        let done = AtomicUsize::new(0);
        volume.data.par_chunks_mut(plane * n).enumerate().for_each(|(z, slice)| {
            for (i, voxel) in slice.chunks_exact_mut(n).enumerate() {
                f(i % dims[0], i / dims[0], z, voxel);
            }
            let slices = done.fetch_add(1, Ordering::Relaxed) + 1;
            progress.update("slices", slices as f32 / dims[2] as f32);
        });
        Ok(volume)
    }

    /// The same volume with `meta` attached.
    pub fn with_meta(mut self, meta: Meta) -> Volume {
        self.meta = meta;
        self
    }

    /// The same volume placed in model space by `grid`.
    pub fn with_model_grid(mut self, grid: Option<ModelGrid>) -> Volume {
        self.model_grid = grid;
        self
    }

    /// Size in voxels along x, y and z.
    pub fn dims(&self) -> [usize; 3] {
        self.dims
    }

    /// The channel roles, in storage order.
    pub fn channels(&self) -> &[Channel] {
        &self.channels
    }

    /// Samples per voxel.
    pub fn channel_count(&self) -> usize {
        self.channels.len()
    }

    /// Position of a channel role, if present.
    pub fn channel_index(&self, channel: &Channel) -> Option<usize> {
        self.channels.iter().position(|c| c == channel)
    }

    /// Number of voxels.
    pub fn voxel_count(&self) -> usize {
        self.dims.iter().product()
    }

    /// All samples, interleaved, x fastest.
    pub fn data(&self) -> &[f32] {
        &self.data
    }

    /// All samples, mutable.
    pub fn data_mut(&mut self) -> &mut [f32] {
        &mut self.data
    }

    /// Take the samples out.
    pub fn into_data(self) -> Vec<f32> {
        self.data
    }

    /// Voxel index of (x, y, z); panics when out of range.
    pub fn index(&self, x: usize, y: usize, z: usize) -> usize {
        assert!(
            x < self.dims[0] && y < self.dims[1] && z < self.dims[2],
            "voxel ({x}, {y}, {z}) outside {:?}",
            self.dims
        );
        x + self.dims[0] * (y + self.dims[1] * z)
    }

    /// The samples of one voxel.
    pub fn voxel(&self, x: usize, y: usize, z: usize) -> &[f32] {
        let n = self.channels.len();
        let i = self.index(x, y, z) * n;
        &self.data[i..i + n]
    }

    /// The samples of one voxel, mutable.
    pub fn voxel_mut(&mut self, x: usize, y: usize, z: usize) -> &mut [f32] {
        let n = self.channels.len();
        let i = self.index(x, y, z) * n;
        &mut self.data[i..i + n]
    }

    /// One sample.
    pub fn get(&self, x: usize, y: usize, z: usize, channel: usize) -> f32 {
        self.voxel(x, y, z)[channel]
    }

    /// Set one sample.
    pub fn set(&mut self, x: usize, y: usize, z: usize, channel: usize, value: f32) {
        self.voxel_mut(x, y, z)[channel] = value;
    }

    /// The axis the Depth channel grows along (0 = x, 1 = y, 2 = z), if there is one: the
    /// axis whose far end differs most from the first voxel.
    pub fn depth_axis(&self) -> Option<usize> {
        let c = self.channel_index(&Channel::Depth)?;
        let d = self.dims();
        let step = |axis: usize| {
            let mut far = [0, 0, 0];
            far[axis] = d[axis] - 1;
            (self.get(far[0], far[1], far[2], c) - self.get(0, 0, 0, c)).abs()
        };
        (0..3).max_by(|x, y| step(*x).total_cmp(&step(*y)))
    }

    /// The first sample that is NaN or infinite, as (x, y, z, channel).
    pub fn first_non_finite(&self) -> Option<[usize; 4]> {
        let n = self.channels.len();
        let i = self.data.iter().position(|v| !v.is_finite())?;
        let [x, y, z] = unindex(self.dims, i / n);
        Some([x, y, z, i % n])
    }
}

/// (x, y, z) of a voxel index in a grid of `dims`.
pub fn unindex(dims: [usize; 3], index: usize) -> [usize; 3] {
    let plane = dims[0] * dims[1];
    [index % dims[0], (index % plane) / dims[0], index / plane]
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn storage_is_x_fastest_and_interleaved() {
        let v = Volume::from_fn([3, 2, 2], Channel::rgb(), |x, y, z, out| {
            out.copy_from_slice(&[x as f32, y as f32, z as f32]);
        })
        .unwrap();
        assert_eq!(&v.data()[3..6], &[1.0, 0.0, 0.0]);
        assert_eq!(&v.data()[9..12], &[0.0, 1.0, 0.0]);
        assert_eq!(v.voxel(2, 1, 1), &[2.0, 1.0, 1.0]);
        assert_eq!(unindex([3, 2, 2], v.index(2, 1, 1)), [2, 1, 1]);
    }

    #[test]
    fn budget_and_zero_dims_are_refused_before_allocation() {
        let err = Volume::with_budget([1 << 20, 1 << 20, 1 << 20], Channel::rgb(), 1 << 30).unwrap_err();
        assert!(matches!(err, Error::Budget { .. }), "{err}");
        assert!(err.to_string().contains("1048576x1048576x1048576"));
        let err = Volume::new([4, 0, 4], Channel::rgb()).unwrap_err().to_string();
        assert!(err.contains("4x0x4") && err.contains("at least 1"), "{err}");
    }

    #[test]
    fn from_data_checks_length() {
        let err = Volume::from_data([2, 2, 2], Channel::grey(), vec![0.0; 7]).unwrap_err();
        assert!(err.to_string().contains("7 samples"), "{err}");
    }

    #[test]
    fn finds_non_finite_samples() {
        let mut v = Volume::new([2, 2, 2], Channel::rgb()).unwrap();
        assert_eq!(v.first_non_finite(), None);
        v.set(1, 0, 1, 2, f32::NAN);
        assert_eq!(v.first_non_finite(), Some([1, 0, 1, 2]));
    }
}
