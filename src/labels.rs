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
//!   the sum, given as `isotropic_surface`).
//!
//! The phases are the distinct values of the first channel (at most [`MAX_PHASES`]).

use crate::correlation::lagged_products;
use crate::error::{Error, Result};
use crate::volume::{Axis, Volume};
use serde::Serialize;

/// Most phases a label volume may have.
pub const MAX_PHASES: usize = 16;
/// Largest lag reported.
pub const MAX_LAG: usize = 32;

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
}

/// The statistics of a label volume.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct LabelStats {
    /// Size in voxels.
    pub dims: [usize; 3],
    /// Largest lag per axis (`min(MAX_LAG, side - 1)`).
    pub lags: [usize; 3],
    /// The phases, by label.
    pub phases: Vec<Phase>,
}

/// Measure the label volume `volume`.
pub fn measure(volume: &Volume) -> Result<LabelStats> {
    let labels: Vec<f32> = volume.data().iter().step_by(volume.channel_count()).copied().collect();
    let mut distinct: Vec<f32> = Vec::new();
    for v in &labels {
        if !distinct.contains(v) {
            if distinct.len() == MAX_PHASES {
                return Err(Error::invalid(format!(
                    "channel {} has more than {MAX_PHASES} distinct values: a label volume holds a few phases",
                    volume.channels()[0].name()
                )));
            }
            distinct.push(*v);
        }
    }
    distinct.sort_by(f32::total_cmp);
    let dims = volume.dims();
    let lags = dims.map(|d| MAX_LAG.min(d.saturating_sub(1)));
    let phases = distinct.iter().map(|&label| phase(&labels, dims, lags, label)).collect();
    Ok(LabelStats { dims, lags, phases })
}

fn phase(labels: &[f32], dims: [usize; 3], lags: [usize; 3], label: f32) -> Phase {
    let indicator: Vec<f64> = labels.iter().map(|v| f64::from(u8::from(*v == label))).collect();
    let share = indicator.iter().sum::<f64>() / indicator.len() as f64;
    let two_point = [0, 1, 2].map(|a| {
        let products = lagged_products(&indicator, dims, Axis::ALL[a], None, lags[a]);
        products.iter().map(|(sum, count)| sum / (*count).max(1) as f64).collect()
    });
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
    }
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
    use crate::volume::Channel;

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

    #[test]
    fn a_grey_photo_is_not_a_label_volume() {
        let err = measure(&labels([8, 8, 1], |x, y, _| (x * 8 + y) as f32)).unwrap_err().to_string();
        assert!(err.contains("more than 16 distinct values"), "{err}");
    }
}
