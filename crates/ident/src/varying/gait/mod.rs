//! Impedance during walking (issue 61): strides cut at heel strikes, gait
//! phase (or time since the event) as the schedule, the mean stride
//! subtracted before impedance can be seen.
//!
//! - [`events`]: events from a 0/1 column or a threshold crossing, strides,
//!   and the flawed ones reported by number.
//! - `ensemble` (continuous small random perturbation on every stride; Lee &
//!   Hogan 2015's continuous variant, Kearney & MacNeil's ensembles): each
//!   stride's filtered positions, velocities, accelerations and torques are
//!   resampled on a grid of gait phase (derivatives taken in time first);
//!   the deviations from the mean of the `neighbours` nearest strides at the
//!   same phase are regressed per phase window exactly as the time-varying
//!   ensemble does (`δf = M δx'' + B δx' + K δx`, jackknife over strides).
//!   A local rather than a global mean keeps a change of walking speed out of
//!   the deviations.
//! - `pulses` (perturbed minus unperturbed; Rouse, Hargrove, Perreault &
//!   Kuiken 2014; Lee & Hogan 2015): each perturbed stride minus the mean of
//!   the unperturbed strides nearest it (phase-normalised, mapped onto the
//!   perturbed stride's duration), I, B, K fitted on a short window around
//!   the onset; see `pulses`.

pub mod events;
mod pulses;

pub use events::{EventRule, StrideFlaw, Strides};

use limpid_core::{Error, Recording, Result};
use limpid_dsp::LowPass;
use schemars::JsonSchema;
use serde::{Deserialize, Serialize};

use super::ensemble::{fit_grid, Ensemble, Layout};
use super::{ScheduleAxis, VaryingEstimate, VaryingMethod, VaryingParams};

/// The schedule name for gait phase (fraction of the stride).
pub const GAIT_PHASE: &str = "gait-phase";
/// The schedule name for time since the stride's event.
pub const TIME_SINCE_EVENT: &str = "time-since-event";

const FILTER_ORDER: usize = 4;

/// Share of each value added in quadrature to its standard error during
/// walking. The jackknife over strides or perturbations sees the noise, not
/// the bias of subtracting a stride-to-stride varying baseline of up to
/// 100 N m, of phase normalisation, and of K and B taken piecewise linear:
/// on the outside walking examples (another generator) K came out 2-3 % and
/// B 5-7 % low in early stance with jackknife SEs of 2-3 %, so ±2 SE covered
/// B at 55 % of the stance points (pulses) and K and B at 62 % (continuous);
/// on limpid's own walking ankle without any noise B is 2-4 % low. See
/// `limpid calibrate` for the coverage with it.
pub const WALKING_MODEL_FLOOR: f64 = 0.05;

/// The relative tolerances (K, B, I) a walking point's verdict is judged
/// against: twice the bench's ([`super::BENCH_TOLERANCES`]). With the model
/// floor a walking K can never come within 3 SE of 10 % (`limpid calibrate`:
/// 0 of 1097 stance points trusted, median error 2.6 %), and walking is
/// harder than the bench: a stride-to-stride varying baseline of up to
/// 100 N m is subtracted. The outside walking examples are judged at the same
/// 20 % and 40 %.
pub const WALKING_TOLERANCES: [f64; 3] = [0.2, 0.4, 0.4];

/// The walking estimators.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize, JsonSchema)]
#[cfg_attr(feature = "clap", derive(clap::ValueEnum))]
#[serde(rename_all = "snake_case")]
pub enum GaitMethod {
    /// Brief perturbations on some strides: perturbed minus unperturbed.
    Pulses,
    /// A small random perturbation on every stride: deviations from the phase-wise mean.
    Ensemble,
}

/// What the strides were and what was done with them.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, JsonSchema)]
pub struct GaitSummary {
    /// The event rule, as given (`heel_strike`, `fz>50`).
    pub event: String,
    /// Full strides between detected events.
    pub strides_found: usize,
    /// Strides used (durations plausible).
    pub strides_used: usize,
    /// Median, shortest and longest duration of the strides used (s).
    pub stride_s: [f64; 3],
    /// Strides left out or events ignored, by stride number.
    pub flawed: Vec<StrideFlaw>,
    /// Pulses: the trigger column.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub trigger: Option<String>,
    /// Pulses: perturbations fitted.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub perturbations: Option<usize>,
    /// What the baseline subtracted was, in words.
    pub baseline: String,
    /// The gait phase where stance is taken to end (drawn in figures).
    pub stance_end: f64,
    /// The relative tolerances (K, B, I) the points' verdicts are judged
    /// against ([`WALKING_TOLERANCES`]).
    pub tolerances: [f64; 3],
}

impl GaitSummary {
    /// The summary of `used` strides of `strides` recorded at `fs` (for
    /// pulses, the trigger is filled in by the caller).
    fn new(
        params: &VaryingParams,
        (strides, fs): (&Strides, f64),
        used: usize,
        baseline: String,
    ) -> Self {
        let lengths = strides.kept.iter().map(|r| r.len() as f64 / fs);
        GaitSummary {
            event: params.event.clone().unwrap_or_default(),
            strides_found: strides.found,
            strides_used: used,
            stride_s: [
                strides.median_len() as f64 / fs,
                lengths.clone().fold(f64::INFINITY, f64::min),
                lengths.fold(0.0, f64::max),
            ],
            flawed: strides.flaws.clone(),
            trigger: None,
            perturbations: None,
            baseline,
            stance_end: params.stance_end,
            tolerances: WALKING_TOLERANCES,
        }
    }
}

/// `estimate varying` with `--event`.
pub(super) fn estimate(
    rec: &Recording,
    params: &VaryingParams,
    coords: Vec<String>,
    forces: Vec<String>,
    cutoff: f64,
) -> Result<VaryingEstimate> {
    let event = params.event.as_deref().unwrap_or_default();
    let rule = EventRule::parse(event)?;
    if coords.iter().chain(&forces).any(|c| c == rule.column()) {
        return Err(Error::invalid(
            "event",
            format!(
                "{} is a coordinate or force being fitted; events come from a column of their own",
                rule.column()
            ),
        ));
    }
    let strides = events::strides(rec, &rule, params.hysteresis, params.refractory_ms / 1e3)?;
    let trigger = params
        .trigger
        .clone()
        .or_else(|| rec.has("perturbation").then(|| "perturbation".to_string()));
    let mut warnings = Vec::new();
    let method = match (params.gait_method, &trigger) {
        (Some(m), _) => m,
        (None, Some(t)) if pulses::marks_some_strides(rec, t, &strides)? => GaitMethod::Pulses,
        (None, Some(t)) => {
            warnings.push(format!(
                "the trigger column {t} marks no stride, or leaves fewer than 3 unmarked: perturbed minus unperturbed is impossible, the ensemble over every stride is used (it assumes a perturbation on every stride)"
            ));
            GaitMethod::Ensemble
        }
        (None, None) => GaitMethod::Ensemble,
    };
    let phase = params.schedule != TIME_SINCE_EVENT;
    let fs = rec.sample_rate();
    let lp = LowPass::butterworth(FILTER_ORDER, cutoff, fs)?;
    let mut est = match method {
        GaitMethod::Pulses => {
            let Some(trigger) = trigger else {
                return Err(Error::invalid(
                    "trigger",
                    "the pulses method needs a trigger column, 1 while a perturbation is active (--trigger COLUMN)",
                ));
            };
            pulses::estimate(
                rec,
                params,
                (&coords, &forces),
                (&strides, &trigger),
                &lp,
                phase,
                &mut warnings,
            )?
        }
        GaitMethod::Ensemble => ensemble(
            rec,
            params,
            (&coords, &forces),
            &strides,
            &lp,
            phase,
            &mut warnings,
        )?,
    };
    if !strides.flaws.is_empty() {
        let list: Vec<String> = strides
            .flaws
            .iter()
            .take(12)
            .map(|f| {
                format!(
                    "{} ({}, t = {} s)",
                    f.stride,
                    f.kind,
                    limpid_core::significant(f.start_s, 5)
                )
            })
            .collect();
        warnings.insert(
            0,
            format!(
                "{} stride(s) with flawed events (left out or joined): {}{}",
                strides.flaws.len(),
                list.join(", "),
                if strides.flaws.len() > 12 {
                    ", ... (all in gait.flawed)"
                } else {
                    ""
                }
            ),
        );
    }
    if let Some(why) = strides.doubt() {
        warnings.push(why);
        distrust(&mut est.points);
    }
    est.warnings.extend(warnings);
    Ok(est)
}

/// Every trusted matrix of `points` demoted to imprecise: its standard
/// error does not carry what the data's flaws may add.
fn distrust(points: &mut [super::VaryingPoint]) {
    use limpid_core::criteria::MatrixVerdict;
    for v in points.iter_mut().filter_map(|p| p.verdicts.as_mut()) {
        for m in [&mut v.stiffness, &mut v.damping, &mut v.inertia] {
            if *m == MatrixVerdict::Trusted {
                *m = MatrixVerdict::Imprecise;
            }
        }
    }
}

/// The schedule axis of a walking estimate.
fn axis(phase: bool, event: &str) -> ScheduleAxis {
    let column = EventRule::parse(event)
        .map(|r| r.column().to_string())
        .unwrap_or_default();
    if phase {
        ScheduleAxis {
            name: format!("gait phase (from {column})"),
            unit: "fraction of the stride".into(),
            values: Vec::new(),
            angle: None,
        }
    } else {
        ScheduleAxis {
            name: format!("time since {column}"),
            unit: "s".into(),
            values: Vec::new(),
            angle: None,
        }
    }
}

/// Position of sample `j` of a grid of `p` over a stride of `len` samples:
/// phase-normalised (`j / p` of the stride) or in time (sample `j`).
fn stride_sample(len: usize, p: usize, j: usize, phase: bool) -> f64 {
    if phase {
        j as f64 * len as f64 / p as f64
    } else {
        j as f64
    }
}

/// Linear interpolation of `x` at fractional index `u` (clamped).
fn interp(x: &[f64], u: f64) -> f64 {
    let i = (u.floor().max(0.0) as usize).min(x.len() - 1);
    let f = u - i as f64;
    if i + 1 < x.len() {
        x[i] * (1.0 - f) + x[i + 1] * f
    } else {
        x[i]
    }
}

/// Indices of the `n` items nearest `k` among `0..count` (including `k`).
fn nearest(k: usize, count: usize, n: usize) -> std::ops::Range<usize> {
    let n = n.min(count);
    let lo = k.saturating_sub(n / 2).min(count - n);
    lo..lo + n
}

/// The continuous-perturbation estimator on phase-normalised strides.
fn ensemble(
    rec: &Recording,
    params: &VaryingParams,
    (coords, forces): (&[String], &[String]),
    strides: &Strides,
    lp: &LowPass,
    phase: bool,
    warnings: &mut Vec<String>,
) -> Result<VaryingEstimate> {
    let fs = rec.sample_rate();
    let d = coords.len();
    // the record is continuous: filter and differentiate it whole, then cut
    let mut channels = Vec::with_capacity(4 * d);
    let mut acc = Vec::new();
    let mut vel = Vec::new();
    let mut pos = Vec::new();
    let mut frc = Vec::new();
    for k in 0..d {
        let x = lp.filtfilt(rec.require(&coords[k], "positions")?)?;
        let (v, a) = super::derivatives(&x, 1.0 / fs);
        acc.push(a);
        vel.push(v);
        pos.push(x);
        frc.push(lp.filtfilt(rec.require(&forces[k], "forces")?)?);
    }
    channels.extend(acc.iter().chain(&vel).chain(&pos).chain(&frc));
    // leave out strides within the filter's unreliable ends of the record
    let edge = (fs / lp.cutoff_hz()).ceil() as usize;
    let n = rec.len();
    let kept: Vec<&std::ops::Range<usize>> = strides
        .kept
        .iter()
        .filter(|r| r.start >= edge && r.end + edge <= n)
        .collect();
    let p = if phase {
        strides.median_len()
    } else {
        kept.iter().map(|r| r.len()).min().unwrap_or(0)
    };
    if !phase && strides.median_len() as f64 > 1.05 * p as f64 {
        warnings.push(format!(
            "strides differ in length (the shortest {} s, the median {} s): against time since the event, away from the event the strides are not at the same point of the gait and the mean subtracted is not their baseline; gait phase (the default) aligns them",
            limpid_core::significant(p as f64 / rec.sample_rate(), 3),
            limpid_core::significant(strides.median_len() as f64 / rec.sample_rate(), 3)
        ));
    }
    let m = 4 * d;
    let raw: Vec<Vec<f64>> = kept
        .iter()
        .map(|r| {
            let mut z = vec![0.0; p * m];
            for j in 0..p {
                let u = r.start as f64 + stride_sample(r.len(), p, j, phase);
                for (c, ch) in channels.iter().enumerate() {
                    z[j * m + c] = interp(ch, u);
                }
            }
            z
        })
        .collect();
    let reps = raw.len();
    if reps < 3 {
        return Err(Error::invalid(
            "event",
            format!(
                "{}: {reps} usable strides: the ensemble needs at least 3",
                rec.path().display()
            ),
        ));
    }
    let neighbours = params.neighbours.unwrap_or(20).max(2);
    let z: Vec<Vec<f64>> = (0..reps)
        .map(|k| {
            let near = nearest(k, reps, neighbours);
            let count = near.len() as f64;
            let mut out = raw[k].clone();
            for i in near {
                for (o, v) in out.iter_mut().zip(&raw[i]) {
                    *o -= v / count;
                }
            }
            out
        })
        .collect();
    let e = Ensemble { z, len: p, d };
    let median_s = strides.median_len() as f64 / fs;
    let sample_s = if phase { median_s / p as f64 } else { 1.0 / fs };
    let step_s = params.step_s.unwrap_or(params.window_s / 2.0);
    let mut layout = Layout::new(&e, (params.window_s, step_s), sample_s, 0)?;
    layout.sigma_per_sample = if phase { 1.0 / p as f64 } else { 1.0 / fs };
    layout.model_floor = WALKING_MODEL_FLOOR;
    layout.tolerances = WALKING_TOLERANCES;
    let (points, fit) = fit_grid(&e, &layout, params.min_repetitions, warnings);
    let mut schedule = axis(phase, params.event.as_deref().unwrap_or_default());
    schedule.values = points.iter().map(|p| p.sigma).collect();
    let baseline = format!(
        "each stride's deviation from the mean of the {} strides nearest it (itself included) at the same {}",
        neighbours.min(reps),
        if phase { "gait phase" } else { "time since the event" }
    );
    Ok(VaryingEstimate {
        method: VaryingMethod::Ensemble,
        schedule,
        coordinates: coords.to_vec(),
        forces: forces.to_vec(),
        sample_rate_hz: fs,
        cutoff_hz: lp.cutoff_hz(),
        resolution: layout.width() as f64 * layout.sigma_per_sample,
        resolution_note: format!(
            "{}{}",
            layout.note(),
            if phase {
                format!(
                    " (on the median stride of {} s)",
                    limpid_core::significant(median_s, 4)
                )
            } else {
                String::new()
            }
        ),
        repetitions: Some(reps),
        basis_order: None,
        order_cv_vaf: Vec::new(),
        points,
        fit,
        reflex: None,
        gait: Some(GaitSummary::new(params, (strides, fs), reps, baseline)),
        warnings: Vec::new(),
    })
}
