//! The project's own drawn inputs for hand-made exemplars: "unrolled" cross-sections
//! (columns run around the object, rows from the outside at row 0 to the core), to be
//! swept along the fibre axis, and a seed shape to stamp.
//!
//! ```text
//!   row 0   outside (the skin is added by the sweep)
//!     |     flesh / cortex / sapwood
//!     v     core
//! ```

use crate::error::{Error, Result};
use crate::noise::fbm;
use crate::volume::{Channel, Image2d};
use glam::Vec3;

/// Names of the drawable cross-sections.
pub const NAMES: [&str; 6] = ["kiwi", "carrot", "trunk", "bark", "fuzz", "bark-skin"];
/// The drawings that are skins seen from outside (for `solidtex surface`), not sections.
pub const SKINS: [&str; 2] = ["fuzz", "bark-skin"];

/// Draw the cross-section `name` at `width` x `height` pixels.
pub fn draw(name: &str, width: usize, height: usize, seed: u64) -> Result<Image2d> {
    let paint: fn(f32, f32, u64, f32) -> [f32; 3] = match name {
        "kiwi" => kiwi,
        "carrot" => carrot,
        "trunk" => trunk,
        "bark" => bark,
        "fuzz" => fuzz,
        "bark-skin" => bark_skin,
        other => {
            return Err(Error::invalid(format!("unknown cross-section {other:?}; allowed: {}", NAMES.join(", "))));
        }
    };
    let aspect = width as f32 / height.max(1) as f32;
    let mut data = Vec::with_capacity(width * height * 3);
    for y in 0..height {
        for x in 0..width {
            let u = (x as f32 + 0.5) / width as f32;
            let depth = y as f32 / (height - 1).max(1) as f32;
            data.extend(paint(u, depth, seed, aspect).map(|c| c.clamp(0.0, 1.0)));
        }
    }
    Image2d::from_data(width, height, Channel::rgb(), data)
}

fn mix(a: [f32; 3], b: [f32; 3], t: f32) -> [f32; 3] {
    let t = t.clamp(0.0, 1.0);
    std::array::from_fn(|k| a[k] + (b[k] - a[k]) * t)
}

fn smooth(e0: f32, e1: f32, x: f32) -> f32 {
    let t = ((x - e0) / (e1 - e0)).clamp(0.0, 1.0);
    t * t * (3.0 - 2.0 * t)
}

/// Tileable noise across the strip (period 8 along u), plain along depth.
fn n(seed: u64, u: f32, depth: f32, scale: f32) -> f32 {
    fbm(seed, Vec3::new(u * 8.0 * scale, depth * 4.0 * scale, 0.5), [(8.0 * scale) as i64, 1 << 20, 1], 3)
}

/// Kiwi: green flesh lightening inwards, pale radial rays, a seed ring band, a creamy core.
fn kiwi(u: f32, depth: f32, seed: u64, _aspect: f32) -> [f32; 3] {
    let flesh = mix([0.38, 0.58, 0.10], [0.62, 0.78, 0.30], depth / 0.85);
    let ray_phase = (u * 48.0 + 0.6 * n(seed, u, depth, 1.0)).fract();
    let ray = smooth(0.42, 0.5, ray_phase) * (1.0 - smooth(0.5, 0.58, ray_phase)) * smooth(0.15, 0.5, depth);
    let rays = mix(flesh, [0.84, 0.90, 0.60], 0.85 * ray);
    let ring = smooth(0.5, 0.56, depth) * (1.0 - smooth(0.74, 0.8, depth));
    let banded = mix(rays, [0.55, 0.72, 0.22], 0.35 * ring);
    let core = smooth(0.84, 0.9, depth + 0.02 * n(seed ^ 1, u, depth, 2.0));
    mix(banded, [0.93, 0.93, 0.78], core).map(|c| c + 0.025 * n(seed ^ 2, u, depth, 4.0))
}

/// Carrot: orange cortex, a darker cambium ring, a paler core with fine radial streaks.
fn carrot(u: f32, depth: f32, seed: u64, _aspect: f32) -> [f32; 3] {
    let wobble = 0.03 * n(seed, u, depth, 1.0);
    let cortex = mix([0.90, 0.40, 0.06], [0.96, 0.52, 0.10], depth / 0.55);
    let cambium = smooth(0.52, 0.56, depth + wobble) * (1.0 - smooth(0.58, 0.62, depth + wobble));
    let ringed = mix(cortex, [0.80, 0.34, 0.04], 0.8 * cambium);
    let core = smooth(0.58, 0.62, depth + wobble);
    let streak = 0.5 + 0.5 * (u * 80.0 + 2.0 * n(seed ^ 3, u, depth, 2.0)).sin();
    let core_colour = mix([0.97, 0.62, 0.22], [1.0, 0.72, 0.35], streak * 0.6);
    mix(ringed, core_colour, core).map(|c| c + 0.02 * n(seed ^ 4, u, depth, 4.0))
}

/// Tree trunk: annual rings (soft early wood, a sharp dark late-wood line), heartwood darker.
fn trunk(u: f32, depth: f32, seed: u64, _aspect: f32) -> [f32; 3] {
    let wobble = 0.015 * n(seed, u, depth, 1.0);
    let ring = ((depth + wobble) * 14.0).fract();
    let late = smooth(0.75, 0.92, ring);
    let sap = mix([0.86, 0.72, 0.50], [0.70, 0.52, 0.32], late);
    let heart = mix([0.72, 0.50, 0.30], [0.52, 0.33, 0.18], late);
    mix(sap, heart, smooth(0.62, 0.7, depth)).map(|c| c + 0.02 * n(seed ^ 5, u, depth, 6.0))
}

/// Bark relief, grey, for a sweep's Displacement channel: near the outside (row 0) twelve
/// ridges around with wandering furrows between them, fading to 0.5 (no displacement)
/// below the skin.
fn bark(u: f32, depth: f32, seed: u64, _aspect: f32) -> [f32; 3] {
    let phase = (u * 12.0 + 0.35 * n(seed, u, depth, 0.5)).fract();
    let plateau = smooth(0.0, 0.3, phase) * (1.0 - smooth(0.7, 1.0, phase));
    let ridge = 0.1 + 0.85 * plateau * (0.85 + 0.3 * n(seed ^ 3, u, depth, 2.0));
    let v = ridge + (0.5 - ridge) * smooth(0.06, 0.2, depth);
    [v; 3]
}

/// A kiwi's skin seen from outside (an exemplar for `solidtex surface`): brown, with fine
/// hairs along the rows' direction (`depth`) over soft blotches.
fn fuzz(u: f32, depth: f32, seed: u64, _aspect: f32) -> [f32; 3] {
    let hairs = n(seed, u, depth * 0.2, 6.0);
    let fine = n(seed ^ 11, u, depth * 0.5, 12.0);
    let blotch = n(seed ^ 5, u, depth, 1.0);
    let t = 0.5 + 0.8 * hairs + 0.4 * fine + 0.3 * blotch;
    mix([0.24, 0.15, 0.07], [0.66, 0.51, 0.32], t)
}

/// Bark seen from outside (an exemplar for `solidtex surface`): grey-brown plates split by
/// dark furrows running along `depth`, the plates cracked across.
fn bark_skin(u: f32, depth: f32, seed: u64, _aspect: f32) -> [f32; 3] {
    let phase = (u * 6.0 + 0.6 * n(seed, u, depth * 0.5, 0.5)).fract();
    let plate = smooth(0.05, 0.3, phase) * (1.0 - smooth(0.7, 0.95, phase));
    let crack = 1.0 - smooth(0.0, 0.05, n(seed ^ 7, u, depth * 4.0, 0.5).abs());
    let grain = n(seed ^ 3, u, depth * 0.3, 8.0);
    let lit = plate * (1.0 - 0.7 * crack) * (0.85 + 0.3 * grain);
    mix([0.10, 0.07, 0.05], [0.50, 0.41, 0.32], lit)
}

/// A kiwi-like seed: a slightly flattened teardrop 2 units long along z, with
/// `rings x segments x 2` triangles (32 x 32 gives about 2,000), closed and outward-facing.
pub fn seed_mesh(rings: usize, segments: usize) -> Result<crate::mesh::Mesh> {
    let (rings, segments) = (rings.max(3), segments.max(3));
    let mut vertices = vec![Vec3::new(0.0, 0.0, -1.0)];
    for i in 1..rings {
        let t = i as f32 / rings as f32;
        let radius = (std::f32::consts::PI * t).sin().powf(0.8) * (0.55 - 0.2 * t);
        for j in 0..segments {
            let a = std::f32::consts::TAU * j as f32 / segments as f32;
            vertices.push(Vec3::new(radius * a.cos(), 0.7 * radius * a.sin(), 2.0 * t - 1.0));
        }
    }
    vertices.push(Vec3::new(0.0, 0.0, 1.0));
    let triangles = crate::mesh::shapes::pole_rings(rings, segments);
    Ok(crate::mesh::Mesh::new(vertices, triangles)?.oriented())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn sections_are_drawn_in_range_and_vary_with_depth() {
        for name in NAMES {
            let img = draw(name, 64, 32, 1).unwrap();
            assert!(img.data().iter().all(|v| (0.0..=1.0).contains(v)), "{name}");
            if SKINS.contains(&name) {
                // a skin seen from outside has no depth: it varies everywhere instead
                let greens: Vec<f32> = img.data().chunks_exact(3).map(|p| p[1]).collect();
                let mean = greens.iter().sum::<f32>() / greens.len() as f32;
                let spread = (greens.iter().map(|g| (g - mean).powi(2)).sum::<f32>() / greens.len() as f32).sqrt();
                assert!(spread > 0.05, "{name}: deviation {spread}");
                continue;
            }
            let top: f32 = (0..64).map(|x| img.pixel(x, 0)[1]).sum::<f32>() / 64.0;
            let bottom: f32 = (0..64).map(|x| img.pixel(x, 31)[1]).sum::<f32>() / 64.0;
            assert!((top - bottom).abs() > 0.05, "{name}: {top} vs {bottom}");
        }
        assert!(draw("lemon", 8, 8, 1).unwrap_err().to_string().contains("allowed: kiwi"));
    }

    #[test]
    fn the_seed_is_closed_and_about_two_thousand_triangles() {
        let seed = seed_mesh(32, 32).unwrap();
        assert_eq!(seed.boundary_edges(), 0);
        assert!(seed.signed_volume() > 0.0);
        assert_eq!(seed.triangles.len(), 2 * 32 + 2 * 30 * 32);
    }
}
