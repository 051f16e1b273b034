//! Rendering an LST model (thesis §6.1): a planar cut composites, at every pixel, the
//! patches of the tet that holds the point, top patch first, each through its mask; a bake
//! stacks cuts into a volume.
//!
//! ```text
//!   pixel -> point p on the plane -> tet t (barycentric b) -> for patch in t, top first:
//!            w = Σ b_k w_k ; colour += (1 - A) α(w) c(w) ; A += (1 - A) α(w) ; stop at A ≈ 1
//! ```
//! Tets are binned by the rows of pixels they span; bands of rows render in parallel and
//! each pixel takes the first tet (in index order) that contains it, so the picture does
//! not depend on the thread count.

use super::locate::Location;
use super::model::LstModel;
use super::sampler::Sampler;
use super::tets::TetMesh;
use crate::error::{Error, Result};
use crate::mesh::{Mesh, Slices};
use crate::render::{Rgb8, to_u8};
use crate::volume::{Channel, ModelGrid, Volume};
use glam::{Affine3A, Vec3};
use rayon::prelude::*;

/// Rows per parallel band.
const BAND: usize = 16;
/// Background colour outside the model.
pub const BACKGROUND: [u8; 3] = [24, 24, 28];

/// The samplers of each source: colour (RGB) and mask.
pub struct Textures {
    /// RGB, one per source.
    pub colour: Vec<Sampler>,
    /// Alpha masks, one per source.
    pub masks: Vec<Sampler>,
}

impl Textures {
    /// Pairs colour and mask volumes (R, G, B of the colour, or its first channel as grey).
    pub fn new(colour: &[Volume], masks: &[Volume]) -> Textures {
        Textures {
            colour: colour.iter().map(Sampler::colour).collect(),
            masks: masks.iter().map(Sampler::mask).collect(),
        }
    }

    /// Channel `wanted` of each colour volume (the first of the list it has) in place of
    /// its colour, read as grey, with the same masks; `Err(i)` when volume `i` has none.
    pub fn channel(colour: &[Volume], masks: &[Volume], wanted: &[Channel]) -> std::result::Result<Textures, usize> {
        let samplers = colour
            .iter()
            .enumerate()
            .map(|(i, v)| {
                let c = wanted.iter().find_map(|w| v.channel_index(w)).ok_or(i)?;
                Ok(Sampler::channel(v, c))
            })
            .collect::<std::result::Result<Vec<_>, usize>>()?;
        Ok(Textures { colour: samplers, masks: masks.iter().map(Sampler::mask).collect() })
    }
}

/// The channels a density is read from, in order of preference.
pub fn density_channels() -> [Channel; 2] {
    [Channel::Named("Density".into()), Channel::A]
}

/// A channel carried through a bake besides the colour: its role and, per model, the
/// textures that sample it.
pub struct Carried<'a> {
    /// The channel.
    pub channel: Channel,
    /// One per model, in the models' order.
    pub textures: Vec<&'a Textures>,
}

/// A rectangle of pixels on a plane in model space.
#[derive(Debug, Clone, Copy)]
pub struct View {
    /// The model point of the top-left pixel's corner.
    pub origin: Vec3,
    /// One pixel step to the right.
    pub right: Vec3,
    /// One pixel step down.
    pub down: Vec3,
    /// Size in pixels.
    pub width: usize,
    /// Size in pixels.
    pub height: usize,
}

impl View {
    /// A square view of `size` pixels on the plane through `point` with `normal`, framing
    /// the box `bounds` as seen along the normal.
    pub fn framing(bounds: (Vec3, Vec3), point: Vec3, normal: Vec3, size: usize) -> Result<View> {
        let n = normal.try_normalize().ok_or_else(|| Error::invalid("the cut plane's normal is zero"))?;
        if !(point.is_finite() && n.is_finite() && (8..=8192).contains(&size)) {
            return Err(Error::invalid(format!("cut size {size} must be 8 to 8192 pixels and the plane finite")));
        }
        let up = if n.y.abs() < 0.9 { Vec3::Y } else { Vec3::Z };
        let u = up.cross(n).normalize();
        let v = n.cross(u);
        let (lo, hi) = extent(bounds, u, v);
        let side = (hi - lo).max_element().max(1e-6) * 1.04;
        let mid = (lo + hi) / 2.0;
        let on_plane = n * n.dot(point);
        let step = side / size as f32;
        let origin = on_plane + u * (mid.x - side / 2.0) + v * (mid.y + side / 2.0);
        Ok(View { origin, right: u * step, down: -v * step, width: size, height: size })
    }

    /// The model point at the centre of pixel (x, y).
    pub fn point(&self, x: usize, y: usize) -> Vec3 {
        self.origin + self.right * (x as f32 + 0.5) + self.down * (y as f32 + 0.5)
    }

    fn normal(&self) -> Vec3 {
        self.right.cross(self.down).normalize()
    }
}

/// The 2D extent of a box's corners projected on (u, v).
fn extent((lo, hi): (Vec3, Vec3), u: Vec3, v: Vec3) -> (glam::Vec2, glam::Vec2) {
    let corners = (0..8).map(|i| Vec3::new([lo.x, hi.x][i & 1], [lo.y, hi.y][(i >> 1) & 1], [lo.z, hi.z][i >> 2]));
    corners
        .map(|p| glam::Vec2::new(u.dot(p), v.dot(p)))
        .fold((glam::Vec2::INFINITY, glam::Vec2::NEG_INFINITY), |(a, b), p| (a.min(p), b.max(p)))
}

/// The bounding box of several models' input surfaces (their shapes).
pub fn bounds(models: &[(&LstModel, &Textures)]) -> (Vec3, Vec3) {
    models
        .iter()
        .flat_map(|(m, _)| m.surface.vertices.iter())
        .fold((Vec3::INFINITY, Vec3::NEG_INFINITY), |(a, b), p| (a.min(*p), b.max(*p)))
}

/// A rendered cut: RGBA in [0, 1] per pixel (alpha 0 outside the model).
pub struct Cut {
    /// Width in pixels.
    pub width: usize,
    /// Height in pixels.
    pub height: usize,
    /// RGBA, row by row.
    pub pixels: Vec<[f32; 4]>,
    /// The patch that shows most at each pixel ([`NO_PATCH`] outside; with several models,
    /// model `m`'s patch `p` is `p + m * MODEL_STRIDE`).
    pub patches: Vec<u32>,
}

/// The patch of a pixel outside the model.
pub const NO_PATCH: u32 = u32::MAX;

impl Cut {
    /// A cut of `view`'s size with nothing in it.
    pub fn empty(view: &View) -> Cut {
        let n = view.width * view.height;
        Cut { width: view.width, height: view.height, pixels: vec![[0.0; 4]; n], patches: vec![NO_PATCH; n] }
    }

    /// Emptied and sized for `view`, keeping its memory.
    fn clear(&mut self, view: &View) {
        let n = view.width * view.height;
        (self.width, self.height) = (view.width, view.height);
        self.pixels.resize(n, [0.0; 4]);
        self.patches.resize(n, NO_PATCH);
        self.pixels.par_iter_mut().for_each(|p| *p = [0.0; 4]);
        self.patches.par_iter_mut().for_each(|p| *p = NO_PATCH);
    }
}
/// Patch numbers of one model in [`Cut::patches`] stay below this.
const MODEL_STRIDE: u32 = 1 << 26;
/// The most models a cut, bake, view or rendering combines (their patch numbers share a u32).
pub const MAX_MODELS: usize = 63;

impl Cut {
    /// As an 8-bit picture over [`BACKGROUND`].
    pub fn picture(&self) -> Rgb8 {
        let mut out = Rgb8::new(self.width, self.height, BACKGROUND);
        for (i, p) in self.pixels.iter().enumerate() {
            if p[3] > 0.0 {
                out.put(i % self.width, i / self.width, [to_u8(p[0]), to_u8(p[1]), to_u8(p[2])]);
            }
        }
        out
    }

    /// Share of pixels inside the model.
    pub fn inside_share(&self) -> f64 {
        self.pixels.iter().filter(|p| p[3] > 0.0).count() as f64 / self.pixels.len().max(1) as f64
    }

    /// Seam strength: the mean colour step (RGB distance) between neighbouring pixels
    /// where the patch that shows most changes (within one model), over the mean step
    /// between neighbours of the same patch. 1 means a patch border is as smooth as the texture inside a patch;
    /// `None` when the cut has no border or no pair inside one patch.
    pub fn seam_strength(&self) -> Option<f64> {
        let (mut across, mut within) = ((0.0f64, 0usize), (0.0f64, 0usize));
        let (w, h) = (self.width, self.height);
        for y in 0..h {
            for x in 0..w {
                let i = y * w + x;
                for j in [(x + 1 < w).then_some(i + 1), (y + 1 < h).then_some(i + w)].into_iter().flatten() {
                    let (a, b) = (self.patches[i], self.patches[j]);
                    // outside, or where one model (material) meets another: no seam
                    if a == NO_PATCH || b == NO_PATCH || a / MODEL_STRIDE != b / MODEL_STRIDE {
                        continue;
                    }
                    let (p, q) = (self.pixels[i], self.pixels[j]);
                    let step = ((p[0] - q[0]).powi(2) + (p[1] - q[1]).powi(2) + (p[2] - q[2]).powi(2)).sqrt() as f64;
                    let sum = if a == b { &mut within } else { &mut across };
                    sum.0 += step;
                    sum.1 += 1;
                }
            }
        }
        if across.1 == 0 || within.1 == 0 || within.0 <= 0.0 {
            return None;
        }
        Some((across.0 / across.1 as f64) / (within.0 / within.1 as f64))
    }
}

/// Renders the cut of `model` seen through `view`: its outline is the input surface's
/// cross-section, its texture that of the tets.
pub fn cut(model: &LstModel, textures: &Textures, view: &View) -> Cut {
    cut_within(model, textures, view, &inside_surface(&model.surface, view))
}

/// Per pixel of `view`, whether it lies inside `surface` (its cross-section filled).
pub fn inside_surface(surface: &Mesh, view: &View) -> Vec<bool> {
    Outlines::new(surface, view, view.normal() * view.right.length(), 1).inside(0)
}

/// The cut of `model` at the pixels of `view` that `inside` marks (its outline).
pub fn cut_within(model: &LstModel, textures: &Textures, view: &View, inside: &[bool]) -> Cut {
    let mut out = Cut::empty(view);
    cut_within_into(model, textures, view, inside, &mut out);
    out
}

/// [`cut_within`] written into `out` (taking the view's size), each band of rows by its own
/// thread, so a stack of cuts reuses one picture's memory.
pub fn cut_within_into(model: &LstModel, textures: &Textures, view: &View, inside: &[bool], out: &mut Cut) {
    // made once before the bands below locate points
    model.locator();
    out.clear(view);
    let bands = bin_tets(&model.mesh, view);
    let rows = out.pixels.par_chunks_mut(BAND * view.width).zip(out.patches.par_chunks_mut(BAND * view.width));
    rows.zip(bands.par_iter()).enumerate().for_each(|(b, ((pixels, patches), tets))| {
        render_band(model, textures, view, (b, tets), inside, (pixels, patches));
    });
}

/// The outlines of a stack of parallel views: `view` moved by `step` for each next one,
/// each pixel inside or outside a closed surface (ray parity along the rows, see
/// [`Slices`]; the surface's cross-section filled).
pub struct Outlines {
    /// None for a flat stack (steps in the views' plane), which holds nothing.
    slices: Option<Slices>,
    pixels: usize,
}

impl Outlines {
    /// The outlines of `surface` in `count` views, the first `view`, each next one moved
    /// by `step` (not in the view's plane).
    pub fn new(surface: &Mesh, view: &View, step: Vec3, count: usize) -> Outlines {
        // voxel (x, y, k) of the grid is pixel (x, y) of view k
        let to_model =
            Affine3A::from_cols(view.right.into(), view.down.into(), step.into(), (view.origin - step * 0.5).into());
        let solid = to_model.matrix3.determinant().abs() > 0.0;
        let grid = [view.width, view.height, count];
        let slices = solid.then(|| Slices::new(&surface.transformed(to_model.inverse()), grid));
        Outlines { slices, pixels: view.width * view.height }
    }

    /// Per pixel of view `k`, whether it lies inside the surface.
    pub fn inside(&self, k: usize) -> Vec<bool> {
        self.slices.as_ref().map_or_else(|| vec![false; self.pixels], |s| s.inside(k))
    }
}

/// For each band of rows, the tets that cross the plane there, in index order.
fn bin_tets(mesh: &TetMesh, view: &View) -> Vec<Vec<u32>> {
    const CHUNK: usize = 1024;
    let n = view.normal();
    let offset = n.dot(view.origin);
    let down = view.down / view.down.length_squared();
    let count = view.height.div_ceil(BAND);
    // chunks of tets binned in parallel, then joined in chunk order: each band in index order
    let chunks: Vec<Vec<Vec<u32>>> = (mesh.tets.par_chunks(CHUNK).enumerate())
        .map(|(k, chunk)| {
            let mut bands = vec![Vec::new(); count];
            for (j, tet) in chunk.iter().enumerate() {
                let c = tet.map(|v| mesh.vertices[v as usize]);
                let side = c.map(|p| n.dot(p) - offset);
                if side.iter().all(|s| *s > 0.0) || side.iter().all(|s| *s < 0.0) {
                    continue;
                }
                let rows = c.map(|p| down.dot(p - view.origin));
                let lo = rows.iter().copied().fold(f32::INFINITY, f32::min).floor().max(0.0) as usize;
                let hi = rows.iter().copied().fold(f32::NEG_INFINITY, f32::max).ceil().max(0.0) as usize;
                for band in bands.iter_mut().take((hi / BAND + 1).min(count)).skip(lo / BAND) {
                    band.push((k * CHUNK + j) as u32);
                }
            }
            bands
        })
        .collect();
    let mut bands = vec![Vec::new(); count];
    for chunk in chunks {
        bands.iter_mut().zip(chunk).for_each(|(band, part)| band.extend(part));
    }
    bands
}

/// The pixels of one band of rows, each with the patch that shows most there.
fn render_band(
    model: &LstModel,
    textures: &Textures,
    view: &View,
    (band, tets): (usize, &[u32]),
    inside: &[bool],
    (pixels, patches): (&mut [[f32; 4]], &mut [u32]),
) {
    let y0 = band * BAND;
    let y1 = (y0 + BAND).min(view.height);
    let mut put = |i: usize, (colour, patch): ([f32; 4], u32)| {
        pixels[i] = colour;
        patches[i] = patch;
    };
    let inside = &inside[y0 * view.width..y1 * view.width];
    // pixels outside the surface count as done: nothing shows there
    let mut done: Vec<bool> = inside.iter().map(|i| !i).collect();
    let (right, down) = (view.right / view.right.length_squared(), view.down / view.down.length_squared());
    let (normal, offset) = (view.normal(), view.normal().dot(view.origin));
    for &t in tets {
        let t = t as usize;
        let c = model.mesh.corners(t);
        let section = section(&c, normal, offset);
        let (xs, ys): (Vec<f32>, Vec<f32>) =
            section.iter().map(|p| (right.dot(*p - view.origin), down.dot(*p - view.origin))).unzip();
        let (x_lo, x_hi) = pixel_span(&xs, view.width);
        let (y_lo, y_hi) = pixel_span(&ys, view.height);
        let (y_lo, y_hi) = (y_lo.max(y0), y_hi.min(y1));
        if y_lo >= y_hi || x_lo >= x_hi {
            continue;
        }
        let inverse = model.mesh.edges(t).inverse();
        let layers = layers_of(model, t);
        for y in y_lo..y_hi {
            for x in x_lo..x_hi {
                let i = (y - y0) * view.width + x;
                if done[i] {
                    continue;
                }
                let l = inverse * (view.point(x, y) - c[0]);
                let b = [1.0 - l.x - l.y - l.z, l.x, l.y, l.z];
                if b.iter().all(|w| *w >= -1e-5) {
                    let layers = (layers.iter().rev().copied(), layers.first().copied());
                    put(i, shade(textures, layers, b, false, lift(model, t, b)));
                    done[i] = true;
                }
            }
        }
    }
    // inside the surface but in no tet: the nearest boundary tet's texture, extended
    for (i, _) in done.iter().enumerate().filter(|(_, d)| !**d) {
        let (x, y) = (i % view.width, y0 + i / view.width);
        if let Some(at) = model.locate(view.point(x, y)) {
            put(i, shade_at_with_patch(model, textures, &at));
        }
    }
}

/// A field given at the mesh's vertices (e.g. depth), interpolated at every pixel of the
/// view inside the mesh (None outside).
pub fn field_cut(mesh: &TetMesh, values: &[f32], view: &View) -> Vec<Option<f32>> {
    let bands = bin_tets(mesh, view);
    let (right, down) = (view.right / view.right.length_squared(), view.down / view.down.length_squared());
    let (normal, offset) = (view.normal(), view.normal().dot(view.origin));
    let rows: Vec<Vec<Option<f32>>> = bands
        .par_iter()
        .enumerate()
        .map(|(band, tets)| {
            let y0 = band * BAND;
            let y1 = (y0 + BAND).min(view.height);
            let mut out = vec![None; (y1 - y0) * view.width];
            for &t in tets {
                let t = t as usize;
                let c = mesh.corners(t);
                let section = section(&c, normal, offset);
                let (xs, ys): (Vec<f32>, Vec<f32>) =
                    section.iter().map(|p| (right.dot(*p - view.origin), down.dot(*p - view.origin))).unzip();
                let ((x_lo, x_hi), (y_lo, y_hi)) = (pixel_span(&xs, view.width), pixel_span(&ys, view.height));
                let inverse = mesh.edges(t).inverse();
                let at = mesh.tets[t].map(|v| values.get(v as usize).copied().unwrap_or(0.0));
                for y in y_lo.max(y0)..y_hi.min(y1) {
                    for x in x_lo..x_hi {
                        let i = (y - y0) * view.width + x;
                        let l = inverse * (view.point(x, y) - c[0]);
                        let b = [1.0 - l.x - l.y - l.z, l.x, l.y, l.z];
                        if out[i].is_none() && b.iter().all(|w| *w >= -1e-5) {
                            out[i] = Some(b.iter().zip(at).map(|(w, v)| w * v).sum());
                        }
                    }
                }
            }
            out
        })
        .collect();
    rows.into_iter().flatten().collect()
}

/// The points where the tet's edges cross the plane `normal . p = offset`.
fn section(c: &[Vec3; 4], normal: Vec3, offset: f32) -> Vec<Vec3> {
    let side = c.map(|p| normal.dot(p) - offset);
    let mut points = Vec::with_capacity(4);
    for (a, b) in super::tets::EDGES {
        if (side[a] <= 0.0) != (side[b] <= 0.0) {
            let t = side[a] / (side[a] - side[b]);
            points.push(c[a].lerp(c[b], t));
        }
    }
    points
}

fn pixel_span(coords: &[f32], limit: usize) -> (usize, usize) {
    let lo = coords.iter().copied().fold(f32::INFINITY, f32::min).floor().max(0.0) as usize;
    let hi = (coords.iter().copied().fold(f32::NEG_INFINITY, f32::max).ceil().max(0.0) as usize + 1).min(limit);
    (lo.min(limit), hi)
}

/// One patch of a tet: its source, its texture coordinates at the tet's corners, its number.
type Layer = (usize, [Vec3; 4], u32);

/// The patches of tet `t`, bottom first.
fn layers_of(model: &LstModel, t: usize) -> Vec<Layer> {
    model.tet_patches[t].iter().map(|&p| layer(model, t, p)).collect()
}

/// Patch `p` of tet `t` as a layer.
fn layer(model: &LstModel, t: usize, p: u32) -> Layer {
    let patch = &model.patches[p as usize];
    (patch.source as usize, patch.corners(model.mesh.tets[t]), p)
}

/// The layers of tet `t` from the top, made one at a time (compositing mostly stops after
/// the first or second), and its bottom layer.
fn lazy_layers(model: &LstModel, t: usize) -> (impl Iterator<Item = Layer> + '_, Option<Layer>) {
    let list = &model.tet_patches[t];
    (list.iter().rev().map(move |&p| layer(model, t, p)), list.first().map(|&p| layer(model, t, p)))
}

/// The composited colour of the model at `point` (see [`LstModel::locate`]); `None` only
/// for a point that is not finite or a model without tets.
pub fn shade_point(model: &LstModel, textures: &Textures, point: Vec3) -> Option<[f32; 4]> {
    model.locate(point).map(|at| shade_at(model, textures, &at))
}

/// The composited colour of the model at a located point.
pub fn shade_at(model: &LstModel, textures: &Textures, at: &Location) -> [f32; 4] {
    shade_at_with_patch(model, textures, at).0
}

/// [`shade_at`], and the patch that contributes most.
fn shade_at_with_patch(model: &LstModel, textures: &Textures, at: &Location) -> ([f32; 4], u32) {
    let t = at.tet as usize;
    shade(textures, lazy_layers(model, t), at.weights, !at.inside, lift(model, t, at.weights))
}

/// How a depth-varying model's texture depth rises at barycentric point `b` of tet `t`
/// above the linear interpolation of the corners' ([`LstModel::depth`]).
fn lift(model: &LstModel, t: usize, b: [f32; 4]) -> Option<Lift> {
    model.depth.as_ref().map(|d| Lift { axis: d.axis, sources: d.sources, by: d.at(t, b) })
}

/// A shift of the texture point along the depth axis, for the layers of the first
/// `sources` sources.
#[derive(Debug, Clone, Copy)]
struct Lift {
    axis: usize,
    sources: usize,
    by: f32,
}

/// The layers of the tet a run of neighbouring points falls in, made once for the run
/// (neighbouring pixels of a view mostly share their tet).
#[derive(Default)]
pub struct TetLayers {
    tet: Option<u32>,
    layers: Vec<Layer>,
}

impl TetLayers {
    /// [`shade_at`], with the layers of `at`'s tet kept for the next point in the same tet.
    pub fn shade_at(&mut self, model: &LstModel, textures: &Textures, at: &Location) -> [f32; 4] {
        if self.tet != Some(at.tet) {
            self.tet = Some(at.tet);
            self.layers = layers_of(model, at.tet as usize);
        }
        let layers = (self.layers.iter().rev().copied(), self.layers.first().copied());
        let t = at.tet as usize;
        shade(textures, layers, at.weights, !at.inside, lift(model, t, at.weights)).0
    }
}

/// Composites the layers at barycentric point `b`, top first; also the patch that
/// contributes most. A point `extended` past its tet reads each texture at the nearest
/// point of the texture cube, so a patch's mask does not end at the tet's face.
fn shade(
    textures: &Textures,
    (top_first, bottom): (impl Iterator<Item = Layer>, Option<Layer>),
    b: [f32; 4],
    extended: bool,
    lift: Option<Lift>,
) -> ([f32; 4], u32) {
    let at = |source: usize, w: &[Vec3; 4]| {
        let mut p = w[0] * b[0] + w[1] * b[1] + w[2] * b[2] + w[3] * b[3];
        if let Some(l) = lift.filter(|l| source < l.sources) {
            p[l.axis] = (p[l.axis] + l.by).clamp(0.0, 1.0);
        }
        if extended { p.clamp(Vec3::ZERO, Vec3::ONE) } else { p }
    };
    let mut colour = Vec3::ZERO;
    let mut cover = 0.0f32;
    let (mut most, mut share) = (NO_PATCH, 0.0f32);
    for (source, w, patch) in top_first {
        let p = at(source, &w);
        let a = textures.masks[source].alpha(p);
        if a <= 0.0 {
            continue;
        }
        let weight = a * (1.0 - cover);
        colour += textures.colour[source].rgb(p) * weight;
        cover += weight;
        if weight > share {
            (most, share) = (patch, weight);
        }
        if cover > 0.996 {
            break;
        }
    }
    if cover > 0.0 {
        colour /= cover;
    } else if let Some((source, w, patch)) = bottom {
        colour = textures.colour[source].rgb(at(source, &w));
        most = patch;
    }
    ([colour.x, colour.y, colour.z, 1.0], most)
}

/// Cuts several models (a multi-material model): each pixel shows the first model that
/// holds it.
pub fn cut_many(models: &[(&LstModel, &Textures)], view: &View) -> Cut {
    let step = view.normal() * view.right.length();
    let insides: Vec<Vec<bool>> =
        models.iter().map(|(m, _)| Outlines::new(&m.surface, view, step, 1).inside(0)).collect();
    cut_many_within(models, view, &insides)
}

/// [`cut_many`] with each model's outline given (`insides`, one per model).
pub fn cut_many_within(models: &[(&LstModel, &Textures)], view: &View, insides: &[Vec<bool>]) -> Cut {
    let (mut out, mut other) = (Cut::empty(view), Cut::empty(view));
    cut_many_within_into(models, view, insides, (&mut out, &mut other));
    out
}

/// [`cut_many_within`] written into `out`, with `other` for the second and later models'
/// cuts: a stack of cuts reuses their memory.
pub fn cut_many_within_into(
    models: &[(&LstModel, &Textures)],
    view: &View,
    insides: &[Vec<bool>],
    (out, other): (&mut Cut, &mut Cut),
) {
    if models.is_empty() {
        out.clear(view);
    }
    for (m, ((model, textures), inside)) in models.iter().zip(insides).enumerate() {
        if m == 0 {
            cut_within_into(model, textures, view, inside, out);
            continue;
        }
        cut_within_into(model, textures, view, inside, other);
        let offset = (m as u32).saturating_mul(MODEL_STRIDE);
        let pairs = out.pixels.par_iter_mut().zip(out.patches.par_iter_mut());
        pairs.zip(other.pixels.par_iter().zip(other.patches.par_iter())).for_each(|((p, a), (q, b))| {
            if p[3] == 0.0 {
                *p = *q;
                *a = if *b == NO_PATCH { NO_PATCH } else { b + offset };
            }
        });
    }
}

/// The outlines of every model in a stack of `count` parallel views, the first `view`,
/// each next moved by `step`.
pub fn stack_outlines(models: &[(&LstModel, &Textures)], view: &View, step: Vec3, count: usize) -> Vec<Outlines> {
    models.iter().map(|(m, _)| Outlines::new(&m.surface, view, step, count)).collect()
}

/// Where [`bake`] puts its grid: the model-space corner of voxel (0, 0, 0)'s cell and one
/// voxel's side.
pub fn bake_grid(models: &[(&LstModel, &Textures)], res: usize) -> (Vec3, f32) {
    let (lo, hi) = bounds(models);
    (lo, (hi - lo).max_element() / res as f32)
}

/// Voxels along each axis of a box of `extent` with `res` along its longest side: exactly
/// `res` there (the extent over one voxel's side can round just past it), enough to cover
/// each other side.
fn bake_dims(extent: Vec3, res: usize) -> [usize; 3] {
    let longest = (extent.max_element() as f64).max(f64::MIN_POSITIVE);
    extent.to_array().map(|e| ((e as f64 / longest * res as f64) * (1.0 - 1e-6)).ceil().clamp(1.0, res as f64) as usize)
}

/// Samples models into a volume of `res` voxels along the longest side of their box: R, G,
/// B, then the `carried` channels, then A (1 inside; every channel 0 outside); a stack of
/// axis-aligned cuts. The volume records its place in model space (voxel (0, 0, 0)'s
/// centre at the box's low corner plus half a voxel).
pub fn bake(models: &[(&LstModel, &Textures)], carried: &[Carried], res: usize, budget: u64) -> Result<Volume> {
    if !(2..=1024).contains(&res) {
        return Err(Error::invalid(format!("bake resolution {res} is out of range; allowed 2 to 1024")));
    }
    if let Some(c) = carried.iter().find(|c| c.textures.len() != models.len()) {
        return Err(Error::invalid(format!(
            "channel {} has {} textures for {} models",
            c.channel,
            c.textures.len(),
            models.len()
        )));
    }
    let (lo, step) = bake_grid(models, res);
    let dims = bake_dims(bounds(models).1 - lo, res);
    let channels: Vec<Channel> = [Channel::R, Channel::G, Channel::B]
        .into_iter()
        .chain(carried.iter().map(|c| c.channel.clone()))
        .chain([Channel::A])
        .collect();
    crate::volume::check_size(dims, channels.len(), budget)?;
    let count = dims[0] * dims[1] * dims[2] * channels.len();
    let mut data: Vec<f32> = Vec::new();
    data.try_reserve_exact(count).map_err(|_| Error::invalid(format!("no memory for a {count}-value bake")))?;
    data.resize(count, 0.0);
    let slice = |z: usize| {
        let origin = Vec3::new(lo.x, lo.y, lo.z + (z as f32 + 0.5) * step);
        View { origin, right: Vec3::X * step, down: Vec3::Y * step, width: dims[0], height: dims[1] }
    };
    let outlines = stack_outlines(models, &slice(0), Vec3::Z * step, dims[2]);
    // slices are independent: several at once keep both cores busy (a slice alone has
    // few bands of rows to share out)
    data.par_chunks_mut(dims[0] * dims[1] * channels.len()).enumerate().for_each(|(z, out)| {
        let view = slice(z);
        let insides: Vec<Vec<bool>> = outlines.iter().map(|o| o.inside(z)).collect();
        let colour = cut_many_within(models, &view, &insides).pixels;
        let extra: Vec<Vec<[f32; 4]>> = carried
            .iter()
            .map(|c| {
                let pairs: Vec<(&LstModel, &Textures)> =
                    models.iter().map(|(m, _)| *m).zip(c.textures.iter().copied()).collect();
                cut_many_within(&pairs, &view, &insides).pixels
            })
            .collect();
        for ((i, p), voxel) in colour.iter().enumerate().zip(out.chunks_exact_mut(channels.len())) {
            voxel[..3].copy_from_slice(&p[..3]);
            voxel[3..3 + extra.len()].iter_mut().zip(&extra).for_each(|(v, e)| *v = e[i][0]);
            voxel[3 + extra.len()] = p[3];
        }
    });
    let grid = ModelGrid { origin: (lo + Vec3::splat(step / 2.0)).to_array(), voxel: step };
    Ok(Volume::from_data(dims, channels, data)?.with_model_grid(Some(grid)))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// `--res N` gives N voxels along the longest side whatever the box (one voxel's side
    /// times N rounds past the box for many), and the other sides cover the box.
    #[test]
    fn a_bake_has_res_voxels_along_its_longest_side() {
        for extent in [Vec3::new(2.0654, 1.3326, 1.3326), Vec3::new(0.731, 2.449, 0.9), Vec3::new(1.0, 1.0, 1.0)] {
            for res in 2..=512 {
                let dims = bake_dims(extent, res);
                let step = extent.max_element() / res as f32;
                assert_eq!(*dims.iter().max().unwrap(), res, "{extent} at {res}: {dims:?}");
                for a in 0..3 {
                    assert!(dims[a] as f32 * step >= extent[a] * (1.0 - 1e-5), "{extent} at {res}: {dims:?}");
                }
            }
        }
    }

    /// A 32x32 cut of a gentle ramp (a step of 0.01 between neighbours), two patches split
    /// at x = 16, with `jump` added to the right patch.
    fn two_patches(jump: f32) -> Cut {
        let (w, h) = (32, 32);
        let pixels = (0..w * h)
            .map(|i| {
                let v = 0.2 + 0.01 * (i % w) as f32 + if i % w >= 16 { jump } else { 0.0 };
                [v, v, v, 1.0]
            })
            .collect();
        let patches = (0..w * h).map(|i| u32::from(i % w >= 16)).collect();
        Cut { width: w, height: h, pixels, patches }
    }

    /// A field linear in x is read back exactly at every pixel of a cut, and nothing
    /// outside the mesh.
    #[test]
    fn field_cut_interpolates_a_linear_field_exactly() {
        let mesh = crate::fill::tets::cube_lattice([4, 4, 4], 0.25);
        let values: Vec<f32> = mesh.vertices.iter().map(|v| 2.0 * v.x + 0.5).collect();
        let view = View::framing((Vec3::ZERO, Vec3::ONE), Vec3::splat(0.5), Vec3::Z, 32).unwrap();
        let cut = field_cut(&mesh, &values, &view);
        let (mut inside, mut outside) = (0, 0);
        for y in 0..32 {
            for x in 0..32 {
                let p = view.point(x, y);
                let within = p.x > 0.0 && p.x < 1.0 && p.y > 0.0 && p.y < 1.0;
                match cut[y * 32 + x] {
                    Some(v) => {
                        assert!((v - (2.0 * p.x + 0.5)).abs() < 1e-4, "{v} at {p}");
                        inside += 1;
                    }
                    None => {
                        assert!(!within || p.x < 0.01 || p.x > 0.99 || p.y < 0.01 || p.y > 0.99, "a hole at {p}");
                        outside += 1;
                    }
                }
            }
        }
        assert!(inside > 800 && outside > 0, "{inside} inside, {outside} outside");
    }

    /// A coarse tet mesh of a ball, one grey patch over it, and the ball.
    fn coarse_ball() -> (LstModel, Textures) {
        let ball = crate::mesh::shapes::ellipsoid(Vec3::splat(1.0), 24, 48);
        let mesh = crate::fill::mesher::tetrahedralize(&ball, 400).unwrap();
        let vertices: Vec<u32> = (0..mesh.vertices.len() as u32).collect();
        let patch = super::super::paste::Patch { source: 0, coords: vec![Vec3::splat(0.5); vertices.len()], vertices };
        let source = super::super::Source {
            exemplar: "grey".into(),
            volume: "grey.exr".into(),
            mask: super::super::MaskRef::File("m.exr".into()),
        };
        let tet_patches = vec![vec![0]; mesh.tets.len()];
        let model = LstModel::new(mesh, ball, vec![source], vec![patch], tet_patches);
        let grey = Volume::from_fn([4; 3], Channel::rgb(), |_, _, _, o| o.fill(0.8)).unwrap();
        let full = Volume::from_fn([4; 3], vec![Channel::A], |_, _, _, o| o.fill(1.0)).unwrap();
        (model, Textures::new(&[grey], &[full]))
    }

    /// A cut's outline is the input surface's cross-section, pixel for pixel, where the
    /// coarse tets' own cross-section strays from it; every pixel inside is textured.
    #[test]
    fn a_cut_takes_its_outline_from_the_input_surface() {
        let (model, textures) = coarse_ball();
        let view =
            View::framing(model.surface.bounds(), Vec3::new(0.0, 0.1, 0.0), Vec3::new(0.3, 1.0, 0.2), 96).unwrap();
        let picture = cut(&model, &textures, &view);
        let ones = vec![1.0; model.mesh.vertices.len()];
        let tets = field_cut(&model.mesh, &ones, &view);
        let (mut wrong, mut tets_wrong) = (0, 0);
        let surface = &model.surface;
        let on_surface = |q: Vec3| {
            let corners = surface.triangles.iter().map(|t| t.map(|v| surface.vertices[v as usize]));
            corners.map(|c| q.distance(crate::mesh::closest_on_triangle(q, c))).fold(f32::INFINITY, f32::min) < 1e-4
        };
        for (i, p) in picture.pixels.iter().enumerate() {
            let q = view.point(i % 96, i / 96);
            let inside = surface.contains(q);
            // a centre on the surface itself may fall either way
            wrong += usize::from((p[3] > 0.0) != inside && !on_surface(q));
            tets_wrong += usize::from(tets[i].is_some() != inside);
            assert!(!inside || (p[0] - 0.8).abs() < 1e-5, "pixel {i}: {p:?}");
        }
        assert_eq!(wrong, 0);
        assert!(tets_wrong > 20, "the tets alone would miss or add {tets_wrong} pixels");
    }

    /// A bake's coverage is the input surface's at every voxel centre.
    #[test]
    fn a_bake_covers_the_voxels_inside_the_input_surface() {
        let (model, textures) = coarse_ball();
        let volume = bake(&[(&model, &textures)], &[], 24, u64::MAX).unwrap();
        let (lo, hi) = bounds(&[(&model, &textures)]);
        let step = (hi - lo).max_element() / 24.0;
        let [nx, ny, nz] = volume.dims();
        let alpha = volume.channel_index(&Channel::A).unwrap();
        let mut wrong = 0;
        for z in 0..nz {
            for y in 0..ny {
                for x in 0..nx {
                    let centre = lo + (Vec3::new(x as f32, y as f32, z as f32) + 0.5) * step;
                    wrong += usize::from((volume.get(x, y, z, alpha) > 0.0) != model.surface.contains(centre));
                }
            }
        }
        assert_eq!(wrong, 0, "of {} voxels", nx * ny * nz);
    }

    #[test]
    fn a_seam_shows_as_a_step_larger_than_the_texture_inside() {
        // Horizontal pairs step 0.01 * sqrt 3, vertical ones 0: within-patch mean about half of it.
        let smooth = two_patches(0.0).seam_strength().unwrap();
        assert!(
            (smooth - 2.0).abs() < 0.1,
            "the border steps like the ramp, against a mean halved by still rows: {smooth}"
        );
        let hard = two_patches(0.2).seam_strength().unwrap();
        assert!(hard > 20.0 * smooth, "a jump of 0.2 at the border: {hard}");
        let one = Cut { patches: vec![0; 32 * 32], ..two_patches(0.2) };
        assert_eq!(one.seam_strength(), None, "no border, no figure");
    }
}
