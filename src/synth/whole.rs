//! A whole solid on the grid's own axes by the coordinate core ([`super::coords`]): the
//! homogeneous and layered synthesis of `synth --core coordinates`.
//!
//! ```text
//!  exemplars   each with a feature channel of its distance to its own edges ([`super::edges`])
//!  frames      the grid's axes; neighbourhoods wrap around the grid where it tiles
//!  layered     rows run along z: the two planes holding z are matched, their Depth
//!              channel against z / (Z - 1)
//!  labels      exemplars of at most 16 colours: every level starts from the mean of
//!              the planes' pixels (photos: a child shows its parent's plane), and two
//!              rounds of settling (each voxel shows the pixel of its triple most of its
//!              face neighbours show)
//!  balance     homogeneous solids: candidates in colours the solid holds too much of
//!              cost more, counted per parity sub-pass ([`super::occupancy`]; `--histogram`),
//!              at the finest level (labels: at every level)
//!  output      each voxel's shown pixel (a layered solid adds its Depth), and the
//!              patch figures ([`super::patches`]) for the volume's provenance
//! ```

use super::coords::{self, Exemplars, Options, Setup};
use super::edges::with_edge_distance;
use super::finer;
use super::params::SynthParams;
use super::patches::Patches;
use super::region::Mask;
use crate::error::Result;
use crate::guided::field::ScalarGrid;
use crate::progress::Progress;
use crate::volume::Image2d;
use glam::Vec3;

/// Side of the neighbourhoods the core matches (odd: centred on the voxel).
const N: usize = 5;

/// Rounds of settling a label solid ([`coords::settled`]): two about halve the pieces per
/// phase on the channels truth (6.2, 8.3, 11.8 times the truth's to 3.1, 4.4, 8.4, with an
/// earlier form of the colour balance); six remove almost no more.
const SETTLE_ROUNDS: usize = 2;

/// The colour balance's strength at `--histogram 1` ([`super::occupancy`]): on three
/// spot exemplars (20, 40, 60 % white) the solid's mean grey was 0.319 without it, 0.344,
/// 0.367, 0.383 and 0.393 at strengths 1, 2, 4 and 8 (the exemplars': 0.396); at 4 the
/// channels truth's pieces per phase fell from 2.9, 3.0, 10.1 to 0.8, 1.9, 2.4 times the
/// truth's and marble's histogram distance to 0.021. Layered solids go without: their
/// colours belong to depths, and a count over the whole solid pushed the cliff photo's
/// layers across depths (length ratio 1.06 to 1.7).
const BALANCE: f32 = 4.0;

/// The coordinate core's settings for `params`.
pub fn options(params: &SynthParams, layered: bool) -> Options {
    Options {
        levels: params.levels,
        n: N,
        coarse_n: N,
        coarse_passes: params.max_iterations,
        passes: params.finest_iterations,
        k: params.coherence,
        max_dims: params.max_pca_dims,
        layered,
        histogram: if layered { 0.0 } else { BALANCE * params.histogram_strength },
        balance_every_level: false,
        keep_shown_plane: true,
        coarse_depth_share: super::coords::DEPTH_SHARE,
        magnified: 0,
    }
}

/// Synthesize `params.size` voxels from `images` (orthogonal to x, y, z; layered: rows
/// along z, a Depth channel last): the samples, x fastest, with the images' channels, and
/// how coherently they copy the images ([`super::patches`]). A homogeneous solid whose
/// exemplars agree on a thin axis is synthesized twice as finely along it ([`finer`]).
pub fn synthesize(
    images: [&Image2d; 3],
    layered: bool,
    params: &SynthParams,
    seed: u64,
    progress: &dyn Progress,
) -> Result<Whole> {
    let finer =
        (!layered).then(|| finer::thin_axis(images)).flatten().filter(|&k| params.size[k] * 2 <= finer::MOST_SIDE);
    let Some(k) = finer else {
        let (samples, patches) = at_sampling(images, layered, params, seed, progress)?;
        return Ok(Whole { samples, patches, finer: None });
    };
    let [x, y, z] = finer::stretched(images, k)?;
    let mut size = params.size;
    size[k] *= 2;
    let (samples, patches) = at_sampling([&x, &y, &z], false, &SynthParams { size, ..params.clone() }, seed, progress)?;
    let channels = samples.len() / size.iter().product::<usize>();
    Ok(Whole { samples: finer::even_slices(&samples, size, channels, k), patches, finer: Some(k) })
}

/// A solid from [`synthesize`]: its samples (x fastest), how coherently they copy the
/// exemplars, and the axis synthesized at twice the sampling ([`finer`]), if any.
pub struct Whole {
    /// The voxels' samples, x fastest.
    pub samples: Vec<f32>,
    /// The patch figures ([`super::patches`]; of the finer solid where an axis was finer).
    pub patches: Option<Patches>,
    /// The axis synthesized at twice the sampling.
    pub finer: Option<usize>,
}

/// [`synthesize`] at the grid's own sampling.
fn at_sampling(
    images: [&Image2d; 3],
    layered: bool,
    params: &SynthParams,
    seed: u64,
    progress: &dyn Progress,
) -> Result<(Vec<f32>, Option<Patches>)> {
    // an image given for several planes is prepared once, and the planes share it
    let mut featured: Vec<Image2d> = Vec::new();
    let mut of_plane = [0; 3];
    for (a, image) in images.iter().enumerate() {
        of_plane[a] = match (0..a).find(|&b| std::ptr::eq(images[b], *image)) {
            Some(b) => of_plane[b],
            None => {
                featured.push(with_edge_distance(image)?);
                featured.len() - 1
            }
        };
    }
    let labels = images.iter().all(|image| super::edges::is_labels(image));
    let options = Options { balance_every_level: labels, keep_shown_plane: !labels, ..options(params, layered) };
    let exemplars = Exemplars::prepare(of_plane.map(|i| &featured[i]), &options)?;
    let dims = params.size;
    let depth = layered.then(|| depth_along_z(dims[2]));
    let wrap = [params.tileable, params.tileable, params.tileable && !layered];
    let setup = Setup { exemplars: &exemplars, frames: None, wrap, depth: depth.as_ref(), dims, seed, options };
    let mut out = coords::run(&setup, &coords::plan(&setup, &Mask::full(dims), &[]), &[], progress)?;
    if labels {
        for _ in 0..SETTLE_ROUNDS {
            out.values = coords::settled(&setup, &out.values);
        }
    }
    Ok((coords::samples(&setup, &out.values, true)?, coords::patches(&setup, &out.values)))
}

/// The depth `z / (Z - 1)` over a grid `z_dim` voxels deep (finest voxel coordinates).
fn depth_along_z(z_dim: usize) -> ScalarGrid {
    let step = (z_dim.max(2) - 1) as f32;
    let values = (0..8).map(|corner| (corner / 4) as f32).collect();
    ScalarGrid { lo: Vec3::ZERO, step, dims: [2, 2, 2], values }
}
