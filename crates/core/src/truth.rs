//! The truth of a virtual recording (`<recording>.truth.json`), typed: what
//! `limpid simulate`, limpid's test examples and the outside examples'
//! generator write beside each recording, and what tests and outside checkers
//! read back. One variant per method, tagged by `method`; the quantities an
//! estimate is compared with are typed fields (SI units, matrices row-major,
//! force on the limb), and everything else a generator says about how it made
//! the recording (protocol, noise, robot, EMG, ...) is kept in `other`.
//!
//! Committed as `schema/limpid-truth.v1.schema.json` (regenerated with
//! `LIMPID_UPDATE_SCHEMA=1 cargo test -p limpid-analysis --test it schema`).

use std::collections::BTreeMap;

use schemars::JsonSchema;
use serde::{Deserialize, Serialize};
use serde_json::Value;

use crate::Matrix;

/// Keys any truth may carry besides its method's own.
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize, JsonSchema)]
pub struct About {
    /// Example family (`cartesian_slow`, `planar`, ...).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub family: Option<String>,
    /// Case name (the recording's stem).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub case: Option<String>,
    /// Random seed the generator used.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub seed: Option<u64>,
    /// Sample rate of the recording (Hz).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub sample_rate: Option<f64>,
    /// Where the subject comes from (paper, table, subject).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub source: Option<String>,
    /// The quantities a test should check (e.g. `stiffness`, `levels[].stiffness`).
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub checked: Vec<String>,
    /// How the recording was made, for a reader.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub notes: Vec<String>,
}

/// A truth file: one variant per method, tagged by `method`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(tag = "method", rename_all = "snake_case")]
pub enum Truth {
    /// Centre-out end-point recording (Artemiadis et al. 2010): M, B, K (3 x 3).
    Cartesian(CartesianTruth),
    /// Co-contraction levels (Patel, O'Neill & Artemiadis): K per level.
    Cocontraction(CocontractionTruth),
    /// Planar two-link arm (Lakatos, Petit & van der Smagt 2011, eq. 9): joint K, D, xi.
    Planar(PlanarTruth),
    /// Spring array on an impedance-controlled rig (Park & Chang 2011, eq. 10).
    Stochastic(StochasticTruth),
    /// One joint with a stretch reflex (intrinsic I, B, K, 1 x 1).
    Reflex(ReflexTruth),
    /// Impedance that varies with time or a schedule.
    Varying(VaryingTruth),
    /// A limb following a periodic command (issue 59): M, B, K about the
    /// posture, with the elastic force's quadratic and cubic terms.
    Periodic(PeriodicTruth),
}

/// Centre-out end-point truth (seed 000).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, JsonSchema)]
pub struct CartesianTruth {
    /// Family, case, seed, rate, notes.
    #[serde(flatten)]
    pub about: About,
    /// M (kg), 3 x 3.
    pub inertia: Matrix,
    /// B (N s/m), 3 x 3.
    pub damping: Matrix,
    /// K (N/m), 3 x 3.
    pub stiffness: Matrix,
    /// Equilibrium (start point) x, y, z (m).
    pub equilibrium: Vec<f64>,
    /// Perturbation profile (`cubic`, `trapezoid`, `sinusoid`).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub profile: Option<String>,
    /// What else the generator recorded (protocol, noise, ...).
    #[serde(flatten)]
    pub other: BTreeMap<String, Value>,
}

/// One co-contraction level's truth.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, JsonSchema)]
pub struct LevelTruth {
    /// The level (0 = relaxed, 1 = the largest).
    pub level: f64,
    /// K at this level (N/m), 3 x 3.
    pub stiffness: Matrix,
    /// Co-contraction index of eq. (1), when the generator computed it from the data.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub cocontraction_index: Option<f64>,
    /// Activation of each muscle (0-1), when the generator knows it.
    #[serde(default)]
    pub muscle_activation: Option<Vec<f64>>,
}

/// Co-contraction truth (seed 001): K per level.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, JsonSchema)]
pub struct CocontractionTruth {
    /// Family, case, seed, rate, notes.
    #[serde(flatten)]
    pub about: About,
    /// M (kg), 3 x 3.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub inertia: Option<Matrix>,
    /// B (N s/m), 3 x 3.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub damping: Option<Matrix>,
    /// Equilibrium x, y, z (m).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub equilibrium: Option<Vec<f64>>,
    /// K per level, in the order of the protocol.
    pub levels: Vec<LevelTruth>,
    /// K at level 0 (N/m).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub stiffness_level0: Option<Matrix>,
    /// dK per unit level (N/m).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub stiffness_increment_per_unit_level: Option<Matrix>,
    /// What else the generator recorded (protocol, EMG, noise, ...).
    #[serde(flatten)]
    pub other: BTreeMap<String, Value>,
}

/// Where a planar recording's motion was measured.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize, JsonSchema)]
#[serde(rename_all = "snake_case")]
pub enum PlanarVariant {
    /// Joint angles and torques.
    Joint,
    /// Hand position and force.
    Endpoint,
}

/// Planar two-link arm truth (seed 003 eq. 9), in joint space.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, JsonSchema)]
pub struct PlanarTruth {
    /// Family, case, seed, rate, notes.
    #[serde(flatten)]
    pub about: About,
    /// Joint or end-point data.
    pub variant: PlanarVariant,
    /// The arm's inertial parameters xi1..xi3 (kg m^2).
    pub inertial_parameters: [f64; 3],
    /// Joint K (N m/rad), 2 x 2.
    pub stiffness: Matrix,
    /// Joint D (N m s/rad), 2 x 2.
    pub damping: Matrix,
    /// Upper arm and forearm lengths (m).
    pub link_lengths: [f64; 2],
    /// Joint angles of the equilibrium (rad, q2 relative).
    pub q0: [f64; 2],
    /// Equilibrium, when the generator states it apart from q0.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub equilibrium: Option<[f64; 2]>,
    /// Shoulder position (m), for end-point data.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub shoulder: Option<[f64; 2]>,
    /// Duration of the minimum-jerk motion T_k (ms).
    pub interpolation_interval_ms: f64,
    /// Observation window after the onset (ms).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub observation_window_ms: Option<f64>,
    /// What else the generator recorded (protocol, noise, reflex, ...).
    #[serde(flatten)]
    pub other: BTreeMap<String, Value>,
}

/// Spring-array truth (seed 004 eq. 10) in x (m), z (m), theta (rad).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, JsonSchema)]
pub struct StochasticTruth {
    /// Family, case, seed, rate, notes.
    #[serde(flatten)]
    pub about: About,
    /// Names and units of the coordinates.
    pub coordinates: Vec<String>,
    /// M (3 x 3).
    pub inertia: Matrix,
    /// B (3 x 3).
    pub damping: Matrix,
    /// K (3 x 3).
    pub stiffness: Matrix,
    /// Equilibrium.
    pub equilibrium: Vec<f64>,
    /// The springs k1a..k4b (N/m).
    #[serde(
        default,
        rename = "springs_N_per_m",
        skip_serializing_if = "Option::is_none"
    )]
    pub springs_n_per_m: Option<BTreeMap<String, f64>>,
    /// The band a test checks the impedance over (Hz).
    #[serde(default, rename = "band_Hz", skip_serializing_if = "Option::is_none")]
    pub band_hz: Option<[f64; 2]>,
    /// What else the generator recorded (robot, input, noise, ...).
    #[serde(flatten)]
    pub other: BTreeMap<String, Value>,
}

/// One joint with a stretch reflex: the intrinsic part (1 x 1 matrices).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, JsonSchema)]
pub struct ReflexTruth {
    /// Family, case, seed, rate, notes.
    #[serde(flatten)]
    pub about: About,
    /// I (kg m^2).
    pub inertia: Matrix,
    /// B (N m s/rad).
    pub damping: Matrix,
    /// K (N m/rad).
    pub stiffness: Matrix,
    /// What else the generator recorded (the reflex pathway, noise, ...).
    #[serde(flatten)]
    pub other: BTreeMap<String, Value>,
}

/// A limb following a periodic command: its linear impedance about the
/// posture and the nonlinear terms of its elastic force, per coordinate.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, JsonSchema)]
pub struct PeriodicTruth {
    /// Family, case, seed, rate, notes.
    #[serde(flatten)]
    pub about: About,
    /// The recording's position columns, in the matrices' order.
    pub coordinates: Vec<String>,
    /// M (kg, or kg m^2 at the posture for joints).
    pub inertia: Matrix,
    /// B (N s/m or N m s/rad).
    pub damping: Matrix,
    /// K (N/m or N m/rad), the slope at the posture.
    pub stiffness: Matrix,
    /// The posture the displacements are taken from (m or rad).
    pub equilibrium: Vec<f64>,
    /// k2 per coordinate (N/m^2 or N m/rad^2): the elastic force adds k2 d^2.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub quadratic: Option<Vec<f64>>,
    /// k3 per coordinate (N/m^3 or N m/rad^3): the elastic force adds k3 d^3.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub cubic: Option<Vec<f64>>,
    /// What else the generator recorded (the protocol, servo, noise, ...).
    #[serde(flatten)]
    pub other: BTreeMap<String, Value>,
}

/// One point of a varying truth.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, JsonSchema)]
pub struct VaryingTruthPoint {
    /// Time since the trial's start (s) or the schedule's value.
    pub sigma: f64,
    /// K (d x d).
    pub stiffness: Matrix,
    /// B (d x d).
    pub damping: Matrix,
    /// I (d x d).
    pub inertia: Matrix,
    /// Reflex gain (N m s/rad), when there is a reflex.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub reflex_gain: Option<f64>,
}

/// Truth of impedance that varies with time or a schedule.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, JsonSchema)]
pub struct VaryingTruth {
    /// Family, case, seed, rate, notes.
    #[serde(flatten)]
    pub about: About,
    /// `time since trial start` or the schedule column.
    pub schedule: String,
    /// Reflex delay (s), when there is a reflex.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub reflex_delay_s: Option<f64>,
    /// The truth on a grid of the schedule.
    pub points: Vec<VaryingTruthPoint>,
}

/// A generator's other keys (`protocol`, `noise`, ...) for a truth's `other`.
pub fn other_keys<const N: usize>(entries: [(&str, Value); N]) -> BTreeMap<String, Value> {
    entries
        .into_iter()
        .map(|(key, value)| (key.to_string(), value))
        .collect()
}

impl Truth {
    /// Parse a truth file's text; `name` (its path) leads the one-line error.
    pub fn from_json(name: &str, text: &str) -> crate::Result<Truth> {
        let de = &mut serde_json::Deserializer::from_str(text);
        serde_path_to_error::deserialize(de).map_err(|e| crate::Error::Format {
            path: name.into(),
            message: format!("not a limpid truth file at `{}`: {}", e.path(), e.inner()),
        })
    }

    /// The stiffness (co-contraction: its first level; varying: its first
    /// point); `None` for a co-contraction or varying truth without any.
    pub fn stiffness(&self) -> Option<&Matrix> {
        match self {
            Truth::Cartesian(t) => Some(&t.stiffness),
            Truth::Cocontraction(t) => t.levels.first().map(|l| &l.stiffness),
            Truth::Planar(t) => Some(&t.stiffness),
            Truth::Stochastic(t) => Some(&t.stiffness),
            Truth::Reflex(t) => Some(&t.stiffness),
            Truth::Varying(t) => t.points.first().map(|p| &p.stiffness),
            Truth::Periodic(t) => Some(&t.stiffness),
        }
    }

    /// Family, case, seed, rate and notes.
    pub fn about(&self) -> &About {
        match self {
            Truth::Cartesian(t) => &t.about,
            Truth::Cocontraction(t) => &t.about,
            Truth::Planar(t) => &t.about,
            Truth::Stochastic(t) => &t.about,
            Truth::Reflex(t) => &t.about,
            Truth::Varying(t) => &t.about,
            Truth::Periodic(t) => &t.about,
        }
    }

    /// The JSON schema of truth files.
    pub fn json_schema() -> Value {
        serde_json::to_value(schemars::schema_for!(Truth)).expect("a schema is JSON")
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_cartesian_truth_keeps_unknown_keys_and_round_trips() {
        let text = r#"{"method": "cartesian", "case": "c1", "seed": 7,
            "inertia": [[1,0],[0,1]], "damping": [[2,0],[0,2]], "stiffness": [[300,10],[10,200]],
            "equilibrium": [0.1, 0.2], "profile": "cubic", "protocol": {"trials": 16}}"#;
        let t = Truth::from_json("t.json", text).unwrap();
        let Truth::Cartesian(c) = &t else {
            panic!("{t:?}")
        };
        assert_eq!(c.stiffness[(0, 1)], 10.0);
        assert_eq!(c.about.seed, Some(7));
        assert_eq!(c.other["protocol"]["trials"], 16);
        let back = Truth::from_json("back", &serde_json::to_string(&t).unwrap()).unwrap();
        assert_eq!(back, t);
        // a co-contraction truth without levels has no stiffness, and says so
        let empty = Truth::from_json("e", r#"{"method": "cocontraction", "levels": []}"#).unwrap();
        assert!(empty.stiffness().is_none());
    }

    #[test]
    fn a_truth_without_its_method_or_with_a_ragged_matrix_is_refused_naming_the_key() {
        let e = Truth::from_json("a.truth.json", r#"{"stiffness": [[1]]}"#).unwrap_err();
        assert!(e.to_string().contains("a.truth.json"), "{e}");
        let e = Truth::from_json(
            "b.truth.json",
            r#"{"method": "reflex", "inertia": [[1]], "damping": [[1, 2], [3]], "stiffness": [[1]]}"#,
        )
        .unwrap_err()
        .to_string();
        assert!(
            e.contains("b.truth.json") && e.contains("rows differ"),
            "{e}"
        );
    }
}
