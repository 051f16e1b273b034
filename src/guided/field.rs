//! The frame field of sketch-guided solid texturing (Zhang et al. 2011, §4): the designer's
//! strokes and depth give local frames; a smooth frame at every point of the model comes
//! from **harmonic interpolation of quaternions** — the four components solved as four
//! Laplace problems on the tet mesh with the sketched frames as (soft) constraints, then
//! renormalized where they are read.
//!
//! ```text
//!  frame convention (exemplar axis -> model direction):
//!    z  the depth gradient (0 outside, 1 inside: the exemplar's rows from the outside in)
//!    x  the stroke's direction, made orthogonal to z
//!    y  z x x
//!  without depth constraints, or where the gradient runs along the stroke (on a depth
//!  axis), z is the world axis least along the stroke, made orthogonal
//! ```
//!
//! q and -q are the same rotation: each constraint's quaternion is flipped into the
//! hemisphere of the one before it (samples along a stroke, strokes in the spec's order),
//! and the four corners of a tet are flipped towards the first before blending.

use crate::error::{Error, Result};
use crate::fill::field::{Rbf, locate_each, smooth_at_vertices};
use crate::fill::render::{View, field_cut};
use crate::fill::tets::TetMesh;
use crate::noise::mix64;
use crate::render::{Rgb8, to_u8};
use glam::{Mat3, Quat, Vec2, Vec3, Vec4};
use rayon::prelude::*;

/// A frame constraint: at `point`, the rotation taking the exemplar's axes to the model's.
pub type FrameAt = (Vec3, Quat);

/// The frames the strokes give: one per stroke sample `(point, tangent)`, with z along the
/// gradient of the depth through `depth` (when there are depth constraints and the
/// gradient there is clear: not on a depth axis, where it vanishes, nor along the stroke).
/// Each is flipped into the hemisphere of the one before it. Then frames where the depth
/// is 0 (up to [`DEPTH_FRAMES`] of those points): z along the gradient, x along the nearest
/// stroke sample's tangent, in that sample's hemisphere; with them the field turns around
/// a depth axis (a log's rings), which frames on the axis alone cannot say.
pub fn sketched_frames(directions: &[(Vec3, Vec3)], depth: &[(Vec3, f32)]) -> Result<Vec<FrameAt>> {
    if directions.is_empty() {
        return Err(Error::invalid("the frame field needs at least one direction stroke ([[direction]])"));
    }
    let rbf = if depth.iter().any(|d| d.1 > 0.0) { Some(Rbf::fit(depth)?) } else { None };
    let (lo, hi) = depth.iter().fold((Vec3::INFINITY, Vec3::NEG_INFINITY), |(a, b), (p, _)| (a.min(*p), b.max(*p)));
    // the depth rises from 0 to 1 over about half the model: a gradient far below that is
    // a maximum's (an axis), whose direction means nothing
    let clear = 0.5 / lo.distance(hi).max(1e-6);
    let mut frames: Vec<FrameAt> = Vec::with_capacity(directions.len());
    for &(p, t) in directions {
        let gradient = rbf.as_ref().map(|f| f.gradient(p)).filter(|g| g.length() > clear);
        let z = gradient
            .and_then(Vec3::try_normalize)
            .filter(|g| g.dot(t.normalize_or_zero()).abs() < 0.9)
            .unwrap_or_else(|| least_along(t));
        let mut q = frame(t, z);
        if let Some(&(_, before)) = frames.last()
            && q.dot(before) < 0.0
        {
            q = -q;
        }
        frames.push((p, q));
    }
    if let Some(rbf) = rbf {
        let strokes = frames.len();
        let outside: Vec<Vec3> = depth.iter().filter(|d| d.1 == 0.0).map(|d| d.0).collect();
        for &p in outside.iter().step_by(outside.len().div_ceil(DEPTH_FRAMES).max(1)) {
            let Some(z) = Some(rbf.gradient(p)).filter(|g| g.length() > clear).and_then(Vec3::try_normalize) else {
                continue;
            };
            let nearest = (0..strokes)
                .min_by(|&a, &b| directions[a].0.distance_squared(p).total_cmp(&directions[b].0.distance_squared(p)));
            let Some(i) = nearest else { continue };
            let t = directions[i].1.normalize_or_zero();
            if z.dot(t).abs() >= 0.9 {
                continue;
            }
            let q = frame(t, z);
            frames.push((p, if q.dot(frames[i].1) < 0.0 { -q } else { q }));
        }
    }
    Ok(frames)
}

/// Most frames taken from points of depth 0.
pub const DEPTH_FRAMES: usize = 200;

/// The world axis least along `t`; near ties (within 0.1) go to z, then y, so a stroke
/// lying in a world plane keeps one axis along its whole length.
fn least_along(t: Vec3) -> Vec3 {
    let a = t.normalize_or_zero().abs();
    let least = a.min_element();
    [(a.z, Vec3::Z), (a.y, Vec3::Y), (a.x, Vec3::X)]
        .into_iter()
        .find(|(c, _)| *c <= least + 0.1)
        .map_or(Vec3::Z, |(_, axis)| axis)
}

/// The rotation whose x axis is `x` made orthogonal to `z`, and whose z axis is `z`.
pub fn frame(x: Vec3, z: Vec3) -> Quat {
    let z = z.try_normalize().unwrap_or(Vec3::Z);
    let x = (x - z * z.dot(x)).try_normalize().unwrap_or_else(|| z.any_orthonormal_vector());
    Quat::from_mat3(&Mat3::from_cols(x, z.cross(x), z)).normalize()
}

/// The harmonic quaternion field: four components per vertex (not normalized; read them
/// with [`FrameField::at`]).
#[derive(Debug, Clone, PartialEq)]
pub struct FrameField {
    /// Per vertex, the solved (x, y, z, w).
    pub components: Vec<[f32; 4]>,
}

/// Solves the four Laplace problems on `mesh` with `frames` as constraints. As in Zhang et
/// al., a frame whose sign disagrees with the field the others make (a later stroke
/// flipped against an earlier one) is flipped to agree with it, and the field solved again.
pub fn solve(mesh: &TetMesh, frames: &[FrameAt]) -> Result<FrameField> {
    if frames.is_empty() {
        return Err(Error::invalid("the frame field needs at least one sketched frame"));
    }
    let first = harmonic(mesh, frames)?;
    let places: Vec<Vec3> = frames.iter().map(|(p, _)| *p).collect();
    let signed: Vec<FrameAt> = frames
        .iter()
        .zip(locate_each(mesh, &places))
        .map(|(&(p, q), (t, b))| {
            let here = first.blend(mesh.tets[t], b);
            (p, if Vec4::from(q).dot(here) < 0.0 { -q } else { q })
        })
        .collect();
    if signed == frames {
        return Ok(first);
    }
    harmonic(mesh, &signed)
}

fn harmonic(mesh: &TetMesh, frames: &[FrameAt]) -> Result<FrameField> {
    let points: Vec<(Vec3, [f32; 4])> = frames.iter().map(|(p, q)| (*p, q.to_array())).collect();
    let solved = smooth_at_vertices(mesh, &points)?;
    let components = solved.chunks_exact(4).map(|c| [c[0] as f32, c[1] as f32, c[2] as f32, c[3] as f32]).collect();
    Ok(FrameField { components })
}

impl FrameField {
    /// The rotation at barycentric point `b` of `tet`: its corners' quaternions flipped
    /// towards the first, blended, normalized.
    pub fn at(&self, tet: [u32; 4], b: [f32; 4]) -> Quat {
        self.blend(tet, b).try_normalize().map_or(Quat::IDENTITY, Quat::from_vec4)
    }

    /// The corners' four-vectors flipped towards the first and blended (not normalized).
    fn blend(&self, tet: [u32; 4], b: [f32; 4]) -> Vec4 {
        let first = Vec4::from_array(self.components[tet[0] as usize]);
        let mut sum = Vec4::ZERO;
        for (v, w) in tet.iter().zip(b) {
            let q = Vec4::from_array(self.components[*v as usize]);
            sum += if q.dot(first) < 0.0 { -q } else { q } * w;
        }
        sum
    }
}

/// The field sampled at the corners of a regular grid over a box, read per voxel by
/// trilinear interpolation of the corners' quaternions (flipped towards the first) and
/// normalization, as Zhang et al. read theirs. Corners outside the mesh take the mean of
/// their sampled neighbours, layer by layer outwards.
#[derive(Debug, Clone, PartialEq)]
pub struct FrameGrid {
    /// The first corner.
    pub lo: Vec3,
    /// Corner spacing.
    pub step: f32,
    /// Corners per axis.
    pub dims: [usize; 3],
    /// Per corner, a unit quaternion as (x, y, z, w), x fastest.
    pub corners: Vec<Vec4>,
    /// Per corner, the gradient of the model's depth, when it has one: frames are then
    /// read from it and the corners' x axes (see [`FrameGrid::at`]).
    pub gradients: Option<Vec<Vec3>>,
    /// Whether a frame read from the gradient gives way to the blended quaternions as the
    /// gradient comes within [`ALONG`] of x (true unless [`FrameGrid::with_x_along`] set the
    /// corners' x along the depth axes).
    pub give_way: bool,
}

impl FrameGrid {
    /// Sample `field` over the box `(lo, hi)` with `cells` cells along its longest side.
    pub fn sample(mesh: &TetMesh, field: &FrameField, (lo, hi): (Vec3, Vec3), cells: usize) -> FrameGrid {
        let step = (hi - lo).max_element().max(1e-6) / cells.max(1) as f32;
        let dims = ((hi - lo) / step).ceil().to_array().map(|d| d as usize + 2);
        let mut corners: Vec<Option<Vec4>> = vec![None; dims.iter().product()];
        corners_in_tets(mesh, (lo, step, dims), |i, t, w| {
            corners[i].get_or_insert_with(|| Vec4::from(field.at(mesh.tets[t], w)));
        });
        fill_outwards(&mut corners, dims);
        let corners = corners.into_iter().map(|c| c.unwrap_or(Vec4::W)).collect();
        FrameGrid { lo, step, dims, corners, gradients: None, give_way: true }
    }

    /// The grid with the depth's gradient (`gradient`, in model units) at its corners.
    pub fn with_depth(self, gradient: impl Fn(Vec3) -> Vec3 + Sync) -> FrameGrid {
        let gradients = (0..self.corners.len()).into_par_iter().map(|i| gradient(self.corner(i))).collect();
        FrameGrid { gradients: Some(gradients), ..self }
    }

    /// The grid with each corner's frame turned (by the shortest arc) so that its x axis
    /// runs along `along(corner)` where that gives a direction (either way along it,
    /// whichever is nearer), and frames that no longer give way near x: where the
    /// gradient past a depth axis' ends aims at the end and x runs along the axis, the two
    /// meet only on the line the axis carries on along, where frames must turn.
    pub fn with_x_along(self, along: impl Fn(Vec3) -> Option<Vec3> + Sync) -> FrameGrid {
        let corners = (0..self.corners.len())
            .into_par_iter()
            .map(|i| {
                let q = Quat::from_vec4(self.corners[i]);
                let Some(d) = along(self.corner(i)).and_then(Vec3::try_normalize) else { return self.corners[i] };
                let x = q * Vec3::X;
                let target = if x.dot(d) < 0.0 { -d } else { d };
                Vec4::from(Quat::from_rotation_arc(x, target) * q)
            })
            .collect();
        FrameGrid { corners, give_way: false, ..self }
    }

    /// Where corner `i` lies.
    fn corner(&self, i: usize) -> Vec3 {
        let [nx, ny, _] = self.dims;
        self.lo + Vec3::new((i % nx) as f32, ((i / nx) % ny) as f32, (i / (nx * ny)) as f32) * self.step
    }

    /// The same grid in the coordinates of a voxel grid whose voxel (0, 0, 0) spans
    /// `origin` to `origin + voxel` (voxel v's centre at v).
    pub fn in_voxels(&self, origin: Vec3, voxel: f32) -> FrameGrid {
        FrameGrid { lo: (self.lo - origin) / voxel - 0.5, step: self.step / voxel, ..self.clone() }
    }

    /// The frame at `p` (clamped into the box): its axes as the columns of a rotation.
    /// With the depth's gradient, z is the corners' gradients blended and x their frames'
    /// x axes blended, both as plain vectors: neither has a sign to flip, so frames turning
    /// around a depth axis turn only on its ridge, where the gradients meet head on
    /// (quaternions half a turn apart blend to nothing across a whole cell). As the
    /// gradient comes within [`ALONG`] of x (past the end of a depth given by points, not
    /// axes: see [`FrameGrid::give_way`]), that frame gives way smoothly to the quaternions
    /// blended; without a gradient, they alone are read.
    pub fn at(&self, p: Vec3) -> Mat3 {
        let corners = trilinear(self.lo, self.step, self.dims, p);
        match self.gradients.as_ref().and_then(|g| self.along_depth(&corners, g)) {
            Some((along, 0.0)) => Mat3::from_quat(along),
            Some((along, weight)) => Mat3::from_quat(along.slerp(self.blended(&corners), weight)),
            None => Mat3::from_quat(self.blended(&corners)),
        }
    }

    /// The corners' quaternions flipped towards the first, blended and normalized.
    fn blended(&self, corners: &[(usize, f32); 8]) -> Quat {
        let mut sum = Vec4::ZERO;
        let mut first = None;
        for &(at, w) in corners {
            let q = self.corners[at];
            let first = *first.get_or_insert(q);
            sum += if q.dot(first) < 0.0 { -q } else { q } * w;
        }
        sum.try_normalize().map_or(Quat::IDENTITY, Quat::from_vec4)
    }

    /// The frame of the blended gradient (z) and x axes, and how much the quaternion blend
    /// should take over (0 while the two are more than [`ALONG`]'s wider bound apart, 1
    /// within its narrower); none without a gradient or x.
    fn along_depth(&self, corners: &[(usize, f32); 8], gradients: &[Vec3]) -> Option<(Quat, f32)> {
        let (mut z, mut x) = (Vec3::ZERO, Vec3::ZERO);
        for &(at, w) in corners {
            z += gradients[at] * w;
            x += Quat::from_vec4(self.corners[at]) * Vec3::X * w;
        }
        let (z, x) = (z.try_normalize()?, x.try_normalize()?);
        if !self.give_way {
            return Some((frame(x, z), 0.0));
        }
        let t = ((z.dot(x).abs() - ALONG.0) / (ALONG.1 - ALONG.0)).clamp(0.0, 1.0);
        Some((frame(x, z), t * t * (3.0 - 2.0 * t)))
    }
}

/// The cosines between the depth's gradient and the frame's x over which a frame built
/// from the gradient gives way to the blended quaternions (about 46° to 11°; chosen on
/// the kiwi and log specs, docs/guided.md).
pub const ALONG: (f32, f32) = (0.7, 0.98);

/// How sharply a frame grid turns across a cut: each point's frame (`points`, row by row,
/// `width` per row, in the grid's coordinates; `None` outside the model) against its right
/// and lower neighbours'.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Turns {
    /// The largest angle between neighbouring frames, in degrees.
    pub largest: f32,
    /// Neighbour pairs turning by more than the limit asked.
    pub over: usize,
    /// Neighbour pairs compared.
    pub pairs: usize,
}

/// The turns of `grid`'s frames between 4-neighbouring `points` (see [`Turns`]), leaving out
/// pairs where `exempt` holds for either point (near a declared singular axis).
pub fn turns(
    grid: &FrameGrid,
    points: &[Option<Vec3>],
    width: usize,
    limit: f32,
    exempt: impl Fn(Vec3) -> bool + Sync,
) -> Turns {
    let frames: Vec<Option<Quat>> =
        points.par_iter().map(|p| p.filter(|p| !exempt(*p)).map(|p| Quat::from_mat3(&grid.at(p)))).collect();
    let angle = |a: Quat, b: Quat| 2.0 * a.dot(b).abs().min(1.0).acos().to_degrees();
    let mut out = Turns { largest: 0.0, over: 0, pairs: 0 };
    for (i, a) in frames.iter().enumerate() {
        let Some(a) = a else { continue };
        let right = (i % width + 1 < width).then(|| frames[i + 1]).flatten();
        let below = frames.get(i + width).copied().flatten();
        for b in [right, below].into_iter().flatten() {
            let turn = angle(*a, b);
            out.largest = out.largest.max(turn);
            out.pairs += 1;
            out.over += usize::from(turn > limit);
        }
    }
    out
}

/// A scalar field (the model's depth) sampled at the corners of a regular grid, read by
/// trilinear interpolation.
#[derive(Debug, Clone, PartialEq)]
pub struct ScalarGrid {
    /// The first corner.
    pub lo: Vec3,
    /// Corner spacing.
    pub step: f32,
    /// Corners per axis.
    pub dims: [usize; 3],
    /// Per corner, x fastest.
    pub values: Vec<f32>,
}

impl ScalarGrid {
    /// Sample `f` over the box `(lo, hi)` with `cells` cells along its longest side.
    pub fn sample(f: impl Fn(Vec3) -> f32 + Sync, (lo, hi): (Vec3, Vec3), cells: usize) -> ScalarGrid {
        let step = (hi - lo).max_element().max(1e-6) / cells.max(1) as f32;
        let dims = ((hi - lo) / step).ceil().to_array().map(|d| d as usize + 2);
        let values = (0..dims.iter().product::<usize>())
            .into_par_iter()
            .map(|i| {
                let c = [i % dims[0], (i / dims[0]) % dims[1], i / (dims[0] * dims[1])];
                f(lo + Vec3::new(c[0] as f32, c[1] as f32, c[2] as f32) * step)
            })
            .collect();
        ScalarGrid { lo, step, dims, values }
    }

    /// Per-vertex `values` of a tet mesh read at the corners of a grid over the box
    /// `(lo, hi)` with `cells` cells along its longest side: inside a tet by its
    /// barycentric blend, outside every tet the mean of the nearest filled corners.
    pub fn from_tets(mesh: &TetMesh, values: &[f32], (lo, hi): (Vec3, Vec3), cells: usize) -> ScalarGrid {
        let step = (hi - lo).max_element().max(1e-6) / cells.max(1) as f32;
        let dims = ((hi - lo) / step).ceil().to_array().map(|d| d as usize + 2);
        let mut corners: Vec<Option<f32>> = vec![None; dims.iter().product()];
        corners_in_tets(mesh, (lo, step, dims), |i, t, w| {
            let tet = mesh.tets[t];
            corners[i].get_or_insert_with(|| (0..4).map(|k| w[k] * values[tet[k] as usize]).sum());
        });
        let stride = [1, dims[0], dims[0] * dims[1]];
        while corners.iter().any(Option::is_none) && corners.iter().any(Option::is_some) {
            let next: Vec<Option<f32>> = (0..corners.len())
                .map(|i| {
                    let v = [i % dims[0], (i / dims[0]) % dims[1], i / (dims[0] * dims[1])];
                    let near = (0..3).flat_map(|a| {
                        let below = (v[a] > 0).then(|| corners[i - stride[a]]).flatten();
                        let above = (v[a] + 1 < dims[a]).then(|| corners[i + stride[a]]).flatten();
                        [below, above]
                    });
                    let (sum, count) = near.flatten().fold((0.0, 0), |(s, n), x| (s + x, n + 1));
                    corners[i].or((count > 0).then(|| sum / count as f32))
                })
                .collect();
            corners = next;
        }
        ScalarGrid { lo, step, dims, values: corners.into_iter().map(|c| c.unwrap_or(0.0)).collect() }
    }

    /// The same grid in the coordinates of a voxel grid (see [`FrameGrid::in_voxels`]).
    pub fn in_voxels(&self, origin: Vec3, voxel: f32) -> ScalarGrid {
        ScalarGrid { lo: (self.lo - origin) / voxel - 0.5, step: self.step / voxel, ..self.clone() }
    }

    /// The value at `p` (clamped into the box).
    pub fn at(&self, p: Vec3) -> f32 {
        trilinear(self.lo, self.step, self.dims, p).iter().map(|&(at, w)| self.values[at] * w).sum()
    }

    /// How far (in this grid's units) the value takes to rise by 1 where it lies strictly
    /// between `0.05` and `0.95`: the median of 1 / gradient length over those corners
    /// (central differences); `None` when no corner has a gradient there.
    pub fn span(&self) -> Option<f32> {
        let d = self.dims;
        let stride = [1, d[0], d[0] * d[1]];
        let mut spans: Vec<f32> = (0..self.values.len())
            .filter_map(|i| {
                let c = [i % d[0], (i / d[0]) % d[1], i / (d[0] * d[1])];
                if !(0.05..0.95).contains(&self.values[i]) || (0..3).any(|a| c[a] == 0 || c[a] + 1 == d[a]) {
                    return None;
                }
                let g = Vec3::from_array([0, 1, 2].map(|a| self.values[i + stride[a]] - self.values[i - stride[a]]));
                let length = g.length() / (2.0 * self.step);
                (length > 1e-6).then(|| 1.0 / length)
            })
            .collect();
        if spans.is_empty() {
            return None;
        }
        let middle = spans.len() / 2;
        Some(*spans.select_nth_unstable_by(middle, f32::total_cmp).1)
    }
}

/// The eight corners around `p` (clamped into the grid of `dims` corners from `lo`, spaced
/// `step`) with their trilinear weights: what both grids read.
fn trilinear(lo: Vec3, step: f32, dims: [usize; 3], p: Vec3) -> [(usize, f32); 8] {
    let top = Vec3::from_array(dims.map(|d| (d - 1) as f32));
    let g = ((p - lo) / step).clamp(Vec3::ZERO, top);
    let base = g.floor().min(Vec3::from_array(dims.map(|d| d.saturating_sub(2) as f32)));
    let f = g - base;
    let b = base.to_array().map(|c| c as usize);
    std::array::from_fn(|k| {
        let (dx, dy, dz) = (k & 1, (k >> 1) & 1, k >> 2);
        let i = [(b[0] + dx).min(dims[0] - 1), (b[1] + dy).min(dims[1] - 1), (b[2] + dz).min(dims[2] - 1)];
        (i[0] + dims[0] * (i[1] + dims[1] * i[2]), [1.0 - f.x, f.x][dx] * [1.0 - f.y, f.y][dy] * [1.0 - f.z, f.z][dz])
    })
}

/// Every corner of the grid `(lo, step, dims)` inside a tet of `mesh`, tet by tet:
/// `visit(corner index, tet, barycentric weights)` (a corner on a shared face is visited
/// for each of its tets, in tet order).
fn corners_in_tets(
    mesh: &TetMesh,
    (lo, step, dims): (Vec3, f32, [usize; 3]),
    mut visit: impl FnMut(usize, usize, [f32; 4]),
) {
    for (t, tet) in mesh.tets.iter().enumerate() {
        let ps = tet.map(|v| mesh.vertices[v as usize]);
        let (a, b) = ps.iter().fold((Vec3::INFINITY, Vec3::NEG_INFINITY), |(a, b), p| (a.min(*p), b.max(*p)));
        let first = ((a - lo) / step).ceil().max(Vec3::ZERO).to_array().map(|c| c as usize);
        let last = ((b - lo) / step).floor().to_array().map(|c| c.max(-1.0) as i64);
        for z in first[2] as i64..=last[2].min(dims[2] as i64 - 1) {
            for y in first[1] as i64..=last[1].min(dims[1] as i64 - 1) {
                for x in first[0] as i64..=last[0].min(dims[0] as i64 - 1) {
                    let w = mesh.barycentric(t, lo + Vec3::new(x as f32, y as f32, z as f32) * step);
                    if w.iter().all(|c| *c >= -1e-5) {
                        visit(x as usize + dims[0] * (y as usize + dims[1] * z as usize), t, w);
                    }
                }
            }
        }
    }
}

/// Give every unset corner the mean of its set face neighbours (flipped towards the
/// first), one layer per round, until all are set (all at identity when none is).
fn fill_outwards(corners: &mut [Option<Vec4>], dims: [usize; 3]) {
    let stride = [1, dims[0], dims[0] * dims[1]];
    while corners.iter().any(Option::is_none) && corners.iter().any(Option::is_some) {
        let next: Vec<Option<Vec4>> = (0..corners.len())
            .map(|i| {
                if corners[i].is_some() {
                    return corners[i];
                }
                let v = [i % dims[0], (i / dims[0]) % dims[1], i / (dims[0] * dims[1])];
                let (mut sum, mut first): (Option<Vec4>, Option<Vec4>) = (None, None);
                for a in 0..3 {
                    for up in [false, true] {
                        let j = match up {
                            true if v[a] + 1 < dims[a] => i + stride[a],
                            false if v[a] > 0 => i - stride[a],
                            _ => continue,
                        };
                        if let Some(q) = corners[j] {
                            first = first.or(Some(q));
                            sum = Some(match sum {
                                Some(s) if q.dot(s) < 0.0 => s - q,
                                Some(s) => s + q,
                                None => q,
                            });
                        }
                    }
                }
                // opposite neighbours cancelling exactly leave the first one's frame
                sum.and_then(Vec4::try_normalize).or(first)
            })
            .collect();
        corners.copy_from_slice(&next);
    }
}

/// Steps of the line integral along the field, each way.
const LIC_STEPS: usize = 14;

/// The field on a cut: line integral convolution of white noise along each pixel's frame x
/// axis projected onto the cut (streaks follow the strokes' direction), coloured by that
/// axis in model space (|x|, |y|, |z| as red, green, blue); black outside the model
/// (`inside`, per pixel: the model's input surface cut by the plane).
pub fn streamlines(mesh: &TetMesh, field: &FrameField, view: &View, inside: &[bool]) -> Rgb8 {
    let (w, h) = (view.width, view.height);
    let parts: Vec<Vec<Option<f32>>> =
        (0..4).map(|k| field_cut(mesh, &field.components.iter().map(|c| c[k]).collect::<Vec<f32>>(), view)).collect();
    let axes: Vec<Option<Vec3>> = (0..w * h)
        .map(|i| {
            let c = Vec4::new(parts[0][i]?, parts[1][i]?, parts[2][i]?, parts[3][i]?);
            Some(Quat::from_vec4(c.try_normalize()?) * Vec3::X)
        })
        .collect();
    let (right, down) = (view.right.normalize(), view.down.normalize());
    let flow: Vec<Option<Vec2>> =
        axes.iter().map(|a| a.and_then(|a| Vec2::new(a.dot(right), a.dot(down)).try_normalize())).collect();
    let noise: Vec<f32> = (0..w * h).map(|i| crate::noise::unit(mix64(i as u64))).collect();
    let pixels: Vec<[u8; 3]> = (0..w * h)
        .into_par_iter()
        .map(|i| {
            let Some(axis) = axes[i].filter(|_| inside[i]) else { return [0, 0, 0] };
            let streak = integrate(&flow, &noise, (w, h), i);
            let tone = 0.35 + 0.65 * streak;
            axis.abs().to_array().map(|c| to_u8((0.25 + 0.75 * c) * tone))
        })
        .collect();
    let mut out = Rgb8::new(w, h, [0, 0, 0]);
    for (i, c) in pixels.into_iter().enumerate() {
        out.put(i % w, i / w, c);
    }
    out
}

/// The mean noise along the streamline through pixel `start`, both ways.
fn integrate(flow: &[Option<Vec2>], noise: &[f32], (w, h): (usize, usize), start: usize) -> f32 {
    let mut sum = noise[start];
    let mut count = 1.0;
    for sign in [1.0f32, -1.0] {
        let mut p = Vec2::new((start % w) as f32 + 0.5, (start / w) as f32 + 0.5);
        let mut heading = flow[start].unwrap_or(Vec2::ZERO) * sign;
        for _ in 0..LIC_STEPS {
            p += heading;
            if p.x < 0.0 || p.y < 0.0 || p.x >= w as f32 || p.y >= h as f32 {
                break;
            }
            let i = p.y as usize * w + p.x as usize;
            let Some(d) = flow[i] else { break };
            heading = if d.dot(heading) < 0.0 { -d } else { d };
            sum += noise[i];
            count += 1.0;
        }
    }
    sum / count
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Across a ridge of the depth (gradients +y, 0, -y in three rows of corners), frames
    /// follow the blended gradient, not the quaternions: z stays +y all the way to the
    /// ridge and is -y past it, though the ridge's corners hold a frame a quarter turn off;
    /// with a gradient along x, the quaternions are blended.
    #[test]
    fn with_the_depth_frames_follow_its_gradient_up_to_the_ridge() {
        let (up, down, off) = (frame(Vec3::X, Vec3::Y), frame(Vec3::X, -Vec3::Y), frame(Vec3::X, Vec3::Z));
        let row = |i: usize| (i / 2) % 3;
        let corners = (0..12).map(|i| Vec4::from([up, off, down][row(i)])).collect();
        let grid = FrameGrid { lo: Vec3::ZERO, step: 1.0, dims: [2, 3, 2], corners, gradients: None, give_way: true };
        let plain = grid.clone();
        let grid = grid.with_depth(|p| Vec3::Y * (1.0 - p.y));
        for (y, z) in [(0.25, Vec3::Y), (0.75, Vec3::Y), (1.5, -Vec3::Y)] {
            let m = grid.at(Vec3::new(0.5, y, 0.5));
            assert!(m.z_axis.distance(z) < 1e-4 && m.x_axis.distance(Vec3::X) < 1e-4, "at y = {y}: {m:?}");
        }
        assert!(plain.at(Vec3::new(0.5, 0.75, 0.5)).z_axis.distance(Vec3::Y) > 0.1, "the quaternions alone tilt");
        let along = plain.clone().with_depth(|_| Vec3::X);
        let (a, b) = (along.at(Vec3::new(0.5, 0.75, 0.5)), plain.at(Vec3::new(0.5, 0.75, 0.5)));
        assert!(a.abs_diff_eq(b, 1e-5), "{a:?} against {b:?}");
    }

    /// Frames turning a quarter turn between two columns of corners: the pairs across it
    /// count, unless exempt; a uniform grid turns nowhere.
    /// Turning the corners' x along a direction keeps their z as close as a shortest arc
    /// allows, picks the nearer way along the direction, leaves corners without one, and
    /// stops the frames giving way near x.
    #[test]
    fn corners_turn_their_x_along_a_given_direction() {
        let corners = vec![Vec4::from(Quat::from_rotation_z(0.3)); 8];
        let grid = FrameGrid { lo: Vec3::ZERO, step: 1.0, dims: [2; 3], corners, gradients: None, give_way: true };
        let turned = grid.clone().with_x_along(|p| (p.x > 0.5).then_some(-Vec3::Y));
        assert!(!turned.give_way);
        for (i, (q, before)) in turned.corners.iter().zip(&grid.corners).enumerate() {
            let x = Quat::from_vec4(*q) * Vec3::X;
            if i % 2 == 1 {
                assert!(x.dot(Vec3::Y) > 0.9999, "corner {i}: x {x}, the nearer way along -y");
                assert!((Quat::from_vec4(*q) * Vec3::Z).dot(Vec3::Z) > 0.9999, "z kept");
            } else {
                assert_eq!(q, before);
            }
        }
    }

    #[test]
    fn turns_count_the_neighbours_whose_frames_differ() {
        let quarter = Vec4::from(Quat::from_rotation_z(std::f32::consts::FRAC_PI_2));
        let corners = (0..4 * 4 * 2).map(|i| if i % 4 >= 2 { quarter } else { Vec4::W }).collect();
        let grid = FrameGrid { lo: Vec3::ZERO, step: 1.0, dims: [4, 4, 2], corners, gradients: None, give_way: true };
        let points: Vec<Option<Vec3>> = (0..16).map(|i| Some(Vec3::new((i % 4) as f32, (i / 4) as f32, 0.0))).collect();
        let turned = turns(&grid, &points, 4, 30.0, |_| false);
        assert_eq!((turned.over, turned.pairs), (4, 24), "{turned:?}");
        assert!((turned.largest - 90.0).abs() < 0.1, "{turned:?}");
        assert_eq!(turns(&grid, &points, 4, 30.0, |p| p.x >= 2.0).over, 0, "exempt points count nowhere");
        let uniform = FrameGrid { corners: vec![Vec4::W; 32], ..grid };
        assert_eq!(turns(&uniform, &points, 4, 30.0, |_| false).largest, 0.0);
    }

    /// A ramp rising by 1 over 10 units spans 10, whichever way it runs and however
    /// finely it is sampled; a constant spans nothing.
    #[test]
    fn a_ramp_spans_its_rise() {
        let ramp = |p: Vec3| ((p.x + p.y) / (10.0 * 2f32.sqrt())).clamp(0.0, 1.0);
        for cells in [16, 40] {
            let grid = ScalarGrid::sample(ramp, (Vec3::ZERO, Vec3::splat(20.0)), cells);
            let span = grid.span().unwrap();
            assert!((span - 10.0).abs() < 0.2, "{cells} cells: {span}");
        }
        assert_eq!(ScalarGrid::sample(|_| 0.5, (Vec3::ZERO, Vec3::ONE), 8).span(), None);
    }
    use crate::fill::tets::cube_lattice;

    #[test]
    fn the_frame_convention_puts_x_on_the_stroke_and_z_on_the_depth_gradient() {
        let q = frame(Vec3::new(1.0, 0.2, 0.0), Vec3::Y);
        assert!((q * Vec3::Z).distance(Vec3::Y) < 1e-5);
        assert!((q * Vec3::X).distance(Vec3::X) < 1e-5);
        assert!((q * Vec3::Y).distance(-Vec3::Z) < 1e-5, "right-handed: y = z x x");
        let depth =
            [(Vec3::ZERO, 0.0), (Vec3::new(0.0, 1.0, 0.0), 1.0), (Vec3::new(1.0, 0.0, 0.0), 0.0), (Vec3::Z, 0.0)];
        let frames = sketched_frames(&[(Vec3::new(0.3, 0.6, 0.3), Vec3::X)], &depth).unwrap();
        assert!((frames[0].1 * Vec3::Z).dot(Vec3::Y) > 0.99, "z follows the depth gradient");
    }

    /// Points of depth 0 give frames too: z towards the depth axis, x along the stroke;
    /// around the axis the frames turn (a log's rings).
    #[test]
    fn depth_points_give_frames_turning_around_the_axis() {
        let mut depth: Vec<(Vec3, f32)> = (0..5).map(|i| (Vec3::new(0.2 * i as f32, 0.5, 0.5), 1.0)).collect();
        for i in 0..5 {
            for (y, z) in [(0.0, 0.5), (1.0, 0.5), (0.5, 0.0), (0.5, 1.0)] {
                depth.push((Vec3::new(0.2 * i as f32 + 0.1, y, z), 0.0));
            }
        }
        let stroke = [(Vec3::new(0.3, 0.5, 0.5), Vec3::X), (Vec3::new(0.7, 0.5, 0.5), Vec3::X)];
        let frames = sketched_frames(&stroke, &depth).unwrap();
        assert_eq!(frames.len(), 2 + 20);
        for &(p, q) in &frames[2..] {
            let inward = (Vec3::new(p.x, 0.5, 0.5) - p).normalize();
            assert!((q * Vec3::Z).dot(inward) > 0.9, "at {p}: z {} towards the axis {inward}", q * Vec3::Z);
            assert!((q * Vec3::X).dot(Vec3::X) > 0.99, "at {p}: x along the stroke");
        }
    }

    /// Frames twisting about x from one face of a cube to the other: the harmonic field
    /// turns smoothly between them, and meets each where it was sketched.
    #[test]
    fn the_harmonic_field_meets_the_sketched_frames_and_turns_smoothly_between() {
        let mesh = cube_lattice([6, 6, 6], 1.0 / 6.0);
        let turned = Quat::from_rotation_x(std::f32::consts::FRAC_PI_2);
        let mut frames = Vec::new();
        for i in 0..5 {
            for j in 0..5 {
                let (y, z) = (0.1 + 0.2 * i as f32, 0.1 + 0.2 * j as f32);
                frames.push((Vec3::new(0.02, y, z), Quat::IDENTITY));
                // one frame given with the other sign: the same rotation, re-signed by the field
                frames.push((Vec3::new(0.98, y, z), if i == 2 && j == 2 { -turned } else { turned }));
            }
        }
        let field = solve(&mesh, &frames).unwrap();
        let at = |p: Vec3| {
            let (t, b) = crate::fill::field::locate(&mesh, p);
            field.at(mesh.tets[t], b)
        };
        assert!(at(Vec3::new(0.02, 0.5, 0.5)).angle_between(Quat::IDENTITY) < 0.1);
        assert!(at(Vec3::new(0.98, 0.5, 0.5)).angle_between(turned) < 0.1);
        let middle = at(Vec3::new(0.5, 0.5, 0.5));
        let half = Quat::from_rotation_x(std::f32::consts::FRAC_PI_4);
        assert!(middle.angle_between(half) < 0.15, "halfway: {middle:?}");
        assert!((middle * Vec3::X).distance(Vec3::X) < 1e-3, "the twist keeps x");
    }

    #[test]
    fn a_picture_of_the_field_streaks_along_the_stroke() {
        let mesh = cube_lattice([4, 4, 4], 0.25);
        let frames = vec![(Vec3::splat(0.5), frame(Vec3::X, Vec3::Z))];
        let field = solve(&mesh, &frames).unwrap();
        let view = View::framing((Vec3::ZERO, Vec3::ONE), Vec3::splat(0.5), Vec3::Z, 96).unwrap();
        // the model's outline: a disc of 40 pixels' radius inside the cube's square
        let inside: Vec<bool> =
            (0..96 * 96).map(|i| ((i % 96) as f32 - 47.5).hypot((i / 96) as f32 - 47.5) < 40.0).collect();
        let picture = streamlines(&mesh, &field, &view, &inside);
        // streaks along x: neighbours along a row differ less than along a column
        let (mut along, mut across) = (0.0, 0.0);
        for y in 24..72 {
            for x in 24..72 {
                let v = |x: usize, y: usize| picture.at(x, y)[0] as f32;
                along += (v(x + 1, y) - v(x, y)).abs();
                across += (v(x, y + 1) - v(x, y)).abs();
            }
        }
        assert!(along * 2.0 < across, "along {along} across {across}");
        assert_eq!(picture.at(0, 0), [0, 0, 0], "outside the mesh is black");
        assert_eq!(picture.at(90, 90), [0, 0, 0], "inside the tets but outside the outline is black");
        assert_ne!(picture.at(80, 48), [0, 0, 0], "inside the outline shows the field");
        assert!(picture.at(48, 48)[0] > picture.at(48, 48)[1], "x axis shows red");
    }
}
