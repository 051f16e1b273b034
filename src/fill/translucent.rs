//! Volume rendering of translucent LST models (thesis §6.1.2 and Fig. 7.2b): slices across
//! the viewing direction, each a planar cut of the models, composited front to back.
//!
//! ```text
//!   yaw/pitch -> camera (right, up, forward) -> slices k = 0..n at depth d_k (front first)
//!   per slice: cut -> colour c, density ρ in [0, 1] per pixel
//!   per pixel: a = 1 - (1 - opacity)^(ρ Δ / L) ; colour += T a c ; T *= 1 - a
//!   picture = colour + T background
//! ```
//!
//! `Δ` is the distance between slices and `L` a tenth of the longest side of the models' box,
//! so a ray through a length `ℓ` of full-density material keeps `(1 - opacity)^(ℓ / L)` of
//! the light behind it (Beer–Lambert): `opacity` is how opaque the material is across a
//! tenth of the model. Every pixel is composited on its own, so the picture does not depend on the
//! thread count.

use super::model::LstModel;
#[cfg(test)]
use super::render::BACKGROUND;
use super::render::{Cut, Textures, View, bounds, cut_many_within_into, stack_outlines};
use super::view::{Hit, Shading, camera, draw_triangle, facets};
use crate::error::{Error, Result};
use crate::render::{Rgb8, to_u8};
use glam::{Vec2, Vec3};
use rayon::prelude::*;

/// Where each voxel's density comes from.
#[derive(Clone, Copy)]
pub enum Density<'a> {
    /// The same everywhere inside the models.
    Uniform,
    /// Dark colours dense, light ones clear (1 - luma).
    Dark,
    /// Light colours dense, dark ones clear (luma).
    Light,
    /// A channel of the exemplars: these textures sample it in place of the colour (see
    /// [`Textures::channel`]), one per model in the models' order.
    Channel(&'a [Textures]),
}

/// How to render.
#[derive(Debug, Clone, Copy)]
pub struct Settings {
    /// Degrees around the vertical axis.
    pub yaw: f32,
    /// Degrees above the horizon.
    pub pitch: f32,
    /// Picture side in pixels.
    pub size: usize,
    /// Slices across the view, front to back.
    pub slices: usize,
    /// How opaque full-density material is across a tenth of the longest side of the
    /// models' box (0 to below 1).
    pub opacity: f32,
    /// A plane (point, normal): material on the side the normal points to is taken away.
    pub cutaway: Option<(Vec3, Vec3)>,
    /// The density ramps from 0 at the first to 1 at the second (0 <= first < second <= 1):
    /// (0, 1) keeps it, (0.6, 0.8) keeps only the densest material.
    pub levels: (f32, f32),
    /// The colour behind the models.
    pub background: [u8; 3],
}

/// A rendered picture and how much of it the models cover.
pub struct Rendering {
    /// RGB over the settings' background.
    pub picture: Rgb8,
    /// Per pixel, the share of light the models stop (0 to 1), row by row.
    pub opacity: Vec<f32>,
    /// The slices composited: all of them, unless every pixel of the picture became
    /// opaque first (the frame's margin usually keeps some clear).
    pub slices: usize,
}

/// The longest side of the models' box over the length across which material is `opacity`
/// opaque.
pub const UNIT_SHARE: f32 = 10.0;

/// The least transmittance that still counts: a pixel below it is opaque.
const OPAQUE: f32 = 1.0 / 1024.0;

/// Bytes a rendering holds per pixel of its picture at its peak (the colour and
/// transmittance so far, the entry hits, one slice's cut and densities; measured at about
/// 130, with room to spare).
const BYTES_PER_PIXEL: u64 = 160;

/// Bytes a rendering of `size`² pixels holds at its peak.
pub fn memory_needed(size: usize) -> u64 {
    (size as u64).saturating_mul(size as u64).saturating_mul(BYTES_PER_PIXEL)
}

/// Renders `models` (the first listed wins where they overlap, as in a cut) as translucent
/// material.
pub fn render(
    models: &[(&LstModel, &Textures)],
    density: Density,
    settings: &Settings,
    skin: Option<SkinLayer>,
) -> Result<Rendering> {
    render_with(models, density, settings, skin, &crate::progress::NoProgress)
}

/// [`render`], telling `progress` how many slices are composited and stopping when it is
/// cancelled.
pub fn render_with(
    models: &[(&LstModel, &Textures)],
    density: Density,
    settings: &Settings,
    skin: Option<SkinLayer>,
    progress: &dyn crate::progress::Progress,
) -> Result<Rendering> {
    check(models, density, settings)?;
    let (forward, frame) = frames(models, settings);
    let depth = (frame.far - frame.near) / settings.slices as f32;
    let (lo, hi) = bounds(models);
    let unit = (hi - lo).max_element().max(1e-6) / UNIT_SHARE;
    let absorb = (1.0 - settings.opacity).ln() * depth / unit;
    let pixels = settings.size * settings.size;
    let mut colour = vec![Vec3::ZERO; pixels];
    let mut through = vec![1.0f32; pixels];
    let entry_hits = entries(models, &frame, forward);
    let entry: Vec<f32> = entry_hits.iter().map(|h| h.map_or(f32::INFINITY, |h| h.depth)).collect();
    if let Some(layer) = skin {
        layer.cover(models, &entry_hits, settings.cutaway, &mut colour, &mut through)?;
    }
    let mut started = vec![false; pixels];
    let mut done = 0;
    let outlines =
        stack_outlines(models, &frame.at(frame.near + 0.5 * depth, forward), forward * depth, settings.slices);
    // one slice's cuts and densities, their memory kept from slice to slice
    let first = frame.at(frame.near + 0.5 * depth, forward);
    let [mut cut, mut other, mut channel] = [(); 3].map(|_| Cut::empty(&first));
    let mut rho = Vec::with_capacity(pixels);
    for k in 0..settings.slices {
        let view = frame.at(frame.near + (k as f32 + 0.5) * depth, forward);
        let kept_share = kept(&view, settings.cutaway, forward * depth);
        let mut insides: Vec<Vec<bool>> = outlines.iter().map(|o| o.inside(k)).collect();
        // a ray that is already opaque takes nothing more: its pixels are not cut
        for inside in &mut insides {
            inside.par_iter_mut().zip(through.par_iter()).for_each(|(i, t)| *i &= *t > OPAQUE);
        }
        cut_many_within_into(models, &view, &insides, (&mut cut, &mut other));
        let scratch = (&mut channel, &mut other);
        densities(models, density, (&cut, &insides), &view, (settings.levels, scratch), &mut rho);
        let centre = frame.near + (k as f32 + 0.5) * depth;
        let pixels = colour.par_iter_mut().zip(through.par_iter_mut()).zip(started.par_iter_mut());
        pixels.enumerate().for_each(|(i, ((c, t), first))| {
            let p = cut.pixels[i];
            let mut share = if p[3] > 0.0 && *t > OPAQUE { kept_share(i) } else { 0.0 };
            if p[3] > 0.0 && !*first {
                // the first sample inside stands for the material from where the ray
                // entered, so the thickness does not step from slice to slice
                *first = true;
                if entry[i] > centre - 1.5 * depth {
                    share *= ((centre + depth / 2.0 - entry[i]) / depth).clamp(0.0, 2.0);
                }
            }
            if share > 0.0 {
                let a = 1.0 - (absorb * rho[i] * share).exp();
                *c += Vec3::new(p[0], p[1], p[2]) * (*t * a);
                *t *= 1.0 - a;
            }
        });
        done = k + 1;
        progress.update("slices", done as f32 / settings.slices as f32);
        if progress.cancelled() {
            return Err(Error::Cancelled);
        }
        if through.par_iter().all(|t| *t <= OPAQUE) {
            break;
        }
    }
    Ok(Rendering {
        picture: picture(settings, &colour, &through),
        opacity: through.iter().map(|t| 1.0 - t).collect(),
        slices: done,
    })
}

fn check(models: &[(&LstModel, &Textures)], density: Density, s: &Settings) -> Result<()> {
    if !(8..=8192).contains(&s.size) || !(1..=8192).contains(&s.slices) {
        return Err(Error::invalid(format!(
            "render size {} must be 8 to 8192 pixels and slices {} 1 to 8192",
            s.size, s.slices
        )));
    }
    if !(0.0..1.0).contains(&s.opacity) {
        return Err(Error::invalid(format!("opacity {} is out of range; allowed 0 to below 1", s.opacity)));
    }
    let (lo, hi) = s.levels;
    if !(0.0 <= lo && lo < hi && hi <= 1.0) {
        return Err(Error::invalid(format!("density levels {lo},{hi} must rise within 0 to 1")));
    }
    if let Some((p, n)) = s.cutaway
        && !(p.is_finite() && n.try_normalize().is_some())
    {
        return Err(Error::invalid("the cutaway plane must be finite with a normal that is not zero"));
    }
    if let Density::Channel(t) = density
        && t.len() != models.len()
    {
        return Err(Error::invalid(format!("{} density textures for {} models", t.len(), models.len())));
    }
    Ok(())
}

/// The picture plane: pixel steps across, and the depth range the models span.
struct Frame {
    corner: Vec3,
    right: Vec3,
    down: Vec3,
    size: usize,
    near: f32,
    far: f32,
}

impl Frame {
    /// The view of the slice at `depth` along `forward`.
    fn at(&self, depth: f32, forward: Vec3) -> View {
        View {
            origin: self.corner + forward * depth,
            right: self.right,
            down: self.down,
            width: self.size,
            height: self.size,
        }
    }
}

/// The camera's forward direction and the square frame that holds the models' box.
fn frames(models: &[(&LstModel, &Textures)], s: &Settings) -> (Vec3, Frame) {
    let (forward, right, up) = camera(s.yaw, s.pitch);
    let (lo, hi) = bounds(models);
    let corners = (0..8).map(|i| Vec3::new([lo.x, hi.x][i & 1], [lo.y, hi.y][(i >> 1) & 1], [lo.z, hi.z][i >> 2]));
    let (mut a, mut b) = (Vec2::INFINITY, Vec2::NEG_INFINITY);
    let (mut near, mut far) = (f32::INFINITY, f32::NEG_INFINITY);
    for p in corners {
        let q = Vec2::new(right.dot(p), up.dot(p));
        (a, b) = (a.min(q), b.max(q));
        (near, far) = (near.min(forward.dot(p)), far.max(forward.dot(p)));
    }
    let side = (b - a).max_element().max(1e-6) * 1.04;
    let mid = (a + b) / 2.0;
    let step = side / s.size as f32;
    let corner = right * (mid.x - side / 2.0) + up * (mid.y + side / 2.0);
    let frame = Frame { corner, right: right * step, down: -up * step, size: s.size, near, far };
    (forward, frame)
}

/// Per pixel, the depth along `forward` where its ray first enters a model (the nearest
/// front-facing triangle of its input surface; none where it enters none).
fn entries(models: &[(&LstModel, &Textures)], frame: &Frame, forward: Vec3) -> Vec<Option<Hit>> {
    let size = frame.size;
    let mut hits: Vec<Option<Hit>> = vec![None; size * size];
    let (right, down) = (frame.right / frame.right.length_squared(), frame.down / frame.down.length_squared());
    let to_pixel = |p: Vec3| Vec2::new(right.dot(p - frame.corner), down.dot(p - frame.corner));
    for (m, (model, _)) in models.iter().enumerate() {
        for f in facets(model, m as u32, Shading::Flat) {
            let normal = f.normal();
            if normal.dot(forward) >= 0.0 {
                continue;
            }
            draw_triangle(&mut hits, size, f.shown.map(to_pixel), |b| {
                let p = f.shown[0] * b[0] + f.shown[1] * b[1] + f.shown[2] * b[2];
                Some(Hit { depth: forward.dot(p), model: f.model, triangle: f.triangle, point: p, normal })
            });
        }
    }
    hits
}

/// A synthesized surface texture drawn where the rays enter the models, over the material.
#[derive(Clone, Copy)]
pub struct SkinLayer<'a> {
    /// The skin and how far from it an entry point may lie.
    pub skin: super::view::Skin<'a>,
    /// How much light the skin stops, 0 to 1 (1: only the skin shows).
    pub opacity: f32,
}

impl SkinLayer<'_> {
    /// Composites the skin at each ray's entry point that the cutaway keeps.
    fn cover(
        &self,
        models: &[(&LstModel, &Textures)],
        entries: &[Option<Hit>],
        cutaway: Option<(Vec3, Vec3)>,
        colour: &mut [Vec3],
        through: &mut [f32],
    ) -> Result<()> {
        if !(0.0..=1.0).contains(&self.opacity) {
            return Err(Error::invalid(format!("skin opacity {} is out of range; allowed 0 to 1", self.opacity)));
        }
        let kept = |p: Vec3| cutaway.is_none_or(|(at, normal)| (p - at).dot(normal) <= 0.0);
        colour.par_iter_mut().zip(through.par_iter_mut()).zip(entries).for_each(|((c, t), entry)| {
            let Some(h) = entry.filter(|h| kept(h.point)) else { return };
            let model = models[h.model as usize].0;
            let at = model.locate(h.point);
            if let Some(rgb) = self.skin.colour_at(model, h.model as usize, h.point, at.as_ref()) {
                *c += Vec3::from_array(rgb) * (*t * self.opacity);
                *t *= 1.0 - self.opacity;
            }
        });
        Ok(())
    }
}

/// The density at each pixel of a slice, into `rho`: from `density`, mapped from `lo..hi`
/// to 0..1; a density channel is cut into the `scratch` cuts.
fn densities(
    models: &[(&LstModel, &Textures)],
    density: Density,
    (cut, insides): (&Cut, &[Vec<bool>]),
    view: &View,
    ((lo, hi), scratch): ((f32, f32), (&mut Cut, &mut Cut)),
    rho: &mut Vec<f32>,
) {
    let luma = |p: &[f32; 4]| crate::volume::luminance([p[0], p[1], p[2]]);
    let scaled = |r: f32| ((r - lo) / (hi - lo)).clamp(0.0, 1.0);
    rho.clear();
    match density {
        Density::Uniform => rho.resize(cut.pixels.len(), scaled(1.0)),
        Density::Dark => rho.par_extend(cut.pixels.par_iter().map(|p| scaled(1.0 - luma(p)))),
        Density::Light => rho.par_extend(cut.pixels.par_iter().map(|p| scaled(luma(p)))),
        Density::Channel(textures) => {
            let pairs: Vec<(&LstModel, &Textures)> = models.iter().map(|(m, _)| *m).zip(textures).collect();
            let (into, other) = scratch;
            cut_many_within_into(&pairs, view, insides, (&mut *into, other));
            rho.par_extend(into.pixels.par_iter().map(|p| scaled(p[0])));
        }
    }
}

/// The share of pixel `i`'s slab of a slice (`step` long along the ray, centred on the
/// slice) that keeps its material: 1 with no cutaway, 0 behind the cutaway plane, a
/// fraction where the plane crosses the slab, so its face shows no steps between slices.
fn kept(view: &View, cutaway: Option<(Vec3, Vec3)>, step: Vec3) -> impl Fn(usize) -> f32 + Sync + '_ {
    let plane = cutaway.map(|(point, normal)| (point, normal.normalize()));
    move |i| match plane {
        None => 1.0,
        Some((point, normal)) => {
            let side = normal.dot(view.point(i % view.width, i / view.width) - point);
            let across = normal.dot(step).abs();
            if across < 1e-9 { if side <= 0.0 { 1.0 } else { 0.0 } } else { (0.5 - side / across).clamp(0.0, 1.0) }
        }
    }
}

fn picture(settings: &Settings, colour: &[Vec3], through: &[f32]) -> Rgb8 {
    let size = settings.size;
    let mut out = Rgb8::new(size, size, settings.background);
    let back = Vec3::from(settings.background.map(|c| c as f32 / 255.0));
    for (i, (c, t)) in colour.iter().zip(through).enumerate() {
        let p = *c + back * *t;
        out.put(i % size, i / size, [p.x, p.y, p.z].map(to_u8));
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::fill::model::{MaskRef, Source};
    use crate::fill::patch::Patch;
    use crate::fill::tets::cube_lattice;
    use crate::volume::{Channel, Volume};

    /// The unit cube as one model of a single patch whose texture coordinates are the
    /// positions, textured with `colour` (RGB) and a full mask.
    fn cube(colour: Volume) -> (LstModel, Textures) {
        let mesh = cube_lattice([4, 4, 4], 0.25);
        let vertices: Vec<u32> = (0..mesh.vertices.len() as u32).collect();
        let coords = mesh.vertices.clone();
        let tet_patches = vec![vec![0]; mesh.tets.len()];
        let source = Source { exemplar: "test".into(), volume: "test.exr".into(), mask: MaskRef::File("m.exr".into()) };
        let surface = LstModel::boundary_of(&mesh).unwrap();
        let model =
            LstModel::new(mesh, surface, vec![source], vec![Patch { source: 0, vertices, coords }], tet_patches);
        let full = Volume::from_fn([4, 4, 4], vec![Channel::A], |_, _, _, o| o[0] = 1.0).unwrap();
        (model, Textures::new(&[colour], &[full]))
    }

    fn flat(rgb: [f32; 3]) -> Volume {
        Volume::from_fn([4, 4, 4], Channel::rgb(), |_, _, _, o| o.copy_from_slice(&rgb)).unwrap()
    }

    fn settings(yaw: f32, opacity: f32) -> Settings {
        Settings {
            yaw,
            pitch: 0.0,
            size: 64,
            slices: 200,
            opacity,
            cutaway: None,
            levels: (0.0, 1.0),
            background: BACKGROUND,
        }
    }

    /// The opacity Beer–Lambert predicts through `sides` sides of the unit cube.
    fn through(opacity: f32, sides: f32) -> f32 {
        1.0 - (1.0 - opacity).powf(sides * UNIT_SHARE)
    }

    #[test]
    fn a_uniform_cube_stops_the_light_beer_lambert_predicts() {
        let (model, textures) = cube(flat([1.0, 1.0, 1.0]));
        let models = [(&model, &textures)];
        for opacity in [0.03, 0.15] {
            // face on: every ray crosses one side
            let face = render(&models, Density::Uniform, &settings(0.0, opacity), None).unwrap();
            let (got, want) = (face.opacity[32 * 64 + 32], through(opacity, 1.0));
            assert!((got - want).abs() < 1e-3, "face on, opacity {opacity}: {got} against {want}");
            // turned 45°: the central ray crosses the diagonal, sqrt 2 sides
            let turned = render(&models, Density::Uniform, &settings(45.0, opacity), None).unwrap();
            let (got, want) = (turned.opacity[32 * 64 + 32], through(opacity, 2f32.sqrt()));
            assert!((got - want).abs() < 0.01, "diagonal, opacity {opacity}: {got} against {want}");
            // off the cube there is nothing
            assert_eq!(face.opacity[0], 0.0);
        }
    }

    #[test]
    fn a_skin_covers_where_the_rays_enter_and_not_where_the_cutaway_opened_the_model() {
        let (model, textures) = cube(flat([1.0, 1.0, 1.0]));
        let models = [(&model, &textures)];
        let skin = crate::mesh::shapes::cuboid(Vec3::ZERO, Vec3::ONE);
        let red = vec![[1.0, 0.0, 0.0]; skin.vertices.len()];
        let lookup = crate::surface::SkinLookup::new(&skin, &red);
        let layer = |opacity: f32| {
            Some(SkinLayer { skin: super::super::view::Skin { lookup: &lookup, within: 0.01, depth: None }, opacity })
        };
        let s = settings(0.0, 0.15);
        let opaque = render(&models, Density::Uniform, &s, layer(1.0)).unwrap();
        assert_eq!(opaque.picture.at(32, 32), [255, 0, 0]);
        assert_eq!(opaque.picture.at(0, 0), BACKGROUND, "no skin off the model");
        let plain = render(&models, Density::Uniform, &s, None).unwrap().picture.at(32, 32);
        let half = render(&models, Density::Uniform, &s, layer(0.5)).unwrap().picture.at(32, 32);
        assert!(half[0].abs_diff(((255.0 + plain[0] as f32) / 2.0) as u8) <= 1, "{half:?} over {plain:?}");
        assert!(half[1].abs_diff(plain[1] / 2) <= 1, "{half:?} over {plain:?}");
        let opened = Settings { cutaway: Some((Vec3::splat(0.5), Vec3::Z)), ..s };
        let cut = render(&models, Density::Uniform, &opened, layer(1.0)).unwrap();
        let without = render(&models, Density::Uniform, &opened, None).unwrap();
        assert_eq!(cut.picture.at(32, 32), without.picture.at(32, 32), "the cut face shows the material");
        let far =
            SkinLayer { skin: super::super::view::Skin { lookup: &lookup, within: 0.01, depth: None }, opacity: 1.5 };
        assert!(render(&models, Density::Uniform, &s, Some(far)).is_err());
    }

    #[test]
    fn a_slanted_view_follows_the_chord_not_the_slices() {
        // a uniform cube seen at a slant with few slices: each pixel's opacity must follow
        // its ray's chord through the cube, not jump with the slices its ray meets
        let (model, textures) = cube(flat([1.0, 1.0, 1.0]));
        let s = Settings { yaw: 30.0, pitch: 20.0, slices: 40, ..settings(0.0, 0.05) };
        let rendering = render(&[(&model, &textures)], Density::Uniform, &s, None).unwrap();
        let (forward, frame) = frames(&[(&model, &textures)], &s);
        let (mut worst, mut n) = (0.0f32, 0);
        for y in 0..64 {
            for x in 0..64 {
                let origin = frame.at(0.0, forward).point(x, y) - forward * 10.0;
                let chord = chord(origin, forward);
                if chord > 0.3 {
                    worst = worst.max((rendering.opacity[y * 64 + x] - through(0.05, chord)).abs());
                    n += 1;
                }
            }
        }
        // 0.009 (the exit side still steps); 0.016 with every sample a whole slab thick
        assert!(n > 1000 && worst < 0.012, "opacity {worst} off the chord's over {n} pixels");
    }

    /// The length of the line `origin + t direction` inside the unit cube.
    fn chord(origin: Vec3, direction: Vec3) -> f32 {
        let (a, b) = ((Vec3::ZERO - origin) / direction, (Vec3::ONE - origin) / direction);
        let (near, far) = (a.min(b).max_element(), a.max(b).min_element());
        (far - near).max(0.0)
    }

    #[test]
    fn colour_and_density_shape_the_picture() {
        // a cube half black (x < 0.5), half white: dark density makes the black half opaque
        let halves =
            Volume::from_fn([8, 4, 4], Channel::rgb(), |x, _, _, o| o.fill(if x < 4 { 0.0 } else { 1.0 })).unwrap();
        let (model, textures) = cube(halves);
        let models = [(&model, &textures)];
        let dark = render(&models, Density::Dark, &settings(0.0, 0.1), None).unwrap();
        let (left, right) = (dark.opacity[32 * 64 + 16], dark.opacity[32 * 64 + 48]);
        let want = through(0.1, 1.0);
        assert!((left - want).abs() < 1e-3 && right < 1e-3, "dark density: left {left}, right {right}");
        let light = render(&models, Density::Light, &settings(0.0, 0.1), None).unwrap();
        assert!(light.opacity[32 * 64 + 16] < 1e-3 && (light.opacity[32 * 64 + 48] - want).abs() < 1e-3);
        // a white cube, almost opaque, shows white; the light it lets through is the background's
        let white = render(&models, Density::Uniform, &settings(0.0, 0.369), None).unwrap();
        let left = 1.0 - through(0.369, 1.0);
        let want = (1.0 - left) * 255.0 + left * BACKGROUND[0] as f32;
        assert!((white.picture.at(48, 32)[0] as f32 - want).abs() <= 1.0, "{:?}", white.picture.at(48, 32));
    }

    #[test]
    fn a_density_channel_and_a_cutaway_take_material_away() {
        let (model, textures) = cube(flat([1.0, 0.5, 0.2]));
        // density from a channel: 0.5 everywhere halves the exponent
        let half = Volume::from_fn([4, 4, 4], Channel::rgb(), |_, _, _, o| o.fill(0.5)).unwrap();
        let (_, density) = cube(half);
        let models = [(&model, &textures)];
        let channel =
            render(&models, Density::Channel(std::slice::from_ref(&density)), &settings(0.0, 0.1), None).unwrap();
        let (got, want) = (channel.opacity[32 * 64 + 32], through(0.1, 0.5));
        assert!((got - want).abs() < 1e-3, "half density through one side: {got} against {want}");
        // cutting away the front half (z > 0.5, toward the camera) leaves half the thickness
        let cut = Settings { cutaway: Some((Vec3::splat(0.5), Vec3::Z)), ..settings(0.0, 0.1) };
        let got = render(&models, Density::Uniform, &cut, None).unwrap().opacity[32 * 64 + 32];
        assert!((got - want).abs() < 1e-3, "half the cube: {got} against {want}");
        // levels: density 0.5 ramped over 0.25..0.75 stays 0.5, over 0.5..1 becomes 0
        let ramped = Settings { levels: (0.25, 0.75), ..settings(0.0, 0.1) };
        let got = render(&models, Density::Channel(std::slice::from_ref(&density)), &ramped, None).unwrap().opacity
            [32 * 64 + 32];
        assert!((got - want).abs() < 1e-3, "{got}");
        let high = Settings { levels: (0.5, 1.0), ..settings(0.0, 0.1) };
        let got = render(&models, Density::Channel(std::slice::from_ref(&density)), &high, None).unwrap().opacity
            [32 * 64 + 32];
        assert_eq!(got, 0.0);
        assert!(render(&models, Density::Uniform, &settings(0.0, 1.0), None).is_err());
        assert!(render(&models, Density::Channel(&[]), &settings(0.0, 0.5), None).is_err());
    }

    #[test]
    fn renders_do_not_depend_on_the_thread_count() {
        let stripes = Volume::from_fn([8, 8, 8], Channel::rgb(), |x, y, z, o| {
            o.copy_from_slice(&[(x % 3) as f32 / 2.0, (y % 2) as f32, (z % 4) as f32 / 3.0])
        })
        .unwrap();
        let (model, textures) = cube(stripes);
        let run = |threads: usize| {
            let pool = rayon::ThreadPoolBuilder::new().num_threads(threads).build().unwrap();
            let s = Settings { pitch: 30.0, cutaway: Some((Vec3::splat(0.4), Vec3::ONE)), ..settings(20.0, 0.9) };
            pool.install(|| render(&[(&model, &textures)], Density::Dark, &s, None).unwrap().picture.data)
        };
        assert_eq!(run(1), run(3));
    }
}
