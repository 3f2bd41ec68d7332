//! The parallel-cascade estimate, step by step: check the input, decimate,
//! run both polarities' cascades, fit the joint parametric model (and the
//! other rectifier order), add the model-error floors to the standard
//! errors, cross-validate, and say what cannot be trusted.

use super::cascade::{
    anti_alias, apply_in, cascade, centre, decimate, decimation_ratio, vaf_in, variance, Cascade,
};
use super::nonlinearity::{estimate_curve, Choice, CurveFit, CurveInput};
use super::parametric::fixed_fit;
use super::parametric::{ibk_fit, parametric_intrinsic, reflex_parametric, Parametric};
use super::segments::{self, gather, Layout, SegmentUse};
use super::{CurveStructure, Nonlinearity};
use super::{
    Decimated, DelayScan, Ibk, IntrinsicPathway, Irf, OtherOrder, Polarity, ReflexEstimate,
    ReflexFreeFit, ReflexParams, ReflexPathway, ReflexTraces, ReflexVerdicts, VafSplit,
    DELAY_INTERVAL_MAX_S, GRID_ERROR_FLOOR, MODEL_ERROR_FLOOR, REFLEX_PRESENT_VAF,
};
use crate::closed_loop::ClosedLoopFit;
use limpid_core::{Error, Recording, Result, Warning, WarningCode};
use rayon::prelude::*;
use std::ops::Range;

/// The parallel-cascade estimate of `rec`.
///
/// # Example
///
/// A virtual ankle with a stretch reflex under a random position
/// perturbation (Kearney et al. 1997), without torque noise:
///
/// ```
/// use limpid_ident::reflex::{estimate_reflex, ReflexParams};
/// use limpid_lab::ankle::{simulate_ankle, AnkleExperiment, AnkleSubject};
///
/// let ankle = AnkleSubject::default();
/// let experiment = AnkleExperiment { torque_noise_nm: 0.0, ..AnkleExperiment::default() };
/// let rec = simulate_ankle(&ankle, &experiment, 1)?;
/// let est = estimate_reflex(&rec, &ReflexParams::default())?;
/// assert!((est.intrinsic.stiffness - ankle.stiffness).abs() < 0.01 * ankle.stiffness);
/// assert!(est.reflex.delay_identifiable);
/// # Ok::<(), limpid_core::Error>(())
/// ```
pub fn estimate_reflex(rec: &Recording, p: &ReflexParams) -> Result<ReflexEstimate> {
    // a position logged faster than it was measured: its measured samples
    // (issue 58); a missing or bookkeeping column is refused just below
    let (rec, measured_rate) = crate::prepare::at_measured_rate(
        std::borrow::Cow::Borrowed(rec),
        std::slice::from_ref(&p.position),
    )?;
    let rec = rec.as_ref();
    let (q, tq) = position_and_torque(rec, p)?;
    // a closed-loop rig: the motion the commanded reference drives (issue 79)
    let closed = crate::closed_loop::predicted_motion(
        rec,
        std::slice::from_ref(&p.position),
        (p.open_loop, ClosedLoopFit::InstrumentalVariables),
    )?;
    let (predicted, closed_loop) = closed.unzip();
    let fs = rec.sample_rate();
    let mut warnings: Vec<Warning> = measured_rate.iter().map(|m| m.warning()).collect();
    warnings.extend(closed_loop.iter().flat_map(|c| c.warnings()));
    // a trial change is a cut, even where the time runs on
    let cuts = limpid_core::trial::segment_ranges(rec)?;
    let shortened: Option<ReflexParams>;
    let (layout, [d, other_decimation], segment_use) = if cuts.len() > 1 {
        if closed_loop.is_some() {
            return Err(Error::invalid(
                rec.path().display().to_string(),
                "a closed-loop recording (with a commanded reference column) of several segments is not estimated yet: pass one continuous record, or --open-loop if the robot imposed the motion",
            ));
        }
        check_rate(rec, p)?;
        let (layout, d, used, short) = segments::prepare(rec, (q, tq), p, &cuts, &mut warnings)?;
        shortened = short;
        (layout, d, Some(used))
    } else {
        shortened = None;
        let layout = lengths(rec, p, q.len())?;
        (layout, decimate(q, tq, fs, p)?, None)
    };
    let p = shortened.as_ref().unwrap_or(p);
    let Layout {
        half,
        n_reflex,
        fit_skip,
    } = layout;
    for (name, raw) in [(&p.position, q), (&p.torque, tq)] {
        check_varies(rec, name, raw)?;
    }
    // closed loop: the decimated predicted motion instruments the joint
    // parametric fit; the nonparametric pathways (least squares) are fitted
    // on it (the plug-in: consistent for the intrinsic IRF, approximate for
    // the reflex's)
    let instrument = match predicted.as_ref().and_then(|m| m.first()) {
        Some(m) => Some(decimate(m, tq, fs, p)?),
        None => None,
    };
    let dc = instrument.as_ref().map_or(&d, |i| &i[0]);
    let skip = n_reflex;
    let cascades = both_polarities(dc, (half, n_reflex, skip));
    let (best, polarity) = if cascades[0].vaf_total >= cascades[1].vaf_total {
        (0, Polarity::Positive)
    } else {
        (1, Polarity::Negative)
    };
    let mut c = &cascades[best];

    let dt = 1.0 / d.fs;
    // the fully parametric model, fitted jointly (I-B-K, delay, gain, low-pass)
    let Some(mut param) = reflex_parametric(
        &d,
        best,
        fit_skip,
        p,
        (fs, instrument.as_ref().map(|i| &i[0])),
    ) else {
        return Err(Error::invalid(
            rec.path().display().to_string(),
            "position, velocity and acceleration are collinear: I, B and K cannot be separated",
        ));
    };
    // the reflex's static curve, estimated (issue 78): one continuous open-loop record
    let curve_fit = if cuts.len() == 1 && instrument.is_none() {
        static_curve(q, (fs, &d, fit_skip), p, &param, best == 0)?
    } else if p.nonlinearity == Nonlinearity::PiecewiseLinear {
        return Err(Error::invalid(
            "nonlinearity",
            "a piecewise-linear reflex curve is estimated only from one continuous open-loop record (this one has several segments or a commanded reference): use auto or rectifier",
        ));
    } else {
        None
    };
    let curve_input = curve_fit
        .as_ref()
        .filter(|cf| cf.curve.structure != CurveStructure::Rectifier)
        .map(|cf| decimated_curve(&cf.applied, fs, d.ratio))
        .transpose()?;
    let curve_cascade = curve_input.as_ref().map(|u| {
        cascade(
            [&dc.position, u, &dc.torque],
            (half, n_reflex, skip),
            &dc.segments,
        )
    });
    if let Some(cc) = &curve_cascade {
        c = cc;
    }
    let curve_warning = curve_fit
        .as_ref()
        .and_then(|cf| adopt_curve(&mut param, cf));
    // The fit with the other rectifier order is reported. A reflex answers
    // the limb's own velocity, so rectifying first is the physical order;
    // with Kearney et al.'s order (after anti-aliasing) the difference is
    // that order's error, and it goes into the standard errors and the
    // delay interval.
    let other_order = reflex_parametric(
        &other_decimation,
        best,
        fit_skip,
        p,
        (fs, instrument.as_ref().map(|i| &i[1])),
    );
    let order_warning = other_order
        .as_ref()
        .filter(|_| !p.rectify_first)
        .and_then(|o| widen_by_other_order(&mut param, o));
    add_error_floors(&mut param);
    let fit = VafSplit {
        vaf_total: c.vaf_total,
        vaf_intrinsic: vaf_in(&d.torque, &c.intrinsic_torque, skip, &d.segments),
        vaf_reflex: vaf_in(&d.torque, &c.reflex_torque, skip, &d.segments),
        vaf_parametric: param.total_vaf,
        vaf_parametric_intrinsic: vaf_in(
            &d.torque,
            &parametric_intrinsic(&d, &param.intrinsic),
            skip,
            &d.segments,
        ),
    };
    let reflex_input = curve_input.as_deref().unwrap_or(&dc.rectified[best]);
    let cross_validated_vaf = cross_validated_vaf(dc, reflex_input, half, n_reflex);

    // intrinsic I-B-K from the joint parametric model; for comparison, the
    // fit of the torque the nonparametric reflex leaves, and the reflex-free fit
    let intrinsic_target: Vec<f64> = d
        .torque
        .iter()
        .zip(&c.reflex_torque)
        .map(|(t, r)| t - r)
        .collect();
    let (irf_fit, _, _) = ibk_fit_in(dc, &intrinsic_target, skip);
    let ibk = param.intrinsic;
    let (plain, _, plain_vaf) = ibk_fit_in(dc, &d.torque, skip);
    warnings.extend(order_warning);
    warnings.extend(curve_warning);
    let delay_identifiable = delay_warnings(&param, fs, &mut warnings);
    let reflex_gain_points = param.total_vaf - param.intrinsic_only_vaf;
    warnings.extend(ambiguous_polarity(&cascades, reflex_gain_points));
    fit_warnings(&ibk, &fit, cross_validated_vaf, &mut warnings);

    let other_polarity_vaf = cascades[1 - best].vaf_total;
    let start_left_out = param.start_left_out;
    let (intrinsic, mut reflex) = pathways(
        c,
        param,
        irf_fit,
        (polarity, other_polarity_vaf),
        delay_identifiable,
        half,
        dt,
    );
    reflex.curve = curve_fit.map(|cf| cf.curve);
    if let Some(curve) = &reflex.curve {
        if curve.structure != CurveStructure::Rectifier {
            reflex.model = "velocity -> delay -> piecewise-linear static curve (estimated) -> second-order low-pass (unit DC gain)".into();
        }
    }
    let (coordinate, assumed) = p.coordinate();
    if assumed {
        warnings.push(Warning::new(
            WarningCode::UnitsAssumed,
            format!(
                "position column {:?} is not a recording-format name: taken as a joint angle (rad, torque in N m); say coordinate = \"displacement\" (--coordinate displacement) if it is in metres",
                p.position
            ),
        ));
    }
    warnings.extend(crate::units::implausible_motion(
        &p.position,
        coordinate,
        crate::units::range(q),
    ));
    let verdicts = Some(ReflexVerdicts::judge(&intrinsic, &reflex, fit.vaf_total));
    // H1 from the measured position: open loop and one continuous record only
    let frequency_response = (closed_loop.is_none() && d.segments.len() == 1)
        .then(|| super::frequency::joint_frequency_response(&d.position, &d.torque, d.fs, &ibk))
        .flatten();
    let est = ReflexEstimate {
        position: p.position.clone(),
        torque: p.torque.clone(),
        units: coordinate.units(),
        sample_rate_hz: fs,
        decimated_rate_hz: d.fs,
        duration_s: rec.len() as f64 / fs,
        intrinsic,
        reflex,
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
        traces: traces(dc, c, skip),
        verdicts,
        frequency_response,
        closed_loop,
        segments: segment_use.map(|u| SegmentUse {
            start_left_out_s: start_left_out as f64 / d.fs,
            ..u
        }),
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

/// The two pathways as reported: the intrinsic I-B-K and the reflex from the
/// joint parametric fit, the IRFs from the cascade.
fn pathways(
    c: &Cascade,
    param: Parametric,
    irf_fit: Ibk,
    (polarity, other_polarity_vaf): (Polarity, f64),
    delay_identifiable: bool,
    half: usize,
    dt: f64,
) -> (IntrinsicPathway, ReflexPathway) {
    let irf = |h: &[f64], first: isize, order: usize| Irf {
        lags_s: (0..h.len())
            .map(|i| (first + i as isize) as f64 * dt)
            .collect(),
        values: h.iter().map(|v| v / dt).collect(),
        order,
    };
    let intrinsic = IntrinsicPathway {
        inertia: param.intrinsic.inertia,
        damping: param.intrinsic.damping,
        stiffness: param.intrinsic.stiffness,
        standard_errors: param.intrinsic_se,
        irf_fit,
        irf: irf(&c.intrinsic, -(half as isize), c.intrinsic_order),
    };
    let reflex = ReflexPathway {
        model:
            "half-wave rectified velocity -> delay -> gain -> second-order low-pass (unit DC gain)"
                .into(),
        polarity,
        other_polarity_vaf,
        gain: param.gain,
        gain_se: param.gain_se,
        delay_s: param.delay_s,
        delay_interval_s: param.interval,
        delay_identifiable,
        natural_frequency_hz: param.natural_hz,
        damping_ratio: param.damping_ratio,
        irf: irf(&c.reflex, 0, c.reflex_order),
        curve: None,
        delay_scan: DelayScan {
            delays_s: param.scan_delays_s,
            vaf: param.scan_vaf,
        },
    };
    (intrinsic, reflex)
}

/// The decimation and IRF lengths, refusing a decimated rate above the
/// recording's and a recording too short for 5 reflex-IRF lengths. The
/// length check comes before decimation, whose zero-phase filter would
/// refuse a short recording without naming it.
fn lengths(rec: &Recording, p: &ReflexParams, samples: usize) -> Result<Layout> {
    check_rate(rec, p)?;
    let fs = rec.sample_rate();
    let ratio = decimation_ratio(fs, p);
    let fsd = fs / ratio as f64;
    let n = samples.div_ceil(ratio);
    let lag = |s: f64| (s * fsd).round() as usize;
    let half = lag(p.intrinsic_lags_s).max(1);
    let n_reflex = lag(p.reflex_lags_s).max(2);
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
            found: samples,
        });
    }
    // a continuous record leaves out one reflex-IRF length, for both fits
    Ok(Layout {
        half,
        n_reflex,
        fit_skip: n_reflex,
    })
}

/// Refuses a decimated rate above the recording's.
fn check_rate(rec: &Recording, p: &ReflexParams) -> Result<()> {
    let fs = rec.sample_rate();
    let too_slow = p.rate_hz > fs * (1.0 + limpid_core::recording::SAMPLING_TOLERANCE);
    if too_slow && p.rate_hz == super::ReflexRequest::default().rate_hz {
        // the default rate: the recording is at fault, not a flag nobody gave
        return Err(Error::Format {
            path: rec.path().to_path_buf(),
            message: format!(
                "sampled at {} Hz, below the {} Hz the parallel cascade works at{}",
                limpid_core::short_number(fs),
                limpid_core::short_number(p.rate_hz),
                if fs < 20.0 {
                    ": is t in seconds? (a rate this low usually means milliseconds: divide t by 1000, or read it through a channel map with unit = \"ms\", which `limpid inspect FILE --map-template` proposes for a column named like time_ms)"
                } else {
                    "; a slower rate can be asked for with --rate"
                }
            ),
        });
    }
    if too_slow {
        return Err(Error::invalid(
            "rate_hz",
            format!(
                "the decimated rate, {} Hz, is above the recording's {} Hz ({}); limpid decimates, it does not interpolate",
                limpid_core::short_number(p.rate_hz),
                limpid_core::short_number(fs),
                rec.path().display()
            ),
        ));
    }
    Ok(())
}

/// Refuses a column that does not vary, or varies outside the range where
/// its squares are computed exactly.
fn check_varies(rec: &Recording, name: &str, raw: &[f64]) -> Result<()> {
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
    match problem {
        Some(problem) => Err(Error::invalid(
            rec.path().display().to_string(),
            format!("column {name} {problem}"),
        )),
        None => Ok(()),
    }
}

/// With Kearney et al.'s rectifier order, the difference to the physical
/// order's fit `o` is that order's error: added (in quadrature) to the
/// standard errors of I, B, K and G, and its delay to the delay interval.
/// A warning when K moves by more than 2 jackknife SE.
fn widen_by_other_order(param: &mut Parametric, o: &Parametric) -> Option<Warning> {
    let z = (param.intrinsic.stiffness - o.intrinsic.stiffness).abs()
        / param.intrinsic_se.stiffness.max(f64::MIN_POSITIVE);
    let warning = (z > 2.0).then(|| {
        Warning::new(
            WarningCode::NoisyRegressors,
            format!(
                "rectifying the velocity after anti-aliasing (Kearney et al.'s order) changes K by {} N m/rad ({z:.1} jackknife SE) from the physical order: the standard errors include this difference",
                limpid_core::short_number(param.intrinsic.stiffness - o.intrinsic.stiffness)
            ),
        )
    });
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
    warning
}

/// The reflex's static curve of a continuous open-loop record, at the
/// scan's low-pass and near its delay ([`super::nonlinearity`]).
fn static_curve(
    q: &[f64],
    (fs, d, skip): (f64, &Decimated, usize),
    p: &ReflexParams,
    param: &Parametric,
    positive: bool,
) -> Result<Option<CurveFit>> {
    let Some(fixed) = fixed_fit(d, skip) else {
        return Ok(None);
    };
    let velocity = limpid_dsp::central_first(q, 1.0 / fs);
    let anti = if d.ratio > 1 {
        Some(anti_alias(fs, d.ratio)?)
    } else {
        None
    };
    let input = CurveInput {
        velocity: &velocity,
        anti_alias: anti.as_ref(),
        rectify_first: p.rectify_first,
        fs,
        ratio: d.ratio,
        low_pass: (param.natural_hz, param.damping_ratio),
        delay: (param.delay_s * fs).round() as usize,
        skip,
        n: d.torque.len(),
    };
    let choice = match p.nonlinearity {
        Nonlinearity::Auto => Choice::Auto,
        Nonlinearity::Rectifier => Choice::Rectifier,
        Nonlinearity::PiecewiseLinear => Choice::PiecewiseLinear,
    };
    estimate_curve(&fixed, &input, positive, choice)
}

/// The chosen curve applied to the recorded velocity, anti-aliased,
/// decimated and centred: the nonparametric reflex pathway's input.
fn decimated_curve(applied: &[f64], fs: f64, ratio: usize) -> Result<Vec<f64>> {
    let filtered = if ratio > 1 {
        anti_alias(fs, ratio)?.filtfilt(applied)?
    } else {
        applied.to_vec()
    };
    let mut u: Vec<f64> = filtered.iter().step_by(ratio).copied().collect();
    centre(&mut u);
    Ok(u)
}

/// The parametric results follow the chosen curve: with a piecewise-linear
/// one, its I, B, K, gain and VAF replace the rectifier's (standard
/// errors: its jackknife and the delay/low-pass profile shift); either way
/// the spread over the structures the data cannot tell apart is added to
/// the standard errors, with a warning when it exceeds them.
fn adopt_curve(param: &mut Parametric, cf: &CurveFit) -> Option<Warning> {
    let shift = param.profile_shift;
    if cf.curve.structure != CurveStructure::Rectifier {
        param.intrinsic = cf.intrinsic;
        param.intrinsic_se = Ibk {
            inertia: cf.intrinsic_se.inertia.hypot(shift[0]),
            damping: cf.intrinsic_se.damping.hypot(shift[1]),
            stiffness: cf.intrinsic_se.stiffness.hypot(shift[2]),
        };
        let scale = if param.gain != 0.0 {
            (cf.gain / param.gain).abs()
        } else {
            1.0
        };
        param.gain = cf.gain;
        param.gain_se = cf.gain_se.hypot(shift[3] * scale);
        param.total_vaf = cf.vaf;
    }
    let se = param.intrinsic_se;
    let warning = (cf.spread.stiffness > se.stiffness).then(|| {
        Warning::new(
            WarningCode::NotIdentifiable,
            format!(
                "the reflex's static curve: structures the data cannot tell apart (held-out error within one standard error) give intrinsic K up to {} apart, more than its standard error ({}): the standard errors include the difference",
                limpid_core::short_number(cf.spread.stiffness),
                limpid_core::short_number(se.stiffness)
            ),
        )
    });
    param.intrinsic_se = Ibk {
        inertia: se.inertia.hypot(cf.spread.inertia),
        damping: se.damping.hypot(cf.spread.damping),
        stiffness: se.stiffness.hypot(cf.spread.stiffness),
    };
    warning
}

/// Model error the resampling cannot see ([`MODEL_ERROR_FLOOR`],
/// [`GRID_ERROR_FLOOR`]), added in quadrature.
fn add_error_floors(param: &mut Parametric) {
    let floor = |se: &mut f64, v: f64, share: f64| *se = se.hypot(share * v);
    floor(
        &mut param.intrinsic_se.inertia,
        param.intrinsic.inertia,
        MODEL_ERROR_FLOOR,
    );
    let g = GRID_ERROR_FLOOR;
    floor(
        &mut param.intrinsic_se.stiffness,
        param.intrinsic.stiffness,
        g.stiffness,
    );
    floor(
        &mut param.intrinsic_se.damping,
        param.intrinsic.damping,
        g.damping,
    );
    floor(&mut param.gain_se, param.gain, g.gain);
}

/// The cascade fitted on the first two thirds, its VAF on the last third
/// (split between segments when there are several).
fn cross_validated_vaf(d: &Decimated, reflex_input: &[f64], half: usize, n_reflex: usize) -> f64 {
    let (fitted, held_out): (Vec<Range<usize>>, Vec<Range<usize>>) = match d.segments.as_slice() {
        [whole] => {
            let split = 2 * whole.len() / 3;
            (
                std::iter::once(0..split).collect(),
                std::iter::once(split..whole.end).collect(),
            )
        }
        many => {
            let split = (2 * many.len() / 3).max(1);
            (many[..split].to_vec(), many[split..].to_vec())
        }
    };
    let cv = cascade(
        [&d.position, reflex_input, &d.torque],
        (half, n_reflex, n_reflex),
        &fitted,
    );
    let predicted: Vec<f64> = apply_in(&cv.intrinsic, -(half as isize), &d.position, &d.segments)
        .iter()
        .zip(apply_in(&cv.reflex, 0, reflex_input, &d.segments))
        .map(|(a, b)| a + b)
        .collect();
    // a continuous record's held-out third continues its fitted part: no start left out
    let skip = if d.segments.len() == 1 { 0 } else { n_reflex };
    vaf_in(&d.torque, &predicted, skip, &held_out)
}

/// I-B-K with jackknife errors and VAF (see [`ibk_fit`]) over each
/// segment's samples past its first `skip`, each segment with its own constant.
fn ibk_fit_in(d: &Decimated, y: &[f64], skip: usize) -> (Ibk, Ibk, f64) {
    let regressors = [&d.acceleration[..], &d.velocity[..], &d.position[..]];
    if d.segments.len() == 1 {
        return ibk_fit(&regressors, y, skip);
    }
    let groups = segments::groups(&d.segments, skip);
    let centred = |x: &[f64]| {
        let mut c = gather(x, &d.segments, skip).into_owned();
        for g in &groups {
            super::cascade::centre(&mut c[g.clone()]);
        }
        c
    };
    let [a, v, q] = regressors.map(centred);
    ibk_fit(&[&a, &v, &q], &centred(y), 0)
}

/// Whether the reflex delay is identifiable; a warning says why not (too
/// little reflex to time, or a profile interval that is wide, split or at
/// the scan's edge).
fn delay_warnings(param: &Parametric, fs: f64, warnings: &mut Vec<Warning>) -> bool {
    let reflex_gain_points = param.total_vaf - param.intrinsic_only_vaf;
    if reflex_gain_points < REFLEX_PRESENT_VAF {
        warnings.push(Warning::new(
            WarningCode::NotIdentifiable,
            format!(
                "reflex delay not identifiable: the reflex pathway explains only {reflex_gain_points:.2} VAF points (< {REFLEX_PRESENT_VAF}), no reflex to time"
            ),
        ));
        return false;
    }
    if !param.interval_contiguous
        || param.interval[1] - param.interval[0] > DELAY_INTERVAL_MAX_S + 0.5 / fs
        || param.at_scan_edge
    {
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
        return false;
    }
    true
}

/// Warnings on the intrinsic parameters' signs and on the fit.
fn fit_warnings(ibk: &Ibk, fit: &VafSplit, cross_validated_vaf: f64, warnings: &mut Vec<Warning>) {
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
}

/// A 10 s stretch after the left-out first reflex-IRF length, every
/// decimated sample: a whole record at this scale is unreadable. Segments
/// are shown end to end past their starts (the time runs on across a cut).
fn traces(d: &Decimated, c: &Cascade, skip: usize) -> ReflexTraces {
    let dt = 1.0 / d.fs;
    let shown: Vec<usize> = segments::rows(&d.segments, skip)
        .take((10.0 * d.fs).round() as usize)
        .collect();
    let pick = |x: &[f64]| shown.iter().map(|&i| x[i]).collect();
    ReflexTraces {
        t_s: match d.segments.as_slice() {
            [_] => shown.iter().map(|&i| i as f64 * dt).collect(),
            _ => (0..shown.len()).map(|k| (skip + k) as f64 * dt).collect(),
        },
        measured: pick(&d.torque),
        intrinsic: pick(&c.intrinsic_torque),
        reflex: pick(&c.reflex_torque),
    }
}

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

/// The position and torque columns; one column as both would "explain" the
/// torque perfectly (K = 1, VAF 100 %).
fn position_and_torque<'r>(rec: &'r Recording, p: &ReflexParams) -> Result<(&'r [f64], &'r [f64])> {
    if p.position == p.torque {
        return Err(Error::invalid(
            "position and torque",
            format!("column {} names both; they must be two columns", p.position),
        ));
    }
    // time, trial ids and markers are not signals of the joint (issue 56: `--position t`)
    for (what, name) in [("position", &p.position), ("torque", &p.torque)] {
        if matches!(name.as_str(), "t" | "trial" | "level") {
            return Err(Error::invalid(
                what,
                format!("column {name} is the recording's time or bookkeeping, not a joint signal"),
            ));
        }
    }
    let q = rec.require(
        &p.position,
        "the joint angle of the parallel-cascade method",
    )?;
    let tq = rec.require(&p.torque, "the torque of the parallel-cascade method")?;
    Ok((q, tq))
}

/// The parallel cascade with the reflex answering positive (0) and negative
/// (1) velocities, in parallel.
fn both_polarities(d: &Decimated, (half, n_reflex, skip): (usize, usize, usize)) -> Vec<Cascade> {
    [0, 1]
        .par_iter()
        .map(|&k| {
            cascade(
                [&d.position, &d.rectified[k], &d.torque],
                (half, n_reflex, skip),
                &d.segments,
            )
        })
        .collect()
}

/// A warning when both polarities explain the torque within 1 VAF point
/// although a reflex is present.
fn ambiguous_polarity(cascades: &[Cascade], reflex_gain_points: f64) -> Option<Warning> {
    ((cascades[0].vaf_total - cascades[1].vaf_total).abs() < 1.0
        && reflex_gain_points >= REFLEX_PRESENT_VAF)
        .then(|| {
            Warning::new(
                WarningCode::NotIdentifiable,
                format!(
                    "reflex polarity ambiguous: total VAF {:.1} % (positive) vs {:.1} % (negative)",
                    cascades[0].vaf_total, cascades[1].vaf_total
                ),
            )
        })
}
