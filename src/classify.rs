//! Estimate the LST type of a volume from measurements (thesis ch. 3).
//!
//! On the luminance of the volume (or its first channel):
//! - **layering** per axis, `w_i` = mean variance within slices orthogonal to i over the
//!   total variance; `1 - w_i` is the share the slices' means hold. An axis is a depth
//!   axis (the pattern varies along it) when its slices' means hold at least
//!   [`MIN_BETWEEN`] of the variance and [`STANDS_OUT`] times the share of every other
//!   axis (two depth axes: both, against the third). A Depth channel growing along an axis
//!   says where to look: that axis needs only [`HINTED_BETWEEN`] and
//!   [`HINTED_STANDS_OUT`] times (the look must still change along it).
//! - **variograms** per axis: half the mean squared difference of values 1, 2, 4 and 8
//!   voxels apart along the axis, over their variance: how fast the pattern changes along
//!   it at four scales. Two axes look alike when their variograms differ by less than a
//!   factor 1.8 at every lag (`ALIKE` in logarithms). Without a depth axis: one group of
//!   alike axes means anisotropy 0, two groups 1 (the odd axis is the primary axis), three
//!   groups 2. With a depth axis the variograms are taken within its slices, each slice
//!   less its mean and over its own variance (so seeds in one band do not drown the rays
//!   of the others): the two axes in the slices alike make 1-b (strata), unlike 2-b
//!   (kiwi, trunk: rays or fibres run one way in the slices).
//! - **gradient energy** per axis (the lag-1 variogram of the whole luminance, twice): the
//!   fill takes its axis order from it.
//!
//! Every type gets a score from how far the measurements would have to move to give it
//! ([`Nearest`]); the confidence is the estimate's share of the scores.

use crate::error::{Error, Result};
use crate::texture_type::TextureType;
use crate::volume::{Axis, Channel, Volume};
use serde::Serialize;

/// Log-variogram difference under which two axes look alike (a factor of 1.8).
pub const ALIKE: f64 = 0.59;
/// Smallest share of the variance a depth axis' slice means hold.
pub const MIN_BETWEEN: f64 = 0.3;
/// How many times every other axis' between-slice share a depth axis' share must be.
pub const STANDS_OUT: f64 = 5.0;
/// [`MIN_BETWEEN`] along the axis a Depth channel grows along.
pub const HINTED_BETWEEN: f64 = 0.1;
/// [`STANDS_OUT`] along the axis a Depth channel grows along.
pub const HINTED_STANDS_OUT: f64 = 2.0;
/// Lags, in voxels, at which each axis' variogram is measured.
pub const LAGS: [usize; 4] = [1, 2, 4, 8];
/// Cost (in threshold units) at which a type's score falls to 1/e of a cost-free one's.
pub const SCORE_SCALE: f64 = 0.25;
/// Confidence under which `classify` names the two nearest types.
pub const LOW_CONFIDENCE: f64 = 0.6;
/// Smallest side that can be classified.
pub const MIN_SIDE: usize = 8;

type Variograms = [[f64; LAGS.len()]; 3];

/// The estimate and the measurements that decided it.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Classification {
    /// The estimated type.
    #[serde(serialize_with = "type_name")]
    pub texture_type: TextureType,
    /// Anisotropy level measured (0, 1, 2) before clamping to a valid type.
    pub anisotropy: u8,
    /// Variation level measured (0..=3).
    pub variation: u8,
    /// The odd axis for anisotropy 1 (fibre or layer normal), the most distinct one for 2
    /// (with a depth axis: the axis in its slices the pattern runs on along longest).
    pub primary_axis: Option<String>,
    /// The axis the pattern varies along, if any.
    pub depth_axis: Option<String>,
    /// 0..1: the estimate's share of the types' scores.
    pub confidence: f64,
    /// The types by score, best first (scores sum to 1).
    pub nearest: Vec<Nearest>,
    /// Gradient energy over variance, per axis x, y, z.
    pub gradient_energy: [f64; 3],
    /// Within-slice variance share, per axis x, y, z (`within_slice_share` in JSON).
    #[serde(rename = "within_slice_share")]
    pub layering: [f64; 3],
    /// The share of the variance the slices' means hold, per axis x, y, z: one minus
    /// [`Classification::layering`], the figure a depth axis is read from.
    pub slice_means_share: [f64; 3],
    /// Per axis x, y, z, the variogram at [`LAGS`]: within the depth axis' slices for the
    /// two axes in them when there is a depth axis, else over the whole volume. A lag
    /// longer than a quarter of its axis is not measured and repeats the last one measured.
    #[serde(skip)]
    pub variogram: Variograms,
    /// [`Classification::variogram`] without the lags not measured: what `classify` prints,
    /// and its JSON's `variogram` (null where not measured).
    #[serde(rename = "variogram")]
    pub variogram_measured: [[Option<f64>; LAGS.len()]; 3],
    /// Anything a reader should know (constant volume, clamping).
    pub notes: Vec<String>,
}

/// One type and its score.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Nearest {
    /// The type.
    #[serde(serialize_with = "type_name")]
    pub texture_type: TextureType,
    /// 0..1; the scores of all seven sum to 1.
    pub score: f64,
}

fn type_name<S: serde::Serializer>(t: &TextureType, s: S) -> std::result::Result<S::Ok, S::Error> {
    s.serialize_str(t.name())
}

/// Classify `volume`.
pub fn classify(volume: &Volume) -> Result<Classification> {
    let d = volume.dims();
    if let Some(k) = (0..3).find(|k| d[*k] < MIN_SIDE) {
        return Err(Error::invalid(format!(
            "axis {} has {} voxels; classifying needs at least {MIN_SIDE} on every axis",
            Axis::ALL[k],
            d[k]
        )));
    }
    let lum = luminance(volume);
    let var = variance(&lum);
    if var < 1e-10 {
        return Ok(constant());
    }
    let energy: [f64; 3] = std::array::from_fn(|k| gradient_energy(&lum, d, k) / var);
    let layering: [f64; 3] = std::array::from_fn(|k| within_slices(&lum, d, k) / var);
    let layered = Layered::of(layering, volume.depth_axis());
    let whole = variograms(&lum, d);
    let sliced = layered.axes().first().map(|&k| (k, in_slices(&lum, d, k)));
    let mut out = decide(energy, layering, &layered, whole, sliced);
    out.variogram_measured =
        std::array::from_fn(|k| std::array::from_fn(|l| measured(l, d[k]).then_some(out.variogram[k][l])));
    Ok(out)
}

fn constant() -> Classification {
    Classification {
        texture_type: TextureType::T0,
        anisotropy: 0,
        variation: 0,
        primary_axis: None,
        depth_axis: None,
        confidence: 1.0,
        nearest: vec![Nearest { texture_type: TextureType::T0, score: 1.0 }],
        gradient_energy: [0.0; 3],
        layering: [1.0; 3],
        slice_means_share: [0.0; 3],
        variogram: [[0.0; LAGS.len()]; 3],
        variogram_measured: [[None; LAGS.len()]; 3],
        notes: vec!["the volume is constant: every cut looks the same, so it is type 0".to_string()],
    }
}

/// Luminance of R, G, B if present, else the first channel that is not Depth.
fn luminance(volume: &Volume) -> Vec<f64> {
    let n = volume.channel_count();
    let find = |c: Channel| volume.channel_index(&c);
    let rgb = (find(Channel::R), find(Channel::G), find(Channel::B));
    let first = volume.channels().iter().position(|c| *c != Channel::Depth).unwrap_or(0);
    volume
        .data()
        .chunks_exact(n)
        .map(|v| match rgb {
            (Some(r), Some(g), Some(b)) => 0.299 * v[r] as f64 + 0.587 * v[g] as f64 + 0.114 * v[b] as f64,
            _ => v[first] as f64,
        })
        .collect()
}

fn variance(values: &[f64]) -> f64 {
    let mean = values.iter().sum::<f64>() / values.len() as f64;
    values.iter().map(|v| (v - mean).powi(2)).sum::<f64>() / values.len() as f64
}

/// Mean squared difference between neighbours along axis `k` (not wrapping).
fn gradient_energy(lum: &[f64], d: [usize; 3], k: usize) -> f64 {
    let stride = [1, d[0], d[0] * d[1]][k];
    let (mut sum, mut count) = (0.0, 0usize);
    for (i, v) in lum.iter().enumerate() {
        let c = crate::volume::unindex(d, i)[k];
        if c + 1 < d[k] {
            sum += (lum[i + stride] - v).powi(2);
            count += 1;
        }
    }
    sum / count.max(1) as f64
}

/// Mean variance inside slices orthogonal to axis `k`.
fn within_slices(lum: &[f64], d: [usize; 3], k: usize) -> f64 {
    let mut sums = vec![(0.0f64, 0.0f64, 0usize); d[k]];
    for (i, v) in lum.iter().enumerate() {
        let s = &mut sums[crate::volume::unindex(d, i)[k]];
        s.0 += v;
        s.1 += v * v;
        s.2 += 1;
    }
    let per: f64 = sums.iter().map(|(s, s2, n)| s2 / *n as f64 - (s / *n as f64).powi(2)).sum();
    per / d[k] as f64
}

/// Turn measurements into levels, axes, a type and the types' scores. `sliced` is the
/// depth axis with the variograms taken in its slices, if there is a depth axis.
fn decide(
    energy: [f64; 3],
    layering: [f64; 3],
    layered: &Layered,
    whole: Variograms,
    sliced: Option<(usize, Variograms)>,
) -> Classification {
    let axes = layered.axes();
    let variation = axes.len() as u8;
    let grouping = Grouping::of(&whole);
    let around = sliced.map(|(d, v)| Around::of(d, &v));
    let (anisotropy, primary) = match &around {
        Some(a) => a.level(),
        None => grouping.level(),
    };
    let mut notes = Vec::new();
    let needed = match variation {
        0 => anisotropy,
        1 => anisotropy.max(1),
        _ => 2,
    };
    if needed != anisotropy {
        notes.push(format!("variation {variation} needs anisotropy of at least {needed}; raised from {anisotropy}"));
    }
    let texture_type = TextureType::from_levels(needed, variation).unwrap_or(TextureType::T2d);
    let depth = axes.first().copied();
    let nearest = scores(layered, &grouping, around.as_ref());
    let confidence = nearest.iter().find(|n| n.texture_type == texture_type).map_or(0.0, |n| n.score);
    Classification {
        texture_type,
        anisotropy,
        variation,
        primary_axis: primary.or(depth).map(|k| Axis::ALL[k].to_string()),
        depth_axis: depth.map(|k| Axis::ALL[k].to_string()),
        confidence,
        nearest,
        gradient_energy: energy,
        layering,
        slice_means_share: layering.map(|w| 1.0 - w),
        variogram: sliced.map_or(whole, |(_, v)| v),
        variogram_measured: [[None; LAGS.len()]; 3],
        notes,
    }
}

/// Which axes are depth axes: sorted by their slices' share of the variance (largest
/// first), the top `v` are when the `v`-th holds at least [`MIN_BETWEEN`] and
/// [`STANDS_OUT`] times the next one's share (the hinted axis, alone, less).
struct Layered {
    order: [usize; 3],
    /// For variation 1, 2, 3: how far past the rule's thresholds, in threshold units
    /// (positive: that many axes are depth axes).
    evidence: [f64; 3],
}

impl Layered {
    fn of(layering: [f64; 3], hint: Option<usize>) -> Layered {
        let between = layering.map(|w| 1.0 - w);
        let mut order = [0usize, 1, 2];
        order.sort_by(|a, b| between[*b].total_cmp(&between[*a]));
        let evidence = std::array::from_fn(|n| {
            let b = between[order[n]];
            let next = order.get(n + 1).map_or(1e-9, |k| between[*k].max(1e-9));
            let (least, times) = if n == 0 && hint == Some(order[0]) {
                (HINTED_BETWEEN, HINTED_STANDS_OUT)
            } else {
                (MIN_BETWEEN, STANDS_OUT)
            };
            let stands_out = if n == 2 { f64::INFINITY } else { ((b / next).ln() - times.ln()) / times.ln() };
            ((b - least) / least).min(stands_out)
        });
        Layered { order, evidence }
    }

    /// The depth axes, most layered first.
    fn axes(&self) -> Vec<usize> {
        let v = (1..=3).rev().find(|v| self.evidence[v - 1] > 0.0).unwrap_or(0);
        self.order[..v].to_vec()
    }

    /// How far the measurements are from giving variation `v` (0 when they give it).
    fn cost(&self, v: usize) -> f64 {
        let short = if v == 0 { 0.0 } else { (-self.evidence[v - 1]).max(0.0) };
        short + self.evidence[v..].iter().map(|e| e.max(0.0)).sum::<f64>()
    }
}

/// How the three axes group by their whole-volume variograms (no depth axis).
struct Grouping {
    /// Axes ordered by how fast the pattern changes along them (slowest first).
    order: [usize; 3],
    /// Signed distances from the alike threshold, in threshold units (positive: unlike):
    /// slowest to middle, middle to fastest, slowest to fastest.
    low: f64,
    high: f64,
    span: f64,
}

impl Grouping {
    fn of(v: &Variograms) -> Grouping {
        let mut order = [0usize, 1, 2];
        order.sort_by(|a, b| mean_log(&v[*a]).total_cmp(&mean_log(&v[*b])));
        let [lo, mid, hi] = order;
        let past = |a: usize, b: usize| (unlike(&v[a], &v[b]) - ALIKE) / ALIKE;
        Grouping { order, low: past(lo, mid), high: past(mid, hi), span: past(lo, hi) }
    }

    /// Anisotropy level and the odd (for 1) or most distinct (for 2) axis.
    fn level(&self) -> (u8, Option<usize>) {
        let [lo, _, hi] = self.order;
        if self.span < 0.0 {
            (0, None)
        } else if self.low < 0.0 || self.high < 0.0 {
            (1, Some(if self.low < self.high { hi } else { lo }))
        } else {
            (2, Some(if self.low > self.high { lo } else { hi }))
        }
    }

    /// How far the distances are from giving anisotropy `level` (0 when they give it).
    fn cost(&self, level: u8) -> f64 {
        match level {
            0 => self.span.max(0.0),
            1 => self.low.max(-self.high).min(self.high.max(-self.low)).max(0.0),
            _ => (-self.low).max(-self.high).max(0.0),
        }
    }
}

/// How the two axes in the depth axis' slices compare.
struct Around {
    depth: usize,
    /// The axis in the slices the pattern runs on along longest.
    longest: usize,
    /// Signed distance from the alike threshold, in threshold units (positive: unlike).
    gap: f64,
}

impl Around {
    fn of(depth: usize, v: &Variograms) -> Around {
        let (i, j) = ((depth + 1) % 3, (depth + 2) % 3);
        let longest = if mean_log(&v[i]) < mean_log(&v[j]) { i } else { j };
        Around { depth, longest, gap: (unlike(&v[i], &v[j]) - ALIKE) / ALIKE }
    }

    /// Anisotropy 1 (the two alike: strata) with the depth axis as the odd one, or 2.
    fn level(&self) -> (u8, Option<usize>) {
        if self.gap < 0.0 { (1, Some(self.depth)) } else { (2, Some(self.longest)) }
    }

    fn cost(&self, level: u8) -> f64 {
        if level <= 1 { self.gap.max(0.0) } else { (-self.gap).max(0.0) }
    }
}

/// Every type's score, best first: exp(-cost / [`SCORE_SCALE`]), normalized to sum 1, where
/// the cost is how far the layering and variogram measurements are from that type's
/// levels. Types with variation take their anisotropy cost from the depth slices (or
/// none can be had without a depth axis candidate: the least layered axis is used).
fn scores(layered: &Layered, grouping: &Grouping, around: Option<&Around>) -> Vec<Nearest> {
    let raw: Vec<(TextureType, f64)> = TextureType::ALL
        .into_iter()
        .map(|t| {
            let v = t.variation() as usize;
            let a = match (v, around) {
                (0, _) => grouping.cost(t.anisotropy()),
                (1, Some(around)) => around.cost(t.anisotropy()),
                _ => 0.0,
            };
            (t, (-(layered.cost(v) + a) / SCORE_SCALE).exp())
        })
        .collect();
    let total: f64 = raw.iter().map(|r| r.1).sum();
    let mut out: Vec<Nearest> = raw.into_iter().map(|(t, s)| Nearest { texture_type: t, score: s / total }).collect();
    out.sort_by(|a, b| b.score.total_cmp(&a.score));
    out
}

/// Per axis, half the mean squared difference of `values` at each of [`LAGS`] along it
/// (not wrapping), over their variance: near 0 where the pattern runs on along the axis,
/// near 1 where it has changed. A lag longer than half the side is left at the last
/// measured one.
/// Whether lag `LAGS[l]` is measured along an axis of `side` voxels: the first always, the
/// others up to a quarter of the side.
fn measured(l: usize, side: usize) -> bool {
    l == 0 || LAGS[l] * 4 <= side
}

fn variograms(values: &[f64], d: [usize; 3]) -> Variograms {
    let var = variance(values).max(1e-12);
    std::array::from_fn(|k| {
        let mut out = [0.0; LAGS.len()];
        for (l, &h) in LAGS.iter().enumerate() {
            out[l] = if measured(l, d[k]) { lagged(values, d, k, h) / (2.0 * var) } else { out[l - 1] };
        }
        out
    })
}

/// Mean squared difference between values `h` apart along axis `k`.
fn lagged(values: &[f64], d: [usize; 3], k: usize, h: usize) -> f64 {
    let (sum, count) = lag_sums(values, d, k, h, 2).into_iter().fold((0.0, 0), |a, s| (a.0 + s.0, a.1 + s.1));
    sum / count.max(1) as f64
}

/// Sums of squared differences between values `h` apart along axis `k`, and their counts,
/// per slice orthogonal to axis `s` (by the first value's place). Slabs of z run in
/// parallel and are added in order, so the sums do not depend on the thread count.
fn lag_sums(values: &[f64], d: [usize; 3], k: usize, h: usize, s: usize) -> Vec<(f64, usize)> {
    use rayon::prelude::*;
    let stride = [1, d[0], d[0] * d[1]][k] * h;
    let ends = std::array::from_fn::<usize, 3, _>(|a| if a == k { d[a].saturating_sub(h) } else { d[a] });
    let slabs: Vec<Vec<(f64, usize)>> = (0..ends[2])
        .into_par_iter()
        .map(|z| {
            let mut acc = vec![(0.0, 0usize); d[s]];
            for y in 0..ends[1] {
                let row = (z * d[1] + y) * d[0];
                for x in 0..ends[0] {
                    let diff = values[row + x + stride] - values[row + x];
                    let slot = &mut acc[[x, y, z][s]];
                    slot.0 += diff * diff;
                    slot.1 += 1;
                }
            }
            acc
        })
        .collect();
    let mut out = vec![(0.0, 0usize); d[s]];
    for slab in slabs {
        for (o, v) in out.iter_mut().zip(slab) {
            o.0 += v.0;
            o.1 += v.1;
        }
    }
    out
}

/// Per axis, the variograms within the slices orthogonal to `depth`: each slice less its
/// mean, over its own variance, averaged over the slices (flat slices left out). Along
/// `depth` itself: the variogram of the values less their slice means.
fn in_slices(values: &[f64], d: [usize; 3], depth: usize) -> Variograms {
    let rest = without_slice_means(values, d, depth);
    let mut out = variograms(&rest, d);
    let mut slice_var = vec![0.0f64; d[depth]];
    for (i, v) in rest.iter().enumerate() {
        slice_var[crate::volume::unindex(d, i)[depth]] += v * v;
    }
    let per_slice = (d[0] * d[1] * d[2] / d[depth]) as f64;
    let floor = 1e-6 * slice_var.iter().sum::<f64>() / d[depth] as f64;
    for k in (0..3).filter(|k| *k != depth) {
        for (l, &h) in LAGS.iter().enumerate() {
            if !measured(l, d[k]) {
                out[k][l] = out[k][l - 1];
                continue;
            }
            let sums = lag_sums(&rest, d, k, h, depth);
            let kept: Vec<f64> = (0..d[depth])
                .filter(|s| slice_var[*s] > floor && sums[*s].1 > 0)
                .map(|s| sums[s].0 / sums[s].1 as f64 / (2.0 * slice_var[s] / per_slice))
                .collect();
            out[k][l] = kept.iter().sum::<f64>() / kept.len().max(1) as f64;
        }
    }
    out
}

/// `values` less the mean of their slice orthogonal to axis `k`.
fn without_slice_means(values: &[f64], d: [usize; 3], k: usize) -> Vec<f64> {
    let mut sums = vec![(0.0f64, 0usize); d[k]];
    for (i, v) in values.iter().enumerate() {
        let s = &mut sums[crate::volume::unindex(d, i)[k]];
        s.0 += v;
        s.1 += 1;
    }
    values
        .iter()
        .enumerate()
        .map(|(i, v)| {
            let (sum, n) = sums[crate::volume::unindex(d, i)[k]];
            v - sum / n as f64
        })
        .collect()
}

/// How unlike two axes' variograms are: the largest absolute difference of their
/// logarithms over the lags.
fn unlike(a: &[f64; LAGS.len()], b: &[f64; LAGS.len()]) -> f64 {
    a.iter().zip(b).map(|(x, y)| (x.max(1e-9).ln() - y.max(1e-9).ln()).abs()).fold(0.0, f64::max)
}

/// The mean logarithm of a variogram: lower where the pattern runs on longer.
fn mean_log(v: &[f64; LAGS.len()]) -> f64 {
    v.iter().map(|x| x.max(1e-9).ln()).sum::<f64>() / LAGS.len() as f64
}

#[cfg(test)]
mod tests {
    use super::*;

    const FLAT: [f64; LAGS.len()] = [0.5, 0.8, 1.0, 1.0];
    const SLOW: [f64; LAGS.len()] = [0.01, 0.02, 0.04, 0.08];

    fn levels(layering: [f64; 3], hint: Option<usize>, whole: Variograms, sliced: Variograms) -> Classification {
        let layered = Layered::of(layering, hint);
        let depth = layered.axes().first().copied();
        decide([1.0; 3], layering, &layered, whole, depth.map(|d| (d, sliced)))
    }

    #[test]
    fn levels_from_measurements() {
        let even = [0.99; 3];
        let iso = levels(even, None, [FLAT; 3], [FLAT; 3]);
        assert_eq!((iso.texture_type, iso.primary_axis.as_deref()), (TextureType::T0, None));
        let fibre = levels(even, None, [SLOW, FLAT, FLAT], [FLAT; 3]);
        assert_eq!((fibre.texture_type, fibre.primary_axis.as_deref()), (TextureType::T1a, Some("x")));
        let three = levels(even, None, [SLOW, [0.1, 0.2, 0.4, 0.6], FLAT], [FLAT; 3]);
        assert_eq!(three.texture_type, TextureType::T2a);
        let strata = levels([0.99, 0.99, 0.1], None, [FLAT; 3], [FLAT; 3]);
        assert_eq!((strata.texture_type, strata.depth_axis.as_deref()), (TextureType::T1b, Some("z")));
        let kiwi = levels([0.99, 0.99, 0.1], None, [FLAT; 3], [SLOW, FLAT, FLAT]);
        assert_eq!(
            (kiwi.texture_type, kiwi.depth_axis.as_deref(), kiwi.primary_axis.as_deref()),
            (TextureType::T2b, Some("z"), Some("x"))
        );
    }

    #[test]
    fn a_depth_channel_says_where_to_look_but_the_look_decides() {
        // Slices along z hold 15 % of the variance, three times the others' share.
        let faint = [0.95, 0.97, 0.85];
        assert_eq!(levels(faint, None, [FLAT; 3], [FLAT; 3]).texture_type, TextureType::T0);
        let hinted = levels(faint, Some(2), [FLAT; 3], [FLAT; 3]);
        assert_eq!((hinted.texture_type, hinted.depth_axis.as_deref()), (TextureType::T1b, Some("z")));
        // A Depth channel along an axis the look does not change along is not enough.
        assert_eq!(levels(faint, Some(0), [FLAT; 3], [FLAT; 3]).texture_type, TextureType::T0);
        assert_eq!(levels([0.99; 3], Some(2), [FLAT; 3], [FLAT; 3]).texture_type, TextureType::T0);
    }

    #[test]
    fn the_estimate_has_the_best_score_and_a_borderline_one_a_low_confidence() {
        let clear = levels([0.99; 3], None, [SLOW, FLAT, FLAT], [FLAT; 3]);
        assert_eq!(clear.nearest[0].texture_type, TextureType::T1a);
        assert!(clear.confidence > 0.9, "{clear:?}");
        // x changes 1.9 times slower than y and z at every lag: just past the alike factor.
        let border = levels([0.99; 3], None, [FLAT.map(|v| v / 1.9), FLAT, FLAT], [FLAT; 3]);
        assert_eq!(border.texture_type, TextureType::T1a);
        assert!(border.confidence < LOW_CONFIDENCE && border.nearest[1].texture_type == TextureType::T0, "{border:?}");
    }

    #[test]
    fn small_and_constant_volumes() {
        let small = Volume::new([8, 7, 8], Channel::rgb()).unwrap();
        assert!(classify(&small).unwrap_err().to_string().contains("axis y has 7 voxels"));
        let flat = Volume::from_fn([8, 8, 8], Channel::rgb(), |_, _, _, o| o.fill(0.3)).unwrap();
        let c = classify(&flat).unwrap();
        assert_eq!(c.texture_type, TextureType::T0);
        assert!(c.notes[0].contains("constant"));
    }
}
