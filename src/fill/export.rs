//! A filled model's surface as a textured mesh to take out of solidtex (`solidtex export`
//! writes it as glTF): the model's input surface split until no edge is longer than a set
//! length, each vertex coloured as `view` colours that point (before lighting), with
//! `view`'s smooth normals (split at creases); optionally displaced as `view
//! --displacement` displaces it, and optionally with a texture atlas instead of vertex
//! colours.
//!
//! ```text
//!  input surface --split (shared edges split alike)--> pieces --vertices merged by where
//!  they lie (corner fan, edge and place on it, or inside a face)--> vertices
//!  vertex --point on the surface--> locate in the tets --> composited colour
//!         --(displacement) moved along the crease-tapered vertex normal
//!  (atlas) each triangle gets a square cell: its texels coloured at the surface points
//!          they map to, the half beyond the triangle from its nearest edge
//! ```
//!
//! Vertices are merged by an exact key, not by comparing floats: a corner by the fan of
//! corners its normal is shared over ([`super::view`]), a point on an edge by the two end
//! fans and its dyadic place between them, so a smooth edge joins its two faces and a
//! crease keeps two vertices with their own normals.

use super::model::LstModel;
use super::render::{Textures, shade_point};
use super::view::{self, Face, Fans, Shading, Taper, at as blend};
use crate::error::{Error, Result};
use crate::mesh::split::{self, Bary};
use crate::progress::Progress;
use crate::render::{Rgb8, to_u8};
use glam::Vec3;
use rayon::prelude::*;
use std::collections::HashMap;

/// The most triangles an exported surface may have (about 60 bytes each in the file).
pub const MAX_TRIANGLES: u64 = 8_000_000;

/// The smallest atlas cell side in texels (a triangle needs a texel of margin each side).
pub const MIN_CELL: usize = 4;

/// The colour of a point no tet holds (none on a filled model's surface in practice).
const UNLOCATED: [f32; 3] = [0.5, 0.5, 0.5];

/// An edge longer than this many times the target length is split (Botsch & Kobbelt's
/// remeshing rule, 2004): the halves of a split edge are at least 2/3 of the target, so the
/// edges come out about the target long rather than all shorter than it.
pub const SPLIT_ABOVE: f32 = 4.0 / 3.0;

/// How the surface is taken out.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Options {
    /// The target edge length (model units): edges longer than [`SPLIT_ABOVE`] times it
    /// are halved until none is; 0: the input surface's triangles as they are.
    pub edge: f32,
    /// Edges sharper than this many degrees keep two normals (as `view --crease`).
    pub crease: f32,
    /// A texture atlas of this side in texels instead of vertex colours.
    pub atlas: Option<usize>,
}

/// Displacement as `view --displacement` does it: the surface moved along its normal by
/// `scale x (d - 0.5)`, `d` sampled from `textures` (the exemplars' Displacement channel).
#[derive(Clone, Copy)]
pub struct Relief<'a> {
    /// Samplers of the displacement channel.
    pub textures: &'a Textures,
    /// Model units per unit of displacement.
    pub scale: f32,
}

/// A coloured triangle mesh.
#[derive(Debug, Clone, PartialEq)]
pub struct Exported {
    /// Vertex positions (displaced, with a relief).
    pub positions: Vec<Vec3>,
    /// Unit vertex normals.
    pub normals: Vec<Vec3>,
    /// Vertex colours as the exemplars store them (sRGB-encoded, 0–1).
    pub colours: Vec<[f32; 3]>,
    /// Triangles, outward facing counter-clockwise.
    pub triangles: Vec<[u32; 3]>,
    /// The texture atlas, when asked for: a UV per vertex and the picture.
    pub atlas: Option<Atlas>,
}

/// A texture atlas: one square cell per triangle.
#[derive(Debug, Clone, PartialEq)]
pub struct Atlas {
    /// Per vertex, its place in the picture (0–1, v down from the top row).
    pub uvs: Vec<[f32; 2]>,
    /// The texture (sRGB).
    pub picture: Rgb8,
}

/// How many triangles splitting `model`'s surface to edges about `edge` long gives, or
/// `None` when more than `most` (counted without keeping them, stopping past `most`).
pub fn triangle_count(model: &LstModel, edge: f32, most: u64) -> Option<u64> {
    let surface = &model.surface;
    let total = std::sync::atomic::AtomicU64::new(0);
    let fits = surface.triangles.par_iter().all(|t| {
        let left = most.saturating_sub(total.load(std::sync::atomic::Ordering::Relaxed));
        let corners = t.map(|v| surface.vertices[v as usize]);
        split::count(corners, edge * SPLIT_ABOVE, left)
            .is_some_and(|n| total.fetch_add(n, std::sync::atomic::Ordering::Relaxed) + n <= most)
    });
    fits.then(|| total.into_inner())
}

/// Where a split surface's vertex lies, exactly: a corner (by the fan of corners sharing
/// its normal), a point on an edge (the end fans, lower first, and the share of the higher
/// in 2^-24), or a point inside a face (the face and two of its coordinates).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
enum Key {
    Corner(u32),
    Edge(u32, u32, u32),
    Inside(u32, u32, u32),
}

/// A barycentric coordinate in 2^-24: exact for the dyadic coordinates of the split.
fn fixed(w: f32) -> u32 {
    (w * (1u32 << 24) as f32).round() as u32
}

fn key(fans: &Fans, face: u32, b: Bary) -> Key {
    let fan = |k: usize| fans.root(3 * face + k as u32);
    let zeros = b.iter().filter(|w| **w == 0.0).count();
    match zeros {
        1 => {
            let z = b.iter().position(|w| *w == 0.0).unwrap_or(0);
            let (i, j) = ((z + 1) % 3, (z + 2) % 3);
            let (fi, fj) = (fan(i), fan(j));
            if fi < fj { Key::Edge(fi, fj, fixed(b[j])) } else { Key::Edge(fj, fi, fixed(b[i])) }
        }
        2 | 3 => Key::Corner(fan((0..3).find(|&k| b[k] != 0.0).unwrap_or(0))),
        _ => Key::Inside(face, fixed(b[0]), fixed(b[1])),
    }
}

/// The split surface: each vertex as (face, coordinates in it), and the triangles.
struct Split {
    vertices: Vec<(u32, Bary)>,
    triangles: Vec<[u32; 3]>,
}

fn split_faces(faces: &[Face], fans: &Fans, edge: f32) -> Split {
    let pieces: Vec<Vec<[Bary; 3]>> = faces.par_iter().map(|f| split::split(f.corners, edge)).collect();
    let mut index: HashMap<Key, u32> = HashMap::new();
    let mut vertices = Vec::new();
    let mut triangles = Vec::with_capacity(pieces.iter().map(Vec::len).sum());
    for (f, list) in pieces.iter().enumerate() {
        for piece in list {
            triangles.push(piece.map(|b| {
                *index.entry(key(fans, f as u32, b)).or_insert_with(|| {
                    vertices.push((f as u32, b));
                    (vertices.len() - 1) as u32
                })
            }));
        }
    }
    Split { vertices, triangles }
}

/// `model`'s surface split to `options.edge`, coloured by `textures` (as `view` colours
/// it), displaced by `relief`, with an atlas if asked. Tells `progress` and stops when it
/// is cancelled.
pub fn export(
    model: &LstModel,
    textures: &Textures,
    relief: Option<Relief>,
    options: Options,
    progress: &dyn Progress,
) -> Result<Exported> {
    if triangle_count(model, options.edge, MAX_TRIANGLES).is_none() {
        return Err(Error::invalid(format!(
            "splitting the surface to edges of {} would give more than {MAX_TRIANGLES} triangles",
            options.edge
        )));
    }
    // made once before the threads below locate points
    _ = model.locator();
    let shading = Shading::Smooth { crease: options.crease };
    let faces = view::surface_faces(model);
    let fans = view::corner_fans(&faces, shading);
    let corner_normals = view::corner_normals(&faces, &fans);
    progress.update("splitting", 0.0);
    let Split { vertices, triangles } = split_faces(&faces, &fans, options.edge * SPLIT_ABOVE);
    let points: Vec<Vec3> = vertices.iter().map(|&(f, b)| blend(faces[f as usize].corners, b)).collect();
    let colours = in_chunks(&points, progress, "colouring", |p| colour_at(model, textures, *p))?;
    let (positions, normals) = match relief {
        None => {
            let normals = vertices.iter().map(|&(f, b)| blend(corner_normals[f as usize], b)).collect();
            (points.clone(), unit(normals, &vertices, &faces))
        }
        Some(relief) => {
            let moved = displaced(model, (&faces, &vertices, &points), relief, options, progress)?;
            let normals = crate::surface::retile::vertex_normals(&moved, &triangles);
            (moved, unit(normals, &vertices, &faces))
        }
    };
    let mut out = Exported { positions, normals, colours, triangles, atlas: None };
    if let Some(side) = options.atlas {
        out = with_atlas(model, textures, out, &points, side, progress)?;
    }
    Ok(out)
}

/// The colour `view` shows at a surface point before lighting, within 0–1.
fn colour_at(model: &LstModel, textures: &Textures, point: Vec3) -> [f32; 3] {
    shade_point(model, textures, point).map_or(UNLOCATED, |c| [c[0], c[1], c[2]].map(|v| v.clamp(0.0, 1.0)))
}

/// `f` of every item, in parallel chunks, telling `progress` after each.
fn in_chunks<T: Sync, U: Send>(
    items: &[T],
    progress: &dyn Progress,
    stage: &str,
    f: impl Fn(&T) -> U + Sync,
) -> Result<Vec<U>> {
    const CHUNK: usize = 1 << 14;
    let mut out = Vec::with_capacity(items.len());
    for (k, chunk) in items.chunks(CHUNK).enumerate() {
        out.par_extend(chunk.par_iter().map(&f));
        progress.update(stage, ((k + 1) * CHUNK).min(items.len()) as f32 / items.len().max(1) as f32);
        if progress.cancelled() {
            return Err(Error::Cancelled);
        }
    }
    Ok(out)
}

/// Unit normals; a zero one takes its face's normal.
fn unit(normals: Vec<Vec3>, vertices: &[(u32, Bary)], faces: &[Face]) -> Vec<Vec3> {
    (normals.into_iter().zip(vertices))
        .map(|(n, &(f, _))| n.try_normalize().unwrap_or(faces[f as usize].normal).normalize_or(Vec3::Y))
        .collect()
}

/// The split surface's points moved as `view --displacement` moves them: along the
/// surface's vertex normal (creases aside) by the relief, tapered to zero at creases.
fn displaced(
    model: &LstModel,
    (faces, vertices, points): (&[Face], &[(u32, Bary)], &[Vec3]),
    relief: Relief,
    options: Options,
    progress: &dyn Progress,
) -> Result<Vec<Vec3>> {
    let facets = view::facets(model, 0, Shading::Smooth { crease: options.crease });
    let vertex_normals = view::vertex_normals(model, &facets);
    let taper = Taper::new(model, &facets, 2.0 * relief.scale.abs() + options.edge);
    let indices: Vec<usize> = (0..points.len()).collect();
    in_chunks(&indices, progress, "displacing", |&i| {
        let (f, b) = vertices[i];
        let face = &faces[f as usize];
        let normal = blend(face.ids.map(|v| vertex_normals[v as usize]), b).normalize_or(face.normal);
        points[i] + normal * view::relief_at(model, (relief.textures, relief.scale), &taper, f as usize, points[i])
    })
}

/// Where a triangle's corners lie in its atlas cell, in texels from the cell's corner: a
/// texel of margin, the right angle at the cell's top left.
fn cell_corners(cell: usize) -> [[f32; 2]; 3] {
    let far = cell as f32 - 1.0;
    [[1.0, 1.0], [far, 1.0], [1.0, far]]
}

/// `exported` with a texture atlas of `side`² texels: every triangle its own cell and three
/// vertices of its own (a UV seam runs along every edge); the colours stay for reference.
fn with_atlas(
    model: &LstModel,
    textures: &Textures,
    exported: Exported,
    points: &[Vec3],
    side: usize,
    progress: &dyn Progress,
) -> Result<Exported> {
    let count = exported.triangles.len();
    let per_row = (count as f64).sqrt().ceil().max(1.0) as usize;
    let cell = side / per_row;
    if cell < MIN_CELL {
        return Err(Error::invalid(format!(
            "an atlas of {side}x{side} texels gives each of the surface's {count} triangles {cell}x{cell} texels (at \
             least {MIN_CELL}x{MIN_CELL}): make it at least {} texels or split the surface less",
            per_row * MIN_CELL
        )));
    }
    let corners = cell_corners(cell);
    let cells = in_chunks(&exported.triangles, progress, "atlas", |t| {
        let samples = t.map(|v| points[v as usize]);
        let mut texels = Vec::with_capacity(cell * cell);
        for y in 0..cell {
            for x in 0..cell {
                let b = cell_bary(corners, x as f32 + 0.5, y as f32 + 0.5);
                texels.push(colour_at(model, textures, blend(samples, b)).map(to_u8));
            }
        }
        texels
    })?;
    let mut picture = Rgb8::new(side, side, UNLOCATED.map(to_u8));
    let mut out = Exported {
        positions: Vec::with_capacity(3 * count),
        normals: Vec::with_capacity(3 * count),
        colours: Vec::with_capacity(3 * count),
        triangles: Vec::with_capacity(count),
        atlas: None,
    };
    let mut uvs = Vec::with_capacity(3 * count);
    for (i, (t, texels)) in exported.triangles.iter().zip(cells).enumerate() {
        let (x0, y0) = ((i % per_row) * cell, (i / per_row) * cell);
        for (k, &v) in t.iter().enumerate() {
            out.positions.push(exported.positions[v as usize]);
            out.normals.push(exported.normals[v as usize]);
            out.colours.push(exported.colours[v as usize]);
            let [u, w] = corners[k];
            uvs.push([(x0 as f32 + u) / side as f32, (y0 as f32 + w) / side as f32]);
        }
        out.triangles.push([0, 1, 2].map(|k| (3 * i + k) as u32));
        for (j, c) in texels.into_iter().enumerate() {
            picture.put(x0 + j % cell, y0 + j / cell, c);
        }
    }
    out.atlas = Some(Atlas { uvs, picture });
    Ok(out)
}

/// The barycentric coordinates of texel point (x, y) of a cell in the triangle at
/// `corners`, moved onto the triangle when outside it (so a texel beyond an edge takes the
/// colour at the edge, and filtering across the edge reads no other triangle's colours).
fn cell_bary(corners: [[f32; 2]; 3], x: f32, y: f32) -> Bary {
    let span = corners[1][0] - corners[0][0];
    let (s, t) = ((x - corners[0][0]) / span, (y - corners[0][1]) / span);
    let b = [1.0 - s - t, s, t].map(|w| w.max(0.0));
    let sum = b[0] + b[1] + b[2];
    b.map(|w| w / sum)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_texel_beyond_the_triangle_takes_the_nearest_edge() {
        let corners = cell_corners(8);
        let inside = cell_bary(corners, 2.5, 2.5);
        assert!(inside.iter().all(|w| *w > 0.0) && (inside.iter().sum::<f32>() - 1.0).abs() < 1e-6);
        // the texel at the cell's far corner lies beyond the long edge: on it
        let beyond = cell_bary(corners, 7.5, 7.5);
        assert_eq!(beyond[0], 0.0);
        assert!((beyond[1] - 0.5).abs() < 1e-6 && (beyond[2] - 0.5).abs() < 1e-6);
    }
}
