//! Synthesis parameters, with the defaults of the thesis (§4.1) and their checks.

use crate::error::{Error, Result};

/// Which synthesis core runs.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum Core {
    /// Kopf et al. 2007: matches' colours blended, then histogram and spectrum matched;
    /// the only core that refines a start volume.
    #[default]
    Blend,
    /// Exemplar coordinates copied in coherent patches, each voxel one exemplar pixel
    /// ([`super::coords`]): lines and outlines stay connected, labels stay labels.
    Coordinates,
}

impl Core {
    /// The core for `images` when none is asked for: the coordinate core for a layered
    /// solid (crisp layers) and for label images (every image of at most 16 colours: each
    /// voxel shows one of them, where blending would make colours the labels do not have),
    /// the blend core for other photos.
    pub fn for_exemplars(images: &[&crate::volume::Image2d], layered: bool) -> Core {
        if layered || (!images.is_empty() && images.iter().all(|image| super::edges::is_labels(image))) {
            Core::Coordinates
        } else {
            Core::Blend
        }
    }
}

impl std::fmt::Display for Core {
    fn fmt(&self, f: &mut std::fmt::Formatter) -> std::fmt::Result {
        f.write_str(match self {
            Core::Coordinates => "coordinates",
            Core::Blend => "blend",
        })
    }
}

/// Parameters shared by homogeneous and layered synthesis.
#[derive(Debug, Clone, PartialEq)]
pub struct SynthParams {
    /// The core (blend; with a start volume always blend).
    pub core: Core,
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
    /// How much the best-matching neighbourhoods dominate the blend: a prediction weighs
    /// `distance^-power`. `None`: 6 for homogeneous synthesis, whose finer levels otherwise
    /// average disagreeing predictions into soft blobs (docs/synthesis.md), and 1.2 for
    /// layered synthesis (Kopf's robust exponent r = 0.8, which keeps its layers smooth).
    pub blend_power: Option<f32>,
    /// Give the finest level's cuts the exemplars' power spectra (true; homogeneous
    /// synthesis with histogram matching on, without a start volume, of a volume that
    /// wraps on every axis):
    /// features at the photo's size
    /// (docs/synthesis.md, "Features at the photo's size").
    pub spectrum: bool,
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
            core: Core::Blend,
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
            blend_power: None,
            spectrum: true,
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

impl LayeredParams {
    /// Allowed depth channel weights (layered synthesis).
    pub const DEPTH_WEIGHT: (f32, f32) = (0.0, 100.0);
}

impl Default for LayeredParams {
    fn default() -> Self {
        LayeredParams { anti_sweeping: true, depth_weight: 1.0 }
    }
}

impl SynthParams {
    /// Allowed pyramid levels.
    pub const LEVELS: (usize, usize) = (1, 8);
    /// Allowed iterations per level (below the finest, and at the finest).
    pub const ITERATIONS: (usize, usize) = (1, 16);
    /// Allowed k-coherence set sizes.
    pub const COHERENCE: (usize, usize) = (1, 32);
    /// Allowed most PCA dimensions.
    pub const PCA_DIMS: (usize, usize) = (1, 64);
    /// Allowed shares of neighbourhood variance PCA keeps.
    pub const PCA_VARIANCE: (f32, f32) = (0.01, 1.0);
    /// Allowed early-stop tolerances.
    pub const TOLERANCE: (f32, f32) = (0.0, 1.0);
    /// Allowed histogram matching strengths.
    pub const HISTOGRAM: (f32, f32) = (0.0, 10.0);
    /// Allowed blend powers.
    pub const BLEND_POWER: (f32, f32) = (0.0, 16.0);
    /// The blend power of homogeneous synthesis unless one is given.
    pub const HOMOGENEOUS_BLEND_POWER: f32 = 6.0;
    /// The blend power of layered synthesis unless one is given (Kopf's r = 0.8).
    pub const LAYERED_BLEND_POWER: f32 = 1.2;
    /// Allowed longest exemplar sides when exemplars are shrunk first, in pixels.
    pub const EXEMPLAR_SIDE: (usize, usize) = (8, 4096);

    /// Check ranges; errors name the parameter and what is allowed.
    pub fn check(&self, channels: usize) -> Result<()> {
        within("levels", self.levels, Self::LEVELS)?;
        within("neighbourhood", self.neighbourhood, (2, 16))?;
        within("iterations", self.max_iterations, Self::ITERATIONS)?;
        within("finest iterations", self.finest_iterations, Self::ITERATIONS)?;
        within("pca_variance", self.pca_variance, Self::PCA_VARIANCE)?;
        within("max_pca_dims", self.max_pca_dims, Self::PCA_DIMS)?;
        within("coherence", self.coherence, Self::COHERENCE)?;
        within("histogram bins", self.histogram_bins, (2, 256))?;
        within("histogram strength", self.histogram_strength, Self::HISTOGRAM)?;
        within("tolerance", self.tolerance, Self::TOLERANCE)?;
        if let Some(power) = self.blend_power {
            within("blend power", power, Self::BLEND_POWER)?;
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

/// An error unless `value` lies in `min..=max` (NaN never does).
fn within<T: PartialOrd + std::fmt::Display>(name: &str, value: T, (min, max): (T, T)) -> Result<()> {
    if value >= min && value <= max {
        Ok(())
    } else {
        Err(Error::invalid(format!("synthesis parameter {name} = {value} is out of range; allowed: {min} to {max}")))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::volume::{Channel, Image2d};

    fn image(values: impl Fn(usize) -> f32) -> Image2d {
        Image2d::from_data(16, 16, Channel::grey(), (0..256).map(values).collect()).unwrap()
    }

    #[test]
    fn label_images_and_layers_get_the_coordinate_core() {
        let labels = image(|i| [0.1, 0.5, 0.9][i % 3]);
        let photo = image(|i| i as f32 / 255.0);
        assert_eq!(Core::for_exemplars(&[&labels, &labels, &labels], false), Core::Coordinates);
        assert_eq!(Core::for_exemplars(&[&labels], false), Core::Coordinates);
        // one photo among the exemplars: its colours would be blended anyway
        assert_eq!(Core::for_exemplars(&[&labels, &photo], false), Core::Blend);
        assert_eq!(Core::for_exemplars(&[&photo], false), Core::Blend);
        assert_eq!(Core::for_exemplars(&[&photo], true), Core::Coordinates);
    }
}
