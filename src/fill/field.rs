//! The tensor field that orients and scales the pasted patches (thesis §6.2.2).
//!
//! ```text
//!  type   primary axis R         secondary S            scale            depth kept
//!  0      random per patch       random per patch       user             no
//!  1-a    strokes, smoothed      random about R         user             no
//!  1-b    grad depth             random about R         1/|grad depth|   yes
//!  2-a    grad depth             strokes on layers      user             no
//!  2-b    grad depth             strokes on layers      1/|grad depth|   yes
//! ```
//! Strokes and scales are interpolated by Laplacian smoothing with soft constraints (a
//! sparse least-squares solve; weights 1/|N_i|, or depth-aware for the secondary direction
//! of 2-a/2-b, which is then made orthogonal to the depth gradient). The depth field is a
//! thin-plate RBF (kernel |r| in 3D, plus a linear term) through the depth constraints.
//! A tet's tensor is the mean of its vertices'.

use super::mesher::closest::Surface;
use super::patch::orthogonal;
use super::solve::{Sparse, dense_solve, least_squares, least_squares_each};
use super::tets::{EDGES, TetGrid, TetMesh};
use crate::TextureType;
use crate::error::{Error, Result};
use crate::mesh::Mesh;
use glam::{DVec3, Vec3};
use rayon::prelude::*;

/// Weight of a constraint row against the smoothing rows.
const CONSTRAINT_WEIGHT: f64 = 10.0;
/// Most RBF centres used; more constraints are thinned evenly.
const MAX_CENTRES: usize = 900;

/// What the user asked for, in model space.
#[derive(Debug, Clone, Default)]
pub struct Constraints {
    /// (point, direction): the fibre axis for 1-a, the secondary direction for 2-a/2-b.
    pub directions: Vec<(Vec3, Vec3)>,
    /// (point, depth) for the RBF: 0 on the outer surface, 1 on the innermost part.
    pub depth: Vec<(Vec3, f32)>,
    /// Per triangle of the filled surface: the depth it holds (`None`: free). The tet
    /// mesh's boundary vertices take the value of the triangle closest to them.
    pub surface_values: Vec<Option<f32>>,
    /// (point, texture scale): the side of the texture cube in model units.
    pub scales: Vec<(Vec3, f32)>,
    /// The scale where no scale constraint says otherwise.
    pub scale: f32,
}

/// The field over a tet mesh.
#[derive(Debug, Clone)]
pub struct Field {
    /// The depth at each vertex, for the depth-varying types (1-b, 2-b).
    pub depth: Option<Vec<f32>>,
    /// Per tet, with `depth`: how far the smooth depth at the middle of each of its
    /// [`EDGES`] lies from the mean of the edge's ends ([`bump`]).
    pub bumps: Option<Vec<[f32; 6]>>,
    /// Per tet: the unit primary direction (zero for type 0).
    pub primary: Vec<Vec3>,
    /// Per tet: the unit secondary direction, orthogonal to the primary (zero when random).
    pub secondary: Vec<Vec3>,
    /// Per tet: the texture scale (side of the texture cube in model units).
    pub scale: Vec<f32>,
}

/// Builds the field for `kind` over `mesh` (a tetrahedralization of `surface`, whose
/// triangles `constraints.surface_values` describe) from `constraints`.
pub fn build(mesh: &TetMesh, kind: TextureType, constraints: &Constraints, surface: Option<&Mesh>) -> Result<Field> {
    check_required(kind, constraints)?;
    let tets = mesh.tets.len();
    let uses_depth = super::uses_depth(kind);
    let rbf = if uses_depth { Some(Rbf::fit(&constraints.depth)?) } else { None };
    let raw: Option<Vec<f32>> = rbf.as_ref().map(|f| mesh.vertices.par_iter().map(|v| f.value(*v)).collect());
    // the pinning's solve runs on one core at a time: the gradients use the other
    let (depth, gradients) = rayon::join(
        || {
            let mut depth = raw.clone();
            if let (Some(d), Some(surface)) = (depth.as_mut(), surface) {
                pin_surface(mesh, surface, &constraints.surface_values, d);
            }
            depth
        },
        || rbf.as_ref().map(|f| (0..tets).into_par_iter().map(|t| f.gradient(mesh.centroid(t))).collect::<Vec<Vec3>>()),
    );
    let primary: Vec<Vec3> = match (kind, &gradients) {
        (TextureType::T1a, _) => per_tet(mesh, &smooth_vectors(mesh, &constraints.directions, None)?),
        (_, Some(g)) => g.iter().map(|g| g.normalize_or(Vec3::Y)).collect(),
        _ => vec![Vec3::ZERO; tets],
    };
    let layered = matches!(kind, TextureType::T1b | TextureType::T2b);
    // the same for the secondary directions' solve and the depth bumps
    let (directions, bumps) = rayon::join(
        || -> Result<(Vec<Vec3>, Vec<f32>)> {
            let secondary = match kind {
                TextureType::T2a | TextureType::T2b => {
                    let smoothed = smooth_vectors(mesh, &constraints.directions, depth.as_deref())?;
                    per_tet(mesh, &smoothed).iter().zip(&primary).map(|(s, r)| orthogonal(*s, *r)).collect()
                }
                _ => vec![Vec3::ZERO; tets],
            };
            let scale = match (layered, &gradients) {
                (true, Some(g)) => g.iter().map(|g| 1.0 / g.length().max(1e-6)).collect(),
                _ => smooth_scales(mesh, constraints)?,
            };
            Ok((secondary, scale))
        },
        || match (&rbf, &raw, &depth) {
            (Some(f), Some(raw), Some(d)) if layered => Some(depth_bumps(mesh, f, raw, d)),
            _ => None,
        },
    );
    let (secondary, scale) = directions?;
    let depth = if layered { depth } else { None };
    Ok(Field { depth, bumps, primary, secondary, scale })
}

fn check_required(kind: TextureType, c: &Constraints) -> Result<()> {
    let needs = |what: &str| Err(Error::invalid(format!("texture type {kind} needs {what} in the fill spec")));
    match kind {
        TextureType::T2c | TextureType::T2d => Err(Error::invalid(format!(
            "texture type {kind} cannot be filled: it varies along more axes than lapped patches can follow \
             (copies of its one-of-a-kind parts would land all over the model; see docs/fill.md); \
             allowed: 0, 1-a, 1-b, 2-a, 2-b"
        ))),
        TextureType::T1a if c.directions.is_empty() => needs("at least one direction stroke ([[direction]])"),
        TextureType::T2a | TextureType::T2b if c.directions.is_empty() => {
            needs("a direction stroke for the secondary direction ([[direction]], e.g. along the fruit axis)")
        }
        TextureType::T1b | TextureType::T2a | TextureType::T2b if !c.depth.iter().any(|d| d.1 > 0.0) => {
            needs("a depth constraint above 0 ([depth] axis, points or a face group)")
        }
        _ if !(c.scale.is_finite() && c.scale > 0.0) => {
            Err(Error::invalid(format!("scale {} must be a positive number of model units", c.scale)))
        }
        _ => Ok(()),
    }
}

/// Holds every boundary vertex of the tet mesh at the depth of the surface triangle closest
/// to it (the RBF meets the surface only at its samples, so between them, on a coarse
/// triangulation, the depth rose above 0 and the skin went missing), and carries the
/// change smoothly inward: the correction is harmonic inside (Laplacian smoothing) and
/// exact at the pinned vertices.
fn pin_surface(mesh: &TetMesh, surface: &Mesh, values: &[Option<f32>], depth: &mut [f32]) {
    if values.len() != surface.triangles.len() || values.iter().all(Option::is_none) {
        return;
    }
    let grid = Surface::new(surface, super::mean_edge(mesh));
    let mut boundary: Vec<u32> = mesh.boundary_faces(&mesh.neighbours()).into_iter().flatten().collect();
    boundary.sort_unstable();
    boundary.dedup();
    let pins: Vec<(usize, f32)> = boundary
        .par_iter()
        .filter_map(|&v| {
            let (t, _) = grid.closest_triangle(mesh.vertices[v as usize]);
            values[t].map(|d| (v as usize, d))
        })
        .collect();
    if pins.is_empty() {
        return;
    }
    let mut a = Smoothing::new(mesh, None).rows;
    let mut b = vec![0.0; mesh.vertices.len()];
    for &(v, d) in &pins {
        a.push_row(std::iter::once((v, CONSTRAINT_WEIGHT)));
        b.push(CONSTRAINT_WEIGHT * (d - depth[v]) as f64);
    }
    let mut correction = vec![0.0; mesh.vertices.len()];
    least_squares(&a, &b, &mut correction, 1e-7, 4000);
    for (d, c) in depth.iter_mut().zip(&correction) {
        *d = (*d as f64 + c).clamp(0.0, 1.0) as f32;
    }
    for (v, d) in pins {
        depth[v] = d;
    }
}

/// The depth at barycentric point `b` of a tet beyond the linear interpolation of its
/// corners' depths: the quadratic (10-node) tet's term, 4 Σ bᵢbⱼ eᵢⱼ over its `edges`.
/// Zero at the corners, `e` at an edge's middle, and the same on a face for both tets
/// that share it, so the depth stays continuous.
pub fn bump(edges: &[f32; 6], b: [f32; 4]) -> f32 {
    4.0 * EDGES.iter().zip(edges).map(|(&(i, j), e)| b[i] * b[j] * e).sum::<f32>()
}

/// Per tet, the smooth depth's [`bump`] at each edge's middle: the RBF there plus the mean
/// of its ends' pinning corrections (`depth` − `raw`), less the mean of the ends' depths.
/// Linear interpolation over lattice-sized tets drew a 2-b axis's pith as a square and its
/// rings as polygons zigzagging with the lattice's period; the quadratic term follows the
/// RBF's curvature inside each tet. An edge's middle is computed from its ends in index
/// order, so both tets of a face get the same bits.
fn depth_bumps(mesh: &TetMesh, rbf: &Rbf, raw: &[f32], depth: &[f32]) -> Vec<[f32; 6]> {
    let mut edges: Vec<(u32, u32)> =
        mesh.tets.iter().flat_map(|t| EDGES.map(|(i, j)| (t[i].min(t[j]), t[i].max(t[j])))).collect();
    edges.par_sort_unstable();
    edges.dedup();
    let middles: Vec<f32> = edges
        .par_iter()
        .map(|&(a, b)| {
            let (a, b) = (a as usize, b as usize);
            let middle = (mesh.vertices[a] + mesh.vertices[b]) * 0.5;
            let correction = (depth[a] - raw[a] + depth[b] - raw[b]) * 0.5;
            (rbf.value(middle) + correction).clamp(0.0, 1.0) - (depth[a] + depth[b]) * 0.5
        })
        .collect();
    mesh.tets
        .par_iter()
        .map(|t| {
            EDGES.map(|(i, j)| {
                let key = (t[i].min(t[j]), t[i].max(t[j]));
                edges.binary_search(&key).map_or(0.0, |k| middles[k])
            })
        })
        .collect()
}

/// The mean of each tet's vertex vectors, normalized.
fn per_tet(mesh: &TetMesh, at_vertices: &[Vec3]) -> Vec<Vec3> {
    let mean = |tet: &[u32; 4]| tet.iter().map(|&v| at_vertices[v as usize]).sum::<Vec3>();
    mesh.tets.iter().map(|t| mean(t).normalize_or(Vec3::Y)).collect()
}

/// Laplacian smoothing of the three components of `directions`, then normalized.
fn smooth_vectors(mesh: &TetMesh, directions: &[(Vec3, Vec3)], depth: Option<&[f32]>) -> Result<Vec<Vec3>> {
    let points: Vec<(Vec3, [f32; 3])> =
        directions.iter().map(|(p, d)| (*p, d.normalize_or_zero().to_array())).collect();
    let solved = smooth(mesh, depth, &points)?;
    Ok((0..mesh.vertices.len())
        .map(|v| glam::DVec3::from_slice(&solved[v * 3..v * 3 + 3]).as_vec3().normalize_or(Vec3::Y))
        .collect())
}

/// `K` values per vertex of `mesh`, as smooth as the uniform Laplacian allows while meeting
/// the values at `points` (soft constraints, interpolated in the tet holding each point).
pub fn smooth_at_vertices<const K: usize>(mesh: &TetMesh, points: &[(Vec3, [f32; K])]) -> Result<Vec<f64>> {
    smooth(mesh, None, points)
}

/// [`Smoothing::solve`] over `mesh` (weighted by `depth` if given). Points that all hold
/// one value give it at every vertex without a solve: a constant meets every constraint
/// and is as smooth as can be (the solve starts there and stops at once).
fn smooth<const K: usize>(mesh: &TetMesh, depth: Option<&[f32]>, points: &[(Vec3, [f32; K])]) -> Result<Vec<f64>> {
    if let Some((_, first)) = points.first().filter(|_| points.iter().all(|p| p.1 == points[0].1)) {
        let value = first.map(f64::from);
        return Ok((0..mesh.vertices.len()).flat_map(|_| value).collect());
    }
    Smoothing::new(mesh, depth).solve(mesh, points)
}

/// Laplacian smoothing of the scale constraints; the default scale where there are none.
fn smooth_scales(mesh: &TetMesh, c: &Constraints) -> Result<Vec<f32>> {
    if c.scales.is_empty() {
        return Ok(vec![c.scale; mesh.tets.len()]);
    }
    if let Some((p, s)) = c.scales.iter().find(|(_, s)| !(s.is_finite() && *s > 0.0)) {
        return Err(Error::invalid(format!("scale {s} at {p} must be a positive number of model units")));
    }
    let points: Vec<(Vec3, [f32; 1])> = c.scales.iter().map(|(p, s)| (*p, [*s])).collect();
    let at_vertices = smooth(mesh, None, &points)?;
    Ok(mesh.tets.iter().map(|t| t.iter().map(|&v| at_vertices[v as usize] as f32).sum::<f32>() / 4.0).collect())
}

/// The smoothing rows `x_i - Σ w_ij x_j` of a tet mesh.
struct Smoothing {
    rows: Sparse,
}

impl Smoothing {
    fn new(mesh: &TetMesh, depth: Option<&[f32]>) -> Smoothing {
        let (offsets, ring) = mesh.one_rings();
        let spread = depth.map(|d| edge_spread(&offsets, &ring, d));
        let mut rows = Sparse::new(mesh.vertices.len());
        for v in 0..mesh.vertices.len() {
            let ring = &ring[offsets[v]..offsets[v + 1]];
            let weights: Vec<f64> = match (depth, spread) {
                (Some(d), Some(s)) => {
                    ring.iter().map(|&j| (-((d[v] - d[j as usize]) as f64 / s).powi(2)).exp()).collect()
                }
                _ => vec![1.0; ring.len()],
            };
            let total: f64 = weights.iter().sum::<f64>().max(f64::MIN_POSITIVE);
            let entries = ring.iter().zip(&weights).map(|(&j, w)| (j as usize, -w / total));
            rows.push_row(std::iter::once((v, 1.0)).chain(entries));
        }
        Smoothing { rows }
    }

    /// Solves for `K` values per vertex that are smooth and meet `points` softly.
    fn solve<const K: usize>(&self, mesh: &TetMesh, points: &[(Vec3, [f32; K])]) -> Result<Vec<f64>> {
        let n = mesh.vertices.len();
        let mut a = self.rows.clone();
        let mut targets: Vec<[f64; K]> = vec![[0.0; K]; n];
        let places: Vec<Vec3> = points.iter().map(|(p, _)| *p).collect();
        for ((_, value), (t, bary)) in points.iter().zip(locate_each(mesh, &places)) {
            a.push_row(mesh.tets[t].iter().zip(bary).map(|(&v, b)| (v as usize, CONSTRAINT_WEIGHT * b as f64)));
            targets.push(value.map(|x| CONSTRAINT_WEIGHT * x as f64));
        }
        let mean: [f64; K] =
            std::array::from_fn(|k| points.iter().map(|p| p.1[k] as f64).sum::<f64>() / points.len() as f64);
        let bs: Vec<Vec<f64>> = (0..K).map(|k| targets.iter().map(|t| t[k]).collect()).collect();
        let mut xs: Vec<Vec<f64>> = mean.iter().map(|&m| vec![m; n]).collect();
        least_squares_each(&a, &bs, &mut xs, 1e-7, 4000);
        let mut out = vec![0.0; n * K];
        for (k, x) in xs.iter().enumerate() {
            for v in 0..n {
                out[v * K + k] = x[v];
            }
        }
        Ok(out)
    }
}

/// The mean depth difference across an edge, so the depth-aware weights do not depend on
/// how fine the mesh is.
fn edge_spread(offsets: &[usize], ring: &[u32], depth: &[f32]) -> f64 {
    let mut total = 0.0;
    for v in 0..depth.len() {
        total +=
            ring[offsets[v]..offsets[v + 1]].iter().map(|&j| (depth[v] - depth[j as usize]).abs() as f64).sum::<f64>();
    }
    (total / ring.len().max(1) as f64).max(1e-9)
}

/// The tet containing `p` (or, outside, the one whose barycentre is nearest) and the
/// barycentric coordinates of `p` in it, clamped to the tet.
pub fn locate(mesh: &TetMesh, p: Vec3) -> (usize, [f32; 4]) {
    let inside = (0..mesh.tets.len()).find(|&t| mesh.barycentric(t, p).iter().all(|b| *b >= -1e-5));
    clamped_in(mesh, inside.unwrap_or_else(|| nearest_of(&centroids(mesh), p)), p)
}

/// Every tet's barycentre.
fn centroids(mesh: &TetMesh) -> Vec<Vec3> {
    (0..mesh.tets.len()).map(|t| mesh.centroid(t)).collect()
}

/// The tet whose barycentre (of `centroids`) is nearest to `p` (the first of equals).
fn nearest_of(centroids: &[Vec3], p: Vec3) -> usize {
    let d = |t: usize| centroids[t].distance_squared(p);
    (0..centroids.len()).min_by(|&a, &b| d(a).total_cmp(&d(b))).unwrap_or(0)
}

/// [`locate`] for many points, the same tets and coordinates: through a [`TetGrid`] (made
/// once); a point no tet holds goes to the nearest barycentre.
pub fn locate_each(mesh: &TetMesh, points: &[Vec3]) -> Vec<(usize, [f32; 4])> {
    let Some(grid) = (if points.len() > 8 { TetGrid::new(mesh).ok() } else { None }) else {
        return points.iter().map(|&p| locate(mesh, p)).collect();
    };
    let centroids = centroids(mesh);
    // no tet holds a point the grid finds none for
    points
        .par_iter()
        .map(|&p| clamped_in(mesh, grid.locate(mesh, p).map_or_else(|| nearest_of(&centroids, p), |t| t as usize), p))
        .collect()
}

/// Tet `t` and the barycentric coordinates of `p` in it, clamped to the tet.
fn clamped_in(mesh: &TetMesh, t: usize, p: Vec3) -> (usize, [f32; 4]) {
    let b = mesh.barycentric(t, p).map(|b| b.max(0.0));
    let sum: f32 = b.iter().sum::<f32>().max(1e-12);
    (t, b.map(|x| x / sum))
}

/// A thin-plate RBF in 3D: `f(p) = Σ w_i |p - c_i| + a·p + b`.
pub struct Rbf {
    centres: Vec<DVec3>,
    weights: Vec<f64>,
    linear: [f64; 4],
}

impl Rbf {
    /// Fits the RBF through `points` (duplicates dropped, then thinned evenly to at most
    /// a few hundred centres). When the points lie in one plane the linear term is
    /// undetermined; the fit then falls back to a constant term.
    pub fn fit(points: &[(Vec3, f32)]) -> Result<Rbf> {
        let mut unique: Vec<(Vec3, f32)> = points.to_vec();
        unique.sort_by(|a, b| a.0.to_array().partial_cmp(&b.0.to_array()).unwrap_or(std::cmp::Ordering::Equal));
        unique.dedup_by(|a, b| a.0.distance_squared(b.0) < 1e-12);
        let step = unique.len().div_ceil(MAX_CENTRES).max(1);
        let kept: Vec<(DVec3, f64)> = unique.iter().step_by(step).map(|(p, v)| (p.as_dvec3(), *v as f64)).collect();
        Rbf::solve(&kept, true).or_else(|| Rbf::solve(&kept, false)).ok_or_else(|| {
            Error::invalid(format!("the {} depth constraint point(s) do not define a depth field", kept.len()))
        })
    }

    fn solve(kept: &[(DVec3, f64)], linear: bool) -> Option<Rbf> {
        let n = kept.len();
        let terms = if linear { 4 } else { 1 };
        let size = n + terms;
        let mut m = vec![0.0; size * size];
        let mut b = vec![0.0; size];
        for (i, (pi, vi)) in kept.iter().enumerate() {
            for (j, (pj, _)) in kept.iter().enumerate() {
                m[i * size + j] = pi.distance(*pj);
            }
            let poly = [1.0, pi.x, pi.y, pi.z];
            for (k, x) in poly.into_iter().take(terms).enumerate() {
                m[i * size + n + k] = x;
                m[(n + k) * size + i] = x;
            }
            b[i] = *vi;
        }
        let x = dense_solve(m, b)?;
        let mut poly = [0.0; 4];
        poly[..terms].copy_from_slice(&x[n..]);
        let centres = kept.iter().map(|(p, _)| *p).collect();
        Some(Rbf { centres, weights: x[..n].to_vec(), linear: [poly[1], poly[2], poly[3], poly[0]] })
    }

    /// The depth at `p`, clamped to [0, 1].
    pub fn value(&self, p: Vec3) -> f32 {
        let p = p.as_dvec3();
        let radial: f64 = self.centres.iter().zip(&self.weights).map(|(c, w)| w * p.distance(*c)).sum();
        let [a, b, c, d] = self.linear;
        (radial + a * p.x + b * p.y + c * p.z + d).clamp(0.0, 1.0) as f32
    }

    /// The gradient of the (unclamped) depth at `p`.
    pub fn gradient(&self, p: Vec3) -> Vec3 {
        let p = p.as_dvec3();
        let mut radial = DVec3::ZERO;
        for (c, w) in self.centres.iter().zip(&self.weights) {
            let d = p - *c;
            let length = d.length();
            if length > 0.0 {
                radial += d * (w / length);
            }
        }
        (radial + DVec3::new(self.linear[0], self.linear[1], self.linear[2])).as_vec3()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::fill::tets::cube_lattice;

    /// Locating many points through the grid gives the tets and coordinates of trying every
    /// tet: inside, on lattice corners, edges and faces (on cell borders, in several tets),
    /// just outside and far outside, on a lattice moved off the origin.
    #[test]
    fn locating_each_point_through_the_grid_equals_trying_every_tet() {
        let mut mesh = cube_lattice([5, 4, 3], 0.3);
        mesh.vertices.iter_mut().for_each(|v| *v += Vec3::new(-0.71, 0.13, 2.0));
        let mut points = Vec::new();
        for i in 0..400 {
            let h = |k: u64| (crate::noise::hash3(11, i, k as i64, 0) % 10_000) as f32 / 10_000.0;
            let p = Vec3::new(-0.8 + 1.7 * h(0), 0.0 + 1.4 * h(1), 1.9 + 1.1 * h(2));
            points.push(p);
        }
        points.extend(mesh.vertices.iter().copied());
        for t in 0..mesh.tets.len() {
            let c = mesh.corners(t);
            points.push((c[0] + c[1]) / 2.0);
            points.push((c[0] + c[1] + c[2]) / 3.0);
        }
        points.extend([Vec3::new(5.0, -3.0, 0.0), Vec3::new(-0.71 - 1e-6, 0.5, 2.3)]);
        let one_by_one: Vec<(usize, [f32; 4])> = points.iter().map(|&p| locate(&mesh, p)).collect();
        assert_eq!(locate_each(&mesh, &points), one_by_one);
    }

    #[test]
    fn rbf_interpolates_a_radial_depth() {
        // surface of a ball at 0, centre at 1: depth grows inwards, its gradient points in
        let mut points: Vec<(Vec3, f32)> = (0..200)
            .map(|i| {
                let (a, b) = (i as f32 * 2.399, (i as f32 + 0.5) / 200.0);
                let z = 1.0 - 2.0 * b;
                let r = (1.0 - z * z).sqrt();
                (Vec3::new(r * a.cos(), r * a.sin(), z), 0.0)
            })
            .collect();
        points.push((Vec3::ZERO, 1.0));
        let rbf = Rbf::fit(&points).unwrap();
        assert!(rbf.value(Vec3::new(0.0, 0.0, 0.999)) < 0.05);
        assert!((rbf.value(Vec3::ZERO) - 1.0).abs() < 1e-3);
        let half = rbf.value(Vec3::new(0.5, 0.0, 0.0));
        assert!(half > 0.2 && half < 0.8, "{half}");
        assert!(rbf.gradient(Vec3::new(0.5, 0.0, 0.0)).normalize().dot(-Vec3::X) > 0.95);
    }

    /// The quadratic term is zero at a tet's corners and the edge's value at its middle,
    /// and the depth it gives inside lattice tets follows a radial RBF several times more
    /// closely than linear interpolation does (the pith drawn round, not as a square).
    #[test]
    fn depth_bumps_follow_the_rbf_inside_each_tet() {
        let edges = [0.1, -0.2, 0.3, 0.05, 0.0, -0.4];
        assert_eq!(bump(&edges, [1.0, 0.0, 0.0, 0.0]), 0.0);
        for (k, &(i, j)) in EDGES.iter().enumerate() {
            let mut b = [0.0; 4];
            (b[i], b[j]) = (0.5, 0.5);
            assert!((bump(&edges, b) - edges[k]).abs() < 1e-6, "edge {k}");
        }
        let mut mesh = cube_lattice([6, 6, 6], 0.25);
        mesh.vertices.iter_mut().for_each(|v| *v -= Vec3::splat(0.75));
        let axis: Vec<(Vec3, f32)> = (0..9).map(|i| (Vec3::new(0.0, 0.0, -0.8 + 0.2 * i as f32), 1.0)).collect();
        let rim = (0..64).flat_map(|i| {
            let a = i as f32 * std::f32::consts::TAU / 16.0;
            let z = -0.8 + 0.4 * (i / 16) as f32;
            [(Vec3::new(0.7 * a.cos(), 0.7 * a.sin(), z), 0.0)]
        });
        let rbf = Rbf::fit(&axis.into_iter().chain(rim).collect::<Vec<_>>()).unwrap();
        let raw: Vec<f32> = mesh.vertices.iter().map(|v| rbf.value(*v)).collect();
        let bumps = depth_bumps(&mesh, &rbf, &raw, &raw);
        let (mut linear, mut quadratic) = (0.0f32, 0.0f32);
        for (t, tet) in mesh.tets.iter().enumerate() {
            let c = mesh.corners(t);
            for b in [[0.25; 4], [0.4, 0.4, 0.1, 0.1], [0.1, 0.2, 0.3, 0.4], [0.0, 0.5, 0.25, 0.25]] {
                let p: Vec3 = c.iter().zip(b).map(|(v, w)| *v * w).sum();
                let flat: f32 = tet.iter().zip(b).map(|(&v, w)| raw[v as usize] * w).sum();
                let truth = rbf.value(p);
                linear = linear.max((flat - truth).abs());
                quadratic = quadratic.max((flat + bump(&bumps[t], b) - truth).abs());
            }
        }
        assert!(quadratic * 3.0 < linear, "largest error: linear {linear}, quadratic {quadratic}");
    }

    #[test]
    fn strokes_spread_over_the_mesh() {
        let mesh = cube_lattice([4, 4, 4], 1.0);
        let c = Constraints { directions: vec![(Vec3::splat(0.5), Vec3::X)], scale: 0.5, ..Default::default() };
        let f = build(&mesh, TextureType::T1a, &c, None).unwrap();
        assert!(f.primary.iter().all(|d| d.dot(Vec3::X) > 0.999));
        assert!(f.scale.iter().all(|s| (*s - 0.5).abs() < 1e-6) && f.depth.is_none());
    }

    #[test]
    fn two_strokes_blend_smoothly_between() {
        let mesh = cube_lattice([6, 2, 2], 1.0);
        let c = Constraints {
            directions: vec![(Vec3::new(0.05, 0.5, 0.5), Vec3::X), (Vec3::new(5.95, 0.5, 0.5), Vec3::Y)],
            scale: 1.0,
            ..Default::default()
        };
        let f = build(&mesh, TextureType::T1a, &c, None).unwrap();
        let (near, _) = locate(&mesh, Vec3::new(0.3, 0.5, 0.5));
        let (mid, _) = locate(&mesh, Vec3::new(3.0, 1.0, 1.0));
        assert!(f.primary[near].dot(Vec3::X) > 0.9, "{}", f.primary[near]);
        let m = f.primary[mid];
        assert!(m.x > 0.3 && m.y > 0.3, "{m}");
    }

    #[test]
    fn layered_types_take_scale_and_axes_from_depth() {
        let mesh = cube_lattice([2, 4, 2], 1.0);
        // depth 0 on top (y = 4), 1 at the bottom: depth gradient -y, scale 4
        let mut depth = Vec::new();
        for &(x, z) in &[(0.0, 0.0), (2.0, 0.0), (0.0, 2.0), (2.0, 2.0), (1.0, 1.0)] {
            depth.push((Vec3::new(x, 4.0, z), 0.0));
            depth.push((Vec3::new(x, 0.0, z), 1.0));
        }
        let c = Constraints {
            directions: vec![(Vec3::new(1.0, 2.0, 1.0), Vec3::new(1.0, 0.3, 0.0))],
            depth,
            scale: 1.0,
            ..Default::default()
        };
        let f = build(&mesh, TextureType::T2b, &c, None).unwrap();
        assert!(f.primary.iter().all(|r| r.dot(-Vec3::Y) > 0.99));
        assert!(f.secondary.iter().zip(&f.primary).all(|(s, r)| s.dot(*r).abs() < 1e-4 && s.dot(Vec3::X) > 0.99));
        assert!(f.scale.iter().all(|s| (s - 4.0).abs() < 0.05), "{:?}", &f.scale[..4]);
        let d = f.depth.unwrap();
        assert!(mesh.vertices.iter().zip(&d).all(|(v, d)| (d - (1.0 - v.y / 4.0)).abs() < 0.02));
    }

    #[test]
    fn missing_constraints_are_named() {
        let mesh = cube_lattice([2, 2, 2], 1.0);
        let c = Constraints { scale: 1.0, ..Default::default() };
        let e = build(&mesh, TextureType::T1a, &c, None).unwrap_err().to_string();
        assert!(e.contains("1-a") && e.contains("direction"), "{e}");
        let e = build(&mesh, TextureType::T2b, &c, None).unwrap_err().to_string();
        assert!(e.contains("direction"), "{e}");
        let c = Constraints { directions: vec![(Vec3::ONE, Vec3::X)], scale: 1.0, ..Default::default() };
        let e = build(&mesh, TextureType::T1b, &c, None).unwrap_err().to_string();
        assert!(e.contains("depth"), "{e}");
        let e = build(&mesh, TextureType::T2c, &c, None).unwrap_err().to_string();
        assert!(e.contains("cannot be filled"), "{e}");
        assert!(build(&mesh, TextureType::T0, &Constraints { scale: -1.0, ..c }, None).is_err());
    }
}
