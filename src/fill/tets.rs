//! A tetrahedral mesh and the topology the filling needs: face neighbours, vertex one-rings,
//! boundary faces, and point location by barycentric coordinates.
//!
//! ```text
//!        3            a tet [v0, v1, v2, v3] is positively oriented:
//!       /|\           (v1 - v0) x (v2 - v0) . (v3 - v0) > 0
//!      / | \          face k is the face opposite vertex k; neighbours()[t][k]
//!     0--|--2         is the tet across it, or NONE on the boundary
//!      \ | /
//!       \|/
//!        1
//! ```

use crate::error::{Error, Result};
use glam::{Mat3, Vec3};
use rayon::prelude::*;

/// Marks "no neighbour" (a boundary face).
pub const NONE: u32 = u32::MAX;

/// A tetrahedral mesh: corner positions and positively oriented index quadruples.
#[derive(Debug, Clone, PartialEq)]
pub struct TetMesh {
    /// Corner positions.
    pub vertices: Vec<Vec3>,
    /// Tetrahedra, each positively oriented (see the module diagram).
    pub tets: Vec<[u32; 4]>,
}

/// The faces of a tet as vertex slots, face k opposite slot k, each seen from outside
/// counter-clockwise for a positively oriented tet.
pub const FACES: [[usize; 3]; 4] = [[1, 2, 3], [0, 3, 2], [0, 1, 3], [0, 2, 1]];

/// A tet's six edges, as pairs of its corners.
pub const EDGES: [(usize, usize); 6] = [(0, 1), (0, 2), (0, 3), (1, 2), (1, 3), (2, 3)];

impl TetMesh {
    /// The four corners of tet `t`.
    pub fn corners(&self, t: usize) -> [Vec3; 4] {
        self.tets[t].map(|i| self.vertices[i as usize])
    }

    /// The signed volume of tet `t` (positive when correctly oriented).
    pub fn volume_of(&self, t: usize) -> f32 {
        let [a, b, c, d] = self.corners(t);
        (b - a).cross(c - a).dot(d - a) / 6.0
    }

    /// The total volume.
    pub fn volume(&self) -> f64 {
        (0..self.tets.len()).map(|t| self.volume_of(t) as f64).sum()
    }

    /// The centroid of tet `t`.
    pub fn centroid(&self, t: usize) -> Vec3 {
        self.corners(t).iter().sum::<Vec3>() / 4.0
    }

    /// The edge matrix `[v1 - v0, v2 - v0, v3 - v0]` of tet `t`.
    pub fn edges(&self, t: usize) -> Mat3 {
        let [a, b, c, d] = self.corners(t);
        Mat3::from_cols(b - a, c - a, d - a)
    }

    /// For each tet, the tet across each face (`NONE` on the boundary).
    pub fn neighbours(&self) -> Vec<[u32; 4]> {
        let mut keyed: Vec<([u32; 3], u32, u8)> = Vec::with_capacity(self.tets.len() * 4);
        for (t, tet) in self.tets.iter().enumerate() {
            for (k, face) in FACES.iter().enumerate() {
                let mut key = face.map(|s| tet[s]);
                key.sort_unstable();
                keyed.push((key, t as u32, k as u8));
            }
        }
        // every entry differs (tet and face), so any sort, on any thread count, gives one order
        keyed.par_sort_unstable();
        let mut out = vec![[NONE; 4]; self.tets.len()];
        for pair in keyed.chunk_by(|a, b| a.0 == b.0).filter(|run| run.len() == 2) {
            let ((_, t0, k0), (_, t1, k1)) = (pair[0], pair[1]);
            out[t0 as usize][k0 as usize] = t1;
            out[t1 as usize][k1 as usize] = t0;
        }
        out
    }

    /// The boundary faces (vertex triples facing outwards), in tet order.
    pub fn boundary_faces(&self, neighbours: &[[u32; 4]]) -> Vec<[u32; 3]> {
        let mut faces = Vec::new();
        for (t, tet) in self.tets.iter().enumerate() {
            for (k, face) in FACES.iter().enumerate() {
                if neighbours[t][k] == NONE {
                    faces.push(face.map(|s| tet[s]));
                }
            }
        }
        faces
    }

    /// The vertex one-rings as compressed rows: the neighbours of vertex `v` are
    /// `list[offsets[v]..offsets[v + 1]]`, sorted.
    pub fn one_rings(&self) -> (Vec<usize>, Vec<u32>) {
        let mut pairs: Vec<(u32, u32)> = Vec::with_capacity(self.tets.len() * 12);
        for tet in &self.tets {
            for i in 0..4 {
                for j in 0..4 {
                    if i != j {
                        pairs.push((tet[i], tet[j]));
                    }
                }
            }
        }
        pairs.sort_unstable();
        pairs.dedup();
        let mut offsets = vec![0usize; self.vertices.len() + 1];
        for &(a, _) in &pairs {
            offsets[a as usize + 1] += 1;
        }
        for v in 0..self.vertices.len() {
            offsets[v + 1] += offsets[v];
        }
        (offsets, pairs.into_iter().map(|(_, b)| b).collect())
    }

    /// The tets around each vertex as compressed rows (like [`TetMesh::one_rings`]).
    pub fn vertex_tets(&self) -> (Vec<usize>, Vec<u32>) {
        let mut offsets = vec![0usize; self.vertices.len() + 1];
        for tet in &self.tets {
            for &v in tet {
                offsets[v as usize + 1] += 1;
            }
        }
        for v in 0..self.vertices.len() {
            offsets[v + 1] += offsets[v];
        }
        let mut fill = offsets.clone();
        let mut list = vec![0u32; offsets[self.vertices.len()]];
        for (t, tet) in self.tets.iter().enumerate() {
            for &v in tet {
                list[fill[v as usize]] = t as u32;
                fill[v as usize] += 1;
            }
        }
        (offsets, list)
    }

    /// The barycentric coordinates of `p` in tet `t` (they sum to 1; all are ≥ 0 inside).
    pub fn barycentric(&self, t: usize, p: Vec3) -> [f32; 4] {
        barycentric_in(self.corners(t), p)
    }

    /// The smallest dihedral angle over all tets, in degrees (a quality figure).
    pub fn min_dihedral_degrees(&self) -> f32 {
        (0..self.tets.len()).map(|t| min_dihedral(self.corners(t))).fold(180.0, f32::min)
    }
}

/// The barycentric coordinates of `p` in the tet with corners `c`.
pub fn barycentric_in(c: [Vec3; 4], p: Vec3) -> [f32; 4] {
    let local = Mat3::from_cols(c[1] - c[0], c[2] - c[0], c[3] - c[0]).inverse() * (p - c[0]);
    [1.0 - local.x - local.y - local.z, local.x, local.y, local.z]
}

/// Tets binned on a grid of cells by their bounding boxes, to find the tet holding a point
/// without trying every tet. Each box is padded a little, so that every tet whose
/// barycentric coordinates of a point all reach -1e-5 is listed in the point's cell: the
/// first such tet by index is the one a search through all tets finds.
#[derive(Debug, Clone)]
pub struct TetGrid {
    lo: Vec3,
    cell: f32,
    dims: [usize; 3],
    offsets: Vec<u32>,
    tets: Vec<u32>,
}

/// The most (cell, tet) entries a [`TetGrid`] holds; a mesh whose tets would need more
/// (long thin tets across many cells) is refused.
const MAX_GRID_ENTRIES: usize = 32_000_000;

impl TetGrid {
    /// The grid of `mesh`'s tets: cells about one tet's volume, at most 128 along the
    /// longest side of the mesh's box.
    pub fn new(mesh: &TetMesh) -> Result<TetGrid> {
        TetGrid::at_most(mesh, 128)
    }

    /// [`TetGrid::new`] with at most `cells` cells along the longest side (a single cell
    /// always fits).
    pub fn at_most(mesh: &TetMesh, cells: usize) -> Result<TetGrid> {
        let (lo, hi) =
            mesh.vertices.iter().fold((Vec3::INFINITY, Vec3::NEG_INFINITY), |(a, b), p| (a.min(*p), b.max(*p)));
        let volume = mesh.volume().max(1e-12) as f32;
        let cell = (volume / mesh.tets.len().max(1) as f32)
            .cbrt()
            .max((hi - lo).max_element() / cells.max(1) as f32)
            .max(1e-6);
        let dims = ((hi - lo) / cell).ceil().as_uvec3().max(glam::UVec3::ONE).to_array().map(|d| d as usize);
        let grid = TetGrid { lo, cell, dims, offsets: Vec::new(), tets: Vec::new() };
        let span = |t: usize| {
            let c = mesh.corners(t);
            let (a, b) = (
                c.iter().copied().fold(Vec3::INFINITY, Vec3::min),
                c.iter().copied().fold(Vec3::NEG_INFINITY, Vec3::max),
            );
            // a point the barycentric test accepts lies within 3e-5 diameters of the tet
            let pad = Vec3::splat(1e-4 * (b - a).max_element() + 1e-6);
            (grid.cell_of(a - pad), grid.cell_of(b + pad))
        };
        let spans: Vec<([usize; 3], [usize; 3])> = (0..mesh.tets.len()).into_par_iter().map(span).collect();
        let entries = spans
            .iter()
            .map(|(a, b)| (0..3).map(|k| b[k] - a[k] + 1).product::<usize>())
            .fold(0usize, usize::saturating_add);
        if entries > MAX_GRID_ENTRIES {
            return Err(Error::invalid(format!(
                "the model's tets are too long to locate points in ({entries} grid entries; at most {MAX_GRID_ENTRIES})"
            )));
        }
        let cells_of = |(a, b): &([usize; 3], [usize; 3])| {
            let (a, b) = (*a, *b);
            (a[2]..=b[2]).flat_map(move |z| {
                (a[1]..=b[1]).flat_map(move |y| (a[0]..=b[0]).map(move |x| x + dims[0] * (y + dims[1] * z)))
            })
        };
        // a counting sort by cell: each cell's tets in index order
        let mut offsets = vec![0u32; dims.iter().product::<usize>() + 1];
        for c in spans.iter().flat_map(cells_of) {
            offsets[c + 1] += 1;
        }
        for i in 1..offsets.len() {
            offsets[i] += offsets[i - 1];
        }
        let mut next = offsets.clone();
        let mut tets = vec![0u32; entries];
        for (t, span) in spans.iter().enumerate() {
            for c in cells_of(span) {
                tets[next[c] as usize] = t as u32;
                next[c] += 1;
            }
        }
        Ok(TetGrid { offsets, tets, ..grid })
    }

    /// The cell holding `p`, clamped into the grid (monotone in each coordinate, so a box's
    /// corner cells span the cells of every point in it).
    fn cell_of(&self, p: Vec3) -> [usize; 3] {
        cell_in(self.lo, self.cell, self.dims, p)
    }

    /// The grid's corner, cell side and cells per axis.
    pub fn layout(&self) -> (Vec3, f32, [usize; 3]) {
        (self.lo, self.cell, self.dims)
    }

    /// The first tet (by index) holding `p` (barycentric coordinates all at least -1e-5).
    pub fn locate(&self, mesh: &TetMesh, p: Vec3) -> Option<u32> {
        self.candidates(p).iter().copied().find(|&t| mesh.barycentric(t as usize, p).iter().all(|w| *w >= -1e-5))
    }

    /// The tets listed in the cell of `p`, in index order (none for a point not finite).
    pub fn candidates(&self, p: Vec3) -> &[u32] {
        if !p.is_finite() {
            return &[];
        }
        let [x, y, z] = self.cell_of(p);
        let i = x + self.dims[0] * (y + self.dims[1] * z);
        &self.tets[self.offsets[i] as usize..self.offsets[i + 1] as usize]
    }
}

/// The cell holding `p` on a grid from `lo` of cells of side `side`, `dims` per axis,
/// clamped into the grid (monotone in each coordinate).
pub(crate) fn cell_in(lo: Vec3, side: f32, dims: [usize; 3], p: Vec3) -> [usize; 3] {
    let c = ((p - lo) / side).floor().max(Vec3::ZERO);
    [0, 1, 2].map(|k| (c[k].min(u32::MAX as f32) as usize).min(dims[k] - 1))
}

/// A box of `cells` cubes of side `h` from the origin, each split into 6 tets around its
/// main diagonal (the Freudenthal split, so neighbouring cubes share faces exactly). Used
/// by tests and benchmarks as a mesh with known geometry.
pub fn cube_lattice(cells: [usize; 3], h: f32) -> TetMesh {
    let [nx, ny, nz] = cells;
    let id = |x: usize, y: usize, z: usize| (x + (nx + 1) * (y + (ny + 1) * z)) as u32;
    let mut vertices = Vec::new();
    for z in 0..=nz {
        for y in 0..=ny {
            for x in 0..=nx {
                vertices.push(Vec3::new(x as f32, y as f32, z as f32) * h);
            }
        }
    }
    let mut tets = Vec::new();
    for z in 0..nz {
        for y in 0..ny {
            for x in 0..nx {
                for order in AXIS_ORDERS {
                    let mut p = [x, y, z];
                    let mut tet = [id(x, y, z); 4];
                    for (slot, axis) in order.iter().enumerate() {
                        p[*axis] += 1;
                        tet[slot + 1] = id(p[0], p[1], p[2]);
                    }
                    tets.push(positive(&vertices, tet));
                }
            }
        }
    }
    TetMesh { vertices, tets }
}

const AXIS_ORDERS: [[usize; 3]; 6] = [[0, 1, 2], [0, 2, 1], [1, 0, 2], [1, 2, 0], [2, 0, 1], [2, 1, 0]];

/// `tet` with two corners swapped if needed so it is positively oriented.
pub fn positive(vertices: &[Vec3], tet: [u32; 4]) -> [u32; 4] {
    let [a, b, c, d] = tet.map(|i| vertices[i as usize]);
    if (b - a).cross(c - a).dot(d - a) < 0.0 { [tet[0], tet[2], tet[1], tet[3]] } else { tet }
}

/// The smallest of the six dihedral angles of a tet, in degrees.
pub fn min_dihedral(c: [Vec3; 4]) -> f32 {
    let normals = FACES.map(|[a, b, d]| (c[b] - c[a]).cross(c[d] - c[a]).normalize_or_zero());
    let mut smallest = 180.0f32;
    for i in 0..4 {
        for j in i + 1..4 {
            let cos = -normals[i].dot(normals[j]);
            smallest = smallest.min(cos.clamp(-1.0, 1.0).acos().to_degrees());
        }
    }
    smallest
}

#[cfg(test)]
mod tests {
    use super::*;

    fn two_tets() -> TetMesh {
        let vertices = vec![Vec3::ZERO, Vec3::X, Vec3::Y, Vec3::Z, Vec3::ONE];
        TetMesh { vertices, tets: vec![[0, 1, 2, 3], [1, 2, 3, 4]] }
    }

    #[test]
    fn faces_are_found_and_shared_once() {
        let m = two_tets();
        assert!(m.volume_of(0) > 0.0);
        let n = m.neighbours();
        assert_eq!(n[0], [1, NONE, NONE, NONE]);
        assert_eq!(n[1][3], 0);
        assert_eq!(m.boundary_faces(&n).len(), 6);
    }

    #[test]
    fn boundary_faces_face_outwards() {
        let m = TetMesh { vertices: vec![Vec3::ZERO, Vec3::X, Vec3::Y, Vec3::Z], tets: vec![[0, 1, 2, 3]] };
        let centre = m.centroid(0);
        for f in m.boundary_faces(&m.neighbours()) {
            let [a, b, c] = f.map(|i| m.vertices[i as usize]);
            assert!((b - a).cross(c - a).dot(a - centre) > 0.0, "face {f:?} faces inwards");
        }
    }

    #[test]
    fn barycentric_coordinates_rebuild_the_point() {
        let m = two_tets();
        let p = Vec3::new(0.2, 0.3, 0.1);
        let b = m.barycentric(0, p);
        let back: Vec3 = m.corners(0).iter().zip(b).map(|(v, w)| *v * w).sum();
        assert!((back - p).length() < 1e-6 && b.iter().all(|w| *w >= 0.0));
        assert!(m.barycentric(0, Vec3::ONE).iter().any(|w| *w < 0.0));
    }

    #[test]
    fn rings_list_each_neighbour_once() {
        let m = two_tets();
        let (off, list) = m.one_rings();
        assert_eq!(&list[off[0]..off[1]], &[1, 2, 3]);
        assert_eq!(&list[off[1]..off[2]], &[0, 2, 3, 4]);
        let (off, list) = m.vertex_tets();
        assert_eq!(&list[off[2]..off[3]], &[0, 1]);
    }

    #[test]
    fn the_lattice_fills_its_box_with_matching_faces() {
        let m = cube_lattice([3, 2, 1], 0.5);
        assert_eq!(m.tets.len(), 36);
        assert!((0..36).all(|t| m.volume_of(t) > 0.0));
        assert!((m.volume() - 1.5 * 0.5).abs() < 1e-5);
        // the box surface: 2 triangles per boundary square
        assert_eq!(m.boundary_faces(&m.neighbours()).len(), 2 * (2 * (6 + 3 + 2)));
        assert!((m.min_dihedral_degrees() - 45.0).abs() < 0.1, "{}", m.min_dihedral_degrees());
    }

    #[test]
    fn regular_tet_dihedral_is_70_degrees() {
        let c = [
            Vec3::new(1.0, 1.0, 1.0),
            Vec3::new(1.0, -1.0, -1.0),
            Vec3::new(-1.0, 1.0, -1.0),
            Vec3::new(-1.0, -1.0, 1.0),
        ];
        assert!((min_dihedral(c) - 70.53).abs() < 0.1);
    }
}
