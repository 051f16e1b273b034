//! A labelled set of solids of known texture type, made by the project: procedural noise
//! and recipes, swept sections, scattered seeds, blocks, and solids synthesized from the
//! project's photos and drawings. Each case says which type it is and why; the classifier's
//! test turns each one into all six axis orders.

use glam::Vec3;
use rand::{RngExt, SeedableRng};
use rand_pcg::Pcg64;
use solidtex::noise::fbm;
use solidtex::procedural::{Recipe, generate};
use solidtex::sweep::{Noise, Skin, SkinLook, Sweep, sweep};
use solidtex::synth::{Exemplars, LayeredParams, SynthParams, synthesize, synthesize_layered};
use solidtex::volume::{Axis, Channel, Image2d, Volume};
use solidtex::{TextureType, progress::NoProgress};
use std::path::Path;

/// Side of the generated solids.
const S: usize = 32;

/// One solid of known type.
pub struct Case {
    pub name: String,
    pub volume: Volume,
    pub want: TextureType,
    /// The axis the type names: a 1-a texture's fibre (or sheet normal) axis, the depth
    /// axis of 1-b and 2-b. None for 0 and 2-a (2-a's three axes all differ).
    pub axis: Option<Axis>,
    pub why: &'static str,
}

fn case(name: impl Into<String>, volume: Volume, want: TextureType, axis: Option<Axis>, why: &'static str) -> Case {
    Case { name: name.into(), volume, want, axis, why }
}

/// Every case of the set, unpermuted.
pub fn cases() -> Vec<Case> {
    let mut out = generated(1..=4);
    out.extend(synthesized());
    out
}

/// The generated cases for these seeds (other seeds make a held-out check).
pub fn generated(seeds: std::ops::RangeInclusive<u64>) -> Vec<Case> {
    let mut out = Vec::new();
    for seed in seeds {
        out.extend(isotropic(seed));
        out.extend(fibrous(seed));
        out.extend(layered(seed));
        out.extend(three_way(seed));
        out.extend(depth_and_axis(seed));
    }
    out
}

fn grey(f: impl Fn(Vec3) -> f32 + Sync) -> Volume {
    Volume::from_fn([S; 3], Channel::grey(), |x, y, z, o| o[0] = f(Vec3::new(x as f32, y as f32, z as f32) / S as f32))
        .unwrap()
}

fn rgb(f: impl Fn(Vec3) -> [f32; 3] + Sync) -> Volume {
    Volume::from_fn([S; 3], Channel::rgb(), |x, y, z, o| {
        o.copy_from_slice(&f(Vec3::new(x as f32, y as f32, z as f32) / S as f32))
    })
    .unwrap()
}

/// fbm with `cells` noise cells along each axis of the unit cube (tiling).
fn noise(seed: u64, p: Vec3, cells: [i64; 3], octaves: u32) -> f32 {
    fbm(seed, p * Vec3::new(cells[0] as f32, cells[1] as f32, cells[2] as f32), cells, octaves)
}

fn isotropic(seed: u64) -> Vec<Case> {
    let t = TextureType::T0;
    let fine = grey(|p| 0.5 + 0.4 * noise(seed, p, [8; 3], 3));
    let coarse = grey(|p| 0.5 + 0.4 * noise(seed, p, [3; 3], 4));
    let ridged = grey(|p| 1.0 - noise(seed, p, [5; 3], 3).abs().powf(0.5));
    vec![
        case(format!("fine noise {seed}"), fine, t, None, "fbm with equal cells on every axis"),
        case(format!("coarse noise {seed}"), coarse, t, None, "fbm with equal cells on every axis"),
        case(format!("ridged veins {seed}"), ridged, t, None, "the zero sheets of isotropic noise: veins every way"),
        case(format!("marble {seed}"), generate(Recipe::Marble, [S; 3], seed).unwrap(), t, None, "the marble recipe"),
        case(format!("sponge {seed}"), generate(Recipe::Sponge, [S; 3], seed).unwrap(), t, None, "isotropic crumb"),
        case(format!("foam {seed}"), generate(Recipe::Foam, [S; 3], seed).unwrap(), t, None, "3D Voronoi stones"),
        case(format!("seeds in noise {seed}"), seeds(seed), t, None, "round seeds scattered in isotropic flesh"),
    ]
}

/// Dark balls at random places in pale isotropic noise.
fn seeds(seed: u64) -> Volume {
    let mut rng = Pcg64::seed_from_u64(seed);
    let balls: Vec<(Vec3, f32)> =
        (0..40).map(|_| (Vec3::new(rng.random(), rng.random(), rng.random()), rng.random_range(0.03..0.07))).collect();
    rgb(|p| {
        let flesh = 0.7 + 0.1 * noise(seed, p, [6; 3], 2);
        let inside = balls.iter().any(|(c, r)| wrapped(p - *c).length() < *r);
        if inside { [0.15, 0.1, 0.05] } else { [flesh, flesh * 0.9, flesh * 0.5] }
    })
}

/// The shortest offset on the unit torus.
fn wrapped(v: Vec3) -> Vec3 {
    v - v.round()
}

fn fibrous(seed: u64) -> Vec<Case> {
    let t = TextureType::T1a;
    let x = Some(Axis::X);
    let fibre = |cells: i64, along: f32| {
        grey(move |p| {
            let section = noise(seed, Vec3::new(0.0, p.y, p.z), [1, cells, cells], 3);
            0.5 + 0.4 * section + along * noise(seed ^ 9, p, [8; 3], 2)
        })
    };
    let sheets = rgb(|p| {
        let streak = noise(seed, p, [2, 2, 8], 4);
        let sheen = (0.5 + 1.2 * streak).clamp(0.0, 1.0).powi(3);
        [0.24 + 0.2 * sheen, 0.13 + 0.15 * sheen, 0.07 + 0.1 * sheen]
    });
    let stretched = grey(|p| 0.5 + 0.4 * noise(seed, p, [2, 8, 8], 3));
    vec![
        case(format!("thin clean fibres {seed}"), fibre(8, 0.0), t, x, "a noise section swept along x"),
        case(
            format!("thick noisy fibres {seed}"),
            fibre(3, 0.08),
            t,
            x,
            "a coarse section swept along x, noise along it",
        ),
        case(format!("stretched noise {seed}"), stretched, t, x, "noise four times longer along x"),
        case(
            format!("flat streaks {seed}"),
            sheets,
            t,
            Some(Axis::Z),
            "noise four times shorter along z: sheets, not layers",
        ),
    ]
}

fn layered(seed: u64) -> Vec<Case> {
    let t = TextureType::T1b;
    let z = Some(Axis::Z);
    let bands = |cells: i64, grain: f32| {
        rgb(move |p| {
            let band = 0.5 + 0.4 * noise(seed, Vec3::new(0.5, 0.5, p.z), [1, 1, cells], 2);
            let g = grain * noise(seed ^ 2, p, [10; 3], 2);
            [band + g, band * 0.9 + g, band * 0.7]
        })
    };
    vec![
        case(
            format!("strata recipe {seed}"),
            generate(Recipe::Strata, [S; 3], seed).unwrap(),
            t,
            z,
            "sandstone bands along z",
        ),
        case(format!("thick clean layers {seed}"), bands(3, 0.03), t, z, "few bands along z, little grain"),
        case(format!("thin grainy layers {seed}"), bands(10, 0.12), t, z, "many bands along z under strong grain"),
        case(format!("cake {seed}"), cake(seed), t, z, "sponge, cream and glaze in layers along z"),
    ]
}

/// A layer cake: crumb, cream, crumb, cream, glaze, from z = 0 up.
fn cake(seed: u64) -> Volume {
    rgb(|p| {
        let wave = 0.03 * noise(seed, p, [3, 3, 1], 2);
        let crumb = 0.1 * noise(seed ^ 4, p, [10; 3], 2);
        match ((p.z + wave) * 5.0) as i32 {
            0 | 2 => [0.9 + crumb, 0.75 + crumb, 0.45],
            1 | 3 => [0.98, 0.95 + crumb * 0.2, 0.88],
            _ => [0.3 + crumb * 0.5, 0.17, 0.08],
        }
    })
}

fn three_way(seed: u64) -> Vec<Case> {
    let t = TextureType::T2a;
    let three = grey(|p| 0.5 + 0.4 * noise(seed, p, [1, 4, 12], 3));
    vec![
        case(
            format!("wood recipe {seed}"),
            generate(Recipe::Wood, [64; 3], seed).unwrap(),
            t,
            None,
            "rings round an axis off the solid: planks (64 voxels: 32 would alias the rings)",
        ),
        case(format!("three scales {seed}"), three, t, None, "noise cells 1, 4 and 12 along x, y, z"),
        case(format!("bricks {seed}"), bricks(seed), t, None, "8 x 4 x 2.5-voxel blocks in staggered courses"),
    ]
}

/// Bricks 8 long in x, 4 deep in y and 2.5 high in z, courses offset, with mortar.
fn bricks(seed: u64) -> Volume {
    rgb(|p| {
        let q = p * S as f32;
        let course = (q.z / 2.5).floor();
        let x = q.x + course * 4.0 + (seed as f32) * 3.0;
        let mortar = (q.z % 2.5) < 0.6 || (x % 8.0) < 1.0 || (q.y % 4.0) < 1.0;
        let spot = 0.08 * noise(seed, p, [8; 3], 2);
        if mortar { [0.75, 0.72, 0.68] } else { [0.6 + spot, 0.25 + spot, 0.18] }
    })
}

fn depth_and_axis(seed: u64) -> Vec<Case> {
    let t = TextureType::T2b;
    let z = Some(Axis::Z);
    let mut out = Vec::new();
    for (name, amplitude) in [("kiwi", 1.2), ("carrot", 0.4), ("trunk", 2.0)] {
        let image = solidtex::sections::draw(name, S, S, seed).unwrap();
        for skin in [false, true] {
            let params = Sweep {
                length: S,
                axis: Axis::X,
                depth_axis: Some(Axis::Z),
                noise: Some(Noise { amplitude, frequency: 4.0, jitter: 0.02 }),
                skin: skin.then_some(Skin { look: SkinLook::Colour([0.3, 0.2, 0.1]), width: 2.0, width_noise: 0.5 }),
                displacement: None,
            };
            let what = if skin { "with a skin" } else { "no skin" };
            out.push(case(
                format!("{name} sweep, {what} {seed}"),
                sweep(&image, &params, seed).unwrap(),
                t,
                z,
                "a drawn section (rays or rings along depth z) swept along x",
            ));
        }
    }
    let ramp = rgb(|p| {
        // luminance rises with depth z
        let fibre = 0.1 * noise(seed, Vec3::new(0.0, p.y, p.z), [1, 8, 8], 2);
        let d = p.z;
        [0.2 + 0.6 * d + fibre, 0.3 + 0.4 * d + fibre, 0.2 + fibre]
    });
    out.push(case(format!("fibres over a ramp {seed}"), ramp, t, z, "fibres along x, colour changing with depth z"));
    out
}

/// The project's photos.
fn photo(name: &str, side: usize) -> Image2d {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("exemplars").join(name);
    solidtex::io::read_image_fit(&path, Some(side)).unwrap()
}

fn params() -> SynthParams {
    SynthParams { size: [S; 3], levels: 2, ..SynthParams::default() }
}

/// Solids synthesized from the project's photos and drawings (homogeneous and layered).
fn synthesized() -> Vec<Case> {
    let mut out = Vec::new();
    let one = |image: &Image2d, seed| {
        synthesize(Exemplars { x: image, y: None, z: None }, &params(), seed, &NoProgress).unwrap()
    };
    let gravel = photo("gravel_photo.png", 64);
    let grass = photo("grass_photo.png", 64);
    out.push(case(
        "gravel synthesized",
        one(&gravel, 1),
        TextureType::T0,
        None,
        "one isotropic photo for all three cuts",
    ));
    out.push(case(
        "grass synthesized",
        one(&grass, 2),
        TextureType::T0,
        None,
        "one isotropic photo for all three cuts",
    ));
    let wood = generate(Recipe::Wood, [64; 3], 5).unwrap();
    let cuts = [Axis::X, Axis::Y, Axis::Z].map(|a| wood.slice(a, 32).unwrap());
    let three = Exemplars { x: &cuts[0], y: Some(&cuts[1]), z: Some(&cuts[2]) };
    out.push(case(
        "wood synthesized",
        synthesize(three, &params(), 3, &NoProgress).unwrap(),
        TextureType::T2a,
        None,
        "three different cuts of the wood recipe",
    ));
    let strata = colours_only(&generate(Recipe::Strata, [64; 3], 6).unwrap().slice(Axis::X, 10).unwrap());
    let trunk = solidtex::sections::draw("trunk", 64, 64, 2).unwrap();
    for (name, image, seed) in [("strata", &strata, 4), ("trunk rings", &trunk, 5)] {
        let layered = SynthParams { size: [S, S, 2 * S], ..params() };
        let volume = synthesize_layered(image, None, &layered, &LayeredParams::default(), seed, &NoProgress).unwrap();
        out.push(case(
            format!("{name} synthesized in layers"),
            volume,
            TextureType::T1b,
            Some(Axis::Z),
            "layered synthesis: the image's rows along depth z",
        ));
    }
    out
}

/// The image's R, G and B.
fn colours_only(image: &Image2d) -> Image2d {
    let n = image.channel_count();
    let data = image.data().chunks_exact(n).flat_map(|p| p[..3].to_vec()).collect();
    Image2d::from_data(image.width(), image.height(), Channel::rgb(), data).unwrap()
}
