//! Spectrum matching: the volume's cuts take the power spectrum of their exemplars.
//!
//! The blend of overlapping neighbourhood predictions keeps features somewhat larger
//! than the photo's (the cuts' autocorrelation falls off more slowly), and every coarser
//! level hands its layout on. The power spectrum is what sets that fall-off, so after a
//! level's last blend the volume's spectrum is reshaped to the exemplars' and the colour
//! distribution transferred again (the two steps alternate, as in Heeger and Bergen's
//! pyramid synthesis; Portilla and Simoncelli impose the autocorrelation the same way).
//!
//! The grey of the volume (every channel standardized by the exemplars' mean and
//! deviation, then averaged) is transformed in 3D. The cuts orthogonal to axis `a` have,
//! on average, the 2D power spectrum of the 3D power summed along `k_a`; per axis the
//! target is the exemplar's own 2D power spectrum. Both are binned on [`CELLS`] x
//! [`CELLS`] frequency cells (cycles per pixel, the exemplar's image x along the plane's
//! first axis) and normalized to sum 1 without the mean. A gain per 3D frequency is
//! fitted by iterative proportional fitting (each axis' cell ratio, read bilinearly so
//! the gain has no steps, contributes its `1/axes`-th power), kept within [`MOST_GAIN`],
//! and every channel's spectrum is scaled by its square root. The phases, and with them
//! where the features are, stay.
//!
//! The transform is periodic: only volumes that wrap on every axis are reshaped.

use crate::sharpness::Standard;
use crate::volume::Axis;
use rayon::prelude::*;
use rustfft::num_complex::Complex;
use rustfft::{Fft, FftPlannerScalar};
use std::sync::Arc;

/// Frequency cells per image direction.
pub const CELLS: usize = 32;
/// Fitting rounds of the gain.
const FIT_ROUNDS: usize = 6;
/// Largest factor the power of one frequency may be raised or lowered by.
const MOST_GAIN: f64 = 16.0;

/// An exemplar's power spectrum on the frequency cells, summing to 1 without the mean.
#[derive(Debug, Clone, PartialEq)]
pub struct Target {
    cells: Vec<f64>,
}

impl Target {
    /// The spectrum of an exemplar's grey (`width` x `height`, interleaved samples).
    pub fn of(colours: &[f32], width: usize, height: usize, channels: usize, standard: &Standard) -> Target {
        let grey = standard.grey_samples(colours, channels, &all(channels));
        let mut data: Vec<Complex<f32>> = grey.iter().map(|g| Complex::new(*g as f32, 0.0)).collect();
        let mut planner = FftPlannerScalar::new();
        transform(&mut data, [width, height, 1], &mut planner, false);
        let mut cells = vec![0.0f64; CELLS * CELLS];
        for y in 0..height {
            for x in 0..width {
                if x == 0 && y == 0 {
                    continue;
                }
                let at = cell(frequency(x, width)) + CELLS * cell(frequency(y, height));
                cells[at] += data[x + width * y].norm_sqr() as f64;
            }
        }
        Target { cells: normalized(cells) }
    }
}

/// Reshape the spectrum of a wrapping volume (`dims`, interleaved `channels`) so its cuts
/// orthogonal to each axis with a target take that target's spectrum.
///
/// Real signals travel in pairs, one as the real and one as the imaginary part of a
/// complex transform: a real gain that is the same at k and -k scales both parts' spectra
/// alike, so one inverse transform gives both reshaped. The grey shares the first
/// transform with channel 0 (its power is separated by the spectrum's symmetry), later
/// channels go two by two.
pub fn match_spectrum(
    data: &mut [f32],
    dims: [usize; 3],
    channels: usize,
    standard: &Standard,
    targets: &[Option<&Target>; 3],
) {
    if targets.iter().all(Option::is_none) || dims.iter().product::<usize>() < 2 {
        return;
    }
    let mut planner = FftPlannerScalar::new();
    let grey = standard.grey_samples(data, channels, &all(channels));
    let mut packed: Vec<Complex<f32>> =
        data.par_chunks_exact(channels).zip(grey).map(|(px, g)| Complex::new(g as f32, px[0])).collect();
    transform(&mut packed, dims, &mut planner, false);
    let gain = fit_gain(&real_part_power(&packed, dims), dims, targets);
    reshape(&mut packed, &gain, dims, &mut planner);
    data.par_chunks_exact_mut(channels).zip(&packed).for_each(|(px, v)| px[0] = v.im);
    for first in (1..channels).step_by(2) {
        let second = (first + 1 < channels).then_some(first + 1);
        let mut packed: Vec<Complex<f32>> =
            data.par_chunks_exact(channels).map(|px| Complex::new(px[first], second.map_or(0.0, |c| px[c]))).collect();
        transform(&mut packed, dims, &mut planner, false);
        reshape(&mut packed, &gain, dims, &mut planner);
        data.par_chunks_exact_mut(channels).zip(&packed).for_each(|(px, v)| {
            px[first] = v.re;
            if let Some(c) = second {
                px[c] = v.im;
            }
        });
    }
}

/// Every channel, in order: the grey of [`Standard::grey_samples`] over all of them.
fn all(channels: usize) -> Vec<usize> {
    (0..channels).collect()
}

/// Scale a transformed pair by the square root of the gain and transform it back
/// (divided by the voxel count, so the values are the volume's).
fn reshape(spectrum: &mut [Complex<f32>], gain: &[f32], dims: [usize; 3], planner: &mut FftPlannerScalar<f32>) {
    spectrum.par_iter_mut().zip(gain).for_each(|(v, g)| *v *= g.sqrt());
    transform(spectrum, dims, planner, true);
    let count = spectrum.len() as f32;
    spectrum.par_iter_mut().for_each(|v| *v /= count);
}

/// The power spectrum of the real part of the signal a packed transform holds:
/// `(Z(k) + conj(Z(-k))) / 2` is the real part's transform.
fn real_part_power(packed: &[Complex<f32>], dims: [usize; 3]) -> Vec<f32> {
    (0..packed.len()).into_par_iter().map(|i| ((packed[i] + packed[mirror(i, dims)].conj()) * 0.5).norm_sqr()).collect()
}

/// The index of frequency -k for the index of k.
fn mirror(i: usize, dims: [usize; 3]) -> usize {
    let k = [i % dims[0], (i / dims[0]) % dims[1], i / (dims[0] * dims[1])];
    let m = [0, 1, 2].map(|a| (dims[a] - k[a]) % dims[a]);
    m[0] + dims[0] * (m[1] + dims[1] * m[2])
}

/// The gain per 3D frequency (the mean's is 1) that brings each axis' summed spectrum to
/// its target.
fn fit_gain(power: &[f32], dims: [usize; 3], targets: &[Option<&Target>; 3]) -> Vec<f32> {
    let axes: Vec<(usize, &Target)> = (0..3).filter_map(|a| targets[a].map(|t| (a, t))).collect();
    let share = 1.0 / axes.len() as f64;
    let places: [Vec<Place>; 3] = [0, 1, 2].map(|d| (0..dims[d]).map(|i| Place::of(frequency(i, dims[d]))).collect());
    let slab = dims[0] * dims[1];
    let mut gain = vec![1.0f32; power.len()];
    gain[0] = 0.0;
    for _ in 0..FIT_ROUNDS {
        let factors: Vec<(usize, Vec<f64>)> = axes
            .iter()
            .map(|&(a, target)| {
                let summed = summed_cells(power, &gain, dims, a, &places);
                let factor = target
                    .cells
                    .iter()
                    .zip(&summed)
                    .map(|(t, s)| if *s > 0.0 { (t / s).max(1e-12).powf(share) } else { 1.0 })
                    .collect();
                (a, factor)
            })
            .collect();
        gain.par_chunks_mut(slab).enumerate().for_each(|(z, plane)| {
            for (i, g) in plane.iter_mut().enumerate() {
                let k = [i % dims[0], i / dims[0], z];
                let mut f = 1.0;
                for (a, factor) in &factors {
                    let (u, v) = Axis::ALL[*a].plane_axes();
                    f *= read(factor, &places[u][k[u]], &places[v][k[v]]);
                }
                *g = ((*g as f64) * f).clamp(1.0 / MOST_GAIN, MOST_GAIN) as f32;
            }
        });
        gain[0] = 0.0;
    }
    gain[0] = 1.0;
    for i in 0..gain.len() {
        let j = mirror(i, dims);
        if j > i {
            let mean = 0.5 * (gain[i] + gain[j]);
            gain[i] = mean;
            gain[j] = mean;
        }
    }
    gain
}

/// The power times the gain, summed on the frequency cells of the plane orthogonal to
/// `axis` and normalized (per slab in parallel, the slabs added in order).
fn summed_cells(power: &[f32], gain: &[f32], dims: [usize; 3], axis: usize, places: &[Vec<Place>; 3]) -> Vec<f64> {
    let slab = dims[0] * dims[1];
    let (u, v) = Axis::ALL[axis].plane_axes();
    let partial: Vec<Vec<f64>> = power
        .par_chunks(slab)
        .zip(gain.par_chunks(slab))
        .enumerate()
        .map(|(z, (p, g))| {
            let mut cells = vec![0.0f64; CELLS * CELLS];
            for i in 0..slab {
                let k = [i % dims[0], i / dims[0], z];
                cells[places[u][k[u]].cell + CELLS * places[v][k[v]].cell] += (p[i] * g[i]) as f64;
            }
            cells
        })
        .collect();
    let mut sum = vec![0.0f64; CELLS * CELLS];
    for cells in &partial {
        for (s, c) in sum.iter_mut().zip(cells) {
            *s += c;
        }
    }
    normalized(sum)
}

/// Where one frequency falls on the cells: the cell it is binned in, and the two cell
/// centres it is read between (clamped at the edges).
#[derive(Debug, Clone, Copy)]
struct Place {
    cell: usize,
    low: usize,
    fraction: f64,
}

impl Place {
    fn of(f: f64) -> Place {
        let p = ((f + 0.5) * CELLS as f64 - 0.5).clamp(0.0, (CELLS - 1) as f64);
        let low = (p.floor() as usize).min(CELLS - 2);
        Place { cell: cell(f), low, fraction: p - low as f64 }
    }
}

/// Signed frequency of index `i` of an `n`-point transform, in [-0.5, 0.5).
fn frequency(i: usize, n: usize) -> f64 {
    let signed = if 2 * i < n { i as f64 } else { i as f64 - n as f64 };
    signed / n as f64
}

fn cell(f: f64) -> usize {
    (((f + 0.5) * CELLS as f64) as usize).min(CELLS - 1)
}

/// A cell table read bilinearly between cell centres.
fn read(table: &[f64], x: &Place, y: &Place) -> f64 {
    let t = |i: usize, j: usize| table[i + CELLS * j];
    let top = t(x.low, y.low) * (1.0 - x.fraction) + t(x.low + 1, y.low) * x.fraction;
    let bottom = t(x.low, y.low + 1) * (1.0 - x.fraction) + t(x.low + 1, y.low + 1) * x.fraction;
    top * (1.0 - y.fraction) + bottom * y.fraction
}

fn normalized(mut cells: Vec<f64>) -> Vec<f64> {
    let sum: f64 = cells.iter().sum();
    if sum > 0.0 {
        cells.iter_mut().for_each(|c| *c /= sum);
    }
    cells
}

/// In-place discrete Fourier transform along every axis of a `dims` grid (x fastest);
/// `inverse` without the 1/n factor. Lines are transformed in groups in parallel, each
/// line alone, so the result does not depend on the thread count.
fn transform(data: &mut [Complex<f32>], dims: [usize; 3], planner: &mut FftPlannerScalar<f32>, inverse: bool) {
    for axis in 0..3 {
        let n = dims[axis];
        if n < 2 {
            continue;
        }
        let fft: Arc<dyn Fft<f32>> = if inverse { planner.plan_fft_inverse(n) } else { planner.plan_fft_forward(n) };
        if axis == 0 {
            data.par_chunks_mut(n * LINES).for_each_init(
                || vec![Complex::new(0.0, 0.0); fft.get_inplace_scratch_len()],
                |scratch, lines| fft.process_with_scratch(lines, scratch),
            );
            continue;
        }
        let stride: usize = dims[..axis].iter().product();
        let start = |line: usize| (line % stride) + (line / stride) * stride * n;
        let lines = data.len() / n;
        let source: &[Complex<f32>] = data;
        let groups: Vec<Vec<Complex<f32>>> = (0..lines.div_ceil(LINES))
            .into_par_iter()
            .map_init(
                || vec![Complex::new(0.0, 0.0); fft.get_inplace_scratch_len()],
                |scratch, group| {
                    let range = group * LINES..((group + 1) * LINES).min(lines);
                    let mut values = Vec::with_capacity(range.len() * n);
                    for line in range {
                        values.extend((0..n).map(|i| source[start(line) + i * stride]));
                    }
                    fft.process_with_scratch(&mut values, scratch);
                    values
                },
            )
            .collect();
        for (group, values) in groups.iter().enumerate() {
            for (j, line_values) in values.chunks_exact(n).enumerate() {
                let at = start(group * LINES + j);
                for (i, v) in line_values.iter().enumerate() {
                    data[at + i * stride] = *v;
                }
            }
        }
    }
}

/// Lines per parallel task of [`transform`].
const LINES: usize = 64;

#[cfg(test)]
mod tests {
    use super::*;
    use crate::noise::mix64;
    use crate::sharpness::measure;
    use crate::volume::{Channel, Image2d, Volume};

    /// White noise on an `n`-cube, blurred periodically by a Gaussian of `sigma` voxels:
    /// blobs whose size grows with `sigma`.
    fn blobs(n: usize, sigma: f64, seed: u64) -> Vec<f32> {
        let mut data: Vec<f64> =
            (0..n * n * n).map(|i| (mix64(seed ^ mix64(i as u64)) % 1000) as f64 / 1000.0).collect();
        let radius = (3.0 * sigma).ceil() as i64;
        let kernel: Vec<f64> = (-radius..=radius).map(|i| (-(i * i) as f64 / (2.0 * sigma * sigma)).exp()).collect();
        let total: f64 = kernel.iter().sum();
        for axis in 0..3 {
            let stride = [1, n, n * n][axis];
            let source = data.clone();
            for (i, out) in data.iter_mut().enumerate() {
                let at = (i / stride) % n;
                *out = kernel
                    .iter()
                    .enumerate()
                    .map(|(k, w)| {
                        let moved = (at as i64 + k as i64 - radius).rem_euclid(n as i64) as usize;
                        w * source[i - at * stride + moved * stride]
                    })
                    .sum::<f64>()
                    / total;
            }
        }
        data.iter().map(|v| *v as f32).collect()
    }

    fn lengths(data: &[f32], n: usize, exemplar: &Image2d) -> Vec<f64> {
        let volume = Volume::from_data([n; 3], Channel::grey(), data.to_vec()).unwrap();
        Axis::ALL.iter().map(|&axis| measure(&volume, exemplar, &[0], axis).unwrap().length_ratio).collect()
    }

    #[test]
    fn blobs_too_large_take_the_exemplars_feature_size() {
        let n = 32;
        let fine = blobs(n, 1.0, 7);
        let exemplar = Image2d::from_data(n, n, Channel::grey(), fine[..n * n].to_vec()).unwrap();
        let mut volume = blobs(n, 1.8, 9);
        let before = lengths(&volume, n, &exemplar);
        assert!(before.iter().all(|l| *l > 1.4), "the blobs start too large: {before:?}");
        let standard = Standard::of_samples(exemplar.data(), 1);
        let target = Target::of(exemplar.data(), n, n, 1, &standard);
        match_spectrum(&mut volume, [n; 3], 1, &standard, &[Some(&target); 3]);
        let after = lengths(&volume, n, &exemplar);
        assert!(after.iter().all(|l| (0.8..=1.2).contains(l)), "{before:?} -> {after:?}");
    }

    #[test]
    fn the_transform_and_its_inverse_give_the_volume_back() {
        let dims = [5, 6, 7];
        let original: Vec<Complex<f32>> =
            (0..5 * 6 * 7).map(|i| Complex::new((mix64(i) % 100) as f32 / 100.0, 0.0)).collect();
        let mut data = original.clone();
        let mut planner = FftPlannerScalar::new();
        transform(&mut data, dims, &mut planner, false);
        assert!((data[0].re - original.iter().map(|c| c.re).sum::<f32>()).abs() < 1e-3, "the mean term is the sum");
        transform(&mut data, dims, &mut planner, true);
        for (a, b) in data.iter().zip(&original) {
            assert!((a.re / 210.0 - b.re).abs() < 1e-5 && (a.im / 210.0).abs() < 1e-5);
        }
    }

    #[test]
    fn a_volume_with_its_exemplars_spectrum_keeps_its_layout() {
        let n = 32;
        let mut volume = blobs(n, 1.5, 3);
        let before = volume.clone();
        let exemplar =
            Image2d::from_data(2 * n, 2 * n, Channel::grey(), blobs(2 * n, 1.5, 4)[..4 * n * n].to_vec()).unwrap();
        let standard = Standard::of_samples(exemplar.data(), 1);
        let target = Target::of(exemplar.data(), 2 * n, 2 * n, 1, &standard);
        match_spectrum(&mut volume, [n; 3], 1, &standard, &[Some(&target); 3]);
        let values = exemplar.data();
        let mean = values.iter().sum::<f32>() / values.len() as f32;
        let spread = (values.iter().map(|v| (v - mean).powi(2)).sum::<f32>() / values.len() as f32).sqrt();
        let moved = volume.iter().zip(&before).map(|(a, b)| (a - b).abs()).sum::<f32>() / before.len() as f32;
        assert!(moved < 0.35 * spread, "mean change {moved} against a deviation of {spread} (mean {mean})");
    }
}
