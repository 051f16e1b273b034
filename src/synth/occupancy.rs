//! The colour distribution of a coordinate synthesis, held by which candidates win (after
//! Chen & Wang 2010): a candidate whose pixels fall in colour bins the solid already
//! holds more of than the exemplars costs more, so the distribution is kept by choice
//! of whole exemplar pixels, never by changing colours.
//!
//! ```text
//!  bins     a label exemplar (at most 16 colours): one bin per label; else each shown
//!           channel cut into equal steps over the exemplars' range (16 for one channel,
//!           8 for two or three, 2 for more), a bin per combination
//!  target   the mean over the matched planes' exemplars of each bin's share
//!  excess   per bin: max(0, share in the solid / target - 1), counted again before each
//!           of a pass's eight sub-passes (one parity class of voxels each)
//!  cost     a candidate's distance times 1 + strength x its pixels' mean excess
//! ```
//!
//! Counted once per pass, every voxel reacted to the same excess at once: weak strengths
//! did nothing, strong ones swung the solid from one colour to another. Eight sub-passes,
//! each seeing the counts the ones before it left, approach the target steadily.

use super::exemplar::Prepared;

/// How colours fall into bins.
#[derive(Debug, Clone)]
pub struct Bins {
    /// A label exemplar's colours (empty for a photo).
    labels: Vec<Vec<f32>>,
    /// Per shown channel, the low end and the step.
    steps: Vec<(f32, f32)>,
    /// Steps per channel.
    per_channel: usize,
    /// Bin count.
    pub count: usize,
}

impl Bins {
    /// The bins of the exemplars' pixels, over their first `shown` channels.
    pub fn of(exemplars: &[&Prepared], shown: usize) -> Bins {
        let pixels = || exemplars.iter().flat_map(|e| e.colours.chunks_exact(e.channels));
        let channels: Vec<usize> = (0..shown).collect();
        if let Some(labels) = super::edges::label_colours(pixels(), &channels) {
            let count = labels.len();
            return Bins { labels, steps: Vec::new(), per_channel: 0, count };
        }
        // four steps of each colour channel hid the thin dark gaps of a photo of beans or
        // bark (their pixels shared a bin with the mid tones, and the solid held a third
        // fewer of them): eight bring the histogram distance of the colour photos down by
        // 0.01-0.06 (docs/synthesis.md, "The colour balance's bins")
        let per_channel = match shown {
            1 => 16,
            2 | 3 => 8,
            _ => 2,
        };
        let steps = (0..shown)
            .map(|c| {
                let (lo, hi) = pixels().fold((f32::MAX, f32::MIN), |(lo, hi), p| (lo.min(p[c]), hi.max(p[c])));
                (lo, ((hi - lo) / per_channel as f32).max(1e-6))
            })
            .collect();
        Bins { labels: Vec::new(), steps, per_channel, count: per_channel.pow(shown as u32) }
    }

    /// The bin of `colour` (its first shown channels): the nearest label, or its steps.
    pub fn of_colour(&self, colour: &[f32]) -> usize {
        if !self.labels.is_empty() {
            let apart = |l: &Vec<f32>| l.iter().zip(colour).map(|(a, b)| (a - b) * (a - b)).sum::<f32>();
            return (0..self.labels.len())
                .min_by(|&a, &b| apart(&self.labels[a]).total_cmp(&apart(&self.labels[b])))
                .unwrap_or(0);
        }
        self.steps.iter().zip(colour).fold(0, |bin, ((lo, step), v)| {
            let k = (((v - lo) / step) as usize).min(self.per_channel - 1);
            bin * self.per_channel + k
        })
    }

    /// Each bin's share of the pixels of `exemplar` (at their centres).
    pub fn shares(&self, exemplar: &Prepared, shown: usize) -> Vec<f64> {
        let mut counts = vec![0.0; self.count];
        for &p in &exemplar.centres {
            let p = p as usize;
            counts[self.of_colour(&exemplar.colours[p * exemplar.channels..][..shown])] += 1.0;
        }
        let total = exemplar.centres.len().max(1) as f64;
        counts.iter().map(|c| c / total).collect()
    }
}

/// What a pass weighs candidates by: each centre slot's bin per plane, and each bin's
/// excess over its target.
#[derive(Debug, Clone)]
pub struct Balance {
    /// The bins.
    bins: Bins,
    /// Per plane, the bin of each centre slot's pixel.
    pub slot_bins: [Vec<u16>; 3],
    /// Per bin, the target share.
    pub target: Vec<f64>,
    /// Per bin, how far the solid holds more than its target (0 when not).
    pub excess: Vec<f32>,
    /// The weight of the excess.
    pub strength: f32,
}

impl Balance {
    /// The balance of one level: `planes` are the matched planes' exemplars there.
    pub fn new(planes: &[&Prepared], all: [&Prepared; 3], shown: usize, strength: f32) -> Balance {
        let bins = Bins::of(planes, shown);
        let mut target = vec![0.0; bins.count];
        for p in planes {
            for (t, s) in target.iter_mut().zip(bins.shares(p, shown)) {
                *t += s / planes.len() as f64;
            }
        }
        let slot_bins = all.map(|e| {
            e.centres.iter().map(|&p| bins.of_colour(&e.colours[p as usize * e.channels..][..shown]) as u16).collect()
        });
        Balance { slot_bins, excess: vec![0.0; bins.count], target, strength, bins }
    }

    /// The bins.
    pub fn bins(&self) -> &Bins {
        &self.bins
    }

    /// Set each bin's excess from the solid's `counts` per bin.
    pub fn measure(&mut self, counts: &[u64]) {
        let total = counts.iter().sum::<u64>().max(1) as f64;
        for ((e, c), t) in self.excess.iter_mut().zip(counts).zip(&self.target) {
            *e = (*c as f64 / total / t.max(1e-9) - 1.0).clamp(0.0, 1e3) as f32;
        }
    }

    /// The factor a candidate triple's distance is multiplied by.
    #[inline]
    pub fn factor(&self, triple: [u32; 3], planes: std::ops::Range<usize>) -> f32 {
        let n = planes.len().max(1) as f32;
        let excess: f32 = planes.map(|a| self.excess[self.slot_bins[a][triple[a] as usize] as usize]).sum();
        1.0 + self.strength * excess / n
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::synth::exemplar::PrepareOptions;
    use crate::volume::{Channel, Image2d};

    fn prepared(data: Vec<f32>) -> Prepared {
        let image = Image2d::from_data(8, 8, Channel::grey(), data).unwrap();
        Prepared::new(&image, &[1.0], PrepareOptions { n: 3, variance: 0.97, max_dims: 4, k: 0 })
    }

    /// Two labels make two bins; a solid with too much of one makes candidates of that
    /// label dearer and leaves the other's as they are.
    #[test]
    fn over_used_labels_cost_more() {
        let ex = prepared((0..64).map(|i| if i % 4 == 0 { 0.9 } else { 0.1 }).collect());
        let mut balance = Balance::new(&[&ex], [&ex, &ex, &ex], 1, 2.0);
        assert_eq!(balance.bins().count, 2);
        let dark = balance.bins().of_colour(&[0.1]);
        let light = balance.bins().of_colour(&[0.9]);
        assert_ne!(dark, light);
        let mut counts = vec![0u64; 2];
        counts[dark] = 90;
        counts[light] = 10;
        balance.measure(&counts);
        let slot_of =
            |bin: usize| (0..ex.centres.len()).find(|&s| balance.slot_bins[0][s] as usize == bin).unwrap() as u32;
        let (d, l) = (slot_of(dark), slot_of(light));
        assert!(balance.factor([d, d, d], 0..3) > 1.1, "{}", balance.factor([d, d, d], 0..3));
        assert_eq!(balance.factor([l, l, l], 0..3), 1.0);
    }

    /// A photo's colours fall into equal steps of each channel over the exemplars' range.
    #[test]
    fn a_photo_is_binned_in_steps() {
        let ex = prepared((0..64).map(|i| i as f32 / 63.0).collect());
        let bins = Bins::of(&[&ex], 1);
        assert_eq!(bins.count, 16);
        assert_eq!((bins.of_colour(&[0.0]), bins.of_colour(&[0.5]), bins.of_colour(&[1.0])), (0, 8, 15));
    }

    /// A colour photo's dark gaps (an eighth of its range above its darkest) get bins of
    /// their own, apart from the mid-dark tones next to them.
    #[test]
    fn a_colour_photo_keeps_its_dark_gaps_apart() {
        let data: Vec<f32> = (0..64).flat_map(|i| [i as f32 / 63.0, i as f32 / 126.0, 0.2]).collect();
        let image = Image2d::from_data(8, 8, Channel::rgb(), data).unwrap();
        let weights = [1.0; 3];
        let ex = Prepared::new(&image, &weights, PrepareOptions { n: 3, variance: 0.97, max_dims: 4, k: 0 });
        let bins = Bins::of(&[&ex], 3);
        assert_eq!(bins.count, 512);
        assert_ne!(bins.of_colour(&[0.05, 0.025, 0.2]), bins.of_colour(&[0.2, 0.1, 0.2]));
    }
}
