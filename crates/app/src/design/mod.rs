//! Experiment design (issue 60): choose a centre-out protocol for the linear
//! estimator (seed 000 eq. (2)-(8)) that minimises the predicted variance of
//! the parameters that matter, within the safety limits and a time budget,
//! at one posture.
//!
//! **Prediction.** A protocol's predicted standard errors are the spread of
//! the linear estimator's own estimates over recordings of the protocol
//! simulated on the prior subject with the prior's noise model (limpid's lab:
//! servo, sensor offsets, drift, signal-dependent force fluctuation, posture
//! drift), each prepared and fitted exactly as `limpid estimate linear` does.
//! This is the estimator's covariance computed through its own preparation
//! (filter, derivatives, rest offsets) rather than through a linearised
//! Fisher information: the realistic noise model is signal-dependent and
//! slow, and the rest-offset subtraction makes it non-stationary, which a
//! closed-form information matrix would have to approximate.
//!
//! **Objective.** A-optimal on relative variances: `Σ_p w_p MSE_p / (‖P‖²/9)`
//! for P in K, B, M, the mean squared error of the nine elements (spread and
//! the preparation's bias alike) against the prior's own matrices; with a
//! prior range (`[other_end]`), the worse of the two ends (worst case).
//!
//! **Search.** The family is the centre-out protocol with recorded return
//! (seed 001's out-hold-back): profile (cubic, quintic, trapezoid; seed 000's
//! sinusoid starts at full speed and so is not at rest at its ends), radius
//! (a share of the largest the displacement, force and workspace limits
//! allow), motion duration (a multiple of the shortest the velocity and
//! acceleration limits allow for that radius), recorded hold and rest; the
//! number of perturbations fills the budget (at least 6 directions). The
//! unrecorded relaxation after each return is fixed at [`RELAX_S`]. Candidates
//! are compared on [`RANKING_RUNS`] recordings with the same noise seeds
//! (common random numbers), by coordinate descent over the five parameters
//! from a fast cubic; the chosen one is then predicted on `runs` fresh seeds.

pub mod planar;
pub mod reflex;
pub mod stochastic;

use std::collections::HashMap;
use std::path::Path;

use nalgebra::{DMatrix, Matrix3, Vector3};
use rayon::prelude::*;
use serde::Deserialize;

use limpid_analysis::result::design::{
    CentreOutChoice, CommandSpectrum, CommandTrace, DesignChoice, DesignResult, LimitMargin,
    ObjectiveWeights, Pooled, Prediction, SearchSummary, Verification,
};
use limpid_core::{Error, Matrix, Result};
use limpid_ident::{fit_linear, prepare, LinearEstimate, LinearParams, PrepareParams};
use limpid_lab::protocol::{self, Limits, Phases, Protocol, StartPoints, Targets};
use limpid_lab::{simulate_centre_out, CentreOut, NoiseModel, Posture, Profile};

/// Largest magnitude of an end-point inertia element a prior may give (kg).
const MOST_INERTIA_KG: f64 = 1e3;
/// Of a damping element (N s/m).
const MOST_DAMPING_N_S_PER_M: f64 = 1e5;
/// Of a stiffness element (N/m).
const MOST_STIFFNESS_N_PER_M: f64 = 1e7;
/// Least eigenvalue of the symmetric part of a prior's inertia (kg),
/// damping (N s/m) and stiffness (N/m): a limb's, far below any arm's, far
/// above where the design's SEs and objective overflow (inertia 1e-300
/// printed "inf %" and wrote a result limpid could not read back; issue 76).
const LEAST_END_POINT: [f64; 3] = [1e-2, 1e-1, 1.0];
/// Smallest radius worth designing (m): below it position noise is the signal.
const LEAST_RADIUS_M: f64 = 1e-4;

/// Unrecorded relaxation after each return (s): the subject's pause before the next rest.
pub const RELAX_S: f64 = 0.5;
/// Fewest perturbation directions: three axes, each both ways.
pub const MIN_TRIALS: usize = 6;
/// Recordings per candidate while searching.
pub const RANKING_RUNS: usize = 6;
/// K within this share of the truth (Frobenius) counts as within tolerance in `--verify`.
pub const STIFFNESS_TOLERANCE: f64 = 0.05;
/// B within this share.
pub const DAMPING_TOLERANCE: f64 = 0.20;

const PROFILES: [Profile; 3] = [Profile::Cubic, Profile::Quintic, Profile::Trapezoid];
/// Radius as a share of the largest the limits allow.
const RADIUS_SHARES: [f64; 5] = [0.2, 0.35, 0.5, 0.7, 1.0];
/// Motion duration as a multiple of the shortest the limits allow.
const SLOWNESS: [f64; 5] = [1.0, 1.4, 2.0, 3.0, 5.0];
const HOLDS_S: [f64; 3] = [0.0, 0.25, 0.6];
const RESTS_S: [f64; 3] = [0.2, 0.4, 0.8];
/// Below the limits by this share, so that rounding never breaches them.
pub(crate) const LIMIT_MARGIN: f64 = 0.995;

/// M, B, K of a subject (SI, force applied to the limb).
#[derive(Debug, Clone, Copy)]
pub struct Impedance {
    /// M (kg).
    pub inertia: Matrix3<f64>,
    /// B (N s/m).
    pub damping: Matrix3<f64>,
    /// K (N/m).
    pub stiffness: Matrix3<f64>,
}

impl Impedance {
    fn blend(&self, other: &Impedance, t: f64) -> Impedance {
        Impedance {
            inertia: self.inertia + (other.inertia - self.inertia) * t,
            damping: self.damping + (other.damping - self.damping) * t,
            stiffness: self.stiffness + (other.stiffness - self.stiffness) * t,
        }
    }

    fn matrices(&self) -> [Matrix3<f64>; 3] {
        [self.stiffness, self.damping, self.inertia]
    }
}

/// What a design's errors are taken against: three groups of parameters
/// (K, B, M; the planar method's K, D and ξ) and the line between the two
/// ends of a prior's range.
pub(crate) trait Truth: Sync {
    /// K, B (or D), M (or ξ, one row).
    fn groups(&self) -> [DMatrix<f64>; 3];
    /// The subject a share `t` of the way to `other`.
    fn blend(&self, other: &Self, t: f64) -> Self;
}

impl Truth for Impedance {
    fn groups(&self) -> [DMatrix<f64>; 3] {
        self.matrices()
            .map(|m| DMatrix::from_column_slice(3, 3, m.as_slice()))
    }

    fn blend(&self, other: &Impedance, t: f64) -> Impedance {
        Impedance::blend(self, other, t)
    }
}

/// What is known of the subject before the experiment.
#[derive(Debug, Clone)]
pub struct Prior {
    /// The posture (start point, m); None: the centre of the limits' workspace.
    pub start: Option<Vector3<f64>>,
    /// Nominal impedance.
    pub nominal: Impedance,
    /// The other end of its range, if any.
    pub other_end: Option<Impedance>,
    /// The rig's and subject's noise.
    pub noise: NoiseModel,
    /// Limits given in the prior file (`[limits]`), if any.
    pub limits: Option<Limits>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct ImpedanceFile {
    inertia: [[f64; 3]; 3],
    damping: [[f64; 3]; 3],
    stiffness: [[f64; 3]; 3],
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct PriorFile {
    #[serde(default)]
    start_m: Option<[f64; 3]>,
    inertia: [[f64; 3]; 3],
    damping: [[f64; 3]; 3],
    stiffness: [[f64; 3]; 3],
    #[serde(default)]
    other_end: Option<ImpedanceFile>,
    #[serde(default)]
    noise: Option<NoiseModel>,
    #[serde(default)]
    limits: Option<Limits>,
}

fn impedance(
    m: &[[f64; 3]; 3],
    b: &[[f64; 3]; 3],
    k: &[[f64; 3]; 3],
    path: &Path,
    table: &str,
) -> Result<Impedance> {
    let m3 = |a: &[[f64; 3]; 3]| Matrix3::from_fn(|r, c| a[r][c]);
    let imp = Impedance {
        inertia: m3(m),
        damping: m3(b),
        stiffness: m3(k),
    };
    for ((name, mat, most), least) in [
        ("inertia", imp.inertia, MOST_INERTIA_KG),
        ("damping", imp.damping, MOST_DAMPING_N_S_PER_M),
        ("stiffness", imp.stiffness, MOST_STIFFNESS_N_PER_M),
    ]
    .into_iter()
    .zip(LEAST_END_POINT)
    {
        if let Some((r, c)) = (0..9)
            .map(|k| (k / 3, k % 3))
            .find(|&(r, c)| mat[(r, c)].abs() > most)
        {
            return Err(Error::Format {
                path: path.to_path_buf(),
                message: format!(
                    "{table}{name}[{r}][{c}] = {}: a limb's {name} is below {most:e} in magnitude",
                    limpid_core::error::Num(mat[(r, c)])
                ),
            });
        }
        if let Some(i) = (0..3).find(|&i| mat[(i, i)] <= 0.0) {
            return Err(Error::Format {
                path: path.to_path_buf(),
                message: format!(
                    "{table}{name}[{i}][{i}] = {}: a prior's diagonal must be positive",
                    limpid_core::error::Num(mat[(i, i)])
                ),
            });
        }
        let dynamic = DMatrix::from_fn(3, 3, |r, c| mat[(r, c)]);
        check_least_eigenvalue(&dynamic, least, path, &format!("{table}{name}"))?;
    }
    Ok(imp)
}

/// A prior's matrix must be a limb's: its symmetric part positive definite
/// with every eigenvalue at least `least` (SI); the error names the file and
/// the key.
pub(crate) fn check_least_eigenvalue(
    m: &DMatrix<f64>,
    least: f64,
    path: &Path,
    key: &str,
) -> Result<()> {
    let eigenvalues = limpid_core::criteria::symmetric_part_eigenvalues(m);
    let smallest = eigenvalues.iter().copied().fold(f64::INFINITY, f64::min);
    if smallest >= least {
        return Ok(());
    }
    let why = if smallest > 0.0 {
        format!("below a limb's floor of {}", limpid_core::error::Num(least))
    } else {
        "not positive definite (indefinite or negative: not a passive limb)".into()
    };
    Err(Error::Format {
        path: path.to_path_buf(),
        message: format!(
            "{key}: the smallest eigenvalue of its symmetric part is {}: {why}",
            limpid_core::error::Num(smallest)
        ),
    })
}

impl Prior {
    /// Read a prior subject file: 3 x 3 `inertia`, `damping`, `stiffness`
    /// (SI), optional `start_m`, `[other_end]` (the same three matrices),
    /// `[noise]` (default: [`NoiseModel::realistic`], a human subject) and
    /// `[limits]` (the centre-out protocol's limits table).
    pub fn from_toml(text: &str, path: &Path) -> Result<Prior> {
        limpid_lab::validate::check_numbers(text, path)?;
        let f: PriorFile = limpid_lab::validate::parse_settings(text, path)?;
        let nominal = impedance(&f.inertia, &f.damping, &f.stiffness, path, "")?;
        let other_end = f
            .other_end
            .as_ref()
            .map(|o| impedance(&o.inertia, &o.damping, &o.stiffness, path, "other_end."))
            .transpose()?;
        let noise = f.noise.unwrap_or_else(NoiseModel::realistic);
        noise.check().map_err(|message| Error::Format {
            path: path.to_path_buf(),
            message: format!("[noise] {message}"),
        })?;
        let start = f.start_m.map(Vector3::from);
        let limits = f.limits;
        Ok(Prior {
            start,
            nominal,
            other_end,
            noise,
            limits,
        })
    }

    /// The demo's realistic subject at start point `index` (0: S1): seed 000
    /// Table I subject 1 with Table II's antisymmetric stiffness and
    /// [`NoiseModel::realistic`].
    pub fn demo(index: usize) -> Prior {
        let mut p = limpid_lab::seed000_subject1().remove(index % 6);
        p.stiffness += limpid_lab::realistic::antisymmetric_part(
            limpid_lab::realistic::SEED000_K_MAX_A[index % 6],
        );
        Prior {
            start: Some(p.start),
            nominal: Impedance {
                inertia: p.inertia,
                damping: p.damping,
                stiffness: p.stiffness,
            },
            other_end: None,
            noise: NoiseModel::realistic(),
            limits: None,
        }
    }

    /// The posture: `start`, else the origin (a request resolves it against
    /// its limits before any use: see [`design`]).
    pub fn start(&self) -> Vector3<f64> {
        self.start.unwrap_or_default()
    }

    fn ends(&self) -> Vec<Impedance> {
        std::iter::once(self.nominal)
            .chain(self.other_end)
            .collect()
    }

    /// The nominal subject and the other end of the range, if any.
    fn range(&self) -> (&Impedance, Option<&Impedance>) {
        (&self.nominal, self.other_end.as_ref())
    }

    fn posture(&self, imp: &Impedance) -> Posture {
        Posture {
            name: "S1".into(),
            start: self.start(),
            inertia: imp.inertia,
            damping: imp.damping,
            stiffness: imp.stiffness,
        }
    }
}

fn workspace_centre(l: &Limits) -> Vector3<f64> {
    Vector3::from_fn(|i, _| 0.5 * (l.workspace_min_m[i] + l.workspace_max_m[i]))
}

/// How a design is robust to the prior's range (`[other_end]`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum Robustness {
    /// The worse of the range's two ends (minimax): the prediction is the
    /// worse end's, conservative for the subjects between.
    #[default]
    WorstCase,
    /// The mean over the range (its ends and midpoint, equally weighted):
    /// the prediction is the range's average.
    Expected,
}

impl Robustness {
    /// `worst` or `expected`.
    pub fn parse(text: &str) -> std::result::Result<Robustness, String> {
        match text {
            "worst" | "worst-case" => Ok(Robustness::WorstCase),
            "expected" => Ok(Robustness::Expected),
            other => Err(format!("{other:?}: expected worst or expected")),
        }
    }

    /// The name a result records.
    pub fn name(self) -> &'static str {
        match self {
            Robustness::WorstCase => "worst-case",
            Robustness::Expected => "expected",
        }
    }
}

/// The subjects a design is ranked and predicted on: the prior's ends for
/// the worst case, its ends and midpoint for the expectation.
pub(crate) fn range_subjects<S: Truth + Clone>(
    nominal: &S,
    other_end: Option<&S>,
    robust: Robustness,
) -> Vec<S> {
    match (other_end, robust) {
        (None, _) => vec![nominal.clone()],
        (Some(o), Robustness::WorstCase) => vec![nominal.clone(), o.clone()],
        (Some(o), Robustness::Expected) => {
            vec![nominal.clone(), nominal.blend(o, 0.5), o.clone()]
        }
    }
}

/// Weights of K, B, M in the objective, and how it meets the prior's range.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Objective {
    /// Of K.
    pub stiffness: f64,
    /// Of B.
    pub damping: f64,
    /// Of M.
    pub inertia: f64,
    /// Worst case or expectation over the prior's range.
    pub robust: Robustness,
}

impl Default for Objective {
    /// Stiffness and damping, equally.
    fn default() -> Self {
        Objective {
            stiffness: 1.0,
            damping: 1.0,
            inertia: 0.0,
            robust: Robustness::WorstCase,
        }
    }
}

impl Objective {
    /// `stiffness,damping` (weight 1 each) or `stiffness=2,damping=1`.
    pub fn parse(text: &str) -> std::result::Result<Objective, String> {
        let mut o = Objective {
            stiffness: 0.0,
            damping: 0.0,
            inertia: 0.0,
            robust: Robustness::WorstCase,
        };
        for part in text.split(',').map(str::trim).filter(|p| !p.is_empty()) {
            let (name, weight) = match part.split_once('=') {
                Some((n, w)) => {
                    let w: f64 = w
                        .trim()
                        .parse()
                        .map_err(|_| format!("{part:?}: the weight after '=' is not a number"))?;
                    (n.trim(), w)
                }
                None => (part, 1.0),
            };
            if !(weight >= 0.0 && weight.is_finite()) {
                return Err(format!("{part:?}: a weight is zero or a positive number"));
            }
            match name {
                "stiffness" => o.stiffness = weight,
                "damping" => o.damping = weight,
                "inertia" => o.inertia = weight,
                other => {
                    return Err(format!(
                        "{other:?} is not a parameter of the linear method; expected stiffness, damping or inertia"
                    ))
                }
            }
        }
        if o.stiffness + o.damping + o.inertia <= 0.0 {
            return Err("no parameter has a positive weight".into());
        }
        Ok(o)
    }

    fn weights(&self) -> [f64; 3] {
        [self.stiffness, self.damping, self.inertia]
    }

    /// As a result records it.
    pub(crate) fn recorded(&self) -> ObjectiveWeights {
        ObjectiveWeights {
            stiffness: self.stiffness,
            damping: self.damping,
            inertia: self.inertia,
            robust: self.robust.name().into(),
        }
    }
}

/// A design request: the prior `P`, the limits `L` and the baseline
/// protocol `B` of the method's family (the linear method's by default: an
/// end-point prior, centre-out limits and protocol;
/// [`stochastic::StochasticDesignRequest`] holds a periodic protocol's,
/// [`planar::PlanarDesignRequest`] a planar arm's).
#[derive(Debug, Clone)]
pub struct DesignRequest<L = Limits, B = Protocol, P = Prior> {
    /// The prior subject.
    pub prior: P,
    /// The limits.
    pub limits: L,
    /// Sample rate of the designed protocol (Hz).
    pub sample_rate_hz: f64,
    /// The whole protocol's length (s).
    pub budget_s: f64,
    /// What matters.
    pub objective: Objective,
    /// Recordings simulated for the chosen design's prediction (and the baseline's).
    pub runs: usize,
    /// The protocol it replaces, if any (a centre-out one's start points are replaced by the prior's).
    pub baseline: Option<B>,
    /// Recordings on subjects drawn from the prior to check the prediction (0: none).
    pub verify: usize,
    /// Seed of the noise.
    pub seed: u64,
}

impl DesignInputs<'_> {
    /// A method's request from its prior, limits, sample rate and baseline;
    /// the budget, objective (parsed), runs, verification and seed are these inputs'.
    pub(crate) fn request<L, B, P>(
        &self,
        prior: P,
        (limits, sample_rate_hz): (L, f64),
        baseline: Option<B>,
    ) -> Result<DesignRequest<L, B, P>> {
        Ok(DesignRequest {
            prior,
            limits,
            sample_rate_hz,
            budget_s: self.budget_s,
            objective: Objective {
                robust: Robustness::parse(self.robust).map_err(|e| Error::invalid("robust", e))?,
                ..Objective::parse(self.objective).map_err(|e| Error::invalid("objective", e))?
            },
            runs: self.runs,
            baseline,
            verify: self.verify,
            seed: self.seed,
        })
    }
}

/// A periodic baseline is simulated `runs` times: at most [`MAX_DESIGN_SAMPLES`].
pub(crate) fn check_periodic_baseline(b: &limpid_lab::periodic::PeriodicDesign) -> Result<()> {
    // its size from its fields before any sample is made (a period of 2000 s
    // was generated and simulated for 31 s before a refusal; issue 76)
    b.validate().map_err(|m| Error::invalid("baseline", m))?;
    let declared = (b.period_samples() * (b.periods + 2)) as f64;
    if declared > MAX_DESIGN_SAMPLES {
        return Err(Error::invalid(
            "baseline",
            format!("{declared:.0} samples; a baseline is simulated `runs` times and may hold at most {MAX_DESIGN_SAMPLES:.0}"),
        ));
    }
    if b.periods < 2 {
        return Err(Error::invalid(
            "baseline",
            format!(
                "{} period: the period-to-period scatter its prediction rests on needs at least 2",
                b.periods
            ),
        ));
    }
    let samples = b.check()?.samples as f64;
    if samples > MAX_DESIGN_SAMPLES {
        return Err(Error::invalid(
            "baseline",
            format!("{samples:.0} samples; a baseline is simulated `runs` times and may hold at most {MAX_DESIGN_SAMPLES:.0}"),
        ));
    }
    Ok(())
}

/// A file's text and its path (for errors).
pub type Text<'a> = (&'a str, &'a Path);

/// What a linear, stochastic or planar design is asked, as the CLI's flags
/// and Python's arguments give it: texts, to be read by the method's own
/// request.
#[derive(Debug, Clone, Copy)]
pub struct DesignInputs<'a> {
    /// The prior: `demo:...`, or a prior file's text.
    pub prior: Text<'a>,
    /// The protocol whose limits are taken, if any.
    pub limits_from: Option<Text<'a>>,
    /// The protocol the design replaces, if any.
    pub baseline: Option<Text<'a>>,
    /// The whole protocol's length (s).
    pub budget_s: f64,
    /// What matters: `stiffness,damping` or weights.
    pub objective: &'a str,
    /// Over the prior's range: `worst` or `expected`.
    pub robust: &'a str,
    /// Recordings behind the prediction.
    pub runs: usize,
    /// Recordings on subjects drawn from the prior to check it (0: none).
    pub verify: usize,
    /// Seed of the noise.
    pub seed: u64,
}

/// A prior from its text: `demo:S1` .. `demo:S6`, or a prior file's text.
pub(crate) fn read_prior(prior: Text<'_>) -> Result<Prior> {
    match prior.0.strip_prefix("demo:") {
        Some(point) => {
            let index = point
                .strip_prefix('S')
                .and_then(|i| i.parse::<usize>().ok())
                .filter(|i| (1..=6).contains(i))
                .ok_or_else(|| {
                    Error::invalid("prior", format!("{}: expected demo:S1 .. demo:S6", prior.0))
                })?;
            Ok(Prior::demo(index - 1))
        }
        None => Prior::from_toml(prior.0, prior.1),
    }
}

/// A design request from its texts, as the CLI and Python take it: the prior
/// (`demo:S1` .. `demo:S6`, or a prior file's text), the limits from a
/// centre-out protocol (else the prior's `[limits]`), the baseline protocol.
/// The sample rate is the limits protocol's, else the baseline's, else 500 Hz.
pub fn request_from_texts(inputs: &DesignInputs<'_>) -> Result<DesignRequest> {
    let DesignInputs {
        prior,
        limits_from,
        baseline,
        ..
    } = *inputs;
    let prior_text = prior;
    let prior = read_prior(prior)?;
    let centre_out = |(text, path): Text<'_>, role: &str| -> Result<Protocol> {
        match limpid_lab::design::Design::from_toml(text, path)? {
            limpid_lab::design::Design::CentreOut(p) => Ok(p),
            _ => Err(Error::Format {
                path: path.to_path_buf(),
                message: format!(
                    "{role} must be a centre-out protocol (the design is for the linear method)"
                ),
            }),
        }
    };
    let limits_from = limits_from
        .map(|t| centre_out(t, "the limits' protocol"))
        .transpose()?;
    let baseline = baseline
        .map(|t| centre_out(t, "the baseline"))
        .transpose()?;
    let (limits, sample_rate_hz) = match (&limits_from, &prior.limits) {
        (Some(p), _) => (p.limits.clone(), p.sample_rate_hz),
        (None, Some(l)) => (
            l.clone(),
            baseline.as_ref().map_or(500.0, |b| b.sample_rate_hz),
        ),
        (None, None) => return Err(Error::invalid(
            "limits_from",
            "no limits: take them from a centre-out protocol or give a [limits] table in the prior",
        )),
    };
    let request = inputs.request(prior, (limits, sample_rate_hz), baseline)?;
    check_request(&request)?;
    check_noise_at(&request.prior, prior_text, request.sample_rate_hz)?;
    Ok(request)
}

/// A linear (centre-out), stochastic (end-point multisine) or planar
/// (quintic joint steps) design from its texts, as the CLI and Python take
/// them: the designed protocol's TOML text, its `kind` first, and the result
/// (`design`, or `planar_design`).
pub fn design_from_texts(
    method: &str,
    inputs: &DesignInputs<'_>,
) -> Result<(String, limpid_analysis::result::Estimate)> {
    use limpid_analysis::result::Estimate;
    match method {
        "linear" => {
            let designed = design(&request_from_texts(inputs)?)?;
            Ok((
                format!("kind = \"centre-out\"\n{}", designed.protocol.to_toml()),
                Estimate::Design(designed.result),
            ))
        }
        "stochastic" => {
            let request = stochastic::stochastic_request_from_texts(inputs)?;
            let designed = stochastic::design_stochastic(&request)?;
            Ok((
                limpid_lab::design::Design::Periodic(designed.protocol).to_toml(),
                Estimate::Design(designed.result),
            ))
        }
        "planar" => {
            let designed = planar::design_planar(&planar::planar_request_from_texts(inputs)?)?;
            Ok((
                limpid_lab::design::Design::Planar(designed.protocol).to_toml(),
                Estimate::PlanarDesign(designed.result),
            ))
        }
        other => Err(Error::invalid(
            "method",
            format!("{other:?}: expected linear, stochastic or planar"),
        )),
    }
}

/// The prior's `[noise]` at the design's sample rate (a tremor the rate
/// cannot hold), named to the prior file: found only when simulated, it
/// refused every candidate and read as "no protocol fits".
pub(crate) fn check_noise_at(prior: &Prior, text: Text<'_>, rate_hz: f64) -> Result<()> {
    prior
        .noise
        .check_at(rate_hz)
        .map_err(|message| match text.0 {
            t if t.starts_with("demo:") => Error::invalid("prior", format!("[noise] {message}")),
            _ => Error::Format {
                path: text.1.to_path_buf(),
                message: format!("[noise] {message}"),
            },
        })
}

/// The designed protocol and its result.
pub struct Designed {
    /// The protocol (single start point: the prior's).
    pub protocol: Protocol,
    /// Everything measured about it.
    pub result: DesignResult,
}

#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
struct Choice {
    profile: usize,
    radius: usize,
    slowness: usize,
    hold: usize,
    rest: usize,
}

impl Grid for Choice {
    const SIZES: &'static [usize] = &[
        PROFILES.len(),
        RADIUS_SHARES.len(),
        SLOWNESS.len(),
        HOLDS_S.len(),
        RESTS_S.len(),
    ];

    fn with(&self, dim: usize, value: usize) -> Choice {
        let mut c = *self;
        match dim {
            0 => c.profile = value,
            1 => c.radius = value,
            2 => c.slowness = value,
            3 => c.hold = value,
            _ => c.rest = value,
        }
        c
    }
}

/// Checked inputs the search works from.
struct Space<'a> {
    req: &'a DesignRequest,
    largest_radius: f64,
}

impl Space<'_> {
    /// The protocol of a choice, or why it is refused.
    /// The protocol of a choice and its trials (directions spread once), or why it is refused.
    fn protocol(&self, c: &Choice) -> std::result::Result<(Protocol, CentreOut), String> {
        let req = self.req;
        let l = &req.limits;
        let profile = PROFILES[c.profile];
        let radius = RADIUS_SHARES[c.radius] * self.largest_radius;
        let (_, v_peak, a_peak) = profile.peaks(1.0);
        let shortest = (radius * v_peak / (LIMIT_MARGIN * l.max_velocity_m_s))
            .max((radius * a_peak / (LIMIT_MARGIN * l.max_acceleration_m_s2)).sqrt());
        let motion = shortest * SLOWNESS[c.slowness];
        let (hold, rest) = (HOLDS_S[c.hold], RESTS_S[c.rest]);
        let trial = rest + motion + hold + motion + RELAX_S;
        let trials = ((req.budget_s / trial).floor() as usize)
            .min(limpid_lab::validate::MAX_TARGETS as usize);
        if trials < MIN_TRIALS {
            return Err(format!(
                "{trials} perturbations of {trial:.2} s fit in {} s; at least {MIN_TRIALS} are needed",
                req.budget_s
            ));
        }
        let p = Protocol {
            name: format!(
                "designed by limpid protocol design: {trials} {} perturbations of {:.1} mm, {:.0} ms out and back",
                format!("{profile:?}").to_lowercase(),
                radius * 1e3,
                motion * 1e3
            ),
            sample_rate_hz: req.sample_rate_hz,
            start_points: StartPoints {
                points: vec![req.prior.start().into()],
                centre_m: [0.0; 3],
                radius_m: 0.0,
            },
            targets: Targets {
                count: trials,
                radius_m: radius,
            },
            phases: Phases {
                profile,
                rest_s: rest,
                centre_out_s: motion,
                hold_s: hold,
                return_s: motion,
                relax_s: RELAX_S,
                record_hold_and_return: true,
                trials_per_set: 0,
                set_rest_s: 0.0,
            },
            limits: l.clone(),
            robot_base: None,
        };
        let centre_out = p.centre_out();
        let peak = peak_force(&p, &centre_out.directions, &req.prior);
        if peak > LIMIT_MARGIN * l.max_force_n {
            return Err(format!(
                "force {peak:.1} N on the prior exceeds the limit {} N",
                l.max_force_n
            ));
        }
        Ok((p, centre_out))
    }
}

/// Largest force `|M a + B v + K x|` the protocol needs on either end of the prior (N).
fn peak_force(p: &Protocol, dirs: &[Vector3<f64>], prior: &Prior) -> f64 {
    let d = p.phases.centre_out_s;
    let r = p.targets.radius_m;
    let mut peak = 0.0f64;
    for imp in prior.ends() {
        for k in 0..=200 {
            let (s, v, a) = p.phases.profile.eval(d * k as f64 / 200.0, d);
            for dir in dirs {
                let f = imp.inertia * dir * (r * a)
                    + imp.damping * dir * (r * v)
                    + imp.stiffness * dir * (r * s);
                peak = peak.max(f.norm());
            }
        }
    }
    peak
}

/// The largest radius the displacement, force and workspace limits allow at the prior's start.
fn largest_radius(req: &DesignRequest) -> Result<f64> {
    let l = &req.limits;
    let s = req.prior.start();
    let room = (0..3)
        .map(|i| (s[i] - l.workspace_min_m[i]).min(l.workspace_max_m[i] - s[i]))
        .fold(f64::INFINITY, f64::min);
    if room <= 0.0 {
        return Err(Error::invalid(
            "prior",
            format!(
                "start_m [{:.3}, {:.3}, {:.3}] is not inside the workspace",
                s[0], s[1], s[2]
            ),
        ));
    }
    // the stiffest direction's static force K r must stay below the force limit
    let stiffest = req
        .prior
        .ends()
        .iter()
        .map(|imp| imp.stiffness.norm())
        .fold(l.nominal_stiffness_n_per_m, f64::max);
    let radius = l.max_displacement_m.min(room).min(l.max_force_n / stiffest) * LIMIT_MARGIN;
    if radius < LEAST_RADIUS_M {
        return Err(Error::invalid(
            "prior",
            format!(
                "the limits leave a largest displacement of {radius:.3e} m (force {} N at a stiffness norm of {stiffest:.4e} N/m, displacement {} m, workspace room {room:.3} m); nothing below {LEAST_RADIUS_M} m can be designed",
                l.max_force_n, l.max_displacement_m
            ),
        ));
    }
    Ok(radius)
}

/// Errors of one recording's estimate against the truth, K, B, M (planar: K, D, ξ).
pub(crate) struct Run {
    errors: [DMatrix<f64>; 3],
    /// Relative Frobenius error of each group against the subject's own (percent).
    error_percent: [f64; 3],
    identifiable: [bool; 3],
}

impl Run {
    /// An estimate's three groups (`Matrix`, SI, shaped as `truth`'s) and
    /// whether each was identifiable, against `truth`.
    pub(crate) fn new(estimate: [&Matrix; 3], identifiable: [bool; 3], truth: &impl Truth) -> Run {
        let truth = truth.groups();
        let errors: [DMatrix<f64>; 3] = std::array::from_fn(|m| &estimate[m].0 - &truth[m]);
        Run {
            error_percent: std::array::from_fn(|m| 100.0 * errors[m].norm() / truth[m].norm()),
            errors,
            identifiable,
        }
    }
}

fn run_once(p: &CentreOut, prior: &Prior, imp: &Impedance, seed: u64) -> Result<Run> {
    let posture = prior.posture(imp);
    let rec = simulate_centre_out(&posture, p, &prior.noise, seed)?;
    let prepared = prepare(&rec, &PrepareParams::default())?;
    let est: LinearEstimate = fit_linear(&prepared, &LinearParams::default())?;
    Ok(Run::new(
        [&est.stiffness, &est.damping, &est.inertia],
        [
            est.identifiable.stiffness,
            est.identifiable.damping,
            est.identifiable.inertia,
        ],
        imp,
    ))
}

/// One simulated recording's errors on subject `S` with noise seed `seed`:
/// the family's simulation and the method's estimator.
pub(crate) trait Runner<S>: Fn(&S, u64) -> Result<Run> + Sync {}
impl<S, F: Fn(&S, u64) -> Result<Run> + Sync> Runner<S> for F {}

/// Recordings of one subject, one per seed, in parallel.
fn runs<S: Truth>(run: &impl Runner<S>, subject: &S, seeds: &[u64]) -> Result<Vec<Run>> {
    seeds.par_iter().map(|&s| run(subject, s)).collect()
}

/// One subject's recordings, its parameter groups and the objective's value on them.
struct Evaluated {
    runs: Vec<Run>,
    truth: [DMatrix<f64>; 3],
    value: f64,
}

/// Every subject's recordings on `seeds`, each judged by the objective once.
fn evaluate<S: Truth>(
    run: &impl Runner<S>,
    subjects: &[S],
    objective: &Objective,
    seeds: &[u64],
) -> Result<Vec<Evaluated>> {
    subjects
        .iter()
        .map(|subject| {
            let rs = runs(run, subject, seeds)?;
            let truth = subject.groups();
            let value = objective_value(&relative_mse(&rs, &truth), objective.weights());
            Ok(Evaluated {
                runs: rs,
                truth,
                value,
            })
        })
        .collect()
}

/// The objective over the ranking seeds on `subjects` (the worse one's, or
/// their mean: `objective.robust`), or why the candidate is refused.
pub(crate) fn rank<S: Truth>(
    run: &impl Runner<S>,
    subjects: &[S],
    objective: &Objective,
    seeds: &[u64],
) -> std::result::Result<f64, String> {
    let value = evaluate(run, subjects, objective, seeds).map(|e| match objective.robust {
        Robustness::WorstCase => e.iter().fold(0.0f64, |a, b| a.max(b.value)),
        Robustness::Expected => e.iter().map(|b| b.value).sum::<f64>() / e.len().max(1) as f64,
    });
    match value {
        Ok(v) if v.is_finite() => Ok(v),
        Ok(v) => Err(format!("objective {v}")),
        Err(e) => Err(e.to_string()),
    }
}

/// Mean squared error of each group's elements relative to its RMS element
/// in `truth` (percent²).
fn relative_mse(runs: &[Run], truth: &[DMatrix<f64>; 3]) -> [f64; 3] {
    std::array::from_fn(|m| {
        let scale = truth[m].norm_squared() / truth[m].len() as f64;
        let mse = runs
            .iter()
            .map(|r| r.errors[m].norm_squared() / truth[m].len() as f64)
            .sum::<f64>()
            / runs.len() as f64;
        1e4 * mse / scale
    })
}

fn objective_value(rel: &[f64; 3], w: [f64; 3]) -> f64 {
    (0..3).map(|m| w[m] * rel[m]).sum()
}

/// Element-wise s.d. over runs of each group.
fn spread(runs: &[Run]) -> [DMatrix<f64>; 3] {
    let n = runs.len() as f64;
    std::array::from_fn(|m| {
        let shape = runs[0].errors[m].shape();
        let zero = DMatrix::<f64>::zeros(shape.0, shape.1);
        let mean = runs.iter().fold(zero.clone(), |a, r| a + &r.errors[m]) / n;
        let var = runs
            .iter()
            .fold(zero, |a, r| a + (&r.errors[m] - &mean).map(|v| v * v))
            / (n - 1.0).max(1.0);
        var.map(f64::sqrt)
    })
}

/// RMS of each group's element s.d.
fn pooled_se(se: &[DMatrix<f64>; 3]) -> [f64; 3] {
    std::array::from_fn(|m| (se[m].norm_squared() / se[m].len() as f64).sqrt())
}

/// The prediction of a protocol of `duration_s` whose recordings `run`
/// makes on `subjects`: the worse one's by the objective, or (`Expected`)
/// the range's average: element variances, errors and shares averaged over
/// the subjects, relative figures against their mean RMS element.
pub(crate) fn predict<S: Truth>(
    run: &impl Runner<S>,
    duration_s: f64,
    subjects: &[S],
    objective: &Objective,
    seeds: &[u64],
) -> Result<Prediction> {
    let evaluated = evaluate(run, subjects, objective, seeds)?;
    let pick: Vec<&Evaluated> = match objective.robust {
        Robustness::Expected => evaluated.iter().collect(),
        // the worse subject; the first of equals
        Robustness::WorstCase => evaluated
            .iter()
            .fold(None::<&Evaluated>, |worst, e| match worst {
                Some(w) if w.value >= e.value => Some(w),
                _ => Some(e),
            })
            .into_iter()
            .collect(),
    };
    if pick.is_empty() {
        return Err(Error::invalid("prior", "no subject to predict on"));
    }
    let k = pick.len() as f64;
    // element variances averaged over the subjects picked
    let spreads: Vec<[DMatrix<f64>; 3]> = pick.iter().map(|e| spread(&e.runs)).collect();
    let se: [DMatrix<f64>; 3] = std::array::from_fn(|m| {
        let var = spreads
            .iter()
            .map(|s| s[m].map(|v| v * v))
            .reduce(|a, b| a + b)
            .expect("at least one subject");
        (var / k).map(f64::sqrt)
    });
    let pooled = pooled_se(&se);
    let rms: [f64; 3] = std::array::from_fn(|m| {
        pick.iter()
            .map(|e| e.truth[m].norm() / (e.truth[m].len() as f64).sqrt())
            .sum::<f64>()
            / k
    });
    let all: Vec<&Run> = pick.iter().flat_map(|e| e.runs.iter()).collect();
    let n = all.len() as f64;
    let [stiffness_se, damping_se, inertia_se] = se.map(Matrix);
    Ok(Prediction {
        stiffness_se,
        damping_se,
        inertia_se,
        pooled: Pooled {
            se: pooled,
            se_percent: std::array::from_fn(|m| 100.0 * pooled[m] / rms[m]),
            error_percent: std::array::from_fn(|m| {
                all.iter().map(|r| r.error_percent[m]).sum::<f64>() / n
            }),
        },
        runs: seeds.len(),
        duration_s,
        identifiable_share: std::array::from_fn(|m| {
            all.iter().filter(|r| r.identifiable[m]).count() as f64 / n
        }),
    })
}

/// A point of a family's grid of choices: an index into each dimension's list.
pub(crate) trait Grid: Copy + Eq + std::hash::Hash {
    /// Each dimension's number of values.
    const SIZES: &'static [usize];
    /// This point with dimension `dim` set to `value`.
    fn with(&self, dim: usize, value: usize) -> Self;
}

/// A grid search's outcome.
pub(crate) struct Searched<C> {
    /// The chosen point.
    pub(crate) best: C,
    /// Its objective.
    pub(crate) objective: f64,
    /// Candidates evaluated.
    pub(crate) candidates: usize,
    /// Candidates refused (a limit, the budget, the estimator).
    pub(crate) refused: usize,
}

/// Coordinate descent over a family's grid from `start`: at most four
/// sweeps, each trying every value of every dimension around the best so
/// far. `evaluate` gives a candidate's objective or why it is refused;
/// `family` names what is searched when nothing fits.
pub(crate) fn coordinate_descent<C: Grid>(
    start: C,
    family: &str,
    mut evaluate: impl FnMut(&C) -> std::result::Result<f64, String>,
) -> Result<Searched<C>> {
    let mut seen: HashMap<C, Option<f64>> = HashMap::new();
    let (mut refused, mut last_refusal) = (0usize, String::new());
    let mut value_of = |c: C, seen: &mut HashMap<C, Option<f64>>| {
        *seen.entry(c).or_insert_with(|| match evaluate(&c) {
            Ok(v) => Some(v),
            Err(why) => {
                refused += 1;
                last_refusal = why;
                None
            }
        })
    };
    let mut best = start;
    let mut best_value = value_of(best, &mut seen);
    for _sweep in 0..4 {
        let before = best;
        for (dim, &size) in C::SIZES.iter().enumerate() {
            for value in 0..size {
                let c = best.with(dim, value);
                if c == best {
                    continue;
                }
                if let Some(v) = value_of(c, &mut seen) {
                    if best_value.is_none_or(|b| v < b) {
                        best = c;
                        best_value = Some(v);
                    }
                }
            }
        }
        if best == before {
            break;
        }
    }
    match best_value {
        Some(objective) => Ok(Searched {
            best,
            objective,
            candidates: seen.len(),
            refused,
        }),
        None => Err(Error::invalid(
            "design",
            format!("no {family} fits the limits and the budget: {last_refusal}"),
        )),
    }
}

/// Length of a centre-out protocol at one start point (s), every phase counted.
pub fn protocol_duration(p: &Protocol) -> f64 {
    let ph = &p.phases;
    let per = ph.rest_s + ph.centre_out_s + ph.hold_s + ph.return_s + ph.relax_s;
    let sets = if ph.trials_per_set > 0 {
        p.targets.count.div_ceil(ph.trials_per_set)
    } else {
        1
    };
    per * p.targets.count as f64 + ph.set_rest_s * sets.saturating_sub(1) as f64
}

pub(crate) fn seeds(base: u64, offset: u64, n: usize) -> Vec<u64> {
    (0..n as u64)
        .map(|i| base.wrapping_mul(1_000_003).wrapping_add(offset + i))
        .collect()
}

fn margins(p: &Protocol, centre_out: &CentreOut, prior: &Prior) -> Vec<LimitMargin> {
    let l = &p.limits;
    let r = p.targets.radius_m;
    let (_, v, a) = p.phases.profile.peaks(p.phases.centre_out_s);
    let s = prior.start();
    let room = (0..3)
        .map(|i| (s[i] - l.workspace_min_m[i]).min(l.workspace_max_m[i] - s[i]))
        .fold(f64::INFINITY, f64::min);
    let entry = LimitMargin::new;
    vec![
        entry("displacement", "m", r, l.max_displacement_m),
        entry("velocity", "m/s", r * v, l.max_velocity_m_s),
        entry("acceleration", "m/s^2", r * a, l.max_acceleration_m_s2),
        entry(
            "force on the prior",
            "N",
            peak_force(p, &centre_out.directions, prior),
            l.max_force_n,
        ),
        entry(
            "force at the nominal stiffness",
            "N",
            l.nominal_stiffness_n_per_m * r,
            l.max_force_n,
        ),
        entry("distance to the workspace's edge used", "m", r, room),
    ]
}

/// Most simulated recordings behind a prediction or a verification.
pub const MAX_RUNS: usize = 1000;

/// A number of recordings for a spread: 2 to [`MAX_RUNS`] (or 0 when `optional`).
pub(crate) fn check_runs(name: &str, runs: usize, optional: bool) -> Result<()> {
    if optional && runs == 0 {
        return Ok(());
    }
    if runs < 2 {
        return Err(Error::invalid(
            name,
            format!(
                "at least 2 recordings are needed for a spread{}",
                if optional { " (0: none)" } else { "" }
            ),
        ));
    }
    if runs > MAX_RUNS {
        return Err(Error::invalid(
            name,
            format!("{runs} recordings: at most {MAX_RUNS}"),
        ));
    }
    Ok(())
}

/// Most samples a design's budget may hold at its sample rate: every
/// candidate is simulated and estimated several times over.
pub const MAX_DESIGN_SAMPLES: f64 = 5e6;

/// A time budget is positive and holds at most [`MAX_DESIGN_SAMPLES`] at `rate_hz`.
pub(crate) fn check_budget(budget_s: f64, rate_hz: f64) -> Result<()> {
    if !(budget_s > 0.0 && budget_s <= limpid_lab::validate::MAX_DURATION_S) {
        return Err(Error::invalid(
            "duration",
            format!(
                "{budget_s} s: expected a positive duration of at most {} s",
                limpid_lab::validate::MAX_DURATION_S
            ),
        ));
    }
    if budget_s * rate_hz > MAX_DESIGN_SAMPLES {
        return Err(Error::invalid(
            "duration",
            format!(
                "{budget_s} s at {rate_hz} Hz is {:.0} samples; a design simulates its candidates many times and takes at most {MAX_DESIGN_SAMPLES:.0} (design one session and repeat it)",
                budget_s * rate_hz
            ),
        ));
    }
    Ok(())
}

/// The request's numbers, before any simulation.
pub fn check_request(req: &DesignRequest) -> Result<()> {
    let l = &req.limits;
    for (name, v) in [
        ("max_displacement_m", l.max_displacement_m),
        ("max_velocity_m_s", l.max_velocity_m_s),
        ("max_acceleration_m_s2", l.max_acceleration_m_s2),
        ("max_force_n", l.max_force_n),
    ] {
        if !(v > 0.0 && v.is_finite()) {
            return Err(Error::invalid(
                "limits",
                format!("{name} = {v}: a limit is a positive number"),
            ));
        }
    }
    if !(req.sample_rate_hz > 0.0 && req.sample_rate_hz <= 10_000.0) {
        return Err(Error::invalid(
            "sample_rate_hz",
            format!("{} Hz: expected 0 < rate <= 10000", req.sample_rate_hz),
        ));
    }
    check_budget(req.budget_s, req.sample_rate_hz)?;
    if let Some(b) = &req.baseline {
        let samples = protocol_duration(b) * b.sample_rate_hz;
        if samples > MAX_DESIGN_SAMPLES {
            return Err(Error::invalid(
                "baseline",
                format!("{samples:.0} samples at one start point; a baseline is simulated `runs` times and may hold at most {MAX_DESIGN_SAMPLES:.0}"),
            ));
        }
    }
    check_runs("runs", req.runs, false)?;
    check_runs("verify", req.verify, true)?;
    Ok(())
}

/// Choose the protocol. Deterministic for a given request (seeded noise).
pub fn design(req: &DesignRequest) -> Result<Designed> {
    check_request(req)?;
    // a prior without a posture is designed for at the centre of the workspace
    let resolved;
    let req = match req.prior.start {
        Some(_) => req,
        None => {
            let mut r = req.clone();
            r.prior.start = Some(workspace_centre(&req.limits));
            resolved = r;
            &resolved
        }
    };
    let space = Space {
        req,
        largest_radius: largest_radius(req)?,
    };
    let ranking = seeds(req.seed, 0, RANKING_RUNS);
    let subjects = range_subjects(
        &req.prior.nominal,
        req.prior.other_end.as_ref(),
        req.objective.robust,
    );
    // start: the fastest cubic at 70 % of the largest radius, short hold, 0.4 s rest
    let start = Choice {
        profile: 0,
        radius: 3,
        slowness: 0,
        hold: 1,
        rest: 1,
    };
    let searched = coordinate_descent(start, "centre-out protocol", |c| {
        let (_, p) = space.protocol(c)?;
        // a candidate whose recordings the estimator refuses (or whose
        // objective is not a number) is refused, with the reason kept
        let run = |imp: &Impedance, s: u64| run_once(&p, &req.prior, imp, s);
        rank(&run, &subjects, &req.objective, &ranking)
    })?;
    let (best, objective) = (searched.best, searched.objective);
    let (protocol, trials) = space
        .protocol(&best)
        .map_err(|why| Error::invalid("design", why))?;
    // the sample-by-sample check `limpid protocol check` makes (the search kept
    // every limit with a margin on the continuous profile)
    protocol::check(&protocol)?;
    let final_seeds = seeds(req.seed, 10_000, req.runs);
    let run = |imp: &Impedance, s: u64| run_once(&trials, &req.prior, imp, s);
    let predicted = predict(
        &run,
        protocol_duration(&protocol),
        &subjects,
        &req.objective,
        &final_seeds,
    )?;
    let baseline = req
        .baseline
        .as_ref()
        .map(|b| {
            let mut b = b.clone();
            b.start_points = StartPoints {
                points: vec![req.prior.start().into()],
                centre_m: [0.0; 3],
                radius_m: 0.0,
            };
            let trials = b.centre_out();
            let run = |imp: &Impedance, s: u64| run_once(&trials, &req.prior, imp, s);
            predict(
                &run,
                protocol_duration(&b),
                &subjects,
                &req.objective,
                &final_seeds,
            )
        })
        .transpose()?;
    let verify = (req.verify > 0)
        .then(|| verify(&run, req.prior.range(), &predicted, req.verify, req.seed))
        .transpose()?;
    let ph = &protocol.phases;
    let result = DesignResult {
        method: "linear".into(),
        family: "centre-out".into(),
        objective: req.objective.recorded(),
        budget_s: req.budget_s,
        start_m: req.prior.start().into(),
        chosen: DesignChoice::CentreOut(CentreOutChoice {
            profile: format!("{:?}", ph.profile).to_lowercase(),
            radius_m: protocol.targets.radius_m,
            motion_s: ph.centre_out_s,
            hold_s: ph.hold_s,
            rest_s: ph.rest_s,
            relax_s: ph.relax_s,
            trials: protocol.targets.count,
            duration_s: protocol_duration(&protocol),
        }),
        predicted,
        baseline,
        protocol: serde_json::to_value(&protocol)
            .map_err(|e| Error::invalid("protocol", e.to_string()))?,
        limits: margins(&protocol, &trials, &req.prior),
        search: SearchSummary {
            candidates: searched.candidates,
            runs_per_candidate: RANKING_RUNS,
            refused: searched.refused,
            objective,
        },
        verify,
        command: command_trace(&protocol),
        spectrum: CommandSpectrum {
            frequency_hz: SPECTRUM_HZ.to_vec(),
            designed_m: amplitude_spectrum(&protocol),
            baseline_m: req.baseline.as_ref().map(amplitude_spectrum),
            limit_m: limit_envelope(
                protocol.limits.max_displacement_m,
                protocol.limits.max_velocity_m_s,
                protocol.limits.max_acceleration_m_s2,
            ),
        },
    };
    Ok(Designed { protocol, result })
}

/// Frequencies of the command spectrum: 0.1 to 30 Hz, 60 log-spaced.
const SPECTRUM_HZ: [f64; 60] = {
    let mut f = [0.0; 60];
    let mut i = 0;
    // 0.1 * 300^(i / 59), by repeated multiplication (const fn has no powf)
    let ratio = 1.101_501_533_257_344; // 300^(1/59)
    let mut v = 0.1;
    while i < 60 {
        f[i] = v;
        v *= ratio;
        i += 1;
    }
    f
};

/// Displacement, velocity and acceleration along the direction of one trial.
fn trial_path(p: &Protocol, t: f64) -> (f64, f64, f64) {
    let ph = &p.phases;
    let r = p.targets.radius_m;
    let (s1, v1, a1) = ph.profile.eval(t - ph.rest_s, ph.centre_out_s);
    let (s2, v2, a2) = ph
        .profile
        .eval(t - ph.rest_s - ph.centre_out_s - ph.hold_s, ph.return_s);
    (r * (s1 - s2), r * (v1 - v2), r * (a1 - a2))
}

fn trial_length(p: &Protocol) -> f64 {
    let ph = &p.phases;
    ph.rest_s + ph.centre_out_s + ph.hold_s + ph.return_s + ph.relax_s
}

fn command_trace(p: &Protocol) -> CommandTrace {
    let n = ((trial_length(p) * p.sample_rate_hz).round() as usize).clamp(2, 2000);
    let t: Vec<f64> = (0..n)
        .map(|i| trial_length(p) * i as f64 / (n - 1) as f64)
        .collect();
    let path: Vec<(f64, f64, f64)> = t.iter().map(|&t| trial_path(p, t)).collect();
    CommandTrace {
        displacement_m: path.iter().map(|v| v.0).collect(),
        velocity_m_s: path.iter().map(|v| v.1).collect(),
        acceleration_m_s2: path.iter().map(|v| v.2).collect(),
        t_s: t,
    }
}

/// `2 |X(f)| / T` of one trial's displacement at [`SPECTRUM_HZ`].
fn amplitude_spectrum(p: &Protocol) -> Vec<f64> {
    let length = trial_length(p);
    let n = ((length * p.sample_rate_hz).round() as usize).max(2);
    let dt = length / n as f64;
    let x: Vec<f64> = (0..n).map(|i| trial_path(p, i as f64 * dt).0).collect();
    sine_amplitudes(&x, dt)
}

/// `2 |X(f)| / n` of the samples `x`, `dt` apart, at [`SPECTRUM_HZ`]: the
/// amplitude a sine filling them would have.
pub(crate) fn sine_amplitudes(x: &[f64], dt: f64) -> Vec<f64> {
    SPECTRUM_HZ
        .iter()
        .map(|f| {
            let w = std::f64::consts::TAU * f * dt;
            let (re, im) = x.iter().enumerate().fold((0.0, 0.0), |(re, im), (i, v)| {
                let phase = w * i as f64;
                (re + v * phase.cos(), im - v * phase.sin())
            });
            2.0 * re.hypot(im) / x.len() as f64
        })
        .collect()
}

/// The largest sine amplitude a displacement, velocity and acceleration
/// limit allow at each of [`SPECTRUM_HZ`]: `min(d, v / ω, a / ω²)`.
pub(crate) fn limit_envelope(displacement: f64, velocity: f64, acceleration: f64) -> Vec<f64> {
    SPECTRUM_HZ
        .iter()
        .map(|f| {
            let w = std::f64::consts::TAU * f;
            displacement.min(velocity / w).min(acceleration / (w * w))
        })
        .collect()
}

/// The frequencies of [`sine_amplitudes`] and [`limit_envelope`] (Hz).
pub(crate) fn spectrum_hz() -> Vec<f64> {
    SPECTRUM_HZ.to_vec()
}

/// Run the design on `n` subjects drawn uniformly between the prior's ends
/// (the nominal subject when it has no range) and compare the achieved
/// spread of the errors with the prediction.
pub(crate) fn verify<S: Truth + Clone + Send>(
    run: &impl Runner<S>,
    (nominal, other_end): (&S, Option<&S>),
    predicted: &Prediction,
    n: usize,
    seed: u64,
) -> Result<Verification> {
    use rand::{rngs::StdRng, Rng, SeedableRng};
    let mut rng = StdRng::seed_from_u64(seed ^ 0x5eed_0060);
    let subjects: Vec<(S, u64)> = seeds(seed, 50_000, n)
        .into_iter()
        .map(|s| {
            let t: f64 = rng.random();
            let subject = match other_end {
                Some(o) => nominal.blend(o, t),
                None => nominal.clone(),
            };
            (subject, s)
        })
        .collect();
    let rs: Vec<Run> = subjects
        .par_iter()
        .map(|(subject, s)| run(subject, *s))
        .collect::<Result<_>>()?;
    let achieved = pooled_se(&spread(&rs));
    let nf = n as f64;
    let within = rs
        .iter()
        .filter(|r| {
            r.error_percent[0] < 100.0 * STIFFNESS_TOLERANCE
                && r.error_percent[1] < 100.0 * DAMPING_TOLERANCE
                && r.identifiable[0]
                && r.identifiable[1]
        })
        .count();
    Ok(Verification {
        runs: n,
        achieved_se: achieved,
        ratio: std::array::from_fn(|m| predicted.pooled.se[m] / achieved[m]),
        within_tolerance_share: within as f64 / nf,
        error_percent: std::array::from_fn(|m| {
            rs.iter().map(|r| r.error_percent[m]).sum::<f64>() / nf
        }),
    })
}
