//! Which lattice points are inside a closed mesh: ray parity along +x against the triangles
//! bucketed by the cells of a (y, z) grid their bounding boxes touch.
//!
//! A ray crosses a triangle when its (y, z) point lies inside the triangle's projection. The
//! edge tests are the watertight ones of the voxelizer ([`crate::mesh::voxelize`]): an edge
//! shared by two triangles gives the same answer from both sides and a point exactly on an
//! edge or a corner counts as moved by an infinitesimal `(ε, ε²)`, so a ray through a
//! shared edge or corner is counted once. Parity ignores orientation.

use super::buckets;
use crate::mesh::Mesh;
use crate::mesh::voxelize::edge;
use glam::DVec3;

/// The triangles of a closed mesh, bucketed by (y, z) grid cells.
pub(super) struct RayGrid {
    tris: Vec<[DVec3; 3]>,
    origin: [f64; 2],
    cell: f64,
    dims: [usize; 2],
    /// The triangles of cell `c` are `ids[offsets[c]..offsets[c + 1]]`.
    offsets: Vec<usize>,
    ids: Vec<u32>,
}

impl RayGrid {
    /// Buckets the triangles of `mesh` on a grid of `dims` square cells of side `cell` whose
    /// corner is at `origin` (y, z). Rays outside the grid see no triangle.
    pub(super) fn new(mesh: &Mesh, origin: [f64; 2], cell: f64, dims: [usize; 2]) -> RayGrid {
        let tris: Vec<[DVec3; 3]> = mesh
            .triangles
            .iter()
            .map(|t| sorted(*t).map(|i| mesh.vertices[i as usize].as_dvec3()))
            .filter(|&[a, b, c]| (b.y - a.y) * (c.z - a.z) != (b.z - a.z) * (c.y - a.y))
            .collect();
        let mut grid = RayGrid { tris, origin, cell, dims, offsets: Vec::new(), ids: Vec::new() };
        let mut pairs: Vec<(usize, u32)> = Vec::new();
        for (id, t) in grid.tris.iter().enumerate() {
            let [(y0, y1), (z0, z1)] = grid.span(t);
            pairs.extend((z0..z1).flat_map(|k| (y0..y1).map(move |j| (j + dims[0] * k, id as u32))));
        }
        (grid.offsets, grid.ids) = buckets(pairs, dims[0] * dims[1]);
        grid
    }

    /// The cell ranges (y, z) a triangle's bounding box touches, widened by a hair so that
    /// rounding never leaves a triangle out of a cell whose rays can hit it.
    fn span(&self, [a, b, c]: &[DVec3; 3]) -> [(usize, usize); 2] {
        let (lo, hi) = (a.min(*b).min(*c), a.max(*b).max(*c));
        let pad = 1e-6 * self.cell;
        let range = |axis: usize, lo: f64, hi: f64| {
            let first = ((lo - pad - self.origin[axis]) / self.cell).floor().max(0.0) as usize;
            let end = ((hi + pad - self.origin[axis]) / self.cell).floor() + 1.0;
            (first, (end.max(0.0) as usize).min(self.dims[axis]))
        };
        [range(0, lo.y, hi.y), range(1, lo.z, hi.z)]
    }

    /// The x of every crossing of the ray `(t, y, z)` with the mesh, sorted, into `out`.
    pub(super) fn crossings(&self, y: f64, z: f64, out: &mut Vec<f64>) {
        out.clear();
        let j = ((y - self.origin[0]) / self.cell).floor();
        let k = ((z - self.origin[1]) / self.cell).floor();
        if j < 0.0 || k < 0.0 || j >= self.dims[0] as f64 || k >= self.dims[1] as f64 {
            return;
        }
        let c = j as usize + self.dims[0] * k as usize;
        let ids = &self.ids[self.offsets[c]..self.offsets[c + 1]];
        out.extend(ids.iter().filter_map(|&id| crossing(&self.tris[id as usize], y, z)));
        out.sort_unstable_by(f64::total_cmp);
    }
}

/// The corner indices in increasing order: the same triangle whichever way it faces, so
/// that an inverted mesh gives bit-identical crossings.
pub(super) fn sorted(mut t: [u32; 3]) -> [u32; 3] {
    t.sort_unstable();
    t
}

/// Where the ray `(t, y, z)` crosses the triangle, if it does.
fn crossing(&[a, b, c]: &[DVec3; 3], y: f64, z: f64) -> Option<f64> {
    let (wa, sa) = edge(b, c, y, z);
    let (wb, sb) = edge(c, a, y, z);
    let (wc, sc) = edge(a, b, y, z);
    if sa != sb || sb != sc {
        return None;
    }
    Some((wa * a.x + wb * b.x + wc * c.x) / (wa + wb + wc))
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::Vec3;

    #[test]
    fn rays_through_the_shared_diagonal_of_a_square_cross_once() {
        // Two triangles of the square x = 1, (y, z) in [0, 2]², split along y = z.
        let v = vec![
            Vec3::new(1.0, 0.0, 0.0),
            Vec3::new(1.0, 2.0, 0.0),
            Vec3::new(1.0, 2.0, 2.0),
            Vec3::new(1.0, 0.0, 2.0),
        ];
        let mesh = Mesh::new(v, vec![[0, 1, 2], [0, 2, 3]]).unwrap();
        let grid = RayGrid::new(&mesh, [-1.0, -1.0], 0.5, [8, 8]);
        let mut out = Vec::new();
        for (y, z, hits) in [(1.0, 1.0, 1), (0.0, 0.0, 1), (0.5, 1.5, 1), (2.5, 1.0, 0), (1.0, -0.5, 0)] {
            grid.crossings(y, z, &mut out);
            assert_eq!(out.len(), hits, "ray at ({y}, {z}): {out:?}");
            assert!(out.iter().all(|&x| x == 1.0));
        }
    }
}
