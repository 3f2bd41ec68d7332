//! Protocol files of every kind. A protocol TOML file names its `kind`:
//!
//! - `centre-out` (the default when `kind` is absent): seed 000 §II-B and
//!   seed 001 "Procedure and Tasks", see [`crate::protocol`];
//! - `planar`: seed 003 §IV-B — quintic (minimum-jerk, eq. (16)) joint-space
//!   displacements of a 2-link arm, each after a random wait (1-3 s);
//! - `stochastic`: seed 004 §III-C — uniform white noise through an 8th-order
//!   Butterworth low-pass (15 Hz), scaled to a peak force, with the input
//!   coherence kept below a limit (0.6) so that the MIMO estimate is well posed.
//!
//! `check` refuses a protocol that breaks its limits, naming the limit and the
//! sample; the conditioning figures that need the estimator (condition number
//! on a nominal subject) are added by the CLI, which has it.

use rand::{rngs::StdRng, Rng, SeedableRng};
use serde::{Deserialize, Serialize};

use crate::planar::{PlanarProtocol, PlanarSubject};
use crate::profile::Profile;
use crate::protocol::{self, conditioning_ratios, Protocol};
use crate::rig::{RigExperiment, Springs};
use limpid_core::{Error, Result};
use limpid_dsp::spectral::{coherence, Welch};

/// Any protocol.
#[derive(Debug, Clone)]
pub enum Design {
    /// Centre-out (seeds 000, 001).
    CentreOut(Protocol),
    /// Planar 2-link arm (seed 003).
    Planar(PlanarDesign),
    /// Stochastic inputs (seed 004).
    Stochastic(StochasticDesign),
    /// Repetitions of a task with random perturbations (time-varying impedance).
    Ensemble(crate::varying::EnsembleExperiment),
    /// Operating angles on a ramp-and-hold schedule under a continuous perturbation (parameter-varying impedance).
    RampAndHold(crate::varying::RampAndHold),
    /// A multisine or PRBS repeated for whole periods (`kind = "multisine"` or `"prbs"`).
    Periodic(crate::periodic::PeriodicDesign),
    /// Walking with pulses on some strides or a perturbation on every stride (`kind = "walking"`).
    Walking(crate::varying::WalkingExperiment),
}

/// Every preset's name, in the order of [`PRESETS`] (`limpid protocol new
/// --help` lists them from here).
pub const PRESET_NAMES: [&str; 12] = [
    "artemiadis-3d",
    "patel-cocontraction",
    "lakatos-planar",
    "park-stochastic",
    "ensemble",
    "ankle-ramp-and-hold",
    "ankle-multisine",
    "planar-multisine",
    "endpoint-multisine",
    "ankle-prbs",
    "walking-pulses",
    "walking-continuous",
];

/// The preset names, by kind.
pub const PRESETS: &str = "artemiadis-3d, patel-cocontraction (centre-out), lakatos-planar (planar), park-stochastic (stochastic), ensemble (ensemble), ankle-ramp-and-hold (ramp-and-hold), ankle-multisine, planar-multisine, endpoint-multisine (multisine), ankle-prbs (prbs), walking-pulses, walking-continuous (walking)";

impl Design {
    /// A preset: seed 000 (`artemiadis-3d`), seed 001 (`patel-cocontraction`),
    /// seed 003 (`lakatos-planar`), seed 004 (`park-stochastic`).
    pub fn preset(name: &str) -> Result<Self> {
        match name {
            "artemiadis-3d" | "patel-cocontraction" => {
                Ok(Design::CentreOut(protocol::preset(name)?))
            }
            "lakatos-planar" => Ok(Design::Planar(PlanarDesign::seed003())),
            "park-stochastic" => Ok(Design::Stochastic(StochasticDesign::seed004())),
            "ensemble" => Ok(Design::Ensemble(Default::default())),
            "ankle-ramp-and-hold" => Ok(Design::RampAndHold(Default::default())),
            "ankle-multisine" => Ok(Design::Periodic(
                crate::periodic::PeriodicDesign::multisine_joint(),
            )),
            "planar-multisine" => Ok(Design::Periodic(
                crate::periodic::PeriodicDesign::multisine_planar(),
            )),
            "endpoint-multisine" => Ok(Design::Periodic(
                crate::periodic::PeriodicDesign::multisine_endpoint(),
            )),
            "ankle-prbs" => Ok(Design::Periodic(
                crate::periodic::PeriodicDesign::prbs_joint(),
            )),
            "walking-pulses" => Ok(Design::Walking(Default::default())),
            "walking-continuous" => Ok(Design::Walking(crate::varying::WalkingExperiment {
                perturbation: crate::varying::WalkingExperiment::continuous(),
                ..Default::default()
            })),
            other => Err(Error::invalid(
                "preset",
                format!("unknown preset {other:?}; presets: {PRESETS}"),
            )),
        }
    }

    /// Parse a protocol file; its `kind` key picks the type. Errors give the
    /// line and column in `text`.
    pub fn from_toml(text: &str, path: &std::path::Path) -> Result<Self> {
        let fail = |message: String| Error::Format {
            path: path.to_path_buf(),
            message,
        };
        let located =
            |text: &str, e: toml::de::Error| Error::settings(path, text, e.span(), e.message());
        #[derive(Deserialize)]
        struct KindKey {
            kind: Option<toml::Spanned<toml::Value>>,
        }
        let key: KindKey = toml::from_str(text).map_err(|e| located(text, e))?;
        let (kind, body) = match key.kind {
            None => ("centre-out".to_string(), text.to_string()),
            Some(spanned) => {
                let span = spanned.span();
                let toml::Value::String(kind) = spanned.into_inner() else {
                    return Err(Error::settings(
                        path,
                        text,
                        Some(span),
                        "kind must be a string: centre-out, planar, stochastic, ensemble, ramp-and-hold, multisine, prbs or walking",
                    ));
                };
                // blank the `kind = ...` line so that every other byte keeps its place
                let start = text[..span.start].rfind('\n').map_or(0, |i| i + 1);
                let end = text[span.end..]
                    .find('\n')
                    .map_or(text.len(), |i| span.end + i);
                let mut body = text.to_string();
                let blank: String = text[start..end]
                    .chars()
                    .map(|c| if c == '\n' { c } else { ' ' })
                    .collect();
                body.replace_range(start..end, &blank);
                (kind, body)
            }
        };
        crate::validate::check_numbers(&body, path)?;
        let design = match kind.as_str() {
            "centre-out" => Design::CentreOut(Protocol::from_toml(&body, path)?),
            "planar" => {
                let d: PlanarDesign = toml::from_str(&body).map_err(|e| located(&body, e))?;
                crate::validate::refuse_extra_elements::<PlanarDesign>(&body, path)?;
                d.validate().map_err(fail)?;
                Design::Planar(d)
            }
            "stochastic" => {
                let d: StochasticDesign = toml::from_str(&body).map_err(|e| located(&body, e))?;
                crate::validate::refuse_extra_elements::<StochasticDesign>(&body, path)?;
                d.validate().map_err(fail)?;
                Design::Stochastic(d)
            }
            "ensemble" => {
                let d: crate::varying::EnsembleExperiment =
                    toml::from_str(&body).map_err(|e| located(&body, e))?;
                crate::validate::refuse_extra_elements::<crate::varying::EnsembleExperiment>(&body, path)?;
                d.validate().map_err(|e| fail(e.to_string()))?;
                Design::Ensemble(d)
            }
            "ramp-and-hold" => {
                let d: crate::varying::RampAndHold =
                    toml::from_str(&body).map_err(|e| located(&body, e))?;
                crate::validate::refuse_extra_elements::<crate::varying::RampAndHold>(&body, path)?;
                d.validate().map_err(|e| fail(e.to_string()))?;
                Design::RampAndHold(d)
            }
            "walking" => {
                let d: crate::varying::WalkingExperiment =
                    toml::from_str(&body).map_err(|e| located(&body, e))?;
                crate::validate::refuse_extra_elements::<crate::varying::WalkingExperiment>(&body, path)?;
                d.validate().map_err(|e| fail(e.to_string()))?;
                Design::Walking(d)
            }
            "multisine" | "prbs" => {
                let d: crate::periodic::PeriodicDesign = toml::from_str(&body).map_err(|e| {
                    let hint = "; a multisine needs period_s, band_hz and rms, a prbs order, switch_interval_s and amplitude, both coordinates, sample_rate_hz, periods and [limits]";
                    Error::settings(path, &body, e.span(), &format!("{}{hint}", e.message()))
                })?;
                crate::validate::refuse_extra_elements::<crate::periodic::PeriodicDesign>(
                    &body, path,
                )?;
                let is_prbs = matches!(d.signal, crate::periodic::Signal::Prbs(_));
                if is_prbs != (kind == "prbs") {
                    return Err(fail(format!(
                        "kind = \"{kind}\" but the fields are a {}'s",
                        if is_prbs { "prbs" } else { "multisine" }
                    )));
                }
                d.validate().map_err(fail)?;
                Design::Periodic(d)
            }
            other => {
                return Err(fail(format!(
                    "unknown kind {other:?}; kinds: centre-out, planar, stochastic, ensemble, ramp-and-hold, multisine, prbs"
                )))
            }
        };
        design.check_size().map_err(|e| fail(e.to_string()))?;
        Ok(design)
    }

    /// Refuse a design that asks for more samples than limpid simulates
    /// ([`crate::validate::MAX_SAMPLES`]) or motions shorter than 4 samples.
    pub fn check_size(&self) -> Result<()> {
        use crate::validate::check_size;
        let short = |what: &str, s: f64, fs: f64| {
            if s * fs < 4.0 {
                Err(Error::invalid(
                    "protocol",
                    format!("{what} = {s} s lasts under 4 samples at {fs} Hz: the motion cannot be sampled"),
                ))
            } else {
                Ok(())
            }
        };
        match self {
            Design::CentreOut(p) => {
                let ph = &p.phases;
                let per = (ph.rest_s
                    + ph.centre_out_s
                    + ph.hold_s
                    + ph.return_s
                    + ph.relax_s
                    + ph.set_rest_s)
                    * p.sample_rate_hz;
                let starts = if p.start_points.points.is_empty() {
                    6
                } else {
                    p.start_points.points.len()
                };
                check_size(
                    per * (starts * p.targets.count) as f64,
                    "start points x targets x trial length x rate",
                )?;
                short("phases.centre_out_s", ph.centre_out_s, p.sample_rate_hz)
            }
            Design::Planar(p) => {
                let per = (p.wait_s[1] + p.after_s + p.rest_s) * p.sample_rate_hz;
                check_size(
                    per * p.trials as f64,
                    "trials x (longest wait + after_s) x rate",
                )?;
                short("interpolation_s", p.interpolation_s, p.sample_rate_hz)
            }
            Design::Stochastic(p) => check_size(
                p.duration_s * p.sample_rate_hz * p.channels.len().max(1) as f64,
                "duration x rate x channels",
            ),
            Design::Ensemble(p) => p.validate(),
            Design::RampAndHold(p) => p.validate(),
            Design::Walking(p) => p.validate(),
            Design::Periodic(p) => p.validate().map_err(|m| Error::invalid("protocol", m)),
        }
    }

    /// TOML text with its `kind` first.
    pub fn to_toml(&self) -> String {
        let (kind, body) = match self {
            Design::CentreOut(p) => ("centre-out", p.to_toml()),
            Design::Planar(p) => ("planar", toml::to_string(p).unwrap_or_default()),
            Design::Stochastic(p) => ("stochastic", toml::to_string(p).unwrap_or_default()),
            Design::Ensemble(p) => ("ensemble", toml::to_string(p).unwrap_or_default()),
            Design::RampAndHold(p) => ("ramp-and-hold", toml::to_string(p).unwrap_or_default()),
            Design::Walking(p) => ("walking", toml::to_string(p).unwrap_or_default()),
            Design::Periodic(p) => (
                match p.signal {
                    crate::periodic::Signal::Prbs(_) => "prbs",
                    crate::periodic::Signal::Multisine(_) => "multisine",
                },
                toml::to_string(p).unwrap_or_default(),
            ),
        };
        format!("kind = \"{kind}\"\n{body}")
    }
}

/// Seed 003 §IV-B: joint-space perturbations of a planar 2-link arm.
#[derive(Debug, Clone, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct PlanarDesign {
    /// Protocol name.
    pub name: String,
    /// Sample rate (Hz).
    pub sample_rate_hz: f64,
    /// Upper-arm and forearm lengths (m).
    pub link_lengths_m: [f64; 2],
    /// Posture q0 (shoulder, relative elbow; rad) held between perturbations.
    pub posture_rad: [f64; 2],
    /// Displacements Δq_f (rad); trials cycle through them in a random order.
    pub displacements_rad: Vec<[f64; 2]>,
    /// Number of perturbations.
    pub trials: usize,
    /// Interpolation interval T_k of the quintic (s).
    pub interpolation_s: f64,
    /// Recorded before and after each onset (s).
    pub rest_s: f64,
    /// Recorded after each onset (s).
    pub after_s: f64,
    /// Random wait before each perturbation, uniform in [min, max] (s).
    pub wait_s: [f64; 2],
    /// Seed of the trial order and the waits.
    pub seed: u64,
    /// Safety limits.
    pub limits: PlanarLimits,
}

/// Safety limits of a planar protocol.
#[derive(Debug, Clone, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct PlanarLimits {
    /// Largest joint displacement (rad).
    pub max_joint_displacement_rad: f64,
    /// Largest joint velocity (rad/s).
    pub max_joint_velocity_rad_s: f64,
    /// Largest joint acceleration (rad/s^2).
    pub max_joint_acceleration_rad_s2: f64,
    /// Largest predicted joint torque (N m).
    pub max_torque_nm: f64,
    /// Joint stiffness used to predict the torque (N m/rad).
    pub nominal_joint_stiffness_nm_per_rad: f64,
}

impl PlanarDesign {
    /// Seed 003: q0 = (0.08, 1.0) rad, six directions of 0.05 rad, 30 trials,
    /// T_k = 200 ms, 1 kHz, waits of 1-3 s; links 0.30 and 0.33 m (the seed's
    /// subject is not given; adult upper arm and forearm-to-handle lengths).
    pub fn seed003() -> Self {
        let sim = PlanarProtocol::seed003();
        PlanarDesign {
            name: "Lakatos, Petit & van der Smagt (2011): 6 joint-space directions x 5, quintic over 200 ms, random waits 1-3 s"
                .into(),
            sample_rate_hz: sim.sample_rate,
            link_lengths_m: [0.30, 0.33],
            posture_rad: [0.08, 1.0],
            displacements_rad: sim.directions,
            trials: sim.trials,
            interpolation_s: sim.interpolation_s,
            rest_s: sim.rest_s,
            after_s: sim.after_s,
            wait_s: [1.0, 3.0],
            seed: 1,
            limits: PlanarLimits {
                max_joint_displacement_rad: 0.1,
                max_joint_velocity_rad_s: 1.0,
                max_joint_acceleration_rad_s2: 15.0,
                max_torque_nm: 20.0,
                nominal_joint_stiffness_nm_per_rad: 40.0,
            },
        }
    }

    fn validate(&self) -> std::result::Result<(), String> {
        if self.sample_rate_hz <= 0.0
            || self.trials == 0
            || self.displacements_rad.is_empty()
            || self.interpolation_s <= 0.0
            || self.rest_s < 0.0
            || self.after_s < self.interpolation_s
        {
            return Err("sample_rate_hz, trials, displacements_rad and interpolation_s must be positive, and after_s at least interpolation_s".into());
        }
        if self.displacements_rad.len() > crate::validate::MAX_TARGETS as usize {
            return Err(format!(
                "{} displacements; a protocol has at most {}",
                self.displacements_rad.len(),
                crate::validate::MAX_TARGETS
            ));
        }
        // each wait holds the return from the last perturbation (over T_k) and the next rest
        if !(self.wait_s[0] >= self.rest_s + self.interpolation_s
            && self.wait_s[1] >= self.wait_s[0])
        {
            return Err(format!(
                "wait_s = {:?} must be an interval starting at or after rest_s + interpolation_s = {} s (the return to the posture, then the recorded rest)",
                self.wait_s,
                self.rest_s + self.interpolation_s
            ));
        }
        Ok(())
    }

    /// The built-in virtual subject (seed 003's arm) held at this protocol's posture.
    pub fn nominal_subject(&self) -> PlanarSubject {
        PlanarSubject {
            q0: self.posture_rad,
            ..PlanarSubject::seed003()
        }
    }

    /// The simulation protocol of [`crate::planar::simulate_planar`].
    pub fn simulation(&self) -> PlanarProtocol {
        PlanarProtocol {
            directions: self.displacements_rad.clone(),
            trials: self.trials,
            interpolation_s: self.interpolation_s,
            rest_s: self.rest_s,
            after_s: self.after_s,
            sample_rate: self.sample_rate_hz,
        }
    }

    /// The schedule: for every trial, its onset time (s from the start of the
    /// session) and its displacement index. Onsets follow random waits.
    pub fn schedule(&self) -> Vec<(f64, usize)> {
        let mut rng = StdRng::seed_from_u64(self.seed);
        let mut t = 0.0;
        (0..self.trials)
            .map(|k| {
                t += rng.random_range(self.wait_s[0]..=self.wait_s[1]);
                let onset = t;
                t += self.after_s;
                (onset, k % self.displacements_rad.len())
            })
            .collect()
    }
}

/// Seed 004 §III-C: random force inputs for a stochastic experiment.
#[derive(Debug, Clone, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct StochasticDesign {
    /// Protocol name.
    pub name: String,
    /// Sample rate (Hz).
    pub sample_rate_hz: f64,
    /// Duration of the input (s).
    pub duration_s: f64,
    /// Input channel names (FORMAT.md: `u<coordinate>`).
    pub channels: Vec<String>,
    /// Peak commanded force or torque per channel (N or N m).
    pub peak: Vec<f64>,
    /// Cut-off of the 8th-order Butterworth low-pass (Hz).
    pub cutoff_hz: f64,
    /// Seed of the random inputs.
    pub seed: u64,
    /// Largest coherence allowed between any two inputs below the cut-off.
    pub max_input_coherence: f64,
    /// Safety limits.
    pub limits: StochasticLimits,
}

/// Safety limits of a stochastic protocol.
#[derive(Debug, Clone, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct StochasticLimits {
    /// Largest commanded force (N).
    pub max_force_n: f64,
    /// Stiffness used to predict the displacement (N/m).
    pub nominal_stiffness_n_per_m: f64,
    /// Largest predicted displacement (m).
    pub max_displacement_m: f64,
}

impl StochasticDesign {
    /// Seed 004: x, z and θ inputs for 50 s at 1 kHz, 15 Hz cut-off; peaks of
    /// the spring-array experiments in the outside examples (`stochastic`).
    pub fn seed004() -> Self {
        StochasticDesign {
            name: "Park & Chang (2011): uniform noise, 8th-order Butterworth 15 Hz, 50 s at 1 kHz"
                .into(),
            sample_rate_hz: 1000.0,
            duration_s: 50.0,
            channels: vec!["ux".into(), "uz".into(), "utheta".into()],
            peak: vec![40.0, 40.0, 4.9],
            cutoff_hz: 15.0,
            seed: 1,
            max_input_coherence: 0.6,
            limits: StochasticLimits {
                max_force_n: 60.0,
                nominal_stiffness_n_per_m: 1000.0,
                max_displacement_m: 0.08,
            },
        }
    }

    fn validate(&self) -> std::result::Result<(), String> {
        if self.sample_rate_hz <= 0.0 || self.duration_s <= 0.0 || self.channels.is_empty() {
            return Err(
                "sample_rate_hz, duration_s and channels must be positive / non-empty".into(),
            );
        }
        if self.channels.len() > 16 {
            return Err(format!(
                "{} channels; a stochastic protocol has at most 16",
                self.channels.len()
            ));
        }
        if self.peak.len() != self.channels.len() {
            return Err(format!(
                "peak has {} values for {} channels",
                self.peak.len(),
                self.channels.len()
            ));
        }
        if !(self.cutoff_hz > 0.0 && self.cutoff_hz < 0.5 * self.sample_rate_hz) {
            return Err(format!(
                "cutoff_hz = {} must lie between 0 and the Nyquist frequency {}",
                self.cutoff_hz,
                0.5 * self.sample_rate_hz
            ));
        }
        Ok(())
    }

    /// The spring array `springs` on the virtual rig, driven by this protocol's
    /// inputs (duration, rate, peaks, cut-off); the rig has three inputs (x, z, θ).
    pub fn rig_experiment(&self, springs: &Springs) -> Result<RigExperiment> {
        let [px, pz, pt] = self.peak[..] else {
            return Err(Error::invalid(
                "protocol",
                format!(
                    "the virtual spring-array rig has three inputs (x, z, theta); the protocol has {}",
                    self.channels.len()
                ),
            ));
        };
        Ok(RigExperiment {
            seconds: self.duration_s,
            sample_rate: self.sample_rate_hz,
            peak: [px, pz, pt],
            cutoff_hz: self.cutoff_hz,
            ..RigExperiment::spring_array(springs)
        })
    }

    /// The input signals, one per channel.
    pub fn inputs(&self) -> Result<Vec<Vec<f64>>> {
        let n = (self.duration_s * self.sample_rate_hz).round() as usize;
        crate::rig::stochastic_input(
            n,
            self.sample_rate_hz,
            &self.peak,
            self.cutoff_hz,
            self.seed,
        )
    }
}

/// What `check` found, per kind.
#[derive(Debug, Clone, Serialize)]
#[serde(tag = "kind", rename_all = "kebab-case")]
pub enum DesignReport {
    /// Centre-out report.
    CentreOut(protocol::CheckReport),
    /// Planar report.
    Planar(PlanarReport),
    /// Stochastic report.
    Stochastic(StochasticReport),
    /// Ensemble or ramp-and-hold report.
    Varying(VaryingReport),
    /// Multisine or PRBS report.
    Periodic(crate::periodic::PeriodicReport),
}

/// What `check` found in an ensemble or ramp-and-hold protocol.
#[derive(Debug, Clone, Serialize)]
pub struct VaryingReport {
    /// Samples recorded.
    pub samples: usize,
    /// Duration recorded (s).
    pub duration_s: f64,
}

/// What `check` found in a planar protocol.
#[derive(Debug, Clone, Serialize)]
pub struct PlanarReport {
    /// Perturbations.
    pub trials: usize,
    /// Duration of the session, waits and the last return included (s).
    pub session_s: f64,
    /// Largest joint displacement (rad).
    pub peak_joint_displacement_rad: f64,
    /// Largest joint velocity (rad/s).
    pub peak_joint_velocity_rad_s: f64,
    /// Largest joint acceleration (rad/s^2).
    pub peak_joint_acceleration_rad_s2: f64,
    /// Largest predicted joint torque (N m).
    pub peak_torque_nm: f64,
    /// Seed 003 eq. (17) of the quintic: [C_12, C_13, C_23].
    pub conditioning_ratios: [f64; 3],
}

/// What `check` found in a stochastic protocol.
#[derive(Debug, Clone, Serialize)]
pub struct StochasticReport {
    /// Samples per channel.
    pub samples: usize,
    /// Peak input per channel (N or N m).
    pub peak_force: Vec<f64>,
    /// Displacement the nominal stiffness predicts for the peak force (m).
    pub predicted_peak_displacement_m: f64,
    /// Largest coherence between two inputs below the cut-off, the pair and the frequency.
    pub max_input_coherence: f64,
    /// The two inputs of the largest coherence.
    pub max_coherence_pair: [String; 2],
    /// Frequency of the largest coherence (Hz).
    pub max_coherence_hz: f64,
}

/// Check a protocol against its limits.
pub fn check(d: &Design) -> Result<DesignReport> {
    match d {
        Design::CentreOut(p) => Ok(DesignReport::CentreOut(protocol::check(p)?)),
        Design::Planar(p) => check_planar(p).map(DesignReport::Planar),
        Design::Stochastic(p) => check_stochastic(p).map(DesignReport::Stochastic),
        Design::Ensemble(p) => {
            p.validate()?;
            let duration_s = p.repetitions as f64 * p.duration_s;
            Ok(DesignReport::Varying(VaryingReport {
                samples: (duration_s * p.rate_hz).round() as usize,
                duration_s,
            }))
        }
        Design::RampAndHold(p) => {
            p.validate()?;
            let duration_s = p.duration_s();
            Ok(DesignReport::Varying(VaryingReport {
                samples: (duration_s * p.rate_hz).round() as usize,
                duration_s,
            }))
        }
        Design::Walking(p) => {
            p.validate()?;
            let duration_s = p.strides as f64 * p.stride_s;
            Ok(DesignReport::Varying(VaryingReport {
                samples: (duration_s * p.rate_hz).round() as usize,
                duration_s,
            }))
        }
        Design::Periodic(p) => p.check().map(DesignReport::Periodic),
    }
}

fn check_planar(p: &PlanarDesign) -> Result<PlanarReport> {
    let l = &p.limits;
    let fs = p.sample_rate_hz;
    let per = ((p.rest_s + p.after_s) * fs).round() as usize;
    let schedule = p.schedule();
    let mut r = PlanarReport {
        trials: p.trials,
        // the last return to the posture ends the session
        session_s: schedule
            .last()
            .map(|s| s.0 + p.after_s + p.interpolation_s)
            .unwrap_or(0.0),
        peak_joint_displacement_rad: 0.0,
        peak_joint_velocity_rad_s: 0.0,
        peak_joint_acceleration_rad_s2: 0.0,
        peak_torque_nm: 0.0,
        conditioning_ratios: conditioning_ratios(Profile::Quintic, p.interpolation_s, 1.0),
    };
    for (di, dq) in p.displacements_rad.iter().enumerate() {
        for i in 0..per {
            let t = i as f64 / fs - p.rest_s;
            let (s, sd, sdd) = Profile::Quintic.eval(t, p.interpolation_s);
            for (j, amp) in dq.iter().enumerate() {
                let checks = [
                    (
                        "joint displacement (rad)",
                        (amp * s).abs(),
                        l.max_joint_displacement_rad,
                    ),
                    (
                        "joint velocity (rad/s)",
                        (amp * sd).abs(),
                        l.max_joint_velocity_rad_s,
                    ),
                    (
                        "joint acceleration (rad/s^2)",
                        (amp * sdd).abs(),
                        l.max_joint_acceleration_rad_s2,
                    ),
                    (
                        "expected torque (N m)",
                        (amp * s).abs() * l.nominal_joint_stiffness_nm_per_rad,
                        l.max_torque_nm,
                    ),
                ];
                let peaks = [
                    &mut r.peak_joint_displacement_rad,
                    &mut r.peak_joint_velocity_rad_s,
                    &mut r.peak_joint_acceleration_rad_s2,
                    &mut r.peak_torque_nm,
                ];
                for ((limit, value, max), peak) in checks.into_iter().zip(peaks) {
                    *peak = peak.max(value);
                    if value > max {
                        return Err(Error::invalid(
                            "protocol",
                            format!("{limit} {value:.4} exceeds the limit {max} on joint {} in displacement {}, t = {t:.3} s after the onset", j + 1, di + 1),
                        ));
                    }
                }
            }
        }
        let (_, v, a) = Profile::Quintic.peaks(p.interpolation_s);
        for (j, amp) in dq.iter().enumerate() {
            for (limit, value, max) in [
                (
                    "joint velocity (rad/s)",
                    amp.abs() * v,
                    l.max_joint_velocity_rad_s,
                ),
                (
                    "joint acceleration (rad/s^2)",
                    amp.abs() * a,
                    l.max_joint_acceleration_rad_s2,
                ),
            ] {
                if value > max {
                    return Err(Error::invalid(
                        "protocol",
                        format!("{limit} {value:.4} exceeds the limit {max} on joint {} in displacement {} (peak of the continuous quintic)", j + 1, di + 1),
                    ));
                }
            }
        }
    }
    Ok(r)
}

fn check_stochastic(p: &StochasticDesign) -> Result<StochasticReport> {
    let l = &p.limits;
    let u = p.inputs()?;
    let mut peak_force = Vec::with_capacity(u.len());
    for (c, sig) in u.iter().enumerate() {
        let (k, v) = sig
            .iter()
            .enumerate()
            .fold((0, 0.0f64), |(bk, bv), (k, v)| {
                if v.abs() > bv {
                    (k, v.abs())
                } else {
                    (bk, bv)
                }
            });
        // torque channels (names ending in an angle) are compared with the force limit in N m
        if v > l.max_force_n {
            return Err(Error::invalid(
                "protocol",
                format!(
                    "peak input {v:.3} on {} exceeds the limit {} at sample {k}",
                    p.channels[c], l.max_force_n
                ),
            ));
        }
        peak_force.push(v);
    }
    let predicted = peak_force.iter().cloned().fold(0.0, f64::max) / l.nominal_stiffness_n_per_m;
    if predicted > l.max_displacement_m {
        return Err(Error::invalid(
            "protocol",
            format!("predicted displacement {predicted:.4} m (peak force / nominal stiffness) exceeds the limit {} m", l.max_displacement_m),
        ));
    }
    let welch = Welch {
        nperseg: (4.0 * p.sample_rate_hz)
            .min(u[0].len() as f64 / 4.0)
            .max(16.0) as usize,
        ..Welch::new(p.sample_rate_hz)
    };
    let mut worst = (0.0, [String::new(), String::new()], 0.0);
    for a in 0..u.len() {
        for b in a + 1..u.len() {
            let (f, c) = coherence(&u[a], &u[b], &welch)?;
            for (fk, ck) in f.iter().zip(&c) {
                if *fk > 0.0 && *fk <= p.cutoff_hz && *ck > worst.0 {
                    worst = (*ck, [p.channels[a].clone(), p.channels[b].clone()], *fk);
                }
            }
        }
    }
    if worst.0 > p.max_input_coherence {
        return Err(Error::invalid(
            "protocol",
            format!(
                "input coherence {:.3} between {} and {} at {:.2} Hz exceeds the limit {}: the inputs are not independent enough for Z = T R^-1",
                worst.0, worst.1[0], worst.1[1], worst.2, p.max_input_coherence
            ),
        ));
    }
    Ok(StochasticReport {
        samples: u[0].len(),
        peak_force,
        predicted_peak_displacement_m: predicted,
        max_input_coherence: worst.0,
        max_coherence_pair: worst.1,
        max_coherence_hz: worst.2,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_preset_round_trips_through_toml_and_passes_its_check() {
        for name in PRESET_NAMES {
            assert!(PRESETS.contains(name), "{name} is not listed in PRESETS");
            let d = Design::preset(name).unwrap();
            let text = d.to_toml();
            let back = Design::from_toml(&text, std::path::Path::new("p.toml")).unwrap();
            assert_eq!(back.to_toml(), text, "{name}");
            check(&back).unwrap_or_else(|e| panic!("{name}: {e}"));
        }
    }

    #[test]
    fn planar_waits_lie_in_their_interval_and_limits_name_the_joint() {
        let mut d = PlanarDesign::seed003();
        let s = d.schedule();
        assert_eq!(s.len(), 30);
        let mut prev_end = 0.0;
        for (onset, _) in &s {
            let wait = onset - prev_end;
            assert!((1.0 - 1e-12..=3.0 + 1e-12).contains(&wait), "wait {wait}");
            prev_end = onset + d.after_s;
        }
        // quintic over 200 ms of 0.05 rad: peak velocity 15/8 * 0.05 / 0.2 = 0.469 rad/s
        let r = check_planar(&d).unwrap();
        assert!((r.peak_joint_velocity_rad_s - 0.46875).abs() < 1e-3);
        d.interpolation_s = 0.05;
        d.limits.max_joint_acceleration_rad_s2 = 1e3;
        let e = check_planar(&d).unwrap_err().to_string();
        // the first sample above 1 rad/s on the way to the 1.875 rad/s peak
        assert!(
            e.starts_with("invalid protocol: joint velocity (rad/s) 1.1105 exceeds the limit 1 on joint 1 in displacement 1, t = 0.013 s"),
            "{e}"
        );
    }

    #[test]
    fn stochastic_inputs_are_independent_and_limits_are_enforced() {
        let d = StochasticDesign::seed004();
        let r = check_stochastic(&d).unwrap();
        // independent noise: the estimated coherence is only the Welch bias (~1/segments)
        assert!(r.max_input_coherence < 0.6 && r.max_input_coherence > 0.0);
        assert!((r.peak_force[0] - 40.0).abs() < 1e-9);
        let mut strict = d.clone();
        strict.max_input_coherence = 0.01;
        let e = check_stochastic(&strict).unwrap_err().to_string();
        assert!(
            e.contains("input coherence") && e.contains("exceeds the limit 0.01"),
            "{e}"
        );
        let mut loud = d;
        loud.peak[0] = 80.0;
        let e = check_stochastic(&loud).unwrap_err().to_string();
        assert!(
            e.contains("peak input 80.000 on ux exceeds the limit 60"),
            "{e}"
        );
    }

    #[test]
    fn unknown_kinds_and_bad_fields_are_refused_with_the_path() {
        let e = Design::from_toml("kind = \"spiral\"\n", std::path::Path::new("x.toml"))
            .unwrap_err()
            .to_string();
        assert!(
            e.contains("x.toml") && e.contains("unknown kind \"spiral\""),
            "{e}"
        );
        let mut text = Design::preset("park-stochastic").unwrap().to_toml();
        text = text.replace("peak = [", "peak = [1.0, ");
        let e = Design::from_toml(&text, std::path::Path::new("s.toml"))
            .unwrap_err()
            .to_string();
        assert!(e.contains("peak has 4 values for 3 channels"), "{e}");
    }
}
