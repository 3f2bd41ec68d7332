//! Ensemble time-varying identification (Kearney & MacNeil's ensemble
//! methods; Lakatos et al., seed 003 §I, on impedance during movement).
//!
//! The repetitions (the `trial` column) are aligned at their first sample and
//! cut to the shortest. Positions and forces are low-passed (zero phase) and
//! differentiated per repetition. At each instant `t` the deviations of every
//! repetition from the ensemble mean satisfy, for a limb linear about its
//! mean path,
//!
//! `δf_r(t) = M(t) δx''_r(t) + B(t) δx'_r(t) + K(t) δx_r(t)`,
//!
//! so one least-squares fit across repetitions gives M, B, K at `t`. The
//! instants within a window of `window_s` around each grid point are pooled
//! (the parameters taken constant over it): the window is the time
//! resolution. Standard errors are the jackknife over repetitions (leave one
//! repetition out, deviations from the remaining mean), the cross-validated
//! VAF predicts each repetition's deviations from the others' fit. Cross
//! products are accumulated once per instant and summed over windows by
//! prefix sums, so a window costs the same however wide it is.

use nalgebra::DMatrix;
use rayon::prelude::*;

use limpid_core::criteria::well_conditioned;
use limpid_core::trial::windows_from_trial_column;
use limpid_core::{Error, Recording, Result};
use limpid_dsp::LowPass;

use super::{
    matrix, scaled_condition, solve_scaled, PointVerdicts, ScheduleAxis, VaryingEstimate,
    VaryingFit, VaryingMethod, VaryingParams, VaryingPoint,
};

const FILTER_ORDER: usize = 4;

/// Per repetition, per instant: `[x'' (d), x' (d), x (d), f (d)]`, row-major `L x 4d`.
pub(super) struct Ensemble {
    pub z: Vec<Vec<f64>>,
    pub len: usize,
    pub d: usize,
}

fn repetitions(
    rec: &Recording,
    coords: &[String],
    forces: &[String],
    cutoff: f64,
    warnings: &mut Vec<String>,
) -> Result<Ensemble> {
    if !rec.has("trial") {
        return Err(Error::MissingColumn {
            path: rec.path().to_path_buf(),
            column: "trial".into(),
            why: "time-varying (ensemble) identification needs repetitions of the task, one trial id each".into(),
            found: rec.names().join(","),
        });
    }
    let fs = rec.sample_rate();
    let dt = 1.0 / fs;
    let lp = LowPass::butterworth(FILTER_ORDER, cutoff, fs)?;
    let mut windows = windows_from_trial_column(rec, "trial")?;
    let mut lengths: Vec<usize> = windows.iter().map(|w| w.range.len()).collect();
    lengths.sort_unstable();
    let median = lengths[lengths.len() / 2];
    let before = windows.len();
    windows.retain(|w| 2 * w.range.len() >= median && w.range.len() > lp.padlen() + 1);
    if windows.len() < before {
        warnings.push(format!(
            "{} of {before} repetitions left out: shorter than half the median ({median} samples) or than the filter needs",
            before - windows.len()
        ));
    }
    if windows.len() < 3 {
        return Err(Error::invalid(
            "trial",
            format!(
                "{}: an ensemble needs at least 3 repetitions of the task, found {}{}",
                rec.path().display(),
                windows.len(),
                schedule_hint(rec)
            ),
        ));
    }
    let len = windows.iter().map(|w| w.range.len()).min().unwrap_or(0);
    let longest = windows.iter().map(|w| w.range.len()).max().unwrap_or(0);
    if longest as f64 > 1.05 * len as f64 {
        warnings.push(format!(
            "repetitions differ in length ({len} to {longest} samples): aligned at their start and cut to the shortest"
        ));
    }
    let d = coords.len();
    let (pos, frc) = (
        crate::prepare::columns(rec, coords),
        crate::prepare::columns(rec, forces),
    );
    let z = windows
        .par_iter()
        .map(|w| {
            let r = w.range.clone();
            let mut out = vec![0.0; len * 4 * d];
            for k in 0..d {
                let x = lp.filtfilt(&pos[k][r.clone()])?;
                let f = lp.filtfilt(&frc[k][r.clone()])?;
                let (v, a) = super::derivatives(&x, dt);
                for t in 0..len {
                    let row = &mut out[t * 4 * d..(t + 1) * 4 * d];
                    row[k] = a[t];
                    row[d + k] = v[t];
                    row[2 * d + k] = x[t];
                    row[3 * d + k] = f[t];
                }
            }
            Ok(out)
        })
        .collect::<Result<Vec<_>>>()?;
    Ok(Ensemble { z, len, d })
}

/// Prefix sums over instants of `Σ_r z`, `Σ_r z zᵀ` and `(Σ_r z)(Σ_r z)ᵀ`.
struct Prefix {
    s: Vec<f64>,
    zz: Vec<f64>,
    ss: Vec<f64>,
}

fn prefix(e: &Ensemble) -> Prefix {
    let m = 4 * e.d;
    let mut s = vec![0.0; (e.len + 1) * m];
    let mut zz = vec![0.0; (e.len + 1) * m * m];
    let mut ss = vec![0.0; (e.len + 1) * m * m];
    let mut sum = vec![0.0; m];
    let mut outer = vec![0.0; m * m];
    for t in 0..e.len {
        sum.iter_mut().for_each(|v| *v = 0.0);
        outer.iter_mut().for_each(|v| *v = 0.0);
        for rep in &e.z {
            let row = &rep[t * m..(t + 1) * m];
            for i in 0..m {
                sum[i] += row[i];
                for j in i..m {
                    outer[i * m + j] += row[i] * row[j];
                }
            }
        }
        let (p, q) = (t * m, (t + 1) * m);
        for i in 0..m {
            s[q + i] = s[p + i] + sum[i];
        }
        let (p2, q2) = (t * m * m, (t + 1) * m * m);
        for i in 0..m {
            for j in i..m {
                zz[q2 + i * m + j] = zz[p2 + i * m + j] + outer[i * m + j];
                ss[q2 + i * m + j] = ss[p2 + i * m + j] + sum[i] * sum[j];
            }
        }
    }
    Prefix { s, zz, ss }
}

/// Split an m x m symmetric (upper triangle filled) cross product into the
/// regressor Gram (3d x 3d), regressor-force (3d x d) and force (d x d) parts.
fn blocks(c: &[f64], d: usize) -> (DMatrix<f64>, DMatrix<f64>, DMatrix<f64>) {
    let m = 4 * d;
    let at = |i: usize, j: usize| {
        if i <= j {
            c[i * m + j]
        } else {
            c[j * m + i]
        }
    };
    let p = 3 * d;
    (
        DMatrix::from_fn(p, p, at),
        DMatrix::from_fn(p, d, |i, j| at(i, p + j)),
        DMatrix::from_fn(d, d, |i, j| at(p + i, p + j)),
    )
}

/// Residual sum of squares `tr(Cff - 2 Θᵀ Cxf + Θᵀ Cxx Θ)`.
fn rss(cxx: &DMatrix<f64>, cxf: &DMatrix<f64>, cff: &DMatrix<f64>, theta: &DMatrix<f64>) -> f64 {
    let fit = theta.transpose() * cxx * theta;
    cff.trace() - 2.0 * (theta.transpose() * cxf).trace() + fit.trace()
}

struct GridFit {
    point: VaryingPoint,
    rss: f64,
    tss: f64,
    press: f64,
    press_tss: f64,
}

pub(super) fn estimate(
    rec: &Recording,
    params: &VaryingParams,
    coords: Vec<String>,
    forces: Vec<String>,
    cutoff: f64,
) -> Result<VaryingEstimate> {
    let mut warnings = Vec::new();
    let fs = rec.sample_rate();
    let e = repetitions(rec, &coords, &forces, cutoff, &mut warnings)?;
    let reps = e.z.len();
    let step_s = params.step_s.unwrap_or(params.window_s / 2.0);
    let layout = Layout::new(
        &e,
        (params.window_s, step_s),
        1.0 / fs,
        // derivatives of the zero-phase filter's padded ends are not trusted within one cut-off period
        (fs / cutoff).ceil() as usize,
    )?;
    let (points, fit) = fit_grid(&e, &layout, params.min_repetitions, &mut warnings);
    Ok(VaryingEstimate {
        method: VaryingMethod::Ensemble,
        schedule: ScheduleAxis {
            name: "time since trial start".into(),
            unit: "s".into(),
            values: points.iter().map(|p| p.sigma).collect(),
            angle: None,
        },
        coordinates: coords,
        forces,
        sample_rate_hz: fs,
        cutoff_hz: cutoff,
        resolution: layout.width() as f64 / fs,
        resolution_note: layout.note(),
        repetitions: Some(reps),
        basis_order: None,
        order_cv_vaf: Vec::new(),
        points,
        fit,
        reflex: None,
        gait: None,
        warnings,
    })
}

/// Where the grid points of an ensemble lie and how wide each pools: in
/// samples of the aligned repetitions, with what a sample is on the schedule
/// (seconds, or a fraction of the stride) and in seconds.
pub(super) struct Layout {
    /// Half the window (samples).
    pub half: usize,
    /// Grid step (samples).
    pub step: usize,
    /// Samples at each end not trusted.
    pub edge: usize,
    /// The schedule's value per sample.
    pub sigma_per_sample: f64,
    /// Seconds per sample (for messages; an average over strides when phase-normalised).
    pub sample_s: f64,
    /// Share of each value added in quadrature to its standard error (see
    /// [`super::gait::WALKING_MODEL_FLOOR`]); 0 for repetitions of a task.
    pub model_floor: f64,
    /// The relative tolerances (K, B, M) the points' verdicts are judged against.
    pub tolerances: [f64; 3],
}

impl Layout {
    /// The layout of a window and step given in seconds, on repetitions
    /// whose samples last `sample_s`; refuses a window or step not shorter
    /// than the repetitions.
    pub(super) fn new(
        e: &Ensemble,
        (window_s, step_s): (f64, f64),
        sample_s: f64,
        edge: usize,
    ) -> Result<Layout> {
        // compared before any cast: 1e307 ms would saturate a sample count
        let repetition_ms = e.len as f64 * sample_s * 1e3;
        for (name, seconds) in [("window_ms", window_s), ("step_ms", step_s)] {
            if seconds * 1e3 >= repetition_ms {
                return Err(Error::invalid(
                    name,
                    format!(
                        "{} ms is not shorter than the repetitions ({} ms)",
                        limpid_core::significant(seconds * 1e3, 4),
                        limpid_core::significant(repetition_ms, 4)
                    ),
                ));
            }
        }
        let half = ((window_s / sample_s / 2.0).round() as usize).max(1);
        let step = ((step_s / sample_s).round() as usize).max(1);
        if e.len < 2 * half + 1 {
            return Err(Error::invalid(
                "window_ms",
                format!(
                    "the window ({} samples) is longer than the repetitions ({} samples)",
                    2 * half + 1,
                    e.len
                ),
            ));
        }
        if (e.len - 2 * half) / step > 100_000 {
            return Err(Error::invalid(
                "step_ms",
                format!(
                    "{} grid points: choose a longer step",
                    (e.len - 2 * half) / step
                ),
            ));
        }
        Ok(Layout {
            half,
            step,
            edge,
            sigma_per_sample: sample_s,
            sample_s,
            model_floor: 0.0,
            tolerances: super::BENCH_TOLERANCES,
        })
    }

    /// Samples pooled per point.
    pub(super) fn width(&self) -> usize {
        2 * self.half + 1
    }

    /// The resolution, in words.
    pub(super) fn note(&self) -> String {
        format!(
            "each point pools the instants within ±{} ms (a box {} ms wide): a change of impedance narrower than that is smoothed",
            crate::varying::round_ms(self.half as f64 * self.sample_s),
            crate::varying::round_ms(self.width() as f64 * self.sample_s)
        )
    }
}

/// Fit every grid point of an aligned ensemble: the points and the overall fit.
pub(super) fn fit_grid(
    e: &Ensemble,
    layout: &Layout,
    min_repetitions: usize,
    warnings: &mut Vec<String>,
) -> (Vec<VaryingPoint>, VaryingFit) {
    let pre = prefix(e);
    let half = layout.half;
    let centres: Vec<usize> = (half..e.len - half).step_by(layout.step).collect();
    let mut fits: Vec<GridFit> = centres
        .par_iter()
        .map(|&c| fit_window(e, &pre, c - half..c + half + 1, min_repetitions, layout))
        .collect();
    judge_with_smoothing_bias(&mut fits, layout);
    let sum = |f: fn(&GridFit) -> f64| {
        fits.iter()
            .filter(|g| g.point.identifiable)
            .map(f)
            .sum::<f64>()
    };
    let (rss, tss, press, press_tss) = (
        sum(|g| g.rss),
        sum(|g| g.tss),
        sum(|g| g.press),
        sum(|g| g.press_tss),
    );
    if !fits.iter().any(|g| g.point.identifiable) {
        warnings.push("no instant is identifiable: see each point's reason".to_string());
    }
    let vaf = |r: f64, t: f64| if t > 0.0 { 100.0 * (1.0 - r / t) } else { 0.0 };
    (
        fits.into_iter().map(|g| g.point).collect(),
        VaryingFit {
            vaf: vaf(rss, tss),
            cross_validated_vaf: vaf(press, press_tss),
        },
    )
}

/// The box average over `width` samples differs from the value at the
/// centre by about `K'' (width² - 1) / 24` samples² where the impedance
/// curves; its standard error does not say so. Each point's verdicts are
/// taken again with `sqrt(SE² + bias²)`, the curvature from the second
/// difference of the neighbouring points (`step` samples apart), so a point on a
/// sharp change is not trusted beyond its tolerance.
fn judge_with_smoothing_bias(fits: &mut [GridFit], layout: &Layout) {
    let (width, step) = (layout.width(), layout.step);
    let factor = (width as f64 * width as f64 - 1.0) / 24.0 / (step as f64 * step as f64);
    let widened: Vec<Option<PointVerdicts>> = (0..fits.len())
        .map(|g| {
            if g == 0 || g + 1 >= fits.len() {
                return None;
            }
            let [a, b, c] = [&fits[g - 1].point, &fits[g].point, &fits[g + 1].point];
            if !(a.identifiable && b.identifiable && c.identifiable) {
                return None;
            }
            let widen = |pick: fn(
                &VaryingPoint,
            ) -> (
                &Option<limpid_core::Matrix>,
                &Option<limpid_core::Matrix>,
            )| {
                let (m0, _) = pick(a);
                let (m1, se) = pick(b);
                let (m2, _) = pick(c);
                let (m0, m1, m2, se) = (m0.as_ref()?, m1.as_ref()?, m2.as_ref()?, se.as_ref()?);
                let d = m1.nrows();
                Some(matrix(d, |i, j| {
                    let bias = factor * (m0[(i, j)] - 2.0 * m1[(i, j)] + m2[(i, j)]);
                    se[(i, j)].hypot(bias)
                }))
            };
            let ks = widen(|p| (&p.stiffness, &p.stiffness_se))?;
            let bs = widen(|p| (&p.damping, &p.damping_se))?;
            let ms = widen(|p| (&p.inertia, &p.inertia_se))?;
            Some(PointVerdicts::within(
                [
                    b.stiffness.as_ref()?,
                    &ks,
                    b.damping.as_ref()?,
                    &bs,
                    b.inertia.as_ref()?,
                    &ms,
                ],
                b.vaf,
                layout.tolerances,
            ))
        })
        .collect();
    for (f, v) in fits.iter_mut().zip(widened) {
        if v.is_some() {
            f.point.verdicts = v;
        }
    }
}

fn fit_window(
    e: &Ensemble,
    pre: &Prefix,
    w: std::ops::Range<usize>,
    min_repetitions: usize,
    layout: &Layout,
) -> GridFit {
    let (d, m, reps) = (e.d, 4 * e.d, e.z.len());
    let r = reps as f64;
    let centre = (w.start + w.end - 1) / 2;
    let sigma = centre as f64 * layout.sigma_per_sample;
    let c = centred_cross_product(pre, &w, m, r);
    let (cxx, cxf, cff) = blocks(&c, d);
    let condition = scaled_condition(&cxx);
    let empty = |reason: String| GridFit {
        point: VaryingPoint {
            condition_number: condition.is_finite().then_some(condition),
            ..VaryingPoint::unidentified(sigma, reason, reps as f64)
        },
        rss: 0.0,
        tss: 0.0,
        press: 0.0,
        press_tss: 0.0,
    };
    if let Some(reason) = refusal(e, &w, min_repetitions, condition, layout) {
        return empty(reason);
    }
    if !repetitions_differ(pre, &w, m, &c) {
        // issue 56: 40 identical repetitions gave K = -1.85 ± 2e-15 "identifiable"
        return empty("the repetitions do not differ here (their deviations from the mean are at rounding level): the ensemble method needs perturbations that vary from one repetition to the next".into());
    }
    let Some(theta) = solve_scaled(&cxx, &cxf) else {
        return empty("the regressors are singular here".into());
    };
    let full_rss = rss(&cxx, &cxf, &cff, &theta);
    let tss = cff.trace();
    let Some(LeaveOneOut {
        se,
        press,
        press_tss,
    }) = leave_one_out(e, pre, &w)
    else {
        return empty("leaving one repetition out makes the regressors singular".into());
    };
    if theta.iter().chain(se.iter()).any(|v| !v.is_finite()) {
        return empty("the estimate is not finite here".into());
    }
    // Θ's row (block b, coordinate k), column j is the element (j, k) of M, B or K
    let part = |t: &DMatrix<f64>, b: usize| matrix(d, |j, k| t[(b * d + k, j)]);
    let [m, ms, b, bs, k, ks] = [
        part(&theta, 0),
        part(&se, 0),
        part(&theta, 1),
        part(&se, 1),
        part(&theta, 2),
        part(&se, 2),
    ];
    let [ms, bs, ks] =
        [(&m, ms), (&b, bs), (&k, ks)].map(|(v, e)| super::floored(v, e, layout.model_floor));
    let vaf = (tss > 0.0).then(|| 100.0 * (1.0 - full_rss / tss));
    let verdicts = PointVerdicts::within([&k, &ks, &b, &bs, &m, &ms], vaf, layout.tolerances);
    GridFit {
        point: VaryingPoint {
            sigma,
            identifiable: true,
            reason: None,
            inertia: Some(m),
            inertia_se: Some(ms),
            damping: Some(b),
            damping_se: Some(bs),
            stiffness: Some(k),
            stiffness_se: Some(ks),
            reflex: None,
            vaf,
            support: reps as f64,
            condition_number: Some(condition),
            verdicts: Some(verdicts),
        },
        rss: full_rss,
        tss,
        press,
        press_tss,
    }
}

/// The window's centred cross product `Σ_t [Σ_r z zᵀ - s sᵀ / R]` (upper
/// triangle, row-major `m x m`) from the prefix sums.
fn centred_cross_product(pre: &Prefix, w: &std::ops::Range<usize>, m: usize, r: f64) -> Vec<f64> {
    let mut c = vec![0.0; m * m];
    for i in 0..m {
        for j in i..m {
            let k = i * m + j;
            let zz = pre.zz[w.end * m * m + k] - pre.zz[w.start * m * m + k];
            let ss = pre.ss[w.end * m * m + k] - pre.ss[w.start * m * m + k];
            c[k] = zz - ss / r;
        }
    }
    c
}

/// Whether the repetitions' deviations from their mean carry more than
/// rounding: the centred power of the regressors against their raw power.
fn repetitions_differ(pre: &Prefix, w: &std::ops::Range<usize>, m: usize, centred: &[f64]) -> bool {
    let regressors = 3 * m / 4;
    let (mut raw, mut dev) = (0.0, 0.0);
    for i in 0..regressors {
        let k = i * m + i;
        raw += pre.zz[w.end * m * m + k] - pre.zz[w.start * m * m + k];
        dev += centred[k];
    }
    raw > 0.0 && dev > 1e-10 * raw
}

/// Why a grid point cannot be identified before any fit: too few
/// repetitions, the filter's unreliable ends, or regressors not excited.
fn refusal(
    e: &Ensemble,
    w: &std::ops::Range<usize>,
    min_repetitions: usize,
    condition: f64,
    layout: &Layout,
) -> Option<String> {
    let edge = layout.edge;
    let reps = e.z.len();
    if reps < min_repetitions {
        return Some(format!(
            "only {reps} repetitions: the ensemble's standard errors need at least {min_repetitions}"
        ));
    }
    if w.start < edge || w.end + edge > e.len {
        return Some(format!(
            "within {} ms of the repetitions' ends, where the zero-phase filter's derivatives are not reliable",
            crate::varying::round_ms(edge as f64 * layout.sample_s)
        ));
    }
    if !well_conditioned(condition) {
        return Some(format!(
            "the repetitions' deviations do not excite the model here (condition number {})",
            if condition.is_finite() {
                format!("{condition:.0}")
            } else {
                "infinite".into()
            }
        ));
    }
    None
}

/// A window's jackknife over repetitions and its leave-one-out prediction.
struct LeaveOneOut {
    /// Jackknife standard errors of Θ.
    se: DMatrix<f64>,
    /// Squared error of predicting each left-out repetition's deviations.
    press: f64,
    /// Their total sum of squares.
    press_tss: f64,
}

/// Refit the window without each repetition in turn (from the prefix sums:
/// the left-out repetition's own cross products are subtracted); None when
/// one leaves the regressors singular.
fn leave_one_out(e: &Ensemble, pre: &Prefix, w: &std::ops::Range<usize>) -> Option<LeaveOneOut> {
    let (d, m, r) = (e.d, 4 * e.d, e.z.len() as f64);
    let sums: Vec<f64> = (0..m)
        .flat_map(|i| (0..m).map(move |j| (i, j)))
        .map(|(i, j)| {
            let (a, b) = (i.min(j), i.max(j));
            pre.zz[w.end * m * m + a * m + b] - pre.zz[w.start * m * m + a * m + b]
        })
        .collect();
    let mut thetas: Vec<DMatrix<f64>> = Vec::with_capacity(e.z.len());
    let (mut press, mut press_tss) = (0.0, 0.0);
    let mut q = vec![0.0; m * m];
    let mut dd = vec![0.0; m * m];
    let (mut u, mut dv) = (vec![0.0; m], vec![0.0; m]);
    for rep in &e.z {
        q.iter_mut().for_each(|v| *v = 0.0);
        dd.iter_mut().for_each(|v| *v = 0.0);
        for t in w.clone() {
            let z = &rep[t * m..(t + 1) * m];
            let s = &pre.s[(t + 1) * m..(t + 2) * m];
            let s0 = &pre.s[t * m..(t + 1) * m];
            for i in 0..m {
                u[i] = (s[i] - s0[i]) - z[i];
                dv[i] = z[i] - u[i] / (r - 1.0);
            }
            for i in 0..m {
                for j in i..m {
                    q[i * m + j] += z[i] * z[j] + u[i] * u[j] / (r - 1.0);
                    dd[i * m + j] += dv[i] * dv[j];
                }
            }
        }
        let loo: Vec<f64> = (0..m * m)
            .map(|k| {
                let (i, j) = (k / m, k % m);
                if i <= j {
                    sums[k] - q[k]
                } else {
                    0.0
                }
            })
            .collect();
        let (lxx, lxf, _) = blocks(&loo, d);
        let th = solve_scaled(&lxx, &lxf)?;
        let (dxx, dxf, dff) = blocks(&dd, d);
        press += rss(&dxx, &dxf, &dff, &th);
        press_tss += dff.trace();
        thetas.push(th);
    }
    let p = 3 * d;
    let mean = thetas.iter().fold(DMatrix::zeros(p, d), |acc, t| acc + t) / r;
    let var = thetas.iter().fold(DMatrix::zeros(p, d), |acc, t| {
        acc + (t - &mean).map(|v| v * v)
    }) * ((r - 1.0) / r);
    Some(LeaveOneOut {
        se: var.map(f64::sqrt),
        press,
        press_tss,
    })
}

/// A recording without repetitions may be a parameter-varying one: its
/// columns that could be a schedule (neither time, trial, motion nor force),
/// named with the flag that takes them.
fn schedule_hint(rec: &Recording) -> String {
    // env_ columns (EMG envelopes) are schedules of their own; the other
    // format columns are time, trials, motion and force
    let motion_or_force = |n: &str| {
        (limpid_core::recording::is_format_column(n) && !n.starts_with("env_")) || n == "period"
    };
    let candidates: Vec<&str> = rec
        .names()
        .iter()
        .map(String::as_str)
        .filter(|n| !motion_or_force(n))
        .collect();
    match candidates.as_slice() {
        [] => String::new(),
        [one] => format!(
            "; for impedance against an operating point the file's column {one} can be the schedule: --schedule {one}"
        ),
        many => format!(
            "; for impedance against an operating point name a schedule column: --schedule {} (or {})",
            many[0],
            many[1..].join(", ")
        ),
    }
}
