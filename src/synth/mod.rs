//! 2D-to-3D solid texture synthesis (Kopf et al. 2007, thesis §4.1) and its layered
//! extension (thesis §4.2 and the poster).
//!
//! ```text
//!  exemplar pyramid (Gaussian)          volume, coarsest level first
//!  E^0 <- E^1 <- E^2                    random (or depth-aware) init
//!                                       per level, until converged:
//!                                         search:   best exemplar neighbourhood per voxel
//!                                                   and axis (PCA + k-coherence)
//!                                         optimize: blend the matches' predictions,
//!                                                   weight d^-1.2 and histogram matching
//!                                       upsample colours and matches to the next level
//! ```
//!
//! Deterministic: every random choice comes from a hash of (seed, level, iteration,
//! voxel, axis), and every pass computes each voxel from the previous state only, so
//! the output is bit-identical on any number of threads.

pub mod coords;
pub mod cube;
mod depth;
pub use depth::depth_error;
mod direction;
mod driver;
pub mod edges;
pub(crate) mod exemplar;
pub mod finer;
mod grid;
pub(crate) mod knn;
pub mod occupancy;
mod optimize;
mod params;
pub mod patches;
mod pca;
pub mod region;
mod search;
pub(crate) mod spectrum;
pub mod triples;
mod whole;

pub use direction::{
    DIRECTIONAL, Direction, LAYERED_ROWS, RowShares, direction, directional_warning, layering_warning, row_shares,
};
pub(crate) use driver::image_pyramid;
pub use params::{Core, LayeredParams, SynthParams};

use crate::error::{Error, Result};
use crate::progress::Progress;
use crate::texture_type::TextureType;
use crate::volume::{Channel, Image2d, Meta, Volume};
use driver::{Init, Job};

/// The exemplars of homogeneous synthesis: the cross-sections orthogonal to x, y and z.
/// A missing `y` is `x`; a missing `z` is `y` (so one image is isotropic, two make a
/// type 1-a texture whose axis is x, three a type 2-a texture).
#[derive(Debug, Clone, Copy)]
pub struct Exemplars<'a> {
    /// Cross-section orthogonal to x.
    pub x: &'a Image2d,
    /// Cross-section orthogonal to y.
    pub y: Option<&'a Image2d>,
    /// Cross-section orthogonal to z.
    pub z: Option<&'a Image2d>,
}

impl Exemplars<'_> {
    /// The same exemplars with a cross-section that repeats the one it defaults to (the same
    /// picture read from two files, or one file named twice) left out: one image named for
    /// every plane is the isotropic case, whatever the command line said.
    fn without_repeats(self) -> Self {
        let y = self.y.filter(|y| !same_image(y, self.x));
        let z = self.z.filter(|z| !same_image(z, y.unwrap_or(self.x)));
        Exemplars { x: self.x, y, z }
    }
}

/// Whether two images hold the same pixels (bit for bit, at the same size and channels).
fn same_image(a: &Image2d, b: &Image2d) -> bool {
    let size = |i: &Image2d| (i.width(), i.height(), i.channels().to_vec());
    std::ptr::eq(a, b) || size(a) == size(b) && a.data().iter().zip(b.data()).all(|(p, q)| p.to_bits() == q.to_bits())
}

/// Synthesize a homogeneous solid texture.
pub fn synthesize(ex: Exemplars, params: &SynthParams, seed: u64, progress: &dyn Progress) -> Result<Volume> {
    let ex = ex.without_repeats();
    let ey = ex.y.unwrap_or(ex.x);
    let ez = ex.z.unwrap_or(ey);
    let images = [ex.x, ey, ez];
    check_exemplars(&images, &["Ex", "Ey", "Ez"], params)?;
    let solid = if blends(params) {
        let weights = vec![1.0; ex.x.channel_count()];
        let start = start_samples(params, ex.x.channels(), false)?;
        let job = Job {
            images: [Some(ex.x), Some(ey), Some(ez)],
            weights,
            init: Init::Random,
            anti_sweeping: false,
            start: start.as_deref(),
        };
        whole::Whole { samples: driver::run(&job, params, seed, progress)?, patches: None, finer: None }
    } else {
        whole::synthesize(images, false, params, seed, progress)?
    };
    let kind = match (ex.y, ex.z) {
        (None, None) => TextureType::T0,
        (_, None) => TextureType::T1a,
        _ => TextureType::T2a,
    };
    finish(params, ex.x.channels().to_vec(), solid, kind, "synth", seed)
}

/// Synthesize a layered (type 1-b) solid texture from one exemplar parallel to the
/// depth direction: image rows run along depth, which becomes the volume's z axis.
/// `depth` gives the depth of every exemplar pixel (first channel, 0 = outside); by
/// default it is the row coordinate. The output carries a `Depth` channel.
pub fn synthesize_layered(
    exemplar: &Image2d,
    depth: Option<&Image2d>,
    params: &SynthParams,
    layered: &LayeredParams,
    seed: u64,
    progress: &dyn Progress,
) -> Result<Volume> {
    check_exemplars(&[exemplar], &["exemplar"], params)?;
    let with_depth = add_depth(exemplar, depth)?;
    let solid = if blends(params) {
        let mut weights = vec![1.0; exemplar.channel_count()];
        weights.push(layered.depth_weight);
        let start = start_samples(params, exemplar.channels(), true)?;
        let job = Job {
            images: [Some(&with_depth), Some(&with_depth), None],
            weights,
            init: Init::ByDepth,
            anti_sweeping: layered.anti_sweeping,
            start: start.as_deref(),
        };
        whole::Whole { samples: driver::run(&job, params, seed, progress)?, patches: None, finer: None }
    } else {
        whole::synthesize([&with_depth; 3], true, params, seed, progress)?
    };
    let volume = finish(params, with_depth.channels().to_vec(), solid, TextureType::T1b, "synth-layered", seed)?;
    if let Some(error) = depth::depth_error(&volume).filter(|e| *e > DEPTH_STRAYS) {
        progress.warn(&format!(
            "the layers stray from their depths (the Depth channel is {error:.2} from each slice's depth on average, \
             more than {DEPTH_STRAYS}): a solid {} voxels deep is shallow for the blend core; a deeper solid or the \
             coordinate core (the default for layered solids) keeps them",
            volume.dims()[2]
        ));
    }
    Ok(volume)
}

/// The mean distance of a layered solid's Depth from its slices' depths past which the
/// synthesis warns: a solid whose layers hold their depths measures 0.01-0.03.
const DEPTH_STRAYS: f64 = 0.08;

/// Whether the blend core runs: asked for, or to refine a start volume.
fn blends(params: &SynthParams) -> bool {
    params.core == Core::Blend || params.start.is_some()
}

fn finish(
    params: &SynthParams,
    channels: Vec<Channel>,
    solid: whole::Whole,
    kind: TextureType,
    recipe: &str,
    seed: u64,
) -> Result<Volume> {
    let mut meta = Meta { texture_type: Some(kind), provenance: Vec::new() };
    meta.set("recipe", recipe);
    meta.set("seed", seed.to_string());
    meta.set("levels", params.levels.to_string());
    meta.set("core", if blends(params) { Core::Blend } else { Core::Coordinates }.to_string());
    if let Some(p) = solid.patches {
        meta.set(patches::COHERENT_PAIRS_KEY, format!("{:.4}", p.coherent_pairs));
        meta.set(patches::LARGEST_KEY, format!("{:.4}", p.largest));
    }
    if let Some(k) = solid.finer {
        meta.set(finer::FINER_KEY, ["x", "y", "z"][k]);
    }
    Ok(Volume::from_data(params.size, channels, solid.samples)?.with_meta(meta))
}

/// The start volume's samples with the exemplar's `channels` (layered: plus a Depth
/// channel `z / (Z - 1)`, replacing any it has), or `None` without a start volume.
fn start_samples(params: &SynthParams, channels: &[Channel], layered: bool) -> Result<Option<Vec<f32>>> {
    check_start(params, channels, layered)?;
    let Some(start) = &params.start else { return Ok(None) };
    let colours = start_channels(start, layered);
    let [dx, dy, dz] = start.dims();
    let per = start.channel_count();
    let mut out = Vec::with_capacity(dx * dy * dz * (channels.len() + usize::from(layered)));
    for (v, voxel) in start.data().chunks_exact(per).enumerate() {
        out.extend(colours.iter().map(|&c| voxel[c]));
        if layered {
            out.push((v / (dx * dy)) as f32 / (dz - 1).max(1) as f32);
        }
    }
    Ok(Some(out))
}

/// The start volume's channels that synthesis reads (layered: all but Depth).
fn start_channels(start: &Volume, layered: bool) -> Vec<usize> {
    (0..start.channel_count()).filter(|&c| !(layered && start.channels()[c] == Channel::Depth)).collect()
}

/// Whether `params.start` (if any) fits an exemplar with `channels`: the asked size, as
/// many channels (layered: a Depth channel aside), finite samples.
pub fn check_start(params: &SynthParams, channels: &[Channel], layered: bool) -> Result<()> {
    let Some(start) = &params.start else { return Ok(()) };
    if start.dims() != params.size {
        let [x, y, z] = start.dims();
        let [sx, sy, sz] = params.size;
        return Err(Error::invalid(format!(
            "the start volume is {x}x{y}x{z} voxels but the size asked is {sx}x{sy}x{sz}; they must be equal"
        )));
    }
    if start_channels(start, layered).len() != channels.len() {
        return Err(Error::invalid(format!(
            "the start volume has channels {} but the exemplar has {}; they must have as many{}",
            crate::volume::channel_names(start.channels()),
            crate::volume::channel_names(channels),
            if layered { " (a Depth channel aside)" } else { "" }
        )));
    }
    match start.first_non_finite() {
        Some([x, y, z, c]) => {
            Err(Error::invalid(format!("the start volume: voxel ({x}, {y}, {z}) channel {c} is not finite")))
        }
        None => Ok(()),
    }
}

/// Channel counts agree, samples are finite, and the coarsest level holds a neighbourhood;
/// a problem with one image is an [`Error::Exemplar`] naming which (its place in `images`).
fn check_exemplars(images: &[&Image2d], names: &[&str], params: &SynthParams) -> Result<()> {
    params.check(images[0].channel_count() + 1)?;
    for (which, (image, name)) in images.iter().zip(names).enumerate() {
        let fault = |message: String| Error::exemplar(which, message);
        if image.channel_count() != images[0].channel_count() {
            return Err(fault(format!(
                "{name} has {} channel(s) ({}), {} has {} ({}); all exemplars need the same channels",
                image.channel_count(),
                crate::volume::channel_names(image.channels()),
                names[0],
                images[0].channel_count(),
                crate::volume::channel_names(images[0].channels())
            )));
        }
        if let Some([x, y, c]) = image.first_non_finite() {
            return Err(fault(format!("{name}: pixel ({x}, {y}) channel {c} is not finite")));
        }
        // every pixel's neighbourhood as a vector (f32), with a channel of features or depth
        let vectors = image.width() as u128
            * image.height() as u128
            * (params.neighbourhood * params.neighbourhood * (image.channel_count() + 1) * 4) as u128;
        if vectors > params.budget_bytes as u128 {
            return Err(fault(format!(
                "{name} is {}x{} pixels: preparing it for synthesis takes about {:.1} GB (every pixel's {n}x{n} \
                 neighbourhood), over the memory budget of {:.1} GB; shrink it with --max-exemplar (128 or 256 for \
                 a photo) or raise SOLIDTEX_MAX_BYTES",
                image.width(),
                image.height(),
                vectors as f64 / 1e9,
                params.budget_bytes as f64 / 1e9,
                n = params.neighbourhood
            )));
        }
        let shrink = |s: usize| (1..params.levels).fold(s, |s, _| s.div_ceil(2));
        let (w, h) = (shrink(image.width()), shrink(image.height()));
        let need = params.neighbourhood + 2;
        if w < need || h < need {
            return Err(fault(too_small(name, image, params.levels, [w, h], params.neighbourhood)));
        }
    }
    Ok(())
}

/// Why exemplar `name` (`image`) is too small for `levels` levels of `n` x `n`
/// neighbourhoods, its coarsest level being `w` x `h` pixels, and what to do.
pub(crate) fn too_small(name: &str, image: &Image2d, levels: usize, [w, h]: [usize; 2], n: usize) -> String {
    let (need, size) = (n + 2, format!("{}x{}", image.width(), image.height()));
    if levels > 1 {
        format!(
            "{name} is {size} pixels; at {levels} levels its coarsest level is {w}x{h}, smaller than the \
             {need}x{need} that neighbourhoods of {n}x{n} pixels need; use fewer levels or a larger exemplar"
        )
    } else {
        format!(
            "{name} is {size} pixels, smaller than the {need}x{need} that neighbourhoods of {n}x{n} pixels need; \
             give an exemplar of at least {need}x{need} pixels"
        )
    }
}

/// The exemplar with a Depth channel appended (from `depth`, else the row coordinate).
fn add_depth(exemplar: &Image2d, depth: Option<&Image2d>) -> Result<Image2d> {
    let (w, h) = (exemplar.width(), exemplar.height());
    if let Some(d) = depth {
        if (d.width(), d.height()) != (w, h) {
            return Err(Error::invalid(format!(
                "the depth image is {}x{} pixels but the exemplar is {w}x{h}; they must be the same size",
                d.width(),
                d.height()
            )));
        }
        if let Some([x, y, _]) = d.first_non_finite() {
            return Err(Error::invalid(format!("depth image: pixel ({x}, {y}) is not finite")));
        }
    }
    let mut channels = exemplar.channels().to_vec();
    channels.retain(|c| *c != Channel::Depth);
    if channels.len() != exemplar.channel_count() {
        return Err(Error::invalid("the exemplar already has a Depth channel; give it as --depth instead"));
    }
    channels.push(Channel::Depth);
    let mut data = Vec::with_capacity(w * h * channels.len());
    for y in 0..h {
        for x in 0..w {
            data.extend_from_slice(exemplar.pixel(x, y));
            data.push(match depth {
                Some(d) => d.pixel(x, y)[0],
                None => y as f32 / (h - 1).max(1) as f32,
            });
        }
    }
    Image2d::from_data(w, h, channels, data)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// An exemplar too small for its levels gets the way out that exists: fewer levels, or
    /// at one level the least size.
    #[test]
    fn a_small_exemplar_is_told_what_size_it_needs() {
        let tiny = Image2d::from_data(4, 4, Channel::grey(), vec![0.5; 16]).unwrap();
        let one = too_small("Ex", &tiny, 1, [4, 4], 5);
        assert_eq!(
            one,
            "Ex is 4x4 pixels, smaller than the 7x7 that neighbourhoods of 5x5 pixels need; give an exemplar of at least 7x7 pixels"
        );
        let three = too_small("Ex", &tiny, 3, [1, 1], 5);
        assert!(three.contains("at 3 levels its coarsest level is 1x1") && three.contains("fewer levels"), "{three}");
        let params = SynthParams { levels: 1, ..SynthParams::default() };
        let error = synthesize(Exemplars { x: &tiny, y: None, z: None }, &params, 1, &crate::progress::NoProgress);
        assert!(error.unwrap_err().to_string().contains("give an exemplar of at least"));
    }
}
