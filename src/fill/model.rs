//! The LST model: a tet mesh, the (exemplar, mask) sources, the pasted patches and, per
//! tet, the patches that show in it. Small: exemplars are referenced, not embedded.

use super::locate::{Location, Locator};
use super::paste::{Patch, Stats};
use super::tets::TetMesh;
use crate::error::{Error, Result};
use crate::mask::{self, Layer};
use crate::mesh::Mesh;
use crate::volume::{Axis, Volume};
use glam::Vec3;
use std::sync::OnceLock;

/// Where a source's mask comes from: a file, or a recipe regenerated on load.
#[derive(Debug, Clone, PartialEq)]
pub enum MaskRef {
    /// A mask volume file (path relative to the model's folder, or absolute).
    File(String),
    /// `mask::splotch(size, falloff, seed)`.
    Splotch {
        /// Side in voxels.
        size: usize,
        /// Fall-off band share.
        falloff: f32,
        /// Seed.
        seed: u64,
    },
    /// `mask::layered(size, falloff, seed, layer, depth)`.
    Layered {
        /// Outer, middle or inner.
        layer: Layer,
        /// The depth axis.
        depth: Axis,
        /// Side in voxels.
        size: usize,
        /// Fall-off band share.
        falloff: f32,
        /// Seed.
        seed: u64,
    },
}

impl MaskRef {
    /// One line of text: `file PATH`, `splotch SIZE FALLOFF SEED` or
    /// `layered LAYER AXIS SIZE FALLOFF SEED`.
    pub fn to_text(&self) -> String {
        match self {
            MaskRef::File(p) => format!("file {p}"),
            MaskRef::Splotch { size, falloff, seed } => format!("splotch {size} {falloff} {seed}"),
            MaskRef::Layered { layer, depth, size, falloff, seed } => {
                format!("layered {} {} {size} {falloff} {seed}", layer.name(), depth)
            }
        }
    }

    /// Parses [`MaskRef::to_text`].
    pub fn parse(text: &str) -> Result<MaskRef> {
        let bad =
            || Error::invalid(format!("mask reference '{text}' is not 'file PATH', 'splotch ...' or 'layered ...'"));
        let words: Vec<&str> = text.split(' ').collect();
        let num = |i: usize| words.get(i).ok_or_else(bad);
        let mask = match words[0] {
            "file" => text.strip_prefix("file ").map(|p| MaskRef::File(p.to_string())).ok_or_else(bad),
            "splotch" => Ok(MaskRef::Splotch {
                size: num(1)?.parse().map_err(|_| bad())?,
                falloff: num(2)?.parse().map_err(|_| bad())?,
                seed: num(3)?.parse().map_err(|_| bad())?,
            }),
            "layered" => Ok(MaskRef::Layered {
                layer: Layer::ALL.into_iter().find(|l| l.name() == *num(1).unwrap_or(&"")).ok_or_else(bad)?,
                depth: num(2)?.parse::<Axis>().map_err(|_| bad())?,
                size: num(3)?.parse().map_err(|_| bad())?,
                falloff: num(4)?.parse().map_err(|_| bad())?,
                seed: num(5)?.parse().map_err(|_| bad())?,
            }),
            _ => Err(bad()),
        }?;
        match mask {
            MaskRef::Splotch { size, falloff, .. } | MaskRef::Layered { size, falloff, .. } => {
                crate::mask::check(size, falloff)
                    .map_err(|e| Error::invalid(format!("mask reference '{text}': {e}")))?
            }
            MaskRef::File(_) => {}
        }
        Ok(mask)
    }

    /// The mask volume for a recipe (files are loaded by `io`).
    pub fn generate(&self) -> Option<Result<Volume>> {
        match *self {
            MaskRef::File(_) => None,
            MaskRef::Splotch { size, falloff, seed } => Some(mask::splotch(size, falloff, seed)),
            MaskRef::Layered { layer, depth, size, falloff, seed } => {
                Some(mask::layered(size, falloff, seed, layer, depth))
            }
        }
    }
}

/// One pasteable source: an exemplar volume and its mask.
#[derive(Debug, Clone, PartialEq)]
pub struct Source {
    /// The exemplar's library name.
    pub exemplar: String,
    /// The exemplar volume file (relative to the model's folder, or absolute).
    pub volume: String,
    /// The mask.
    pub mask: MaskRef,
}

/// A filled model: the input surface gives its shape, the tets its texture.
#[derive(Debug, Clone, PartialEq)]
pub struct LstModel {
    /// The tet mesh (not to be moved once [`LstModel::locate`] has been called: the
    /// locator it makes is kept).
    pub mesh: TetMesh,
    /// The closed surface that was filled: every picture takes the model's shape from it.
    pub surface: Mesh,
    /// The sources the patches use.
    pub sources: Vec<Source>,
    /// The patches, in paste order.
    pub patches: Vec<Patch>,
    /// Per tet, its patches bottom first.
    pub tet_patches: Vec<Vec<u32>>,
    /// The smooth depth's quadratic term, for fills whose texture depth follows the depth
    /// field (1-b, 2-b).
    pub depth: Option<DepthBumps>,
    located: Located,
}

/// Where a depth-varying fill's texture depth departs from the linear interpolation of its
/// tets' corner depths (see [`super::field::bump`]).
#[derive(Debug, Clone, PartialEq)]
pub struct DepthBumps {
    /// The texture axis that holds depth.
    pub axis: usize,
    /// The sources whose patches take their depth from the field: the first `sources`
    /// (manual pastes are rigid).
    pub sources: usize,
    /// Per tet, the bump at the middle of each of its edges ([`super::tets::EDGES`]).
    pub edges: Vec<[f32; 6]>,
}

impl DepthBumps {
    /// The texture point's shift along [`DepthBumps::axis`] at barycentric point `b` of tet
    /// `t`. A point outside its tet (negative weights) takes the bump of the tet's nearest
    /// point of the same weights clamped and renormalized, which meets the bump on the face.
    pub fn at(&self, t: usize, b: [f32; 4]) -> f32 {
        let clamped = b.map(|w| w.max(0.0));
        let sum: f32 = clamped.iter().sum();
        if sum <= 0.0 {
            return 0.0;
        }
        super::field::bump(&self.edges[t], clamped.map(|w| w / sum))
    }
}

/// The model's [`Locator`], made on first use.
#[derive(Debug, Clone, Default)]
struct Located(OnceLock<Locator>);

impl PartialEq for Located {
    /// A cache: equal whether made or not.
    fn eq(&self, _: &Located) -> bool {
        true
    }
}

impl LstModel {
    /// A model of `mesh` filling `surface`.
    pub fn new(
        mesh: TetMesh,
        surface: Mesh,
        sources: Vec<Source>,
        patches: Vec<Patch>,
        tet_patches: Vec<Vec<u32>>,
    ) -> LstModel {
        LstModel { mesh, surface, sources, patches, tet_patches, depth: None, located: Located::default() }
    }

    /// The model with its texture depth made smooth by `bumps`.
    pub fn with_depth(self, bumps: DepthBumps) -> LstModel {
        LstModel { depth: Some(bumps), ..self }
    }

    /// The boundary of `mesh` as a surface: for models written before the input surface
    /// was kept, and for tests that fill a tet mesh directly.
    pub fn boundary_of(mesh: &TetMesh) -> Result<Mesh> {
        Mesh::new(mesh.vertices.clone(), mesh.boundary_faces(&mesh.neighbours()))
    }

    /// Checks that every tet's corners are vertices of the mesh.
    pub fn check_tets(mesh: &TetMesh) -> Result<()> {
        let nv = mesh.vertices.len() as u32;
        match mesh.tets.iter().position(|t| t.iter().any(|v| *v >= nv)) {
            Some(t) => Err(Error::invalid(format!("tet {t} uses a vertex beyond the {nv} vertices"))),
            None => Ok(()),
        }
    }

    /// Where `p` takes its texture (see [`Locator::locate`]).
    pub fn locate(&self, p: Vec3) -> Option<Location> {
        self.locator().locate(p)
    }

    /// [`LstModel::locate`] for a point near the last one located with the same `hint`
    /// ([`Locator::locate_near`]).
    pub fn locate_near(&self, p: Vec3, hint: &mut Option<u32>) -> Option<Location> {
        self.locator().locate_near(p, hint)
    }

    /// The model's locator, made on first use: call it before many threads locate points,
    /// so that it is made once, in parallel, rather than waited for.
    pub fn locator(&self) -> &Locator {
        self.located.0.get_or_init(|| Locator::new(&self.mesh))
    }

    /// Checks the cross references (after reading a file).
    pub fn check(&self) -> Result<()> {
        LstModel::check_tets(&self.mesh)?;
        let np = self.patches.len() as u32;
        if let Some(p) = self.patches.iter().position(|p| p.source as usize >= self.sources.len()) {
            return Err(Error::invalid(format!("patch {p} uses a source beyond the {} sources", self.sources.len())));
        }
        if self.tet_patches.len() != self.mesh.tets.len() {
            return Err(Error::invalid(format!(
                "{} patch lists for {} tets",
                self.tet_patches.len(),
                self.mesh.tets.len()
            )));
        }
        for (t, list) in self.tet_patches.iter().enumerate() {
            for &p in list {
                let patch = self
                    .patches
                    .get(p as usize)
                    .ok_or_else(|| Error::invalid(format!("tet {t} lists patch {p} of {np}")))?;
                if self.mesh.tets[t].iter().any(|v| patch.vertices.binary_search(v).is_err()) {
                    return Err(Error::invalid(format!("tet {t} lists patch {p}, which lacks its corners")));
                }
            }
        }
        if let Some(d) = &self.depth {
            if d.axis > 2 || d.sources > self.sources.len() || d.edges.len() != self.mesh.tets.len() {
                return Err(Error::invalid(format!(
                    "depth bumps on axis {} for {} sources and {} tets; allowed: axis 0 to 2, at most {} sources, \
                     one entry per tet ({})",
                    d.axis,
                    d.sources,
                    d.edges.len(),
                    self.sources.len(),
                    self.mesh.tets.len()
                )));
            }
            if let Some(t) = d.edges.iter().position(|e| e.iter().any(|x| !(-1.0..=1.0).contains(x))) {
                return Err(Error::invalid(format!("tet {t}'s depth bumps lie outside -1 to 1")));
            }
        }
        Ok(())
    }
}

/// A fill's figures, for `--json` and the report.
#[derive(Debug, Clone, Default, serde::Serialize)]
pub struct FillReport {
    /// Tets in the mesh.
    pub tets: usize,
    /// Vertices in the mesh.
    pub vertices: usize,
    /// Smallest dihedral angle of the tet mesh, degrees.
    pub min_dihedral: f32,
    /// Tets whose texture scale was raised to the smallest allowed.
    pub raised_scale: usize,
    /// Options of the spec this fill did not use, each with the reason.
    pub ignored: Vec<String>,
    /// The paste loop's figures.
    pub paste: Stats,
    /// The depth field at the tet mesh's vertices (depth-varying types), for showing it.
    #[serde(skip)]
    pub depth: Option<Vec<f32>>,
    /// The share of the volume whose depth is under [`OUTER_DEPTH`] (depth-varying types):
    /// near 1, the exemplar's skin or bark fills most of the model.
    pub outer_share: Option<f32>,
}

/// The depth under which a depth-varying fill shows its outermost layer (skin, bark).
pub const OUTER_DEPTH: f32 = 0.1;
/// An outer share above this is warned about.
pub const OUTER_WARNING: f32 = 0.5;

/// The share of `mesh`'s volume whose depth (given at the vertices) is under
/// [`OUTER_DEPTH`], each tet counted by its volume and the mean depth of its corners.
pub fn outer_share(mesh: &TetMesh, depth: &[f32]) -> f32 {
    let (mut outer, mut total) = (0.0f64, 0.0f64);
    for (t, tet) in mesh.tets.iter().enumerate() {
        let v = f64::from(mesh.volume_of(t).abs());
        let mean = tet.iter().map(|&i| depth.get(i as usize).copied().unwrap_or(0.0)).sum::<f32>() / 4.0;
        total += v;
        if mean < OUTER_DEPTH {
            outer += v;
        }
    }
    (outer / total.max(f64::MIN_POSITIVE)) as f32
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn mask_references_parse_back_and_a_bare_word_is_an_error() {
        for text in ["file masks/a.exr", "splotch 32 0.1 7"] {
            assert_eq!(MaskRef::parse(text).unwrap().to_text(), text);
        }
        for text in ["file", "splotch 32", "layered", ""] {
            assert!(MaskRef::parse(text).unwrap_err().to_string().contains("mask reference"), "{text}");
        }
        // a recipe out of range is refused where it is read (a model file's mask), not later
        for (text, says) in
            [("splotch 100000 0.075 0", "allowed 6 to 512"), ("layered outer z 32 0.7 1", "fall-off 0.7")]
        {
            let error = MaskRef::parse(text).unwrap_err().to_string();
            assert!(error.contains(text) && error.contains(says), "{error}");
        }
    }
}
