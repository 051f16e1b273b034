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

pub mod field;
pub mod model;
pub mod paste;
pub mod render;
pub mod solve;
pub mod spec;
pub mod tets;
pub mod warp;

use crate::TextureType;
use crate::error::{Error, Result};
use crate::mesh::Mesh;
use crate::progress::Progress;
use crate::volume::Volume;
use glam::Vec3;
pub use model::{FillReport, LstModel, MaskRef, Source};
use spec::FillSpec;
use tets::TetMesh;
use warp::Frame;

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
    let default_scale = spec::size_of(job.surface) / 4.0;
    let constraints = spec::constraints(job.spec, job.surface, default_scale)?;
    progress.update("tensor field", 0.0);
    let field = field::build(&mesh, job.kind, &constraints)?;
    check_scale(&mesh, &field, job.kind)?;
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
        paste: pasted.stats.clone(),
    };
    let model = LstModel { mesh, sources: job.sources.clone(), patches: pasted.patches, tet_patches: pasted.tet_patches };
    Ok((model, report))
}

fn unit(axis: usize) -> Vec3 {
    let mut v = Vec3::ZERO;
    v[axis] = 1.0;
    v
}

/// Refuses a texture scale so small that a patch could not cover a tet.
fn check_scale(mesh: &TetMesh, field: &field::Field, kind: TextureType) -> Result<()> {
    let edge = mean_edge(mesh);
    let smallest = field.scale.iter().copied().fold(f32::INFINITY, f32::min);
    if smallest < 3.0 * edge {
        let hint = match kind {
            TextureType::T1b | TextureType::T2b => "the depth field changes too fast (depth 0 and 1 too close); use more tets",
            _ => "raise scale (or scale_at) or use more tets",
        };
        return Err(Error::invalid(format!(
            "texture scale {smallest:.4} is below 3 tet edges ({:.4}): patches could not cover the tets; {hint}",
            3.0 * edge
        )));
    }
    Ok(())
}

/// The mean edge length of the tets.
pub fn mean_edge(mesh: &TetMesh) -> f32 {
    let total: f32 = (0..mesh.tets.len())
        .map(|t| {
            let c = mesh.corners(t);
            [(0, 1), (0, 2), (0, 3), (1, 2), (1, 3), (2, 3)].iter().map(|&(a, b)| c[a].distance(c[b])).sum::<f32>()
        })
        .sum();
    total / (6 * mesh.tets.len().max(1)) as f32
}
