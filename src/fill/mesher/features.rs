//! The creases of a surface: edges where the normals of the two triangles turn by more than
//! [`CREASE_DEGREES`]. The mesher rounds them off over about one lattice spacing, so the
//! distance check samples them densely.

use crate::mesh::Mesh;
use glam::Vec3;

/// How far (degrees) the normals of an edge's two triangles must turn for a crease.
pub(crate) const CREASE_DEGREES: f32 = 40.0;

/// The crease edges of `mesh` as segments. A neighbour wound the same way along the edge
/// (inconsistent orientation) has its normal flipped for the test.
pub(crate) fn creases(mesh: &Mesh) -> Vec<[Vec3; 2]> {
    features(mesh).creases
}

/// The creases of a surface and the smooth patches between them.
pub(crate) struct Features {
    /// The crease edges as segments.
    pub creases: Vec<[Vec3; 2]>,
    /// Per triangle, the patch it belongs to: triangles joined across edges that are not
    /// creases share one.
    pub patch: Vec<u32>,
    /// The points where three or more creases meet (a box's corners).
    pub corners: Vec<Vec3>,
    /// Per crease, the patches on its two sides (the smaller first).
    pub sides: Vec<(u32, u32)>,
}

/// The creases of `mesh` and its patches.
pub(crate) fn features(mesh: &Mesh) -> Features {
    let normal = |t: [u32; 3]| {
        let [a, b, c] = t.map(|i| mesh.vertices[i as usize]);
        (b - a).cross(c - a).normalize_or_zero()
    };
    // (edge key, directed start, triangle)
    let mut edges: Vec<((u32, u32), u32, u32)> = Vec::with_capacity(mesh.triangles.len() * 3);
    for (i, t) in mesh.triangles.iter().enumerate() {
        for k in 0..3 {
            let (a, b) = (t[k], t[(k + 1) % 3]);
            edges.push(((a.min(b), a.max(b)), a, i as u32));
        }
    }
    edges.sort_unstable();
    let limit = CREASE_DEGREES.to_radians().cos();
    let mut creases = Vec::new();
    let mut ends: Vec<u32> = Vec::new();
    let mut between: Vec<(u32, u32)> = Vec::new();
    let mut parent: Vec<u32> = (0..mesh.triangles.len() as u32).collect();
    for pair in edges.chunk_by(|x, y| x.0 == y.0).filter(|run| run.len() == 2) {
        let (n0, n1) = (normal(mesh.triangles[pair[0].2 as usize]), normal(mesh.triangles[pair[1].2 as usize]));
        let n1 = if pair[0].1 == pair[1].1 { -n1 } else { n1 };
        if n0 != Vec3::ZERO && n1 != Vec3::ZERO && n0.dot(n1) < limit {
            let (a, b) = pair[0].0;
            creases.push([mesh.vertices[a as usize], mesh.vertices[b as usize]]);
            ends.extend([a, b]);
            between.push((pair[0].2, pair[1].2));
        } else {
            let (r0, r1) = (root(&mut parent, pair[0].2), root(&mut parent, pair[1].2));
            parent[r0.max(r1) as usize] = r0.min(r1);
        }
    }
    let patch: Vec<u32> = (0..mesh.triangles.len() as u32).map(|t| root(&mut parent, t)).collect();
    let sides = between
        .iter()
        .map(|&(t0, t1)| {
            let (p0, p1) = (patch[t0 as usize], patch[t1 as usize]);
            (p0.min(p1), p0.max(p1))
        })
        .collect();
    ends.sort_unstable();
    let corners = ends.chunk_by(|a, b| a == b).filter(|run| run.len() >= 3).map(|run| mesh.vertices[run[0] as usize]);
    Features { creases, patch, corners: corners.collect(), sides }
}

/// The representative of `t`'s set (union-find with path halving).
fn root(parent: &mut [u32], mut t: u32) -> u32 {
    while parent[t as usize] != t {
        parent[t as usize] = parent[parent[t as usize] as usize];
        t = parent[t as usize];
    }
    t
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::mesh::shapes::cuboid;

    #[test]
    fn a_box_has_twelve_creases_and_a_smooth_fruit_none() {
        // each box face is two triangles: the diagonals are flat, the 12 edges are creases
        assert_eq!(creases(&cuboid(Vec3::ZERO, Vec3::new(2.0, 1.0, 1.0))).len(), 12);
        assert!(creases(&crate::mesh::shapes::named("fruit").unwrap()).is_empty());
        // the same box with every other triangle wound the wrong way: still 12
        let mut mixed = cuboid(Vec3::ZERO, Vec3::ONE);
        mixed.triangles.iter_mut().step_by(2).for_each(|t| t.swap(1, 2));
        assert_eq!(creases(&mixed).len(), 12);
        // its six faces are six patches, each of two triangles
        let patches = features(&mixed).patch;
        let mut ids = patches.clone();
        ids.sort_unstable();
        ids.dedup();
        assert_eq!(ids.len(), 6);
        assert!(patches.chunks(2).all(|p| p[0] == p[1]), "{patches:?}");
        assert_eq!(features(&mixed).corners.len(), 8);
    }
}
