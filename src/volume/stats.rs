//! Per-channel statistics: mean, standard deviation, range and histogram.
//!
//! Sums run in storage order in f64, so results do not depend on threads.

use super::Volume;
use serde::Serialize;

/// Statistics of one channel.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct ChannelStats {
    /// The channel's name.
    pub channel: String,
    /// Mean value.
    pub mean: f64,
    /// Population standard deviation.
    pub std: f64,
    /// Smallest value.
    pub min: f32,
    /// Largest value.
    pub max: f32,
    /// Counts in equal bins over [0, 1]; values outside go to the end bins.
    pub histogram: Vec<u64>,
}

impl Volume {
    /// Statistics of every channel with `bins` histogram bins (at least 1).
    pub fn channel_stats(&self, bins: usize) -> Vec<ChannelStats> {
        let n = self.channel_count();
        (0..n).map(|c| stats_of(self.channels()[c].name(), self.data().iter().skip(c).step_by(n), bins)).collect()
    }
}

/// Statistics of a sequence of values.
pub fn stats_of<'a>(name: &str, values: impl Iterator<Item = &'a f32>, bins: usize) -> ChannelStats {
    let bins = bins.max(1);
    let mut histogram = vec![0u64; bins];
    let (mut sum, mut sum2, mut count) = (0.0f64, 0.0f64, 0u64);
    let (mut min, mut max) = (f32::INFINITY, f32::NEG_INFINITY);
    for &v in values {
        sum += v as f64;
        sum2 += (v as f64) * (v as f64);
        count += 1;
        min = min.min(v);
        max = max.max(v);
        let bin = (v.clamp(0.0, 1.0) * bins as f32) as usize;
        histogram[bin.min(bins - 1)] += 1;
    }
    let mean = sum / count.max(1) as f64;
    let var = (sum2 / count.max(1) as f64 - mean * mean).max(0.0);
    ChannelStats { channel: name.to_string(), mean, std: var.sqrt(), min, max, histogram }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::volume::Channel;

    #[test]
    fn stats_of_a_two_valued_channel() {
        let v =
            Volume::from_fn([2, 2, 1], Channel::rgb(), |x, _, _, o| o.copy_from_slice(&[x as f32, 0.5, 1.0])).unwrap();
        let s = v.channel_stats(4);
        assert_eq!(s[0].mean, 0.5);
        assert_eq!(s[0].std, 0.5);
        assert_eq!(s[0].histogram, vec![2, 0, 0, 2]);
        assert_eq!((s[1].min, s[1].max), (0.5, 0.5));
        assert_eq!(s[2].histogram, vec![0, 0, 0, 4]);
    }
}
