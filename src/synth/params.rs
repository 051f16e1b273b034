//! Synthesis parameters, with the defaults of the thesis (§4.1) and their checks.

use crate::error::{Error, Result};

/// Parameters shared by homogeneous and layered synthesis.
#[derive(Debug, Clone, PartialEq)]
pub struct SynthParams {
    /// Output size in voxels (any size, not only powers of two).
    pub size: [usize; 3],
    /// Pyramid levels (3 by default; 1 synthesizes at full size only).
    pub levels: usize,
    /// Side of the square slice neighbourhoods (8).
    pub neighbourhood: usize,
    /// Most search + optimize iterations per level below the finest (4).
    pub max_iterations: usize,
    /// Most iterations at the finest level, where one costs as much as all coarser
    /// levels together (2).
    pub finest_iterations: usize,
    /// Stop a level early when the mean match distance improves by less than this share (0.01).
    pub tolerance: f32,
    /// Share of neighbourhood variance PCA keeps (0.95).
    pub pca_variance: f32,
    /// Most PCA dimensions (16; measured: 8 to 24 give the same slice energy).
    pub max_pca_dims: usize,
    /// k-coherence set size (6).
    pub coherence: usize,
    /// Histogram bins per channel (32).
    pub histogram_bins: usize,
    /// Histogram matching strength; 0 switches it off (1).
    pub histogram_strength: f32,
    /// Wrap around so the output tiles (true). Layered volumes never wrap along depth.
    pub tileable: bool,
    /// Voxel budget in bytes for the output.
    pub budget_bytes: u64,
    /// Start from this volume instead of random exemplar pixels (`None`): its size must
    /// be `size`, its channels the exemplar's (layered: without Depth, which is set from z).
    /// Synthesis then refines it: the start's coarse layout stays, the exemplar's look comes in.
    pub start: Option<crate::volume::Volume>,
}

impl Default for SynthParams {
    fn default() -> Self {
        SynthParams {
            size: [64, 64, 64],
            levels: 3,
            neighbourhood: 8,
            max_iterations: 4,
            finest_iterations: 2,
            tolerance: 0.01,
            pca_variance: 0.95,
            max_pca_dims: 16,
            coherence: 6,
            histogram_bins: 32,
            histogram_strength: 1.0,
            tileable: true,
            budget_bytes: crate::volume::DEFAULT_BUDGET_BYTES,
            start: None,
        }
    }
}

/// What layered synthesis adds.
#[derive(Debug, Clone, PartialEq)]
pub struct LayeredParams {
    /// Apply the two-best-match anti-sweeping rule (true).
    pub anti_sweeping: bool,
    /// Weight of the depth channel in neighbourhood distances (1).
    pub depth_weight: f32,
}

impl Default for LayeredParams {
    fn default() -> Self {
        LayeredParams { anti_sweeping: true, depth_weight: 1.0 }
    }
}

impl SynthParams {
    /// Check ranges; errors name the parameter and what is allowed.
    pub fn check(&self, channels: usize) -> Result<()> {
        let bad = |name: &str, value: String, allowed: &str| {
            Err(Error::invalid(format!("synthesis parameter {name} = {value} is out of range; allowed: {allowed}")))
        };
        if !(1..=8).contains(&self.levels) {
            return bad("levels", self.levels.to_string(), "1 to 8");
        }
        if !(2..=16).contains(&self.neighbourhood) {
            return bad("neighbourhood", self.neighbourhood.to_string(), "2 to 16");
        }
        if !(1..=64).contains(&self.max_iterations) || !(1..=64).contains(&self.finest_iterations) {
            return bad(
                "iterations",
                format!("{} / {} (finest)", self.max_iterations, self.finest_iterations),
                "1 to 64",
            );
        }
        if self.pca_variance.is_nan() || self.pca_variance <= 0.0 || self.pca_variance > 1.0 {
            return bad("pca_variance", self.pca_variance.to_string(), "over 0 and at most 1");
        }
        if !(1..=64).contains(&self.max_pca_dims) || !(1..=64).contains(&self.coherence) {
            return bad("max_pca_dims / coherence", format!("{} / {}", self.max_pca_dims, self.coherence), "1 to 64");
        }
        if !(2..=256).contains(&self.histogram_bins)
            || self.histogram_strength.is_nan()
            || self.histogram_strength < 0.0
        {
            return bad(
                "histogram",
                format!("{} bins, strength {}", self.histogram_bins, self.histogram_strength),
                "2 to 256 bins, strength >= 0",
            );
        }
        crate::volume::check_size(self.size, channels, self.budget_bytes).map(|_| ())
    }

    /// Most iterations at `level` (0 = coarsest).
    pub fn iterations_at(&self, level: usize) -> usize {
        if level + 1 == self.levels { self.finest_iterations } else { self.max_iterations }
    }

    /// Volume dims at every level, coarsest first.
    pub fn level_dims(&self) -> Vec<[usize; 3]> {
        let mut dims = vec![self.size];
        for _ in 1..self.levels {
            let last = dims[dims.len() - 1];
            dims.push(last.map(|d| d.div_ceil(2).max(1)));
        }
        dims.reverse();
        dims
    }
}
