//! Two-point statistics along an axis: sums of lagged products, for the ground-truth
//! comparison of synthesis (normalized autocorrelation of grey values). Label volumes count
//! the same pairs on rows of bits ([`crate::labels`]), checked against this routine.

use crate::volume::Axis;

/// The lag at which a falling correlation crosses 1/e, given its values `before` at
/// `lag - 1` (above 1/e) and `at` at `lag` (at or below): linear between the two.
pub fn e_folding(lag: usize, before: f64, at: f64) -> f64 {
    (lag - 1) as f64 + (before - (-1.0f64).exp()) / (before - at)
}

/// For each lag `0..=max_lag`: the sum of `values(p) * values(p + lag along axis)` over the
/// points `p` (all of the volume, or with `Some((other, index))` only the slice across
/// `other` at `index`) whose partner lies inside the volume (no wrapping), and how many
/// such pairs there are. `values` holds one number per voxel, x fastest.
pub fn lagged_products(
    values: &[f64],
    dims: [usize; 3],
    axis: Axis,
    within: Option<(Axis, usize)>,
    max_lag: usize,
) -> Vec<(f64, usize)> {
    let a = axis.index();
    let stride = [1, dims[0], dims[0] * dims[1]][a];
    let range = |k: usize| match within {
        Some((other, index)) if other.index() == k => index..index + 1,
        _ => 0..dims[k],
    };
    (0..=max_lag)
        .map(|lag| {
            let (mut sum, mut count) = (0.0, 0);
            for z in range(2) {
                for y in range(1) {
                    for x in range(0) {
                        if [x, y, z][a] + lag >= dims[a] {
                            continue;
                        }
                        let i = (z * dims[1] + y) * dims[0] + x;
                        sum += values[i] * values[i + lag * stride];
                        count += 1;
                    }
                }
            }
            (sum, count)
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn products_count_the_pairs_inside() {
        // 3x1x1 along x: values 1, 2, 3
        let p = lagged_products(&[1.0, 2.0, 3.0], [3, 1, 1], Axis::X, None, 2);
        assert_eq!(p, [(14.0, 3), (8.0, 2), (3.0, 1)]);
        let across = lagged_products(&[1.0, 2.0, 3.0, 4.0], [2, 2, 1], Axis::Y, Some((Axis::X, 1)), 1);
        assert_eq!(across, [(20.0, 2), (8.0, 1)]);
    }
}
