//! The optimization phase (thesis Fig. 4.5): every voxel becomes the weighted blend of
//! what the exemplar neighbourhoods matched around it predict for it. The weight is
//! `d^-power` (power 1.2: one IRLS step for Kopf's robust exponent r = 0.8; homogeneous
//! synthesis uses 6, so the best-matching neighbourhoods decide), divided by
//! `1 + strength * excess`, where `excess` sums, over channels, how much the colour's
//! histogram bin is over-represented in the volume compared with the exemplars
//! (histogram matching, Fig. 4.6). Each voxel is computed from the previous state
//! only, so the result does not depend on the order or the threads.

use super::depth;
use super::exemplar::Prepared;
use super::grid::Grid;
use super::search::Matches;
use crate::volume::Axis;
use rayon::prelude::*;

/// Histogram matching settings and target.
pub struct Histograms {
    /// Bins per channel over [0, 1].
    pub bins: usize,
    /// 0 switches histogram matching off.
    pub strength: f32,
    /// Target density per channel (`bins` values averaging 1).
    pub target: Vec<Vec<f32>>,
}

/// Density histograms (mean 1 per bin) of every channel of interleaved samples.
pub fn densities(samples: &[f32], channels: usize, bins: usize) -> Vec<Vec<f32>> {
    let mut counts = vec![vec![0u64; bins]; channels];
    for px in samples.chunks_exact(channels) {
        for (c, v) in px.iter().enumerate() {
            counts[c][bin(*v, bins)] += 1;
        }
    }
    let total = (samples.len() / channels).max(1) as f32;
    counts.iter().map(|h| h.iter().map(|&n| n as f32 * bins as f32 / total).collect()).collect()
}

/// The bin of a sample.
pub fn bin(v: f32, bins: usize) -> usize {
    ((v.clamp(0.0, 1.0) * bins as f32) as usize).min(bins - 1)
}

/// One optimization pass; returns the new samples.
pub fn optimize(
    grid: &Grid,
    matches: &[Matches; 3],
    exemplars: [Option<&Prepared>; 3],
    hist: &Histograms,
    power: f32,
) -> Vec<f32> {
    let current = densities(&grid.data, grid.channels, hist.bins);
    let weighted: Vec<Vec<f32>> =
        exemplars.iter().map(|ex| ex.map(|ex| weighted_pixels(ex, &current, hist)).unwrap_or_default()).collect();
    // Match pixel and blending weight side by side: one memory access per prediction.
    let packed: Vec<Vec<(u32, f32)>> = matches
        .iter()
        .map(|m| m.pixel.iter().zip(&m.dist).map(|(p, d)| (*p, (d + 1e-3).powf(-power))).collect())
        .collect();
    let planes: Vec<Option<PlaneView>> = (0..3)
        .map(|axis| exemplars[axis].map(|ex| PlaneView::new(grid, ex, &packed[axis], &weighted[axis], axis)))
        .collect();
    let plane = grid.dims[0] * grid.dims[1] * grid.channels;
    let mut out = vec![0.0; grid.data.len()];
    out.par_chunks_mut(plane).enumerate().for_each(|(z, slice)| {
        // Per voxel of a row: its colour sums, then its weight sum (the last of c + 1).
        let mut acc = vec![0.0f32; grid.dims[0] * (grid.channels + 1)];
        for (y, voxels) in slice.chunks_exact_mut(grid.dims[0] * grid.channels).enumerate() {
            acc.fill(0.0);
            for view in planes.iter().flatten() {
                view.add_row(grid, y, z, &mut acc);
            }
            for (x, (voxel, sums)) in
                voxels.chunks_exact_mut(grid.channels).zip(acc.chunks_exact(grid.channels + 1)).enumerate()
            {
                let total = sums[grid.channels];
                if total <= 0.0 {
                    let keep = grid.index(x, y, z) * grid.channels;
                    voxel.copy_from_slice(&grid.data[keep..keep + grid.channels]);
                    continue;
                }
                for (o, a) in voxel.iter_mut().zip(sums) {
                    *o = a / total;
                }
            }
        }
    });
    out
}

/// Exact per-channel histogram transfer of the channels in `which`: the k-th smallest
/// volume sample takes the value of the same quantile of the exemplar samples (ties broken
/// by position, so the result is deterministic). Keeps the order of values, restores the
/// exemplar's contrast.
fn transfer_channels(data: &mut [f32], channels: usize, exemplar: &[f32], which: std::ops::Range<usize>) {
    let count = data.len() / channels;
    let targets = exemplar.len() / channels;
    for c in which {
        let mut target: Vec<f32> = exemplar.iter().skip(c).step_by(channels).copied().collect();
        target.sort_by(f32::total_cmp);
        let keys = (0..count).map(|i| ordered_bits(data[i * channels + c]));
        for (rank, &key) in sorted_by_key(keys).iter().enumerate() {
            let q = ((rank as f64 + 0.5) / count as f64 * targets as f64) as usize;
            data[(key as u32) as usize * channels + c] = target[q.min(targets - 1)];
        }
    }
}

/// Rounds of the joint colour transfer in synthesis (each along the axes of one rotation of
/// colour space, the last along the channels' own axes). 4 leave no invented colour on the
/// red-green-blue test exemplar, as 8 do, at half the cost (docs/synthesis.md).
pub const JOINT_ROUNDS: usize = 4;

/// Joint colour transfer (Pitié's iterative distribution transfer, a sliced optimal
/// transport): `rounds` times, along every axis of a pseudo-random rotation of colour
/// space, the volume's projections take the same quantiles of the exemplar's projections
/// (an exact 1D transfer) and each sample moves along that axis by the difference. A
/// per-channel transfer maps every channel alone, so a voxel blended from red and green
/// can come out yellow or black, colours the exemplar never shows; moving along rotating
/// axes matches the distribution of whole colours. One channel: the exact transfer.
pub fn transfer_joint(data: &mut [f32], channels: usize, exemplar: &[f32], rounds: usize) {
    if channels == 1 {
        transfer_channels(data, 1, exemplar, 0..1);
        return;
    }
    let count = data.len() / channels;
    let mut target = vec![0.0f32; exemplar.len() / channels];
    let mut along = vec![0.0f32; count];
    // Rounds count down so that the last one is along the channels' own axes: the
    // per-channel histograms end up exact, after the joint rounds brought whole colours close.
    for round in (0..rounds.max(1)).rev() {
        for axis in rotation(channels, round as u64) {
            let project = |px: &[f32]| px.iter().zip(&axis).map(|(v, a)| v * a).sum::<f32>();
            for (t, px) in target.iter_mut().zip(exemplar.chunks_exact(channels)) {
                *t = project(px);
            }
            for (p, px) in along.iter_mut().zip(data.chunks_exact(channels)) {
                *p = project(px);
            }
            let mut moved = along.clone();
            transfer_channels(&mut moved, 1, &target, 0..1);
            for ((px, before), after) in data.chunks_exact_mut(channels).zip(&along).zip(&moved) {
                for (v, a) in px.iter_mut().zip(&axis) {
                    *v += (after - before) * a;
                }
            }
        }
    }
}

/// An orthonormal basis of `n` dimensions, pseudo-random but fixed for `round` (Gram-Schmidt
/// on hashed directions); round 0 is the channels' own axes.
fn rotation(n: usize, round: u64) -> Vec<Vec<f32>> {
    let unit = |i: usize| -> Vec<f32> { (0..n).map(|j| f32::from(u8::from(i == j))).collect() };
    let hashed = |i: usize| -> Vec<f32> {
        (0..n).map(|j| (crate::noise::hash3(round, i as i64, j as i64, 11) % 20_001) as f32 / 10_000.0 - 1.0).collect()
    };
    let mut basis: Vec<Vec<f32>> = Vec::with_capacity(n);
    for i in 0..n {
        let first = if round == 0 { unit(i) } else { hashed(i) };
        // A draw (nearly) inside the span so far is replaced by the first channel axis that is not.
        let next = std::iter::once(first).chain((0..n).map(unit)).find_map(|mut v| {
            for b in &basis {
                let dot: f32 = v.iter().zip(b).map(|(x, y)| x * y).sum();
                v.iter_mut().zip(b).for_each(|(x, y)| *x -= dot * y);
            }
            let norm = v.iter().map(|x| x * x).sum::<f32>().sqrt();
            (norm > 1e-3).then(|| v.into_iter().map(|x| x / norm).collect::<Vec<f32>>())
        });
        basis.push(next.expect("n unit axes span n dimensions"));
    }
    basis
}

/// The bits of `v` as an integer that sorts like `f32::total_cmp`.
fn ordered_bits(v: f32) -> u32 {
    let b = v.to_bits();
    if b >> 31 == 1 { !b } else { b | 0x8000_0000 }
}

/// Bits per digit of [`sorted_by_key`]: three passes cover a 32-bit key, and a pass's
/// counts (2,048) stay in the first-level cache.
const DIGIT: u32 = 11;

/// The samples as `key << 32 | index` (index = position in `keys`), in increasing order:
/// by key, ties by index. A least-significant-digit radix sort of the keys, stable, so
/// samples of one key keep their index order: the order `sort_unstable` gives the packed
/// values, at a few passes over the samples instead of a comparison sort.
fn sorted_by_key(keys: impl ExactSizeIterator<Item = u32>) -> Vec<u64> {
    let mut order: Vec<u64> = keys.enumerate().map(|(i, k)| (u64::from(k) << 32) | i as u64).collect();
    let mut spare = vec![0u64; order.len()];
    for shift in (32..64).step_by(DIGIT as usize) {
        let digit = |v: u64| ((v >> shift) & ((1 << DIGIT) - 1)) as usize;
        let mut starts = vec![0usize; 1 << DIGIT];
        order.iter().for_each(|&v| starts[digit(v)] += 1);
        if starts.contains(&order.len()) {
            continue;
        }
        let mut next = 0;
        for s in starts.iter_mut() {
            (*s, next) = (next, next + *s);
        }
        for &v in &order {
            let d = digit(v);
            spare[starts[d]] = v;
            starts[d] += 1;
        }
        std::mem::swap(&mut order, &mut spare);
    }
    order
}

/// Layered histogram transfer: every z-slice's colour channels take the histogram of the
/// exemplar pixels whose depth (the last channel) is nearest to the slice's depth
/// `z / (Z - 1)`, a band of about three slices' worth of pixels. A global transfer would
/// match the spread between layers and leave each layer flat; per depth it restores the
/// contrast inside each layer. The depth channel keeps the global transfer.
pub fn transfer_histograms_by_depth(data: &mut [f32], dims: [usize; 3], channels: usize, exemplar: &[f32]) {
    let pixels = exemplar.len() / channels;
    let order =
        depth::sorted_by_depth((0..pixels).map(|p| (exemplar[p * channels + channels - 1], p as u32)).collect());
    let width = (3 * pixels / dims[2].max(1)).clamp(pixels.min(64), pixels);
    let plane = dims[0] * dims[1] * channels;
    let mut band_colours = Vec::with_capacity(width * channels);
    for (z, slice) in data.chunks_exact_mut(plane).enumerate() {
        band_colours.clear();
        for &(_, p) in &order[depth::band(&order, depth::slice_depth(z, dims[2]), width)] {
            band_colours.extend_from_slice(&exemplar[p as usize * channels..(p as usize + 1) * channels]);
        }
        transfer_channels(slice, channels, &band_colours, 0..channels - 1);
    }
    transfer_channels(data, channels, exemplar, channels - 1..channels);
}

/// Every exemplar pixel's colour times its histogram factor, followed by the factor
/// (channels + 1 values per pixel): the blend reads one place per prediction.
fn weighted_pixels(ex: &Prepared, current: &[Vec<f32>], hist: &Histograms) -> Vec<f32> {
    ex.colours
        .chunks_exact(ex.channels)
        .flat_map(|px| {
            let excess: f32 = px
                .iter()
                .enumerate()
                .map(|(c, v)| {
                    let b = bin(*v, hist.bins);
                    (current[c][b] - hist.target[c][b]).max(0.0)
                })
                .sum();
            let factor = 1.0 / (1.0 + hist.strength * excess);
            px.iter().map(move |c| c * factor).chain(std::iter::once(factor))
        })
        .collect()
}

/// One axis' matches, prepared for blending: for each in-plane offset, where the
/// neighbour sits (folded once into tables) and how far its match pixel is shifted.
struct PlaneView<'a> {
    ex: &'a Prepared,
    /// Per voxel: its match's centre pixel and blending weight.
    matches: &'a [(u32, f32)],
    /// Per exemplar pixel: its colour times its histogram factor, then the factor.
    weighted: &'a [f32],
    axes: (usize, usize),
    /// `fold_a[dx * len + c]`: the neighbour's coordinate along the first plane axis, or
    /// `u32::MAX` (`len`: the volume's size along it).
    fold_a: Vec<u32>,
    fold_b: Vec<u32>,
    /// Exemplar pixel offset of each (dy, dx).
    shift: Vec<i64>,
}

impl<'a> PlaneView<'a> {
    fn new(grid: &Grid, ex: &'a Prepared, matches: &'a [(u32, f32)], weighted: &'a [f32], axis: usize) -> Self {
        let (a, b) = Axis::ALL[axis].plane_axes();
        let (n, h) = (ex.n, ex.half() as i64);
        let table = |k: usize| -> Vec<u32> {
            // Along an axis that does not wrap, only neighbours whose whole neighbourhood
            // lies inside predict: a clamped neighbourhood's match is placed wrongly.
            let len = grid.dims[k] as i64;
            let whole = |u: usize| grid.wrap[k] || len < n as i64 || (h..=len - n as i64 + h).contains(&(u as i64));
            (0..grid.dims[k] * n)
                .map(|i| {
                    let (d, c) = ((i / grid.dims[k]) as i64, (i % grid.dims[k]) as i64);
                    grid.inside(k, c - (d - h)).filter(|u| whole(*u)).map_or(u32::MAX, |u| u as u32)
                })
                .collect()
        };
        let shift = (0..n * n).map(|i| ((i / n) as i64 - h) * ex.width as i64 + (i % n) as i64 - h).collect();
        PlaneView { ex, matches, weighted, axes: (a, b), fold_a: table(a), fold_b: table(b), shift }
    }

    /// Add the predictions this axis makes for the voxels of row (y, z) to their sums in
    /// `acc` (c + 1 per voxel): for each in-plane neighbour, the exemplar pixel its match
    /// puts at the voxel's position, as weighted colour and histogram factor (see
    /// [`weighted_pixels`]). Each voxel adds its predictions in the same order whatever
    /// the row: offset by offset, so the sums do not depend on how voxels are grouped.
    fn add_row(&self, grid: &Grid, y: usize, z: usize, acc: &mut [f32]) {
        let (a, b) = self.axes;
        let (n, row, c1) = (self.ex.n, grid.dims[0], self.ex.channels + 1);
        let v = [0, y, z];
        for dy in 0..n {
            let ub = self.fold_b[dy * grid.dims[b] + v[b]];
            if ub == u32::MAX {
                continue;
            }
            for dx in 0..n {
                let shift = self.shift[dy * n + dx];
                let mut u = v;
                u[b] = ub as usize;
                if a == 0 {
                    // The plane holds the row: each voxel's neighbour lies along it.
                    let base = grid.index(0, u[1], u[2]);
                    let along = &self.fold_a[dx * row..(dx + 1) * row];
                    for (sums, &ua) in acc.chunks_exact_mut(c1).zip(along) {
                        if ua != u32::MAX {
                            self.add(base + ua as usize, shift, sums);
                        }
                    }
                } else {
                    // The plane crosses the row: every voxel's neighbour has the same offset.
                    let ua = self.fold_a[dx * grid.dims[a] + v[a]];
                    if ua == u32::MAX {
                        continue;
                    }
                    u[a] = ua as usize;
                    let base = grid.index(0, u[1], u[2]);
                    for (x, sums) in acc.chunks_exact_mut(c1).enumerate() {
                        self.add(base + x, shift, sums);
                    }
                }
            }
        }
    }

    /// Add the prediction of the match at voxel `at`, shifted by `shift` pixels, to `sums`.
    #[inline(always)]
    fn add(&self, at: usize, shift: i64, sums: &mut [f32]) {
        let c1 = sums.len();
        let (centre, weight) = self.matches[at];
        let pix = (centre as i64 + shift) as usize;
        for (s, p) in sums.iter_mut().zip(&self.weighted[pix * c1..(pix + 1) * c1]) {
            *s += weight * p;
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The radix order is the comparison sort's order of the packed samples, ties (many
    /// equal keys) by index, keys spanning every digit.
    #[test]
    fn the_radix_order_is_the_sorted_order() {
        let mut state = 7u64;
        let mut next = || {
            state = crate::noise::mix64(state);
            state
        };
        for spread in [4u64, 1 << 12, 1 << 32] {
            let keys: Vec<u32> = (0..5000).map(|_| (next() % spread) as u32).collect();
            let mut want: Vec<u64> = keys.iter().enumerate().map(|(i, &k)| (u64::from(k) << 32) | i as u64).collect();
            want.sort_unstable();
            assert_eq!(sorted_by_key(keys.iter().copied()), want, "keys below {spread}");
        }
        let floats = [0.5f32, -0.0, 0.0, -1.0, f32::NAN, 0.25, 1.0, -f32::NAN, 0.5];
        let order = sorted_by_key(floats.iter().map(|&v| ordered_bits(v)));
        let ranked: Vec<usize> = order.iter().map(|&v| (v as u32) as usize).collect();
        assert_eq!(ranked, [7, 3, 1, 2, 5, 0, 8, 6, 4]);
    }
    use crate::synth::exemplar::PrepareOptions;
    use crate::volume::{Channel, Image2d};

    /// Inside each z-slice the order of colours is kept; the depth channel is matched over
    /// the whole exemplar.
    #[test]
    fn the_layered_transfer_keeps_order_and_matches_depth_globally() {
        // 4 rows of 16 pixels: row r has colours r + 0.01 * x, depth r / 3. The band (at
        // least 64 pixels) is the whole exemplar here, so every slice gets the same values.
        let exemplar: Vec<f32> =
            (0..64).flat_map(|i| [(i / 16) as f32 + 0.01 * (i % 16) as f32, (i / 16) as f32 / 3.0]).collect();
        let mut data: Vec<f32> = (0..64).flat_map(|i| [1.5 + 0.001 * ((i * 37) % 64) as f32, 0.5]).collect();
        let before = data.clone();
        transfer_histograms_by_depth(&mut data, [4, 4, 4], 2, &exemplar);
        let sorted = |z: usize| {
            let mut s: Vec<f32> = (0..16).map(|i| data[(z * 16 + i) * 2]).collect();
            s.sort_by(f32::total_cmp);
            s
        };
        for z in 0..4 {
            assert_eq!(sorted(z), sorted(0), "slice {z}");
            for i in 1..16 {
                let (a, b) = ((z * 16 + i - 1) * 2, (z * 16 + i) * 2);
                assert_eq!(before[a] < before[b], data[a] < data[b], "slice {z}, voxel {i}");
            }
        }
        let mut depths: Vec<f32> = data.iter().skip(1).step_by(2).copied().collect();
        depths.sort_by(f32::total_cmp);
        assert_eq!((depths[0], depths[63]), (0.0, 1.0), "depth spans the exemplar's depths");
    }

    /// With more rows than the band, slices at different depths get different colours.
    #[test]
    fn the_layered_transfer_separates_depths() {
        // 32 rows of 8 pixels: colour = row / 31 + tiny jitter, depth = row / 31.
        let exemplar: Vec<f32> = (0..256)
            .flat_map(|i| {
                let r = (i / 8) as f32 / 31.0;
                [r + 0.001 * (i % 8) as f32, r]
            })
            .collect();
        let mut data: Vec<f32> = (0..8 * 8 * 32).flat_map(|i| [0.5 + 0.0001 * (i % 97) as f32, 0.5]).collect();
        transfer_histograms_by_depth(&mut data, [8, 8, 32], 2, &exemplar);
        for z in 0..32 {
            let mean = (0..64).map(|i| data[(z * 64 + i) * 2]).sum::<f32>() / 64.0;
            let ideal = z as f32 / 31.0;
            // The band is 64 pixels (8 rows), so a slice's colours lie within 4 rows of its own.
            assert!((mean - ideal).abs() < 4.5 / 31.0, "slice {z}: mean {mean}, ideal {ideal}");
        }
    }

    /// When every voxel's match is the exemplar pixel it copies, the blend is that copy.
    #[test]
    fn coherent_matches_reproduce_the_exemplar() {
        let (w, h) = (24, 20);
        let data: Vec<f32> = (0..w * h).map(|i| ((i * 37) % 101) as f32 / 100.0).collect();
        let image = Image2d::from_data(w, h, Channel::grey(), data.clone()).unwrap();
        let ex = Prepared::new(&image, &[1.0], PrepareOptions { n: 4, variance: 1.0, max_dims: 8, k: 2 });
        let (gw, gh) = (12, 10);
        let (ox, oy) = (6, 5);
        let grid = Grid { dims: [gw, gh, 1], channels: 1, data: vec![0.5; gw * gh], wrap: [false; 3] };
        let pixel: Vec<u32> = (0..gw * gh).map(|i| ((i / gw + oy) * w + i % gw + ox) as u32).collect();
        let m = Matches { pixel, dist: vec![0.1; gw * gh] };
        let matches = [Matches::default(), Matches::default(), m];
        let hist = Histograms { bins: 8, strength: 0.0, target: vec![vec![1.0; 8]] };
        let out = optimize(&grid, &matches, [None, None, Some(&ex)], &hist, 1.2);
        for y in 0..gh {
            for x in 0..gw {
                assert!((out[y * gw + x] - data[(y + oy) * w + x + ox]).abs() < 1e-6, "voxel ({x}, {y})");
            }
        }
    }

    /// Blends of red, green and blue voxels come back as colours the exemplar has: the
    /// joint transfer leaves no voxel far from all three (a per-channel transfer made some
    /// yellow or black), and every channel's histogram ends exact.
    #[test]
    fn the_joint_transfer_invents_no_colours() {
        let palette = [[1.0f32, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]];
        let exemplar: Vec<f32> = (0..300).flat_map(|i| palette[i % 3]).collect();
        // Voxels: pure colours and half-half blends of two of them, as a soft blend leaves.
        let mut data: Vec<f32> = (0..600)
            .flat_map(|i| {
                let (a, b) = (palette[i % 3], palette[(i / 3) % 3]);
                let t = if i % 2 == 0 { 0.5 } else { 0.9 };
                [0, 1, 2].map(|c| t * a[c] + (1.0 - t) * b[c])
            })
            .collect();
        let mut per_channel = data.clone();
        transfer_channels(&mut per_channel, 3, &exemplar, 0..3);
        transfer_joint(&mut data, 3, &exemplar, JOINT_ROUNDS);
        let off = |d: &[f32]| {
            d.chunks_exact(3)
                .filter(|px| {
                    palette.iter().all(|p| p.iter().zip(*px).map(|(a, b)| (a - b) * (a - b)).sum::<f32>() > 0.25)
                })
                .count()
        };
        assert!(off(&per_channel) > 30, "the per-channel transfer invents colours here: {}", off(&per_channel));
        assert_eq!(off(&data), 0, "the joint transfer invents none");
        for c in 0..3 {
            let mut got: Vec<f32> = data.iter().skip(c).step_by(3).copied().collect();
            got.sort_by(f32::total_cmp);
            let ones = got.iter().filter(|v| **v > 0.5).count();
            assert_eq!(ones, 200, "channel {c}: a third of the voxels take its colour");
        }
    }

    /// The integer sort key orders floats exactly as `total_cmp` (negatives, zeros,
    /// infinities), so the transfer ranks samples as before.
    #[test]
    fn sort_keys_order_like_total_cmp() {
        let values = [0.5f32, -0.0, 0.0, -1.5, f32::INFINITY, 1e-30, -1e-30, f32::NEG_INFINITY, 0.25, -0.25];
        for a in values {
            for b in values {
                assert_eq!(ordered_bits(a).cmp(&ordered_bits(b)), a.total_cmp(&b), "{a} vs {b}");
            }
        }
    }
}
