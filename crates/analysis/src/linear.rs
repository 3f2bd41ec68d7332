//! The complete result of `estimate linear`: the estimate of seed 000
//! eq. (3)-(8), its analysis (symmetric/antisymmetric split eq. (10)-(11),
//! Table II, ellipsoids eq. (13)-(17)), its quality and verdict, and the
//! optional joint-space view of seed 004's 3-DoF shoulder.

use schemars::JsonSchema;
use serde::{Deserialize, Serialize};

use crate::markers::MarkerConfiguration;
use crate::{
    antisymmetric, criteria, ellipsoid, symmetric, table_ii, Ellipsoid, Matrix, MatrixCriteria,
    TableII,
};
pub use limpid_core::criteria::{
    matrix_verdict, tolerance, MatrixKind, MatrixVerdict, VAF_FLOOR_PERCENT,
};
use limpid_core::{Error, Result, Warning, WarningCode};
use limpid_ident::linear::{units, FitQuality, Identifiable, LinearEstimate, StandardErrors};
use limpid_ident::Prepared;

/// One value per matrix kind.
#[derive(Debug, Clone, Serialize, Deserialize, JsonSchema)]
pub struct PerMatrix<T> {
    /// Of the inertia M.
    pub inertia: T,
    /// Of the damping B.
    pub damping: T,
    /// Of the stiffness K.
    pub stiffness: T,
}

impl<T> PerMatrix<Option<T>> {
    fn none() -> Self {
        PerMatrix {
            inertia: None,
            damping: None,
            stiffness: None,
        }
    }

    /// True when no matrix has a value.
    pub fn all_none(&self) -> bool {
        self.inertia.is_none() && self.damping.is_none() && self.stiffness.is_none()
    }
}

impl<T> PerMatrix<T> {
    fn from_fn(est: &LinearEstimate, f: impl Fn(&Matrix) -> T) -> Self {
        PerMatrix {
            inertia: f(&est.inertia),
            damping: f(&est.damping),
            stiffness: f(&est.stiffness),
        }
    }
}

/// Quality criteria of the whole estimate.
#[derive(Debug, Clone, Serialize, Deserialize, JsonSchema)]
pub struct Criteria {
    /// Condition number of the column-scaled regressor.
    pub condition_number: f64,
    /// Positive definiteness and symmetry per matrix.
    pub matrices: PerMatrix<MatrixCriteria>,
    /// Which matrices the data identify.
    pub identifiable: Identifiable,
    /// `[acceleration, velocity, displacement]` signal share per coordinate.
    pub regressor_reliability: Vec<[f64; 3]>,
    /// How the standard errors were obtained.
    pub standard_error_method: String,
    /// Samples used.
    pub samples: usize,
    /// Parameters fitted.
    pub parameters: usize,
    /// The verdict on each matrix ([`MatrixVerdict`]; thresholds in its docs).
    pub verdicts: PerMatrix<MatrixVerdict>,
}

/// Where the data came from and how it was prepared.
#[derive(Debug, Clone, Serialize, Deserialize, JsonSchema)]
pub struct Provenance {
    /// The recording's path.
    pub recording: String,
    /// Coordinate names, in the order of the matrices' rows and columns.
    pub coordinates: Vec<String>,
    /// Force column of each coordinate.
    pub force_columns: Vec<String>,
    /// Units of inertia, damping, stiffness entries.
    pub units: [String; 3],
    /// Sample rate (Hz).
    pub sample_rate_hz: f64,
    /// Windows (trials) used.
    pub windows: usize,
    /// One continuous window (no trials).
    pub continuous: bool,
    /// Low-pass cut-off (Hz).
    pub cutoff_hz: f64,
    /// Butterworth order per pass.
    pub filter_order: usize,
    /// Derivative method (`central`, `savgol`).
    pub derivative: String,
    /// Force offsets (`rest`, `fit`, `constant`).
    pub offsets: String,
    /// Samples dropped at each window edge.
    pub edge_trim_samples: usize,
}

/// Everything `estimate linear --json` prints.
#[derive(Debug, Clone, Serialize, Deserialize, JsonSchema)]
pub struct LinearResult {
    /// M (kg, or kg m^2 for angles), row = force component, column = coordinate.
    pub inertia: Matrix,
    /// B (N s/m, N m s/rad).
    pub damping: Matrix,
    /// K (N/m, N m/rad).
    pub stiffness: Matrix,
    /// Absolute equilibrium position; absent when not estimated (see `warnings`).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub equilibrium: Option<Vec<f64>>,
    /// Standard errors, same layout.
    pub standard_errors: StandardErrors,
    /// Symmetric parts (seed 000 eq. (10)).
    pub symmetric: PerMatrix<Matrix>,
    /// Antisymmetric parts (seed 000 eq. (11)).
    pub antisymmetric: PerMatrix<Matrix>,
    /// Ellipsoids of the symmetric parts (2 or 3 coordinates; the key is
    /// absent for 1 coordinate, where no ellipsoid exists).
    #[serde(
        default = "PerMatrix::<Option<Ellipsoid>>::none",
        skip_serializing_if = "PerMatrix::all_none"
    )]
    pub ellipsoids: PerMatrix<Option<Ellipsoid>>,
    /// Seed 000 Table II quantities.
    pub table_ii: PerMatrix<TableII>,
    /// Goodness of fit per force component.
    pub fit: FitQuality,
    /// Quality criteria and identifiability.
    pub criteria: Criteria,
    /// What the reader should know about this estimate.
    pub warnings: Vec<Warning>,
    /// Where the data came from and how they were prepared.
    pub provenance: Provenance,
    /// The arm's configuration from tracked markers, when the recording has them.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub arm_configuration: Option<MarkerConfiguration>,
    /// The estimate in the shoulder's joint space (seed 004), when asked for.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub shoulder: Option<ShoulderImpedance>,
}

/// Analyse a linear estimate.
pub fn linear_result(est: &LinearEstimate, data: &Prepared) -> LinearResult {
    let (mu, bu, ku) = units(&data.coordinates);
    let matrices = PerMatrix::from_fn(est, |m| criteria(m));
    let mut warnings = est.warnings.clone();
    for (name, c, identified) in [
        ("stiffness", &matrices.stiffness, est.identifiable.stiffness),
        ("damping", &matrices.damping, est.identifiable.damping),
    ] {
        if identified && !c.positive_definite {
            warnings.push(Warning::new(WarningCode::NotPositiveDefinite, format!(
                "the symmetric part of the {name} matrix is not positive definite (smallest eigenvalue {:.4}): not a passive {name}",
                c.min_eigenvalue
            )));
        }
    }
    LinearResult {
        inertia: est.inertia.clone(),
        damping: est.damping.clone(),
        stiffness: est.stiffness.clone(),
        equilibrium: est.equilibrium.clone(),
        standard_errors: est.standard_errors.clone(),
        symmetric: PerMatrix::from_fn(est, symmetric),
        antisymmetric: PerMatrix::from_fn(est, antisymmetric),
        ellipsoids: PerMatrix::from_fn(est, ellipsoid),
        table_ii: PerMatrix::from_fn(est, table_ii),
        fit: est.fit.clone(),
        criteria: Criteria {
            condition_number: est.condition_number,
            verdicts: PerMatrix {
                inertia: judge(est, &matrices.inertia, MatrixKind::Inertia),
                damping: judge(est, &matrices.damping, MatrixKind::Damping),
                stiffness: judge(est, &matrices.stiffness, MatrixKind::Stiffness),
            },
            matrices,
            identifiable: est.identifiable.clone(),
            regressor_reliability: est.regressor_reliability.clone(),
            standard_error_method: est.standard_error_method.clone(),
            samples: est.samples,
            parameters: est.parameters,
        },
        warnings,
        provenance: Provenance {
            recording: data.path.display().to_string(),
            coordinates: data.coordinates.clone(),
            force_columns: data.force_columns.clone(),
            units: [mu.into(), bu.into(), ku.into()],
            sample_rate_hz: data.fs,
            windows: data.windows.len(),
            continuous: data.continuous,
            cutoff_hz: data.cutoff_hz,
            filter_order: data.filter_order,
            derivative: format!("{:?}", data.derivative).to_lowercase(),
            offsets: if data.continuous {
                "constant".into()
            } else if data.demeaned {
                "fit".into()
            } else {
                "rest".into()
            },
            edge_trim_samples: data.trim,
        },
        arm_configuration: None,
        shoulder: None,
    }
}

/// The verdict on one matrix of a fit.
fn judge(est: &LinearEstimate, c: &MatrixCriteria, kind: MatrixKind) -> MatrixVerdict {
    let (value, se, identified) = match kind {
        MatrixKind::Inertia => (
            &est.inertia,
            &est.standard_errors.inertia,
            est.identifiable.inertia,
        ),
        MatrixKind::Damping => (
            &est.damping,
            &est.standard_errors.damping,
            est.identifiable.damping,
        ),
        MatrixKind::Stiffness => (
            &est.stiffness,
            &est.standard_errors.stiffness,
            est.identifiable.stiffness,
        ),
    };
    // in closed loop the force the subject adds is left in the residual of
    // a consistent fit: the VAF is reported, the standard errors judge (issue 79)
    let fit_ok = est.closed_loop.is_some() || est.fit.vaf.iter().all(|v| *v >= VAF_FLOOR_PERCENT);
    matrix_verdict(kind, value, se, fit_ok, identified, c.positive_definite)
}

impl Criteria {
    /// The verdict on one matrix.
    pub fn verdict_of(&self, kind: MatrixKind) -> MatrixVerdict {
        match kind {
            MatrixKind::Inertia => self.verdicts.inertia,
            MatrixKind::Damping => self.verdicts.damping,
            MatrixKind::Stiffness => self.verdicts.stiffness,
        }
    }
}

impl<T> PerMatrix<T> {
    /// The value of one kind.
    pub fn get(&self, kind: MatrixKind) -> &T {
        match kind {
            MatrixKind::Stiffness => &self.stiffness,
            MatrixKind::Damping => &self.damping,
            MatrixKind::Inertia => &self.inertia,
        }
    }
}

impl LinearResult {
    /// The matrix of one kind.
    pub fn matrix(&self, kind: MatrixKind) -> &Matrix {
        match kind {
            MatrixKind::Stiffness => &self.stiffness,
            MatrixKind::Damping => &self.damping,
            MatrixKind::Inertia => &self.inertia,
        }
    }

    /// The standard errors of one kind.
    pub fn standard_error(&self, kind: MatrixKind) -> &Matrix {
        match kind {
            MatrixKind::Stiffness => &self.standard_errors.stiffness,
            MatrixKind::Damping => &self.standard_errors.damping,
            MatrixKind::Inertia => &self.standard_errors.inertia,
        }
    }

    /// The verdict in words: per matrix, then the fit's VAF per coordinate.
    pub fn verdict(&self) -> String {
        let parts: Vec<String> = MatrixKind::ALL
            .iter()
            .map(|&kind| {
                let name = kind.name();
                let tol = 100.0 * tolerance(kind);
                match self.criteria.verdict_of(kind) {
                    MatrixVerdict::Trusted => format!(
                        "{name} trusted (identifiable, positive definite, 2 SE within {tol:.0} %)"
                    ),
                    MatrixVerdict::PoorFit => format!(
                        "{name} NOT trusted: the model explains less than {VAF_FLOOR_PERCENT:.0} % of a force component"
                    ),
                    MatrixVerdict::NotPassive => format!(
                        "{name} identified but not positive definite: not a passive impedance"
                    ),
                    MatrixVerdict::NotIdentifiable => {
                        format!("{name} NOT identifiable from this data: treat it as unknown")
                    }
                    MatrixVerdict::Imprecise => format!(
                        "{name} imprecise: 2 SE exceed {tol:.0} % of its norm"
                    ),
                }
            })
            .collect();
        let vafs: Vec<String> = self
            .fit
            .vaf
            .iter()
            .map(|v| format!("{} %", limpid_core::significant(*v, 4)))
            .collect();
        format!("{}; fit VAF {}", parts.join("; "), vafs.join(" / "))
    }
}

/// Seed 004's 3-DoF shoulder (flexion, abduction, internal rotation): the
/// hand estimate mapped to joint space, `J_h^T Z J_h`.
#[derive(Debug, Clone, Serialize, Deserialize, JsonSchema)]
pub struct ShoulderImpedance {
    /// Flexion, abduction, rotation (degrees).
    pub angles_deg: [f64; 3],
    /// J_h at the posture (m/rad).
    pub jacobian: Matrix,
    /// J_h^T K J_h (N m/rad).
    pub stiffness: Matrix,
    /// J_h^T B J_h (N m s/rad).
    pub damping: Matrix,
    /// What the mapping leaves out.
    pub note: String,
}

/// The shoulder's posture and segments for [`shoulder_impedance`] and
/// [`crate::shoulder::joint_space_recording`].
#[derive(Debug, Clone, Copy)]
pub struct ShoulderPosture {
    /// Upper-arm length (m).
    pub upper_arm_m: f64,
    /// Forearm length (m).
    pub forearm_m: f64,
    /// Elbow angle (degrees).
    pub elbow_deg: f64,
    /// Flexion, abduction, rotation (degrees).
    pub angles_deg: [f64; 3],
}

impl ShoulderPosture {
    /// The arm model and the posture's angles (rad); lengths must be in
    /// [0.01, 2] m (a human segment; shorter ones make J_h numerically
    /// singular) and every angle finite.
    pub fn shoulder(&self) -> Result<(limpid_core::arm::Shoulder, [f64; 3])> {
        for (name, v) in [
            ("upper arm length", self.upper_arm_m),
            ("forearm length", self.forearm_m),
        ] {
            if !((0.01..=2.0).contains(&v)) {
                return Err(Error::invalid(
                    "shoulder",
                    if v.abs() < 1e6 && (v == 0.0 || v.abs() >= 1e-3) {
                        format!("{name} must be in [0.01, 2] m, found {v}")
                    } else {
                        format!("{name} must be in [0.01, 2] m, found {v:e}")
                    },
                ));
            }
        }
        if !(self.elbow_deg.is_finite() && self.angles_deg.iter().all(|a| a.is_finite())) {
            return Err(Error::invalid(
                "shoulder",
                format!(
                    "angles must be finite degrees, found elbow {}, flexion, abduction, rotation {:?}",
                    self.elbow_deg, self.angles_deg
                ),
            ));
        }
        Ok((
            limpid_core::arm::Shoulder {
                upper_arm_m: self.upper_arm_m,
                forearm_m: self.forearm_m,
                elbow_rad: self.elbow_deg.to_radians(),
            },
            self.angles_deg.map(f64::to_radians),
        ))
    }
}

/// Map a 3-D end-point estimate to the shoulder's joint space (seed 004).
pub fn shoulder_impedance(est: &LinearResult, p: &ShoulderPosture) -> Result<ShoulderImpedance> {
    let (Some(k), Some(b)) = (est.stiffness.to_matrix3(), est.damping.to_matrix3()) else {
        return Err(Error::invalid("shoulder", "needs a 3-D estimate (x, y, z)"));
    };
    let (s, q) = p.shoulder()?;
    Ok(ShoulderImpedance {
        angles_deg: p.angles_deg,
        jacobian: s.jacobian(q).into(),
        stiffness: s.joint_impedance(&k, q).into(),
        damping: s.joint_impedance(&b, q).into(),
        note: "J_h^T Z J_h about the posture; the static-load term dJ^T/dq F is not included. With the elbow fixed the hand moves on a sphere about the shoulder, so J_h has rank 2: the hand's position cannot sense rotation about the shoulder-hand line, and these matrices are singular along it. Park & Chang (2011) takes the rotation from the hand's orientation instead: estimate stochastic --shoulder with theta, tauy and utheta columns"
            .into(),
    })
}
