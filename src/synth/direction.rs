//! How directional a 2D exemplar is: the coherence of its structure tensor.
//!
//! The tensor sums, over the image, the outer product of the gradient (central
//! differences of the channel mean, smoothed first by a Gaussian of 2 pixels so that pixel
//! noise does not hide the features' direction). Its coherence `(l1 - l2) / (l1 + l2)` (eigenvalues
//! `l1 >= l2`) is 0 when edges run every way (granite, gravel) and near 1 when they all
//! run one way (wood grain, bark, strata). A homogeneous synthesis from one such image
//! puts the same grain in all three cut directions, which no solid can satisfy: one cut
//! becomes a smear. Such an exemplar wants `--ey/--ez` or `--layered`.

use crate::volume::Image2d;

/// Coherence above which an exemplar counts as directional. On the photos shrunk to 128 px:
/// long-grain wood, bark and planks 0.46 to 0.85, strata 0.92, a brick wall's courses 0.52;
/// granite, marble, pebbles, gravel, grass and coffee beans 0.02 to 0.29 (docs/synthesis.md).
pub const DIRECTIONAL: f64 = 0.4;

/// Smoothing before the gradients, in pixels.
const SIGMA: f64 = 2.0;

/// The structure tensor's coherence and the direction the features run along.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Direction {
    /// 0 (no preferred direction) to 1 (every edge runs one way).
    pub coherence: f64,
    /// Angle of the features from the image's x axis, in degrees (0 to 180).
    pub angle_degrees: f64,
}

/// What to tell a designer who asks for a homogeneous solid from one `image` whose
/// features run one way (`None` when they do not): the coherence and the direction, and
/// why one cut will smear. Front ends add how to give the other cross-sections.
pub fn directional_warning(image: &Image2d) -> Option<String> {
    let d = direction(image);
    (d.coherence > DIRECTIONAL).then(|| {
        format!(
            "the features run one way (structure-tensor coherence {:.2}, along {:.0} degrees); one image for all \
             three axes will smear one cut",
            d.coherence, d.angle_degrees
        )
    })
}

/// Share of an image's grey variance its row means hold at least for its rows to read as
/// layers on their own. Measured on the photos shrunk to 128 px: the library's sections
/// 0.90-0.96, the strata 0.75, the layered cliff 0.15, long-grain wood 0.16-0.28; granite,
/// marble, gravel, grass, pebbles and walnut 0.01-0.06 (docs/synthesis.md).
pub const LAYERED_ROWS: f64 = 0.1;

/// How much of an image's grey variance (channels averaged) its row means and its column
/// means hold, each 0 to 1: a layered exemplar's rows, each one depth, differ from each
/// other far more than its columns do.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct RowShares {
    /// The variance of the row means over the image's variance.
    pub rows: f64,
    /// The variance of the column means over the image's variance.
    pub columns: f64,
}

/// Measure `image`'s [`RowShares`] (0 and 0 for a flat image).
pub fn row_shares(image: &Image2d) -> RowShares {
    let (w, h, n) = (image.width(), image.height(), image.channel_count());
    let grey: Vec<f64> =
        image.data().chunks_exact(n).map(|p| p.iter().map(|v| *v as f64).sum::<f64>() / n as f64).collect();
    let variance = |values: &[f64]| {
        let mean = values.iter().sum::<f64>() / values.len().max(1) as f64;
        values.iter().map(|v| (v - mean).powi(2)).sum::<f64>() / values.len().max(1) as f64
    };
    let total = variance(&grey);
    if total <= 1e-12 {
        return RowShares { rows: 0.0, columns: 0.0 };
    }
    let rows: Vec<f64> = grey.chunks_exact(w).map(|r| r.iter().sum::<f64>() / w as f64).collect();
    let columns: Vec<f64> = (0..w).map(|x| (0..h).map(|y| grey[y * w + x]).sum::<f64>() / h as f64).collect();
    RowShares { rows: variance(&rows) / total, columns: variance(&columns) / total }
}

/// What to tell a designer who asks for a layered solid from `image` with each row as one
/// depth, when its rows do not read as layers (`None` when they do): its layers run down
/// the columns (column means hold twice the row means' share and at least
/// [`LAYERED_ROWS`]), or its rows hold under [`LAYERED_ROWS`] without dominating the
/// columns threefold. Front ends add how to give the depth otherwise.
pub fn layering_warning(image: &Image2d) -> Option<String> {
    let RowShares { rows, columns } = row_shares(image);
    let shares = format!("row means hold {:.0} % of its variance, column means {:.0} %", rows * 100.0, columns * 100.0);
    if columns >= LAYERED_ROWS && columns > 2.0 * rows {
        Some(format!(
            "its layers run down the columns, not along the rows ({shares}); layered synthesis takes each row as one \
             depth"
        ))
    } else if rows < LAYERED_ROWS && rows <= 3.0 * columns {
        Some(format!(
            "its rows do not read as layers ({shares}; a layered photo's rows hold {:.0} % or more); layered \
             synthesis takes each row as one depth",
            LAYERED_ROWS * 100.0
        ))
    } else {
        None
    }
}

/// Measure `image` (all its channels, averaged).
pub fn direction(image: &Image2d) -> Direction {
    let (w, h, n) = (image.width(), image.height(), image.channel_count());
    let mean: Vec<f64> =
        image.data().chunks_exact(n).map(|p| p.iter().map(|v| *v as f64).sum::<f64>() / n as f64).collect();
    let smooth = smoothed(&mean, w, h);
    let grey = |x: usize, y: usize| smooth[y * w + x];
    let (mut xx, mut yy, mut xy) = (0.0, 0.0, 0.0);
    for y in 1..h.saturating_sub(1) {
        for x in 1..w.saturating_sub(1) {
            let gx = (grey(x + 1, y) - grey(x - 1, y)) / 2.0;
            let gy = (grey(x, y + 1) - grey(x, y - 1)) / 2.0;
            xx += gx * gx;
            yy += gy * gy;
            xy += gx * gy;
        }
    }
    let trace = xx + yy;
    if trace <= 1e-12 {
        return Direction { coherence: 0.0, angle_degrees: 0.0 };
    }
    let spread = ((xx - yy).powi(2) + 4.0 * xy * xy).sqrt();
    // The dominant gradient direction is at 0.5 * atan2(2xy, xx - yy); features run across it.
    let gradient = 0.5 * (2.0 * xy).atan2(xx - yy);
    let along = (gradient.to_degrees() + 90.0).rem_euclid(180.0);
    Direction { coherence: spread / trace, angle_degrees: along }
}

/// A separable Gaussian blur of [`SIGMA`] pixels, clamped at the borders.
fn smoothed(values: &[f64], w: usize, h: usize) -> Vec<f64> {
    let radius = (3.0 * SIGMA).ceil() as i64;
    let kernel: Vec<f64> = (-radius..=radius).map(|i| (-((i * i) as f64) / (2.0 * SIGMA * SIGMA)).exp()).collect();
    let total: f64 = kernel.iter().sum();
    let pass = |source: &[f64], step: (i64, i64)| -> Vec<f64> {
        (0..w * h)
            .map(|i| {
                let (x, y) = ((i % w) as i64, (i / w) as i64);
                let sum: f64 = kernel
                    .iter()
                    .enumerate()
                    .map(|(k, weight)| {
                        let d = k as i64 - radius;
                        let sx = (x + d * step.0).clamp(0, w as i64 - 1);
                        let sy = (y + d * step.1).clamp(0, h as i64 - 1);
                        weight * source[(sy * w as i64 + sx) as usize]
                    })
                    .sum();
                sum / total
            })
            .collect()
    };
    pass(&pass(values, (1, 0)), (0, 1))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::noise::hash3;
    use crate::volume::Channel;

    fn image(f: impl Fn(usize, usize) -> f32) -> Image2d {
        let data = (0..48 * 48).map(|i| f(i % 48, i / 48)).collect();
        Image2d::from_data(48, 48, Channel::grey(), data).unwrap()
    }

    #[test]
    fn grain_is_directional_and_speckle_is_not() {
        let grain = direction(&image(|_, y| ((y as f32) * 0.5).sin() * 0.5 + 0.5));
        assert!(grain.coherence > 0.95, "{grain:?}");
        assert!((grain.angle_degrees - 0.0).abs() < 1.0 || (grain.angle_degrees - 180.0).abs() < 1.0, "{grain:?}");
        let upright = direction(&image(|x, _| ((x as f32) * 0.5).sin() * 0.5 + 0.5));
        assert!((upright.angle_degrees - 90.0).abs() < 1.0, "{upright:?}");
        let speckle = direction(&image(|x, y| (hash3(1, x as i64, y as i64, 0) % 1000) as f32 / 1000.0));
        assert!(speckle.coherence < DIRECTIONAL / 2.0, "{speckle:?}");
        assert_eq!(direction(&image(|_, _| 0.5)).coherence, 0.0);
    }

    #[test]
    fn rows_read_as_layers_only_when_they_differ_more_than_the_columns() {
        let stripes = |t: usize| ((t as f32) * 0.5).sin() * 0.5 + 0.5;
        let layers = image(|x, y| stripes(y) * 0.9 + (hash3(2, x as i64, y as i64, 0) % 100) as f32 / 1000.0);
        let shares = row_shares(&layers);
        assert!(shares.rows > 0.9 && shares.columns < 0.01, "{shares:?}");
        assert_eq!(layering_warning(&layers), None);
        let upright = layering_warning(&image(|x, _| stripes(x))).expect("a warning");
        assert!(upright.contains("run down the columns") && upright.contains("column means 100 %"), "{upright}");
        let speckle = image(|x, y| (hash3(1, x as i64, y as i64, 0) % 1000) as f32 / 1000.0);
        let said = layering_warning(&speckle).expect("a warning");
        assert!(said.contains("rows do not read as layers"), "{said}");
        // fine grain along the rows: a small share, but three times the columns'
        let grain = image(|x, y| stripes(y) * 0.2 + (hash3(3, x as i64, y as i64, 0) % 1000) as f32 / 1000.0);
        let shares = row_shares(&grain);
        assert!(shares.rows < LAYERED_ROWS && shares.rows > 3.0 * shares.columns, "{shares:?}");
        assert_eq!(layering_warning(&grain), None);
        assert_eq!(layering_warning(&image(|_, _| 0.5)).map(|w| w.contains("do not read")), Some(true));
    }
}
