//! How coherently a coordinate solid copies its exemplars: in cuts across each axis, the
//! patches of voxels that copy one piece of the exemplar of the cut's plane.
//!
//! ```text
//!  cuts        across each matched plane's axis at 1/4, 1/2 and 3/4 of the grid (as the
//!              sharpness and line figures); a voxel's pixel is its triple's member of the
//!              plane the cut lies in
//!  coherent    two 4-neighbours of a cut whose pixels differ by the neighbours' own
//!              offset (one step along the plane's first or second axis)
//!  patches     4-connected groups joined by coherent pairs
//! ```
//!
//! A patch as large as the exemplar is a visible tile; a solid of one-voxel patches copies
//! nothing coherently and keeps only what single pixels say (its lines break wherever
//! neighbours disagree).

use crate::volume::Axis;
use serde::{Deserialize, Serialize};

/// The largest share of its exemplar's area one patch may cover before a cut looks tiled.
pub const LARGEST_PATCH_MOST: f64 = 0.25;

/// The provenance key of [`Patches::coherent_pairs`] in a synthesized volume.
pub const COHERENT_PAIRS_KEY: &str = "coherent_pairs";
/// The provenance key of [`Patches::largest`].
pub const LARGEST_KEY: &str = "largest_patch";

/// The patch figures of a solid.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Patches {
    /// Share of the cuts' 4-neighbour pairs that are coherent.
    pub coherent_pairs: f64,
    /// The largest patch of any cut, as a share of its exemplar's area.
    pub largest: f64,
}

impl Patches {
    /// The figures a synthesis recorded in `meta`, if it did.
    pub fn of_meta(meta: &crate::volume::Meta) -> Option<Patches> {
        let read = |key: &str| meta.get(key).and_then(|v| v.parse::<f64>().ok()).filter(|v| v.is_finite() && *v >= 0.0);
        Some(Patches { coherent_pairs: read(COHERENT_PAIRS_KEY)?, largest: read(LARGEST_KEY)? })
    }
}

/// The patch figures of a grid of `dims` voxels whose voxel `v` shows pixel `pixel(a, v)`
/// of plane `a`'s exemplar (column, row), for the planes in `planes`; `areas[a]` is plane
/// `a`'s exemplar's area in pixels. `None` without a plane or a cut of two voxels.
pub fn measure(
    dims: [usize; 3],
    planes: std::ops::Range<usize>,
    areas: [usize; 3],
    pixel: impl Fn(usize, [usize; 3]) -> (i64, i64),
) -> Option<Patches> {
    let (mut coherent, mut pairs, mut largest) = (0usize, 0usize, 0.0f64);
    for a in planes {
        let (pa, sa) = Axis::ALL[a].plane_axes();
        let (w, h) = (dims[pa], dims[sa]);
        for quarter in 1..=3 {
            let at = dims[a] * quarter / 4;
            let voxel = |x: usize, y: usize| {
                let mut v = [0; 3];
                (v[a], v[pa], v[sa]) = (at, x, y);
                v
            };
            let pixels: Vec<(i64, i64)> = (0..w * h).map(|i| pixel(a, voxel(i % w, i / w))).collect();
            let cut = Cut::join(&pixels, w, h);
            coherent += cut.coherent;
            pairs += cut.pairs;
            largest = largest.max(cut.largest as f64 / areas[a].max(1) as f64);
        }
    }
    (pairs > 0).then(|| Patches { coherent_pairs: coherent as f64 / pairs as f64, largest })
}

/// One cut's coherent pairs, its pairs and its largest patch in voxels.
struct Cut {
    coherent: usize,
    pairs: usize,
    largest: usize,
}

impl Cut {
    /// Join the coherent neighbours of a `w` x `h` cut of `pixels` (rows of `w`).
    fn join(pixels: &[(i64, i64)], w: usize, h: usize) -> Cut {
        let mut parent: Vec<usize> = (0..w * h).collect();
        let mut cut = Cut { coherent: 0, pairs: 0, largest: 0 };
        for i in 0..w * h {
            let (x, y) = (i % w, i / w);
            let (px, py) = pixels[i];
            let right = (x + 1 < w).then(|| (i + 1, (px + 1, py)));
            let below = (y + 1 < h).then(|| (i + w, (px, py + 1)));
            for (j, expected) in right.into_iter().chain(below) {
                cut.pairs += 1;
                if pixels[j] == expected {
                    cut.coherent += 1;
                    let (ri, rj) = (root(&mut parent, i), root(&mut parent, j));
                    parent[ri.max(rj)] = ri.min(rj);
                }
            }
        }
        let mut sizes = vec![0usize; w * h];
        for i in 0..w * h {
            let r = root(&mut parent, i);
            sizes[r] += 1;
            cut.largest = cut.largest.max(sizes[r]);
        }
        cut
    }
}

/// The root of `i`'s group, halving the paths on the way.
fn root(parent: &mut [usize], mut i: usize) -> usize {
    while parent[i] != i {
        parent[i] = parent[parent[i]];
        i = parent[i];
    }
    i
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_solid_copying_one_exemplar_whole_is_one_patch_per_cut() {
        // every voxel shows the pixel at its own position in each plane: cuts are copies
        let copy = |a: usize, v: [usize; 3]| {
            let (pa, sa) = Axis::ALL[a].plane_axes();
            (v[pa] as i64, v[sa] as i64)
        };
        let p = measure([8, 6, 4], 0..3, [96; 3], copy).unwrap();
        assert_eq!(p.coherent_pairs, 1.0);
        assert_eq!(p.largest, 48.0 / 96.0, "the z cuts (8 x 6) are the largest");
    }

    #[test]
    fn scattered_pixels_make_one_voxel_patches() {
        // neighbours' pixels jump by 7 columns: nothing is coherent
        let scattered = |_: usize, v: [usize; 3]| ((v[0] * 7 + v[1] * 13 + v[2] * 29) as i64, 0);
        let p = measure([8, 8, 8], 0..3, [64; 3], scattered).unwrap();
        assert_eq!(p.coherent_pairs, 0.0);
        assert_eq!(p.largest, 1.0 / 64.0);
    }

    #[test]
    fn rows_copied_in_runs_of_four_are_patches_of_four() {
        // along x the pixel steps by one within runs of 4, then jumps; along y it jumps
        let runs = |_: usize, v: [usize; 3]| ((v[0] % 4 + 100 * (v[0] / 4 + 10 * v[1])) as i64, 0);
        let p = measure([8, 8, 8], 2..3, [256; 3], runs).unwrap();
        // a z cut has 8 rows of 7 pairs along x (6 coherent) and 7 rows of 8 pairs along y
        assert!((p.coherent_pairs - 48.0 / 112.0).abs() < 1e-12, "{}", p.coherent_pairs);
        assert_eq!(p.largest, 4.0 / 256.0);
    }

    #[test]
    fn a_grid_without_pairs_has_no_figures() {
        assert_eq!(measure([1, 1, 1], 0..3, [4; 3], |_, _| (0, 0)), None);
        assert_eq!(measure([4, 4, 4], 0..0, [4; 3], |_, _| (0, 0)), None);
    }
}
