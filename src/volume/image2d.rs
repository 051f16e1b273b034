//! `Image2d`: a 2D grid of interleaved f32 samples (exemplars, slices), x fastest.

use super::channel::Channel;
use crate::error::{Error, Result};

/// A 2D image of f32 samples with channel roles, x fastest.
#[derive(Debug, Clone, PartialEq)]
pub struct Image2d {
    width: usize,
    height: usize,
    channels: Vec<Channel>,
    data: Vec<f32>,
}

impl Image2d {
    /// A zero-filled image.
    pub fn new(width: usize, height: usize, channels: Vec<Channel>) -> Result<Image2d> {
        let len = width * height * channels.len();
        Self::from_data(width, height, channels, vec![0.0; len])
    }

    /// Wrap existing samples; `data.len()` must be width x height x channels.
    pub fn from_data(width: usize, height: usize, channels: Vec<Channel>, data: Vec<f32>) -> Result<Image2d> {
        Channel::check_list(&channels)?;
        if width == 0 || height == 0 {
            return Err(Error::invalid(format!(
                "image size {width}x{height} contains a zero; both sides must be at least 1"
            )));
        }
        let len = width * height * channels.len();
        if data.len() != len {
            return Err(Error::invalid(format!(
                "{} samples given for a {width}x{height} image with {} channel(s), which needs {len}",
                data.len(),
                channels.len()
            )));
        }
        Ok(Image2d { width, height, channels, data })
    }

    /// Width in pixels.
    pub fn width(&self) -> usize {
        self.width
    }

    /// Height in pixels.
    pub fn height(&self) -> usize {
        self.height
    }

    /// Channel roles.
    pub fn channels(&self) -> &[Channel] {
        &self.channels
    }

    /// Samples per pixel.
    pub fn channel_count(&self) -> usize {
        self.channels.len()
    }

    /// All samples.
    pub fn data(&self) -> &[f32] {
        &self.data
    }

    /// All samples, mutable.
    pub fn data_mut(&mut self) -> &mut [f32] {
        &mut self.data
    }

    /// The samples of pixel (x, y).
    pub fn pixel(&self, x: usize, y: usize) -> &[f32] {
        let n = self.channels.len();
        let i = (x + y * self.width) * n;
        &self.data[i..i + n]
    }

    /// The samples of pixel (x, y), mutable.
    pub fn pixel_mut(&mut self, x: usize, y: usize) -> &mut [f32] {
        let n = self.channels.len();
        let i = (x + y * self.width) * n;
        &mut self.data[i..i + n]
    }

    /// The first NaN or infinite sample, as (x, y, channel).
    pub fn first_non_finite(&self) -> Option<[usize; 3]> {
        let n = self.channels.len();
        let i = self.data.iter().position(|v| !v.is_finite())?;
        let p = i / n;
        Some([p % self.width, p / self.width, i % n])
    }
}
