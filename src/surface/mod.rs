//! Texture synthesis on surfaces (Turk 2001; Wei and Levoy on meshes): a 2D exemplar
//! grown directly over a mesh's surface, so a filled model gets a real skin.
//!
//! ```text
//!  mesh --re-tile--> even points (N)        direction field (up)       exemplar pyramid
//!        (retile)    + normals, edges  -->  (directions: a guide,  --> (matching: coarse
//!                                            smoothed over edges)       to fine, per point
//!                                                                       an exemplar pixel)
//!                                                        --> per-vertex colours (Skin)
//! ```
//!
//! One exemplar pixel covers `texel` model units on the surface (by default two spacings of
//! the points, [`DEFAULT_TEXEL`]). Everything is deterministic for a seed, on any thread
//! count.

pub mod directions;
pub mod matching;
pub mod retile;

pub use directions::Guide;

use crate::error::{Error, Result};
use crate::fill::mesher::closest::Surface;
use crate::mesh::Mesh;
use crate::progress::Progress;
use crate::quality::histogram;
use crate::volume::{Channel, Image2d};
use glam::Vec3;
use std::ops::RangeInclusive;

/// The point counts `synthesize` takes (at most about 1.2 GB of neighbour lists when every
/// point is matched: 200,000 points took 460 MB).
pub const POINTS: RangeInclusive<usize> = 100..=500_000;
/// Exemplar pixels are this many point spacings long unless told otherwise: four points
/// per pixel, so colours blended across the skin's triangles keep the photo's edges.
pub const DEFAULT_TEXEL: f32 = 2.0;
/// The smallest exemplar side.
pub const MIN_EXEMPLAR: usize = 16;

/// What to synthesize.
#[derive(Debug, Clone, PartialEq)]
pub struct Options {
    /// About how many points (vertices) the skin gets.
    pub points: usize,
    /// Seed of the random start.
    pub seed: u64,
    /// Model units one exemplar pixel covers; `None`: [`DEFAULT_TEXEL`] point spacings.
    pub texel: Option<f32>,
    /// Where the texture's "up" points.
    pub guide: Guide,
}

/// A synthesized surface texture: the re-tiled mesh and a colour per vertex.
#[derive(Debug, Clone)]
pub struct Skin {
    /// The re-tiled surface.
    pub mesh: Mesh,
    /// RGB per vertex, in [0, 1].
    pub colours: Vec<[f32; 3]>,
    /// The exemplar pixel each vertex shows.
    pub pixels: Vec<[i32; 2]>,
    /// Each vertex's texture "up" (unit, tangent).
    pub ups: Vec<Vec3>,
    /// The points' spacing: the edge of an equilateral tiling of the surface with as many points.
    pub spacing: f32,
    /// Model units per exemplar pixel.
    pub texel: f32,
    /// Levels of the point hierarchy.
    pub levels: usize,
}

/// Grows `exemplar` (RGB, or grey shown as grey) over the surface of `mesh`.
pub fn synthesize(mesh: &Mesh, exemplar: &Image2d, options: &Options, progress: &dyn Progress) -> Result<Skin> {
    check(exemplar, options)?;
    let rgb = rgb_of(exemplar)?;
    let tiled = retile::retile(&mesh.clone().oriented(), options.points, progress)?;
    let normals = retile::vertex_normals(&tiled.vertices, &tiled.triangles);
    let (offsets, neighbours) = neighbour_lists(&tiled);
    let spacing = retile::target_edge(retile::area(&tiled), tiled.vertices.len());
    let (lo, hi) = tiled.bounds();
    let ups =
        directions::field(&tiled.vertices, &normals, (&offsets, &neighbours), &options.guide, 0.02 * lo.distance(hi));
    let texel = options.texel.unwrap_or(DEFAULT_TEXEL * spacing);
    let points = matching::Points { positions: &tiled.vertices, normals: &normals, ups: &ups, spacing };
    let (pixels, levels) = matching::coordinates(&points, &rgb, texel, options.seed, progress)?;
    let colours = pixels
        .iter()
        .map(|&[x, y]| {
            let p = rgb.pixel(x as usize, y as usize);
            [p[0], p[1], p[2]]
        })
        .collect();
    Ok(Skin { mesh: tiled, colours, pixels, ups, spacing, texel, levels })
}

/// A skin showing less of its photo across the model than this share of the photo's shorter
/// side gets [`scale_note`]: the photo's features then look large on the model.
pub const SMALL_SHARE: f32 = 0.5;

/// How a skin was scaled, for [`scale_note`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Scale {
    /// The model's longest side, in model units.
    pub across: f32,
    /// Model units per exemplar pixel.
    pub texel: f32,
    /// Whether the texel was given (else [`DEFAULT_TEXEL`] point spacings).
    pub texel_given: bool,
    /// The points' spacing.
    pub spacing: f32,
    /// The points asked for.
    pub points: usize,
    /// The photo's shorter side, in pixels.
    pub photo_side: usize,
}

/// What to tell a designer whose model spans fewer exemplar pixels along its longest side
/// than [`SMALL_SHARE`] of the photo's shorter side: how much of the photo shows, and each
/// change that would show more of it (a smaller texel down to one point per pixel, more
/// points where the texel follows them, a smaller photo). `None` when enough shows.
pub fn scale_note(scale: &Scale) -> Option<String> {
    let pixels = scale.across / scale.texel;
    if pixels >= SMALL_SHARE * scale.photo_side as f32 {
        return None;
    }
    let mut ways = Vec::new();
    let per_point = scale.texel / scale.spacing;
    if per_point > 1.05 {
        let texel = four_digits(scale.spacing);
        ways.push(format!("--texel {texel} (one point per pixel) shows {per_point:.1} times as much"));
    }
    let more_points = scale.points < *POINTS.end();
    match (scale.texel_given, more_points) {
        (false, true) => ways.push(format!("more --points (up to {}) more still", POINTS.end())),
        (true, true) => ways.push("more --points and a smaller --texel show more at a point per pixel".to_string()),
        _ => {}
    }
    if scale.photo_side >= 2 * MIN_EXEMPLAR {
        ways.push("a photo shrunk so its features span fewer pixels".to_string());
    }
    let how = match ways.len() {
        0 => String::new(),
        _ => format!("; {}", ways.join(", or ")),
    };
    Some(format!(
        "the model is about {pixels:.0} exemplar pixels across, the photo {}: its features look large on the model{how}",
        scale.photo_side
    ))
}

/// A length with four significant digits at most, however small (a model in millimetres
/// or in kilometres): `0.0008123`, `1.235`, `1235`, `0.025`.
pub fn four_digits(value: f32) -> String {
    if value == 0.0 || !value.is_finite() {
        return format!("{value}");
    }
    let decimals = (3 - value.abs().log10().floor() as i32).clamp(0, 40) as usize;
    let text = format!("{value:.decimals$}");
    if text.contains('.') { text.trim_end_matches('0').trim_end_matches('.').to_string() } else { text }
}

/// Refuses an exemplar smaller than [`MIN_EXEMPLAR`] on a side.
pub fn check_exemplar(exemplar: &Image2d) -> Result<()> {
    if exemplar.width() < MIN_EXEMPLAR || exemplar.height() < MIN_EXEMPLAR {
        return Err(Error::invalid(format!(
            "the exemplar is {}x{}; surface synthesis needs at least {MIN_EXEMPLAR}x{MIN_EXEMPLAR} pixels",
            exemplar.width(),
            exemplar.height()
        )));
    }
    Ok(())
}

fn check(exemplar: &Image2d, options: &Options) -> Result<()> {
    check_exemplar(exemplar)?;
    if !POINTS.contains(&options.points) {
        return Err(Error::invalid(format!(
            "points = {} is out of range; allowed: {} to {}",
            options.points,
            POINTS.start(),
            POINTS.end()
        )));
    }
    if let Some(texel) = options.texel
        && !(texel.is_finite() && texel > 0.0)
    {
        return Err(Error::invalid(format!("texel = {texel} must be a length greater than 0")));
    }
    if let Guide::Along(d) = options.guide
        && !(d.is_finite() && d.length() > 1e-6)
    {
        return Err(Error::invalid(format!("direction = {d} must be a non-zero vector")));
    }
    Ok(())
}

/// The exemplar's R, G and B channels (a grey one repeated three times).
fn rgb_of(image: &Image2d) -> Result<Image2d> {
    let find = |c: Channel| image.channels().iter().position(|x| *x == c);
    let picks = match (find(Channel::R), find(Channel::G), find(Channel::B)) {
        (Some(r), Some(g), Some(b)) => [r, g, b],
        _ if image.channel_count() >= 1 => [0, 0, 0],
        _ => return Err(Error::invalid("the exemplar has no channels")),
    };
    let data = image.data().chunks_exact(image.channel_count()).flat_map(|p| picks.map(|k| p[k])).collect();
    Image2d::from_data(image.width(), image.height(), Channel::rgb(), data)
}

/// Each vertex's neighbours along edges: offsets and the list.
fn neighbour_lists(mesh: &Mesh) -> (Vec<usize>, Vec<u32>) {
    let mut pairs: Vec<(u32, u32)> =
        mesh.triangles.iter().flat_map(|&[a, b, c]| [(a, b), (b, a), (b, c), (c, b), (c, a), (a, c)]).collect();
    pairs.sort_unstable();
    pairs.dedup();
    let mut offsets = vec![0; mesh.vertices.len() + 1];
    for &(a, _) in &pairs {
        offsets[a as usize + 1] += 1;
    }
    for v in 0..mesh.vertices.len() {
        offsets[v + 1] += offsets[v];
    }
    (offsets, pairs.into_iter().map(|(_, b)| b).collect())
}

/// Per channel (R, G, B), the L1 distance between the 32-bin histograms of the skin's
/// vertex colours and the exemplar's pixels (0 = equal, 2 = disjoint).
pub fn histogram_distances(colours: &[[f32; 3]], exemplar: &Image2d) -> Result<[f64; 3]> {
    let rgb = rgb_of(exemplar)?;
    Ok([0, 1, 2].map(|c| {
        let mine = histogram(colours.iter().map(|p| &p[c]));
        let theirs = histogram(rgb.data().iter().skip(c).step_by(3));
        mine.iter().zip(&theirs).map(|(a, b)| (a - b).abs()).sum()
    }))
}

/// The colours of a skin lying in a plane z = const, resampled to an image of `pixel`
/// model units per pixel starting at `origin` (x right, y down the rows): each pixel centre
/// takes the barycentric blend of the corners of the triangle over it (black where none).
pub fn resampled_on_plane(skin: &Skin, origin: Vec3, pixel: f32, width: usize, height: usize) -> Result<Image2d> {
    let mut data = vec![0.0f32; width * height * 3];
    for &[a, b, c] in &skin.mesh.triangles {
        let corner = |v: u32| {
            let p = (skin.mesh.vertices[v as usize] - origin) / pixel;
            (glam::Vec2::new(p.x, p.y), skin.colours[v as usize])
        };
        let [(pa, ca), (pb, cb), (pc, cc)] = [corner(a), corner(b), corner(c)];
        let area = (pb - pa).perp_dot(pc - pa);
        if area.abs() < 1e-12 {
            continue;
        }
        let lo = pa.min(pb).min(pc).floor().max(glam::Vec2::ZERO);
        let hi = pa.max(pb).max(pc).ceil();
        for y in lo.y as usize..(hi.y as usize).min(height) {
            for x in lo.x as usize..(hi.x as usize).min(width) {
                let q = glam::Vec2::new(x as f32 + 0.5, y as f32 + 0.5);
                let wa = (pb - q).perp_dot(pc - q) / area;
                let wb = (pc - q).perp_dot(pa - q) / area;
                let wc = 1.0 - wa - wb;
                if wa < -1e-5 || wb < -1e-5 || wc < -1e-5 {
                    continue;
                }
                for k in 0..3 {
                    data[(y * width + x) * 3 + k] = wa * ca[k] + wb * cb[k] + wc * cc[k];
                }
            }
        }
    }
    Image2d::from_data(width, height, Channel::rgb(), data)
}

/// The yardstick of a surface texture: grown on a flat unit square with `points` points,
/// its colours resampled to an image of one exemplar pixel per pixel, the gradient and
/// autocorrelation-length ratios of that image against the exemplar
/// ([`crate::sharpness::compare`]), and the histogram distances of the vertex colours.
#[derive(Debug, Clone)]
pub struct Yardstick {
    /// The skin grown on the square.
    pub skin: Skin,
    /// The skin resampled to an image.
    pub image: Image2d,
    /// Sharpness and feature size against the exemplar.
    pub sharpness: crate::sharpness::AxisSharpness,
    /// Per channel histogram distance of the vertex colours.
    pub histogram: [f64; 3],
}

/// Grows `exemplar` on the unit square in the plane z = 0 and measures it (see [`Yardstick`]).
pub fn on_a_square(exemplar: &Image2d, points: usize, seed: u64, progress: &dyn Progress) -> Result<Yardstick> {
    let corners = vec![Vec3::ZERO, Vec3::X, Vec3::new(1.0, 1.0, 0.0), Vec3::Y];
    let square = Mesh::new(corners, vec![[0, 1, 2], [0, 2, 3]])?;
    let options = Options { points, seed, texel: None, guide: Guide::Along(Vec3::Y) };
    let skin = synthesize(&square, exemplar, &options, progress)?;
    yardstick(skin, exemplar)
}

/// [`Yardstick`] of a skin grown on the unit square.
pub fn yardstick(skin: Skin, exemplar: &Image2d) -> Result<Yardstick> {
    let side = ((1.0 / skin.texel).floor() as usize).clamp(3, 4096);
    let image = resampled_on_plane(&skin, Vec3::ZERO, skin.texel, side, side)?;
    let rgb = rgb_of(exemplar)?;
    let sharpness = crate::sharpness::compare(std::slice::from_ref(&image), &rgb, &[0, 1, 2])?;
    let histogram = histogram_distances(&skin.colours, exemplar)?;
    Ok(Yardstick { skin, image, sharpness, histogram })
}

/// Colours of a skin looked up at points near its surface.
pub struct SkinLookup<'a> {
    mesh: &'a Mesh,
    colours: &'a [[f32; 3]],
    surface: Surface,
}

impl<'a> SkinLookup<'a> {
    /// A lookup over `mesh` with one colour per vertex.
    pub fn new(mesh: &'a Mesh, colours: &'a [[f32; 3]]) -> SkinLookup<'a> {
        SkinLookup { mesh, colours, surface: Surface::new(mesh, f32::INFINITY) }
    }

    /// The distance from `p` to the skin and the skin's colour at the closest point (the
    /// barycentric blend of its triangle's corners).
    pub fn at(&self, p: Vec3) -> (f32, [f32; 3]) {
        let (t, q) = self.surface.closest_triangle(p);
        let [a, b, c] = self.mesh.triangles[t];
        let [pa, pb, pc] = [a, b, c].map(|v| self.mesh.vertices[v as usize]);
        let n = (pb - pa).cross(pc - pa);
        let whole = n.length_squared().max(f32::MIN_POSITIVE);
        let wa = ((pb - q).cross(pc - q)).dot(n) / whole;
        let wb = ((pc - q).cross(pa - q)).dot(n) / whole;
        let wc = 1.0 - wa - wb;
        let [ca, cb, cc] = [a, b, c].map(|v| self.colours[v as usize]);
        (p.distance(q), [0, 1, 2].map(|k| wa * ca[k] + wb * cb[k] + wc * cc[k]))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Lengths keep four significant digits at any scale, so advice never reads 0.0000.
    #[test]
    fn lengths_keep_four_digits() {
        assert_eq!(four_digits(0.000_812_34), "0.0008123");
        assert_eq!(four_digits(1.23456), "1.235");
        assert_eq!(four_digits(1234.5), "1234");
        assert_eq!(four_digits(3e-9), "0.000000003");
        assert_eq!(four_digits(0.025), "0.025");
    }

    #[test]
    fn a_model_showing_little_of_its_photo_is_told_how_to_show_more() {
        // 2 units across at 0.05 units a pixel (two spacings, the default): 40 pixels of 512
        let default =
            Scale { across: 2.0, texel: 0.05, texel_given: false, spacing: 0.025, points: 20_000, photo_side: 512 };
        let note = scale_note(&default).expect("a note");
        assert!(note.contains("about 40 exemplar pixels across, the photo 512"), "{note}");
        assert!(note.contains("--texel 0.025 (one point per pixel) shows 2.0 times as much"), "{note}");
        assert!(note.contains("more --points (up to 500000)") && note.contains("a photo shrunk"), "{note}");
        // a texel given: points alone change nothing, and at a point per pixel no smaller
        // texel is offered; at the most points none are offered; a 16-px photo is not shrunk
        let given = Scale { texel_given: true, ..default };
        let note = scale_note(&given).unwrap();
        assert!(!note.contains("more --points (up to") && note.contains("--texel 0.025 "), "{note}");
        let fine = Scale { texel: 0.01, texel_given: true, ..default };
        let note = scale_note(&Scale { across: 1.0, ..fine }).unwrap();
        assert!(
            !note.contains("one point per pixel") && note.contains("more --points and a smaller --texel"),
            "{note}"
        );
        let most = Scale { points: 500_000, photo_side: 16, across: 0.2, ..default };
        let note = scale_note(&most).unwrap();
        assert!(!note.contains("--points") && !note.contains("shrunk"), "{note}");
        // 400 pixels of a 512-px photo, or 40 of a 64-px one: enough shows
        assert_eq!(scale_note(&Scale { texel: 0.005, spacing: 0.0025, ..default }), None);
        assert_eq!(scale_note(&Scale { photo_side: 64, ..default }), None);
    }
}
