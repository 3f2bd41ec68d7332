//! Intrinsic and reflex joint stiffness by the parallel-cascade method.
//!
//! Kearney, Stein & Parameswaran (1997), IEEE TBME 44(6) 493-504: the torque
//! of a joint under a stochastic position perturbation is the sum of an
//! *intrinsic* pathway, a two-sided impulse response (IRF) from position, and
//! a *reflex* pathway, a Hammerstein system: velocity, half-wave rectified,
//! through delayed linear dynamics. The two are fitted alternately, each on
//! the torque the other leaves unexplained, until the total VAF stops rising.
//! Seed 003 motivates it (a reflex limits how short a window can be); seed
//! 001's co-contraction changes both pathways.
//!
//! Choices (the papers leave them open; documented in docs/ARCHITECTURE.md):
//! - velocity and acceleration: central differences at the recorded rate
//!   (anti-aliased with the rest); velocity rectified after anti-aliasing,
//!   as Kearney et al. rectify the decimated velocity (`rectify_first`
//!   rectifies before, the physical order: on the virtual ankle, whose
//!   reflex acts on the true velocity, rectifying after biases the reflex
//!   gain by about -5 % and K by up to 7 %, rectifying first by under 2 %);
//! - decimation: 8th-order Butterworth zero-phase anti-alias filter at 0.8
//!   of the new Nyquist, then every R-th sample (R = round(fs / 100 Hz));
//! - IRFs: correlation functions and the Toeplitz pseudo-inverse, keeping the
//!   singular modes in order of their output variance and choosing their
//!   number by minimum description length (Westwick & Kearney 2003, ch. 5);
//! - VAF: `100 (1 - var(e) / var(tq))` on the decimated total torque, without
//!   the first reflex-IRF length (whose prediction lacks input history);
//! - intrinsic I-B-K: the joint parametric model below (its I-B-K part),
//!   standard errors by a 10-block jackknife (the residuals are coloured);
//!   `intrinsic.irf_fit` is the I-B-K least-squares fit of the torque the
//!   nonparametric reflex pathway leaves, for comparison;
//! - the rectifier's order is a choice the data cannot settle: the joint fit
//!   is repeated with the other order and the differences of I, B, K and G
//!   are added (in quadrature) to their standard errors, the other delay to
//!   the delay interval;
//! - joint parametric model: `tq = I q'' + B q' + K q + G LP2(rect v)(t - d)`,
//!   the reflex a rectified velocity -> delay -> gain -> unit-DC
//!   second-order low-pass; linear in I, B, K, G for a given delay and
//!   low-pass, which are scanned: delay on the recorded rate's grid (1 ms
//!   at 1 kHz), low-pass on a grid refined locally; the delay interval is a
//!   95 % profile-likelihood interval, with the residual's autocorrelation
//!   reducing the effective sample count.

use limpid_core::{Error, Recording, Result, Warning, WarningCode};
use limpid_dsp::LowPass;
use nalgebra::{DMatrix, DVector};
use rayon::prelude::*;
use schemars::JsonSchema;
use serde::{Deserialize, Serialize};

/// Settings of the parallel-cascade estimator.
#[derive(Debug, Clone)]
pub struct ReflexParams {
    /// Joint angle column (rad), e.g. `q1`; end-point `x` (m) works the same way.
    pub position: String,
    /// Torque (N m) or force (N) applied to the limb, e.g. `tau1`.
    pub torque: String,
    /// Rate the data are decimated to (Hz).
    pub decimated_rate_hz: f64,
    /// Intrinsic IRF spans +- this (s).
    pub intrinsic_half_width_s: f64,
    /// Reflex IRF length (s); also the span left out of every VAF.
    pub reflex_irf_s: f64,
    /// Largest reflex delay scanned by the parametric fit (s).
    pub max_delay_s: f64,
    /// Stop when the total VAF rises by less than this (percentage points).
    pub tolerance_vaf: f64,
    /// At most this many alternations.
    pub max_iterations: usize,
    /// Rectify the velocity at the recorded rate, before anti-aliasing (the
    /// physical order), instead of after (Kearney et al.'s method, default).
    pub rectify_first: bool,
}

impl Default for ReflexParams {
    fn default() -> Self {
        ReflexParams {
            position: "q1".into(),
            torque: "tau1".into(),
            decimated_rate_hz: 100.0,
            intrinsic_half_width_s: 0.04,
            reflex_irf_s: 1.0,
            max_delay_s: 0.15,
            tolerance_vaf: 0.05,
            max_iterations: 10,
            rectify_first: false,
        }
    }
}

/// A discrete impulse response: `torque(t) = sum values[i] * input(t - lags_s[i]) * dt`.
#[derive(Debug, Clone, Serialize, Deserialize, JsonSchema)]
pub struct Irf {
    /// Lags (s); negative lags weigh future input (two-sided IRFs).
    pub lags_s: Vec<f64>,
    /// Values per second of lag (input units to torque per s).
    pub values: Vec<f64>,
    /// Singular modes kept by the pseudo-inverse (MDL), of `lags_s.len()`.
    pub order: usize,
}

/// Which half of the velocity the rectifier passes.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize, JsonSchema)]
#[serde(rename_all = "snake_case")]
pub enum Polarity {
    /// `max(v, 0)`: the position column increasing.
    Positive,
    /// `max(-v, 0)`: the position column decreasing.
    Negative,
}

/// Intrinsic pathway.
#[derive(Debug, Clone, Serialize, Deserialize, JsonSchema)]
pub struct IntrinsicPathway {
    /// I (kg m^2 in joint space).
    pub inertia: f64,
    /// B (N m s/rad).
    pub damping: f64,
    /// K (N m/rad).
    pub stiffness: f64,
    /// Standard errors of I, B, K (10-block jackknife).
    pub standard_errors: Ibk,
    /// I-B-K fitted to the torque the nonparametric reflex pathway leaves (compare).
    pub irf_fit: Ibk,
    /// The two-sided IRF from position.
    pub irf: Irf,
}

/// Inertia, damping, stiffness.
#[derive(Debug, Clone, Copy, Serialize, Deserialize, JsonSchema)]
pub struct Ibk {
    /// I.
    pub inertia: f64,
    /// B.
    pub damping: f64,
    /// K.
    pub stiffness: f64,
}

/// Reflex pathway.
#[derive(Debug, Clone, Serialize, Deserialize, JsonSchema)]
pub struct ReflexPathway {
    /// The parametric model's structure.
    pub model: String,
    /// Half of the velocity that drives the reflex (the better fit of the two).
    pub polarity: Polarity,
    /// Total VAF (%) with the other polarity, for comparison.
    pub other_polarity_vaf: f64,
    /// DC gain on rectified velocity (N m s/rad).
    pub gain: f64,
    /// Standard error of the gain (autocorrelation-corrected).
    pub gain_se: f64,
    /// Delay (s) of the best parametric fit.
    pub delay_s: f64,
    /// 95 % profile-likelihood interval of the delay (s).
    pub delay_interval_s: [f64; 2],
    /// False when the data do not pin the delay down (see `warnings`).
    pub delay_identifiable: bool,
    /// Natural frequency of the low-pass (Hz).
    pub natural_frequency_hz: f64,
    /// Damping ratio of the low-pass.
    pub damping_ratio: f64,
    /// The one-sided IRF from rectified velocity (nonparametric pathway).
    pub irf: Irf,
    /// Total VAF (%) with the parametric reflex against delay (the scan).
    pub delay_scan: DelayScan,
}

/// The parametric fit's VAF against delay.
#[derive(Debug, Clone, Serialize, Deserialize, JsonSchema)]
pub struct DelayScan {
    /// Delays (s).
    pub delays_s: Vec<f64>,
    /// Total VAF (%), intrinsic plus parametric reflex, best low-pass per delay.
    pub vaf: Vec<f64>,
}

/// VAF split (percent of the decimated torque's variance).
#[derive(Debug, Clone, Copy, Serialize, Deserialize, JsonSchema)]
pub struct VafSplit {
    /// Intrinsic plus reflex pathway.
    pub vaf_total: f64,
    /// Intrinsic pathway alone.
    pub vaf_intrinsic: f64,
    /// Reflex pathway alone.
    pub vaf_reflex: f64,
    /// The joint parametric model (I-B-K plus delay-gain-low-pass reflex).
    pub vaf_parametric: f64,
    /// The I-B-K part of the joint parametric model alone.
    pub vaf_parametric_intrinsic: f64,
}

/// The plain I-B-K fit without a reflex pathway, for comparison.
#[derive(Debug, Clone, Copy, Serialize, Deserialize, JsonSchema)]
pub struct ReflexFreeFit {
    /// I, B, K of `tq = I q'' + B q' + K q`.
    pub parameters: Ibk,
    /// Its VAF (%).
    pub vaf: f64,
}

/// The joint parametric fit with the other rectifier order.
#[derive(Debug, Clone, Copy, Serialize, Deserialize, JsonSchema)]
pub struct OtherOrder {
    /// True: rectified before anti-aliasing.
    pub rectify_first: bool,
    /// I, B, K.
    pub intrinsic: Ibk,
    /// Reflex gain (N m s/rad).
    pub gain: f64,
    /// Reflex delay (s).
    pub delay_s: f64,
}

/// Decimated torque over 10 s (after the first reflex-IRF length), for plots.
#[derive(Debug, Clone, Serialize, Deserialize, JsonSchema)]
pub struct ReflexTraces {
    /// Time (s).
    pub t_s: Vec<f64>,
    /// Measured torque, mean removed.
    pub measured: Vec<f64>,
    /// Intrinsic pathway's torque.
    pub intrinsic: Vec<f64>,
    /// Reflex pathway's torque.
    pub reflex: Vec<f64>,
}

/// Result of the parallel-cascade estimator.
#[derive(Debug, Clone, Serialize, Deserialize, JsonSchema)]
pub struct ReflexEstimate {
    /// Position column.
    pub position: String,
    /// Torque column.
    pub torque: String,
    /// Recorded sample rate (Hz).
    pub sample_rate_hz: f64,
    /// Rate after decimation (Hz).
    pub decimated_rate_hz: f64,
    /// Duration (s).
    pub duration_s: f64,
    /// Intrinsic pathway.
    pub intrinsic: IntrinsicPathway,
    /// Reflex pathway.
    pub reflex: ReflexPathway,
    /// VAF of the nonparametric pathways.
    pub fit: VafSplit,
    /// Total VAF (%) on the last third when fitted on the first two thirds.
    pub cross_validated_vaf: f64,
    /// Alternations run.
    pub iterations: usize,
    /// The reflex-free I-B-K fit, to see what the reflex pathway changes.
    pub reflex_free: ReflexFreeFit,
    /// The joint parametric fit with the rectifier on the other side of the
    /// anti-alias filter; its differences are included in the standard errors.
    pub other_rectifier_order: Option<OtherOrder>,
    /// Torque traces.
    pub traces: ReflexTraces,
    /// What the reader should know.
    pub warnings: Vec<Warning>,
}

/// A reflex pathway that raises the total VAF by less than this (points) is called absent.
pub const REFLEX_PRESENT_VAF: f64 = 1.0;
/// A delay interval wider than this (s) is "not identifiable".
pub const DELAY_INTERVAL_MAX_S: f64 = 0.03;

/// Data decimated and centred, ready for the cascade.
struct Decimated {
    fs: f64,
    ratio: usize,
    position: Vec<f64>,
    velocity: Vec<f64>,
    acceleration: Vec<f64>,
    torque: Vec<f64>,
    /// Rectified velocity per polarity, decimated and centred.
    rectified: [Vec<f64>; 2],
    /// Anti-aliased velocity rectified per polarity at the recorded rate (for delays finer than a decimated sample).
    rectified_full: [Vec<f64>; 2],
}

/// The parallel-cascade estimate of `rec`.
pub fn estimate_reflex(rec: &Recording, p: &ReflexParams) -> Result<ReflexEstimate> {
    // one column as both would "explain" the torque perfectly (K = 1, VAF 100 %)
    if p.position == p.torque {
        return Err(Error::invalid(
            "position and torque",
            format!("column {} names both; they must be two columns", p.position),
        ));
    }
    let q = rec.require(
        &p.position,
        "the joint angle of the parallel-cascade method",
    )?;
    let tq = rec.require(&p.torque, "the torque of the parallel-cascade method")?;
    let fs = rec.sample_rate();
    if p.decimated_rate_hz > fs * (1.0 + limpid_core::recording::SAMPLING_TOLERANCE) {
        return Err(Error::invalid(
            "decimated rate",
            format!(
                "{} Hz is above the recording's {} Hz ({}); limpid decimates, it does not interpolate",
                limpid_core::short_number(p.decimated_rate_hz),
                limpid_core::short_number(fs),
                rec.path().display()
            ),
        ));
    }
    // the length check comes before decimation, whose zero-phase filter
    // would refuse a short recording without naming it
    let ratio = ((fs / p.decimated_rate_hz).round() as usize).max(1);
    let fsd = fs / ratio as f64;
    let n = q.len().div_ceil(ratio);
    let lag = |s: f64| (s * fsd).round() as usize;
    let half = lag(p.intrinsic_half_width_s).max(1);
    let n_reflex = lag(p.reflex_irf_s).max(2);
    let needed = 5 * n_reflex.max(2 * half + 1);
    if n < needed {
        return Err(Error::TooFewSamples {
            path: rec.path().to_path_buf(),
            what: format!(
                "the parallel-cascade method at {} Hz (5 reflex-IRF lengths, {:.1} s; found {:.2} s)",
                limpid_core::short_number(fsd),
                needed as f64 / fsd,
                n as f64 / fsd
            ),
            needed: needed * ratio,
            found: q.len(),
        });
    }
    let [d, other_decimation] = decimate(q, tq, fs, p)?;
    debug_assert_eq!(d.position.len(), n);
    for (name, raw) in [(&p.position, q), (&p.torque, tq)] {
        let scale = raw.iter().fold(0.0_f64, |m, v| m.max(v.abs()));
        // scaled first, so that tiny or huge columns do not under- or overflow here
        let scaled: Vec<f64> = raw
            .iter()
            .map(|v| v / scale.max(f64::MIN_POSITIVE))
            .collect();
        let sd = variance(&scaled).sqrt() * scale;
        let problem = if !(sd > 1e-9 * scale && sd > 0.0) {
            Some("does not vary: nothing to identify".to_string())
        } else if !(1e-150..1e150).contains(&sd) {
            Some(format!(
                "varies by {} (standard deviation), outside 1e-150..1e150 where its squares are computed exactly: rescale the column",
                limpid_core::short_number(sd)
            ))
        } else {
            None
        };
        if let Some(problem) = problem {
            return Err(Error::invalid(
                rec.path().display().to_string(),
                format!("column {name} {problem}"),
            ));
        }
    }
    let skip = n_reflex;
    let cascades: Vec<Cascade> = [0, 1]
        .par_iter()
        .map(|&k| {
            cascade(
                &d.position,
                &d.rectified[k],
                &d.torque,
                half,
                n_reflex,
                skip,
                p,
            )
        })
        .collect();
    let best = if cascades[0].vaf_total >= cascades[1].vaf_total {
        0
    } else {
        1
    };
    let c = &cascades[best];
    let polarity = if best == 0 {
        Polarity::Positive
    } else {
        Polarity::Negative
    };
    let mut warnings = Vec::new();

    let dt = 1.0 / d.fs;
    // the fully parametric model, fitted jointly (I-B-K, delay, gain, low-pass)
    let Some(mut param) = reflex_parametric(&d, best, skip, p, fs) else {
        return Err(Error::invalid(
            rec.path().display().to_string(),
            "position, velocity and acceleration are collinear: I, B and K cannot be separated",
        ));
    };
    // Rectifying before or after anti-aliasing is a modelling choice the data
    // cannot settle (the reflex acts on the true velocity, the method
    // rectifies the decimated one); the fit with the other order is reported
    // and its difference added to the standard errors and the delay interval.
    let other_order = reflex_parametric(&other_decimation, best, skip, p, fs);
    let mut order_warning = None;
    if let Some(o) = &other_order {
        let z = (param.intrinsic.stiffness - o.intrinsic.stiffness).abs()
            / param.intrinsic_se.stiffness.max(f64::MIN_POSITIVE);
        if z > 2.0 {
            order_warning = Some(Warning::new(
                WarningCode::NoisyRegressors,
                format!(
                    "rectifying {} anti-aliasing changes K by {} N m/rad ({z:.1} jackknife SE): the standard errors include this difference",
                    if p.rectify_first { "after" } else { "before" },
                    limpid_core::short_number(o.intrinsic.stiffness - param.intrinsic.stiffness)
                ),
            ));
        }
        let widen = |se: &mut f64, a: f64, b: f64| *se = se.hypot(a - b);
        widen(
            &mut param.intrinsic_se.inertia,
            param.intrinsic.inertia,
            o.intrinsic.inertia,
        );
        widen(
            &mut param.intrinsic_se.damping,
            param.intrinsic.damping,
            o.intrinsic.damping,
        );
        widen(
            &mut param.intrinsic_se.stiffness,
            param.intrinsic.stiffness,
            o.intrinsic.stiffness,
        );
        widen(&mut param.gain_se, param.gain, o.gain);
        param.interval = [
            param.interval[0].min(o.delay_s),
            param.interval[1].max(o.delay_s),
        ];
    }
    // model error the resampling cannot see (see MODEL_ERROR_FLOOR)
    let floor = |se: &mut f64, v: f64| *se = se.hypot(MODEL_ERROR_FLOOR * v);
    floor(&mut param.intrinsic_se.damping, param.intrinsic.damping);
    floor(&mut param.intrinsic_se.inertia, param.intrinsic.inertia);
    let fit = VafSplit {
        vaf_total: c.vaf_total,
        vaf_intrinsic: vaf(&d.torque, &c.intrinsic_torque, skip),
        vaf_reflex: vaf(&d.torque, &c.reflex_torque, skip),
        vaf_parametric: param.total_vaf,
        vaf_parametric_intrinsic: vaf(&d.torque, &parametric_intrinsic(&d, &param.intrinsic), skip),
    };

    // cross-validation: fit on the first two thirds, predict the last third
    let split = 2 * n / 3;
    let cv = cascade(
        &d.position[..split],
        &d.rectified[best][..split],
        &d.torque[..split],
        half,
        n_reflex,
        skip,
        p,
    );
    let predicted: Vec<f64> = apply(&cv.intrinsic, -(half as isize), &d.position)
        .iter()
        .zip(apply(&cv.reflex, 0, &d.rectified[best]))
        .map(|(a, b)| a + b)
        .collect();
    let cross_validated_vaf = vaf(&d.torque[split..], &predicted[split..], 0);

    // intrinsic I-B-K from the joint parametric model; for comparison, the
    // fit of the torque the nonparametric reflex leaves, and the reflex-free fit
    let regressors = [&d.acceleration[..], &d.velocity[..], &d.position[..]];
    let intrinsic_target: Vec<f64> = d
        .torque
        .iter()
        .zip(&c.reflex_torque)
        .map(|(t, r)| t - r)
        .collect();
    let (irf_fit, _, _) = ibk_fit(&regressors, &intrinsic_target, skip);
    let (ibk, ibk_se) = (param.intrinsic, param.intrinsic_se);
    let (plain, _, plain_vaf) = ibk_fit(&regressors, &d.torque, skip);
    let reflex_gain_points = param.total_vaf - param.intrinsic_only_vaf;
    let mut delay_identifiable = true;
    warnings.extend(order_warning);
    if reflex_gain_points < REFLEX_PRESENT_VAF {
        delay_identifiable = false;
        warnings.push(Warning::new(
            WarningCode::NotIdentifiable,
            format!(
                "reflex delay not identifiable: the reflex pathway explains only {reflex_gain_points:.2} VAF points (< {REFLEX_PRESENT_VAF}), no reflex to time"
            ),
        ));
    } else if !param.interval_contiguous
        || param.interval[1] - param.interval[0] > DELAY_INTERVAL_MAX_S + 0.5 / fs
        || param.at_scan_edge
    {
        delay_identifiable = false;
        warnings.push(Warning::new(
            WarningCode::NotIdentifiable,
            format!(
                "reflex delay not identifiable: the fit is as good for delays {:.0}-{:.0} ms{}{}",
                param.interval[0] * 1e3,
                param.interval[1] * 1e3,
                if param.interval_contiguous {
                    ""
                } else {
                    " and elsewhere in the scan"
                },
                if param.at_scan_edge {
                    " (best at the end of the scanned range)"
                } else {
                    ""
                }
            ),
        ));
    }
    if (cascades[0].vaf_total - cascades[1].vaf_total).abs() < 1.0
        && reflex_gain_points >= REFLEX_PRESENT_VAF
    {
        warnings.push(Warning::new(
            WarningCode::NotIdentifiable,
            format!(
                "reflex polarity ambiguous: total VAF {:.1} % (positive) vs {:.1} % (negative)",
                cascades[0].vaf_total, cascades[1].vaf_total
            ),
        ));
    }
    if ibk.inertia < 0.0 || ibk.stiffness < 0.0 || ibk.damping < 0.0 {
        warnings.push(Warning::new(
            WarningCode::NotPositiveDefinite,
            format!(
                "intrinsic I-B-K has a negative parameter (I {:.4}, B {:.4}, K {:.4}): not a passive joint",
                ibk.inertia, ibk.damping, ibk.stiffness
            ),
        ));
    }
    if fit.vaf_total < 50.0 {
        warnings.push(Warning::new(
            WarningCode::PoorFit,
            format!(
                "the two pathways explain only {:.1} % of the torque variance",
                fit.vaf_total
            ),
        ));
    }
    if fit.vaf_total - cross_validated_vaf > 5.0 {
        warnings.push(Warning::new(
            WarningCode::PoorFit,
            format!(
                "over-fitting: VAF {:.1} % on the fitted data but {:.1} % on the held-out last third",
                fit.vaf_total, cross_validated_vaf
            ),
        ));
    }

    let irf = |h: &[f64], first: isize, order: usize| Irf {
        lags_s: (0..h.len())
            .map(|i| (first + i as isize) as f64 * dt)
            .collect(),
        values: h.iter().map(|v| v / dt).collect(),
        order,
    };
    // a 10 s stretch after the left-out first reflex-IRF length, every
    // decimated sample: a whole record at this scale is unreadable
    let shown = skip..(skip + (10.0 * d.fs).round() as usize).min(n);
    let traces = ReflexTraces {
        t_s: shown.clone().map(|i| i as f64 * dt).collect(),
        measured: d.torque[shown.clone()].to_vec(),
        intrinsic: c.intrinsic_torque[shown.clone()].to_vec(),
        reflex: c.reflex_torque[shown].to_vec(),
    };
    let est = ReflexEstimate {
        position: p.position.clone(),
        torque: p.torque.clone(),
        sample_rate_hz: fs,
        decimated_rate_hz: d.fs,
        duration_s: rec.len() as f64 / fs,
        intrinsic: IntrinsicPathway {
            inertia: ibk.inertia,
            damping: ibk.damping,
            stiffness: ibk.stiffness,
            standard_errors: ibk_se,
            irf_fit,
            irf: irf(&c.intrinsic, -(half as isize), c.intrinsic_order),
        },
        reflex: ReflexPathway {
            model: "half-wave rectified velocity -> delay -> gain -> second-order low-pass (unit DC gain)".into(),
            polarity,
            other_polarity_vaf: cascades[1 - best].vaf_total,
            gain: param.gain,
            gain_se: param.gain_se,
            delay_s: param.delay_s,
            delay_interval_s: param.interval,
            delay_identifiable,
            natural_frequency_hz: param.natural_hz,
            damping_ratio: param.damping_ratio,
            irf: irf(&c.reflex, 0, c.reflex_order),
            delay_scan: DelayScan {
                delays_s: param.scan_delays_s,
                vaf: param.scan_vaf,
            },
        },
        fit,
        cross_validated_vaf,
        iterations: c.iterations,
        reflex_free: ReflexFreeFit {
            parameters: plain,
            vaf: plain_vaf,
        },
        other_rectifier_order: other_order.as_ref().map(|o| OtherOrder {
            rectify_first: !p.rectify_first,
            intrinsic: o.intrinsic,
            gain: o.gain,
            delay_s: o.delay_s,
        }),
        traces,
        warnings,
    };
    if !all_finite(&est) {
        return Err(Error::invalid(
            rec.path().display().to_string(),
            "the parallel-cascade fit did not give finite numbers (values too large or degenerate input)",
        ));
    }
    Ok(est)
}

/// Share of I and B added (in quadrature) to their standard errors: the
/// finite differences, the anti-aliasing and the reflex model's discretisation
/// bias B by a shared amount that no jackknife block sees (`limpid calibrate`
/// on virtual ankles: +1.5 % without a reflex, +2 to +8 % with one; with this
/// floor 95 % of 80 B values lie within ±2 SE, 84 % at 1 %).
pub const MODEL_ERROR_FLOOR: f64 = 0.02;

fn all_finite(e: &ReflexEstimate) -> bool {
    let i = &e.intrinsic;
    let r = &e.reflex;
    [
        i.inertia,
        i.damping,
        i.stiffness,
        i.standard_errors.inertia,
        i.standard_errors.damping,
        i.standard_errors.stiffness,
        r.gain,
        r.gain_se,
        r.delay_s,
        r.natural_frequency_hz,
        r.damping_ratio,
        e.fit.vaf_parametric,
        e.fit.vaf_parametric_intrinsic,
        e.fit.vaf_total,
        e.fit.vaf_intrinsic,
        e.fit.vaf_reflex,
        e.cross_validated_vaf,
        e.reflex_free.vaf,
    ]
    .iter()
    .chain(&i.irf.values)
    .chain(&r.irf.values)
    .all(|v| v.is_finite())
}

fn mean(x: &[f64]) -> f64 {
    x.iter().sum::<f64>() / x.len().max(1) as f64
}

fn variance(x: &[f64]) -> f64 {
    let m = mean(x);
    x.iter().map(|v| (v - m) * (v - m)).sum::<f64>() / x.len().max(1) as f64
}

fn centre(x: &mut [f64]) {
    let m = mean(x);
    x.iter_mut().for_each(|v| *v -= m);
}

/// `100 (1 - var(y - yhat) / var(y))` over `y[skip..]`.
pub fn vaf(y: &[f64], yhat: &[f64], skip: usize) -> f64 {
    let y = &y[skip.min(y.len())..];
    let yhat = &yhat[skip.min(yhat.len())..];
    let e: Vec<f64> = y.iter().zip(yhat).map(|(a, b)| a - b).collect();
    let vy = variance(y);
    if vy > 0.0 {
        100.0 * (1.0 - variance(&e) / vy)
    } else {
        0.0
    }
}

/// Anti-alias and decimate angle, torque, velocity and acceleration, with the
/// rectified velocity in both orders: `[p.rectify_first's order, the other]`
/// (the two share every filtered column but the rectified ones).
fn decimate(q: &[f64], tq: &[f64], fs: f64, p: &ReflexParams) -> Result<[Decimated; 2]> {
    let ratio = ((fs / p.decimated_rate_hz).round() as usize).max(1);
    let fsd = fs / ratio as f64;
    let velocity = limpid_dsp::central_first(q, 1.0 / fs);
    let acceleration = limpid_dsp::central_second(q, 1.0 / fs);
    let rectify =
        |v: &[f64], sign: f64| -> Vec<f64> { v.iter().map(|x| (sign * x).max(0.0)).collect() };
    // rectified before anti-aliasing: the physical order
    let (pos_raw, neg_raw) = (rectify(&velocity, 1.0), rectify(&velocity, -1.0));
    let columns: Vec<Vec<f64>> = vec![
        q.to_vec(),
        tq.to_vec(),
        velocity,
        acceleration,
        pos_raw,
        neg_raw,
    ];
    let mut filtered: Vec<Vec<f64>> = if ratio > 1 {
        let lp = LowPass::butterworth(8, 0.8 * fsd / 2.0, fs)?;
        columns
            .par_iter()
            .map(|x| lp.filtfilt(x))
            .collect::<Result<Vec<_>>>()?
    } else {
        columns
    };
    // rectified after anti-aliasing, so that every decimation phase of it
    // is the rectified decimated velocity (Kearney et al.)
    let after = [rectify(&filtered[2], 1.0), rectify(&filtered[2], -1.0)];
    let negative = filtered.pop().unwrap_or_default();
    let positive = filtered.pop().unwrap_or_default();
    let before = [positive, negative];
    let pick = |x: &[f64]| -> Vec<f64> {
        let mut d: Vec<f64> = x.iter().step_by(ratio).copied().collect();
        centre(&mut d);
        d
    };
    let with = |[positive, negative]: [Vec<f64>; 2]| Decimated {
        fs: fsd,
        ratio,
        position: pick(&filtered[0]),
        velocity: pick(&filtered[2]),
        acceleration: pick(&filtered[3]),
        torque: pick(&filtered[1]),
        rectified: [pick(&positive), pick(&negative)],
        rectified_full: [positive, negative],
    };
    Ok(if p.rectify_first {
        [with(before), with(after)]
    } else {
        [with(after), with(before)]
    })
}

/// `sum_t a[t] b[t + k] / n`.
fn correlation(a: &[f64], b: &[f64], k: isize) -> f64 {
    let n = a.len();
    let s: f64 = if k >= 0 {
        let k = k as usize;
        a[..n - k.min(n)]
            .iter()
            .zip(&b[k.min(n)..])
            .map(|(x, y)| x * y)
            .sum()
    } else {
        let k = (-k) as usize;
        a[k.min(n)..]
            .iter()
            .zip(&b[..n - k.min(n)])
            .map(|(x, y)| x * y)
            .sum()
    };
    s / n as f64
}

/// IRF with lags `first..first + lags` from `u` to `y` by the Toeplitz
/// pseudo-inverse; modes kept in order of output variance, their number by
/// minimum description length. Returns the per-sample IRF and the order.
fn irf_pinv(u: &[f64], y: &[f64], first: isize, lags: usize) -> (Vec<f64>, usize) {
    let n = u.len() as f64;
    let auto: Vec<f64> = (0..lags).map(|k| correlation(u, u, k as isize)).collect();
    let cross: Vec<f64> = (0..lags)
        .map(|j| correlation(u, y, first + j as isize))
        .collect();
    let toeplitz = DMatrix::from_fn(lags, lags, |i, j| auto[i.abs_diff(j)]);
    let Some(eig) = limpid_core::linalg::symmetric_eigen(toeplitz) else {
        return (vec![0.0; lags], 0);
    };
    let smax = eig.eigenvalues.iter().fold(0.0_f64, |m, v| m.max(*v));
    let c = eig.eigenvectors.transpose() * DVector::from_column_slice(&cross);
    let mut modes: Vec<(usize, f64)> = (0..lags)
        .filter(|&i| eig.eigenvalues[i] > smax * 1e-12)
        .map(|i| (i, c[i] * c[i] / eig.eigenvalues[i]))
        .collect();
    modes.sort_by(|a, b| b.1.total_cmp(&a.1));
    let yy = correlation(y, y, 0);
    let mut explained = 0.0;
    let mut order = 0;
    let mut best = yy;
    for (k, (_, v)) in modes.iter().enumerate() {
        explained += v;
        let mdl = (1.0 + (k + 1) as f64 * n.ln() / n) * (yy - explained);
        if mdl < best {
            best = mdl;
            order = k + 1;
        }
    }
    let mut h = vec![0.0; lags];
    for &(i, _) in &modes[..order] {
        let w = c[i] / eig.eigenvalues[i];
        for (hj, vj) in h.iter_mut().zip(eig.eigenvectors.column(i).iter()) {
            *hj += w * vj;
        }
    }
    (h, order)
}

/// `y[t] = sum_j h[j] u[t - (first + j)]`, zero input outside the record.
fn apply(h: &[f64], first: isize, u: &[f64]) -> Vec<f64> {
    let n = u.len() as isize;
    let mut y = vec![0.0; u.len()];
    for (j, &hj) in h.iter().enumerate() {
        let l = first + j as isize;
        let (lo, hi) = (l.max(0), (n + l).min(n));
        for t in lo..hi {
            y[t as usize] += hj * u[(t - l) as usize];
        }
    }
    y
}

struct Cascade {
    intrinsic: Vec<f64>,
    intrinsic_order: usize,
    reflex: Vec<f64>,
    reflex_order: usize,
    intrinsic_torque: Vec<f64>,
    reflex_torque: Vec<f64>,
    vaf_total: f64,
    iterations: usize,
}

/// Alternate the two pathways, each on the other's residual (Kearney et al. 1997).
fn cascade(
    position: &[f64],
    rectified: &[f64],
    torque: &[f64],
    half: usize,
    n_reflex: usize,
    skip: usize,
    p: &ReflexParams,
) -> Cascade {
    let mut reflex_torque = vec![0.0; torque.len()];
    let mut best: Option<Cascade> = None;
    for iteration in 1..=p.max_iterations.max(1) {
        let target: Vec<f64> = torque
            .iter()
            .zip(&reflex_torque)
            .map(|(t, r)| t - r)
            .collect();
        let (hi, oi) = irf_pinv(position, &target, -(half as isize), 2 * half + 1);
        let intrinsic_torque = apply(&hi, -(half as isize), position);
        let target: Vec<f64> = torque
            .iter()
            .zip(&intrinsic_torque)
            .map(|(t, i)| t - i)
            .collect();
        let (hr, or) = irf_pinv(rectified, &target, 0, n_reflex);
        reflex_torque = apply(&hr, 0, rectified);
        let total: Vec<f64> = intrinsic_torque
            .iter()
            .zip(&reflex_torque)
            .map(|(a, b)| a + b)
            .collect();
        let v = vaf(torque, &total, skip);
        let previous = best.as_ref().map_or(f64::NEG_INFINITY, |b| b.vaf_total);
        let done = v - previous < p.tolerance_vaf;
        if v >= previous {
            best = Some(Cascade {
                intrinsic: hi,
                intrinsic_order: oi,
                reflex: hr,
                reflex_order: or,
                intrinsic_torque,
                reflex_torque: reflex_torque.clone(),
                vaf_total: v,
                iterations: iteration,
            });
        }
        if done {
            break;
        }
    }
    best.expect("at least one iteration")
}

/// The torque of the intrinsic I-B-K model (centred).
fn parametric_intrinsic(d: &Decimated, p: &Ibk) -> Vec<f64> {
    (0..d.torque.len())
        .map(|t| {
            p.inertia * d.acceleration[t] + p.damping * d.velocity[t] + p.stiffness * d.position[t]
        })
        .collect()
}

/// I-B-K (with a constant) by least squares on `rows[skip..]`, with
/// 10-block jackknife standard errors, and the fit's VAF.
fn ibk_fit(regressors: &[&[f64]; 3], y: &[f64], skip: usize) -> (Ibk, Ibk, f64) {
    let n = y.len();
    let rows = skip..n;
    let scale: Vec<f64> = regressors
        .iter()
        .map(|x| variance(&x[rows.clone()]).sqrt().max(f64::MIN_POSITIVE))
        .collect();
    let blocks = 10;
    let len = rows.len();
    let mut grams = vec![(DMatrix::<f64>::zeros(4, 4), DVector::<f64>::zeros(4)); blocks];
    for (b, (g, r)) in grams.iter_mut().enumerate() {
        for t in skip + b * len / blocks..skip + (b + 1) * len / blocks {
            let x = [
                regressors[0][t] / scale[0],
                regressors[1][t] / scale[1],
                regressors[2][t] / scale[2],
                1.0,
            ];
            for i in 0..4 {
                r[i] += x[i] * y[t];
                for j in 0..4 {
                    g[(i, j)] += x[i] * x[j];
                }
            }
        }
    }
    let solve = |skip_block: Option<usize>| -> [f64; 3] {
        let mut g = DMatrix::<f64>::zeros(4, 4);
        let mut r = DVector::<f64>::zeros(4);
        for (b, (gb, rb)) in grams.iter().enumerate() {
            if Some(b) != skip_block {
                g += gb;
                r += rb;
            }
        }
        let th = g
            .clone()
            .cholesky()
            .map(|c| c.solve(&r))
            .or_else(|| g.lu().solve(&r));
        match th {
            Some(th) => [th[0] / scale[0], th[1] / scale[1], th[2] / scale[2]],
            None => [f64::NAN; 3],
        }
    };
    let full = solve(None);
    let reps: Vec<[f64; 3]> = (0..blocks).map(|b| solve(Some(b))).collect();
    let se: Vec<f64> = (0..3)
        .map(|k| {
            let m = reps.iter().map(|r| r[k]).sum::<f64>() / blocks as f64;
            let ss: f64 = reps.iter().map(|r| (r[k] - m).powi(2)).sum();
            (ss * (blocks - 1) as f64 / blocks as f64).sqrt()
        })
        .collect();
    let fitted: Vec<f64> = (0..n)
        .map(|t| {
            full[0] * regressors[0][t] + full[1] * regressors[1][t] + full[2] * regressors[2][t]
        })
        .collect();
    let v = vaf(y, &fitted, skip);
    (
        Ibk {
            inertia: full[0],
            damping: full[1],
            stiffness: full[2],
        },
        Ibk {
            inertia: se[0],
            damping: se[1],
            stiffness: se[2],
        },
        v,
    )
}

/// Unit-DC second-order low-pass by the bilinear transform, prewarped at its natural frequency.
pub(crate) fn low_pass(x: &[f64], natural_hz: f64, zeta: f64, fs: f64) -> Vec<f64> {
    let w = 2.0 * std::f64::consts::PI * natural_hz;
    let k = w / (w / (2.0 * fs)).tan();
    let a0 = k * k + 2.0 * zeta * w * k + w * w;
    let b = [w * w / a0, 2.0 * w * w / a0, w * w / a0];
    let a1 = (2.0 * w * w - 2.0 * k * k) / a0;
    let a2 = (k * k - 2.0 * zeta * w * k + w * w) / a0;
    let mut y = vec![0.0; x.len()];
    // start in the steady state of the first sample (unit DC gain)
    let x0 = x.first().copied().unwrap_or(0.0);
    let (mut x1, mut x2, mut y1, mut y2) = (x0, x0, x0, x0);
    for (yi, &xi) in y.iter_mut().zip(x) {
        let v = b[0] * xi + b[1] * x1 + b[2] * x2 - a1 * y1 - a2 * y2;
        x2 = x1;
        x1 = xi;
        y2 = y1;
        y1 = v;
        *yi = v;
    }
    y
}

struct Parametric {
    intrinsic: Ibk,
    intrinsic_se: Ibk,
    gain: f64,
    gain_se: f64,
    delay_s: f64,
    interval: [f64; 2],
    interval_contiguous: bool,
    at_scan_edge: bool,
    natural_hz: f64,
    damping_ratio: f64,
    total_vaf: f64,
    intrinsic_only_vaf: f64,
    scan_delays_s: Vec<f64>,
    scan_vaf: Vec<f64>,
}

/// The I-B-K regressors over the fitted rows, centred, with their Gram
/// matrix inverse, the I-B-K-only solution and its residual.
struct Fixed {
    columns: [Vec<f64>; 3],
    gram_inv: nalgebra::Matrix3<f64>,
    theta: nalgebra::Vector3<f64>,
    residual: Vec<f64>,
    rss: f64,
    total_ss: f64,
}

fn fixed_fit(d: &Decimated, skip: usize) -> Option<Fixed> {
    let centred = |x: &[f64]| {
        let mut c = x[skip..].to_vec();
        centre(&mut c);
        c
    };
    let columns = [
        centred(&d.acceleration),
        centred(&d.velocity),
        centred(&d.position),
    ];
    let y = centred(&d.torque);
    let mut g = nalgebra::Matrix3::<f64>::zeros();
    let mut r = nalgebra::Vector3::<f64>::zeros();
    for i in 0..3 {
        r[i] = dot(&columns[i], &y);
        for j in 0..3 {
            g[(i, j)] = dot(&columns[i], &columns[j]);
        }
    }
    let gram_inv = g.try_inverse()?;
    let theta = gram_inv * r;
    let residual: Vec<f64> = (0..y.len())
        .map(|t| {
            y[t] - theta[0] * columns[0][t] - theta[1] * columns[1][t] - theta[2] * columns[2][t]
        })
        .collect();
    Some(Fixed {
        rss: dot(&residual, &residual),
        total_ss: dot(&y, &y),
        columns,
        gram_inv,
        theta,
        residual,
    })
}

fn dot(a: &[f64], b: &[f64]) -> f64 {
    a.iter().zip(b).map(|(x, y)| x * y).sum()
}

/// Residual sum of squares and gain of the joint model
/// `tq = I q'' + B q' + K q + G x + c` for one reflex regressor `x` (over the fitted rows).
fn joint_rss(f: &Fixed, x: &[f64]) -> (f64, f64) {
    let m = x.len() as f64;
    let [c0, c1, c2] = &f.columns;
    let (mut sx, mut xx, mut xe, mut b0, mut b1, mut b2) = (0.0, 0.0, 0.0, 0.0, 0.0, 0.0);
    // one pass over memory: the six sums the Schur complement needs
    for ((((&xv, &e), &a0), &a1), &a2) in x.iter().zip(&f.residual).zip(c0).zip(c1).zip(c2) {
        sx += xv;
        xx += xv * xv;
        xe += xv * e;
        b0 += xv * a0;
        b1 += xv * a1;
        b2 += xv * a2;
    }
    let b = nalgebra::Vector3::new(b0, b1, b2);
    let xx_resid = xx - sx * sx / m - (b.transpose() * f.gram_inv * b)[0];
    if xx_resid <= 1e-12 * xx {
        return (f.rss, 0.0);
    }
    let gain = xe / xx_resid;
    ((f.rss - xe * gain).max(0.0), gain)
}

/// Decimation phases of `y`: `phases[r][k] = y[k ratio - r]` (zero before the record).
fn phases(y: &[f64], ratio: usize, n: usize) -> Vec<Vec<f64>> {
    (0..ratio)
        .map(|r| {
            (0..n)
                .map(|k| {
                    if k * ratio >= r {
                        y.get(k * ratio - r).copied().unwrap_or(0.0)
                    } else {
                        0.0
                    }
                })
                .collect()
        })
        .collect()
}

/// The reflex regressor over the fitted rows `skip..n` for a delay of
/// `delay` recorded samples: a slice of one decimation phase.
fn delayed(phases: &[Vec<f64>], ratio: usize, delay: usize, skip: usize, n: usize) -> &[f64] {
    let (m, r) = (delay / ratio, delay % ratio);
    &phases[r][skip - m..n - m]
}

/// The fully parametric model, fitted jointly: intrinsic I-B-K plus
/// rectified velocity -> delay -> gain -> unit-DC second-order low-pass. For
/// a given delay and low-pass the model is linear in I, B, K, G; delay and
/// low-pass are scanned (delays on the recorded rate's grid).
fn reflex_parametric(
    d: &Decimated,
    polarity: usize,
    skip: usize,
    p: &ReflexParams,
    fs: f64,
) -> Option<Parametric> {
    let f = fixed_fit(d, skip)?;
    let n = d.torque.len();
    let full = &d.rectified_full[polarity];
    let max_delay = (p.max_delay_s * fs).round() as usize;
    let delays = max_delay + 1;
    let nyquist = d.fs / 2.0;
    let scan = |combos: &[(f64, f64)]| -> Vec<Vec<(f64, f64)>> {
        combos
            .par_iter()
            .map(|&(w, z)| {
                let ph = phases(&low_pass(full, w, z, fs), d.ratio, n);
                (0..delays)
                    .map(|dl| joint_rss(&f, delayed(&ph, d.ratio, dl, skip, n)))
                    .collect()
            })
            .collect()
    };
    let mut combos: Vec<(f64, f64)> = (0..10)
        .map(|i| 0.8 * 25f64.powf(i as f64 / 9.0))
        .filter(|w| *w < 0.45 * nyquist)
        .flat_map(|w| [0.3, 0.5, 0.75, 1.1, 1.6].map(|z| (w, z)))
        .collect();
    if combos.is_empty() {
        // no low-pass of the grid lies below the decimated Nyquist frequency
        return None;
    }
    let mut fits = scan(&combos);
    let best = |fits: &[Vec<(f64, f64)>]| {
        let mut b = (f64::INFINITY, 0, 0);
        for (ci, row) in fits.iter().enumerate() {
            for (dl, &(rss, _)) in row.iter().enumerate() {
                if rss < b.0 {
                    b = (rss, ci, dl);
                }
            }
        }
        b
    };
    let (_, c0, _) = best(&fits);
    let (w0, z0) = combos[c0];
    let local: Vec<(f64, f64)> = (-2..=2)
        .flat_map(|i| (-2..=2).map(move |j| (w0 * 1.08f64.powi(i), z0 * 1.1f64.powi(j))))
        .filter(|(w, _)| *w < 0.45 * nyquist)
        .collect();
    fits.extend(scan(&local));
    combos.extend(local);
    let (rss_min, ci, delay) = best(&fits);
    let (w, z) = combos[ci];
    let profile: Vec<f64> = (0..delays)
        .map(|dl| {
            fits.iter()
                .map(|row| row[dl].0)
                .fold(f64::INFINITY, f64::min)
        })
        .collect();

    // the joint fit at the optimum, its residual and jackknife errors
    let ph = phases(&low_pass(full, w, z, fs), d.ratio, n);
    let x = delayed(&ph, d.ratio, delay, skip, n);
    let (_, gain) = joint_rss(&f, x);
    let xm = mean(x);
    let bx = nalgebra::Vector3::new(
        dot(x, &f.columns[0]),
        dot(x, &f.columns[1]),
        dot(x, &f.columns[2]),
    );
    let theta = f.theta - f.gram_inv * bx * gain;
    let resid: Vec<f64> = (0..x.len())
        .map(|t| {
            f.residual[t] - gain * (x[t] - xm)
                + (f.theta - theta).dot(&nalgebra::Vector3::new(
                    f.columns[0][t],
                    f.columns[1][t],
                    f.columns[2][t],
                ))
        })
        .collect();
    let inflation = autocorrelation_inflation(&resid);
    let m = x.len() as f64;
    let n_eff = (m / inflation).max(5.0);
    let threshold = rss_min * (1.0 + 3.84 / n_eff);
    let inside: Vec<bool> = profile.iter().map(|r| *r <= threshold).collect();
    let (mut lo, mut hi) = (delay, delay);
    while lo > 0 && inside[lo - 1] {
        lo -= 1;
    }
    while hi < max_delay && inside[hi + 1] {
        hi += 1;
    }
    let contiguous = inside
        .iter()
        .enumerate()
        .all(|(i, &v)| !v || (lo..=hi).contains(&i));
    let mut se = joint_jackknife(&f, x);
    // the jackknife holds the delay fixed; B, K, I and G move with it, so the
    // largest change over the delay's interval is added (in quadrature)
    let at = |x: &[f64]| {
        let (_, g) = joint_rss(&f, x);
        let bx = nalgebra::Vector3::new(
            dot(x, &f.columns[0]),
            dot(x, &f.columns[1]),
            dot(x, &f.columns[2]),
        );
        let t = f.theta - f.gram_inv * bx * g;
        [t[0], t[1], t[2], g]
    };
    let mut shift = [0.0f64; 4];
    for dl in [lo, hi] {
        let other = at(delayed(&ph, d.ratio, dl, skip, n));
        for (s, (o, v)) in shift
            .iter_mut()
            .zip(other.iter().zip([theta[0], theta[1], theta[2], gain]))
        {
            *s = s.max((o - v).abs());
        }
    }
    for (e, s) in se.iter_mut().zip(shift) {
        *e = e.hypot(s);
    }
    Some(Parametric {
        intrinsic: Ibk {
            inertia: theta[0],
            damping: theta[1],
            stiffness: theta[2],
        },
        intrinsic_se: Ibk {
            inertia: se[0],
            damping: se[1],
            stiffness: se[2],
        },
        gain,
        gain_se: se[3],
        delay_s: delay as f64 / fs,
        interval: [lo as f64 / fs, hi as f64 / fs],
        interval_contiguous: contiguous,
        at_scan_edge: delay == 0 || delay == max_delay,
        natural_hz: w,
        damping_ratio: z,
        total_vaf: 100.0 * (1.0 - rss_min / f.total_ss),
        intrinsic_only_vaf: 100.0 * (1.0 - f.rss / f.total_ss),
        scan_delays_s: (0..delays).map(|i| i as f64 / fs).collect(),
        scan_vaf: profile
            .iter()
            .map(|r| 100.0 * (1.0 - r / f.total_ss))
            .collect(),
    })
}

/// 10-block delete-one jackknife standard errors of (I, B, K, G) of the joint model.
fn joint_jackknife(f: &Fixed, x: &[f64]) -> [f64; 4] {
    let blocks = 10;
    let m = x.len();
    let y: Vec<f64> = (0..m)
        .map(|t| {
            f.residual[t]
                + f.theta.dot(&nalgebra::Vector3::new(
                    f.columns[0][t],
                    f.columns[1][t],
                    f.columns[2][t],
                ))
        })
        .collect();
    let scale: Vec<f64> = f
        .columns
        .iter()
        .map(|c| c.as_slice())
        .chain([x])
        .map(|c| (dot(c, c) / m as f64).sqrt().max(f64::MIN_POSITIVE))
        .collect();
    let row = |t: usize| {
        [
            f.columns[0][t] / scale[0],
            f.columns[1][t] / scale[1],
            f.columns[2][t] / scale[2],
            x[t] / scale[3],
            1.0,
        ]
    };
    let mut grams = vec![
        (
            nalgebra::SMatrix::<f64, 5, 5>::zeros(),
            nalgebra::SVector::<f64, 5>::zeros()
        );
        blocks
    ];
    for (b, (g, r)) in grams.iter_mut().enumerate() {
        #[allow(clippy::needless_range_loop)] // row(t) reads five columns at t
        for t in b * m / blocks..(b + 1) * m / blocks {
            let v = nalgebra::SVector::<f64, 5>::from(row(t));
            *g += v * v.transpose();
            *r += v * y[t];
        }
    }
    let reps: Vec<[f64; 4]> = (0..blocks)
        .map(|skip| {
            let mut g = nalgebra::SMatrix::<f64, 5, 5>::zeros();
            let mut r = nalgebra::SVector::<f64, 5>::zeros();
            for (b, (gb, rb)) in grams.iter().enumerate() {
                if b != skip {
                    g += gb;
                    r += rb;
                }
            }
            match g.lu().solve(&r) {
                Some(th) => [0, 1, 2, 3].map(|k| th[k] / scale[k]),
                None => [f64::NAN; 4],
            }
        })
        .collect();
    [0, 1, 2, 3].map(|k| {
        let mk = reps.iter().map(|r| r[k]).sum::<f64>() / blocks as f64;
        let ss: f64 = reps.iter().map(|r| (r[k] - mk).powi(2)).sum();
        (ss * (blocks - 1) as f64 / blocks as f64).sqrt()
    })
}

/// `1 + 2 sum rho_k` over the residual's autocorrelation, summed until it first turns negative (at most 200 lags).
fn autocorrelation_inflation(e: &[f64]) -> f64 {
    let v = correlation(e, e, 0);
    if v <= 0.0 {
        return 1.0;
    }
    let mut s = 1.0;
    for k in 1..200.min(e.len() / 4) {
        let r = correlation(e, e, k as isize) / v;
        if r <= 0.0 {
            break;
        }
        s += 2.0 * r;
    }
    s
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn pseudo_inverse_recovers_a_known_irf_from_white_input() {
        // y = 2 u[t] - 1 u[t-1] + 0.5 u[t+1]
        let mut s = 12345u64;
        let u: Vec<f64> = (0..5000)
            .map(|_| {
                s = s
                    .wrapping_mul(6364136223846793005)
                    .wrapping_add(1442695040888963407);
                (s >> 11) as f64 / (1u64 << 53) as f64 - 0.5
            })
            .collect();
        let y = apply(&[0.5, 2.0, -1.0], -1, &u);
        let (h, order) = irf_pinv(&u, &y, -2, 5);
        let want = [0.0, 0.5, 2.0, -1.0, 0.0];
        for (a, b) in h.iter().zip(want) {
            assert!((a - b).abs() < 2e-3, "{h:?}");
        }
        assert!(order >= 3);
    }

    #[test]
    fn low_pass_has_unit_dc_gain_and_its_step_settles() {
        let x = vec![1.0; 4000];
        let y = low_pass(&x, 5.0, 0.7, 1000.0);
        assert!((y[3999] - 1.0).abs() < 1e-9);
        let mut step = vec![0.0; 4000];
        step[100..].fill(1.0);
        let y = low_pass(&step, 5.0, 0.7, 1000.0);
        assert!(y[99].abs() < 1e-12 && (y[3999] - 1.0).abs() < 1e-6);
    }
}
