//! A triangle split until none of its edges is longer than a given length, in barycentric
//! coordinates of the triangle, so that what lies on the surface (colour, normal) is
//! blended from its corners.
//!
//! An edge longer than the limit is halved; halves go on being halved while they are too
//! long. Whether an edge is split depends only on its two end points, so two triangles
//! sharing an edge split it at the same points and the split surface has no cracks.
//!
//! ```text
//!   edges too long:  none      one         two               three
//!                    as is     2 pieces    3 pieces          4 pieces
//!                    /\        /|\         /\                 /\
//!                   /  \      / | \       /__\               /__\
//!                  /____\    /__|__\     /\  /\  (the quad  /\  /\
//!                                          cut along its   /__\/__\
//!                                          shorter diagonal)
//! ```

use glam::Vec3;

/// Barycentric coordinates in the triangle being split.
pub type Bary = [f32; 3];

/// The triangle with these `corners` split until no piece has an edge longer than
/// `longest`, each piece's corners in barycentric coordinates, in the triangle's own
/// winding. `longest` of 0 or less leaves it whole. See [`count`] before asking for short
/// edges on a large triangle.
pub fn split(corners: [Vec3; 3], longest: f32) -> Vec<[Bary; 3]> {
    let mut out = Vec::new();
    split_each(corners, longest, |piece| {
        out.push(piece);
        true
    });
    out
}

/// How many pieces [`split`] gives, or `None` when more than `most`.
pub fn count(corners: [Vec3; 3], longest: f32, most: u64) -> Option<u64> {
    let mut n = 0u64;
    let whole = split_each(corners, longest, |_| {
        n += 1;
        n <= most
    });
    whole.then_some(n)
}

/// Hands each piece of [`split`] to `visit`, in the same order, until it returns false;
/// whether every piece was handed over.
fn split_each(corners: [Vec3; 3], longest: f32, mut visit: impl FnMut([Bary; 3]) -> bool) -> bool {
    let whole = [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]];
    if longest.is_nan() || longest <= 0.0 {
        return visit(whole);
    }
    let point = |b: Bary| corners[0] * b[0] + corners[1] * b[1] + corners[2] * b[2];
    // depends on the edge's end points alone (not on the rest of the triangle)
    let too_long = |a: Bary, b: Bary| {
        let length = point(a).distance(point(b));
        length > longest && length.is_finite()
    };
    let mut work = vec![whole];
    while let Some(t) = work.pop() {
        let long: [bool; 3] = std::array::from_fn(|k| too_long(t[k], t[(k + 1) % 3]));
        let mid = |k: usize| midpoint(t[k], t[(k + 1) % 3]);
        match long.iter().filter(|l| **l).count() {
            0 => {
                if !visit(t) {
                    return false;
                }
            }
            1 => {
                // rotate so the long edge runs from corner 0 to corner 1
                let k = long.iter().position(|l| *l).unwrap_or(0);
                let (a, b, c) = (t[k], t[(k + 1) % 3], t[(k + 2) % 3]);
                let m = mid(k);
                work.extend([[a, m, c], [m, b, c]]);
            }
            2 => {
                // the edge left whole runs from corner k to k + 1; the long ones meet at k + 2
                let k = long.iter().position(|l| !*l).unwrap_or(0);
                let (a, b, c) = (t[k], t[(k + 1) % 3], t[(k + 2) % 3]);
                let (bc, ca) = (mid((k + 1) % 3), mid((k + 2) % 3));
                work.push([ca, bc, c]);
                // the quad a, b, bc, ca, cut along its shorter diagonal
                if point(a).distance(point(bc)) <= point(b).distance(point(ca)) {
                    work.extend([[a, b, bc], [a, bc, ca]]);
                } else {
                    work.extend([[a, b, ca], [b, bc, ca]]);
                }
            }
            _ => {
                let (ab, bc, ca) = (mid(0), mid(1), mid(2));
                work.extend([[t[0], ab, ca], [ab, t[1], bc], [ca, bc, t[2]], [ab, bc, ca]]);
            }
        }
    }
    true
}

/// The midpoint of two barycentric points: exact (the coordinates are dyadic), and the same
/// whichever comes first.
fn midpoint(a: Bary, b: Bary) -> Bary {
    std::array::from_fn(|k| (a[k] + b[k]) * 0.5)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn point(corners: [Vec3; 3], b: Bary) -> Vec3 {
        corners[0] * b[0] + corners[1] * b[1] + corners[2] * b[2]
    }

    fn area(p: [Vec3; 3]) -> f32 {
        (p[1] - p[0]).cross(p[2] - p[0]).length() / 2.0
    }

    #[test]
    fn pieces_are_short_cover_the_triangle_and_keep_its_winding() {
        let corners = [Vec3::ZERO, Vec3::new(3.0, 0.0, 0.0), Vec3::new(0.4, 1.1, 0.0)];
        let whole = area(corners);
        for longest in [0.1, 0.37, 1.0, 5.0] {
            let pieces = split(corners, longest);
            let mut sum = 0.0;
            for piece in &pieces {
                let p = piece.map(|b| point(corners, b));
                for k in 0..3 {
                    assert!(p[k].distance(p[(k + 1) % 3]) <= longest + 1e-5, "an edge longer than {longest}");
                }
                assert!((p[1] - p[0]).cross(p[2] - p[0]).z > 0.0, "winding kept");
                sum += area(p);
            }
            assert!((sum - whole).abs() < 1e-4 * whole, "pieces cover the triangle: {sum} against {whole}");
            assert_eq!(count(corners, longest, u64::MAX), Some(pieces.len() as u64));
            assert_eq!(count(corners, longest, pieces.len() as u64 - 1), None.filter(|_| pieces.len() > 1));
        }
        assert_eq!(split(corners, 0.0).len(), 1, "0 leaves it whole");
    }

    #[test]
    fn two_triangles_split_their_shared_edge_at_the_same_points() {
        // a long, thin triangle beside a small one: the shared edge is split the same way
        let (a, b) = (Vec3::new(0.0, 0.0, 0.0), Vec3::new(2.0, 0.3, 0.0));
        let first = [a, b, Vec3::new(0.5, 3.0, 0.0)];
        let second = [b, a, Vec3::new(1.0, -0.2, 0.0)];
        let on_edge = |corners: [Vec3; 3], pieces: Vec<[Bary; 3]>, zero: usize| {
            let mut points: Vec<[u32; 3]> = pieces
                .iter()
                .flatten()
                .filter(|b| b[zero] == 0.0)
                .map(|b| point(corners, *b).to_array().map(f32::to_bits))
                .collect();
            points.sort_unstable();
            points.dedup();
            points
        };
        let (p, q) = (on_edge(first, split(first, 0.3), 2), on_edge(second, split(second, 0.3), 2));
        assert!(p.len() > 4, "the edge is split");
        assert_eq!(p, q, "both sides split the edge at bit-identical points");
    }
}
