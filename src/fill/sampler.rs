//! Fast trilinear lookups in texture coordinates (the unit cube), for the two hot loops of
//! the filling: mask alpha at the coverage samples, colour and alpha at every cut pixel.
//!
//! Texture point `w` maps to voxel position `w x dims - 0.5`; lookups clamp at the border.
//! Masks are zero outside the cube, so a patch never shows beyond its exemplar.

use crate::volume::{Channel, Volume};
use glam::Vec3;

/// Points per batch of [`Sampler::alphas`].
pub const BATCH: usize = 8;

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

    /// A sampler of R, G, B (or the first channel, read as grey, for a grey volume).
    pub fn colour(volume: &Volume) -> Sampler {
        let rgb: Vec<usize> =
            [Channel::R, Channel::G, Channel::B].iter().filter_map(|c| volume.channel_index(c)).collect();
        Sampler::pick(volume, if rgb.len() == 3 { &rgb } else { &[0] })
    }

    /// A sampler of channel `c` of `volume`, read as grey ([`Sampler::rgb`] gives its value
    /// three times; it is stored once).
    pub fn channel(volume: &Volume, c: usize) -> Sampler {
        Sampler::pick(volume, &[c])
    }

    /// The chosen channels, with one more voxel on the high side of each axis repeating
    /// the last one, so a lookup reads its upper neighbours without clamping indices.
    fn pick(volume: &Volume, channels: &[usize]) -> Sampler {
        let n = volume.channel_count();
        let d = volume.dims();
        let voxels = volume.data();
        let mut data = Vec::with_capacity((d[0] + 1) * (d[1] + 1) * (d[2] + 1) * channels.len());
        for z in 0..=d[2] {
            for y in 0..=d[1] {
                for x in 0..=d[0] {
                    let i = x.min(d[0] - 1) + d[0] * (y.min(d[1] - 1) + d[1] * z.min(d[2] - 1));
                    data.extend(channels.iter().map(|&c| voxels[i * n + c]));
                }
            }
        }
        Sampler { dims: d, size: Vec3::new(d[0] as f32, d[1] as f32, d[2] as f32), channels: channels.len(), data }
    }

    /// Channel `c` of voxel (x, y, z).
    fn value(&self, x: usize, y: usize, z: usize, c: usize) -> f32 {
        let [dx, dy, _] = self.dims;
        self.data[(x + (dx + 1) * (y + (dy + 1) * z)) * self.channels + c]
    }

    /// Alpha at `w` (the first channel): trilinear inside the unit cube, 0 outside.
    #[inline]
    pub fn alpha(&self, w: Vec3) -> f32 {
        if w.cmplt(Vec3::ZERO).any() || w.cmpgt(Vec3::ONE).any() {
            return 0.0;
        }
        // a mask has one channel: its stride known at compile time spares the multiplies
        match self.channels {
            1 => self.first::<1>(w),
            _ => self.first::<0>(w),
        }
    }

    /// Alpha at each point of a batch (`p[axis][lane]`), bit for bit what [`Sampler::alpha`]
    /// gives: the arithmetic runs in passes over the batch, so it takes the vector lanes;
    /// only the eight voxel reads go one point at a time.
    pub fn alphas(&self, p: &[[f32; BATCH]; 3]) -> [f32; BATCH] {
        if self.channels != 1 {
            return std::array::from_fn(|i| self.alpha(Vec3::new(p[0][i], p[1][i], p[2][i])));
        }
        let mut inside = [true; BATCH];
        let (mut cell, mut t) = ([[0u32; BATCH]; 3], [[0.0f32; BATCH]; 3]);
        for k in 0..3 {
            let (size, top) = (self.size[k], self.size[k] - 1.0);
            for i in 0..BATCH {
                let w = p[k][i];
                // not `contains`: a NaN counts as inside, as in `alpha`
                #[allow(clippy::manual_range_contains)]
                let outside = w < 0.0 || w > 1.0;
                inside[i] &= !outside;
                // the clamp as glam's (a NaN goes to 0), and truncation as the floor
                let q = w * size - 0.5;
                let q = if q > 0.0 { q } else { 0.0 };
                let q = if q < top { q } else { top };
                cell[k][i] = q as u32;
                t[k][i] = q - cell[k][i] as f32;
            }
        }
        let (sx, sy) = (self.dims[0] + 1, (self.dims[0] + 1) * (self.dims[1] + 1));
        let mut v = [[0.0f32; BATCH]; 8];
        for i in 0..BATCH {
            let at = cell[0][i] as usize + sx * cell[1][i] as usize + sy * cell[2][i] as usize;
            let d = &self.data[at..=at + sy + sx + 1];
            for (j, o) in [0, 1, sx, sx + 1, sy, sy + 1, sy + sx, sy + sx + 1].into_iter().enumerate() {
                v[j][i] = d[o];
            }
        }
        let lerp = |a: f32, b: f32, t: f32| a + (b - a) * t;
        std::array::from_fn(|i| {
            let x = |j: usize| lerp(v[j][i], v[j + 1][i], t[0][i]);
            let near = lerp(x(0), x(2), t[1][i]);
            let far = lerp(x(4), x(6), t[1][i]);
            if inside[i] { lerp(near, far, t[2][i]) } else { 0.0 }
        })
    }

    /// The first channel at `w` (inside the unit cube), trilinear; `C` is the channel count
    /// when known, else 0.
    #[inline]
    fn first<const C: usize>(&self, w: Vec3) -> f32 {
        let p = (w * self.size - 0.5).clamp(Vec3::ZERO, self.size - 1.0);
        let (x0, y0, z0) = (p.x as usize, p.y as usize, p.z as usize);
        let t = p - Vec3::new(x0 as f32, y0 as f32, z0 as f32);
        let (sx, sy) = (self.dims[0] + 1, (self.dims[0] + 1) * (self.dims[1] + 1));
        let c = if C == 0 { self.channels } else { C };
        let d = &self.data[(x0 + sx * y0 + sy * z0) * c..];
        let lerp = |a: f32, b: f32, t: f32| a + (b - a) * t;
        let along_x = |o: usize| lerp(d[o * c], d[(o + 1) * c], t.x);
        let near = lerp(along_x(0), along_x(sx), t.y);
        let far = lerp(along_x(sy), along_x(sy + sx), t.y);
        lerp(near, far, t.z)
    }

    /// R, G, B at `w`, clamped at the border (a one-channel sampler's value three times).
    #[inline]
    pub fn rgb(&self, w: Vec3) -> Vec3 {
        if self.channels == 1 {
            let mut grey = [0.0; 1];
            self.lookup(w, &mut grey);
            return Vec3::splat(grey[0]);
        }
        let mut out = [0.0; 3];
        self.lookup(w, &mut out);
        Vec3::from(out)
    }

    #[inline]
    fn lookup<const C: usize>(&self, w: Vec3, out: &mut [f32; C]) {
        let p = (w * self.size - 0.5).clamp(Vec3::ZERO, self.size - 1.0);
        // p is not negative, so truncation is the floor (without a libm call per axis)
        let (x0, y0, z0) = (p.x as usize, p.y as usize, p.z as usize);
        let t = p - Vec3::new(x0 as f32, y0 as f32, z0 as f32);
        let (sx, sy) = (self.dims[0] + 1, (self.dims[0] + 1) * (self.dims[1] + 1));
        let at = x0 + sx * y0 + sy * z0;
        let corners = [(0, 1.0 - t.x), (1, t.x)];
        for (dzo, wz) in [(0, 1.0 - t.z), (sy, t.z)] {
            for (dyo, wy) in [(0, 1.0 - t.y), (sx, t.y)] {
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

/// Voxels per block side of [`AlphaBounds`].
const BLOCK: usize = 4;

/// The least and greatest mask value per block of voxels, to tell without sampling that
/// every lookup inside a box of texture space is 0, or full.
#[derive(Debug, Clone)]
pub struct AlphaBounds {
    voxels: [usize; 3],
    size: Vec3,
    blocks: [usize; 3],
    low: Vec<f32>,
    high: Vec<f32>,
}

impl AlphaBounds {
    /// The bounds of the first channel of `mask`. A block holding NaN is neither empty nor
    /// full.
    pub fn new(mask: &Sampler) -> AlphaBounds {
        let voxels = mask.dims;
        let blocks = voxels.map(|d| d.div_ceil(BLOCK));
        let mut low = vec![f32::INFINITY; blocks.iter().product()];
        let mut high = vec![f32::NEG_INFINITY; low.len()];
        for z in 0..voxels[2] {
            for y in 0..voxels[1] {
                for x in 0..voxels[0] {
                    let v = mask.value(x, y, z, 0);
                    let b = x / BLOCK + blocks[0] * (y / BLOCK + blocks[1] * (z / BLOCK));
                    let (lo, hi) = if v.is_nan() { (f32::NEG_INFINITY, f32::INFINITY) } else { (v, v) };
                    low[b] = low[b].min(lo);
                    high[b] = high[b].max(hi);
                }
            }
        }
        AlphaBounds { voxels, size: mask.size, blocks, low, high }
    }

    /// The least and greatest value [`Sampler::alpha`] can return at points of the box
    /// `lo..=hi` (conservative: widened by a little for rounding, 0 counted as possible
    /// where the box leaves the unit cube).
    pub fn range(&self, lo: Vec3, hi: Vec3) -> (f32, f32) {
        let (lo, hi) = (lo - 1e-4, hi + 1e-4);
        let outside = lo.cmplt(Vec3::ZERO).any() || hi.cmpgt(Vec3::ONE).any();
        let cell = |w: Vec3| (w * self.size - 0.5).clamp(Vec3::ZERO, self.size - 1.0);
        let (a, b) = (cell(lo), cell(hi));
        let first = [a.x, a.y, a.z].map(|p| p as usize / BLOCK);
        let last = [(b.x, 0), (b.y, 1), (b.z, 2)].map(|(p, k)| ((p as usize + 1).min(self.voxels[k] - 1)) / BLOCK);
        let (mut least, mut most) = (f32::INFINITY, f32::NEG_INFINITY);
        for z in first[2]..=last[2] {
            for y in first[1]..=last[1] {
                for x in first[0]..=last[0] {
                    let i = x + self.blocks[0] * (y + self.blocks[1] * z);
                    least = least.min(self.low[i]);
                    most = most.max(self.high[i]);
                }
            }
        }
        if outside { (least.min(0.0), most.max(0.0)) } else { (least, most) }
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
        for w in [Vec3::new(0.7, 0.5, 0.5), Vec3::new(0.2, 0.9, 0.35)] {
            // one channel and three: the first channel either way
            assert!((m.alpha(w) - s.rgb(w).x).abs() < 1e-6);
            assert!((s.alpha(w) - s.rgb(w).x).abs() < 1e-6);
        }
    }

    #[test]
    fn batched_lookups_equal_single_ones_bit_for_bit() {
        let v = Volume::from_fn([7, 5, 6], Channel::rgb(), |x, y, z, o| {
            let h = ((x * 7 + y * 13 + z * 29) % 17) as f32 / 16.0;
            o.copy_from_slice(&[h, 1.0 - h, h * h]);
        })
        .unwrap();
        let (one, three) = (Sampler::mask(&v), Sampler::colour(&v));
        let mut points: Vec<Vec3> = (0..200)
            .map(|i| {
                let f = |k: u32| ((i * 37 + k * 11) % 101) as f32 / 100.0 * 1.3 - 0.15;
                Vec3::new(f(0), f(1), f(2))
            })
            .collect();
        points.extend([Vec3::ZERO, Vec3::ONE, Vec3::new(f32::NAN, 0.5, 0.5), Vec3::new(0.5, 1.0 + 1e-7, 0.5)]);
        points.resize(points.len().next_multiple_of(BATCH), Vec3::splat(0.5));
        for sampler in [&one, &three] {
            for chunk in points.chunks(BATCH) {
                let p: [[f32; BATCH]; 3] = std::array::from_fn(|k| std::array::from_fn(|i| chunk[i][k]));
                let batch = sampler.alphas(&p);
                for (w, got) in chunk.iter().zip(batch) {
                    assert_eq!(got.to_bits(), sampler.alpha(*w).to_bits(), "{w}");
                }
            }
        }
    }

    #[test]
    fn alpha_bounds_hold_every_lookup_in_the_box() {
        let v = Volume::from_fn([13, 9, 7], vec![Channel::A], |x, y, z, o| {
            o[0] = if x >= 8 {
                1.0
            } else if x < 4 {
                0.0
            } else {
                ((x * 7 + y * 3 + z) % 5) as f32 / 4.0
            };
        })
        .unwrap();
        let m = Sampler::mask(&v);
        let bounds = AlphaBounds::new(&m);
        let mut seed = 1u32;
        let mut next = || {
            seed = seed.wrapping_mul(1664525).wrapping_add(1013904223);
            (seed >> 8) as f32 / (1u32 << 24) as f32 * 1.2 - 0.1
        };
        for _ in 0..300 {
            let (a, b) = (Vec3::new(next(), next(), next()), Vec3::new(next(), next(), next()));
            let (lo, hi) = (a.min(b), a.min(b) + (a - b).abs() * 0.3);
            let (least, most) = bounds.range(lo, hi);
            for i in 0..=4 {
                for j in 0..=4 {
                    let w = lo + (hi - lo) * Vec3::new(i as f32 / 4.0, j as f32 / 4.0, (i + j) as f32 / 8.0);
                    let a = m.alpha(w);
                    assert!(a >= least - 1e-6 && a <= most + 1e-6, "{a} outside {least}..{most} at {w}");
                }
            }
        }
        assert_eq!(bounds.range(Vec3::new(0.0, 0.2, 0.2), Vec3::new(0.1, 0.8, 0.8)).1, 0.0);
        assert_eq!(bounds.range(Vec3::new(0.8, 0.2, 0.2), Vec3::new(0.9, 0.8, 0.8)).0, 1.0);
    }
}
