//! The result of `limpid demo` (the virtual experiment itself runs in
//! `limpid-app`): seed 000's 3-D study on a subject whose matrices are known
//! (seed 000 Table I, subject 1).
//!
//! Six start points, 16 centre-out perturbations each (3 cm, 3 s; 6 s for the
//! sinusoid), a position-controlled robot, an F/T sensor with per-trial
//! offset, drift and noise (`limpid_lab`). The default subject is realistic
//! ([`DemoSubject::Realistic`]: Table II's antisymmetric stiffness,
//! signal-dependent force noise, posture drift); `Ideal` is the clean one.
//! Every start point is estimated
//! with the linear estimator (seed 000 eq. (3)-(8)) and compared with the
//! subject's true matrices by the relative Frobenius error.

use limpid_core::Matrix;
use schemars::JsonSchema;
use serde::{Deserialize, Serialize};

use crate::linear::{LinearResult, MatrixKind};

/// One start point: truth, estimate, errors.
#[derive(Debug, Clone, Serialize, Deserialize, JsonSchema)]
pub struct DemoPoint {
    /// Start point name (S1..S6).
    pub start_point: String,
    /// Start point (m).
    pub position: [f64; 3],
    /// The subject's K at this start point (N/m).
    pub true_stiffness: Matrix,
    /// The subject's B (N s/m).
    pub true_damping: Matrix,
    /// The subject's M (kg).
    pub true_inertia: Matrix,
    /// Relative Frobenius errors, percent.
    pub stiffness_error_percent: f64,
    /// Damping error (%).
    pub damping_error_percent: f64,
    /// Inertia error (%).
    pub inertia_error_percent: f64,
    /// The full linear result.
    pub estimate: LinearResult,
}

impl DemoPoint {
    /// The true matrix of one kind.
    pub fn truth(&self, kind: MatrixKind) -> &Matrix {
        match kind {
            MatrixKind::Stiffness => &self.true_stiffness,
            MatrixKind::Damping => &self.true_damping,
            MatrixKind::Inertia => &self.true_inertia,
        }
    }

    /// The relative error of one kind (percent).
    pub fn error_percent(&self, kind: MatrixKind) -> f64 {
        match kind {
            MatrixKind::Stiffness => self.stiffness_error_percent,
            MatrixKind::Damping => self.damping_error_percent,
            MatrixKind::Inertia => self.inertia_error_percent,
        }
    }
}

/// Which virtual subject the demo perturbs.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Serialize, Deserialize, JsonSchema)]
#[serde(rename_all = "lowercase")]
pub enum DemoSubject {
    /// Seed 000 Table I plus Table II's antisymmetric stiffness, with
    /// the lab's realistic noise model (signal-dependent force noise, posture drift).
    #[default]
    Realistic,
    /// Table I exactly, sensor noise only (the lab's default noise model); documents
    /// written before the subject was recorded are of this subject.
    Ideal,
}

/// The whole virtual study.
#[derive(Debug, Clone, Serialize, Deserialize, JsonSchema)]
pub struct DemoResult {
    /// The virtual subject (absent in older documents: ideal).
    #[serde(default = "ideal")]
    pub subject: DemoSubject,
    /// Perturbation profile of the centre-out phase.
    pub profile: String,
    /// Target directions per start point.
    pub directions: usize,
    /// Perturbation amplitude (m).
    pub radius_m: f64,
    /// Duration of one motion (s).
    pub motion_s: f64,
    /// Sample rate (Hz).
    pub sample_rate_hz: f64,
    /// Random seed of the sensor noise.
    pub seed: u64,
    /// One entry per start point.
    pub points: Vec<DemoPoint>,
    /// The protocol `limpid protocol design` chooses for the first start
    /// point on the same subject, limits and time, run with the same noise
    /// seed (realistic subject; absent with `--no-design`).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub designed: Option<DemoDesigned>,
}

/// The designed protocol beside the seed's at one start point.
#[derive(Debug, Clone, Serialize, Deserialize, JsonSchema)]
pub struct DemoDesigned {
    /// What was chosen.
    pub chosen: crate::result::design::CentreOutChoice,
    /// The seed protocol's length at one start point, the design's budget (s).
    pub budget_s: f64,
    /// Predicted RMS element s.d. of K, B, M relative to the RMS element (percent).
    pub predicted_se_percent: [f64; 3],
    /// The designed protocol simulated and estimated at the start point.
    pub point: DemoPoint,
}

impl DemoResult {
    /// The largest error of one kind over the start points whose data
    /// identify that matrix (percent); `None` when no point does. An
    /// unidentifiable matrix's error measures the data, not limpid.
    pub fn worst_error_percent(&self, kind: MatrixKind) -> Option<f64> {
        self.points
            .iter()
            .filter(|p| {
                p.estimate.criteria.verdicts.get(kind)
                    != &crate::linear::MatrixVerdict::NotIdentifiable
            })
            .map(|p| p.error_percent(kind))
            .reduce(f64::max)
    }
}

/// Relative Frobenius error, percent.
pub fn relative_error_percent(estimate: &Matrix, truth: &Matrix) -> f64 {
    100.0 * (&estimate.0 - &truth.0).norm() / truth.norm()
}

fn ideal() -> DemoSubject {
    DemoSubject::Ideal
}
