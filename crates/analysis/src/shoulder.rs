//! Seed 004 §II-B: the shoulder's joint space before estimation.
//!
//! Seed 004 estimates the 3-DoF shoulder's impedance from commanded torque
//! perturbations τ_Δ, interaction torques τ and angular displacements θ (its
//! Figs. 2-3, eq. (1)-(2)). The robot perturbs and measures the hand in its
//! task coordinates [X, Z, θ_y]; the paper turns them into the shoulder's
//! before estimating:
//!
//! - flexion/extension and abduction/adduction: τ_Δ = J_h^T F_Δ (eq. (3)),
//!   τ = J_h^T F with the same Jacobian, and the two angles "by the kinematic
//!   relationship between the shoulder rotation and hand's position";
//! - internal/external rotation: the hand's θ_y, τ_y and its commanded torque
//!   "are assumed to be identical to those at the subject's shoulder".
//!
//! [`joint_space_recording`] does this sample by sample with the arm model of
//! [`limpid_core::arm::Shoulder`] (elbow fixed by the arm trough): J_h is the
//! 2 x 2 Jacobian of the hand's X and Z over flexion and abduction at each
//! sample's angles, the angles solve the hand's X and Z (the rotation held
//! at the posture's). Choices the seed leaves open, ours:
//!
//! - the posture given is the operating point: the recording's mean X and Z
//!   are taken as the hand's position there, so positions may be displacements
//!   or absolute (the stochastic method removes means either way);
//! - Y, if recorded, is left out, as the paper neglects Y motion.
//!
//! For small motions the result equals the hand estimate mapped afterwards
//! (Z_joint = J^T Z J, J = diag(J_h, 1)); estimating in joint space gives the
//! coherences and the parametric fit of the joint coordinates themselves.

use limpid_core::{Error, Recording, Result};

use crate::linear::ShoulderPosture;

/// Condition number of J_h above which X and Z no longer determine flexion
/// and abduction usefully (a millimetre of hand motion would be radians).
const SINGULAR_CONDITION: f64 = 1e4;

/// J = diag(J_h, 1) at the posture: the hand's (X, Z, θ_y) per (flexion,
/// abduction, internal rotation). A hand impedance Z in those coordinates is
/// J^T Z J in the shoulder's joint space for small motions.
pub fn task_jacobian(posture: &ShoulderPosture) -> Result<nalgebra::Matrix3<f64>> {
    let (shoulder, q0) = posture.shoulder()?;
    let jh = shoulder.jacobian_xz(q0);
    let mut j = nalgebra::Matrix3::identity();
    j.fixed_view_mut::<2, 2>(0, 0).copy_from(&jh);
    Ok(j)
}

/// A recording with `x`, `z`, `fx`, `fz`, `ux`, `uz` (and optionally `theta`,
/// `tauy`, `utheta`) turned into the shoulder's joint space: columns `t`,
/// `q1`/`tau1`/`u1` (flexion), `q2`/`tau2`/`u2` (abduction) and, with a
/// rotation axis, `q3`/`tau3`/`u3` (internal rotation = the hand's θ_y).
/// Angles in rad, torques in N m. The path stays the recording's, for errors.
pub fn joint_space_recording(rec: &Recording, posture: &ShoulderPosture) -> Result<Recording> {
    let (shoulder, q0) = posture.shoulder()?;
    let j0 = shoulder.jacobian_xz(q0);
    let singular = j0.singular_values();
    let condition = singular.max() / singular.min();
    // NaN (a zero singular value over zero) counts as singular too
    if condition.is_nan() || condition >= SINGULAR_CONDITION {
        return Err(Error::invalid(
            "shoulder",
            format!(
                "at flexion {} deg, abduction {} deg the hand's X and Z do not determine the two angles (condition number of J_h {condition:.3e}); choose a posture away from it",
                posture.angles_deg[0], posture.angles_deg[1]
            ),
        ));
    }
    let t = rec.require("t", "sample time")?;
    let col = |name: &str, why: &str| rec.require(name, why);
    let (x, z) = (col("x", "hand X")?, col("z", "hand Z")?);
    let (fx, fz) = (col("fx", "force X")?, col("fz", "force Z")?);
    let (ux, uz) = (
        col("ux", "commanded force X")?,
        col("uz", "commanded force Z")?,
    );
    let rotation = match (
        rec.column("theta"),
        rec.column("tauy"),
        rec.column("utheta"),
    ) {
        (Some(a), Some(b), Some(c)) => Some([a, b, c]),
        (None, _, _) => None,
        (Some(_), tauy, _) => {
            let missing = if tauy.is_none() { "tauy" } else { "utheta" };
            return Err(Error::MissingColumn {
                path: rec.path().to_path_buf(),
                column: missing.into(),
                why: "the rotation theta is recorded; the shoulder's internal rotation needs its torque and commanded torque too".into(),
                found: rec.names().join(","),
            });
        }
    };
    let n = t.len();
    let mean = |v: &[f64]| v.iter().sum::<f64>() / n as f64;
    let hand0 = shoulder.hand(q0);
    let (dx, dz) = (hand0[0] - mean(x), hand0[2] - mean(z));
    let mut cols: Vec<Vec<f64>> = (0..7).map(|_| Vec::with_capacity(n)).collect();
    let mut q = q0;
    for i in 0..n {
        q = shoulder
            .flexion_abduction_of(x[i] + dx, z[i] + dz, q)
            .ok_or_else(|| {
                Error::invalid(
                    "shoulder",
                    format!(
                        "{}: row {}, columns x,z: the hand at ({}, {}) m about the posture cannot be reached by flexion and abduction of the arm given",
                        rec.path().display(),
                        rec.row_of(i),
                        x[i],
                        z[i]
                    ),
                )
            })?;
        let jt = shoulder.jacobian_xz(q).transpose();
        let tau = jt * nalgebra::Vector2::new(fx[i], fz[i]);
        let u = jt * nalgebra::Vector2::new(ux[i], uz[i]);
        for (c, v) in cols
            .iter_mut()
            .zip([t[i], q[0], q[1], tau[0], tau[1], u[0], u[1]])
        {
            c.push(v);
        }
    }
    let mut names: Vec<String> = ["t", "q1", "q2", "tau1", "tau2", "u1", "u2"]
        .map(String::from)
        .to_vec();
    if let Some([theta, tauy, utheta]) = rotation {
        names.extend(["q3", "tau3", "u3"].map(String::from));
        cols.push(theta.to_vec());
        cols.push(tauy.to_vec());
        cols.push(utheta.to_vec());
    }
    Recording::new(rec.path(), names, cols, rec.row_of(0))
}
