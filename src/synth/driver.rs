//! The multi-resolution loop: prepare exemplar pyramids, initialize the coarsest
//! volume, then per level {search, optimize} until converged, and upsample.
//!
//! Contrast per band: after each blend of a homogeneous finer level, only the detail the
//! level adds (the volume minus its own coarser version grown back) takes the histogram
//! of the exemplars' detail band; the layout the coarser levels made stays. An exact
//! transfer of the whole volume would stretch that layout, the only variation a soft
//! blend leaves, to the exemplar's full contrast: large blobs where the photo has none
//! (docs/synthesis.md, "The blur, measured"). The finest level ends by giving the cuts
//! the exemplars' power spectra ([`super::spectrum`]: the blend leaves features larger
//! than the photo's) and one exact transfer of the whole volume, so its colour
//! distribution is the exemplars'.
//!
//! A finer level takes the coarser volume's colours (interpolated on the sample grid the
//! exemplar pyramid uses: coarse voxel i at fine voxel 2i) but not its matches. Doubled
//! matches (each coarse match predicting a 2x2 block of fine ones) lock the finer level
//! into blocks: each voxel's own block predicts it coherently, so the blend keeps a step
//! at every block border, a 2- and 4-voxel grid that the finest iterations hardly remove
//! (docs/synthesis.md). Instead, a homogeneous level's first search looks every voxel up
//! in the whole exemplar; a layered level starts from random pixels of the voxel's depth
//! (a lookup would give a voxel's x and y planes, alike in a smooth volume, the same
//! pixel: the coincidence the anti-sweeping rule is there to stop).

use super::depth;
use super::exemplar::{PrepareOptions, Prepared};
use super::grid::Grid;
use super::knn::KdTree;
use super::optimize::{Histograms, JOINT_ROUNDS, densities, optimize, transfer_histograms_by_depth, transfer_joint};
use super::params::SynthParams;
use super::search::{Matches, SearchSetup, pass_seed, search};
use super::spectrum;
use crate::error::{Error, Result};
use crate::noise::hash3;
use crate::progress::Progress;
use crate::volume::{Edge, Image2d, Volume, downsample, upsample_on_samples};
use rayon::prelude::*;

/// How the coarsest volume starts.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Init {
    /// Random exemplar pixels.
    Random,
    /// Random exemplar pixels of the voxel's depth (the last channel); depth runs along z.
    ByDepth,
}

/// One synthesis run: the exemplar per axis (`None`: the axis is not searched).
pub struct Job<'a> {
    /// Exemplar image per axis.
    pub images: [Option<&'a Image2d>; 3],
    /// Channel weights in neighbourhood distances.
    pub weights: Vec<f32>,
    /// Initialization.
    pub init: Init,
    /// Two-best-match rule between x and y.
    pub anti_sweeping: bool,
    /// Finest-level samples to start from instead of random pixels (size and channels of
    /// the output).
    pub start: Option<&'a [f32]>,
}

/// The share of an iteration's time its search takes (the rest: blending and balancing
/// colours), for progress that moves evenly.
const SEARCH_SHARE: f64 = 0.8;

/// Run the synthesis; returns the finest level's samples.
pub fn run(job: &Job, params: &SynthParams, seed: u64, progress: &dyn Progress) -> Result<Vec<f32>> {
    let pyramids = prepare(job, params, progress)?;
    let levels = params.level_dims();
    let work: Vec<f64> = levels.iter().map(|d| d.iter().product::<usize>() as f64).collect();
    let total_work: f64 = work.iter().enumerate().map(|(l, w)| w * params.iterations_at(l) as f64).sum();
    let mut done = 0.0;
    let mut state: Option<(Grid, [Matches; 3])> = None;
    for (level, dims) in levels.iter().enumerate() {
        let ex = level_exemplars(&pyramids, level);
        let (mut grid, mut matches) = match state.take() {
            None => match job.start {
                Some(start) => init_from(job, &ex, *dims, params, start),
                None => init(job, &ex, *dims, params, seed),
            },
            Some((coarse, _)) => upsample_level(job, &coarse, &ex, *dims, level_seed(seed, level)),
        };
        let mut previous = f64::INFINITY;
        let pooled = pooled_colours(&ex);
        let by_band = level > 0 && job.init == Init::Random;
        let detail = by_band.then(|| detail_band(&ex, &level_exemplars(&pyramids, level - 1), grid.channels));
        let power = params.blend_power.unwrap_or(match job.init {
            Init::Random => SynthParams::HOMOGENEOUS_BLEND_POWER,
            Init::ByDepth => SynthParams::LAYERED_BLEND_POWER,
        });
        let iterations = params.iterations_at(level);
        for iteration in 0..iterations {
            if progress.cancelled() {
                return Err(Error::Cancelled);
            }
            let setup = SearchSetup {
                exemplars: ex,
                anti_sweeping: job.anti_sweeping,
                seed: pass_seed(seed, level, iteration),
                fresh: level > 0 && iteration == 0 && job.init == Init::Random,
            };
            let stage = format!("level {}/{}, iteration {}", level + 1, levels.len(), iteration + 1);
            let part = crate::progress::Part {
                whole: progress,
                stage: format!("{stage}: searching"),
                from: (done / total_work) as f32,
                span: (SEARCH_SHARE * work[level] / total_work) as f32,
            };
            let (found, energy) = search(&grid, &matches, &setup, &part).ok_or(Error::Cancelled)?;
            matches = found;
            done += SEARCH_SHARE * work[level];
            progress.update(&format!("{stage}: searched"), (done / total_work) as f32);
            grid.data = optimize(&grid, &matches, ex, &histograms(&ex, params), power);
            if params.histogram_strength > 0.0 {
                let first = ex.iter().flatten().next().expect("at least one axis is searched");
                match (&detail, job.init) {
                    (Some(detail), _) => transfer_detail(&mut grid, detail),
                    (None, Init::ByDepth) => {
                        transfer_histograms_by_depth(&mut grid.data, grid.dims, grid.channels, &first.colours)
                    }
                    (None, Init::Random) => transfer_joint(&mut grid.data, grid.channels, &pooled, JOINT_ROUNDS),
                }
            }
            if progress.cancelled() {
                return Err(Error::Cancelled);
            }
            done += (1.0 - SEARCH_SHARE) * work[level];
            progress.update(&format!("{stage}: optimized"), (done / total_work) as f32);
            let mean = energy / work[level];
            if (previous - mean) < params.tolerance as f64 * previous {
                done += work[level] * (iterations - iteration - 1) as f64;
                break;
            }
            previous = mean;
        }
        if job.init == Init::Random && level + 1 == levels.len() && params.histogram_strength > 0.0 {
            // A start volume's layout is the user's: its large features stay as large as they are.
            let reshape = params.spectrum && job.start.is_none() && grid.wrap.iter().all(|w| *w);
            let rounds = if reshape { SPECTRUM_ROUNDS } else { 0 };
            for round in 0..rounds {
                match_spectrum(&mut grid, &ex, &pooled);
                let last = round + 1 == rounds;
                transfer_joint(&mut grid.data, grid.channels, &pooled, if last { JOINT_ROUNDS } else { 1 });
            }
            if rounds == 0 && by_band {
                transfer_joint(&mut grid.data, grid.channels, &pooled, JOINT_ROUNDS);
            }
        }
        progress.level_done(level + 1, levels.len(), grid.dims, grid.channels, &grid.data);
        state = Some((grid, matches));
    }
    progress.update("done", 1.0);
    Ok(state.map(|(g, _)| g.data).unwrap_or_default())
}

/// Rounds of spectrum matching, each followed by a colour transfer (per channel after the
/// first round, the joint one after the last), which moves the spectrum a little. Against the known solid of docs/synthesis.md, one round left
/// the correlation error along x at 1.50-1.62 times the slices' own (seeds 1-3), two at
/// 1.19-1.33, three no better (z up to 1.54).
const SPECTRUM_ROUNDS: usize = 2;

/// Give the volume's cuts the power spectra of the level's exemplars (the colour
/// distribution is transferred again afterwards).
fn match_spectrum(grid: &mut Grid, ex: &[Option<&Prepared>; 3], pooled: &[f32]) {
    let standard = crate::sharpness::Standard::of_samples(pooled, grid.channels);
    let targets = ex.map(|e| e.map(|e| spectrum::Target::of(&e.colours, e.width, e.height, e.channels, &standard)));
    spectrum::match_spectrum(
        &mut grid.data,
        grid.dims,
        grid.channels,
        &standard,
        &targets.each_ref().map(Option::as_ref),
    );
}

/// Per axis, the prepared pyramid (coarsest first); axes sharing an image share it.
type Pyramids = [Option<std::sync::Arc<Vec<Prepared>>>; 3];

fn prepare(job: &Job, params: &SynthParams, progress: &dyn Progress) -> Result<Pyramids> {
    let opt = PrepareOptions {
        n: params.neighbourhood,
        variance: params.pca_variance,
        max_dims: params.max_pca_dims,
        k: params.coherence,
    };
    let mut out: Pyramids = Default::default();
    for axis in 0..3 {
        let Some(image) = job.images[axis] else { continue };
        let shared = (0..axis).find(|&a| job.images[a].is_some_and(|other| std::ptr::eq(other, image)));
        if let Some(a) = shared {
            out[axis] = out[a].clone();
            continue;
        }
        progress.update(&format!("preparing exemplar for axis {axis}"), 0.0);
        let levels = image_pyramid(image, params.levels)?;
        let prepared: Vec<Prepared> = levels.iter().map(|img| Prepared::new(img, &job.weights, opt)).collect();
        for (level, p) in prepared.iter().enumerate() {
            let (dims, share) = (p.pca.dims, p.pca.explained * 100.0);
            progress.update(
                &format!("axis {axis} level {}: {dims} PCA dims keep {share:.0} % of the variance", level + 1),
                0.0,
            );
        }
        out[axis] = Some(std::sync::Arc::new(prepared));
    }
    progress.update("exemplars prepared", 0.0);
    Ok(out)
}

/// Gaussian pyramid of a 2D image, coarsest first.
pub(crate) fn image_pyramid(image: &Image2d, levels: usize) -> Result<Vec<Image2d>> {
    let mut volume =
        Volume::from_data([image.width(), image.height(), 1], image.channels().to_vec(), image.data().to_vec())?;
    let mut out = vec![image.clone()];
    for _ in 1..levels {
        volume = downsample(&volume, Edge::Clamp)?;
        let [w, h, _] = volume.dims();
        out.push(Image2d::from_data(w, h, image.channels().to_vec(), volume.data().to_vec())?);
    }
    out.reverse();
    Ok(out)
}

fn level_exemplars(pyramids: &Pyramids, level: usize) -> [Option<&Prepared>; 3] {
    [0, 1, 2].map(|a| pyramids[a].as_ref().map(|p| &p[level]))
}

fn histograms(ex: &[Option<&Prepared>; 3], params: &SynthParams) -> Histograms {
    let used: Vec<&Prepared> = ex.iter().flatten().copied().collect();
    let per: Vec<Vec<Vec<f32>>> =
        used.iter().map(|e| densities(&e.colours, e.channels, params.histogram_bins)).collect();
    let target = (0..used[0].channels)
        .map(|c| {
            (0..params.histogram_bins).map(|b| per.iter().map(|h| h[c][b]).sum::<f32>() / per.len() as f32).collect()
        })
        .collect();
    Histograms { bins: params.histogram_bins, strength: params.histogram_strength, target }
}

/// The distinct exemplars of a level (axes sharing an image share it).
fn distinct<'a>(ex: &[Option<&'a Prepared>; 3]) -> Vec<&'a Prepared> {
    let mut out: Vec<&Prepared> = Vec::new();
    for e in ex.iter().flatten() {
        if !out.iter().any(|d| std::ptr::eq(*d, *e)) {
            out.push(e);
        }
    }
    out
}

/// The colour distribution the volume should have: every distinct exemplar of the level
/// counts equally (each contributes the same number of quantiles per channel), so Ey and Ez
/// weigh as much as Ex whatever their sizes. One exemplar gives its own pixels.
fn pooled_colours(ex: &[Option<&Prepared>; 3]) -> Vec<f32> {
    let samples: Vec<Vec<f32>> = distinct(ex).iter().map(|e| e.colours.clone()).collect();
    pooled(samples, ex.iter().flatten().next().map_or(1, |e| e.channels))
}

/// The distribution of the detail band a finer level adds: per distinct exemplar, its
/// pixels minus its coarser level grown back on the pyramid's sample grid, pooled as
/// [`pooled_colours`] pools colours.
fn detail_band(ex: &[Option<&Prepared>; 3], coarser: &[Option<&Prepared>; 3], channels: usize) -> Vec<f32> {
    let fine = distinct(ex);
    let coarse = distinct(coarser);
    let samples = fine
        .iter()
        .zip(&coarse)
        .map(|(f, k)| {
            let small = as_volume([k.width, k.height, 1], channels, k.colours.clone());
            let grown = upsample_on_samples(&small, [f.width, f.height, 1], Edge::Clamp)
                .expect("an exemplar level fits the budget")
                .into_data();
            f.colours.iter().zip(&grown).map(|(a, b)| a - b).collect()
        })
        .collect();
    pooled(samples, channels)
}

/// Transfer the histogram of the volume's detail band (the volume minus itself shrunk and
/// grown back) to `detail`, keeping the layout underneath.
fn transfer_detail(grid: &mut Grid, detail: &[f32]) {
    let volume = as_volume(grid.dims, grid.channels, grid.data.clone());
    let layout = downsample(&volume, edge(grid.wrap))
        .and_then(|small| upsample_on_samples(&small, grid.dims, edge(grid.wrap)))
        .expect("a smaller volume fits the budget")
        .into_data();
    let mut band: Vec<f32> = grid.data.iter().zip(&layout).map(|(v, l)| v - l).collect();
    transfer_joint(&mut band, grid.channels, detail, JOINT_ROUNDS);
    for ((out, l), b) in grid.data.iter_mut().zip(&layout).zip(&band) {
        *out = l + b;
    }
}

/// Samples of several sources pooled so that each counts equally: as many whole samples
/// from each as the largest has (every sample of the largest once, the others' spread
/// evenly over it), so the joint transfer aims at colours the sources really hold. One
/// source is returned as it is.
fn pooled(mut samples: Vec<Vec<f32>>, channels: usize) -> Vec<f32> {
    if samples.len() == 1 {
        return samples.remove(0);
    }
    let per = samples.iter().map(|s| s.len() / channels).max().unwrap_or(1);
    let mut pooled = Vec::with_capacity(samples.len() * per * channels);
    for source in &samples {
        let count = source.len() / channels;
        for q in 0..per {
            let at = (q * count / per).min(count.saturating_sub(1));
            pooled.extend_from_slice(&source[at * channels..(at + 1) * channels]);
        }
    }
    pooled
}

fn wraps(job: &Job, params: &SynthParams) -> [bool; 3] {
    let depth_axis = job.init == Init::ByDepth;
    [params.tileable, params.tileable, params.tileable && !depth_axis]
}

/// The coarsest level: every voxel gets random matches and the colour of one of them.
fn init(
    job: &Job,
    ex: &[Option<&Prepared>; 3],
    dims: [usize; 3],
    params: &SynthParams,
    seed: u64,
) -> (Grid, [Matches; 3]) {
    let picks = random_picks(job, ex, dims, seed);
    let first = ex.iter().flatten().next().expect("at least one axis is searched");
    let channels = first.channels;
    let mut data = Vec::with_capacity(picks.len() * channels);
    for (v, p) in picks.iter().enumerate() {
        let axes: Vec<usize> = (0..3).filter(|a| ex[*a].is_some()).collect();
        let a = axes[(hash3(seed, v as i64, 7, 2) % axes.len() as u64) as usize];
        let e = ex[a].expect("chosen among searched axes");
        data.extend_from_slice(&e.colours[p[a] as usize * channels..(p[a] as usize + 1) * channels]);
    }
    (Grid { dims, channels, data, wrap: wraps(job, params) }, as_matches(ex, &picks))
}

/// A random centre per voxel and searched axis (of the voxel's depth in layered runs).
fn random_picks(job: &Job, ex: &[Option<&Prepared>; 3], dims: [usize; 3], seed: u64) -> Vec<[u32; 3]> {
    let count = dims.iter().product::<usize>();
    let first = ex.iter().flatten().next().expect("at least one axis is searched");
    let by_depth = (job.init == Init::ByDepth).then(|| depth_order(first));
    (0..count)
        .into_par_iter()
        .map(|v| {
            let z = v / (dims[0] * dims[1]);
            [0, 1, 2].map(|a| match (ex[a], &by_depth) {
                (None, _) => 0,
                (Some(e), None) => e.random_centre(hash3(seed, v as i64, a as i64, 1)),
                (Some(_), Some(order)) => pick_by_depth(order, z, dims[2], hash3(seed, v as i64, a as i64, 1)),
            })
        })
        .collect()
}

/// Picks as matches of unknown distance.
fn as_matches(ex: &[Option<&Prepared>; 3], picks: &[[u32; 3]]) -> [Matches; 3] {
    [0, 1, 2].map(|a| match ex[a] {
        Some(_) => Matches { pixel: picks.iter().map(|p| p[a]).collect(), dist: vec![1.0; picks.len()] },
        None => Matches::default(),
    })
}

/// The seed of a level's fresh random matches.
fn level_seed(seed: u64, level: usize) -> u64 {
    hash3(seed, level as i64, 0, 3)
}

/// The coarsest level from a start volume: its samples shrunk to the level's size, and
/// for every voxel and axis the exemplar neighbourhood nearest to the voxel's own (exact
/// search over all centres), so the first search refines what the volume already shows.
fn init_from(
    job: &Job,
    ex: &[Option<&Prepared>; 3],
    dims: [usize; 3],
    params: &SynthParams,
    start: &[f32],
) -> (Grid, [Matches; 3]) {
    let first = ex.iter().flatten().next().expect("at least one axis is searched");
    let wrap = wraps(job, params);
    let mut volume = as_volume(params.size, first.channels, start.to_vec());
    while volume.dims() != dims {
        volume = downsample(&volume, edge(wrap)).expect("a smaller volume fits the budget");
    }
    let grid = Grid { dims, channels: first.channels, data: volume.into_data(), wrap };
    let matches = [0, 1, 2].map(|a| ex[a].map(|e| nearest_matches(&grid, e, a)).unwrap_or_default());
    (grid, matches)
}

/// Every voxel's nearest exemplar neighbourhood on one axis.
fn nearest_matches(grid: &Grid, ex: &Prepared, axis: usize) -> Matches {
    let dims = ex.pca.dims;
    let tree = KdTree::build(ex.projected.packed(dims), dims);
    let [dx, dy, dz] = grid.dims;
    let rows: Vec<Vec<(f32, u32)>> = (0..dy * dz)
        .into_par_iter()
        .map(|r| {
            let (mut taps, mut proj, mut query) = (Vec::new(), Vec::new(), Vec::new());
            grid.project_row(ex, crate::volume::Axis::ALL[axis], r % dy, r / dy, &mut taps, &mut proj);
            (0..dx)
                .map(|x| {
                    query.clear();
                    query.extend((0..dims).map(|k| proj[k * dx + x]));
                    let (d, slot) = tree.nearest(&query, 1)[0];
                    (d.sqrt(), ex.centres[slot as usize])
                })
                .collect()
        })
        .collect();
    let flat = rows.into_iter().flatten();
    let (dist, pixel) = flat.unzip();
    Matches { pixel, dist }
}

/// Valid centres sorted by their depth (the last channel), as (depth, pixel).
fn depth_order(ex: &Prepared) -> Vec<(f32, u32)> {
    let c = ex.channels;
    depth::sorted_by_depth(ex.centres.iter().map(|&p| (ex.colours[p as usize * c + c - 1], p)).collect())
}

/// A random centre among those whose depth is nearest to slice z's depth.
fn pick_by_depth(order: &[(f32, u32)], z: usize, depth: usize, hash: u64) -> u32 {
    let window = (order.len() / depth.max(1)).clamp(1, order.len());
    let start = depth::band(order, depth::slice_depth(z, depth), window).start;
    order[start + (hash % window as u64) as usize].1
}

/// Move to the next finer level: colours interpolated; matches not carried over (see the
/// module notes): random pixels of each voxel's depth for layered runs, none otherwise.
fn upsample_level(
    job: &Job,
    coarse: &Grid,
    ex: &[Option<&Prepared>; 3],
    dims: [usize; 3],
    seed: u64,
) -> (Grid, [Matches; 3]) {
    let fine = upsample_samples(coarse, dims);
    // A homogeneous level's first search looks every voxel up and reads no matches.
    let matches = match job.init {
        Init::ByDepth => as_matches(ex, &random_picks(job, ex, dims, seed)),
        Init::Random => Default::default(),
    };
    (Grid { dims, channels: coarse.channels, data: fine, wrap: coarse.wrap }, matches)
}

fn upsample_samples(coarse: &Grid, dims: [usize; 3]) -> Vec<f32> {
    let volume = as_volume(coarse.dims, coarse.channels, coarse.data.clone());
    upsample_on_samples(&volume, dims, edge(coarse.wrap))
        .expect("the finer level fits the budget checked up front")
        .into_data()
}

/// Samples as a volume for the pyramid's resamplers (channels named c0, c1, ...: the
/// resamplers read only the samples).
fn as_volume(dims: [usize; 3], channels: usize, data: Vec<f32>) -> Volume {
    let names = (0..channels).map(|i| crate::volume::Channel::Named(format!("c{i}"))).collect();
    Volume::from_data(dims, names, data).expect("grid sizes are consistent")
}

/// The resamplers' edge rule: that of the first axis (x and y always agree).
fn edge(wrap: [bool; 3]) -> Edge {
    if wrap[0] { Edge::Wrap } else { Edge::Clamp }
}

#[cfg(test)]
mod tests {
    use super::pooled;

    /// Pooling keeps whole colours (a red-and-blue exemplar never pools into black or
    /// magenta, as per-channel quantiles did) and gives each source the same weight
    /// whatever its size.
    #[test]
    fn pooling_keeps_whole_colours_and_weighs_sources_alike() {
        let red_blue = [1.0f32, 0.0, 0.0, 0.0, 0.0, 1.0].repeat(2);
        let green = [0.0f32, 1.0, 0.0].repeat(2);
        let out = pooled(vec![red_blue, green], 3);
        assert_eq!(out.len(), 8 * 3, "four samples from each");
        let colours: Vec<&[f32]> = out.chunks_exact(3).collect();
        let count = |c: [f32; 3]| colours.iter().filter(|x| **x == c).count();
        assert_eq!((count([1.0, 0.0, 0.0]), count([0.0, 0.0, 1.0]), count([0.0, 1.0, 0.0])), (2, 2, 4));
    }

    /// Counts how often the work asks whether to stop.
    struct Polls(std::sync::atomic::AtomicUsize);

    impl crate::progress::Progress for Polls {
        fn update(&self, _stage: &str, _fraction: f32) {}
        fn cancelled(&self) -> bool {
            self.0.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
            false
        }
    }

    /// Cancellation is polled per z-slice of every search, not once per iteration, so a
    /// cancel stops a large synthesis within a slice's work.
    #[test]
    fn cancellation_is_polled_per_slice() {
        use crate::synth::{Exemplars, SynthParams, synthesize};
        let pixels = (0..32 * 32).flat_map(|i| [((i % 32 / 4 + i / 128) % 2) as f32; 3]).collect();
        let ex = crate::volume::Image2d::from_data(32, 32, crate::Channel::rgb(), pixels).unwrap();
        let params = SynthParams { size: [16; 3], levels: 1, finest_iterations: 1, ..SynthParams::default() };
        let polls = Polls(Default::default());
        synthesize(Exemplars { x: &ex, y: None, z: None }, &params, 1, &polls).unwrap();
        assert!(polls.0.into_inner() >= 16, "at least one poll per slice of the one search");
    }
}
