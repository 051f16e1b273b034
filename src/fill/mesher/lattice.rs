//! The cube lattice, its Kuhn split into tets, and the cut: the tets whose centroids lie
//! inside the mesh, as lattice vertex ids, and then as a compact tet mesh.

use super::inside::RayGrid;
use crate::error::{Error, Result};
use crate::fill::tets::TetMesh;
use glam::{DVec3, Vec3};
use rayon::prelude::*;

/// The most lattice columns (cubes in y times cubes in z) a mesh may need.
const MAX_COLUMNS: usize = 1 << 24;

/// The axis orderings `(a, b, c)` of the Kuhn split: the even permutations, then the odd.
const KUHN: [[usize; 3]; 6] = [[0, 1, 2], [1, 2, 0], [2, 0, 1], [0, 2, 1], [2, 1, 0], [1, 0, 2]];

/// The cube lattice: `cubes` cubes of side `h` per axis from `origin`.
pub(super) struct Lattice {
    pub(super) origin: DVec3,
    pub(super) h: f64,
    pub(super) cubes: [usize; 3],
}

impl Lattice {
    /// A lattice over the bounds plus at least one cube on each side, centred on them.
    pub(super) fn new((lo, hi): (Vec3, Vec3), h: f64) -> Result<Lattice> {
        let (lo, hi) = (lo.as_dvec3(), hi.as_dvec3());
        let cubes = ((hi - lo) / h).to_array().map(|n| n.ceil() as usize + 2);
        if cubes[1].saturating_mul(cubes[2]) > MAX_COLUMNS || cubes[0] > MAX_COLUMNS {
            let [x, y, z] = cubes;
            return Err(Error::invalid(format!(
                "the mesh is too thin for its bounding box: a lattice of spacing {h:.3e} over it needs \
                 {x}x{y}x{z} cubes; lower target_tets"
            )));
        }
        let size = DVec3::from_array(cubes.map(|n| n as f64)) * h;
        Ok(Lattice { origin: (lo + hi) / 2.0 - size / 2.0, h, cubes })
    }

    /// The id of lattice vertex `(i, j, k)`.
    fn id(&self, [i, j, k]: [usize; 3]) -> u64 {
        let [nx, ny, _] = self.cubes.map(|n| n as u64 + 1);
        i as u64 + nx * (j as u64 + ny * k as u64)
    }

    /// The position of the lattice vertex with id `id`.
    fn position(&self, id: u64) -> Vec3 {
        let [nx, ny, _] = self.cubes.map(|n| n as u64 + 1);
        let ijk = DVec3::new((id % nx) as f64, (id / nx % ny) as f64, (id / nx / ny) as f64);
        (self.origin + ijk * self.h).as_vec3()
    }

    /// Tet `p` (an index into [`KUHN`]) of cube `cube`, positively oriented, as vertex ids.
    fn kuhn_tet(&self, cube: [usize; 3], p: usize) -> [u64; 4] {
        let [a, b, _] = KUHN[p];
        let mut c = cube;
        let v0 = self.id(c);
        c[a] += 1;
        let v1 = self.id(c);
        c[b] += 1;
        let v2 = self.id(c);
        let v3 = self.id(cube.map(|x| x + 1));
        // The volume has the sign of the permutation.
        if p < 3 { [v0, v1, v2, v3] } else { [v0, v2, v1, v3] }
    }

    /// The tets whose centroids are inside, by z-slab, row and x, as vertex ids.
    pub(super) fn cut(&self, rays: &RayGrid) -> Vec<[u64; 4]> {
        let slabs: Vec<Vec<[u64; 4]>> = (0..self.cubes[2]).into_par_iter().map(|k| self.cut_slab(rays, k)).collect();
        slabs.concat()
    }

    /// The kept tets of the cubes with z index `k`.
    fn cut_slab(&self, rays: &RayGrid, k: usize) -> Vec<[u64; 4]> {
        let (mut out, mut crossings, mut cells) = (Vec::new(), Vec::new(), Vec::new());
        for j in 0..self.cubes[1] {
            cells.clear();
            for (p, perm) in KUHN.iter().enumerate() {
                // The centroid is p0 + (3 e_a + 2 e_b + e_c) / 4.
                let mut w = [0.0; 3];
                perm.iter().zip([0.75, 0.5, 0.25]).for_each(|(&axis, weight)| w[axis] = weight);
                let y = self.origin.y + (j as f64 + w[1]) * self.h;
                rays.crossings(y, self.origin.z + (k as f64 + w[2]) * self.h, &mut crossings);
                for span in crossings.chunks_exact(2) {
                    let (first, end) = (self.first_centroid(span[0], w[0]), self.first_centroid(span[1], w[0]));
                    cells.extend((first..end).map(|i| (i, p)));
                }
            }
            cells.sort_unstable();
            out.extend(cells.iter().map(|&(i, p)| self.kuhn_tet([i, j, k], p)));
        }
        out
    }

    /// The first cube along x whose centroid at offset `w` (in cubes) is at or after `x`.
    fn first_centroid(&self, x: f64, w: f64) -> usize {
        let n = self.cubes[0];
        let at = |i: usize| self.origin.x + (i as f64 + w) * self.h;
        let mut i = ((x - self.origin.x) / self.h - w).ceil().clamp(0.0, n as f64) as usize;
        while i > 0 && at(i - 1) >= x {
            i -= 1;
        }
        while i < n && at(i) < x {
            i += 1;
        }
        i
    }

    /// The tet mesh of the kept tets: only the vertices they use, numbered in id order.
    pub(super) fn compact(&self, kept: Vec<[u64; 4]>) -> TetMesh {
        let mut ids: Vec<u64> = kept.iter().flatten().copied().collect();
        ids.par_sort_unstable();
        ids.dedup();
        let tets = kept.par_iter().map(|t| t.map(|id| ids.partition_point(|&x| x < id) as u32)).collect();
        TetMesh { vertices: ids.par_iter().map(|&id| self.position(id)).collect(), tets }
    }
}
