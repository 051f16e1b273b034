//! Where guided synthesis runs and what it gives back: the voxel grid around a model, the
//! voxels a cut needs, the cut's picture and the whole solid as a volume.

use super::field::{FrameField, FrameGrid, ScalarGrid};
use crate::error::{Error, Result};
use crate::fill::render::View;
use crate::fill::render::{BACKGROUND, inside_surface};
use crate::fill::tets::TetMesh;
use crate::mesh::voxelize::Slices;
use crate::mesh::{Mesh, closest_on_segment};
use crate::progress::Progress;
use crate::render::{ColourMap, Rgb8};
use crate::synth::coords::{self as synth, Held, Kept, Setup, Synthesized, Voxel};
use crate::synth::region::{Mask, Sparse};
use crate::volume::{Channel, Image2d, ModelGrid, Volume};
use glam::{Affine3A, Vec3};

/// Finest-level resolutions `guided` accepts (voxels along the grid's longest side).
pub const RESOLUTION: std::ops::RangeInclusive<usize> = 16..=1024;

/// Share of the model's longest side added around it on every side: neighbourhoods at the
/// surface read texture, not the grid's clamped edge.
const MARGIN: f32 = 0.05;

/// The finest voxel grid around a model.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Domain {
    /// The corner of voxel (0, 0, 0).
    pub origin: Vec3,
    /// Voxel side in model units.
    pub voxel: f32,
    /// Voxels per axis.
    pub dims: [usize; 3],
}

impl Domain {
    /// The grid over `bounds` plus a margin, `res` voxels along its longest side.
    pub fn around((lo, hi): (Vec3, Vec3), res: usize) -> Result<Domain> {
        if !RESOLUTION.contains(&res) {
            return Err(Error::invalid(format!(
                "resolution {res} is out of range; allowed {} to {}",
                RESOLUTION.start(),
                RESOLUTION.end()
            )));
        }
        let longest = (hi - lo).max_element();
        if !(longest.is_finite() && longest > 0.0) {
            return Err(Error::invalid("the mesh has no extent"));
        }
        let margin = Vec3::splat(MARGIN * longest);
        let (lo, hi) = (lo - margin, hi + margin);
        let voxel = (hi - lo).max_element() / res as f32;
        let dims = ((hi - lo) / voxel).round().to_array().map(|d| (d as usize).clamp(1, res));
        Ok(Domain { origin: lo, voxel, dims })
    }

    /// The voxel holding model point `p` (clamped into the grid).
    pub fn voxel_of(&self, p: Vec3) -> [usize; 3] {
        let g = (p - self.origin) / self.voxel;
        [0, 1, 2].map(|a| (g[a].floor().max(0.0) as usize).min(self.dims[a] - 1))
    }

    /// The centre of voxel `v` in model units.
    pub fn centre(&self, v: [usize; 3]) -> Vec3 {
        self.origin + (Vec3::from_array(v.map(|c| c as f32)) + 0.5) * self.voxel
    }
}

/// Corners of the field's sampling grid along the grid's longest side (Zhang et al.: 20-30
/// cells on the shortest side suffice for a smooth field).
const FIELD_CELLS: usize = 32;

/// The field sampled over `domain`, in its voxel coordinates, with the gradient of the
/// depth through `depth` (the spec's constraints) when they rise above 0, aimed at the
/// nearest of its `axes` (the spec's depth axes) near them and past their ends
/// ([`aimed_at_axes`]).
pub fn frames_over(
    tets: &TetMesh,
    field: &FrameField,
    domain: &Domain,
    depth: &[(Vec3, f32)],
    axes: &[Vec<Vec3>],
) -> Result<FrameGrid> {
    let hi = domain.origin + Vec3::from_array(domain.dims.map(|d| d as f32)) * domain.voxel;
    let grid = FrameGrid::sample(tets, field, (domain.origin, hi), FIELD_CELLS);
    let grid = match depth.iter().any(|d| d.1 > 0.0) {
        true => {
            let rbf = crate::fill::field::Rbf::fit(depth)?;
            let cell = grid.step;
            let grid = grid.with_depth(|p| aimed_at_axes(axes, p, rbf.gradient(p), cell));
            match axes.is_empty() {
                true => grid,
                false => grid.with_x_along(|p| past_end(axes, p).map(|(_, out)| out)),
            }
        }
        false => grid,
    };
    Ok(grid.in_voxels(domain.origin, domain.voxel))
}

/// Field cells from a depth axis within which the depth's gradient is aimed at the axis
/// ([`aimed_at_axes`]), and beyond which the gradient is the RBF's alone.
const AIMED_CELLS: (f32, f32) = (1.0, 2.0);

/// The depth's gradient `g` at `p` aimed at the nearest of the depth `axes`: at the
/// nearest point of that axis within [`AIMED_CELLS`] (`cell` long each) of it, giving way
/// smoothly to `g` between the two; at the axis' end wherever `p` lies past that end
/// ([`past_end`]). Frames turning around an axis then turn around the axis the spec
/// declares, where the cut's figures leave them out: the RBF's own ridge wanders with
/// the surface's samples (half a voxel at `--res 256` on the drawn fruit), and frames
/// turning round it turned 31-34° per voxel just outside the two voxels left out. Within a
/// cell of the axis the aimed vector's length falls with the distance, so the grid's
/// trilinear blend of its corners stays aimed at the axis between them (the vectors to a
/// line or a point are linear in the position).
pub fn aimed_at_axes(axes: &[Vec<Vec3>], p: Vec3, g: Vec3, cell: f32) -> Vec3 {
    let Some((at, past)) = nearest_on_axes(axes, p) else { return g };
    let cells = p.distance(at) / cell.max(f32::MIN_POSITIVE);
    let aimed = (at - p).normalize_or(g.normalize_or_zero()) * g.length() * cells.min(1.0);
    let (inner, outer) = AIMED_CELLS;
    let t = ((cells - inner) / (outer - inner)).clamp(0.0, 1.0);
    match past {
        true => aimed,
        false => aimed.lerp(g, t * t * (3.0 - 2.0 * t)),
    }
}

/// The point of the depth axes (polylines) nearest to `p`, and whether `p` lies past an
/// end of that axis ([`past_end`]: the point is then the end).
fn nearest_on_axes(axes: &[Vec<Vec3>], p: Vec3) -> Option<(Vec3, bool)> {
    if let Some((end, _)) = past_end(axes, p) {
        return Some((end, true));
    }
    let segments = axes.iter().flat_map(|line| line.windows(2));
    let nearest =
        segments.map(|w| closest_on_segment(p, w[0], w[1])).min_by(|a, b| a.distance(p).total_cmp(&b.distance(p)));
    nearest.map(|at| (at, false))
}

/// The end of the depth axis (polyline) nearest to `p` and its outward direction, when `p`
/// lies past that end (beyond the plane through it across its last segment).
pub fn past_end(axes: &[Vec<Vec3>], p: Vec3) -> Option<(Vec3, Vec3)> {
    let mut nearest: (f32, Option<(Vec3, Vec3)>) = (f32::INFINITY, None);
    for line in axes.iter().filter(|l| l.len() >= 2) {
        let last = line.len() - 2;
        for (k, w) in line.windows(2).enumerate() {
            let d = w[1] - w[0];
            let t = (p - w[0]).dot(d) / d.length_squared().max(f32::MIN_POSITIVE);
            let distance = p.distance(w[0] + d * t.clamp(0.0, 1.0));
            if distance < nearest.0 {
                let end = match () {
                    _ if k == 0 && t < 0.0 => Some((w[0], -d)),
                    _ if k == last && t > 1.0 => Some((w[1], d)),
                    _ => None,
                };
                nearest = (distance, end);
            }
        }
    }
    nearest.1.filter(|(_, out)| *out != Vec3::ZERO)
}

/// The model's depth (the RBF through the spec's depth constraints, as the fill computes
/// it, clamped to 0..1) sampled over `domain`, in its voxel coordinates.
pub fn depth_over(constraints: &[(Vec3, f32)], domain: &Domain) -> Result<ScalarGrid> {
    if !constraints.iter().any(|c| c.1 > 0.0) {
        return Err(Error::invalid(
            "layered guided synthesis needs the spec's depth: a [depth] section with an axis or points inside",
        ));
    }
    let rbf = crate::fill::field::Rbf::fit(constraints)?;
    let hi = domain.origin + Vec3::from_array(domain.dims.map(|d| d as f32)) * domain.voxel;
    let grid = ScalarGrid::sample(|p| rbf.value(p).clamp(0.0, 1.0), (domain.origin, hi), FIELD_CELLS);
    Ok(grid.in_voxels(domain.origin, domain.voxel))
}

/// Fewest and most rows a layered exemplar is scaled to (see [`layer_rows`]).
pub const LAYER_ROWS: std::ops::RangeInclusive<usize> = 16..=512;

/// How many rows a layered exemplar should have at finest-level resolution `res`: as many
/// as the voxels the model's depth (`depth`, in voxels) takes to run from 0 to 1.
pub fn layer_rows(depth: &ScalarGrid, res: usize) -> Result<usize> {
    let span = depth.span().ok_or_else(|| Error::invalid("the spec's depth does not vary inside the model"))?;
    let rows = span.round() as usize;
    if rows < *LAYER_ROWS.start() {
        let wanted = (res as f32 * *LAYER_ROWS.start() as f32 / span).ceil();
        return Err(Error::invalid(format!(
            "the model's depth runs over only {span:.0} voxels at resolution {res}; layered synthesis needs at least \
             {} (one exemplar row per voxel): raise the resolution to {wanted:.0} or more",
            LAYER_ROWS.start()
        )));
    }
    Ok(rows.min(*LAYER_ROWS.end()))
}

/// A cut through the model synthesized on demand: its picture and the run (voxels,
/// corrections and the values it computed). `kept`: per level, values an earlier run kept
/// (a cache), read instead of computed where they reach.
pub fn cut(
    setup: &Setup,
    domain: &Domain,
    surface: &Mesh,
    view: &View,
    kept: &Kept,
    progress: &dyn Progress,
) -> Result<(Image2d, Synthesized)> {
    // the outline is the model's surface cut by the plane (as the lapped fill's), not the
    // tets' faces
    let inside = inside_surface(surface, view);
    let request = cut_request(domain, view, &inside);
    let out = synth::run(setup, &synth::plan(setup, &request, kept), kept, progress)?;
    let picture = match kept.get(out.finest).copied().flatten() {
        Some(earlier) => {
            let shown = Sparse::compute(&request, |v| match out.values.holds(v) {
                true => out.values.at(v.map(|c| c as i64)),
                false => {
                    let held = earlier.at(v.map(|c| c as i64));
                    setup.restored(out.finest, held.slot, held.shown)
                }
            });
            cut_image(setup, &shown, domain, view, &inside)?
        }
        None => cut_image(setup, &out.values, domain, view, &inside)?,
    };
    Ok((picture, out))
}

/// How much of part `k` a voxel shows (the weights of a voxel summing to 1).
pub type Weight<'a> = dyn Fn(usize, [usize; 3]) -> f32 + Sync + 'a;

/// A cut through a model textured by several parts blended per voxel: regions of depth
/// with their own exemplars, or one exemplar at several scales. `parts` holds one setup
/// per part (the same grid and field), each synthesized over the cut's voxels where its
/// `weight` is above 0, and the pixel blends them by weight. The picture is red, green,
/// blue (a grey exemplar's grey on all three) and alpha; also the voxels and corrections of
/// all the runs.
pub fn cut_blend(
    parts: &[Setup],
    weight: &Weight,
    domain: &Domain,
    surface: &Mesh,
    view: &View,
    progress: &dyn Progress,
) -> Result<(Image2d, [usize; 2])> {
    let inside = inside_surface(surface, view);
    let request = cut_request(domain, view, &inside);
    let (runs, counts) = part_runs(parts, weight, &request, progress)?;
    let mut data = Vec::with_capacity(view.width * view.height * 4);
    for (i, inside) in inside.iter().enumerate() {
        match inside {
            true => {
                let v = domain.voxel_of(view.point(i % view.width, i / view.width));
                data.extend(blended(parts, &runs, weight, v).into_iter().chain([1.0]));
            }
            false => data.extend([0.0; 4]),
        }
    }
    Ok((Image2d::from_data(view.width, view.height, RGBA.to_vec(), data)?, counts))
}

/// The whole solid of a model textured by blended parts ([`cut_blend`]): every voxel's
/// colour, then `alpha` (the model's coverage per voxel); also the runs' voxels and
/// corrections.
pub fn solid_blend(
    parts: &[Setup],
    weight: &Weight,
    alpha: &[f32],
    progress: &dyn Progress,
) -> Result<(Volume, [usize; 2])> {
    let dims = parts.first().map_or([0; 3], |p| p.dims);
    let (runs, counts) = part_runs(parts, weight, &Mask::full(dims), progress)?;
    let mut data = Vec::with_capacity(alpha.len() * 4);
    for (i, a) in alpha.iter().enumerate() {
        let v = [i % dims[0], (i / dims[0]) % dims[1], i / (dims[0] * dims[1])];
        data.extend(blended(parts, &runs, weight, v).into_iter().chain([*a]));
    }
    Ok((Volume::from_data(dims, RGBA.to_vec(), data)?, counts))
}

/// The model's input surface seen from `view`, textured by blended parts ([`cut_blend`]):
/// each part synthesized over only the voxels under visible points (and what their
/// neighbourhoods need). Also the runs' voxels and corrections.
pub fn view_blend(
    parts: &[Setup],
    weight: &Weight,
    domain: &Domain,
    surface: &Mesh,
    view: crate::fill::view::View,
    progress: &dyn Progress,
) -> Result<(crate::render::Rgb8, [usize; 2])> {
    let mut counts = [0, 0];
    let picture = crate::fill::view::mesh_picture(surface, view, |points| {
        let mut request = Mask::empty(domain.dims);
        for p in points {
            request.insert(domain.voxel_of(*p));
        }
        let (runs, made) = part_runs(parts, weight, &request, progress)?;
        counts = made;
        Ok(points.iter().map(|p| blended(parts, &runs, weight, domain.voxel_of(*p))).collect())
    })?;
    Ok((picture, counts))
}

/// The channels of a blended solid ([`solid_blend`]): colours and the model's coverage.
pub const RGBA: [Channel; 4] = [Channel::R, Channel::G, Channel::B, Channel::A];

/// Each part's synthesis over the voxels of `request` it weighs in, and the runs' voxels
/// and corrections summed.
fn part_runs(
    parts: &[Setup],
    weight: &Weight,
    request: &Mask,
    progress: &dyn Progress,
) -> Result<(Vec<Sparse<Voxel>>, [usize; 2])> {
    let mut runs = Vec::with_capacity(parts.len());
    let mut counts = [0, 0];
    for (k, setup) in parts.iter().enumerate() {
        let mut mine = Mask::empty(request.dims);
        for v in request.voxels().filter(|&v| weight(k, v) > 0.0) {
            mine.insert(v);
        }
        let out = synth::run(setup, &synth::plan(setup, &mine, &[]), &[], progress)?;
        counts = [counts[0] + out.voxels, counts[1] + out.corrections];
        runs.push(out.values);
    }
    Ok((runs, counts))
}

/// The value of a grid in voxel coordinates (the model's depth, the texture's scale) at
/// voxel `v`.
pub fn grid_at(grid: &ScalarGrid, v: [usize; 3]) -> f32 {
    grid.at(Vec3::from_array(v.map(|c| c as f32)))
}

/// The parts' colours at voxel `v` blended by their weights.
fn blended(parts: &[Setup], runs: &[Sparse<Voxel>], weight: &Weight, v: [usize; 3]) -> [f32; 3] {
    let mut rgb = [0.0; 3];
    for (k, (setup, run)) in parts.iter().zip(runs).enumerate() {
        let w = weight(k, v);
        if w > 0.0 {
            let colour = &run.at(v.map(|c| c as i64)).colour;
            let grey = setup.exemplars.channels() < 3;
            for (c, out) in rgb.iter_mut().enumerate() {
                *out += w * colour[if grey { 0 } else { c }];
            }
        }
    }
    rgb
}

/// Steps of the texture's scale a scale field is synthesized at: half an octave apart, so
/// a voxel between two shows a blend of the two nearest.
pub const SCALE_STEPS_PER_OCTAVE: f32 = 2.0;

/// Most scale steps one synthesis takes (four octaves).
pub const MOST_SCALE_STEPS: usize = 9;

/// The texture's scale over `domain` as log2 of an exemplar pixel's size in voxels, for an
/// exemplar `side` pixels wide: the spec's `scales` (point, the exemplar's side in model
/// units) interpolated on the tets as the fill's field interpolates them, through their
/// logarithms (halfway between two scales lies their geometric mean).
pub fn scale_over(tets: &TetMesh, scales: &[(Vec3, f32)], side: usize, domain: &Domain) -> Result<ScalarGrid> {
    let points: Vec<(Vec3, [f32; 1])> =
        scales.iter().map(|(p, s)| (*p, [(s / (side as f32 * domain.voxel)).log2()])).collect();
    let values: Vec<f32> =
        crate::fill::field::smooth_at_vertices(tets, &points)?.into_iter().map(|v| v as f32).collect();
    let hi = domain.origin + Vec3::from_array(domain.dims.map(|d| d as f32)) * domain.voxel;
    let grid = ScalarGrid::from_tets(tets, &values, (domain.origin, hi), FIELD_CELLS);
    Ok(grid.in_voxels(domain.origin, domain.voxel))
}

/// The steps a scale grid ([`scale_over`]) spans, as log2 of the pixel size: half an
/// octave apart, from the smallest to the largest scale of its corners. An error beyond
/// [`MOST_SCALE_STEPS`].
pub fn scale_steps(scale: &ScalarGrid) -> Result<Vec<f32>> {
    let (lo, hi) = scale.values.iter().fold((f32::INFINITY, f32::NEG_INFINITY), |(a, b), &v| (a.min(v), b.max(v)));
    let (first, last) = ((lo * SCALE_STEPS_PER_OCTAVE).round() as i64, (hi * SCALE_STEPS_PER_OCTAVE).round() as i64);
    let count = (last - first + 1).max(1) as usize;
    if !(lo.is_finite() && hi.is_finite()) || count > MOST_SCALE_STEPS {
        return Err(Error::invalid(format!(
            "the scale_at points ask for exemplar pixels from {:.3} to {:.3} voxels wide, more than {} octaves apart; \
             bring the scales closer together",
            lo.exp2(),
            hi.exp2(),
            (MOST_SCALE_STEPS - 1) as f32 / SCALE_STEPS_PER_OCTAVE
        )));
    }
    Ok((first..=last).map(|j| j as f32 / SCALE_STEPS_PER_OCTAVE).collect())
}

/// The masks of the levels below the finest that make corrections
/// ([`synth::Options::coarse_levels`]) holding every voxel a cut of the model inside
/// `surface` can need, coarsest first (none when there is one level): the finest of them
/// over its voxels whose centre lies inside, grown by the reach of the passes above it and
/// by one voxel for cells the surface enters short of their centre. Outside the model
/// (the grid's margin, a log's corners) nothing is computed.
pub fn interior_plan(setup: &Setup, domain: &Domain, surface: &Mesh) -> Vec<Vec<Mask>> {
    let Some(top) = setup.options.coarse_levels().checked_sub(1) else { return Vec::new() };
    let dims = setup.level_dims()[top];
    let side = domain.voxel * (1usize << (setup.options.levels - 1 - top)) as f32;
    let local =
        surface.transformed(Affine3A::from_scale(Vec3::splat(1.0 / side)) * Affine3A::from_translation(-domain.origin));
    let slices = Slices::new(&local, dims);
    let mut inside = Mask::empty(dims);
    for k in 0..dims[2] {
        for (i, _) in slices.inside(k).iter().enumerate().filter(|(_, b)| **b) {
            inside.insert([i % dims[0], i / dims[0], k]);
        }
    }
    let above = top + 1;
    let reach = setup.options.passes_at(above) as f32 * setup.options.footprint_at(above);
    synth::plan_from(setup, top, &inside.grown(1 + (reach / 2.0).ceil() as usize), &[])
}

/// The levels of `plan` ([`interior_plan`]) computed, coarsest first, as a cache keeps
/// them: kept, a cut computes only the levels above them.
pub fn coarse_levels(setup: &Setup, plan: &[Vec<Mask>], progress: &dyn Progress) -> Result<Vec<Sparse<Held>>> {
    if plan.is_empty() {
        return Ok(Vec::new());
    }
    let out = synth::run(setup, plan, &[], progress)?;
    Ok(out.levels().map(|l| l.map(Held::from)).collect())
}

/// About how many bytes synthesizing needs (before it starts): every level and version's
/// mask holds a brick table (4 bytes per 8³ voxels), and for the whole solid a flag per
/// voxel and two versions of every voxel. A cut's own voxels are not counted: they are a
/// slab, a small share of the grid.
pub fn memory_needed(setup: &Setup, whole: bool) -> u128 {
    let per_voxel = std::mem::size_of::<Voxel>() as u128;
    setup
        .level_dims()
        .iter()
        .enumerate()
        .map(|(level, d)| {
            let voxels = d.iter().map(|&n| n as u128).product::<u128>();
            let per_mask = voxels / 128 + if whole { voxels / 8 } else { 0 };
            let masks = per_mask * (setup.options.passes_at(level) as u128 + 1);
            masks + if whole { 2 * voxels * per_voxel } else { 0 }
        })
        .sum()
}

/// Refuse a synthesis that would need more than `budget` bytes, naming `--res`.
pub fn check_memory(setup: &Setup, whole: bool, res: usize, budget: u64) -> Result<()> {
    let needed = memory_needed(setup, whole);
    if needed > budget as u128 {
        let what = if whole { "the whole solid" } else { "a cut" };
        return Err(Error::invalid(format!(
            "--res {res}: synthesizing {what} needs about {} MB, more than the budget of {} MB; lower --res{} or \
             raise the budget with SOLIDTEX_MAX_BYTES",
            needed >> 20,
            budget >> 20,
            if whole { ", cut with --cut," } else { "" }
        )));
    }
    Ok(())
}

/// The voxels a cut shows: the one under each pixel inside the model (`inside`, per pixel).
pub fn cut_request(domain: &Domain, view: &View, inside: &[bool]) -> Mask {
    let mut mask = Mask::empty(domain.dims);
    for (i, _) in inside.iter().enumerate().filter(|(_, b)| **b) {
        mask.insert(domain.voxel_of(view.point(i % view.width, i / view.width)));
    }
    mask
}

/// The cut's picture: each pixel inside the model takes the colour of the voxel under it
/// (the exemplar's channels, then alpha 1); outside, transparent.
pub fn cut_image(
    setup: &Setup,
    values: &Sparse<Voxel>,
    domain: &Domain,
    view: &View,
    inside: &[bool],
) -> Result<Image2d> {
    let channels = setup.exemplars.channels();
    let mut data = Vec::with_capacity(view.width * view.height * (channels + 1));
    for (i, inside) in inside.iter().enumerate() {
        if *inside {
            let v = domain.voxel_of(view.point(i % view.width, i / view.width));
            data.extend_from_slice(&values.at(v.map(|c| c as i64)).colour[..channels]);
            data.push(1.0);
        } else {
            data.extend(std::iter::repeat_n(0.0, channels + 1));
        }
    }
    Image2d::from_data(view.width, view.height, with_alpha(setup), data)
}

/// A cut's picture as `solidtex cut` shows a lapped fill's: each pixel inside the model
/// (alpha, the last channel, above 0) in its colour (R, G, B, or the first channel as
/// grey), every other pixel the cut's background.
pub fn cut_picture(picture: &Image2d) -> Rgb8 {
    let map = ColourMap::for_channels(picture.channels());
    let alpha = picture.channel_count() - 1;
    let mut out = Rgb8::new(picture.width(), picture.height(), BACKGROUND);
    for y in 0..picture.height() {
        for x in 0..picture.width() {
            let p = picture.pixel(x, y);
            if p[alpha] > 0.0 {
                out.put(x, y, map.colour(p));
            }
        }
    }
    out
}

/// The whole solid as a bake writes it: every channel 0 in voxels the model does not
/// cover (alpha, the last channel, 0), as a lapped fill's bake leaves them, and its place
/// in model space (`domain`'s voxel (0, 0, 0) centre and side).
pub fn baked(mut volume: Volume, domain: &Domain) -> Volume {
    let n = volume.channel_count();
    for voxel in volume.data_mut().chunks_exact_mut(n).filter(|v| v[n - 1] == 0.0) {
        voxel.fill(0.0);
    }
    let origin = domain.centre([0, 0, 0]).to_array();
    volume.with_model_grid(Some(ModelGrid { origin, voxel: domain.voxel }))
}

/// The whole solid: every voxel's colour, then `alpha` (the model's coverage per voxel).
pub fn solid_volume(setup: &Setup, out: &Synthesized, alpha: &[f32]) -> Result<Volume> {
    let dims = setup.dims;
    let channels = setup.exemplars.channels();
    let mut data = Vec::with_capacity(alpha.len() * (channels + 1));
    for (i, a) in alpha.iter().enumerate() {
        let v = [i % dims[0], (i / dims[0]) % dims[1], i / (dims[0] * dims[1])];
        data.extend(out.colour(setup, v));
        data.push(*a);
    }
    Volume::from_data(dims, with_alpha(setup), data)
}

/// The sharpness yardstick ([`crate::sharpness`]) of a cut's largest centred square of
/// opaque pixels against the exemplar's shown channels (a feature mask or depth left out):
/// meaningful when a pixel spans about one voxel.
pub fn cut_sharpness(picture: &Image2d, exemplar: &Image2d) -> Result<crate::sharpness::AxisSharpness> {
    let (square, exemplar, shown) = shown_square(picture, exemplar)?;
    crate::sharpness::compare(&[square], &exemplar, &shown)
}

/// [`cut_sharpness`] and the line-structure yardstick ([`crate::lines`]) of the same
/// square against the same channels, the square found once.
pub fn cut_figures(
    picture: &Image2d,
    exemplar: &Image2d,
) -> Result<(crate::sharpness::AxisSharpness, crate::lines::Lines)> {
    let (square, exemplar, shown) = shown_square(picture, exemplar)?;
    let square = [square];
    Ok((crate::sharpness::compare(&square, &exemplar, &shown)?, crate::lines::compare(&square, &exemplar, &shown)?))
}

/// A cut's largest centred square of opaque pixels, the exemplar's shown channels, and
/// which of the square's channels hold them.
fn shown_square(picture: &Image2d, exemplar: &Image2d) -> Result<(Image2d, Image2d, Vec<usize>)> {
    let shown: Vec<usize> =
        (0..exemplar.channel_count()).filter(|&c| !synth::matched_only(&exemplar.channels()[c])).collect();
    let mut colours = Vec::with_capacity(exemplar.width() * exemplar.height() * shown.len());
    for y in 0..exemplar.height() {
        for x in 0..exemplar.width() {
            colours.extend(shown.iter().map(|&c| exemplar.pixel(x, y)[c]));
        }
    }
    let names = shown.iter().map(|&c| exemplar.channels()[c].clone()).collect();
    let exemplar = Image2d::from_data(exemplar.width(), exemplar.height(), names, colours)?;
    Ok((inside_square(picture)?, exemplar, shown))
}

/// The largest centred square of opaque pixels (alpha: the last channel), without alpha.
fn inside_square(picture: &Image2d) -> Result<Image2d> {
    let (w, h, c) = (picture.width(), picture.height(), picture.channel_count());
    let (cx, cy) = (w / 2, h / 2);
    let opaque = |r: usize| (cx - r..cx + r).all(|x| (cy - r..cy + r).all(|y| picture.pixel(x, y)[c - 1] > 0.5));
    let r = (1..cx.min(cy)).take_while(|r| opaque(*r)).last().unwrap_or(1);
    let mut data = Vec::with_capacity(4 * r * r * (c - 1));
    for y in cy - r..cy + r {
        for x in cx - r..cx + r {
            data.extend_from_slice(&picture.pixel(x, y)[..c - 1]);
        }
    }
    Image2d::from_data(2 * r, 2 * r, picture.channels()[..c - 1].to_vec(), data)
}

/// The exemplars' channels (alpha-free: [`crate::synth::coords::Exemplars::prepare`]) and alpha.
fn with_alpha(setup: &Setup) -> Vec<Channel> {
    setup.exemplars.names.iter().cloned().chain([Channel::A]).collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Past either end of a depth axis (beyond the plane across its end segment) the
    /// gradient is aimed at that end, within a cell of the axis at its nearest point (its
    /// length falling with the distance there), and from two cells out it is left as it is.
    #[test]
    fn the_gradient_is_aimed_at_the_axis_and_past_an_axis_end_at_the_end() {
        let axes = vec![vec![Vec3::new(-1.0, 0.0, 0.0), Vec3::ZERO, Vec3::new(1.0, 0.0, 0.0)]];
        let g = Vec3::new(-2.0, 0.3, 0.0);
        assert_eq!(past_end(&axes, Vec3::new(2.0, 0.1, 0.0)), Some((Vec3::X, Vec3::X)));
        assert_eq!(past_end(&axes, Vec3::new(-1.5, 0.0, 0.2)), Some((-Vec3::X, -Vec3::X)));
        assert_eq!(past_end(&axes, Vec3::new(0.9, 1.0, 0.0)), None);
        let aimed = aimed_at_axes(&axes, Vec3::new(2.0, 1.0, 0.0), g, 0.5);
        assert!((aimed.length() - g.length()).abs() < 1e-5);
        assert!(aimed.normalize().dot(Vec3::new(-1.0, -1.0, 0.0).normalize()) > 0.9999, "{aimed}");
        assert_eq!(aimed_at_axes(&axes, Vec3::new(0.5, 1.0, 0.0), g, 0.5), g, "two cells out");
        let near = aimed_at_axes(&axes, Vec3::new(0.5, 0.25, 0.0), g, 0.5);
        assert!(near.normalize().dot(-Vec3::Y) > 0.9999, "{near}");
        assert!((near.length() - g.length() / 2.0).abs() < 1e-5, "half a cell from the axis: half the length");
        let between = aimed_at_axes(&axes, Vec3::new(0.5, 0.75, 0.0), g, 0.5);
        let (to_axis, own) = (between.normalize().dot(-Vec3::Y), between.normalize().dot(g.normalize()));
        assert!(to_axis < 0.9999 && own < 0.9999 && to_axis > 0.0, "a cell and a half out: between the two, {between}");
        // the blend of the grid's corners stays aimed at the axis within a cell of it
        let corner = |x: f32, y: f32| aimed_at_axes(&axes, Vec3::new(0.3, x, y), g, 0.5);
        let (a, b, c, d) = (corner(0.1, 0.1), corner(0.3, 0.1), corner(0.1, 0.3), corner(0.3, 0.3));
        let blend = (a + b + c + d) / 4.0;
        assert!(blend.normalize().dot(Vec3::new(0.0, -1.0, -1.0).normalize()) > 0.9999, "{blend}");
        let two = vec![axes[0].clone(), vec![Vec3::new(1.5, -1.0, 0.0), Vec3::new(1.5, 1.0, 0.0)]];
        assert_eq!(past_end(&two, Vec3::new(1.6, 0.0, 0.0)), None, "nearer the second axis' middle");
    }
}
