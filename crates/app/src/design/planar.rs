//! Experiment design for the planar method (seed 003 §IV-B, eq. (9), (13),
//! (16)): choose the quintic joint-space perturbations of a planar 2-link
//! arm (amplitude, interpolation interval T_k, recorded hold and rest) that
//! minimise the predicted variance of the joint stiffness K, damping D and
//! inertial parameters ξ, within the protocol's joint limits and a time
//! budget, at one posture.
//!
//! **Prediction.** As the linear design's ([`super`]): the spread of `limpid
//! estimate planar`'s own estimates (the whole recorded window of every
//! trial, the 11-parameter model) over recordings of the candidate
//! simulated on the prior arm with its noise: white torque and angle noise,
//! a slow torque fluctuation (a subject holding a load, seed 003 §IV) and,
//! when the prior has one, a stretch reflex that raises K and D after its
//! latency (seed 003 §I-B). The errors are taken against the arm's
//! intrinsic K and D, before the reflex: what seed 003's short observation
//! windows are for. A window that reaches past the latency therefore pays
//! the reflex's bias, and the design weighs it against the precision a
//! longer window gives.
//!
//! **Search.** Six directions as seed 003's, (±a, 0), (0, ±a), ±(a, −a);
//! the amplitude a as a share of the largest the displacement and torque
//! limits allow, T_k a multiple of the shortest the velocity and
//! acceleration limits allow for it, the recorded hold after the motion
//! (the observation window is T_k and the hold) and the recorded rest
//! before the onset (the posture and baseline torque are its means). The
//! random wait before each perturbation is the limits protocol's (it keeps
//! the subject from anticipating the onset; not a precision question), and
//! the perturbations fill the budget. Coordinate descent on
//! [`RANKING_RUNS`] common-seed recordings, worst case over the prior's
//! range.

use std::path::Path;

use nalgebra::{DMatrix, Matrix2, Vector2};
use serde::{Deserialize, Serialize};

use limpid_analysis::result::design::{
    JointCommandSpectrum, JointCommandTrace, LimitMargin, PlanarChoice, PlanarDesignResult,
    SearchSummary,
};
use limpid_core::criteria::MatrixVerdict;
use limpid_core::{Error, Matrix, Result};
use limpid_ident::planar::{fit_planar, prepare_planar, PlanarPrepare};
use limpid_lab::design::{Design, PlanarDesign, PlanarLimits};
use limpid_lab::planar::{
    add_torque_fluctuation, simulate_planar, PlanarProtocol, PlanarSubject, Reflex,
};
use limpid_lab::Profile;

use super::{
    check_budget, check_runs, coordinate_descent, limit_envelope, predict, rank, seeds,
    sine_amplitudes, spectrum_hz, verify, DesignInputs, DesignRequest, Grid, Run, Text, Truth,
    LIMIT_MARGIN, MIN_TRIALS, RANKING_RUNS,
};

/// Amplitude as a share of the largest the limits allow.
const AMPLITUDE_SHARES: [f64; 7] = [0.05, 0.1, 0.2, 0.35, 0.5, 0.7, 1.0];
/// T_k as a multiple of the shortest the limits allow.
const SLOWNESS: [f64; 4] = [1.0, 1.4, 2.0, 3.0];
/// Recorded hold after the motion (s).
const HOLDS_S: [f64; 7] = [0.0, 0.01, 0.02, 0.04, 0.08, 0.15, 0.3];
/// Recorded rest before the onset (s).
const RESTS_S: [f64; 3] = [0.1, 0.2, 0.3];
/// Seed 003's six directions, per unit amplitude.
const DIRECTIONS: [[f64; 2]; 6] = [
    [1.0, 0.0],
    [-1.0, 0.0],
    [0.0, 1.0],
    [0.0, -1.0],
    [1.0, -1.0],
    [-1.0, 1.0],
];
/// Largest magnitude of a joint stiffness element a prior may give (N m/rad).
const MOST_JOINT_STIFFNESS: f64 = 1e5;
/// Of a joint damping element (N m s/rad).
const MOST_JOINT_DAMPING: f64 = 1e4;
/// Least eigenvalue of the symmetric part of a prior's joint stiffness
/// (N m/rad) and damping (N m s/rad): an arm's floor.
const LEAST_JOINT: [f64; 2] = [0.1, 0.01];
/// Smallest amplitude worth designing (rad): below it the angle noise is the signal.
const LEAST_AMPLITUDE_RAD: f64 = 1e-4;
/// Slowest torque fluctuation a prior may give (Hz): within a trial of a
/// second, anything slower is a constant the rest's mean removes.
const LEAST_FLUCTUATION_HZ: f64 = 0.01;
/// Largest baseline joint torque a prior may give (N m): a human arm's are tens.
const MOST_BASELINE_TORQUE_NM: f64 = 1e3;
/// Most perturbations a planar design holds.
const MOST_TRIALS: usize = 2000;

/// ξ, K and D of a planar arm (joint space, SI).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ArmImpedance {
    /// Base inertial parameters ξ1..ξ3 (kg m²).
    pub xi: [f64; 3],
    /// Joint stiffness K (N m/rad).
    pub stiffness: Matrix2<f64>,
    /// Joint damping D (N m s/rad).
    pub damping: Matrix2<f64>,
}

impl Truth for ArmImpedance {
    fn groups(&self) -> [DMatrix<f64>; 3] {
        [
            DMatrix::from_column_slice(2, 2, self.stiffness.as_slice()),
            DMatrix::from_column_slice(2, 2, self.damping.as_slice()),
            DMatrix::from_row_slice(1, 3, &self.xi),
        ]
    }

    fn blend(&self, other: &Self, t: f64) -> Self {
        ArmImpedance {
            xi: std::array::from_fn(|i| self.xi[i] + (other.xi[i] - self.xi[i]) * t),
            stiffness: self.stiffness + (other.stiffness - self.stiffness) * t,
            damping: self.damping + (other.damping - self.damping) * t,
        }
    }
}

/// The noise of a planar recording: the rig's sensors and the subject's fluctuation.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct PlanarNoise {
    /// White torque noise per joint (N m).
    #[serde(default = "white_torque")]
    pub torque_white_nm: f64,
    /// White angle noise per joint (rad).
    #[serde(default = "white_angle")]
    pub angle_white_rad: f64,
    /// RMS of the subject's slow torque fluctuation per joint (N m).
    #[serde(default)]
    pub torque_fluctuation_nm: f64,
    /// The fluctuation's band: below this frequency (Hz).
    #[serde(default = "fluctuation_band")]
    pub fluctuation_below_hz: f64,
}

fn white_torque() -> f64 {
    0.02
}
fn white_angle() -> f64 {
    1e-5
}
fn fluctuation_band() -> f64 {
    3.0
}

impl Default for PlanarNoise {
    /// `limpid simulate`'s planar noise: 0.02 N m and 1e-5 rad white, no fluctuation.
    fn default() -> Self {
        PlanarNoise {
            torque_white_nm: white_torque(),
            angle_white_rad: white_angle(),
            torque_fluctuation_nm: 0.0,
            fluctuation_below_hz: fluctuation_band(),
        }
    }
}

impl PlanarNoise {
    /// A subject holding 5 N at the hand (seed 003 §IV), as `limpid
    /// reproduce 003` simulates one: 0.15 N m white and 0.15 N m of slow
    /// fluctuation below 3 Hz per joint, 2e-5 rad angle noise.
    pub fn holding_a_load() -> Self {
        PlanarNoise {
            torque_white_nm: 0.15,
            angle_white_rad: 2e-5,
            torque_fluctuation_nm: 0.15,
            fluctuation_below_hz: 3.0,
        }
    }

    fn check(&self, rate_hz: f64) -> std::result::Result<(), String> {
        for (name, v) in [
            ("torque_white_nm", self.torque_white_nm),
            ("angle_white_rad", self.angle_white_rad),
            ("torque_fluctuation_nm", self.torque_fluctuation_nm),
        ] {
            if !(0.0..1e3).contains(&v) {
                return Err(format!("{name} = {v}: expected 0 <= value < 1000"));
            }
        }
        let f = self.fluctuation_below_hz;
        if !(f >= LEAST_FLUCTUATION_HZ && f < 0.5 * rate_hz) {
            return Err(format!(
                "fluctuation_below_hz = {f}: expected a frequency from {LEAST_FLUCTUATION_HZ} Hz (slower is an offset within a trial) to half the sample rate ({} Hz)",
                0.5 * rate_hz
            ));
        }
        Ok(())
    }
}

/// What is known of the arm before the experiment.
#[derive(Debug, Clone)]
pub struct PlanarPrior {
    /// Nominal ξ, K, D.
    pub nominal: ArmImpedance,
    /// The other end of its range, if any.
    pub other_end: Option<ArmImpedance>,
    /// The posture q0 (rad); None: the limits protocol's.
    pub posture_rad: Option<[f64; 2]>,
    /// Joint torques at q0 (N m).
    pub tau0: [f64; 2],
    /// A stretch reflex the arm has, if any.
    pub reflex: Option<Reflex>,
    /// The noise.
    pub noise: PlanarNoise,
    /// Limits given in the prior file (`[limits]`), if any.
    pub limits: Option<PlanarLimits>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct ArmFile {
    xi: [f64; 3],
    stiffness: [[f64; 2]; 2],
    damping: [[f64; 2]; 2],
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct PlanarPriorFile {
    xi: [f64; 3],
    stiffness: [[f64; 2]; 2],
    damping: [[f64; 2]; 2],
    #[serde(default)]
    posture_rad: Option<[f64; 2]>,
    #[serde(default)]
    tau0: [f64; 2],
    #[serde(default)]
    other_end: Option<ArmFile>,
    #[serde(default)]
    reflex: Option<Reflex>,
    #[serde(default)]
    noise: Option<PlanarNoise>,
    #[serde(default)]
    limits: Option<PlanarLimits>,
}

fn arm_impedance(f: &ArmFile, path: &Path, table: &str) -> Result<ArmImpedance> {
    let fail = |message: String| Error::Format {
        path: path.to_path_buf(),
        message,
    };
    limpid_ident::planar::check_inertial_parameters(&f.xi)
        .map_err(|e| fail(format!("{table}xi: {e}")))?;
    for ((name, m, most), least) in [
        ("stiffness", &f.stiffness, MOST_JOINT_STIFFNESS),
        ("damping", &f.damping, MOST_JOINT_DAMPING),
    ]
    .into_iter()
    .zip(LEAST_JOINT)
    {
        if let Some((r, c)) = (0..4)
            .map(|k| (k / 2, k % 2))
            .find(|&(r, c)| m[r][c].abs().is_nan() || m[r][c].abs() > most)
        {
            return Err(fail(format!(
                "{table}{name}[{r}][{c}] = {}: an arm's joint {name} is below {most:e} in magnitude",
                limpid_core::error::Num(m[r][c])
            )));
        }
        if let Some(i) = (0..2).find(|&i| m[i][i] <= 0.0) {
            return Err(fail(format!(
                "{table}{name}[{i}][{i}] = {}: a prior's diagonal must be positive",
                limpid_core::error::Num(m[i][i])
            )));
        }
        let dynamic = nalgebra::DMatrix::from_fn(2, 2, |r, c| m[r][c]);
        super::check_least_eigenvalue(&dynamic, least, path, &format!("{table}{name}"))?;
    }
    let m2 = |a: &[[f64; 2]; 2]| Matrix2::new(a[0][0], a[0][1], a[1][0], a[1][1]);
    Ok(ArmImpedance {
        xi: f.xi,
        stiffness: m2(&f.stiffness),
        damping: m2(&f.damping),
    })
}

impl PlanarPrior {
    /// Read a prior arm file: `xi` (3, kg m²), 2 x 2 `stiffness` (N m/rad)
    /// and `damping` (N m s/rad), optional `posture_rad`, `tau0`,
    /// `[other_end]` (xi, stiffness, damping), `[reflex]` (latency_s,
    /// stiffness_gain, damping_gain), `[noise]` ([`PlanarNoise`]) and
    /// `[limits]` (a planar protocol's limits table).
    pub fn from_toml(text: &str, path: &Path) -> Result<PlanarPrior> {
        limpid_lab::validate::check_numbers(text, path)?;
        let f: PlanarPriorFile = limpid_lab::validate::parse_settings(text, path)?;
        let nominal = arm_impedance(
            &ArmFile {
                xi: f.xi,
                stiffness: f.stiffness,
                damping: f.damping,
            },
            path,
            "",
        )?;
        let other_end = f
            .other_end
            .as_ref()
            .map(|o| arm_impedance(o, path, "other_end."))
            .transpose()?;
        if let Some(r) = &f.reflex {
            let gain = |g: f64| g > -1.0 && g < 10.0;
            if !((0.0..1.0).contains(&r.latency_s)
                && gain(r.stiffness_gain)
                && gain(r.damping_gain))
            {
                return Err(Error::Format {
                    path: path.to_path_buf(),
                    message: format!(
                        "[reflex] latency_s = {}, stiffness_gain = {}, damping_gain = {}: expected a latency in [0, 1) s and gains in (-1, 10)",
                        r.latency_s, r.stiffness_gain, r.damping_gain
                    ),
                });
            }
        }
        if let Some(i) =
            (0..2).find(|&i| f.tau0[i].is_nan() || f.tau0[i].abs() > MOST_BASELINE_TORQUE_NM)
        {
            return Err(Error::Format {
                path: path.to_path_buf(),
                message: format!(
                    "tau0[{i}] = {}: an arm's baseline joint torque is below {MOST_BASELINE_TORQUE_NM:e} N m in magnitude",
                    limpid_core::error::Num(f.tau0[i])
                ),
            });
        }
        if let Some(q) = f
            .posture_rad
            .filter(|q| q.iter().any(|v| v.abs() > std::f64::consts::TAU))
        {
            return Err(Error::Format {
                path: path.to_path_buf(),
                message: format!(
                    "posture_rad = [{}, {}]: joint angles within ±2π rad",
                    limpid_core::error::Num(q[0]),
                    limpid_core::error::Num(q[1])
                ),
            });
        }
        Ok(PlanarPrior {
            nominal,
            other_end,
            posture_rad: f.posture_rad,
            tau0: f.tau0,
            reflex: f.reflex,
            noise: f.noise.unwrap_or_else(PlanarNoise::holding_a_load),
            limits: f.limits,
        })
    }

    /// `demo:planar`: the seed 003 arm (the outside examples' truth) with the
    /// spinal reflex and the 5 N load of `limpid reproduce 003` (latency 90
    /// ms, K and D up 30 % after it), held rigidly (no cuff).
    pub fn demo() -> PlanarPrior {
        let s = PlanarSubject::seed003();
        PlanarPrior {
            nominal: ArmImpedance {
                xi: s.xi,
                stiffness: s.stiffness,
                damping: s.damping,
            },
            other_end: None,
            posture_rad: Some(s.q0),
            tau0: s.tau0,
            reflex: Some(Reflex {
                latency_s: 0.09,
                stiffness_gain: 0.3,
                damping_gain: 0.3,
            }),
            noise: PlanarNoise::holding_a_load(),
            limits: None,
        }
    }

    fn ends(&self) -> Vec<ArmImpedance> {
        std::iter::once(self.nominal)
            .chain(self.other_end)
            .collect()
    }

    fn subject(&self, arm: &ArmImpedance, posture: [f64; 2]) -> PlanarSubject {
        PlanarSubject {
            xi: arm.xi,
            stiffness: arm.stiffness,
            damping: arm.damping,
            q0: posture,
            tau0: self.tau0,
            reflex: self.reflex,
            cuff: None,
        }
    }
}

/// What a planar design takes from its limits' protocol: the limits, the
/// arm's links, the posture and the waits.
#[derive(Debug, Clone)]
pub struct PlanarFrame {
    /// The joint limits.
    pub limits: PlanarLimits,
    /// Upper-arm and forearm lengths (m).
    pub link_lengths_m: [f64; 2],
    /// The posture (rad): the prior's, else the protocol's.
    pub posture_rad: [f64; 2],
    /// Random wait before each perturbation (s).
    pub wait_s: [f64; 2],
}

/// A planar design request.
pub type PlanarDesignRequest = DesignRequest<PlanarFrame, PlanarDesign, PlanarPrior>;

/// A planar design request from its texts, as the CLI and Python take
/// them: the prior (`demo:planar` or a prior arm file's text), the planar
/// protocol whose limits, links, posture, waits and sample rate are taken
/// (else the seed's, `lakatos-planar`, with the prior's `[limits]`), the
/// baseline protocol.
pub fn planar_request_from_texts(inputs: &DesignInputs<'_>) -> Result<PlanarDesignRequest> {
    let DesignInputs {
        prior,
        limits_from,
        baseline,
        ..
    } = *inputs;
    let (prior_text, prior_path) = prior;
    let prior = match prior_text {
        "demo:planar" => PlanarPrior::demo(),
        t if t.starts_with("demo:") => {
            return Err(Error::invalid(
                "prior",
                format!("{t}: the planar method's demo prior is demo:planar"),
            ))
        }
        t => PlanarPrior::from_toml(t, prior_path)?,
    };
    let planar = |(text, path): Text<'_>, role: &str| -> Result<PlanarDesign> {
        match Design::from_toml(text, path)? {
            Design::Planar(p) => Ok(p),
            _ => Err(Error::Format {
                path: path.to_path_buf(),
                message: format!(
                    "{role} must be a planar protocol (kind = \"planar\"; the design is for the planar method)"
                ),
            }),
        }
    };
    let limits_from = limits_from
        .map(|t| planar(t, "the limits' protocol"))
        .transpose()?;
    let baseline = baseline.map(|t| planar(t, "the baseline")).transpose()?;
    // the limits: the protocol's, else the prior's table, else the seed's
    let limits = match (&limits_from, &prior.limits) {
        (Some(p), _) => p.limits.clone(),
        (None, Some(l)) => l.clone(),
        (None, None) => PlanarDesign::seed003().limits,
    };
    let frame_of = limits_from.unwrap_or_else(PlanarDesign::seed003);
    // the arm and posture the design simulates, named to the protocol they come from
    let links = frame_of.link_lengths_m;
    let posture = prior.posture_rad.unwrap_or(frame_of.posture_rad);
    let unfit = if !links
        .iter()
        .all(|l| (limpid_ident::planar::MIN_LINK_M..=limpid_ident::planar::MAX_LINK_M).contains(l))
    {
        Some(format!(
            "link_lengths_m = [{}, {}]: an arm's links are {} to {} m",
            limpid_core::error::Num(links[0]),
            limpid_core::error::Num(links[1]),
            limpid_ident::planar::MIN_LINK_M,
            limpid_ident::planar::MAX_LINK_M
        ))
    } else if posture
        .iter()
        .any(|q| q.is_nan() || q.abs() > std::f64::consts::TAU)
    {
        Some(format!(
            "posture_rad = [{}, {}]: joint angles within ±2π rad",
            limpid_core::error::Num(posture[0]),
            limpid_core::error::Num(posture[1])
        ))
    } else {
        None
    };
    if let Some(message) = unfit {
        return Err(match inputs.limits_from {
            Some((_, path)) => Error::Format {
                path: path.to_path_buf(),
                message,
            },
            None => Error::invalid("limits_from", message),
        });
    }
    prior
        .noise
        .check(frame_of.sample_rate_hz)
        .map_err(|message| match prior_text {
            t if t.starts_with("demo:") => Error::invalid("prior", format!("[noise] {message}")),
            _ => Error::Format {
                path: prior_path.to_path_buf(),
                message: format!("[noise] {message}"),
            },
        })?;
    let frame = PlanarFrame {
        limits,
        link_lengths_m: links,
        posture_rad: posture,
        wait_s: frame_of.wait_s,
    };
    let request = inputs.request(prior, (frame, frame_of.sample_rate_hz), baseline)?;
    check_planar_request(&request)?;
    Ok(request)
}

/// The request's numbers, before any simulation.
pub fn check_planar_request(req: &PlanarDesignRequest) -> Result<()> {
    let l = &req.limits.limits;
    for (name, v) in [
        ("max_joint_displacement_rad", l.max_joint_displacement_rad),
        ("max_joint_velocity_rad_s", l.max_joint_velocity_rad_s),
        (
            "max_joint_acceleration_rad_s2",
            l.max_joint_acceleration_rad_s2,
        ),
        ("max_torque_nm", l.max_torque_nm),
    ] {
        if !(v > 0.0 && v.is_finite()) {
            return Err(Error::invalid(
                "limits",
                format!("{name} = {v}: a limit is a positive number"),
            ));
        }
    }
    if !(l.nominal_joint_stiffness_nm_per_rad >= 0.0
        && l.nominal_joint_stiffness_nm_per_rad.is_finite())
    {
        return Err(Error::invalid(
            "limits",
            format!(
                "nominal_joint_stiffness_nm_per_rad = {}: expected a non-negative number",
                l.nominal_joint_stiffness_nm_per_rad
            ),
        ));
    }
    if !(req.sample_rate_hz > 0.0 && req.sample_rate_hz <= 10_000.0) {
        return Err(Error::invalid(
            "sample_rate_hz",
            format!("{} Hz: expected 0 < rate <= 10000", req.sample_rate_hz),
        ));
    }
    check_budget(req.budget_s, req.sample_rate_hz)?;
    if let Some(b) = &req.baseline {
        let report = limpid_lab::design::check(&Design::Planar(b.clone()))?;
        let samples = b.trials as f64 * (b.rest_s + b.after_s) * b.sample_rate_hz;
        if samples > super::MAX_DESIGN_SAMPLES || b.trials > MOST_TRIALS {
            return Err(Error::invalid(
                "baseline",
                format!(
                    "{} perturbations, {samples:.0} recorded samples ({:.0} s session); a baseline is simulated `runs` times and may hold at most {MOST_TRIALS} and {:.0}",
                    b.trials,
                    report_session(&report),
                    super::MAX_DESIGN_SAMPLES
                ),
            ));
        }
    }
    req.prior
        .noise
        .check(req.sample_rate_hz)
        .map_err(|m| Error::invalid("noise", m))?;
    check_runs("runs", req.runs, false)?;
    check_runs("verify", req.verify, true)?;
    Ok(())
}

fn report_session(r: &limpid_lab::design::DesignReport) -> f64 {
    match r {
        limpid_lab::design::DesignReport::Planar(p) => p.session_s,
        _ => f64::NAN,
    }
}

/// Indices into the four lists of choices.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
struct Choice {
    amplitude: usize,
    slowness: usize,
    hold: usize,
    rest: usize,
}

impl Grid for Choice {
    const SIZES: &'static [usize] = &[
        AMPLITUDE_SHARES.len(),
        SLOWNESS.len(),
        HOLDS_S.len(),
        RESTS_S.len(),
    ];

    fn with(&self, dim: usize, value: usize) -> Choice {
        let mut c = *self;
        match dim {
            0 => c.amplitude = value,
            1 => c.slowness = value,
            2 => c.hold = value,
            _ => c.rest = value,
        }
        c
    }
}

/// A candidate: the protocol and its simulation.
struct Candidate {
    design: PlanarDesign,
    simulation: PlanarProtocol,
}

/// Checked inputs the search works from.
struct Space<'a> {
    req: &'a PlanarDesignRequest,
    largest_amplitude: f64,
}

/// The largest amplitude the displacement and static torque limits allow.
fn largest_amplitude(req: &PlanarDesignRequest) -> Result<f64> {
    let l = &req.limits.limits;
    // the static torque K Δq of the stiffest direction, at either end of the prior
    let stiffest = req
        .prior
        .ends()
        .iter()
        .flat_map(|arm| DIRECTIONS.map(|d| (arm.stiffness * Vector2::new(d[0], d[1])).amax()))
        .fold(l.nominal_joint_stiffness_nm_per_rad, f64::max);
    let amplitude = l.max_joint_displacement_rad.min(l.max_torque_nm / stiffest) * LIMIT_MARGIN;
    if amplitude.is_nan() || amplitude < LEAST_AMPLITUDE_RAD {
        return Err(Error::invalid(
            "limits",
            format!(
                "the limits leave a largest joint displacement of {amplitude:.3e} rad (torque {} N m at a joint stiffness of {stiffest:.4e} N m/rad, displacement {} rad); nothing below {LEAST_AMPLITUDE_RAD} rad can be designed",
                l.max_torque_nm, l.max_joint_displacement_rad
            ),
        ));
    }
    Ok(amplitude)
}

/// Largest joint torque `|M(q) q'' + C q' + D q' + K Δq|` (τ0 aside) the
/// perturbations need on either end of the prior (N m).
fn peak_torque(d: &PlanarDesign, prior: &PlanarPrior) -> f64 {
    let tk = d.interpolation_s;
    let q0 = Vector2::new(d.posture_rad[0], d.posture_rad[1]);
    let mut peak = 0.0f64;
    for arm in prior.ends() {
        for dir in &d.displacements_rad {
            let dir = Vector2::new(dir[0], dir[1]);
            for k in 0..=200 {
                let (s, sd, sdd) = Profile::Quintic.eval(tk * k as f64 / 200.0, tk);
                let (dq, qd, qdd) = (dir * s, dir * sd, dir * sdd);
                let q = q0 + dq;
                let (k_scale, d_scale) = match prior.reflex {
                    // the reflex may act before the motion ends
                    Some(r) => (
                        1.0 + r.stiffness_gain.max(0.0),
                        1.0 + r.damping_gain.max(0.0),
                    ),
                    None => (1.0, 1.0),
                };
                let tau = limpid_core::arm::mass_matrix(q[1], arm.xi) * qdd
                    + limpid_core::arm::coriolis(q[1], [qd[0], qd[1]], arm.xi)
                    + arm.damping * qd * d_scale
                    + arm.stiffness * dq * k_scale;
                peak = peak.max(tau.amax());
            }
        }
    }
    peak
}

impl Space<'_> {
    /// The protocol of a choice, or why it is refused.
    fn candidate(&self, c: &Choice) -> std::result::Result<Candidate, String> {
        let req = self.req;
        let frame = &req.limits;
        let l = &frame.limits;
        let amplitude = AMPLITUDE_SHARES[c.amplitude] * self.largest_amplitude;
        let (_, v_peak, a_peak) = Profile::Quintic.peaks(1.0);
        let shortest = (amplitude * v_peak / (LIMIT_MARGIN * l.max_joint_velocity_rad_s))
            .max((amplitude * a_peak / (LIMIT_MARGIN * l.max_joint_acceleration_rad_s2)).sqrt());
        // a motion of at least 10 samples, so that the quintic is sampled
        let tk = (shortest * SLOWNESS[c.slowness]).max(10.0 / req.sample_rate_hz);
        let (hold, rest) = (HOLDS_S[c.hold], RESTS_S[c.rest]);
        // the return to the posture (over T_k) and the recorded rest fit in every wait
        if rest + tk > frame.wait_s[0] {
            return Err(format!(
                "a return over {tk:.3} s and a recorded rest of {rest} s do not fit in the shortest wait, {} s",
                frame.wait_s[0]
            ));
        }
        let after = tk + hold;
        let mut design = PlanarDesign {
            name: String::new(),
            sample_rate_hz: req.sample_rate_hz,
            link_lengths_m: frame.link_lengths_m,
            posture_rad: frame.posture_rad,
            displacements_rad: DIRECTIONS
                .iter()
                .map(|d| [d[0] * amplitude, d[1] * amplitude])
                .collect(),
            trials: MOST_TRIALS,
            interpolation_s: tk,
            rest_s: rest,
            after_s: after,
            wait_s: frame.wait_s,
            seed: req.seed,
            limits: l.clone(),
        };
        // as many perturbations as the budget holds (the schedule's random
        // waits are a prefix of a longer schedule's)
        let trials = design
            .schedule()
            .iter()
            .take_while(|(onset, _)| onset + after + tk <= req.budget_s)
            .count();
        if trials < MIN_TRIALS {
            return Err(format!(
                "{trials} perturbations of {after:.3} s (and a return) after random waits of {:?} s fit in {} s; at least {MIN_TRIALS} are needed",
                frame.wait_s, req.budget_s
            ));
        }
        design.trials = trials;
        design.name = format!(
            "designed by limpid protocol design --method planar: {trials} quintic perturbations of {:.3} rad over {:.0} ms, recorded {:.0} ms after each onset",
            amplitude,
            tk * 1e3,
            after * 1e3
        );
        let peak = peak_torque(&design, &req.prior);
        if peak > LIMIT_MARGIN * l.max_torque_nm {
            return Err(format!(
                "torque {peak:.2} N m on the prior exceeds the limit {} N m",
                l.max_torque_nm
            ));
        }
        let simulation = design.simulation();
        Ok(Candidate { design, simulation })
    }
}

/// One recording of `c` on arm `arm`, estimated as `limpid estimate planar`
/// does (every recorded sample of every trial, ξ estimated).
fn run_once(
    c: &Candidate,
    req: &PlanarDesignRequest,
    arm: &ArmImpedance,
    seed: u64,
) -> Result<Run> {
    let prior = &req.prior;
    let subject = prior.subject(arm, c.design.posture_rad);
    let noise = &prior.noise;
    let mut rec = simulate_planar(
        &subject,
        &c.simulation,
        noise.torque_white_nm,
        noise.angle_white_rad,
        seed,
    )?;
    add_torque_fluctuation(
        &mut rec,
        noise.torque_fluctuation_nm,
        noise.fluctuation_below_hz,
        seed ^ 0x5eed,
    )?;
    let links = c.design.link_lengths_m;
    let data = prepare_planar(&rec, &PlanarPrepare::new(links[0], links[1]))?;
    let all: Vec<usize> = (0..data.trials.len()).collect();
    let est = fit_planar(&data, usize::MAX, None, &all)?;
    let v = &est.criteria.verdicts;
    let identified =
        |v: MatrixVerdict| !matches!(v, MatrixVerdict::NotIdentifiable | MatrixVerdict::PoorFit);
    let (xi, xi_se) = (
        est.inertial_parameters,
        est.standard_errors.inertial_parameters,
    );
    // ξ identified when every parameter is at least 2 SE from zero, as the criteria ask of K's and D's diagonals
    let xi_identified = (0..3).all(|i| xi[i].abs() >= 2.0 * xi_se[i]);
    Ok(Run::new(
        [
            &est.stiffness,
            &est.damping,
            &Matrix(DMatrix::from_row_slice(1, 3, &xi)),
        ],
        [
            identified(v.stiffness),
            identified(v.damping),
            xi_identified,
        ],
        arm,
    ))
}

/// The designed protocol and its result.
pub struct PlanarDesigned {
    /// The protocol (`kind = "planar"`).
    pub protocol: PlanarDesign,
    /// Everything measured about it.
    pub result: PlanarDesignResult,
}

/// Length of a planar session (s): the schedule's waits, recorded windows
/// and the last return (as `protocol check` and `protocol export` count it).
fn session_s(d: &PlanarDesign) -> f64 {
    d.schedule()
        .last()
        .map_or(0.0, |(onset, _)| onset + d.after_s + d.interpolation_s)
}

/// Choose the perturbations. Deterministic for a given request (seeded noise).
pub fn design_planar(req: &PlanarDesignRequest) -> Result<PlanarDesigned> {
    check_planar_request(req)?;
    let space = Space {
        req,
        largest_amplitude: largest_amplitude(req)?,
    };
    let ranking = seeds(req.seed, 0, RANKING_RUNS);
    let subjects = super::range_subjects(
        &req.prior.nominal,
        req.prior.other_end.as_ref(),
        req.objective.robust,
    );
    // start: 35 % of the largest amplitude, the fastest motion, 80 ms hold, 0.2 s rest
    let start = Choice {
        amplitude: 3,
        slowness: 0,
        hold: 4,
        rest: 1,
    };
    let searched = coordinate_descent(start, "planar perturbation", |c| {
        let cand = space.candidate(c)?;
        let run = |arm: &ArmImpedance, s: u64| run_once(&cand, req, arm, s);
        rank(&run, &subjects, &req.objective, &ranking)
    })?;
    let chosen = space
        .candidate(&searched.best)
        .map_err(|why| Error::invalid("design", why))?;
    // the sample-by-sample check `limpid protocol check` makes
    limpid_lab::design::check(&Design::Planar(chosen.design.clone()))?;
    let final_seeds = seeds(req.seed, 10_000, req.runs);
    let run = |arm: &ArmImpedance, s: u64| run_once(&chosen, req, arm, s);
    let predicted = predict(
        &run,
        session_s(&chosen.design),
        &subjects,
        &req.objective,
        &final_seeds,
    )?;
    let baseline = req
        .baseline
        .as_ref()
        .map(|b| {
            let mut b = b.clone();
            b.posture_rad = req.limits.posture_rad;
            let base = Candidate {
                simulation: b.simulation(),
                design: b,
            };
            let run = |arm: &ArmImpedance, s: u64| run_once(&base, req, arm, s);
            predict(
                &run,
                session_s(&base.design),
                &subjects,
                &req.objective,
                &final_seeds,
            )
        })
        .transpose()?;
    let verify = (req.verify > 0)
        .then(|| {
            verify(
                &run,
                (&req.prior.nominal, req.prior.other_end.as_ref()),
                &predicted,
                req.verify,
                req.seed,
            )
        })
        .transpose()?;
    let d = &chosen.design;
    let l = &d.limits;
    let amplitude = d.displacements_rad[0][0].abs();
    let (_, v, a) = Profile::Quintic.peaks(d.interpolation_s);
    let result = PlanarDesignResult {
        objective: req.objective.recorded(),
        budget_s: req.budget_s,
        posture_rad: d.posture_rad,
        chosen: PlanarChoice {
            amplitude_rad: amplitude,
            interpolation_s: d.interpolation_s,
            hold_s: d.after_s - d.interpolation_s,
            rest_s: d.rest_s,
            window_ms: 1e3 * d.after_s,
            wait_s: d.wait_s,
            trials: d.trials,
            duration_s: session_s(d),
        },
        predicted,
        baseline,
        protocol: serde_json::to_value(d).map_err(|e| Error::invalid("protocol", e.to_string()))?,
        limits: vec![
            LimitMargin::new(
                "joint displacement",
                "rad",
                amplitude,
                l.max_joint_displacement_rad,
            ),
            LimitMargin::new(
                "joint velocity",
                "rad/s",
                amplitude * v,
                l.max_joint_velocity_rad_s,
            ),
            LimitMargin::new(
                "joint acceleration",
                "rad/s^2",
                amplitude * a,
                l.max_joint_acceleration_rad_s2,
            ),
            LimitMargin::new(
                "torque on the prior",
                "N m",
                peak_torque(d, &req.prior),
                l.max_torque_nm,
            ),
            LimitMargin::new(
                "torque at the nominal stiffness",
                "N m",
                amplitude * l.nominal_joint_stiffness_nm_per_rad,
                l.max_torque_nm,
            ),
        ],
        search: SearchSummary {
            candidates: searched.candidates,
            runs_per_candidate: RANKING_RUNS,
            refused: searched.refused,
            objective: searched.objective,
        },
        verify,
        command: command_trace(d),
        spectrum: JointCommandSpectrum {
            frequency_hz: spectrum_hz(),
            designed_rad: trial_spectrum(d),
            baseline_rad: req.baseline.as_ref().map(trial_spectrum),
            limit_rad: limit_envelope(
                l.max_joint_displacement_rad,
                l.max_joint_velocity_rad_s,
                l.max_joint_acceleration_rad_s2,
            ),
        },
    };
    Ok(PlanarDesigned {
        protocol: chosen.design,
        result,
    })
}

/// One recorded trial of the first direction's moving joint: rest, motion, hold.
fn trial_path(d: &PlanarDesign, t: f64) -> (f64, f64, f64) {
    let a = d.displacements_rad[0]
        .iter()
        .fold(0.0f64, |m, v| if v.abs() > m.abs() { *v } else { m });
    let (s, v, acc) = Profile::Quintic.eval(t - d.rest_s, d.interpolation_s);
    (a * s, a * v, a * acc)
}

fn command_trace(d: &PlanarDesign) -> JointCommandTrace {
    let length = d.rest_s + d.after_s;
    let n = ((length * d.sample_rate_hz).round() as usize).clamp(2, 2000);
    let t: Vec<f64> = (0..n).map(|i| length * i as f64 / (n - 1) as f64).collect();
    let path: Vec<(f64, f64, f64)> = t.iter().map(|&t| trial_path(d, t)).collect();
    JointCommandTrace {
        displacement_rad: path.iter().map(|p| p.0).collect(),
        velocity_rad_s: path.iter().map(|p| p.1).collect(),
        acceleration_rad_s2: path.iter().map(|p| p.2).collect(),
        t_s: t,
    }
}

/// `2 |X(f)| / T` of one recorded trial's displacement.
fn trial_spectrum(d: &PlanarDesign) -> Vec<f64> {
    let length = d.rest_s + d.after_s;
    let n = ((length * d.sample_rate_hz).round() as usize).max(2);
    let dt = length / n as f64;
    let x: Vec<f64> = (0..n).map(|i| trial_path(d, i as f64 * dt).0).collect();
    sine_amplitudes(&x, dt)
}
