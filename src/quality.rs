//! How good is a solid texture? Measurements that read as ratios against baselines.
//!
//! - **Slice energy** per axis (Kopf's energy): for sampled voxels, the distance from the
//!   voxel's 8x8 slice neighbourhood to its nearest exemplar neighbourhood, as RMS per
//!   sample raised to r = 0.8, averaged. Shown beside two baselines on the same scale: a
//!   volume of random exemplar pixels (what synthesis starts from) and the exemplar against
//!   itself (neighbourhoods of its left half matched in its right half). An exemplar that
//!   repeats itself (a photo made by tiling or cloning one patch) would make that baseline
//!   a copy, not unseen texture: offsets at which most neighbourhoods find themselves again
//!   are detected, and the baseline skips those copies (the plain figure is kept too).
//! - **Sharpness** per axis ([`crate::sharpness`]): gradient and autocorrelation-length
//!   ratios of the cuts against the exemplar, and the distance of their gradient histograms.
//!   Slice energy alone rewards blur (a flat volume scores well); these fail it.
//! - **Histogram distance** per channel: L1 between 32-bin histograms (0 = equal, 2 = disjoint).
//! - For layered volumes: **depth error** (mean |Depth - z / (Z - 1)|), whether the mean depth
//!   rises monotonically along z, and the **sweeping index**: the share of voxels whose best x
//!   and y matches point to the same exemplar pixel.

use crate::error::{Error, Result};
use crate::noise::mix64;
use crate::synth::exemplar::{PrepareOptions, Prepared};
use crate::volume::{Axis, Channel, Image2d, Volume};
use serde::Serialize;

/// Neighbourhood side of the measurements.
pub const N: usize = 8;
/// The least exemplar side `quality` measures: the slice energy's neighbourhoods and a pixel
/// of margin each side (the sharpness and line figures need less).
pub const LEAST_EXEMPLAR: usize = N + 2;
/// The smallest cut, in voxels each way, the per-axis figures are measured on: the slice
/// energy's N x N neighbourhood (on a smaller cut it wraps onto itself), which also holds
/// the line measures' 5x5 element and the gradients' 3x3 stencil.
pub const SMALLEST_CUT: usize = N;
/// Robust exponent of Kopf's energy.
pub const R: f64 = 0.8;
/// Histogram bins.
pub const BINS: usize = 32;
/// Voxels sampled per axis.
pub const SAMPLES: usize = 2000;
/// Candidates kept from the PCA search before exact re-ranking.
const SHORTLIST: usize = 8;
/// Neighbourhoods sampled to find where an exemplar repeats itself.
const REPEAT_SAMPLES: usize = 200;

/// Slice energy of one axis with its baselines.
#[derive(Debug, Clone, Serialize)]
pub struct AxisEnergy {
    /// `x`, `y` or `z`.
    pub axis: String,
    /// Energy of the volume's slices.
    pub volume: f64,
    /// Energy of a random-pixel volume.
    pub random: f64,
    /// Energy of the exemplar against itself (split halves).
    pub exemplar: f64,
    /// `volume / exemplar`: 1 means as good as unseen parts of the exemplar itself.
    pub ratio: f64,
    /// The split-half energy with the exemplar's repeated copies allowed (present only
    /// when the exemplar repeats itself; `exemplar` then skips the copies).
    pub exemplar_with_copies: Option<f64>,
    /// Offsets (x, y) in exemplar pixels at which the exemplar repeats itself.
    pub repeats: Vec<[i64; 2]>,
}

/// Histogram distance of one channel.
#[derive(Debug, Clone, Serialize)]
pub struct HistogramDistance {
    /// Channel name.
    pub channel: String,
    /// L1 distance between the normalized histograms.
    pub distance: f64,
}

/// Measurements specific to layered volumes.
#[derive(Debug, Clone, Serialize)]
pub struct LayeredQuality {
    /// Mean |Depth - z / (Z - 1)|.
    pub depth_error: f64,
    /// Mean depth per z-slice never decreases.
    pub depth_monotonic: bool,
    /// The largest fall of the mean depth from one z-slice to the next (0 when monotonic);
    /// compare with the step between ideal slice depths, 1 / (Z - 1).
    pub depth_largest_drop: f64,
    /// Share of voxels whose x and y best matches are the same exemplar pixel.
    pub sweeping_index: f64,
}

/// A quality report.
#[derive(Debug, Clone, Serialize)]
pub struct Report {
    /// One entry per measured axis.
    pub axes: Vec<AxisEnergy>,
    /// Sharpness and feature size per measured axis (see [`crate::sharpness`]).
    pub sharpness: Vec<crate::sharpness::AxisSharpness>,
    /// Line structure per measured axis (see [`crate::lines`]).
    pub lines: Vec<crate::lines::Lines>,
    /// One entry per exemplar channel.
    pub histograms: Vec<HistogramDistance>,
    /// For layered volumes.
    pub layered: Option<LayeredQuality>,
    /// How coherently the volume copies its exemplars, as the coordinate core recorded it
    /// in the volume's provenance ([`crate::synth::patches`]); `None` for other volumes.
    pub patches: Option<crate::synth::patches::Patches>,
    /// The axes given an exemplar whose cuts are smaller than [`SMALLEST_CUT`]: their slice
    /// energy, sharpness and line figures are not measured.
    pub not_measured: Vec<String>,
}

/// Whether the cuts across `axis` of a volume of `dims` are large enough to measure
/// (at least [`SMALLEST_CUT`] voxels each way).
pub fn measurable(dims: [usize; 3], axis: Axis) -> bool {
    let (a, b) = axis.plane_axes();
    dims[a] >= SMALLEST_CUT && dims[b] >= SMALLEST_CUT
}

/// Measure `volume` against its exemplars: one per axis (`None`: not measured).
/// For a layered volume pass the exemplar for x and y and `layered = true`.
pub fn assess(volume: &Volume, exemplars: [Option<&Image2d>; 3], layered: bool) -> Result<Report> {
    let first = exemplars.iter().flatten().next().ok_or_else(|| Error::invalid("no exemplar to measure against"))?;
    if let Some(other) = exemplars.iter().flatten().find(|e| e.channels() != first.channels()) {
        return Err(Error::invalid(format!(
            "the exemplars have channels {} and {}; all exemplars need the same channels",
            crate::volume::channel_names(first.channels()),
            crate::volume::channel_names(other.channels())
        )));
    }
    let picks = channel_positions(volume, first.channels())?;
    let given: Vec<Axis> = Axis::ALL.into_iter().filter(|a| exemplars[a.index()].is_some()).collect();
    let dims = volume.dims();
    if !given.iter().any(|&a| measurable(dims, a)) {
        let [x, y, z] = dims;
        let names: Vec<String> = given.iter().map(Axis::to_string).collect();
        return Err(Error::invalid(format!(
            "the volume is {x}x{y}x{z} voxels: no cut across {} is at least {s}x{s} voxels, the smallest the \
             figures are measured on; measure a volume with two sides of at least {s}",
            listed(&names, "or"),
            s = SMALLEST_CUT
        )));
    }
    let mut axes = Vec::new();
    let mut sharpness = Vec::new();
    let mut lines = Vec::new();
    let mut not_measured = Vec::new();
    let mut best = [Vec::new(), Vec::new(), Vec::new()];
    for axis in Axis::ALL {
        let Some(image) = exemplars[axis.index()] else { continue };
        if !measurable(dims, axis) {
            not_measured.push(axis.to_string());
            continue;
        }
        sharpness.push(crate::sharpness::measure(volume, image, &picks, axis)?);
        lines.push(crate::lines::measure(volume, image, &picks, axis)?);
        let measure = Measure::new(image, volume, &picks, layered)?;
        let (energy, matches) = measure.volume_energy(volume, axis);
        let random = measure.random_energy();
        let repeats = measure.repeats();
        let exemplar = measure.split_half_energy(&repeats);
        let with_copies = (!repeats.is_empty()).then(|| measure.split_half_energy(&[]));
        axes.push(AxisEnergy {
            axis: axis.to_string(),
            volume: energy,
            random,
            exemplar,
            ratio: energy / exemplar.max(1e-12),
            exemplar_with_copies: with_copies,
            repeats,
        });
        best[axis.index()] = matches;
    }
    let histograms = histogram_distances(volume, first, &picks);
    let layered = layered.then(|| layered_quality(volume, &best)).transpose()?;
    let patches = crate::synth::patches::Patches::of_meta(&volume.meta);
    Ok(Report { axes, sharpness, lines, histograms, layered, patches, not_measured })
}

/// `x`, `x or y`, `x, y or z` (with `and`: `x and y`).
pub fn listed(names: &[String], word: &str) -> String {
    match names {
        [] => String::new(),
        [one] => one.clone(),
        [rest @ .., last] => format!("{} {word} {last}", rest.join(", ")),
    }
}

/// The figures a designer reads at a glance (the cheap part of [`assess`]): per axis the
/// gradient and autocorrelation-length ratios of the cuts against the exemplar, and the
/// largest histogram distance over the exemplar's channels.
#[derive(Debug, Clone, PartialEq, Serialize, serde::Deserialize)]
pub struct Glance {
    /// `[axis, gradient ratio, length ratio]` per measured axis (axis 0, 1, 2 = x, y, z).
    pub axes: Vec<(usize, f64, f64)>,
    /// The largest histogram distance over the channels (0 = equal, 2 = disjoint).
    pub histogram: f64,
}

/// The largest histogram distance a synthesized volume should show (per channel).
pub const HISTOGRAM_TARGET: f64 = 0.05;
/// The largest slice-energy ratio (volume over the exemplar's split halves).
pub const ENERGY_TARGET: f64 = 1.5;

impl Report {
    /// Every figure outside its documented band (docs/synthesis.md, "Checking a volume"),
    /// named with its value and the band. Figures without an exemplar baseline (the
    /// layered depth and sweeping measures) are not checked.
    pub fn outside_bands(&self) -> Vec<String> {
        use crate::sharpness::{GRADIENT_RANGE as G, LENGTH_RANGE as L, within};
        let mut out = Vec::new();
        for a in self.axes.iter().filter(|a| !within(a.ratio, (0.0, ENERGY_TARGET))) {
            out.push(format!("{} slice energy ratio {:.2} (allowed at most {ENERGY_TARGET})", a.axis, a.ratio));
        }
        for s in &self.sharpness {
            if !within(s.gradient_ratio, G) {
                out.push(format!("{} gradient ratio {:.2} (allowed {}-{})", s.axis, s.gradient_ratio, G.0, G.1));
            }
            if !within(s.length_ratio, L) {
                out.push(format!("{} length ratio {:.2} (allowed {}-{})", s.axis, s.length_ratio, L.0, L.1));
            }
        }
        out.extend(self.lines.iter().flat_map(crate::lines::Lines::outside_bands));
        use crate::synth::patches::LARGEST_PATCH_MOST as MOST;
        if let Some(p) = self.patches.filter(|p| p.largest > MOST) {
            out.push(format!(
                "largest coherent patch {:.3} of the exemplar's area (allowed at most {MOST})",
                p.largest
            ));
        }
        for h in self.histograms.iter().filter(|h| !within(h.distance, (0.0, HISTOGRAM_TARGET))) {
            out.push(format!(
                "{} histogram distance {:.3} (allowed at most {HISTOGRAM_TARGET})",
                h.channel, h.distance
            ));
        }
        out
    }
}

impl Glance {
    /// Whether every ratio lies in its target range and the histograms are close (never
    /// for a volume too small to measure any cut of).
    pub fn in_range(&self) -> bool {
        use crate::sharpness::{GRADIENT_RANGE, LENGTH_RANGE, within};
        !self.axes.is_empty()
            && self.axes.iter().all(|&(_, g, l)| within(g, GRADIENT_RANGE) && within(l, LENGTH_RANGE))
            && within(self.histogram, (0.0, HISTOGRAM_TARGET))
    }

    /// One word for the list: `ok`, or the first thing wrong (`blurred`, `noisy`, `coarse`
    /// features larger than the photo's, `fine` smaller, `colours` off), or `small` when no
    /// cut is large enough to measure ([`SMALLEST_CUT`]).
    pub fn verdict(&self) -> &'static str {
        let (g, l) = (crate::sharpness::GRADIENT_RANGE, crate::sharpness::LENGTH_RANGE);
        let any = |f: &dyn Fn(&(usize, f64, f64)) -> bool| self.axes.iter().any(f);
        if self.axes.is_empty() {
            "small"
        } else if any(&|a| a.1 < g.0) {
            "blurred"
        } else if any(&|a| a.1 > g.1) {
            "noisy"
        } else if any(&|a| a.2 > l.1) {
            "coarse"
        } else if any(&|a| a.2 < l.0) {
            "fine"
        } else if self.histogram > HISTOGRAM_TARGET {
            "colours"
        } else {
            "ok"
        }
    }

    /// One line: `sharp 0.91-1.02  size 0.95-1.10  hist 0.08` (lowest-highest over the axes).
    pub fn summary(&self) -> String {
        if self.axes.is_empty() {
            return format!("cuts under {SMALLEST_CUT} voxels, not measured  hist {:.2}", self.histogram);
        }
        let span = |f: fn(&(usize, f64, f64)) -> f64| {
            let v: Vec<f64> = self.axes.iter().map(f).collect();
            let (lo, hi) = v.iter().fold((f64::MAX, f64::MIN), |(a, b), x| (a.min(*x), b.max(*x)));
            if (hi - lo) < 0.005 { format!("{lo:.2}") } else { format!("{lo:.2}-{hi:.2}") }
        };
        format!("sharp {}  size {}  hist {:.2}", span(|a| a.1), span(|a| a.2), self.histogram)
    }
}

/// [`Glance`] of `volume` against its exemplars (one per axis, `None`: not measured).
pub fn glance(volume: &Volume, exemplars: [Option<&Image2d>; 3]) -> Result<Glance> {
    let first = exemplars.iter().flatten().next().ok_or_else(|| Error::invalid("no exemplar to measure against"))?;
    let picks = channel_positions(volume, first.channels())?;
    let mut axes = Vec::new();
    for axis in Axis::ALL {
        let Some(image) = exemplars[axis.index()].filter(|_| measurable(volume.dims(), axis)) else { continue };
        let s = crate::sharpness::measure(volume, image, &picks, axis)?;
        axes.push((axis.index(), s.gradient_ratio, s.length_ratio));
    }
    let histogram = histogram_distances(volume, first, &picks).iter().map(|h| h.distance).fold(0.0, f64::max);
    Ok(Glance { axes, histogram })
}

/// Positions in the volume of the exemplar's channels.
fn channel_positions(volume: &Volume, channels: &[Channel]) -> Result<Vec<usize>> {
    channels
        .iter()
        .map(|c| {
            volume.channel_index(c).ok_or_else(|| {
                Error::invalid(format!(
                    "the volume has no channel {c} (it has {}), which the exemplar has",
                    crate::volume::channel_names(volume.channels())
                ))
            })
        })
        .collect()
}

/// One exemplar prepared for exact nearest-neighbourhood queries.
struct Measure<'a> {
    ex: Prepared,
    picks: &'a [usize],
    clamp_z: bool,
    dims: [usize; 3],
}

impl<'a> Measure<'a> {
    fn new(image: &Image2d, volume: &Volume, picks: &'a [usize], clamp_z: bool) -> Result<Measure<'a>> {
        if image.width() < LEAST_EXEMPLAR || image.height() < LEAST_EXEMPLAR {
            return Err(Error::invalid(format!(
                "the exemplar is {}x{}; measuring needs at least {LEAST_EXEMPLAR}x{LEAST_EXEMPLAR}",
                image.width(),
                image.height()
            )));
        }
        let weights = vec![1.0; image.channel_count()];
        let ex = Prepared::new(image, &weights, PrepareOptions { n: N, variance: 0.99, max_dims: 32, k: 0 });
        Ok(Measure { ex, picks, clamp_z, dims: volume.dims() })
    }

    /// Energy of one neighbourhood vector and its nearest exemplar centre pixel.
    fn nearest(&self, q: &[f32], exclude: impl Fn(u32) -> bool) -> (f64, u32) {
        let mut proj = vec![0.0; self.ex.pca.dims];
        self.ex.pca.project(q, &mut proj);
        let mut short: Vec<(f32, usize)> = Vec::with_capacity(SHORTLIST + 1);
        for (slot, &c) in self.ex.centres.iter().enumerate() {
            if exclude(c) {
                continue;
            }
            let d = crate::synth::exemplar::squared(&proj, self.ex.projection(slot));
            if short.len() < SHORTLIST || d < short[short.len() - 1].0 {
                let at = short.partition_point(|e| e.0 <= d);
                short.insert(at, (d, slot));
                short.truncate(SHORTLIST);
            }
        }
        let mut buf = Vec::with_capacity(q.len());
        let exact = short.iter().map(|&(_, slot)| {
            let c = self.ex.centres[slot] as usize;
            buf.clear();
            self.ex.vector(c % self.ex.width, c / self.ex.width, &mut buf);
            (crate::synth::exemplar::squared(q, &buf), c as u32)
        });
        let (d, pixel) =
            exact.fold((f32::INFINITY, 0), |b, e| if e.0 < b.0 || (e.0 == b.0 && e.1 < b.1) { e } else { b });
        (((d as f64) / q.len() as f64).sqrt().powf(R), pixel)
    }

    /// Mean energy of sampled voxels' slice neighbourhoods across `axis`, and their matches.
    fn volume_energy(&self, volume: &Volume, axis: Axis) -> (f64, Vec<(usize, u32)>) {
        let count = volume.voxel_count();
        let mut q = Vec::new();
        let mut sum = 0.0;
        let mut matches = Vec::new();
        for i in 0..SAMPLES.min(count) {
            let v = (mix64(i as u64 ^ 0x5eed) % count as u64) as usize;
            self.gather(volume, axis, crate::volume::unindex(self.dims, v), &mut q);
            let (e, pixel) = self.nearest(&q, |_| false);
            sum += e;
            matches.push((v, pixel));
        }
        (sum / matches.len().max(1) as f64, matches)
    }

    /// The unweighted neighbourhood of voxel `v` across `axis` (exemplar channels only).
    fn gather(&self, volume: &Volume, axis: Axis, v: [usize; 3], out: &mut Vec<f32>) {
        let (a, b) = axis.plane_axes();
        let h = (N / 2) as i64;
        out.clear();
        for dy in 0..N as i64 {
            for dx in 0..N as i64 {
                let mut p = [v[0] as i64, v[1] as i64, v[2] as i64];
                p[a] += dx - h;
                p[b] += dy - h;
                let fold = |k: usize| {
                    let len = self.dims[k] as i64;
                    if k == 2 && self.clamp_z { p[k].clamp(0, len - 1) as usize } else { p[k].rem_euclid(len) as usize }
                };
                let voxel = volume.voxel(fold(0), fold(1), fold(2));
                out.extend(self.picks.iter().map(|&c| voxel[c]));
            }
        }
    }

    /// Energy of neighbourhoods made of independent random exemplar pixels.
    fn random_energy(&self) -> f64 {
        let pixels = self.ex.width * self.ex.height;
        let c_n = self.ex.channels;
        let mut q = Vec::with_capacity(N * N * c_n);
        let samples = SAMPLES / 4;
        let mut sum = 0.0;
        for i in 0..samples {
            q.clear();
            for j in 0..N * N {
                let p = (mix64((i * N * N + j) as u64 ^ 0xabcd) % pixels as u64) as usize;
                q.extend_from_slice(&self.ex.colours[p * c_n..(p + 1) * c_n]);
            }
            sum += self.nearest(&q, |_| false).0;
        }
        sum / samples as f64
    }

    /// Offsets (one sign of each) at which at least an eighth of sampled neighbourhoods find their nearest
    /// other neighbourhood (within a pixel): the exemplar repeats itself there. Offsets just
    /// past the excluded square around the query are not repeats: a texture uniform along
    /// one direction finds itself there.
    fn repeats(&self) -> Vec<[i64; 2]> {
        let at = |p: u32| pixel_xy(p, self.ex.width);
        let count = REPEAT_SAMPLES.min(self.ex.centres.len());
        let mut q = Vec::new();
        let offsets: Vec<[i64; 2]> = (0..count)
            .map(|i| {
                let c = self.ex.centres[(mix64(i as u64 ^ 0x7e9e) % self.ex.centres.len() as u64) as usize];
                let (cx, cy) = at(c);
                q.clear();
                self.ex.vector(cx as usize, cy as usize, &mut q);
                let (_, p) = self.nearest(&q, |p| {
                    let (px, py) = at(p);
                    (px - cx).abs().max((py - cy).abs()) < N as i64
                });
                let (px, py) = at(p);
                [px - cx, py - cy]
            })
            .collect();
        let support =
            |o: &[i64; 2]| offsets.iter().filter(|p| (p[0] - o[0]).abs().max((p[1] - o[1]).abs()) <= 1).count();
        let mut found: Vec<([i64; 2], usize)> = Vec::new();
        for o in &offsets {
            let s = support(o);
            let seen = |f: &[i64; 2]| {
                let close = |sx: i64, sy: i64| (f[0] - sx).abs().max((f[1] - sy).abs()) <= 1;
                close(o[0], o[1]) || close(-o[0], -o[1])
            };
            let beyond = o[0].abs().max(o[1].abs()) > N as i64 + 1;
            if 8 * s < count || !beyond || found.iter().any(|(f, _)| seen(f)) {
                continue;
            }
            found.push((*o, s));
        }
        found.sort_by(|a, b| b.1.cmp(&a.1).then(a.0.cmp(&b.0)));
        found.into_iter().map(|(o, _)| o).collect()
    }

    /// Energy of left-half exemplar neighbourhoods matched only in the right half, away
    /// from the copies of the query at the `repeats` offsets (either sign).
    fn split_half_energy(&self, repeats: &[[i64; 2]]) -> f64 {
        let (w, n) = (self.ex.width, N);
        let middle = w / 2;
        let copy = |q: u32, p: u32| {
            let ((qx, qy), (px, py)) = (pixel_xy(q, w), pixel_xy(p, w));
            let (dx, dy) = (px - qx, py - qy);
            repeats.iter().any(|o| {
                let near = |sx: i64, sy: i64| (dx - sx).abs().max((dy - sy).abs()) < (n / 2) as i64;
                near(o[0], o[1]) || near(-o[0], -o[1])
            })
        };
        let left: Vec<u32> = self.ex.centres.iter().copied().filter(|c| (*c as usize % w) + n / 2 <= middle).collect();
        let mut q = Vec::new();
        let samples = (SAMPLES / 2).min(left.len());
        let mut sum = 0.0;
        for i in 0..samples {
            let c = left[(mix64(i as u64 ^ 0x1234) % left.len() as u64) as usize] as usize;
            q.clear();
            self.ex.vector(c % w, c / w, &mut q);
            sum += self.nearest(&q, |p| (p as usize % w) < middle + n / 2 || copy(c as u32, p)).0;
        }
        sum / samples.max(1) as f64
    }
}

/// Column and row of a pixel index.
fn pixel_xy(p: u32, width: usize) -> (i64, i64) {
    (p as i64 % width as i64, p as i64 / width as i64)
}

fn histogram_distances(volume: &Volume, exemplar: &Image2d, picks: &[usize]) -> Vec<HistogramDistance> {
    let (n_v, n_e) = (volume.channel_count(), exemplar.channel_count());
    picks
        .iter()
        .enumerate()
        .map(|(e, &v)| {
            let a = histogram(volume.data().iter().skip(v).step_by(n_v));
            let b = histogram(exemplar.data().iter().skip(e).step_by(n_e));
            let distance = a.iter().zip(&b).map(|(x, y)| (x - y).abs()).sum();
            HistogramDistance { channel: exemplar.channels()[e].to_string(), distance }
        })
        .collect()
}

/// The normalized [`BINS`]-bin histogram of values in [0, 1] (outside values clamped).
pub(crate) fn histogram<'a>(values: impl Iterator<Item = &'a f32>) -> Vec<f64> {
    let mut h = vec![0.0; BINS];
    let mut total = 0.0;
    for v in values {
        h[((v.clamp(0.0, 1.0) * BINS as f32) as usize).min(BINS - 1)] += 1.0;
        total += 1.0;
    }
    h.iter().map(|c| c / f64::max(total, 1.0)).collect()
}

fn layered_quality(volume: &Volume, best: &[Vec<(usize, u32)>; 3]) -> Result<LayeredQuality> {
    let depth = volume
        .channel_index(&Channel::Depth)
        .ok_or_else(|| Error::invalid("a layered volume needs a Depth channel"))?;
    let [dx, dy, dz] = volume.dims();
    let means: Vec<f64> = (0..dz)
        .map(|z| {
            let sum: f64 = (0..dy)
                .flat_map(|y| (0..dx).map(move |x| (x, y)))
                .map(|(x, y)| volume.get(x, y, z, depth) as f64)
                .sum();
            sum / (dx * dy) as f64
        })
        .collect();
    let same = best[0].iter().zip(&best[1]).filter(|(a, b)| a.1 == b.1).count();
    Ok(LayeredQuality {
        depth_error: crate::synth::depth_error(volume).unwrap_or(0.0),
        depth_monotonic: means.windows(2).all(|w| w[1] >= w[0]),
        depth_largest_drop: means.windows(2).map(|w| w[0] - w[1]).fold(0.0, f64::max),
        sweeping_index: same as f64 / best[0].len().max(1) as f64,
    })
}
