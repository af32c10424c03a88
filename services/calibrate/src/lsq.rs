//! Small least-squares helpers on top of nalgebra (SVD, so rank problems are detected rather
//! than turned into huge coefficients).

use nalgebra::{DMatrix, DVector, Matrix4, SymmetricEigen};

/// Least squares `min |A x - b|` for the rows `a` (each of length `cols`). Columns are scaled
/// to unit norm first so regressors of very different sizes (T and T^3) stay well conditioned.
/// None if the problem is rank deficient (fewer independent rows than unknowns).
pub fn solve(rows: &[Vec<f64>], b: &[f64]) -> Option<Vec<f64>> {
    let cols = rows.first()?.len();
    if rows.len() < cols || rows.len() != b.len() {
        return None;
    }
    let mut a = DMatrix::from_fn(rows.len(), cols, |i, j| rows[i][j]);
    let mut scale = vec![1.0; cols];
    for (j, s) in scale.iter_mut().enumerate() {
        let norm = a.column(j).norm();
        if !(norm.is_finite() && norm > 0.0) {
            return None;
        }
        *s = norm;
        a.column_mut(j).scale_mut(1.0 / norm);
    }
    let svd = a.svd(true, true);
    let sv = &svd.singular_values;
    let max = sv.max();
    if !(max.is_finite() && sv.min() > 1e-10 * max) {
        return None;
    }
    let x = svd.solve(&DVector::from_column_slice(b), 0.0).ok()?;
    let out: Vec<f64> = x.iter().zip(&scale).map(|(v, s)| v / s).collect();
    out.iter().all(|v| v.is_finite()).then_some(out)
}

/// The unit vector `w` minimising `|A w|` for a 3x4 `A` (its null space), and the ratio of the
/// second smallest to the largest eigenvalue of `A^T A`: near 0 when `A` has rank < 3 and the
/// null space is not one-dimensional, so `w` is not determined.
pub fn null_vector_3x4(a: &[[f64; 4]; 3]) -> ([f64; 4], f64) {
    let m: Matrix4<f64> = Matrix4::from_fn(|i, j| (0..3).map(|k| a[k][i] * a[k][j]).sum());
    let eig: SymmetricEigen<f64, nalgebra::U4> = SymmetricEigen::new(m);
    let mut order: Vec<usize> = (0..4).collect();
    order.sort_by(|&i, &j| eig.eigenvalues[i].total_cmp(&eig.eigenvalues[j]));
    let v = eig.eigenvectors.column(order[0]);
    let ratio = eig.eigenvalues[order[1]].abs() / eig.eigenvalues[order[3]].abs();
    ([v[0], v[1], v[2], v[3]], ratio)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn fits_a_line_and_detects_rank_loss() {
        let rows: Vec<Vec<f64>> = (0..5).map(|i| vec![1.0, i as f64]).collect();
        let b: Vec<f64> = (0..5).map(|i| 2.0 + 3.0 * i as f64).collect();
        let x = solve(&rows, &b).unwrap();
        assert!((x[0] - 2.0).abs() < 1e-12 && (x[1] - 3.0).abs() < 1e-12);
        let same: Vec<Vec<f64>> = (0..5).map(|_| vec![1.0, 2.0]).collect();
        assert!(solve(&same, &b).is_none());
    }

    #[test]
    fn null_vector_of_a_rank_3_matrix() {
        let a = [
            [1.0, 0.0, -1.0, 0.0],
            [0.0, 1.0, 0.0, -1.0],
            [1.0, -1.0, 1.0, -1.0],
        ];
        let (w, ratio) = null_vector_3x4(&a);
        assert!(ratio > 0.1, "{ratio}");
        for row in a {
            let dot: f64 = row.iter().zip(w).map(|(x, y)| x * y).sum();
            assert!(dot.abs() < 1e-12);
        }
        assert!((w[0] - w[1]).abs() < 1e-12 && (w[0] - w[2]).abs() < 1e-12);
    }
}
