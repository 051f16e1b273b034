//! A picture of the filled model's surface: an orthographic z-buffer of the tet mesh's
//! boundary faces, each pixel coloured by compositing the patches of the tet behind it and
//! lit by a light over the viewer's shoulder.
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

/// What each pixel sees: the tet, the surface point, the face normal.
#[derive(Clone, Copy)]
struct Hit {
    depth: f32,
    tet: u32,
    point: Vec3,
    normal: Vec3,
}

/// Renders the surface of `model` seen from `yaw` degrees around y and `pitch` degrees up.
pub fn surface(model: &LstModel, textures: &Textures, yaw: f32, pitch: f32, size: usize) -> Rgb8 {
    let (yaw, pitch) = (yaw.to_radians(), pitch.to_radians());
    let forward = -Vec3::new(yaw.sin() * pitch.cos(), pitch.sin(), yaw.cos() * pitch.cos());
    let right = forward.cross(Vec3::Y).normalize_or(Vec3::X);
    let up = right.cross(forward);
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
    let hits = rasterize(model, size, &to_pixel, forward);
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

fn rasterize(model: &LstModel, size: usize, to_pixel: &dyn Fn(Vec3) -> Vec2, forward: Vec3) -> Vec<Option<Hit>> {
    let mesh = &model.mesh;
    let neighbours = mesh.neighbours();
    let mut hits: Vec<Option<Hit>> = vec![None; size * size];
    for (t, tet) in mesh.tets.iter().enumerate() {
        for (k, face) in FACES.iter().enumerate() {
            if neighbours[t][k] != super::tets::NONE {
                continue;
            }
            let p = face.map(|s| mesh.vertices[tet[s] as usize]);
            let normal = (p[1] - p[0]).cross(p[2] - p[0]).normalize_or_zero();
            if normal.dot(forward) >= 0.0 {
                continue;
            }
            let inward = (mesh.centroid(t) - (p[0] + p[1] + p[2]) / 3.0) * 1e-3;
            let s = p.map(to_pixel);
            draw_triangle(&mut hits, size, s, |b| {
                let point = p[0] * b[0] + p[1] * b[1] + p[2] * b[2];
                Hit { depth: forward.dot(point), tet: t as u32, point: point + inward, normal }
            });
        }
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
