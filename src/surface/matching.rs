//! Neighbourhood matching over a point hierarchy (Turk 2001; Wei and Levoy 2001), with
//! each point holding an exemplar pixel (its coordinates) rather than a colour, as in
//! Lefebvre and Hoppe's parallel synthesis, so results are copies of exemplar pixels and
//! stay as sharp as the photo.
//!
//! ```text
//!  points (even) --Poisson subsets--> S0 ⊃ S1 ⊃ ... ⊃ Sk        exemplar pyramid E0 .. Ek
//!  Sk: random pixels of Ek, then passes;   S(l): from the nearest point q of S(l+1):
//!  u(p) = 2 u(q) + offset(q -> p), then passes; colour = E0(u) on S0
//!
//!  a pass: for each point p, the neighbours q within a radius, their offsets d(q) in
//!  p's frame (up = the direction field, right = up x normal) in pixels of E(l);
//!  candidates u(q) - d(q) and their k-coherence sets; keep the u minimizing
//!  sum_q w(q) |E(u + d(q)) - E(u(q))|²  x (1 + usage penalty), halved for an exact
//!  continuation of a neighbour's patch
//! ```
//!
//! Matching runs on the sparsest point level still at least as dense as the exemplar's
//! pixels; the denser levels below copy the nearest matched point's coordinates plus
//! their offset. The usage penalties (colour bins and exemplar blocks used more than
//! their share) keep k-coherence from settling on a few parts of the photo.
//!
//! Order independence (the result is the same on any thread count): space is cut into
//! cubes the size of the neighbourhood radius, and each pass runs eight sub-passes, one
//! per parity class of the cubes' coordinates. Cubes of one class are at least one cube
//! apart, so no point reads another being updated in a different cube; the cubes of a
//! class run in parallel, the points inside one cube in index order.

use crate::error::{Error, Result};
use crate::hashing::IntMap;
use crate::noise::mix64;
use crate::progress::Progress;
use crate::quality::{BINS, histogram};
use crate::synth::exemplar::{PrepareOptions, Prepared};
use crate::volume::{Edge, Image2d, Volume, downsample};
use glam::Vec3;
use rayon::prelude::*;

/// Neighbourhood radius in exemplar pixels of the level.
const RADIUS: f32 = 4.5;
/// The most neighbours a point compares (the nearest).
const MAX_NEIGHBOURS: usize = 72;
/// A candidate that continues a neighbour's patch exactly (the first of a coherence set)
/// counts its cost times `1 - COHERENT`: larger copied patches, fewer seams, and the
/// skin keeps the photo's edges (0.5 measured best on the photos of docs/surface.md).
const COHERENT: f32 = 0.5;
/// Neighbours whose coordinates propose candidates (the nearest).
const PROPOSERS: usize = 8;
/// Size of the k-coherence sets.
const COHERENCE: usize = 4;
/// Neighbourhood side of the exemplar analysis behind the coherence sets.
const ANALYSIS: usize = 5;
/// Passes at the coarsest level and at the finer ones.
const PASSES: (usize, usize) = (5, 2);
/// The coarsest level's exemplar keeps at least this many pixels on its shorter side.
const COARSEST_SIDE: usize = 20;
/// Most levels.
const MAX_LEVELS: usize = 5;
/// A neighbour whose normal turns further than this (cosine) lies on another sheet.
const SAME_SHEET: f32 = 0.3;

/// The points to texture and their frames.
pub struct Points<'a> {
    /// Positions.
    pub positions: &'a [Vec3],
    /// Unit normals.
    pub normals: &'a [Vec3],
    /// Unit tangents: the exemplar's "up".
    pub ups: &'a [Vec3],
    /// The points' typical spacing.
    pub spacing: f32,
}

/// Per point, the level-0 exemplar pixel `(x, y)` it shows; and the number of levels.
pub fn coordinates(
    points: &Points,
    exemplar: &Image2d,
    texel: f32,
    seed: u64,
    progress: &dyn Progress,
) -> Result<(Vec<[i32; 2]>, usize)> {
    let below = below_exemplar(texel, points.spacing);
    let images = pyramid(exemplar, points.positions.len() >> (2 * below));
    let levels = images.len();
    let subsets = subsets(points, below + levels);
    let mut coords: Vec<[i32; 2]> = Vec::new();
    // each level's share of the work: its points (the finest holds most of them)
    let work: Vec<f32> = (0..levels).map(|level| subsets[below + level].len() as f32).collect();
    let total = work.iter().sum::<f32>().max(1.0);
    let mut done = 0.0;
    for level in (0..levels).rev() {
        if progress.cancelled() {
            return Err(Error::Cancelled);
        }
        let stage = format!("level {}/{levels}", levels - level);
        progress.update(&stage, done / total);
        let image = &images[level];
        let options = PrepareOptions { n: ANALYSIS, variance: 0.95, max_dims: 16, k: COHERENCE };
        let prepared = Prepared::new(image, &vec![1.0; image.channel_count()], options);
        let scale = texel * (1 << level) as f32;
        let at = below + level;
        let members = &subsets[at];
        let graph = Graph::new(points, members, scale, points.spacing * (1 << at) as f32);
        coords = if level + 1 == levels {
            let start = |p: u32| prepared_pixel(&prepared, prepared.random_centre(mix64(seed ^ u64::from(p))));
            members.iter().map(|&p| start(p)).collect()
        } else {
            finer(points, (&subsets[at + 1], poisson_radius(points, at + 1)), &coords, members, (scale, 2), image)
        };
        let passes = if level + 1 == levels { PASSES.0 } else { PASSES.1 };
        let pixels: Vec<[i32; 2]> = (0..image.width() * image.height())
            .map(|i| [(i % image.width()) as i32, (i / image.width()) as i32])
            .collect();
        let wanted = shares(&prepared, &pixels);
        for pass in 0..passes {
            graph.pass(&prepared, &mut coords, &wanted);
            progress.update(&stage, (done + work[level] * (pass + 1) as f32 / passes as f32) / total);
        }
        done += work[level];
    }
    for at in (0..below).rev() {
        coords = finer(
            points,
            (&subsets[at + 1], poisson_radius(points, at + 1)),
            &coords,
            &subsets[at],
            (texel, 1),
            exemplar,
        );
    }
    Ok((coords, levels))
}

/// How many point levels lie below the exemplar's full resolution: with pixels `texel`
/// long and points `spacing` apart, log2(texel / spacing) rounded down, so matching runs
/// on the sparsest points still at least as dense as the pixels; the denser points below
/// take their coordinates from the nearest matched one (each point still shows one
/// exemplar pixel, so the colours blended across a triangle stay as sharp as the photo).
fn below_exemplar(texel: f32, spacing: f32) -> usize {
    let ratio = (texel / spacing).log2() + 1e-3;
    if ratio.is_finite() && ratio > 0.0 { (ratio.floor() as usize).min(4) } else { 0 }
}

/// The exemplar and its 2x reductions, as many as keep [`COARSEST_SIDE`] pixels and leave
/// the coarsest point set a few hundred points.
fn pyramid(exemplar: &Image2d, points: usize) -> Vec<Image2d> {
    let mut images = vec![exemplar.clone()];
    while images.len() < MAX_LEVELS {
        let last = &images[images.len() - 1];
        let next_points = points >> (2 * images.len());
        if last.width().min(last.height()) / 2 < COARSEST_SIDE || next_points < 300 {
            break;
        }
        images.push(reduced(last));
    }
    images
}

/// The image blurred by the 5-tap binomial and halved (sides rounded up), edges clamped:
/// the volumes' pyramid step on a one-voxel-deep volume.
fn reduced(image: &Image2d) -> Image2d {
    let names = image.channels().to_vec();
    let flat = Volume::from_data([image.width(), image.height(), 1], names.clone(), image.data().to_vec())
        .expect("the sizes agree");
    let half = downsample(&flat, Edge::Clamp).expect("a smaller image fits the budget the larger did");
    let [w, h, _] = half.dims();
    Image2d::from_data(w, h, names, half.into_data()).expect("the sizes agree")
}

fn prepared_pixel(prepared: &Prepared, centre: u32) -> [i32; 2] {
    [(centre as usize % prepared.width) as i32, (centre as usize / prepared.width) as i32]
}

/// Nested subsets of the points, level `l` about `4^-l` of them spread evenly (a greedy
/// Poisson-disk pick in index order with radius 0.78 x spacing x 2^l, the radius at which a
/// random close packing has the density of an even tiling at that spacing).
fn subsets(points: &Points, levels: usize) -> Vec<Vec<u32>> {
    let mut sets = vec![(0..points.positions.len() as u32).collect::<Vec<u32>>()];
    for level in 1..levels {
        let radius = poisson_radius(points, level);
        let mut grid: IntMap<[i32; 3], Vec<u32>> = IntMap::default();
        let mut kept = Vec::new();
        for &p in &sets[level - 1] {
            let at = points.positions[p as usize];
            let cell = cell_of(at, radius);
            let near = neighbour_cells(cell).any(|c| {
                grid.get(&c).is_some_and(|list| {
                    list.iter().any(|&q| points.positions[q as usize].distance_squared(at) < radius * radius)
                })
            });
            if !near {
                grid.entry(cell).or_default().push(p);
                kept.push(p);
            }
        }
        sets.push(kept);
    }
    sets
}

/// The smallest distance between the points of subset `level`.
fn poisson_radius(points: &Points, level: usize) -> f32 {
    0.78 * points.spacing * (1 << level) as f32
}

fn cell_of(p: Vec3, size: f32) -> [i32; 3] {
    (p / size).floor().to_array().map(|v| v as i32)
}

fn neighbour_cells([x, y, z]: [i32; 3]) -> impl Iterator<Item = [i32; 3]> {
    (-1..=1).flat_map(move |dz| (-1..=1).flat_map(move |dy| (-1..=1).map(move |dx| [x + dx, y + dy, z + dz])))
}

/// Points bucketed by cubes of one side.
struct Buckets {
    size: f32,
    cells: IntMap<[i32; 3], Vec<u32>>,
}

impl Buckets {
    /// `items[i]` is the point at slot `i`; buckets hold slots.
    fn new(positions: &[Vec3], items: &[u32], size: f32) -> Buckets {
        let mut cells: IntMap<[i32; 3], Vec<u32>> = IntMap::default();
        for (slot, &p) in items.iter().enumerate() {
            cells.entry(cell_of(positions[p as usize], size)).or_default().push(slot as u32);
        }
        Buckets { size, cells }
    }

    fn near(&self, p: Vec3) -> impl Iterator<Item = u32> + '_ {
        neighbour_cells(cell_of(p, self.size)).flat_map(|c| self.cells.get(&c).into_iter().flatten().copied())
    }
}

/// A point's offset to another in its frame, in pixels of a level: right, down.
fn offset(points: &Points, from: usize, to: usize, scale: f32) -> [f32; 2] {
    let d = points.positions[to] - points.positions[from];
    let up = points.ups[from];
    let right = up.cross(points.normals[from]);
    [d.dot(right) / scale, -d.dot(up) / scale]
}

/// Each point's neighbours on one level: slots, rounded pixel offsets and weights.
struct Graph {
    offsets: Vec<usize>,
    slots: Vec<u32>,
    offsets_px: Vec<[f32; 2]>,
    weights: Vec<f32>,
    /// Slots grouped by cube, cubes grouped by parity class.
    classes: Vec<Vec<Vec<u32>>>,
    /// Each slot's cube, as an index into the cubes of its class.
    cube: Vec<u32>,
}

impl Graph {
    /// The graph of `members`, pixels of `scale` model units, points `spacing` apart: the
    /// neighbourhood radius is [`RADIUS`] pixels, widened to 1.6 spacings where the points
    /// are sparser than the pixels.
    fn new(points: &Points, members: &[u32], scale: f32, spacing: f32) -> Graph {
        let radius = (RADIUS * scale).max(1.6 * spacing);
        let buckets = Buckets::new(points.positions, members, radius);
        let lists: Vec<Vec<(f32, u32, [f32; 2])>> = members
            .par_iter()
            .enumerate()
            .map(|(slot, &p)| {
                let (at, normal) = (points.positions[p as usize], points.normals[p as usize]);
                let mut near: Vec<(f32, u32, [f32; 2])> = buckets
                    .near(at)
                    .filter(|&s| s as usize != slot)
                    .filter_map(|s| {
                        let q = members[s as usize] as usize;
                        let d = points.positions[q].distance(at);
                        (d < radius && points.normals[q].dot(normal) > SAME_SHEET)
                            .then(|| (d, s, offset(points, p as usize, q, scale)))
                    })
                    .collect();
                near.sort_by(|a, b| a.0.total_cmp(&b.0).then(a.1.cmp(&b.1)));
                near.truncate(MAX_NEIGHBOURS);
                near
            })
            .collect();
        let sigma = radius / 2.0;
        let mut graph = Graph {
            offsets: vec![0],
            slots: Vec::new(),
            offsets_px: Vec::new(),
            weights: Vec::new(),
            classes: vec![Vec::new(); 8],
            cube: vec![0; members.len()],
        };
        for list in lists {
            for (d, s, shift) in list {
                graph.slots.push(s);
                graph.offsets_px.push(shift);
                graph.weights.push((-(d * d) / (2.0 * sigma * sigma)).exp());
            }
            graph.offsets.push(graph.slots.len());
        }
        let mut cubes: Vec<([i32; 3], Vec<u32>)> = buckets.cells.into_iter().collect();
        cubes.sort_by_key(|(c, _)| *c);
        for (c, slots) in cubes {
            let class = c.iter().enumerate().map(|(a, v)| (v.rem_euclid(2) as usize) << a).sum::<usize>();
            for &s in &slots {
                graph.cube[s as usize] = graph.classes[class].len() as u32;
            }
            graph.classes[class].push(slots);
        }
        graph
    }

    fn neighbours(&self, slot: usize) -> std::ops::Range<usize> {
        self.offsets[slot]..self.offsets[slot + 1]
    }

    /// One pass of eight sub-passes over the parity classes; `wanted` is the exemplar
    /// level's [`Shares`].
    fn pass(&self, ex: &Prepared, coords: &mut [[i32; 2]], wanted: &Shares) {
        for class in &self.classes {
            let penalty = Penalty::new(ex, coords, wanted);
            let updates: Vec<Vec<(u32, [i32; 2])>> =
                class.par_iter().map(|slots| self.update_cube(ex, coords, slots, &penalty)).collect();
            for (slot, value) in updates.into_iter().flatten() {
                coords[slot as usize] = value;
            }
        }
    }

    /// The new coordinates of the points of one cube, in slot order, each seeing those
    /// before it.
    fn update_cube(
        &self,
        ex: &Prepared,
        coords: &[[i32; 2]],
        slots: &[u32],
        penalty: &Penalty,
    ) -> Vec<(u32, [i32; 2])> {
        // the cube's points run in slot order (`slots` is sorted), each reading the new
        // coordinates of those before it
        debug_assert!(slots.windows(2).all(|w| w[0] < w[1]), "a cube's points in slot order");
        let mut done: Vec<(u32, [i32; 2])> = Vec::with_capacity(slots.len());
        let mut seen: Vec<[f32; 3]> = Vec::with_capacity(MAX_NEIGHBOURS);
        let mut tried: Vec<[i32; 2]> = Vec::with_capacity(PROPOSERS * COHERENCE + 1);
        for &slot in slots {
            let read = |s: u32| match slots[..done.len()].binary_search(&s) {
                Ok(j) => done[j].1,
                Err(_) => coords[s as usize],
            };
            let range = self.neighbours(slot as usize);
            seen.clear();
            seen.extend(self.slots[range.clone()].iter().map(|&s| colour(ex, read(s))));
            // the cost of `u` times `factor`, or `None` once its partial sum shows it cannot
            // come under `bound` (the terms are not negative, and rounding keeps a larger sum
            // larger, so the candidate chosen is the one the whole sums choose)
            let cost = |u: [i32; 2], factor: f32, bound: f32| -> Option<f32> {
                let over = 1.0 + penalty.at(ex, u);
                let mut sum = 0.0;
                for (k, i) in range.clone().enumerate() {
                    let [dx, dy] = self.offsets_px[i];
                    let c = bilinear(ex, u[0] as f32 + dx, u[1] as f32 + dy);
                    let d = (c[0] - seen[k][0]).powi(2) + (c[1] - seen[k][1]).powi(2) + (c[2] - seen[k][2]).powi(2);
                    sum += self.weights[i] * d;
                    if k % 8 == 7 && sum * over * factor >= bound {
                        return None;
                    }
                }
                Some(sum * over * factor)
            };
            let mine = coords[slot as usize];
            let mut best = (cost(mine, 1.0, f32::INFINITY).unwrap_or(f32::INFINITY), mine);
            tried.clear();
            tried.push(mine);
            for i in range.clone().take(PROPOSERS) {
                let q = read(self.slots[i]);
                let [dx, dy] = self.offsets_px[i].map(|v| v.round() as i64);
                let source = ex.clamped_slot(i64::from(q[0]) - dx, i64::from(q[1]) - dy);
                for (k, similar) in ex.coherence_of(source).enumerate() {
                    let candidate = prepared_pixel(ex, ex.centres[similar as usize]);
                    if tried.contains(&candidate) {
                        continue;
                    }
                    tried.push(candidate);
                    let factor = if k == 0 { 1.0 - COHERENT } else { 1.0 };
                    if let Some(c) = cost(candidate, factor, best.0).filter(|c| *c < best.0) {
                        best = (c, candidate);
                    }
                }
            }
            done.push((slot, best.1));
        }
        done
    }
}

/// How much a colour bin used twice as often as in the exemplar costs: matches there count
/// `1 + COLOUR_USE` times (Kopf et al. 2007 weight matches by the histogram in a similar way).
const COLOUR_USE: f32 = 1.0;
/// How much an exemplar block used twice as often as an even spread would use it costs.
const PLACE_USE: f32 = 0.5;
/// Blocks of the place penalty per exemplar side.
const BLOCKS: usize = 16;

fn bin(v: f32) -> usize {
    ((v.clamp(0.0, 1.0) * BINS as f32) as usize).min(BINS - 1)
}

/// Per channel, the share of colours in each of the [`BINS`] bins.
type Shares = [Vec<f64>; 3];

/// The [`Shares`] of the exemplar colours at `pixels`.
fn shares(ex: &Prepared, pixels: &[[i32; 2]]) -> Shares {
    let colours: Vec<[f32; 3]> = pixels.iter().map(|&u| colour(ex, u)).collect();
    std::array::from_fn(|k| histogram(colours.iter().map(|c| &c[k])))
}

/// What over-use costs, frozen for one sub-pass: the matches of a candidate whose colour
/// is over-represented among the points, or whose part of the exemplar the points already
/// show more than their share, count more. Without it k-coherence settles on a few parts
/// of the exemplar and the skin's colours drift from the photo's.
struct Penalty {
    colour: [[f32; BINS]; 3],
    places: Vec<f32>,
    block: [usize; 2],
}

impl Penalty {
    fn new(ex: &Prepared, coords: &[[i32; 2]], wanted: &Shares) -> Penalty {
        let used = shares(ex, coords);
        let over = |u: f64, w: f64| COLOUR_USE * if w > 0.0 { (u / w - 1.0).max(0.0) as f32 } else { 0.0 };
        let colour: [[f32; BINS]; 3] = std::array::from_fn(|k| std::array::from_fn(|b| over(used[k][b], wanted[k][b])));
        let block = [ex.width.div_ceil(BLOCKS), ex.height.div_ceil(BLOCKS)];
        let mut counts = vec![0.0f32; BLOCKS * BLOCKS];
        for &u in coords {
            counts[Penalty::block_of(block, u)] += 1.0;
        }
        // a block is over-used past its share of the points, or past one point per pixel
        // when the points are fewer than the pixels (a patch copied whole is no over-use)
        let share = (coords.len() as f32 / (BLOCKS * BLOCKS) as f32).max((block[0] * block[1]) as f32);
        let places = counts.iter().map(|&c| PLACE_USE * (c / share.max(1e-6) - 1.0).max(0.0)).collect();
        Penalty { colour, places, block }
    }

    fn block_of(block: [usize; 2], [x, y]: [i32; 2]) -> usize {
        let bx = (x.max(0) as usize / block[0]).min(BLOCKS - 1);
        let by = (y.max(0) as usize / block[1]).min(BLOCKS - 1);
        by * BLOCKS + bx
    }

    /// The extra weight of matches at `u`.
    fn at(&self, ex: &Prepared, u: [i32; 2]) -> f32 {
        let c = colour(ex, u);
        (0..3).map(|k| self.colour[k][bin(c[k])]).sum::<f32>() + self.places[Penalty::block_of(self.block, u)]
    }
}

/// The exemplar pixel at `u`, clamped to the image (the first three channels).
fn colour(ex: &Prepared, [x, y]: [i32; 2]) -> [f32; 3] {
    let x = x.clamp(0, ex.width as i32 - 1) as usize;
    let y = y.clamp(0, ex.height as i32 - 1) as usize;
    let at = (y * ex.width + x) * ex.channels;
    let px = &ex.colours[at..at + ex.channels];
    [px[0], px[1.min(ex.channels - 1)], px[2.min(ex.channels - 1)]]
}

/// Coordinates of `members` from the nearest point of the coarser subset (whose points are
/// at least `radius` apart): its coordinates times `factor` (2 when the exemplar level
/// doubles too, else 1) plus the offset between them in pixels of `scale`, clamped to
/// `image`.
fn finer(
    points: &Points,
    (coarser, radius): (&[u32], f32),
    coarse: &[[i32; 2]],
    members: &[u32],
    (scale, factor): (f32, i32),
    image: &Image2d,
) -> Vec<[i32; 2]> {
    let buckets = Buckets::new(points.positions, coarser, radius);
    let (w, h) = (image.width() as i32, image.height() as i32);
    members
        .par_iter()
        .map(|&p| {
            let at = points.positions[p as usize];
            let nearest = buckets
                .near(at)
                .map(|s| (points.positions[coarser[s as usize] as usize].distance_squared(at), s))
                .min_by(|a, b| a.0.total_cmp(&b.0).then(a.1.cmp(&b.1)));
            match nearest {
                Some((_, s)) => {
                    let q = coarser[s as usize] as usize;
                    let [dx, dy] = offset(points, q, p as usize, scale);
                    let [ux, uy] = coarse[s as usize];
                    [
                        (factor * ux + dx.round() as i32).clamp(0, w - 1),
                        (factor * uy + dy.round() as i32).clamp(0, h - 1),
                    ]
                }
                None => [w / 2, h / 2],
            }
        })
        .collect()
}

/// The exemplar's colour at `(x, y)` pixels, bilinear between pixel centres, clamped.
#[inline(always)]
fn bilinear(ex: &Prepared, x: f32, y: f32) -> [f32; 3] {
    let (x0, y0) = (x.floor(), y.floor());
    let (tx, ty) = (x - x0, y - y0);
    let (x0, y0) = (x0 as i32, y0 as i32);
    let (right, bottom) = (ex.width as i32 - 1, ex.height as i32 - 1);
    let (xa, xb) = (x0.clamp(0, right) as usize, (x0 + 1).clamp(0, right) as usize);
    let (ya, yb) = (y0.clamp(0, bottom) as usize, (y0 + 1).clamp(0, bottom) as usize);
    let (c, last) = (ex.channels, ex.channels - 1);
    let at = |x: usize, y: usize, k: usize| ex.colours[(y * ex.width + x) * c + k.min(last)];
    let mut out = [0.0; 3];
    for (k, o) in out.iter_mut().enumerate() {
        let (a, b) = (at(xa, ya, k), at(xb, ya, k));
        let (c, d) = (at(xa, yb, k), at(xb, yb, k));
        *o = (a * (1.0 - tx) + b * tx) * (1.0 - ty) + (c * (1.0 - tx) + d * tx) * ty;
    }
    out
}
