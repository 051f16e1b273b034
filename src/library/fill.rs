//! The exemplars a fill spec names, resolved from a built library: the texture type and
//! axes, one source per layer or paste with its mask, and the fill preview both front ends
//! show.

use super::build::{self, Observer, Outcome, Request};
use super::files;
use crate::TextureType;
use crate::error::{Error, Result};
use crate::fill::render::Textures;
use crate::fill::spec::{self, FillSpec};
use crate::fill::{self, FillPreview, Job, MaskRef, Source};
use crate::io::{self, manifest};
use crate::mask::Layer;
use crate::volume::{Axis, Volume};
use std::path::Path;
use std::time::Instant;

/// The spec's exemplars turned into a type, texture axes, sources and masks.
pub struct Resolved {
    /// The texture type of the main exemplar.
    pub kind: TextureType,
    /// Which volume axis each texture axis is.
    pub axes: [usize; 3],
    /// One source per layer of the main exemplar, then one per paste.
    pub sources: Vec<Source>,
    /// The mask of each source.
    pub masks: Vec<Volume>,
}

/// The exemplars a fill spec uses (the main one, then its pastes).
pub fn names(spec: &FillSpec) -> Vec<String> {
    let mut names = vec![spec.exemplar.clone()];
    names.extend(spec.pastes.iter().map(|p| p.exemplar.clone()));
    names
}

/// The exemplars of guided synthesis by regions: each `[[region]]`'s, in order.
pub fn region_names(spec: &FillSpec) -> Vec<String> {
    spec.regions.iter().map(|r| r.exemplar.clone()).collect()
}

/// Of the exemplars `names` of `spec`'s library, those whose volumes are not built yet; an
/// error if the library has no entry of one of them.
pub fn missing(spec: &FillSpec, names: &[String]) -> Result<Vec<String>> {
    check_names(spec, &manifest::read_plan(&spec.library)?, names)?;
    Ok(names.iter().filter(|n| !files::volume(&spec.built, n).exists()).cloned().collect())
}

fn check_names(spec: &FillSpec, plan: &manifest::Plan, names: &[String]) -> Result<()> {
    for name in names {
        if !plan.entries.iter().any(|e| &e.name == name) {
            let known: Vec<&str> = plan.entries.iter().map(|e| e.name.as_str()).collect();
            return Err(Error::invalid(format!(
                "exemplar '{name}' is not in the library {}; it has: {}",
                spec.library.display(),
                known.join(", ")
            )));
        }
    }
    Ok(())
}

/// Build (cached) the exemplars `names` of the spec's library. While another build holds
/// the built folder, wait for it (up to [`build::LOCK_WAIT`]; `waiting` is called when the
/// wait starts): it may be building the same exemplars.
pub fn build_first(spec: &FillSpec, names: Vec<String>, observer: &dyn Observer, waiting: &dyn Fn()) -> Result<()> {
    let request =
        Request { manifest: spec.library.clone(), output: spec.built.clone(), force: false, only: names, shard: None };
    let entries = build::select(&request)?;
    let outcomes = build::build_when_free(&request, &entries, observer, (build::LOCK_WAIT, waiting))?;
    match outcomes.iter().find(|o| !matches!(o, Outcome::Built(_) | Outcome::Cached(_))) {
        Some(Outcome::Failed(name, why)) => Err(Error::invalid(format!("building exemplar '{name}' failed: {why}"))),
        Some(_) => Err(Error::Cancelled),
        None => Ok(()),
    }
}

/// Resolve a spec whose exemplars are built; `model_path` is where the model will be
/// written (its sources name files relative to it).
pub fn resolve(spec: &FillSpec, model_path: &Path) -> Result<Resolved> {
    let plan = manifest::read_plan(&spec.library)?;
    check_names(spec, &plan, &names(spec))?;
    let entry = plan.entries.iter().find(|e| e.name == spec.exemplar).expect("checked above");
    let volume = load_built(spec, &spec.exemplar)?;
    let declared = entry.texture_type.or(volume.meta.texture_type);
    let kind = match (spec.texture_type, declared) {
        (Some(t), _) | (None, Some(t)) => t,
        (None, None) => crate::classify::classify(&volume)?.texture_type,
    };
    let axes = spec::texture_axes(&volume, kind, spec.axes)?;
    let size = *volume.dims().iter().max().expect("three dims");
    let base = model_path.parent().unwrap_or(Path::new("."));
    let mut sources = Vec::new();
    let layered = matches!(kind, TextureType::T1b | TextureType::T2b);
    let layers: &[Option<Layer>] =
        if layered { &[Some(Layer::Outer), Some(Layer::Middle), Some(Layer::Inner)] } else { &[None] };
    for layer in layers {
        sources.push(source(spec, &spec.exemplar, *layer, Axis::ALL[axes[0]], size, base));
    }
    for p in &spec.pastes {
        let v = load_built(spec, &p.exemplar)?;
        sources.push(source(spec, &p.exemplar, None, Axis::Z, *v.dims().iter().max().expect("dims"), base));
    }
    let masks = sources.iter().map(|s| load_mask(&s.mask, base)).collect::<Result<Vec<_>>>()?;
    Ok(Resolved { kind, axes, sources, masks })
}

/// The built volume of exemplar `name`.
pub fn load_built(spec: &FillSpec, name: &str) -> Result<Volume> {
    io::read_volume(&files::volume(&spec.built, name), io::budget_from_env()?)
}

fn source(spec: &FillSpec, name: &str, layer: Option<Layer>, depth: Axis, size: usize, base: &Path) -> Source {
    let file = match layer {
        Some(l) => files::layer_mask(&spec.built, name, l),
        None => files::splotch_mask(&spec.built, name),
    };
    let (falloff, seed) = (spec.mask_falloff.unwrap_or(crate::mask::DEFAULT_FALLOFF), spec.seed);
    let mask = match layer {
        _ if file.exists() => MaskRef::File(io::written_relative(&file, base)),
        Some(layer) => MaskRef::Layered { layer, depth, size, falloff, seed },
        None => MaskRef::Splotch { size, falloff, seed },
    };
    Source { exemplar: name.to_string(), volume: io::written_relative(&files::volume(&spec.built, name), base), mask }
}

/// A source's mask: generated from its parameters, or read from its file (relative to `base`).
pub fn load_mask(mask: &MaskRef, base: &Path) -> Result<Volume> {
    match (mask.generate(), mask) {
        (Some(generated), _) => generated,
        (None, MaskRef::File(path)) => io::read_volume(&base.join(path), io::budget_from_env()?),
        (None, _) => unreachable!("only files are not generated"),
    }
}

/// The spec and drawn shape of the fill preview of built exemplar `name` of the library
/// `manifest` (built into `output`): a block for type 1-a, a fruit otherwise, with its axis
/// as the core (tapered toward the ends) and the stroke; 2500 tets.
pub fn preview_spec(manifest: &Path, output: &Path, name: &str) -> Result<(FillSpec, &'static str)> {
    let mut spec = FillSpec::new(name);
    spec.library = manifest.to_path_buf();
    spec.built = output.to_path_buf();
    spec.tets = 2500;
    let probe = resolve(&spec, &output.join("preview.lst"))?;
    let (shape, axis) = match probe.kind {
        TextureType::T1a => ("block", vec![glam::Vec3::new(-0.9, 0.0, 0.0), glam::Vec3::new(0.9, 0.0, 0.0)]),
        _ => ("fruit", vec![glam::Vec3::new(-0.75, 0.0, 0.0), glam::Vec3::new(0.75, 0.0, 0.0)]),
    };
    if matches!(probe.kind, TextureType::T1b | TextureType::T2a | TextureType::T2b) {
        spec.depth.axes = vec![axis.clone()];
        // the fruit's core closes toward its ends, as the repository's kiwi spec does
        spec.depth.taper = if shape == "fruit" { 0.5 } else { 0.0 };
    }
    spec.directions = vec![axis];
    Ok((spec, shape))
}

/// A small fill of a drawn shape with the default spec of [`preview_spec`]. Nothing is
/// written; `progress` may cancel it.
pub fn preview(
    manifest: &Path,
    output: &Path,
    name: &str,
    progress: &dyn crate::progress::Progress,
) -> Result<FillPreview> {
    let (spec, shape) = preview_spec(manifest, output, name)?;
    preview_with(&spec, shape, progress)
}

/// A fill of the drawn shape `shape` by `spec` (its exemplars built). Nothing is written.
pub fn preview_with(spec: &FillSpec, shape: &str, progress: &dyn crate::progress::Progress) -> Result<FillPreview> {
    let started = Instant::now();
    let probe = resolve(spec, &spec.built.join("preview.lst"))?;
    let surface = crate::mesh::shapes::named(shape)
        .ok_or_else(|| Error::invalid(format!("no drawn shape named {shape}")))?
        .canonical();
    let (tets, _) = fill::tetrahedralize(&surface, spec, fill::uses_depth(probe.kind))?;
    let job = Job {
        surface: &surface,
        spec,
        kind: probe.kind,
        axes: probe.axes,
        sources: probe.sources.clone(),
        masks: probe.masks.clone(),
    };
    let (model, report) = fill::fill(&job, tets, progress)?;
    let colour = probe.sources.iter().map(|s| load_built(spec, &s.exemplar)).collect::<Result<Vec<_>>>()?;
    let textures = Textures::new(&colour, &probe.masks);
    let summary = format!(
        "{} (type {}) in a {shape}: {} tets, {} patches, {:.2} s",
        spec.exemplar,
        probe.kind,
        report.tets,
        report.paste.patches,
        started.elapsed().as_secs_f64()
    );
    Ok(FillPreview {
        model,
        textures,
        summary,
        depth: report.depth,
        spec: spec.clone(),
        shape: shape.to_string(),
        kind: probe.kind,
    })
}
