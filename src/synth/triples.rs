//! Candidate triples (Dong et al. 2008, used by Zhang et al. 2011 §3): for every exemplar
//! pixel of each plane, the pixels of the two other planes that make a consistent voxel
//! with it. Two planes share an axis, and their neighbourhoods cross along it: a triple is
//! good when the three crossbars agree.
//!
//! ```text
//!  plane a is orthogonal to frame axis a; planes a and b share axis c (the third)
//!  plane 0: columns y, rows z    plane 1: columns x, rows z    plane 2: columns x, rows y
//!  the crossbar of plane p along axis c: its row segment if c is its column axis, else
//!  its column segment (n pixels through the centre)
//! ```
//!
//! For pixel p of plane a: the `WIDE` pixels of plane b nearest by the crossbar on the axis
//! a and b share, the same for plane c, and of those pairs the `k` whose summed three
//! crossbar distances are least. The nearest crossbars are found among a shortlist by
//! their leading PCA dimensions (a tree over 20 dimensions visits most of its leaves).

use crate::synth::exemplar::{Prepared, fit_sampled, project_all};
use crate::synth::knn::KdTree;
use crate::synth::pca::Pca;
use crate::volume::Axis;
use rayon::prelude::*;
use std::sync::Arc;

/// Pixels of each other plane considered per pixel before pairing.
const WIDE: usize = 8;

/// Leading PCA dimensions of the crossbar trees; each search takes [`SHORTLIST`] points
/// by them and keeps the [`WIDE`] nearest by whole crossbars.
const TREE_DIMS: usize = 6;

/// Points a crossbar search takes by its leading dimensions.
const SHORTLIST: usize = 2 * WIDE;

/// Points a crossbar search weighs before it settles for the best found.
const BUDGET: usize = 8 * SHORTLIST;

/// The candidate triples of one pyramid level.
#[derive(Debug, Clone)]
pub struct Triples {
    /// Triples per centre.
    pub k: usize,
    /// Per plane, per centre slot of that plane's exemplar, `k` triples of centre slots
    /// (one per plane), best first.
    pub sets: [Vec<[u32; 3]>; 3],
}

/// The crossbars of one plane along one axis, and a tree over their leading PCA
/// dimensions.
struct Bars {
    /// `n` weighted pixels per centre, one centre after another.
    values: Vec<f32>,
    /// Values per crossbar.
    width: usize,
    pca: Pca,
    tree: KdTree,
}

impl Bars {
    fn new(values: Vec<f32>, width: usize) -> Bars {
        let pca = fit_sampled(&values, width, 1.0, TREE_DIMS);
        let tree = KdTree::build(project_all(&pca, &values, width), pca.dims);
        Bars { values, width, pca, tree }
    }

    /// The crossbar of centre `slot`.
    fn of(&self, slot: usize) -> &[f32] {
        &self.values[slot * self.width..][..self.width]
    }

    /// The [`WIDE`] crossbars nearest to `query` (a crossbar of another plane along the
    /// same axis): a shortlist by the leading dimensions, ranked by whole crossbars.
    fn nearest(&self, query: &[f32]) -> Vec<(f32, u32)> {
        let mut low = vec![0.0; self.pca.dims];
        self.pca.project(query, &mut low);
        let mut hits: Vec<(f32, u32)> = self
            .tree
            .nearest_within(&low, SHORTLIST, BUDGET)
            .into_iter()
            .map(|(_, i)| (crate::synth::exemplar::squared(query, self.of(i as usize)), i))
            .collect();
        hits.sort_by(|x, y| x.0.total_cmp(&y.0).then(x.1.cmp(&y.1)));
        hits.truncate(WIDE);
        hits
    }
}

impl Triples {
    /// No triples: for a level that is never corrected.
    pub fn none() -> Triples {
        Triples { k: 0, sets: [Vec::new(), Vec::new(), Vec::new()] }
    }

    /// The candidate triples of `planes` (one level of each plane's exemplar).
    pub fn new(planes: [&Prepared; 3], k: usize) -> Triples {
        let bars = all_bars(planes);
        let bar = |p: usize, axis: usize| bars[p][axis].as_deref().expect("a plane's own axes");
        let sets = [0, 1, 2].map(|a| {
            let (b, c) = others(a);
            (0..planes[a].centres.len())
                .into_par_iter()
                .flat_map_iter(|slot| {
                    // plane b shares axis c with a; plane c shares axis b
                    let near_b = bar(b, c).nearest(bar(a, c).of(slot));
                    let near_c = bar(c, b).nearest(bar(a, b).of(slot));
                    let mut pairs: Vec<(f32, u32, u32)> = Vec::with_capacity(WIDE * WIDE);
                    for &(db, sb) in &near_b {
                        for &(dc, sc) in &near_c {
                            let across =
                                crate::synth::exemplar::squared(bar(b, a).of(sb as usize), bar(c, a).of(sc as usize));
                            pairs.push((db + dc + across, sb, sc));
                        }
                    }
                    pairs.sort_by(|x, y| x.0.total_cmp(&y.0).then(x.1.cmp(&y.1)).then(x.2.cmp(&y.2)));
                    let triple = move |&(_, sb, sc): &(f32, u32, u32)| {
                        let mut t = [0u32; 3];
                        t[a] = slot as u32;
                        t[b] = sb;
                        t[c] = sc;
                        t
                    };
                    let mut set: Vec<[u32; 3]> = pairs.iter().take(k).map(triple).collect();
                    let last = *set.last().expect("one pair at least");
                    set.resize(k, last);
                    set
                })
                .collect()
        });
        Triples { k, sets }
    }

    /// The triples of centre `slot` of plane `a`.
    pub fn of(&self, a: usize, slot: usize) -> &[[u32; 3]] {
        &self.sets[a][slot * self.k..(slot + 1) * self.k]
    }
}

/// The two other planes, in order.
fn others(a: usize) -> (usize, usize) {
    match a {
        0 => (1, 2),
        1 => (0, 2),
        _ => (0, 1),
    }
}

/// Per plane and axis of it, its crossbars ([`Bars`]); planes showing the same image
/// share the crossbars of the same direction (rows or columns), built once.
fn all_bars(planes: [&Prepared; 3]) -> [[Option<Arc<Bars>>; 3]; 3] {
    let mut made: Vec<((usize, bool), Arc<Bars>)> = Vec::new();
    [0, 1, 2].map(|p| {
        [0, 1, 2].map(|axis| {
            if axis == p {
                return None;
            }
            let key = (std::ptr::from_ref(planes[p]) as usize, axis == Axis::ALL[p].plane_axes().0);
            if let Some((_, bars)) = made.iter().find(|(k, _)| *k == key) {
                return Some(bars.clone());
            }
            let bars = Arc::new(Bars::new(crossbars(planes[p], p, axis), planes[p].n * planes[p].channels));
            made.push((key, bars.clone()));
            Some(bars)
        })
    })
}

/// The crossbar along `axis` of every centre of plane `p`'s exemplar: `n` weighted pixels
/// through it along its row (when `axis` is the plane's column axis) or column.
fn crossbars(ex: &Prepared, p: usize, axis: usize) -> Vec<f32> {
    let (columns, _) = Axis::ALL[p].plane_axes();
    let (n, h, ch) = (ex.n, ex.half(), ex.channels);
    let mut out = Vec::with_capacity(ex.centres.len() * n * ch);
    for &c in &ex.centres {
        let (x, y) = (c as usize % ex.width, c as usize / ex.width);
        for i in 0..n {
            let (px, py) = if axis == columns { (x + i - h, y) } else { (x, y + i - h) };
            let at = (py * ex.width + px) * ch;
            out.extend(ex.colours[at..at + ch].iter().zip(&ex.weights).map(|(v, w)| v * w));
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::synth::exemplar::PrepareOptions;
    use crate::volume::{Channel, Image2d};

    /// On an exemplar of colour f(x) + f(y), every crossbar of a pixel is found in the
    /// other planes: the best triples' three crossbars agree far better than random ones.
    #[test]
    fn the_best_triples_agree_along_all_three_crossbars() {
        let (w, h) = (24, 24);
        let f = |t: usize| (t as f32 * 0.37).sin() * 0.3;
        let data: Vec<f32> = (0..w * h).map(|i| 0.5 + f(i % w) + f(i / w)).collect();
        let image = Image2d::from_data(w, h, Channel::grey(), data).unwrap();
        let ex = Prepared::new(&image, &[1.0], PrepareOptions { n: 5, variance: 1.0, max_dims: 8, k: 0 });
        let t = Triples::new([&ex, &ex, &ex], 3);
        let bars: Vec<[Vec<f32>; 3]> = (0..3).map(|p| [0, 1, 2].map(|axis| crossbars(&ex, p, axis))).collect();
        let disagreement = |triple: [u32; 3]| -> f32 {
            [(1, 2, 0), (0, 2, 1), (0, 1, 2)]
                .iter()
                .map(|&(p, q, axis)| {
                    let bar = |plane: usize| &bars[plane][axis][triple[plane] as usize * 5..][..5];
                    crate::synth::exemplar::squared(bar(p), bar(q))
                })
                .sum()
        };
        let count = ex.centres.len() as u32;
        let (mut best, mut random) = (0.0, 0.0);
        for a in 0..3 {
            for slot in 0..count {
                let triple = t.of(a, slot as usize)[0];
                assert_eq!(triple[a], slot, "plane {a}: the triple holds its own pixel");
                best += disagreement(triple);
                random += disagreement([slot, (slot * 7 + 3) % count, (slot * 13 + 5) % count]);
            }
        }
        assert!(best * 10.0 < random, "best triples disagree by {best}, random ones by {random}");
    }
}
