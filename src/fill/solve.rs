//! Small linear algebra the filling needs: a sparse matrix in compressed rows, least
//! squares by conjugate gradients on the normal equations, and a dense solve for the RBF.
//!
//! Everything runs in a fixed order on one thread, so results do not depend on the
//! thread count.

/// A sparse matrix in compressed-row form.
#[derive(Debug, Clone, Default)]
pub struct Sparse {
    /// Number of columns.
    pub cols: usize,
    offsets: Vec<usize>,
    indices: Vec<u32>,
    values: Vec<f64>,
}

impl Sparse {
    /// An empty matrix with `cols` columns.
    pub fn new(cols: usize) -> Sparse {
        Sparse { cols, offsets: vec![0], indices: Vec::new(), values: Vec::new() }
    }

    /// Appends a row given as (column, value) pairs.
    pub fn push_row(&mut self, entries: impl IntoIterator<Item = (usize, f64)>) {
        for (c, v) in entries {
            self.indices.push(c as u32);
            self.values.push(v);
        }
        self.offsets.push(self.indices.len());
    }

    /// Number of rows.
    pub fn rows(&self) -> usize {
        self.offsets.len() - 1
    }

    fn row(&self, r: usize) -> impl Iterator<Item = (usize, f64)> + '_ {
        let span = self.offsets[r]..self.offsets[r + 1];
        self.indices[span.clone()].iter().map(|&c| c as usize).zip(self.values[span].iter().copied())
    }

    /// `A x`.
    pub fn times(&self, x: &[f64]) -> Vec<f64> {
        (0..self.rows()).map(|r| self.row(r).map(|(c, v)| v * x[c]).sum()).collect()
    }

    /// `Aᵀ y`.
    pub fn transpose_times(&self, y: &[f64]) -> Vec<f64> {
        let mut out = vec![0.0; self.cols];
        for (r, yr) in y.iter().enumerate() {
            for (c, v) in self.row(r) {
                out[c] += v * yr;
            }
        }
        out
    }

    /// The diagonal of `AᵀA` (the squared column norms), for a Jacobi preconditioner.
    fn normal_diagonal(&self) -> Vec<f64> {
        let mut out = vec![0.0; self.cols];
        for (&c, v) in self.indices.iter().zip(&self.values) {
            out[c as usize] += v * v;
        }
        out
    }
}

/// Minimizes `|A x - b|²` by preconditioned conjugate gradients on `AᵀA x = Aᵀb`, starting
/// from `x`, until the residual drops by `tolerance` or `max_iterations` pass. Returns the
/// number of iterations used.
pub fn least_squares(a: &Sparse, b: &[f64], x: &mut [f64], tolerance: f64, max_iterations: usize) -> usize {
    let diagonal: Vec<f64> = a.normal_diagonal().iter().map(|d| if *d > 0.0 { 1.0 / d } else { 0.0 }).collect();
    let normal = |v: &[f64]| a.transpose_times(&a.times(v));
    let atb = a.transpose_times(b);
    let mut r: Vec<f64> = atb.iter().zip(normal(x)).map(|(p, q)| p - q).collect();
    let start = norm(&r).max(norm(&atb)) * tolerance;
    let mut z: Vec<f64> = r.iter().zip(&diagonal).map(|(r, d)| r * d).collect();
    let mut p = z.clone();
    let mut rz = dot(&r, &z);
    for iteration in 0..max_iterations {
        if norm(&r) <= start {
            return iteration;
        }
        let ap = normal(&p);
        let step = rz / dot(&p, &ap).max(f64::MIN_POSITIVE);
        for i in 0..x.len() {
            x[i] += step * p[i];
            r[i] -= step * ap[i];
        }
        z = r.iter().zip(&diagonal).map(|(r, d)| r * d).collect();
        let next = dot(&r, &z);
        let beta = next / rz.max(f64::MIN_POSITIVE);
        rz = next;
        for i in 0..p.len() {
            p[i] = z[i] + beta * p[i];
        }
    }
    max_iterations
}

fn dot(a: &[f64], b: &[f64]) -> f64 {
    a.iter().zip(b).map(|(x, y)| x * y).sum()
}

fn norm(a: &[f64]) -> f64 {
    dot(a, a).sqrt()
}

/// Solves the dense system `m x = b` (row-major `n x n`) by Gaussian elimination with
/// partial pivoting. `None` when the matrix is singular.
pub fn dense_solve(mut m: Vec<f64>, mut b: Vec<f64>) -> Option<Vec<f64>> {
    let n = b.len();
    for col in 0..n {
        let pivot = (col..n).max_by(|&i, &j| m[i * n + col].abs().total_cmp(&m[j * n + col].abs()))?;
        if m[pivot * n + col].abs() < 1e-12 {
            return None;
        }
        if pivot != col {
            for k in 0..n {
                m.swap(pivot * n + k, col * n + k);
            }
            b.swap(pivot, col);
        }
        eliminate_below(&mut m, &mut b, n, col);
    }
    let mut x = vec![0.0; n];
    for row in (0..n).rev() {
        let tail: f64 = (row + 1..n).map(|k| m[row * n + k] * x[k]).sum();
        x[row] = (b[row] - tail) / m[row * n + row];
    }
    Some(x)
}

fn eliminate_below(m: &mut [f64], b: &mut [f64], n: usize, col: usize) {
    let inv = 1.0 / m[col * n + col];
    for row in col + 1..n {
        let f = m[row * n + col] * inv;
        if f == 0.0 {
            continue;
        }
        for k in col..n {
            m[row * n + k] -= f * m[col * n + k];
        }
        b[row] -= f * b[col];
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn least_squares_fits_an_overdetermined_line() {
        // y = 2 + 3 t at t = 0..5, unknowns (2, 3)
        let mut a = Sparse::new(2);
        let mut b = Vec::new();
        for t in 0..6 {
            a.push_row([(0, 1.0), (1, t as f64)]);
            b.push(2.0 + 3.0 * t as f64);
        }
        let mut x = vec![0.0; 2];
        least_squares(&a, &b, &mut x, 1e-12, 50);
        assert!((x[0] - 2.0).abs() < 1e-8 && (x[1] - 3.0).abs() < 1e-8, "{x:?}");
    }

    #[test]
    fn dense_solve_needs_pivoting_and_finds_singular() {
        let x = dense_solve(vec![0.0, 1.0, 1.0, 1.0], vec![2.0, 3.0]).unwrap();
        assert!((x[0] - 1.0).abs() < 1e-12 && (x[1] - 2.0).abs() < 1e-12);
        assert!(dense_solve(vec![1.0, 2.0, 2.0, 4.0], vec![1.0, 2.0]).is_none());
    }
}
