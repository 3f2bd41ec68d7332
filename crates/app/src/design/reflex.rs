//! Experiment design for the reflex method (issue 60): the PRBS switching
//! interval and register order that minimise the predicted mean squared
//! error of the stretch-reflex gain of the parallel cascade (Kearney, Stein &
//! Parameswaran 1997), at a fixed amplitude and within a time budget.
//!
//! The amplitude is the limits' largest joint displacement (so a design and
//! its baseline compare at equal amplitude when the limits say the
//! baseline's amplitude); the level changes are the periodic protocol's
//! shortest raised-cosine ramps within the velocity and acceleration limits
//! (`limpid_lab::periodic`). Candidates are ranked by the information the
//! recording holds about the gain in the cascade's parametric model (delay
//! and low-pass known, white torque noise): `Σ r⊥²`, the reflex pathway's
//! torque per unit gain left after least squares on the intrinsic regressors
//! `q, q', q'', 1`, from noise-free simulations of the command on the prior
//! ankle (`limpid_lab::ankle`). A spread over a few noisy recordings is too
//! rough to rank by (±30 % with six). The chosen PRBS and the baseline are
//! then predicted by the spread of the estimator's own gain over `runs`
//! recordings simulated with the prior's torque noise and estimated as
//! `limpid estimate reflex` does, beside the estimator's mean SE and the
//! information's `σ / sqrt(Σ r⊥²)`. A shorter
//! switching interval gives the reflex more velocity pulses to answer, until
//! the ramps and the actuator round them off and the reflex's own delay and
//! low-pass blur successive pulses: the optimum depends on the prior.

use std::path::Path;

use rayon::prelude::*;
use serde::Deserialize;

use limpid_analysis::result::design::{
    JointCommandTrace, JointLineSpectrum, LimitMargin, PrbsChoice, ReflexDesignResult,
    ReflexPrediction, SearchSummary,
};
use limpid_core::{Error, Result};
use limpid_ident::reflex::{estimate_reflex, ReflexParams};
use limpid_lab::ankle::{simulate_ankle_following, AnkleExperiment, AnkleReflex, AnkleSubject};
use limpid_lab::periodic::{PeriodicDesign, PeriodicLimits, PrbsSignal, Signal};

/// Switching intervals tried (s).
const SWITCH_INTERVALS_S: [f64; 9] = [0.02, 0.03, 0.04, 0.05, 0.07, 0.1, 0.15, 0.2, 0.3];
/// Register orders tried: the longest period that leaves at least [`MIN_PERIODS`] in the budget.
const ORDERS: std::ops::RangeInclusive<usize> = 4..=12;
/// Fewest recorded periods.
const MIN_PERIODS: usize = 2;
/// Shortest period (s): the cascade's nonparametric IRFs need an input that
/// does not repeat within many IRF lengths; an order-4 PRBS repeating every
/// second left the reflex gain 70 % off on the virtual ankle.
const MIN_PERIOD_S: f64 = 4.0;

/// The ankle as it is expected.
#[derive(Debug, Clone, Copy)]
pub struct ReflexPrior {
    /// Intrinsic I-B-K and the reflex.
    pub subject: AnkleSubject,
    /// White torque noise (N m, s.d.).
    pub torque_noise_nm: f64,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct ReflexPriorFile {
    inertia: f64,
    damping: f64,
    stiffness: f64,
    reflex: AnkleReflex,
    #[serde(default)]
    torque_noise_nm: Option<f64>,
}

impl ReflexPrior {
    /// limpid's virtual ankle (`limpid_lab::ankle`'s default subject, 0.1 N m noise).
    pub fn demo() -> ReflexPrior {
        ReflexPrior {
            subject: AnkleSubject::default(),
            torque_noise_nm: AnkleExperiment::default().torque_noise_nm,
        }
    }

    /// Read a prior ankle: `inertia`, `damping`, `stiffness` (SI), a
    /// `[reflex]` table (gain, delay_s, natural_hz, damping_ratio, positive)
    /// and optionally `torque_noise_nm` (default 0.1).
    pub fn from_toml(text: &str, path: &Path) -> Result<ReflexPrior> {
        limpid_lab::validate::check_numbers(text, path)?;
        let f: ReflexPriorFile = limpid_lab::validate::parse_settings(text, path)?;
        let noise = f.torque_noise_nm.unwrap_or(0.1);
        // an ankle's floors and a reflex's range (all positive): a gain of
        // 1e-300 or a delay of 10 s was designed for (issue 76)
        if let Some(message) = limpid_lab::validate::field_out_of_range(&[
            ("inertia", f.inertia, 1e-4, 10.0),
            ("damping", f.damping, 1e-3, 1e3),
            ("stiffness", f.stiffness, 1e-1, 1e5),
            ("reflex.gain", f.reflex.gain, 1e-3, 1e3),
            ("reflex.delay_s", f.reflex.delay_s, 1e-3, 0.5),
            ("reflex.natural_hz", f.reflex.natural_hz, 0.1, 100.0),
            ("reflex.damping_ratio", f.reflex.damping_ratio, 0.05, 10.0),
            ("torque_noise_nm", noise, 0.0, 1e3),
        ]) {
            return Err(Error::Format {
                path: path.to_path_buf(),
                message,
            });
        }
        Ok(ReflexPrior {
            subject: AnkleSubject {
                inertia: f.inertia,
                damping: f.damping,
                stiffness: f.stiffness,
                reflex: Some(f.reflex),
                ..AnkleSubject::default()
            },
            torque_noise_nm: noise,
        })
    }

    fn gain(&self) -> f64 {
        self.subject.reflex.map_or(0.0, |r| r.gain)
    }
}

/// A reflex design request.
#[derive(Debug, Clone)]
pub struct ReflexDesignRequest {
    /// The prior ankle.
    pub prior: ReflexPrior,
    /// Joint limits (the amplitude is their largest displacement).
    pub limits: PeriodicLimits,
    /// Sample rate (Hz).
    pub sample_rate_hz: f64,
    /// The whole command's length (s).
    pub budget_s: f64,
    /// Recordings behind the prediction.
    pub runs: usize,
    /// The PRBS it replaces.
    pub baseline: Option<PeriodicDesign>,
    /// Noise seed.
    pub seed: u64,
}

/// A reflex design request from its texts, as the CLI and Python take it:
/// the prior (`demo:ankle` or a prior ankle file's text), the limits and
/// sample rate from a PRBS protocol (else the baseline's), the baseline PRBS.
pub fn reflex_request_from_texts(
    prior: super::Text<'_>,
    limits_from: Option<super::Text<'_>>,
    baseline: Option<super::Text<'_>>,
    budget_s: f64,
    runs: usize,
    seed: u64,
) -> Result<ReflexDesignRequest> {
    let prior = match prior.0 {
        "demo:ankle" => ReflexPrior::demo(),
        other if other.starts_with("demo:") => {
            return Err(Error::invalid(
                "prior",
                format!("{other}: the reflex method's demo prior is demo:ankle"),
            ))
        }
        text => ReflexPrior::from_toml(text, prior.1)?,
    };
    let prbs = |(text, path): super::Text<'_>, role: &str| -> Result<PeriodicDesign> {
        match limpid_lab::design::Design::from_toml(text, path)? {
            limpid_lab::design::Design::Periodic(p) if matches!(p.signal, Signal::Prbs(_)) => Ok(p),
            _ => Err(Error::Format {
                path: path.to_path_buf(),
                message: format!("{role} must be a PRBS protocol (kind = \"prbs\") on one joint"),
            }),
        }
    };
    let limits_from = limits_from
        .map(|t| prbs(t, "the limits' protocol"))
        .transpose()?;
    let baseline = baseline.map(|t| prbs(t, "the baseline")).transpose()?;
    let Some(source) = limits_from.as_ref().or(baseline.as_ref()) else {
        return Err(Error::invalid(
            "limits_from",
            "no limits: take them from a PRBS protocol (e.g. the ankle-prbs preset)",
        ));
    };
    Ok(ReflexDesignRequest {
        prior,
        limits: source.limits.clone(),
        sample_rate_hz: source.sample_rate_hz,
        budget_s,
        runs,
        baseline,
        seed,
    })
}

/// The designed PRBS and its result.
pub struct ReflexDesigned {
    /// The protocol (`kind = "prbs"`).
    pub protocol: PeriodicDesign,
    /// What was measured about it.
    pub result: ReflexDesignResult,
}

fn prbs(
    req: &ReflexDesignRequest,
    switch_s: f64,
    order: usize,
    periods: usize,
    amplitude: f64,
) -> PeriodicDesign {
    PeriodicDesign {
        name: format!(
            "designed by limpid protocol design: PRBS {amplitude:.3} rad, {:.0} ms switching, order {order}, for the reflex gain",
            switch_s * 1e3
        ),
        coordinates: limpid_lab::periodic::Coordinates::Joint,
        channels: vec!["q1".into()],
        sample_rate_hz: req.sample_rate_hz,
        periods,
        seed: 1,
        signal: Signal::Prbs(PrbsSignal {
            order,
            switch_interval_s: switch_s,
            amplitude: vec![amplitude],
            ternary: false,
            edge_s: None,
        }),
        limits: req.limits.clone(),
    }
}

/// The candidate for one switching interval: of the register orders whose
/// period lasts at least [`MIN_PERIOD_S`], the one whose whole periods (at
/// least [`MIN_PERIODS`] recorded, plus fade-in and fade-out) fill most of
/// the budget; of equal fillings the longer period.
fn candidate(req: &ReflexDesignRequest, switch_s: f64, amplitude: f64) -> Option<PeriodicDesign> {
    let samples = (switch_s * req.sample_rate_hz).round();
    if samples < 1.0 {
        return None;
    }
    let switch_s = samples / req.sample_rate_hz;
    ORDERS
        .rev()
        .filter_map(|order| {
            let period = switch_s * ((1usize << order) - 1) as f64;
            let fit = (req.budget_s / period).floor() as usize;
            (fit >= MIN_PERIODS + 2 && period >= MIN_PERIOD_S).then_some((
                fit as f64 * period,
                order,
                fit,
            ))
        })
        // the most time used; `rev` puts the longer period first among equals
        .fold(None::<(f64, usize, usize)>, |best, c| match best {
            Some(b) if b.0 >= c.0 - 1e-9 => Some(b),
            _ => Some(c),
        })
        .map(|(_, order, fit)| prbs(req, switch_s, order, fit - 2, amplitude))
        .filter(|p| p.check().is_ok())
}

struct Runs {
    gains: Vec<f64>,
    gain_ses: Vec<f64>,
    intrinsic: Vec<[f64; 2]>,
}

fn simulate_runs(p: &PeriodicDesign, prior: &ReflexPrior, seeds: &[u64]) -> Result<Runs> {
    let command = p.command()?;
    let experiment = AnkleExperiment {
        rate_hz: p.sample_rate_hz,
        duration_s: command.t.len() as f64 / p.sample_rate_hz,
        torque_noise_nm: prior.torque_noise_nm,
        ..AnkleExperiment::default()
    };
    let params = ReflexParams::default();
    let out: Vec<(f64, f64, [f64; 2])> = seeds
        .par_iter()
        .map(|&seed| {
            let rec =
                simulate_ankle_following(&prior.subject, &experiment, &command.values[0], seed)?;
            let est = estimate_reflex(&rec, &params)?;
            Ok((
                est.reflex.gain,
                est.reflex.gain_se,
                [est.intrinsic.stiffness, est.intrinsic.damping],
            ))
        })
        .collect::<Result<_>>()?;
    Ok(Runs {
        gains: out.iter().map(|o| o.0).collect(),
        gain_ses: out.iter().map(|o| o.1).collect(),
        intrinsic: out.iter().map(|o| o.2).collect(),
    })
}

fn sd(v: &[f64]) -> f64 {
    let n = v.len() as f64;
    let mean = v.iter().sum::<f64>() / n;
    (v.iter().map(|x| (x - mean).powi(2)).sum::<f64>() / (n - 1.0).max(1.0)).sqrt()
}

/// The information the recording holds about the reflex gain: `Σ r⊥²`, the
/// reflex pathway's regressor (its torque per unit gain: delayed, rectified,
/// low-passed velocity) left after least squares on the intrinsic
/// regressors `q, q', q'', 1`. With white torque noise σ the gain's variance
/// in the parametric model (delay and low-pass known) is `σ² / Σ r⊥²`.
/// Computed from two noise-free simulations of the command (with and
/// without the reflex: the position servo makes q the same in both).
fn gain_information(p: &PeriodicDesign, prior: &ReflexPrior) -> Result<f64> {
    let command = p.command()?;
    let fs = p.sample_rate_hz;
    let experiment = AnkleExperiment {
        rate_hz: fs,
        duration_s: command.t.len() as f64 / fs,
        torque_noise_nm: 0.0,
        ..AnkleExperiment::default()
    };
    let with = simulate_ankle_following(&prior.subject, &experiment, &command.values[0], 0)?;
    let without_subject = AnkleSubject {
        reflex: None,
        ..prior.subject
    };
    let without = simulate_ankle_following(&without_subject, &experiment, &command.values[0], 0)?;
    let column = |rec: &limpid_core::Recording, name: &str| -> Vec<f64> {
        rec.column(name).map(<[f64]>::to_vec).unwrap_or_default()
    };
    let q = column(&with, "q1");
    let (t1, t0) = (column(&with, "tau1"), column(&without, "tau1"));
    let n = q.len();
    if n < 3 {
        return Ok(0.0);
    }
    let gain = prior.gain();
    let r: Vec<f64> = t1.iter().zip(&t0).map(|(a, b)| (a - b) / gain).collect();
    let mut x = nalgebra::DMatrix::<f64>::zeros(n - 2, 4);
    let mut y = nalgebra::DVector::<f64>::zeros(n - 2);
    for i in 1..n - 1 {
        x[(i - 1, 0)] = q[i];
        x[(i - 1, 1)] = (q[i + 1] - q[i - 1]) * fs / 2.0;
        x[(i - 1, 2)] = (q[i + 1] - 2.0 * q[i] + q[i - 1]) * fs * fs;
        x[(i - 1, 3)] = 1.0;
        y[i - 1] = r[i];
    }
    // columns scaled to unit norm, solved by SVD: the residual is what no intrinsic term explains
    let norms: Vec<f64> = (0..4).map(|c| x.column(c).norm().max(1e-300)).collect();
    for (c, norm) in norms.iter().enumerate() {
        x.column_mut(c).unscale_mut(*norm);
    }
    let beta = x
        .clone()
        .svd(true, true)
        .solve(&y, 1e-12)
        .map_err(|e| Error::invalid("design", e.to_string()))?;
    Ok((y - x * beta).norm_squared())
}

fn prediction(p: &PeriodicDesign, prior: &ReflexPrior, seeds: &[u64]) -> Result<ReflexPrediction> {
    let r = simulate_runs(p, prior, seeds)?;
    let n = r.gains.len() as f64;
    let truth = prior.gain();
    let information = gain_information(p, prior)?;
    Ok(ReflexPrediction {
        gain_se_information: prior.torque_noise_nm / information.max(1e-300).sqrt(),
        gain_sd: sd(&r.gains),
        gain_se_mean: r.gain_ses.iter().sum::<f64>() / n,
        gain_error_percent: 100.0 * r.gains.iter().map(|g| (g - truth).abs()).sum::<f64>()
            / n
            / truth,
        intrinsic_sd: [
            sd(&r.intrinsic.iter().map(|v| v[0]).collect::<Vec<_>>()),
            sd(&r.intrinsic.iter().map(|v| v[1]).collect::<Vec<_>>()),
        ],
        runs: r.gains.len(),
        duration_s: p.command()?.t.len() as f64 / p.sample_rate_hz,
    })
}

fn margins(p: &PeriodicDesign) -> Result<Vec<LimitMargin>> {
    let r = p.check()?;
    let l = &p.limits;
    let entry = |quantity: &str, unit: &str, peak: f64, limit: Option<f64>| {
        limit.map(|limit| LimitMargin::new(quantity, unit, peak, limit))
    };
    Ok([
        entry(
            "displacement",
            "rad",
            r.peak_displacement[0],
            l.max_joint_displacement_rad,
        ),
        entry(
            "velocity",
            "rad/s",
            r.peak_velocity[0],
            l.max_joint_velocity_rad_s,
        ),
        entry(
            "acceleration",
            "rad/s^2",
            r.peak_acceleration[0],
            l.max_joint_acceleration_rad_s2,
        ),
        entry(
            "torque at the nominal stiffness",
            "N m",
            r.peak_force[0],
            l.max_torque_nm,
        ),
    ]
    .into_iter()
    .flatten()
    .collect())
}

/// Choose the PRBS. Deterministic for a given request.
pub fn design_reflex(req: &ReflexDesignRequest) -> Result<ReflexDesigned> {
    if req.prior.gain() <= 0.0 {
        return Err(Error::invalid(
            "prior",
            "the prior ankle has no reflex to design for",
        ));
    }
    super::check_budget(req.budget_s, req.sample_rate_hz)?;
    req.baseline
        .as_ref()
        .map(super::check_periodic_baseline)
        .transpose()?;
    super::check_runs("runs", req.runs, false)?;
    let amplitude = req
        .limits
        .max_joint_displacement_rad
        .filter(|v| *v > 0.0)
        .ok_or_else(|| Error::invalid("limits", "max_joint_displacement_rad is missing: the PRBS amplitude is the largest displacement"))?
        * super::LIMIT_MARGIN;
    let mut best: Option<(f64, PeriodicDesign)> = None;
    let (mut candidates, mut refused) = (0usize, 0usize);
    for &switch_s in &SWITCH_INTERVALS_S {
        let Some(p) = candidate(req, switch_s, amplitude) else {
            refused += 1;
            continue;
        };
        candidates += 1;
        // the gain's variance per unit noise variance: smaller is better
        let value = 1.0 / gain_information(&p, &req.prior)?.max(1e-300);
        if best.as_ref().is_none_or(|(v, _)| value < *v) {
            best = Some((value, p));
        }
    }
    let Some((objective, protocol)) = best else {
        return Err(Error::invalid(
            "design",
            format!("no PRBS of {MIN_PERIODS} periods plus fade-in and fade-out fits the limits and {} s", req.budget_s),
        ));
    };
    let seeds = super::seeds(req.seed, 10_000, req.runs);
    let predicted = prediction(&protocol, &req.prior, &seeds)?;
    let baseline = req
        .baseline
        .as_ref()
        .map(|b| prediction(b, &req.prior, &seeds))
        .transpose()?;
    let Signal::Prbs(s) = &protocol.signal else {
        unreachable!("the candidates are PRBS")
    };
    let result = ReflexDesignResult {
        budget_s: req.budget_s,
        chosen: PrbsChoice {
            switch_interval_s: s.switch_interval_s,
            order: s.order,
            periods: protocol.periods,
            amplitude_rad: amplitude,
            duration_s: predicted.duration_s,
        },
        gain_spread_ratio: baseline.as_ref().map(|b| predicted.gain_sd / b.gain_sd),
        predicted,
        baseline,
        protocol: serde_json::to_value(&protocol)
            .map_err(|e| Error::invalid("protocol", e.to_string()))?,
        limits: margins(&protocol)?,
        search: SearchSummary {
            candidates,
            // noise-free: the information needs no noisy recordings
            runs_per_candidate: 0,
            refused,
            // the information's relative variance of the gain, percent²
            objective: 1e4 * objective * req.prior.torque_noise_nm.powi(2)
                / req.prior.gain().powi(2),
        },
        command: Some(command_trace(&protocol)?),
        spectrum: Some(line_spectrum(
            &protocol,
            req.baseline.as_ref(),
            s.switch_interval_s,
        )?),
    };
    Ok(ReflexDesigned { protocol, result })
}

/// The first samples (at most 2000) of the first recorded period.
fn command_trace(p: &PeriodicDesign) -> Result<JointCommandTrace> {
    let command = p.command()?;
    let fs = p.sample_rate_hz;
    let n = command.period_samples;
    let x = &command.values[0];
    let shown = n.min(2000);
    let at = |i: usize| x[n + i];
    Ok(JointCommandTrace {
        t_s: (0..shown).map(|i| i as f64 / fs).collect(),
        displacement_rad: (0..shown).map(at).collect(),
        velocity_rad_s: (0..shown).map(|i| (at(i + 1) - at(i)) * fs).collect(),
        acceleration_rad_s2: (0..shown)
            .map(|i| (at(i + 2) - 2.0 * at(i + 1) + at(i)) * fs * fs)
            .collect(),
    })
}

/// `2 |X_k| / n` at each excited line of one recorded period up to `1.5 / switch_s`.
fn period_lines(p: &PeriodicDesign, switch_s: f64) -> Result<(Vec<f64>, Vec<f64>)> {
    let command = p.command()?;
    let n = command.period_samples;
    let x = &command.values[0][n..2 * n];
    let spectrum = limpid_dsp::excitation::line_amplitudes(x);
    let df = p.sample_rate_hz / n as f64;
    let top = (1.5 / switch_s / df).floor() as usize;
    let amplitude = |k: usize| spectrum[k];
    let peak = spectrum.iter().skip(1).fold(0.0f64, |m, v| m.max(*v));
    // the sequence's nulls (multiples of 1 / switch_s) hold rounding only
    let lines: Vec<usize> = (1..spectrum.len().min(top + 1))
        .filter(|&k| amplitude(k) > 1e-3 * peak)
        .collect();
    Ok((
        lines.iter().map(|&k| k as f64 * df).collect(),
        lines.iter().map(|&k| amplitude(k)).collect(),
    ))
}

fn line_spectrum(
    p: &PeriodicDesign,
    baseline: Option<&PeriodicDesign>,
    switch_s: f64,
) -> Result<JointLineSpectrum> {
    let (frequency_hz, designed_rad) = period_lines(p, switch_s)?;
    let l = &p.limits;
    let limit = |v: Option<f64>| v.unwrap_or(f64::INFINITY);
    let limit_rad = frequency_hz
        .iter()
        .map(|f| {
            let w = std::f64::consts::TAU * f;
            limit(l.max_joint_displacement_rad)
                .min(limit(l.max_joint_velocity_rad_s) / w)
                .min(limit(l.max_joint_acceleration_rad_s2) / (w * w))
        })
        .collect();
    let base = baseline
        .map(|b| {
            let switch = match &b.signal {
                Signal::Prbs(s) => s.switch_interval_s,
                Signal::Multisine(_) => switch_s,
            };
            period_lines(b, switch)
        })
        .transpose()?;
    let (baseline_frequency_hz, baseline_rad) = base.unzip();
    Ok(JointLineSpectrum {
        frequency_hz,
        designed_rad,
        limit_rad,
        baseline_frequency_hz,
        baseline_rad,
    })
}
