//! Planar two-link arm in joint space (seed 003).
//!
//! Model, eq. (9): `M(q, ξ) q'' + (C(q, q', ξ) + D) q' + K Δq = Δτ_ext` with
//! `M = [[ξ1 + 2 ξ2 cos q2, ξ3 + ξ2 cos q2], [ξ3 + ξ2 cos q2, ξ3]]`, q1 the
//! shoulder and q2 the relative elbow angle. The regressor rows are eq. (13)
//! (11 parameters: ξ1..ξ3, D11, D12, D21, D22, K11, K12, K21, K22); with known ξ
//! the reduced model eq. (23)-(25) has 8.
//!
//! Data: joint-space recordings (`q1,q2,tau1,tau2`) or end-point recordings
//! (`x,y,fx,fy`), converted by analytical inverse kinematics (elbow branch
//! q2 > 0, i.e. the elbow flexed, unless told otherwise) and `τ = J(q)^T F`
//! (§IV-C). Per trial, `q0` and `τ0` are the means over the pre-onset rest;
//! angles and torques get the same zero-phase low-pass (each window end
//! extended by the reflection that keeps it consistent), derivatives by
//! central differences. The observation window of a trial runs from the
//! perturbation onset for `T_obs` (seed 003 Fig. 3).
//!
//! Criteria (§III-C): condition number of W (eq. (19), reported both for W
//! as is and with unit-RMS columns), positive definiteness of the symmetric
//! parts of K and D (eq. (20)), and the symmetry ratio ||X_a|| / ||X_s|| of K
//! and D (eq. (22)). Verdict "trusted" when the scaled condition number is
//! below 1000, K_s and D_s are positive definite and both ratios are below 0.1
//! ("quasi-symmetric", our threshold).

pub use limpid_core::arm::{coriolis, mass_matrix, Arm};

mod compliance;
mod fit;
mod noise;
mod prepare;
mod sweep;

pub use compliance::{fit_series_compliance, SeriesCompliance, SERIES_COMPLIANCE_RATIO};
pub use fit::{
    check_inertial_parameters, criteria, estimate_planar, fit_planar, leave_one_out_vaf,
    PlanarCriteria, PlanarErrors, PlanarEstimate, PlanarFit, MAX_INERTIAL_PARAMETER, MAX_LINK_M,
    MIN_LINK_M, MIN_WINDOW_SAMPLES,
};
pub use noise::AngleNoise;
pub use prepare::{prepare_planar, PlanarData, MAX_ONSET_LEAD_S, ONSET_LEAD_S};
pub(crate) use sweep::jackknife_sd;
pub use sweep::{
    impedance_change, interpolation_interval_s, interval_sweep, window_sweep, ImpedanceChange,
    IntervalRow, Sweep, SweepRow, CHANGE_P, MAX_SWEEP_WINDOWS, MIN_TRIALS_FOR_CHANGE_TEST,
    MIN_TRIALS_PER_INTERVAL, NEIGHBOURHOOD_MS, OBSERVATION_AFTER_INTERPOLATION_MS, QUASI_CONSTANT,
    SWEEP_TOLERANCE_D, SWEEP_TOLERANCE_K, SYSTEMATIC_TORQUE_ERROR,
};

/// Regressor rows X (2 x 11) of eq. (13) at one sample.
pub fn regressor(q2: f64, qd: [f64; 2], qdd: [f64; 2], dq: [f64; 2]) -> [[f64; 11]; 2] {
    let (s, c) = q2.sin_cos();
    let mut x = [[0.0; 11]; 2];
    x[0][0] = qdd[0];
    x[0][1] = (2.0 * qdd[0] + qdd[1]) * c - (2.0 * qd[0] * qd[1] + qd[1] * qd[1]) * s;
    x[0][2] = qdd[1];
    x[1][1] = qdd[0] * c + qd[0] * qd[0] * s;
    x[1][2] = qdd[0] + qdd[1];
    x[0][3] = qd[0];
    x[0][4] = qd[1];
    x[1][5] = qd[0];
    x[1][6] = qd[1];
    x[0][7] = dq[0];
    x[0][8] = dq[1];
    x[1][9] = dq[0];
    x[1][10] = dq[1];
    x
}

/// One prepared trial: samples from the perturbation onset to the end of the window.
#[derive(Debug, Clone)]
pub struct PlanarTrial {
    /// Trial id (the recording's `trial` column).
    pub id: i64,
    /// Joint angles q1, q2 (rad).
    pub q: [Vec<f64>; 2],
    /// Joint velocities (rad/s).
    pub qd: [Vec<f64>; 2],
    /// Joint accelerations (rad/s^2).
    pub qdd: [Vec<f64>; 2],
    /// Δq = q - q0.
    pub dq: [Vec<f64>; 2],
    /// Δτ = τ - τ0.
    pub dtau: [Vec<f64>; 2],
    /// Posture before the onset: mean over the rest (rad).
    pub q0: [f64; 2],
    /// Joint torques before the onset: mean over the rest (N m).
    pub tau0: [f64; 2],
}

/// Preparation settings of planar data.
///
/// | Name | Default | Purpose | Range |
/// |---|---|---|---|
/// | `arm` | required | link lengths, shoulder | l1, l2 > 0 |
/// | `cutoff_hz` | 30 Hz (at most 0.4 fs) | zero-phase low-pass of angles and torques | (0, fs/2) |
/// | `order` | 4 | Butterworth order | 1..=20 |
/// | `elbow_positive` | true | inverse-kinematics branch for end-point data | |
#[derive(Debug, Clone)]
pub struct PlanarPrepare {
    /// Link lengths and shoulder position.
    pub arm: Arm,
    /// Low-pass cut-off (Hz); `None`: 30 Hz, at most 0.4 fs.
    pub cutoff_hz: Option<f64>,
    /// Butterworth order.
    pub order: usize,
    /// Elbow branch of the inverse kinematics: q2 > 0 (flexed).
    pub elbow_positive: bool,
}

pub use limpid_core::criteria::{MAX_CONDITION, QUASI_SYMMETRIC};

#[cfg(test)]
mod tests {
    use super::*;
    use limpid_core::Matrix;
    use nalgebra::{Matrix2, Vector2};

    fn crit(k: [[f64; 2]; 2], d: [[f64; 2]; 2], cond: f64, scaled: f64) -> PlanarCriteria {
        let zero = Matrix::zeros(2, 2);
        criteria(&k.into(), &d.into(), (&zero, &zero), true, cond, scaled)
    }

    #[test]
    fn regressor_matches_inverse_dynamics() {
        // Ψ = M q'' + (C + D) q' + K Δq must equal X ζ, and C must follow from M
        let xi = [0.35, 0.14, 0.15];
        let d = [[1.8, 0.6], [0.5, 1.4]];
        let k = [[38.0, 9.0], [9.5, 10.0]];
        let zeta = [
            xi[0], xi[1], xi[2], d[0][0], d[0][1], d[1][0], d[1][1], k[0][0], k[0][1], k[1][0],
            k[1][1],
        ];
        let (q2, qd, qdd, dq) = (0.9, [0.7, -1.1], [3.0, -2.0], [0.02, -0.01]);
        let x = regressor(q2, qd, qdd, dq);
        let psi = mass_matrix(q2, xi) * Vector2::new(qdd[0], qdd[1])
            + coriolis(q2, qd, xi)
            + Matrix2::new(d[0][0], d[0][1], d[1][0], d[1][1]) * Vector2::new(qd[0], qd[1])
            + Matrix2::new(k[0][0], k[0][1], k[1][0], k[1][1]) * Vector2::new(dq[0], dq[1]);
        for r in 0..2 {
            let xz: f64 = (0..11).map(|j| x[r][j] * zeta[j]).sum();
            assert!((xz - psi[r]).abs() < 1e-12, "row {r}: {xz} vs {}", psi[r]);
        }
        // Coriolis from the Christoffel symbols of M by finite differences: c_i = Σ_jk (∂M_ij/∂q_k - ½ ∂M_jk/∂q_i) q'_j q'_k
        let h = 1e-6;
        let dm = (mass_matrix(q2 + h, xi) - mass_matrix(q2 - h, xi)) / (2.0 * h); // only q2 matters
        let mut c = [0.0; 2];
        for i in 0..2 {
            for j in 0..2 {
                for kk in 0..2 {
                    let dmij_dqk = if kk == 1 { dm[(i, j)] } else { 0.0 };
                    let dmjk_dqi = if i == 1 { dm[(j, kk)] } else { 0.0 };
                    c[i] += (dmij_dqk - 0.5 * dmjk_dqi) * qd[j] * qd[kk];
                }
            }
        }
        let cor = coriolis(q2, qd, xi);
        assert!(
            (c[0] - cor[0]).abs() < 1e-6 && (c[1] - cor[1]).abs() < 1e-6,
            "{c:?} vs {cor}"
        );
    }

    #[test]
    fn a_nan_anywhere_is_never_trusted() {
        let good_k = [[30.0, 8.0], [8.0, 12.0]];
        let good_d = [[2.0, 0.4], [0.4, 1.5]];
        for c in [
            crit([[f64::NAN, 8.0], [8.0, 12.0]], good_d, 50.0, 20.0),
            crit(good_k, [[2.0, f64::NAN], [0.4, 1.5]], 50.0, 20.0),
            crit(good_k, good_d, 50.0, f64::NAN),
        ] {
            assert!(!c.trusted, "{:?}", c.reasons);
        }
    }

    #[test]
    fn criteria_flags_hand_made_matrices() {
        let good = crit(
            [[30.0, 8.0], [8.0, 12.0]],
            [[2.0, 0.4], [0.4, 1.5]],
            50.0,
            20.0,
        );
        assert!(good.trusted, "{:?}", good.reasons);
        let indefinite = crit(
            [[30.0, 25.0], [25.0, 12.0]],
            [[2.0, 0.4], [0.4, 1.5]],
            50.0,
            20.0,
        );
        assert!(!indefinite.stiffness_positive_definite && !indefinite.trusted);
        let skew = crit(
            [[30.0, 8.0], [2.0, 12.0]],
            [[2.0, 0.4], [0.4, 1.5]],
            50.0,
            20.0,
        );
        assert!(skew.stiffness_symmetry_ratio > QUASI_SYMMETRIC && !skew.trusted);
        let ill = crit(
            [[30.0, 8.0], [8.0, 12.0]],
            [[2.0, 0.4], [0.4, 1.5]],
            1e6,
            5e3,
        );
        assert!(!ill.trusted && ill.reasons[0].contains("ill-conditioned"));
    }
}
