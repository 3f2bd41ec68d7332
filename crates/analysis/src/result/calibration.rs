//! The result of `limpid calibrate` (the study itself runs in `limpid-app`):
//! do the standard errors and the verdicts mean what they
//! say? (issue 15). A Monte Carlo study over virtual subjects of every method
//! with the sensor models of `limpid_lab`: centre-out cubic, trapezoid and
//! sinusoid perturbations (seed 000), co-contraction sessions (seed 001),
//! planar-arm perturbations and their observation-window sweep (seed 003),
//! and the stochastic spring-array experiment (seed 004).
//!
//! For each method and matrix it reports the share of elements whose truth
//! lies within ±2 reported standard errors (target 90-98 %), the share of
//! "trusted" matrices further from the truth than the documented tolerance
//! (K 10 %, B 25 %, relative Frobenius norm; target at most 5 %), and the
//! share of matrices within the tolerance that were nevertheless not trusted.
//!
//! Subjects are drawn from realistic ranges: end-point stiffness eigenvalues
//! 100-1000 N/m, damping 5-50 N s/m, inertia 0.2-2 kg (seed 000 Table I,
//! seed 001 Tables 1-4), each with a random orientation and an antisymmetric
//! part of 1-3 %; joint stiffness 5-50 N m/rad and damping 0.5-3 N m s/rad
//! around seed 003's subject, a third of them with a stretch reflex (latency
//! 40-80 ms, K and D +30-60 %); spring arrays of 20-70 N/m springs (seed 004).
//! Half the centre-out recordings use an ideal position servo (velocity steps
//! at the onset, as in the outside examples), half a 30 Hz servo.

use schemars::JsonSchema;
use serde::{Deserialize, Serialize};

/// One matrix kind of one method over the whole study.
#[derive(Debug, Clone, Serialize, Deserialize, JsonSchema)]
pub struct MatrixCalibration {
    /// `stiffness` or `damping`.
    pub matrix: String,
    /// Elements compared with the truth.
    pub elements: usize,
    /// Share of elements whose truth lies within ±2 reported SE (%).
    pub coverage_percent: f64,
    /// The same against the SE without the method's fixed model-error floor
    /// (`floor_percent` of each value, added in quadrature): what the
    /// estimator's own error model achieves; none when the method has no floor.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub coverage_without_floor_percent: Option<f64>,
    /// The floor, as a share of each value (%); none when there is none.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub floor_percent: Option<f64>,
    /// Largest |estimate - truth| / SE over the elements.
    pub worst_abs_z: f64,
    /// Median relative Frobenius error of the matrix (%).
    pub median_error_percent: f64,
    /// The tolerance a trusted matrix promises (%).
    pub tolerance_percent: f64,
    /// Matrices judged (one per recording; one per level for co-contraction).
    pub judged: usize,
    /// Matrices called trusted.
    pub trusted: usize,
    /// Of those, the share further from the truth than the tolerance (%); none when none was trusted.
    pub trusted_beyond_tolerance_percent: Option<f64>,
    /// Matrices within the tolerance.
    pub within_tolerance: usize,
    /// Of those, the share not trusted (%); none when none was within.
    pub correct_but_untrusted_percent: Option<f64>,
}

/// One method over the whole study.
#[derive(Debug, Clone, Serialize, Deserialize, JsonSchema)]
pub struct MethodCalibration {
    /// Method and protocol.
    pub method: String,
    /// Virtual recordings simulated.
    pub recordings: usize,
    /// Recordings the estimator refused, with the first error.
    pub refused: usize,
    /// The first refusal's message.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub first_refusal: Option<String>,
    /// Stiffness, then damping.
    pub matrices: Vec<MatrixCalibration>,
    /// Wall-clock time of this method's simulations and estimates (s).
    pub seconds: f64,
}

/// The observation-window sweep's trust over planar subjects (seed 003).
#[derive(Debug, Clone, Default, Serialize, Deserialize, JsonSchema)]
pub struct SweepCalibration {
    /// Sweeps run (50-400 ms in 10 ms steps, or to the trials' end).
    pub sweeps: usize,
    /// Of those, subjects with a stretch reflex.
    pub with_reflex: usize,
    /// Windows called trusted.
    pub trusted_windows: usize,
    /// Of those, windows with K beyond 10 % or D beyond 25 % of the truth.
    pub trusted_but_wrong: usize,
    /// Windows within both tolerances.
    pub correct_windows: usize,
    /// Sweeps that trusted at least one window, without and with a reflex.
    pub sweeps_with_a_trusted_window: [usize; 2],
    /// Of the sweeps, those on end-point data (positions through inverse kinematics).
    #[serde(default)]
    pub endpoint_sweeps: usize,
    /// Of the sweeps, those through a cuff of soft tissue.
    #[serde(default)]
    pub cuff_sweeps: usize,
    /// Sweeps that claimed a change of the impedance within the trials (a
    /// reflex?), without and with a reflex: false alarms and detections.
    #[serde(default)]
    pub changes_claimed: [usize; 2],
    /// Of the cuffed sweeps, those with a reflex.
    #[serde(default)]
    pub cuff_with_reflex: usize,
    /// Of the changes claimed, those on cuffed sweeps (without and with a reflex).
    #[serde(default)]
    pub cuff_changes_claimed: [usize; 2],
    /// Of the changes claimed, those the sweep put down to soft tissue in
    /// series (a compliance explaining the trials), without and with a reflex.
    #[serde(default)]
    pub tissue_named: [usize; 2],
    /// Subjects whose simulation, preparation or sweep failed (not counted above).
    #[serde(default)]
    pub refused: usize,
    /// Wall-clock time (s).
    pub seconds: f64,
}

impl SweepCalibration {
    /// Sweeps without a reflex.
    pub fn without_reflex(&self) -> usize {
        self.sweeps.saturating_sub(self.with_reflex)
    }
}

/// The whole study.
#[derive(Debug, Clone, Serialize, Deserialize, JsonSchema)]
pub struct Calibration {
    /// Random seed.
    pub seed: u64,
    /// Recordings per method.
    pub recordings_per_method: usize,
    /// One entry per method.
    pub methods: Vec<MethodCalibration>,
    /// The window sweep on seed 003's session around its subject.
    pub window_sweep: SweepCalibration,
    /// The window sweep on subjects unlike it: end-point data, 20-60 trials,
    /// T_k 150-250 ms observed for T_k + 70 or 450 ms, cuffs, other sensor noise.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub window_sweep_varied: Option<SweepCalibration>,
    /// Reflex claims of the parameter-varying ankle.
    #[serde(default)]
    pub varying_reflex: ReflexClaims,
    /// `limpid protocol design` checked against what its design achieves.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub design: Option<DesignCalibration>,
    /// The same for `--method stochastic` (an end-point multisine).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub stochastic_design: Option<DesignCalibration>,
    /// The same for `--method planar` (seed 003's arm; K, D and ξ).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub planar_design: Option<DesignCalibration>,
}

/// A design (linear or stochastic for the demo's S1, planar for seed 003's
/// arm) on a prior range, predicted at the range's worse end and run on
/// subjects drawn uniformly from the range.
#[derive(Debug, Clone, Serialize, Deserialize, JsonSchema)]
pub struct DesignCalibration {
    /// The prior, in words.
    pub prior: String,
    /// Subjects drawn from the prior (and recordings behind the prediction).
    pub recordings: usize,
    /// Predicted pooled SE of K (N/m), B (N s/m), M (kg); planar: joint K
    /// (N m/rad), D (N m s/rad), ξ (kg m²).
    pub predicted_se: [f64; 3],
    /// Achieved pooled s.d. of the errors.
    pub achieved_se: [f64; 3],
    /// Predicted over achieved.
    pub ratio: [f64; 3],
    /// Share with K within 5 % and B (D) within 20 % of the truth, both identifiable.
    pub within_tolerance_share: f64,
    /// Wall time (s).
    pub seconds: f64,
}

/// How often the parameter-varying fit claims a reflex, with and without one.
#[derive(Debug, Clone, Default, Serialize, Deserialize, JsonSchema)]
pub struct ReflexClaims {
    /// Subjects without a reflex.
    pub without_reflex: usize,
    /// Of those, fits that claimed one.
    pub claimed_without: usize,
    /// Subjects with a reflex.
    pub with_reflex: usize,
    /// Of those, fits that detected it.
    pub detected: usize,
}

fn percent(v: Option<f64>) -> String {
    v.map_or_else(|| "-".into(), |p| format!("{p:.1} %"))
}

impl Calibration {
    /// The study as a table: header, then one row per method and matrix
    /// (the README's table is this, printed by `limpid calibrate`).
    pub fn table(&self) -> (Vec<String>, Vec<Vec<String>>) {
        let header = [
            "method",
            "matrix",
            "elements",
            "within ±2 SE",
            "without the SE floor",
            "largest abs z",
            "median error",
            "trusted",
            "trusted beyond tolerance",
            "correct but not trusted",
            "time",
        ]
        .map(String::from)
        .to_vec();
        let mut rows = Vec::new();
        for m in &self.methods {
            for c in &m.matrices {
                rows.push(vec![
                    if m.refused > 0 {
                        format!("{} ({} of {} refused)", m.method, m.refused, m.recordings)
                    } else {
                        m.method.clone()
                    },
                    format!("{} (tolerance {:.0} %)", c.matrix, c.tolerance_percent),
                    c.elements.to_string(),
                    format!("{:.1} %", c.coverage_percent),
                    match (c.coverage_without_floor_percent, c.floor_percent) {
                        (Some(cov), Some(floor)) => format!("{cov:.1} % (floor {floor} %)"),
                        _ => "no floor".into(),
                    },
                    format!("{:.1}", c.worst_abs_z),
                    format!("{:.2} %", c.median_error_percent),
                    format!("{} of {}", c.trusted, c.judged),
                    percent(c.trusted_beyond_tolerance_percent),
                    percent(c.correct_but_untrusted_percent),
                    format!("{:.1} s", m.seconds),
                ]);
            }
        }
        (header, rows)
    }
}
