//! Where a point of a filled model takes its texture: the tet holding it or, for a point of
//! the input solid that no tet holds (the tets approximate the input surface to within a
//! fraction of a tet edge), the tet of the nearest boundary face, its affine map extended
//! past the face (barycentric weights not clamped).
//!
//! ```text
//!   p --TetGrid--> tet holding p ? --yes--> (tet, weights ≥ 0)
//!                                  --no---> nearest boundary face (rings of cells) -> (its tet, weights)
//! ```
//!
//! Extending the nearest face's map keeps the texture continuous across the face; where the
//! nearest face changes from one tet to its neighbour, the two maps agree on their shared
//! edge and differ away from it by the distance times the difference of their gradients,
//! so a point a fraction of an edge outside sees a step of a fraction of that difference.

use super::tets::{FACES, NONE, TetGrid, TetMesh};
use crate::mesh::closest_on_triangle;
use glam::Vec3;

/// A point's tet and its barycentric weights there (some negative outside the tets).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Location {
    /// The tet whose patches colour the point.
    pub tet: u32,
    /// Barycentric weights of the point in the tet (they sum to 1).
    pub weights: [f32; 4],
    /// Whether the tet holds the point.
    pub inside: bool,
}

/// The tets and boundary faces of a mesh, binned for point queries.
#[derive(Debug, Clone)]
pub struct Locator {
    tets: TetGrid,
    lo: Vec3,
    cell: f32,
    dims: [usize; 3],
    /// Per cell, the range of `faces` listed there (offsets, one more than cells).
    offsets: Vec<u32>,
    /// Boundary faces by cell: (tet, corners).
    faces: Vec<(u32, [Vec3; 3])>,
}

impl Locator {
    /// The locator of `mesh`: its tets on a grid of about one tet per cell (coarser when
    /// long tets would need too many entries), its boundary faces on the same cells.
    pub fn new(mesh: &TetMesh) -> Locator {
        let tets = [128, 32, 8, 1]
            .into_iter()
            .find_map(|cells| TetGrid::at_most(mesh, cells).ok())
            .unwrap_or_else(|| TetGrid::at_most(mesh, 1).expect("one cell holds every tet once"));
        let (lo, cell, dims) = tets.layout();
        let neighbours = mesh.neighbours();
        let cell_of = |p: Vec3| {
            let c = ((p - lo) / cell).floor().max(Vec3::ZERO);
            [0, 1, 2].map(|k| (c[k].min(u32::MAX as f32) as usize).min(dims[k] - 1))
        };
        let mut pairs: Vec<(u32, u32, [Vec3; 3])> = Vec::new();
        for (t, tet) in mesh.tets.iter().enumerate() {
            for (k, face) in FACES.iter().enumerate() {
                if neighbours[t][k] != NONE {
                    continue;
                }
                let corners = face.map(|s| mesh.vertices[tet[s] as usize]);
                let (a, b) = (corners[0].min(corners[1]).min(corners[2]), corners[0].max(corners[1]).max(corners[2]));
                let (a, b) = (cell_of(a), cell_of(b));
                for z in a[2]..=b[2] {
                    for y in a[1]..=b[1] {
                        for x in a[0]..=b[0] {
                            pairs.push(((x + dims[0] * (y + dims[1] * z)) as u32, t as u32, corners));
                        }
                    }
                }
            }
        }
        pairs.sort_by_key(|p| (p.0, p.1));
        let mut offsets = vec![0u32; dims.iter().product::<usize>() + 1];
        pairs.iter().for_each(|p| offsets[p.0 as usize + 1] += 1);
        for i in 1..offsets.len() {
            offsets[i] += offsets[i - 1];
        }
        let faces = pairs.into_iter().map(|(_, t, c)| (t, c)).collect();
        Locator { tets, lo, cell, dims, offsets, faces }
    }

    /// Where `p` takes its texture; `None` for a point that is not finite or a mesh
    /// without tets.
    pub fn locate(&self, mesh: &TetMesh, p: Vec3) -> Option<Location> {
        if !p.is_finite() {
            return None;
        }
        if let Some(t) = self.tets.locate(mesh, p) {
            return Some(Location { tet: t, weights: mesh.barycentric(t as usize, p), inside: true });
        }
        let tet = self.nearest_face(p)?;
        Some(Location { tet, weights: mesh.barycentric(tet as usize, p), inside: false })
    }

    /// The tet of the boundary face nearest `p` (the lowest tet among equals),
    /// searched in growing rings of cells until no cell left can hold a nearer face.
    fn nearest_face(&self, p: Vec3) -> Option<u32> {
        let c = ((p - self.lo) / self.cell).floor();
        let centre = [0, 1, 2].map(|k| c[k].clamp(0.0, (self.dims[k] - 1) as f32) as i64);
        let dims = self.dims.map(|d| d as i64);
        let mut best: Option<(f32, u32)> = None;
        for r in 0.. {
            let lo = centre.map(|c| c - r);
            let hi = [0, 1, 2].map(|k| centre[k] + r);
            for z in lo[2].max(0)..=hi[2].min(dims[2] - 1) {
                for y in lo[1].max(0)..=hi[1].min(dims[1] - 1) {
                    for x in lo[0].max(0)..=hi[0].min(dims[0] - 1) {
                        let ring = [x, y, z].iter().zip(centre).any(|(v, c)| (v - c).abs() == r);
                        if ring {
                            self.nearest_in((x + dims[0] * (y + dims[1] * z)) as usize, p, &mut best);
                        }
                    }
                }
            }
            // faces not yet seen lie in cells beyond one of the box's sides inside the grid
            let mut bound = f32::INFINITY;
            for k in 0..3 {
                if lo[k] > 0 {
                    bound = bound.min(p[k] - (self.lo[k] + lo[k] as f32 * self.cell));
                }
                if hi[k] < dims[k] - 1 {
                    bound = bound.min(self.lo[k] + (hi[k] + 1) as f32 * self.cell - p[k]);
                }
            }
            if bound == f32::INFINITY || best.is_some_and(|(d, _)| d <= bound) {
                break;
            }
        }
        best.map(|(_, t)| t)
    }

    /// Keeps in `best` the nearer of it and the faces of cell `i`.
    fn nearest_in(&self, i: usize, p: Vec3, best: &mut Option<(f32, u32)>) {
        for &(tet, corners) in &self.faces[self.offsets[i] as usize..self.offsets[i + 1] as usize] {
            let d = p.distance(closest_on_triangle(p, corners));
            if best.is_none_or(|(b, t)| d < b || (d == b && tet < t)) {
                *best = Some((d, tet));
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::fill::tets::cube_lattice;

    #[test]
    fn points_inside_find_their_tet_and_points_outside_the_nearest_face() {
        let mesh = cube_lattice([4, 4, 4], 0.25);
        let locator = Locator::new(&mesh);
        let inside = locator.locate(&mesh, Vec3::new(0.3, 0.6, 0.45)).unwrap();
        assert!(inside.inside && inside.weights.iter().all(|w| *w >= -1e-5));
        // just above the top face: the tet under it, one weight a little below 0
        for p in [Vec3::new(0.4, 1.02, 0.6), Vec3::new(-0.05, 0.5, 0.5), Vec3::new(1.3, 1.3, 1.3)] {
            let l = locator.locate(&mesh, p).unwrap();
            assert!(!l.inside, "{p}");
            let c = mesh.corners(l.tet as usize);
            let near =
                FACES.iter().map(|f| p.distance(closest_on_triangle(p, f.map(|s| c[s])))).fold(f32::INFINITY, f32::min);
            // no tet of the mesh comes nearer
            let nearest = (0..mesh.tets.len())
                .flat_map(|t| {
                    let c = mesh.corners(t);
                    FACES.map(|f| p.distance(closest_on_triangle(p, f.map(|s| c[s]))))
                })
                .fold(f32::INFINITY, f32::min);
            assert!((near - nearest).abs() < 1e-6, "{p}: {near} against {nearest}");
            let back: Vec3 = (0..4).map(|k| c[k] * l.weights[k]).sum();
            assert!(back.distance(p) < 1e-5, "the weights extend the tet's map to {p}");
        }
        assert_eq!(locator.locate(&mesh, Vec3::NAN), None);
    }
}
