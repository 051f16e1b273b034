//! Alpha masks for pasting patches (thesis §6.2.1, §6.2.7): a soft 3D splotch, and the
//! outer / middle / inner variants for depth-varying textures.
//!
//! ```text
//!  splotch, middle        outer              inner        (a slice, depth 0 at the top)
//!                       .:#######:.                       # opaque
//!     ..:::..           .:#######:.                       : fall-off
//!   .:#######:.         :#########:         ..:::..       . nearly 0
//!   :#########:         .:#######:.       .:#######:.
//!   .:#######:.           ..:::..         :#########:
//!     ..:::..                             .:#######:.
//!                                         .:#######:.
//! ```
//! Alpha is 1 inside, falls linearly to 0 across a band `falloff x size` wide, 0 outside,
//! and stays inside the cube. The outer mask also reaches the depth-0 face (a slab from the
//! face to the ball, as wide across as the ball), so every pasted outer patch covers the
//! skin, and the inner one the innermost face; across, the slab fades like the ball, so a
//! patch's alpha is 0 before its texture coordinates leave the cube on any side.

use crate::error::{Error, Result};
use crate::mesh::Mesh;
use crate::noise::Fbm;
use crate::volume::{Axis, Channel, Volume};
use glam::Vec3;
use serde::Serialize;

/// Default fall-off band, as a share of the mask size.
pub const DEFAULT_FALLOFF: f32 = 0.075;
/// How much the splotch radius varies with direction.
const WOBBLE: f32 = 0.15;

/// Where a layered mask sits along the depth axis.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Layer {
    /// Centred at a quarter of the depth, opaque over the depth-0 face.
    Outer,
    /// Centred.
    Middle,
    /// Centred at three quarters, opaque over the innermost face.
    Inner,
}

impl Layer {
    /// All three, outside in.
    pub const ALL: [Layer; 3] = [Layer::Outer, Layer::Middle, Layer::Inner];

    /// `outer`, `middle` or `inner`.
    pub fn name(self) -> &'static str {
        match self {
            Layer::Outer => "outer",
            Layer::Middle => "middle",
            Layer::Inner => "inner",
        }
    }
}

/// Allowed mask sides, in voxels. The least is the smallest cube whose splotch and layers
/// are opaque somewhere at the default fall-off, for any seed: the ball's radius is
/// (size / 2 - 1) / (1 + WOBBLE), at least 0.85 of that where the wobble shrinks it, and
/// must reach a fall-off band past the voxel centres nearest the middle (0.87 voxels away
/// in an even cube). Size 6 leaves 1.48 - 0.87 = 0.61 voxels against a band of 0.45; size 5
/// one opaque voxel; size 4 none (its ball, 0.74 to 1.0 voxels, ends inside the band).
pub const SIZE: (usize, usize) = (6, 512);
/// Alpha at or above this counts as opaque.
const OPAQUE: f32 = 0.999;

/// Refuses a mask side outside [`SIZE`] or a fall-off outside (0, 0.5).
pub fn check(size: usize, falloff: f32) -> Result<()> {
    let (lo, hi) = SIZE;
    if !(lo..=hi).contains(&size) {
        return Err(Error::invalid(format!("mask size {size} is out of range; allowed {lo} to {hi} voxels")));
    }
    if falloff.is_nan() || falloff <= 0.0 || falloff >= 0.5 {
        return Err(Error::invalid(format!(
            "fall-off {falloff} is outside (0, 0.5): it is the width of the soft band as a share of the size"
        )));
    }
    Ok(())
}

/// A splotch: a noisy ball, opaque inside, soft across `falloff x size` voxels.
pub fn splotch(size: usize, falloff: f32, seed: u64) -> Result<Volume> {
    layered(size, falloff, seed, Layer::Middle, Axis::Z)
}

/// The splotch placed at `layer` along `depth` (see the module diagram).
pub fn layered(size: usize, falloff: f32, seed: u64, layer: Layer, depth: Axis) -> Result<Volume> {
    check(size, falloff)?;
    let s = size as f32;
    let band = falloff * s;
    let radius = (s / 2.0 - 1.0) / (1.0 + WOBBLE);
    let d = depth.index();
    let mut centre = Vec3::splat(s / 2.0);
    centre[d] = s * match layer {
        Layer::Outer => 0.25,
        Layer::Middle => 0.5,
        Layer::Inner => 0.75,
    };
    let wobble = Fbm::new(seed, [4; 3], 2);
    let volume = Volume::from_fn_par([size; 3], vec![Channel::A], |x, y, z, o| {
        let p = Vec3::new(x as f32, y as f32, z as f32) + 0.5;
        let r = p - centre;
        let rim = |r: Vec3| {
            let surface = radius * (1.0 + WOBBLE * wobble.sample(r.try_normalize().unwrap_or(Vec3::X) * 1.5 + 2.0));
            ((surface - r.length()) / band).clamp(0.0, 1.0)
        };
        let mut alpha = rim(r);
        let face = match layer {
            Layer::Outer => Some(p[d]),
            Layer::Inner => Some(s - p[d]),
            Layer::Middle => None,
        };
        if let Some(f) = face {
            // a slab from the face to the ball, as wide as the ball across (its rim fades
            // inside the cube, so a patch never ends where its texture coordinates do)
            let mut across = r;
            across[d] = 0.0;
            alpha = alpha.max(((s * 0.25 - f) / band + 1.0).clamp(0.0, 1.0) * rim(across));
        }
        o[0] = alpha;
    })?;
    check_opaque(&volume, size, falloff)?;
    Ok(with_meta(volume, &format!("mask:{}", layer.name()), seed))
}

/// A mask must be opaque somewhere: a patch pasted with it covers the model only where it
/// is. A fall-off band as wide as the shape's radius leaves no voxel opaque, at any size.
fn check_opaque(mask: &Volume, size: usize, falloff: f32) -> Result<()> {
    if mask.data().iter().any(|a| *a >= OPAQUE) {
        return Ok(());
    }
    Err(Error::invalid(format!(
        "a mask of size {size} with fall-off {falloff} is opaque nowhere: its soft band ({:.1} voxels) is as \
         wide as the shape; a smaller fall-off (or, for a small mask, a larger size) leaves an opaque core",
        falloff * size as f32
    )))
}

fn with_meta(volume: Volume, recipe: &str, seed: u64) -> Volume {
    let mut v = volume;
    v.meta.set("recipe", recipe);
    v.meta.set("seed", seed.to_string());
    v
}

/// A mask from a closed mesh: the mesh scaled to fit the cube (leaving room for the band),
/// opaque inside, soft across the band by distance to its surface.
pub fn from_mesh(mesh: &Mesh, size: usize, falloff: f32) -> Result<Volume> {
    check(size, falloff)?;
    let open = mesh.boundary_edges();
    if open > 0 {
        return Err(Error::invalid(format!(
            "the mesh has {open} boundary edge(s); a mask needs a closed mesh (every edge shared by two triangles)"
        )));
    }
    let s = size as f32;
    let band = falloff * s;
    let (lo, hi) = mesh.bounds();
    let scale = (s - 2.0) / (hi - lo).max_element().max(1e-6);
    let offset = Vec3::splat(s / 2.0) - (lo + hi) / 2.0 * scale;
    let placed = mesh.transformed(glam::Affine3A::from_scale_rotation_translation(
        Vec3::splat(scale),
        glam::Quat::IDENTITY,
        offset,
    ));
    let inside = crate::mesh::voxelize(&placed, [size; 3], 1);
    let volume = Volume::from_fn_par([size; 3], vec![Channel::A], |x, y, z, o| {
        let p = Vec3::new(x as f32, y as f32, z as f32) + 0.5;
        if inside.at(x, y, z) < 0.5 {
            o[0] = 0.0;
            return;
        }
        o[0] = (distance_to_surface(&placed, p) / band).clamp(0.0, 1.0);
    })?;
    check_opaque(&volume, size, falloff)?;
    Ok(with_meta(volume, "mask:mesh", 0))
}

/// Distance from `p` to the nearest triangle of `mesh`.
fn distance_to_surface(mesh: &Mesh, p: Vec3) -> f32 {
    mesh.triangles
        .iter()
        .map(|t| p.distance(crate::mesh::closest_on_triangle(p, t.map(|i| mesh.vertices[i as usize]))))
        .fold(f32::INFINITY, f32::min)
}

/// What a mask covers.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct MaskMeasures {
    /// Share of voxels with alpha at least 0.999.
    pub opaque_fraction: f64,
    /// Width of the soft band in voxels: the median of 1 / |gradient of alpha| over the
    /// voxels whose alpha lies in (0.1, 0.9) (alpha falls by 1 across the band).
    pub falloff_width: f64,
    /// Edge of the largest regular tetrahedron around the opaque centre that the mask fully
    /// covers, in voxels (the filler's coverage test needs it).
    pub inscribed_tetrahedron: f64,
}

/// Measure the alpha channel (the first channel) of a mask.
pub fn measure(mask: &Volume) -> MaskMeasures {
    let n = mask.channel_count();
    let alpha: Vec<f32> = mask.data().iter().step_by(n).copied().collect();
    let opaque = alpha.iter().filter(|a| **a >= OPAQUE).count() as f64 / alpha.len() as f64;
    let centre = opaque_centre(mask);
    let inner = directions(64).into_iter().map(|dir| opaque_reach(mask, centre, dir)).fold(f32::INFINITY, f32::min);
    MaskMeasures {
        opaque_fraction: opaque,
        falloff_width: band_width(mask),
        inscribed_tetrahedron: inner as f64 * (8.0f64 / 3.0).sqrt(),
    }
}

/// Median of 1 / |grad alpha| (central differences) over voxels with alpha in (0.1, 0.9).
fn band_width(mask: &Volume) -> f64 {
    let d = mask.dims();
    let a = |x: usize, y: usize, z: usize| mask.get(x, y, z, 0) as f64;
    let mut widths = Vec::new();
    for z in 1..d[2] - 1 {
        for y in 1..d[1] - 1 {
            for x in 1..d[0] - 1 {
                if !(0.1..0.9).contains(&a(x, y, z)) {
                    continue;
                }
                let g = Vec3::new(
                    (a(x + 1, y, z) - a(x - 1, y, z)) as f32,
                    (a(x, y + 1, z) - a(x, y - 1, z)) as f32,
                    (a(x, y, z + 1) - a(x, y, z - 1)) as f32,
                ) / 2.0;
                if g.length() > 1e-6 {
                    widths.push(1.0 / g.length() as f64);
                }
            }
        }
    }
    widths.sort_by(f64::total_cmp);
    widths.get(widths.len() / 2).copied().unwrap_or(0.0)
}

/// Mean position of the opaque voxels.
fn opaque_centre(mask: &Volume) -> Vec3 {
    let (mut sum, mut count) = (Vec3::ZERO, 0.0);
    let d = mask.dims();
    for z in 0..d[2] {
        for y in 0..d[1] {
            for x in 0..d[0] {
                if mask.get(x, y, z, 0) >= OPAQUE {
                    sum += Vec3::new(x as f32, y as f32, z as f32);
                    count += 1.0;
                }
            }
        }
    }
    if count > 0.0 { sum / count } else { Vec3::new(d[0] as f32, d[1] as f32, d[2] as f32) / 2.0 - 0.5 }
}

/// Distance along `dir` from `centre` to where alpha first drops below 0.999.
fn opaque_reach(mask: &Volume, centre: Vec3, dir: Vec3) -> f32 {
    let d = mask.dims();
    let mut out = [0.0f32];
    let mut r = 0.0;
    loop {
        let p = centre + dir * r;
        if (0..3).any(|k| p[k] < 0.0 || p[k] > (d[k] - 1) as f32) {
            return r;
        }
        mask.sample_trilinear(p, crate::volume::Edge::Clamp, &mut out);
        if out[0] < OPAQUE {
            return r;
        }
        r += 0.05;
    }
}

/// `count` directions spread over the sphere (Fibonacci lattice).
fn directions(count: usize) -> Vec<Vec3> {
    let golden = std::f32::consts::PI * (3.0 - 5.0f32.sqrt());
    (0..count)
        .map(|i| {
            let y = 1.0 - 2.0 * (i as f32 + 0.5) / count as f32;
            let r = (1.0 - y * y).sqrt();
            Vec3::new(r * (golden * i as f32).cos(), y, r * (golden * i as f32).sin())
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_falloff_band_is_as_wide_as_asked() {
        let m = splotch(48, 0.1, 3).unwrap();
        let measured = measure(&m);
        assert!((measured.falloff_width - 4.8).abs() <= 1.0, "{measured:?}");
        assert!(measured.opaque_fraction > 0.1 && measured.opaque_fraction < 0.5, "{measured:?}");
        assert!(measured.inscribed_tetrahedron > 20.0, "{measured:?}");
        let d = m.dims();
        for k in 0..d[0] {
            assert_eq!(m.get(k, 0, 0, 0), 0.0, "the corner rim is transparent");
        }
    }

    #[test]
    fn masks_replay_from_the_seed_and_differ_across_seeds() {
        assert_eq!(splotch(16, 0.1, 1).unwrap(), splotch(16, 0.1, 1).unwrap());
        assert_ne!(splotch(16, 0.1, 1).unwrap().data(), splotch(16, 0.1, 2).unwrap().data());
    }

    #[test]
    fn the_outer_mask_covers_the_depth_0_face_and_fades_before_the_sides() {
        let outer = layered(24, 0.1, 1, Layer::Outer, Axis::Z).unwrap();
        let inner = layered(24, 0.1, 1, Layer::Inner, Axis::Z).unwrap();
        for (mask, face) in [(&outer, 0), (&inner, 23)] {
            let opaque = (0..24 * 24).filter(|i| mask.get(i % 24, i / 24, face, 0) == 1.0).count();
            assert!(opaque >= 24 * 24 / 4, "{opaque} opaque voxels on the face");
            assert_eq!(mask.get(12, 12, face, 0), 1.0);
        }
        for mask in [&outer, &inner] {
            for z in 0..24 {
                for k in 0..24 {
                    let sides = [(0, k), (23, k), (k, 0), (k, 23)];
                    assert!(
                        sides.iter().all(|&(x, y)| mask.get(x, y, z, 0) == 0.0),
                        "a side at depth {z} is not clear"
                    );
                }
            }
        }
        assert!(outer.get(12, 12, 23, 0) == 0.0 && inner.get(12, 12, 0, 0) == 0.0);
    }

    #[test]
    fn masks_of_the_least_size_are_opaque_somewhere_for_every_seed_and_layer() {
        for seed in 1..=40 {
            for layer in Layer::ALL {
                let m = layered(SIZE.0, DEFAULT_FALLOFF, seed, layer, Axis::Z).unwrap();
                assert!(measure(&m).opaque_fraction > 0.0, "seed {seed}, {}", layer.name());
            }
        }
        let err = splotch(4, DEFAULT_FALLOFF, 1).unwrap_err().to_string();
        assert!(err.contains("size 4 is out of range; allowed 6 to 512"), "{err}");
        let err = splotch(64, 0.45, 1).unwrap_err().to_string();
        assert!(err.contains("opaque nowhere") && err.contains("smaller fall-off"), "{err}");
    }

    #[test]
    fn bad_falloffs_are_refused() {
        for f in [0.0, 0.5, -0.1, f32::NAN] {
            assert!(splotch(16, f, 1).unwrap_err().to_string().contains("outside (0, 0.5)"), "{f}");
        }
    }
}
