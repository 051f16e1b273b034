//! The synthesis volume at one level, and the gathering of its slice neighbourhoods
//! into PCA space, one x-row of voxels at a time (a small matrix product that
//! vectorizes well).
//!
//! For axis i the neighbourhood of voxel v lies in the plane orthogonal to i; the
//! exemplar's image x runs along the first plane axis, image y along the second:
//!
//! ```text
//! axis x: plane (y, z)    axis y: plane (x, z)    axis z: plane (x, y)
//! ```

use super::exemplar::Prepared;
use crate::volume::Axis;

/// The synthesis volume: raw samples, interleaved, x fastest.
#[derive(Debug, Clone)]
pub struct Grid {
    /// Size in voxels.
    pub dims: [usize; 3],
    /// Samples per voxel.
    pub channels: usize,
    /// Samples.
    pub data: Vec<f32>,
    /// Per axis: wrap around (tileable) or clamp at the border.
    pub wrap: [bool; 3],
}

impl Grid {
    /// Fold a coordinate into range: wrap or clamp, per axis.
    pub fn fold(&self, axis: usize, c: i64) -> usize {
        let len = self.dims[axis] as i64;
        if self.wrap[axis] { c.rem_euclid(len) as usize } else { c.clamp(0, len - 1) as usize }
    }

    /// Like [`Grid::fold`], but `None` for a clamped axis out of range.
    #[inline]
    pub fn inside(&self, axis: usize, c: i64) -> Option<usize> {
        let len = self.dims[axis] as i64;
        if (0..len).contains(&c) { Some(c as usize) } else { self.wrap[axis].then(|| c.rem_euclid(len) as usize) }
    }

    /// Voxel index.
    pub fn index(&self, x: usize, y: usize, z: usize) -> usize {
        x + self.dims[0] * (y + self.dims[1] * z)
    }

    /// Project the axis-`axis` neighbourhoods of the row (y, z) into `out`
    /// (`dims x row length`, component-major), using `taps` for one neighbourhood row's
    /// gathered values. Every lane adds its terms in the same order (tap by tap), so the
    /// result does not depend on how the row is split into blocks.
    #[inline(always)]
    pub fn project_row(&self, ex: &Prepared, axis: Axis, y: usize, z: usize, taps: &mut Vec<f32>, out: &mut Vec<f32>) {
        let (row, c_n, n) = (self.dims[0], self.channels, ex.n);
        let (m, dims, span) = (ex.pca.input, ex.pca.dims, n * c_n);
        out.clear();
        out.resize(dims * row, 0.0);
        taps.clear();
        taps.resize(span * row, 0.0);
        for dy in 0..n {
            for dx in 0..n {
                let at = dx * c_n * row..(dx + 1) * c_n * row;
                self.gather_tap(ex, axis, [dx, dy], [y, z], &mut taps[at]);
            }
            let j0 = dy * span;
            add_taps(out, taps, &ex.pca.basis, j0..j0 + span, m);
        }
    }

    /// Gather the weighted, mean-centred values of one tap (offset `d` in the plane) for
    /// the row (y, z): `taps[c * row + x]`.
    #[inline(always)]
    fn gather_tap(&self, ex: &Prepared, axis: Axis, d: [usize; 2], yz: [usize; 2], taps: &mut [f32]) {
        let (row, c_n, h) = (self.dims[0], self.channels, ex.half() as i64);
        let (a, b) = axis.plane_axes();
        let mut off = [0i64; 3];
        off[a] += d[0] as i64 - h;
        off[b] += d[1] as i64 - h;
        let base =
            self.dims[0] * (self.fold(1, yz[0] as i64 + off[1]) + self.dims[1] * self.fold(2, yz[1] as i64 + off[2]));
        let j0 = (d[1] * ex.n + d[0]) * c_n;
        let src = &self.data[base * c_n..(base + row) * c_n];
        for (c, tap) in taps.chunks_exact_mut(row).enumerate() {
            let (w, mean) = (ex.weights[c], ex.pca.mean[j0 + c]);
            let value = |px: &[f32]| px[c] * w - mean;
            if off[0] == 0 || self.wrap[0] {
                // Wrapped: the row rotated by the shift, as two contiguous runs.
                let shift = off[0].rem_euclid(row as i64) as usize;
                let (head, tail) = tap.split_at_mut(row - shift);
                for (t, px) in head.iter_mut().zip(src[shift * c_n..].chunks_exact(c_n)) {
                    *t = value(px);
                }
                for (t, px) in tail.iter_mut().zip(src.chunks_exact(c_n)) {
                    *t = value(px);
                }
            } else {
                for (x, t) in tap.iter_mut().enumerate() {
                    let along = self.fold(0, x as i64 + off[0]);
                    *t = value(&src[along * c_n..]);
                }
            }
        }
    }
}

/// For every component k: `out[k][x] += sum_j basis[k][j] * taps[j][x]` over the taps
/// `js`, term by term in j order. Up to four components and eight lanes at a time stay
/// in registers, so each gathered value is loaded once per four components.
#[inline(always)]
fn add_taps(out: &mut [f32], taps: &[f32], basis: &[f32], js: std::ops::Range<usize>, m: usize) {
    let row = taps.len() / js.len();
    let dims = out.len() / row;
    let coef = |k: usize| &basis[k * m + js.start..k * m + js.end];
    let mut k = 0;
    while k < dims {
        let rows = &mut out[k * row..];
        k += match dims - k {
            left if left >= 4 => add_group::<4>(rows, taps, std::array::from_fn(|g| coef(k + g))),
            left if left >= 2 => add_group::<2>(rows, taps, std::array::from_fn(|g| coef(k + g))),
            _ => add_group::<1>(rows, taps, [coef(k)]),
        };
    }
}

/// [`add_taps`] for the `G` components whose rows start `out`; returns `G`.
#[inline(always)]
fn add_group<const G: usize>(out: &mut [f32], taps: &[f32], coef: [&[f32]; G]) -> usize {
    const LANES: usize = 8;
    let row = taps.len() / coef[0].len();
    let blocks = row / LANES * LANES;
    for x0 in (0..blocks).step_by(LANES) {
        let mut acc = [[0.0f32; LANES]; G];
        for (g, a) in acc.iter_mut().enumerate() {
            a.copy_from_slice(&out[g * row + x0..g * row + x0 + LANES]);
        }
        for (j, t) in taps.chunks_exact(row).enumerate() {
            let t: &[f32; LANES] = t[x0..x0 + LANES].try_into().expect("a block of lanes");
            for (a, cg) in acc.iter_mut().zip(&coef) {
                let b = cg[j];
                for (al, tl) in a.iter_mut().zip(t) {
                    *al += b * tl;
                }
            }
        }
        for (g, a) in acc.iter().enumerate() {
            out[g * row + x0..g * row + x0 + LANES].copy_from_slice(a);
        }
    }
    for (g, cg) in coef.iter().enumerate() {
        for (x, o) in out[g * row..(g + 1) * row].iter_mut().enumerate().skip(blocks) {
            for (j, &b) in cg.iter().enumerate() {
                *o += b * taps[j * row + x];
            }
        }
    }
    G
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::synth::exemplar::PrepareOptions;
    use crate::volume::{Channel, Image2d};

    /// A volume whose z-slice is the exemplar projects exactly like the exemplar.
    #[test]
    fn row_projection_matches_exemplar_projection() {
        let (w, h) = (20, 16);
        let data: Vec<f32> = (0..w * h * 2).map(|i| ((i * 37) % 101) as f32 / 100.0).collect();
        let image = Image2d::from_data(w, h, vec![Channel::R, Channel::G], data.clone()).unwrap();
        // 7 components: groups of 4, 2 and 1; a row of 20: two blocks of 8 lanes and 4 more.
        let opt = PrepareOptions { n: 4, variance: 1.0, max_dims: 7, k: 2 };
        let ex = Prepared::new(&image, &[1.0, 0.5], opt);
        assert_eq!(ex.pca.dims, 7);
        for wrap in [true, false] {
            let grid = Grid { dims: [w, h, 1], channels: 2, data: data.clone(), wrap: [wrap; 3] };
            let (mut taps, mut out, mut vector, mut expected) = (Vec::new(), Vec::new(), Vec::new(), vec![0.0; 7]);
            for y in 0..h {
                grid.project_row(&ex, Axis::Z, y, 0, &mut taps, &mut out);
                for x in 0..w {
                    // The neighbourhood of (x, y), folded as the grid folds, projected directly.
                    vector.clear();
                    for dy in 0..4 {
                        for dx in 0..4 {
                            let (u, v) = (grid.fold(0, x as i64 + dx - 2), grid.fold(1, y as i64 + dy - 2));
                            vector.extend([data[(v * w + u) * 2], data[(v * w + u) * 2 + 1] * 0.5]);
                        }
                    }
                    ex.pca.project(&vector, &mut expected);
                    for (k, e) in expected.iter().enumerate() {
                        let got = out[k * w + x];
                        assert!((got - e).abs() < 1e-4, "wrap {wrap}, ({x}, {y}), component {k}: {got} vs {e}");
                    }
                }
            }
        }
    }
}
