//! Closest points on a triangle mesh: the triangles are bucketed by the cells of a uniform
//! 3D grid their bounding boxes touch, and a query visits shells of cells around its own
//! until no unvisited cell can hold anything closer than the best point found.

use super::buckets;
use super::inside::sorted;
use crate::mesh::{Mesh, closest_on_triangle};
use glam::Vec3;

/// How many cells, and (cell, triangle) entries, the grid may hold before its cells are
/// made coarser.
const ENTRY_BUDGET: usize = 1 << 23;

/// The triangles of a mesh bucketed on a uniform grid.
pub(crate) struct Surface {
    tris: Vec<[Vec3; 3]>,
    lo: Vec3,
    cell: f32,
    dims: [usize; 3],
    /// The triangles of cell `c` are `ids[offsets[c]..offsets[c + 1]]`.
    offsets: Vec<usize>,
    ids: Vec<u32>,
}

impl Surface {
    /// Buckets the triangles of `mesh` on cells of their mean edge length, or `max_cell` if
    /// that is smaller (a query near the surface then looks at a few cells of a few triangles
    /// each), made coarser while the grid would hold too many entries.
    pub(crate) fn new(mesh: &Mesh, max_cell: f32) -> Surface {
        let tris: Vec<[Vec3; 3]> =
            mesh.triangles.iter().map(|t| sorted(*t).map(|i| mesh.vertices[i as usize])).collect();
        let edges: f64 = tris.iter().map(|[a, b, c]| f64::from(a.distance(*b) + b.distance(*c) + c.distance(*a))).sum();
        let cell = max_cell.min((edges / (3 * tris.len()) as f64) as f32);
        let (lo, hi) = mesh.bounds();
        let mut s = Surface { tris, lo, cell, dims: [1; 3], offsets: Vec::new(), ids: Vec::new() };
        loop {
            s.dims = ((hi - lo) / s.cell).to_array().map(|n| (n.floor() as usize + 1).min(1 << 20));
            let entries: usize = s.tris.iter().map(|t| s.span(t).iter().map(|(a, b)| b - a).product::<usize>()).sum();
            let cells: usize = s.dims.iter().product();
            if cells <= ENTRY_BUDGET && entries <= ENTRY_BUDGET.max(8 * s.tris.len()) {
                break;
            }
            s.cell *= 2.0;
        }
        s.bucket();
        s
    }

    fn bucket(&mut self) {
        let mut pairs: Vec<(usize, u32)> = Vec::new();
        for (id, t) in self.tris.iter().enumerate() {
            let [(x0, x1), (y0, y1), (z0, z1)] = self.span(t);
            for z in z0..z1 {
                for y in y0..y1 {
                    pairs.extend((x0..x1).map(|x| (self.index([x, y, z]), id as u32)));
                }
            }
        }
        (self.offsets, self.ids) = buckets(pairs, self.dims.iter().product());
    }

    fn index(&self, [x, y, z]: [usize; 3]) -> usize {
        x + self.dims[0] * (y + self.dims[1] * z)
    }

    /// The cell of `p` along each axis, clamped to the grid.
    fn cell_of(&self, p: Vec3) -> [usize; 3] {
        let c = ((p - self.lo) / self.cell).to_array();
        [0, 1, 2].map(|a| (c[a].max(0.0) as usize).min(self.dims[a] - 1))
    }

    /// The cell ranges (end exclusive) the bounding box of a triangle touches.
    fn span(&self, [a, b, c]: &[Vec3; 3]) -> [(usize, usize); 3] {
        let (lo, hi) = (self.cell_of(a.min(*b).min(*c)), self.cell_of(a.max(*b).max(*c)));
        [0, 1, 2].map(|k| (lo[k], hi[k] + 1))
    }

    /// The point of the mesh closest to `p`.
    pub(super) fn closest(&self, p: Vec3) -> Vec3 {
        self.closest_triangle(p).1
    }

    /// The triangle of the mesh closest to `p` (its index in the mesh; the lowest index
    /// among equally close ones) and the closest point on it.
    pub(crate) fn closest_triangle(&self, p: Vec3) -> (usize, Vec3) {
        let home = self.cell_of(p);
        let mut best = (f32::INFINITY, p, u32::MAX);
        for r in 0.. {
            let lo = home.map(|h| h.saturating_sub(r));
            let hi = [0, 1, 2].map(|a| (home[a] + r).min(self.dims[a] - 1));
            self.visit_shell(p, home, r, (lo, hi), &mut best);
            match self.unvisited_distance(p, lo, hi) {
                Some(d) if best.0 > d * d => continue,
                _ => break,
            }
        }
        (best.2 as usize, best.1)
    }

    /// Tests the triangles of the cells in `lo..=hi` at Chebyshev distance `r` from `home`.
    fn visit_shell(
        &self,
        p: Vec3,
        home: [usize; 3],
        r: usize,
        (lo, hi): ([usize; 3], [usize; 3]),
        best: &mut (f32, Vec3, u32),
    ) {
        for z in lo[2]..=hi[2] {
            for y in lo[1]..=hi[1] {
                for x in lo[0]..=hi[0] {
                    let ring = [x, y, z].iter().zip(home).map(|(&c, h)| c.abs_diff(h)).max().unwrap_or(0);
                    if ring != r {
                        continue;
                    }
                    if self.cell_distance_squared(p, [x, y, z]) >= best.0 {
                        continue;
                    }
                    let c = self.index([x, y, z]);
                    for &id in &self.ids[self.offsets[c]..self.offsets[c + 1]] {
                        let q = closest_on_triangle(p, self.tris[id as usize]);
                        let d = q.distance_squared(p);
                        if d < best.0 || (d == best.0 && id < best.2) {
                            *best = (d, q, id);
                        }
                    }
                }
            }
        }
    }

    /// The squared distance from `p` to the box of cell `c`.
    fn cell_distance_squared(&self, p: Vec3, c: [usize; 3]) -> f32 {
        let lo = self.lo + Vec3::from_array(c.map(|i| i as f32)) * self.cell;
        (lo - p).max(p - lo - self.cell).max(Vec3::ZERO).length_squared()
    }

    /// A lower bound on the distance from `p` to any triangle outside the cells `lo..=hi`,
    /// or `None` when those are all the cells.
    fn unvisited_distance(&self, p: Vec3, lo: [usize; 3], hi: [usize; 3]) -> Option<f32> {
        let mut bound: Option<f32> = None;
        for a in 0..3 {
            if lo[a] > 0 {
                let d = p[a] - (self.lo[a] + lo[a] as f32 * self.cell);
                bound = Some(bound.map_or(d, |b| b.min(d)));
            }
            if hi[a] + 1 < self.dims[a] {
                let d = self.lo[a] + (hi[a] + 1) as f32 * self.cell - p[a];
                bound = Some(bound.map_or(d, |b| b.min(d)));
            }
        }
        bound.map(|b| b.max(0.0))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_grid_finds_what_brute_force_finds() {
        // A wavy closed-ish strip of triangles and points around it, near and far.
        let n = 24;
        let vertices: Vec<Vec3> = (0..2 * n)
            .map(|i| {
                let t = (i / 2) as f32 / n as f32 * 6.0;
                Vec3::new(t, t.sin(), if i % 2 == 0 { 0.0 } else { 1.5 })
            })
            .collect();
        let triangles = (0..2 * n as u32 - 2).map(|i| [i, i + 1, i + 2]).collect();
        let mesh = Mesh::new(vertices, triangles).unwrap();
        let surface = Surface::new(&mesh, 0.2);
        for i in 0..200 {
            let f = i as f32;
            let p = Vec3::new((f * 0.37) % 8.0 - 1.0, (f * 0.71) % 4.0 - 2.0, (f * 0.53) % 3.0 - 0.7);
            let brute = mesh
                .triangles
                .iter()
                .map(|t| closest_on_triangle(p, t.map(|i| mesh.vertices[i as usize])))
                .fold(f32::INFINITY, |d, q| d.min(q.distance(p)));
            let found = surface.closest(p).distance(p);
            assert!((found - brute).abs() < 1e-5, "point {p}: grid {found}, brute force {brute}");
        }
    }
}
