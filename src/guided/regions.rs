//! Exemplars by depth (Zhang et al. 2011, Fig. 15: bark outside, wood inside): each depth
//! range of the model takes its own exemplar, synthesized along the same field over the
//! voxels it weighs in, and neighbouring ranges blend across a band at their border. The
//! same ranges over the log of the texture's scale blend one exemplar synthesized at
//! several scales (a scale field).
//!
//! ```text
//!   weight   region 0           region 1
//!     1 ─────────────╮        ╭──────────────
//!                     ╲      ╱
//!     0               ╰──────╯  ...
//!     depth 0      border - band/2   border + band/2        1
//! ```
//! A region's weight is a smoothstep up across its outer border's band and down across its
//! inner one; the weights at any depth sum to 1, since each border's ramp is taken from
//! one region and given to the next.

/// Borders between depth ranges and the band they blend across.
#[derive(Debug, Clone, PartialEq)]
pub struct Regions {
    /// Depths where one region gives way to the next, increasing.
    borders: Vec<f32>,
    /// The blend's width in depth (0: a sharp border).
    band: f32,
}

impl Regions {
    /// Regions covering `ranges` (each `[from, to]`, in order, each starting where the one
    /// before ends), blending across `band`.
    pub fn new(ranges: &[[f32; 2]], band: f32) -> Regions {
        let borders = ranges.iter().skip(1).map(|r| r[0]).collect();
        Regions { borders, band }
    }

    /// Regions meeting at `borders` (increasing), blending across `band`.
    pub fn with_borders(borders: Vec<f32>, band: f32) -> Regions {
        Regions { borders, band }
    }

    /// How many regions there are.
    pub fn count(&self) -> usize {
        self.borders.len() + 1
    }

    /// The share of the next region at `depth` across the border at `border`: 0 before its
    /// band, 1 after it, a smoothstep between.
    fn past(&self, border: f32, depth: f32) -> f32 {
        if self.band <= 0.0 {
            return if depth >= border { 1.0 } else { 0.0 };
        }
        let t = ((depth - border) / self.band + 0.5).clamp(0.0, 1.0);
        t * t * (3.0 - 2.0 * t)
    }

    /// Region `k`'s weight at `depth`.
    pub fn weight(&self, k: usize, depth: f32) -> f32 {
        let entered = if k == 0 { 1.0 } else { self.past(self.borders[k - 1], depth) };
        let left = self.borders.get(k).map_or(0.0, |&b| self.past(b, depth));
        entered - left
    }

    /// The region alone at `depth` (weight 1), or `None` within a blend band.
    pub fn alone(&self, depth: f32) -> Option<usize> {
        (0..self.count()).find(|&k| self.weight(k, depth) >= 1.0)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Weights sum to 1 at every depth; each region is alone away from the bands, and the
    /// two share a border's band, half each on the border.
    #[test]
    fn weights_sum_to_one_and_blend_only_across_the_band() {
        let r = Regions::new(&[[0.0, 0.2], [0.2, 0.7], [0.7, 1.0]], 0.1);
        for i in 0..=100 {
            let d = i as f32 / 100.0;
            let sum: f32 = (0..3).map(|k| r.weight(k, d)).sum();
            assert!((sum - 1.0).abs() < 1e-6, "depth {d}: {sum}");
            assert!((0..3).all(|k| (0.0..=1.0).contains(&r.weight(k, d))));
        }
        assert_eq!((r.alone(0.1), r.alone(0.26), r.alone(0.5), r.alone(0.9)), (Some(0), Some(1), Some(1), Some(2)));
        assert_eq!((r.alone(0.2), r.alone(0.72)), (None, None));
        assert!((r.weight(0, 0.2) - 0.5).abs() < 1e-6 && (r.weight(1, 0.2) - 0.5).abs() < 1e-6);
        let sharp = Regions::new(&[[0.0, 0.5], [0.5, 1.0]], 0.0);
        assert_eq!((sharp.weight(0, 0.49), sharp.weight(1, 0.5)), (1.0, 1.0));
    }
}
