//! The project's synthesis core: solid texture synthesis by exemplar coordinates (Dong et
//! al. 2008), along a frame field and on demand (Zhang et al. 2011, §4–5). `synth`,
//! layered synthesis and `guided` all run it; without a frame field the frames are the
//! grid's axes.
//!
//! Every voxel holds a coordinate triple: a pixel of each plane's exemplar (the planes
//! orthogonal to its frame's x, y and z axes), whose crossbars agree ([`super::triples`]).
//! It shows **one** exemplar pixel, never a blend: after a correction, the pixel of the
//! triple member whose neighbourhood agrees best with the voxel's neighbours in its plane;
//! a child of a finer level starts showing the plane its parent shows (the coarsest
//! level's start, and with labels every start, shows the mean of the three, which favours
//! no plane). A cut through the solid is then made of
//! exemplar pixels copied in coherent patches, so its edges are as sharp as the photo's
//! and a label image stays labels; the mean of three pixels that seldom agree on a photo
//! was soft (docs/guided.md, "Two exemplars").
//!
//! ```text
//!  coarsest level  pixels from the voxel's position in its frame, plus a random offset
//!                  per block of 8 voxels (coherent patches along the field)
//!  finer level     a child takes its parent's pixels doubled plus its own offset in the
//!                  parent's frame (Zhang et al., Eq. 3), then
//!  each pass       the voxel's three n x n neighbourhoods sampled in the planes of its
//!                  frame; candidates: each 3 x 3 in-plane neighbour's whole triple moved
//!                  back by its offset (Eq. 4), the candidate triples of the pixel it
//!                  predicts (Zhang et al.'s reduced set; at the finest level its best
//!                  two), the voxel's own triple and one random one; the least summed
//!                  PCA distance wins
//! ```
//!
//! With a solid exemplar ([`super::cube`]) a voxel holds one place in the cube instead:
//! it starts, is upsampled and corrected the same way, its three neighbourhoods compared
//! with the cube's at candidate places, and shows the cube's colour there, so cuts are as
//! sharp as the cube's. The mean of a triple is soft on photos, whose three pixels seldom
//! agree (docs/guided.md, "Two exemplars").
//!
//! A pass reads only the previous version of the voxels within its reach, so the voxels
//! a request needs form a pyramid of masks ([`plan`]; [`super::region`]), and a cut
//! synthesized alone is bit-identical to the same voxels of the whole solid, on any number
//! of threads.

use super::cube::Cube;
use super::occupancy::Balance;
use super::region::{Mask, Sparse, grid_voxel};
use super::triples::Triples;
use crate::error::{Error, Result};
use crate::guided::field::{FrameGrid, ScalarGrid};
use crate::noise::hash3;
use crate::progress::Progress;
use crate::synth::exemplar::{PrepareOptions, Prepared};
use crate::volume::{Axis, Channel, Image2d};
use glam::{Mat3, Vec3};
use std::sync::Arc;

/// Synthesis settings.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Options {
    /// Pyramid levels.
    pub levels: usize,
    /// Side of the square neighbourhoods at the levels above the coarsest.
    pub n: usize,
    /// Side of the square neighbourhoods at the coarsest level.
    pub coarse_n: usize,
    /// Correction passes at the coarsest level.
    pub coarse_passes: usize,
    /// Correction passes at every finer level.
    pub passes: usize,
    /// Candidate triples per exemplar pixel (the finest matched level offers at most
    /// [`FINEST_TRIPLES`]).
    pub k: usize,
    /// Most PCA dimensions.
    pub max_dims: usize,
    /// Layered: the exemplars' rows run along depth (frame z), as in the library's
    /// cross-sections; only the two planes holding z are matched and coloured (the plane
    /// along a layer is free, as in layered synthesis, thesis §4.2).
    pub layered: bool,
    /// How strongly candidates in colours the solid holds too much of are passed over
    /// ([`super::occupancy`]); 0: not at all. Only runs over the whole grid weigh it (a
    /// cut on demand must equal the same voxels of the whole solid).
    pub histogram: f32,
    /// Weigh the colour balance at every level, not only the finest: for label exemplars,
    /// whose phases must be placed in the right shares from the coarsest level on. On a
    /// photo, balancing the coarse levels lengthens its features (their layout is fixed
    /// there, and an over-used colour is moved in long runs).
    pub balance_every_level: bool,
    /// A child of a finer level starts showing the plane its parent shows (else the mean
    /// of its planes' pixels). On photos this keeps features at the photo's size (the
    /// mean is soft and draws matches to smooth patches, which spread); a label
    /// exemplar's phases kept fewer pieces from the mean (the channels truth: 1.9 times
    /// the truth's pieces against 2.4, over three seeds).
    pub keep_shown_plane: bool,
    /// How many times the colours' summed variance the depth channel's weighted variance
    /// is at the levels above the finest: how tightly a layered exemplar's rows keep to
    /// their depth while the layers are laid out ([`DEPTH_SHARE`]; [`SECTION_DEPTH_SHARE`]
    /// for a built cross-section). The finest matched level matches at [`DEPTH_SHARE`].
    pub coarse_depth_share: f32,
    /// How many of the finest levels only magnify the level below: a layered exemplar
    /// fitted up to the model's depth ([`Options::magnifying`]) holds no detail there that
    /// the level below lacks, so those levels make no corrections (matches among
    /// magnified pixels find many near-equal neighbourhoods and break the layers into
    /// specks); a child keeps its parent's column doubled and takes the row of its depth.
    pub magnified: usize,
}

impl Default for Options {
    fn default() -> Options {
        Options {
            levels: 4,
            n: 5,
            coarse_n: 5,
            coarse_passes: 4,
            passes: 2,
            k: 4,
            max_dims: 16,
            layered: false,
            histogram: 0.0,
            balance_every_level: false,
            keep_shown_plane: true,
            coarse_depth_share: DEPTH_SHARE,
            magnified: 0,
        }
    }
}

impl Options {
    /// The defaults with as many levels (at most the default's) as leave the exemplar's
    /// coarsest level at least 16 pixels on its shorter side (`side`).
    pub fn for_exemplar(side: usize) -> Options {
        let mut options = Options::default();
        while options.levels > 1 && (side >> (options.levels - 1)) < 16 {
            options.levels -= 1;
        }
        options
    }

    /// These settings for a layered exemplar of `source` rows fitted to `fitted` rows: the
    /// levels whose exemplar is more than [`MAGNIFIED`] times the source's rows only
    /// magnify (at most all but the coarsest).
    pub fn magnifying(self, source: usize, fitted: usize) -> Options {
        let (mut magnified, mut rows) = (0, fitted);
        while magnified + 1 < self.levels && rows as f32 > MAGNIFIED * source as f32 {
            magnified += 1;
            // each level halves its image's rows, rounding up ([`crate::synth::image_pyramid`])
            rows = rows.div_ceil(2);
        }
        Options { magnified, ..self }
    }

    /// The finest level that is matched (0: coarsest): the finest, or the one below the
    /// levels that only magnify. The finest level's rules ([`FINEST_TRIPLES`], the depth
    /// at [`DEPTH_SHARE`], the colour balance of a photo) apply there.
    pub fn finest_matched(&self) -> usize {
        self.levels.saturating_sub(1 + self.magnified)
    }

    /// Whether `level` (0: coarsest) only magnifies the level below.
    pub fn magnifies(&self, level: usize) -> bool {
        level > 0 && level + self.magnified >= self.levels
    }

    /// The coarse levels: those below the finest that make corrections, which a guided
    /// cache may hold whole so that a cut computes only the levels above them.
    pub fn coarse_levels(&self) -> usize {
        self.levels.saturating_sub(self.magnified.max(1))
    }

    /// Correction passes at `level` (0: coarsest).
    pub fn passes_at(&self, level: usize) -> usize {
        if self.magnifies(level) {
            0
        } else if level == 0 {
            self.coarse_passes
        } else {
            self.passes
        }
    }

    /// Candidate triples kept per exemplar pixel at `level` (0: coarsest): `k`, at most
    /// [`FINEST_TRIPLES`] at the finest matched level (the fewer kept, the smaller the table each
    /// correction reads at random).
    pub fn triples_at(&self, level: usize) -> usize {
        if level == self.finest_matched() { self.k.min(FINEST_TRIPLES) } else { self.k }
    }

    /// The neighbourhood side at `level` (0: coarsest).
    pub fn n_at(&self, level: usize) -> usize {
        if level == 0 { self.coarse_n } else { self.n }
    }

    /// How far (in voxels) from the centre of the voxel it corrects a pass at `level`
    /// samples: a neighbourhood offset, up to n/2 along two orthonormal axes (n/2·√2), with
    /// the 3 x 3 candidate sources within it; a sample reads the voxel it falls in
    /// ([`Mask::grown_round`]). A hair more, so that rounding in the frames' axes never
    /// reaches a voxel the plan left out.
    pub fn footprint_at(&self, level: usize) -> f32 {
        (self.n_at(level) / 2) as f32 * std::f32::consts::SQRT_2 * (1.0 + 1e-4)
    }
}

/// What a voxel holds: a neighbourhood centre (its slot) in the exemplar of each plane,
/// orthogonal to frame axis 0, 1, 2.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct Voxel {
    /// Centre slot per plane.
    pub slot: [u32; 3],
    /// Its colour: one of the three pixels (the first channels; see [`MAX_CHANNELS`]).
    pub colour: [f32; MAX_CHANNELS],
    /// The plane whose pixel it shows, or [`MEAN`].
    pub shown: u8,
}

/// [`Voxel::shown`] of a voxel showing the mean of its planes' pixels (or a cube's colour).
pub const MEAN: u8 = 3;

/// Most exemplar channels (colour with alpha, a feature mask, depth).
pub const MAX_CHANNELS: usize = 6;

/// The name of an exemplar channel holding a feature mask (Zhang et al. 2011, Fig. 16):
/// matched with the colours, so structures the mask marks are kept whole, but not shown.
pub const FEATURE: &str = "feature";

/// Whether an exemplar channel is matched but not shown: a feature mask or the depth.
pub fn matched_only(channel: &Channel) -> bool {
    *channel == Channel::Depth || *channel == Channel::Named(FEATURE.into())
}

/// The exemplars per plane, prepared at every level (coarsest first).
#[derive(Debug, Clone)]
pub struct Exemplars {
    /// Per plane (orthogonal to frame x, y, z), its pyramid; planes sharing an image share it.
    pub planes: [Arc<Vec<Prepared>>; 3],
    /// Per level, the candidate triples (none at a level that only magnifies).
    pub triples: Vec<Triples>,
    /// The channels shown: the exemplars' own, a feature mask and a Depth channel (matched,
    /// not shown) aside.
    pub names: Vec<Channel>,
    /// The index of the Depth channel, if the exemplars carry one.
    pub depth: Option<usize>,
    /// A solid exemplar instead of the planes: a voxel's slot is then its place in the
    /// cube ([`super::cube`]); `planes` and `triples` are empty.
    pub cube: Option<Arc<Cube>>,
}

impl Exemplars {
    /// Prepare `images` (orthogonal to frame x, y, z) for `options`; every level must hold
    /// a neighbourhood and the images must have the same channels, none of them alpha (the
    /// synthesized solid's alpha is the model's coverage).
    pub fn prepare(images: [&Image2d; 3], options: &Options) -> Result<Exemplars> {
        let names = ["Ex", "Ey", "Ez"];
        let channels = images[0].channels();
        if channels.len() > MAX_CHANNELS {
            return Err(Error::invalid(format!(
                "the exemplar has {} channels ({}); synthesis takes at most {MAX_CHANNELS}",
                channels.len(),
                crate::volume::channel_names(channels)
            )));
        }
        let opt =
            |level: usize| PrepareOptions { n: options.n_at(level), variance: 0.97, max_dims: options.max_dims, k: 0 };
        let smallest = (options.n_at(0) + 2).max(options.n + 2);
        let mut planes: Vec<Arc<Vec<Prepared>>> = Vec::new();
        for (a, image) in images.iter().enumerate() {
            if image.channels() != channels {
                return Err(Error::exemplar(
                    a,
                    format!(
                        "{} has channels {}, the first {}; all exemplars need the same channels",
                        names[a],
                        crate::volume::channel_names(image.channels()),
                        crate::volume::channel_names(channels)
                    ),
                ));
            }
            if let Some(b) = (0..a).find(|&b| std::ptr::eq(images[b], *image)) {
                planes.push(planes[b].clone());
                continue;
            }
            let shrink = |s: usize| (1..options.levels).fold(s, |s, _| s.div_ceil(2));
            let (w, h) = (shrink(image.width()), shrink(image.height()));
            if w < smallest || h < smallest {
                let why = super::too_small(names[a], image, options.levels, [w, h], smallest - 2);
                return Err(Error::exemplar(a, why));
            }
            let (coarse, finest) = (weights(image, options.coarse_depth_share), weights(image, DEPTH_SHARE));
            let pyramid = crate::synth::image_pyramid(image, options.levels)?;
            let prepared: Result<Vec<Prepared>> = pyramid
                .iter()
                .enumerate()
                .map(|(l, image)| {
                    let weights = if l >= options.finest_matched() { &finest } else { &coarse };
                    let image = padded_rows(image, pad_rows(options, l))?;
                    let prepare = if options.magnifies(l) { Prepared::unsearched } else { Prepared::new };
                    Ok(prepare(&image, weights, opt(l)))
                })
                .collect();
            planes.push(Arc::new(prepared?));
        }
        let planes = [planes[0].clone(), planes[1].clone(), planes[2].clone()];
        let triples = (0..options.levels)
            .map(|l| match options.magnifies(l) {
                true => Triples::none(),
                false => Triples::new([&planes[0][l], &planes[1][l], &planes[2][l]], options.triples_at(l)),
            })
            .collect();
        let depth = channels.iter().position(|c| *c == Channel::Depth);
        if depth.is_some_and(|d| d + 1 != channels.len()) {
            return Err(Error::invalid(format!(
                "the exemplar has channels {}; a Depth channel must be the last",
                crate::volume::channel_names(channels)
            )));
        }
        let names: Vec<Channel> = channels.iter().filter(|c| !matched_only(c)).cloned().collect();
        if channels[..names.len()] != names[..] {
            return Err(Error::invalid(format!(
                "the exemplar has channels {}; a {FEATURE} channel must follow the colours",
                crate::volume::channel_names(channels)
            )));
        }
        Ok(Exemplars { planes, triples, names, depth, cube: None })
    }

    /// An error unless the exemplars are free of alpha: a guided solid's alpha is the
    /// model's coverage.
    pub fn refuse_alpha(&self) -> Result<()> {
        if !self.names.contains(&Channel::A) {
            return Ok(());
        }
        Err(Error::invalid(format!(
            "the exemplar has channels {}; drop its alpha channel (the solid's alpha is the model's coverage)",
            crate::volume::channel_names(&self.names)
        )))
    }

    /// A solid exemplar of `volume`'s channels but alpha ([`super::cube`]), at the levels of
    /// `options`: e.g. the tiling cube [`super::cube::synthesize`] makes of plain exemplars.
    pub fn of_volume(volume: &crate::volume::Volume, options: &Options) -> Result<Exemplars> {
        let keep: Vec<usize> = (0..volume.channel_count()).filter(|&c| volume.channels()[c] != Channel::A).collect();
        let cube = Cube::new(volume, &keep, options.levels, super::cube::SMALLEST)?;
        Exemplars::of_cube(cube, keep.iter().map(|&c| volume.channels()[c].clone()).collect())
    }

    /// A solid exemplar, its channels named `names` (colours only).
    pub fn of_cube(cube: Cube, names: Vec<Channel>) -> Result<Exemplars> {
        if names.len() != cube.channels || names.iter().any(|c| matched_only(c) || *c == Channel::A) {
            return Err(Error::invalid(format!(
                "a solid exemplar shows colours only; channels {} do not fit its {}",
                crate::volume::channel_names(&names),
                cube.channels
            )));
        }
        let none = Arc::new(Vec::new());
        Ok(Exemplars {
            planes: [none.clone(), none.clone(), none],
            triples: Vec::new(),
            names,
            depth: None,
            cube: Some(Arc::new(cube)),
        })
    }

    /// Per plane, how many slots a voxel of `level` may hold there: the exemplar's centres,
    /// or with a cube its side (a slot is then a place's coordinate).
    pub fn slot_counts(&self, level: usize) -> [usize; 3] {
        match &self.cube {
            Some(cube) => [cube.levels[level].side; 3],
            None => [0, 1, 2].map(|a| self.planes[a][level].centres.len()),
        }
    }

    /// The channels a voxel shows (a feature mask and a Depth channel aside).
    pub fn channels(&self) -> usize {
        self.names.len()
    }
}

/// Rows added above and below a layered exemplar's `level` (see [`padded_rows`]).
fn pad_rows(options: &Options, level: usize) -> usize {
    if options.layered { options.n_at(level) / 2 } else { 0 }
}

/// `image` with its first and last rows repeated `pad` times: a neighbourhood centre must
/// have its whole neighbourhood in the image, so without them a layered exemplar's outer
/// and inner rows (a skin, a core) could never be a voxel's pixel; the repeated rows match
/// the model's depth, which stays 0 outside the surface and 1 at the innermost.
fn padded_rows(image: &Image2d, pad: usize) -> Result<Image2d> {
    if pad == 0 {
        return Ok(image.clone());
    }
    let (w, h, c) = (image.width(), image.height(), image.channel_count());
    let row = |y: usize| &image.data()[y * w * c..(y + 1) * w * c];
    let data: Vec<f32> = (0..h + 2 * pad).flat_map(|y| row(y.saturating_sub(pad).min(h - 1)).iter().copied()).collect();
    Image2d::from_data(w, h + 2 * pad, image.channels().to_vec(), data)
}

/// How many times the colours' summed variance the depth channel's weighted variance is.
/// Matched at the colours' own share, a region that has taken the wrong layer's colours
/// keeps them (its neighbours agree with it), and a kiwi's pale core or a log's heartwood
/// never forms; at 16 times, a neighbourhood a tenth of the depth off costs about as much
/// as one of wholly other colours. A photo's layers taken tighter sweep: the cliff photo's
/// length ratio 1.07 at 16, 1.6-1.9 at 32, 2.7-3.2 at 64.
pub const DEPTH_SHARE: f32 = 16.0;

/// [`DEPTH_SHARE`] at the coarse levels for a built cross-section (a library exemplar with
/// a Depth channel): its rows are depths exactly, and its thinnest layers are a few rows
/// (the trunk's bark is depth 0 to 0.032), one row or none a few levels down. At 16 and
/// 24 times the log's guided cuts had no bark; at 32 it darkens 54-72 % of the outer band
/// from `--res 256` up (the lapped fill 40 %; at 128, where the bark is one voxel thick,
/// none), the kiwi's seeds as at 16; at 64 the bark is the same and the seeds fainter.
/// Held that tight at the finest matched level too, neighbouring voxels took their columns apart
/// and the rings turned to a comb (gradient ratio 1.54 at `--res 1024`, 0.90 without).
pub const SECTION_DEPTH_SHARE: f32 = 32.0;

/// Each channel's matching weight: 1, but a feature mask's scaled so that its variance
/// equals the colours' summed variance (a mask of 0 and 1 would otherwise outweigh the
/// colours of most photos many times over, and a faint one count for nothing), and the
/// depth's so that its variance is `depth_share` times theirs (at least 1).
fn weights(image: &Image2d, depth_share: f32) -> Vec<f32> {
    let c = image.channel_count();
    let variance = |k: usize| {
        let values = image.data().iter().skip(k).step_by(c);
        let n = (image.data().len() / c).max(1) as f64;
        let mean = values.clone().map(|v| *v as f64).sum::<f64>() / n;
        values.map(|v| (*v as f64 - mean).powi(2)).sum::<f64>() / n
    };
    let names = image.channels();
    let colours: f64 = (0..c).filter(|&k| !matched_only(&names[k])).map(variance).sum();
    (0..c)
        .map(|k| match &names[k] {
            Channel::Named(name) if name == FEATURE => (colours / variance(k).max(1e-12)).sqrt().min(1e3) as f32,
            Channel::Depth => (f64::from(depth_share) * colours / variance(k).max(1e-12)).sqrt().clamp(1.0, 1e3) as f32,
            _ => 1.0,
        })
        .collect()
}

/// One synthesis: the exemplars, the field, the finest grid, the seed.
pub struct Setup<'a> {
    /// The prepared exemplars.
    pub exemplars: &'a Exemplars,
    /// The frame field, in the finest level's voxel coordinates (voxel v's centre at v);
    /// `None`: every frame is the grid's axes.
    pub frames: Option<&'a FrameGrid>,
    /// Per axis, whether neighbourhoods wrap around the grid (the solid then tiles along
    /// it), else they are clamped to it.
    pub wrap: [bool; 3],
    /// The model's depth in the same coordinates: with exemplars carrying a Depth channel,
    /// a neighbourhood's depth is the model's there, so rows land at their depth.
    pub depth: Option<&'a ScalarGrid>,
    /// The finest level's size in voxels.
    pub dims: [usize; 3],
    /// The seed of every random choice.
    pub seed: u64,
    /// Settings.
    pub options: Options,
}

impl Setup<'_> {
    /// Every level's size, coarsest first (a coarse voxel i sits at fine voxel 2i).
    pub fn level_dims(&self) -> Vec<[usize; 3]> {
        let mut out = vec![self.dims];
        for _ in 1..self.options.levels {
            let last = out[out.len() - 1];
            out.push(last.map(|d| d.div_ceil(2)));
        }
        out.reverse();
        out
    }

    /// The frame at voxel `v` of `level`.
    fn frame(&self, level: usize, v: [usize; 3]) -> Mat3 {
        let Some(frames) = self.frames else { return Mat3::IDENTITY };
        let scale = (1usize << (self.options.levels - 1 - level)) as f32;
        frames.at(Vec3::new(v[0] as f32, v[1] as f32, v[2] as f32) * scale)
    }

    /// The value of `values` at the voxel nearest to `p`, wrapped or clamped per axis.
    #[inline]
    fn read(&self, values: &Sparse<Voxel>, p: Vec3) -> Voxel {
        self.read_voxel(values, nearest(p))
    }

    /// The value of `values` at voxel `v`, wrapped or clamped per axis.
    #[inline(always)]
    fn read_voxel(&self, values: &Sparse<Voxel>, mut v: [i64; 3]) -> Voxel {
        for (a, c) in v.iter_mut().enumerate() {
            if self.wrap[a] {
                *c = wrapped(*c, values.dims[a] as i64);
            }
        }
        values.at(v)
    }

    fn exemplar(&self, plane: usize, level: usize) -> &Prepared {
        &self.exemplars.planes[plane][level]
    }

    /// The planes matched: all three, or (layered) the two holding frame z.
    fn planes(&self) -> std::ops::Range<usize> {
        if self.options.layered { 0..2 } else { 0..3 }
    }

    /// The voxel of `level` holding `slot` where no plane is chosen yet (the coarsest
    /// level's start, a child of a parent showing the mean, a value read from a cache):
    /// the mean of its matched planes' pixels, which favours no plane (or the cube's
    /// colour). Corrections show one pixel.
    pub fn voxel(&self, level: usize, slot: [u32; 3]) -> Voxel {
        let mut colour = [0.0; MAX_CHANNELS];
        if let Some(cube) = &self.exemplars.cube {
            colour[..cube.channels].copy_from_slice(cube.at(level, slot.map(i64::from)));
            return Voxel { slot, colour, shown: MEAN };
        }
        let share = 1.0 / self.planes().len() as f32;
        for a in self.planes() {
            let ex = self.exemplar(a, level);
            let p = ex.centres[slot[a] as usize] as usize;
            for (o, c) in colour.iter_mut().zip(&ex.colours[p * ex.channels..(p + 1) * ex.channels]) {
                *o += c * share;
            }
        }
        Voxel { slot, colour, shown: MEAN }
    }

    /// The voxel of `level` holding `slot`, showing plane `a`'s pixel.
    fn showing(&self, level: usize, slot: [u32; 3], a: usize) -> Voxel {
        let mut colour = [0.0; MAX_CHANNELS];
        let ex = self.exemplar(a, level);
        let p = ex.centres[slot[a] as usize] as usize;
        colour[..ex.channels].copy_from_slice(&ex.colours[p * ex.channels..(p + 1) * ex.channels]);
        Voxel { slot, colour, shown: a as u8 }
    }

    /// The voxel of `level` holding `slot` and showing plane `shown` (or [`MEAN`]), as a
    /// run left it: e.g. read back from a cache.
    pub fn restored(&self, level: usize, slot: [u32; 3], shown: u8) -> Voxel {
        match shown {
            MEAN => self.voxel(level, slot),
            a => self.showing(level, slot, usize::from(a)),
        }
    }
}

/// A voxel as a cache keeps it: its slots and the plane it shows, 16 bytes (its colour is
/// the exemplar's, [`Setup::restored`]; a [`Voxel`] with its colours takes 40).
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct Held {
    /// Centre slot per plane.
    pub slot: [u32; 3],
    /// The plane whose pixel it shows, or [`MEAN`].
    pub shown: u8,
}

impl From<Voxel> for Held {
    fn from(v: Voxel) -> Held {
        Held { slot: v.slot, shown: v.shown }
    }
}

/// Per level, the values an earlier run kept (a cache): a voxel held there is read, not
/// computed again. A level past the slice's end keeps nothing.
pub type Kept<'a> = [Option<&'a Sparse<Held>>];

/// The voxels each level and version needs for `request` (voxels of the finest level):
/// `masks[level][version]`, version 0 the upsampled (or initialized) one. A level's last
/// version leaves out what `kept` holds there, and its coarser levels serve only the rest.
pub fn plan(setup: &Setup, request: &Mask, kept: &Kept) -> Vec<Vec<Mask>> {
    plan_from(setup, setup.options.levels - 1, request, kept)
}

/// [`plan`] for a `request` of voxels of level `top`: the masks of levels 0 to `top`.
pub fn plan_from(setup: &Setup, top: usize, request: &Mask, kept: &Kept) -> Vec<Vec<Mask>> {
    let dims = setup.level_dims();
    let mut out: Vec<Vec<Mask>> = vec![Vec::new(); top + 1];
    let mut last = request.clone();
    for level in (0..=top).rev() {
        let (passes, reach) = (setup.options.passes_at(level), setup.options.footprint_at(level));
        let needed = match kept.get(level).copied().flatten() {
            Some(k) => last.without(k.mask()),
            None => last,
        };
        let mut versions = vec![needed];
        for _ in 0..passes {
            let grown = versions[versions.len() - 1].grown_round(reach);
            versions.push(grown);
        }
        versions.reverse();
        last = if level > 0 { versions[0].parents(dims[level - 1]) } else { Mask::empty([0; 3]) };
        out[level] = versions;
    }
    out
}

/// What a run gives: the final version of its last level, and how much it computed.
pub struct Synthesized {
    /// The last level's final values (the voxels computed in this run).
    pub values: Sparse<Voxel>,
    /// The coarser levels' final values computed in this run, coarsest first.
    pub coarser: Vec<Sparse<Voxel>>,
    /// The last level's index.
    pub finest: usize,
    /// Voxels materialized (every computed level's version 0).
    pub voxels: usize,
    /// Corrections made (the later versions' voxels).
    pub corrections: usize,
}

impl Synthesized {
    /// The colour of finest voxel `v` (meaningful where the request asked for it).
    pub fn colour(&self, setup: &Setup, v: [usize; 3]) -> Vec<f32> {
        self.values.at(v.map(|c| c as i64)).colour[..setup.exemplars.channels()].to_vec()
    }

    /// Every level's final values computed in this run, coarsest first.
    pub fn levels(&self) -> impl Iterator<Item = &Sparse<Voxel>> {
        self.coarser.iter().chain([&self.values])
    }
}

/// A level's values as a finer level reads them: computed in this run, else kept.
struct Level<'a> {
    made: &'a Sparse<Voxel>,
    kept: Option<&'a Sparse<Held>>,
}

impl Level<'_> {
    /// Voxel `v` of `level` (this level) of `setup`.
    fn at(&self, setup: &Setup, level: usize, v: [usize; 3]) -> Voxel {
        let v = [0, 1, 2].map(|a| v[a].min(self.made.dims[a] - 1));
        match self.kept {
            Some(kept) if !self.made.holds(v) => {
                let held = kept.at(v.map(|c| c as i64));
                setup.restored(level, held.slot, held.shown)
            }
            _ => self.made.at(v.map(|c| c as i64)),
        }
    }
}

/// Synthesize the voxels `masks` lists ([`plan`]), reading what `kept` holds (the same
/// `kept` the plan was made with).
pub fn run(setup: &Setup, masks: &[Vec<Mask>], kept: &Kept, progress: &dyn Progress) -> Result<Synthesized> {
    let levels = masks.len();
    let mut made: Vec<Sparse<Voxel>> = Vec::with_capacity(levels);
    let (mut voxels, mut corrections) = (0, 0);
    let total: f64 = masks.iter().flatten().map(|m| m.count() as f64).sum::<f64>().max(1.0);
    let mut done = 0.0;
    for (level, versions) in masks.iter().enumerate() {
        if progress.cancelled() {
            return Err(Error::Cancelled);
        }
        let stop = || progress.cancelled();
        let mut current = match made.last() {
            None => Sparse::compute(&versions[0], |v| initial(setup, v)),
            Some(p) => {
                let parents = Level { made: p, kept: kept.get(level - 1).copied().flatten() };
                Sparse::compute(&versions[0], |v| upsampled(setup, level, &parents, v))
            }
        };
        voxels += versions[0].count();
        done += versions[0].count() as f64;
        let mut balance = balance_at(setup, level, versions);
        for (pass, mask) in versions.iter().enumerate().skip(1) {
            current = match balance.as_mut() {
                None => {
                    let before = &current;
                    Sparse::compute_unless(mask, &stop, |v| corrected(setup, level, pass, before, v, None))
                }
                Some(b) => balanced_pass(setup, level, pass, current, mask, b, &stop),
            };
            if progress.cancelled() {
                return Err(Error::Cancelled);
            }
            corrections += mask.count();
            done += mask.count() as f64;
            progress.update(&format!("level {}/{levels}, pass {pass}", level + 1), (done / total) as f32);
        }
        if versions.last().is_some_and(Mask::is_full) {
            show_level(setup, level, &current, progress);
        }
        made.push(current);
    }
    let values = made.pop().ok_or_else(|| Error::invalid("guided synthesis was asked for no level"))?;
    Ok(Synthesized { values, coarser: made, finest: levels - 1, voxels, corrections })
}

/// The colour balance of `level` when its options ask for one and every version covers
/// the whole grid.
fn balance_at(setup: &Setup, level: usize, versions: &[Mask]) -> Option<Balance> {
    let whole = versions.iter().all(Mask::is_full);
    let weighed = setup.options.balance_every_level || level == setup.options.finest_matched();
    if setup.options.histogram <= 0.0 || setup.exemplars.cube.is_some() || !whole || !weighed {
        return None;
    }
    let planes: Vec<&Prepared> = setup.planes().map(|a| setup.exemplar(a, level)).collect();
    let all = [0, 1, 2].map(|a| setup.exemplar(a, level));
    Some(Balance::new(&planes, all, setup.exemplars.channels(), setup.options.histogram))
}

/// One pass over the whole grid with the colour balance: in eight sub-passes, one per
/// parity class of the voxel coordinates, each class corrected from the state the classes
/// before it left and weighed by the counts of that state, so not every voxel reacts to
/// the same over-used colour at once.
fn balanced_pass(
    setup: &Setup,
    level: usize,
    pass: usize,
    mut state: Sparse<Voxel>,
    mask: &Mask,
    balance: &mut Balance,
    stop: &(dyn Fn() -> bool + Sync),
) -> Sparse<Voxel> {
    for class in 0..8 {
        balance.measure(&bin_counts(setup, balance, &state));
        let (before, b) = (&state, &*balance);
        let in_class = |v: [usize; 3]| (v[0] & 1) | (v[1] & 1) << 1 | (v[2] & 1) << 2 == class;
        state = Sparse::compute_unless(mask, stop, |v| {
            if in_class(v) { corrected(setup, level, pass, before, v, Some(b)) } else { before.at(v.map(|c| c as i64)) }
        });
    }
    state
}

/// How many voxels of `values` (a whole grid) show a colour of each bin.
fn bin_counts(setup: &Setup, balance: &Balance, values: &Sparse<Voxel>) -> Vec<u64> {
    use rayon::prelude::*;
    let shown = setup.exemplars.channels();
    let bins = balance.bins();
    (0..values.dims.iter().product())
        .into_par_iter()
        .fold(
            || vec![0u64; bins.count],
            |mut counts, i| {
                let colour = values.at(grid_voxel(values.dims, i).map(|c| c as i64)).colour;
                counts[bins.of_colour(&colour[..shown])] += 1;
                counts
            },
        )
        .reduce(|| vec![0u64; bins.count], |a, b| a.iter().zip(&b).map(|(x, y)| x + y).collect())
}

/// Hand a whole level's shown colours to `progress` (e.g. a preview of the levels).
fn show_level(setup: &Setup, level: usize, values: &Sparse<Voxel>, progress: &dyn Progress) {
    if let Ok(data) = samples(setup, values, false) {
        progress.level_done(level + 1, setup.options.levels, values.dims, setup.exemplars.channels(), &data);
    }
}

/// The shown colours of `values` over its whole grid, x fastest, each voxel followed by
/// its pixel's depth when `with_depth` and the exemplars carry a Depth channel.
pub fn samples(setup: &Setup, values: &Sparse<Voxel>, with_depth: bool) -> Result<Vec<f32>> {
    let shown = setup.exemplars.channels();
    let depth = setup.exemplars.depth.filter(|_| with_depth);
    let count: usize = values.dims.iter().product();
    let mut data = Vec::new();
    data.try_reserve_exact(count * (shown + usize::from(depth.is_some())))
        .map_err(|_| Error::invalid("not enough memory for the solid's samples"))?;
    for i in 0..count {
        let colour = values.at(grid_voxel(values.dims, i).map(|c| c as i64)).colour;
        data.extend_from_slice(&colour[..shown]);
        data.extend(depth.map(|d| colour[d]));
    }
    Ok(data)
}

/// The patch figures of the finest level's `values` over its whole grid
/// ([`super::patches`]); `None` with a solid exemplar (its places are not pixels).
pub fn patches(setup: &Setup, values: &Sparse<Voxel>) -> Option<super::patches::Patches> {
    if setup.exemplars.cube.is_some() {
        return None;
    }
    let level = setup.options.levels - 1;
    let pad = 2 * pad_rows(&setup.options, level);
    let areas = [0, 1, 2].map(|a| {
        let ex = setup.exemplar(a, level);
        ex.width * ex.height.saturating_sub(pad)
    });
    super::patches::measure(values.dims, setup.planes(), areas, |a, v| {
        setup.exemplar(a, level).slot_xy(values.at(v.map(|c| c as i64)).slot[a] as usize)
    })
}

/// A key of everything a synthesis depends on (exemplars, field, grid, seed, settings):
/// the cache's name for its levels.
pub fn fingerprint(setup: &Setup) -> u64 {
    let mut h = crate::noise::mix64(0x5011_d7e8);
    let mut add = |x: u64| h = crate::noise::mix64(h ^ x);
    for finest in setup.exemplars.planes.iter().filter_map(|plane| plane.last()) {
        add(finest.width as u64);
        add(finest.height as u64);
        finest.colours.iter().for_each(|c| add(u64::from(c.to_bits())));
    }
    if let Some(finest) = setup.exemplars.cube.as_ref().and_then(|c| c.levels.last()) {
        add(finest.side as u64);
        finest.colours.iter().for_each(|c| add(u64::from(c.to_bits())));
    }
    if let Some(d) = setup.depth {
        d.values.iter().chain(&d.lo.to_array()).chain([d.step].iter()).for_each(|c| add(u64::from(c.to_bits())));
    }
    if let Some(f) = setup.frames {
        f.lo.to_array().iter().chain([f.step].iter()).for_each(|c| add(u64::from(c.to_bits())));
        f.dims.iter().for_each(|d| add(*d as u64));
        f.corners.iter().flat_map(|q| q.to_array()).for_each(|c| add(u64::from(c.to_bits())));
        f.gradients.iter().flatten().flat_map(|g| g.to_array()).for_each(|c| add(u64::from(c.to_bits())));
        add(u64::from(f.give_way));
    }
    setup.dims.iter().for_each(|d| add(*d as u64));
    setup.wrap.iter().for_each(|w| add(u64::from(*w)));
    let o = setup.options;
    let flags = usize::from(o.layered) | usize::from(o.keep_shown_plane) << 1;
    [o.levels, o.n, o.coarse_n, o.coarse_passes, o.passes, o.k, o.max_dims, flags].iter().for_each(|v| add(*v as u64));
    add(u64::from(o.coarse_depth_share.to_bits()));
    if o.magnified > 0 {
        add(o.magnified as u64);
    }
    add(setup.seed);
    h
}

/// Triples a predicted pixel offers at the finest level (its best by crossbars; the
/// coarser levels offer all `k`): the layout is settled there, and two gave the photos and
/// the channels truth the same figures as six in 30 % less time (docs/synthesis.md).
const FINEST_TRIPLES: usize = 2;

/// How many times its source's rows a layered exemplar's level may hold before the level
/// only magnifies the one below ([`Options::magnifying`]): √2, halfway (in octaves) between
/// the source's own size and twice it.
const MAGNIFIED: f32 = std::f32::consts::SQRT_2;

/// Side of the blocks the coarsest level starts coherent in.
const BLOCK: usize = 8;

/// The coarsest level's start: each plane's pixel follows the voxel's position in its
/// frame from its block's corner, shifted by a random offset per block and plane.
fn initial(setup: &Setup, v: [usize; 3]) -> Voxel {
    if let Some(cube) = &setup.exemplars.cube {
        return cube_initial(setup, cube, v);
    }
    let frame = setup.frame(0, v);
    let block = v.map(|c| (c / BLOCK) as i64);
    let local = frame.transpose() * Vec3::from_array(v.map(|c| (c % BLOCK) as f32));
    let slot = [0, 1, 2].map(|a| {
        let ex = setup.exemplar(a, 0);
        let (pa, sa) = Axis::ALL[a].plane_axes();
        let h = hash3(setup.seed, block[0] + 4096 * a as i64, block[1], block[2]);
        let (w, hgt) = ((ex.width + 1 - ex.n) as i64, (ex.height + 1 - ex.n) as i64);
        let x = ((h & 0xffff) as i64 + local[pa].round() as i64).rem_euclid(w) + ex.half() as i64;
        let y = ((h >> 16 & 0xffff) as i64 + local[sa].round() as i64).rem_euclid(hgt) + ex.half() as i64;
        ex.clamped_slot(x, y) as u32
    });
    setup.voxel(0, slot)
}

/// A voxel of `level` from its parent: the parent's pixels doubled, plus the child's
/// offset from the parent's place turned into the parent's frame (Zhang et al., Eq. 3).
fn upsampled(setup: &Setup, level: usize, parents: &Level, v: [usize; 3]) -> Voxel {
    let p = v.map(|c| c / 2);
    let parent = parents.at(setup, level - 1, p);
    let offset = Vec3::from_array([0, 1, 2].map(|a| (v[a] - 2 * p[a]) as f32));
    let local = setup.frame(level - 1, p).transpose() * offset;
    if let Some(cube) = &setup.exemplars.cube {
        let place = [0, 1, 2].map(|a| 2 * i64::from(parent.slot[a]) + local[a].round() as i64);
        return setup.voxel(level, cube.wrapped(level, place));
    }
    let slot = [0, 1, 2].map(|a| {
        let (coarse, fine) = (setup.exemplar(a, level - 1), setup.exemplar(a, level));
        let (pa, sa) = Axis::ALL[a].plane_axes();
        let (px, py) = coarse.slot_xy(parent.slot[a] as usize);
        let pad = [level - 1, level].map(|l| pad_rows(&setup.options, l) as i64);
        let x = 2 * px + local[pa].round() as i64;
        let y = 2 * (py - pad[0]) + local[sa].round() as i64 + pad[1];
        fine.clamped_slot(x, y) as u32
    });
    let slot = match (setup.depth, setup.exemplars.depth) {
        (Some(depth), Some(channel)) if setup.options.layered && setup.options.magnifies(level) => {
            rows_of_depth(setup, level, slot, v, (depth, channel))
        }
        _ => slot,
    };
    // a child shows the plane its parent shows: a correction's neighbourhoods then see
    // exemplar pixels, not the mean of three (soft, it drew matches to smooth patches that
    // spread: features 1.2-1.5 times the photo's length on granite, 1.1-1.3 this way)
    if setup.options.keep_shown_plane { setup.restored(level, slot, parent.shown) } else { setup.voxel(level, slot) }
}

/// `slot` of voxel `v` with each layered plane's row set to the row whose Depth channel
/// (`channel`, rising down the rows) is nearest the model's `depth` at `v`, in the slot's
/// column. Where a level only magnifies, the layers then bend with the model's depth from
/// voxel to voxel; the parent's rows doubled draw them in steps of two and four voxels
/// (the log's rings at `--res 1024`: gradient ratio 1.41-1.47 with the parent's offset
/// from its depth's row doubled, 1.17-1.27 from the depth alone).
fn rows_of_depth(
    setup: &Setup,
    level: usize,
    mut slot: [u32; 3],
    v: [usize; 3],
    (depth, channel): (&ScalarGrid, usize),
) -> [u32; 3] {
    let scale = (1usize << (setup.options.levels - 1 - level)) as f32;
    let wanted = depth.at(Vec3::from_array(v.map(|c| c as f32)) * scale);
    let pad = pad_rows(&setup.options, level);
    for (a, s) in slot.iter_mut().enumerate().take(2) {
        let ex = setup.exemplar(a, level);
        let (x, _) = ex.slot_xy(*s as usize);
        let at = |y: usize| ex.colours[(y * ex.width + x as usize) * ex.channels + channel];
        // the first row at or past the depth, or the one before it, whichever is nearer
        let (first, last) = (pad, ex.height - pad - 1);
        let (mut lo, mut hi) = (first, last);
        while lo < hi {
            let mid = (lo + hi) / 2;
            if at(mid) < wanted { lo = mid + 1 } else { hi = mid }
        }
        let y = if lo > first && wanted - at(lo - 1) < at(lo) - wanted { lo - 1 } else { lo };
        *s = ex.clamped_slot(x, y as i64) as u32;
    }
    slot
}

/// A scalar field near a point, as its value there plus its gradient: a correction reads the
/// model's depth at its 3 x n x n neighbourhood samples, all within a few voxels of the
/// voxel, where the depth (the field grid's trilinear cells, tens of voxels wide) is near
/// linear; one value and three central differences instead of a trilinear read per sample.
struct Linear {
    value: f32,
    gradient: Vec3,
}

impl Linear {
    /// `grid` at `here` (a level's voxel coordinates, `scale` finest voxels each).
    fn at(grid: &ScalarGrid, here: Vec3, scale: f32) -> Linear {
        let read = |p: Vec3| grid.at(p * scale);
        let gradient = Vec3::from_array([Vec3::X, Vec3::Y, Vec3::Z].map(|e| (read(here + e) - read(here - e)) / 2.0));
        Linear { value: read(here), gradient }
    }

    /// The value at `offset` (level voxels) from the point.
    fn at_offset(&self, offset: Vec3) -> f32 {
        self.value + self.gradient.dot(offset)
    }
}

/// One correction of voxel `v` of `level` from the previous version `before`, candidates
/// weighed by `balance` if given.
fn corrected(
    setup: &Setup,
    level: usize,
    pass: usize,
    before: &Sparse<Voxel>,
    v: [usize; 3],
    balance: Option<&Balance>,
) -> Voxel {
    if let Some(cube) = &setup.exemplars.cube {
        return cube_corrected(setup, cube, level, pass, before, v);
    }
    let frame = setup.frame(level, v);
    let here = Vec3::from_array(v.map(|c| c as f32));
    let centre = v.map(|c| c as i64);
    // the voxel at in-plane offset (dx, dy) of plane `a`, and its position; on the grid's
    // own axes by integers (the same voxel the rounded position gives)
    let sample = |a: usize, dx: i64, dy: i64| -> (Voxel, Vec3) {
        let (pa, sa) = Axis::ALL[a].plane_axes();
        if setup.frames.is_none() {
            let mut q = centre;
            q[pa] += dx;
            q[sa] += dy;
            return (setup.read_voxel(before, q), Vec3::new(q[0] as f32, q[1] as f32, q[2] as f32));
        }
        let p = here + frame.col(pa) * dx as f32 + frame.col(sa) * dy as f32;
        (setup.read(before, p), p)
    };
    let channels = setup.exemplar(0, level).channels;
    let scale = (1usize << (setup.options.levels - 1 - level)) as f32;
    let depth = setup.exemplars.depth.zip(setup.depth).map(|(d, grid)| (d, Linear::at(grid, here, scale)));
    // neighbours propose the same triples and pixels again and again: each is weighed once
    SCRATCH.with_borrow_mut(|scratch| {
        let Scratch { distances, triples: seen, predicted, vector, queries } = scratch;
        for (a, query) in queries.iter_mut().enumerate().take(setup.planes().end) {
            let ex = setup.exemplar(a, level);
            let (n, h) = (ex.n as i64, ex.half() as i64);
            vector.clear();
            for dy in 0..n {
                for dx in 0..n {
                    let (voxel, p) = sample(a, dx - h, dy - h);
                    let mut colour = voxel.colour;
                    if let Some((d, linear)) = &depth {
                        colour[*d] = linear.at_offset(p - here);
                    }
                    vector.extend(colour[..channels].iter().zip(&ex.weights).map(|(c, k)| c * k));
                }
            }
            query.resize(ex.pca.dims, 0.0);
            ex.pca.project_centring(vector, query);
        }
        distances.iter_mut().for_each(Table::start);
        predicted.iter_mut().for_each(Table::start);
        seen.start();
        // the summed distance of triple `t`, or infinity once a partial sum passes `bound`
        // (distances are not negative: such a triple cannot win)
        let mut cost = |t: [u32; 3], bound: f32| -> f32 {
            let factor = balance.map_or(1.0, |b| b.factor(t, setup.planes()));
            let mut sum = 0.0;
            for a in setup.planes() {
                sum += distances[a].get_or(t[a], || {
                    crate::synth::exemplar::squared(&queries[a], setup.exemplar(a, level).projection(t[a] as usize))
                }) * factor;
                if sum > bound {
                    return f32::INFINITY;
                }
            }
            sum
        };
        let own = before.at(v.map(|c| c as i64)).slot;
        seen.contains_else_add(own);
        let mut best = (cost(own, f32::INFINITY), own);
        let mut consider = |t: [u32; 3]| {
            if seen.contains_else_add(t) {
                return;
            }
            let d = cost(t, best.0);
            if d < best.0 || (d == best.0 && t < best.1) {
                best = (d, t);
            }
        };
        let triples = &setup.exemplars.triples[level];
        for a in setup.planes() {
            let ex = setup.exemplar(a, level);
            let (pa, sa) = Axis::ALL[a].plane_axes();
            for ey in -1i64..=1 {
                for ex_ in -1i64..=1 {
                    let neighbour = sample(a, ex_, ey).0;
                    // the neighbour's whole triple, each plane shifted back by the offset (Eq. 4)
                    let mut offset = [0i64; 3];
                    offset[pa] = ex_;
                    offset[sa] = ey;
                    if let Some(t) = shifted(setup, level, neighbour, offset) {
                        consider(t);
                    }
                    let (sx, sy) = ex.slot_xy(neighbour.slot[a] as usize);
                    let (x, y) = (sx - ex_, sy - ey);
                    let pixel = ex.clamped_slot(x, y);
                    if !predicted[a].contains_else_add(pixel as u32) {
                        for &t in triples.of(a, pixel) {
                            consider(t);
                        }
                    }
                }
            }
        }
        let key = [v[0] as i64, v[1] as i64, v[2] as i64 + (((level * 64 + pass) as i64) << 32)];
        let random = setup.exemplar(0, level).random_slot(hash3(setup.seed, key[0], key[1], key[2]));
        consider(triples.of(0, random)[0]);
        // the member whose neighbourhood fits best is the one shown
        let t = best.1;
        let mut fit = |a: usize| {
            distances[a].get_or(t[a], || {
                crate::synth::exemplar::squared(&queries[a], setup.exemplar(a, level).projection(t[a] as usize))
            })
        };
        let shown = setup.planes().min_by(|&a, &b| fit(a).total_cmp(&fit(b))).unwrap_or(0);
        setup.showing(level, t, shown)
    })
}

/// One round of settling a label solid: every voxel of `values` (the finest level, whole
/// grid) shows, of its own triple's pixels, the one most of its six face neighbours
/// show (its current pixel on a tie). Thin sheets keep their colour (most of a sheet
/// voxel's neighbours lie in the sheet), a lone voxel of another label takes its
/// surroundings' when its triple holds it, and nothing is blended.
pub fn settled(setup: &Setup, values: &Sparse<Voxel>) -> Sparse<Voxel> {
    let level = setup.options.levels - 1;
    let shown = setup.exemplars.channels();
    let mask = Mask::full(values.dims);
    Sparse::compute(&mask, |v| {
        let here = values.at(v.map(|c| c as i64));
        let p = Vec3::from_array(v.map(|c| c as f32));
        let around =
            [Vec3::X, -Vec3::X, Vec3::Y, -Vec3::Y, Vec3::Z, -Vec3::Z].map(|d| setup.read(values, p + d).colour);
        let votes = |c: &[f32; MAX_CHANNELS]| around.iter().filter(|n| n[..shown] == c[..shown]).count();
        let mut best = (votes(&here.colour), here);
        for a in setup.planes() {
            let candidate = setup.showing(level, here.slot, a);
            let count = votes(&candidate.colour);
            if count > best.0 {
                best = (count, candidate);
            }
        }
        best.1
    })
}

/// The coarsest level's start with a solid exemplar: the voxel's position in its frame
/// from its block's corner, plus a random place per block.
fn cube_initial(setup: &Setup, cube: &Cube, v: [usize; 3]) -> Voxel {
    let frame = setup.frame(0, v);
    let block = v.map(|c| (c / BLOCK) as i64);
    let local = frame.transpose() * Vec3::from_array(v.map(|c| (c % BLOCK) as f32));
    let h = hash3(setup.seed, block[0], block[1], block[2]);
    let place = [0, 1, 2].map(|a| ((h >> (16 * a)) & 0xffff) as i64 + local[a].round() as i64);
    setup.voxel(0, cube.wrapped(0, place))
}

/// Most values of one plane's neighbourhood (11 x 11 of [`MAX_CHANNELS`]).
const MOST: usize = 121 * MAX_CHANNELS;

/// One correction of voxel `v` with a solid exemplar: its three n x n neighbourhoods in
/// the planes of its frame against the cube's axis-aligned ones at each candidate place;
/// candidates: each 3 x 3 in-plane neighbour's place moved back by its offset, the
/// voxel's own and one random place; the least summed squared distance wins.
fn cube_corrected(
    setup: &Setup,
    cube: &Cube,
    level: usize,
    pass: usize,
    before: &Sparse<Voxel>,
    v: [usize; 3],
) -> Voxel {
    let frame = setup.frame(level, v);
    let here = Vec3::from_array(v.map(|c| c as f32));
    let at = |p: Vec3| setup.read(before, p);
    let (n, ch) = (setup.options.n_at(level), cube.channels);
    let h = (n / 2) as i64;
    let mut queries = [[0.0f32; MOST]; 3];
    for (a, query) in queries.iter_mut().enumerate() {
        let (pa, sa) = Axis::ALL[a].plane_axes();
        let (u, w) = (frame.col(pa), frame.col(sa));
        for (k, (dx, dy)) in (-h..=h).flat_map(|dy| (-h..=h).map(move |dx| (dx, dy))).enumerate() {
            let colour = at(here + u * dx as f32 + w * dy as f32).colour;
            query[k * ch..(k + 1) * ch].copy_from_slice(&colour[..ch]);
        }
    }
    // the summed distance at place `t`, or infinity once a partial sum passes `bound`
    let cost = |t: [u32; 3], bound: f32| -> f32 {
        let mut sum = 0.0;
        for (a, query) in queries.iter().enumerate() {
            sum += cube.plane_distance(level, t, a, n, query);
            if sum > bound {
                return f32::INFINITY;
            }
        }
        sum
    };
    let own = before.at(v.map(|c| c as i64)).slot;
    let mut seen = [[0u32; 3]; 32];
    let mut count = 0;
    let mut best = (cost(own, f32::INFINITY), own);
    let mut consider = |t: [u32; 3]| {
        if t == own || seen[..count].contains(&t) {
            return;
        }
        if count < seen.len() {
            seen[count] = t;
            count += 1;
        }
        let d = cost(t, best.0);
        if d < best.0 || (d == best.0 && t < best.1) {
            best = (d, t);
        }
    };
    for a in 0..3 {
        let (pa, sa) = Axis::ALL[a].plane_axes();
        let (u, w) = (frame.col(pa), frame.col(sa));
        for oy in -1i64..=1 {
            for ox in -1i64..=1 {
                if ox == 0 && oy == 0 {
                    continue;
                }
                let mut p = at(here + u * ox as f32 + w * oy as f32).slot.map(i64::from);
                p[pa] -= ox;
                p[sa] -= oy;
                consider(cube.wrapped(level, p));
            }
        }
    }
    let key = [v[0] as i64, v[1] as i64, v[2] as i64 + (((level * 64 + pass) as i64) << 32)];
    let r = crate::noise::mix64(hash3(setup.seed, key[0], key[1], key[2]));
    consider(cube.wrapped(level, [0, 1, 2].map(|a| ((r >> (20 * a)) & 0xfffff) as i64)));
    setup.voxel(level, best.1)
}

/// `c` wrapped into `0..d` (a division only when `c` lies more than one period out:
/// neighbourhoods reach a few voxels past the grid, and the search reads them by the
/// hundred per voxel).
#[inline]
fn wrapped(c: i64, d: i64) -> i64 {
    if c < 0 {
        if c >= -d { c + d } else { c.rem_euclid(d) }
    } else if c >= d {
        if c < 2 * d { c - d } else { c.rem_euclid(d) }
    } else {
        c
    }
}

/// The voxel nearest to `p` (halves round up): a float-to-integer conversion of a value
/// made positive, which is several times cheaper than `round` where neighbourhoods are
/// sampled. Positions lie within the grid and its reach, far above -4096.
#[inline]
fn nearest(p: Vec3) -> [i64; 3] {
    const LIFT: f32 = 4096.0;
    [p.x, p.y, p.z].map(|c| (c + 0.5 + LIFT) as i64 - LIFT as i64)
}

/// What one correction remembers: each plane's distances by slot, the triples weighed,
/// each plane's predicted pixels whose candidate triples were taken.
struct Scratch {
    distances: [Table<u32, f32>; 3],
    triples: Table<[u32; 3], ()>,
    predicted: [Table<u32, ()>; 3],
    /// One plane's neighbourhood before its projection.
    vector: Vec<f32>,
    /// Each plane's projected neighbourhood.
    queries: [Vec<f32>; 3],
}

thread_local! {
    /// Each thread's scratch tables, started afresh per correction by a new stamp instead
    /// of being cleared.
    static SCRATCH: std::cell::RefCell<Scratch> = std::cell::RefCell::new(Scratch {
        distances: [Table::new(), Table::new(), Table::new()],
        triples: Table::new(),
        predicted: [Table::new(), Table::new(), Table::new()],
        vector: Vec::new(),
        queries: Default::default(),
    });
}

/// Entries of a [`Table`] (a correction weighs at most about 140 triples).
const TABLE: usize = 256;

/// A key a [`Table`] can hash.
trait TableKey: Copy + PartialEq + Default {
    fn hashed(&self) -> u32;
}

impl TableKey for u32 {
    #[inline]
    fn hashed(&self) -> u32 {
        self.wrapping_mul(0x9e37_79b1)
    }
}

impl TableKey for [u32; 3] {
    #[inline]
    fn hashed(&self) -> u32 {
        (self[0] ^ self[1].wrapping_mul(0x85eb_ca6b) ^ self[2].wrapping_mul(0xc2b2_ae35)).wrapping_mul(0x9e37_79b1)
    }
}

/// A small open-addressing map for one correction; `start` forgets every entry at once.
struct Table<K, V> {
    keys: [K; TABLE],
    /// An entry holds a value of this correction when its stamp is `now`.
    stamps: [u32; TABLE],
    values: [V; TABLE],
    now: u32,
}

impl<K: TableKey, V: Copy + Default> Table<K, V> {
    fn new() -> Self {
        Table { keys: [K::default(); TABLE], stamps: [0; TABLE], values: [V::default(); TABLE], now: 0 }
    }

    /// Forget every entry.
    fn start(&mut self) {
        self.now = self.now.wrapping_add(1);
        if self.now == 0 {
            self.stamps = [0; TABLE];
            self.now = 1;
        }
    }

    /// The value of `key`, computed by `value` the first time.
    #[inline]
    fn get_or(&mut self, key: K, value: impl FnOnce() -> V) -> V {
        let mut i = (key.hashed() >> 24) as usize;
        for _ in 0..TABLE {
            if self.stamps[i] != self.now {
                let v = value();
                (self.keys[i], self.stamps[i], self.values[i]) = (key, self.now, v);
                return v;
            }
            if self.keys[i] == key {
                return self.values[i];
            }
            i = (i + 1) % TABLE;
        }
        value()
    }
}

impl<K: TableKey> Table<K, ()> {
    /// Whether `key` was added before in this correction; it is added.
    #[inline]
    fn contains_else_add(&mut self, key: K) -> bool {
        let mut i = (key.hashed() >> 24) as usize;
        for _ in 0..TABLE {
            if self.stamps[i] != self.now {
                (self.keys[i], self.stamps[i]) = (key, self.now);
                return false;
            }
            if self.keys[i] == key {
                return true;
            }
            i = (i + 1) % TABLE;
        }
        false
    }
}

/// A triple moved back by `offset` (in frame axes): each plane's pixel moves by the
/// offset's components along its own two axes (Zhang et al., Eq. 4). `None` when a pixel
/// would leave its exemplar's centres (clamping it would stretch the border's pixels).
fn shifted(setup: &Setup, level: usize, value: Voxel, offset: [i64; 3]) -> Option<[u32; 3]> {
    let mut out = [0u32; 3];
    for (b, slot) in out.iter_mut().enumerate() {
        let ex = setup.exemplar(b, level);
        let (pb, sb) = Axis::ALL[b].plane_axes();
        let (px, py) = ex.slot_xy(value.slot[b] as usize);
        let (x, y) = (px - offset[pb], py - offset[sb]);
        let h = ex.half() as i64;
        if x < h || y < h || x > (ex.width - ex.n) as i64 + h || y > (ex.height - ex.n) as i64 + h {
            return None;
        }
        *slot = ex.clamped_slot(x, y) as u32;
    }
    Some(out)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::fill::tets::cube_lattice;
    use crate::guided::field::{FrameField, solve};
    use glam::Quat;

    /// Progress that counts its polls and the levels it was shown, and asks to stop after
    /// `stop_after` polls.
    #[derive(Default)]
    struct Watch {
        polls: std::sync::atomic::AtomicUsize,
        levels: std::sync::Mutex<Vec<(usize, [usize; 3], usize)>>,
        stop_after: usize,
    }

    impl crate::progress::Progress for Watch {
        fn update(&self, _: &str, _: f32) {}
        fn cancelled(&self) -> bool {
            self.polls.fetch_add(1, std::sync::atomic::Ordering::Relaxed) >= self.stop_after
        }
        fn level_done(&self, level: usize, _: usize, dims: [usize; 3], channels: usize, data: &[f32]) {
            assert_eq!(data.len(), dims.iter().product::<usize>() * channels);
            self.levels.lock().unwrap().push((level, dims, channels));
        }
    }

    /// A whole run shows every level; a cancel is seen per brick of a pass (not once per
    /// pass), and the run stops with `Cancelled`.
    #[test]
    fn a_run_shows_its_levels_and_stops_within_a_pass() {
        let (exemplars, frames) = world(32);
        let setup = setup(&exemplars, &frames, 32);
        let masks = plan(&setup, &Mask::full([32; 3]), &[]);
        let watch = Watch { stop_after: usize::MAX, ..Watch::default() };
        run(&setup, &masks, &[], &watch).unwrap();
        assert_eq!(*watch.levels.lock().unwrap(), [(1, [16; 3], 3), (2, [32; 3], 3)]);
        let polls = watch.polls.into_inner();
        // 2 passes over 2³ bricks and 2 over 4³ bricks, each brick asking once
        assert!(polls >= 2 * 8 + 2 * 64, "{polls} polls");
        let watch = Watch { stop_after: 20, ..Watch::default() };
        assert!(matches!(run(&setup, &masks, &[], &watch), Err(Error::Cancelled)));
        assert!(watch.levels.lock().unwrap().len() <= 1);
    }

    #[test]
    fn a_photo_is_balanced_at_its_finest_level_and_labels_at_every_level() {
        let (exemplars, frames) = world(16);
        let photo = Setup { options: Options { histogram: 4.0, ..options() }, ..setup(&exemplars, &frames, 16) };
        let whole = |level: usize| vec![Mask::full([8 << level; 3]); 3];
        let weighed =
            |setup: &Setup| (0..2).map(|level| balance_at(setup, level, &whole(level)).is_some()).collect::<Vec<_>>();
        assert_eq!(weighed(&photo), vec![false, true]);
        let labels = Setup { options: Options { balance_every_level: true, ..photo.options }, ..photo };
        assert_eq!(weighed(&labels), vec![true, true]);
        let off = Setup { options: Options { histogram: 0.0, ..labels.options }, ..labels };
        assert_eq!(weighed(&off), vec![false, false]);
    }

    /// Every voxel a turned neighbourhood samples (offsets up to n/2 along two orthonormal
    /// axes, read at the nearest voxel) lies in the footprint the plan grows by.
    #[test]
    fn the_footprint_covers_a_turned_neighbourhood() {
        for n in [3, 5, 7, 9] {
            let o = Options { n, ..Options::default() };
            let dims = [41; 3];
            let mut one = Mask::empty(dims);
            one.insert([20; 3]);
            let grown = one.grown_round(o.footprint_at(1));
            let h = (n / 2) as i64;
            for k in 0..2000u64 {
                let r = |s: u64| crate::noise::unit(crate::noise::mix64(k * 7 + s)) * 2.0 - 1.0;
                let turn = glam::Quat::from_euler(glam::EulerRot::XYZ, r(1) * 3.2, r(2) * 3.2, r(3) * 3.2);
                let (u, w) = (turn * Vec3::X, turn * Vec3::Y);
                let centre = Vec3::splat(20.0);
                for dy in -h..=h {
                    for dx in -h..=h {
                        let v = nearest(centre + u * dx as f32 + w * dy as f32).map(|c| c as usize);
                        assert!(grown.contains(v), "n {n}: offset {dx},{dy} along {u}, {w} reads {v:?}");
                    }
                }
            }
        }
    }

    /// A 32x32 exemplar of blobs, a unit cube whose frames turn 60° about x from one face
    /// to the other, a grid of `side`³ voxels.
    fn world(side: usize) -> (Exemplars, FrameGrid) {
        let texel = |x: usize, y: usize| {
            let f = ((x as f32 * 0.41).sin() + (y as f32 * 0.53 + x as f32 * 0.13).cos()) * 0.25 + 0.5;
            let n = (crate::noise::hash3(7, x as i64, y as i64, 0) % 100) as f32 / 1000.0;
            [f + n, 0.8 - f * 0.5, n * 4.0]
        };
        let data = (0..32 * 32).flat_map(|i| texel(i % 32, i / 32)).collect();
        let image = Image2d::from_data(32, 32, Channel::rgb(), data).unwrap();
        let exemplars = Exemplars::prepare([&image, &image, &image], &options()).unwrap();
        let mesh = cube_lattice([4, 4, 4], 0.25);
        let turned = Quat::from_rotation_x(std::f32::consts::FRAC_PI_3);
        let frames = vec![(Vec3::new(0.05, 0.5, 0.5), Quat::IDENTITY), (Vec3::new(0.95, 0.5, 0.5), turned)];
        let field: FrameField = solve(&mesh, &frames).unwrap();
        let grid =
            FrameGrid::sample(&mesh, &field, (Vec3::ZERO, Vec3::ONE), 8).in_voxels(Vec3::ZERO, 1.0 / side as f32);
        (exemplars, grid)
    }

    /// Two levels, a wider neighbourhood at the coarsest (so each level has its own reach).
    fn options() -> Options {
        Options {
            levels: 2,
            n: 5,
            coarse_n: 7,
            coarse_passes: 2,
            passes: 2,
            k: 3,
            max_dims: 8,
            balance_every_level: false,
            keep_shown_plane: true,
            layered: false,
            histogram: 0.0,
            coarse_depth_share: DEPTH_SHARE,
            magnified: 0,
        }
    }

    fn setup<'a>(exemplars: &'a Exemplars, frames: &'a FrameGrid, side: usize) -> Setup<'a> {
        Setup {
            exemplars,
            frames: Some(frames),
            wrap: [false; 3],
            depth: None,
            dims: [side; 3],
            seed: 5,
            options: options(),
        }
    }

    fn colours(setup: &Setup, out: &Synthesized, voxels: &[[usize; 3]]) -> Vec<f32> {
        voxels.iter().flat_map(|v| out.colour(setup, *v)).collect()
    }

    /// A slanted cut synthesized alone equals the same voxels of the whole solid, bit for
    /// bit, and needs fewer voxels; the whole solid is the same on 1 and 3 threads.
    #[test]
    fn a_cut_alone_equals_the_whole_solid_on_any_thread_count() {
        const SIDE: usize = 64;
        let (exemplars, frames) = world(SIDE);
        cut_equals_whole(&setup(&exemplars, &frames, SIDE));
    }

    /// After the coarsest level's passes a voxel shows one plane's pixel, and each of its
    /// children starts showing the same plane's pixel, not the mean of the three.
    #[test]
    fn a_child_shows_the_plane_its_parent_shows() {
        let (exemplars, frames) = world(32);
        let setup = setup(&exemplars, &frames, 32);
        let mut masks = plan(&setup, &Mask::full([32; 3]), &[]);
        masks.truncate(1);
        let coarse = run(&setup, &masks, &[], &crate::progress::NoProgress).unwrap().values;
        let shown = |v: [usize; 3]| coarse.at(v.map(|c| c as i64)).shown;
        let parents: Vec<[usize; 3]> = (0..16 * 16 * 16).map(|i| [i % 16, i / 16 % 16, i / 256]).collect();
        assert!(parents.iter().all(|&p| shown(p) < MEAN), "every corrected voxel shows one plane");
        let planes: std::collections::BTreeSet<u8> = parents.iter().map(|&p| shown(p)).collect();
        assert!(planes.len() > 1, "the planes shown vary: {planes:?}");
        for p in parents.iter().step_by(37) {
            let child = upsampled(&setup, 1, &Level { made: &coarse, kept: None }, p.map(|c| 2 * c + 1));
            assert_eq!(child.shown, shown(*p));
            assert_eq!(child, setup.showing(1, child.slot, usize::from(child.shown)));
        }
    }

    /// The same with a solid exemplar.
    #[test]
    fn with_a_cube_a_cut_alone_equals_the_whole_solid_on_any_thread_count() {
        const SIDE: usize = 64;
        let frames = world(SIDE).1;
        let exemplars = cube_exemplars();
        cut_equals_whole(&Setup { exemplars: &exemplars, ..setup(&exemplars, &frames, SIDE) });
    }

    /// A slanted cut synthesized alone has the colours of the whole solid made on 1 thread;
    /// the whole solid on 3 threads is the same; a cut from a kept coarse level too.
    fn cut_equals_whole(setup: &Setup) {
        let side = setup.dims[0];
        let mut request = Mask::empty(setup.dims);
        let mut cut = Vec::new();
        for y in 0..side {
            for x in 0..side {
                let v = [x, y, (20 + x / 3).min(side - 1)];
                request.insert(v);
                cut.push(v);
            }
        }
        let alone = run(setup, &plan(setup, &request, &[]), &[], &crate::progress::NoProgress).unwrap();
        let full_mask = Mask::full(setup.dims);
        let pool = |threads: usize| rayon::ThreadPoolBuilder::new().num_threads(threads).build().unwrap();
        let whole =
            pool(1).install(|| run(setup, &plan(setup, &full_mask, &[]), &[], &crate::progress::NoProgress).unwrap());
        assert_eq!(colours(setup, &alone, &cut), colours(setup, &whole, &cut));
        assert!(alone.voxels < whole.voxels, "{} voxels for the cut, {} for the whole", alone.voxels, whole.voxels);
        let every: Vec<[usize; 3]> = (0..side * side * side).map(|i| grid_voxel(setup.dims, i)).collect();
        let three =
            pool(3).install(|| run(setup, &plan(setup, &full_mask, &[]), &[], &crate::progress::NoProgress).unwrap());
        assert_eq!(colours(setup, &whole, &every), colours(setup, &three, &every));
        // a level taken over from an earlier whole run (a cache) gives the same cut
        let mut coarse_masks = plan(setup, &full_mask, &[]);
        coarse_masks.truncate(1);
        let coarse = run(setup, &coarse_masks, &[], &crate::progress::NoProgress).unwrap().values;
        let held = coarse.map(Held::from);
        let kept = [Some(&held)];
        let resumed = run(setup, &plan(setup, &request, &kept), &kept, &crate::progress::NoProgress).unwrap();
        assert_eq!(colours(setup, &resumed, &cut), colours(setup, &whole, &cut));
        // what a cut computed, kept (a brick cache): another cut shows the whole solid's
        // colours, a cut beside it reads the coarser voxels they share and computes fewer,
        // the same cut again computes nothing
        let levels: Vec<&Sparse<Voxel>> = alone.levels().collect();
        let held: Vec<Sparse<Held>> = levels.iter().map(|l| l.map(Held::from)).collect();
        let kept: Vec<Option<&Sparse<Held>>> = held.iter().map(Some).collect();
        let merged = |out: &Synthesized, v: [usize; 3]| match out.values.holds(v) {
            true => out.colour(setup, v),
            false => levels[levels.len() - 1].at(v.map(|c| c as i64)).colour[..setup.exemplars.channels()].to_vec(),
        };
        let plane = |f: &dyn Fn(usize, usize) -> [usize; 3]| -> Vec<[usize; 3]> {
            (0..side * side).map(|i| f(i % side, i / side)).collect()
        };
        let crossing = plane(&|a, b| [a, 24, b]);
        let beside = plane(&|x, y| [x, y, (22 + x / 3).min(side - 1)]);
        for (voxels, shares_much) in [(crossing, false), (beside, true)] {
            let mut other = Mask::empty(setup.dims);
            voxels.iter().for_each(|v| other.insert(*v));
            let fresh = run(setup, &plan(setup, &other, &[]), &[], &crate::progress::NoProgress).unwrap();
            let reused = run(setup, &plan(setup, &other, &kept), &kept, &crate::progress::NoProgress).unwrap();
            let shown: Vec<f32> = voxels.iter().flat_map(|v| merged(&reused, *v)).collect();
            assert_eq!(shown, colours(setup, &whole, &voxels));
            if shares_much {
                assert!(reused.voxels < fresh.voxels, "{} voxels kept, {} fresh", reused.voxels, fresh.voxels);
            }
        }
        let again = run(setup, &plan(setup, &request, &kept), &kept, &crate::progress::NoProgress).unwrap();
        assert_eq!((again.voxels, again.corrections), (0, 0));
    }

    /// A tiling 32³ cube of sharp-edged blobs (gradient noise cut at 0) with a little noise, a solid exemplar of two
    /// levels.
    fn cube_exemplars() -> Exemplars {
        let v = crate::volume::Volume::from_fn([32; 3], Channel::grey(), |x, y, z, o| {
            let f = crate::noise::gradient(9, Vec3::new(x as f32, y as f32, z as f32) / 4.0, [8; 3]);
            let n = (hash3(3, x as i64, y as i64, z as i64) % 100) as f32 / 1000.0;
            o[0] = if f > 0.0 { 0.75 } else { 0.25 } + n;
        })
        .unwrap();
        Exemplars::of_cube(Cube::new(&v, &[0], 2, 8).unwrap(), Channel::grey()).unwrap()
    }

    /// The central cut across x of the whole solid synthesized from `exemplars` along a field
    /// turning 60°, and the cube's central slice across x: the solid's sharpness against it.
    fn sharpness_against_the_cube(exemplars: &Exemplars) -> crate::sharpness::AxisSharpness {
        const SIDE: usize = 48;
        let frames = world(SIDE).1;
        let setup = Setup { exemplars, ..setup(exemplars, &frames, SIDE) };
        let out = run(&setup, &plan(&setup, &Mask::full([SIDE; 3]), &[]), &[], &crate::progress::NoProgress).unwrap();
        let cut: Vec<f32> = (0..SIDE * SIDE).map(|i| out.colour(&setup, [SIDE / 2, i % SIDE, i / SIDE])[0]).collect();
        let cut = Image2d::from_data(SIDE, SIDE, Channel::grey(), cut).unwrap();
        crate::sharpness::compare(&[cut], &cube_slice(), &[0]).unwrap()
    }

    fn cube_slice() -> Image2d {
        let cube = cube_exemplars().cube.unwrap();
        let slice = (0..32 * 32).map(|i| cube.at(1, [16, (i % 32) as i64, (i / 32) as i64])[0]).collect();
        Image2d::from_data(32, 32, Channel::grey(), slice).unwrap()
    }

    /// With a solid exemplar the solid's cuts keep the cube's sharpness and feature size
    /// (the yardstick's targets); with the cube's central slice as the three planes'
    /// exemplar too, as each voxel shows one pixel (a mean of three was soft).
    #[test]
    fn cuts_keep_the_exemplars_sharpness() {
        let cube = sharpness_against_the_cube(&cube_exemplars());
        assert!(cube.in_range(), "{cube:?}");
        let slice = cube_slice();
        let planes = Exemplars::prepare([&slice, &slice, &slice], &options()).unwrap();
        let sharp = sharpness_against_the_cube(&planes);
        assert!(sharp.in_range(), "{sharp:?}");
    }

    /// Every voxel shows one exemplar pixel, never a blend: the solid's colours are the
    /// exemplar's, and it is not flat.
    #[test]
    fn the_solid_is_made_of_exemplar_pixels() {
        let (exemplars, frames) = world(32);
        let setup = setup(&exemplars, &frames, 32);
        let out = run(&setup, &plan(&setup, &Mask::full([32; 3]), &[]), &[], &crate::progress::NoProgress).unwrap();
        let image = &exemplars.planes[0][1].colours;
        let range = |c: usize, xs: &[f32]| {
            xs.iter().skip(c).step_by(3).fold((f32::MAX, f32::MIN), |(lo, hi), v| (lo.min(*v), hi.max(*v)))
        };
        let all: Vec<[usize; 3]> = (0..32 * 32 * 32).map(|i| grid_voxel([32; 3], i)).collect();
        let solid = colours(&setup, &out, &all);
        let pixels: Vec<&[f32]> = image.chunks_exact(3).collect();
        for colour in solid.chunks_exact(3) {
            assert!(pixels.contains(&colour), "{colour:?} is no pixel of the exemplar");
        }
        for c in 0..3 {
            let ((lo, hi), (slo, shi)) = (range(c, image), range(c, &solid));
            assert!(slo >= lo - 1e-6 && shi <= hi + 1e-6, "channel {c}: solid {slo}..{shi}, exemplar {lo}..{hi}");
            assert!(shi - slo > 0.3 * (hi - lo), "channel {c} is not flat: {slo}..{shi} of {lo}..{hi}");
        }
    }

    /// Layered settings, frames whose z runs along x and a depth rising from 0 to 1 along x,
    /// over a 32³ grid.
    fn layered_along_x() -> (Options, FrameGrid, ScalarGrid) {
        let options = Options { coarse_n: 5, layered: true, ..options() };
        let z_along_x = Quat::from_rotation_y(std::f32::consts::FRAC_PI_2);
        assert!((z_along_x * Vec3::Z).distance(Vec3::X) < 1e-6);
        let q = glam::Vec4::from(z_along_x);
        let frames = FrameGrid {
            lo: Vec3::splat(-0.5),
            step: 32.0,
            dims: [2; 3],
            corners: vec![q; 8],
            gradients: None,
            give_way: true,
        };
        let depth = crate::guided::field::ScalarGrid {
            lo: Vec3::splat(-0.5),
            step: 32.0,
            dims: [2; 3],
            values: (0..8).map(|i| (i % 2) as f32).collect(),
        };
        (options, frames, depth)
    }

    /// Layered, with the model's depth: an exemplar whose rows darken from the outside
    /// in lands each row at its depth (the depth rising along x, the frames' z along x).
    #[test]
    fn layered_rows_land_at_their_depth() {
        let (w, h) = (32, 32);
        let data = (0..w * h)
            .flat_map(|i| {
                let row = (i / w) as f32 / (h - 1) as f32;
                let n = (crate::noise::hash3(3, (i % w) as i64, (i / w) as i64, 0) % 100) as f32 / 1000.0;
                [1.0 - row + n, 0.3 + n, row]
            })
            .collect();
        let names = vec![Channel::R, Channel::G, Channel::Depth];
        let image = Image2d::from_data(w, h, names, data).unwrap();
        let (options, frames, depth) = layered_along_x();
        let exemplars = Exemplars::prepare([&image, &image, &image], &options).unwrap();
        assert_eq!(exemplars.channels(), 2, "the Depth channel is matched, not shown");
        let run_with = |depth: Option<&crate::guided::field::ScalarGrid>| {
            let setup = Setup {
                exemplars: &exemplars,
                frames: Some(&frames),
                wrap: [false; 3],
                depth,
                dims: [32; 3],
                seed: 2,
                options,
            };
            let out = run(&setup, &plan(&setup, &Mask::full([32; 3]), &[]), &[], &crate::progress::NoProgress).unwrap();
            // how far each voxel's red is from what its depth asks for (1 - depth)
            let mut error = 0.0;
            for i in 0..32 * 32 * 32 {
                let v = grid_voxel([32; 3], i);
                let want = 1.0 - (v[0] as f32 + 0.5) / 32.0;
                error += (out.colour(&setup, v)[0] - want).abs();
            }
            error / (32.0 * 32.0 * 32.0)
        };
        let (guided, free) = (run_with(Some(&depth)), run_with(None));
        assert!(guided < 0.12 && guided * 2.0 < free, "mean error with depth {guided}, without {free}");
    }

    /// A layered exemplar fitted up past √2 times its rows only magnifies at the levels it
    /// fills beyond that, never at the coarsest; those levels make no corrections.
    #[test]
    fn levels_past_the_source_only_magnify() {
        let four = Options::default();
        assert_eq!(four.levels, 4);
        let count = |source, fitted| four.magnifying(source, fitted).magnified;
        let counts = [count(64, 64), count(64, 87), count(64, 100), count(64, 181), count(64, 216), count(4, 4096)];
        assert_eq!(counts, [0, 0, 1, 2, 2, 3], "181 rows halve to 91, past 90.5");
        let magnified = four.magnifying(64, 216);
        assert_eq!((0..4).map(|l| magnified.passes_at(l)).collect::<Vec<_>>(), [4, 2, 0, 0]);
        assert_eq!((magnified.coarse_levels(), four.coarse_levels()), (2, 3));
        // the finest level's rules go to the finest matched level
        assert_eq!((magnified.finest_matched(), four.finest_matched()), (1, 3));
        assert_eq!((magnified.triples_at(1), four.triples_at(1)), (FINEST_TRIPLES, four.k));
    }

    /// Rows of faint noise whose Depth channel rises down them, prepared with `magnified`
    /// levels magnifying, and the setup of a 32³ grid whose depth rises along x.
    fn magnifying_world(magnified: usize) -> (Exemplars, Options, FrameGrid, ScalarGrid) {
        let (w, h) = (32, 32);
        let data = (0..w * h)
            .flat_map(|i| {
                let n = (crate::noise::hash3(7, (i % w) as i64, (i / w) as i64, 0) % 100) as f32 / 200.0;
                [n, 1.0 - n, (i / w) as f32 / (h - 1) as f32]
            })
            .collect();
        let image = Image2d::from_data(w, h, vec![Channel::R, Channel::G, Channel::Depth], data).unwrap();
        let (layered, frames, depth) = layered_along_x();
        let options = Options { magnified, ..layered };
        (Exemplars::prepare([&image, &image, &image], &options).unwrap(), options, frames, depth)
    }

    fn layered_setup<'a>(
        exemplars: &'a Exemplars,
        options: Options,
        frames: &'a FrameGrid,
        depth: &'a ScalarGrid,
    ) -> Setup<'a> {
        Setup { exemplars, frames: Some(frames), wrap: [false; 3], depth: Some(depth), dims: [32; 3], seed: 3, options }
    }

    /// At a level that only magnifies, every voxel's layered rows are its depth's row
    /// (the layers bend with the depth voxel by voxel) and nothing is corrected; matched,
    /// the same level puts some voxels' rows elsewhere.
    #[test]
    fn a_magnifying_level_takes_its_rows_from_the_depth() {
        let off_their_depth = |magnified: usize| {
            let (exemplars, options, frames, depth) = magnifying_world(magnified);
            let setup = layered_setup(&exemplars, options, &frames, &depth);
            let masks = plan(&setup, &Mask::full([32; 3]), &[]);
            let out = run(&setup, &masks, &[], &crate::progress::NoProgress).unwrap();
            let coarse: usize = masks[0][1..].iter().map(Mask::count).sum();
            let pad = pad_rows(&options, 1) as i64;
            let off = (0..32 * 32 * 32)
                .filter(|&i| {
                    let v = grid_voxel([32; 3], i);
                    let slot = out.values.at(v.map(|c| c as i64)).slot;
                    let d = depth.at(Vec3::from_array(v.map(|c| c as f32))).clamp(0.0, 1.0);
                    let row = pad + (d * 31.0).round() as i64;
                    (0..2).any(|a| exemplars.planes[a][1].slot_xy(slot[a] as usize).1 != row)
                })
                .count();
            (off, out.corrections == coarse)
        };
        assert_eq!(off_their_depth(1), (0, true));
        let (off, only_coarse) = off_their_depth(0);
        assert!(off > 1000 && !only_coarse, "{off} voxels off their depth's row when matched");
    }

    /// With a level that only magnifies, a cut alone is the whole solid's plane, on one
    /// thread and three.
    #[test]
    fn a_magnified_cut_alone_equals_the_whole_solid_on_any_thread_count() {
        let (exemplars, options, frames, depth) = magnifying_world(1);
        let setup = layered_setup(&exemplars, options, &frames, &depth);
        let cut: Vec<[usize; 3]> = (0..32 * 32).map(|i| [i % 32, 9 + i / 32 % 32 / 4, i / 32]).collect();
        let mut request = Mask::empty(setup.dims);
        cut.iter().for_each(|v| request.insert(*v));
        let on = |threads: usize, mask: &Mask| {
            let pool = rayon::ThreadPoolBuilder::new().num_threads(threads).build().unwrap();
            pool.install(|| run(&setup, &plan(&setup, mask, &[]), &[], &crate::progress::NoProgress).unwrap())
        };
        let whole = colours(&setup, &on(1, &Mask::full(setup.dims)), &cut);
        assert_eq!(colours(&setup, &on(1, &request), &cut), whole);
        assert_eq!(colours(&setup, &on(3, &request), &cut), whole);
    }

    /// A layered exemplar's outermost and innermost rows (a skin, a core, two rows each,
    /// whose pixels have no whole neighbourhood in the image) are shown where the depth
    /// asks for them, though the colourful rows between them fit their neighbours better.
    #[test]
    fn the_skin_and_core_rows_land_at_the_surface_and_the_axis() {
        let (w, h) = (32, 32);
        let (skin, core) = ([0.1, 0.2, 0.05], [0.95, 0.95, 0.8]);
        let data = (0..w * h)
            .flat_map(|i| {
                let (x, y) = ((i % w) as i64, (i / w) as i64);
                let n = |k: i64| (crate::noise::hash3(5 + k as u64, x, y, 0) % 1000) as f32 / 1000.0;
                let colour = match y {
                    0 | 1 => skin,
                    30 | 31 => core,
                    _ => [0.2 + 0.6 * n(0), 0.5 + 0.4 * n(1), 0.1 + 0.5 * n(2)],
                };
                colour.into_iter().chain([y as f32 / (h - 1) as f32])
            })
            .collect();
        let names = vec![Channel::R, Channel::G, Channel::B, Channel::Depth];
        let image = Image2d::from_data(w, h, names, data).unwrap();
        let (options, frames, depth) = layered_along_x();
        let exemplars = Exemplars::prepare([&image, &image, &image], &options).unwrap();
        let setup = Setup {
            exemplars: &exemplars,
            frames: Some(&frames),
            wrap: [false; 3],
            depth: Some(&depth),
            dims: [32; 3],
            seed: 4,
            options,
        };
        let out = run(&setup, &plan(&setup, &Mask::full([32; 3]), &[]), &[], &crate::progress::NoProgress).unwrap();
        // the share of the voxels of layer x (depth (x + 0.5) / 32) showing `colour`
        let share = |x: usize, colour: [f32; 3]| {
            let near = |v: [usize; 3]| {
                let c = out.colour(&setup, v);
                (0..3).all(|k| (c[k] - colour[k]).abs() < 0.02)
            };
            (0..32 * 32).filter(|i| near([x, i % 32, i / 32])).count() as f32 / 1024.0
        };
        let (outside, inside) = (share(0, skin), share(31, core));
        assert!(outside > 0.8 && inside > 0.8, "skin at the surface {outside}, core at the axis {inside}");
    }

    /// A feature mask is matched: an exemplar of faint noise whose structure only its mask
    /// holds (blobs). With the mask, a voxel's three planes agree on it far more often than
    /// without, and the mask is not a shown channel.
    #[test]
    fn a_feature_mask_is_matched_not_shown() {
        let blob = |x: usize, y: usize| ((x as f32 * 0.45).sin() * (y as f32 * 0.4).cos() > 0.0) as u8 as f32;
        let noise = |i: usize, c: i64| (hash3(11, i as i64, c, 0) % 100) as f32 / 1000.0;
        let image = |masked: bool| {
            let data = (0..32 * 32)
                .flat_map(|i| {
                    let px = [noise(i, 0), noise(i, 1), noise(i, 2), blob(i % 32, i / 32)];
                    px.into_iter().take(if masked { 4 } else { 3 })
                })
                .collect();
            let mut names = Channel::rgb();
            if masked {
                names.push(Channel::Named(FEATURE.into()));
            }
            Image2d::from_data(32, 32, names, data).unwrap()
        };
        let (_, frames) = world(32);
        let agreement = |masked: bool| {
            let image = image(masked);
            let options = Options { coarse_n: 5, ..options() };
            let exemplars = Exemplars::prepare([&image, &image, &image], &options).unwrap();
            assert_eq!(exemplars.channels(), 3, "the mask is not shown");
            let setup = setup(&exemplars, &frames, 32);
            let out = run(&setup, &plan(&setup, &Mask::full([32; 3]), &[]), &[], &crate::progress::NoProgress).unwrap();
            let mut agree = 0;
            for i in 0..32 * 32 * 32 {
                let slot = out.values.at(grid_voxel([32; 3], i).map(|c| c as i64)).slot;
                let mask = [0, 1, 2].map(|a| {
                    let p = exemplars.planes[a][1].centres[slot[a] as usize] as usize;
                    blob(p % 32, p / 32)
                });
                agree += usize::from(mask[0] == mask[1] && mask[1] == mask[2]);
            }
            agree as f32 / (32.0 * 32.0 * 32.0)
        };
        let (with, without) = (agreement(true), agreement(false));
        assert!(with > 0.8 && with > without + 0.25, "planes agree on the mask: {with} with it, {without} without");
    }
}
