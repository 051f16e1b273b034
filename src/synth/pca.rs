//! Principal component analysis of neighbourhood vectors: the basis that keeps a
//! chosen share of the variance, found with the cyclic Jacobi eigenvalue method
//! (exact, deterministic, fast enough for the 192x192 covariance of 8x8 RGB).

/// A PCA projection: `project(x) = basis * (x - mean)`.
#[derive(Debug, Clone)]
pub struct Pca {
    /// Length of the input vectors.
    pub input: usize,
    /// Number of kept components.
    pub dims: usize,
    /// Mean input vector.
    pub mean: Vec<f32>,
    /// `dims` rows of `input` values, strongest component first.
    pub basis: Vec<f32>,
    /// Share of the total variance the kept components explain.
    pub explained: f32,
}

impl Pca {
    /// Fit on `count` vectors of length `input` (row-major in `data`), keeping the fewest
    /// components that explain `variance` of the total, between 1 and `max_dims`.
    pub fn fit(data: &[f32], input: usize, variance: f32, max_dims: usize) -> Pca {
        let count = data.len() / input;
        let mean: Vec<f64> = (0..input)
            .map(|j| data.iter().skip(j).step_by(input).map(|v| *v as f64).sum::<f64>() / count.max(1) as f64)
            .collect();
        let cov = covariance(data, input, &mean);
        let total: f64 = (0..input).map(|i| cov[i * input + i]).sum::<f64>().max(1e-30);
        let wanted = max_dims.min(input);
        let (values, vectors, columns) = if input <= 2 * wanted + 16 {
            let (values, vectors) = jacobi_eigen(cov, input);
            (values, vectors, input)
        } else {
            let columns = wanted + 8;
            let (values, vectors) = top_eigen(&cov, input, columns);
            (values, vectors, columns)
        };
        let mut order: Vec<usize> = (0..values.len()).collect();
        order.sort_by(|a, b| values[*b].total_cmp(&values[*a]).then(a.cmp(b)));
        let (mut kept, mut sum) = (0, 0.0);
        while kept < wanted && (kept == 0 || sum / total < variance as f64) {
            sum += values[order[kept]].max(0.0);
            kept += 1;
        }
        let basis = order[..kept]
            .iter()
            .flat_map(|&k| (0..input).map(move |j| (j, k)))
            .map(|(j, k)| vectors[j * columns + k] as f32)
            .collect();
        Pca {
            input,
            dims: kept,
            mean: mean.iter().map(|m| *m as f32).collect(),
            basis,
            explained: (sum / total) as f32,
        }
    }

    /// Project one vector into `out` (length `dims`).
    pub fn project(&self, x: &[f32], out: &mut [f32]) {
        for (k, o) in out.iter_mut().enumerate() {
            let row = &self.basis[k * self.input..(k + 1) * self.input];
            *o = row.iter().zip(x).zip(&self.mean).map(|((b, v), m)| b * (v - m)).sum();
        }
    }
}

impl Pca {
    /// As [`Pca::project`], with `x` centred in place and every component summed in eight
    /// lanes: several times faster, equal to `project` up to rounding.
    pub fn project_centring(&self, x: &mut [f32], out: &mut [f32]) {
        x.iter_mut().zip(&self.mean).for_each(|(v, m)| *v -= m);
        for (k, o) in out.iter_mut().enumerate() {
            *o = super::knn::lane_sum(&self.basis[k * self.input..(k + 1) * self.input], x, |b, v| b * v);
        }
    }
}

/// Covariance matrix (input x input, f64) of row-major vectors.
fn covariance(data: &[f32], input: usize, mean: &[f64]) -> Vec<f64> {
    let count = (data.len() / input).max(1);
    let mut cov = vec![0.0f64; input * input];
    let mut centred = vec![0.0f64; input];
    for row in data.chunks_exact(input) {
        for (c, (v, m)) in centred.iter_mut().zip(row.iter().zip(mean)) {
            *c = *v as f64 - m;
        }
        for i in 0..input {
            let ci = centred[i];
            let line = &mut cov[i * input..i * input + i + 1];
            for (slot, cj) in line.iter_mut().zip(&centred) {
                *slot += ci * cj;
            }
        }
    }
    for i in 0..input {
        for j in 0..=i {
            let v = cov[i * input + j] / count as f64;
            cov[i * input + j] = v;
            cov[j * input + i] = v;
        }
    }
    cov
}

/// The `m` largest eigenpairs of a symmetric n x n matrix by subspace iteration with a
/// final Rayleigh-Ritz step: (values, n x m row-major matrix whose columns are vectors).
fn top_eigen(a: &[f64], n: usize, m: usize) -> (Vec<f64>, Vec<f64>) {
    let mut q: Vec<f64> = (0..n * m).map(|i| (crate::noise::mix64(i as u64) % 2001) as f64 / 1000.0 - 1.0).collect();
    orthonormalize(&mut q, n, m);
    for _ in 0..40 {
        q = multiply(a, &q, n, m);
        orthonormalize(&mut q, n, m);
    }
    let aq = multiply(a, &q, n, m);
    let mut t = vec![0.0; m * m];
    for i in 0..m {
        for j in 0..m {
            t[i * m + j] = (0..n).map(|k| q[k * m + i] * aq[k * m + j]).sum();
        }
    }
    let (values, small) = jacobi_eigen(t, m);
    let mut vectors = vec![0.0; n * m];
    for k in 0..n {
        for j in 0..m {
            vectors[k * m + j] = (0..m).map(|i| q[k * m + i] * small[i * m + j]).sum();
        }
    }
    (values, vectors)
}

/// `a (n x n) * q (n x m)`.
fn multiply(a: &[f64], q: &[f64], n: usize, m: usize) -> Vec<f64> {
    let mut out = vec![0.0; n * m];
    for i in 0..n {
        let row = &mut out[i * m..(i + 1) * m];
        for k in 0..n {
            let aik = a[i * n + k];
            for (o, qk) in row.iter_mut().zip(&q[k * m..(k + 1) * m]) {
                *o += aik * qk;
            }
        }
    }
    out
}

/// Modified Gram-Schmidt on the m columns of an n x m row-major matrix.
fn orthonormalize(q: &mut [f64], n: usize, m: usize) {
    for j in 0..m {
        for i in 0..j {
            let dot: f64 = (0..n).map(|k| q[k * m + i] * q[k * m + j]).sum();
            for k in 0..n {
                q[k * m + j] -= dot * q[k * m + i];
            }
        }
        let norm = (0..n).map(|k| q[k * m + j].powi(2)).sum::<f64>().sqrt().max(1e-300);
        for k in 0..n {
            q[k * m + j] /= norm;
        }
    }
}

/// Eigenvalues and eigenvectors (columns of the returned row-major matrix) of a
/// symmetric matrix, by cyclic Jacobi rotations.
pub fn jacobi_eigen(mut a: Vec<f64>, n: usize) -> (Vec<f64>, Vec<f64>) {
    let mut v = vec![0.0f64; n * n];
    for i in 0..n {
        v[i * n + i] = 1.0;
    }
    let scale: f64 = a.iter().map(|x| x * x).sum::<f64>().sqrt().max(1e-300);
    for _sweep in 0..60 {
        let off: f64 = (0..n)
            .flat_map(|i| (0..n).filter(move |j| *j != i).map(move |j| (i, j)))
            .map(|(i, j)| a[i * n + j].powi(2))
            .sum();
        if off.sqrt() <= 1e-12 * scale {
            break;
        }
        for p in 0..n {
            for q in p + 1..n {
                rotate(&mut a, &mut v, n, p, q);
            }
        }
    }
    ((0..n).map(|i| a[i * n + i]).collect(), v)
}

/// One Jacobi rotation zeroing a[p][q].
fn rotate(a: &mut [f64], v: &mut [f64], n: usize, p: usize, q: usize) {
    let apq = a[p * n + q];
    if apq.abs() < 1e-300 {
        return;
    }
    let theta = (a[q * n + q] - a[p * n + p]) / (2.0 * apq);
    let t = theta.signum() / (theta.abs() + (theta * theta + 1.0).sqrt());
    let t = if theta == 0.0 { 1.0 } else { t };
    let c = 1.0 / (t * t + 1.0).sqrt();
    let s = t * c;
    for k in 0..n {
        let (akp, akq) = (a[k * n + p], a[k * n + q]);
        a[k * n + p] = c * akp - s * akq;
        a[k * n + q] = s * akp + c * akq;
    }
    for k in 0..n {
        let (apk, aqk) = (a[p * n + k], a[q * n + k]);
        a[p * n + k] = c * apk - s * aqk;
        a[q * n + k] = s * apk + c * aqk;
    }
    for k in 0..n {
        let (vkp, vkq) = (v[k * n + p], v[k * n + q]);
        v[k * n + p] = c * vkp - s * vkq;
        v[k * n + q] = s * vkp + c * vkq;
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn jacobi_finds_known_eigenvalues() {
        let a = vec![2.0, 1.0, 0.0, 1.0, 2.0, 0.0, 0.0, 0.0, 5.0];
        let (mut values, _) = jacobi_eigen(a, 3);
        values.sort_by(f64::total_cmp);
        for (got, want) in values.iter().zip([1.0, 3.0, 5.0]) {
            assert!((got - want).abs() < 1e-9, "{values:?}");
        }
    }

    #[test]
    fn subspace_iteration_finds_the_top_eigenpairs() {
        // A diagonal-dominant matrix with a known spectrum, rotated by a fixed orthogonal mix.
        let n = 60;
        let mut a = vec![0.0; n * n];
        for i in 0..n {
            a[i * n + i] = 100.0 / (1.0 + i as f64);
        }
        let (values, _) = top_eigen(&a, n, 8);
        let mut values = values;
        values.sort_by(|x, y| y.total_cmp(x));
        for (i, v) in values.iter().take(5).enumerate() {
            assert!((v - 100.0 / (1.0 + i as f64)).abs() < 1e-6, "{values:?}");
        }
    }

    #[test]
    fn pca_keeps_the_line_data_lies_on() {
        // Points on the line t * (3, 4) / 5 plus tiny noise: one component explains it.
        let data: Vec<f32> = (0..50)
            .flat_map(|i| {
                let t = i as f32 - 24.5;
                let e = if i % 2 == 0 { 0.01 } else { -0.01 };
                [t * 0.6 + e, t * 0.8 - e]
            })
            .collect();
        let pca = Pca::fit(&data, 2, 0.95, 2);
        assert_eq!(pca.dims, 1);
        assert!(pca.explained > 0.999);
        let dir = (pca.basis[0].abs(), pca.basis[1].abs());
        assert!((dir.0 - 0.6).abs() < 1e-3 && (dir.1 - 0.8).abs() < 1e-3, "{dir:?}");
        let mut out = [0.0];
        pca.project(&[0.6 * 10.0, 0.8 * 10.0], &mut out);
        assert!((out[0].abs() - 10.0).abs() < 0.01);
    }

    /// The lane-summed projection gives the plain one's values, on vectors longer than a
    /// lane group and with a remainder (27 inputs).
    #[test]
    fn the_lane_sums_project_as_the_plain_sums() {
        let data: Vec<f32> = (0..40 * 27).map(|i| ((i * 37 % 101) as f32 * 0.013).sin()).collect();
        let pca = Pca::fit(&data, 27, 0.99, 6);
        let x: Vec<f32> = (0..27).map(|i| (i as f32 * 0.7).cos()).collect();
        let (mut plain, mut lanes) = (vec![0.0; pca.dims], vec![0.0; pca.dims]);
        pca.project(&x, &mut plain);
        pca.project_centring(&mut x.clone(), &mut lanes);
        for (p, l) in plain.iter().zip(&lanes) {
            assert!((p - l).abs() < 1e-5 * (1.0 + p.abs()), "{plain:?} against {lanes:?}");
        }
    }
}
