//! Procedural exemplars made from noise alone: marble (type 0), strata (type 1-b)
//! and wood (type 2-a). They need no input files, so a fresh clone has something
//! real to build, look at and test against.

use crate::error::{Error, Result};
use crate::noise::fbm;
use crate::progress::Progress;
use crate::texture_type::TextureType;
use crate::volume::{Channel, Meta, Volume};
use glam::Vec3;
use std::fmt;
use std::str::FromStr;

pub mod truths;

/// A procedural recipe.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Recipe {
    /// White marble with dark turbulent veins; isotropic and tileable in 3D.
    Marble,
    /// Sandstone strata stacked along z, with a Depth channel; tileable in x and y.
    Strata,
    /// A piece of a log: growth rings around an axis parallel to x, fibres along x.
    Wood,
    /// Sponge-cake crumb: pale yellow with fine grain (bubbles are scattered on top).
    Sponge,
    /// Whipped cream: near white with soft swirls.
    Cream,
    /// Chocolate glaze: dark brown with faint lighter streaks.
    Chocolate,
    /// A 3D Voronoi foam: stones of twelve greys with thin dark joints (a label volume).
    Foam,
    /// Long sinuous sand channels with levees in mud along x (a label volume of three).
    Channels,
}

impl Recipe {
    /// The channels the recipe's volume has: R, G, B (strata: and Depth).
    pub fn channels(self) -> Vec<Channel> {
        let mut channels = Channel::rgb();
        if self == Recipe::Strata {
            channels.push(Channel::Depth);
        }
        channels
    }

    /// All recipes.
    pub const ALL: [Recipe; 8] = [
        Recipe::Marble,
        Recipe::Strata,
        Recipe::Wood,
        Recipe::Sponge,
        Recipe::Cream,
        Recipe::Chocolate,
        Recipe::Foam,
        Recipe::Channels,
    ];

    /// The recipe's name in manifests.
    pub fn name(self) -> &'static str {
        match self {
            Recipe::Marble => "marble",
            Recipe::Strata => "strata",
            Recipe::Wood => "wood",
            Recipe::Sponge => "sponge",
            Recipe::Cream => "cream",
            Recipe::Chocolate => "chocolate",
            Recipe::Foam => "foam",
            Recipe::Channels => "channels",
        }
    }

    /// The LST type the recipe produces.
    pub fn texture_type(self) -> TextureType {
        match self {
            Recipe::Marble => TextureType::T0,
            Recipe::Strata => TextureType::T1b,
            Recipe::Wood => TextureType::T2a,
            Recipe::Sponge | Recipe::Cream | Recipe::Chocolate | Recipe::Foam => TextureType::T0,
            Recipe::Channels => TextureType::T1a,
        }
    }
}

impl fmt::Display for Recipe {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

impl FromStr for Recipe {
    type Err = Error;

    fn from_str(text: &str) -> Result<Recipe> {
        Recipe::ALL.into_iter().find(|r| r.name() == text).ok_or_else(|| {
            let names: Vec<&str> = Recipe::ALL.iter().map(|r| r.name()).collect();
            Error::invalid(format!("unknown procedural recipe {text:?}; allowed: {}", names.join(", ")))
        })
    }
}

/// Make the volume of `recipe` with `dims` from `seed`.
pub fn generate(recipe: Recipe, dims: [usize; 3], seed: u64) -> Result<Volume> {
    generate_with(recipe, dims, seed, &crate::progress::NoProgress)
}

/// [`generate`], telling `progress` the share of the volume made.
pub fn generate_with(recipe: Recipe, dims: [usize; 3], seed: u64, progress: &dyn Progress) -> Result<Volume> {
    let size = Vec3::new(dims[0] as f32, dims[1] as f32, dims[2] as f32);
    let volume = match recipe {
        Recipe::Marble => Volume::from_fn_par_with(
            dims,
            recipe.channels(),
            |x, y, z, o| o.copy_from_slice(&marble(seed, unit(x, y, z, size))),
            progress,
        )?,
        Recipe::Strata => {
            let channels = recipe.channels();
            let paint = |x, y, z, o: &mut [f32]| {
                o[..3].copy_from_slice(&strata(seed, unit(x, y, z, size)));
                o[3] = if dims[2] > 1 { z as f32 / (dims[2] - 1) as f32 } else { 0.0 };
            };
            Volume::from_fn_par_with(dims, channels, paint, progress)?
        }
        Recipe::Wood => Volume::from_fn_par_with(
            dims,
            recipe.channels(),
            |x, y, z, o| o.copy_from_slice(&wood(seed, unit(x, y, z, size), size)),
            progress,
        )?,
        Recipe::Sponge | Recipe::Cream | Recipe::Chocolate => {
            let paint = match recipe {
                Recipe::Sponge => sponge,
                Recipe::Cream => cream,
                _ => chocolate,
            };
            let fill = |x, y, z, o: &mut [f32]| o.copy_from_slice(&paint(seed, unit(x, y, z, size)));
            Volume::from_fn_par_with(dims, recipe.channels(), fill, progress)?
        }
        Recipe::Foam => {
            let foam = truths::Foam::new(dims, seed);
            Volume::from_fn_par_with(dims, recipe.channels(), |x, y, z, o| o.fill(foam.label(x, y, z)), progress)?
        }
        Recipe::Channels => {
            let channels = truths::Channels::new(dims, seed);
            Volume::from_fn_par_with(dims, recipe.channels(), |x, y, z, o| o.fill(channels.label(x, y, z)), progress)?
        }
    };
    let mut meta = Meta { texture_type: Some(recipe.texture_type()), provenance: Vec::new() };
    meta.set("recipe", format!("procedural:{recipe}"));
    meta.set("seed", seed.to_string());
    Ok(volume.with_meta(meta))
}

/// Voxel centre in [0, 1)^3.
fn unit(x: usize, y: usize, z: usize, size: Vec3) -> Vec3 {
    (Vec3::new(x as f32, y as f32, z as f32) + 0.5) / size
}

fn marble(seed: u64, p: Vec3) -> [f32; 3] {
    let turbulence = fbm(seed, p * 4.0, [4; 3], 5);
    let phase = std::f32::consts::TAU * (2.0 * p.x + p.y + p.z) + 5.0 * turbulence;
    let vein = 1.0 - phase.sin().abs().powf(0.25);
    let grain = 0.04 * fbm(seed ^ 0xabc, p * 16.0, [16; 3], 2);
    let base = [0.93 + grain, 0.92 + grain, 0.89 + grain];
    mix(base, [0.28, 0.31, 0.33], vein)
}

const SANDSTONE: [[f32; 3]; 5] =
    [[0.80, 0.62, 0.42], [0.66, 0.45, 0.30], [0.88, 0.76, 0.58], [0.55, 0.38, 0.28], [0.74, 0.56, 0.38]];

fn strata(seed: u64, p: Vec3) -> [f32; 3] {
    let wave = 0.06 * fbm(seed, Vec3::new(p.x * 3.0, p.y * 3.0, p.z * 2.0), [3, 3, 64], 3);
    let t = (p.z + wave) * 7.0;
    let band = t.floor().rem_euclid(SANDSTONE.len() as f32) as usize;
    let next = (band + 1) % SANDSTONE.len();
    let edge = ((t.fract() - 0.85) / 0.15).clamp(0.0, 1.0);
    let grain = 0.05 * fbm(seed ^ 0x51, p * 24.0, [24; 3], 2);
    mix(SANDSTONE[band], SANDSTONE[next], edge).map(|c| c + grain)
}

fn wood(seed: u64, p: Vec3, size: Vec3) -> [f32; 3] {
    let aspect = size / size.max_element();
    let q = p * aspect;
    let axis = Vec3::new(q.x, -0.35, 0.3 * aspect.z);
    let fibre = 0.15 * fbm(seed, Vec3::new(p.x * 1.0, p.y * 6.0, p.z * 6.0), [1, 6, 6], 3);
    let radius = (q - axis).length() + 0.02 * fibre;
    let ring = (radius * 14.0).fract();
    let late = ((ring - 0.7) / 0.3).clamp(0.0, 1.0);
    let streak = 0.06 * fbm(seed ^ 0x77, Vec3::new(p.x * 2.0, p.y * 40.0, p.z * 40.0), [2, 40, 40], 2);
    mix([0.82, 0.62, 0.40], [0.52, 0.32, 0.18], late).map(|c| c + streak)
}

fn sponge(seed: u64, p: Vec3) -> [f32; 3] {
    let crumb = fbm(seed, p * 12.0, [12; 3], 3);
    let fine = fbm(seed ^ 0x5f, p * 32.0, [32; 3], 2);
    mix([0.95, 0.82, 0.52], [0.80, 0.62, 0.34], (0.45 + 0.9 * crumb + 0.5 * fine).clamp(0.0, 1.0))
}

fn cream(seed: u64, p: Vec3) -> [f32; 3] {
    let swirl = fbm(seed, p * 3.0, [3; 3], 4);
    let band = (std::f32::consts::TAU * (p.y * 2.0 + 2.0 * swirl)).sin() * 0.5 + 0.5;
    let grain = 0.015 * fbm(seed ^ 0x3c, p * 24.0, [24; 3], 2);
    mix([0.99, 0.97, 0.91], [0.93, 0.88, 0.76], 0.35 * band).map(|c| c + grain)
}

/// Isotropic on purpose: a type-0 material is pasted at a random orientation per patch,
/// so sheen streaks running one way would cross at random angles at the seams.
fn chocolate(seed: u64, p: Vec3) -> [f32; 3] {
    let swirl = fbm(seed, p * 4.0, [4; 3], 4);
    let sheen = (0.5 + 1.2 * swirl).clamp(0.0, 1.0).powi(3);
    mix([0.24, 0.13, 0.07], [0.45, 0.28, 0.17], sheen)
}

fn mix(a: [f32; 3], b: [f32; 3], t: f32) -> [f32; 3] {
    std::array::from_fn(|k| (a[k] + (b[k] - a[k]) * t).clamp(0.0, 1.0))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::volume::Axis;

    #[test]
    fn same_seed_same_volume_other_seed_other_volume() {
        let a = generate(Recipe::Marble, [12, 12, 12], 5).unwrap();
        let b = generate(Recipe::Marble, [12, 12, 12], 5).unwrap();
        let c = generate(Recipe::Marble, [12, 12, 12], 6).unwrap();
        assert_eq!(a, b);
        assert_ne!(a.data(), c.data());
        assert_eq!(a.meta.get("seed"), Some("5"));
    }

    #[test]
    fn strata_depth_rises_along_z_and_colour_varies_with_it() {
        let v = generate(Recipe::Strata, [16, 16, 32], 1).unwrap();
        assert_eq!(v.meta.texture_type, Some(TextureType::T1b));
        let depth = v.channel_index(&Channel::Depth).unwrap();
        assert_eq!(v.get(3, 3, 0, depth), 0.0);
        assert_eq!(v.get(3, 3, 31, depth), 1.0);
        // Red varies little within a z-slice compared with the whole volume.
        let total = v.channel_stats(8)[0].std.powi(2);
        let within: f64 = (0..32)
            .map(|z| {
                let s = v.slice(Axis::Z, z).unwrap();
                let reds: Vec<f32> = s.data().chunks(4).map(|p| p[0]).collect();
                crate::volume::stats_of("R", reds.iter(), 8).std.powi(2)
            })
            .sum::<f64>()
            / 32.0;
        assert!(within < 0.35 * total, "within-slice variance {within} vs total {total}");
    }

    #[test]
    fn marble_tiles_seamlessly() {
        let v = generate(Recipe::Marble, [16, 16, 16], 2).unwrap();
        let step = |a: [usize; 3], b: [usize; 3]| {
            let (p, q) = (v.voxel(a[0], a[1], a[2]), v.voxel(b[0], b[1], b[2]));
            p.iter().zip(q).map(|(x, y)| (x - y).abs()).fold(0.0, f32::max)
        };
        let mut wrap_max: f32 = 0.0;
        let mut inner_max: f32 = 0.0;
        for y in 0..16 {
            for z in 0..16 {
                wrap_max = wrap_max.max(step([15, y, z], [0, y, z]));
                inner_max = inner_max.max(step([7, y, z], [8, y, z]));
            }
        }
        assert!(wrap_max < 2.0 * inner_max + 0.05, "wrap {wrap_max} inner {inner_max}");
        assert!("granite".parse::<Recipe>().unwrap_err().to_string().contains("allowed"));
    }
}
