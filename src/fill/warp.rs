//! Texture coordinates of a clump: the seed's affine map (thesis §6.2.4) and the
//! least-squares texture optimization that warps it along the tensor field (§6.2.5).
//!
//! ```text
//!   model space                      texture space [0,1]³
//!      R_i (scaled by s_i)              e_r
//!     ^                                ^
//!     |  tet i         J_i (from w)    |
//!     +---->  S_i     ----------->     +----> e_s      minimise Σ_i |J_i R_i - e_r|² + ...
//! ```
//! `J_i R_i` is linear in the vertex coordinates `w`: `Σ_k r_k w_k` with `r` the barycentric
//! coordinates of the vector `R_i` in tet i (they sum to 0). Each texture component is an
//! independent sparse least-squares problem; the seed's centre is pinned by a heavy row.

use super::solve::{Sparse, least_squares_each};
use super::tets::TetMesh;
use glam::{Mat3, Vec3};
use rayon::prelude::*;

/// Weight of the row pinning the seed's centre.
const PIN_WEIGHT: f64 = 30.0;

/// An orthonormal frame and scale: where one texture cube goes in model space.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Frame {
    /// Unit directions in model space that map to the texture axes `axes[0..3]`.
    pub dirs: [Vec3; 3],
    /// Model units per texture unit.
    pub scale: f32,
}

/// The rigid map of a frame: model point `p` -> texture point, sending `anchor` to `centre`.
#[derive(Debug, Clone, Copy)]
pub struct Rigid {
    rows: Mat3,
    anchor: Vec3,
    centre: Vec3,
}

impl Rigid {
    /// The map sending `frame.dirs[i]` (scaled) to texture axis `axes[i]` and `anchor` to `centre`.
    pub fn new(frame: &Frame, axes: [usize; 3], anchor: Vec3, centre: Vec3) -> Rigid {
        let mut rows = [Vec3::ZERO; 3];
        for i in 0..3 {
            rows[axes[i]] = frame.dirs[i] / frame.scale;
        }
        Rigid { rows: Mat3::from_cols(rows[0], rows[1], rows[2]).transpose(), anchor, centre }
    }

    /// The texture point of model point `p`.
    pub fn apply(&self, p: Vec3) -> Vec3 {
        self.centre + self.rows * (p - self.anchor)
    }
}

/// The barycentric coordinates (summing to 0) of the vector `a` in a tet whose edge
/// matrix has the `inverse`.
fn direction_weights(inverse: Mat3, a: Vec3) -> [f64; 4] {
    let local = inverse * a;
    let l = local.as_dvec3();
    [-(l.x + l.y + l.z), l.x, l.y, l.z]
}

/// One clump's optimization problem.
pub struct Warp<'a> {
    /// The mesh.
    pub mesh: &'a TetMesh,
    /// The clump's tets.
    pub tets: &'a [u32],
    /// The clump's vertices, sorted (the unknowns, in this order).
    pub vertices: &'a [u32],
    /// Per clump tet, its target frame.
    pub frames: &'a [Frame],
    /// Texture axes for the frame directions.
    pub axes: [usize; 3],
    /// The pinned seed tet (index into `tets`) and its texture centre.
    pub pin: (usize, Vec3),
    /// A texture component that is given, not solved (the depth axis of layered types).
    pub fixed: Option<usize>,
}

impl Warp<'_> {
    /// Improves `coords` (one per vertex, in `vertices` order) in place.
    pub fn solve(&self, coords: &mut [Vec3]) {
        let local = |v: u32| self.vertices.binary_search(&v).expect("clump vertex");
        // each tet's three rows, made side by side and pushed in tet order
        let rows: Vec<[[(usize, f64); 4]; 3]> = self
            .tets
            .par_iter()
            .zip(self.frames)
            .map(|(&t, frame)| {
                let tet = self.mesh.tets[t as usize].map(local);
                let inverse = self.mesh.edges(t as usize).inverse();
                frame.dirs.map(|dir| {
                    let r = direction_weights(inverse, dir * frame.scale);
                    std::array::from_fn(|k| (tet[k], r[k]))
                })
            })
            .collect();
        let mut a = Sparse::new(self.vertices.len());
        let mut targets: Vec<Vec3> = Vec::with_capacity(rows.len() * 3 + 1);
        for tet_rows in rows {
            for (k, row) in tet_rows.into_iter().enumerate() {
                a.push_row(row);
                let mut target = Vec3::ZERO;
                target[self.axes[k]] = 1.0;
                targets.push(target);
            }
        }
        let seed = self.mesh.tets[self.tets[self.pin.0] as usize];
        a.push_row(seed.iter().map(|&v| (local(v), PIN_WEIGHT * 0.25)));
        targets.push(self.pin.1 * PIN_WEIGHT as f32);
        let solved: Vec<usize> = (0..3).filter(|c| Some(*c) != self.fixed).collect();
        let bs: Vec<Vec<f64>> = solved.iter().map(|&c| targets.iter().map(|t| t[c] as f64).collect()).collect();
        let mut xs: Vec<Vec<f64>> = solved.iter().map(|&c| coords.iter().map(|w| w[c] as f64).collect()).collect();
        least_squares_each(&a, &bs, &mut xs, 1e-4, 300);
        for (&c, x) in solved.iter().zip(xs) {
            for (w, x) in coords.iter_mut().zip(x) {
                w[c] = x as f32;
            }
        }
    }
}

/// The Jacobian (model -> texture) of the affine map of tet `t` with corner coords `w`.
pub fn jacobian(mesh: &TetMesh, t: usize, w: [Vec3; 4]) -> Mat3 {
    let texture_edges = Mat3::from_cols(w[1] - w[0], w[2] - w[0], w[3] - w[0]);
    texture_edges * mesh.edges(t).inverse()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::fill::tets::cube_lattice;

    fn clump(mesh: &TetMesh) -> (Vec<u32>, Vec<u32>) {
        let tets: Vec<u32> = (0..mesh.tets.len() as u32).collect();
        let mut vertices: Vec<u32> = mesh.tets.iter().flatten().copied().collect();
        vertices.sort_unstable();
        vertices.dedup();
        (tets, vertices)
    }

    #[test]
    fn rigid_map_sends_frame_axes_to_texture_axes() {
        let frame = Frame { dirs: [Vec3::Y, Vec3::Z, Vec3::X], scale: 2.0 };
        let map = Rigid::new(&frame, [2, 0, 1], Vec3::ONE, Vec3::splat(0.5));
        assert_eq!(map.apply(Vec3::ONE), Vec3::splat(0.5));
        assert!((map.apply(Vec3::ONE + Vec3::Y * 2.0) - Vec3::new(0.5, 0.5, 1.5)).length() < 1e-6);
        assert!((map.apply(Vec3::ONE + Vec3::Z * 2.0) - Vec3::new(1.5, 0.5, 0.5)).length() < 1e-6);
    }

    #[test]
    fn optimization_follows_a_turning_field() {
        // a field that turns 40 degrees about z from x = 0 to x = 4
        let mesh = cube_lattice([4, 2, 2], 0.25);
        let (tets, vertices) = clump(&mesh);
        let frames: Vec<Frame> = tets
            .iter()
            .map(|&t| {
                let angle = (mesh.centroid(t as usize).x / 1.0) * 40f32.to_radians();
                let r = Vec3::new(angle.cos(), angle.sin(), 0.0);
                Frame { dirs: [r, Vec3::Z.cross(r), Vec3::Z], scale: 1.0 }
            })
            .collect();
        let start = Rigid::new(&frames[0], [0, 1, 2], mesh.centroid(0), Vec3::splat(0.5));
        let mut coords: Vec<Vec3> = vertices.iter().map(|&v| start.apply(mesh.vertices[v as usize])).collect();
        let warp = Warp {
            mesh: &mesh,
            tets: &tets,
            vertices: &vertices,
            frames: &frames,
            axes: [0, 1, 2],
            pin: (0, Vec3::splat(0.5)),
            fixed: None,
        };
        let error = |coords: &[Vec3]| -> f32 {
            tets.iter()
                .enumerate()
                .map(|(i, &t)| {
                    let w = mesh.tets[t as usize].map(|v| coords[vertices.binary_search(&v).unwrap()]);
                    let image = jacobian(&mesh, t as usize, w) * frames[i].dirs[0];
                    image.normalize().dot(Vec3::X).clamp(-1.0, 1.0).acos().to_degrees()
                })
                .sum::<f32>()
                / tets.len() as f32
        };
        let before = error(&coords);
        warp.solve(&mut coords);
        let after = error(&coords);
        assert!(before > 10.0 && after < before * 0.5, "mean angle {before} -> {after}");
        let pinned: Vec3 =
            mesh.tets[0].iter().map(|&v| coords[vertices.binary_search(&v).unwrap()]).sum::<Vec3>() / 4.0;
        assert!((pinned - Vec3::splat(0.5)).length() < 0.02, "{pinned}");
    }
}
