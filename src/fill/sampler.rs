//! Fast trilinear lookups in texture coordinates (the unit cube), for the two hot loops of
//! the filling: mask alpha at the coverage samples, colour and alpha at every cut pixel.
//!
//! Texture point `w` maps to voxel position `w x dims - 0.5`; lookups clamp at the border.
//! Masks are zero outside the cube, so a patch never shows beyond its exemplar.

use crate::volume::{Channel, Volume};
use glam::Vec3;

/// One volume's samples, ready for lookups.
#[derive(Debug, Clone)]
pub struct Sampler {
    dims: [usize; 3],
    size: Vec3,
    channels: usize,
    data: Vec<f32>,
}

impl Sampler {
    /// A sampler of the first channel of `volume` (a mask).
    pub fn mask(volume: &Volume) -> Sampler {
        Sampler::pick(volume, &[0])
    }

    /// A sampler of R, G, B (or the first channel three times for a grey volume).
    pub fn colour(volume: &Volume) -> Sampler {
        let rgb: Vec<usize> =
            [Channel::R, Channel::G, Channel::B].iter().filter_map(|c| volume.channel_index(c)).collect();
        Sampler::pick(volume, if rgb.len() == 3 { &rgb } else { &[0, 0, 0] })
    }

    fn pick(volume: &Volume, channels: &[usize]) -> Sampler {
        let n = volume.channel_count();
        let data = volume.data().chunks_exact(n).flat_map(|v| channels.iter().map(|&c| v[c])).collect();
        let d = volume.dims();
        Sampler { dims: d, size: Vec3::new(d[0] as f32, d[1] as f32, d[2] as f32), channels: channels.len(), data }
    }

    /// Alpha at `w`: trilinear inside the unit cube, 0 outside.
    #[inline]
    pub fn alpha(&self, w: Vec3) -> f32 {
        if w.cmplt(Vec3::ZERO).any() || w.cmpgt(Vec3::ONE).any() {
            return 0.0;
        }
        let mut out = [0.0];
        self.lookup(w, &mut out);
        out[0]
    }

    /// R, G, B at `w`, clamped at the border.
    #[inline]
    pub fn rgb(&self, w: Vec3) -> Vec3 {
        let mut out = [0.0; 3];
        self.lookup(w, &mut out);
        Vec3::from(out)
    }

    #[inline]
    fn lookup<const C: usize>(&self, w: Vec3, out: &mut [f32; C]) {
        let p = (w * self.size - 0.5).clamp(Vec3::ZERO, self.size - 1.0);
        let base = p.floor();
        let t = p - base;
        let [dx, dy, _] = self.dims;
        let (x0, y0, z0) = (base.x as usize, base.y as usize, base.z as usize);
        let x1 = (x0 + 1).min(dx - 1) - x0;
        let y1 = ((y0 + 1).min(dy - 1) - y0) * dx;
        let z1 = ((z0 + 1).min(self.dims[2] - 1) - z0) * dx * dy;
        let at = x0 + dx * (y0 + dy * z0);
        let corners = [(0, 1.0 - t.x), (x1, t.x)];
        for (dzo, wz) in [(0, 1.0 - t.z), (z1, t.z)] {
            for (dyo, wy) in [(0, 1.0 - t.y), (y1, t.y)] {
                for &(dxo, wx) in &corners {
                    let weight = wx * wy * wz;
                    let i = (at + dxo + dyo + dzo) * self.channels;
                    for (c, o) in out.iter_mut().enumerate() {
                        *o += weight * self.data[i + c];
                    }
                }
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::volume::Edge;

    #[test]
    fn lookups_match_the_volume_sampler() {
        let v = Volume::from_fn([5, 4, 3], Channel::rgb(), |x, y, z, o| {
            o.copy_from_slice(&[x as f32 / 4.0, (y * y) as f32 / 9.0, (x + z) as f32 / 6.0]);
        })
        .unwrap();
        let s = Sampler::colour(&v);
        for w in [Vec3::new(0.3, 0.6, 0.5), Vec3::new(0.95, 0.1, 0.9), Vec3::new(0.5, 0.5, 0.5)] {
            let mut want = [0.0; 3];
            v.sample_trilinear(w * Vec3::new(5.0, 4.0, 3.0) - 0.5, Edge::Clamp, &mut want);
            assert!((s.rgb(w) - Vec3::from(want)).abs().max_element() < 1e-5, "{w}");
        }
        let m = Sampler::mask(&v);
        assert_eq!(m.alpha(Vec3::new(1.01, 0.5, 0.5)), 0.0);
        assert!((m.alpha(Vec3::new(0.7, 0.5, 0.5)) - s.rgb(Vec3::new(0.7, 0.5, 0.5)).x).abs() < 1e-6);
    }
}
