//! A picture of the filled model's surface: an orthographic z-buffer of the tet mesh's
//! boundary faces, each pixel coloured by compositing the patches of the tet behind it and
//! lit by a light over the viewer's shoulder, with normals blended smoothly across faces
//! except at creases (or flat, one normal per face).
//!
//! ```text
//!   yaw/pitch -> view axes (right, up, forward) -> rasterize boundary faces (nearest wins)
//!             -> per pixel: tet + point -> patches composited -> x (ambient + diffuse)
//! ```

use super::model::LstModel;
use super::render::{BACKGROUND, Textures, shade_point};
use super::tets::FACES;
use crate::render::{Rgb8, to_u8};
use glam::{Vec2, Vec3};
use rayon::prelude::*;

/// What each pixel sees: the tet, the surface point, the shading normal.
#[derive(Clone, Copy)]
struct Hit {
    depth: f32,
    tet: u32,
    point: Vec3,
    normal: Vec3,
}

/// How the surface is lit.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Shading {
    /// One normal per boundary face: the tet faces show.
    Flat,
    /// Normals blended across each face from its corners. A corner's normal is the
    /// area-weighted mean of the faces around it whose normals lie within `crease` degrees
    /// of the face's own, so edges sharper than that stay sharp.
    Smooth {
        /// Degrees, 0 to 180.
        crease: f32,
    },
}

/// The crease angle of [`Shading::Smooth`] by default, in degrees.
pub const DEFAULT_CREASE: f32 = 40.0;

/// Renders the surface of `model` seen from `yaw` degrees around y and `pitch` degrees up,
/// smooth-shaded with the [`DEFAULT_CREASE`].
pub fn surface(model: &LstModel, textures: &Textures, yaw: f32, pitch: f32, size: usize) -> Rgb8 {
    surface_shaded(model, textures, yaw, pitch, size, Shading::Smooth { crease: DEFAULT_CREASE })
}

/// [`surface`] with the given shading.
pub fn surface_shaded(
    model: &LstModel,
    textures: &Textures,
    yaw: f32,
    pitch: f32,
    size: usize,
    shading: Shading,
) -> Rgb8 {
    let (forward, right, up) = camera(yaw, pitch);
    let project = |p: Vec3| Vec2::new(right.dot(p), up.dot(p));
    let (lo, hi) = model
        .mesh
        .vertices
        .iter()
        .fold((Vec2::INFINITY, Vec2::NEG_INFINITY), |(a, b), p| (a.min(project(*p)), b.max(project(*p))));
    let side = (hi - lo).max_element().max(1e-6) * 1.08;
    let scale = size as f32 / side;
    let centre = (lo + hi) / 2.0;
    let to_pixel = |p: Vec3| {
        let q = (project(p) - centre) * scale;
        Vec2::new(q.x + size as f32 / 2.0, size as f32 / 2.0 - q.y)
    };
    let hits = rasterize(model, size, &to_pixel, forward, shading);
    let light = (up * 0.6 - forward + right * 0.3).normalize();
    let colours: Vec<[u8; 3]> = hits
        .par_iter()
        .map(|hit| match hit {
            None => BACKGROUND,
            Some(h) => {
                let c = shade_point(model, textures, h.tet as usize, h.point);
                let lit = 0.35 + 0.65 * h.normal.dot(light).max(0.0);
                [c[0], c[1], c[2]].map(|v| to_u8(v * lit))
            }
        })
        .collect();
    let mut out = Rgb8::new(size, size, BACKGROUND);
    for (i, c) in colours.into_iter().enumerate() {
        out.put(i % size, i / size, c);
    }
    out
}

/// The axes of an orthographic camera `yaw` degrees around y and `pitch` degrees up from
/// the +z side, looking at the origin: (forward, right, up), orthonormal.
pub fn camera(yaw: f32, pitch: f32) -> (Vec3, Vec3, Vec3) {
    let (yaw, pitch) = (yaw.to_radians(), pitch.to_radians());
    let forward = -Vec3::new(yaw.sin() * pitch.cos(), pitch.sin(), yaw.cos() * pitch.cos());
    let right = forward.cross(Vec3::Y).normalize_or(Vec3::X);
    (forward, right, right.cross(forward))
}

/// A boundary face of the tet mesh: its tet, corners (vertex ids and points), unit normal
/// and area.
struct Face {
    tet: usize,
    ids: [u32; 3],
    corners: [Vec3; 3],
    normal: Vec3,
    area: f32,
}

fn boundary_faces(model: &LstModel) -> Vec<Face> {
    let mesh = &model.mesh;
    let neighbours = mesh.neighbours();
    let mut faces = Vec::new();
    for (t, tet) in mesh.tets.iter().enumerate() {
        for (k, face) in FACES.iter().enumerate() {
            if neighbours[t][k] == super::tets::NONE {
                let ids = face.map(|s| tet[s]);
                let corners = ids.map(|v| mesh.vertices[v as usize]);
                let cross = (corners[1] - corners[0]).cross(corners[2] - corners[0]);
                faces.push(Face {
                    tet: t,
                    ids,
                    corners,
                    normal: cross.normalize_or_zero(),
                    area: cross.length() / 2.0,
                });
            }
        }
    }
    faces
}

/// The normal at each corner of each face under `shading`.
fn corner_normals(faces: &[Face], shading: Shading) -> Vec<[Vec3; 3]> {
    let Shading::Smooth { crease } = shading else {
        return faces.iter().map(|f| [f.normal; 3]).collect();
    };
    let mut incident: Vec<(u32, u32)> =
        faces.iter().enumerate().flat_map(|(i, f)| f.ids.map(|v| (v, i as u32))).collect();
    incident.sort_unstable();
    let around = |v: u32| {
        let start = incident.partition_point(|e| e.0 < v);
        incident[start..].iter().take_while(move |e| e.0 == v).map(|e| &faces[e.1 as usize])
    };
    let limit = crease.clamp(0.0, 180.0).to_radians().cos();
    faces
        .par_iter()
        .map(|f| {
            f.ids.map(|v| {
                let alike = around(v).filter(|g| g.normal.dot(f.normal) >= limit);
                alike.map(|g| g.normal * g.area).sum::<Vec3>().normalize_or(f.normal)
            })
        })
        .collect()
}

fn rasterize(
    model: &LstModel,
    size: usize,
    to_pixel: &dyn Fn(Vec3) -> Vec2,
    forward: Vec3,
    shading: Shading,
) -> Vec<Option<Hit>> {
    let faces = boundary_faces(model);
    let normals = corner_normals(&faces, shading);
    let mut hits: Vec<Option<Hit>> = vec![None; size * size];
    for (f, n) in faces.iter().zip(&normals) {
        if f.normal.dot(forward) >= 0.0 {
            continue;
        }
        let p = f.corners;
        let inward = (model.mesh.centroid(f.tet) - (p[0] + p[1] + p[2]) / 3.0) * 1e-3;
        draw_triangle(&mut hits, size, p.map(to_pixel), |b| {
            let point = p[0] * b[0] + p[1] * b[1] + p[2] * b[2];
            let normal = (n[0] * b[0] + n[1] * b[1] + n[2] * b[2]).normalize_or(f.normal);
            Hit { depth: forward.dot(point), tet: f.tet as u32, point: point + inward, normal }
        });
    }
    hits
}

fn draw_triangle(hits: &mut [Option<Hit>], size: usize, s: [Vec2; 3], hit_at: impl Fn([f32; 3]) -> Hit) {
    let area = (s[1] - s[0]).perp_dot(s[2] - s[0]);
    if area.abs() < 1e-12 {
        return;
    }
    let lo = s[0].min(s[1]).min(s[2]).floor().max(Vec2::ZERO);
    let hi = (s[0].max(s[1]).max(s[2]).ceil() + 1.0).min(Vec2::splat(size as f32));
    for y in lo.y as usize..hi.y as usize {
        for x in lo.x as usize..hi.x as usize {
            let q = Vec2::new(x as f32 + 0.5, y as f32 + 0.5);
            let b1 = (q - s[0]).perp_dot(s[2] - s[0]) / area;
            let b2 = (s[1] - s[0]).perp_dot(q - s[0]) / area;
            let b = [1.0 - b1 - b2, b1, b2];
            if b.iter().any(|w| *w < -1e-4) {
                continue;
            }
            let hit = hit_at(b);
            let slot = &mut hits[y * size + x];
            if slot.is_none_or(|old| hit.depth < old.depth) {
                *slot = Some(hit);
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::fill::model::{MaskRef, Source};
    use crate::fill::paste::Patch;
    use crate::volume::{Channel, Volume};

    /// The drawn fruit, tetrahedralized, with one grey patch over every tet: only the
    /// lighting varies across the picture.
    fn grey_fruit() -> (LstModel, Textures) {
        let mesh = crate::fill::mesher::tetrahedralize(&crate::mesh::shapes::named("fruit").unwrap(), 3000).unwrap();
        let vertices: Vec<u32> = (0..mesh.vertices.len() as u32).collect();
        let patch = Patch { source: 0, coords: vec![Vec3::splat(0.5); vertices.len()], vertices };
        let source = Source { exemplar: "grey".into(), volume: "grey.exr".into(), mask: MaskRef::File("m.exr".into()) };
        let tet_patches = vec![vec![0]; mesh.tets.len()];
        let model = LstModel { mesh, sources: vec![source], patches: vec![patch], tet_patches };
        let grey = Volume::from_fn([4; 3], Channel::rgb(), |_, _, _, o| o.fill(0.8)).unwrap();
        let full = Volume::from_fn([4; 3], vec![Channel::A], |_, _, _, o| o.fill(1.0)).unwrap();
        (model, Textures::new(&[grey], &[full]))
    }

    /// The 98th percentile of the brightness steps between neighbouring object pixels.
    fn steps(picture: &Rgb8) -> u8 {
        let at = |x: usize, y: usize| picture.data[(x + y * picture.width) * 3];
        let mut all: Vec<u8> = Vec::new();
        for y in 0..picture.height {
            for x in 0..picture.width - 1 {
                let (a, b) = (at(x, y), at(x + 1, y));
                if a != BACKGROUND[0] && b != BACKGROUND[0] {
                    all.push(a.abs_diff(b));
                }
            }
        }
        all.sort_unstable();
        all[all.len() * 98 / 100]
    }

    #[test]
    fn smooth_shading_hides_the_tet_faces_that_flat_shading_shows() {
        let (model, textures) = grey_fruit();
        let flat = surface_shaded(&model, &textures, 35.0, 25.0, 256, Shading::Flat);
        let smooth = surface(&model, &textures, 35.0, 25.0, 256);
        let (f, s) = (steps(&flat), steps(&smooth));
        assert!(f >= 10 && s <= 6, "flat steps {f}, smooth steps {s}");
        // a crease of 0 degrees averages nothing: flat again
        let no_crease = surface_shaded(&model, &textures, 35.0, 25.0, 256, Shading::Smooth { crease: 0.0 });
        assert!(steps(&no_crease) >= 10);
    }
}
