//! Closed meshes the project makes itself, for fills, tests and benchmarks: an ellipsoid
//! (a kiwi fruit), a torus (a pipe, genus 1), a capped cylinder (a trunk), a box and a vase.
//! All are outward-facing and watertight (shared vertices, no seams).

use super::Mesh;
use glam::Affine3A;
use glam::Vec3;
use std::f32::consts::{PI, TAU};

/// An ellipsoid with the given radii: `rings` latitude bands, `segments` around.
pub fn ellipsoid(radii: Vec3, rings: usize, segments: usize) -> Mesh {
    let (rings, segments) = (rings.max(2), segments.max(3));
    let mut vertices = vec![Vec3::new(0.0, 0.0, -radii.z)];
    for i in 1..rings {
        let theta = PI * i as f32 / rings as f32;
        for j in 0..segments {
            let phi = TAU * j as f32 / segments as f32;
            let d = Vec3::new(theta.sin() * phi.cos(), theta.sin() * phi.sin(), -theta.cos());
            vertices.push(d * radii);
        }
    }
    vertices.push(Vec3::new(0.0, 0.0, radii.z));
    let triangles = pole_rings(rings, segments);
    Mesh::new(vertices, triangles).expect("a valid ellipsoid").oriented()
}

/// The triangles of a closed surface of revolution laid out as: a bottom pole (vertex 0),
/// `rings - 1` rings of `segments` vertices each, and a top pole (the last vertex).
pub fn pole_rings(rings: usize, segments: usize) -> Vec<[u32; 3]> {
    let ring = |i: usize, j: usize| (1 + (i - 1) * segments + j % segments) as u32;
    let top = ring(rings - 1, segments - 1) + 1;
    let mut triangles = Vec::new();
    for j in 0..segments {
        triangles.push([0, ring(1, j + 1), ring(1, j)]);
        triangles.push([top, ring(rings - 1, j), ring(rings - 1, j + 1)]);
    }
    for i in 1..rings - 1 {
        for j in 0..segments {
            triangles.push([ring(i, j), ring(i, j + 1), ring(i + 1, j + 1)]);
            triangles.push([ring(i, j), ring(i + 1, j + 1), ring(i + 1, j)]);
        }
    }
    triangles
}

/// A torus around the z axis: `major` radius to the tube centre, `minor` tube radius.
pub fn torus(major: f32, minor: f32, around: usize, tube: usize) -> Mesh {
    let (around, tube) = (around.max(3), tube.max(3));
    let mut vertices = Vec::new();
    for i in 0..around {
        let a = TAU * i as f32 / around as f32;
        for j in 0..tube {
            let b = TAU * j as f32 / tube as f32;
            let r = major + minor * b.cos();
            vertices.push(Vec3::new(r * a.cos(), r * a.sin(), minor * b.sin()));
        }
    }
    let id = |i: usize, j: usize| ((i % around) * tube + j % tube) as u32;
    let mut triangles = Vec::new();
    for i in 0..around {
        for j in 0..tube {
            triangles.push([id(i, j), id(i + 1, j), id(i + 1, j + 1)]);
            triangles.push([id(i, j), id(i + 1, j + 1), id(i, j + 1)]);
        }
    }
    Mesh::new(vertices, triangles).expect("a valid torus").oriented()
}

/// A cylinder along z from 0 to `height`, capped at both ends.
pub fn cylinder(radius: f32, height: f32, segments: usize, stacks: usize) -> Mesh {
    let (segments, stacks) = (segments.max(3), stacks.max(1));
    let mut vertices = vec![Vec3::ZERO];
    for i in 0..=stacks {
        let z = height * i as f32 / stacks as f32;
        for j in 0..segments {
            let a = TAU * j as f32 / segments as f32;
            vertices.push(Vec3::new(radius * a.cos(), radius * a.sin(), z));
        }
    }
    vertices.push(Vec3::new(0.0, 0.0, height));
    let ring = |i: usize, j: usize| (1 + i * segments + j % segments) as u32;
    let top = vertices.len() as u32 - 1;
    let mut triangles = Vec::new();
    for j in 0..segments {
        triangles.push([0, ring(0, j + 1), ring(0, j)]);
        triangles.push([top, ring(stacks, j), ring(stacks, j + 1)]);
    }
    for i in 0..stacks {
        for j in 0..segments {
            triangles.push([ring(i, j), ring(i, j + 1), ring(i + 1, j + 1)]);
            triangles.push([ring(i, j), ring(i + 1, j + 1), ring(i + 1, j)]);
        }
    }
    Mesh::new(vertices, triangles).expect("a valid cylinder").oriented()
}

/// An axis-aligned box from `lo` to `hi`.
pub fn cuboid(lo: Vec3, hi: Vec3) -> Mesh {
    let corner = |i: usize| Vec3::new([lo.x, hi.x][i & 1], [lo.y, hi.y][(i >> 1) & 1], [lo.z, hi.z][i >> 2]);
    let vertices = (0..8).map(corner).collect();
    let quads = [[0, 2, 3, 1], [4, 5, 7, 6], [0, 1, 5, 4], [2, 6, 7, 3], [0, 4, 6, 2], [1, 3, 7, 5]];
    let triangles = quads.iter().flat_map(|&[a, b, c, d]| [[a, b, c], [a, c, d]]).collect();
    Mesh::new(vertices, triangles).expect("a valid box").oriented()
}

/// The radius of the vase at height `t` (0 at the foot, 1 at the lip) for a height of 2: a
/// belly a third of the way up, a narrow neck, a flared lip.
pub fn vase_radius(t: f32) -> f32 {
    let bump = |at: f32, width: f32| (-((t - at) / width).powi(2)).exp();
    0.28 + 0.42 * bump(0.33, 0.24) + 0.16 * bump(1.0, 0.1)
}

/// A vase (a solid of revolution about z from 0 to 2, closed at the foot and the lip):
/// `rings` bands up its height, `segments` around.
pub fn vase(rings: usize, segments: usize) -> Mesh {
    let (rings, segments) = (rings.max(2), segments.max(3));
    let mut vertices = vec![Vec3::ZERO];
    for i in 1..rings {
        let t = i as f32 / rings as f32;
        let r = vase_radius(t);
        for j in 0..segments {
            let a = TAU * j as f32 / segments as f32;
            vertices.push(Vec3::new(r * a.cos(), r * a.sin(), 2.0 * t));
        }
    }
    vertices.push(Vec3::new(0.0, 0.0, 2.0));
    Mesh::new(vertices, pole_rings(rings, segments)).expect("a valid vase").oriented()
}

/// One layer of the cake `solidtex draw cake` makes: its file stem, its mesh, and how to
/// fill it (the library exemplar, the texture scale in model units, the tet count).
pub struct CakeLayer {
    /// File stem, e.g. `sponge-low`.
    pub name: &'static str,
    /// A closed disc of the cake, its axis vertical (y).
    pub mesh: Mesh,
    /// The exemplar that fills it.
    pub exemplar: &'static str,
    /// Texture cube side in model units.
    pub scale: f32,
    /// Tets asked for.
    pub tets: usize,
}

/// A round layer cake of radius 1 standing on y = 0: sponge, cream, sponge and a thin
/// chocolate glaze on top (thesis Fig. 7.2d), each layer its own closed mesh; neighbouring
/// layers share their flat faces.
pub fn cake() -> Vec<CakeLayer> {
    // (name, exemplar, bottom, top, scale, tets): thinner layers get more tets so the
    // lattice has cells across them
    let layers = [
        ("sponge-low", "sponge", 0.0, 0.42, 0.9, 5000),
        ("cream", "cream", 0.42, 0.56, 0.7, 8000),
        ("sponge-high", "sponge", 0.56, 0.98, 0.9, 5000),
        ("glaze", "chocolate", 0.98, 1.08, 0.6, 12000),
    ];
    let stand_up = Affine3A::from_rotation_x(-std::f32::consts::FRAC_PI_2);
    layers
        .into_iter()
        .map(|(name, exemplar, bottom, top, scale, tets)| {
            let disc = cylinder(1.0, top - bottom, 96, 2);
            let mesh = disc.transformed(Affine3A::from_translation(Vec3::new(0.0, bottom, 0.0)) * stand_up);
            CakeLayer { name, mesh, exemplar, scale, tets }
        })
        .collect()
}

/// The named shapes `solidtex draw` makes, in model units of about 2.
pub const NAMES: [&str; 5] = ["fruit", "pipe", "log", "block", "vase"];

/// A named shape: `fruit` (a 2 x 1.3 x 1.3 ellipsoid along x, like a kiwi), `pipe` (a torus,
/// genus 1), `log` (a capped cylinder along z), `block` (a 2 x 1 x 1 box) or `vase` (a solid of
/// revolution about z, 2 high, with a belly, a neck and a lip).
pub fn named(name: &str) -> Option<Mesh> {
    match name {
        "fruit" => Some(ellipsoid(Vec3::new(1.0, 0.65, 0.65), 24, 48)),
        "pipe" => Some(torus(0.75, 0.3, 64, 24)),
        "log" => Some(cylinder(0.5, 2.0, 48, 8)),
        "block" => Some(cuboid(Vec3::new(-1.0, -0.5, -0.5), Vec3::new(1.0, 0.5, 0.5))),
        "vase" => Some(vase(64, 48)),
        _ => None,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn shapes_are_closed_with_the_right_volume() {
        let checks = [
            (ellipsoid(Vec3::new(1.0, 1.0, 2.0), 32, 64), 4.0 / 3.0 * PI * 2.0),
            (torus(2.0, 0.5, 64, 32), 2.0 * PI * PI * 2.0 * 0.25),
            (cylinder(1.0, 2.0, 128, 3), PI * 2.0),
            (cuboid(Vec3::ZERO, Vec3::new(1.0, 2.0, 3.0)), 6.0),
            (vase(256, 128), (0..2000).map(|i| PI * vase_radius((i as f32 + 0.5) / 2000.0).powi(2) / 1000.0).sum()),
        ];
        for (mesh, volume) in checks {
            assert_eq!(mesh.boundary_edges(), 0);
            let v = mesh.signed_volume();
            assert!((v - volume).abs() / volume < 0.02, "volume {v}, expected {volume}");
        }
    }
}
