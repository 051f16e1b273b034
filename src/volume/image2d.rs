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

    /// The image resampled to `width` x `height`: along each axis a shrinking output pixel
    /// is the mean of the input it covers (pixels partly covered count by their share), an
    /// enlarging one the linear blend of the two input pixels around its centre.
    pub fn resized(&self, width: usize, height: usize) -> Result<Image2d> {
        let c = self.channels.len();
        // along x: rows of `self.width` pixels to rows of `width`
        let across: Vec<f32> = self.data.chunks_exact(self.width * c).flat_map(|row| resample(row, c, width)).collect();
        // along y: the columns, gathered and scattered back
        let mut out = vec![0.0; width * height * c];
        let mut column = vec![0.0; self.height * c];
        for x in 0..width {
            for y in 0..self.height {
                column[y * c..(y + 1) * c].copy_from_slice(&across[(y * width + x) * c..][..c]);
            }
            for (y, px) in resample(&column, c, height).chunks_exact(c).enumerate() {
                out[(y * width + x) * c..][..c].copy_from_slice(px);
            }
        }
        Image2d::from_data(width, height, self.channels.clone(), out)
    }

    /// The first NaN or infinite sample, as (x, y, channel).
    pub fn first_non_finite(&self) -> Option<[usize; 3]> {
        let n = self.channels.len();
        let i = self.data.iter().position(|v| !v.is_finite())?;
        let p = i / n;
        Some([p % self.width, p / self.width, i % n])
    }
}

/// `line` (pixels of `c` samples) resampled to `len` pixels (see [`Image2d::resized`]).
fn resample(line: &[f32], c: usize, len: usize) -> Vec<f32> {
    let from = line.len() / c;
    let scale = from as f64 / len as f64;
    let mut out = Vec::with_capacity(len * c);
    for i in 0..len {
        let mut px = vec![0.0f64; c];
        if scale > 1.0 {
            let (start, end) = (i as f64 * scale, (i + 1) as f64 * scale);
            for j in start.floor() as usize..(end.ceil() as usize).min(from) {
                let share = (end.min(j as f64 + 1.0) - start.max(j as f64)).max(0.0) / scale;
                px.iter_mut().zip(&line[j * c..(j + 1) * c]).for_each(|(o, v)| *o += share * f64::from(*v));
            }
        } else {
            let at = ((i as f64 + 0.5) * scale - 0.5).clamp(0.0, (from - 1) as f64);
            let (j, t) = (at.floor() as usize, at.fract());
            let next = (j + 1).min(from - 1);
            for (k, o) in px.iter_mut().enumerate() {
                *o = (1.0 - t) * f64::from(line[j * c + k]) + t * f64::from(line[next * c + k]);
            }
        }
        out.extend(px.iter().map(|v| *v as f32));
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    fn grey(width: usize, height: usize, value: impl Fn(usize, usize) -> f32) -> Image2d {
        let data = (0..width * height).map(|i| value(i % width, i / width)).collect();
        Image2d::from_data(width, height, vec![Channel::R], data).unwrap()
    }

    /// Shrinking averages what an output pixel covers (a checkerboard halved is even grey,
    /// a ramp keeps its mean), enlarging blends neighbours (a ramp stays a ramp), and a
    /// constant stays constant either way.
    #[test]
    fn resizing_averages_when_shrinking_and_blends_when_enlarging() {
        let board = grey(8, 6, |x, y| ((x + y) % 2) as f32);
        let half = board.resized(4, 3).unwrap();
        assert!(half.data().iter().all(|v| (v - 0.5).abs() < 1e-6), "{:?}", half.data());
        let ramp = grey(9, 2, |x, _| x as f32);
        let third = ramp.resized(3, 2).unwrap();
        assert_eq!(third.data(), &[1.0, 4.0, 7.0, 1.0, 4.0, 7.0]);
        let odd = ramp.resized(4, 2).unwrap();
        let mean = odd.data()[..4].iter().sum::<f32>() / 4.0;
        assert!((mean - 4.0).abs() < 1e-5 && odd.data()[0] < odd.data()[3], "{:?}", odd.data());
        let wide = grey(4, 1, |x, _| x as f32).resized(8, 3).unwrap();
        let row = &wide.data()[8..16];
        assert!(row.windows(2).all(|w| w[1] >= w[0]) && row[0] == 0.0 && row[7] == 3.0, "{row:?}");
        assert!((row[2] - 0.75).abs() < 1e-6, "{row:?}");
        let flat = grey(5, 7, |_, _| 0.3).resized(13, 2).unwrap();
        assert!(flat.data().iter().all(|v| (v - 0.3).abs() < 1e-6));
    }
}
