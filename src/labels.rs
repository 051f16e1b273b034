//! Materials statistics of label volumes (a few phases, e.g. pore and grain of a rock), the
//! figures papers report for 3D reconstructions from 2D slices, per phase:
//!
//! - **share** (volume fraction) `phi`;
//! - **two-point probability** `S2(r)` along each axis: the chance that two voxels `r`
//!   apart along the axis are both in the phase (pairs inside the volume, no wrapping);
//!   `S2(0) = phi`;
//! - **lineal path** `L(r)` along each axis: the chance that a segment of `r + 1` voxels
//!   along the axis lies wholly in the phase; `L(0) = phi`;
//! - **interface per voxel**: faces between the phase and the others per voxel of the
//!   volume, per axis and summed (the specific surface area in 1/voxel for interfaces that
//!   follow the grid; for curved, randomly oriented ones the true area is about 2/3 of
//!   the sum, given as `isotropic_surface`);
//! - **pieces**: face-connected (6-connected, no wrapping) groups of the phase's voxels, per
//!   100,000 voxels, and how many of them hold only 1 or 2 voxels (specks);
//! - **correlation length** along each axis: the first lag at which the normalized two-point
//!   correlation `(S2(r) - phi^2) / (phi - phi^2)` falls to 1/e, interpolated between lags
//!   (none when it stays above within [`CORRELATION_LAG`] voxels or the side).
//!
//! [`against_truth`] compares a volume with a 3D truth: the volume's values are first
//! snapped to the nearest of the truth's labels (a synthesized volume holds blends), then
//! each phase's figures are given as volume over truth. Both are measured in boxes of the
//! same size (the smaller of the two on each axis; the larger volume cut into as many such
//! tiles as fit, their figures pooled): pieces are counted without wrapping, so a box
//! half as wide cuts about twice as many pieces per voxel at its faces (the channels
//! truth's sand phase: 1.1 pieces per 100k voxels in its 128³, 1.5-5.3 in its 64³ octants).
//!
//! The phases are the distinct values of the first channel (at most [`MAX_PHASES`]).

use crate::error::{Error, Result};
use crate::sharpness::ratio;
use crate::volume::Volume;
use serde::Serialize;
use std::borrow::Cow;

/// Most phases a label volume may have.
pub const MAX_PHASES: usize = 16;
/// Largest lag reported.
pub const MAX_LAG: usize = 32;
/// Largest lag searched for the correlation length.
pub const CORRELATION_LAG: usize = 64;
/// Against a truth: the band of the pieces ratio.
pub const PIECES_BAND: (f64, f64) = (0.7, 1.3);
/// Against a truth: the band of each axis' correlation-length ratio.
pub const CORRELATION_BAND: (f64, f64) = (0.7, 1.3);
/// Against a truth: the band of the share ratio.
pub const SHARE_BAND: (f64, f64) = (0.8, 1.25);
/// Against a truth: the fewest voxels along each axis of both volumes (as the per-axis
/// figures of `quality` need cuts of at least 8 x 8).
pub const LEAST_SIDE: usize = 8;
/// Against a truth: the most pieces of 1 or 2 voxels per 100,000 voxels the volume may
/// hold beyond the truth's.
pub const MOST_EXTRA_SPECKS: f64 = 1.0;

/// One phase's statistics.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Phase {
    /// The label (the first channel's value).
    pub label: f32,
    /// Volume fraction.
    pub share: f64,
    /// Per axis x, y, z: `S2(r)` for `r = 0..=lags`.
    pub two_point: [Vec<f64>; 3],
    /// Per axis: `L(r)` for `r = 0..=lags`.
    pub lineal_path: [Vec<f64>; 3],
    /// Per axis: faces to other phases across that axis, per voxel.
    pub interface_per_axis: [f64; 3],
    /// Their sum: faces per voxel.
    pub interface_per_voxel: f64,
    /// 2/3 of the sum: the surface per voxel of curved, randomly oriented interfaces.
    pub isotropic_surface: f64,
    /// Face-connected pieces of the phase per 100,000 voxels.
    pub pieces_per_100k: f64,
    /// Pieces of 1 or 2 voxels.
    pub specks: usize,
    /// Pieces of 1 or 2 voxels per 100,000 voxels.
    pub specks_per_100k: f64,
    /// Per axis: the lag (voxels) at which the normalized two-point correlation falls to
    /// 1/e; `None` when it does not within the lags searched.
    pub correlation_length: [Option<f64>; 3],
}

/// The statistics of a label volume.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct LabelStats {
    /// Size in voxels.
    pub dims: [usize; 3],
    /// The box measured: `dims`, or the tiles `dims` was cut into when compared with a
    /// smaller volume ([`against_truth`]).
    pub tile: [usize; 3],
    /// How many tiles of `tile` voxels were measured and pooled (1: the whole volume).
    pub tiles: usize,
    /// Largest lag per axis (`min(MAX_LAG, side - 1)` of the tile).
    pub lags: [usize; 3],
    /// The phases, by label.
    pub phases: Vec<Phase>,
}

/// Measure the label volume `volume`.
pub fn measure(volume: &Volume) -> Result<LabelStats> {
    let labels = first_channel(volume);
    let distinct = distinct_labels(&labels, volume.channels()[0].name())?;
    Ok(measure_labels(&labels, volume.dims(), &distinct))
}

/// One phase of a volume against the same phase of a truth: volume over truth.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct PhaseAgainstTruth {
    /// The label.
    pub label: f32,
    /// Share, volume over truth.
    pub share_ratio: f64,
    /// Pieces per 100,000 voxels, volume over truth.
    pub pieces_ratio: f64,
    /// Per axis: correlation length, volume over truth (`None` when either has none).
    pub correlation_ratio: [Option<f64>; 3],
    /// Pieces of 1 or 2 voxels per 100,000 voxels, volume minus truth.
    pub extra_specks_per_100k: f64,
}

/// A label volume compared with its truth.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct TruthComparison {
    /// The volume's statistics, its values snapped to the truth's labels.
    pub volume: LabelStats,
    /// The truth's statistics.
    pub truth: LabelStats,
    /// Per truth phase, the ratios.
    pub ratios: Vec<PhaseAgainstTruth>,
}

impl TruthComparison {
    /// Every ratio outside its band, named; a correlation length the truth has and the
    /// volume lacks (or the reverse) counts as outside.
    pub fn outside_bands(&self) -> Vec<String> {
        use crate::sharpness::within;
        let mut out = Vec::new();
        for r in &self.ratios {
            let phase = format!("phase {}", r.label);
            if !within(r.share_ratio, SHARE_BAND) {
                out.push(format!(
                    "{phase} share ratio {:.2} (allowed {}-{})",
                    r.share_ratio, SHARE_BAND.0, SHARE_BAND.1
                ));
            }
            if !within(r.pieces_ratio, PIECES_BAND) {
                out.push(format!(
                    "{phase} pieces ratio {:.2} (allowed {}-{})",
                    r.pieces_ratio, PIECES_BAND.0, PIECES_BAND.1
                ));
            }
            if r.extra_specks_per_100k > MOST_EXTRA_SPECKS {
                out.push(format!(
                    "{phase} has {:.1} more pieces of 1-2 voxels per 100k voxels than the truth (allowed {MOST_EXTRA_SPECKS})",
                    r.extra_specks_per_100k
                ));
            }
            for (a, c) in r.correlation_ratio.iter().enumerate() {
                let axis = ["x", "y", "z"][a];
                match *c {
                    Some(c) if within(c, CORRELATION_BAND) => {}
                    Some(c) => out.push(format!(
                        "{phase} {axis} correlation length ratio {c:.2} (allowed {}-{})",
                        CORRELATION_BAND.0, CORRELATION_BAND.1
                    )),
                    None => {
                        let has = |s: &LabelStats| {
                            s.phases.iter().find(|p| p.label == r.label).and_then(|p| p.correlation_length[a])
                        };
                        if has(&self.truth).is_some() != has(&self.volume).is_some() {
                            out.push(format!("{phase} {axis} correlation length: one of volume and truth has none"));
                        }
                    }
                }
            }
        }
        out
    }
}

/// Compare `volume` with the label volume `truth`: the volume's first channel is snapped to
/// the nearest of the truth's labels, both are measured, and each phase's figures are
/// given as volume over truth.
pub fn against_truth(volume: &Volume, truth: &Volume) -> Result<TruthComparison> {
    let truth_labels = first_channel(truth);
    let distinct = distinct_labels(&truth_labels, truth.channels()[0].name())?;
    if distinct.len() < 2 {
        return Err(Error::invalid(format!(
            "the truth holds one label ({}): a truth to compare with has at least two phases",
            distinct.first().copied().unwrap_or_default()
        )));
    }
    let (v, t) = (volume.dims(), truth.dims());
    let tile = [0, 1, 2].map(|a| v[a].min(t[a]));
    if tile.iter().any(|side| *side < LEAST_SIDE) {
        return Err(Error::invalid(format!(
            "the volume is {}x{}x{} and the truth {}x{}x{}: comparing them needs at least {LEAST_SIDE} voxels \
             along each axis of both",
            v[0], v[1], v[2], t[0], t[1], t[2]
        )));
    }
    let truth_stats = measure_in_tiles(&truth_labels, t, tile, &distinct);
    let snapped: Vec<f32> = first_channel(volume).iter().map(|v| nearest(*v, &distinct)).collect();
    let volume_stats = measure_in_tiles(&snapped, v, tile, &distinct);
    let ratios = truth_stats
        .phases
        .iter()
        .zip(&volume_stats.phases)
        .map(|(t, v)| PhaseAgainstTruth {
            label: t.label,
            share_ratio: ratio(v.share, t.share),
            pieces_ratio: ratio(v.pieces_per_100k, t.pieces_per_100k),
            correlation_ratio: [0, 1, 2].map(|a| Some(ratio(v.correlation_length[a]?, t.correlation_length[a]?))),
            extra_specks_per_100k: v.specks_per_100k - t.specks_per_100k,
        })
        .collect();
    Ok(TruthComparison { volume: volume_stats, truth: truth_stats, ratios })
}

fn first_channel(volume: &Volume) -> Vec<f32> {
    volume.data().iter().step_by(volume.channel_count()).copied().collect()
}

/// The distinct values of `labels`, sorted; an error naming `channel` past [`MAX_PHASES`].
fn distinct_labels(labels: &[f32], channel: &str) -> Result<Vec<f32>> {
    let mut distinct: Vec<f32> = Vec::new();
    for v in labels {
        if !distinct.contains(v) {
            if distinct.len() == MAX_PHASES {
                return Err(Error::invalid(format!(
                    "channel {channel} has more than {MAX_PHASES} distinct values: a label volume holds a few phases"
                )));
            }
            distinct.push(*v);
        }
    }
    distinct.sort_by(f32::total_cmp);
    Ok(distinct)
}

/// The label nearest to `value` (the first of equals).
fn nearest(value: f32, labels: &[f32]) -> f32 {
    labels.iter().copied().min_by(|a, b| (a - value).abs().total_cmp(&(b - value).abs())).unwrap_or(value)
}

fn measure_labels(labels: &[f32], dims: [usize; 3], distinct: &[f32]) -> LabelStats {
    measure_in_tiles(labels, dims, dims, distinct)
}

/// The statistics of `labels` (`dims` voxels) cut into tiles of `tile` voxels from its
/// origin, as many as fit on each axis: every figure pooled over the tiles (means of
/// equal-sized boxes; the correlation length from the pooled two-point probability).
fn measure_in_tiles(labels: &[f32], dims: [usize; 3], tile: [usize; 3], distinct: &[f32]) -> LabelStats {
    let counts = [0, 1, 2].map(|a| dims[a] / tile[a].max(1));
    let tiles = counts.iter().product::<usize>();
    let lags = tile.map(|d| MAX_LAG.min(d.saturating_sub(1)));
    let mut pooled: Vec<Phase> = Vec::new();
    for k in 0..tiles {
        let place = [k % counts[0], (k / counts[0]) % counts[1], k / (counts[0] * counts[1])];
        let cut = crop(labels, dims, [0, 1, 2].map(|a| place[a] * tile[a]), tile);
        let pieces = pieces(&cut, tile);
        for (i, &label) in distinct.iter().enumerate() {
            let sizes = pieces.iter().filter(|p| p.0 == label).map(|p| p.1);
            let one = phase(&cut, tile, label, sizes);
            match pooled.get_mut(i) {
                Some(sum) => add(sum, &one),
                None => pooled.push(one),
            }
        }
    }
    let phases = pooled.into_iter().map(|p| finished(p, tiles)).collect();
    LabelStats { dims, tile, tiles, lags, phases }
}

/// The `tile`-sized box of `labels` (`dims` voxels) whose lowest corner is `corner`
/// (`labels` itself, uncopied, when the box is the whole volume).
fn crop(labels: &[f32], dims: [usize; 3], corner: [usize; 3], tile: [usize; 3]) -> Cow<'_, [f32]> {
    if tile == dims {
        return Cow::Borrowed(labels);
    }
    let mut out = Vec::with_capacity(tile.iter().product());
    for z in corner[2]..corner[2] + tile[2] {
        for y in corner[1]..corner[1] + tile[1] {
            let start = (z * dims[1] + y) * dims[0] + corner[0];
            out.extend_from_slice(&labels[start..start + tile[0]]);
        }
    }
    Cow::Owned(out)
}

/// `sum` plus `one`, figure by figure (the same phase in another tile of the same size).
fn add(sum: &mut Phase, one: &Phase) {
    let plus = |a: &mut Vec<f64>, b: &Vec<f64>| a.iter_mut().zip(b).for_each(|(a, b)| *a += b);
    sum.share += one.share;
    for a in 0..3 {
        plus(&mut sum.two_point[a], &one.two_point[a]);
        plus(&mut sum.lineal_path[a], &one.lineal_path[a]);
        sum.interface_per_axis[a] += one.interface_per_axis[a];
    }
    sum.interface_per_voxel += one.interface_per_voxel;
    sum.pieces_per_100k += one.pieces_per_100k;
    sum.specks += one.specks;
    sum.specks_per_100k += one.specks_per_100k;
}

/// The mean of a phase's figures summed over `tiles` tiles, its correlation lengths from
/// the mean two-point probability, which is then cut to [`MAX_LAG`].
fn finished(mut p: Phase, tiles: usize) -> Phase {
    let n = tiles as f64;
    p.share /= n;
    for a in 0..3 {
        p.two_point[a].iter_mut().chain(&mut p.lineal_path[a]).for_each(|v| *v /= n);
        p.interface_per_axis[a] /= n;
    }
    p.interface_per_voxel /= n;
    p.isotropic_surface = p.interface_per_voxel * 2.0 / 3.0;
    p.pieces_per_100k /= n;
    p.specks_per_100k /= n;
    p.correlation_length = [0, 1, 2].map(|a| correlation_length(&p.two_point[a], p.share));
    p.two_point.iter_mut().for_each(|v| v.truncate(MAX_LAG + 1));
    p
}

/// One phase's figures in one box, its two-point probability out to the correlation
/// length's lags and no correlation length yet ([`finished`] gives both).
fn phase(labels: &[f32], dims: [usize; 3], label: f32, piece_sizes: impl Iterator<Item = usize>) -> Phase {
    let indicator: Vec<f64> = labels.iter().map(|v| f64::from(u8::from(*v == label))).collect();
    let share = indicator.iter().sum::<f64>() / indicator.len() as f64;
    let lags = dims.map(|d| MAX_LAG.min(d.saturating_sub(1)));
    let correlation_lags = dims.map(|d| CORRELATION_LAG.min(d.saturating_sub(1)));
    let two_point = [0, 1, 2].map(|a| two_point(labels, label, dims, a, correlation_lags[a].max(lags[a])));
    let (mut count, mut specks) = (0usize, 0usize);
    for size in piece_sizes {
        count += 1;
        specks += usize::from(size <= 2);
    }
    let lineal_path = [0, 1, 2].map(|a| lineal(&indicator, dims, a, lags[a]));
    let voxels = indicator.len() as f64;
    let interface_per_axis = [0, 1, 2].map(|a| {
        let stride = [1, dims[0], dims[0] * dims[1]][a];
        let faces = (0..indicator.len())
            .filter(|&i| (i / stride) % dims[a] + 1 < dims[a] && indicator[i] != indicator[i + stride])
            .count();
        faces as f64 / voxels
    });
    let interface_per_voxel = interface_per_axis.iter().sum();
    Phase {
        label,
        share,
        two_point,
        lineal_path,
        interface_per_axis,
        interface_per_voxel,
        isotropic_surface: interface_per_voxel * 2.0 / 3.0,
        pieces_per_100k: count as f64 * 1e5 / voxels,
        specks,
        specks_per_100k: specks as f64 * 1e5 / voxels,
        correlation_length: [None; 3],
    }
}

/// `S2(r)` of the phase `label` along axis `a` for `r = 0..=max_lag`: each line along the
/// axis as a row of bits, the pairs `r` apart counted by shifting the row onto itself.
fn two_point(labels: &[f32], label: f32, dims: [usize; 3], a: usize, max_lag: usize) -> Vec<f64> {
    let side = dims[a];
    let words = side.div_ceil(64);
    let stride = [1, dims[0], dims[0] * dims[1]][a];
    let lines = labels.len() / side;
    let mut bits = vec![0u64; lines * words];
    for (line, start) in (0..labels.len()).filter(|&i| (i / stride).is_multiple_of(side)).enumerate() {
        for k in 0..side {
            if labels[start + k * stride] == label {
                bits[line * words + k / 64] |= 1 << (k % 64);
            }
        }
    }
    (0..=max_lag)
        .map(|r| {
            let pairs: u64 = bits.chunks_exact(words).map(|row| overlap(row, r)).sum();
            pairs as f64 / (lines * (side - r)).max(1) as f64
        })
        .collect()
}

/// How many bits `k` of `row` have bit `k + r` set too.
fn overlap(row: &[u64], r: usize) -> u64 {
    let (q, s) = (r / 64, r % 64);
    (0..row.len())
        .map(|w| {
            let high = row.get(w + q).copied().unwrap_or(0);
            let next = row.get(w + q + 1).copied().unwrap_or(0);
            let shifted = if s == 0 { high } else { (high >> s) | (next << (64 - s)) };
            u64::from((row[w] & shifted).count_ones())
        })
        .sum()
}

/// The first lag at which `(S2(r) - phi^2) / (phi - phi^2)` falls to 1/e, linearly
/// interpolated between the lags around it.
fn correlation_length(s2: &[f64], phi: f64) -> Option<f64> {
    let variance = phi - phi * phi;
    if variance <= 0.0 {
        return None;
    }
    let c: Vec<f64> = s2.iter().map(|v| (v - phi * phi) / variance).collect();
    let r = c.iter().position(|v| *v <= (-1.0f64).exp())?;
    if r == 0 {
        return Some(0.0);
    }
    Some(crate::correlation::e_folding(r, c[r - 1], c[r]))
}

/// The face-connected pieces of equal labels (no wrapping): `(label, voxels)` each.
fn pieces(labels: &[f32], dims: [usize; 3]) -> Vec<(f32, usize)> {
    let [nx, ny, nz] = dims;
    let mut seen = vec![false; labels.len()];
    let mut stack = Vec::new();
    let mut found = Vec::new();
    for start in 0..labels.len() {
        if seen[start] {
            continue;
        }
        let label = labels[start];
        seen[start] = true;
        stack.push(start);
        let mut size = 0;
        while let Some(i) = stack.pop() {
            size += 1;
            let (x, y, z) = (i % nx, (i / nx) % ny, i / (nx * ny));
            let steps = [
                (x > 0, i.wrapping_sub(1)),
                (x + 1 < nx, i + 1),
                (y > 0, i.wrapping_sub(nx)),
                (y + 1 < ny, i + nx),
                (z > 0, i.wrapping_sub(nx * ny)),
                (z + 1 < nz, i + nx * ny),
            ];
            for (inside, j) in steps {
                if inside && !seen[j] && labels[j] == label {
                    seen[j] = true;
                    stack.push(j);
                }
            }
        }
        found.push((label, size));
    }
    found
}

/// `L(r)` along axis `a`: windows of `r + 1` voxels wholly in the phase over all windows,
/// counted from the runs of the phase along every line.
fn lineal(indicator: &[f64], dims: [usize; 3], a: usize, max_lag: usize) -> Vec<f64> {
    let stride = [1, dims[0], dims[0] * dims[1]][a];
    let mut inside = vec![0u64; max_lag + 1];
    let lines = indicator.len() / dims[a];
    for start in (0..indicator.len()).filter(|&i| (i / stride).is_multiple_of(dims[a])) {
        let mut run = 0usize;
        for k in 0..=dims[a] {
            let on = k < dims[a] && indicator[start + k * stride] > 0.5;
            if on {
                run += 1;
                continue;
            }
            for (r, count) in inside.iter_mut().enumerate().take(run) {
                *count += (run - r) as u64;
            }
            run = 0;
        }
    }
    (0..=max_lag).map(|r| inside[r] as f64 / (lines * (dims[a] - r)) as f64).collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::volume::{Axis, Channel};

    fn labels(dims: [usize; 3], f: impl Fn(usize, usize, usize) -> f32) -> Volume {
        Volume::from_fn(dims, Channel::grey(), |x, y, z, o| o[0] = f(x, y, z)).unwrap()
    }

    /// A 3D checkerboard of single voxels: half each phase, S2 = 1/2 at even lags and 0 at
    /// odd ones, no segment of two voxels in one phase, three faces per voxel.
    #[test]
    fn a_checkerboard_has_the_textbook_figures() {
        let stats = measure(&labels([8, 8, 8], |x, y, z| ((x + y + z) % 2) as f32)).unwrap();
        assert_eq!(stats.phases.len(), 2);
        let p = &stats.phases[1];
        assert_eq!(p.share, 0.5);
        for a in 0..3 {
            assert_eq!(&p.two_point[a][..4], &[0.5, 0.0, 0.5, 0.0]);
            assert_eq!(&p.lineal_path[a][..3], &[0.5, 0.0, 0.0]);
        }
        // faces inside the 8-voxel lines: 7 per line of 8, per axis
        assert!((p.interface_per_voxel - 3.0 * 7.0 / 8.0).abs() < 1e-12, "{}", p.interface_per_voxel);
    }

    /// Slabs 4 voxels thick stacked along z: along x and y everything stays in the phase;
    /// along z, S2 and L fall linearly over the slab's thickness.
    #[test]
    fn parallel_slabs_have_their_known_profiles() {
        let stats = measure(&labels([6, 5, 16], |_, _, z| ((z / 4) % 2) as f32)).unwrap();
        let p = &stats.phases[0];
        assert_eq!(p.share, 0.5);
        assert!(p.two_point[0].iter().chain(&p.lineal_path[1]).all(|v| *v == 0.5));
        let z = &p.two_point[2];
        // S2 along z: pairs in one slab; r = 4 pairs each voxel with the other phase
        assert_eq!(z[0], 0.5);
        assert_eq!(z[4], 0.0);
        assert_eq!(z[8], 0.5);
        let l = &p.lineal_path[2];
        // 2 slabs of 4 in 16 voxels: windows of r + 1 voxels inside = 2 * (4 - r) of 16 - r
        for (r, value) in l.iter().enumerate().take(5) {
            assert!((value - 2.0 * (4 - r) as f64 / (16 - r) as f64).abs() < 1e-12, "L({r}) = {value}");
        }
        assert_eq!(p.interface_per_axis[..2], [0.0, 0.0]);
        assert!((p.interface_per_axis[2] - 3.0 / 16.0).abs() < 1e-12, "3 interfaces in 16 layers");
    }

    /// Pieces are face-connected: the checkerboard's voxels are all single specks, the
    /// slabs are whole pieces; correlation lengths follow the textbook profiles.
    #[test]
    fn pieces_specks_and_correlation_lengths() {
        let board = measure(&labels([8, 8, 8], |x, y, z| ((x + y + z) % 2) as f32)).unwrap();
        let p = &board.phases[1];
        assert_eq!((p.pieces_per_100k, p.specks), (256.0 * 1e5 / 512.0, 256));
        // C(0) = 1, C(1) = -1: 1/e is crossed at (1 - 1/e) / 2 of the first lag
        let expected = (1.0 - (-1.0f64).exp()) / 2.0;
        assert!(p.correlation_length.iter().all(|c| (c.unwrap() - expected).abs() < 1e-12), "{p:?}");
        let slabs = measure(&labels([6, 5, 16], |_, _, z| ((z / 4) % 2) as f32)).unwrap();
        let p = &slabs.phases[0];
        assert_eq!((p.pieces_per_100k, p.specks), (2.0 * 1e5 / 480.0, 0));
        assert_eq!(p.correlation_length[..2], [None, None], "along x and y nothing decorrelates");
        let z = p.correlation_length[2].unwrap();
        assert!(z > 1.0 && z < 4.0, "slabs 4 voxels thick decorrelate within a slab: {z}");
    }

    /// A blended copy of the truth snaps back to it: every ratio is 1; a volume of specks
    /// has many times the truth's pieces and a shorter correlation.
    #[test]
    fn a_volume_is_snapped_to_the_truths_labels_and_compared() {
        let truth = labels([8, 8, 16], |_, _, z| ((z / 4) % 2) as f32);
        let blended = labels([8, 8, 16], |x, _, z| ((z / 4) % 2) as f32 * 0.9 + 0.05 * (x % 2) as f32);
        let same = against_truth(&blended, &truth).unwrap();
        for r in &same.ratios {
            assert_eq!((r.share_ratio, r.pieces_ratio), (1.0, 1.0), "{r:?}");
            assert_eq!(r.correlation_ratio[2], Some(1.0));
        }
        let specks = labels([8, 8, 16], |x, y, z| ((x + y + z) % 2) as f32);
        let bad = against_truth(&specks, &truth).unwrap();
        assert!(bad.ratios[0].pieces_ratio > 50.0, "{:?}", bad.ratios[0]);
        assert!(bad.ratios[0].correlation_ratio[2].unwrap() < 0.5, "{:?}", bad.ratios[0]);
    }

    /// A truth twice the volume's side is measured in tiles of the volume's size: a crop of
    /// a truth whose blocks repeat every 8 voxels (and cross the tiles' faces) scores 1 on
    /// every figure, though the whole truth joins the blocks a face cuts (fewer pieces per
    /// voxel); lone voxels the truth lacks fail as specks.
    #[test]
    fn a_larger_truth_is_measured_in_tiles_of_the_volumes_size() {
        let block = |x: usize, y: usize, z: usize| f32::from(u8::from([x, y, z].iter().all(|c| (c + 2) % 8 < 4)));
        let truth = labels([32; 3], block);
        let crop = labels([16; 3], block);
        let whole = measure(&truth).unwrap().phases[1].pieces_per_100k;
        assert!(whole < measure(&crop).unwrap().phases[1].pieces_per_100k, "the whole truth joins cut blocks");
        let same = against_truth(&crop, &truth).unwrap();
        assert_eq!((same.truth.tiles, same.truth.tile, same.volume.tiles), (8, [16; 3], 1));
        for r in &same.ratios {
            let figures = [r.share_ratio, r.pieces_ratio, r.extra_specks_per_100k + 1.0].into_iter();
            let lengths = r.correlation_ratio.iter().flatten().copied();
            assert!(figures.chain(lengths).all(|f| (f - 1.0).abs() < 1e-9), "{r:?}");
        }
        assert!(same.outside_bands().is_empty(), "{:?}", same.outside_bands());
        let lone = [(12, 4, 4), (4, 12, 12), (12, 12, 4)];
        let specked = labels([16; 3], |x, y, z| if lone.contains(&(x, y, z)) { 1.0 } else { block(x, y, z) });
        let bad = against_truth(&specked, &truth).unwrap();
        assert!((bad.ratios[1].extra_specks_per_100k - 3e5 / 4096.0).abs() < 1e-9, "{:?}", bad.ratios[1]);
        assert!(bad.outside_bands().iter().any(|o| o.contains("pieces of 1-2 voxels")), "{:?}", bad.outside_bands());
    }

    /// A truth of one label, or volumes too small to measure, are refused, naming why.
    #[test]
    fn a_truth_of_one_phase_or_a_tiny_box_is_refused() {
        let truth = labels([16; 3], |x, _, _| (x / 4 % 2) as f32);
        let flat = labels([16; 3], |_, _, _| 0.5);
        let error = against_truth(&truth, &flat).unwrap_err().to_string();
        assert!(error.contains("one label (0.5)") && error.contains("at least two phases"), "{error}");
        let tiny = labels([16, 16, 4], |x, _, _| (x / 4 % 2) as f32);
        let error = against_truth(&tiny, &truth).unwrap_err().to_string();
        assert!(error.contains("16x16x4") && error.contains("at least 8 voxels"), "{error}");
        assert!(against_truth(&truth, &truth).is_ok());
    }

    /// Counting pairs with shifted rows of bits gives the plain sum of products, also on
    /// lines longer than one 64-bit word and lags past a word.
    #[test]
    fn bit_rows_count_the_same_pairs_as_products() {
        let dims = [150, 3, 70];
        let v = labels(dims, |x, y, z| (crate::noise::mix64((x + 150 * (y + 3 * z)) as u64) % 3) as f32);
        let values = first_channel(&v);
        let indicator: Vec<f64> = values.iter().map(|l| f64::from(u8::from(*l == 1.0))).collect();
        for a in [0, 2] {
            let plain = crate::correlation::lagged_products(&indicator, dims, Axis::ALL[a], None, 69);
            let bits = two_point(&values, 1.0, dims, a, 69);
            for (r, ((sum, count), s2)) in plain.iter().zip(&bits).enumerate() {
                assert!((sum / *count as f64 - s2).abs() < 1e-12, "axis {a} lag {r}");
            }
        }
    }

    #[test]
    fn a_grey_photo_is_not_a_label_volume() {
        let err = measure(&labels([8, 8, 1], |x, y, _| (x * 8 + y) as f32)).unwrap_err().to_string();
        assert!(err.contains("more than 16 distinct values"), "{err}");
    }
}
