//! What a fill asks for (read from a TOML fill spec by `io::fill_spec`, documented in
//! `docs/fill.md`), and how it becomes field constraints on a given surface.

use super::field::Constraints;
use crate::TextureType;
use crate::error::{Error, Result};
use crate::mesh::Mesh;
use crate::volume::Axis;
use glam::{Quat, Vec3};
use std::path::PathBuf;

/// Most depth constraint points taken from the surface.
const SURFACE_POINTS: usize = 600;
/// Stroke samples per unit of the model's size.
const STROKE_SAMPLES: usize = 24;

/// A validated fill spec.
#[derive(Debug, Clone, PartialEq)]
pub struct FillSpec {
    /// The exemplar's name in the library.
    pub exemplar: String,
    /// The library manifest.
    pub library: PathBuf,
    /// The folder `solidtex build` wrote the library into.
    pub built: PathBuf,
    /// The texture type (else the library's declared type, else classified).
    pub texture_type: Option<TextureType>,
    /// Seed of the paste loop.
    pub seed: u64,
    /// Texture cube side in model units (types 0, 1-a, 2-a).
    pub scale: Option<f32>,
    /// Target tet count.
    pub tets: usize,
    /// Texture axes of the primary and secondary directions (else from the exemplar).
    pub axes: Option<[Axis; 2]>,
    /// Fall-off of generated masks (`None`: the default).
    pub mask_falloff: Option<f32>,
    /// Direction strokes (polylines).
    pub directions: Vec<Vec<Vec3>>,
    /// Depth constraints.
    pub depth: DepthSpec,
    /// Scale constraints (point, scale).
    pub scales: Vec<(Vec3, f32)>,
    /// Manual pastes after the automatic fill.
    pub pastes: Vec<PasteSpec>,
    /// Guided synthesis: exemplars by depth range, outside in (empty: `exemplar` everywhere).
    pub regions: Vec<RegionSpec>,
    /// Width in depth of the band where neighbouring regions blend.
    pub region_band: f32,
}

impl FillSpec {
    /// A spec with the defaults of the TOML form: no constraints, 5,000 tets, seed 0, the
    /// default library and build folder, the surface at depth 0.
    pub fn new(exemplar: &str) -> FillSpec {
        FillSpec {
            exemplar: exemplar.to_string(),
            library: PathBuf::from("exemplars/library.toml"),
            built: PathBuf::from("out"),
            texture_type: None,
            seed: 0,
            scale: None,
            tets: 5000,
            axes: None,
            mask_falloff: None,
            directions: Vec::new(),
            depth: DepthSpec { surface: true, ..Default::default() },
            scales: Vec::new(),
            pastes: Vec::new(),
            regions: Vec::new(),
            region_band: DEFAULT_REGION_BAND,
        }
    }
}

/// The band neighbouring regions blend across when a spec gives none.
pub const DEFAULT_REGION_BAND: f32 = 0.05;

/// A depth range of the model textured by its own exemplar (guided synthesis, Zhang et
/// al.'s bark outside and wood inside).
#[derive(Debug, Clone, PartialEq)]
pub struct RegionSpec {
    /// The exemplar's name in the library.
    pub exemplar: String,
    /// The depths it covers, from the outer (smaller) to the inner.
    pub depth: [f32; 2],
}

/// Depth constraints: the surface, axis polylines, points and face groups.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct DepthSpec {
    /// Whether the whole surface is depth 0 (face groups override their part).
    pub surface: bool,
    /// Polylines at depth 1 (e.g. the core of a fruit).
    pub axes: Vec<Vec<Vec3>>,
    /// The share of each axis polyline's length, from either end, over which its depth
    /// falls from 1 to [`TAPER_END`] along a quarter ellipse, so the core rounds off
    /// toward the ends instead of stopping squarely; 0 (no taper) to 0.5.
    pub taper: f32,
    /// Points with their depth.
    pub points: Vec<(Vec3, f32)>,
    /// Face groups with their own depth.
    pub faces: Vec<FaceGroup>,
}

impl DepthSpec {
    /// Whether any depth constraint inside or on the surface is given (axes, points or
    /// face groups).
    pub fn given(&self) -> bool {
        !(self.axes.is_empty() && self.points.is_empty() && self.faces.is_empty())
    }
}

/// Surface faces reached from the face nearest `at` (the seed) without crossing a crease
/// sharper than `crease` degrees (the thesis' multi-face fill) and whose normals lie within
/// `angle` degrees of the seed's (the TUI's single-face fill; 180 for no limit).
#[derive(Debug, Clone, PartialEq)]
pub struct FaceGroup {
    /// A point on or near the seed face.
    pub at: Vec3,
    /// Crease angle in degrees.
    pub crease: f32,
    /// The largest angle between a face's normal and the seed face's, degrees.
    pub angle: f32,
    /// The group's depth.
    pub value: f32,
}

/// A manual paste (thesis §5.6).
#[derive(Debug, Clone, PartialEq)]
pub struct PasteSpec {
    /// The exemplar's name in the library.
    pub exemplar: String,
    /// Where the texture centre goes.
    pub at: Vec3,
    /// The texture's orientation.
    pub rotation: Quat,
    /// Texture cube side in model units.
    pub scale: f32,
}

/// Turns the spec's strokes, depth and scales into field constraints on `surface`,
/// refusing points outside the model. `default_scale` applies where no scale is given.
pub fn constraints(spec: &FillSpec, surface: &Mesh, default_scale: f32) -> Result<Constraints> {
    let size = size_of(surface);
    for (i, stroke) in spec.directions.iter().enumerate() {
        check_inside(surface, stroke, &format!("direction[{i}]"))?;
    }
    let directions = spec.directions.iter().flat_map(|s| stroke_samples(s, size)).collect();
    let surface_values = surface_values(spec, surface)?;
    let mut depth = surface_depth(spec, surface, &surface_values)?;
    for (i, axis) in spec.depth.axes.iter().enumerate() {
        check_inside(surface, axis, &format!("depth.axis[{i}]"))?;
        depth.extend(tapered(&resample(axis, size), spec.depth.taper));
    }
    for (i, (p, d)) in spec.depth.points.iter().enumerate() {
        check_inside(surface, &[*p], &format!("depth.points[{i}]"))?;
        depth.push((*p, *d));
    }
    for (i, (p, _)) in spec.scales.iter().enumerate() {
        check_inside(surface, &[*p], &format!("scale_at[{i}]"))?;
    }
    for (i, paste) in spec.pastes.iter().enumerate() {
        check_inside(surface, &[paste.at], &format!("paste[{i}].at"))?;
    }
    Ok(Constraints {
        directions,
        depth,
        surface_values,
        scales: spec.scales.clone(),
        scale: spec.scale.unwrap_or(default_scale),
    })
}

/// The options of `spec` a fill of texture type `kind` with these `sources` does not use,
/// each with the reason (so a spec that changes nothing says so instead of writing the
/// same model silently).
pub fn ignored(spec: &FillSpec, kind: TextureType, sources: &[super::Source]) -> Vec<String> {
    let mut out = Vec::new();
    let layered = matches!(kind, TextureType::T1b | TextureType::T2b);
    if layered && spec.scale.is_some() {
        out.push(format!(
            "scale is not used by type {kind}: its texture scale follows the depth field (1 / |grad depth|)"
        ));
    }
    if layered && !spec.scales.is_empty() {
        out.push(format!("[[scale_at]] is not used by type {kind}: its texture scale follows the depth field"));
    }
    let generated = sources.iter().any(|s| !matches!(s.mask, super::MaskRef::File(_)));
    if spec.mask_falloff.is_some() && !generated {
        out.push(
            "mask_falloff is not used: every mask comes from the built library (NAME.mask.exr or NAME.masks/), \
             whose fall-off the manifest's mask_falloff sets"
                .to_string(),
        );
    }
    let depth_given = spec.depth.given();
    if depth_given && matches!(kind, TextureType::T0 | TextureType::T1a) {
        out.push(format!("[depth] is not used by type {kind}: it has no depth-varying layers"));
    }
    if spec.depth.taper > 0.0 && spec.depth.axes.is_empty() {
        out.push("depth.taper is not used: there is no depth axis to taper ([depth] axis)".to_string());
    }
    if !spec.directions.is_empty() && matches!(kind, TextureType::T0 | TextureType::T1b) {
        out.push(format!(
            "[[direction]] is not used by type {kind}: its orientation is random about the depth gradient or everywhere"
        ));
    }
    out
}

/// The model's size: the diagonal of its bounding box.
pub fn size_of(surface: &Mesh) -> f32 {
    let (lo, hi) = surface.bounds();
    (hi - lo).length()
}

fn check_inside(surface: &Mesh, points: &[Vec3], field: &str) -> Result<()> {
    match points.iter().position(|p| surface.winding_number(*p).abs() < 0.25) {
        Some(k) => Err(Error::invalid(format!(
            "{field}: point {} ({}) is outside the model; constraints must lie inside or on the surface",
            k, points[k]
        ))),
        None => Ok(()),
    }
}

/// A stroke as (point, unit tangent) samples, evenly spaced.
pub fn stroke_samples(stroke: &[Vec3], size: f32) -> Vec<(Vec3, Vec3)> {
    if stroke.len() == 1 {
        return Vec::new();
    }
    let points = resample(stroke, size);
    points
        .windows(2)
        .map(|w| ((w[0] + w[1]) / 2.0, (w[1] - w[0]).normalize_or_zero()))
        .filter(|s| s.1 != Vec3::ZERO)
        .collect()
}

/// The depth at the ends of a tapered axis.
pub const TAPER_END: f32 = 0.5;

/// The points of an axis polyline with their depth: 1, falling to [`TAPER_END`] over the
/// share `taper` of the length at either end.
fn tapered(points: &[Vec3], taper: f32) -> Vec<(Vec3, f32)> {
    let mut along = vec![0.0f32; points.len()];
    for i in 1..points.len() {
        along[i] = along[i - 1] + points[i].distance(points[i - 1]);
    }
    let length = along.last().copied().unwrap_or(0.0);
    let span = taper.clamp(0.0, 0.5) * length;
    let depth = |s: f32| {
        if span.is_nan() || span <= 0.0 {
            return 1.0;
        }
        let u = (s.min(length - s) / span).clamp(0.0, 1.0);
        TAPER_END + (1.0 - TAPER_END) * (1.0 - (1.0 - u) * (1.0 - u)).sqrt()
    };
    points.iter().zip(&along).map(|(p, s)| (*p, depth(*s))).collect()
}

/// Points along a polyline about `size / STROKE_SAMPLES` apart (the corners included).
fn resample(line: &[Vec3], size: f32) -> Vec<Vec3> {
    let step = size / STROKE_SAMPLES as f32;
    let mut out = vec![line[0]];
    for w in line.windows(2) {
        let n = ((w[1] - w[0]).length() / step).ceil().max(1.0) as usize;
        out.extend((1..=n).map(|k| w[0].lerp(w[1], k as f32 / n as f32)));
    }
    out
}

/// The depth each surface triangle holds: 0 everywhere (if asked), face groups their value,
/// `None` where the surface is free.
pub fn surface_values(spec: &FillSpec, surface: &Mesh) -> Result<Vec<Option<f32>>> {
    let mut value: Vec<Option<f32>> = vec![if spec.depth.surface { Some(0.0) } else { None }; surface.triangles.len()];
    for group in &spec.depth.faces {
        for t in face_group(surface, group)? {
            value[t] = Some(group.value);
        }
    }
    Ok(value)
}

/// Depth constraints on the surface for the RBF: about [`SURFACE_POINTS`] points spread by
/// area (so a few long triangles are sampled along their length, not only at their
/// centres), each with its triangle's value; free triangles give none.
fn surface_depth(spec: &FillSpec, surface: &Mesh, value: &[Option<f32>]) -> Result<Vec<(Vec3, f32)>> {
    let corners = |t: usize| {
        // corners in index order, so a flipped triangle gives the same bits
        let mut c = surface.triangles[t];
        c.sort_unstable();
        c.map(|i| surface.vertices[i as usize])
    };
    let areas: Vec<f64> = (0..surface.triangles.len())
        .map(|t| {
            let [a, b, c] = corners(t);
            f64::from((b - a).cross(c - a).length() / 2.0)
        })
        .collect();
    let total: f64 = areas.iter().sum();
    let mut out: Vec<(Vec3, f32)> = Vec::new();
    let (mut t, mut before) = (0, 0.0);
    for k in 0..SURFACE_POINTS {
        // stratified by area: sample k sits at the middle of its share of the total area
        let at = (k as f64 + 0.5) / SURFACE_POINTS as f64 * total;
        while t + 1 < areas.len() && before + areas[t] < at {
            before += areas[t];
            t += 1;
        }
        if let Some(d) = value[t] {
            let [a, b, c] = corners(t);
            let (mut u, mut v) = (fract(0.5 + k as f32 * 0.754_877_7), fract(0.5 + k as f32 * 0.569_840_3));
            if u + v > 1.0 {
                (u, v) = (1.0 - u, 1.0 - v);
            }
            out.push((a + (b - a) * u + (c - a) * v, d));
        }
    }
    // small groups could fall between the thinned samples: keep some corners of each
    for group in &spec.depth.faces {
        let faces = face_group(surface, group)?;
        let every = faces.len().div_ceil(40).max(1);
        let corners = faces.iter().step_by(every).flat_map(|&t| surface.triangles[t]);
        out.extend(corners.map(|i| (surface.vertices[i as usize], group.value)));
    }
    Ok(out)
}

fn fract(x: f32) -> f32 {
    x - x.floor()
}

/// The triangles of a face group, sorted.
pub fn face_group(surface: &Mesh, group: &FaceGroup) -> Result<Vec<usize>> {
    let degrees = 0.0..=180.0;
    if !(degrees.contains(&group.crease) && degrees.contains(&group.angle) && (0.0..=1.0).contains(&group.value)) {
        return Err(Error::invalid(format!(
            "depth.faces at {}: crease {} and angle {} must be 0 to 180 degrees and value {} in 0 to 1",
            group.at, group.crease, group.angle, group.value
        )));
    }
    let normal = |t: usize| {
        let [a, b, c] = surface.triangles[t].map(|i| surface.vertices[i as usize]);
        (b - a).cross(c - a).normalize_or_zero()
    };
    let distance = |t: usize| {
        let c = surface.triangles[t].iter().map(|&i| surface.vertices[i as usize]).sum::<Vec3>() / 3.0;
        c.distance_squared(group.at)
    };
    let seed = (0..surface.triangles.len()).min_by(|&a, &b| distance(a).total_cmp(&distance(b))).unwrap_or(0);
    let adjacency = edge_adjacency(surface);
    let (cos, spread) = (group.crease.to_radians().cos(), group.angle.to_radians().cos());
    let mut seen = vec![false; surface.triangles.len()];
    let mut stack = vec![seed];
    seen[seed] = true;
    while let Some(t) = stack.pop() {
        for &n in &adjacency[t] {
            let along = group.angle >= 180.0 || normal(seed).dot(normal(n)) >= spread;
            if !seen[n] && normal(t).dot(normal(n)) >= cos && along {
                seen[n] = true;
                stack.push(n);
            }
        }
    }
    Ok((0..seen.len()).filter(|&t| seen[t]).collect())
}

fn edge_adjacency(surface: &Mesh) -> Vec<Vec<usize>> {
    let mut edges: Vec<(u32, u32, usize)> = Vec::new();
    for (t, &[a, b, c]) in surface.triangles.iter().enumerate() {
        for (p, q) in [(a, b), (b, c), (c, a)] {
            edges.push((p.min(q), p.max(q), t));
        }
    }
    edges.sort_unstable();
    let mut out = vec![Vec::new(); surface.triangles.len()];
    for run in edges.chunk_by(|x, y| (x.0, x.1) == (y.0, y.1)) {
        for x in run {
            out[x.2].extend(run.iter().filter(|y| y.2 != x.2).map(|y| y.2));
        }
    }
    out
}

/// The axis whose gradient energy lies farthest (in logarithms) from the other two's.
fn odd_one(energy: [f64; 3]) -> usize {
    let log = energy.map(|e| e.max(1e-12).ln());
    let apart = |k: usize| (log[k] - (log[(k + 1) % 3] + log[(k + 2) % 3]) / 2.0).abs();
    (0..3).max_by(|a, b| apart(*a).total_cmp(&apart(*b))).unwrap_or(2)
}

/// The texture axes (0 = x, 1 = y, 2 = z) that the primary, secondary and third field
/// directions map to: `given` if set; else the primary is the axis the exemplar's Depth
/// channel runs along (or, without one, the axis it changes fastest along — for a 1-a
/// texture the odd one: the fibre axis it changes slowest along, or the normal of sheets
/// it changes fastest across) and the secondary the remaining axis it changes slowest along.
pub fn texture_axes(exemplar: &crate::Volume, kind: TextureType, given: Option<[Axis; 2]>) -> Result<[usize; 3]> {
    let [a, b] = match given {
        Some([a, b]) => [a.index(), b.index()],
        None => {
            let energy = crate::classify::classify(exemplar)?.gradient_energy;
            let order = |x: &usize, y: &usize| energy[*x].total_cmp(&energy[*y]);
            let primary = match exemplar.depth_axis() {
                Some(d) => d,
                None if kind == TextureType::T1a => odd_one(energy),
                None => (0..3).max_by(order).unwrap_or(2),
            };
            let secondary = (0..3).filter(|&i| i != primary).min_by(order).unwrap_or((primary + 1) % 3);
            [primary, secondary]
        }
    };
    Ok([a, b, 3 - a - b])
}

#[cfg(test)]
mod tests {
    use super::*;

    /// On a smooth fruit a crease never stops the flood; the angle from the clicked face's
    /// normal does: a patch around the click, every face of it within the angle.
    #[test]
    fn a_face_group_with_an_angle_stays_near_the_clicked_face() {
        let fruit = crate::mesh::shapes::named("fruit").unwrap();
        let at = Vec3::new(0.0, 0.7, 0.0);
        let flood = face_group(&fruit, &FaceGroup { at, crease: 30.0, angle: 180.0, value: 0.0 }).unwrap();
        assert_eq!(flood.len(), fruit.triangles.len());
        let patch = face_group(&fruit, &FaceGroup { at, crease: 30.0, angle: 20.0, value: 0.0 }).unwrap();
        assert!(
            patch.len() > 1 && patch.len() < fruit.triangles.len() / 5,
            "{} of {}",
            patch.len(),
            fruit.triangles.len()
        );
        let normal = |t: usize| {
            let [a, b, c] = fruit.triangles[t].map(|i| fruit.vertices[i as usize]);
            (b - a).cross(c - a).normalize()
        };
        let centre = |t: usize| fruit.triangles[t].iter().map(|&i| fruit.vertices[i as usize]).sum::<Vec3>() / 3.0;
        let clicked =
            (0..fruit.triangles.len()).min_by(|&a, &b| centre(a).distance(at).total_cmp(&centre(b).distance(at)));
        let seed = normal(clicked.unwrap());
        assert!(patch.iter().all(|&t| normal(t).dot(seed) >= 20f32.to_radians().cos() - 1e-6));
    }

    #[test]
    fn a_tapered_axis_falls_from_1_in_the_middle_to_the_end_depth() {
        let line: Vec<Vec3> = (0..=20).map(|i| Vec3::new(i as f32 / 10.0 - 1.0, 0.0, 0.0)).collect();
        let flat = tapered(&line, 0.0);
        assert!(flat.iter().all(|(_, d)| *d == 1.0));
        let depths: Vec<f32> = tapered(&line, 0.5).iter().map(|(_, d)| *d).collect();
        assert_eq!((depths[0], depths[20], depths[10]), (TAPER_END, TAPER_END, 1.0));
        assert!(depths[..=10].windows(2).all(|w| w[1] > w[0]), "{depths:?}");
        // a quarter ellipse: steep at the end, flat in the middle
        assert!(depths[1] - depths[0] > 4.0 * (depths[10] - depths[9]), "{depths:?}");
        let quarter: Vec<f32> = tapered(&line, 0.25).iter().map(|(_, d)| *d).collect();
        assert!(quarter[5..=15].iter().all(|d| *d == 1.0) && quarter[4] < 1.0, "{quarter:?}");
    }
}
