//! Caps on spikes and tips: where a point of the surface lies more than half a tet edge from
//! the tet mesh's boundary (a corner where three or more creases meet, or the smooth end of
//! a part thinner than the lattice, which no lattice vertex reaches), one tet is added from
//! a boundary face below the point to the point itself. A tall three-sided cap keeps good
//! angles (near right angles at its base, the spike's own at its sides), and it is added
//! only where it keeps [`MIN_DIHEDRAL`], crosses no other part of the boundary and lies
//! closer to the surface than the point was to the boundary.

use super::closest::Surface;
use super::conform::MIN_DIHEDRAL;
use super::face_samples;
use super::features::Features;
use crate::fill::tets::{TetMesh, barycentric_in, min_dihedral};
use crate::mesh::closest_on_triangle;
use glam::Vec3;

/// A point farther than this from the boundary (in mean tet edges) is capped.
pub(super) const FAR: f32 = 0.5;
/// Boundary faces within this many mean tet edges of a corner are tried as a cap's base.
const REACH: f32 = 2.5;

/// Caps the corners of `features` that `mesh` leaves uncovered (see the module docs).
pub(super) fn cap_far_corners(mesh: &mut TetMesh, surface: &Surface, features: &Features) {
    cap_far_points(mesh, surface, &features.corners);
}

/// Caps the `points` (on the surface) that `mesh` leaves uncovered, in the order given.
pub(super) fn cap_far_points(mesh: &mut TetMesh, surface: &Surface, points: &[Vec3]) {
    if points.is_empty() || mesh.tets.is_empty() {
        return;
    }
    let edge = crate::fill::mean_edge(mesh);
    // a point with a tet corner that near is not far from the boundary either (or lies
    // inside the tets, where no cap goes): most are, and need no boundary
    let far: Vec<Vec3> =
        points.iter().copied().filter(|c| mesh.vertices.iter().all(|v| v.distance(*c) > FAR * edge)).collect();
    if far.is_empty() {
        return;
    }
    let mut faces = mesh.boundary_faces(&mesh.neighbours());
    for corner in far {
        // a cap lies within REACH edges of its tip, so only the faces that near can cross it
        let (gap, local) = nearby(mesh, &faces, corner, 1.01 * REACH * edge);
        if gap <= FAR * edge {
            continue;
        }
        let local_faces: Vec<[u32; 3]> = local.iter().map(|&i| faces[i]).collect();
        let near = |f: &[u32; 3]| f.iter().all(|&v| mesh.vertices[v as usize].distance(corner) <= REACH * edge);
        let best = local
            .iter()
            .zip(&local_faces)
            .filter(|(_, f)| near(f))
            .filter_map(|(&i, f)| cap_reach(mesh, &local_faces, surface, *f, corner).map(|d| (d, i)))
            .filter(|(d, _)| *d < gap)
            .min_by(|a, b| a.0.total_cmp(&b.0).then(a.1.cmp(&b.1)));
        let Some((_, i)) = best else { continue };
        let [a, b, c] = faces.swap_remove(i);
        let p = mesh.vertices.len() as u32;
        mesh.vertices.push(corner);
        mesh.tets.push([a, b, c, p]);
        faces.extend([[b, c, p], [a, p, c], [a, b, p]]);
    }
}

/// How far `p` lies from the boundary `faces` of `mesh`, and the faces within `radius` of it.
fn nearby(mesh: &TetMesh, faces: &[[u32; 3]], p: Vec3, radius: f32) -> (f32, Vec<usize>) {
    let corners = |f: &[u32; 3]| f.map(|v| mesh.vertices[v as usize]);
    let mut gap = f32::INFINITY;
    let mut within = Vec::new();
    for (i, f) in faces.iter().enumerate() {
        let d = closest_on_triangle(p, corners(f)).distance(p);
        gap = gap.min(d);
        if d <= radius {
            within.push(i);
        }
    }
    (gap, within)
}

/// For a cap from boundary face `f` (facing outwards) to `corner`: how far its three new
/// faces reach from the surface, or `None` when the cap is inverted, sharper than
/// [`MIN_DIHEDRAL`], or would cross the boundary `faces` or hold one of their corners.
fn cap_reach(mesh: &TetMesh, faces: &[[u32; 3]], surface: &Surface, f: [u32; 3], corner: Vec3) -> Option<f32> {
    let [a, b, c] = f.map(|v| mesh.vertices[v as usize]);
    let tet = [a, b, c, corner];
    if (b - a).cross(c - a).dot(corner - a) <= 0.0 || min_dihedral(tet) < MIN_DIHEDRAL {
        return None;
    }
    let new_faces = [[b, c, corner], [a, corner, c], [a, b, corner]];
    let others = faces.iter().filter(|g| **g != f);
    for g in others {
        let h = g.map(|v| mesh.vertices[v as usize]);
        // the new edges against every face not at their base corner
        for (k, &base) in f.iter().enumerate() {
            if !g.contains(&base) && crosses(tet[k], corner, h) {
                return None;
            }
        }
        // the face's edges and corners against the cap, except where they are the base's
        for k in 0..3 {
            let (u, w) = (g[k], g[(k + 1) % 3]);
            let (p, q) = (h[k], h[(k + 1) % 3]);
            if !(f.contains(&u) && f.contains(&w)) && new_faces.iter().any(|t| crosses(p, q, *t)) {
                return None;
            }
            if !f.contains(&u) && barycentric_in(tet, p).iter().all(|b| *b > 1e-6) {
                return None;
            }
        }
    }
    let reach = new_faces.iter().flat_map(|t| face_samples(*t)).map(|q| surface.closest(q).distance(q));
    Some(reach.fold(0.0, f32::max))
}

/// Whether segment `p`-`q` passes through the inside of triangle `t` (touching at an end or
/// along an edge does not count).
fn crosses(p: Vec3, q: Vec3, [a, b, c]: [Vec3; 3]) -> bool {
    let (d, e1, e2) = (q - p, b - a, c - a);
    let h = d.cross(e2);
    let det = e1.dot(h);
    if det.abs() <= f32::EPSILON * e1.length() * e2.length() * d.length() {
        return false;
    }
    let s = p - a;
    let u = s.dot(h) / det;
    let n = s.cross(e1);
    let v = d.dot(n) / det;
    let t = e2.dot(n) / det;
    let open = 1e-4;
    u > open && v > open && u + v < 1.0 - open && t > open && t < 1.0 - open
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_segment_through_a_triangle_crosses_it_and_one_beside_it_does_not() {
        let t = [Vec3::ZERO, Vec3::X, Vec3::Y];
        let through = (Vec3::new(0.2, 0.2, -1.0), Vec3::new(0.2, 0.2, 1.0));
        assert!(crosses(through.0, through.1, t));
        assert!(!crosses(Vec3::new(1.2, 1.2, -1.0), Vec3::new(1.2, 1.2, 1.0), t));
        // ending on the triangle, or at a corner, is touching
        assert!(!crosses(Vec3::new(0.2, 0.2, 0.0), Vec3::new(0.2, 0.2, 1.0), t));
        assert!(!crosses(Vec3::ZERO, Vec3::new(0.0, 0.0, 1.0), t));
    }
}
