//! Soft tissue in series with the handle (seed 003 §IV-A: the robot holds
//! the forearm "via a plastic cuff"): the robot measures its own position
//! `q_r`, the arm sits behind a spring-damper. With the tissue's damping
//! proportional to its stiffness (`D_c = T_c K_c`, as for isotropic tissue
//! at the hand), the deflection `e = q_r - q_a` obeys
//! `T_c ė + e = C Δτ` (C = K_c⁻¹), so the arm's angles follow from the
//! recording given the compliance C (2 x 2, symmetric, positive
//! semi-definite) and T_c. The rigid model of eq. (9) fitted to `q_r` sees
//! window-dependent K and D instead, which the window sweep's change scan
//! reads as a change within the trials.
//!
//! limpid fits C and T_c by variable projection (Nelder-Mead over C = L Lᵀ
//! and T_c; eq. (13)'s least squares inside) and asks whether the arm behind
//! that compliance still changes: a change it explains is reported as soft
//! tissue in series, not as a reflex. The choice of model (proportional
//! damping, massless tissue) is ours; the paper does not model the cuff.

use super::fit::trial_rows;
use super::prepare::PlanarData;
use crate::lsq::{merge, triangle};
use argmin::core::{CostFunction, Executor};
use argmin::solver::neldermead::NelderMead;
use limpid_dsp::central_first;
use nalgebra::{DMatrix, Matrix2};
use schemars::JsonSchema;
use serde::{Deserialize, Serialize};

/// A compliance in series with the arm, from [`fit_series_compliance`].
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize, JsonSchema)]
pub struct SeriesCompliance {
    /// Joint-space compliance C = K_c⁻¹ (rad/(N m)).
    pub compliance: [[f64; 2]; 2],
    /// Time constant of the tissue, D_c = T_c K_c (s).
    pub time_constant_s: f64,
    /// Residual sum of squares of the rigid fit over that with the compliance.
    pub residual_ratio: f64,
}

/// Nelder-Mead runs (each restarted around the last one's best point) and
/// iterations per run.
const ROUNDS: usize = 2;
const MAX_ITERATIONS: u64 = 300;

/// Longest tissue time constant searched (s).
const MAX_TIME_CONSTANT_S: f64 = 0.05;

/// The trials as the arm behind a compliance `c` with time constant `tc`
/// sees them: `Δq_a = Δq_r - C y`, `T_c ẏ + y = Δτ` (y = 0 at the onset,
/// where the arm rests), velocities and accelerations alike.
pub(crate) fn behind_compliance(data: &PlanarData, c: &Matrix2<f64>, tc: f64) -> PlanarData {
    let dt = 1.0 / data.fs;
    let trials = data
        .trials
        .iter()
        .map(|t| {
            let n = t.dq[0].len();
            let mut out = t.clone();
            // y, ẏ, ÿ of each joint's torque through the first-order lag
            let lag = [lagged(&t.dtau[0], tc, dt), lagged(&t.dtau[1], tc, dt)];
            for j in 0..2 {
                let shift =
                    |d: usize, i: usize| c[(j, 0)] * lag[0][d][i] + c[(j, 1)] * lag[1][d][i];
                for i in 0..n {
                    out.dq[j][i] -= shift(0, i);
                    out.q[j][i] -= shift(0, i);
                    out.qd[j][i] -= shift(1, i);
                    out.qdd[j][i] -= shift(2, i);
                }
            }
            out
        })
        .collect();
    PlanarData {
        trials,
        path: data.path.clone(),
        ..*data
    }
}

/// `[y, ẏ, ÿ]` of `T_c ẏ + y = Δτ` from y = 0 at the onset: the exact
/// response to Δτ interpolated linearly between samples (y = Δτ when
/// `tc` is 0).
fn lagged(tau: &[f64], tc: f64, dt: f64) -> [Vec<f64>; 3] {
    let dtau = central_first(tau, dt);
    if tc <= 0.0 {
        let ddtau = central_first(&dtau, dt);
        return [tau.to_vec(), dtau, ddtau];
    }
    let a = (-dt / tc).exp();
    let mut y = vec![0.0; tau.len()];
    let mut state = 0.0;
    for i in 0..tau.len() {
        let prev = tau[i.saturating_sub(1)];
        let slope = (tau[i] - prev) / dt;
        state = a * state + (1.0 - a) * prev + slope * (dt - tc * (1.0 - a));
        y[i] = state;
    }
    let yd: Vec<f64> = tau.iter().zip(&y).map(|(u, y)| (u - y) / tc).collect();
    let ydd = dtau.iter().zip(&yd).map(|(u, v)| (u - v) / tc).collect();
    [y, yd, ydd]
}

/// Residual sum of squares of eq. (13)'s least squares over the first
/// `window` samples of every trial.
fn rss(data: &PlanarData, window: usize, xi: Option<[f64; 3]>) -> f64 {
    let tris: Vec<DMatrix<f64>> = data
        .trials
        .iter()
        .map(|t| {
            let b = trial_rows(t, window, xi);
            let q = b.ncols();
            triangle(b, q)
        })
        .collect();
    let q = tris.first().map_or(1, |t| t.ncols());
    let r = merge(tris.iter(), q);
    r[(q - 1, q - 1)].powi(2)
}

/// C = L Lᵀ and T_c from the search's parameters.
fn unpack(p: &[f64]) -> (Matrix2<f64>, f64) {
    let l = Matrix2::new(p[0], 0.0, p[1], p[2]) * 0.1;
    (
        l * l.transpose(),
        (p[3] * 0.01).abs().min(MAX_TIME_CONSTANT_S),
    )
}

/// Residual ratio (rigid over with-compliance) from which the sweep reports
/// soft tissue in series: without a cuff the ratio stayed within 1.00-1.05
/// (with and without a reflex, joint and end-point data); with seed 003's
/// cuff it was 31-141 (`crates/ident/tests/it/planar.rs`).
pub const SERIES_COMPLIANCE_RATIO: f64 = 2.0;

/// The compliance in series that best explains the trials' first `window`
/// samples; None when the search fails or the rigid fit is not improved.
/// With noisy torques the compliance itself comes out small (its
/// accelerations carry the torque noise, errors in variables): it tells
/// whether tissue is in series, not how stiff it is.
pub fn fit_series_compliance(
    data: &PlanarData,
    window: usize,
    xi: Option<[f64; 3]>,
) -> Option<SeriesCompliance> {
    struct Problem<'a> {
        data: &'a PlanarData,
        window: usize,
        xi: Option<[f64; 3]>,
    }
    impl CostFunction for Problem<'_> {
        type Param = Vec<f64>;
        type Output = f64;
        fn cost(&self, p: &Vec<f64>) -> std::result::Result<f64, argmin::core::Error> {
            let (c, tc) = unpack(p);
            let r = rss(&behind_compliance(self.data, &c, tc), self.window, self.xi);
            Ok(if r.is_finite() { r } else { f64::MAX })
        }
    }
    // a simplex of `at` and one step along each parameter
    let around = |at: &[f64], step: f64| -> Vec<Vec<f64>> {
        (0..=at.len())
            .map(|k| {
                let mut v = at.to_vec();
                if k > 0 {
                    v[k - 1] += step;
                }
                v
            })
            .collect()
    };
    let rigid = rss(data, window, xi);
    let mut best = vec![0.5, 0.0, 0.5, 1.0];
    let mut simplex = around(&best, 0.3);
    for _ in 0..ROUNDS {
        let solver = NelderMead::new(simplex).with_sd_tolerance(1e-12).ok()?;
        let res = Executor::new(Problem { data, window, xi }, solver)
            .configure(|s| s.max_iters(MAX_ITERATIONS))
            .run()
            .ok()?;
        best = res.state().best_param.clone()?;
        // restart around the best point: Nelder-Mead stalls on narrow valleys
        simplex = around(&best, 0.05);
    }
    let (c, tc) = unpack(&best);
    let with = rss(&behind_compliance(data, &c, tc), window, xi);
    (with < rigid).then_some(SeriesCompliance {
        compliance: [[c[(0, 0)], c[(0, 1)]], [c[(1, 0)], c[(1, 1)]]],
        time_constant_s: tc,
        residual_ratio: rigid / with,
    })
}
