//! The file-to-file subcommands: convert, slice, sheet, make, build.

use crate::error::{Error, Result};
use crate::io;
use crate::procedural::{self, Recipe};
use crate::render::{self, ColourMap};
use crate::volume::{Axis, Volume};
use std::path::Path;

fn load(path: &Path) -> Result<Volume> {
    io::read_volume(path, io::budget_from_env()?)
}

/// Largest side of a volume asked for with `--size`, as in a manifest (the voxel budget
/// may allow less).
pub const MAX_SIDE: usize = io::manifest::MAX_SIDE;

/// A value error of the command line as a usage error (exit code 2); other errors unchanged.
pub fn usage(error: Error) -> Error {
    match error {
        Error::Invalid(message) => Error::Usage(message),
        other => other,
    }
}

/// `solidtex convert IN OUT [--dds-format F]`.
pub fn convert(input: &Path, output: &Path, dds_format: Option<&str>) -> Result<()> {
    let format = dds_format.map(io::dds::DdsFormat::parse).transpose().map_err(usage)?;
    if format.is_some() && io::Format::of(output)? != io::Format::Dds {
        return Err(Error::usage("--dds-format applies to a .dds output only"));
    }
    io::check_output(output, &[input])?;
    let volume = load(input)?;
    match format {
        Some(format) => {
            io::dds::write(output, &volume, format)?;
            if let Some(note) = io::model_grid_lost(output, &volume) {
                tell!("warning: {note}");
            }
        }
        None => super::write_volume(output, &volume)?,
    }
    tell!("wrote {}", output.display());
    Ok(())
}

/// `solidtex flipbook FILE -o OUT.png [--columns C] [--rows R] [--padding P] [--pow2]`.
pub fn flipbook(
    file: &Path,
    output: &Path,
    columns: Option<usize>,
    rows: Option<usize>,
    padding: usize,
    pow2: bool,
) -> Result<()> {
    io::guard::png_output(output, &[file])?;
    let sidecar = output.with_extension("json");
    io::guard::not_an_input(&sidecar, &[file])?;
    if sidecar.is_dir() {
        return Err(Error::file(&sidecar, "is a folder; the flipbook's layout is written there"));
    }
    io::guard::side_file(&sidecar, "the flipbook's layout goes there: move that file away or name another flipbook")?;
    let volume = load(file)?;
    let layout = io::flipbook::Layout::new(volume.dims(), columns, rows, padding, pow2).map_err(usage)?;
    let samples = io::flipbook::flipbook(&volume, &layout);
    let image =
        crate::volume::Image2d::from_data(layout.width, layout.height, crate::volume::Channel::rgba(), samples)?;
    io::write_image(output, &image)?;
    let name = output.file_name().map(|n| n.to_string_lossy().into_owned()).unwrap_or_default();
    io::write_bytes(&sidecar, io::flipbook::sidecar(&layout, &name).as_bytes())?;
    tell!(
        "wrote {} ({}x{} pixels, {} columns x {} rows) and {}",
        output.display(),
        layout.width,
        layout.height,
        layout.columns,
        layout.rows,
        sidecar.display()
    );
    Ok(())
}

/// `solidtex slice FILE --axis A --index N -o out.png`.
pub fn slice(file: &Path, axis: &str, index: Option<usize>, output: &Path) -> Result<()> {
    let axis: Axis = axis.parse().map_err(usage)?;
    io::guard::png_output(output, &[file])?;
    let volume = load(file)?;
    let index = index.unwrap_or(volume.dims()[axis.index()] / 2);
    let image = volume.slice(axis, index).map_err(|e| e.in_file(file))?;
    let picture = render::picture(&image, ColourMap::for_channels(image.channels()), 1);
    io::write_rgb8(output, &picture)?;
    tell!("wrote {} ({axis} = {index})", output.display());
    Ok(())
}

/// `solidtex slice FILE --plane PX,PY,PZ,NX,NY,NZ -o out.png`: an oblique cut through P
/// with normal N, as wide as the volume's longest side; the volume repeats past its faces.
pub fn oblique_slice(file: &Path, plane: &str, output: &Path) -> Result<()> {
    let numbers = parse_plane(plane)?;
    io::guard::png_output(output, &[file])?;
    let volume = load(file)?;
    let side = volume.dims().into_iter().max().unwrap_or(1);
    crate::volume::check_size([side, side, 1], volume.channel_count(), io::budget_from_env()?).map_err(|e| {
        Error::invalid(format!(
            "{}: an oblique cut {side} pixels wide (its longest side) does not fit: {e}",
            file.display()
        ))
    })?;
    let (point, normal) = (glam::Vec3::from_slice(&numbers[..3]), glam::Vec3::from_slice(&numbers[3..]));
    let cut = crate::volume::Plane::through(point, normal, side).map_err(usage)?;
    let image = volume.plane_slice(&cut, side, side, crate::volume::Edge::Wrap)?;
    let picture = render::picture(&image, ColourMap::for_channels(image.channels()), 1);
    io::write_rgb8(output, &picture)?;
    tell!("wrote {} ({side}x{side}, through {point} with normal {})", output.display(), normal.normalize());
    Ok(())
}

/// `PX,PY,PZ,NX,NY,NZ`: six finite numbers, the normal not zero (usage errors).
fn parse_plane(text: &str) -> Result<[f32; 6]> {
    let bad = || {
        Error::usage(format!(
            "--plane {text:?}: give six numbers PX,PY,PZ,NX,NY,NZ (a point in voxels and a normal, e.g. 32,32,32,1,1,0)"
        ))
    };
    let values: Vec<f32> =
        text.split(',').map(|v| v.trim().parse::<f32>()).collect::<std::result::Result<_, _>>().map_err(|_| bad())?;
    let numbers: [f32; 6] = values.try_into().map_err(|_| bad())?;
    if numbers.iter().any(|v| !v.is_finite()) {
        return Err(bad());
    }
    io::values::positions("--plane", text, &numbers).map_err(usage)?;
    if numbers[3..].iter().all(|v| *v == 0.0) {
        return Err(Error::usage(format!("--plane {text:?}: the normal NX,NY,NZ must not be zero")));
    }
    Ok(numbers)
}

/// `solidtex sheet FILE -o sheet.png`.
pub fn sheet(file: &Path, output: &Path, title: Option<String>) -> Result<()> {
    io::guard::png_output(output, &[file])?;
    let volume = load(file)?;
    let title = title.unwrap_or_else(|| file.file_name().map(|n| n.to_string_lossy().into_owned()).unwrap_or_default());
    io::write_rgb8(output, &render::sheet(&volume, &title))?;
    tell!("wrote {}", output.display());
    Ok(())
}

/// `solidtex make RECIPE --size N --seed S -o out.exr`.
pub fn make(recipe: &str, size: &str, seed: u64, output: &Path) -> Result<()> {
    let recipe: Recipe = recipe.parse().map_err(usage)?;
    let dims = parse_size(size)?;
    let (channels, budget) = (recipe.channels().len(), io::budget_from_env()?);
    let samples = crate::volume::check_size(dims, channels, budget).map_err(usage)?;
    // a writer holds a copy of the samples in its file's layout (an EXR its atlas) beside
    // the volume: both must fit, or the allocation aborts past the budget's reserve
    let bytes = samples as u128 * 4;
    if bytes * 2 > u128::from(budget) {
        let [x, y, z] = dims;
        return Err(Error::invalid(format!(
            "a {x}x{y}x{z} volume with {channels} channel(s) needs {bytes} bytes, and writing it a copy as large: {} \
             bytes in all, over the voxel budget of {budget} bytes (raise it with SOLIDTEX_MAX_BYTES or choose \
             smaller dims)",
            bytes * 2
        )));
    }
    io::check_output(output, &[])?;
    let bar = super::fill::Bar::new();
    let volume = procedural::generate_with(recipe, dims, seed, &bar);
    bar.0.finish_and_clear();
    let volume = volume?;
    super::write_volume(output, &volume)?;
    tell!("wrote {}", output.display());
    Ok(())
}

/// `64` or `64x64x32` as dims, each side 1 to [`MAX_SIDE`]; errors are usage errors.
pub fn parse_size(text: &str) -> Result<[usize; 3]> {
    let dims = match text.parse::<usize>() {
        Ok(n) => [n; 3],
        Err(_) if super::all_digits(text) => {
            return Err(Error::usage(format!("--size {text} is too large; allowed: each side at most {MAX_SIDE}")));
        }
        Err(_) => io::parse_dims(text)
            .map_err(|_| Error::usage(format!("--size {text:?} is not N or XxYxZ (for example 64 or 64x64x32)")))?,
    };
    if dims.iter().any(|d| !(1..=MAX_SIDE).contains(d)) {
        return Err(Error::usage(format!(
            "--size {text:?} is out of range; allowed: each side at least 1 and at most {MAX_SIDE}, within the \
             voxel budget"
        )));
    }
    Ok(dims)
}
