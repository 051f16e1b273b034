//! A feature channel made from an exemplar's own edges: each pixel's distance to the
//! nearest edge, matched with the colours but not shown ([`super::coords::FEATURE`]).
//!
//! ```text
//!  edges     a label image (at most 16 distinct colours): pixels whose right or lower
//!            neighbour has another label; a photo: the 15 % of pixels with the largest
//!            grey gradient (central differences)
//!  distance  city-block distance to the nearest edge pixel, at most 8 pixels, over 8
//! ```
//!
//! Colours alone tell a voxel next to a thin dark line from one a few pixels away only
//! by the line's few pixels in its neighbourhood; the distance tells them apart over the
//! whole neighbourhood, so matches continue lines and outlines instead of ending them.

use super::coords::{FEATURE, matched_only};
use crate::error::Result;
use crate::volume::{Channel, Image2d};

/// Farthest distance told apart, in pixels.
const REACH: f32 = 8.0;

/// Share of a photo's pixels taken as edges.
const EDGE_SHARE: f32 = 0.15;

/// Most distinct colours of a label image.
pub const MOST_LABELS: usize = 16;

/// `image` with a feature channel of each pixel's distance to the nearest edge, inserted
/// after the colours (before a Depth channel).
pub fn with_edge_distance(image: &Image2d) -> Result<Image2d> {
    let (w, h, c) = (image.width(), image.height(), image.channel_count());
    let shown = shown_channels(image);
    let edges = if is_labels(image) { label_edges(image, &shown) } else { gradient_edges(image, &shown) };
    let distance = distance_to(&edges, w, h);
    let at = shown.len();
    let mut names = image.channels().to_vec();
    names.insert(at, Channel::Named(FEATURE.into()));
    let mut data = Vec::with_capacity(w * h * (c + 1));
    for (i, pixel) in image.data().chunks_exact(c).enumerate() {
        data.extend_from_slice(&pixel[..at]);
        data.push(distance[i].min(REACH) / REACH);
        data.extend_from_slice(&pixel[at..]);
    }
    Image2d::from_data(w, h, names, data)
}

/// The channels of `image` a voxel shows (a feature mask and a Depth channel aside).
fn shown_channels(image: &Image2d) -> Vec<usize> {
    (0..image.channel_count()).filter(|&k| !matched_only(&image.channels()[k])).collect()
}

/// Whether the shown channels of `image` take at most [`MOST_LABELS`] distinct colours.
pub fn is_labels(image: &Image2d) -> bool {
    label_colours(image.data().chunks_exact(image.channel_count()), &shown_channels(image)).is_some()
}

/// The distinct colours of `pixels` over their `shown` channels, in order of first
/// appearance, if there are at most [`MOST_LABELS`]: a label image's labels.
pub fn label_colours<'a>(pixels: impl Iterator<Item = &'a [f32]>, shown: &[usize]) -> Option<Vec<Vec<f32>>> {
    let mut seen: Vec<Vec<f32>> = Vec::new();
    for pixel in pixels {
        let key: Vec<f32> = shown.iter().map(|&k| pixel[k]).collect();
        if !seen.contains(&key) {
            if seen.len() == MOST_LABELS {
                return None;
            }
            seen.push(key);
        }
    }
    Some(seen)
}

/// Pixels whose right or lower neighbour has another label.
fn label_edges(image: &Image2d, shown: &[usize]) -> Vec<bool> {
    let (w, h) = (image.width(), image.height());
    let same = |a: &[f32], b: &[f32]| shown.iter().all(|&k| a[k] == b[k]);
    (0..w * h)
        .map(|i| {
            let (x, y) = (i % w, i / w);
            let here = image.pixel(x, y);
            (x + 1 < w && !same(here, image.pixel(x + 1, y))) || (y + 1 < h && !same(here, image.pixel(x, y + 1)))
        })
        .collect()
}

/// The [`EDGE_SHARE`] of pixels with the largest grey gradient.
fn gradient_edges(image: &Image2d, shown: &[usize]) -> Vec<bool> {
    let (w, h) = (image.width(), image.height());
    let grey = |x: usize, y: usize| {
        let p = image.pixel(x.min(w - 1), y.min(h - 1));
        shown.iter().map(|&k| p[k]).sum::<f32>() / shown.len().max(1) as f32
    };
    let magnitude: Vec<f32> = (0..w * h)
        .map(|i| {
            let (x, y) = (i % w, i / w);
            let gx = grey(x + 1, y) - grey(x.saturating_sub(1), y);
            let gy = grey(x, y + 1) - grey(x, y.saturating_sub(1));
            gx.hypot(gy)
        })
        .collect();
    let mut sorted = magnitude.clone();
    sorted.sort_by(f32::total_cmp);
    let threshold = sorted[((sorted.len() as f32 * (1.0 - EDGE_SHARE)) as usize).min(sorted.len() - 1)];
    magnitude.iter().map(|m| *m > threshold).collect()
}

/// Each pixel's city-block distance to the nearest `edges` pixel (two chamfer sweeps);
/// without edges, [`REACH`] everywhere.
fn distance_to(edges: &[bool], w: usize, h: usize) -> Vec<f32> {
    let mut d: Vec<f32> = edges.iter().map(|e| if *e { 0.0 } else { REACH }).collect();
    for y in 0..h {
        for x in 0..w {
            let mut m = d[y * w + x];
            if x > 0 {
                m = m.min(d[y * w + x - 1] + 1.0);
            }
            if y > 0 {
                m = m.min(d[(y - 1) * w + x] + 1.0);
            }
            d[y * w + x] = m;
        }
    }
    for y in (0..h).rev() {
        for x in (0..w).rev() {
            let mut m = d[y * w + x];
            if x + 1 < w {
                m = m.min(d[y * w + x + 1] + 1.0);
            }
            if y + 1 < h {
                m = m.min(d[(y + 1) * w + x] + 1.0);
            }
            d[y * w + x] = m;
        }
    }
    d
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A 12x4 grey image, dark left of column 5 and light from it.
    fn step() -> Image2d {
        let data = (0..48).map(|i| if i % 12 < 5 { 0.1 } else { 0.9 }).collect();
        Image2d::from_data(12, 4, vec![Channel::R], data).unwrap()
    }

    #[test]
    fn a_label_image_gets_the_distance_to_its_label_changes() {
        let out = with_edge_distance(&step()).unwrap();
        assert_eq!(out.channels(), &[Channel::R, Channel::Named(FEATURE.into())]);
        let row: Vec<f32> = (0..12).map(|x| out.pixel(x, 2)[1] * REACH).collect();
        assert_eq!(row, vec![4.0, 3.0, 2.0, 1.0, 0.0, 1.0, 2.0, 3.0, 4.0, 5.0, 6.0, 7.0]);
        assert_eq!(out.pixel(7, 1)[0], 0.9, "the colours are kept");
    }

    #[test]
    fn the_feature_goes_before_a_depth_channel() {
        let data = (0..48).flat_map(|i| [if i % 12 < 5 { 0.1 } else { 0.9 }, (i / 12) as f32 / 3.0]).collect();
        let image = Image2d::from_data(12, 4, vec![Channel::R, Channel::Depth], data).unwrap();
        let out = with_edge_distance(&image).unwrap();
        assert_eq!(out.channels(), &[Channel::R, Channel::Named(FEATURE.into()), Channel::Depth]);
        assert_eq!(out.pixel(0, 3)[2], 1.0);
    }

    #[test]
    fn a_photo_takes_its_strongest_gradients_as_edges() {
        // 40 grey levels (exact in binary), one sharp step at column 20 of 40
        let data = (0..40 * 8).map(|i| (i % 40) as f32 / 1024.0 + if i % 40 < 20 { 0.25 } else { 0.75 }).collect();
        let image = Image2d::from_data(40, 8, vec![Channel::R], data).unwrap();
        assert!(!is_labels(&image));
        let out = with_edge_distance(&image).unwrap();
        let d = |x: usize| out.pixel(x, 4)[1] * REACH;
        assert_eq!((d(19), d(20)), (0.0, 0.0));
        assert_eq!((d(15), d(27), d(0)), (4.0, 7.0, 8.0));
    }
}
