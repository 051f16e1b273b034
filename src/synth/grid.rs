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
    /// (`dims x row length`, component-major), using `scratch` for the gathered values.
    pub fn project_row(
        &self,
        ex: &Prepared,
        axis: Axis,
        y: usize,
        z: usize,
        scratch: &mut Vec<f32>,
        out: &mut Vec<f32>,
    ) {
        let row = self.dims[0];
        self.gather_row(ex, axis, y, z, scratch);
        let (m, dims) = (ex.pca.input, ex.pca.dims);
        out.clear();
        out.resize(dims * row, 0.0);
        for k in 0..dims {
            let basis = &ex.pca.basis[k * m..(k + 1) * m];
            let o = &mut out[k * row..(k + 1) * row];
            for (j, b) in basis.iter().enumerate() {
                let g = &scratch[j * row..(j + 1) * row];
                for (oi, gi) in o.iter_mut().zip(g) {
                    *oi += b * gi;
                }
            }
        }
    }

    /// Gather weighted, mean-centred neighbourhood values: `scratch[j * row + x]`.
    fn gather_row(&self, ex: &Prepared, axis: Axis, y: usize, z: usize, scratch: &mut Vec<f32>) {
        let (row, c_n, n, h) = (self.dims[0], self.channels, ex.n, ex.half() as i64);
        let (a, b) = axis.plane_axes();
        scratch.clear();
        scratch.resize(n * n * c_n * row, 0.0);
        for dy in 0..n {
            for dx in 0..n {
                let mut d = [0i64; 3];
                d[a] += dx as i64 - h;
                d[b] += dy as i64 - h;
                let base =
                    self.dims[0] * (self.fold(1, y as i64 + d[1]) + self.dims[1] * self.fold(2, z as i64 + d[2]));
                let j0 = (dy * n + dx) * c_n;
                let shift = d[0].rem_euclid(row as i64) as usize;
                for x in 0..row {
                    let along = if d[0] == 0 {
                        x
                    } else if self.wrap[0] {
                        (x + shift) % row
                    } else {
                        self.fold(0, x as i64 + d[0])
                    };
                    let src = (base + along) * c_n;
                    for c in 0..c_n {
                        scratch[(j0 + c) * row + x] = self.data[src + c] * ex.weights[c] - ex.pca.mean[j0 + c];
                    }
                }
            }
        }
    }
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
        let opt = PrepareOptions { n: 4, variance: 1.0, max_dims: 12, k: 2 };
        let ex = Prepared::new(&image, &[1.0, 0.5], opt);
        let grid = Grid { dims: [w, h, 1], channels: 2, data, wrap: [true; 3] };
        let (mut scratch, mut out) = (Vec::new(), Vec::new());
        let (x, y) = (7, 9);
        grid.project_row(&ex, Axis::Z, y, 0, &mut scratch, &mut out);
        let slot = ex.clamped_slot(x as i64, y as i64);
        assert_eq!(ex.centres[slot] as usize, y * w + x);
        for k in 0..ex.pca.dims {
            assert!((out[k * w + x] - ex.projection(slot)[k]).abs() < 1e-4, "component {k}");
        }
    }
}
