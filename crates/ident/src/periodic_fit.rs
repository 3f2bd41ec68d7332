//! M, B and K from a periodic experiment (issue 59): the period-averaged
//! spectra at the excited lines fitted directly to
//! `F(ω) = (K + jωB - ω²M) X(ω)` (Pintelon & Schoukens, *System
//! Identification: a Frequency Domain Approach*, ch. 9: a weighted linear
//! least squares in the frequency domain), row by row of the matrices.
//!
//! With several inputs on disjoint (zippered) line sets every line carries
//! the full displacement vector X̄ and force vector F̄, so no interpolation
//! between lines is needed. Weights: each line's residual noise
//! `var(F̄_o - Z_o X̄)`, from the period-to-period (co)variances of all the
//! signals at that line (the displacement noise included), with Z from a
//! first pass weighted by the force's noise alone. Standard errors: the weighted least-squares
//! covariance, scaled by the weighted residual per degree of freedom when it
//! exceeds 1 (what the noise leaves unexplained: model error, a nonlinearity,
//! drift), so they carry the misfit instead of assuming the model exact.

use limpid_core::criteria::{judge_matrix, MatrixKind, Verdicts, VAF_FLOOR_PERCENT};
use limpid_core::Matrix;
use limpid_dsp::periodic::{PeriodSpectra, PeriodicAnalysis};
use nalgebra::{DMatrix, DVector};
use num_complex::Complex64;
use schemars::JsonSchema;
use serde::{Deserialize, Serialize};

use crate::stochastic::ParametricErrors;

/// M, B and K fitted to the response at the excited lines of a periodic
/// experiment whose inputs are displacements and outputs forces.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, JsonSchema)]
pub struct PeriodicImpedance {
    /// M (rows: the outputs, forces; columns: the inputs, displacements).
    pub inertia: Matrix,
    /// B, same layout.
    pub damping: Matrix,
    /// K, same layout.
    pub stiffness: Matrix,
    /// Standard errors: weighted least squares over the lines, scaled by
    /// `residual_ratio` when it exceeds 1.
    pub standard_errors: ParametricErrors,
    /// Excited lines fitted.
    pub lines: usize,
    /// Weighted VAF (%) of the forces at the excited lines.
    pub fit_vaf: f64,
    /// Weighted residual per degree of freedom: about 1 when M, B, K explain
    /// the response within its noise; above 1 the model misses something
    /// (a nonlinearity, an unmodelled resonance, drift).
    pub residual_ratio: f64,
    /// The verdicts on K, B and M by the rules every estimator uses; none is
    /// trusted below the VAF floor or when the detection lines show
    /// distortion that reaches the excited lines (M, B, K are then the best
    /// linear approximation at this amplitude; even distortion under an odd
    /// multisine does not reach them).
    pub verdicts: Verdicts,
}

/// Fit M, B, K to the excited lines of `analysis`: `spectra`'s first
/// `inputs` signals are displacements, the next `inputs` forces; `nonlinear`:
/// the detection lines of either show distortion that reaches the excited lines. `None` with
/// fewer equations than twice the unknowns of a row.
pub fn fit(
    spectra: &PeriodSpectra,
    analysis: &PeriodicAnalysis,
    inputs: usize,
    period_s: f64,
    nonlinear: bool,
) -> Option<PeriodicImpedance> {
    let n = inputs;
    let lines: Vec<usize> = analysis.responses.iter().map(|r| r.line).collect();
    let unknowns = 3 * n;
    if spectra.mean.len() != 2 * n || 2 * lines.len() < 2 * unknowns {
        return None;
    }
    let omega = |line: usize| 2.0 * std::f64::consts::PI * line as f64 / period_s;
    let mut rows: Vec<Row> = Vec::with_capacity(n);
    for o in 0..n {
        let f = n + o;
        // a first pass weighted by each line's force noise alone, then by
        // the residual's own noise with that Z
        let first = solve(spectra, &lines, n, f, &omega, |k| {
            spectra.variance_of_mean(f, k)
        })?;
        let z_of = |k: usize, theta: &DVector<f64>| -> Vec<Complex64> {
            let w = omega(k);
            (0..n)
                .map(|j| Complex64::new(theta[j] - w * w * theta[2 * n + j], w * theta[n + j]))
                .collect()
        };
        let second = solve(spectra, &lines, n, f, &omega, |k| {
            residual_variance(spectra, n, f, k, &z_of(k, &first.theta))
        })?;
        rows.push(second);
    }
    let total_dof = rows.iter().map(|r| r.equations).sum::<usize>() - n * unknowns;
    let chi2: f64 = rows.iter().map(|r| r.chi2).sum();
    let power: f64 = rows.iter().map(|r| r.weighted_power).sum();
    let residual_ratio = chi2 / total_dof.max(1) as f64;
    let scale = residual_ratio.max(1.0);
    let fit_vaf = 100.0 * (1.0 - chi2 / power);
    let mut m = Matrix::zeros(n, n);
    let mut b = Matrix::zeros(n, n);
    let mut k = Matrix::zeros(n, n);
    let (mut sm, mut sb, mut sk) = (
        Matrix::zeros(n, n),
        Matrix::zeros(n, n),
        Matrix::zeros(n, n),
    );
    for (o, r) in rows.iter().enumerate() {
        for j in 0..n {
            k[(o, j)] = r.theta[j];
            b[(o, j)] = r.theta[n + j];
            m[(o, j)] = r.theta[2 * n + j];
            sk[(o, j)] = (r.variance[j] * scale).sqrt();
            sb[(o, j)] = (r.variance[n + j] * scale).sqrt();
            sm[(o, j)] = (r.variance[2 * n + j] * scale).sqrt();
        }
    }
    // where the distortion reaches the excited lines a linear model is the
    // response's best linear approximation at this amplitude, not the limb's impedance
    let fit_ok = fit_vaf >= VAF_FLOOR_PERCENT && !nonlinear;
    let verdicts = Verdicts {
        stiffness: judge_matrix(MatrixKind::Stiffness, &k, &sk, fit_ok),
        damping: judge_matrix(MatrixKind::Damping, &b, &sb, fit_ok),
        inertia: Some(judge_matrix(MatrixKind::Inertia, &m, &sm, fit_ok)),
    };
    Some(PeriodicImpedance {
        inertia: m,
        damping: b,
        stiffness: k,
        standard_errors: ParametricErrors {
            method: if residual_ratio > 1.0 {
                format!(
                    "weighted least squares over the excited lines (noise from the period-to-period scatter), scaled by the residual ratio {}",
                    limpid_core::significant(residual_ratio, 3)
                )
            } else {
                "weighted least squares over the excited lines (noise from the period-to-period scatter)".into()
            },
            inertia: sm,
            damping: sb,
            stiffness: sk,
        },
        lines: lines.len(),
        fit_vaf,
        residual_ratio,
        verdicts,
    })
}

/// One output's row of K, B, M: the estimate, its variances (unscaled), the
/// weighted residual and force power, and the equations used.
struct Row {
    theta: DVector<f64>,
    variance: Vec<f64>,
    chi2: f64,
    weighted_power: f64,
    equations: usize,
}

/// Weighted least squares of output signal `f` on the displacements at
/// `lines`, each line's complex residual of variance `noise(line)` (half on
/// each of its real equations).
fn solve(
    spectra: &PeriodSpectra,
    lines: &[usize],
    n: usize,
    f: usize,
    omega: &dyn Fn(usize) -> f64,
    noise: impl Fn(usize) -> f64,
) -> Option<Row> {
    let p = 3 * n;
    let rows = 2 * lines.len();
    let mut a = DMatrix::<f64>::zeros(rows, p);
    let mut y = DVector::<f64>::zeros(rows);
    let mut weight = DVector::<f64>::zeros(rows);
    for (r, &k) in lines.iter().enumerate() {
        let w = omega(k);
        let fk = spectra.mean[f][k];
        // a noise-free line (simulated, quantised away) keeps a finite weight
        let floor = 1e-24 + (1e-9 * fk.norm()).powi(2);
        let var = noise(k).max(floor);
        for j in 0..n {
            let x = spectra.mean[j][k];
            // Re: K Re X - ω B Im X - ω² M Re X; Im: K Im X + ω B Re X - ω² M Im X
            a[(2 * r, j)] = x.re;
            a[(2 * r, n + j)] = -w * x.im;
            a[(2 * r, 2 * n + j)] = -w * w * x.re;
            a[(2 * r + 1, j)] = x.im;
            a[(2 * r + 1, n + j)] = w * x.re;
            a[(2 * r + 1, 2 * n + j)] = -w * w * x.im;
        }
        y[2 * r] = fk.re;
        y[2 * r + 1] = fk.im;
        weight[2 * r] = 2.0 / var;
        weight[2 * r + 1] = 2.0 / var;
    }
    let sqrt_w = weight.map(f64::sqrt);
    let mut aw = a.clone();
    for r in 0..rows {
        aw.row_mut(r).scale_mut(sqrt_w[r]);
    }
    let yw = y.component_mul(&sqrt_w);
    // columns scaled to unit norm: K, ωB and ω²M differ by orders of magnitude
    let norms: Vec<f64> = (0..p).map(|c| aw.column(c).norm()).collect();
    if norms.iter().any(|v| !(v.is_finite() && *v > 0.0)) {
        return None;
    }
    for (c, v) in norms.iter().enumerate() {
        aw.column_mut(c).scale_mut(1.0 / v);
    }
    let svd = aw.clone().svd(true, true);
    let smax = svd.singular_values.max();
    if !(smax.is_finite() && smax > 0.0) || svd.singular_values.min() < 1e-12 * smax {
        return None;
    }
    let scaled = svd.solve(&yw, 0.0).ok()?;
    let v = svd.v_t.as_ref()?.transpose();
    let inv_s2 = svd.singular_values.map(|s| 1.0 / (s * s));
    let theta = DVector::from_fn(p, |c, _| scaled[c] / norms[c]);
    let variance = (0..p)
        .map(|c| {
            (0..p)
                .map(|q| v[(c, q)] * v[(c, q)] * inv_s2[q])
                .sum::<f64>()
                / (norms[c] * norms[c])
        })
        .collect();
    let residual = &y - &a * &theta;
    let chi2 = residual
        .iter()
        .zip(weight.iter())
        .map(|(r, w)| w * r * r)
        .sum();
    let weighted_power = y.iter().zip(weight.iter()).map(|(v, w)| w * v * v).sum();
    Some(Row {
        theta,
        variance,
        chi2,
        weighted_power,
        equations: rows,
    })
}

/// Variance of the period average of `F_f - Σ_j z_j X_j` at `line`, from the
/// (co)variances of the signals.
fn residual_variance(
    spectra: &PeriodSpectra,
    n: usize,
    f: usize,
    line: usize,
    z: &[Complex64],
) -> f64 {
    // coefficients of the signals in the residual: 1 for F, -z_j for X_j
    let mut terms: Vec<(usize, Complex64)> = vec![(f, Complex64::new(1.0, 0.0))];
    terms.extend((0..n).map(|j| (j, -z[j])));
    let mut v = Complex64::new(0.0, 0.0);
    for &(a, ca) in &terms {
        for &(b, cb) in &terms {
            v += ca * cb.conj() * spectra.covariance_of_mean(a, b, line);
        }
    }
    v.re.max(0.0)
}
