//! Errors in the regressors of seed 003's eq. (13): the measured joint angles
//! carry noise, and its filtered second difference in the acceleration
//! columns biases least squares (errors in variables). Seed 003 does not
//! treat it; limpid compensates it as the linear estimator does
//! (bias-compensated least squares: `W^T W - E[N^T N]`, `W^T y - E[N^T n_y]`),
//! with the noise covariance of every regressor row derived from the angles'
//! white-noise covariance and the impulse response of the preparation.
//!
//! Why it matters: with 50 µrad of angle noise (or end-point positions through
//! the inverse kinematics) the shared inertia came out attenuated, and its
//! error entered K with opposite signs while the arm accelerated and while it
//! decelerated; the window sweep's change scan read that as a reflex in 20 of
//! 20 reflex-free arms (issue 37).
//!
//! Every row's noise is linear in the six noises `(Δq1, Δq2, q'1, q'2, q''1,
//! q''2)` with coefficients `L0 + cos(q2) L1`, so a trial's sum over rows
//! needs only the count, `Σ cos q2` and `Σ cos² q2` of its samples.

use super::PlanarTrial;
use limpid_core::trial::noise_sigma;
use nalgebra::{DMatrix, DVector};
/// White noise of the two recorded joint angles and what the preparation
/// makes of it.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct AngleNoise {
    /// Covariance of the angles' white noise (rad²), from robust second
    /// differences of q1, q2, q1 + q2 and q1 - q2 (end-point data make the
    /// joints' noise correlated through the inverse kinematics).
    pub covariance: [[f64; 2]; 2],
    /// Variance of the prepared angle, velocity and acceleration per unit
    /// white-noise variance, and the angle-acceleration covariance.
    pub gains: [f64; 4],
}

impl AngleNoise {
    /// Estimate from the raw angles; `gains` from the preparation's filter.
    pub fn estimate(q: &[Vec<f64>; 2], gains: [f64; 4]) -> Self {
        let combined = |sign: f64| {
            let c: Vec<f64> = q[0].iter().zip(&q[1]).map(|(a, b)| a + sign * b).collect();
            noise_sigma(&c).powi(2)
        };
        let (v1, v2) = (noise_sigma(&q[0]).powi(2), noise_sigma(&q[1]).powi(2));
        // |cov| <= sqrt(v1 v2): the robust estimates need not be consistent
        let bound = (v1 * v2).sqrt();
        let cov = ((combined(1.0) - combined(-1.0)) / 4.0).clamp(-bound, bound);
        let covariance = [[v1, cov], [cov, v2]];
        let finite = covariance
            .iter()
            .flatten()
            .chain(&gains)
            .all(|v| v.is_finite());
        if finite {
            Self { covariance, gains }
        } else {
            Self::default()
        }
    }

    fn is_zero(&self) -> bool {
        self.covariance.iter().flatten().all(|v| *v == 0.0)
    }
}

/// The rows' noise covariance summed over samples, per power of `cos q2`, in
/// the column layout of `trial_rows` (regressors, then the torque).
pub(crate) struct RegressorNoise {
    terms: Option<[DMatrix<f64>; 3]>,
}

impl RegressorNoise {
    pub(crate) fn new(noise: &AngleNoise, xi: Option<[f64; 3]>) -> Self {
        if noise.is_zero() {
            return Self { terms: None };
        }
        // covariance of (Δq1, Δq2, q'1, q'2, q''1, q''2)
        let (s, g) = (noise.covariance, noise.gains);
        let mut gamma = DMatrix::<f64>::zeros(6, 6);
        for j in 0..2 {
            for k in 0..2 {
                gamma[(j, k)] = s[j][k] * g[0];
                gamma[(2 + j, 2 + k)] = s[j][k] * g[1];
                gamma[(4 + j, 4 + k)] = s[j][k] * g[2];
                gamma[(j, 4 + k)] = s[j][k] * g[3];
                gamma[(4 + k, j)] = s[j][k] * g[3];
            }
        }
        let first = if xi.is_some() { 3 } else { 0 };
        let cols = 12 - first;
        let mut terms = [
            DMatrix::zeros(cols, cols),
            DMatrix::zeros(cols, cols),
            DMatrix::zeros(cols, cols),
        ];
        for r in 0..2 {
            // loadings of the 11 regressors and the torque (column 11) on the six noises
            let (mut l0, mut l1) = (DMatrix::<f64>::zeros(12, 6), DMatrix::<f64>::zeros(12, 6));
            if r == 0 {
                l0[(0, 4)] = 1.0;
                l1[(1, 4)] = 2.0;
                l1[(1, 5)] = 1.0;
                l0[(2, 5)] = 1.0;
                l0[(3, 2)] = 1.0;
                l0[(4, 3)] = 1.0;
                l0[(7, 0)] = 1.0;
                l0[(8, 1)] = 1.0;
            } else {
                l1[(1, 4)] = 1.0;
                l0[(2, 4)] = 1.0;
                l0[(2, 5)] = 1.0;
                l0[(5, 2)] = 1.0;
                l0[(6, 3)] = 1.0;
                l0[(9, 0)] = 1.0;
                l0[(10, 1)] = 1.0;
            }
            if let Some(xi) = xi {
                // the known M q'' moves to the torque side: its noise enters the torque column
                let m0 = [[xi[0], xi[2]], [xi[2], xi[2]]];
                let m1 = [[2.0 * xi[1], xi[1]], [xi[1], 0.0]];
                for k in 0..2 {
                    l0[(11, 4 + k)] = -m0[r][k];
                    l1[(11, 4 + k)] = -m1[r][k];
                }
            }
            let (l0, l1) = (l0.rows(first, cols), l1.rows(first, cols));
            let cross = l0 * &gamma * l1.transpose();
            terms[0] += l0 * &gamma * l0.transpose();
            terms[1] += &cross + cross.transpose();
            terms[2] += l1 * &gamma * l1.transpose();
        }
        Self { terms: Some(terms) }
    }

    /// The noise covariance summed over a trial's samples `range`, or None
    /// when the angles carry none.
    pub(crate) fn over(
        &self,
        t: &PlanarTrial,
        range: std::ops::Range<usize>,
    ) -> Option<DMatrix<f64>> {
        let terms = self.terms.as_ref()?;
        let range = range.start.min(t.q[1].len())..range.end.min(t.q[1].len());
        let (mut s1, mut s2) = (0.0, 0.0);
        for q2 in &t.q[1][range.clone()] {
            let c = q2.cos();
            s1 += c;
            s2 += c * c;
        }
        Some(&terms[0] * range.len() as f64 + &terms[1] * s1 + &terms[2] * s2)
    }
}

/// Solve the scaled normal equations with the regressors' noise removed:
/// `(R^T R - N) θ = R^T z - n` (all in the unit-RMS column scaling), over the
/// columns whose noise is at most half their mean square (as the linear
/// estimator's `MIN_CORRECTABLE`: below that the correction amplifies noise
/// more than it removes bias). None when the corrected Gram matrix is not
/// positive definite (then the uncorrected solution stands).
pub(crate) fn compensated_solve(
    r_aug: &DMatrix<f64>,
    noise_scaled: &DMatrix<f64>,
    correctable: &[bool],
) -> Option<DVector<f64>> {
    let p = r_aug.ncols() - 1;
    let r = r_aug.view((0, 0), (p, p));
    let z = r_aug.view((0, p), (p, 1));
    let mut gram = r.transpose() * r;
    let mut rhs = r.transpose() * z;
    for i in (0..p).filter(|&i| correctable[i]) {
        for j in (0..p).filter(|&j| correctable[j]) {
            gram[(i, j)] -= noise_scaled[(i, j)];
        }
        rhs[(i, 0)] -= noise_scaled[(i, p)];
    }
    gram.cholesky()
        .map(|c| c.solve(&rhs).column(0).into_owned())
        .filter(|t| t.iter().all(|v| v.is_finite()))
}
