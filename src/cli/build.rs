//! `solidtex build`: make every exemplar a manifest lists, each into `DIR/NAME.exr` and a
//! contact sheet `DIR/NAME.sheet.png`.

use crate::error::{Error, Result};
use crate::io;
use crate::io::manifest::{self, Entry, SkinSource, Source, Step, SweepSpec};
use crate::stamp::{self, Region, Scatter};
use crate::sweep::{self, Skin, SkinLook, Sweep};
use crate::volume::Volume;
use crate::{procedural, render};
use std::path::Path;
use std::time::Instant;

/// Build every entry of the manifest at `manifest_path` into `output`.
pub fn run(manifest_path: &Path, output: &Path) -> Result<()> {
    let plan = manifest::read_plan(manifest_path)?;
    std::fs::create_dir_all(output).map_err(|e| Error::io(output, e))?;
    let total = plan.entries.len();
    for (k, entry) in plan.entries.iter().enumerate() {
        let started = Instant::now();
        let volume = make(entry).map_err(|e| match e {
            Error::Invalid(m) => Error::file(manifest_path, format!("exemplar {}: {m}", entry.name)),
            other => other,
        })?;
        let file = output.join(format!("{}.exr", entry.name));
        io::write_volume(&file, &volume)?;
        io::write_rgb8(&output.join(format!("{}.sheet.png", entry.name)), &render::sheet(&volume, &entry.name))?;
        let [x, y, z] = volume.dims();
        let kind = volume.meta.texture_type.map(|t| format!("type {t}")).unwrap_or_default();
        eprintln!("[{}/{total}] {} {x}x{y}x{z} {kind} in {:.2} s", k + 1, entry.name, started.elapsed().as_secs_f64());
    }
    eprintln!("built {total} exemplar(s) into {}", output.display());
    Ok(())
}

/// Make one entry's volume: its source, then its steps.
pub fn make(entry: &Entry) -> Result<Volume> {
    let mut volume = match &entry.source {
        Source::Procedural(recipe) => {
            let dims = entry.dims.ok_or_else(|| Error::invalid("size is missing"))?;
            procedural::generate(*recipe, dims, entry.seed)?
        }
        Source::Sweep(spec) => swept(spec, entry.dims, entry.seed)?,
    };
    for step in &entry.steps {
        apply(step, &mut volume)?;
    }
    if entry.texture_type.is_some() {
        volume.meta.texture_type = entry.texture_type;
    }
    volume.meta.set("name", entry.name.clone());
    Ok(volume)
}

fn swept(spec: &SweepSpec, dims: Option<[usize; 3]>, seed: u64) -> Result<Volume> {
    let image = io::read_image(&spec.image)?;
    let (a, b) = spec.axis.plane_axes();
    if let Some(d) = dims {
        let along = d[spec.axis.index()];
        if (d[a], d[b], along) != (image.width(), image.height(), spec.length) {
            return Err(Error::file(
                &spec.image,
                format!(
                    "the sweep image is {}x{} pixels, which with length {} along {} makes {:?}, not the size {d:?} asked for",
                    image.width(),
                    image.height(),
                    spec.length,
                    spec.axis,
                    planned(image.width(), image.height(), spec)
                ),
            ));
        }
    }
    let skin = match &spec.skin {
        None => None,
        Some((look, width, noise)) => {
            let look = match look {
                SkinSource::Colour(c) => SkinLook::Colour(*c),
                SkinSource::Image(p) => SkinLook::Image(io::read_image(p)?),
            };
            Some(Skin { look, width: *width, width_noise: *noise })
        }
    };
    let params = Sweep { length: spec.length, axis: spec.axis, depth_axis: spec.depth_axis, noise: spec.noise, skin };
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

fn apply(step: &Step, volume: &mut Volume) -> Result<()> {
    match step {
        Step::Stamp { mesh, placement, colour } => {
            let seed = super::handmade::read_seed(mesh)?;
            stamp::stamp(volume, &seed, placement, *colour).map_err(|e| e.in_file(mesh))?;
        }
        Step::Scatter { mesh, count, region, scale, colour, seed } => {
            let shape = super::handmade::read_seed(mesh)?;
            let d = volume.dims();
            let region =
                region.unwrap_or(Region::Box(glam::Vec3::ZERO, glam::Vec3::new(d[0] as f32, d[1] as f32, d[2] as f32)));
            let params = Scatter { count: *count, region, scale: *scale, colour: *colour, attempts: 200 };
            let done = stamp::scatter(volume, &shape, &params, *seed).map_err(|e| e.in_file(mesh))?;
            if done.placed.len() < *count {
                eprintln!(
                    "warning: placed {} of {count} seeds from {}: no room for the rest",
                    done.placed.len(),
                    mesh.display()
                );
            }
        }
        Step::Blur { at, radius, strength } => {
            stamp::blur(volume, *at, *radius, *strength)?;
        }
    }
    Ok(())
}
