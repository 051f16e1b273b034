//! A pasted patch and the small pieces of geometry the paste loop uses: the 165 coverage
//! samples per tet, the mask-touch test, random frames, and pruning a patch to the tets
//! it shows in.

use super::sampler::{BATCH, Sampler};
use super::tets::{NONE, TetMesh};
use glam::Vec3;
use rand::RngExt;
use rand_pcg::Pcg64Mcg;

/// Sample points per tet for the coverage test.
pub const SAMPLES: usize = 165;

/// [`SAMPLES`] rounded up to whole batches of [`BATCH`].
pub const BATCHED: usize = SAMPLES.next_multiple_of(BATCH);

/// A pasted patch: which source it shows and the texture coordinates of its vertices.
#[derive(Debug, Clone, PartialEq)]
pub struct Patch {
    /// Index of the (exemplar, mask) source.
    pub source: u16,
    /// The patch's vertices, sorted.
    pub vertices: Vec<u32>,
    /// Texture coordinates, one per vertex.
    pub coords: Vec<Vec3>,
}

impl Patch {
    /// The texture coordinates of the corners of `tet` (all must be patch vertices).
    pub fn corners(&self, tet: [u32; 4]) -> [Vec3; 4] {
        tet.map(|v| self.coords[self.vertices.binary_search(&v).expect("patch vertex")])
    }
}

/// Drops the vertices of tets the patch does not show in (`alphas`: [`SAMPLES`] coverage
/// bytes per tet of `tets`; `local`: the [`local_index`] of the patch's vertices).
pub fn prune(patch: Patch, local: &[u32], mesh: &TetMesh, tets: &[u32], alphas: &[u8]) -> Patch {
    let shown: Vec<u32> = tets
        .iter()
        .zip(alphas.chunks_exact(SAMPLES))
        .filter(|(_, a)| a.iter().any(|x| *x > 0))
        .map(|(t, _)| *t)
        .collect();
    let vertices = vertices_of(mesh, &shown);
    let coords = vertices.iter().map(|&v| patch.coords[local[v as usize] as usize]).collect();
    Patch { source: patch.source, vertices, coords }
}

/// The vertices of `tets`, sorted, each once.
pub fn vertices_of(mesh: &TetMesh, tets: &[u32]) -> Vec<u32> {
    let mut seen = vec![false; mesh.vertices.len()];
    let corners = tets.iter().flat_map(|&t| mesh.tets[t as usize]);
    let mut v: Vec<u32> = corners.filter(|&v| !std::mem::replace(&mut seen[v as usize], true)).collect();
    v.sort_unstable();
    v
}

/// For each vertex of `mesh`, its index in `vertices`, or [`NONE`] where it is not there.
pub fn local_index(mesh: &TetMesh, vertices: &[u32]) -> Vec<u32> {
    let mut local = vec![NONE; mesh.vertices.len()];
    vertices.iter().enumerate().for_each(|(i, &v)| local[v as usize] = i as u32);
    local
}

/// `s` made orthogonal to the unit vector `r` and normalized (any orthogonal unit vector if
/// `s` is parallel to `r`).
pub fn orthogonal(s: Vec3, r: Vec3) -> Vec3 {
    (s - s.dot(r) * r).try_normalize().unwrap_or_else(|| r.any_orthonormal_vector())
}

/// A uniformly random orthonormal frame.
pub fn random_frame(rng: &mut Pcg64Mcg) -> [Vec3; 3] {
    let mut unit = || {
        let z = rng.random::<f32>() * 2.0 - 1.0;
        let phi = rng.random::<f32>() * std::f32::consts::TAU;
        let r = (1.0 - z * z).max(0.0).sqrt();
        Vec3::new(r * phi.cos(), r * phi.sin(), z)
    };
    let a = unit();
    let b = orthogonal(unit(), a);
    [a, b, a.cross(b)]
}

/// The 165 barycentric sample points `(i, j, k, l) / 8`.
pub fn sample_points() -> Vec<[f32; 4]> {
    let mut out = Vec::with_capacity(SAMPLES);
    for i in 0..=8 {
        for j in 0..=8 - i {
            for k in 0..=8 - i - j {
                out.push([i, j, k, 8 - i - j - k].map(|n| n as f32 / 8.0));
            }
        }
    }
    out
}

/// The coverage samples in batches for [`Sampler::alphas`], `[batch][corner][lane]`
/// (barycentric), the last batch padded with the last sample.
pub fn sample_batches() -> Vec<[[f32; BATCH]; 4]> {
    let points = sample_points();
    let at = |i: usize| points[i.min(SAMPLES - 1)];
    (0..BATCHED / BATCH).map(|j| std::array::from_fn(|k| std::array::from_fn(|i| at(j * BATCH + i)[k]))).collect()
}

/// The mask's value at each coverage sample of a tet whose corners have texture
/// coordinates `w`, into `out` ([`BATCHED`] long): bit for bit the single lookups at
/// `w[0] b[0] + w[1] b[1] + w[2] b[2] + w[3] b[3]`.
pub fn mask_at_samples(mask: &Sampler, w: &[Vec3; 4], batches: &[[[f32; BATCH]; 4]], out: &mut [f32]) {
    for (b, o) in batches.iter().zip(out.chunks_exact_mut(BATCH)) {
        let mut p = [[0.0; BATCH]; 3];
        for (k, axis) in p.iter_mut().enumerate() {
            for (i, x) in axis.iter_mut().enumerate() {
                *x = w[0][k] * b[0][i] + w[1][k] * b[1][i] + w[2][k] * b[2][i] + w[3][k] * b[3][i];
            }
        }
        o.copy_from_slice(&mask.alphas(&p));
    }
}

/// Alpha in [0, 1] as a coverage byte.
pub fn to_byte(a: f32) -> u8 {
    // rounding half up by truncation: the value is not negative (NaN stays NaN through the
    // clamp and `as u8` turns it into 0)
    (a.clamp(0.0, 1.0) * 255.0 + 0.5) as u8
}

/// Whether a tet with corner texture coords `w` reaches into the mask (sampled at its
/// corners, edge midpoints and centre).
pub fn touches(mask: &Sampler, w: [Vec3; 4]) -> bool {
    let centre = (w[0] + w[1] + w[2] + w[3]) / 4.0;
    let mids = super::tets::EDGES.map(|(a, b)| (w[a] + w[b]) / 2.0);
    w.iter().chain(&mids).chain(std::iter::once(&centre)).any(|p| mask.alpha(*p) > 0.0)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn there_are_165_samples_summing_to_one() {
        let s = sample_points();
        assert_eq!(s.len(), SAMPLES);
        assert!(s.iter().all(|b| (b.iter().sum::<f32>() - 1.0).abs() < 1e-6));
    }
}
