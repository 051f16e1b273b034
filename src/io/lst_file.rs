//! The `.lst` model file (layout in `docs/formats.md`): little-endian binary, versioned,
//! written atomically; every count is checked against the bytes left before anything is
//! allocated, and cross references are checked after reading.

use super::atomic::{read_bytes, write_bytes};
use crate::error::{Error, Result};
use crate::fill::model::{DepthBumps, LstModel, MaskRef, Source};
use crate::fill::paste::Patch;
use crate::fill::tets::TetMesh;
use crate::mesh::Mesh;
use glam::Vec3;
use std::path::Path;

/// The first 8 bytes.
pub const MAGIC: &[u8; 8] = b"SOLIDLST";
/// The version this code writes; it also reads the versions from [`FIRST_VERSION`] on.
pub const VERSION: u32 = 3;
/// Models with their input surface but without the smooth depth's bumps (read with the
/// depth linear over each tet, as they were drawn).
pub const SURFACE_VERSION: u32 = 2;
/// Models without their input surface, read with the tet mesh's boundary as the surface.
pub const FIRST_VERSION: u32 = 1;

/// The model as bytes.
pub fn to_bytes(model: &LstModel) -> Vec<u8> {
    let mut out = Vec::new();
    out.extend_from_slice(MAGIC);
    let counts = [VERSION, model.mesh.vertices.len() as u32, model.mesh.tets.len() as u32];
    let counts = [counts[0], counts[1], counts[2], model.sources.len() as u32, model.patches.len() as u32];
    counts.iter().for_each(|c| out.extend_from_slice(&c.to_le_bytes()));
    for s in &model.sources {
        for text in [&s.exemplar, &s.volume, &s.mask.to_text()] {
            out.extend_from_slice(&(text.len() as u32).to_le_bytes());
            out.extend_from_slice(text.as_bytes());
        }
    }
    model.mesh.vertices.iter().flat_map(|v| v.to_array()).for_each(|x| out.extend_from_slice(&x.to_le_bytes()));
    model.mesh.tets.iter().flatten().for_each(|i| out.extend_from_slice(&i.to_le_bytes()));
    for p in &model.patches {
        out.extend_from_slice(&p.source.to_le_bytes());
        out.extend_from_slice(&(p.vertices.len() as u32).to_le_bytes());
        p.vertices.iter().for_each(|v| out.extend_from_slice(&v.to_le_bytes()));
        p.coords.iter().flat_map(|c| c.to_array()).for_each(|x| out.extend_from_slice(&x.to_le_bytes()));
    }
    for list in &model.tet_patches {
        out.extend_from_slice(&(list.len() as u32).to_le_bytes());
        list.iter().for_each(|p| out.extend_from_slice(&p.to_le_bytes()));
    }
    let surface = &model.surface;
    for count in [surface.vertices.len(), surface.triangles.len()] {
        out.extend_from_slice(&(count as u32).to_le_bytes());
    }
    surface.vertices.iter().flat_map(|v| v.to_array()).for_each(|x| out.extend_from_slice(&x.to_le_bytes()));
    surface.triangles.iter().flatten().for_each(|i| out.extend_from_slice(&i.to_le_bytes()));
    match &model.depth {
        None => out.extend_from_slice(&0u32.to_le_bytes()),
        Some(d) => {
            for n in [1, d.axis as u32, d.sources as u32] {
                out.extend_from_slice(&n.to_le_bytes());
            }
            d.edges.iter().flatten().for_each(|x| out.extend_from_slice(&x.to_le_bytes()));
        }
    }
    out
}

/// Writes the model atomically.
pub fn write_lst(path: &Path, model: &LstModel) -> Result<()> {
    write_bytes(path, &to_bytes(model))
}

/// Reads and checks a model.
pub fn read_lst(path: &Path) -> Result<LstModel> {
    from_bytes(&read_bytes(path)?).map_err(|e| e.in_file(path))
}

/// Parses and checks model bytes.
pub fn from_bytes(bytes: &[u8]) -> Result<LstModel> {
    if bytes.len() < 8 || &bytes[..8] != MAGIC {
        return Err(Error::invalid("not a solidtex .lst model (the file does not start with SOLIDLST)"));
    }
    let mut r = Reader { bytes, at: 8 };
    let version = r.u32()?;
    if !(FIRST_VERSION..=VERSION).contains(&version) {
        return Err(Error::invalid(format!(
            "model version {version} is not supported; this solidtex reads versions {FIRST_VERSION} to {VERSION}"
        )));
    }
    let (nv, nt, ns, np) = (r.count(12)?, r.count(16)?, r.count(12)?, r.count(6)?);
    let sources = (0..ns).map(|_| r.source()).collect::<Result<Vec<_>>>()?;
    let vertices = (0..nv).map(|_| r.vec3()).collect::<Result<Vec<_>>>()?;
    let tets = (0..nt).map(|_| Ok([r.u32()?, r.u32()?, r.u32()?, r.u32()?])).collect::<Result<Vec<_>>>()?;
    let patches = (0..np).map(|_| r.patch()).collect::<Result<Vec<_>>>()?;
    let tet_patches = (0..nt).map(|_| r.list()).collect::<Result<Vec<_>>>()?;
    let mesh = TetMesh { vertices, tets };
    let surface = if version == FIRST_VERSION { None } else { Some(r.surface()?) };
    let depth = if version > SURFACE_VERSION { r.depth(nt)? } else { None };
    if r.at != bytes.len() {
        return Err(Error::invalid(format!("{} unexpected byte(s) after the model", bytes.len() - r.at)));
    }
    let surface = match surface {
        Some(s) => s,
        // checked first: the boundary is made from the tets' vertex numbers
        None => {
            LstModel::check_tets(&mesh)?;
            LstModel::boundary_of(&mesh)?
        }
    };
    let mut model = LstModel::new(mesh, surface, sources, patches, tet_patches);
    if let Some(d) = depth {
        model = model.with_depth(d);
    }
    model.check()?;
    Ok(model)
}

struct Reader<'a> {
    bytes: &'a [u8],
    at: usize,
}

impl Reader<'_> {
    fn take(&mut self, n: usize) -> Result<&[u8]> {
        if self.bytes.len() - self.at < n {
            return Err(Error::invalid(format!("truncated at byte {} (needed {n} more)", self.at)));
        }
        self.at += n;
        Ok(&self.bytes[self.at - n..self.at])
    }

    fn u32(&mut self) -> Result<u32> {
        Ok(u32::from_le_bytes(self.take(4)?.try_into().expect("4 bytes")))
    }

    /// A count of items of at least `each` bytes, checked against the bytes left.
    fn count(&mut self, each: usize) -> Result<usize> {
        let n = self.u32()? as usize;
        if n.saturating_mul(each) > self.bytes.len() - self.at {
            return Err(Error::invalid(format!(
                "truncated or damaged: count {n} at byte {} is more than the file holds",
                self.at - 4
            )));
        }
        Ok(n)
    }

    fn f32(&mut self) -> Result<f32> {
        let x = f32::from_le_bytes(self.take(4)?.try_into().expect("4 bytes"));
        if x.is_finite() { Ok(x) } else { Err(Error::invalid(format!("non-finite number at byte {}", self.at - 4))) }
    }

    fn vec3(&mut self) -> Result<Vec3> {
        Ok(Vec3::new(self.f32()?, self.f32()?, self.f32()?))
    }

    fn text(&mut self) -> Result<String> {
        let n = self.count(1)?;
        String::from_utf8(self.take(n)?.to_vec())
            .map_err(|_| Error::invalid(format!("text at byte {} is not UTF-8", self.at)))
    }

    fn source(&mut self) -> Result<Source> {
        let (exemplar, volume) = (self.text()?, self.text()?);
        Ok(Source { exemplar, volume, mask: MaskRef::parse(&self.text()?)? })
    }

    fn patch(&mut self) -> Result<Patch> {
        let source = u16::from_le_bytes(self.take(2)?.try_into().expect("2 bytes"));
        let n = self.count(16)?;
        let vertices = (0..n).map(|_| self.u32()).collect::<Result<Vec<_>>>()?;
        if vertices.windows(2).any(|w| w[0] >= w[1]) {
            return Err(Error::invalid(format!("patch vertices before byte {} are not sorted", self.at)));
        }
        let coords = (0..n).map(|_| self.vec3()).collect::<Result<Vec<_>>>()?;
        Ok(Patch { source, vertices, coords })
    }

    /// The input surface: vertex and triangle counts, then each; checked as any mesh.
    fn surface(&mut self) -> Result<Mesh> {
        let (nv, nt) = (self.count(12)?, self.count(12)?);
        let vertices = (0..nv).map(|_| self.vec3()).collect::<Result<Vec<_>>>()?;
        let triangles = (0..nt).map(|_| Ok([self.u32()?, self.u32()?, self.u32()?])).collect::<Result<Vec<_>>>()?;
        Mesh::new(vertices, triangles).map_err(|e| Error::invalid(format!("the model's input surface: {e}")))
    }

    /// The smooth depth's bumps: a flag, then the depth axis, the sources that follow
    /// depth and six numbers per tet.
    fn depth(&mut self, tets: usize) -> Result<Option<DepthBumps>> {
        match self.u32()? {
            0 => Ok(None),
            1 => {
                let (axis, sources) = (self.u32()? as usize, self.u32()? as usize);
                if tets.saturating_mul(24) > self.bytes.len() - self.at {
                    return Err(Error::invalid(format!(
                        "truncated: the depth bumps of {tets} tets at byte {}",
                        self.at
                    )));
                }
                let edges = (0..tets)
                    .map(|_| Ok([self.f32()?, self.f32()?, self.f32()?, self.f32()?, self.f32()?, self.f32()?]))
                    .collect::<Result<Vec<_>>>()?;
                Ok(Some(DepthBumps { axis, sources, edges }))
            }
            flag => Err(Error::invalid(format!("depth flag {flag} at byte {}; allowed: 0 or 1", self.at - 4))),
        }
    }

    fn list(&mut self) -> Result<Vec<u32>> {
        let n = self.count(4)?;
        (0..n).map(|_| self.u32()).collect()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::fill::tets::cube_lattice;

    fn model() -> LstModel {
        let mesh = cube_lattice([2, 2, 2], 0.5);
        let surface = crate::mesh::shapes::ellipsoid(Vec3::splat(0.5), 6, 8);
        let vertices: Vec<u32> = (0..mesh.vertices.len() as u32).collect();
        let patch = Patch { source: 0, coords: mesh.vertices.clone(), vertices };
        let source = Source { exemplar: "e".into(), volume: "e.exr".into(), mask: MaskRef::File("m.exr".into()) };
        let tet_patches = vec![vec![0]; mesh.tets.len()];
        LstModel::new(mesh, surface, vec![source], vec![patch], tet_patches)
    }

    #[test]
    fn a_model_reads_back_with_its_input_surface() {
        let m = model();
        let back = from_bytes(&to_bytes(&m)).unwrap();
        assert_eq!(back, m);
        assert_eq!(back.surface, m.surface);
    }

    /// A model written before the input surface was kept (version 1: no surface after
    /// the patch lists) reads with its tets' boundary as the surface.
    #[test]
    fn a_first_version_model_reads_with_the_tets_boundary_as_its_surface() {
        let m = model();
        let mut bytes = to_bytes(&m);
        // two counts, then three numbers per vertex and per triangle
        let surface = 4 * (2 + 3 * m.surface.vertices.len() + 3 * m.surface.triangles.len());
        bytes.truncate(bytes.len() - surface - 4);
        bytes[8..12].copy_from_slice(&FIRST_VERSION.to_le_bytes());
        let old = from_bytes(&bytes).unwrap();
        assert_eq!(old.surface, LstModel::boundary_of(&m.mesh).unwrap());
        assert_eq!(old.mesh, m.mesh);
        bytes[8..12].copy_from_slice(&4u32.to_le_bytes());
        assert!(from_bytes(&bytes).unwrap_err().to_string().contains("versions 1 to 3"));
    }

    /// A depth-varying model keeps its depth bumps; a version 2 model (without them) reads
    /// with none; bumps out of range or of the wrong count are refused, naming what.
    #[test]
    fn depth_bumps_read_back_and_are_checked() {
        let tets = model().mesh.tets.len();
        let edges: Vec<[f32; 6]> = (0..tets).map(|t| [0.01 * t as f32, -0.02, 0.0, 0.03, 0.0, 0.1]).collect();
        let m = model().with_depth(DepthBumps { axis: 2, sources: 1, edges });
        let bytes = to_bytes(&m);
        assert_eq!(from_bytes(&bytes).unwrap(), m);
        let mut old = to_bytes(&model());
        old[8..12].copy_from_slice(&SURFACE_VERSION.to_le_bytes());
        old.truncate(old.len() - 4);
        assert_eq!(from_bytes(&old).unwrap().depth, None);
        let flag = bytes.len() - 4 * (3 + 6 * tets);
        let mut bad = bytes.clone();
        bad[flag..flag + 4].copy_from_slice(&2u32.to_le_bytes());
        assert!(from_bytes(&bad).unwrap_err().to_string().contains("depth flag 2"));
        let mut bad = bytes.clone();
        bad[flag + 4..flag + 8].copy_from_slice(&3u32.to_le_bytes());
        assert!(from_bytes(&bad).unwrap_err().to_string().contains("axis 3"));
        let mut bad = bytes.clone();
        bad[flag + 12..flag + 16].copy_from_slice(&1.5f32.to_le_bytes());
        assert!(from_bytes(&bad).unwrap_err().to_string().contains("outside -1 to 1"));
        let mut bad = bytes.clone();
        bad.truncate(bytes.len() - 4);
        assert!(from_bytes(&bad).unwrap_err().to_string().contains("truncated"));
    }
}
