//! One exemplar at one pyramid level, prepared for search: its neighbourhood vectors
//! projected by PCA, and k-coherence sets (for every valid centre, the k centres
//! whose neighbourhoods are most alike, itself first); or, for a level never matched,
//! only its pixels and centres ([`Prepared::unsearched`]).
//!
//! A centre is valid when its whole n x n neighbourhood lies inside the image:
//!
//! ```text
//!  offsets -h .. n-1-h  (h = n / 2)     valid x: h ..= width - n + h
//! ```

use super::knn::KdTree;
use super::pca::Pca;
use crate::noise::mix64;
use crate::volume::Image2d;
use rayon::prelude::*;
use std::sync::OnceLock;
use std::sync::atomic::{AtomicU32, Ordering};

/// Most neighbourhood vectors used to fit the PCA basis (evenly strided).
const PCA_SAMPLES: usize = 4096;

/// Leading PCA dimensions the coherence kd-tree splits on (candidates are re-ranked in all).
const TREE_DIMS: usize = 6;

/// Leading PCA dimensions of the lookup tree that starts each finer level's search. Two
/// (roughly a neighbourhood's mean and slope) gave the photos the same slice energies as
/// four (within 0.01), and the lookup pass then costs no more than the k-coherence pass
/// it replaces; with four the whole run took 25 % longer (docs/synthesis.md).
const LOOKUP_DIMS: usize = 2;

/// An exemplar level ready for neighbourhood search.
#[derive(Debug, Clone)]
pub struct Prepared {
    /// Width in pixels.
    pub width: usize,
    /// Height in pixels.
    pub height: usize,
    /// Samples per pixel.
    pub channels: usize,
    /// Raw samples, interleaved.
    pub colours: Vec<f32>,
    /// Per-channel weights used in neighbourhood distances.
    pub weights: Vec<f32>,
    /// Neighbourhood side.
    pub n: usize,
    /// Pixel index of every valid centre, row-major.
    pub centres: Vec<u32>,
    /// Pixel column and row of every valid centre (the search's inner loops read these
    /// instead of dividing a pixel index by the width).
    pub centre_xy: Vec<[u32; 2]>,
    /// The PCA projection of neighbourhood vectors.
    pub pca: Pca,
    /// The projected neighbourhood of every centre, one row per slot.
    pub projected: LineRows,
    /// The k-coherence sets, each found when first asked for ([`Prepared::coherence_of`]).
    coherence: Coherence,
    /// Size of each coherence set.
    pub k: usize,
    /// Every centre's slot by its first [`LOOKUP_DIMS`] projected components: the
    /// nearest-neighbour lookup over the whole exemplar.
    pub lookup: KdTree,
}

/// What preparing needs besides the image.
#[derive(Debug, Clone, Copy)]
pub struct PrepareOptions {
    /// Neighbourhood side.
    pub n: usize,
    /// Share of variance PCA keeps.
    pub variance: f32,
    /// Most PCA dimensions.
    pub max_dims: usize,
    /// Coherence set size (0: no coherence sets, for measuring only).
    pub k: usize,
}

impl Prepared {
    /// Prepare `image` with per-channel `weights`.
    pub fn new(image: &Image2d, weights: &[f32], opt: PrepareOptions) -> Prepared {
        let mut prepared = Prepared::unsearched(image, weights, opt);
        let vectors = prepared.all_vectors();
        let m = opt.n * opt.n * prepared.channels;
        prepared.pca = fit_sampled(&vectors, m, opt.variance, opt.max_dims);
        prepared.projected = LineRows::new(&project_all(&prepared.pca, &vectors, m), prepared.pca.dims);
        let low = prepared.pca.dims.min(LOOKUP_DIMS);
        prepared.lookup = KdTree::build(prepared.projected.packed(low), low);
        if opt.k > 0 {
            let low = prepared.pca.dims.min(TREE_DIMS);
            let tree = KdTree::build(prepared.projected.packed(low), low);
            prepared.coherence = Coherence::new(tree, low, prepared.centres.len(), opt.k);
        }
        prepared
    }

    /// `image`'s pixels and neighbourhood centres without anything to search them by: for
    /// a level that is never matched, only read (a level that only magnifies the one below).
    pub fn unsearched(image: &Image2d, weights: &[f32], opt: PrepareOptions) -> Prepared {
        let (width, height, channels) = (image.width(), image.height(), image.channel_count());
        let h = opt.n / 2;
        let centres: Vec<u32> = (h..=height - opt.n + h)
            .flat_map(|y| (h..=width - opt.n + h).map(move |x| (y * width + x) as u32))
            .collect();
        let centre_xy = centres.iter().map(|&c| [c % width as u32, c / width as u32]).collect();
        Prepared {
            width,
            height,
            channels,
            colours: image.data().to_vec(),
            weights: weights.to_vec(),
            n: opt.n,
            centres,
            centre_xy,
            pca: Pca { input: 0, dims: 0, mean: vec![], basis: vec![], explained: 0.0 },
            projected: LineRows::new(&[], 1),
            coherence: Coherence::new(KdTree::build(Vec::new(), 0), 0, 0, 0),
            k: opt.k,
            lookup: KdTree::build(Vec::new(), 0),
        }
    }

    /// Offset range start: offsets run from `-half` to `n - 1 - half`.
    pub fn half(&self) -> usize {
        self.n / 2
    }

    /// The weighted neighbourhood vector of the centre at pixel `(cx, cy)`, appended to `out`.
    pub fn vector(&self, cx: usize, cy: usize, out: &mut Vec<f32>) {
        let h = self.half();
        for dy in 0..self.n {
            for dx in 0..self.n {
                let p = (cy + dy - h) * self.width + cx + dx - h;
                let px = &self.colours[p * self.channels..(p + 1) * self.channels];
                out.extend(px.iter().zip(&self.weights).map(|(v, w)| v * w));
            }
        }
    }

    fn all_vectors(&self) -> Vec<f32> {
        let m = self.n * self.n * self.channels;
        let mut out = Vec::with_capacity(self.centres.len() * m);
        for &c in &self.centres {
            let c = c as usize;
            self.vector(c % self.width, c / self.width, &mut out);
        }
        out
    }

    /// The slot of the valid centre nearest to pixel (x, y) (no division: the search's
    /// inner loop calls this for every candidate source).
    #[inline]
    pub fn clamped_slot(&self, x: i64, y: i64) -> usize {
        let (vw, vh) = ((self.width + 1 - self.n) as i64, (self.height + 1 - self.n) as i64);
        let h = self.half() as i64;
        ((y - h).clamp(0, vh - 1) * vw + (x - h).clamp(0, vw - 1)) as usize
    }

    /// The pixel column and row of the centre in `slot`.
    #[inline]
    pub fn slot_xy(&self, slot: usize) -> (i64, i64) {
        let [x, y] = self.centre_xy[slot];
        (i64::from(x), i64::from(y))
    }

    /// The projected neighbourhood of the centre in `slot`.
    pub fn projection(&self, slot: usize) -> &[f32] {
        self.projected.row(slot)
    }

    /// A pseudo-random valid centre from a hash value.
    pub fn random_centre(&self, hash: u64) -> u32 {
        self.centres[self.random_slot(hash)]
    }

    /// The slot of a pseudo-random valid centre.
    pub fn random_slot(&self, hash: u64) -> usize {
        (mix64(hash) % self.centres.len() as u64) as usize
    }

    /// The k-coherence set of the centre in `slot`: itself, then its k - 1 most alike
    /// centres (in the projection) that are at least `max(n / 2, 2)` pixels away (close
    /// spatial neighbours would add nothing new). Found on first use: a large photo's
    /// search visits a fraction of its centres, and a set is the same whichever thread
    /// asks first.
    pub fn coherence_of(&self, slot: usize) -> impl Iterator<Item = u32> + '_ {
        let set = &self.coherence.sets[slot * self.k..(slot + 1) * self.k];
        self.coherence.found[slot].get_or_init(|| {
            set.iter().zip(self.coherence_set(slot)).for_each(|(at, c)| at.store(c, Ordering::Relaxed));
        });
        set.iter().map(|c| c.load(Ordering::Relaxed))
    }

    fn coherence_set(&self, slot: usize) -> Vec<u32> {
        let Coherence { tree, low, .. } = &self.coherence;
        let k = self.k;
        let away = (self.n / 2).max(2) as i64;
        let here = self.projection(slot);
        let (mx, my) = self.slot_xy(slot);
        let mut hits: Vec<(f32, u32)> = tree
            .nearest(&here[..*low], 2 * k + 6)
            .into_iter()
            .map(|(_, i)| (super::knn::squared(here, self.projection(i as usize)), i))
            .collect();
        hits.sort_by(|a, b| a.0.total_cmp(&b.0).then(a.1.cmp(&b.1)));
        let others = hits.into_iter().map(|(_, i)| i).filter(move |&i| {
            let (px, py) = self.slot_xy(i as usize);
            (px - mx).abs().max((py - my).abs()) >= away
        });
        let mut set: Vec<u32> = std::iter::once(slot as u32).chain(others).take(k).collect();
        set.resize(k, slot as u32);
        set
    }
}

/// The k-coherence sets of an exemplar level: the kd-tree over the leading
/// [`TREE_DIMS`] projected components that finds them, and each centre's set once found,
/// all sets in one array (`k` per centre, read in place by the search's hot loop).
#[derive(Debug)]
struct Coherence {
    tree: KdTree,
    low: usize,
    found: Vec<OnceLock<()>>,
    sets: Vec<AtomicU32>,
}

impl Coherence {
    fn new(tree: KdTree, low: usize, centres: usize, k: usize) -> Coherence {
        let sets = (0..centres * k).map(|_| AtomicU32::new(0)).collect();
        Coherence { tree, low, found: vec![OnceLock::new(); centres], sets }
    }
}

impl Clone for Coherence {
    fn clone(&self) -> Coherence {
        // the marks first: a set marked found was stored before its mark
        let found = self.found.clone();
        let sets = self.sets.iter().map(|c| AtomicU32::new(c.load(Ordering::Relaxed))).collect();
        Coherence { tree: self.tree.clone(), low: self.low, found, sets }
    }
}

/// Rows of equal length laid out on 64-byte cache lines: a row of up to 16 values lies
/// inside one line, a longer one starts a line, so reading one candidate's projection
/// never touches the end of one line and the start of the next.
#[derive(Debug)]
pub struct LineRows {
    data: Vec<f32>,
    start: usize,
    stride: usize,
    width: usize,
}

/// f32 values per cache line.
const LINE: usize = 16;

impl LineRows {
    /// Lay out the rows of `width` values in `values`.
    pub fn new(values: &[f32], width: usize) -> LineRows {
        // Rows of up to a line take a power-of-two share of one (6 values: half a line).
        let stride = if width <= LINE { width.max(1).next_power_of_two() } else { width.div_ceil(LINE) * LINE };
        let count = values.len() / width.max(1);
        let mut data = vec![0.0; count * stride + LINE];
        let misaligned = (data.as_ptr() as usize / std::mem::size_of::<f32>()) % LINE;
        let start = (LINE - misaligned) % LINE;
        for (i, row) in values.chunks_exact(width.max(1)).enumerate() {
            data[start + i * stride..start + i * stride + width].copy_from_slice(row);
        }
        LineRows { data, start, stride, width }
    }

    /// Row `i`.
    #[inline]
    pub fn row(&self, i: usize) -> &[f32] {
        let at = self.start + i * self.stride;
        &self.data[at..at + self.width]
    }

    /// The first `width` values of every row, packed one row after another.
    pub fn packed(&self, width: usize) -> Vec<f32> {
        let rows = (self.data.len() - LINE) / self.stride;
        (0..rows).flat_map(|i| self.row(i)[..width].iter().copied()).collect()
    }
}

impl Clone for LineRows {
    /// A copy aligned for its own allocation.
    fn clone(&self) -> LineRows {
        LineRows::new(&self.packed(self.width), self.width)
    }
}

/// A PCA of row-major `vectors` of length `m`, fitted on at most [`PCA_SAMPLES`] of them
/// (evenly strided).
pub(crate) fn fit_sampled(vectors: &[f32], m: usize, variance: f32, max_dims: usize) -> Pca {
    let stride = (vectors.len() / m / PCA_SAMPLES).max(1);
    let sample: Vec<f32> = vectors.chunks_exact(m).step_by(stride).flatten().copied().collect();
    Pca::fit(&sample, m, variance, max_dims)
}

/// Every vector of `vectors` (length `m` each) projected by `pca`, in parallel.
pub(crate) fn project_all(pca: &Pca, vectors: &[f32], m: usize) -> Vec<f32> {
    let dims = pca.dims;
    let mut out = vec![0.0; vectors.len() / m * dims];
    out.par_chunks_mut(dims * 256).zip(vectors.par_chunks(m * 256)).for_each(|(o, v)| {
        for (oi, vi) in o.chunks_exact_mut(dims).zip(v.chunks_exact(m)) {
            pca.project(vi, oi);
        }
    });
    out
}
pub use super::knn::squared;

#[cfg(test)]
mod tests {
    use super::*;

    /// Rows read back unchanged and never cross a cache line, copies included.
    #[test]
    fn line_rows_keep_values_inside_lines() {
        for width in [1, 3, 6, 8, 16, 20] {
            let values: Vec<f32> = (0..width * 37).map(|i| i as f32 * 0.5).collect();
            let rows = LineRows::new(&values, width);
            for copy in [&rows, &rows.clone()] {
                for i in 0..37 {
                    let row = copy.row(i);
                    assert_eq!(row, &values[i * width..(i + 1) * width], "width {width}, row {i}");
                    let at = row.as_ptr() as usize % 64;
                    assert!(if width <= LINE { at + 4 * width <= 64 } else { at == 0 }, "width {width}, row {i}");
                }
            }
        }
    }
}
