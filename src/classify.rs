//! Estimate the LST type of a volume from measurements (thesis ch. 3).
//!
//! On the luminance of the volume (or its first channel):
//! - **gradient energy** per axis, `g_i` = mean squared difference between neighbours along
//!   axis i, over the variance. Isotropic solids have g_x ~ g_y ~ g_z; fibres along x have a
//!   small g_x; layers stacked along z a large g_z. Axes whose log energies lie within
//!   `ALIKE` of each other look alike: one group means anisotropy 0, two groups 1 (the odd
//!   axis is the primary axis), three groups 2.
//! - **layering** per axis, `w_i` = mean variance within slices orthogonal to i over the total
//!   variance. Below `LAYERED` most of the variation runs along i: the pattern changes along
//!   that axis (variation), which becomes the depth axis.
//!
//! The combination is clamped to one of the seven types (variation needs anisotropy).

use crate::error::{Error, Result};
use crate::texture_type::TextureType;
use crate::volume::{Axis, Channel, Volume};
use serde::Serialize;

/// Log-energy difference under which two axes look alike (a factor of 1.8).
pub const ALIKE: f64 = 0.59;
/// Within-slice variance share under which an axis is layered.
pub const LAYERED: f64 = 0.45;
/// Smallest side that can be classified.
pub const MIN_SIDE: usize = 8;

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
    /// The odd axis for anisotropy 1 (fibre or layer normal), the most distinct one for 2.
    pub primary_axis: Option<String>,
    /// The axis the pattern varies along, if any.
    pub depth_axis: Option<String>,
    /// 0..1: how far the deciding measurements are from their thresholds.
    pub confidence: f64,
    /// Gradient energy over variance, per axis x, y, z.
    pub gradient_energy: [f64; 3],
    /// Within-slice variance share, per axis x, y, z.
    pub layering: [f64; 3],
    /// Anything a reader should know (constant volume, clamping).
    pub notes: Vec<String>,
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
    Ok(decide(energy, layering))
}

fn constant() -> Classification {
    Classification {
        texture_type: TextureType::T0,
        anisotropy: 0,
        variation: 0,
        primary_axis: None,
        depth_axis: None,
        confidence: 1.0,
        gradient_energy: [0.0; 3],
        layering: [1.0; 3],
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

/// Turn measurements into levels, axes and a type.
fn decide(energy: [f64; 3], layering: [f64; 3]) -> Classification {
    let logs = energy.map(|e| e.max(1e-12).ln());
    let (anisotropy, primary, margin_a) = anisotropy(logs);
    let layered: Vec<usize> = (0..3).filter(|k| layering[*k] < LAYERED).collect();
    let variation = layered.len() as u8;
    let margin_v = layering.iter().map(|w| (w - LAYERED).abs() / LAYERED).fold(f64::INFINITY, f64::min);
    let depth = layered.iter().copied().min_by(|a, b| layering[*a].total_cmp(&layering[*b]));
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
    let primary = primary.or(depth);
    Classification {
        texture_type,
        anisotropy,
        variation,
        primary_axis: primary.map(|k| Axis::ALL[k].to_string()),
        depth_axis: depth.map(|k| Axis::ALL[k].to_string()),
        confidence: margin_a.min(margin_v).clamp(0.0, 1.0),
        gradient_energy: energy,
        layering,
        notes,
    }
}

/// Anisotropy level, the odd axis (for 1) or most distinct axis (for 2), and the margin.
fn anisotropy(logs: [f64; 3]) -> (u8, Option<usize>, f64) {
    let mut order = [0usize, 1, 2];
    order.sort_by(|a, b| logs[*a].total_cmp(&logs[*b]));
    let [lo, mid, hi] = order;
    let (low_gap, high_gap) = (logs[mid] - logs[lo], logs[hi] - logs[mid]);
    let span = logs[hi] - logs[lo];
    let margin = |gap: f64| (gap - ALIKE).abs() / ALIKE;
    if span < ALIKE {
        return (0, None, margin(span));
    }
    if low_gap < ALIKE || high_gap < ALIKE {
        let odd = if low_gap < high_gap { hi } else { lo };
        return (1, Some(odd), margin(low_gap).min(margin(high_gap)));
    }
    let odd = if low_gap > high_gap { lo } else { hi };
    (2, Some(odd), margin(low_gap).min(margin(high_gap)))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn levels_from_measurements() {
        let iso = decide([1.0, 1.1, 0.9], [0.9, 0.95, 0.9]);
        assert_eq!((iso.texture_type, iso.primary_axis.as_deref()), (TextureType::T0, None));
        let fibre = decide([0.05, 1.0, 1.2], [0.9, 0.9, 0.9]);
        assert_eq!((fibre.texture_type, fibre.primary_axis.as_deref()), (TextureType::T1a, Some("x")));
        let strata = decide([0.1, 0.12, 2.0], [0.95, 0.95, 0.1]);
        assert_eq!((strata.texture_type, strata.depth_axis.as_deref()), (TextureType::T1b, Some("z")));
        let three = decide([0.05, 0.5, 4.0], [0.9, 0.9, 0.9]);
        assert_eq!(three.texture_type, TextureType::T2a);
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
