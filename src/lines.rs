//! Line structure: whether cuts keep the exemplar's thin dark or light lines (cracks, veins,
//! mortar, stone outlines) as long connected pieces, which a noise with the exemplar's
//! spectrum and colours does not.
//!
//! - **grey**: the channels standardized by the exemplar's mean and deviation and averaged
//!   (as the sharpness figures do);
//! - **lines**: the black top-hat (closing minus image: thin dark lines) and the white
//!   top-hat (image minus opening: thin light lines), 5x5 square, reflect padding; a line
//!   pixel is strictly above the exemplar's 90th percentile of that top-hat;
//! - **pieces**: 8-connected groups of line pixels, in 64x64 windows at stride 32 (the
//!   whole image when smaller), for the exemplar and the cuts alike, pooled over all
//!   windows: pieces per 1000 pixels, the share of line pixels in the three largest pieces
//!   of each window, and the share of line pixels.
//!
//! The polarity whose exemplar top-3 share is larger is "the lines"; the figures apply when
//! that share is at least [`APPLIES`] (lines that form long pieces). The exemplar's own
//! window-to-window spread of the pieces and top-3 figures is the baseline.

use crate::error::{Error, Result};
use crate::sharpness::{Standard, ratio, within};
use crate::volume::Image2d;
use serde::Serialize;

/// Side of the square structuring element.
const ELEMENT: usize = 5;
/// Side of a measuring window.
const WINDOW: usize = 64;
/// Step between windows.
const STRIDE: usize = 32;
/// The exemplar's top-hat percentile a line pixel must exceed.
const PERCENTILE: f64 = 0.9;
/// Least exemplar top-3 share for which the line figures apply.
pub const APPLIES: f64 = 0.3;
/// The band of the pieces ratio (cuts over exemplar).
pub const PIECES_BAND: (f64, f64) = (0.7, 1.3);
/// The least top-3 share ratio.
pub const TOP3_LEAST: f64 = 0.8;
/// The band of the line share ratio.
pub const SHARE_BAND: (f64, f64) = (0.5, 1.5);

/// Pooled line figures of a set of images.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct Pooled {
    /// Line pieces per 1000 pixels.
    pub pieces_per_1000: f64,
    /// Share of line pixels in the three largest pieces of each window.
    pub top3_share: f64,
    /// Share of pixels that are line pixels.
    pub line_share: f64,
}

/// One polarity's figures: the exemplar's, the cuts', and their ratios.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Polarity {
    /// `dark` (black top-hat) or `light` (white top-hat).
    pub name: &'static str,
    /// The exemplar's pooled figures.
    pub exemplar: Pooled,
    /// The cuts' pooled figures.
    pub cuts: Pooled,
    /// Pieces per 1000 pixels, cuts over exemplar.
    pub pieces_ratio: f64,
    /// Top-3 share, cuts over exemplar.
    pub top3_ratio: f64,
    /// Line share, cuts over exemplar.
    pub share_ratio: f64,
    /// The exemplar's windows' pieces per 1000 pixels over its pooled value: 10th and
    /// 90th percentile (how much the figure varies within the exemplar itself).
    pub pieces_spread: (f64, f64),
    /// The same for the top-3 share.
    pub top3_spread: (f64, f64),
}

/// The line figures of cuts against an exemplar.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Lines {
    /// `x`, `y` or `z` for the cuts of a volume; empty for plain images.
    pub axis: String,
    /// The polarity whose exemplar top-3 share is larger.
    pub lines: Polarity,
    /// The other polarity.
    pub other: Polarity,
    /// Whether the exemplar's lines form long pieces (top-3 share at least [`APPLIES`]).
    pub applies: bool,
}

impl Lines {
    /// The figures outside their bands, named (empty when the figures do not apply).
    pub fn outside_bands(&self) -> Vec<String> {
        let p = &self.lines;
        if !self.applies {
            return Vec::new();
        }
        let mut out = Vec::new();
        let axis = &self.axis;
        if !within(p.pieces_ratio, PIECES_BAND) {
            out.push(format!(
                "{axis} {} line pieces ratio {:.2} (allowed {}-{})",
                p.name, p.pieces_ratio, PIECES_BAND.0, PIECES_BAND.1
            ));
        }
        if !within(p.top3_ratio, (TOP3_LEAST, f64::INFINITY)) {
            out.push(format!(
                "{axis} {} line top-3 share ratio {:.2} (allowed at least {TOP3_LEAST})",
                p.name, p.top3_ratio
            ));
        }
        if !within(p.share_ratio, SHARE_BAND) {
            out.push(format!(
                "{axis} {} line share ratio {:.2} (allowed {}-{})",
                p.name, p.share_ratio, SHARE_BAND.0, SHARE_BAND.1
            ));
        }
        out
    }
}

/// The line figures of `cuts` against `exemplar`; `picks[c]` is the cut channel that holds
/// exemplar channel `c`.
pub fn compare(cuts: &[Image2d], exemplar: &Image2d, picks: &[usize]) -> Result<Lines> {
    if exemplar.width() < ELEMENT || exemplar.height() < ELEMENT {
        return Err(Error::invalid(format!(
            "measuring line structure needs an exemplar of at least {ELEMENT}x{ELEMENT} pixels"
        )));
    }
    let scale = Standard::of_samples(exemplar.data(), exemplar.channel_count());
    let identity: Vec<usize> = (0..exemplar.channel_count()).collect();
    let grey = |image: &Image2d, picks: &[usize]| Grey {
        width: image.width(),
        height: image.height(),
        values: scale.grey_samples(image.data(), image.channel_count(), picks),
    };
    let ex = grey(exemplar, &identity);
    let cut_greys: Vec<Grey> = cuts.iter().map(|c| grey(c, picks)).collect();
    let [dark, light] = [TopHat::Black, TopHat::White].map(|kind| polarity(kind, &ex, &cut_greys));
    let (lines, other) =
        if dark.exemplar.top3_share >= light.exemplar.top3_share { (dark, light) } else { (light, dark) };
    let applies = lines.exemplar.top3_share >= APPLIES;
    Ok(Lines { axis: String::new(), lines, other, applies })
}

/// The line figures of the cuts of `volume` across `axis` at 1/4, 1/2 and 3/4 (as the
/// sharpness figures) against `exemplar`.
pub fn measure(
    volume: &crate::Volume,
    exemplar: &Image2d,
    picks: &[usize],
    axis: crate::volume::Axis,
) -> Result<Lines> {
    let mut figures = compare(&crate::sharpness::quarter_cuts(volume, axis)?, exemplar, picks)?;
    figures.axis = axis.to_string();
    Ok(figures)
}

/// Which thin features a top-hat keeps.
#[derive(Debug, Clone, Copy)]
enum TopHat {
    /// Dark lines: closing minus image.
    Black,
    /// Light lines: image minus opening.
    White,
}

fn polarity(kind: TopHat, exemplar: &Grey, cuts: &[Grey]) -> Polarity {
    let ex_hat = top_hat(exemplar, kind);
    let threshold = percentile(&ex_hat.values, PERCENTILE);
    let ex_windows = windows(&ex_hat, threshold);
    let cut_windows: Vec<Window> = cuts.iter().flat_map(|c| windows(&top_hat(c, kind), threshold)).collect();
    let (exemplar, cuts) = (pooled(&ex_windows), pooled(&cut_windows));
    let spread = |value: fn(&Window) -> f64, whole: f64| {
        let mut ratios: Vec<f64> = ex_windows.iter().map(|w| ratio(value(w), whole)).collect();
        ratios.sort_by(f64::total_cmp);
        (percentile_sorted(&ratios, 0.1), percentile_sorted(&ratios, 0.9))
    };
    Polarity {
        name: match kind {
            TopHat::Black => "dark",
            TopHat::White => "light",
        },
        exemplar,
        cuts,
        pieces_ratio: ratio(cuts.pieces_per_1000, exemplar.pieces_per_1000),
        top3_ratio: ratio(cuts.top3_share, exemplar.top3_share),
        share_ratio: ratio(cuts.line_share, exemplar.line_share),
        pieces_spread: spread(|w| w.pieces as f64 * 1000.0 / w.pixels as f64, exemplar.pieces_per_1000),
        top3_spread: spread(|w| w.top3 as f64 / w.lines.max(1) as f64, exemplar.top3_share),
    }
}

/// One value per pixel, rows of `width`.
struct Grey {
    width: usize,
    height: usize,
    values: Vec<f64>,
}

/// The top-hat of `image`: closing minus image (black) or image minus opening (white).
fn top_hat(image: &Grey, kind: TopHat) -> Grey {
    let values = match kind {
        TopHat::Black => {
            let closed = filter(&filter(image, f64::max), f64::min);
            closed.values.iter().zip(&image.values).map(|(c, v)| c - v).collect()
        }
        TopHat::White => {
            let opened = filter(&filter(image, f64::min), f64::max);
            image.values.iter().zip(&opened.values).map(|(v, o)| v - o).collect()
        }
    };
    Grey { width: image.width, height: image.height, values }
}

/// `pick` (min or max) over the [`ELEMENT`]-square around each pixel, reflect padding
/// (`dcb|abcd|cba`): a row pass, then a column pass.
fn filter(image: &Grey, pick: fn(f64, f64) -> f64) -> Grey {
    let (w, h) = (image.width, image.height);
    let reach = (ELEMENT / 2) as i64;
    let at = |i: i64, n: usize| reflect(i, n);
    let mut rows = vec![0.0; w * h];
    for y in 0..h {
        for x in 0..w {
            let around = (-reach..=reach).map(|d| image.values[y * w + at(x as i64 + d, w)]);
            rows[y * w + x] = around.reduce(pick).expect("the element has pixels");
        }
    }
    let mut values = vec![0.0; w * h];
    for y in 0..h {
        for x in 0..w {
            let around = (-reach..=reach).map(|d| rows[at(y as i64 + d, h) * w + x]);
            values[y * w + x] = around.reduce(pick).expect("the element has pixels");
        }
    }
    Grey { width: w, height: h, values }
}

/// Index `i` reflected into `0..n` without repeating the edge (`-1` is `1`).
fn reflect(i: i64, n: usize) -> usize {
    let n = n as i64;
    if n == 1 {
        return 0;
    }
    let period = 2 * (n - 1);
    let m = i.rem_euclid(period);
    (if m < n { m } else { period - m }) as usize
}

/// The line pieces of one window.
struct Window {
    pixels: usize,
    lines: usize,
    pieces: usize,
    top3: usize,
}

/// The windows of a top-hat, each measured with line pixels strictly above `threshold`.
fn windows(hat: &Grey, threshold: f64) -> Vec<Window> {
    let starts =
        |n: usize| -> Vec<usize> { if n <= WINDOW { vec![0] } else { (0..=n - WINDOW).step_by(STRIDE).collect() } };
    let mut out = Vec::new();
    for y0 in starts(hat.height) {
        for x0 in starts(hat.width) {
            let (w, h) = (WINDOW.min(hat.width), WINDOW.min(hat.height));
            let line: Vec<bool> =
                (0..w * h).map(|i| hat.values[(y0 + i / w) * hat.width + x0 + i % w] > threshold).collect();
            out.push(pieces(&line, w, h));
        }
    }
    out
}

/// The 8-connected pieces of the line pixels of a `w` x `h` window.
fn pieces(line: &[bool], w: usize, h: usize) -> Window {
    let mut seen = vec![false; line.len()];
    let mut sizes = Vec::new();
    let mut stack = Vec::new();
    for start in 0..line.len() {
        if !line[start] || seen[start] {
            continue;
        }
        seen[start] = true;
        stack.push(start);
        let mut size = 0;
        while let Some(i) = stack.pop() {
            size += 1;
            let (x, y) = ((i % w) as i64, (i / w) as i64);
            for (dx, dy) in [(-1, -1), (0, -1), (1, -1), (-1, 0), (1, 0), (-1, 1), (0, 1), (1, 1)] {
                let (nx, ny) = (x + dx, y + dy);
                if nx < 0 || ny < 0 || nx >= w as i64 || ny >= h as i64 {
                    continue;
                }
                let j = ny as usize * w + nx as usize;
                if line[j] && !seen[j] {
                    seen[j] = true;
                    stack.push(j);
                }
            }
        }
        sizes.push(size);
    }
    sizes.sort_unstable_by(|a, b| b.cmp(a));
    Window { pixels: line.len(), lines: sizes.iter().sum(), pieces: sizes.len(), top3: sizes.iter().take(3).sum() }
}

/// Figures pooled over windows: counts summed, then divided.
fn pooled(windows: &[Window]) -> Pooled {
    let sum = |f: fn(&Window) -> usize| windows.iter().map(f).sum::<usize>() as f64;
    let (pixels, lines) = (sum(|w| w.pixels).max(1.0), sum(|w| w.lines));
    Pooled {
        pieces_per_1000: sum(|w| w.pieces) * 1000.0 / pixels,
        top3_share: if lines > 0.0 { sum(|w| w.top3) / lines } else { 0.0 },
        line_share: lines / pixels,
    }
}

/// The `q` quantile of `values` (nearest rank).
fn percentile(values: &[f64], q: f64) -> f64 {
    let mut sorted = values.to_vec();
    sorted.sort_by(f64::total_cmp);
    percentile_sorted(&sorted, q)
}

fn percentile_sorted(sorted: &[f64], q: f64) -> f64 {
    if sorted.is_empty() {
        return 0.0;
    }
    sorted[((sorted.len() - 1) as f64 * q).round() as usize]
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::volume::Channel;
    use rand::{RngExt, SeedableRng};
    use rand_pcg::Pcg64;
    use rustfft::num_complex::Complex;

    /// Grey stones of three shades with thin dark joints between them (a Voronoi foam),
    /// `side`² pixels.
    fn stones(side: usize, seed: u64) -> Image2d {
        let mut rng = Pcg64::seed_from_u64(seed);
        let centres: Vec<(f32, f32, f32)> = (0..side * side / 300)
            .map(|_| {
                (
                    rng.random_range(0.0..side as f32),
                    rng.random_range(0.0..side as f32),
                    [0.55, 0.7, 0.85][rng.random_range(0..3usize)],
                )
            })
            .collect();
        let mut data = Vec::with_capacity(side * side);
        for y in 0..side {
            for x in 0..side {
                let mut d: Vec<(f32, f32)> =
                    centres.iter().map(|&(cx, cy, shade)| ((cx - x as f32).hypot(cy - y as f32), shade)).collect();
                d.sort_by(|a, b| a.0.total_cmp(&b.0));
                data.push(if d[1].0 - d[0].0 < 0.9 { 0.12 } else { d[0].1 });
            }
        }
        Image2d::from_data(side, side, Channel::grey(), data).unwrap()
    }

    fn figures(cut: &Image2d, exemplar: &Image2d) -> Lines {
        compare(std::slice::from_ref(cut), exemplar, &[0]).unwrap()
    }

    /// Inside the target band: pieces 0.7-1.3, top-3 share at least 0.8, line share 0.5-1.5.
    fn keeps_lines(l: &Lines) -> bool {
        let p = &l.lines;
        (0.7..=1.3).contains(&p.pieces_ratio) && p.top3_ratio >= 0.8 && (0.5..=1.5).contains(&p.share_ratio)
    }

    /// `image` with its spectrum's phases made random and its exact values given back in
    /// the order of the noise (the same power spectrum, nearly, and the same colours).
    fn random_phase(image: &Image2d, seed: u64) -> Image2d {
        let (w, h) = (image.width(), image.height());
        let mut rng = Pcg64::seed_from_u64(seed);
        let mut cells: Vec<Complex<f32>> = image.data().iter().map(|v| Complex::new(*v, 0.0)).collect();
        let mut planner = rustfft::FftPlanner::new();
        transform(&mut cells, w, h, &*planner.plan_fft_forward(w), &*planner.plan_fft_forward(h));
        for c in cells.iter_mut() {
            *c = Complex::from_polar(c.norm(), rng.random_range(0.0..std::f32::consts::TAU));
        }
        transform(&mut cells, w, h, &*planner.plan_fft_inverse(w), &*planner.plan_fft_inverse(h));
        let mut order: Vec<usize> = (0..cells.len()).collect();
        order.sort_by(|a, b| cells[*a].re.total_cmp(&cells[*b].re));
        let mut values = image.data().to_vec();
        values.sort_by(f32::total_cmp);
        let mut data = vec![0.0; values.len()];
        for (rank, at) in order.into_iter().enumerate() {
            data[at] = values[rank];
        }
        Image2d::from_data(w, h, Channel::grey(), data).unwrap()
    }

    /// A 2D FFT in place: rows, then columns.
    fn transform(
        cells: &mut [Complex<f32>],
        w: usize,
        h: usize,
        rows: &dyn rustfft::Fft<f32>,
        cols: &dyn rustfft::Fft<f32>,
    ) {
        cells.chunks_exact_mut(w).for_each(|row| rows.process(row));
        for x in 0..w {
            let mut column: Vec<Complex<f32>> = (0..h).map(|y| cells[y * w + x]).collect();
            cols.process(&mut column);
            column.into_iter().enumerate().for_each(|(y, c)| cells[y * w + x] = c);
        }
    }

    /// A Gaussian blur of `sigma` pixels (clamped edges).
    fn blurred(image: &Image2d, sigma: f32) -> Image2d {
        let (w, h) = (image.width(), image.height());
        let reach = (3.0 * sigma).ceil() as i64;
        let weights: Vec<f32> = (-reach..=reach).map(|d| (-(d * d) as f32 / (2.0 * sigma * sigma)).exp()).collect();
        let total: f32 = weights.iter().sum();
        let pass = |data: &[f32], along_x: bool| -> Vec<f32> {
            (0..w * h)
                .map(|i| {
                    let (x, y) = ((i % w) as i64, (i / w) as i64);
                    let sum: f32 = (-reach..=reach)
                        .zip(&weights)
                        .map(|(d, k)| {
                            let (sx, sy) = if along_x {
                                ((x + d).clamp(0, w as i64 - 1), y)
                            } else {
                                (x, (y + d).clamp(0, h as i64 - 1))
                            };
                            k * data[sy as usize * w + sx as usize]
                        })
                        .sum();
                    sum / total
                })
                .collect()
        };
        let data = pass(&pass(image.data(), true), false);
        Image2d::from_data(w, h, Channel::grey(), data).unwrap()
    }

    /// Another piece of the same stone wall keeps the lines; random-phase noise with its
    /// spectrum and exact values, a blurred, a flat and a shuffled copy do not.
    #[test]
    fn the_same_material_passes_and_shapeless_copies_fail() {
        let exemplar = stones(192, 1);
        let own = figures(&exemplar, &exemplar);
        assert!(own.applies && own.lines.name == "dark", "{own:?}");
        assert!(keeps_lines(&own), "{own:?}");
        let other = figures(&stones(192, 2), &exemplar);
        assert!(keeps_lines(&other), "another wall of the same stones: {:?}", other.lines);
        let noise = figures(&random_phase(&exemplar, 3), &exemplar);
        assert!(!keeps_lines(&noise), "random phase: {:?}", noise.lines);
        let blur = figures(&blurred(&exemplar, 1.5), &exemplar);
        assert!(!keeps_lines(&blur), "blurred: {:?}", blur.lines);
        let flat = Image2d::from_data(192, 192, Channel::grey(), vec![0.6; 192 * 192]).unwrap();
        assert!(!keeps_lines(&figures(&flat, &exemplar)), "flat");
        let mut rng = Pcg64::seed_from_u64(4);
        let mut shuffled = exemplar.data().to_vec();
        for i in (1..shuffled.len()).rev() {
            shuffled.swap(i, rng.random_range(0..=i));
        }
        let shuffled = Image2d::from_data(192, 192, Channel::grey(), shuffled).unwrap();
        assert!(!keeps_lines(&figures(&shuffled, &exemplar)), "shuffled");
    }

    /// Pieces are 8-connected; a window's top three hold their pixels; reflection does not
    /// repeat the edge.
    #[test]
    fn pieces_and_reflection_count_as_documented() {
        let line = [true, false, false, true, false, true, false, false, false, false, true, true];
        let w = pieces(&line, 4, 3);
        assert_eq!((w.pieces, w.lines, w.top3), (2, 5, 5), "diagonal touches join pixels");
        assert_eq!([-2, -1, 0, 3, 4, 5].map(|i| reflect(i, 4)), [2, 1, 0, 3, 2, 1]);
    }
}
