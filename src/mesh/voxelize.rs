//! Voxelization: anti-aliased occupancy of a mesh on a voxel grid, by ray parity along x
//! on supersample rows (closed meshes), with a cone patch over open boundaries whose
//! winding number corrects the parity (open meshes).

use super::*;
use rayon::prelude::*;

/// Anti-aliased occupancy of a mesh given in voxel coordinates (voxel (i, j, k) is the cube
/// [i, i+1) x [j, j+1) x [k, k+1)), restricted to the voxels of a grid that the mesh's
/// bounding box touches.
///
/// A mesh wholly outside the grid (or a grid with a zero dimension) gives the empty
/// coverage: origin and dims `[0, 0, 0]`, no alpha; see [`Coverage::is_empty`].
#[derive(Debug, Clone, PartialEq)]
pub struct Coverage {
    /// The grid voxel at `alpha[0]`.
    pub origin: [usize; 3],
    /// The size of the covered box in voxels.
    pub dims: [usize; 3],
    /// Inside fraction per voxel of the box, x fastest, each in [0, 1].
    pub alpha: Vec<f32>,
}

impl Coverage {
    /// Whether the mesh missed the grid entirely.
    pub fn is_empty(&self) -> bool {
        self.alpha.is_empty()
    }

    /// The covered volume in voxels: the sum of alpha (in f64, storage order).
    pub fn volume(&self) -> f64 {
        self.alpha.iter().map(|&a| f64::from(a)).sum()
    }

    /// The alpha of grid voxel `(x, y, z)`: 0 outside the covered box.
    pub fn at(&self, x: usize, y: usize, z: usize) -> f32 {
        let [ox, oy, oz] = self.origin;
        let [nx, ny, nz] = self.dims;
        let (Some(i), Some(j), Some(k)) = (x.checked_sub(ox), y.checked_sub(oy), z.checked_sub(oz)) else {
            return 0.0;
        };
        if i >= nx || j >= ny || k >= nz {
            return 0.0;
        }
        self.alpha[i + nx * (j + ny * k)]
    }
}

/// The coverage of `mesh` (in voxel coordinates) on a grid of `grid` voxels, sampling each
/// voxel at `supersample`³ points (clamped to 1..=256). Parts outside the grid are clipped.
/// Closed meshes use ray parity, open ones the winding number; see the module documentation.
pub fn voxelize(mesh: &Mesh, grid: [usize; 3], supersample: usize) -> Coverage {
    let Some(frame) = Frame::new(mesh.bounds(), grid, supersample.clamp(1, 256)) else {
        return Coverage { origin: [0; 3], dims: [0; 3], alpha: Vec::new() };
    };
    let rule = if mesh.boundary_edges() == 0 { Rule::Parity } else { Rule::Winding(Cone::new(mesh)) };
    let rays = RayTable::new(mesh, &rule, &frame);
    let slices: Vec<Vec<f32>> = (0..frame.dims[2]).into_par_iter().map(|k| rays.slice(&rule, &frame, k)).collect();
    Coverage { origin: frame.origin, dims: frame.dims, alpha: slices.concat() }
}

/// Which voxel centres of a grid lie inside a mesh (given in voxel coordinates), one
/// z-slice at a time: for grids too large to hold whole (a bake at 1024³), the triangles
/// are prepared once and each slice is read on demand. Slice `k` agrees with
/// [`voxelize`] at supersample 1.
pub struct Slices {
    grid: [usize; 3],
    found: Option<(Frame, Rule, RayTable)>,
}

impl Slices {
    /// The slices of `mesh` on a grid of `grid` voxels.
    pub fn new(mesh: &Mesh, grid: [usize; 3]) -> Slices {
        let found = Frame::new(mesh.bounds(), grid, 1).map(|frame| {
            let rule = if mesh.boundary_edges() == 0 { Rule::Parity } else { Rule::Winding(Cone::new(mesh)) };
            let rays = RayTable::new(mesh, &rule, &frame);
            (frame, rule, rays)
        });
        Slices { grid, found }
    }

    /// Per row of grid slice `k` (the line through the voxel centres along x), where it
    /// crosses the mesh, sorted, in grid coordinates (voxel `i` spans `i..i + 1`): inside
    /// between the first and second, the third and fourth, and so on, for a closed mesh.
    pub fn crossings(&self, k: usize) -> Vec<Vec<f64>> {
        let [_, ny, _] = self.grid;
        let mut out = vec![Vec::new(); ny];
        let Some((frame, _, rays)) = &self.found else { return out };
        let Some(local) = k.checked_sub(frame.origin[2]).filter(|l| *l < frame.dims[2]) else { return out };
        let pz = frame.sample(2, local);
        let mut found = Vec::new();
        for (m, ids) in rays.by_row(frame, local).iter().enumerate() {
            rays.crossings(ids, local, [frame.sample(1, m), pz], &mut found);
            out[frame.origin[1] + m] = found.iter().map(|c| c.0).collect();
        }
        out
    }

    /// Per voxel of grid slice `k` (x fastest), whether its centre is inside.
    pub fn inside(&self, k: usize) -> Vec<bool> {
        let [nx, ny, _] = self.grid;
        let mut out = vec![false; nx * ny];
        let Some((frame, rule, rays)) = &self.found else { return out };
        let Some(local) = k.checked_sub(frame.origin[2]).filter(|l| *l < frame.dims[2]) else { return out };
        let alpha = rays.slice(rule, frame, local);
        let [ox, oy, _] = frame.origin;
        for (j, row) in alpha.chunks_exact(frame.dims[0]).enumerate() {
            let at = ox + nx * (oy + j);
            out[at..at + row.len()].iter_mut().zip(row).for_each(|(o, a)| *o = *a > 0.5);
        }
        out
    }
}

/// The covered box and the sample lattice inside it.
struct Frame {
    origin: [usize; 3],
    dims: [usize; 3],
    ss: usize,
}

impl Frame {
    /// The grid voxels the bounds touch, or `None` when there are none.
    fn new((lo, hi): (Vec3, Vec3), grid: [usize; 3], ss: usize) -> Option<Frame> {
        let mut frame = Frame { origin: [0; 3], dims: [0; 3], ss };
        for a in 0..3 {
            // max and min drop a NaN, so neither is NaN.
            let start = f64::from(lo[a]).floor().max(0.0);
            let end = f64::from(hi[a]).ceil().min(grid[a] as f64);
            if end <= start {
                return None;
            }
            frame.origin[a] = start as usize;
            frame.dims[a] = (end - start) as usize;
        }
        Some(frame)
    }

    /// How many samples lie along axis `a`.
    fn samples(&self, a: usize) -> usize {
        self.dims[a] * self.ss
    }

    /// The position of sample `m` along axis `a`.
    fn sample(&self, a: usize, m: usize) -> f64 {
        self.origin[a] as f64 + (m as f64 + 0.5) / self.ss as f64
    }

    /// The first sample along axis `a` at or after `x` (`samples(a)` when there is none).
    fn first_from(&self, a: usize, x: f64) -> usize {
        let n = self.samples(a);
        let guess = ((x - self.origin[a] as f64) * self.ss as f64 - 0.5).ceil().clamp(0.0, n as f64) as usize;
        let mut m = guess;
        while m > 0 && self.sample(a, m - 1) >= x {
            m -= 1;
        }
        while m < n && self.sample(a, m) < x {
            m += 1;
        }
        m
    }

    /// The samples along axis `a` within `[lo, hi]` (plus possibly the next one), or `None`
    /// when there are none. Uses [`Frame::sample`] itself, so a box that only touches a
    /// sample keeps it.
    fn samples_within(&self, a: usize, lo: f64, hi: f64) -> Option<(usize, usize)> {
        let first = self.first_from(a, lo);
        let last = self.first_from(a, hi).min(self.samples(a) - 1);
        (first <= last && self.sample(a, first) <= hi).then_some((first, last))
    }
}

/// How the crossings of a row decide inside.
enum Rule {
    /// Closed mesh: inside between odd and even crossings.
    Parity,
    /// Open mesh: generalized winding number above 0.5, from the integer winding of the mesh
    /// closed by a cone plus the cone's own (exact) winding number.
    Winding(Cone),
}

/// The cone from one apex over the boundary chain of an open mesh: the mesh minus the cone
/// is closed, so its winding number is an integer found by counting signed crossings, and
/// the mesh's winding number is that integer plus the cone's, which costs one solid angle
/// per boundary edge instead of one per triangle.
struct Cone {
    /// Cone triangles (apex, u, v) with their integer weight in the boundary chain.
    triangles: Vec<([DVec3; 3], i32)>,
    /// +1 or -1: the sign that makes the inside positive (signed volume seen from the apex,
    /// which is the volume of the closed mesh-minus-cone and so does not depend on placement).
    sign: f64,
}

impl Cone {
    fn new(mesh: &Mesh) -> Cone {
        let chain = boundary_chain(mesh);
        let ends = chain.iter().flat_map(|&(u, v, _)| [u, v]).map(|i| mesh.vertices[i as usize].as_dvec3());
        let apex = ends.clone().sum::<DVec3>() / (2 * chain.len()).max(1) as f64;
        let triangles = chain
            .iter()
            .map(|&(u, v, weight)| {
                ([apex, mesh.vertices[u as usize].as_dvec3(), mesh.vertices[v as usize].as_dvec3()], weight)
            })
            .collect();
        let volume: f64 = mesh
            .triangles
            .iter()
            .map(|t| mesh.corners(*t))
            .map(|[a, b, c]| (a - apex).dot((b - apex).cross(c - apex)))
            .sum();
        Cone { triangles, sign: if volume < 0.0 { -1.0 } else { 1.0 } }
    }

    /// The cone's generalized winding number at `p`.
    fn winding(&self, p: DVec3) -> f64 {
        let total: f64 =
            self.triangles.iter().map(|&(corners, weight)| f64::from(weight) * solid_angle(corners, p)).sum();
        total / (4.0 * PI)
    }
}

/// The boundary of the mesh as a chain: each undirected edge `(u, v)` with `u < v` and the
/// net number of times the triangles run along it from u to v (minus from v to u), where
/// that is not zero. Sorted by edge.
fn boundary_chain(mesh: &Mesh) -> Vec<(u32, u32, i32)> {
    let mut directed: Vec<(u32, u32, i32)> = mesh
        .triangles
        .iter()
        .flat_map(|&[a, b, c]| [(a, b), (b, c), (c, a)])
        .map(|(u, v)| if u < v { (u, v, 1) } else { (v, u, -1) })
        .collect();
    directed.sort_unstable();
    directed
        .chunk_by(|x, y| (x.0, x.1) == (y.0, y.1))
        .map(|run| (run[0].0, run[0].1, run.iter().map(|e| e.2).sum::<i32>()))
        .filter(|e| e.2 != 0)
        .collect()
}

/// A triangle ready for rays along x: corners in f64, its signed weight (crossing it along
/// +x changes the winding number by minus this), and the sample rows (y) and layers (z) its
/// bounding box spans.
struct RayTri {
    corners: [DVec3; 3],
    weight: i32,
    rows: (usize, usize),
    layers: (usize, usize),
}

/// The triangles a ray can hit, with the triangle ids of each voxel z-slice.
struct RayTable {
    tris: Vec<RayTri>,
    by_slice: Vec<Vec<u32>>,
}

impl RayTable {
    fn new(mesh: &Mesh, rule: &Rule, frame: &Frame) -> RayTable {
        let own = mesh.triangles.iter().map(|t| (mesh.corners(*t), 1));
        let cone = match rule {
            Rule::Parity => &[][..],
            Rule::Winding(cone) => &cone.triangles[..],
        };
        let all = own.chain(cone.iter().map(|&(corners, weight)| (corners, -weight)));
        let tris: Vec<RayTri> = all.filter_map(|(corners, weight)| ray_tri(corners, weight, frame)).collect();
        let mut by_slice = vec![Vec::new(); frame.dims[2]];
        for (id, tri) in tris.iter().enumerate() {
            for slice in &mut by_slice[tri.layers.0 / frame.ss..=tri.layers.1 / frame.ss] {
                slice.push(id as u32);
            }
        }
        RayTable { tris, by_slice }
    }

    /// The triangles of voxel slice `k` by sample row.
    fn by_row(&self, frame: &Frame, k: usize) -> Vec<Vec<u32>> {
        let mut by_row = vec![Vec::new(); frame.samples(1)];
        for &id in &self.by_slice[k] {
            let (first, last) = self.tris[id as usize].rows;
            for row in &mut by_row[first..=last] {
                row.push(id);
            }
        }
        by_row
    }

    /// Into `out`, where the sample row at `(py, pz)` of sample layer `layer` crosses the
    /// triangles `ids`: (x, weight), sorted.
    fn crossings(&self, ids: &[u32], layer: usize, [py, pz]: [f64; 2], out: &mut Vec<(f64, i32)>) {
        out.clear();
        for &id in ids {
            let tri = &self.tris[id as usize];
            if (tri.layers.0..=tri.layers.1).contains(&layer) {
                out.extend(crossing(tri, py, pz));
            }
        }
        out.sort_unstable_by(|a, b| a.0.total_cmp(&b.0).then(a.1.cmp(&b.1)));
    }

    /// The alpha of voxel slice `k`, x fastest.
    fn slice(&self, rule: &Rule, frame: &Frame, k: usize) -> Vec<f32> {
        let [nx, ny, _] = frame.dims;
        let ss = frame.ss;
        let by_row = self.by_row(frame, k);
        let mut counts = vec![0u32; nx * ny];
        let mut crossings = Vec::new();
        for layer in k * ss..(k + 1) * ss {
            let pz = frame.sample(2, layer);
            for (m, ids) in by_row.iter().enumerate() {
                let py = frame.sample(1, m);
                self.crossings(ids, layer, [py, pz], &mut crossings);
                let row = &mut counts[(m / ss) * nx..][..nx];
                match rule {
                    Rule::Parity => fill_row(frame, &crossings, row),
                    Rule::Winding(cone) => wind_row(frame, &crossings, cone, [py, pz], row),
                }
            }
        }
        to_alpha(&counts, ss)
    }
}

/// A triangle prepared for rays, or `None` when no ray of the frame can hit it (non-finite,
/// flat as seen along x, or outside the sampled rows and layers).
fn ray_tri(corners: [DVec3; 3], weight: i32, frame: &Frame) -> Option<RayTri> {
    if !corners.iter().all(|c| c.is_finite()) {
        return None;
    }
    let [a, b, c] = corners;
    let facing = (b.y - a.y) * (c.z - a.z) - (b.z - a.z) * (c.y - a.y);
    if facing == 0.0 {
        return None;
    }
    let (lo, hi) = (a.min(b).min(c), a.max(b).max(c));
    let rows = frame.samples_within(1, lo.y, hi.y)?;
    let layers = frame.samples_within(2, lo.z, hi.z)?;
    let weight = if facing > 0.0 { weight } else { -weight };
    Some(RayTri { corners, weight, rows, layers })
}

/// Where the ray `(t, py, pz)` crosses the triangle, with the triangle's signed weight.
fn crossing(tri: &RayTri, py: f64, pz: f64) -> Option<(f64, i32)> {
    let [a, b, c] = tri.corners;
    let (wa, sa) = edge(b, c, py, pz);
    let (wb, sb) = edge(c, a, py, pz);
    let (wc, sc) = edge(a, b, py, pz);
    if sa != sb || sb != sc {
        return None;
    }
    Some(((wa * a.x + wb * b.x + wc * c.x) / (wa + wb + wc), tri.weight))
}

/// The edge function of `u -> v` at `(py, pz)` in the (y, z) plane and its sign, with exact
/// antisymmetry (the edge is always evaluated from its lexicographically smaller end) and
/// zero resolved as if the point were moved by `(ε, ε²)`.
pub(crate) fn edge(u: DVec3, v: DVec3, py: f64, pz: f64) -> (f64, bool) {
    let swap = (u.y, u.z) > (v.y, v.z);
    let (s, t) = if swap { (v, u) } else { (u, v) };
    let e = (t.y - s.y) * (pz - s.z) - (t.z - s.z) * (py - s.y);
    let positive = if e != 0.0 {
        e > 0.0
    } else if t.z != s.z {
        t.z < s.z
    } else {
        t.y > s.y
    };
    if swap { (-e, !positive) } else { (e, positive) }
}

/// Count the samples of one row between odd and even crossings, per voxel.
fn fill_row(frame: &Frame, crossings: &[(f64, i32)], counts: &mut [u32]) {
    for pair in crossings.chunks_exact(2) {
        for m in frame.first_from(0, pair[0].0)..frame.first_from(0, pair[1].0) {
            counts[m / frame.ss] += 1;
        }
    }
}

/// Count the samples of one row whose winding number (crossings passed plus the cone's)
/// is above 0.5, per voxel.
fn wind_row(frame: &Frame, crossings: &[(f64, i32)], cone: &Cone, [py, pz]: [f64; 2], counts: &mut [u32]) {
    let mut passed = 0;
    let mut winding = 0;
    for m in 0..frame.samples(0) {
        let x = frame.sample(0, m);
        while let Some(&(_, weight)) = crossings.get(passed).filter(|c| c.0 <= x) {
            winding -= weight;
            passed += 1;
        }
        let w = f64::from(winding) + cone.winding(DVec3::new(x, py, pz));
        if cone.sign * w > 0.5 {
            counts[m / frame.ss] += 1;
        }
    }
}

fn to_alpha(counts: &[u32], ss: usize) -> Vec<f32> {
    let total = (ss * ss * ss) as f32;
    counts.iter().map(|&c| c as f32 / total).collect()
}
