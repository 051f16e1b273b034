//! Re-tiling: the surface covered again by nearly equilateral triangles of one edge length,
//! so their corners are a dense, even set of points on it (the substitute for Turk's point
//! repulsion the issue allows: subdivision plus relaxation). Isotropic remeshing after
//! Botsch and Kobbelt (2004), in rounds of four global passes:
//!
//! ```text
//!   split edges > 4/3 L   collapse edges < 4/5 L   flip towards valence 6   relax
//!      /\       /\            /|\       /\             |\ /|    |\ |           move each point to its
//!     /  \  -> /__\          /_|_\  -> /__\            | X |  ->| \|           neighbours' centroid in
//!    /____\   /_\/_\                                    |/ \|    |__\           its tangent plane, then
//!                                                                               onto the input surface
//! ```
//!
//! `L = sqrt(2 A / (sqrt(3) N))` gives about `N` points for a surface of area `A` (an
//! equilateral tiling has two triangles of area `sqrt(3) L² / 4` per point); after the
//! rounds the length is corrected once by the count reached. Every pass visits edges and
//! triangles in a fixed order and the relaxation computes all new positions from the old
//! ones, so the result does not depend on the thread count. Open borders stay: their
//! edges are split, their points never move and are never collapsed.

use crate::error::{Error, Result};
use crate::fill::mesher::closest::Surface;
use crate::hashing::IntMap;
use crate::mesh::Mesh;
use crate::progress::Progress;
use glam::Vec3;
use rayon::prelude::*;

/// Rounds of split, collapse, flip and relax at each edge length.
const ROUNDS: usize = 5;
/// Edge lengths tried: the first from the area, the others corrected by the count reached
/// (from a coarse input, such as a 162-vertex sphere, three left the count 30 % off).
const ATTEMPTS: usize = 6;
/// Relaxations after the last round.
const FINAL_RELAXATIONS: usize = 3;
/// The most collapsing passes per round (each collapses edges with disjoint neighbourhoods).
const MAX_COLLAPSES: usize = 8;
/// The most splitting passes before the first round (each halves the longest edges).
const MAX_SPLITS: usize = 40;

/// The even re-tiling of `mesh` with about `points` corners.
pub fn retile(mesh: &Mesh, points: usize, progress: &dyn Progress) -> Result<Mesh> {
    let area = area(mesh);
    if !(area > 0.0 && area.is_finite()) {
        return Err(Error::invalid("the mesh has no area to cover with points"));
    }
    let mut edge = target_edge(area, points);
    let surface = Surface::new(mesh, 2.0 * edge);
    let mut tiling = Tiling::new(mesh);
    for attempt in 0..ATTEMPTS {
        for _ in 0..MAX_SPLITS {
            if tiling.split_long(4.0 / 3.0 * edge) == 0 {
                break;
            }
            let budget = 32 * points + 4 * mesh.triangles.len();
            if tiling.triangles.len() > budget {
                return Err(Error::invalid(format!(
                    "the mesh's triangles are too long and thin to tile with {points} points: splitting them \
                     reached {} triangles before their edges came down to {edge:.3e}",
                    tiling.triangles.len()
                )));
            }
        }
        for round in 0..ROUNDS {
            if progress.cancelled() {
                return Err(Error::Cancelled);
            }
            progress.update("re-tiling", (attempt * ROUNDS + round) as f32 / (ATTEMPTS * ROUNDS) as f32);
            tiling.split_long(4.0 / 3.0 * edge);
            for _ in 0..MAX_COLLAPSES {
                if tiling.collapse_short(4.0 / 5.0 * edge, 4.0 / 3.0 * edge) == 0 {
                    break;
                }
            }
            tiling.flip_for_valence();
            tiling.relax(&surface);
        }
        let reached = tiling.vertices.len() as f32;
        let off = reached / points as f32;
        if (0.92..=1.08).contains(&off) {
            break;
        }
        edge *= off.sqrt();
    }
    for _ in 0..FINAL_RELAXATIONS {
        tiling.relax(&surface);
    }
    Mesh::new(tiling.vertices, tiling.triangles)
}

/// The edge length that tiles `area` with about `points` corners.
pub fn target_edge(area: f64, points: usize) -> f32 {
    (2.0 * area / (3f64.sqrt() * points.max(1) as f64)).sqrt() as f32
}

/// The surface area of a mesh.
pub fn area(mesh: &Mesh) -> f64 {
    let corners = mesh.triangles.iter().map(|t| t.map(|i| mesh.vertices[i as usize].as_dvec3()));
    corners.map(|[a, b, c]| (b - a).cross(c - a).length() / 2.0).sum()
}

/// An undirected edge as one number, the smaller index first.
fn key(a: u32, b: u32) -> u64 {
    (u64::from(a.min(b)) << 32) | u64::from(a.max(b))
}

/// A triangle's normal scaled by twice its area.
fn cross([a, b, c]: [Vec3; 3]) -> Vec3 {
    (b - a).cross(c - a)
}

/// The mesh being re-tiled.
struct Tiling {
    vertices: Vec<Vec3>,
    triangles: Vec<[u32; 3]>,
}

/// Each vertex's neighbours (sorted), whether it lies on an open border, and its
/// triangles.
struct Adjacency {
    offsets: Vec<usize>,
    neighbours: Vec<u32>,
    border: Vec<bool>,
    around: Around,
}

impl Adjacency {
    /// Each vertex's neighbours are the other corners of its triangles; an edge that only
    /// one triangle (or more than two) holds is an open border. Blocks of vertices are
    /// listed in parallel, each into its own stretch of one buffer (two corners per
    /// triangle around a vertex at most), then packed.
    fn build(vertices: usize, triangles: &[[u32; 3]]) -> Adjacency {
        const BLOCK: usize = 4096;
        let around = triangles_around(vertices, triangles);
        let mut scratch = vec![0u32; 2 * around.offsets[vertices]];
        let mut stretches = Vec::with_capacity(vertices.div_ceil(BLOCK));
        let mut rest = scratch.as_mut_slice();
        for start in (0..vertices).step_by(BLOCK) {
            let end = (start + BLOCK).min(vertices);
            let (this, next) = rest.split_at_mut(2 * (around.offsets[end] - around.offsets[start]));
            stretches.push((start..end, this));
            rest = next;
        }
        let listed: Vec<(Vec<u32>, Vec<bool>)> =
            stretches.into_par_iter().map(|(range, buffer)| list_block(&around, triangles, range, buffer)).collect();
        let mut offsets = Vec::with_capacity(vertices + 1);
        offsets.push(0);
        let mut neighbours = Vec::new();
        let mut border = Vec::with_capacity(vertices);
        let mut v = 0;
        for (counts, borders) in listed {
            for (count, b) in counts.into_iter().zip(borders) {
                let start = 2 * around.offsets[v];
                neighbours.extend_from_slice(&scratch[start..start + count as usize]);
                offsets.push(neighbours.len());
                border.push(b);
                v += 1;
            }
        }
        Adjacency { offsets, neighbours, border, around }
    }

    fn of(&self, v: usize) -> &[u32] {
        &self.neighbours[self.offsets[v]..self.offsets[v + 1]]
    }
}

impl Tiling {
    fn new(mesh: &Mesh) -> Tiling {
        Tiling { vertices: mesh.vertices.clone(), triangles: mesh.triangles.clone() }
    }

    /// Splits every edge longer than `limit` at its middle (each triangle into 2, 3 or 4);
    /// the number split.
    fn split_long(&mut self, limit: f32) -> usize {
        let mut middles: IntMap<u64, u32> = IntMap::default();
        let limit2 = limit * limit;
        for t in &self.triangles {
            for k in 0..3 {
                let (a, b) = (t[k], t[(k + 1) % 3]);
                let (pa, pb) = (self.vertices[a as usize], self.vertices[b as usize]);
                if pa.distance_squared(pb) > limit2 && !middles.contains_key(&key(a, b)) {
                    middles.insert(key(a, b), self.vertices.len() as u32);
                    self.vertices.push((pa + pb) / 2.0);
                }
            }
        }
        if middles.is_empty() {
            return 0;
        }
        let mut out = Vec::with_capacity(self.triangles.len() * 2);
        for &t in &self.triangles {
            let marks = [0, 1, 2].map(|k| middles.get(&key(t[k], t[(k + 1) % 3])).copied());
            self.split_triangle(t, marks, &mut out);
        }
        self.triangles = out;
        middles.len()
    }

    /// The triangles `t` becomes with the middles `marks[k]` of its edges `(t[k], t[k+1])`.
    fn split_triangle(&self, t: [u32; 3], marks: [Option<u32>; 3], out: &mut Vec<[u32; 3]>) {
        let count = marks.iter().flatten().count();
        let rotated = |r: usize| ([0, 1, 2].map(|k| t[(k + r) % 3]), [0, 1, 2].map(|k| marks[(k + r) % 3]));
        match count {
            0 => out.push(t),
            1 => {
                let r = marks.iter().position(Option::is_some).unwrap_or(0);
                let ([a, b, c], m) = rotated(r);
                let ab = m[0].unwrap_or(a);
                out.extend([[a, ab, c], [ab, b, c]]);
            }
            2 => {
                let unmarked = marks.iter().position(Option::is_none).unwrap_or(0);
                let ([a, b, c], m) = rotated((unmarked + 1) % 3);
                let (ab, bc) = (m[0].unwrap_or(a), m[1].unwrap_or(b));
                out.push([ab, b, bc]);
                let p = |i: u32| self.vertices[i as usize];
                if p(a).distance_squared(p(bc)) < p(ab).distance_squared(p(c)) {
                    out.extend([[a, ab, bc], [a, bc, c]]);
                } else {
                    out.extend([[a, ab, c], [ab, bc, c]]);
                }
            }
            _ => {
                let [a, b, c] = t;
                let [ab, bc, ca] = marks.map(|m| m.unwrap_or(a));
                out.extend([[a, ab, ca], [ab, b, bc], [ca, bc, c], [ab, bc, ca]]);
            }
        }
    }

    /// Collapses edges shorter than `low` into their middle where that keeps the surface a
    /// manifold, makes no edge longer than `high` and turns no triangle over; the number
    /// collapsed. Collapses in one pass touch disjoint neighbourhoods.
    fn collapse_short(&mut self, low: f32, high: f32) -> usize {
        let n = self.vertices.len();
        let adjacency = Adjacency::build(n, &self.triangles);
        let around = &adjacency.around;
        let vertices = &self.vertices;
        let mut short: Vec<(f32, u32, u32)> = (0..n)
            .into_par_iter()
            .flat_map_iter(|a| {
                adjacency.of(a).iter().filter_map(move |&b| {
                    let d = vertices[a].distance_squared(vertices[b as usize]);
                    ((a as u32) < b && d < low * low).then_some((d, a as u32, b))
                })
            })
            .collect();
        short.par_sort_unstable_by(|x, y| x.0.total_cmp(&y.0).then(x.1.cmp(&y.1)).then(x.2.cmp(&y.2)));
        let mut locked = vec![false; n];
        let mut into: Vec<u32> = (0..n as u32).collect();
        let mut collapsed = 0;
        for (_, a, b) in short {
            let (ua, ub) = (a as usize, b as usize);
            if locked[ua] || locked[ub] || adjacency.border[ua] || adjacency.border[ub] {
                continue;
            }
            let Some(p) = self.collapse_point(&adjacency, around, (a, b), high) else { continue };
            self.vertices[ua] = p;
            into[ub] = a;
            collapsed += 1;
            for &v in adjacency.of(ua).iter().chain(adjacency.of(ub)) {
                locked[v as usize] = true;
            }
            locked[ua] = true;
            locked[ub] = true;
        }
        if collapsed > 0 {
            let kept: Vec<[u32; 3]> = self
                .triangles
                .iter()
                .map(|t| t.map(|v| into[v as usize]))
                .filter(|&[a, b, c]| a != b && b != c && c != a)
                .collect();
            self.triangles = kept;
            self.drop_unused();
        }
        collapsed
    }

    /// Where edge `(a, b)` collapses to, if it may.
    fn collapse_point(&self, adjacency: &Adjacency, around: &Around, (a, b): (u32, u32), high: f32) -> Option<Vec3> {
        let (na, nb) = (adjacency.of(a as usize), adjacency.of(b as usize));
        if na.len() <= 3 || nb.len() <= 3 {
            return None;
        }
        let common = na.iter().filter(|v| nb.binary_search(v).is_ok()).count();
        if common != 2 {
            return None;
        }
        let p = (self.vertices[a as usize] + self.vertices[b as usize]) / 2.0;
        if na.iter().chain(nb).any(|&w| w != a && w != b && self.vertices[w as usize].distance(p) > high) {
            return None;
        }
        let kept_upright = around.of(a as usize).iter().chain(around.of(b as usize)).all(|&t| {
            let tri = self.triangles[t as usize];
            if tri.contains(&a) && tri.contains(&b) {
                return true;
            }
            let before = tri.map(|v| self.vertices[v as usize]);
            let after = tri.map(|v| if v == a || v == b { p } else { self.vertices[v as usize] });
            let (n0, n1) = (cross(before), cross(after));
            n1.dot(n0) > 0.1 * n0.length() * n1.length()
        });
        kept_upright.then_some(p)
    }

    /// Removes the vertices no triangle uses, keeping the others' order.
    fn drop_unused(&mut self) {
        let mut used = vec![false; self.vertices.len()];
        for t in &self.triangles {
            for &v in t {
                used[v as usize] = true;
            }
        }
        let mut new_index = vec![u32::MAX; self.vertices.len()];
        let mut kept = Vec::with_capacity(self.vertices.len());
        for (i, p) in self.vertices.iter().enumerate() {
            if used[i] {
                new_index[i] = kept.len() as u32;
                kept.push(*p);
            }
        }
        self.vertices = kept;
        for t in &mut self.triangles {
            *t = t.map(|v| new_index[v as usize]);
        }
    }

    /// Flips interior edges where that brings the four corners' valences closer to 6
    /// (4 on a border) and both new triangles face the way the old ones did.
    fn flip_for_valence(&mut self) -> usize {
        let n = self.vertices.len();
        let adjacency = Adjacency::build(n, &self.triangles);
        let mut valence: Vec<i32> = (0..n).map(|v| adjacency.of(v).len() as i32).collect();
        let target: Vec<i32> = adjacency.border.iter().map(|&b| if b { 4 } else { 6 }).collect();
        // the triangles as they were: a flip locks both its triangles, so a lookup that
        // finds one it changed skips it either way
        let before = self.triangles.clone();
        let around = &adjacency.around;
        let owner = |from: u32, to: u32| {
            let has = |t: &[u32; 3]| (0..3).any(|k| t[k] == from && t[(k + 1) % 3] == to);
            around.of(from as usize).iter().rev().copied().find(|&t| has(&before[t as usize]))
        };
        // edges flipped away (false) or into being (true) since `adjacency` was built
        let mut changed: IntMap<u64, bool> = IntMap::default();
        let is_edge = |changed: &IntMap<u64, bool>, a: u32, b: u32| match changed.get(&key(a, b)) {
            Some(now) => *now,
            None => adjacency.of(a as usize).binary_search(&b).is_ok(),
        };
        let mut locked = vec![false; self.triangles.len()];
        let mut flipped = 0;
        for i in 0..self.triangles.len() {
            for k in 0..3 {
                if locked[i] {
                    break;
                }
                let t = self.triangles[i];
                let (a, b, c) = (t[k], t[(k + 1) % 3], t[(k + 2) % 3]);
                let Some(j) = owner(b, a) else { continue };
                let j = j as usize;
                if a > b || locked[j] {
                    continue;
                }
                let other = self.triangles[j];
                let d = other.into_iter().find(|&v| v != a && v != b).unwrap_or(a);
                if d == a || c == d || is_edge(&changed, c, d) {
                    continue;
                }
                let [ua, ub, uc, ud] = [a, b, c, d].map(|v| v as usize);
                let dev = |v: usize, change: i32| (valence[v] + change - target[v]).abs();
                let before = dev(ua, 0) + dev(ub, 0) + dev(uc, 0) + dev(ud, 0);
                let after = dev(ua, -1) + dev(ub, -1) + dev(uc, 1) + dev(ud, 1);
                if after >= before || valence[ua] <= 3 || valence[ub] <= 3 || !self.flip_keeps_facing([a, b, c, d]) {
                    continue;
                }
                self.triangles[i] = [a, d, c];
                self.triangles[j] = [d, b, c];
                locked[i] = true;
                locked[j] = true;
                valence[ua] -= 1;
                valence[ub] -= 1;
                valence[uc] += 1;
                valence[ud] += 1;
                changed.insert(key(a, b), false);
                changed.insert(key(c, d), true);
                flipped += 1;
            }
        }
        flipped
    }

    /// Whether triangles `(a, b, c)` and `(b, a, d)` turned into `(a, d, c)` and `(d, b, c)`
    /// still face their common side.
    fn flip_keeps_facing(&self, [a, b, c, d]: [u32; 4]) -> bool {
        let p = |v: u32| self.vertices[v as usize];
        let old = cross([p(a), p(b), p(c)]) + cross([p(b), p(a), p(d)]);
        let (n1, n2) = (cross([p(a), p(d), p(c)]), cross([p(d), p(b), p(c)]));
        let fair = |n: Vec3| n.dot(old) > 0.2 * n.length() * old.length();
        fair(n1) && fair(n2)
    }

    /// Moves every point off a border to its neighbours' centroid within its tangent plane,
    /// then onto the input surface; all moves computed from the old positions.
    fn relax(&mut self, surface: &Surface) {
        let n = self.vertices.len();
        let adjacency = Adjacency::build(n, &self.triangles);
        let normals = vertex_normals(&self.vertices, &self.triangles);
        let old = &self.vertices;
        let moved: Vec<Vec3> = (0..n)
            .into_par_iter()
            .map(|v| {
                let around = adjacency.of(v);
                if adjacency.border[v] || around.is_empty() {
                    return old[v];
                }
                let centre = around.iter().map(|&w| old[w as usize]).sum::<Vec3>() / around.len() as f32;
                let normal = normals[v];
                let target = centre + normal * normal.dot(old[v] - centre);
                surface.closest_triangle(target).1
            })
            .collect();
        self.vertices = moved;
    }
}

/// The neighbours of the vertices `range` (sorted, each at the start of its stretch of
/// `buffer`, which begins at the first vertex's place: two corners per triangle around a
/// vertex), and per vertex their count and whether it lies on an open border.
fn list_block(
    around: &Around,
    triangles: &[[u32; 3]],
    range: std::ops::Range<usize>,
    buffer: &mut [u32],
) -> (Vec<u32>, Vec<bool>) {
    let (mut counts, mut borders) = (Vec::with_capacity(range.len()), Vec::with_capacity(range.len()));
    let first = 2 * around.offsets[range.start];
    for v in range {
        let start = 2 * around.offsets[v] - first;
        let mut at = start;
        for &t in around.of(v) {
            for w in triangles[t as usize].into_iter().filter(|&w| w != v as u32) {
                buffer[at] = w;
                at += 1;
            }
        }
        let others = &mut buffer[start..at];
        others.sort_unstable();
        let (mut unique, mut border, mut k) = (0, false, 0);
        while k < others.len() {
            let run = others[k..].iter().take_while(|&&w| w == others[k]).count();
            border |= run != 2;
            others[unique] = others[k];
            unique += 1;
            k += run;
        }
        counts.push(unique as u32);
        borders.push(border);
    }
    (counts, borders)
}

/// Each vertex's triangles.
struct Around {
    offsets: Vec<usize>,
    triangles: Vec<u32>,
}

impl Around {
    fn of(&self, v: usize) -> &[u32] {
        &self.triangles[self.offsets[v]..self.offsets[v + 1]]
    }
}

fn triangles_around(vertices: usize, triangles: &[[u32; 3]]) -> Around {
    let mut offsets = vec![0; vertices + 1];
    for t in triangles {
        for &v in t {
            offsets[v as usize + 1] += 1;
        }
    }
    for v in 0..vertices {
        offsets[v + 1] += offsets[v];
    }
    let mut fill = offsets.clone();
    let mut list = vec![0u32; offsets[vertices]];
    for (i, t) in triangles.iter().enumerate() {
        for &v in t {
            list[fill[v as usize]] = i as u32;
            fill[v as usize] += 1;
        }
    }
    Around { offsets, triangles: list }
}

/// Area-weighted vertex normals (unit; zero where no triangle has area).
pub fn vertex_normals(vertices: &[Vec3], triangles: &[[u32; 3]]) -> Vec<Vec3> {
    let mut normals = vec![Vec3::ZERO; vertices.len()];
    for t in triangles {
        let n = cross(t.map(|v| vertices[v as usize]));
        for &v in t {
            normals[v as usize] += n;
        }
    }
    normals.iter().map(|n| n.normalize_or_zero()).collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::mesh::shapes;
    use crate::progress::NoProgress;

    fn edge_lengths(mesh: &Mesh) -> Vec<f32> {
        let p = |v: u32| mesh.vertices[v as usize];
        mesh.triangles
            .iter()
            .flat_map(|&[a, b, c]| [p(a).distance(p(b)), p(b).distance(p(c)), p(c).distance(p(a))])
            .collect()
    }

    #[test]
    fn a_coarse_sphere_gets_the_points_asked_for_evenly_on_its_surface() {
        let sphere = shapes::ellipsoid(Vec3::ONE, 6, 8);
        let tiled = retile(&sphere, 3000, &NoProgress).unwrap();
        let count = tiled.vertices.len();
        assert!((2700..=3300).contains(&count), "{count} points for 3000");
        assert_eq!(tiled.boundary_edges(), 0);
        let edge = target_edge(area(&sphere), count);
        let lengths = edge_lengths(&tiled);
        let within = lengths.iter().filter(|&&l| l > 0.6 * edge && l < 1.45 * edge).count();
        assert!(within as f64 > 0.97 * lengths.len() as f64, "{within} of {} edges near {edge}", lengths.len());
        let surface = Surface::new(&sphere, 1.0);
        let off = tiled.vertices.iter().map(|p| p.distance(surface.closest_triangle(*p).1)).fold(0.0f32, f32::max);
        assert!(off < 1e-4, "a point {off} off the surface");
    }

    #[test]
    fn a_sliver_too_long_for_the_points_is_refused_before_it_fills_memory() {
        let sliver =
            Mesh::new(vec![Vec3::ZERO, Vec3::new(1e6, 0.0, 0.0), Vec3::new(0.0, 1e-4, 0.0)], vec![[0, 1, 2]]).unwrap();
        let err = retile(&sliver, 100, &NoProgress).unwrap_err().to_string();
        assert!(err.contains("too long and thin to tile with 100 points"), "{err}");
    }

    #[test]
    fn a_torus_keeps_its_genus_and_a_flat_square_its_border() {
        let torus = shapes::torus(1.0, 0.35, 24, 10);
        let tiled = retile(&torus, 2000, &NoProgress).unwrap();
        let euler = tiled.vertices.len() as i64 - (tiled.triangles.len() * 3 / 2) as i64 + tiled.triangles.len() as i64;
        assert_eq!(euler, 0, "a torus has Euler characteristic 0");
        let square =
            Mesh::new(vec![Vec3::ZERO, Vec3::X, Vec3::new(1.0, 1.0, 0.0), Vec3::Y], vec![[0, 1, 2], [0, 2, 3]])
                .unwrap();
        let tiled = retile(&square, 500, &NoProgress).unwrap();
        let (lo, hi) = tiled.bounds();
        assert_eq!((lo, hi), (Vec3::ZERO, Vec3::new(1.0, 1.0, 0.0)));
        assert!((area(&tiled) - 1.0).abs() < 1e-4);
    }
}
