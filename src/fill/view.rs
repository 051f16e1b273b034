//! A picture of the filled model's surface: an orthographic z-buffer of the model's input
//! surface (the closed mesh that was filled), each pixel coloured by compositing the
//! patches of the tet that holds the point (or of the nearest, its map extended: the tets
//! only approximate the surface) and lit by a light over the viewer's shoulder, with
//! normals blended smoothly across triangles except at creases (or flat, one normal per
//! triangle).
//!
//! ```text
//!   yaw/pitch -> view axes (right, up, forward) -> rasterize input triangles (nearest wins)
//!             -> per pixel: point -> tet -> patches composited -> x (ambient + diffuse)
//! ```

use super::locate::Location;
use super::model::LstModel;
use super::render::{BACKGROUND, TetLayers, Textures, shade_at, shade_point};
use crate::error::Result;
use crate::mesh::Mesh;
use crate::render::{Rgb8, to_u8};
use crate::surface::SkinLookup;
use glam::{Vec2, Vec3};
use rayon::prelude::*;

/// What each pixel sees: the model, the surface point, the shading normal.
#[derive(Clone, Copy)]
pub(super) struct Hit {
    /// Distance along the view direction (nearest wins).
    pub depth: f32,
    /// Which of the models drawn.
    pub model: u32,
    /// The triangle drawn (of the model's input surface, or of a skin's mesh).
    pub triangle: u32,
    /// The point sampled for colour.
    pub point: Vec3,
    /// The shading normal.
    pub normal: Vec3,
}

/// An orthographic camera framing a model: its axes and the model-to-pixel map.
pub(super) struct Frame {
    /// The view direction.
    pub forward: Vec3,
    right: Vec3,
    up: Vec3,
    centre: Vec2,
    scale: f32,
    /// Picture side in pixels.
    pub size: usize,
}

impl Frame {
    /// The camera `yaw`/`pitch` degrees around the models, their vertices filling the
    /// picture with a margin.
    pub fn new(models: &[&LstModel], camera: (f32, f32), size: usize) -> Frame {
        Frame::around(models.iter().flat_map(|m| m.surface.vertices.iter().copied()), camera, size)
    }

    /// The camera `yaw`/`pitch` degrees around `points`, which fill the picture with a margin.
    pub fn around(points: impl Iterator<Item = Vec3>, (yaw, pitch): (f32, f32), size: usize) -> Frame {
        let (forward, right, up) = camera(yaw, pitch);
        let project = |p: Vec3| Vec2::new(right.dot(p), up.dot(p));
        let (lo, hi) =
            points.fold((Vec2::INFINITY, Vec2::NEG_INFINITY), |(a, b), p| (a.min(project(p)), b.max(project(p))));
        let side = (hi - lo).max_element().max(1e-6) * 1.08;
        Frame { forward, right, up, centre: (lo + hi) / 2.0, scale: size as f32 / side, size }
    }

    /// Where a model point lands in the picture, in pixels.
    pub fn to_pixel(&self, p: Vec3) -> Vec2 {
        let q = (Vec2::new(self.right.dot(p), self.up.dot(p)) - self.centre) * self.scale;
        Vec2::new(q.x + self.size as f32 / 2.0, self.size as f32 / 2.0 - q.y)
    }

    /// The direction towards the light, over the viewer's shoulder.
    fn light(&self) -> Vec3 {
        (self.up * 0.6 - self.forward + self.right * 0.3).normalize()
    }

    /// Model units per pixel.
    pub fn pixel(&self) -> f32 {
        1.0 / self.scale
    }

    /// The picture of `hits`: each point's composited colour, lit by a light over the
    /// viewer's shoulder.
    pub fn shade(&self, models: &[(&LstModel, &Textures)], hits: &[Option<Hit>]) -> Rgb8 {
        self.shade_with_skin(models, hits, None)
    }

    /// [`Frame::shade`], with the colour of the points the skin covers taken from the skin
    /// instead of the solid texture.
    pub fn shade_with_skin(&self, models: &[(&LstModel, &Textures)], hits: &[Option<Hit>], skin: Option<Skin>) -> Rgb8 {
        let light = self.light();
        // a row at a time: neighbouring pixels mostly fall in one tet, whose layers are
        // then made once
        let rows: Vec<Vec<[u8; 3]>> = hits
            .par_chunks(self.size.max(1))
            .map(|row| {
                let mut near = vec![];
                near.resize_with(models.len(), Near::default);
                row.iter().map(|hit| self.colour_of(models, hit.as_ref(), skin, light, &mut near)).collect()
            })
            .collect();
        let mut out = Rgb8::new(self.size, self.size, BACKGROUND);
        for (i, c) in rows.into_iter().flatten().enumerate() {
            out.put(i % self.size, i / self.size, c);
        }
        out
    }

    /// The lit colour of one pixel's `hit` (`near`: per model, what its last pixel found).
    fn colour_of(
        &self,
        models: &[(&LstModel, &Textures)],
        hit: Option<&Hit>,
        skin: Option<Skin>,
        light: Vec3,
        near: &mut [Near],
    ) -> [u8; 3] {
        let Some(h) = hit else { return BACKGROUND };
        let (model, textures) = models[h.model as usize];
        let last = &mut near[h.model as usize];
        // located once for the skin's depth test and the colour
        let at = model.locate_near(h.point, &mut last.face);
        let on_skin = skin.and_then(|s| s.colour_at(model, h.model as usize, h.point, at.as_ref()));
        let colour =
            on_skin.map(|[r, g, b]| [r, g, b, 1.0]).or_else(|| at.map(|at| last.layers.shade_at(model, textures, &at)));
        let Some(c) = colour else { return BACKGROUND };
        let lit = 0.35 + 0.65 * h.normal.dot(light).max(0.0);
        [c[0], c[1], c[2]].map(|v| to_u8(v * lit))
    }
}

/// What a model's last pixel of a row found: the boundary face nearest its point and its
/// tet's layers (neighbouring pixels mostly share both).
#[derive(Default)]
struct Near {
    face: Option<u32>,
    layers: TetLayers,
}

/// Where the rays of a picture cross a model's input surface: per pixel, the depths at
/// which its ray enters and leaves the solid, to tell whether a point seen at a pixel
/// (on a stroke cut's face) lies inside.
pub(super) struct Rays {
    forward: Vec3,
    near: f32,
    step: f32,
    /// Per pixel row: where each pixel's crossings start in the row's list (one more
    /// than the pixels), and the crossings in steps from `near`, sorted per pixel.
    rows: Vec<(Vec<u32>, Vec<f64>)>,
}

impl Rays {
    /// The rays of `frame` through `surface` (closed).
    pub fn new(surface: &Mesh, frame: &Frame) -> Rays {
        let depths = surface.vertices.iter().map(|p| frame.forward.dot(*p));
        let (lo, hi) = depths.fold((f32::INFINITY, f32::NEG_INFINITY), |(a, b), d| (a.min(d), b.max(d)));
        let step = frame.pixel();
        let near = lo - step;
        let along = ((hi - near) / step).ceil() as usize + 2;
        // grid x: depth in steps from `near`; grid y and z: the pixel's x and y
        let (s, half) = (frame.scale, frame.size as f32 / 2.0);
        let to_grid = glam::Affine3A::from_cols(
            Vec3::new(frame.forward.x / step, frame.right.x * s, -frame.up.x * s).into(),
            Vec3::new(frame.forward.y / step, frame.right.y * s, -frame.up.y * s).into(),
            Vec3::new(frame.forward.z / step, frame.right.z * s, -frame.up.z * s).into(),
            Vec3::new(-near / step, half - frame.centre.x * s, half + frame.centre.y * s).into(),
        );
        let slices = crate::mesh::Slices::new(&surface.transformed(to_grid), [along, frame.size, frame.size]);
        let rows = (0..frame.size)
            .into_par_iter()
            .map(|y| {
                let pixels = slices.crossings(y);
                let mut starts = Vec::with_capacity(pixels.len() + 1);
                starts.push(0u32);
                let mut all = Vec::new();
                for crossings in pixels {
                    all.extend(crossings);
                    starts.push(all.len() as u32);
                }
                (starts, all)
            })
            .collect();
        Rays { forward: frame.forward, near, step, rows }
    }

    /// Whether `p`, seen at pixel `(x, y)`, lies inside the surface.
    pub fn inside(&self, x: usize, y: usize, p: Vec3) -> bool {
        let depth = f64::from((self.forward.dot(p) - self.near) / self.step);
        let (starts, all) = &self.rows[y];
        let crossings = &all[starts[x] as usize..starts[x + 1] as usize];
        crossings.partition_point(|c| *c < depth) % 2 == 1
    }
}

/// How the surface is lit.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Shading {
    /// One normal per triangle: the input mesh's facets show.
    Flat,
    /// Normals blended across each triangle from its corners. A corner's normal is the
    /// area-weighted mean of the triangles around it whose normals lie within `crease`
    /// degrees of the triangle's own, so edges sharper than that stay sharp.
    Smooth {
        /// Degrees, 0 to 180.
        crease: f32,
    },
}

/// The crease angle of [`Shading::Smooth`] by default, in degrees.
pub const DEFAULT_CREASE: f32 = 60.0;

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
    surfaces(&[(model, textures)], None, None, (yaw, pitch), size, shading).0
}

/// Displacement mapping (thesis §7, Figs. 5.1d and 7.1c): the surface moved along its
/// normal by `scale x (d - MIDLEVEL)`, `d` the exemplars' Displacement channel sampled on
/// the surface.
#[derive(Clone, Copy)]
pub struct Displacement<'a> {
    /// Per model, textures sampling the displacement (see [`Textures::channel`]).
    pub textures: &'a [Textures],
    /// Model units per unit of displacement.
    pub scale: f32,
}

/// The displacement value that leaves the surface in place (as Blender's midlevel).
pub const MIDLEVEL: f32 = 0.5;

/// The finest subdivision of a boundary face: its edges split in this many parts.
const MAX_LEVEL: usize = 32;
/// The most triangles a displaced surface is split into (about 120 bytes each).
const MAX_TRIANGLES: usize = 2_000_000;

/// A synthesized surface texture drawn where the model's surface lies within `within`
/// model units of it (see [`crate::surface`]) and, when the exemplars carry a Depth
/// channel, where the solid is at depth 0 there (so the cut ends of a log keep their
/// rings while its side shows bark).
#[derive(Clone, Copy)]
pub struct Skin<'a> {
    /// The skin's colours near the surface.
    pub lookup: &'a SkinLookup<'a>,
    /// How far from the skin a surface point may be and still take its colour.
    pub within: f32,
    /// Per model, its exemplars' Depth channel (see [`Textures::channel`]), if they have one.
    pub depth: Option<&'a [Textures]>,
}

/// The deepest solid depth the skin covers (depth runs from 0 outside to 1 inside).
pub const SKIN_DEPTH: f32 = 0.05;

impl Skin<'_> {
    /// The skin's colour at `point` of model `index` (located at `at`, see
    /// [`LstModel::locate`]), or `None` where the solid shows.
    pub fn colour_at(&self, model: &LstModel, index: usize, point: Vec3, at: Option<&Location>) -> Option<[f32; 3]> {
        if let Some(depth) = self.depth
            && at.is_none_or(|at| shade_at(model, &depth[index], at)[0] > SKIN_DEPTH)
        {
            return None;
        }
        let (distance, colour) = self.lookup.at(point);
        (distance <= self.within).then_some(colour)
    }
}

/// The surfaces of several models (each pixel shows the nearest), seen from `camera`
/// (yaw, pitch degrees); with a displacement, the surface is subdivided into triangles
/// about two pixels across and displaced, lit by the displaced triangles' normals; with a
/// skin, the surface near it shows the skin's colours. Also the triangles drawn.
pub fn surfaces(
    models: &[(&LstModel, &Textures)],
    displacement: Option<Displacement>,
    skin: Option<Skin>,
    camera: (f32, f32),
    size: usize,
    shading: Shading,
) -> (Rgb8, usize) {
    let view = View { camera, size, shading };
    surfaces_with(models, displacement, skin, view, &crate::progress::NoProgress)
        .expect("work that is never cancelled ends")
}

/// Where a surface picture is seen from: camera (yaw, pitch degrees), side in pixels,
/// shading.
#[derive(Debug, Clone, Copy)]
pub struct View {
    /// Yaw and pitch in degrees.
    pub camera: (f32, f32),
    /// The picture's side in pixels.
    pub size: usize,
    /// Flat or smooth.
    pub shading: Shading,
}

/// [`surfaces`], telling `progress` how many triangles are drawn and stopping when it is
/// cancelled.
pub fn surfaces_with(
    models: &[(&LstModel, &Textures)],
    displacement: Option<Displacement>,
    skin: Option<Skin>,
    View { camera, size, shading }: View,
    progress: &dyn crate::progress::Progress,
) -> Result<(Rgb8, usize)> {
    let meshes: Vec<&LstModel> = models.iter().map(|(m, _)| *m).collect();
    // made once before the threads below locate points
    meshes.iter().for_each(|m| _ = m.locator());
    let frame = Frame::new(&meshes, camera, size);
    let mut all = Vec::new();
    for (i, (model, _)) in models.iter().enumerate() {
        let mut facets = facets(model, i as u32, shading);
        if let Some(d) = displacement {
            let edges = facets.iter().flat_map(|f| (0..3).map(|k| (f.shown[k] - f.shown[(k + 1) % 3]).length()));
            let pixels = edges.fold(0.0f32, f32::max) / frame.pixel();
            let affordable = ((MAX_TRIANGLES / facets.len().max(1)) as f32).sqrt() as usize;
            let level = ((pixels / 2.0).ceil() as usize).clamp(1, MAX_LEVEL.min(affordable.max(1)));
            let normals = vertex_normals(model, &facets);
            let taper = Taper::new(model, &facets, 2.0 * d.scale.abs() + frame.pixel());
            facets = displaced(model, &facets, (&normals, &taper), &d.textures[i], d.scale, level);
        }
        all.extend(facets);
    }
    let mut hits = vec![None; frame.size * frame.size];
    const CHUNK: usize = 1 << 16;
    for (k, chunk) in all.chunks(CHUNK).enumerate() {
        draw_facets(&mut hits, chunk, &frame, |_| true);
        progress.update("triangles", ((k + 1) * CHUNK).min(all.len()) as f32 / all.len() as f32);
        if progress.cancelled() {
            return Err(crate::Error::Cancelled);
        }
    }
    Ok((frame.shade_with_skin(models, &hits, skin), all.len()))
}

/// A closed mesh seen as [`surfaces`] sees a model's input surface, each visible point
/// coloured by `colours`, which is given every visible point at once (in pixel order) so
/// that what the colours need can be made together: the picture, lit as [`surfaces`]
/// lights a model.
pub fn mesh_picture(
    mesh: &Mesh,
    View { camera, size, shading }: View,
    colours: impl FnOnce(&[Vec3]) -> Result<Vec<[f32; 3]>>,
) -> Result<Rgb8> {
    let frame = Frame::around(mesh.vertices.iter().copied(), camera, size);
    let faces = faces_of(mesh);
    let normals = corner_normals(&faces, &corner_fans(&faces, shading));
    let facets: Vec<Facet> = faces
        .iter()
        .zip(normals)
        .map(|(f, normals)| {
            let p = f.corners;
            Facet { model: 0, triangle: f.triangle, ids: f.ids, shown: p, sampled: p, normals }
        })
        .collect();
    let mut hits = vec![None; size * size];
    draw_facets(&mut hits, &facets, &frame, |_| true);
    let points: Vec<Vec3> = hits.iter().flatten().map(|h| h.point).collect();
    let coloured = colours(&points)?;
    let light = frame.light();
    let mut out = Rgb8::new(size, size, BACKGROUND);
    for ((i, h), c) in hits.iter().enumerate().filter_map(|(i, h)| h.as_ref().map(|h| (i, h))).zip(coloured) {
        let lit = 0.35 + 0.65 * h.normal.dot(light).max(0.0);
        out.put(i % size, i / size, c.map(|v| to_u8(v * lit)));
    }
    Ok(out)
}

/// A skin (a mesh with an RGB colour per vertex, see [`crate::surface`]) seen from
/// `camera` (yaw, pitch degrees), its colours blended across each triangle, smooth-shaded
/// by its vertex normals and lit as [`surfaces`] lights a model.
pub fn skin_picture(mesh: &Mesh, colours: &[[f32; 3]], camera: (f32, f32), size: usize) -> Rgb8 {
    let frame = Frame::around(mesh.vertices.iter().copied(), camera, size);
    let normals = crate::surface::retile::vertex_normals(&mesh.vertices, &mesh.triangles);
    let mut hits: Vec<Option<Hit>> = vec![None; size * size];
    for (i, t) in mesh.triangles.iter().enumerate() {
        let corners = t.map(|v| mesh.vertices[v as usize]);
        let flat = (corners[1] - corners[0]).cross(corners[2] - corners[0]).normalize_or_zero();
        draw_triangle(&mut hits, size, corners.map(|p| frame.to_pixel(p)), |b| {
            let point = at(corners, b);
            let normal = at(t.map(|v| normals[v as usize]), b).normalize_or(flat);
            // the model field holds nothing; `point` the barycentric weights, for the colour
            Some(Hit { depth: frame.forward.dot(point), model: 0, triangle: i as u32, point: Vec3::from(b), normal })
        });
    }
    let light = frame.light();
    let mut out = Rgb8::new(size, size, BACKGROUND);
    for (i, hit) in hits.iter().enumerate() {
        let Some(h) = hit else { continue };
        let t = mesh.triangles[h.triangle as usize];
        let [a, b, c] = t.map(|v| colours[v as usize]);
        let w = h.point;
        let lit = 0.35 + 0.65 * h.normal.dot(light).max(0.0);
        out.put(i % size, i / size, [0, 1, 2].map(|k| to_u8((w.x * a[k] + w.y * b[k] + w.z * c[k]) * lit)));
    }
    out
}

/// How shattered a surface picture looks: the share of the pixels inside the outline
/// (eroded by 3 px) with a luminance step above 6/255 to a 4-neighbour, leaving out the
/// pixels within 2 px of an occlusion edge or of an edge of `surface` sharper than `crease`
/// degrees. The edges are found by drawing `surface` with the picture's camera (a depth
/// step of over 3 pixels between neighbours; neighbouring triangles whose normals differ by
/// more than `crease`). A picture of a uniform exemplar shows shading only, so what this
/// counts are facets the surface does not have.
pub fn shard_share(picture: &Rgb8, surface: &Mesh, camera: (f32, f32), crease: f32) -> f64 {
    let size = picture.width;
    let frame = Frame::around(surface.vertices.iter().copied(), camera, size);
    let normals: Vec<Vec3> = surface
        .triangles
        .iter()
        .map(|t| {
            let c = t.map(|v| surface.vertices[v as usize]);
            (c[1] - c[0]).cross(c[2] - c[0]).normalize_or_zero()
        })
        .collect();
    let mut hits: Vec<Option<Hit>> = vec![None; size * size];
    for (i, t) in surface.triangles.iter().enumerate() {
        let corners = t.map(|v| surface.vertices[v as usize]);
        if normals[i].dot(frame.forward) >= 0.0 {
            continue;
        }
        draw_triangle(&mut hits, size, corners.map(|p| frame.to_pixel(p)), |b| {
            let point = at(corners, b);
            Some(Hit { depth: frame.forward.dot(point), model: 0, triangle: i as u32, point, normal: normals[i] })
        });
    }
    let (limit, jump) = (crease.to_radians().cos(), 3.0 * frame.pixel());
    let mut edge = vec![false; size * size];
    let mut outside = vec![false; size * size];
    for y in 0..size {
        for x in 0..size {
            let i = y * size + x;
            let Some(a) = hits[i] else {
                outside[i] = true;
                continue;
            };
            for j in [(x + 1 < size).then_some(i + 1), (y + 1 < size).then_some(i + size)].into_iter().flatten() {
                let Some(b) = hits[j] else { continue };
                let creased =
                    a.triangle != b.triangle && normals[a.triangle as usize].dot(normals[b.triangle as usize]) < limit;
                if creased || (a.depth - b.depth).abs() > jump {
                    (edge[i], edge[j]) = (true, true);
                }
            }
        }
    }
    let (near_edge, near_outside) = (grow(&edge, size, 2), grow(&outside, size, 3));
    let luma = |i: usize| {
        let p = &picture.data[i * 3..i * 3 + 3];
        crate::volume::luminance([p[0] as f32, p[1] as f32, p[2] as f32])
    };
    let counted = |i: usize| !near_edge[i] && !near_outside[i];
    let (mut steps, mut total) = (0usize, 0usize);
    for y in 0..size {
        for x in 0..size {
            let i = y * size + x;
            if !counted(i) {
                continue;
            }
            total += 1;
            let neighbours = [
                (x + 1 < size).then_some(i + 1),
                (y + 1 < size).then_some(i + size),
                (x > 0).then(|| i - 1),
                (y > 0).then(|| i - size),
            ];
            if neighbours.into_iter().flatten().any(|j| counted(j) && (luma(i) - luma(j)).abs() > 6.0) {
                steps += 1;
            }
        }
    }
    steps as f64 / total.max(1) as f64
}

/// The pixels within `reach` (Chebyshev) of a marked one.
fn grow(marked: &[bool], size: usize, reach: usize) -> Vec<bool> {
    let mut out = vec![false; marked.len()];
    for (i, _) in marked.iter().enumerate().filter(|(_, m)| **m) {
        let (x, y) = (i % size, i / size);
        for v in y.saturating_sub(reach)..(y + reach + 1).min(size) {
            for u in x.saturating_sub(reach)..(x + reach + 1).min(size) {
                out[v * size + u] = true;
            }
        }
    }
    out
}

/// Model units per pixel of a `size`-pixel picture of `models` seen from `camera` (yaw,
/// pitch degrees), as [`surfaces`] frames them.
pub fn pixel_size(models: &[&LstModel], camera: (f32, f32), size: usize) -> f32 {
    Frame::new(models, camera, size).pixel()
}

/// The axes of an orthographic camera `yaw` degrees around y and `pitch` degrees up from
/// the +z side, looking at the origin: (forward, right, up), orthonormal.
pub fn camera(yaw: f32, pitch: f32) -> (Vec3, Vec3, Vec3) {
    let (yaw, pitch) = (yaw.to_radians(), pitch.to_radians());
    let forward = -Vec3::new(yaw.sin() * pitch.cos(), pitch.sin(), yaw.cos() * pitch.cos());
    // looking straight up or down, the cross product with y vanishes (and its sign follows
    // the rounding of cos 90°, which turned the picture half round): take the yaw's own
    // right, the limit from any pitch short of it
    let right = if pitch.cos() > 1e-4 {
        forward.cross(Vec3::Y).normalize_or(Vec3::X)
    } else {
        Vec3::new(yaw.cos(), 0.0, -yaw.sin())
    };
    (forward, right, right.cross(forward))
}

/// A triangle of a model's input surface: its number, corners (vertex ids and points),
/// unit normal and area.
pub(super) struct Face {
    pub triangle: u32,
    pub ids: [u32; 3],
    pub corners: [Vec3; 3],
    pub normal: Vec3,
    pub area: f32,
}

/// The triangles of the model's input surface as faces.
pub(super) fn surface_faces(model: &LstModel) -> Vec<Face> {
    faces_of(&model.surface)
}

/// The triangles of a mesh as faces.
fn faces_of(surface: &Mesh) -> Vec<Face> {
    (surface.triangles.iter().enumerate())
        .map(|(i, &ids)| {
            let corners = ids.map(|v| surface.vertices[v as usize]);
            let cross = (corners[1] - corners[0]).cross(corners[2] - corners[0]);
            Face { triangle: i as u32, ids, corners, normal: cross.normalize_or_zero(), area: cross.length() / 2.0 }
        })
        .collect()
}

/// The corners of the faces (slot 3f + k: corner k of face f) gathered into fans under
/// `shading`. Smooth: the corners of a vertex are joined across every edge that is not a
/// crease (an edge whose faces' normals differ by more than the crease angle, or that is
/// not shared by exactly two faces). Flat: every corner is its own fan.
pub(super) fn corner_fans(faces: &[Face], shading: Shading) -> Fans {
    let mut fans = Fans((0..3 * faces.len() as u32).collect());
    let Shading::Smooth { crease } = shading else { return fans };
    let limit = crease.clamp(0.0, 180.0).to_radians().cos();
    let mut edges: Vec<((u32, u32), u32)> = (faces.iter().enumerate())
        .flat_map(|(i, f)| (0..3).map(move |k| (f.ids[k], f.ids[(k + 1) % 3], i as u32)))
        .map(|(a, b, f)| ((a.min(b), a.max(b)), f))
        .collect();
    edges.sort_unstable();
    for run in edges.chunk_by(|x, y| x.0 == y.0) {
        let [(key, f), (_, g)] = run else { continue };
        let (f, g) = (&faces[*f as usize], &faces[*g as usize]);
        if f.normal.dot(g.normal) < limit {
            continue;
        }
        for v in [key.0, key.1] {
            let slot = |face: &Face| 3 * face.triangle + face.ids.iter().position(|&u| u == v).unwrap_or(0) as u32;
            fans.join(slot(f), slot(g));
        }
    }
    fans
}

/// The normal at each corner of each face: the area-weighted mean normal of the faces of
/// its fan ([`corner_fans`]), so the normal is continuous across every edge that is not a
/// crease (and each face's own under flat shading).
pub(super) fn corner_normals(faces: &[Face], fans: &Fans) -> Vec<[Vec3; 3]> {
    let mut sums = vec![Vec3::ZERO; 3 * faces.len()];
    for (i, f) in faces.iter().enumerate() {
        for k in 0..3 {
            sums[fans.root(3 * i as u32 + k) as usize] += f.normal * f.area;
        }
    }
    (faces.iter().enumerate())
        .map(|(i, f)| std::array::from_fn(|k| sums[fans.root((3 * i + k) as u32) as usize].normalize_or(f.normal)))
        .collect()
}

/// Union–find over corner slots.
pub(super) struct Fans(Vec<u32>);

impl Fans {
    /// The slot that stands for the fan of `i`.
    pub(super) fn root(&self, mut i: u32) -> u32 {
        while self.0[i as usize] != i {
            i = self.0[i as usize];
        }
        i
    }

    fn join(&mut self, a: u32, b: u32) {
        let (a, b) = (self.root(a), self.root(b));
        // the lower slot is the root: the result does not depend on the order of joins
        let (low, high) = (a.min(b), a.max(b));
        self.0[high as usize] = low;
    }
}

/// A triangle to draw: the points shown (on the surface, or displaced), the points its
/// colour is sampled at (on the surface), and the shading normal at each corner.
pub(super) struct Facet {
    pub model: u32,
    /// The input surface's triangle it is or lies on.
    pub triangle: u32,
    /// The surface vertices at the corners (of the triangle it is or lies on).
    pub ids: [u32; 3],
    pub shown: [Vec3; 3],
    pub sampled: [Vec3; 3],
    pub normals: [Vec3; 3],
}

impl Facet {
    /// The unit normal of the shown triangle (outward, as the surface's triangles are).
    pub fn normal(&self) -> Vec3 {
        let s = self.shown;
        (s[1] - s[0]).cross(s[2] - s[0]).normalize_or_zero()
    }
}

/// Blends three corner values at barycentric `b`.
pub(super) fn at<T: std::ops::Mul<f32, Output = T> + std::ops::Add<Output = T> + Copy>(v: [T; 3], b: [f32; 3]) -> T {
    v[0] * b[0] + v[1] * b[1] + v[2] * b[2]
}

/// The input surface of model number `index` as facets, with their corner normals under
/// `shading`.
pub(super) fn facets(model: &LstModel, index: u32, shading: Shading) -> Vec<Facet> {
    let faces = surface_faces(model);
    let normals = corner_normals(&faces, &corner_fans(&faces, shading));
    faces
        .iter()
        .zip(normals)
        .map(|(f, normals)| {
            let p = f.corners;
            Facet { model: index, triangle: f.triangle, ids: f.ids, shown: p, sampled: p, normals }
        })
        .collect()
}

/// Per surface vertex, the area-weighted mean normal of the facets around it (creases
/// and shading aside), so faces that share an edge move it the same way.
pub(super) fn vertex_normals(model: &LstModel, facets: &[Facet]) -> Vec<Vec3> {
    let mut normals = vec![Vec3::ZERO; model.surface.vertices.len()];
    for f in facets {
        let s = f.shown;
        let weighted = (s[1] - s[0]).cross(s[2] - s[0]);
        f.ids.iter().for_each(|&v| normals[v as usize] += weighted);
    }
    normals.into_iter().map(|n| n.normalize_or_zero()).collect()
}

/// How much of the displacement a surface point takes: 0 on a crease (an edge whose
/// triangles' normals differ by more than [`DEFAULT_CREASE`]), rising linearly to 1 at
/// `band` from the nearest crease edge. Vertex normals lean across a crease, so moving its
/// points along them would throw spikes out of it; tapered, both sides meet on the crease.
pub(super) struct Taper {
    band: f32,
    /// Per facet, the crease edges within `band` of it.
    near: Vec<Vec<[Vec3; 2]>>,
}

impl Taper {
    pub(super) fn new(model: &LstModel, facets: &[Facet], band: f32) -> Taper {
        let limit = DEFAULT_CREASE.to_radians().cos();
        let mut edges: Vec<((u32, u32), usize)> = facets
            .iter()
            .enumerate()
            .flat_map(|(i, f)| {
                (0..3)
                    .map(move |k| (f.ids[k].min(f.ids[(k + 1) % 3]), f.ids[k].max(f.ids[(k + 1) % 3])))
                    .map(move |e| (e, i))
            })
            .collect();
        edges.sort_unstable();
        let creases: Vec<[Vec3; 2]> = edges
            .chunk_by(|a, b| a.0 == b.0)
            .filter(|run| run.len() != 2 || facets[run[0].1].normal().dot(facets[run[1].1].normal()) < limit)
            .map(|run| [run[0].0.0, run[0].0.1].map(|v| model.surface.vertices[v as usize]))
            .collect();
        let near = facets
            .par_iter()
            .map(|f| {
                let (lo, hi) = (
                    f.shown[0].min(f.shown[1]).min(f.shown[2]) - band,
                    f.shown[0].max(f.shown[1]).max(f.shown[2]) + band,
                );
                creases
                    .iter()
                    .copied()
                    .filter(|[a, b]| a.min(*b).cmple(hi).all() && a.max(*b).cmpge(lo).all())
                    .collect()
            })
            .collect();
        Taper { band: band.max(1e-9), near }
    }

    /// The share of the displacement at `point` of facet `facet`.
    pub(super) fn at(&self, facet: usize, point: Vec3) -> f32 {
        let nearest = self.near[facet]
            .iter()
            .map(|[a, b]| point.distance(crate::mesh::closest_on_segment(point, *a, *b)))
            .fold(f32::INFINITY, f32::min);
        (nearest / self.band).min(1.0)
    }
}

/// How far displacement moves `point` (on facet `facet`) along its normal: `scale x (d -
/// MIDLEVEL)`, `d` sampled from `textures` there, times the crease taper.
pub(super) fn relief_at(
    model: &LstModel,
    (textures, scale): (&Textures, f32),
    taper: &Taper,
    facet: usize,
    point: Vec3,
) -> f32 {
    let value = shade_point(model, textures, point).map_or(MIDLEVEL, |c| c[0]);
    scale * (value - MIDLEVEL) * taper.at(facet, point)
}

/// Each facet split into `level`² triangles whose corners move along the surface's vertex
/// normals (blended) by `scale x (d - MIDLEVEL)` times the taper, `d` sampled at the
/// corner's point of the surface; every new triangle is lit by its own normal.
fn displaced(
    model: &LstModel,
    facets: &[Facet],
    (vertex_normals, taper): (&[Vec3], &Taper),
    textures: &Textures,
    scale: f32,
    level: usize,
) -> Vec<Facet> {
    let row = |j: usize| (0..j).map(|r| level + 1 - r).sum::<usize>();
    facets
        .par_iter()
        .enumerate()
        .flat_map_iter(|(n, f)| {
            let mut corners = Vec::with_capacity((level + 1) * (level + 2) / 2);
            for j in 0..=level {
                for i in 0..=level - j {
                    let (s, t) = (i as f32 / level as f32, j as f32 / level as f32);
                    let b = [1.0 - s - t, s, t];
                    let (sampled, on_face) = (at(f.sampled, b), at(f.shown, b));
                    let normal = at(f.ids.map(|v| vertex_normals[v as usize]), b).normalize_or(f.normal());
                    let moved = relief_at(model, (textures, scale), taper, n, on_face);
                    corners.push((sampled, on_face + normal * moved));
                }
            }
            let id = move |i: usize, j: usize| row(j) + i;
            let mut out = Vec::with_capacity(level * level);
            for j in 0..level {
                for i in 0..level - j {
                    out.push([id(i, j), id(i + 1, j), id(i, j + 1)]);
                    if i + j + 1 < level {
                        out.push([id(i + 1, j), id(i + 1, j + 1), id(i, j + 1)]);
                    }
                }
            }
            let (model, triangle, ids) = (f.model, f.triangle, f.ids);
            out.into_iter().map(move |k| {
                let shown = k.map(|c| corners[c].1);
                let mut facet =
                    Facet { model, triangle, ids, shown, sampled: k.map(|c| corners[c].0), normals: [Vec3::ZERO; 3] };
                facet.normals = [facet.normal(); 3];
                facet
            })
        })
        .collect()
}

/// The nearest front-facing facet at each pixel, among the points `keep` accepts.
pub(super) fn rasterize(facets: &[Facet], frame: &Frame, keep: impl Fn(Vec3) -> bool) -> Vec<Option<Hit>> {
    let mut hits: Vec<Option<Hit>> = vec![None; frame.size * frame.size];
    draw_facets(&mut hits, facets, frame, keep);
    hits
}

/// Draws the facets facing the camera into `hits` where they are nearer.
fn draw_facets(hits: &mut [Option<Hit>], facets: &[Facet], frame: &Frame, keep: impl Fn(Vec3) -> bool) {
    for f in facets {
        let flat = f.normal();
        if flat.dot(frame.forward) >= 0.0 {
            continue;
        }
        draw_triangle(hits, frame.size, f.shown.map(|p| frame.to_pixel(p)), |b| {
            let shown = at(f.shown, b);
            keep(shown).then(|| Hit {
                depth: frame.forward.dot(shown),
                model: f.model,
                triangle: f.triangle,
                point: at(f.sampled, b),
                normal: at(f.normals, b).normalize_or(flat),
            })
        });
    }
}

/// Writes the hits of a triangle (`s`: its corners in pixels; `hit_at`: the hit at
/// barycentric point, or none to leave the pixel) where they are nearer than what is there.
pub(super) fn draw_triangle(
    hits: &mut [Option<Hit>],
    size: usize,
    s: [Vec2; 3],
    hit_at: impl Fn([f32; 3]) -> Option<Hit>,
) {
    let area = (s[1] - s[0]).perp_dot(s[2] - s[0]);
    if !(area.is_finite() && area.abs() >= 1e-12) {
        return;
    }
    let lo = s[0].min(s[1]).min(s[2]).floor().max(Vec2::ZERO);
    let hi = (s[0].max(s[1]).max(s[2]).ceil() + 1.0).min(Vec2::splat(size as f32));
    for y in lo.y as usize..hi.y as usize {
        // Only the pixels of the row near the triangle: a sliver across the picture costs
        // its own pixels, not its box's.
        let Some((from, to)) = row_span(s, area, y as f32 + 0.5) else { continue };
        let from = from.floor().max(lo.x) as usize;
        let to = to.ceil().min(hi.x).max(0.0) as usize;
        for x in from..to {
            let q = Vec2::new(x as f32 + 0.5, y as f32 + 0.5);
            let b1 = (q - s[0]).perp_dot(s[2] - s[0]) / area;
            let b2 = (s[1] - s[0]).perp_dot(q - s[0]) / area;
            let b = [1.0 - b1 - b2, b1, b2];
            if b.iter().any(|w| *w < -1e-4) {
                continue;
            }
            let Some(hit) = hit_at(b) else { continue };
            let slot = &mut hits[y * size + x];
            if slot.is_none_or(|old| hit.depth < old.depth) {
                *slot = Some(hit);
            }
        }
    }
}

/// The pixel centres `x` of the row at height `y` (pixel centre) where the barycentric
/// weights of triangle `s` (signed `area`) may pass the inclusion test, as an interval
/// `[from, to]` of x taken with a margin (the test itself decides each pixel); `None` when
/// the row misses the triangle.
fn row_span(s: [Vec2; 3], area: f32, y: f32) -> Option<(f32, f32)> {
    // Each weight is linear along the row, w(x) = w(c) + slope (x - c), taken about the
    // triangle's middle so the rounding stays that of the per-pixel test.
    let c = (s[0].x + s[1].x + s[2].x) / 3.0;
    let w1 = (Vec2::new(c, y) - s[0]).perp_dot(s[2] - s[0]) / area;
    let w2 = (s[1] - s[0]).perp_dot(Vec2::new(c, y) - s[0]) / area;
    let slopes = [-(s[2].y - s[1].y) / area, (s[2].y - s[0].y) / area, -(s[1].y - s[0].y) / area];
    const MARGIN: f32 = 1e-2;
    let (mut from, mut to) = (f32::NEG_INFINITY, f32::INFINITY);
    for (w, slope) in [1.0 - w1 - w2, w1, w2].into_iter().zip(slopes) {
        let edge = c + (-MARGIN - w) / slope;
        if slope > 0.0 {
            from = from.max(edge);
        } else if slope < 0.0 {
            to = to.min(edge);
        } else if w < -MARGIN {
            return None;
        }
    }
    (from <= to).then_some((from - 2.0, to + 2.0))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::fill::model::{MaskRef, Source};

    /// Looking straight down or up turns the picture no more than looking almost so.
    #[test]
    fn the_camera_turns_smoothly_to_straight_up_and_down() {
        for yaw in [0.0, 30.0, 135.0, -100.0] {
            for (near, at) in [(89.9, 90.0), (-89.9, -90.0)] {
                let (a, b) = (camera(yaw, near), camera(yaw, at));
                for (u, v) in [(a.0, b.0), (a.1, b.1), (a.2, b.2)] {
                    assert!(u.dot(v) > 0.999, "yaw {yaw}, pitch {near} against {at}: {u} and {v}");
                }
            }
        }
    }
    use crate::fill::paste::Patch;
    use crate::volume::{Channel, Volume};

    /// The drawn fruit, tetrahedralized, with one grey patch over every tet: only the
    /// lighting varies across the picture.
    fn grey_fruit() -> (LstModel, Textures) {
        let fruit = crate::mesh::shapes::named("fruit").unwrap();
        let mesh = crate::fill::mesher::tetrahedralize(&fruit, 3000).unwrap();
        let vertices: Vec<u32> = (0..mesh.vertices.len() as u32).collect();
        let patch = Patch { source: 0, coords: vec![Vec3::splat(0.5); vertices.len()], vertices };
        let source = Source { exemplar: "grey".into(), volume: "grey.exr".into(), mask: MaskRef::File("m.exr".into()) };
        let tet_patches = vec![vec![0]; mesh.tets.len()];
        let model = LstModel::new(mesh, fruit, vec![source], vec![patch], tet_patches);
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

    /// Drawing a row only across the triangle's span sets exactly the pixels the test of
    /// every pixel of its box sets: slivers across the picture, tiny, huge and far-off
    /// triangles alike.
    #[test]
    fn row_spans_draw_the_pixels_the_whole_box_draws() {
        use rand::{RngExt, SeedableRng};
        let mut rng = rand_pcg::Pcg64::seed_from_u64(5);
        let size = 48;
        let hit = |b: [f32; 3]| Some(Hit { depth: b[0], model: 0, triangle: 0, point: Vec3::ZERO, normal: Vec3::Z });
        for case in 0..3000 {
            let reach = [2.0, 60.0, 4000.0][case % 3];
            let s: [Vec2; 3] = std::array::from_fn(|_| {
                Vec2::new(rng.random_range(-reach..reach), rng.random_range(-reach..reach)) + 24.0
            });
            let mut spans = vec![None; size * size];
            draw_triangle(&mut spans, size, s, hit);
            let area = (s[1] - s[0]).perp_dot(s[2] - s[0]);
            let mut boxed: Vec<Option<Hit>> = vec![None; size * size];
            if area.is_finite() && area.abs() >= 1e-12 {
                for (i, slot) in boxed.iter_mut().enumerate() {
                    let q = Vec2::new((i % size) as f32 + 0.5, (i / size) as f32 + 0.5);
                    let b1 = (q - s[0]).perp_dot(s[2] - s[0]) / area;
                    let b2 = (s[1] - s[0]).perp_dot(q - s[0]) / area;
                    let b = [1.0 - b1 - b2, b1, b2];
                    if b.iter().all(|w| *w >= -1e-4) {
                        *slot = hit(b);
                    }
                }
            }
            let set = |v: &[Option<Hit>]| v.iter().map(Option::is_some).collect::<Vec<_>>();
            assert_eq!(set(&spans), set(&boxed), "triangle {s:?}");
        }
    }

    #[test]
    fn displacement_moves_a_flat_face_along_its_normal_by_the_channel() {
        // the unit cube, one patch whose texture coordinates are the positions; the
        // displacement channel is x itself (texel centres of an 8-voxel ramp)
        let mesh = crate::fill::tets::cube_lattice([4, 4, 4], 0.25);
        let vertices: Vec<u32> = (0..mesh.vertices.len() as u32).collect();
        let patch = Patch { source: 0, coords: mesh.vertices.clone(), vertices };
        let source = Source { exemplar: "ramp".into(), volume: "ramp.exr".into(), mask: MaskRef::File("m.exr".into()) };
        let tet_patches = vec![vec![0]; mesh.tets.len()];
        let surface = LstModel::boundary_of(&mesh).unwrap();
        let model = LstModel::new(mesh, surface, vec![source], vec![patch], tet_patches);
        let ramp = Volume::from_fn([8, 2, 2], vec![Channel::Displacement], |x, _, _, o| o[0] = (x as f32 + 0.5) / 8.0)
            .unwrap();
        let full = Volume::from_fn([2; 3], vec![Channel::A], |_, _, _, o| o.fill(1.0)).unwrap();
        let textures = Textures::channel(&[ramp], &[full], &[Channel::Displacement]).unwrap();
        let plain = facets(&model, 0, Shading::Smooth { crease: DEFAULT_CREASE });
        let normals = vertex_normals(&model, &plain);
        let taper = Taper::new(&model, &plain, 0.2);
        let moved = displaced(&model, &plain, (&normals, &taper), &textures, 0.2, 4);
        assert_eq!(moved.len(), plain.len() * 16);
        let mut checked = 0;
        for f in moved.iter().filter(|f| f.sampled.iter().all(|p| p.y > 0.99)) {
            for (shown, sampled) in f.shown.iter().zip(f.sampled) {
                // away from the cube's edges, whose vertex normals lean over them
                if (0.25..0.75).contains(&sampled.x) && (0.25..0.75).contains(&sampled.z) {
                    let want = Vec3::new(sampled.x, 1.0 + 0.2 * (sampled.x - MIDLEVEL), sampled.z);
                    assert!((*shown - want).length() < 2e-3, "{shown} against {want}");
                    checked += 1;
                }
            }
            let inner = f.sampled.iter().all(|p| (0.2..0.8).contains(&p.x) && (0.2..0.8).contains(&p.z));
            assert!(!inner || f.normal().y > 0.9, "the top stays facing up, tilted by the ramp: {}", f.normal());
        }
        assert!(checked > 100, "{checked} corners on the top face");
        // the cube's edges are creases: their points stay where they are, no spikes
        let on_edge = |p: Vec3| p.to_array().iter().filter(|c| **c < 1e-4 || **c > 1.0 - 1e-4).count() >= 2;
        let edges: Vec<(Vec3, Vec3)> =
            moved.iter().flat_map(|f| f.shown.into_iter().zip(f.sampled)).filter(|(_, p)| on_edge(*p)).collect();
        assert!(edges.len() > 100 && edges.iter().all(|(a, b)| a.distance(*b) < 1e-5), "{} edge corners", edges.len());
        // no displacement channel, no move: scale 0 leaves every corner on the face
        let still = displaced(&model, &plain, (&normals, &taper), &textures, 0.0, 2);
        assert!(still.iter().all(|f| f.shown.iter().zip(f.sampled).all(|(a, b)| (*a - b).length() < 2e-3)));
    }

    /// The picture's outline is the input mesh's, drawn by the same camera, pixel for
    /// pixel; the tets' boundary would give another.
    #[test]
    fn the_view_shows_the_input_surface_not_the_tets_boundary() {
        let (model, textures) = grey_fruit();
        let picture = surface(&model, &textures, 35.0, 25.0, 256);
        let shown: Vec<bool> = picture.data.chunks_exact(3).map(|p| p != BACKGROUND).collect();
        let outline = |surface: Mesh| {
            let alone = LstModel::new(model.mesh.clone(), surface, vec![], vec![], vec![]);
            let frame = Frame::around(model.surface.vertices.iter().copied(), (35.0, 25.0), 256);
            let hits = rasterize(&facets(&alone, 0, Shading::Flat), &frame, |_| true);
            hits.iter().zip(&shown).filter(|(h, s)| h.is_some() != **s).count()
        };
        assert_eq!(outline(model.surface.clone()), 0);
        assert!(outline(LstModel::boundary_of(&model.mesh).unwrap()) > 50);
    }

    /// A point seen at a pixel is inside by the ray crossings exactly when the surface holds
    /// it (points within a hair of the surface aside).
    #[test]
    fn the_rays_of_a_picture_tell_inside_from_outside() {
        let fruit = crate::mesh::shapes::named("fruit").unwrap();
        let frame = Frame::around(fruit.vertices.iter().copied(), (35.0, 25.0), 64);
        let rays = Rays::new(&fruit, &frame);
        let on_surface = |q: Vec3| {
            let corners = fruit.triangles.iter().map(|t| t.map(|v| fruit.vertices[v as usize]));
            corners.map(|c| q.distance(crate::mesh::closest_on_triangle(q, c))).fold(f32::INFINITY, f32::min) < 1e-4
        };
        let (mut inside, mut checked) = (0, 0);
        for y in (0..64).step_by(3) {
            for x in (0..64).step_by(3) {
                let mx = (x as f32 + 0.5 - 32.0) / frame.scale + frame.centre.x;
                let my = (32.0 - (y as f32 + 0.5)) / frame.scale + frame.centre.y;
                for k in -20..=20 {
                    let p = frame.right * mx + frame.up * my + frame.forward * (k as f32 * 0.05);
                    if on_surface(p) {
                        continue;
                    }
                    let want = fruit.contains(p);
                    assert_eq!(rays.inside(x, y, p), want, "pixel {x}, {y}, depth {k}");
                    (inside, checked) = (inside + usize::from(want), checked + 1);
                }
            }
        }
        assert!(inside > 1000 && inside < checked, "{inside} of {checked} inside");
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
