//! Nearest and trilinear sampling at continuous positions.
//!
//! Positions are in voxel units: voxel (i, j, k) sits at exactly (i, j, k).

use super::Volume;
use glam::Vec3;

/// What happens outside the grid.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum Edge {
    /// Wrap around: the volume tiles (the default for synthesized exemplars).
    #[default]
    Wrap,
    /// Repeat the border voxel.
    Clamp,
}

impl Edge {
    /// Map an integer coordinate into `0..len`.
    pub fn fold(self, i: i64, len: usize) -> usize {
        match self {
            Edge::Wrap => i.rem_euclid(len as i64) as usize,
            Edge::Clamp => i.clamp(0, len as i64 - 1) as usize,
        }
    }
}

impl Volume {
    /// The voxel nearest to `p`, written into `out` (one value per channel).
    pub fn sample_nearest(&self, p: Vec3, edge: Edge, out: &mut [f32]) {
        let d = self.dims();
        let x = edge.fold(p.x.round() as i64, d[0]);
        let y = edge.fold(p.y.round() as i64, d[1]);
        let z = edge.fold(p.z.round() as i64, d[2]);
        out.copy_from_slice(self.voxel(x, y, z));
    }

    /// Trilinear interpolation of the 8 voxels around `p`, written into `out`.
    pub fn sample_trilinear(&self, p: Vec3, edge: Edge, out: &mut [f32]) {
        let d = self.dims();
        let base = p.floor();
        let t = p - base;
        let (bx, by, bz) = (base.x as i64, base.y as i64, base.z as i64);
        out.fill(0.0);
        for corner in 0..8 {
            let (ox, oy, oz) = (corner & 1, (corner >> 1) & 1, (corner >> 2) & 1);
            let w = weight(t.x, ox) * weight(t.y, oy) * weight(t.z, oz);
            if w == 0.0 {
                continue;
            }
            let x = edge.fold(bx + ox, d[0]);
            let y = edge.fold(by + oy, d[1]);
            let z = edge.fold(bz + oz, d[2]);
            for (o, v) in out.iter_mut().zip(self.voxel(x, y, z)) {
                *o += w * v;
            }
        }
    }
}

fn weight(t: f32, offset: i64) -> f32 {
    if offset == 0 { 1.0 - t } else { t }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::volume::Channel;

    fn ramp() -> Volume {
        Volume::from_fn([4, 4, 4], Channel::grey(), |x, y, z, o| {
            o[0] = x as f32 + 10.0 * y as f32 + 100.0 * z as f32;
        })
        .unwrap()
    }

    #[test]
    fn trilinear_is_exact_on_a_linear_ramp_inside() {
        let v = ramp();
        let mut out = [0.0];
        v.sample_trilinear(Vec3::new(1.25, 2.5, 0.75), Edge::Clamp, &mut out);
        assert!((out[0] - (1.25 + 25.0 + 75.0)).abs() < 1e-4, "{}", out[0]);
        v.sample_trilinear(Vec3::new(2.0, 1.0, 3.0), Edge::Wrap, &mut out);
        assert_eq!(out[0], 312.0);
    }

    #[test]
    fn wrap_and_clamp_differ_past_the_edge() {
        let v = ramp();
        let mut out = [0.0];
        v.sample_trilinear(Vec3::new(3.5, 0.0, 0.0), Edge::Wrap, &mut out);
        assert_eq!(out[0], 1.5); // halfway between x=3 and x=0
        v.sample_trilinear(Vec3::new(3.5, 0.0, 0.0), Edge::Clamp, &mut out);
        assert_eq!(out[0], 3.0);
        v.sample_nearest(Vec3::new(-1.0, 0.0, 0.0), Edge::Wrap, &mut out);
        assert_eq!(out[0], 3.0);
    }
}
