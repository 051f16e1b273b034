//! Seeded, tileable 3D gradient noise and its fractal sum (fBm).
//!
//! The lattice wraps with a period, so noise sampled over one period tiles
//! seamlessly. Gradients come from a hash of (seed, lattice point): no tables,
//! no global state, the same value on any thread.

use glam::Vec3;

/// Mix 64 bits thoroughly (SplitMix64's finaliser).
pub fn mix64(mut z: u64) -> u64 {
    z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
    z ^ (z >> 31)
}

/// A uniform number in [0, 1) from the top 24 bits of a hash.
pub fn unit(h: u64) -> f32 {
    (h >> 40) as f32 / (1u64 << 24) as f32
}

/// A hash of a seed and three integers.
pub fn hash3(seed: u64, x: i64, y: i64, z: i64) -> u64 {
    let a = mix64(seed ^ 0x9e37_79b9_7f4a_7c15);
    let b = mix64(a ^ x as u64);
    let c = mix64(b ^ (y as u64).rotate_left(21));
    mix64(c ^ (z as u64).rotate_left(42))
}

const GRADIENTS: [[f32; 3]; 12] = [
    [1.0, 1.0, 0.0],
    [-1.0, 1.0, 0.0],
    [1.0, -1.0, 0.0],
    [-1.0, -1.0, 0.0],
    [1.0, 0.0, 1.0],
    [-1.0, 0.0, 1.0],
    [1.0, 0.0, -1.0],
    [-1.0, 0.0, -1.0],
    [0.0, 1.0, 1.0],
    [0.0, -1.0, 1.0],
    [0.0, 1.0, -1.0],
    [0.0, -1.0, -1.0],
];

/// Gradient noise at `p` (lattice units) with the lattice wrapping every `period`
/// cells on each axis; roughly in [-1, 1], zero at lattice points.
pub fn gradient(seed: u64, p: Vec3, period: [i64; 3]) -> f32 {
    gradient_with(p, period, |l| [(hash3(seed, l[0], l[1], l[2]) % 12) as usize])[0]
}

/// `N` gradient noises sharing one lattice: `grad` gives each noise's gradient index at a
/// (folded) lattice point.
fn gradient_with<const N: usize>(p: Vec3, period: [i64; 3], grad: impl Fn([i64; 3]) -> [usize; N]) -> [f32; N] {
    let cell: [i64; 3] = std::array::from_fn(|k| floor(p[k]));
    let f = p - Vec3::new(cell[0] as f32, cell[1] as f32, cell[2] as f32);
    let fade = f * f * f * (f * (f * 6.0 - 15.0) + 10.0);
    let lattice: [[i64; 2]; 3] = std::array::from_fn(|k| {
        let b = cell[k];
        let per = period[k].max(1);
        [b.rem_euclid(per), (b + 1).rem_euclid(per)]
    });
    let weights: [[f32; 2]; 3] = std::array::from_fn(|k| [1.0 - fade[k], fade[k]]);
    let mut sum = [0.0; N];
    for corner in 0..8 {
        let o = [corner & 1, (corner >> 1) & 1, (corner >> 2) & 1];
        let ids = grad([lattice[0][o[0]], lattice[1][o[1]], lattice[2][o[2]]]);
        let d = f - Vec3::new(o[0] as f32, o[1] as f32, o[2] as f32);
        let w = weights[0][o[0]] * weights[1][o[1]] * weights[2][o[2]];
        for (s, id) in sum.iter_mut().zip(ids) {
            let g = GRADIENTS[id];
            *s += w * (g[0] * d.x + g[1] * d.y + g[2] * d.z);
        }
    }
    sum
}

/// Floor without a libm call (baseline x86-64 has no rounding instruction).
fn floor(x: f32) -> i64 {
    let i = x as i64;
    if (i as f32) > x { i - 1 } else { i }
}

/// Fractal sum of `octaves` gradient noises; each octave doubles frequency and
/// period and halves amplitude. Roughly in [-1, 1].
pub fn fbm(seed: u64, p: Vec3, period: [i64; 3], octaves: u32) -> f32 {
    let (mut sum, mut amp, mut norm) = (0.0, 1.0, 0.0);
    for o in 0..octaves {
        let scale = (1u32 << o) as f32;
        let per = period.map(|v| v << o);
        sum += amp * gradient(seed.wrapping_add(o as u64), p * scale, per);
        norm += amp;
        amp *= 0.5;
    }
    sum / norm.max(1e-6) * 1.4
}

/// Largest gradient table [`Fbm`] builds per octave (entries); beyond it, it hashes.
const TABLE_LIMIT: i64 = 1 << 22;

/// [`fbm`] with each octave's lattice gradients computed once: the same values, several
/// times faster when a whole volume is sampled.
#[derive(Debug, Clone)]
pub struct Fbm {
    seed: u64,
    period: [i64; 3],
    tables: Vec<Vec<u8>>,
}

impl Fbm {
    /// Precompute `octaves` octaves of [`fbm`]`(seed, _, period, octaves)`.
    pub fn new(seed: u64, period: [i64; 3], octaves: u32) -> Fbm {
        let tables = (0..octaves)
            .map(|o| {
                let per = period.map(|v| v.saturating_mul(1 << o.min(62)).max(1));
                let entries = per.iter().try_fold(1i64, |n, &p| n.checked_mul(p));
                if entries.is_none_or(|n| n > TABLE_LIMIT) {
                    return Vec::new();
                }
                let s = seed.wrapping_add(o as u64);
                let mut t = Vec::with_capacity(per.iter().product::<i64>() as usize);
                for z in 0..per[2] {
                    for y in 0..per[1] {
                        for x in 0..per[0] {
                            t.push((hash3(s, x, y, z) % 12) as u8);
                        }
                    }
                }
                t
            })
            .collect();
        Fbm { seed, period, tables }
    }

    /// The noise at `p`, equal to [`fbm`] with the same arguments.
    pub fn sample(&self, p: Vec3) -> f32 {
        self.sample_many([self], p)[0]
    }

    /// Several fields with the same period and octaves sampled at once (sharing the
    /// lattice arithmetic); each value equals its own [`Fbm::sample`].
    pub fn sample_many<const N: usize>(&self, fields: [&Fbm; N], p: Vec3) -> [f32; N] {
        let (mut sum, mut amp, mut norm) = ([0.0; N], 1.0, 0.0);
        for o in 0..self.tables.len() {
            let scale = (1u32 << o) as f32;
            let per = self.period.map(|v| v << o);
            let value: [f32; N] = if fields.iter().any(|f| f.tables[o].is_empty()) {
                fields.map(|f| gradient(f.seed.wrapping_add(o as u64), p * scale, per))
            } else {
                let (px, py) = (per[0].max(1), per[1].max(1));
                gradient_with(p * scale, per, |l| {
                    let at = (l[0] + px * (l[1] + py * l[2])) as usize;
                    fields.map(|f| f.tables[o][at] as usize)
                })
            };
            for (s, v) in sum.iter_mut().zip(value) {
                *s += amp * v;
            }
            norm += amp;
            amp *= 0.5;
        }
        sum.map(|s| s / norm.max(1e-6) * 1.4)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn noise_tiles_with_its_period() {
        let per = [4, 4, 4];
        for k in 0..20 {
            let p = Vec3::new(k as f32 * 0.37, k as f32 * 0.71, 1.3);
            let a = fbm(7, p, per, 3);
            let b = fbm(7, p + Vec3::new(4.0, 0.0, -4.0), per, 3);
            assert!((a - b).abs() < 1e-4, "{a} vs {b}");
        }
    }

    #[test]
    fn the_table_version_equals_the_hashed_version() {
        let field = Fbm::new(9, [3, 5, 2], 3);
        for k in 0..50 {
            let p = Vec3::new(k as f32 * 0.31, k as f32 * 0.17 - 3.0, k as f32 * 0.05);
            assert_eq!(field.sample(p), fbm(9, p, [3, 5, 2], 3));
            let other = Fbm::new(4, [3, 5, 2], 3);
            assert_eq!(field.sample_many([&field, &other], p), [fbm(9, p, [3, 5, 2], 3), fbm(4, p, [3, 5, 2], 3)]);
        }
    }

    #[test]
    fn noise_depends_on_the_seed_and_varies() {
        let p = Vec3::new(1.5, 2.25, 0.75);
        assert_ne!(gradient(1, p, [8; 3]), gradient(2, p, [8; 3]));
        assert_eq!(gradient(1, Vec3::new(3.0, 2.0, 1.0), [8; 3]), 0.0);
        let values: Vec<f32> = (0..200).map(|i| fbm(3, Vec3::splat(i as f32 * 0.13), [64; 3], 4)).collect();
        let spread = values.iter().cloned().fold(f32::MIN, f32::max) - values.iter().cloned().fold(f32::MAX, f32::min);
        assert!(spread > 0.5 && values.iter().all(|v| v.abs() < 2.0), "{spread}");
    }
}
