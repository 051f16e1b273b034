//! Cutting by strokes (thesis §6.1.1): each stroke is a polyline swept along a direction
//! into a surface that splits the model in two; the side holding a chosen point stays.
//! Several strokes keep what lies on the kept side of every one. The result is drawn as a
//! lit 3D view: the model's surface where it stays, and each cut face inside the model,
//! textured by the patches there.
//!
//! ```text
//!   stroke p0 p1 ... pn, extrude e -> the surface { p(s) + t e }; side(x) = left (+) / right (-)
//!                                      of the polyline seen along e (ends continue straight)
//!   per pixel, nearest of: boundary faces where every stroke keeps the point,
//!                          each stroke's surface where the model holds the point and the
//!                          other strokes keep it
//! ```

use super::model::LstModel;
use super::render::Textures;
use super::render::shade_point;
use super::tets::TetMesh;
use super::view::{Displacement, Frame, Hit, MIDLEVEL, Rays, Shading, draw_triangle, facets, rasterize};
use crate::error::{Error, Result};
use crate::render::Rgb8;
use glam::{Vec2, Vec3};

/// A polyline swept along a direction.
#[derive(Debug, Clone)]
pub struct Stroke {
    /// Two or more points.
    pub points: Vec<Vec3>,
    /// The direction the polyline is swept along (not zero; normalized on use).
    pub extrude: Vec3,
}

/// A stroke ready to test points: the polyline seen along its direction.
struct Side {
    extrude: Vec3,
    u: Vec3,
    v: Vec3,
    points: Vec<Vec2>,
    /// +1 or -1: the sign of the kept side.
    kept: f32,
}

impl Side {
    fn new(stroke: &Stroke, keep: Vec3) -> Result<Side> {
        let e = stroke.extrude.try_normalize().ok_or_else(|| Error::invalid("a stroke's extrude direction is zero"))?;
        let u = e.any_orthonormal_vector();
        let v = e.cross(u);
        let mut points: Vec<Vec2> = stroke.points.iter().map(|p| Vec2::new(u.dot(*p), v.dot(*p))).collect();
        points.dedup_by(|a, b| a.distance(*b) < 1e-6);
        if points.len() < 2 {
            return Err(Error::invalid(
                "a stroke needs two points apart when seen along its extrude direction (it sweeps a line into a surface)",
            ));
        }
        let mut side = Side { extrude: e, u, v, points, kept: 1.0 };
        let at_keep = side.signed(keep);
        if at_keep == 0.0 {
            return Err(Error::invalid(format!(
                "the keep point {keep} lies on a stroke's surface; move it to one side"
            )));
        }
        side.kept = at_keep.signum();
        Ok(side)
    }

    /// Positive left of the polyline (seen along the extrude direction, the first end
    /// continuing backward and the last forward), negative right, 0 on it.
    fn signed(&self, p: Vec3) -> f32 {
        let q = Vec2::new(self.u.dot(p), self.v.dot(p));
        let n = self.points.len() - 1;
        let mut best = (f32::INFINITY, 0.0f32);
        for i in 0..n {
            let (a, b) = (self.points[i], self.points[i + 1]);
            let d = b - a;
            let t = (q - a).dot(d) / d.length_squared();
            let t = match (i == 0, i + 1 == n) {
                (true, true) => t,
                (true, false) => t.min(1.0),
                (false, true) => t.max(0.0),
                (false, false) => t.clamp(0.0, 1.0),
            };
            let closest = a + d * t;
            let normal = if (t <= 0.0 && i > 0) || (t >= 1.0 && i + 1 < n) {
                // a corner: both segments meet there; their left normals averaged
                let j = if t <= 0.0 { i - 1 } else { i + 1 };
                let other = if j < i { a - self.points[j] } else { self.points[j + 1] - b };
                left(d) + left(other)
            } else {
                left(d)
            };
            let distance = q.distance_squared(closest);
            if distance < best.0 {
                best = (distance, (q - closest).dot(normal));
            }
        }
        best.1
    }

    /// Whether `p` is on the kept side (or on the surface).
    fn keeps(&self, p: Vec3) -> bool {
        self.signed(p) * self.kept >= 0.0
    }
}

fn left(d: Vec2) -> Vec2 {
    Vec2::new(-d.y, d.x).normalize_or_zero()
}

/// What a carved view drew.
pub struct Carving {
    /// The lit picture.
    pub picture: Rgb8,
    /// Share of the picture's pixels that show a cut face.
    pub cut_share: f64,
}

/// Draws `model` cut by `strokes`, keeping the side of each that holds `keep`, seen from
/// `camera` (yaw, pitch degrees) at `size` pixels; with a `relief`, the cut faces are split
/// into triangles about two pixels across whose corners move along the face's normal (out
/// of the material) by `scale x (d - 0.5)`, `d` the Displacement channel inside.
pub fn carve(
    model: &LstModel,
    textures: &Textures,
    strokes: &[Stroke],
    keep: Vec3,
    camera: (f32, f32),
    size: usize,
    relief: Option<Displacement>,
) -> Result<Carving> {
    if strokes.is_empty() {
        return Err(Error::invalid("no stroke to cut by"));
    }
    let sides = strokes.iter().map(|s| Side::new(s, keep)).collect::<Result<Vec<_>>>()?;
    let relief = match relief {
        Some(d) => Some((d.textures.first().ok_or_else(|| Error::invalid("no displacement texture given"))?, d.scale)),
        None => None,
    };
    let frame = Frame::new(&[model], camera, size);
    let shading = Shading::Smooth { crease: super::view::DEFAULT_CREASE };
    let mut hits = rasterize(&facets(model, 0, shading), &frame, |p| sides.iter().all(|s| s.keeps(p)));
    let boundary: Vec<Option<f32>> = hits.iter().map(|h| h.map(|h| h.depth)).collect();
    let rays = Rays::new(&model.surface, &frame);
    let reach = reach(&model.mesh, &strokes.iter().flat_map(|s| s.points.iter().copied()).collect::<Vec<_>>());
    for (k, side) in sides.iter().enumerate() {
        let others = |p: Vec3| sides.iter().enumerate().all(|(j, s)| j == k || s.keeps(p));
        for quad in surface(side, reach) {
            let normal = (quad[1] - quad[0]).cross(quad[2] - quad[0]).normalize_or_zero();
            let facing = if normal.dot(frame.forward) > 0.0 { -normal } else { normal };
            let triangles = match &relief {
                None => vec![
                    [(quad[0], quad[0]), (quad[1], quad[1]), (quad[2], quad[2])],
                    [(quad[0], quad[0]), (quad[2], quad[2]), (quad[3], quad[3])],
                ],
                Some((textures, scale)) => relief_triangles(&quad, facing, model, (textures, *scale), frame.pixel()),
            };
            for tri in triangles {
                let shown = tri.map(|c| c.1);
                let lit = (shown[1] - shown[0]).cross(shown[2] - shown[0]).normalize_or(facing);
                let lit = if lit.dot(facing) < 0.0 { -lit } else { lit };
                draw_triangle(&mut hits, size, shown.map(|p| frame.to_pixel(p)), |b| {
                    let p = tri[0].0 * b[0] + tri[1].0 * b[1] + tri[2].0 * b[2];
                    let q = shown[0] * b[0] + shown[1] * b[1] + shown[2] * b[2];
                    // inside by the ray through p's own pixel (q is p displaced)
                    let pixel = frame.to_pixel(p).floor();
                    let (x, y) = (
                        pixel.x.clamp(0.0, (size - 1) as f32) as usize,
                        pixel.y.clamp(0.0, (size - 1) as f32) as usize,
                    );
                    if !rays.inside(x, y, p) {
                        return None;
                    }
                    let hit = Hit { depth: frame.forward.dot(q), model: 0, triangle: u32::MAX, point: p, normal: lit };
                    others(p).then_some(hit)
                });
            }
        }
    }
    let cut = hits.iter().zip(&boundary).filter(|(h, b)| h.is_some_and(|h| **b != Some(h.depth))).count();
    Ok(Carving { picture: frame.shade(&[(model, textures)], &hits), cut_share: cut as f64 / (size * size) as f64 })
}

/// The most triangles one displaced cut face is split into.
const MAX_RELIEF_TRIANGLES: usize = 2_000_000;

/// The part of a stroke's quad inside the model's bounds as a grid of triangles about two
/// pixels across, each corner (point on the face, point shown) moved along `facing` by
/// `scale x (d - 0.5)`, `d` the model's Displacement channel there (see [`LstModel::locate`]).
fn relief_triangles(
    quad: &[Vec3; 4],
    facing: Vec3,
    model: &LstModel,
    (textures, scale): (&Textures, f32),
    pixel: f32,
) -> Vec<[(Vec3, Vec3); 3]> {
    let (origin, along, across) = (quad[0], quad[1] - quad[0], quad[3] - quad[0]);
    let (lo, hi) =
        model.mesh.vertices.iter().fold((Vec3::INFINITY, Vec3::NEG_INFINITY), |(a, b), p| (a.min(*p), b.max(*p)));
    // the quad's parameters (0 to 1 along each side) that reach the model's bounds
    let span = |axis: Vec3| {
        let corners = (0..8).map(|i| Vec3::new([lo.x, hi.x][i & 1], [lo.y, hi.y][(i >> 1) & 1], [lo.z, hi.z][i >> 2]));
        let t: Vec<f32> = corners.map(|c| (c - origin).dot(axis) / axis.length_squared()).collect();
        let (a, b) = t.iter().fold((f32::INFINITY, f32::NEG_INFINITY), |(a, b), x| (a.min(*x), b.max(*x)));
        (a.clamp(0.0, 1.0), b.clamp(0.0, 1.0))
    };
    let ((s0, s1), (t0, t1)) = (span(along), span(across));
    let step = 2.0 * pixel.max(1e-9);
    let cells = |length: f32| ((length / step).ceil() as usize).max(1);
    let (mut ns, mut nt) = (cells(along.length() * (s1 - s0)), cells(across.length() * (t1 - t0)));
    let over = ((2 * ns * nt) as f32 / MAX_RELIEF_TRIANGLES as f32).sqrt();
    if over > 1.0 {
        (ns, nt) = (((ns as f32 / over) as usize).max(1), ((nt as f32 / over) as usize).max(1));
    }
    let corner = |i: usize, j: usize| {
        let (s, t) = (s0 + (s1 - s0) * i as f32 / ns as f32, t0 + (t1 - t0) * j as f32 / nt as f32);
        let p = origin + along * s + across * t;
        let d = shade_point(model, textures, p).map_or(MIDLEVEL, |c| c[0]);
        (p, p + facing * scale * (d - MIDLEVEL))
    };
    let corners: Vec<(Vec3, Vec3)> =
        (0..=nt).flat_map(|j| (0..=ns).map(move |i| (i, j))).map(|(i, j)| corner(i, j)).collect();
    let at = |i: usize, j: usize| corners[j * (ns + 1) + i];
    let mut out = Vec::with_capacity(2 * ns * nt);
    for j in 0..nt {
        for i in 0..ns {
            out.push([at(i, j), at(i + 1, j), at(i + 1, j + 1)]);
            out.push([at(i, j), at(i + 1, j + 1), at(i, j + 1)]);
        }
    }
    out
}

/// A length that carries a stroke's surface past the model on every side.
fn reach(mesh: &TetMesh, points: &[Vec3]) -> f32 {
    let (lo, hi) = mesh.vertices.iter().fold((Vec3::INFINITY, Vec3::NEG_INFINITY), |(a, b), p| (a.min(*p), b.max(*p)));
    let centre = (lo + hi) / 2.0;
    let far = points.iter().map(|p| p.distance(centre)).fold(0.0f32, f32::max);
    2.0 * ((hi - lo).length() + far + centre.length())
}

/// The stroke's surface as quads (corners in order), its ends carried `reach` further.
fn surface(side: &Side, reach: f32) -> Vec<[Vec3; 4]> {
    // the polyline on the plane through the origin across the extrude direction
    let points: Vec<Vec3> = side.points.iter().map(|q| side.u * q.x + side.v * q.y).collect();
    let n = points.len() - 1;
    let e = side.extrude * reach;
    (0..n)
        .map(|i| {
            let (mut a, mut b) = (points[i], points[i + 1]);
            let d = (b - a).normalize();
            if i == 0 {
                a -= d * reach;
            }
            if i + 1 == n {
                b += d * reach;
            }
            [a - e, b - e, b + e, a + e]
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::fill::model::{MaskRef, Source};
    use crate::fill::patch::Patch;
    use crate::fill::render::{View, cut};
    use crate::fill::tets::cube_lattice;
    use crate::volume::{Channel, Volume};

    fn side(points: &[[f32; 3]], extrude: Vec3, keep: Vec3) -> Side {
        let stroke = Stroke { points: points.iter().map(|p| Vec3::from(*p)).collect(), extrude };
        Side::new(&stroke, keep).unwrap()
    }

    #[test]
    fn a_bent_stroke_splits_space_into_the_inside_and_outside_of_its_bend() {
        // a V in the xy plane, swept along z: inside the V is left of the stroke
        let v = side(&[[-1.0, 1.0, 0.0], [0.0, 0.0, 0.0], [1.0, 1.0, 0.0]], Vec3::Z, Vec3::new(0.0, 0.5, 0.0));
        for (p, inside) in
            [([0.0, 0.5, 3.0], true), ([0.0, -0.5, -2.0], false), ([0.9, 0.95, 0.0], true), ([3.0, 0.0, 0.0], false)]
        {
            assert_eq!(v.keeps(Vec3::from(p)), inside, "{p:?}");
            assert_eq!(v.signed(Vec3::from(p)) > 0.0, inside, "{p:?}");
        }
        // the ends continue straight: far along the first segment's line the side holds
        assert!(v.keeps(Vec3::new(-5.0, 5.5, 0.0)) && !v.keeps(Vec3::new(-5.0, 4.5, 0.0)));
        let on = Stroke { points: vec![Vec3::ZERO, Vec3::X], extrude: Vec3::Z };
        assert!(Side::new(&on, Vec3::new(0.5, 0.0, 1.0)).is_err(), "a keep point on the surface is refused");
        let along = Stroke { points: vec![Vec3::ZERO, Vec3::Z], extrude: Vec3::Z };
        assert!(Side::new(&along, Vec3::X).is_err(), "a stroke along its own sweep makes no surface");
    }

    /// The unit cube, one patch whose texture coordinates are the positions, coloured by
    /// position (R = x, G = y, B = 0.5).
    fn cube() -> (LstModel, Textures) {
        let mesh = cube_lattice([4, 4, 4], 0.25);
        let vertices: Vec<u32> = (0..mesh.vertices.len() as u32).collect();
        let patch = Patch { source: 0, coords: mesh.vertices.clone(), vertices };
        let source = Source { exemplar: "ramp".into(), volume: "ramp.exr".into(), mask: MaskRef::File("m.exr".into()) };
        let tet_patches = vec![vec![0]; mesh.tets.len()];
        let surface = LstModel::boundary_of(&mesh).unwrap();
        let model = LstModel::new(mesh, surface, vec![source], vec![patch], tet_patches);
        let colour = Volume::from_fn([16; 3], Channel::rgb(), |x, y, _, o| {
            o.copy_from_slice(&[(x as f32 + 0.5) / 16.0, (y as f32 + 0.5) / 16.0, 0.5])
        })
        .unwrap();
        let full = Volume::from_fn([2; 3], vec![Channel::A], |_, _, _, o| o.fill(1.0)).unwrap();
        (model, Textures::new(&[colour], &[full]))
    }

    #[test]
    fn a_straight_stroke_cuts_the_face_the_planar_cut_shows() {
        let (model, textures) = cube();
        let size = 64;
        // the stroke runs along x at z = 0.5 and is swept along y: the plane z = 0.5
        let stroke = Stroke { points: vec![Vec3::new(-1.0, 0.3, 0.5), Vec3::new(2.0, 0.3, 0.5)], extrude: Vec3::Y };
        let below = Vec3::new(0.5, 0.5, 0.2);
        let carved = carve(&model, &textures, std::slice::from_ref(&stroke), below, (0.0, 0.0), size, None).unwrap();
        let plane = View::framing((Vec3::ZERO, Vec3::ONE), Vec3::splat(0.5), Vec3::Z, size).unwrap();
        let planar = cut(&model, &textures, &plane);
        // looking down -z from +z at the face z = 0.5, lit at 0.35 + 0.65 (n . light)
        let lit = 0.35 + 0.65 * Vec3::Z.dot(Vec3::new(0.3, 0.6, 1.0).normalize());
        let mut compared = 0;
        for y in 4..size - 4 {
            for x in 4..size - 4 {
                let (mx, my) =
                    (0.5 + (x as f32 + 0.5 - 32.0) * 1.08 / 64.0, 0.5 - (y as f32 + 0.5 - 32.0) * 1.08 / 64.0);
                if !(0.05..0.95).contains(&mx) || !(0.05..0.95).contains(&my) {
                    continue;
                }
                let step = 1.04 / size as f32;
                let (i, j) = (((mx + 0.02) / step) as usize, ((1.02 - my) / step) as usize);
                let want = planar.pixels[j * size + i];
                let got = carved.picture.at(x, y);
                for k in 0..3 {
                    let expected = want[k] * lit * 255.0;
                    assert!(
                        (got[k] as f32 - expected).abs() < 8.0,
                        "pixel {x},{y} channel {k}: {got:?} against {want:?}"
                    );
                }
                compared += 1;
            }
        }
        assert!(compared > 2500, "{compared}");
        assert!(carved.cut_share > 0.6, "the face fills most of the picture: {}", carved.cut_share);
        // keeping the other side, the camera sees the cube's own top (z = 1): no cut face
        // a relief of scale 0 draws the same face through its grid of small triangles
        let flat = Displacement { textures: std::slice::from_ref(&textures), scale: 0.0 };
        let gridded =
            carve(&model, &textures, std::slice::from_ref(&stroke), below, (0.0, 0.0), size, Some(flat)).unwrap();
        let differ = carved.picture.data.iter().zip(&gridded.picture.data).filter(|(a, b)| a.abs_diff(**b) > 2).count();
        assert!(differ < size * 4, "{differ} samples differ");
        let above = carve(&model, &textures, &[stroke], Vec3::new(0.5, 0.5, 0.8), (0.0, 0.0), size, None).unwrap();
        assert_eq!(above.cut_share, 0.0);
    }

    /// Displaced cut faces: on the unit cube whose Displacement is x, the face z = 0.5 seen
    /// from +z moves up by s (x - 0.5) at every corner inside; outside the model nothing moves.
    #[test]
    fn a_displaced_cut_face_follows_the_channel() {
        let (model, _) = cube();
        let relief =
            Volume::from_fn([16; 3], vec![Channel::Displacement], |x, _, _, o| o[0] = (x as f32 + 0.5) / 16.0).unwrap();
        let full = Volume::from_fn([2; 3], vec![Channel::A], |_, _, _, o| o.fill(1.0)).unwrap();
        let textures = Textures::channel(&[relief], &[full], &[Channel::Displacement]).unwrap();
        let quad = [
            Vec3::new(-1.0, -1.0, 0.5),
            Vec3::new(2.0, -1.0, 0.5),
            Vec3::new(2.0, 2.0, 0.5),
            Vec3::new(-1.0, 2.0, 0.5),
        ];
        let scale = 0.2;
        let triangles = relief_triangles(&quad, Vec3::Z, &model, (&textures, scale), 0.01);
        let mut checked = 0;
        for (p, q) in triangles.iter().flatten() {
            assert!((q.x, q.y) == (p.x, p.y), "corners move along the normal only");
            if (0.1..0.9).contains(&p.x) && (0.05..0.95).contains(&p.y) {
                let want = 0.5 + scale * (p.x - 0.5);
                assert!((q.z - want).abs() < 0.002, "at {p}: {} against {want}", q.z);
                checked += 1;
            }
            if p.x < -0.01 || p.x > 1.01 {
                assert_eq!(q.z, 0.5, "outside the model at {p}");
            }
        }
        assert!(checked > 1000, "{checked}");
        // the grid covers the model's part of the quad only, about two pixels a cell
        assert!(triangles.len() < 2 * 120 * 120, "{}", triangles.len());
    }
}
