//! Sketch-guided synthesis on a fill preview (the TUI's fill editor): the frame field the
//! spec's strokes and depth give, drawn as streamlines on the preview's cut, and a guided
//! cut synthesized along it from the exemplar's own central slices.

use super::fill::load_built;
use crate::error::{Error, Result};
use crate::fill::FillPreview;
use crate::fill::render::View;
use crate::fill::spec::FillSpec;
use crate::guided::field::{FrameField, sketched_frames, solve, streamlines};
use crate::guided::solid::{self, Domain};
use crate::guided::synth::{Exemplars, Options, Setup};
use crate::mesh::Mesh;
use crate::progress::Progress;
use crate::volume::{Axis, Channel, Image2d, Volume};

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

/// The drawn shape the preview fills, and the frame field of `spec` (its strokes and
/// depth, as `solidtex field` reads them) over the preview's tet mesh.
fn field_of(filled: &FillPreview, spec: &FillSpec) -> Result<(Mesh, FrameField)> {
    let surface = crate::mesh::shapes::named(&filled.shape)
        .ok_or_else(|| Error::invalid(format!("no drawn shape named {}", filled.shape)))?
        .canonical();
    let constraints = crate::fill::spec::constraints(spec, &surface, 1.0)?;
    let frames = sketched_frames(&constraints.directions, &constraints.depth)?;
    let field = solve(&filled.model.mesh, &frames)?;
    Ok((surface, field))
}

/// The `overlay` picture of `spec` on the preview's cut `view` (a square view).
pub fn picture(
    filled: &FillPreview,
    spec: &FillSpec,
    overlay: Overlay,
    view: &View,
    progress: &dyn Progress,
) -> Result<Picture> {
    let (surface, field) = field_of(filled, spec)?;
    let mesh = &filled.model.mesh;
    let ones = vec![1.0; mesh.vertices.len()];
    let inside: Vec<bool> = crate::fill::render::field_cut(mesh, &ones, view).iter().map(Option::is_some).collect();
    let pixels = match overlay {
        Overlay::Field => {
            let lines = streamlines(mesh, &field, view);
            lines.data.chunks_exact(3).zip(&inside).map(|(p, i)| i.then(|| [p[0], p[1], p[2]])).collect()
        }
        Overlay::Guided => {
            let volume = load_built(spec, &spec.exemplar)?;
            let planes = central_slices(&volume)?;
            let side = planes.iter().map(|e| e.width().min(e.height())).min().unwrap_or(0);
            let options = Options::for_exemplar(side);
            let exemplars = Exemplars::prepare([&planes[0], &planes[1], &planes[2]], &options)?;
            let domain = Domain::around(surface.bounds(), GUIDED_RES)?;
            let frames = solid::frames_over(mesh, &field, &domain);
            let setup = Setup {
                exemplars: &exemplars,
                frames: &frames,
                depth: None,
                dims: domain.dims,
                seed: spec.seed,
                options,
            };
            let (cut, _) = solid::cut(&setup, &domain, mesh, view, None, progress)?;
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
    };
    Ok(Picture { size: view.width, pixels })
}

/// The exemplar volume's central slices across x, y and z as exemplars of the planes
/// orthogonal to frame x, y and z: its colour channels (red, green, blue, or the first as
/// grey), shrunk to at most 64 pixels.
fn central_slices(volume: &Volume) -> Result<[Image2d; 3]> {
    let d = volume.dims();
    let names = volume.channels();
    let keep: Vec<usize> =
        [Channel::R, Channel::G, Channel::B].iter().filter_map(|c| names.iter().position(|n| n == c)).collect();
    let keep = if keep.is_empty() { vec![0] } else { keep };
    let slice = |axis: Axis| -> Result<Image2d> {
        let image = volume.slice(axis, d[axis.index()] / 2)?;
        let c = image.channel_count();
        let data = image.data().chunks_exact(c).flat_map(|px| keep.iter().map(|&k| px[k])).collect();
        let channels = [Channel::R, Channel::G, Channel::B][..keep.len()].to_vec();
        let picked = Image2d::from_data(image.width(), image.height(), channels, data)?;
        shrunk(picked, 64)
    };
    Ok([slice(Axis::X)?, slice(Axis::Y)?, slice(Axis::Z)?])
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
