//! Small linear algebra the filling needs: a sparse matrix in compressed rows, least
//! squares by conjugate gradients on the normal equations, and a dense solve for the RBF.
//!
//! Every sum runs in a fixed order (several right-hand sides may run side by side, and the
//! rows of a large product are split across threads, each row summed alone), so results do
//! not depend on the thread count.

use rayon::prelude::*;

/// Rows from which a product with a vector is worth splitting across threads.
const PARALLEL_ROWS: usize = 4096;

/// Rows of `AᵀA` made together on one thread.
const NORMAL_BLOCK: usize = 256;

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

    /// `A x` written into `out` (rows in parallel when there are many: each row's sum runs
    /// in order, so the result is the same on any thread count).
    pub fn times_into(&self, x: &[f64], out: &mut [f64]) {
        let row = |r: usize| self.row(r).map(|(c, v)| v * x[c]).sum();
        if out.len() >= PARALLEL_ROWS {
            out.par_iter_mut().enumerate().for_each(|(r, o)| *o = row(r));
        } else {
            out.iter_mut().enumerate().for_each(|(r, o)| *o = row(r));
        }
    }

    /// The diagonal of a square matrix.
    fn diagonal(&self) -> Vec<f64> {
        (0..self.rows()).map(|r| self.row(r).filter(|(c, _)| *c == r).map(|(_, v)| v).sum()).collect()
    }

    /// `Aᵀ`, with the rows of each of its rows in increasing order.
    fn transpose(&self) -> Sparse {
        let mut offsets = vec![0; self.cols + 1];
        for &c in &self.indices {
            offsets[c as usize + 1] += 1;
        }
        for c in 0..self.cols {
            offsets[c + 1] += offsets[c];
        }
        let mut next = offsets.clone();
        let mut indices = vec![0; self.indices.len()];
        let mut values = vec![0.0; self.values.len()];
        for r in 0..self.rows() {
            for (c, v) in self.row(r) {
                indices[next[c]] = r as u32;
                values[next[c]] = v;
                next[c] += 1;
            }
        }
        Sparse { cols: self.rows(), offsets, indices, values }
    }

    /// `AᵀA`, square with `cols` rows, columns sorted in each row. Entries are summed in row
    /// order of `A`, so the result is the same on every run; blocks of rows are made side by
    /// side (each row alone), so also on any thread count.
    pub fn normal(&self) -> Sparse {
        let by_column = self.transpose();
        let blocks: Vec<Sparse> = (0..self.cols.div_ceil(NORMAL_BLOCK))
            .into_par_iter()
            .map(|b| self.normal_rows(&by_column, b * NORMAL_BLOCK..((b + 1) * NORMAL_BLOCK).min(self.cols)))
            .collect();
        let mut out = Sparse::new(self.cols);
        for block in blocks {
            let base = out.indices.len();
            out.offsets.extend(block.offsets[1..].iter().map(|o| o + base));
            out.indices.extend(block.indices);
            out.values.extend(block.values);
        }
        out
    }

    /// The rows `rows` of `AᵀA` (`by_column` is `Aᵀ`).
    fn normal_rows(&self, by_column: &Sparse, rows: std::ops::Range<usize>) -> Sparse {
        let mut out = Sparse::new(self.cols);
        let mut sums = vec![0.0; self.cols];
        let mut seen = vec![false; self.cols];
        let mut touched: Vec<usize> = Vec::new();
        for column in rows {
            for (r, v) in by_column.row(column) {
                for (c, w) in self.row(r) {
                    if !seen[c] {
                        seen[c] = true;
                        touched.push(c);
                    }
                    sums[c] += v * w;
                }
            }
            touched.sort_unstable();
            out.push_row(touched.iter().map(|&c| (c, sums[c])));
            for &c in &touched {
                sums[c] = 0.0;
                seen[c] = false;
            }
            touched.clear();
        }
        out
    }
}

/// Minimizes `|A x - b|²` by preconditioned conjugate gradients on `AᵀA x = Aᵀb`, starting
/// from `x`, until the residual drops by `tolerance` or `max_iterations` pass. Returns the
/// number of iterations used.
pub fn least_squares(a: &Sparse, b: &[f64], x: &mut [f64], tolerance: f64, max_iterations: usize) -> usize {
    let normal = a.normal();
    conjugate_gradients(&normal, &a.transpose_times(b), x, tolerance, max_iterations)
}

/// [`least_squares`] for several right-hand sides of one matrix (`bs[k]` with start and
/// result `xs[k]`), solved side by side on the thread pool. Each solve runs alone in a
/// fixed order, so the results do not depend on the thread count.
pub fn least_squares_each(a: &Sparse, bs: &[Vec<f64>], xs: &mut [Vec<f64>], tolerance: f64, max_iterations: usize) {
    let normal = a.normal();
    xs.par_iter_mut().zip(bs).for_each(|(x, b)| {
        conjugate_gradients(&normal, &a.transpose_times(b), x, tolerance, max_iterations);
    });
}

/// Solves `n x = rhs` for a symmetric positive (semi-)definite `n` by Jacobi-preconditioned
/// conjugate gradients, starting from `x`, until the residual drops by `tolerance` (relative
/// to the larger of the start residual and `rhs`) or `max_iterations` pass. Returns the
/// number of iterations used.
pub fn conjugate_gradients(n: &Sparse, rhs: &[f64], x: &mut [f64], tolerance: f64, max_iterations: usize) -> usize {
    let diagonal: Vec<f64> = n.diagonal().iter().map(|d| if *d > 0.0 { 1.0 / d } else { 0.0 }).collect();
    let mut ap = vec![0.0; x.len()];
    n.times_into(x, &mut ap);
    let mut r: Vec<f64> = rhs.iter().zip(&ap).map(|(p, q)| p - q).collect();
    let start = norm(&r).max(norm(rhs)) * tolerance;
    let mut z: Vec<f64> = r.iter().zip(&diagonal).map(|(r, d)| r * d).collect();
    let mut p = z.clone();
    let mut rz = dot(&r, &z);
    for iteration in 0..max_iterations {
        if norm(&r) <= start {
            return iteration;
        }
        n.times_into(&p, &mut ap);
        let step = rz / dot(&p, &ap).max(f64::MIN_POSITIVE);
        for i in 0..x.len() {
            x[i] += step * p[i];
            r[i] -= step * ap[i];
            z[i] = r[i] * diagonal[i];
        }
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

/// Subtracts multiples of row `col` from the rows below it (each row on its own, so the
/// rows can run in parallel with the same result).
fn eliminate_below(m: &mut [f64], b: &mut [f64], n: usize, col: usize) {
    let inv = 1.0 / m[col * n + col];
    let (top, below) = m.split_at_mut((col + 1) * n);
    let pivot_row = &top[col * n..];
    let pivot_b = b[col];
    below.par_chunks_mut(n).zip(b[col + 1..].par_iter_mut()).for_each(|(row, b)| {
        let f = row[col] * inv;
        if f == 0.0 {
            return;
        }
        for k in col..n {
            row[k] -= f * pivot_row[k];
        }
        *b -= f * pivot_b;
    });
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

    /// A sparse matrix with a few entries per row.
    fn scattered(rows: usize, cols: usize) -> Sparse {
        let mut a = Sparse::new(cols);
        for r in 0..rows {
            let columns = [r % cols, (r * 7 + 3) % cols, (r * 13 + 5) % cols];
            a.push_row(columns.map(|c| (c, 1.0 + (r + c) as f64 * 0.37 % 1.3)));
        }
        a
    }

    #[test]
    fn the_normal_matrix_is_a_transpose_a() {
        // three blocks of rows made apart: check rows on each side of their borders
        let cols = 2 * NORMAL_BLOCK + 11;
        let a = scattered(3 * cols, cols);
        let unit = |i: usize| (0..cols).map(|k| if k == i { 1.0 } else { 0.0 }).collect::<Vec<f64>>();
        let columns: Vec<Vec<f64>> = (0..cols).map(|j| a.times(&unit(j))).collect();
        let n = a.normal();
        for i in [0, 5, NORMAL_BLOCK - 1, NORMAL_BLOCK, 2 * NORMAL_BLOCK - 1, 2 * NORMAL_BLOCK, cols - 1] {
            let mut row = vec![0.0; cols];
            n.times_into(&unit(i), &mut row);
            for j in 0..cols {
                let want: f64 = columns[i].iter().zip(&columns[j]).map(|(p, q)| p * q).sum();
                assert!((row[j] - want).abs() < 1e-9, "({i}, {j}): {} against {want}", row[j]);
            }
        }
    }

    #[test]
    fn several_right_hand_sides_solve_alike_on_any_thread_count() {
        let a = scattered(60, 17);
        let bs: Vec<Vec<f64>> = (0..3).map(|k| (0..60).map(|r| ((r * (k + 2)) % 9) as f64 - 4.0).collect()).collect();
        let solve = |threads: usize| {
            let pool = rayon::ThreadPoolBuilder::new().num_threads(threads).build().unwrap();
            let mut xs = vec![vec![0.0; 17]; 3];
            pool.install(|| least_squares_each(&a, &bs, &mut xs, 1e-10, 500));
            xs
        };
        let one = solve(1);
        assert!(one.iter().zip(solve(3)).all(|(a, b)| a.iter().zip(&b).all(|(x, y)| x.to_bits() == y.to_bits())));
        for (b, x) in bs.iter().zip(&one) {
            let mut alone = vec![0.0; 17];
            least_squares(&a, b, &mut alone, 1e-10, 500);
            assert_eq!(&alone, x);
            // the normal equations hold: Aᵀ(Ax - b) = 0
            let residual: Vec<f64> = a.times(x).iter().zip(b).map(|(p, q)| p - q).collect();
            assert!(a.transpose_times(&residual).iter().all(|g| g.abs() < 1e-6), "{residual:?}");
        }
    }

    #[test]
    fn a_large_solve_is_the_same_on_any_thread_count() {
        let rows = PARALLEL_ROWS + 1000;
        let a = scattered(rows, rows);
        let b: Vec<f64> = (0..rows).map(|r| (r % 7) as f64).collect();
        let solve = |threads: usize| {
            let pool = rayon::ThreadPoolBuilder::new().num_threads(threads).build().unwrap();
            let mut x = vec![0.0; rows];
            pool.install(|| least_squares(&a, &b, &mut x, 1e-8, 200));
            x
        };
        let (one, four) = (solve(1), solve(4));
        assert!(one.iter().zip(&four).all(|(x, y)| x.to_bits() == y.to_bits()));
        assert!(one.iter().any(|x| *x != 0.0));
    }

    #[test]
    fn the_dense_solve_is_the_same_on_any_thread_count() {
        let n = 70;
        let m: Vec<f64> =
            (0..n * n).map(|i| if i % (n + 1) == 0 { 9.0 } else { ((i * 31) % 17) as f64 / 17.0 - 0.5 }).collect();
        let b: Vec<f64> = (0..n).map(|i| i as f64).collect();
        let solve = |threads: usize| {
            let pool = rayon::ThreadPoolBuilder::new().num_threads(threads).build().unwrap();
            pool.install(|| dense_solve(m.clone(), b.clone()).unwrap())
        };
        let (one, four) = (solve(1), solve(4));
        assert!(one.iter().zip(&four).all(|(x, y)| x.to_bits() == y.to_bits()));
        for row in 0..n {
            let got: f64 = (0..n).map(|k| m[row * n + k] * one[k]).sum();
            assert!((got - b[row]).abs() < 1e-9);
        }
    }
}
