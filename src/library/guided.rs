//! Sketch-guided synthesis on a fill preview (the TUI's fill editor): the frame field the
//! spec's strokes and depth give, drawn as streamlines on the preview's cut, and a guided
//! cut synthesized along it: from the exemplar volume itself as a solid exemplar, or from
//! its central slices (layered, with the spec's depth, when the exemplar has a Depth
//! channel; or when the volume is not a cube).

use super::fill::load_built;
use crate::error::{Error, Result};
use crate::fill::FillPreview;
use crate::fill::render::View;
use crate::fill::spec::FillSpec;
use crate::guided::field::{FrameField, FrameGrid, ScalarGrid, sketched_frames, solve, streamlines};
use crate::guided::regions::Regions;
use crate::guided::solid::{self, Domain};
use crate::mesh::Mesh;
use crate::progress::Progress;
use crate::synth::coords::{Exemplars, Options, SECTION_DEPTH_SHARE, Setup};
use crate::synth::cube::{self, Cube};
use crate::volume::{Axis, Channel, Image2d, Volume};
use glam::Vec3;

/// What a picture over the preview's cut shows.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Overlay {
    /// The frame field's streamlines.
    Field,
    /// A cut of the solid synthesized along the field.
    Guided,
}

/// Voxels along the guided grid's longest side: a quick look, not the final solid.
pub const GUIDED_RES: usize = 96;

/// A square picture over the cut: `None` outside the model.
#[derive(Debug, Clone, PartialEq)]
pub struct Picture {
    /// Side in pixels.
    pub size: usize,
    /// Row-major colours.
    pub pixels: Vec<Option<[u8; 3]>>,
}

/// What a spec gives over a fill preview: the drawn shape it fills, the frame field of the
/// spec's strokes and depth (as `solidtex field` reads them) over the preview's tet mesh,
/// and the depth constraints.
struct Guide {
    surface: Mesh,
    field: FrameField,
    depths: Vec<(Vec3, f32)>,
}

fn field_of(filled: &FillPreview, spec: &FillSpec) -> Result<Guide> {
    let surface = crate::mesh::shapes::named(&filled.shape)
        .ok_or_else(|| Error::invalid(format!("no drawn shape named {}", filled.shape)))?
        .canonical();
    let constraints = crate::fill::spec::constraints(spec, &surface, 1.0)?;
    let frames = sketched_frames(&constraints.directions, &constraints.depth)?;
    let field = solve(&filled.model.mesh, &frames)?;
    Ok(Guide { surface, field, depths: constraints.depth })
}

/// The `overlay` picture of `spec` on the preview's cut `view` (a square view).
pub fn picture(
    filled: &FillPreview,
    spec: &FillSpec,
    overlay: Overlay,
    view: &View,
    progress: &dyn Progress,
) -> Result<Picture> {
    let Guide { surface, field, depths } = field_of(filled, spec)?;
    let mesh = &filled.model.mesh;
    // the outline is the model's input surface cut by the plane, as the fill's cut shows it
    let inside = crate::fill::render::inside_surface(&filled.model.surface, view);
    let pixels = match overlay {
        Overlay::Field => {
            let lines = streamlines(mesh, &field, view, &inside);
            lines.data.chunks_exact(3).zip(&inside).map(|(p, i)| i.then(|| [p[0], p[1], p[2]])).collect()
        }
        Overlay::Guided if !spec.regions.is_empty() => {
            let domain = Domain::around(surface.bounds(), GUIDED_RES)?;
            let depth = solid::depth_over(&depths, &domain)?;
            let made = region_exemplars(spec, &depths, &domain)?;
            let frames = solid::frames_over(mesh, &field, &domain, &depths, &spec.depth.axes)?;
            let parts = region_setups(&made, &frames, domain.dims, spec.seed);
            let regions = region_blend(spec);
            let weight = |k: usize, v: [usize; 3]| regions.weight(k, solid::grid_at(&depth, v));
            let (cut, _) = solid::cut_blend(&parts, &weight, &domain, &filled.model.surface, view, progress)?;
            shown_pixels(&cut)
        }
        Overlay::Guided => {
            let volume = load_built(spec, &spec.exemplar)?;
            let domain = Domain::around(surface.bounds(), GUIDED_RES)?;
            let (exemplars, options, depth) = volume_exemplars(&volume, spec.axes, &depths, &domain)?;
            let frames = solid::frames_over(mesh, &field, &domain, &depths, &spec.depth.axes)?;
            let setup = Setup {
                exemplars: &exemplars,
                frames: Some(&frames),
                wrap: [false; 3],
                depth: depth.as_ref(),
                dims: domain.dims,
                seed: spec.seed,
                options,
            };
            let (cut, _) = solid::cut(&setup, &domain, &filled.model.surface, view, &[], progress)?;
            shown_pixels(&cut)
        }
    };
    Ok(Picture { size: view.width, pixels })
}

/// A cut's pixels as bytes (grey on all three), `None` where it is transparent.
fn shown_pixels(cut: &Image2d) -> Vec<Option<[u8; 3]>> {
    let grey = cut.channel_count() < 4;
    cut.data()
        .chunks_exact(cut.channel_count())
        .map(|p| {
            let byte = |v: f32| (v.clamp(0.0, 1.0) * 255.0).round() as u8;
            let alpha = p[p.len() - 1];
            (alpha > 0.0).then(|| if grey { [byte(p[0]); 3] } else { [byte(p[0]), byte(p[1]), byte(p[2])] })
        })
        .collect()
}

/// The exemplars of the spec's `[[region]]` entries, in order ([`volume_exemplars`] of
/// their built volumes, which must exist).
pub fn region_exemplars(
    spec: &FillSpec,
    depths: &[(Vec3, f32)],
    domain: &Domain,
) -> Result<Vec<(Exemplars, Options, Option<ScalarGrid>)>> {
    let each = |(i, region): (usize, &crate::fill::spec::RegionSpec)| {
        let volume = load_built(spec, &region.exemplar)?;
        volume_exemplars(&volume, spec.axes, depths, domain)
            .map_err(|e| Error::invalid(format!("region[{i}] (exemplar '{}'): {e}", region.exemplar)))
    };
    spec.regions.iter().enumerate().map(each).collect()
}

/// One synthesis setup per region's exemplars (`made`, [`region_exemplars`]) over a grid
/// of `dims` along `frames`, each with its own settings.
pub fn region_setups<'a>(
    made: &'a [(Exemplars, Options, Option<ScalarGrid>)],
    frames: &'a FrameGrid,
    dims: [usize; 3],
    seed: u64,
) -> Vec<Setup<'a>> {
    made.iter()
        .map(|(exemplars, options, layered)| Setup {
            exemplars,
            frames: Some(frames),
            wrap: [false; 3],
            depth: layered.as_ref(),
            dims,
            seed,
            options: *options,
        })
        .collect()
}

/// How the spec's regions blend by depth.
pub fn region_blend(spec: &FillSpec) -> Regions {
    let ranges: Vec<[f32; 2]> = spec.regions.iter().map(|r| r.depth).collect();
    Regions::new(&ranges, spec.region_band)
}

/// A built exemplar volume ready to follow along a field over `domain`: with a Depth
/// channel and a spec whose depth (`depths`) rises inside the model, its layers fitted to
/// the voxels the depth spans ([`layered_slices`]); else the volume itself as a solid
/// exemplar, or its central slices ([`plain_exemplars`]). Also the settings, and the
/// model's depth when layered.
pub fn volume_exemplars(
    volume: &Volume,
    given: Option<[Axis; 2]>,
    depths: &[(Vec3, f32)],
    domain: &Domain,
) -> Result<(Exemplars, Options, Option<ScalarGrid>)> {
    match layered_slices(volume, given, depths, domain)? {
        Some((planes, depth)) => {
            let options = section_options(&planes, volume);
            Ok((Exemplars::prepare([&planes[0], &planes[1], &planes[2]], &options)?, options, Some(depth)))
        }
        None => {
            let (exemplars, options) = plain_exemplars(volume)?;
            Ok((exemplars, options, None))
        }
    }
}

/// The exemplars of a volume without layers: the volume itself as the solid exemplar when
/// it is a cube that halves evenly down to the coarsest level, else its central slices.
fn plain_exemplars(volume: &Volume) -> Result<(Exemplars, Options)> {
    let options = Options::for_exemplar(volume.dims()[0]);
    let keep = colour_channels(volume);
    if let Ok(cube) = Cube::new(volume, &keep, options.levels, cube::SMALLEST) {
        let names = [Channel::R, Channel::G, Channel::B][..keep.len()].to_vec();
        return Ok((Exemplars::of_cube(cube, names)?, options));
    }
    let planes = central_slices(volume)?;
    let side = planes.iter().map(|e| e.width().min(e.height())).min().unwrap_or(0);
    let options = Options::for_exemplar(side);
    Ok((Exemplars::prepare([&planes[0], &planes[1], &planes[2]], &options)?, options))
}

/// The exemplar volume's central slices across x, y and z as exemplars of the planes
/// orthogonal to frame x, y and z: its colour channels (red, green, blue, or the first as
/// grey), shrunk to at most 64 pixels.
fn central_slices(volume: &Volume) -> Result<[Image2d; 3]> {
    let d = volume.dims();
    let keep = colour_channels(volume);
    let slice = |axis: Axis| -> Result<Image2d> {
        shrunk(picked(&volume.slice(axis, d[axis.index()] / 2)?, &keep, false)?, 64)
    };
    Ok([slice(Axis::X)?, slice(Axis::Y)?, slice(Axis::Z)?])
}

/// For a volume with a Depth channel and a spec whose depth rises inside the model: the
/// layered planes ([`layered_planes`]) fitted to the voxels the model's depth spans on the
/// grid, with the model's depth. `None` otherwise, and where the depth spans too few voxels
/// of the grid to be layered.
fn layered_slices(
    volume: &Volume,
    given: Option<[Axis; 2]>,
    depths: &[(Vec3, f32)],
    domain: &Domain,
) -> Result<Option<([Image2d; 3], ScalarGrid)>> {
    if volume.channel_index(&Channel::Depth).is_none() || !depths.iter().any(|d| d.1 > 0.0) {
        return Ok(None);
    }
    let depth = solid::depth_over(depths, domain)?;
    let res = domain.dims.iter().copied().max().unwrap_or(0);
    let Ok(rows) = solid::layer_rows(&depth, res) else {
        return Ok(None);
    };
    Ok(layered_planes(volume, given, rows)?.map(|planes| (planes, depth)))
}

/// The settings for a built cross-section's layered planes ([`layered_planes`] of
/// `volume`): layered, their depth held at [`SECTION_DEPTH_SHARE`] while the layers are
/// laid out, and the levels that only magnify the section, fitted past the volume's rows
/// along its depth ([`Options::magnifying`]).
pub fn section_options(planes: &[Image2d; 3], volume: &Volume) -> Options {
    let side = planes.iter().map(|e| e.width().min(e.height())).min().unwrap_or(0);
    let options = Options { layered: true, coarse_depth_share: SECTION_DEPTH_SHARE, ..Options::for_exemplar(side) };
    match volume.depth_axis() {
        Some(axis) => options.magnifying(volume.dims()[axis], planes[0].height()),
        None => options,
    }
}

/// For a volume with a Depth channel (a library cross-section's build): the two central
/// slices holding its depth axis, rows along it from the outside in (as `solidtex guided
/// --layered` takes a section), `rows` tall, with their Depth channel; the third plane
/// (not matched) repeats the second. `None` for a volume without layers.
///
/// The strokes run along frame x, so the first slice is the one across the volume axis
/// the lapped fill lays along them (the spec's `given` texture axes, else the axis the
/// volume changes slowest along: a kiwi's length), the second across the remaining one.
pub fn layered_planes(volume: &Volume, given: Option<[Axis; 2]>, rows: usize) -> Result<Option<[Image2d; 3]>> {
    let (Some(axis), Some(c)) = (volume.depth_axis(), volume.channel_index(&Channel::Depth)) else {
        return Ok(None);
    };
    let keep: Vec<usize> = colour_channels(volume).into_iter().chain([c]).collect();
    let d = volume.dims();
    let slice = |across: usize| -> Result<Image2d> {
        let image = picked(&volume.slice(Axis::ALL[across], d[across] / 2)?, &keep, true)?;
        let image = if Axis::ALL[across].plane_axes().0 == axis { transposed(&image)? } else { image };
        let depth_at = |y: usize| image.pixel(image.width() / 2, y)[keep.len() - 1];
        let image = if depth_at(0) > depth_at(image.height() - 1) { flipped(&image)? } else { image };
        let width = (image.width() * rows).div_ceil(image.height()).max(1);
        image.resized(width, rows)
    };
    // with a Depth channel the type does not enter the choice (see `texture_axes`)
    let along = match crate::fill::spec::texture_axes(volume, crate::TextureType::T2b, given)? {
        [_, along, _] if along != axis => along,
        _ => (0..3).find(|&a| a != axis).expect("two axes besides depth"),
    };
    let (first, second) = (slice(along)?, slice(3 - axis - along)?);
    Ok(Some([first, second.clone(), second]))
}

/// The volume's colour channels (red, green, blue, or the first as grey).
fn colour_channels(volume: &Volume) -> Vec<usize> {
    let names = volume.channels();
    let keep: Vec<usize> =
        [Channel::R, Channel::G, Channel::B].iter().filter_map(|c| names.iter().position(|n| n == c)).collect();
    if keep.is_empty() { vec![0] } else { keep }
}

/// The channels `keep` of `image`, named red, green, blue (and Depth last, with `depth`).
fn picked(image: &Image2d, keep: &[usize], depth: bool) -> Result<Image2d> {
    let c = image.channel_count();
    let data = image.data().chunks_exact(c).flat_map(|px| keep.iter().map(|&k| px[k])).collect();
    let colours = keep.len() - usize::from(depth);
    let mut channels = [Channel::R, Channel::G, Channel::B][..colours].to_vec();
    if depth {
        channels.push(Channel::Depth);
    }
    Image2d::from_data(image.width(), image.height(), channels, data)
}

/// `image` with rows and columns swapped.
fn transposed(image: &Image2d) -> Result<Image2d> {
    let (w, h) = (image.width(), image.height());
    let data = (0..w * h).flat_map(|i| image.pixel(i / h, i % h).to_vec()).collect();
    Image2d::from_data(h, w, image.channels().to_vec(), data)
}

/// `image` upside down.
fn flipped(image: &Image2d) -> Result<Image2d> {
    let (w, h) = (image.width(), image.height());
    let data = (0..w * h).flat_map(|i| image.pixel(i % w, h - 1 - i / w).to_vec()).collect();
    Image2d::from_data(w, h, image.channels().to_vec(), data)
}

/// `image` halved (a Gaussian pyramid) until its longer side is at most `side`.
fn shrunk(image: Image2d, side: usize) -> Result<Image2d> {
    let mut levels = 1;
    while (image.width().max(image.height()) >> (levels - 1)) > side && image.width().min(image.height()) >> levels >= 8
    {
        levels += 1;
    }
    Ok(crate::synth::image_pyramid(&image, levels)?.swap_remove(0))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A cubic volume is the solid exemplar itself (its colour channels, Depth left out);
    /// one that is not a cube gives its central slices as planes.
    #[test]
    fn a_cubic_volume_is_its_own_solid_exemplar() {
        let channels = vec![Channel::R, Channel::G, Channel::B, Channel::Depth];
        let fill = |x: usize, y: usize, z: usize, o: &mut [f32]| {
            o.copy_from_slice(&[x as f32 / 31.0, y as f32 / 31.0, 0.5, z as f32 / 31.0]);
        };
        let cubic = Volume::from_fn([32, 32, 32], channels.clone(), fill).unwrap();
        let (exemplars, options) = plain_exemplars(&cubic).unwrap();
        let cube = exemplars.cube.expect("a cube");
        assert_eq!((cube.channels, options.levels), (3, 2));
        assert_eq!(cube.at(1, [31, 2, 5]), [1.0, 2.0 / 31.0, 0.5]);
        let long = Volume::from_fn([32, 32, 48], channels, fill).unwrap();
        let (exemplars, _) = plain_exemplars(&long).unwrap();
        assert!(exemplars.cube.is_none() && exemplars.planes[0].len() == 2, "planes of two levels");
    }

    /// A volume layered along z (its Depth channel), striped along x and the same along y:
    /// the strokes' axis is y (the slowest), so the first slice is the one across y (its
    /// rows show the stripes), the second across x (its rows are even).
    #[test]
    fn the_first_layered_slice_is_across_the_strokes_axis() {
        let volume =
            Volume::from_fn([32, 32, 32], vec![Channel::R, Channel::G, Channel::B, Channel::Depth], |x, _, z, o| {
                let stripe = ((x / 8) % 2) as f32;
                o.copy_from_slice(&[stripe, z as f32 / 31.0, 0.5, z as f32 / 31.0]);
            })
            .unwrap();
        let box_corners = (0..8).map(|i| Vec3::new([-1.0, 1.0][i & 1], [-0.5, 0.5][(i >> 1) & 1], [-0.5, 0.5][i >> 2]));
        let depths: Vec<(Vec3, f32)> = box_corners
            .map(|p| (p, 0.0))
            .chain((0..5).map(|i| (Vec3::new(i as f32 * 0.4 - 0.8, 0.0, 0.0), 1.0)))
            .collect();
        let domain = Domain::around((Vec3::new(-1.0, -0.5, -0.5), Vec3::new(1.0, 0.5, 0.5)), GUIDED_RES).unwrap();
        let (planes, _) = layered_slices(&volume, None, &depths, &domain).unwrap().expect("layered");
        // the spread of red along the middle row
        let spread = |image: &Image2d| {
            let y = image.height() / 2;
            let reds: Vec<f32> = (0..image.width()).map(|x| image.pixel(x, y)[0]).collect();
            reds.iter().cloned().fold(f32::MIN, f32::max) - reds.iter().cloned().fold(f32::MAX, f32::min)
        };
        assert!(spread(&planes[0]) > 0.8, "across y: {}", spread(&planes[0]));
        assert!(spread(&planes[1]) < 0.05, "across x: {}", spread(&planes[1]));
    }
}
