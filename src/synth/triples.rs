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
//! crossbar distances are least.

use crate::synth::exemplar::Prepared;
use crate::synth::knn::KdTree;
use crate::volume::Axis;
use rayon::prelude::*;

/// Pixels of each other plane considered per pixel before pairing.
const WIDE: usize = 8;

/// The candidate triples of one pyramid level.
#[derive(Debug, Clone)]
pub struct Triples {
    /// Triples per centre.
    pub k: usize,
    /// Per plane, per centre slot of that plane's exemplar, `k` triples of centre slots
    /// (one per plane), best first.
    pub sets: [Vec<[u32; 3]>; 3],
}

impl Triples {
    /// The candidate triples of `planes` (one level of each plane's exemplar).
    pub fn new(planes: [&Prepared; 3], k: usize) -> Triples {
        let bars = [0, 1, 2].map(|p| [0, 1, 2].map(|axis| (axis != p).then(|| crossbars(planes[p], p, axis))));
        let trees = [0, 1, 2].map(|p| {
            [0, 1, 2]
                .map(|axis| bars[p][axis].as_ref().map(|b| KdTree::build(b.clone(), planes[p].n * planes[p].channels)))
        });
        let sets = [0, 1, 2].map(|a| {
            let (b, c) = others(a);
            let width = planes[a].n * planes[a].channels;
            (0..planes[a].centres.len())
                .into_par_iter()
                .flat_map_iter(|slot| {
                    let mine =
                        |axis: usize| &bars[a][axis].as_ref().expect("a plane's own axes")[slot * width..][..width];
                    // plane b shares axis c with a; plane c shares axis b
                    let near_b = trees[b][c].as_ref().expect("shared axis").nearest(mine(c), WIDE);
                    let near_c = trees[c][b].as_ref().expect("shared axis").nearest(mine(b), WIDE);
                    let bar = |p: usize, axis: usize, s: u32| {
                        let w = planes[p].n * planes[p].channels;
                        &bars[p][axis].as_ref().expect("a plane's own axes")[s as usize * w..][..w]
                    };
                    let mut pairs: Vec<(f32, u32, u32)> = Vec::with_capacity(WIDE * WIDE);
                    for &(db, sb) in &near_b {
                        for &(dc, sc) in &near_c {
                            let across = crate::synth::exemplar::squared(bar(b, a, sb), bar(c, a, sc));
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
