//! Control volumes that a quality figure must fail: what a synthesis that keeps the
//! exemplar's numbers but not its shapes would give.
//!
//! - [`spectral_noise`]: random-phase noise with the exemplars' power spectra and their
//!   exact colours: white noise whose spectrum is reshaped to the exemplars' along every
//!   axis (the synthesis' own spectrum matching, [`ROUNDS`] times), then every voxel given
//!   an exemplar pixel's colour by rank of grey (the darkest voxels take the darkest
//!   pixels). Its cuts have the exemplars' sharpness and feature size and colours, and no
//!   shapes.
//! - [`blurred`]: a separable Gaussian blur; [`shuffled`]: the voxels in random order;
//!   [`flat`]: one colour everywhere.

use crate::error::{Error, Result};
use crate::noise::{mix64, unit};
use crate::sharpness::Standard;
use crate::synth::spectrum::{Target, match_spectrum};
use crate::volume::{Image2d, Volume};

/// Rounds of spectrum matching (each moves a frequency's power at most 16-fold).
pub const ROUNDS: usize = 4;

/// Random-phase noise of `dims` with the spectra of `exemplars` (x, y, z; `None`: that
/// axis is not matched) and their exact colours. The volume wraps on every axis.
pub fn spectral_noise(exemplars: [Option<&Image2d>; 3], dims: [usize; 3], seed: u64) -> Result<Volume> {
    let given: Vec<&Image2d> = exemplars.iter().flatten().copied().collect();
    let first = given.first().ok_or_else(|| Error::invalid("spectral noise needs at least one exemplar"))?;
    let channels = first.channel_count();
    if let Some(other) = given.iter().find(|e| e.channel_count() != channels) {
        return Err(Error::invalid(format!(
            "the exemplars have {} and {} channels: spectral noise needs them alike",
            channels,
            other.channel_count()
        )));
    }
    let pool: Vec<f32> = given.iter().flat_map(|e| e.data().iter().copied()).collect();
    let standard = Standard::of_samples(&pool, channels);
    let targets: Vec<Option<Target>> =
        exemplars.iter().map(|e| e.map(|e| Target::of(e.data(), e.width(), e.height(), channels, &standard))).collect();
    let targets = [targets[0].as_ref(), targets[1].as_ref(), targets[2].as_ref()];
    let samples = dims
        .iter()
        .try_fold(channels, |n, d| n.checked_mul(*d))
        .filter(|n| *n > 0)
        .ok_or_else(|| Error::invalid(format!("spectral noise of {dims:?} voxels is empty or too large")))?;
    let mut data: Vec<f32> = (0..samples).map(|i| unit(mix64(seed ^ mix64(i as u64)))).collect();
    for _ in 0..ROUNDS {
        match_spectrum(&mut data, dims, channels, &standard, &targets);
    }
    let all: Vec<usize> = (0..channels).collect();
    let order = ranks(&standard.grey_samples(&data, channels, &all));
    let pixel_order = ranks(&standard.grey_samples(&pool, channels, &all));
    let (voxels, pixels) = (order.len(), pixel_order.len());
    for (rank, &voxel) in order.iter().enumerate() {
        let pixel = pixel_order[rank * pixels / voxels];
        data[voxel * channels..(voxel + 1) * channels].copy_from_slice(&pool[pixel * channels..(pixel + 1) * channels]);
    }
    let mut meta = crate::volume::Meta { texture_type: Some(crate::TextureType::T0), ..Default::default() };
    meta.set("recipe", "noise");
    meta.set("seed", seed.to_string());
    Ok(Volume::from_data(dims, first.channels().to_vec(), data)?.with_meta(meta))
}

/// The indices of `values` from the smallest to the largest (ties by index).
fn ranks(values: &[f64]) -> Vec<usize> {
    let mut order: Vec<usize> = (0..values.len()).collect();
    order.sort_by(|a, b| values[*a].total_cmp(&values[*b]).then(a.cmp(b)));
    order
}

/// Largest blur, in voxels.
pub const MOST_SIGMA: f64 = 64.0;

/// `volume` with a separable Gaussian blur of `sigma` voxels (above 0, at most
/// [`MOST_SIGMA`]) on every channel, clamped at the borders.
pub fn blurred(volume: &Volume, sigma: f64) -> Result<Volume> {
    if !(sigma > 0.0 && sigma <= MOST_SIGMA) {
        return Err(Error::invalid(format!("blur sigma {sigma} is out of range; allowed above 0 up to {MOST_SIGMA}")));
    }
    let radius = (3.0 * sigma).ceil() as i64;
    let kernel: Vec<f64> = (-radius..=radius).map(|i| (-(i * i) as f64 / (2.0 * sigma * sigma)).exp()).collect();
    let total: f64 = kernel.iter().sum();
    let dims = volume.dims();
    let mut current = volume.clone();
    for axis in 0..3 {
        let source = current;
        current = Volume::from_fn(dims, volume.channels().to_vec(), |x, y, z, out| {
            for (c, o) in out.iter_mut().enumerate() {
                let mut sum = 0.0;
                for (k, w) in kernel.iter().enumerate() {
                    let mut p = [x as i64, y as i64, z as i64];
                    p[axis] = (p[axis] + k as i64 - radius).clamp(0, dims[axis] as i64 - 1);
                    sum += w * source.get(p[0] as usize, p[1] as usize, p[2] as usize, c) as f64;
                }
                *o = (sum / total) as f32;
            }
        })?;
    }
    Ok(current.with_meta(volume.meta.clone()))
}

/// `volume` with its voxels in a random order from `seed` (every voxel's colour kept).
pub fn shuffled(volume: &Volume, seed: u64) -> Result<Volume> {
    let n = volume.channel_count();
    let mut data = volume.data().to_vec();
    for i in (1..volume.voxel_count()).rev() {
        let j = (mix64(seed ^ mix64(i as u64)) % (i as u64 + 1)) as usize;
        for c in 0..n {
            data.swap(i * n + c, j * n + c);
        }
    }
    Volume::from_data(volume.dims(), volume.channels().to_vec(), data)
}

/// A volume like `volume` with every voxel `value` in every channel.
pub fn flat(volume: &Volume, value: f32) -> Result<Volume> {
    Volume::from_fn(volume.dims(), volume.channels().to_vec(), |_, _, _, o| o.fill(value))
}
