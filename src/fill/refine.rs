//! Local refinement of a tet mesh by edge bisection (thesis §7.1, Fig. 7.3: tets are
//! subdivided near a singularity such as a fruit's axis, where the depth field turns fast
//! and linear interpolation over lattice-sized tets draws a faceted, square core).
//!
//! ```text
//!        c                     c
//!       /|\                   /|\
//!      / | \        a tet    / | \        every tet around the edge a-b is split at its
//!     a--+--b   ->  split   a--m--b       midpoint m, so no face is left with a hanging
//!      \ | /       in two    \ | /        vertex: the mesh stays conforming
//!       \|/                   \|/
//!        d                     d
//! ```
//! The edge split is the longest edge of a tet that asks for a finer size, after the longer
//! edges of the tets around it (Rivara's longest-edge propagation: every split halves the
//! longest edge of each tet it cuts, which keeps lattice tets within a few similarity
//! classes). A split that would leave any tet around the edge with a dihedral angle under
//! [`MIN_DIHEDRAL_DEGREES`](super::mesher::MIN_DIHEDRAL_DEGREES) is not made.

use super::tets::{TetMesh, min_dihedral};
use glam::Vec3;
use std::collections::HashSet;

/// Passes over the tets at most (each pass halves the longest edges that ask for it once).
const PASSES: usize = 8;

/// Bisects the longest edges of the tets whose longest edge is longer than `size` at their
/// centroid (`f32::INFINITY` where no refinement is wanted), until none is or no split is
/// allowed. Deterministic: tets are visited in index order. Returns how many tets were added.
pub fn refine(mesh: &mut TetMesh, size: &dyn Fn(Vec3) -> f32) -> usize {
    let before = mesh.tets.len();
    let mut around = vertex_tets(mesh);
    let mut refused = HashSet::new();
    for _ in 0..PASSES {
        let mut split = false;
        for t in 0..mesh.tets.len() {
            let (a, b, length) = longest_edge(mesh, t);
            if length > size(mesh.centroid(t)) && !refused.contains(&(a, b)) {
                split |= split_longest(mesh, &mut around, (a, b), &mut refused);
            }
        }
        if !split {
            break;
        }
    }
    mesh.tets.len() - before
}

/// Bisects the edge `a`-`b` after first bisecting, in turn, the longest edge of any tet
/// around it whose longest edge it is not (Rivara's longest-edge propagation), so that
/// every split halves the longest edge of each tet it cuts and shapes stay good. Whether
/// `a`-`b` was split; edges whose split would spoil a tet are added to `refused`.
fn split_longest(
    mesh: &mut TetMesh,
    around: &mut Vec<Vec<u32>>,
    edge: (u32, u32),
    refused: &mut HashSet<(u32, u32)>,
) -> bool {
    let min = super::mesher::MIN_DIHEDRAL_DEGREES;
    let mut path = vec![edge];
    for _ in 0..MAX_STEPS {
        let Some(&(a, b)) = path.last() else {
            return true;
        };
        let shared = tets_around(mesh, around, (a, b));
        if shared.is_empty() {
            // split on the way by a longer neighbour's propagation
            path.pop();
            continue;
        }
        let longer = shared.iter().map(|&t| longest_edge(mesh, t as usize)).find(|l| (l.0, l.1) != (a, b));
        match longer {
            // each step goes to a strictly longer edge (or an equal one with smaller
            // indices), so the path ends
            Some((c, d, _)) if path.len() < MAX_PATH && !refused.contains(&(c, d)) => path.push((c, d)),
            Some(_) => {
                refused.insert(edge);
                return false;
            }
            None if bisect(mesh, around, (a, b), &shared, min) => {
                path.pop();
            }
            None => {
                refused.insert((a, b));
                refused.insert(edge);
                return false;
            }
        }
    }
    refused.insert(edge);
    false
}

/// Longest-edge paths longer than this are not followed (a path on a mesh of good tets is
/// a few edges long).
const MAX_PATH: usize = 64;
/// Steps (path extensions and splits) one refinement may take before it is given up.
const MAX_STEPS: usize = 4096;

/// The tets that hold both `a` and `b` (`around`: the tets at each vertex, as
/// [`vertex_tets`] gives them; a list may still name tets that no longer hold it).
pub(crate) fn tets_around(mesh: &TetMesh, around: &[Vec<u32>], (a, b): (u32, u32)) -> Vec<u32> {
    around[a as usize].iter().copied().filter(|&t| mesh.tets[t as usize].contains(&b)).collect()
}

/// The tets around each vertex.
pub(crate) fn vertex_tets(mesh: &TetMesh) -> Vec<Vec<u32>> {
    let mut around = vec![Vec::new(); mesh.vertices.len()];
    for (t, tet) in mesh.tets.iter().enumerate() {
        tet.iter().for_each(|&v| around[v as usize].push(t as u32));
    }
    around
}

/// The longest edge of tet `t` as (smaller index, larger index, length); ties go to the
/// edge with the smaller indices.
fn longest_edge(mesh: &TetMesh, t: usize) -> (u32, u32, f32) {
    let tet = mesh.tets[t];
    let mut best = (0, 0, -1.0f32);
    for (i, j) in super::tets::EDGES {
        let (a, b) = (tet[i].min(tet[j]), tet[i].max(tet[j]));
        let length = mesh.vertices[a as usize].distance(mesh.vertices[b as usize]);
        if length > best.2 || (length == best.2 && (a, b) < (best.0, best.1)) {
            best = (a, b, length);
        }
    }
    best
}

/// Splits the tets `shared` around the edge `a`-`b` at its midpoint, if every new tet keeps
/// a dihedral angle of at least `min` degrees. Whether it did.
fn bisect(mesh: &mut TetMesh, around: &mut Vec<Vec<u32>>, (a, b): (u32, u32), shared: &[u32], min: f32) -> bool {
    let mid = (mesh.vertices[a as usize] + mesh.vertices[b as usize]) / 2.0;
    // each tet around the edge as its two halves: one without b, one without a (the
    // missing corner, u32::MAX, is the midpoint)
    let halves: Vec<[[u32; 4]; 2]> = shared
        .iter()
        .map(|&t| [b, a].map(|gone| mesh.tets[t as usize].map(|v| if v == gone { u32::MAX } else { v })))
        .collect();
    let corner = |v: u32| if v == u32::MAX { mid } else { mesh.vertices[v as usize] };
    if !halves.iter().flatten().all(|h| min_dihedral(h.map(corner)) >= min) {
        return false;
    }
    let m = mesh.vertices.len() as u32;
    mesh.vertices.push(mid);
    around.push(Vec::new());
    for (&t, pair) in shared.iter().zip(halves) {
        let [keep_a, keep_b] = pair.map(|h| h.map(|v| if v == u32::MAX { m } else { v }));
        let new = mesh.tets.len() as u32;
        mesh.tets[t as usize] = keep_a;
        mesh.tets.push(keep_b);
        // t lost b and gained m; the new tet has b, m and the two other corners
        around[b as usize].retain(|&x| x != t);
        for v in keep_b {
            around[v as usize].push(new);
        }
        around[m as usize].push(t);
    }
    true
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::fill::tets::cube_lattice;

    #[test]
    fn tets_near_a_point_are_split_and_the_mesh_stays_whole() {
        let mut mesh = cube_lattice([4, 4, 4], 0.25);
        let (tets, volume) = (mesh.tets.len(), mesh.volume());
        let centre = Vec3::splat(0.5);
        let size = |p: Vec3| if p.distance(centre) < 0.3 { 0.13 } else { f32::INFINITY };
        let added = refine(&mut mesh, &size);
        assert!(added > 0 && mesh.tets.len() == tets + added);
        assert!((mesh.volume() - volume).abs() < 1e-5, "volume {} against {volume}", mesh.volume());
        assert!((0..mesh.tets.len()).all(|t| mesh.volume_of(t) > 0.0), "an inverted tet");
        // near the centre every tet is now small; far from it nothing changed
        for t in 0..mesh.tets.len() {
            let (_, _, longest) = longest_edge(&mesh, t);
            if mesh.centroid(t).distance(centre) < 0.3 {
                assert!(longest <= 0.13, "tet {t}: longest edge {longest}");
            }
        }
        assert!(mesh.min_dihedral_degrees() >= crate::fill::mesher::MIN_DIHEDRAL_DEGREES);
        // every face inside the cube has a tet on each side (no hanging vertex)
        let outside = mesh.boundary_faces(&mesh.neighbours());
        let on_cube = |p: Vec3| p.min_element() < 1e-6 || p.max_element() > 1.0 - 1e-6;
        assert!(outside.iter().all(|f| f.iter().all(|&v| on_cube(mesh.vertices[v as usize]))));
    }

    #[test]
    fn nothing_changes_where_no_size_is_asked() {
        let mut mesh = cube_lattice([3, 3, 3], 1.0 / 3.0);
        let before = mesh.clone();
        assert_eq!(refine(&mut mesh, &|_| f32::INFINITY), 0);
        assert_eq!(mesh, before);
    }
}
