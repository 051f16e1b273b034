//! Synthesis against a known solid: take the three central slices of a stationary 3D
//! volume (the truth) as Ex, Ey and Ez, synthesize, and compare the result with the truth
//! itself rather than with the slices.
//!
//! - **Two-point correlation** along each axis: the normalized autocorrelation of the grey
//!   volume (channels standardized by the truth's mean and deviation, then averaged) at lags
//!   1 to 16 voxels along the axis, with the biased estimator (sum of products over the sum
//!   of squares). Error = mean absolute difference from the truth's over the lags.
//! - **Baseline**: the same error for what the exemplars themselves show: the correlation
//!   along the axis measured in the two central slices that contain it. A synthesis cannot
//!   be expected to know the truth better than its inputs do.
//! - **Shares**: the grey values' histogram in 8 bins over the truth's range; the largest
//!   difference of a bin's share from the truth's, in points (1 point = 1 % of the voxels).

use crate::error::{Error, Result};
use crate::sharpness::Standard;
use crate::volume::{Axis, Volume};
use serde::Serialize;

/// Largest lag of the two-point correlation.
const LAGS: usize = 16;
/// Bins of the share histogram.
const BINS: usize = 8;

/// One axis of the comparison.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct AxisTruth {
    /// `x`, `y` or `z`.
    pub axis: String,
    /// Two-point correlation error of the volume against the truth.
    pub volume_error: f64,
    /// The same error of the central slices containing the axis (the baseline).
    pub slices_error: f64,
}

/// The whole comparison.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct TruthComparison {
    /// Per axis.
    pub axes: Vec<AxisTruth>,
    /// Largest share difference of the volume from the truth, in points.
    pub share_error: f64,
    /// Largest share difference of the three central slices (pooled) from the truth, in points.
    pub slices_share_error: f64,
}

/// Compare `volume` with `truth` (same channels; sizes may differ).
pub fn compare(volume: &Volume, truth: &Volume) -> Result<TruthComparison> {
    if volume.channels() != truth.channels() {
        return Err(Error::invalid(format!(
            "the volume's channels ({}) differ from the truth's ({})",
            crate::volume::channel_names(volume.channels()),
            crate::volume::channel_names(truth.channels())
        )));
    }
    if truth.dims().iter().chain(volume.dims().iter()).any(|d| *d < 2 * LAGS) {
        return Err(Error::invalid(format!(
            "comparing with a truth needs volumes of at least {} voxels a side",
            2 * LAGS
        )));
    }
    let n = truth.channel_count();
    let scale = Standard::of_samples(truth.data(), n);
    let all: Vec<usize> = (0..n).collect();
    let (g_volume, g_truth) = (scale.grey_samples(volume.data(), n, &all), scale.grey_samples(truth.data(), n, &all));
    let axes = Axis::ALL
        .iter()
        .map(|&axis| {
            let want = correlation(&g_truth, truth.dims(), axis, None);
            let got = correlation(&g_volume, volume.dims(), axis, None);
            let in_slices: Vec<Vec<f64>> = Axis::ALL
                .iter()
                .filter(|&&other| other != axis)
                .map(|&other| correlation(&g_truth, truth.dims(), axis, Some((other, truth.dims()[other.index()] / 2))))
                .collect();
            let slices: Vec<f64> = (0..LAGS).map(|r| (in_slices[0][r] + in_slices[1][r]) / 2.0).collect();
            AxisTruth {
                axis: axis.to_string(),
                volume_error: distance(&got, &want),
                slices_error: distance(&slices, &want),
            }
        })
        .collect();
    let (lo, hi) = range(&g_truth);
    let truth_shares = shares(g_truth.iter().copied(), lo, hi);
    let slice_values = Axis::ALL.iter().flat_map(|&a| slice_values(&g_truth, truth.dims(), a));
    Ok(TruthComparison {
        axes,
        share_error: largest_gap(&shares(g_volume.iter().copied(), lo, hi), &truth_shares),
        slices_share_error: largest_gap(&shares(slice_values, lo, hi), &truth_shares),
    })
}

/// Normalized autocorrelation along `axis` at lags 1..=LAGS, over the whole volume or, with
/// `Some((other, index))`, over the slice across `other` at `index`: the sum of products of
/// the centred values at each lag over their sum of squares.
fn correlation(grey: &[f64], dims: [usize; 3], axis: Axis, within: Option<(Axis, usize)>) -> Vec<f64> {
    let inside = |i: usize| {
        let p = [i % dims[0], i / dims[0] % dims[1], i / (dims[0] * dims[1])];
        within.is_none_or(|(other, index)| p[other.index()] == index)
    };
    let (sum, count) =
        grey.iter().enumerate().filter(|(i, _)| inside(*i)).fold((0.0, 0), |(s, n), (_, v)| (s + v, n + 1));
    let mean = sum / count.max(1) as f64;
    let centred: Vec<f64> = grey.iter().map(|v| v - mean).collect();
    let products = crate::correlation::lagged_products(&centred, dims, axis, within, LAGS);
    let energy = products[0].0;
    products[1..].iter().map(|(sum, _)| if energy <= 1e-12 { 0.0 } else { sum / energy }).collect()
}

fn distance(a: &[f64], b: &[f64]) -> f64 {
    a.iter().zip(b).map(|(x, y)| (x - y).abs()).sum::<f64>() / a.len() as f64
}

fn range(values: &[f64]) -> (f64, f64) {
    values.iter().fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), v| (lo.min(*v), hi.max(*v)))
}

/// Share of values per bin over [lo, hi] (values outside go to the end bins).
fn shares(values: impl Iterator<Item = f64>, lo: f64, hi: f64) -> [f64; BINS] {
    let mut counts = [0.0; BINS];
    let span = (hi - lo).max(1e-12);
    for v in values {
        let bin = (((v - lo) / span) * BINS as f64).floor().clamp(0.0, (BINS - 1) as f64) as usize;
        counts[bin] += 1.0;
    }
    let total: f64 = counts.iter().sum();
    counts.map(|c| c / total.max(1.0))
}

fn largest_gap(a: &[f64; BINS], b: &[f64; BINS]) -> f64 {
    a.iter().zip(b).map(|(x, y)| (x - y).abs() * 100.0).fold(0.0, f64::max)
}

/// The grey values of the central slice across `axis`.
fn slice_values(grey: &[f64], dims: [usize; 3], axis: Axis) -> Vec<f64> {
    let index = dims[axis.index()] / 2;
    (0..dims[2])
        .flat_map(|z| (0..dims[1]).flat_map(move |y| (0..dims[0]).map(move |x| [x, y, z])))
        .filter(|p| p[axis.index()] == index)
        .map(|p| grey[(p[2] * dims[1] + p[1]) * dims[0] + p[0]])
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    fn marble() -> Volume {
        crate::procedural::generate(crate::procedural::Recipe::Marble, [32, 32, 32], 3).unwrap()
    }

    /// The truth against itself has no error; a copy smoothed along x has a larger error
    /// along x than the truth's own slices.
    #[test]
    fn the_truth_matches_itself_and_a_smoothed_copy_does_not() {
        let truth = marble();
        let same = compare(&truth, &truth).unwrap();
        assert!(same.axes.iter().all(|a| a.volume_error == 0.0) && same.share_error == 0.0, "{same:?}");
        let dims = truth.dims();
        let smeared = Volume::from_fn(dims, truth.channels().to_vec(), |x, y, z, out| {
            for (c, o) in out.iter_mut().enumerate() {
                *o = (0..6).map(|d| truth.get((x + d) % dims[0], y, z, c)).sum::<f32>() / 6.0;
            }
        })
        .unwrap();
        let along_x = &compare(&smeared, &truth).unwrap().axes[0];
        assert!(along_x.volume_error > 2.0 * along_x.slices_error, "{along_x:?}");
    }
}
