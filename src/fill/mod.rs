//! The lapped-solid-textures filling backend (thesis ch. 6): a closed triangle mesh becomes
//! a tetrahedral mesh, a tensor field is built from the fill spec's constraints, exemplar
//! patches are pasted along the field until every tet is covered, and the result — an
//! [`LstModel`] — renders planar cuts and bakes to a volume.
//!
//! ```text
//!  surface mesh --tetrahedralize--> TetMesh --+
//!  fill spec --constraints--> field::build ---+--> paste::Paster --> LstModel --> cut / bake
//!  exemplar masks (splotch or outer/middle/inner) -+
//! ```

pub mod carve;
pub mod export;
pub mod field;
pub mod locate;
pub mod mesher;
pub mod model;
pub mod paste;
pub mod patch;
pub mod refine;
pub mod render;
pub mod sampler;
pub mod solve;
pub mod spec;
pub mod tets;
pub mod translucent;
pub mod view;
pub mod warp;

use crate::TextureType;
use crate::error::{Error, Result};
use crate::mesh::Mesh;
use crate::progress::Progress;
use crate::volume::Volume;
use glam::Vec3;
pub use model::{FillReport, LstModel, MaskRef, Source};

/// A filled model with the textures to cut it: what a front end shows as a quick preview.
pub struct FillPreview {
    /// The model.
    pub model: LstModel,
    /// Its textures.
    pub textures: render::Textures,
    /// One line about the fill (shape, tets, patches, time).
    pub summary: String,
    /// The depth field at the mesh's vertices (depth-varying types).
    pub depth: Option<Vec<f32>>,
    /// The spec it was filled by.
    pub spec: spec::FillSpec,
    /// The drawn shape it fills (`fruit`, `block`).
    pub shape: String,
    /// The texture type it was filled as.
    pub kind: TextureType,
}

impl std::fmt::Debug for FillPreview {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(&self.summary)
    }
}
use spec::FillSpec;
use tets::TetMesh;
use warp::Frame;

/// The smallest texture scale, in mean tet edges, a patch may have.
pub const MIN_SCALE_EDGES: f32 = 2.5;

/// Everything a fill needs besides the tet mesh, resolved by the caller.
pub struct Job<'a> {
    /// The closed surface being filled.
    pub surface: &'a Mesh,
    /// The spec.
    pub spec: &'a FillSpec,
    /// The texture type.
    pub kind: TextureType,
    /// Texture axes of the primary, secondary and third directions.
    pub axes: [usize; 3],
    /// Sources: the automatic fill's first (1, or 3 for outer/middle/inner), then one per
    /// manual paste.
    pub sources: Vec<Source>,
    /// One mask per source.
    pub masks: Vec<Volume>,
}

/// Fills `mesh` (a tetrahedralization of `job.surface`): field, automatic pasting, then
/// the manual pastes on top.
pub fn fill(job: &Job, mesh: TetMesh, progress: &dyn Progress) -> Result<(LstModel, FillReport)> {
    // on a pool thread, the paste's many small parallel steps hand out work without waking
    // and parking the calling thread each time
    rayon::scope(|_| fill_here(job, mesh, progress))
}

fn fill_here(job: &Job, mesh: TetMesh, progress: &dyn Progress) -> Result<(LstModel, FillReport)> {
    let default_scale = spec::size_of(job.surface) / 4.0;
    let constraints = spec::constraints(job.spec, job.surface, default_scale)?;
    progress.update("tensor field", 0.0);
    let mut field = field::build(&mesh, job.kind, &constraints, Some(job.surface))?;
    let raised = check_scale(&mesh, &mut field, job.kind)?;
    check_paste_scales(&mesh, job.spec)?;
    let params = paste::Params { kind: job.kind, axes: job.axes, seed: job.spec.seed };
    let auto = if field.depth.is_some() { 3 } else { 1 };
    let mut paster = paste::Paster::new(&mesh, &field, &job.masks, params)?;
    paster.fill(progress)?;
    for (i, p) in job.spec.pastes.iter().enumerate() {
        let dirs = [0, 1, 2].map(|k| p.rotation * unit(job.axes[k]));
        paster.paste_manual(p.at, Frame { dirs, scale: p.scale }, (auto + i) as u16)?;
    }
    let pasted = paster.finish();
    let report = FillReport {
        tets: mesh.tets.len(),
        vertices: mesh.vertices.len(),
        min_dihedral: mesh.min_dihedral_degrees(),
        raised_scale: raised,
        ignored: spec::ignored(job.spec, job.kind, &job.sources),
        paste: pasted.stats.clone(),
        outer_share: field.depth.as_deref().map(|d| model::outer_share(&mesh, d)),
        depth: field.depth.clone(),
    };
    let mut model = LstModel::new(mesh, job.surface.clone(), job.sources.clone(), pasted.patches, pasted.tet_patches);
    if let Some(edges) = field.bumps {
        model = model.with_depth(model::DepthBumps { axis: job.axes[0], sources: auto, edges });
    }
    Ok((model, report))
}

/// Whether a fill of `kind` reads the spec's depth (its layers vary with depth, or its
/// directions follow the depth's gradient); the other types leave `[depth]` unused.
pub fn uses_depth(kind: TextureType) -> bool {
    matches!(kind, TextureType::T1b | TextureType::T2a | TextureType::T2b)
}

/// The tet mesh a fill of `surface` by `spec` uses: the lattice mesh covering the solid (see
/// [`mesher::tetrahedralize_covering`]: the model takes its shape from `surface`), refined near the
/// spec's depth axes when `depth` (the fill reads the spec's depth: [`uses_depth`]); when the
/// refinement takes the count more than 15 % past `spec.tets`, the lattice is made again,
/// coarser by the share the refinement added. Also how many tets the refinement added.
pub fn tetrahedralize(surface: &Mesh, spec: &FillSpec, depth: bool) -> Result<(TetMesh, usize)> {
    let margin = cover_margin(spec, depth);
    let axes: &[Vec<Vec3>] = if depth { &spec.depth.axes } else { &[] };
    let mut tets = mesher::tetrahedralize_covering(surface, spec.tets, margin)?;
    let added = refine_axes(&mut tets, axes);
    let total = tets.tets.len() as f64;
    if added == 0 || total <= spec.tets as f64 * (1.0 + COUNT_TOLERANCE) {
        return Ok((tets, added));
    }
    // the refinement adds about the same share to a coarser lattice: leave room for it
    let lattice = (total - added as f64).max(1.0);
    let target = (spec.tets as f64 * lattice / total).max(*mesher::TARGET_TETS.start() as f64);
    let mut again = mesher::tetrahedralize_covering(surface, target.round() as usize, margin)?;
    let added = refine_axes(&mut again, axes);
    Ok((again, added))
}

/// How far the tets' boundary is moved out past the surface, in lattice spacings, so that
/// they hold it and its points find their tet at once. Not for a fill with a depth field:
/// its boundary vertices are held at the surface's depth, which must lie on the surface.
const COVER_MARGIN: f32 = 0.3;

/// How far [`tetrahedralize`] moves the tets' boundary out for `spec`, in lattice spacings
/// (`depth`: the fill reads the spec's depth).
pub fn cover_margin(spec: &FillSpec, depth: bool) -> f32 {
    if depth && spec.depth.given() { 0.0 } else { COVER_MARGIN }
}

/// How far past the tet count asked for the refinement may take it (15 %) before the
/// lattice is made again, coarser.
const COUNT_TOLERANCE: f64 = 0.15;

/// How far from a depth axis tets are refined, in mean tet edges.
const AXIS_REACH_EDGES: f32 = 0.9;
/// The longest edge wanted there, in mean tet edges.
const AXIS_EDGE: f32 = 1.0;

/// Refines the tets within [`AXIS_REACH_EDGES`] of the depth `axes` until their longest
/// edges are at most [`AXIS_EDGE`] (thesis §7.1, Fig. 7.3): the depth field peaks along an
/// axis, and over lattice-sized tets the core it draws is square. Returns how many tets
/// were added.
fn refine_axes(mesh: &mut TetMesh, axes: &[Vec<Vec3>]) -> usize {
    if axes.is_empty() {
        return 0;
    }
    let edge = mean_edge(mesh);
    let (reach, wanted) = (AXIS_REACH_EDGES * edge, AXIS_EDGE * edge);
    let size = |p: Vec3| {
        let near = |s: &[Vec3]| p.distance(crate::mesh::closest_on_segment(p, s[0], s[1])) <= reach;
        let near = axes.iter().any(|line| line.windows(2).any(near));
        if near { wanted } else { f32::INFINITY }
    };
    refine::refine(mesh, &size)
}

fn unit(axis: usize) -> Vec3 {
    let mut v = Vec3::ZERO;
    v[axis] = 1.0;
    v
}

/// Refuses a texture scale so small that patches could not cover the tets, and raises
/// the scale of the tets below [`MIN_SCALE_EDGES`] edges (where the depth field is steep,
/// e.g. near a fruit's axis: over a tenth of a kiwi's tets). Returns how many were raised;
/// the command line reports the share.
fn check_scale(mesh: &TetMesh, field: &mut field::Field, kind: TextureType) -> Result<usize> {
    let floor = MIN_SCALE_EDGES * mean_edge(mesh);
    let mut sorted = field.scale.clone();
    sorted.sort_by(f32::total_cmp);
    let median = sorted[sorted.len() / 2];
    if median < floor {
        let hint = match kind {
            TextureType::T1b | TextureType::T2b => "depth 0 and 1 are too close for this many tets; use more tets",
            _ => "raise scale (or scale_at) or use more tets",
        };
        return Err(Error::invalid(format!(
            "the median texture scale {median:.4} is below {MIN_SCALE_EDGES} tet edges ({floor:.4}): patches could not cover the tets; {hint}"
        )));
    }
    let low = field.scale.iter().filter(|s| **s < floor).count();
    field.scale.iter_mut().for_each(|s| *s = s.max(floor));
    Ok(low)
}

/// Refuse a manual paste whose texture cube is smaller than [`MIN_SCALE_EDGES`] tet edges:
/// its patch could cover no tet, and the paste would show nowhere.
fn check_paste_scales(mesh: &TetMesh, spec: &FillSpec) -> Result<()> {
    let floor = MIN_SCALE_EDGES * mean_edge(mesh);
    match spec.pastes.iter().position(|p| p.scale < floor) {
        Some(i) => Err(Error::invalid(format!(
            "paste[{i}].scale {} is below {MIN_SCALE_EDGES} tet edges ({floor:.4}): the paste could cover no tet; \
             raise it or use more tets",
            spec.pastes[i].scale
        ))),
        None => Ok(()),
    }
}

/// The mean edge length of the tets.
pub fn mean_edge(mesh: &TetMesh) -> f32 {
    let total: f32 = (0..mesh.tets.len())
        .map(|t| {
            let c = mesh.corners(t);
            tets::EDGES.iter().map(|&(a, b)| c[a].distance(c[b])).sum::<f32>()
        })
        .sum();
    total / (6 * mesh.tets.len().max(1)) as f32
}

#[cfg(test)]
mod tests {
    use super::render::{Textures, View, cut};
    use super::spec::{DepthSpec, FaceGroup};
    use super::*;
    use crate::mask::{self, Layer};
    use crate::mesh::shapes::cuboid;
    use crate::progress::NoProgress;
    use crate::volume::{Axis, Channel};

    fn layered_spec() -> FillSpec {
        let group = |y: f32, value: f32| FaceGroup { at: Vec3::new(0.5, y, 0.5), crease: 30.0, angle: 180.0, value };
        let mut spec = FillSpec::new("ramp");
        spec.seed = 2;
        spec.depth = DepthSpec { surface: false, faces: vec![group(1.0, 0.0), group(0.0, 1.0)], ..Default::default() };
        spec
    }

    /// Red at texture depth 0 (z = 0) fading to blue at depth 1.
    fn ramp() -> Volume {
        Volume::from_fn([16, 16, 16], Channel::rgb(), |_, _, z, o| {
            let d = z as f32 / 15.0;
            o.copy_from_slice(&[1.0 - d, 0.0, d]);
        })
        .unwrap()
    }

    #[test]
    fn a_layered_fill_puts_texture_depth_at_model_depth() {
        // a unit box whose top (y = 1) is depth 0 and bottom depth 1
        let surface = cuboid(Vec3::ZERO, Vec3::ONE);
        let spec = layered_spec();
        let masks: Vec<Volume> = Layer::ALL.iter().map(|l| mask::layered(16, 0.1, 1, *l, Axis::Z).unwrap()).collect();
        let source = |l: Layer| Source {
            exemplar: "ramp".into(),
            volume: "ramp.exr".into(),
            mask: MaskRef::Layered { layer: l, depth: Axis::Z, size: 16, falloff: 0.1, seed: 1 },
        };
        let job = Job {
            surface: &surface,
            spec: &spec,
            kind: TextureType::T1b,
            axes: [2, 0, 1],
            sources: Layer::ALL.map(source).to_vec(),
            masks: masks.clone(),
        };
        let (model, report) = fill(&job, tets::cube_lattice([8, 8, 8], 0.125), &NoProgress).unwrap();
        assert_eq!(report.paste.forced, 0);
        assert!(model.tet_patches.iter().all(|l| !l.is_empty()));
        model.check().unwrap();
        let textures = Textures::new(&[ramp(), ramp(), ramp()], &masks);
        let view = View::framing((Vec3::ZERO, Vec3::ONE), Vec3::splat(0.5), Vec3::Z, 64).unwrap();
        let picture = cut(&model, &textures, &view);
        let at = |y: f32| {
            let row = ((1.0 - y) * 64.0 / 1.04 + 64.0 * 0.02 / 1.04) as usize;
            let p = picture.pixels[row.min(63) * 64 + 32];
            (p[0], p[2])
        };
        let (top, bottom, middle) = (at(0.97), at(0.03), at(0.5));
        assert!(top.0 > 0.85, "top {top:?}");
        assert!(bottom.1 > 0.85, "bottom {bottom:?}");
        assert!((middle.0 - 0.5).abs() < 0.15, "middle {middle:?}");
        assert!(picture.inside_share() > 0.9);
    }
}
