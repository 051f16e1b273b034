//! Sealing flat pockets: a tet given up while conforming, whose corners then all moved
//! onto the surface, can end up flat between live tets on all four sides (in a part about
//! one lattice cell thick, a bunny's ear). It leaves a slit of no width through the solid,
//! whose walls are boundary faces deep inside it although the tets around meet there.
//!
//! ```text
//!     p-------s        the flat pocket (p, q, r, s) seen from above: the tets over it
//!     |\     /|        hold its diagonal p-r, those under it q-s. A vertex x where the
//!     | \   / |        diagonals cross splits every tet around p-r and every tet around
//!     |   x   |        q-s; the faces over and under are then the same four triangles
//!     | /   \ |        (p, q, x), (q, r, x), (r, s, x), (s, p, x), the tets meet across
//!     |/     \|        them, and the slit is gone
//!     q-------r
//! ```
//!
//! A pocket is sealed only where every new tet is positive with [`MIN_DIHEDRAL`] or more.

use super::conform::MIN_DIHEDRAL;
use crate::fill::refine::{tets_around, vertex_tets};
use crate::fill::tets::{TetMesh, min_dihedral};
use glam::Vec3;

/// A pocket thinner than this (its volume over its longest edge cubed) is flat.
const FLAT: f32 = 1e-2;

/// Seals the flat pockets of `mesh` (see the module docs); how many.
pub(super) fn seal_flat_pockets(mesh: &mut TetMesh) -> usize {
    let faces = boundary_keys(mesh);
    let mut around = vertex_tets(mesh);
    // a pocket next to one sealed already waits: the tets around it changed
    let mut changed = vec![false; mesh.tets.len()];
    let mut sealed = 0;
    for pocket in pockets(&faces) {
        if flat(mesh, pocket) && seal(mesh, &mut around, &mut changed, pocket) {
            sealed += 1;
        }
    }
    sealed
}

/// The boundary faces of `mesh`, each as its sorted corners, sorted.
fn boundary_keys(mesh: &TetMesh) -> Vec<[u32; 3]> {
    let mut faces = mesh.boundary_faces(&mesh.neighbours());
    faces.iter_mut().for_each(|f| f.sort_unstable());
    faces.sort_unstable();
    faces
}

/// Splits the tets around the pocket's two diagonals at their crossing (see the module
/// docs), if every new tet is good and none of them changed before. Whether it did;
/// `around` (the tets at each vertex, possibly listing tets that no longer hold it) and
/// `changed` follow the new tets.
fn seal(mesh: &mut TetMesh, around: &mut Vec<Vec<u32>>, changed: &mut Vec<bool>, pocket: [u32; 4]) -> bool {
    let ([p, r], [q, s]) = diagonals(mesh, pocket);
    let x = crossing(mesh, (p, r), (q, s));
    let split: Vec<(u32, (u32, u32))> = [(p, r), (q, s)]
        .into_iter()
        .flat_map(|e| tets_around(mesh, around, e).into_iter().map(move |t| (t, e)))
        .collect();
    if split.iter().any(|(t, _)| changed[*t as usize]) {
        return false;
    }
    let halves: Vec<[[u32; 4]; 2]> = split.iter().map(|&(t, edge)| halves_of(mesh.tets[t as usize], edge)).collect();
    let at = |v: u32| if v == u32::MAX { x } else { mesh.vertices[v as usize] };
    if !halves.iter().flatten().all(|h| good(h.map(at))) {
        return false;
    }
    let m = mesh.vertices.len() as u32;
    mesh.vertices.push(x);
    around.push(Vec::new());
    let with_m = |h: [u32; 4]| h.map(|v| if v == u32::MAX { m } else { v });
    for (&(t, _), [first, second]) in split.iter().zip(halves) {
        let new = mesh.tets.len() as u32;
        mesh.tets[t as usize] = with_m(first);
        mesh.tets.push(with_m(second));
        changed[t as usize] = true;
        changed.push(true);
        around[m as usize].push(t);
        with_m(second).iter().for_each(|&v| around[v as usize].push(new));
    }
    true
}

/// The sets of four vertices whose four triangles are all boundary faces (`faces`, each
/// sorted, sorted), each once, sorted.
fn pockets(faces: &[[u32; 3]]) -> Vec<[u32; 4]> {
    let is_face = |key: [u32; 3]| faces.binary_search(&key).is_ok();
    // (edge, third corner) for every boundary face
    let mut by_edge: Vec<((u32, u32), u32)> = Vec::with_capacity(faces.len() * 3);
    for [a, b, c] in faces {
        by_edge.extend([((*a, *b), *c), ((*a, *c), *b), ((*b, *c), *a)]);
    }
    by_edge.sort_unstable();
    let mut found = Vec::new();
    for run in by_edge.chunk_by(|x, y| x.0 == y.0) {
        let (a, b) = run[0].0;
        for (i, x) in run.iter().enumerate() {
            for y in &run[i + 1..] {
                let (c, d) = (x.1.min(y.1), x.1.max(y.1));
                let key = |mut k: [u32; 3]| {
                    k.sort_unstable();
                    k
                };
                if is_face(key([a, c, d])) && is_face(key([b, c, d])) {
                    let mut pocket = [a, b, c, d];
                    pocket.sort_unstable();
                    found.push(pocket);
                }
            }
        }
    }
    found.sort_unstable();
    found.dedup();
    found
}

/// Whether the pocket's corners are nearly coplanar.
fn flat(mesh: &TetMesh, pocket: [u32; 4]) -> bool {
    let [a, b, c, d] = pocket.map(|v| mesh.vertices[v as usize]);
    let longest = [a.distance(b), a.distance(c), a.distance(d), b.distance(c), b.distance(d), c.distance(d)]
        .into_iter()
        .fold(0.0f32, f32::max);
    ((b - a).cross(c - a).dot(d - a) / 6.0).abs() <= FLAT * longest.powi(3)
}

/// The two opposite edges of a flat pocket that cross (its quad's diagonals): of the
/// three ways to pair its corners into opposite edges, the one whose edges come closest.
fn diagonals(mesh: &TetMesh, [a, b, c, d]: [u32; 4]) -> ([u32; 2], [u32; 2]) {
    let pairs = [([a, b], [c, d]), ([a, c], [b, d]), ([a, d], [b, c])];
    let gap = |(e, f): &([u32; 2], [u32; 2])| {
        let (p, q) = closest_points(mesh, (e[0], e[1]), (f[0], f[1]));
        p.distance(q)
    };
    let mut best = pairs[0];
    for pair in &pairs[1..] {
        if gap(pair) < gap(&best) {
            best = *pair;
        }
    }
    best
}

/// The closest points of two edges, one on each.
fn closest_points(mesh: &TetMesh, (a, b): (u32, u32), (c, d): (u32, u32)) -> (Vec3, Vec3) {
    let at = |v: u32| mesh.vertices[v as usize];
    crate::mesh::closest_between_segments([at(a), at(b)], [at(c), at(d)])
}

/// Where two nearly crossing edges cross: halfway between their closest points.
fn crossing(mesh: &TetMesh, e: (u32, u32), f: (u32, u32)) -> Vec3 {
    let (p, q) = closest_points(mesh, e, f);
    (p + q) / 2.0
}

/// A tet split at a new vertex (`u32::MAX`) on its edge `a`-`b`: the half without `b`
/// and the half without `a`, each keeping the tet's orientation.
fn halves_of(tet: [u32; 4], (a, b): (u32, u32)) -> [[u32; 4]; 2] {
    [b, a].map(|gone| tet.map(|v| if v == gone { u32::MAX } else { v }))
}

/// Whether a tet is positive with a dihedral angle of at least [`MIN_DIHEDRAL`].
fn good(c: [Vec3; 4]) -> bool {
    (c[1] - c[0]).cross(c[2] - c[0]).dot(c[3] - c[0]) > 0.0 && min_dihedral(c) >= MIN_DIHEDRAL
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::fill::tets::positive;

    /// Four tets around a flat square pocket (p, q, r, s) in the plane z = 0: two above it
    /// on the diagonal p-r, two under it on q-s, each with its own apex. With `lift`, s is
    /// raised off the plane.
    fn around_a_pocket(lift: f32) -> TetMesh {
        let vertices = vec![
            Vec3::new(-1.0, 0.0, 0.0),
            Vec3::new(0.0, -1.0, 0.0),
            Vec3::new(1.0, 0.0, 0.0),
            Vec3::new(0.0, 1.0, lift),
            Vec3::new(0.0, -0.4, 0.9),
            Vec3::new(0.0, 0.4, 0.9),
            Vec3::new(-0.4, 0.0, -0.9),
            Vec3::new(0.4, 0.0, -0.9),
        ];
        let [p, q, r, s, u1, u2, d1, d2] = [0, 1, 2, 3, 4, 5, 6, 7];
        let tets = [[p, q, r, u1], [p, r, s, u2], [p, q, s, d1], [q, r, s, d2]];
        let tets = tets.iter().map(|t| positive(&vertices, *t)).collect();
        TetMesh { vertices, tets }
    }

    /// The boundary faces with every corner in the plane z = 0.
    fn faces_in_the_plane(mesh: &TetMesh) -> usize {
        let faces = mesh.boundary_faces(&mesh.neighbours());
        faces.iter().filter(|f| f.iter().all(|&v| mesh.vertices[v as usize].z.abs() < 1e-6)).count()
    }

    #[test]
    fn a_flat_pocket_is_sealed_and_the_tets_across_it_meet() {
        let mut mesh = around_a_pocket(0.0);
        assert_eq!(faces_in_the_plane(&mesh), 4, "the pocket's four faces are boundary faces");
        let volume = mesh.volume();
        assert_eq!(seal_flat_pockets(&mut mesh), 1);
        assert_eq!(mesh.tets.len(), 8);
        assert_eq!(faces_in_the_plane(&mesh), 0, "a face of the slit is left");
        assert!(mesh.vertices[8].length() < 1e-6, "the new vertex is where the diagonals cross");
        assert!((0..8).all(|t| good(mesh.corners(t))), "a new tet is inverted or sharper than the bound");
        assert!((mesh.volume() - volume).abs() < 1e-6 * volume);
    }

    #[test]
    fn a_pocket_with_room_inside_is_left_alone() {
        let mut mesh = around_a_pocket(0.3);
        let before = mesh.clone();
        assert_eq!(seal_flat_pockets(&mut mesh), 0);
        assert!(mesh == before);
    }
}
