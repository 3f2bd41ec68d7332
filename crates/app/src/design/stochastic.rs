//! Experiment design for the stochastic method (issue 60): a periodic
//! multisine at the 3-D end point (x, y, z zippered random-odd lines),
//! estimated by `limpid estimate stochastic --period` (seed 004's M, B, K
//! fitted to Z over the excited lines, issue 59), chosen to minimise the
//! predicted relative mean squared error of the parameters that matter within
//! the limits and the time budget, at the prior's posture.
//!
//! **Family.** Period (the frequency resolution), band, amplitude spectrum
//! (`flat`: equal displacement per line; `1/f`: equal velocity; `1/f^2`:
//! equal acceleration) and the largest RMS every limit allows at every sample
//! (displacement, velocity and acceleration per channel, the force
//! `|M a + B v + K x|` on either end of the prior, the force at the limits'
//! nominal stiffness); the number of periods fills the budget after the
//! fade-in and fade-out periods (at least [`MIN_RECORDED_PERIODS`] recorded:
//! the standard errors come from their scatter).
//!
//! **Prediction.** As for the linear method: the spread of the estimator's
//! own M, B, K over recordings simulated on the prior
//! (`limpid_lab::session::periodic_endpoint_noisy`: the prior's noise model,
//! whose slow force fluctuation and posture drift sit below about 2 Hz and so
//! favour excitation above them, against inertia's need for acceleration
//! that the acceleration limit caps). Candidates are ranked on
//! [`super::RANKING_RUNS`] common-seed recordings by coordinate descent over
//! the four choices with Schroeder's phases (no optimisation: 0.2-0.5 s per
//! candidate saved); the chosen one gets optimised phases, is rescaled to the
//! limits and predicted on `runs` fresh seeds.

use limpid_analysis::result::design::{
    CommandSpectrum, CommandTrace, DesignChoice, DesignResult, LimitMargin, MultisineChoice,
    SearchSummary,
};
use limpid_core::criteria::MatrixVerdict;
use limpid_core::{Error, Result};
use limpid_ident::periodic_stochastic::estimate_stochastic_periodic;
use limpid_lab::design::Design;
use limpid_lab::follow::EndpointFollower;
use limpid_lab::periodic::{
    Command, Coordinates, MultisineSignal, PeriodicDesign, PeriodicLimits, Signal,
};
use limpid_lab::protocol::Limits;
use nalgebra::Vector3;

use super::{
    check_budget, check_runs, coordinate_descent, predict, rank, seeds, verify, DesignInputs, Grid,
    Impedance, Prior, Run, LIMIT_MARGIN, RANKING_RUNS,
};

/// Periods tried (s).
const PERIODS_S: [f64; 3] = [5.0, 10.0, 20.0];
/// Lower band edges tried (Hz).
const BAND_LOW_HZ: [f64; 4] = [0.2, 0.5, 1.0, 2.0];
/// Upper band edges tried (Hz).
const BAND_HIGH_HZ: [f64; 5] = [3.0, 5.0, 8.0, 12.0, 20.0];
/// Amplitude spectra tried.
const SHAPES: [&str; 3] = ["flat", "1/f", "1/f^2"];
/// Fewest recorded periods: the standard errors are their scatter.
pub const MIN_RECORDED_PERIODS: usize = 4;
/// Fewest excited lines per channel: M, B, K per coordinate need three, and a margin.
const MIN_LINES_PER_CHANNEL: usize = 4;
/// A line whose power is above this share of the strongest is excited (a
/// `1/f^2` spectrum over 0.2-20 Hz spans 1e-8; lines not excited hold rounding only).
const EXCITED_POWER: f64 = 1e-12;
/// Smallest RMS displacement designed (m), whatever the prior's position noise.
const LEAST_RMS_M: f64 = 1e-6;
/// The channels, in the end point's order.
const CHANNELS: [&str; 3] = ["x", "y", "z"];

/// A design request for the stochastic method: end-point limits
/// (displacement, velocity, acceleration, force, nominal stiffness) and an
/// end-point multisine as the baseline; the prior's posture is the
/// follower's equilibrium, the budget the whole command (fade-in, periods,
/// fade-out).
pub type StochasticDesignRequest = super::DesignRequest<PeriodicLimits, PeriodicDesign>;

/// A centre-out protocol's limits at the end point, the displacement within
/// the workspace around `start` when there is one.
fn endpoint_limits(l: &Limits, start: Option<Vector3<f64>>) -> PeriodicLimits {
    let room = start.map_or(f64::INFINITY, |s| {
        (0..3)
            .map(|i| (s[i] - l.workspace_min_m[i]).min(l.workspace_max_m[i] - s[i]))
            .fold(f64::INFINITY, f64::min)
    });
    PeriodicLimits {
        max_displacement_m: Some(l.max_displacement_m.min(room)),
        max_velocity_m_s: Some(l.max_velocity_m_s),
        max_acceleration_m_s2: Some(l.max_acceleration_m_s2),
        max_force_n: Some(l.max_force_n),
        nominal_stiffness_n_per_m: Some(l.nominal_stiffness_n_per_m),
        ..PeriodicLimits::default()
    }
}

/// A stochastic design request from its texts, as the CLI and Python take
/// them: the prior (as the linear method's), the limits from an end-point
/// periodic protocol or a centre-out one (its displacement limit kept inside
/// the workspace around the prior's posture; else the prior's `[limits]`),
/// the baseline end-point multisine. The sample rate is the limits
/// protocol's, else the baseline's, else 500 Hz.
pub fn stochastic_request_from_texts(inputs: &DesignInputs<'_>) -> Result<StochasticDesignRequest> {
    let DesignInputs {
        prior,
        limits_from,
        baseline,
        ..
    } = *inputs;
    let prior_text = prior;
    let prior = super::read_prior(prior)?;
    let limits_from = limits_from
        .map(|(text, path)| -> Result<(PeriodicLimits, f64)> {
            match Design::from_toml(text, path)? {
                Design::Periodic(p) if p.coordinates == Coordinates::Endpoint => {
                    Ok((p.limits, p.sample_rate_hz))
                }
                Design::CentreOut(p) => Ok((endpoint_limits(&p.limits, prior.start), p.sample_rate_hz)),
                _ => Err(Error::Format {
                    path: path.to_path_buf(),
                    message: "the limits' protocol must be an end-point periodic protocol (e.g. the endpoint-multisine preset) or a centre-out one".into(),
                }),
            }
        })
        .transpose()?;
    let baseline = baseline
        .map(|(text, path)| match Design::from_toml(text, path)? {
            Design::Periodic(p)
                if p.coordinates == Coordinates::Endpoint
                    && matches!(p.signal, Signal::Multisine(_)) =>
            {
                Ok(p)
            }
            _ => Err(Error::Format {
                path: path.to_path_buf(),
                message: "the baseline must be an end-point multisine (kind = \"multisine\", coordinates = \"endpoint\"): the stochastic design compares periodic protocols".into(),
            }),
        })
        .transpose()?;
    let (limits, sample_rate_hz) = match (limits_from, &prior.limits) {
        (Some(l), _) => l,
        (None, Some(l)) => (
            endpoint_limits(l, prior.start),
            baseline.as_ref().map_or(500.0, |b| b.sample_rate_hz),
        ),
        (None, None) => {
            return Err(Error::invalid(
                "limits_from",
                "no limits: take them from an end-point periodic or a centre-out protocol, or give a [limits] table in the prior",
            ))
        }
    };
    let request = inputs.request(prior, (limits, sample_rate_hz), baseline)?;
    check_request(&request)?;
    super::check_noise_at(&request.prior, prior_text, request.sample_rate_hz)?;
    Ok(request)
}

/// The request's numbers, before any simulation.
pub fn check_request(req: &StochasticDesignRequest) -> Result<()> {
    let l = &req.limits;
    for (name, v) in [
        ("max_displacement_m", l.max_displacement_m),
        ("max_velocity_m_s", l.max_velocity_m_s),
        ("max_acceleration_m_s2", l.max_acceleration_m_s2),
        ("max_force_n", l.max_force_n),
        ("nominal_stiffness_n_per_m", l.nominal_stiffness_n_per_m),
    ] {
        match v {
            Some(v) if v > 0.0 && v.is_finite() => {}
            Some(v) => {
                return Err(Error::invalid(
                    "limits",
                    format!(
                        "{name} = {}: a limit is a positive number",
                        limpid_core::error::Num(v)
                    ),
                ))
            }
            None => {
                return Err(Error::invalid(
                    "limits",
                    format!("{name} is missing: an end-point design needs it"),
                ))
            }
        }
    }
    if !(req.sample_rate_hz > 0.0 && req.sample_rate_hz <= 10_000.0) {
        return Err(Error::invalid(
            "sample_rate_hz",
            format!("{} Hz: expected 0 < rate <= 10000", req.sample_rate_hz),
        ));
    }
    check_budget(req.budget_s, req.sample_rate_hz)?;
    req.baseline
        .as_ref()
        .map(super::check_periodic_baseline)
        .transpose()?;
    check_runs("runs", req.runs, false)?;
    check_runs("verify", req.verify, true)?;
    Ok(())
}

/// Indices into the four lists of choices.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
struct Choice {
    period: usize,
    low: usize,
    high: usize,
    shape: usize,
}

impl Grid for Choice {
    const SIZES: &'static [usize] = &[
        PERIODS_S.len(),
        BAND_LOW_HZ.len(),
        BAND_HIGH_HZ.len(),
        SHAPES.len(),
    ];

    fn with(&self, dim: usize, value: usize) -> Choice {
        let mut c = *self;
        match dim {
            0 => c.period = value,
            1 => c.low = value,
            2 => c.high = value,
            _ => c.shape = value,
        }
        c
    }
}

/// A candidate: the protocol (scaled to the limits) and its command.
struct Candidate {
    protocol: PeriodicDesign,
    command: Command,
}

/// Peaks of a command, per quantity: the largest over channels of
/// displacement, velocity and acceleration (forward differences, as
/// `protocol check` takes them) and of the force on either end of the prior.
struct Peaks {
    displacement: f64,
    velocity: f64,
    acceleration: f64,
    force_on_prior: f64,
}

fn peaks(command: &Command, fs: f64, prior: &Prior) -> Peaks {
    let n = command.t.len();
    let mut places = [None; 3];
    for (c, name) in command.channels.iter().enumerate() {
        if let Some(i) = CHANNELS.iter().position(|n| n == name) {
            places[i] = Some(c);
        }
    }
    let at = |axis: usize, i: usize| places[axis].map_or(0.0, |c| command.values[c][i]);
    let mut p = Peaks {
        displacement: 0.0,
        velocity: 0.0,
        acceleration: 0.0,
        force_on_prior: 0.0,
    };
    let ends = prior.ends();
    for i in 0..n {
        let x = Vector3::from_fn(|a, _| at(a, i));
        let v = if i + 1 < n {
            Vector3::from_fn(|a, _| (at(a, i + 1) - at(a, i)) * fs)
        } else {
            Vector3::zeros()
        };
        let a = if i + 2 < n {
            Vector3::from_fn(|a, _| (at(a, i + 2) - 2.0 * at(a, i + 1) + at(a, i)) * fs * fs)
        } else {
            Vector3::zeros()
        };
        p.displacement = p.displacement.max(x.amax());
        p.velocity = p.velocity.max(v.amax());
        p.acceleration = p.acceleration.max(a.amax());
        for imp in &ends {
            let f = imp.inertia * a + imp.damping * v + imp.stiffness * x;
            p.force_on_prior = p.force_on_prior.max(f.norm());
        }
    }
    p
}

/// The limits' room over the peaks: the factor the command may be scaled by.
fn room(p: &Peaks, l: &PeriodicLimits) -> f64 {
    let limit = |v: Option<f64>| v.unwrap_or(f64::INFINITY);
    let stiffness = limit(l.nominal_stiffness_n_per_m);
    [
        limit(l.max_displacement_m) / p.displacement,
        limit(l.max_velocity_m_s) / p.velocity,
        limit(l.max_acceleration_m_s2) / p.acceleration,
        limit(l.max_force_n) / p.force_on_prior,
        limit(l.max_force_n) / (stiffness * p.displacement),
    ]
    .into_iter()
    .fold(f64::INFINITY, f64::min)
}

/// The protocol of a choice, scaled to the limits, or why it is refused.
fn candidate(
    req: &StochasticDesignRequest,
    c: &Choice,
    phases: &str,
) -> std::result::Result<Candidate, String> {
    let period_s = PERIODS_S[c.period];
    let band = [BAND_LOW_HZ[c.low], BAND_HIGH_HZ[c.high]];
    let fs = req.sample_rate_hz;
    if band[1] < 2.0 * band[0] {
        return Err(format!(
            "band {}-{} Hz is under an octave",
            band[0], band[1]
        ));
    }
    if band[1] > 0.4 * fs {
        return Err(format!(
            "band's top {} Hz is above 0.4 x the {fs} Hz rate",
            band[1]
        ));
    }
    let whole = (req.budget_s / period_s).floor() as usize;
    if whole < MIN_RECORDED_PERIODS + 2 {
        return Err(format!(
            "{whole} periods of {period_s} s fit in {} s; {MIN_RECORDED_PERIODS} recorded ones and the two fades are needed",
            req.budget_s
        ));
    }
    let shape = SHAPES[c.shape];
    let unit_rms = 1e-3;
    let mut protocol = PeriodicDesign {
        name: String::new(),
        coordinates: Coordinates::Endpoint,
        channels: CHANNELS.map(String::from).to_vec(),
        sample_rate_hz: fs,
        periods: whole - 2,
        seed: 1,
        signal: Signal::Multisine(MultisineSignal {
            phases: phases.into(),
            amplitude_shape: shape.into(),
            ..MultisineSignal::random_odd(period_s, band, vec![unit_rms; 3])
        }),
        limits: req.limits.clone(),
    };
    let mut command = protocol.command().map_err(|e| e.to_string())?;
    let lines = lines_per_channel(&command);
    if lines < MIN_LINES_PER_CHANNEL {
        return Err(format!(
            "{lines} lines per channel in {}-{} Hz at a {period_s} s period; at least {MIN_LINES_PER_CHANNEL}",
            band[0], band[1]
        ));
    }
    let scale = LIMIT_MARGIN * room(&peaks(&command, fs, &req.prior), &req.limits);
    if !(scale.is_finite() && scale > 0.0) {
        return Err("the limits leave no amplitude".into());
    }
    let rms = unit_rms * scale;
    // below the position noise the recorded displacement is the noise
    let floor = req.prior.noise.position_std_m.max(LEAST_RMS_M);
    if rms < floor {
        return Err(format!(
            "the limits leave {rms:.3e} m RMS per axis at {}-{} Hz {shape}, below the position noise's {floor:.1e} m",
            band[0], band[1]
        ));
    }
    for v in command.values.iter_mut().flatten() {
        *v *= scale;
    }
    if let Signal::Multisine(m) = &mut protocol.signal {
        m.rms = vec![rms; 3];
    }
    protocol.name = format!(
        "designed by limpid protocol design: zippered random-odd multisine at x, y, z, {}-{} Hz {shape}, {period_s} s period, {:.2} mm RMS",
        band[0],
        band[1],
        rms * 1e3
    );
    Ok(Candidate { protocol, command })
}

/// Excited lines of one recorded period, fewest over the channels.
fn lines_per_channel(command: &Command) -> usize {
    let n = command.period_samples;
    command
        .values
        .iter()
        .map(|x| {
            let s = limpid_dsp::excitation::period_spectrum(&x[n..2 * n]);
            let top = s.iter().skip(1).map(|c| c.norm_sqr()).fold(0.0, f64::max);
            s.iter()
                .skip(1)
                .filter(|c| c.norm_sqr() > EXCITED_POWER * top)
                .count()
        })
        .min()
        .unwrap_or(0)
}

/// One recording of `c` on subject `imp`, estimated as `limpid estimate
/// stochastic --period` does over the multisine's band.
fn run_once(c: &Candidate, prior: &Prior, imp: &Impedance, seed: u64) -> Result<Run> {
    let rows =
        |m: &nalgebra::Matrix3<f64>| std::array::from_fn(|r| std::array::from_fn(|k| m[(r, k)]));
    let subject = EndpointFollower {
        inertia: rows(&imp.inertia),
        damping: rows(&imp.damping),
        stiffness: rows(&imp.stiffness),
        equilibrium: prior.start().into(),
        ..EndpointFollower::default()
    };
    let rec = limpid_lab::session::periodic_endpoint_noisy(
        &c.protocol,
        &c.command,
        &subject,
        &prior.noise,
        seed,
    )?;
    let Signal::Multisine(m) = &c.protocol.signal else {
        unreachable!("the candidates are multisines")
    };
    let est = estimate_stochastic_periodic(&rec, m.period_s, (m.band_hz[0], m.band_hz[1]))?;
    let v = &est.criteria.verdicts;
    let identified = |verdict: Option<MatrixVerdict>| {
        verdict
            .is_some_and(|v| !matches!(v, MatrixVerdict::NotIdentifiable | MatrixVerdict::PoorFit))
    };
    Ok(Run::new(
        [&est.stiffness, &est.damping, &est.inertia],
        [
            identified(Some(v.stiffness)),
            identified(Some(v.damping)),
            identified(v.inertia),
        ],
        imp,
    ))
}

/// The designed multisine and its result.
pub struct StochasticDesigned {
    /// The protocol (`kind = "multisine"`, end point).
    pub protocol: PeriodicDesign,
    /// Everything measured about it.
    pub result: DesignResult,
}

/// Choose the multisine. Deterministic for a given request (seeded noise).
pub fn design_stochastic(req: &StochasticDesignRequest) -> Result<StochasticDesigned> {
    check_request(req)?;
    let ranking = seeds(req.seed, 0, RANKING_RUNS);
    let subjects = super::range_subjects(
        &req.prior.nominal,
        req.prior.other_end.as_ref(),
        req.objective.robust,
    );
    // start: the endpoint-multisine preset's shape (10 s, 0.5-5 Hz, flat)
    let start = Choice {
        period: 1,
        low: 1,
        high: 1,
        shape: 0,
    };
    let searched = coordinate_descent(start, "multisine", |c| {
        let cand = candidate(req, c, "schroeder")?;
        let run = |imp: &Impedance, s: u64| run_once(&cand, &req.prior, imp, s);
        rank(&run, &subjects, &req.objective, &ranking)
    })?;
    let (best, objective) = (searched.best, searched.objective);
    let chosen = candidate(req, &best, "optimised").map_err(|why| Error::invalid("design", why))?;
    // the sample-by-sample check `limpid protocol check` makes
    let report = chosen.protocol.check()?;
    let final_seeds = seeds(req.seed, 10_000, req.runs);
    let run = |imp: &Impedance, s: u64| run_once(&chosen, &req.prior, imp, s);
    let predicted = predict(
        &run,
        report.duration_s,
        &subjects,
        &req.objective,
        &final_seeds,
    )?;
    let baseline = req
        .baseline
        .as_ref()
        .map(|b| {
            let base = Candidate {
                protocol: b.clone(),
                command: b.command()?,
            };
            let run = |imp: &Impedance, s: u64| run_once(&base, &req.prior, imp, s);
            predict(
                &run,
                base.command.t.len() as f64 / b.sample_rate_hz,
                &subjects,
                &req.objective,
                &final_seeds,
            )
        })
        .transpose()?;
    let verify = (req.verify > 0)
        .then(|| verify(&run, req.prior.range(), &predicted, req.verify, req.seed))
        .transpose()?;
    let Signal::Multisine(m) = &chosen.protocol.signal else {
        unreachable!("the candidates are multisines")
    };
    let result = DesignResult {
        method: "stochastic".into(),
        family: "multisine".into(),
        objective: req.objective.recorded(),
        budget_s: req.budget_s,
        start_m: req.prior.start().into(),
        chosen: DesignChoice::Multisine(MultisineChoice {
            band_hz: m.band_hz,
            amplitude_shape: m.amplitude_shape.clone(),
            period_s: m.period_s,
            periods: chosen.protocol.periods,
            rms_m: m.rms[0],
            lines_per_channel: lines_per_channel(&chosen.command),
            duration_s: report.duration_s,
        }),
        predicted,
        baseline,
        protocol: serde_json::to_value(&chosen.protocol)
            .map_err(|e| Error::invalid("protocol", e.to_string()))?,
        limits: margins(&chosen, &req.prior),
        search: SearchSummary {
            candidates: searched.candidates,
            runs_per_candidate: RANKING_RUNS,
            refused: searched.refused,
            objective,
        },
        verify,
        command: command_trace(&chosen.command, req.sample_rate_hz),
        spectrum: line_spectrum(&chosen.command, req.sample_rate_hz, &req.limits),
    };
    Ok(StochasticDesigned {
        protocol: chosen.protocol,
        result,
    })
}

fn margins(c: &Candidate, prior: &Prior) -> Vec<LimitMargin> {
    let p = peaks(&c.command, c.protocol.sample_rate_hz, prior);
    let l = &c.protocol.limits;
    let entry = |quantity: &str, unit: &str, peak: f64, limit: Option<f64>| {
        limit.map(|limit| LimitMargin::new(quantity, unit, peak, limit))
    };
    [
        entry("displacement", "m", p.displacement, l.max_displacement_m),
        entry("velocity", "m/s", p.velocity, l.max_velocity_m_s),
        entry(
            "acceleration",
            "m/s^2",
            p.acceleration,
            l.max_acceleration_m_s2,
        ),
        entry("force on the prior", "N", p.force_on_prior, l.max_force_n),
        entry(
            "force at the nominal stiffness",
            "N",
            l.nominal_stiffness_n_per_m.unwrap_or(0.0) * p.displacement,
            l.max_force_n,
        ),
    ]
    .into_iter()
    .flatten()
    .collect()
}

/// One recorded period of the first channel, at most 2000 points.
fn command_trace(command: &Command, fs: f64) -> CommandTrace {
    let n = command.period_samples;
    let x = &command.values[0][n..2 * n + 2];
    let stride = n.div_ceil(2000).max(1);
    let picks: Vec<usize> = (0..n).step_by(stride).collect();
    CommandTrace {
        t_s: picks.iter().map(|&i| i as f64 / fs).collect(),
        displacement_m: picks.iter().map(|&i| x[i]).collect(),
        velocity_m_s: picks.iter().map(|&i| (x[i + 1] - x[i]) * fs).collect(),
        acceleration_m_s2: picks
            .iter()
            .map(|&i| (x[i + 2] - 2.0 * x[i + 1] + x[i]) * fs * fs)
            .collect(),
    }
}

/// The amplitude of every excited line (of the channel that excites it)
/// beside the limits' envelope `min(d, v / ω, a / ω²)`.
fn line_spectrum(command: &Command, fs: f64, l: &PeriodicLimits) -> CommandSpectrum {
    let n = command.period_samples;
    let spectra: Vec<Vec<f64>> = command
        .values
        .iter()
        .map(|x| limpid_dsp::excitation::line_amplitudes(&x[n..2 * n]))
        .collect();
    let top = spectra
        .iter()
        .flatten()
        .skip(1)
        .fold(0.0f64, |m, v| m.max(*v));
    let (mut frequency_hz, mut designed_m) = (Vec::new(), Vec::new());
    for k in 1..=n / 2 {
        let a = spectra.iter().map(|s| s[k]).fold(0.0f64, f64::max);
        if a * a > EXCITED_POWER * top * top {
            frequency_hz.push(k as f64 * fs / n as f64);
            designed_m.push(a);
        }
    }
    let limit = |v: Option<f64>| v.unwrap_or(f64::INFINITY);
    let limit_m = frequency_hz
        .iter()
        .map(|f| {
            let w = std::f64::consts::TAU * f;
            limit(l.max_displacement_m)
                .min(limit(l.max_velocity_m_s) / w)
                .min(limit(l.max_acceleration_m_s2) / (w * w))
        })
        .collect();
    CommandSpectrum {
        frequency_hz,
        designed_m,
        baseline_m: None,
        limit_m,
    }
}
