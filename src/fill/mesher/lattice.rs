//! The cube lattice, its Kuhn split into tets, and the cut: the tets whose centroids lie
//! inside the mesh, as lattice vertex ids, and then as a compact tet mesh. Some cubes may be
//! split into eight, and the cubes beside them cut into fans around their centres, so that
//! all tets still meet face to face (see [`Lattice::refine_near`]).

use super::inside::RayGrid;
use crate::error::{Error, Result};
use crate::fill::tets::TetMesh;
use glam::{DVec3, Vec3};
use rayon::prelude::*;

/// The most lattice columns (cubes in y times cubes in z) a mesh may need.
const MAX_COLUMNS: usize = 1 << 24;

/// The axis orderings `(a, b, c)` of the Kuhn split: the even permutations, then the odd.
const KUHN: [[usize; 3]; 6] = [[0, 1, 2], [1, 2, 0], [2, 0, 1], [0, 2, 1], [2, 1, 0], [1, 0, 2]];

/// The cube lattice: `cubes` cubes of side `h` per axis from `origin`, some of them split
/// into eight (see [`Lattice::refine_near`]).
pub(super) struct Lattice {
    pub(super) origin: DVec3,
    pub(super) h: f64,
    pub(super) cubes: [usize; 3],
    /// The cubes split into eight, as `i + nx (j + ny k)`, sorted: few, where a dense flag
    /// per cube could take more memory than the tets where the box is mostly empty.
    fine: Vec<usize>,
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
        Ok(Lattice { origin: (lo + hi) / 2.0 - size / 2.0, h, cubes, fine: Vec::new() })
    }

    /// The id of lattice vertex `(i, j, k)`.
    fn id(&self, ijk: [usize; 3]) -> u64 {
        self.half_id(ijk.map(|x| 2 * x))
    }

    /// The id of the point `(x, y, z)` of the lattice of half the spacing (lattice vertex
    /// `(i, j, k)` is `(2i, 2j, 2k)` there), which holds the vertices of the split cubes.
    fn half_id(&self, [x, y, z]: [usize; 3]) -> u64 {
        let [nx, ny, _] = self.cubes.map(|n| 2 * n as u64 + 1);
        x as u64 + nx * (y as u64 + ny * z as u64)
    }

    /// The position of the point with id `id` (see [`Lattice::half_id`]).
    fn position(&self, id: u64) -> Vec3 {
        let [nx, ny, _] = self.cubes.map(|n| 2 * n as u64 + 1);
        let xyz = DVec3::new((id % nx) as f64, (id / nx % ny) as f64, (id / nx / ny) as f64);
        (self.origin + xyz * (self.h / 2.0)).as_vec3()
    }

    /// Tet `p` (an index into [`KUHN`]) of cube `cube`, positively oriented, as vertex ids.
    fn kuhn_tet(&self, cube: [usize; 3], p: usize) -> [u64; 4] {
        kuhn_points(cube, p).map(|ijk| self.id(ijk))
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
            if !self.fine.is_empty() {
                cells.retain(|&(i, _)| self.plain([i, j, k]));
            }
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

    /// Splits the cube holding each point into eight cubes of half the side, each split
    /// the Kuhn way. The cubes that share a face or an edge with a split one are cut into
    /// tets around their centre instead (see [`Lattice::cube_tets`]), so that the tets
    /// meet face to face.
    pub(super) fn refine_near(&mut self, points: &[Vec3]) {
        for p in points {
            let at = ((p.as_dvec3() - self.origin) / self.h).floor().to_array();
            let cube = [0, 1, 2].map(|a| at[a].clamp(0.0, (self.cubes[a] - 1) as f64) as usize);
            self.fine.push(self.cube_index(cube));
        }
        self.fine.sort_unstable();
        self.fine.dedup();
    }

    fn cube_index(&self, [i, j, k]: [usize; 3]) -> usize {
        let [nx, ny, _] = self.cubes;
        i + nx * (j + ny * k)
    }

    /// Whether the cube at `c` (which may lie off the lattice) is split into eight.
    fn is_fine(&self, c: [isize; 3]) -> bool {
        let inside = (0..3).all(|a| (0..self.cubes[a] as isize).contains(&c[a]));
        inside && self.fine.binary_search(&self.cube_index(c.map(|x| x as usize))).is_ok()
    }

    /// Whether cube `c` is split the plain Kuhn way: neither it nor a cube sharing a face or
    /// an edge with it is split into eight.
    fn plain(&self, c: [usize; 3]) -> bool {
        let c = c.map(|x| x as isize);
        let near = (0..27).map(|n| [n % 3 - 1, n / 3 % 3 - 1, n / 9 - 1]);
        !near
            .filter(|d: &[isize; 3]| d.iter().filter(|&&x| x != 0).count() < 3)
            .any(|[a, b, e]| self.is_fine([c[0] + a, c[1] + b, c[2] + e]))
    }

    /// The tets of the cubes not split the plain way whose centroids are inside, by cube.
    pub(super) fn cut_graded(&self, rays: &RayGrid) -> Vec<[u64; 4]> {
        let [nx, ny, nz] = self.cubes;
        // the split cubes and the cubes around them, in index order
        let mut cubes: Vec<[usize; 3]> = Vec::new();
        for &n in &self.fine {
            let [i, j, k] = [n % nx, n / nx % ny, n / nx / ny];
            let span = |x: usize, n: usize| x.saturating_sub(1)..(x + 2).min(n);
            for k in span(k, nz) {
                for j in span(j, ny) {
                    cubes.extend(span(i, nx).map(|i| [i, j, k]));
                }
            }
        }
        cubes.sort_unstable_by_key(|&c| self.cube_index(c));
        cubes.dedup();
        cubes.retain(|&c| !self.plain(c));
        let kept = cubes.par_iter().map(|&c| {
            let mut crossings = Vec::new();
            let tets = self.cube_tets(c).into_iter();
            let inside = tets.filter(|tet| {
                let sum = tet.iter().fold([0usize; 3], |s, p| [s[0] + p[0], s[1] + p[1], s[2] + p[2]]);
                let at = self.origin + DVec3::from_array(sum.map(|x| x as f64)) * (self.h / 8.0);
                rays.crossings(at.y, at.z, &mut crossings);
                crossings.iter().filter(|&&x| x <= at.x).count() % 2 == 1
            });
            inside.map(|tet| tet.map(|p| self.half_id(p))).collect::<Vec<_>>()
        });
        kept.collect::<Vec<_>>().concat()
    }

    /// The tets of cube `c`, positively oriented, as points of the lattice of half the
    /// spacing: a split cube's eight cubes split the Kuhn way, or else a fan from the
    /// cube's centre over the triangles of its faces (see [`Lattice::face_triangles`]).
    fn cube_tets(&self, c: [usize; 3]) -> Vec<[[usize; 3]; 4]> {
        let base = c.map(|x| 2 * x);
        let mut tets = Vec::new();
        if self.is_fine(c.map(|x| x as isize)) {
            for s in 0..8 {
                let corner = [base[0] + (s & 1), base[1] + (s >> 1 & 1), base[2] + (s >> 2)];
                tets.extend((0..6).map(|p| kuhn_points(corner, p)));
            }
            return tets;
        }
        let centre = base.map(|x| x + 1);
        for axis in 0..3 {
            for side in 0..2 {
                let (u, v) = ((axis + 1) % 3, (axis + 2) % 3);
                for triangle in self.face_triangles(c, axis, side) {
                    let [a, b, d] = triangle.map(|[du, dv]| {
                        let mut p = base;
                        p[axis] += 2 * side;
                        p[u] += du;
                        p[v] += dv;
                        p
                    });
                    tets.push(if orientation([a, b, d, centre]) > 0 { [a, b, d, centre] } else { [b, a, d, centre] });
                }
            }
        }
        tets
    }

    /// The triangles of face `(axis, side)` of the unsplit cube `c`, as `(u, v)` offsets
    /// (0 to 2, in half cubes) along the two other axes in cyclic order. Both cubes that
    /// share the face triangulate it the same way: as the split neighbour's eight Kuhn
    /// triangles if it is split, else as a fan from the face's centre if an edge of the
    /// face is split (one of the other cubes around it is), else along the Kuhn diagonal.
    fn face_triangles(&self, c: [usize; 3], axis: usize, side: usize) -> Vec<[[usize; 2]; 3]> {
        let (u, v) = ((axis + 1) % 3, (axis + 2) % 3);
        let step = |c: [isize; 3], a: usize, up: bool| {
            let mut c = c;
            c[a] += if up { 1 } else { -1 };
            c
        };
        let c = c.map(|x| x as isize);
        let across = step(c, axis, side == 1);
        if self.is_fine(across) {
            let squares = [[0, 0], [1, 0], [0, 1], [1, 1]];
            return squares
                .iter()
                .flat_map(|&[a, b]| [[[a, b], [a + 1, b], [a + 1, b + 1]], [[a, b], [a + 1, b + 1], [a, b + 1]]])
                .collect();
        }
        // whether the face's edge on the near or far (`up`) side along in-face axis `other`
        // is split: one of the two other cubes around that edge is
        let split = |other: usize, up: bool| {
            let beside = step(c, other, up);
            self.is_fine(beside) || self.is_fine(step(across, other, up))
        };
        let (v0, v2, u0, u2) = (split(v, false), split(v, true), split(u, false), split(u, true));
        if !(v0 || v2 || u0 || u2) {
            return vec![[[0, 0], [2, 0], [2, 2]], [[0, 0], [2, 2], [0, 2]]];
        }
        // the face's outline, counterclockwise in (u, v), with the midpoints of split edges
        let mut outline = vec![[0, 0]];
        for (split, mid, corner) in
            [(v0, [1, 0], [2, 0]), (u2, [2, 1], [2, 2]), (v2, [1, 2], [0, 2]), (u0, [0, 1], [0, 0])]
        {
            if split {
                outline.push(mid);
            }
            outline.push(corner);
        }
        outline.windows(2).map(|w| [w[0], w[1], [1, 1]]).collect()
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

/// Tet `p` (an index into [`KUHN`]) of the unit cube at `corner`, positively oriented.
fn kuhn_points(corner: [usize; 3], p: usize) -> [[usize; 3]; 4] {
    let [a, b, _] = KUHN[p];
    let mut c = corner;
    let v0 = c;
    c[a] += 1;
    let v1 = c;
    c[b] += 1;
    let v2 = c;
    let v3 = corner.map(|x| x + 1);
    // The volume has the sign of the permutation.
    if p < 3 { [v0, v1, v2, v3] } else { [v0, v2, v1, v3] }
}

/// Six times the signed volume of a tet of lattice points.
fn orientation(tet: [[usize; 3]; 4]) -> i64 {
    let [o, a, b, c] = tet.map(|p| p.map(|x| x as i64));
    let d = |p: [i64; 3]| [p[0] - o[0], p[1] - o[1], p[2] - o[2]];
    let (a, b, c) = (d(a), d(b), d(c));
    a[0] * (b[1] * c[2] - b[2] * c[1]) - a[1] * (b[0] * c[2] - b[2] * c[0]) + a[2] * (b[0] * c[1] - b[1] * c[0])
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::mesh::shapes::cuboid;

    /// Every tet of a lattice of 6³ cubes of side 0.5 (from -1.5 to 1.5) wholly inside a
    /// box, with the cubes holding `split` split into eight.
    fn every_tet(split: &[Vec3]) -> TetMesh {
        let mesh = cuboid(Vec3::splat(-5.0), Vec3::splat(5.0));
        let mut lattice = Lattice::new((Vec3::splat(-1.0), Vec3::splat(1.0)), 0.5).unwrap();
        lattice.refine_near(split);
        let [_, ny, nz] = lattice.cubes;
        let rays = RayGrid::new(&mesh, [lattice.origin.y, lattice.origin.z], lattice.h, [ny, nz]);
        let mut kept = lattice.cut(&rays);
        kept.extend(lattice.cut_graded(&rays));
        lattice.compact(kept)
    }

    #[test]
    fn split_cubes_and_their_neighbours_fill_the_lattice_face_to_face() {
        assert_eq!(every_tet(&[]).tets.len(), 6 * 216);
        // cube (2, 2, 2); (3, 3, 2) shares only an edge with it, (1, 1, 1) only a corner,
        // and (4, 2, 2) is a face away from it, beside the unsplit (3, 2, 2)
        let centre = |c: [f32; 3]| Vec3::from_array(c.map(|i| -1.5 + (i + 0.5) * 0.5));
        let split = [[2.0, 2.0, 2.0], [3.0, 3.0, 2.0], [1.0, 1.0, 1.0], [4.0, 2.0, 2.0]].map(centre);
        let tets = every_tet(&split);
        assert!((0..tets.tets.len()).all(|t| tets.volume_of(t) > 0.0));
        assert!((tets.volume() - 27.0).abs() < 1e-4, "{}", tets.volume());
        // the tets meet face to face: the only open faces are on the lattice's outside
        let open = tets.boundary_faces(&tets.neighbours());
        let outside = |f: &[u32; 3]| {
            let [a, b, c] = f.map(|v| tets.vertices[v as usize]);
            (0..3).any(|k| [a, b, c].iter().all(|p| (p[k].abs() - 1.5).abs() < 1e-5))
        };
        assert!(open.iter().all(outside), "{} open faces inside", open.iter().filter(|f| !outside(f)).count());
        assert_eq!(open.len(), 6 * 6 * 6 * 2);
        // the fans around the centres of the cubes beside split ones keep at least 35.26°
        // (the Kuhn tets have 45°)
        assert!(tets.min_dihedral_degrees() >= 35.0, "{}", tets.min_dihedral_degrees());
    }
}
