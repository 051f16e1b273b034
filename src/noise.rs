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
    let base = p.floor();
    let f = p - base;
    let fade = f * f * f * (f * (f * 6.0 - 15.0) + 10.0);
    let mut sum = 0.0;
    for corner in 0..8 {
        let o = [corner & 1, (corner >> 1) & 1, (corner >> 2) & 1];
        let lattice: [i64; 3] = std::array::from_fn(|k| (base[k] as i64 + o[k]).rem_euclid(period[k].max(1)));
        let g = GRADIENTS[(hash3(seed, lattice[0], lattice[1], lattice[2]) % 12) as usize];
        let d = f - Vec3::new(o[0] as f32, o[1] as f32, o[2] as f32);
        let w: f32 = (0..3).map(|k| if o[k] == 0 { 1.0 - fade[k] } else { fade[k] }).product();
        sum += w * (g[0] * d.x + g[1] * d.y + g[2] * d.z);
    }
    sum
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
    fn noise_depends_on_the_seed_and_varies() {
        let p = Vec3::new(1.5, 2.25, 0.75);
        assert_ne!(gradient(1, p, [8; 3]), gradient(2, p, [8; 3]));
        assert_eq!(gradient(1, Vec3::new(3.0, 2.0, 1.0), [8; 3]), 0.0);
        let values: Vec<f32> = (0..200).map(|i| fbm(3, Vec3::splat(i as f32 * 0.13), [64; 3], 4)).collect();
        let spread = values.iter().cloned().fold(f32::MIN, f32::max) - values.iter().cloned().fold(f32::MAX, f32::min);
        assert!(spread > 0.5 && values.iter().all(|v| v.abs() < 2.0), "{spread}");
    }
}
