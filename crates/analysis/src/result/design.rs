//! The result of `limpid protocol design` (issue 60): the chosen protocol,
//! the standard errors it is predicted to give on the prior subject, the same
//! for the protocol it replaces, the margin to every limit and, with
//! `--verify`, the spread it achieved on subjects drawn from the prior.

use limpid_core::Matrix;
use schemars::JsonSchema;
use serde::{Deserialize, Serialize};

/// A designed experiment.
#[derive(Debug, Clone, Serialize, Deserialize, JsonSchema)]
pub struct DesignResult {
    /// The estimator the design is for (`linear` or `stochastic`).
    pub method: String,
    /// The family the protocol was chosen from (`centre-out` or `multisine`).
    pub family: String,
    /// Weights of the relative variances of K, B and M in the objective.
    pub objective: ObjectiveWeights,
    /// The time budget (s): rests, motions, holds, returns and relaxation counted.
    pub budget_s: f64,
    /// The start point the design is for (m): the prior's posture.
    pub start_m: [f64; 3],
    /// The family's parameters that were chosen.
    pub chosen: DesignChoice,
    /// Predicted on the prior subject (the nominal one; the worse end when the prior has a range).
    pub predicted: Prediction,
    /// The same for the protocol it replaces (`--baseline`), at the same start point.
    pub baseline: Option<Prediction>,
    /// The designed protocol (the TOML written by `-o`, as JSON).
    pub protocol: serde_json::Value,
    /// Largest value reached against each limit.
    pub limits: Vec<LimitMargin>,
    /// How the design was searched.
    pub search: SearchSummary,
    /// With `--verify N`: the design run on subjects drawn from the prior.
    pub verify: Option<Verification>,
    /// One perturbation of the design along its direction, for plots.
    pub command: CommandTrace,
    /// What one perturbation excites, against the limits.
    pub spectrum: CommandSpectrum,
}

/// The parameters a design chose, by family.
#[derive(Debug, Clone, Serialize, Deserialize, JsonSchema)]
#[serde(untagged)]
pub enum DesignChoice {
    /// A centre-out protocol's (the linear method's).
    CentreOut(CentreOutChoice),
    /// A periodic multisine's (the stochastic method's).
    Multisine(MultisineChoice),
}

impl DesignChoice {
    /// Length of the whole protocol (s).
    pub fn duration_s(&self) -> f64 {
        match self {
            DesignChoice::CentreOut(c) => c.duration_s,
            DesignChoice::Multisine(c) => c.duration_s,
        }
    }

    /// The protocol in words, numbers written by `num` (the caller's rounding):
    /// the one description the CLI, the report and the demo print.
    pub fn describe(&self, num: impl Fn(f64) -> String) -> String {
        match self {
            DesignChoice::CentreOut(c) => c.describe(num),
            DesignChoice::Multisine(c) => format!(
                "a zippered random-odd multisine at x, y, z over {}-{} Hz ({} amplitude), {} s period, {} recorded periods between a fade-in and a fade-out period, {} mm RMS per axis, {} lines each",
                num(c.band_hz[0]),
                num(c.band_hz[1]),
                c.amplitude_shape,
                num(c.period_s),
                c.periods,
                num(c.rms_m * 1e3),
                c.lines_per_channel
            ),
        }
    }

    /// The centre-out parameters, when the family is centre-out.
    pub fn centre_out(&self) -> Option<&CentreOutChoice> {
        match self {
            DesignChoice::CentreOut(c) => Some(c),
            DesignChoice::Multisine(_) => None,
        }
    }
}

/// The parameters of an end-point multisine that the design chooses
/// (zippered random-odd lines over x, y, z).
#[derive(Debug, Clone, Serialize, Deserialize, JsonSchema)]
pub struct MultisineChoice {
    /// Excited band (Hz).
    pub band_hz: [f64; 2],
    /// Amplitude across the lines: `flat`, `1/f` or `1/f^2`.
    pub amplitude_shape: String,
    /// Period (s): the frequency resolution is its inverse.
    pub period_s: f64,
    /// Recorded periods (a fade-in and a fade-out period come on top).
    pub periods: usize,
    /// RMS displacement of each channel over a period (m).
    pub rms_m: f64,
    /// Excited lines per channel.
    pub lines_per_channel: usize,
    /// Length of the whole protocol (s).
    pub duration_s: f64,
}

/// One perturbation (rest, out, hold, back, relax) along its direction, or
/// one period of a multisine's first channel.
#[derive(Debug, Clone, Serialize, Deserialize, JsonSchema)]
pub struct CommandTrace {
    /// Time from the start of the trial (s).
    pub t_s: Vec<f64>,
    /// Displacement from the start point (m).
    pub displacement_m: Vec<f64>,
    /// Velocity (m/s).
    pub velocity_m_s: Vec<f64>,
    /// Acceleration (m/s^2).
    pub acceleration_m_s2: Vec<f64>,
}

/// Amplitude of one perturbation's displacement by frequency: `2 |X(f)| / T`
/// over the trial of length T (the amplitude a sine filling the trial would
/// have), beside the largest sine amplitude the limits allow at that
/// frequency, `min(d_max, v_max / ω, a_max / ω²)`. For a multisine: the
/// amplitude of each excited line (of whichever channel excites it), no baseline.
#[derive(Debug, Clone, Serialize, Deserialize, JsonSchema)]
pub struct CommandSpectrum {
    /// Frequencies (Hz), log-spaced.
    pub frequency_hz: Vec<f64>,
    /// The design's (m).
    pub designed_m: Vec<f64>,
    /// The baseline's, when there is one (m).
    pub baseline_m: Option<Vec<f64>>,
    /// The limits' envelope (m).
    pub limit_m: Vec<f64>,
}

/// Weights of the objective.
#[derive(Debug, Clone, Serialize, Deserialize, JsonSchema)]
pub struct ObjectiveWeights {
    /// Of K's relative variance.
    pub stiffness: f64,
    /// Of B's relative variance.
    pub damping: f64,
    /// Of M's relative variance.
    pub inertia: f64,
    /// Over the prior's range: `worst-case` (the worse end) or `expected`
    /// (the mean over its ends and midpoint).
    #[serde(default = "worst_case")]
    pub robust: String,
}

fn worst_case() -> String {
    "worst-case".into()
}

impl CentreOutChoice {
    /// The protocol in words (see [`DesignChoice::describe`]).
    pub fn describe(&self, num: impl Fn(f64) -> String) -> String {
        format!(
            "{} {} perturbations of {} mm, {} ms out, {} ms hold, {} ms back; rest {} s, relax {} s",
            self.trials,
            self.profile,
            num(self.radius_m * 1e3),
            num(self.motion_s * 1e3),
            num(self.hold_s * 1e3),
            num(self.motion_s * 1e3),
            num(self.rest_s),
            num(self.relax_s)
        )
    }
}

/// The parameters of a centre-out protocol that the design chooses.
#[derive(Debug, Clone, Serialize, Deserialize, JsonSchema)]
pub struct CentreOutChoice {
    /// Profile of the motion out and of the return.
    pub profile: String,
    /// Distance from start to target (m).
    pub radius_m: f64,
    /// Duration of the motion out, and of the return (s).
    pub motion_s: f64,
    /// Recorded hold at the target (s).
    pub hold_s: f64,
    /// Recorded rest before each perturbation (s).
    pub rest_s: f64,
    /// Unrecorded relaxation after each return (s).
    pub relax_s: f64,
    /// Perturbations (target directions).
    pub trials: usize,
    /// Length of the whole protocol (s).
    pub duration_s: f64,
}

/// Standard errors and bias a protocol is predicted to give.
#[derive(Debug, Clone, Serialize, Deserialize, JsonSchema)]
pub struct Prediction {
    /// Spread (s.d.) of each K element over the simulated recordings (N/m).
    pub stiffness_se: Matrix,
    /// Of each B element (N s/m).
    pub damping_se: Matrix,
    /// Of each M element (kg).
    pub inertia_se: Matrix,
    /// Root mean square of the nine s.d. of K, B and M, and relative to the
    /// RMS element of the prior's matrix (percent).
    pub pooled: Pooled,
    /// Recordings simulated for the prediction.
    pub runs: usize,
    /// Length of the protocol at one start point (s).
    pub duration_s: f64,
    /// Share of the runs whose estimate the criteria called identifiable: K, B, M.
    pub identifiable_share: [f64; 3],
}

/// Pooled figures of a matrix triple.
#[derive(Debug, Clone, Copy, Serialize, Deserialize, JsonSchema)]
pub struct Pooled {
    /// RMS of the element s.d. of K (N/m), B (N s/m), M (kg).
    pub se: [f64; 3],
    /// The same relative to the prior's RMS element (percent).
    pub se_percent: [f64; 3],
    /// Mean relative Frobenius error of K, B, M against the truth (percent): bias and spread.
    pub error_percent: [f64; 3],
}

/// The largest value a protocol reaches against one limit.
#[derive(Debug, Clone, Serialize, Deserialize, JsonSchema)]
pub struct LimitMargin {
    /// What is limited.
    pub quantity: String,
    /// Unit of `peak` and `limit`.
    pub unit: String,
    /// Largest value over every sample.
    pub peak: f64,
    /// The limit.
    pub limit: f64,
    /// `1 - peak / limit`, percent.
    pub margin_percent: f64,
}

impl LimitMargin {
    /// The margin of `peak` to `limit` (same unit).
    pub fn new(quantity: &str, unit: &str, peak: f64, limit: f64) -> Self {
        LimitMargin {
            quantity: quantity.into(),
            unit: unit.into(),
            peak,
            limit,
            margin_percent: 100.0 * (1.0 - peak / limit),
        }
    }
}

/// How the search went.
#[derive(Debug, Clone, Serialize, Deserialize, JsonSchema)]
pub struct SearchSummary {
    /// Candidate protocols evaluated.
    pub candidates: usize,
    /// Simulated recordings per candidate (the same noise seeds for every candidate).
    pub runs_per_candidate: usize,
    /// Candidates refused by a limit or the time budget.
    pub refused: usize,
    /// The objective of the chosen design (weighted relative variance, percent squared).
    pub objective: f64,
}

/// Predicted against achieved spread on subjects drawn from the prior.
#[derive(Debug, Clone, Serialize, Deserialize, JsonSchema)]
pub struct Verification {
    /// Recordings simulated.
    pub runs: usize,
    /// Achieved pooled s.d. of the estimate's error for K, B, M (same units as `Pooled::se`).
    pub achieved_se: [f64; 3],
    /// Predicted over achieved, K, B, M.
    pub ratio: [f64; 3],
    /// Share of runs with K within 5 % and B within 20 % of the truth (Frobenius), both identifiable.
    pub within_tolerance_share: f64,
    /// Mean relative Frobenius error of K, B, M (percent).
    pub error_percent: [f64; 3],
}

/// A PRBS designed for the reflex method (`limpid protocol design --method reflex`).
#[derive(Debug, Clone, Serialize, Deserialize, JsonSchema)]
pub struct ReflexDesignResult {
    /// The time budget (s): fade-in, periods and fade-out counted.
    pub budget_s: f64,
    /// What was chosen.
    pub chosen: PrbsChoice,
    /// Predicted on the prior ankle.
    pub predicted: ReflexPrediction,
    /// The same for the protocol it replaces, if given.
    pub baseline: Option<ReflexPrediction>,
    /// Predicted spread of the reflex gain over the baseline's (when there is one).
    pub gain_spread_ratio: Option<f64>,
    /// The designed protocol (`kind = "prbs"`, as JSON).
    pub protocol: serde_json::Value,
    /// Largest value reached against each limit.
    pub limits: Vec<LimitMargin>,
    /// How the design was searched.
    pub search: SearchSummary,
    /// The start of one period of the designed command, for plots.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub command: Option<JointCommandTrace>,
    /// What one period of the design and of the baseline excite, against the limits.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub spectrum: Option<JointLineSpectrum>,
}

/// The first seconds (at most 2000 samples) of one recorded period of a joint command.
#[derive(Debug, Clone, Serialize, Deserialize, JsonSchema)]
pub struct JointCommandTrace {
    /// Time from the period's start (s).
    pub t_s: Vec<f64>,
    /// Displacement from the posture (rad).
    pub displacement_rad: Vec<f64>,
    /// Velocity (rad/s).
    pub velocity_rad_s: Vec<f64>,
    /// Acceleration (rad/s^2).
    pub acceleration_rad_s2: Vec<f64>,
}

/// The amplitude of each line of one period, `2 |X_k| / n` (the amplitude
/// of a sine at that line), for the design and the baseline (each at its
/// own period's lines, up to 1.5 / switching interval), beside the largest
/// sine the limits allow, `min(d, v / ω, a / ω²)`, at the design's lines.
#[derive(Debug, Clone, Serialize, Deserialize, JsonSchema)]
pub struct JointLineSpectrum {
    /// The design's lines (Hz).
    pub frequency_hz: Vec<f64>,
    /// The design's amplitude per line (rad).
    pub designed_rad: Vec<f64>,
    /// The limits' envelope at the design's lines (rad).
    pub limit_rad: Vec<f64>,
    /// The baseline's lines (Hz), when there is one.
    pub baseline_frequency_hz: Option<Vec<f64>>,
    /// The baseline's amplitude per line (rad).
    pub baseline_rad: Option<Vec<f64>>,
}

/// The PRBS parameters the design chooses.
#[derive(Debug, Clone, Serialize, Deserialize, JsonSchema)]
pub struct PrbsChoice {
    /// Switching interval (s).
    pub switch_interval_s: f64,
    /// Register order (period 2^order - 1 intervals).
    pub order: usize,
    /// Recorded periods (a fade-in and a fade-out period come on top).
    pub periods: usize,
    /// Half-swing (rad).
    pub amplitude_rad: f64,
    /// Length of the whole command (s).
    pub duration_s: f64,
}

/// The reflex gain's (and the intrinsic K and B's) predicted precision.
#[derive(Debug, Clone, Serialize, Deserialize, JsonSchema)]
pub struct ReflexPrediction {
    /// Spread (s.d.) of the reflex gain over the simulated recordings (N m s/rad).
    pub gain_sd: f64,
    /// Mean of the estimator's own standard error of the gain (N m s/rad).
    pub gain_se_mean: f64,
    /// The gain's standard error from the information in the parametric
    /// model with white torque noise, `σ / sqrt(Σ r⊥²)` (N m s/rad): what
    /// the design ranks by.
    pub gain_se_information: f64,
    /// Mean relative error of the gain against the prior's (percent).
    pub gain_error_percent: f64,
    /// Spread of the intrinsic stiffness (N m/rad) and damping (N m s/rad).
    pub intrinsic_sd: [f64; 2],
    /// Recordings simulated.
    pub runs: usize,
    /// Length of the protocol (s).
    pub duration_s: f64,
}

/// A perturbation protocol designed for the planar method (`limpid protocol
/// design --method planar`, seed 003): quintic joint-space displacements in
/// six directions from one posture.
#[derive(Debug, Clone, Serialize, Deserialize, JsonSchema)]
pub struct PlanarDesignResult {
    /// Weights of the relative variances of K, D and ξ in the objective.
    pub objective: ObjectiveWeights,
    /// The time budget (s): waits, perturbations and recorded holds counted.
    pub budget_s: f64,
    /// The posture q0 the design is for (shoulder, relative elbow; rad).
    pub posture_rad: [f64; 2],
    /// What was chosen.
    pub chosen: PlanarChoice,
    /// Predicted on the prior arm (the worse end when it has a range):
    /// `stiffness_se` K (N m/rad, 2 x 2), `damping_se` D (N m s/rad, 2 x 2),
    /// `inertia_se` ξ1..ξ3 (kg m², one row); errors against the arm's
    /// intrinsic K and D (before any reflex).
    pub predicted: Prediction,
    /// The same for the protocol it replaces (`--baseline`), at the same posture.
    pub baseline: Option<Prediction>,
    /// The designed protocol (`kind = "planar"`, as JSON).
    pub protocol: serde_json::Value,
    /// Largest value reached against each limit.
    pub limits: Vec<LimitMargin>,
    /// How the design was searched.
    pub search: SearchSummary,
    /// With `--verify N`: the design run on arms drawn from the prior (K, D, ξ).
    pub verify: Option<Verification>,
    /// One recorded trial of the first (shoulder) direction, for plots.
    pub command: JointCommandTrace,
    /// What one recorded trial excites, against the limits.
    pub spectrum: JointCommandSpectrum,
}

impl PlanarChoice {
    /// The perturbations in words, numbers written by `num` (the caller's
    /// rounding): the one description the CLI and the report print.
    pub fn describe(&self, num: impl Fn(f64) -> String) -> String {
        format!(
            "{} quintic perturbations of {} rad over {} ms in six joint directions, recorded {} ms before and {} ms after each onset (the observation window), after random waits of {}-{} s",
            self.trials,
            num(self.amplitude_rad),
            num(self.interpolation_s * 1e3),
            num(self.rest_s * 1e3),
            num(self.window_ms),
            num(self.wait_s[0]),
            num(self.wait_s[1])
        )
    }
}

/// The planar protocol's parameters a design chose.
#[derive(Debug, Clone, Serialize, Deserialize, JsonSchema)]
pub struct PlanarChoice {
    /// Displacement of each joint that moves (rad): directions (±a, 0), (0, ±a), ±(a, -a).
    pub amplitude_rad: f64,
    /// Interpolation interval T_k of the quintic (s).
    pub interpolation_s: f64,
    /// Recorded hold after the motion (s).
    pub hold_s: f64,
    /// Recorded rest before each onset (s): the posture and baseline torque are its means.
    pub rest_s: f64,
    /// The observation window after each onset the estimate uses (ms): T_k and the hold.
    pub window_ms: f64,
    /// The random wait before each perturbation (s), the limits' protocol's.
    pub wait_s: [f64; 2],
    /// Perturbations.
    pub trials: usize,
    /// Length of the whole session, waits included (s).
    pub duration_s: f64,
}

/// Amplitude of one recorded trial's displacement by frequency, `2 |X(f)| /
/// T` over the trial of length T, beside the largest sine amplitude the
/// limits allow at that frequency, `min(d_max, v_max / ω, a_max / ω²)`.
#[derive(Debug, Clone, Serialize, Deserialize, JsonSchema)]
pub struct JointCommandSpectrum {
    /// Frequencies (Hz), log-spaced.
    pub frequency_hz: Vec<f64>,
    /// The design's (rad).
    pub designed_rad: Vec<f64>,
    /// The baseline's, when there is one (rad).
    pub baseline_rad: Option<Vec<f64>>,
    /// The limits' envelope (rad).
    pub limit_rad: Vec<f64>,
}
