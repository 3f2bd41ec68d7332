//! Bounded matrix decompositions.
//!
//! nalgebra's `svd()` and `symmetric_eigen()` iterate until convergence with
//! no limit: a matrix holding a non-finite or enormous entry can make them
//! spin for ever (issue 13: one `x` of 1e307 hung `estimate linear`). Every
//! iterative decomposition in limpid goes through these wrappers, which refuse
//! non-finite input and stop after [`MAX_ITERATIONS`] sweeps, returning `None`
//! so the caller can say why instead of hanging.

use nalgebra::{ComplexField, DMatrix, DVector, Dyn, SymmetricEigen, SVD};

/// Most QR sweeps one decomposition may take (converged ones take a few per
/// singular value; limpid's matrices are at most a few dozen wide).
pub const MAX_ITERATIONS: usize = 10_000;

/// Singular value decomposition, or `None` for a non-finite matrix or no convergence.
pub fn svd<T>(m: DMatrix<T>, compute_u: bool, compute_v: bool) -> Option<SVD<T, Dyn, Dyn>>
where
    T: ComplexField<RealField = f64>,
{
    if !m.iter().all(|v| v.is_finite()) {
        return None;
    }
    let out = m.try_svd(compute_u, compute_v, f64::EPSILON, MAX_ITERATIONS)?;
    out.singular_values
        .iter()
        .all(|s| s.is_finite())
        .then_some(out)
}

/// Singular values only.
pub fn singular_values<T>(m: DMatrix<T>) -> Option<DVector<f64>>
where
    T: ComplexField<RealField = f64>,
{
    svd(m, false, false).map(|s| s.singular_values)
}

/// Eigen-decomposition of a symmetric (Hermitian) matrix, or `None` for a
/// non-finite matrix or no convergence.
pub fn symmetric_eigen<T>(m: DMatrix<T>) -> Option<SymmetricEigen<T, Dyn>>
where
    T: ComplexField<RealField = f64>,
{
    if !m.iter().all(|v| v.is_finite()) {
        return None;
    }
    let out = SymmetricEigen::try_new(m, f64::EPSILON, MAX_ITERATIONS)?;
    out.eigenvalues.iter().all(|s| s.is_finite()).then_some(out)
}

/// Eigenvalues of a symmetric (Hermitian) matrix.
pub fn symmetric_eigenvalues<T>(m: DMatrix<T>) -> Option<DVector<f64>>
where
    T: ComplexField<RealField = f64>,
{
    symmetric_eigen(m).map(|e| e.eigenvalues)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn non_finite_and_huge_matrices_end_without_hanging() {
        let mut m = DMatrix::<f64>::identity(4, 4);
        m[(1, 2)] = f64::NAN;
        assert!(svd(m.clone(), true, true).is_none());
        assert!(symmetric_eigen(m).is_none());
        // squares of 1e307 overflow: the result is either None or finite, never a hang
        let mut big = DMatrix::<f64>::identity(4, 4);
        big[(0, 0)] = 1e307;
        big[(3, 0)] = 1e307;
        if let Some(s) = svd(big, true, true) {
            assert!(s.singular_values.iter().all(|v| v.is_finite()));
        }
    }

    #[test]
    fn agrees_with_nalgebra_on_ordinary_matrices() {
        let m = DMatrix::from_row_slice(3, 3, &[4.0, 1.0, 0.5, 1.0, 3.0, 0.2, 0.5, 0.2, 2.0]);
        let a = singular_values(m.clone()).unwrap();
        let b = m.clone().svd(false, false).singular_values;
        assert!((a - b).norm() < 1e-12);
        let e = symmetric_eigenvalues(m.clone()).unwrap();
        assert!((e.sum() - m.trace()).abs() < 1e-12);
    }
}
