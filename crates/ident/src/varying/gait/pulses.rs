//! Perturbed minus unperturbed (Rouse, Hargrove, Perreault & Kuiken 2014;
//! Lee & Hogan 2015): brief perturbations on some strides, marked by a 0/1
//! trigger column.
//!
//! For each perturbation (a rise of the trigger inside a stride kept):
//! 1. the baseline is the mean of the `neighbours` unperturbed strides nearest
//!    it, each resampled on gait phase, read at every sample's phase in its
//!    own stride (so it is stretched to the perturbed stride's duration);
//! 2. the deviations `δx`, `δf` (sample minus baseline) are low-passed (zero
//!    phase) and differentiated around the perturbation;
//! 3. the fit window runs from 50 ms before the onset to 50 ms after the
//!    trigger falls (at most `pulse_window_ms` after the onset): the
//!    perturbation out and back, so a stride-to-stride offset and drift of the
//!    torque (each perturbation's own `c0 + c1 t`, projected out) cannot pass
//!    for stiffness.
//!
//! All perturbations are fitted together with K and B piecewise linear in
//! the schedule (hat functions on knots `bin` apart) and I constant:
//!
//! `δf = I δx'' + Σ_j h_j(φ) (B_j δx' + K_j δx) + c0,p + c1,p t`.
//!
//! A window lasts up to a fifth of a stride, over which stance stiffness can
//! double: a constant K per window would average it, and a rising K biases B
//! (the outward and return ramps see different K). Each knot is a point of
//! the result; its perturbation count is the number of windows that put at
//! least 5 % of their displacement weight on it. Knots carried by fewer than
//! 3 perturbations are left out with the samples they cover. Standard errors
//! are the jackknife over perturbations, widened by the interpolation bias
//! the neighbouring knots' curvature implies (a sixth of the second
//! difference); a point with fewer than `min_pulses` perturbations is not
//! identifiable.

use nalgebra::DMatrix;

use limpid_core::criteria::well_conditioned;
use limpid_core::{Error, Recording, Result};
use limpid_dsp::LowPass;

use super::super::floored;
use super::super::{
    matrix, scaled_condition, solve_scaled, PointVerdicts, VaryingEstimate, VaryingFit,
    VaryingMethod, VaryingParams, VaryingPoint,
};
use super::{axis, interp, GaitSummary, Strides, WALKING_MODEL_FLOOR, WALKING_TOLERANCES};

/// Fit window before the onset (s).
const PRE_S: f64 = 0.05;
/// Fit window after the trigger falls (s).
const POST_S: f64 = 0.05;
/// Longest window after the onset by default (s).
const DEFAULT_WINDOW_S: f64 = 0.4;

/// The trigger's 0/1 values, checked.
fn trigger_values<'a>(rec: &'a Recording, column: &str) -> Result<&'a [f64]> {
    let v = rec.require(
        column,
        "perturbation trigger (1 while a perturbation is active)",
    )?;
    if let Some(i) = v.iter().position(|&x| x != 0.0 && x != 1.0) {
        return Err(Error::Format {
            path: rec.path().to_path_buf(),
            message: format!(
                "row {}, column {column}: expected 0 or 1 (1 while a perturbation is active), found {}",
                rec.row_of(i),
                limpid_core::error::Num(v[i])
            ),
        });
    }
    Ok(v)
}

/// Whether the trigger marks some strides and leaves at least 3 unmarked.
pub(super) fn marks_some_strides(rec: &Recording, column: &str, s: &Strides) -> Result<bool> {
    let v = trigger_values(rec, column)?;
    let marked = s
        .kept
        .iter()
        .filter(|r| v[(*r).clone()].contains(&1.0))
        .count();
    Ok(marked > 0 && s.kept.len() - marked >= 3)
}

/// One perturbation's window, ready to be fitted.
struct Pulse {
    /// Per window sample: `[x'' (d), x' (d), x (d)]`, and `f (d)`.
    x: Vec<Vec<f64>>,
    f: Vec<Vec<f64>>,
    /// The schedule at each window sample (relative to the perturbed stride).
    sigma: Vec<f64>,
    /// Seconds since the onset at each window sample.
    t: Vec<f64>,
}

pub(super) fn estimate(
    rec: &Recording,
    params: &VaryingParams,
    (coords, forces): (&[String], &[String]),
    (strides, trigger): (&Strides, &str),
    lp: &LowPass,
    phase: bool,
    warnings: &mut Vec<String>,
) -> Result<VaryingEstimate> {
    let fs = rec.sample_rate();
    let d = coords.len();
    let trig = trigger_values(rec, trigger)?;
    let kept = &strides.kept;
    let perturbed: Vec<bool> = kept
        .iter()
        .map(|r| trig[r.clone()].contains(&1.0))
        .collect();
    let baseline_strides: Vec<usize> = (0..kept.len()).filter(|&k| !perturbed[k]).collect();
    if baseline_strides.len() < 3 {
        return Err(Error::invalid(
            "trigger",
            format!(
                "{}: {} of {} strides carry no perturbation: perturbed minus unperturbed needs at least 3 unperturbed strides",
                rec.path().display(),
                baseline_strides.len(),
                kept.len()
            ),
        ));
    }
    let p = strides.median_len();
    // every kept stride's raw positions and forces, phase-normalised
    let raw_cols: Vec<&[f64]> = coords
        .iter()
        .map(|c| rec.require(c, "positions"))
        .chain(forces.iter().map(|c| rec.require(c, "forces")))
        .collect::<Result<_>>()?;
    let normalised = |k: usize| -> Vec<Vec<f64>> {
        let r = &kept[k];
        raw_cols
            .iter()
            .map(|col| {
                (0..p)
                    .map(|j| {
                        interp(
                            col,
                            r.start as f64 + super::stride_sample(r.len(), p, j, true),
                        )
                    })
                    .collect()
            })
            .collect()
    };
    let curves: Vec<Option<Vec<Vec<f64>>>> = (0..kept.len())
        .map(|k| (!perturbed[k]).then(|| normalised(k)))
        .collect();
    let neighbours = params.neighbours.unwrap_or(10).max(1);
    let cap_s = params
        .pulse_window_ms
        .map_or(DEFAULT_WINDOW_S, |ms| ms / 1e3);
    let pad = 3 * (fs / lp.cutoff_hz()).ceil() as usize;
    let (pre, post, cap) = (
        (PRE_S * fs).round() as usize,
        (POST_S * fs).round() as usize,
        (cap_s * fs).round() as usize,
    );
    // the stride (by event) each sample lies in, for its phase
    let events = &strides.events;
    let phase_at = |i: usize| -> Option<f64> {
        let e = events.partition_point(|&e| e <= i);
        if e == 0 || e >= events.len() {
            return None;
        }
        let (a, b) = (events[e - 1], events[e]);
        Some((i - a) as f64 / (b - a) as f64)
    };
    let mut pulses = Vec::new();
    let mut unused = 0usize;
    let mut too_few_baseline = 0usize;
    for (k, r) in kept.iter().enumerate() {
        if !perturbed[k] {
            continue;
        }
        for onset in r.clone() {
            if trig[onset] != 1.0 || (onset > 0 && trig[onset - 1] == 1.0) {
                continue;
            }
            let mut end = onset;
            while end < trig.len() && trig[end] == 1.0 {
                end += 1;
            }
            let w0 = onset.saturating_sub(pre);
            let w1 = (end + post).min(onset + cap);
            if w0 < pad || w1 + pad > rec.len() {
                unused += 1;
                continue;
            }
            // the nearest unperturbed strides
            let mut near: Vec<usize> = baseline_strides.clone();
            near.sort_by_key(|&j| j.abs_diff(k));
            near.truncate(neighbours);
            if near.len() < 3 {
                too_few_baseline += 1;
                continue;
            }
            let mean: Vec<Vec<f64>> = (0..2 * d)
                .map(|c| {
                    (0..p)
                        .map(|j| {
                            near.iter()
                                .map(|&s| curves[s].as_ref().expect("unperturbed")[c][j])
                                .sum::<f64>()
                                / near.len() as f64
                        })
                        .collect()
                })
                .collect();
            let (s0, s1) = (w0 - pad, w1 + pad);
            let mut dev: Vec<Vec<f64>> = vec![Vec::with_capacity(s1 - s0); 2 * d];
            let mut ok = true;
            for row in s0..s1 {
                let Some(ph) = phase_at(row) else {
                    ok = false;
                    break;
                };
                let u = ph * p as f64;
                // the curve wraps at the heel strike
                let j = u.floor() as usize % p;
                let f = u - u.floor();
                for ((out, curve), col) in dev.iter_mut().zip(&mean).zip(&raw_cols) {
                    let base = curve[j] * (1.0 - f) + curve[(j + 1) % p] * f;
                    out.push(col[row] - base);
                }
            }
            if !ok {
                unused += 1;
                continue;
            }
            let mut x = vec![Vec::with_capacity(w1 - w0); 3 * d];
            let mut f = vec![Vec::with_capacity(w1 - w0); d];
            for c in 0..d {
                let xs = lp.filtfilt(&dev[c])?;
                let fsig = lp.filtfilt(&dev[d + c])?;
                let (v, a) = super::super::derivatives(&xs, 1.0 / fs);
                let win = w0 - s0..w1 - s0;
                x[c] = a[win.clone()].to_vec();
                x[d + c] = v[win.clone()].to_vec();
                x[2 * d + c] = xs[win.clone()].to_vec();
                f[c] = fsig[win].to_vec();
            }
            let len = r.len() as f64;
            let sched = |row: usize| {
                if phase {
                    (row as f64 - r.start as f64) / len
                } else {
                    (row as f64 - r.start as f64) / fs
                }
            };
            let sigma: Vec<f64> = (w0..w1).map(sched).collect();
            let weight: Vec<f64> = (0..w1 - w0)
                .map(|t| (0..d).map(|c| x[2 * d + c][t].powi(2)).sum())
                .collect();
            let total: f64 = weight.iter().sum();
            if total <= 0.0 || !total.is_finite() {
                unused += 1;
                continue;
            }
            pulses.push(Pulse {
                x,
                f,
                sigma,
                t: (w0..w1)
                    .map(|row| (row as f64 - onset as f64) / fs)
                    .collect(),
            });
        }
    }
    if unused > 0 {
        warnings.push(format!(
            "{unused} perturbation(s) not used: too near the record's ends, or without displacement"
        ));
    }
    if too_few_baseline > 0 {
        warnings.push(format!(
            "{too_few_baseline} perturbation(s) not used: fewer than 3 unperturbed strides to compare with"
        ));
    }
    if pulses.is_empty() {
        return Err(Error::invalid(
            "trigger",
            format!(
                "{}: no perturbation could be used (see the trigger column {trigger})",
                rec.path().display()
            ),
        ));
    }
    let width = params.bin.unwrap_or(0.05);
    let top = if phase {
        1.0
    } else {
        kept.iter().map(|r| r.len()).max().unwrap_or(0) as f64 / fs
    };
    check_bin(&pulses, strides.median_len(), width, top, phase, fs)?;
    let fitted = fit_knots(&pulses, d, width, top, params.min_pulses);
    let points = fitted.points;
    let (rss, tss, press, press_tss) = fitted.sums;
    if let Some(why) = fitted.failure {
        warnings.push(why);
    }
    if !points.iter().any(|p| p.identifiable) {
        warnings.push(format!(
            "no point is identifiable: {} perturbations, at least {} needed at a point",
            pulses.len(),
            params.min_pulses
        ));
    }
    let vaf = |r: f64, t: f64| if t > 0.0 { 100.0 * (1.0 - r / t) } else { 0.0 };
    let mut schedule = axis(phase, params.event.as_deref().unwrap_or_default());
    schedule.values = points.iter().map(|p| p.sigma).collect();
    let window_note = format!(
        "K and B piecewise linear between knots {} {} apart, fitted on windows from {} ms before each onset to {} ms after its trigger falls (at most {} ms after the onset)",
        limpid_core::significant(width, 3),
        if phase { "of the stride" } else { "s" },
        crate::varying::round_ms(PRE_S),
        crate::varying::round_ms(POST_S),
        crate::varying::round_ms(cap_s)
    );
    Ok(VaryingEstimate {
        method: VaryingMethod::Pulses,
        schedule,
        coordinates: coords.to_vec(),
        forces: forces.to_vec(),
        sample_rate_hz: fs,
        cutoff_hz: lp.cutoff_hz(),
        resolution: width,
        resolution_note: window_note,
        repetitions: Some(pulses.len()),
        basis_order: None,
        order_cv_vaf: Vec::new(),
        points,
        fit: VaryingFit {
            vaf: vaf(rss, tss),
            cross_validated_vaf: vaf(press, press_tss),
        },
        reflex: None,
        gait: Some(GaitSummary {
            trigger: Some(trigger.to_string()),
            perturbations: Some(pulses.len()),
            ..GaitSummary::new(
                params,
                (strides, fs),
                kept.len(),
                format!(
                    "each perturbed stride minus the mean of the {} unperturbed strides nearest it ({} unperturbed in all), phase-normalised and stretched to its duration",
                    neighbours.min(baseline_strides.len()),
                    baseline_strides.len()
                ),
            )
        }),
        warnings: Vec::new(),
    })
}

/// The knots' fit: its points, `(rss, tss, press, press_tss)` over the
/// identifiable points' samples, and why it failed, if it did.
struct KnotFit {
    points: Vec<VaryingPoint>,
    sums: (f64, f64, f64, f64),
    failure: Option<String>,
}

/// Knots `h` apart on the schedule, the first at `first · h`.
struct Knots {
    at: Vec<f64>,
    h: f64,
    first: i64,
}

impl Knots {
    /// The knots whose hat functions cover `s`, with the hats' values there.
    fn around(&self, s: f64) -> impl Iterator<Item = (usize, f64)> + '_ {
        let j = (((s / self.h).floor() as i64) - self.first) as usize;
        [j, j + 1]
            .into_iter()
            .filter(|&jj| jj < self.at.len())
            .map(move |jj| (jj, (1.0 - (s - self.at[jj]).abs() / self.h).max(0.0)))
    }
}

/// Least perturbations behind a knot for it to be fitted at all (the jackknife's minimum).
const MIN_FITTED: usize = 3;
/// Share of a window's displacement weight on a knot for the window to count there.
const MIN_SHARE: f64 = 0.05;

/// Most knots a fit may have (a knot every 1e-12 of a stride asked for
/// 8 TB; issue 76).
const MAX_KNOTS: f64 = 2000.0;

/// A bin no shorter than one sample (in the schedule's unit: a fraction of
/// the median stride, or seconds) and at most [`MAX_KNOTS`] knots over the
/// windows' span; the error names `bin`.
fn check_bin(
    pulses: &[Pulse],
    median_stride: usize,
    width: f64,
    top: f64,
    phase: bool,
    fs: f64,
) -> Result<()> {
    let sample = if phase {
        1.0 / median_stride.max(1) as f64
    } else {
        1.0 / fs
    };
    let unit = if phase { " of the stride" } else { " s" };
    if width < sample {
        return Err(Error::invalid(
            "bin",
            format!(
                "a bin of {}{unit} is shorter than one sample ({}{unit}): knots closer than the samples cannot be fitted",
                limpid_core::error::Num(width),
                limpid_core::error::Num(sample)
            ),
        ));
    }
    let (lo, hi) = knot_span(pulses, top);
    let knots = (hi - lo) / width + 2.0;
    if knots > MAX_KNOTS {
        return Err(Error::invalid(
            "bin",
            format!(
                "a bin of {}{unit} puts {} knots over the windows' span of {}{unit}: at most {MAX_KNOTS}; widen the bin",
                limpid_core::error::Num(width),
                limpid_core::error::Num(knots.ceil()),
                limpid_core::error::Num(hi - lo)
            ),
        ));
    }
    Ok(())
}

/// Where the knots lie: over the whole stride, 0 to `top` (the figures show
/// where nothing was perturbed), and over every window's schedule values.
fn knot_span(pulses: &[Pulse], top: f64) -> (f64, f64) {
    pulses
        .iter()
        .flat_map(|p| p.sigma.iter())
        .fold((0.0_f64, top), |(lo, hi), &s| (lo.min(s), hi.max(s)))
}

fn fit_knots(pulses: &[Pulse], d: usize, h: f64, top: f64, min_pulses: usize) -> KnotFit {
    let (lo, hi) = knot_span(pulses, top);
    let first = (lo / h).floor() as i64;
    let last = (hi / h).ceil() as i64;
    let knots = Knots {
        at: (first..=last).map(|i| i as f64 * h).collect(),
        h,
        first,
    };
    let nk = knots.at.len();
    // each window's share of displacement weight per knot
    let share: Vec<Vec<f64>> = pulses
        .iter()
        .map(|p| {
            let mut w = vec![0.0; nk];
            for (t, &s) in p.sigma.iter().enumerate() {
                let x2: f64 = (0..d).map(|c| p.x[2 * d + c][t].powi(2)).sum();
                for (jj, hat) in knots.around(s) {
                    w[jj] += hat * x2;
                }
            }
            let total: f64 = w.iter().sum();
            w.iter().map(|v| v / total.max(f64::MIN_POSITIVE)).collect()
        })
        .collect();
    let support: Vec<usize> = (0..nk)
        .map(|j| share.iter().filter(|w| w[j] >= MIN_SHARE).count())
        .collect();
    let fitted: Vec<bool> = support.iter().map(|&n| n >= MIN_FITTED).collect();
    // columns: I (d), then per fitted knot K (d) and B (d)
    let column: Vec<Option<usize>> = {
        let mut next = d;
        fitted
            .iter()
            .map(|&f| {
                f.then(|| {
                    let c = next;
                    next += 2 * d;
                    c
                })
            })
            .collect()
    };
    let q = d + 2 * d * fitted.iter().filter(|&&f| f).count();
    let designs: Vec<Design> = pulses
        .iter()
        .map(|p| design(p, d, &knots, &column, q))
        .collect();
    let normals: Vec<Normal> = designs.iter().map(Normal::of).collect();
    let mut g = DMatrix::zeros(q, q);
    let mut hh = DMatrix::zeros(q, d);
    let mut ff = 0.0;
    for n in &normals {
        g += &n.g;
        hh += &n.h;
        ff += n.ff;
    }
    let grid: Vec<usize> = (0..nk)
        .filter(|&j| knots.at[j] >= -1e-9 && knots.at[j] < top - 1e-9)
        .collect();
    let blank = |j: usize, reason: String| {
        VaryingPoint::unidentified(knots.at[j], reason, support[j] as f64)
    };
    let reason_few = |j: usize| {
        if support[j] == 0 {
            "no perturbation moved the joint here".to_string()
        } else {
            format!(
                "only {} perturbation(s) moved the joint here: at least {min_pulses} are needed",
                support[j]
            )
        }
    };
    let fail = |why: String| KnotFit {
        points: grid
            .iter()
            .map(|&j| {
                blank(
                    j,
                    if support[j] < min_pulses {
                        reason_few(j)
                    } else {
                        why.clone()
                    },
                )
            })
            .collect(),
        sums: (0.0, 0.0, 0.0, 0.0),
        failure: Some(why),
    };
    if q == d {
        return fail("no point has perturbations enough to be fitted".into());
    }
    let Some(theta) = solve_scaled(&g, &hh) else {
        return fail("the perturbations' regressors are singular".into());
    };
    let mut thetas = Vec::with_capacity(normals.len());
    let mut press_of = Vec::with_capacity(normals.len());
    for n in &normals {
        let Some(th) = solve_scaled(&(&g - &n.g), &(&hh - &n.h)) else {
            return fail("leaving one perturbation out makes the regressors singular".into());
        };
        press_of.push(rss_of(n, &th));
        thetas.push(th);
    }
    let r = normals.len() as f64;
    let mean = thetas.iter().fold(DMatrix::zeros(q, d), |acc, t| acc + t) / r;
    let se = thetas
        .iter()
        .fold(DMatrix::zeros(q, d), |acc, t| {
            acc + (t - &mean).map(|v| v * v)
        })
        .map(|v| (v * (r - 1.0) / r).sqrt());
    if theta.iter().chain(se.iter()).any(|v| !v.is_finite()) {
        return fail("the estimate is not finite".into());
    }
    // value and SE of block `off` (0: K, d: B) at knot j, element (row i, column k)
    let value = |j: usize, off: usize| column[j].map(|c| matrix(d, |i, k| theta[(c + off + k, i)]));
    let error = |j: usize, off: usize| column[j].map(|c| matrix(d, |i, k| se[(c + off + k, i)]));
    let inertia = matrix(d, |i, k| theta[(k, i)]);
    let inertia_se = matrix(d, |i, k| se[(k, i)]);
    // per knot VAF over the samples its hat covers, weighted by the hat
    let mut knot_rss = vec![0.0; nk];
    let mut knot_tss = vec![0.0; nk];
    for (p, Design { x, f, rows }) in pulses.iter().zip(&designs) {
        let res = f - x * &theta;
        for (t, s) in rows.iter().map(|&row| p.sigma[row]).enumerate() {
            for (jj, hat) in knots.around(s) {
                knot_rss[jj] += hat * res.row(t).iter().map(|v| v * v).sum::<f64>();
                knot_tss[jj] += hat * f.row(t).iter().map(|v| v * v).sum::<f64>();
            }
        }
    }
    let (mut rss, mut tss, mut press, mut press_tss) = (0.0, 0.0, 0.0, 0.0);
    let mut points = Vec::with_capacity(grid.len());
    for &j in &grid {
        if support[j] < min_pulses || column[j].is_none() {
            points.push(blank(j, reason_few(j)));
            continue;
        }
        let c = column[j].expect("fitted");
        let block = DMatrix::from_fn(2 * d, 2 * d, |a, b| g[(c + a, c + b)]);
        let condition = scaled_condition(&block);
        if !well_conditioned(condition) {
            let mut p = blank(
                j,
                "the perturbations here do not excite the model (condition number too high)".into(),
            );
            p.condition_number = condition.is_finite().then_some(condition);
            points.push(p);
            continue;
        }
        // interpolation bias from the neighbours' curvature, in quadrature
        let widen = |off: usize| -> limpid_core::Matrix {
            let (v, e) = (
                value(j, off).expect("fitted"),
                error(j, off).expect("fitted"),
            );
            let near = (j > 0 && j + 1 < nk)
                .then(|| Some((value(j - 1, off)?, value(j + 1, off)?)))
                .flatten();
            matrix(d, |a, b| {
                let bias = near.as_ref().map_or(0.0, |(l, r)| {
                    (l[(a, b)] - 2.0 * v[(a, b)] + r[(a, b)]) / 6.0
                });
                e[(a, b)].hypot(bias)
            })
        };
        let (k, b) = (value(j, 0).expect("fitted"), value(j, d).expect("fitted"));
        let ks = floored(&k, widen(0), WALKING_MODEL_FLOOR);
        let bs = floored(&b, widen(d), WALKING_MODEL_FLOOR);
        let inertia_se = floored(&inertia, inertia_se.clone(), WALKING_MODEL_FLOOR);
        let vaf = (knot_tss[j] > 0.0).then(|| 100.0 * (1.0 - knot_rss[j] / knot_tss[j]));
        let verdicts = PointVerdicts::within(
            [&k, &ks, &b, &bs, &inertia, &inertia_se],
            vaf,
            WALKING_TOLERANCES,
        );
        rss += knot_rss[j];
        tss += knot_tss[j];
        points.push(VaryingPoint {
            sigma: knots.at[j],
            identifiable: true,
            reason: None,
            stiffness: Some(k),
            stiffness_se: Some(ks),
            damping: Some(b),
            damping_se: Some(bs),
            inertia: Some(inertia.clone()),
            inertia_se: Some(inertia_se),
            reflex: None,
            vaf,
            support: support[j] as f64,
            condition_number: Some(condition),
            verdicts: Some(verdicts),
        });
    }
    // the cross-validated VAF is over every perturbation (each predicted from the others)
    if points.iter().any(|p| p.identifiable) {
        press = press_of.iter().sum();
        press_tss = ff;
    }
    KnotFit {
        points,
        sums: (rss, tss, press, press_tss),
        failure: None,
    }
}

/// One perturbation's normal equations after its offset and drift are
/// projected out: `G = Xᵀ X`, `H = Xᵀ F`, `F`'s sum of squares.
struct Normal {
    g: DMatrix<f64>,
    h: DMatrix<f64>,
    ff: f64,
}

impl Normal {
    fn of(d: &Design) -> Normal {
        Normal {
            g: d.x.transpose() * &d.x,
            h: d.x.transpose() * &d.f,
            ff: d.f.iter().map(|v| v * v).sum(),
        }
    }
}

/// One perturbation's regressors `x` (I, then K and B of each fitted knot)
/// and forces `f`, its offset and drift projected out, over the window
/// samples `rows` kept (those on a knot not fitted are left out).
struct Design {
    x: DMatrix<f64>,
    f: DMatrix<f64>,
    rows: Vec<usize>,
}

fn design(p: &Pulse, d: usize, knots: &Knots, column: &[Option<usize>], q: usize) -> Design {
    let rows: Vec<usize> = (0..p.sigma.len())
        .filter(|&t| {
            knots
                .around(p.sigma[t])
                .all(|(jj, hat)| hat == 0.0 || column[jj].is_some())
        })
        .collect();
    let n = rows.len();
    let mut x = DMatrix::zeros(n, q);
    let mut f = DMatrix::zeros(n, d);
    for (r, &t) in rows.iter().enumerate() {
        let s = p.sigma[t];
        for c in 0..d {
            x[(r, c)] = p.x[c][t];
            f[(r, c)] = p.f[c][t];
        }
        for (jj, w) in knots.around(s) {
            let Some(col) = column[jj] else {
                continue;
            };
            for c in 0..d {
                x[(r, col + c)] = w * p.x[2 * d + c][t];
                x[(r, col + d + c)] = w * p.x[d + c][t];
            }
        }
    }
    // orthonormal basis of [1, t] over the rows kept
    if n >= 3 {
        let ts: Vec<f64> = rows.iter().map(|&t| p.t[t]).collect();
        let mean_t = ts.iter().sum::<f64>() / n as f64;
        let u1 = vec![1.0 / (n as f64).sqrt(); n];
        let centred: Vec<f64> = ts.iter().map(|t| t - mean_t).collect();
        let norm = centred.iter().map(|v| v * v).sum::<f64>().sqrt();
        let u2: Vec<f64> = centred
            .iter()
            .map(|v| v / norm.max(f64::MIN_POSITIVE))
            .collect();
        let project = |m: &mut DMatrix<f64>| {
            for c in 0..m.ncols() {
                for u in [&u1, &u2] {
                    let dot: f64 = (0..n).map(|t| u[t] * m[(t, c)]).sum();
                    for t in 0..n {
                        m[(t, c)] -= dot * u[t];
                    }
                }
            }
        };
        project(&mut x);
        project(&mut f);
    } else {
        x.fill(0.0);
        f.fill(0.0);
    }
    Design { x, f, rows }
}

fn rss_of(n: &Normal, theta: &DMatrix<f64>) -> f64 {
    n.ff - 2.0 * (theta.transpose() * &n.h).trace() + (theta.transpose() * &n.g * theta).trace()
}
