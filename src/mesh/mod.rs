//! Triangle meshes (seed shapes for stamping, models to fill): validation, orientation,
//! inside tests and voxelization with anti-aliased coverage. Pure: loading is in `io`.
//!
//! [`voxelize`] samples every voxel on a `supersample`³ lattice of points at
//! `i + (s + 0.5) / supersample` and reports the inside fraction. It has two paths:
//!
//! - **closed meshes** (no boundary edges): ray parity along x. Triangles are bucketed by the
//!   sample rows their bounding box spans, each row is intersected with its triangles, the
//!   crossings are sorted and the spans between pairs are filled. The edge tests are
//!   watertight: an edge shared by two triangles is evaluated identically from both sides,
//!   and a sample exactly on an edge or a corner is treated as if moved by an infinitesimal
//!   `(0, ε, ε²)`, so a ray through a shared edge or corner is counted once. Parity does not
//!   care about orientation, so an inverted closed mesh gives the same coverage; where two
//!   closed parts overlap, they cancel.
//! - **open or non-manifold meshes**: the generalized winding number at every sample, inside
//!   when it exceeds 0.5 (after orienting by the sign of the volume). Summing a solid angle
//!   per triangle per sample would cost O(samples x triangles); instead the mesh is closed
//!   by a cone from one apex over its boundary edges. The closed mesh-minus-cone has an
//!   integer winding number, counted from signed crossings along the row exactly as above,
//!   and the cone adds its own winding number, one solid angle per boundary edge. So an open
//!   mesh costs O(samples x boundary edges) on top of the parity path: cheap for a few holes,
//!   slow for a triangle soup where every edge is a boundary edge.
//!
//! Both paths split the work by z-slice with rayon and collect in order, so the result does
//! not depend on the thread count.

use crate::error::{Error, Result};
use glam::{Affine3A, DVec3, Vec3};
use std::f64::consts::PI;

pub mod shapes;
pub mod split;
pub(crate) mod voxelize;
pub use voxelize::{Coverage, Slices, voxelize};

/// A triangle mesh: corner positions and index triples.
///
/// [`Mesh::new`] checks the invariants (at least one triangle, indices in range, finite
/// coordinates) and drops degenerate triangles. The fields are public for reading; the
/// methods panic if the fields are later edited to hold an index out of range.
#[derive(Debug, Clone, PartialEq)]
pub struct Mesh {
    /// Corner positions.
    pub vertices: Vec<Vec3>,
    /// Triangles as indices into `vertices`; counter-clockwise seen from outside once
    /// [`Mesh::oriented`].
    pub triangles: Vec<[u32; 3]>,
    dropped: usize,
}

impl Mesh {
    /// A checked mesh: at least one triangle, every index in range and every coordinate
    /// finite (the error names the first bad vertex and its value). Degenerate triangles
    /// (a repeated index, or exactly zero area) are dropped and counted in
    /// [`Mesh::dropped_degenerate`]; it is an error only when none remain.
    pub fn new(vertices: Vec<Vec3>, triangles: Vec<[u32; 3]>) -> Result<Mesh> {
        check_vertices(&vertices)?;
        check_indices(&triangles, vertices.len())?;
        let total = triangles.len();
        let kept: Vec<[u32; 3]> = triangles.into_iter().filter(|t| !is_degenerate(&vertices, *t)).collect();
        if kept.is_empty() {
            return Err(Error::invalid(format!(
                "all {total} triangle(s) of the mesh are degenerate (a repeated corner or zero area); none is left"
            )));
        }
        Ok(Mesh { vertices, dropped: total - kept.len(), triangles: kept })
    }

    /// The enclosed volume by the divergence theorem (sum of signed tetrahedra against the
    /// origin, in f64): positive when the triangles face outwards. For an open mesh the
    /// value depends on where the origin is.
    pub fn signed_volume(&self) -> f32 {
        let six: f64 = self.triangles.iter().map(|t| self.corners(*t)).map(|[a, b, c]| a.dot(b.cross(c))).sum();
        (six / 6.0) as f32
    }

    /// The same mesh with every triangle flipped when its signed volume is negative, so
    /// the triangles face outwards.
    pub fn oriented(self) -> Mesh {
        if self.signed_volume() < 0.0 { self.flipped() } else { self }
    }

    /// The mesh [`oriented`](Mesh::oriented) with every triangle's corners rotated so the
    /// smallest index comes first: a mesh and its inverted copy give identical triangles,
    /// so everything computed from them is bit-identical.
    pub fn canonical(self) -> Mesh {
        let mut mesh = self.oriented();
        for t in &mut mesh.triangles {
            let first = (0..3).min_by_key(|&k| t[k]).unwrap_or(0);
            t.rotate_left(first);
        }
        mesh
    }

    /// How many undirected edges are not shared by exactly two triangles: 0 for a closed
    /// mesh; open borders (one triangle) and non-manifold edges (three or more) count.
    pub fn boundary_edges(&self) -> usize {
        let (open, non_manifold) = self.unpaired_edges();
        open + non_manifold
    }

    /// How many undirected edges belong to one triangle only (open borders) and how many
    /// to more than two (non-manifold: faces touching along an edge, a duplicated face).
    pub fn unpaired_edges(&self) -> (usize, usize) {
        let mut edges: Vec<u64> =
            self.triangles.iter().flat_map(|&[a, b, c]| [edge_key(a, b), edge_key(b, c), edge_key(c, a)]).collect();
        edges.sort_unstable();
        let runs = edges.chunk_by(|x, y| x == y).map(<[u64]>::len);
        runs.fold((0, 0), |(open, more), n| (open + usize::from(n == 1), more + usize::from(n > 2)))
    }

    /// How many degenerate triangles [`Mesh::new`] dropped.
    pub fn dropped_degenerate(&self) -> usize {
        self.dropped
    }

    /// The axis-aligned bounding box `(min, max)` of the vertices the triangles use.
    pub fn bounds(&self) -> (Vec3, Vec3) {
        self.triangles
            .iter()
            .flatten()
            .map(|&i| self.vertices[i as usize])
            .fold((Vec3::INFINITY, Vec3::NEG_INFINITY), |(lo, hi), v| (lo.min(v), hi.max(v)))
    }

    /// The mesh moved by `m`. A mirroring transform (negative determinant) also flips every
    /// triangle, so an outward-facing mesh stays outward-facing. Nothing is re-checked: a
    /// singular transform leaves flat triangles, which cover no samples in [`voxelize`].
    pub fn transformed(&self, m: Affine3A) -> Mesh {
        let vertices = self.vertices.iter().map(|v| m.transform_point3(*v)).collect();
        let mesh = Mesh { vertices, triangles: self.triangles.clone(), dropped: self.dropped };
        if m.matrix3.determinant() < 0.0 { mesh.flipped() } else { mesh }
    }

    /// The generalized winding number at `p`: the sum of the triangles' signed solid angles
    /// over 4π. About 1 inside and 0 outside an outward-facing closed mesh (-1 inside an
    /// inverted one); for an open mesh it varies smoothly across the holes.
    pub fn winding_number(&self, p: Vec3) -> f32 {
        self.winding(p.as_dvec3()) as f32
    }

    /// Whether `p` is inside: winding number above 0.5.
    pub fn contains(&self, p: Vec3) -> bool {
        self.winding(p.as_dvec3()) > 0.5
    }

    fn winding(&self, p: DVec3) -> f64 {
        let total: f64 = self.triangles.iter().map(|t| solid_angle(self.corners(*t), p)).sum();
        total / (4.0 * PI)
    }

    fn corners(&self, [a, b, c]: [u32; 3]) -> [DVec3; 3] {
        [a, b, c].map(|i| self.vertices[i as usize].as_dvec3())
    }

    fn flipped(mut self) -> Mesh {
        for t in &mut self.triangles {
            t.swap(1, 2);
        }
        self
    }
}

fn check_vertices(vertices: &[Vec3]) -> Result<()> {
    match vertices.iter().position(|v| !v.is_finite()) {
        Some(i) => {
            let v = vertices[i];
            Err(Error::invalid(format!(
                "vertex {i} (counting from 0) is ({}, {}, {}); every coordinate must be finite (no NaN or infinity)",
                v.x, v.y, v.z
            )))
        }
        None => Ok(()),
    }
}

fn check_indices(triangles: &[[u32; 3]], vertex_count: usize) -> Result<()> {
    if triangles.is_empty() {
        return Err(Error::invalid("the mesh has no triangles; at least one is needed"));
    }
    for (t, corners) in triangles.iter().enumerate() {
        if let Some(&i) = corners.iter().find(|&&i| i as usize >= vertex_count) {
            let allowed = match vertex_count {
                0 => "there are no vertices".to_string(),
                n => format!("allowed are 0..={}", n - 1),
            };
            return Err(Error::invalid(format!("triangle {t} uses vertex index {i} (counting from 0), but {allowed}")));
        }
    }
    Ok(())
}

fn is_degenerate(vertices: &[Vec3], [a, b, c]: [u32; 3]) -> bool {
    if a == b || b == c || c == a {
        return true;
    }
    let [a, b, c] = [a, b, c].map(|i| vertices[i as usize].as_dvec3());
    (b - a).cross(c - a) == DVec3::ZERO
}

fn edge_key(a: u32, b: u32) -> u64 {
    (u64::from(a.min(b)) << 32) | u64::from(a.max(b))
}

/// The signed solid angle of triangle `[a, b, c]` seen from `p` (Van Oosterom and Strackee).
fn solid_angle([a, b, c]: [DVec3; 3], p: DVec3) -> f64 {
    let (a, b, c) = (a - p, b - p, c - p);
    let (la, lb, lc) = (a.length(), b.length(), c.length());
    let det = a.dot(b.cross(c));
    let div = la * lb * lc + a.dot(b) * lc + a.dot(c) * lb + b.dot(c) * la;
    2.0 * det.atan2(div)
}

/// The point of the segment `a`-`b` closest to `p` (`a` when the segment has no length).
pub fn closest_on_segment(p: Vec3, a: Vec3, b: Vec3) -> Vec3 {
    let d = b - a;
    a + d * ((p - a).dot(d) / d.length_squared().max(f32::MIN_POSITIVE)).clamp(0.0, 1.0)
}

/// The closest points of segments `p1`-`q1` and `p2`-`q2`, one on each (Ericson, Real-Time
/// Collision Detection, 5.1.9); a segment may be a point.
pub fn closest_between_segments([p1, q1]: [Vec3; 2], [p2, q2]: [Vec3; 2]) -> (Vec3, Vec3) {
    let (d1, d2, r) = (q1 - p1, q2 - p2, p1 - p2);
    let (a, e, f) = (d1.dot(d1), d2.dot(d2), d2.dot(r));
    let tiny = 1e-12;
    let (s, t) = if a <= tiny && e <= tiny {
        (0.0, 0.0)
    } else if a <= tiny {
        (0.0, (f / e).clamp(0.0, 1.0))
    } else {
        let c = d1.dot(r);
        if e <= tiny {
            ((-c / a).clamp(0.0, 1.0), 0.0)
        } else {
            let b = d1.dot(d2);
            let denom = a * e - b * b;
            let mut s = if denom > tiny { ((b * f - c * e) / denom).clamp(0.0, 1.0) } else { 0.0 };
            let mut t = (b * s + f) / e;
            if t < 0.0 {
                t = 0.0;
                s = (-c / a).clamp(0.0, 1.0);
            } else if t > 1.0 {
                t = 1.0;
                s = ((b - c) / a).clamp(0.0, 1.0);
            }
            (s, t)
        }
    };
    (p1 + d1 * s, p2 + d2 * t)
}

/// The point of triangle `[a, b, c]` closest to `p` (Ericson, Real-Time Collision
/// Detection 5.1.5).
pub fn closest_on_triangle(p: Vec3, [a, b, c]: [Vec3; 3]) -> Vec3 {
    let (ab, ac, ap) = (b - a, c - a, p - a);
    let (d1, d2) = (ab.dot(ap), ac.dot(ap));
    if d1 <= 0.0 && d2 <= 0.0 {
        return a;
    }
    let bp = p - b;
    let (d3, d4) = (ab.dot(bp), ac.dot(bp));
    if d3 >= 0.0 && d4 <= d3 {
        return b;
    }
    let vc = d1 * d4 - d3 * d2;
    if vc <= 0.0 && d1 >= 0.0 && d3 <= 0.0 {
        return a + ab * (d1 / (d1 - d3));
    }
    let cp = p - c;
    let (d5, d6) = (ab.dot(cp), ac.dot(cp));
    if d6 >= 0.0 && d5 <= d6 {
        return c;
    }
    let vb = d5 * d2 - d1 * d6;
    if vb <= 0.0 && d2 >= 0.0 && d6 <= 0.0 {
        return a + ac * (d2 / (d2 - d6));
    }
    let va = d3 * d6 - d5 * d4;
    if va <= 0.0 && (d4 - d3) >= 0.0 && (d5 - d6) >= 0.0 {
        return b + (c - b) * ((d4 - d3) / ((d4 - d3) + (d5 - d6)));
    }
    let denom = 1.0 / (va + vb + vc);
    a + ab * (vb * denom) + ac * (vc * denom)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// An outward-facing axis-aligned box from `lo` to `hi`.
    fn cuboid(lo: Vec3, hi: Vec3) -> Mesh {
        let v = (0..8)
            .map(|i| {
                Vec3::new(
                    if i & 1 == 0 { lo.x } else { hi.x },
                    if i & 2 == 0 { lo.y } else { hi.y },
                    if i & 4 == 0 { lo.z } else { hi.z },
                )
            })
            .collect();
        let quads = [[0, 2, 3, 1], [4, 5, 7, 6], [0, 1, 5, 4], [2, 6, 7, 3], [0, 4, 6, 2], [1, 3, 7, 5]];
        let t = quads.iter().flat_map(|&[a, b, c, d]| [[a, b, c], [a, c, d]]).collect();
        Mesh::new(v, t).unwrap()
    }

    fn unit_cube() -> Mesh {
        cuboid(Vec3::ZERO, Vec3::ONE)
    }

    /// An octahedron-based sphere: subdivided `level` times and pushed onto the sphere.
    fn ball(center: Vec3, radius: f32, level: usize) -> Mesh {
        let mut v: Vec<Vec3> = vec![Vec3::X, -Vec3::X, Vec3::Y, -Vec3::Y, Vec3::Z, -Vec3::Z];
        let mut t: Vec<[u32; 3]> =
            vec![[0, 2, 4], [2, 1, 4], [1, 3, 4], [3, 0, 4], [2, 0, 5], [1, 2, 5], [3, 1, 5], [0, 3, 5]];
        for _ in 0..level {
            let mut next = Vec::new();
            let mut mids = std::collections::BTreeMap::new();
            let mut mid = |a: u32, b: u32, v: &mut Vec<Vec3>| {
                *mids.entry(edge_key(a, b)).or_insert_with(|| {
                    v.push(((v[a as usize] + v[b as usize]) / 2.0).normalize());
                    v.len() as u32 - 1
                })
            };
            for [a, b, c] in t {
                let (ab, bc, ca) = (mid(a, b, &mut v), mid(b, c, &mut v), mid(c, a, &mut v));
                next.extend([[a, ab, ca], [ab, b, bc], [ca, bc, c], [ab, bc, ca]]);
            }
            t = next;
        }
        let v = v.into_iter().map(|p| center + p * radius).collect();
        Mesh::new(v, t).unwrap()
    }

    #[test]
    fn new_rejects_bad_meshes_with_the_culprit_named() {
        let v = vec![Vec3::ZERO, Vec3::X, Vec3::Y];
        let err = Mesh::new(v.clone(), vec![]).unwrap_err().to_string();
        assert!(err.contains("no triangles"), "{err}");
        let err = Mesh::new(v.clone(), vec![[0, 1, 3]]).unwrap_err().to_string();
        assert!(err.contains("triangle 0") && err.contains("index 3") && err.contains("0..=2"), "{err}");
        let mut bad = v.clone();
        bad[1].y = f32::NAN;
        let err = Mesh::new(bad, vec![[0, 1, 2]]).unwrap_err().to_string();
        assert!(err.contains("vertex 1") && err.contains("NaN"), "{err}");
        let err = Mesh::new(v, vec![[0, 0, 1]]).unwrap_err().to_string();
        assert!(err.contains("degenerate"), "{err}");
    }

    #[test]
    fn degenerate_triangles_are_dropped_and_counted() {
        let v = vec![Vec3::ZERO, Vec3::X, Vec3::Y, Vec3::X * 2.0];
        let m = Mesh::new(v, vec![[0, 1, 2], [0, 0, 2], [0, 1, 3]]).unwrap();
        assert_eq!(m.triangles, vec![[0, 1, 2]]);
        assert_eq!(m.dropped_degenerate(), 2);
    }

    #[test]
    fn volume_orientation_and_mirroring() {
        let cube = unit_cube();
        assert!((cube.signed_volume() - 1.0).abs() < 1e-6);
        assert_eq!(cube.boundary_edges(), 0);
        let inverted = cube.clone().flipped();
        assert!((inverted.signed_volume() + 1.0).abs() < 1e-6);
        assert_eq!(inverted.oriented(), cube);
        let mirror = Affine3A::from_scale(Vec3::new(-2.0, 1.0, 1.0));
        assert!((cube.transformed(mirror).signed_volume() - 2.0).abs() < 1e-6);
        assert_eq!(cube.bounds(), (Vec3::ZERO, Vec3::ONE));
    }

    #[test]
    fn boundary_edges_count_open_and_non_manifold_edges() {
        let mut cube = unit_cube();
        cube.triangles.pop();
        assert_eq!(cube.boundary_edges(), 3);
        let fin =
            Mesh::new(vec![Vec3::ZERO, Vec3::X, Vec3::Y, Vec3::Z, -Vec3::Y], vec![[0, 1, 2], [0, 1, 3], [0, 1, 4]])
                .unwrap();
        assert_eq!(fin.boundary_edges(), 7);
        assert_eq!(fin.unpaired_edges(), (6, 1));
        assert_eq!(cube.unpaired_edges(), (3, 0));
    }

    #[test]
    fn winding_number_is_one_inside_zero_outside_and_minus_one_inverted() {
        let cube = unit_cube();
        assert!((cube.winding_number(Vec3::splat(0.3)) - 1.0).abs() < 1e-5);
        assert!(cube.winding_number(Vec3::splat(1.7)).abs() < 1e-5);
        assert!(cube.contains(Vec3::splat(0.5)) && !cube.contains(Vec3::new(0.5, 0.5, 1.5)));
        assert!((cube.flipped().winding_number(Vec3::splat(0.5)) + 1.0).abs() < 1e-5);
    }

    #[test]
    fn a_box_on_voxel_boundaries_is_covered_exactly_despite_rays_on_its_diagonals() {
        let cover = voxelize(&cuboid(Vec3::splat(2.0), Vec3::splat(6.0)), [10, 10, 10], 4);
        assert_eq!((cover.origin, cover.dims), ([2; 3], [4; 3]));
        assert!(cover.alpha.iter().all(|&a| a == 1.0));
        assert_eq!(cover.at(5, 5, 5), 1.0);
        assert_eq!(cover.at(6, 5, 5), 0.0);
    }

    #[test]
    fn a_box_with_faces_on_sample_rows_covers_its_exact_volume() {
        let cover = voxelize(&cuboid(Vec3::splat(2.125), Vec3::splat(5.125)), [10, 10, 10], 4);
        // Samples on the low faces count as inside, those on the high faces as outside.
        assert_eq!(cover.volume(), 27.0);
        assert_eq!((cover.at(2, 2, 2), cover.at(4, 4, 4), cover.at(5, 5, 5)), (1.0, 1.0, 0.0));
    }

    #[test]
    fn parity_agrees_with_the_winding_number_on_a_ball() {
        let ball = ball(Vec3::new(8.3, 7.9, 8.1), 5.5, 3);
        let cover = voxelize(&ball, [16, 16, 16], 1);
        for z in 0..16 {
            for y in 0..16 {
                for x in 0..16 {
                    let centre = Vec3::new(x as f32, y as f32, z as f32) + 0.5;
                    assert_eq!(cover.at(x, y, z) == 1.0, ball.contains(centre), "voxel {x} {y} {z}");
                }
            }
        }
    }

    #[test]
    fn open_meshes_use_the_winding_number_and_inversion_does_not_matter() {
        let ball = ball(Vec3::splat(4.0), 3.0, 2);
        let closed = voxelize(&ball, [8, 8, 8], 2);
        let mut open = ball.clone().flipped();
        open.triangles.truncate(open.triangles.len() - 1);
        assert!(open.boundary_edges() > 0);
        let cover = voxelize(&open, [8, 8, 8], 2);
        assert_eq!((cover.origin, cover.dims), (closed.origin, closed.dims));
        let diff: f64 = cover.alpha.iter().zip(&closed.alpha).map(|(a, b)| f64::from((a - b).abs())).sum();
        assert!(diff < 2.0, "open and closed differ by {diff} voxels");
    }

    #[test]
    fn the_open_path_matches_the_winding_number_at_every_sample() {
        // A bowl (a ball without its top) and the same bowl mirrored: big holes, both ways round.
        let ball = ball(Vec3::new(6.3, 5.8, 6.1), 4.6, 3);
        let rim = 6.1 + 2.0;
        let bowl: Vec<[u32; 3]> = ball
            .triangles
            .iter()
            .copied()
            .filter(|t| t.iter().map(|&i| ball.vertices[i as usize].z).sum::<f32>() / 3.0 < rim)
            .collect();
        let bowl = Mesh::new(ball.vertices.clone(), bowl).unwrap();
        assert!(bowl.boundary_edges() > 10);
        let centre = Affine3A::from_translation(Vec3::new(6.3, 5.8, 6.1));
        let mirror = centre * Affine3A::from_scale(Vec3::new(1.0, -1.0, 1.0)) * centre.inverse();
        for mesh in [bowl.clone(), bowl.transformed(mirror), bowl.clone().flipped()] {
            let mesh = mesh.transformed(Affine3A::from_translation(Vec3::new(0.4, 1.5, 0.2)));
            let sign = if mesh.signed_volume() < 0.0 { -1.0 } else { 1.0 };
            let cover = voxelize(&mesh, [14, 14, 14], 1);
            let mut inside = 0;
            for z in 0..14 {
                for y in 0..14 {
                    for x in 0..14 {
                        let w = mesh.winding_number(Vec3::new(x as f32, y as f32, z as f32) + 0.5) * sign;
                        assert_eq!(cover.at(x, y, z) == 1.0, w > 0.5, "voxel {x} {y} {z}: winding {w}");
                        inside += usize::from(w > 0.5);
                    }
                }
            }
            assert!(inside > 100, "{inside}");
        }
    }

    #[test]
    fn clipping_and_missing_the_grid() {
        let cube = cuboid(Vec3::splat(-2.0), Vec3::splat(3.0));
        let cover = voxelize(&cube, [2, 8, 8], 2);
        assert_eq!((cover.origin, cover.dims), ([0; 3], [2, 3, 3]));
        assert!(cover.alpha.iter().all(|&a| a == 1.0));
        let far = cube.transformed(Affine3A::from_translation(Vec3::splat(100.0)));
        let cover = voxelize(&far, [8, 8, 8], 2);
        assert!(cover.is_empty() && cover.dims == [0; 3]);
    }

    #[test]
    fn the_result_does_not_depend_on_the_thread_count() {
        let ball = ball(Vec3::new(6.2, 5.9, 6.4), 4.7, 3);
        let run = |threads| {
            let pool = rayon::ThreadPoolBuilder::new().num_threads(threads).build().unwrap();
            pool.install(|| voxelize(&ball, [12, 12, 12], 3))
        };
        let one = run(1);
        assert_eq!(one, run(3));
        assert!(one.alpha.iter().all(|a| (0.0..=1.0).contains(a)));
    }
}
