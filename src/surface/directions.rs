//! The direction field on the surface: at every point the tangent the exemplar's "up"
//! (against its rows) follows. Turk (2001, §4) asks for a smooth field from the user's
//! directions; here the guide gives each point a wish (a fixed direction projected into
//! its tangent plane, or the fill spec's strokes, nearer samples weighing more), and
//! Jacobi rounds of smoothing over the mesh's edges fill in where the wish is weak (a
//! direction along the normal says nothing) and smooth where it turns fast.

use glam::Vec3;
use rayon::prelude::*;

/// Where the texture's "up" points.
#[derive(Debug, Clone, PartialEq)]
pub enum Guide {
    /// One direction in model space, projected onto the surface.
    Along(Vec3),
    /// Samples of direction strokes: (point, unit tangent); a point follows the strokes
    /// near it, weighted by one over the squared distance.
    Strokes(Vec<(Vec3, Vec3)>),
}

/// Smoothing rounds.
const ROUNDS: usize = 40;
/// How strongly a full-strength wish holds against the average of the neighbours.
const HOLD: f32 = 2.0;

/// One unit tangent per vertex (`normals` unit; the vertices sharing an edge with `v` are
/// `list[offsets[v]..offsets[v + 1]]`); `softening` keeps stroke weights finite at the
/// stroke.
pub fn field(
    vertices: &[Vec3],
    normals: &[Vec3],
    (offsets, list): (&[usize], &[u32]),
    guide: &Guide,
    softening: f32,
) -> Vec<Vec3> {
    let neighbours = |v: usize| &list[offsets[v]..offsets[v + 1]];
    let wishes: Vec<(Vec3, f32)> =
        vertices.par_iter().zip(normals).map(|(p, n)| wish(*p, *n, guide, softening)).collect();
    let mut field: Vec<Vec3> = wishes
        .iter()
        .zip(normals)
        .map(|((w, strength), n)| if *strength > 0.05 { *w } else { n.any_orthonormal_vector() })
        .collect();
    for _ in 0..ROUNDS {
        field = (0..vertices.len())
            .into_par_iter()
            .map(|v| {
                let n = normals[v];
                let sum: Vec3 = neighbours(v).iter().map(|&w| field[w as usize]).sum();
                let (wish, strength) = wishes[v];
                let pulled = sum + wish * (HOLD * strength * neighbours(v).len().max(1) as f32);
                let tangent = pulled - n * n.dot(pulled);
                tangent.try_normalize().unwrap_or(field[v])
            })
            .collect();
    }
    field
}

/// The guide's direction at `p` in the tangent plane of `normal`, and how much it says
/// (0 along the normal, 1 in the plane).
fn wish(p: Vec3, normal: Vec3, guide: &Guide, softening: f32) -> (Vec3, f32) {
    let direction = match guide {
        Guide::Along(d) => d.normalize_or_zero(),
        Guide::Strokes(samples) => {
            let sum: Vec3 = samples.iter().map(|(q, d)| *d / (p.distance_squared(*q) + softening * softening)).sum();
            sum.normalize_or_zero()
        }
    };
    let tangent = direction - normal * normal.dot(direction);
    let strength = tangent.length();
    (tangent.normalize_or_zero(), strength)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A ring of vertices around the equator of a unit sphere, each joined to two others.
    fn equator(n: usize) -> (Vec<Vec3>, Vec<u32>) {
        let points = (0..n)
            .map(|i| {
                let a = i as f32 / n as f32 * std::f32::consts::TAU;
                Vec3::new(a.cos(), 0.0, a.sin())
            })
            .collect();
        let links = (0..n).flat_map(|i| [((i + n - 1) % n) as u32, ((i + 1) % n) as u32]).collect();
        (points, links)
    }

    #[test]
    fn a_direction_is_followed_in_each_tangent_plane() {
        let (points, links) = equator(32);
        let normals = points.clone();
        let offsets: Vec<usize> = (0..=points.len()).map(|v| 2 * v).collect();
        let around = (offsets.as_slice(), links.as_slice());
        let field = field(&points, &normals, around, &Guide::Along(Vec3::Y), 0.1);
        for (t, n) in field.iter().zip(&normals) {
            assert!(t.dot(*n).abs() < 1e-5);
            assert!((t.dot(Vec3::Y) - 1.0).abs() < 1e-5, "{t}");
        }
        let strokes = Guide::Strokes(vec![(Vec3::new(1.0, 0.0, 0.0), Vec3::Y), (Vec3::new(-1.0, 0.0, 0.0), -Vec3::Y)]);
        let field = super::field(&points, &normals, around, &strokes, 0.1);
        assert!(field[0].dot(Vec3::Y) > 0.99, "{}", field[0]);
        assert!(field[16].dot(Vec3::Y) < -0.99, "{}", field[16]);
    }
}
