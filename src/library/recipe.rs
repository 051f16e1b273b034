//! Making one library exemplar: its source (procedural, sweep, synthesis, a loaded file),
//! its steps (stamp, scatter, blur), and the masks and exports written beside it.

use super::files;
use crate::error::{Error, Result};
use crate::io;
use crate::io::manifest::{Entry, Lines, MaskKind, SkinSource, Source, Step, SweepSpec, SynthSpec};
use crate::progress::Progress;
use crate::stamp::{self, Region, Scatter};
use crate::sweep::{self, Skin, SkinLook, Sweep};
use crate::volume::Volume;
use crate::{procedural, synth};
use std::path::Path;

/// Make one entry's volume: its source, then its steps.
pub fn make(entry: &Entry) -> Result<Volume> {
    make_with(entry, &crate::progress::NoProgress)
}

/// [`make`], reporting a synthesis' progress (per pyramid level) to `progress`, which may
/// also cancel it.
pub fn make_with(entry: &Entry, progress: &dyn Progress) -> Result<Volume> {
    let lines = &entry.lines;
    let mut volume = match &entry.source {
        Source::Procedural(recipe) => {
            let dims = entry.dims.ok_or_else(|| Error::invalid("size is missing"))?;
            procedural::generate(*recipe, dims, entry.seed)?
        }
        Source::Sweep(spec) => swept(spec, entry.dims, entry.seed, lines)?,
        Source::Synth(spec) => {
            let size = entry.dims.ok_or_else(|| Error::invalid("size is missing"))?;
            synthesized(spec, size, entry.seed, progress, lines)?
        }
        Source::Load(path) => io::read_volume(path, io::budget_from_env()?).map_err(|e| lines.error("volume", e))?,
    };
    for (k, step) in entry.steps.iter().enumerate() {
        apply(step, &mut volume, progress, (lines, k))?;
    }
    if entry.texture_type.is_some() {
        volume.meta.texture_type = entry.texture_type;
    }
    volume.meta.set("name", entry.name.clone());
    // Checked here, before any of the entry's files is written, for sizes the manifest
    // does not state (a sweep's comes from its image, a loaded volume's from its file).
    io::manifest::check_exports(&entry.exports, volume.dims())?;
    Ok(volume)
}
/// A quick, low-resolution build of exemplar `name` from manifest `text` (for the editor's
/// live preview): procedural and synthesized sizes are capped at 32 and 24 voxels, sweeps at
/// 32 voxels along their axis; an entry with steps is built at its full size, since its
/// stamps, scatters and blurs are placed in the full volume's voxels. Masks and exports
/// are not made. Returns the volume and the warnings the build gave (for a status line,
/// not stderr).
pub fn preview(manifest: &Path, name: &str, text: &str) -> Result<(Volume, Vec<String>)> {
    let folder = manifest.parent().unwrap_or(Path::new("."));
    // Mistakes in other entries do not stop this one's preview.
    let mut entry = crate::io::manifest::parse_entry(text, folder, name)?;
    entry.lines.manifest = Some(manifest.to_path_buf());
    let cap = match &mut entry.source {
        _ if !entry.steps.is_empty() => 0,
        Source::Sweep(spec) => {
            spec.length = spec.length.min(32);
            entry.dims = None;
            0
        }
        Source::Synth(_) => 24,
        _ => 32,
    };
    if cap > 0 {
        entry.dims = entry.dims.map(|d| d.map(|x| x.min(cap)));
    }
    let warnings = Warnings::default();
    let volume = make_with(&entry, &warnings)?;
    Ok((volume, warnings.0.into_inner().unwrap_or_else(|e| e.into_inner())))
}

/// Progress that keeps the warnings and ignores the rest.
#[derive(Default)]
struct Warnings(std::sync::Mutex<Vec<String>>);

impl Progress for Warnings {
    fn update(&self, _stage: &str, _fraction: f32) {}

    fn warn(&self, message: &str) {
        self.0.lock().unwrap_or_else(|e| e.into_inner()).push(message.to_string());
    }
}

fn synthesized(spec: &SynthSpec, size: [usize; 3], seed: u64, none: &dyn Progress, lines: &Lines) -> Result<Volume> {
    let read_as = |field: &str, p: &Path| io::read_image_fit(p, spec.max_exemplar).map_err(|e| lines.error(field, e));
    let ex = read_as("image", &spec.image)?;
    // layers come out crisp and labels stay labels in the coordinate core (docs/synthesis.md)
    let core = synth::Core::for_exemplars(&[&ex], spec.layered);
    let params = synth::SynthParams { core, size, levels: spec.levels, ..synth::SynthParams::default() };
    let volume = if spec.layered {
        let depth = spec.depth.as_deref().map(|p| read_as("depth_image", p)).transpose()?;
        if let (None, Some(warning)) = (&depth, synth::layering_warning(&ex)) {
            none.warn(&format!(
                "{}: {warning}. Turn the image so its rows are the layers, or give each pixel's depth (depth_image = \"...\")",
                spec.image.display()
            ));
        }
        synth::synthesize_layered(&ex, depth.as_ref(), &params, &synth::LayeredParams::default(), seed, none)
    } else {
        let ey = spec.ey.as_deref().map(|p| read_as("ey", p)).transpose()?;
        let ez = spec.ez.as_deref().map(|p| read_as("ez", p)).transpose()?;
        if let (None, None, Some(warning)) = (&ey, &ez, synth::directional_warning(&ex)) {
            none.warn(&format!(
                "{}: {warning}. Give the other cross-sections (ey = \"...\", ez = \"...\"), or recipe = \"synth-layered\" if \
                 the image is layers along its rows",
                spec.image.display()
            ));
        }
        synth::synthesize(synth::Exemplars { x: &ex, y: ey.as_ref(), z: ez.as_ref() }, &params, seed, none)
    };
    let mut volume = volume.map_err(|e| exemplar_error(spec, lines, e))?;
    if let Some(side) = spec.max_exemplar {
        // `quality` shrinks the photos alike when it is not told otherwise
        volume.meta.set(crate::volume::MAX_EXEMPLAR_KEY, side.to_string());
    }
    Ok(volume)
}

/// A synthesis error, given the manifest line and field of the exemplar it is about (Ey's or
/// Ez's when it names one, where Ez defaults to Ey and Ey to the image) and its file.
fn exemplar_error(spec: &SynthSpec, lines: &Lines, error: Error) -> Error {
    let ey = spec.ey.as_deref().map(|p| ("ey", p));
    let (field, path) = match &error {
        Error::Exemplar { which: 1, .. } => ey,
        Error::Exemplar { which: 2, .. } => spec.ez.as_deref().map(|p| ("ez", p)).or(ey),
        _ => None,
    }
    .unwrap_or(("image", &spec.image));
    lines.error(field, error.in_file(path))
}

/// The at-a-glance quality of a synthesized entry's volume against its photos (read again,
/// shrunk as for the synthesis); `None` for other recipes, or when a photo cannot be read.
pub fn glance(entry: &Entry, volume: &Volume) -> Option<crate::quality::Glance> {
    let Source::Synth(spec) = &entry.source else { return None };
    let [x, y, z] = photos(spec).ok()?;
    crate::quality::glance(volume, [Some(&x), Some(&y), (!spec.layered).then_some(&z)]).ok()
}

/// The photos of a synthesis entry for the x, y and z cuts, shrunk as for the synthesis
/// (a layered synthesis shows its one exemplar across x and y).
pub fn photos(spec: &SynthSpec) -> Result<[crate::volume::Image2d; 3]> {
    let read = |p: &Path| io::read_image_fit(p, spec.max_exemplar);
    let ex = read(&spec.image)?;
    let ey = match (&spec.ey, spec.layered) {
        (Some(p), false) => read(p)?,
        _ => ex.clone(),
    };
    let ez = match (&spec.ez, spec.layered) {
        (Some(p), false) => read(p)?,
        _ => ey.clone(),
    };
    Ok([ex, ey, ez])
}

/// An entry's masks, made before any of its files is written (a mask that cannot be made
/// fails the entry with the earlier build's files as they were).
pub struct Masks {
    splotch: Option<Volume>,
    layers: Option<Vec<(crate::mask::Layer, Volume)>>,
}

/// Make the masks `entry` asks for, at the size of its `volume`.
pub fn masks(entry: &Entry, volume: &Volume) -> Result<Masks> {
    let size = *volume.dims().iter().max().expect("three dims");
    let mut out = Masks { splotch: None, layers: None };
    for kind in &entry.masks {
        match kind {
            MaskKind::Splotch => out.splotch = Some(crate::mask::splotch(size, entry.mask_falloff, entry.seed)?),
            MaskKind::Layered => {
                let depth = depth_axis(entry);
                let layers = crate::mask::Layer::ALL
                    .iter()
                    .map(|l| Ok((*l, crate::mask::layered(size, entry.mask_falloff, entry.seed, *l, depth)?)))
                    .collect::<Result<_>>()?;
                out.layers = Some(layers);
            }
        }
    }
    Ok(out)
}

/// Write the extra formats and the `masks` beside the volume.
pub fn write_extras(entry: &Entry, volume: &Volume, masks: &Masks, output: &Path) -> Result<()> {
    let name = &entry.name;
    for export in &entry.exports {
        io::write_volume(&files::export(output, name, export), volume)?;
    }
    if let Some(m) = &masks.splotch {
        io::write_volume(&files::splotch_mask(output, name), m)?;
    }
    if let Some(layers) = &masks.layers {
        io::write_folder(&files::layer_folder(output, name), |dir| {
            for (l, m) in layers {
                io::write_volume(&dir.join(files::layer_file(*l)), m)?;
            }
            Ok(())
        })?;
    }
    Ok(())
}

/// The depth axis of an entry: the sweep's, else z.
fn depth_axis(entry: &Entry) -> crate::volume::Axis {
    match &entry.source {
        Source::Sweep(spec) => spec.depth_axis.unwrap_or(crate::volume::Axis::Z),
        _ => crate::volume::Axis::Z,
    }
}

fn swept(spec: &SweepSpec, dims: Option<[usize; 3]>, seed: u64, lines: &Lines) -> Result<Volume> {
    let image = io::read_image(&spec.image).map_err(|e| lines.error("image", e))?;
    let (a, b) = spec.axis.plane_axes();
    if let Some(d) = dims {
        let along = d[spec.axis.index()];
        if (d[a], d[b], along) != (image.width(), image.height(), spec.length) {
            return Err(lines.error("size", Error::file(
                &spec.image,
                format!(
                    "the sweep image is {}x{} pixels, which with length {} along {} makes {:?}, not the size {d:?} asked for",
                    image.width(),
                    image.height(),
                    spec.length,
                    spec.axis,
                    planned(image.width(), image.height(), spec)
                ),
            )));
        }
    }
    let skin = match &spec.skin {
        None => None,
        Some((look, width, noise)) => {
            let look = match look {
                SkinSource::Colour(c) => SkinLook::Colour(*c),
                SkinSource::Image(p) => SkinLook::Image(io::read_image(p).map_err(|e| lines.error("skin", e))?),
            };
            Some(Skin { look, width: *width, width_noise: *noise })
        }
    };
    let relief = |p: &Path| io::read_image(p).map_err(|e| lines.error("displacement", e));
    let displacement = spec.displacement.as_deref().map(relief).transpose()?;
    if let (Some(relief), Some(path)) = (&displacement, &spec.displacement)
        && (relief.width(), relief.height()) != (image.width(), image.height())
    {
        let message = format!(
            "the displacement image is {}x{} but the cross-section {} is {}x{}; they must be the same size",
            relief.width(),
            relief.height(),
            spec.image.display(),
            image.width(),
            image.height()
        );
        return Err(lines.error("displacement", Error::file(path, message)));
    }
    let params = Sweep {
        length: spec.length,
        axis: spec.axis,
        depth_axis: spec.depth_axis,
        noise: spec.noise,
        skin,
        displacement,
    };
    if let (Some(skin), Some((SkinSource::Image(path), ..))) = (&params.skin, &spec.skin) {
        sweep::check_skin(&image, skin).map_err(|e| e.in_file(path))?;
    }
    sweep::sweep(&image, &params, seed).map_err(|e| e.in_file(&spec.image))
}

fn planned(w: usize, h: usize, spec: &SweepSpec) -> [usize; 3] {
    let (a, b) = spec.axis.plane_axes();
    let mut d = [0; 3];
    d[a] = w;
    d[b] = h;
    d[spec.axis.index()] = spec.length;
    d
}

/// A seed mesh, oriented; degenerate triangles dropped and an open mesh are reported as
/// warnings to `progress`.
pub fn read_seed(path: &Path, progress: &dyn Progress) -> Result<crate::mesh::Mesh> {
    let mesh = io::mesh_file::read_mesh(path)?;
    let dropped = mesh.dropped_degenerate();
    if dropped > 0 {
        progress.warn(&format!(
            "{}: dropped {dropped} degenerate triangle(s) (zero area or a repeated corner)",
            path.display()
        ));
    }
    let open = mesh.boundary_edges();
    if open > 0 {
        progress.warn(&format!(
            "{}: the mesh has {open} boundary edge(s) (open or non-manifold); inside is decided by winding number",
            path.display()
        ));
    }
    Ok(mesh.oriented())
}

/// Apply step `k` of an entry written at `lines`.
fn apply(step: &Step, volume: &mut Volume, progress: &dyn Progress, (lines, k): (&Lines, usize)) -> Result<()> {
    match step {
        Step::Stamp { mesh, placement, colour } => {
            let seed = read_seed(mesh, progress).map_err(|e| lines.error(&format!("steps[{k}].stamp"), e))?;
            stamp::stamp(volume, &seed, placement, *colour).map_err(|e| e.in_file(mesh))?;
        }
        Step::Scatter { mesh, count, region, scale, colour, seed } => {
            let shape = read_seed(mesh, progress).map_err(|e| lines.error(&format!("steps[{k}].scatter"), e))?;
            let d = volume.dims();
            let region =
                region.unwrap_or(Region::Box(glam::Vec3::ZERO, glam::Vec3::new(d[0] as f32, d[1] as f32, d[2] as f32)));
            let params = Scatter { count: *count, region, scale: *scale, colour: *colour, attempts: 200 };
            stamp::check_region_fits(volume, region)?;
            let done = stamp::scatter(volume, &shape, &params, *seed).map_err(|e| e.in_file(mesh))?;
            if done.too_small > 0 {
                progress.warn(&format!(
                    "{} of {count} seeds from {} were smaller than a voxel and changed nothing; a larger scale \
                     places them",
                    done.too_small,
                    mesh.display()
                ));
            }
            if done.placed.len() + done.too_small < *count {
                progress.warn(&format!(
                    "placed {} of {count} seeds from {}: no room for the rest",
                    done.placed.len(),
                    mesh.display()
                ));
            }
        }
        Step::Blur { at, radius, strength } => {
            stamp::blur(volume, *at, *radius, *strength)?;
        }
    }
    Ok(())
}
