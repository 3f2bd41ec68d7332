//! Preparation: from a checked recording to generalized coordinates
//! `x, x', x''` and forces `f` per window (seed 000 §II-C, seed 001 "Data
//! Processing").
//!
//! Steps, in order:
//! 1. choose coordinates and their forces (`x,y,z`/`fx,fy,fz`, `theta`/`tauy`,
//!    or `q1..qn`/`tau1..taun`), optionally negate forces read by a sensor;
//! 2. optional frame change (seed 000 eq. (1), or any homogeneous transform);
//! 3. cut into windows: the `trial` column, onsets found from the motion, or
//!    one continuous window;
//! 4. per perturbation window: subtract the mean force of the pre-onset rest
//!    (sensor bias, arm weight) and measure position from the rest position;
//!    continuous windows keep their constant, which the estimator fits;
//! 5. per window: the same zero-phase low-pass on positions and forces (so
//!    the linear model still holds exactly between the filtered signals),
//!    then derivatives by central differences; or Savitzky-Golay smoothing
//!    and derivatives of one window and order;
//! 6. drop `trim` samples at both ends of every window (filter/derivative
//!    edge effects) and concatenate.

use std::borrow::Cow;
use std::ops::Range;
use std::path::PathBuf;

use limpid_core::trial::{native_noise_sigma, noise_sigma, resampling, Resampled};
use limpid_core::{Error, FrameTransform, Recording, Result, Warning, WarningCode, Window};
use limpid_dsp::LowPass;
use rayon::prelude::*;
use serde::{Deserialize, Serialize};

mod filter;
mod windows;

use filter::filter_and_differentiate;
pub use filter::savgol_window;
pub(crate) use filter::{edge_kinds, noise_gains};
pub use windows::FORCE_LEAD_S;
use windows::{fits_offsets, keep_level, make_windows, resolved_windowing};

/// How velocity and acceleration are obtained.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize, schemars::JsonSchema)]
#[cfg_attr(feature = "clap", derive(clap::ValueEnum))]
#[serde(rename_all = "lowercase")]
pub enum Derivative {
    /// Butterworth zero-phase low-pass, then central differences.
    Central,
    /// Savitzky-Golay (cubic) smoothing and derivatives (window from the cut-off).
    Savgol,
}

/// How per-trial force offsets (sensor bias, arm weight, slow drift) are handled.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize, schemars::JsonSchema)]
#[cfg_attr(feature = "clap", derive(clap::ValueEnum))]
#[serde(rename_all = "lowercase")]
pub enum Offsets {
    /// Subtract the pre-onset rest mean (Artemiadis et al. 2010 §II-C; Patel et al. 2013); equilibrium estimated.
    ///
    /// The equilibrium position is then estimated with a constant term.
    Rest,
    /// Fit one force offset per trial (robust to slow drift; no equilibrium).
    ///
    /// Within-trial demeaning of forces and regressors: every sample of a
    /// trial finds its offset, so slow force drift biases damping of slow
    /// perturbations less (ex_cubic: damping error 14.5 % -> 10 %), but any
    /// model mismatch during fast motion moves the offsets and so the
    /// stiffness (ex_config7: K error 0.1 % -> 1.6 %); the equilibrium is not
    /// identifiable.
    Fit,
    /// Fitted for trials longer than 2 s (slow perturbations), rest mean otherwise.
    ///
    /// `Fit` when the trials last longer than [`AUTO_FIT_ABOVE_S`] (median),
    /// `Rest` otherwise: over a short trial the force drifts little after the
    /// rest, while over seconds its drift rivals the damping force.
    Auto,
}

/// Median trial duration (s) above which [`Offsets::Auto`] fits the offsets.
pub const AUTO_FIT_ABOVE_S: f64 = 2.0;

/// How the recording is cut into estimation windows.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize, schemars::JsonSchema)]
#[cfg_attr(feature = "clap", derive(clap::ValueEnum))]
#[serde(rename_all = "lowercase")]
pub enum Windowing {
    /// The `trial` column if present, else one continuous window.
    ///
    /// Onsets are not searched for automatically: a pseudo-random step perturbation
    /// (e.g. the real ankle recordings of Kearney's laboratory) has rests and steps that look like trials.
    Auto,
    /// Use the `trial` column (error if absent).
    Trials,
    /// Detect perturbation onsets from the motion.
    Onsets,
    /// One continuous window with a constant term.
    Continuous,
    /// The `trial` column, each trial a continuous window with its own force offset (holds of a continuous perturbation; no rest needed).
    #[serde(rename = "continuous-trials")]
    ContinuousTrials,
}

/// Preparation settings.
///
/// | Name | Default | Purpose | Range |
/// |---|---|---|---|
/// | `windowing` | `Auto` | how windows are formed | see [`Windowing`] |
/// | `cutoff_hz` | 30 Hz (capped at 0.4 fs, [`default_cutoff`]) | zero-phase low-pass cut-off | (0, fs/2) |
/// | `filter_order` | 4 | Butterworth order per pass | 1..=20 |
/// | `derivative` | `Central` | derivative scheme | see [`Derivative`] |
/// | `offsets` | `Auto` | per-trial force offsets: rest mean or fitted | see [`Offsets`] |
/// | `negate_force` | false | force columns hold the hand's force on the sensor | |
/// | `transform` | none | frame change applied to `x,y,z`, `fx,fy,fz` | rotation det +1 |
/// | `min_rest_s` | 0.02 s | shortest rest before an onset | > 0 |
/// | `trial_column` | `trial` | column with trial ids | |
/// | `level` | none | keep only windows of this `level` | a value of the `level` column |
#[derive(Debug, Clone)]
pub struct PrepareParams {
    /// How the data are cut into windows.
    pub windowing: Windowing,
    /// Low-pass cut-off (Hz); `None`: 30 Hz, at most 0.4 fs.
    pub cutoff_hz: Option<f64>,
    /// Butterworth order per pass.
    pub filter_order: usize,
    /// How velocity and acceleration are computed.
    pub derivative: Derivative,
    /// How per-trial force offsets are removed.
    pub offsets: Offsets,
    /// The force columns hold the hand's force on the sensor: negate them.
    pub negate_force: bool,
    /// Frame change applied to positions and forces.
    pub transform: Option<FrameTransform>,
    /// Shortest rest before an onset (s).
    pub min_rest_s: f64,
    /// Column with trial ids.
    pub trial_column: String,
    /// Keep only windows whose samples all carry this `level` (condition label).
    pub level: Option<f64>,
    /// Use the measured motion even when commanded reference columns are
    /// recorded (else the motion they predict: [`crate::closed_loop`]).
    pub open_loop: bool,
}

impl Default for PrepareParams {
    fn default() -> Self {
        PrepareParams {
            windowing: Windowing::Auto,
            cutoff_hz: None,
            filter_order: 4,
            derivative: Derivative::Central,
            offsets: Offsets::Auto,
            negate_force: false,
            transform: None,
            min_rest_s: 0.02,
            trial_column: "trial".into(),
            level: None,
            open_loop: false,
        }
    }
}

/// Samples dropped at each window edge, in periods of the cut-off frequency
/// (at least 2 samples, the derivative stencil). Zero: each window end is
/// extended by the reflection that obeys the impedance model there (see
/// [`LowPass::filtfilt_edges`]), so filtered samples up to the edge stay
/// consistent; trimming measured worse (it removes the pre-onset rest that pins
/// the stiffness: ex_config7 level 0.5 with fitted offsets, K error 0.6 % -> 30 %
/// at a 10 Hz cut-off with one period trimmed).
pub const TRIM_PERIODS: f64 = 0.0;

/// Extra samples dropped at the end of every perturbation window, in periods
/// of the cut-off. A window usually ends where the limb is still decelerating
/// (a cubic ends with zero velocity but full deceleration); no reflection
/// keeps the model exact there, and the error spreads over about one period
/// (seed 001 trials cut after the 100 ms motion: K error 14 % -> see README).
/// The start of a window is at rest, where both reflections are exact.
pub const END_TRIM_PERIODS: f64 = 1.0;

/// Default low-pass cut-off (Hz): 30 Hz, but never above 0.4 of the sample rate.
///
/// Chosen on the examples: high enough that 100 ms perturbations (seed 001) and
/// the ankle data keep their inertial content, low enough that position noise
/// does not dominate the acceleration of slow ones (see the README).
pub fn default_cutoff(fs: f64) -> f64 {
    30.0f64.min(0.4 * fs)
}

/// One window after preparation, as a range of the concatenated samples.
#[derive(Debug, Clone, Serialize)]
pub struct PreparedWindow {
    /// Trial id.
    pub id: i64,
    /// Range into the concatenated arrays of [`Prepared`].
    pub samples: Range<usize>,
    /// Rows of the source recording used (absolute sample indices).
    pub rows: Range<usize>,
    /// Pre-onset rest samples (0 for continuous windows).
    pub rest_samples: usize,
    /// Force offset removed (N or N m), one per coordinate.
    pub force_offset: Vec<f64>,
    /// Rest (reference) position, one per coordinate.
    pub reference: Vec<f64>,
}

/// Prepared data: per coordinate, concatenated over windows.
#[derive(Debug, Clone)]
pub struct Prepared {
    /// The recording's path.
    pub path: PathBuf,
    /// Coordinate names (`x`, `y`, `z`, `theta`, `q1`, ...).
    pub coordinates: Vec<String>,
    /// Force column of each coordinate.
    pub force_columns: Vec<String>,
    /// Sample rate (Hz).
    pub fs: f64,
    /// Displacement from the window's reference position.
    pub disp: Vec<Vec<f64>>,
    /// Velocity, per coordinate.
    pub vel: Vec<Vec<f64>>,
    /// Acceleration, per coordinate.
    pub acc: Vec<Vec<f64>>,
    /// Force with the rest offset removed (perturbation windows) or raw (continuous).
    pub force: Vec<Vec<f64>>,
    /// The windows, in the order of the concatenated samples.
    pub windows: Vec<PreparedWindow>,
    /// True when the data is one continuous window (a constant term is needed).
    pub continuous: bool,
    /// True when every window was demeaned (per-trial offsets fitted): no constant term.
    pub demeaned: bool,
    /// Effective settings, for reports.
    pub cutoff_hz: f64,
    /// Butterworth order used.
    pub filter_order: usize,
    /// Derivative method used.
    pub derivative: Derivative,
    /// Samples dropped at each window edge.
    pub trim: usize,
    /// Mean reference position over windows (absolute coordinates).
    pub reference: Vec<f64>,
    /// `(min, max)` of each coordinate's position column over the recording
    /// (its own numbers: a plausibility check of its unit reads them).
    pub position_range: Vec<(f64, f64)>,
    /// Position noise σ per coordinate, estimated from second differences of
    /// the raw data at the rate they were measured (see `resampled`).
    pub position_noise: Vec<f64>,
    /// Per coordinate: the position was logged faster than measured (held
    /// or interpolated samples, issue 56); its velocity and acceleration are
    /// then steps and spikes, so damping and inertia cannot be trusted.
    pub resampled: Vec<Option<limpid_core::trial::Resampled>>,
    /// Every position was logged faster than it was measured, alike: the
    /// recording was cut to the measured samples first (issue 58).
    pub measured_rate: Option<MeasuredRate>,
    /// A closed-loop recording: the positions are the motion the commanded
    /// references predict ([`crate::closed_loop`]).
    pub closed_loop: Option<crate::closed_loop::ClosedLoop>,
    /// Variance that the position noise contributes to the prepared
    /// displacement, velocity and acceleration of each coordinate, and the
    /// displacement-acceleration noise covariance (`[disp, vel, acc, disp_acc]`;
    /// velocity noise is uncorrelated with both, the operators being odd and even).
    pub regressor_noise_var: Vec<[f64; 4]>,
}

impl Prepared {
    /// Number of coordinates.
    pub fn dims(&self) -> usize {
        self.coordinates.len()
    }
    /// Number of samples used.
    pub fn len(&self) -> usize {
        self.disp.first().map_or(0, Vec::len)
    }
    /// True when no sample is used.
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }
    /// Lags over which residuals are correlated by the low-pass (for standard errors).
    pub fn correlation_lags(&self) -> usize {
        ((self.fs / self.cutoff_hz).round() as usize).max(1)
    }
}

/// Pick coordinates and their force columns from what the recording has.
pub fn choose_coordinates(rec: &Recording) -> Result<(Vec<String>, Vec<String>)> {
    let mut coords = Vec::new();
    let mut forces = Vec::new();
    for (c, f) in [("x", "fx"), ("y", "fy"), ("z", "fz"), ("theta", "tauy")] {
        if rec.has(c) {
            rec.require(f, &format!("force paired with position {c}"))?;
            coords.push(c.to_string());
            forces.push(f.to_string());
        }
    }
    if !coords.is_empty() {
        for (c, f) in [("x", "fx"), ("y", "fy"), ("z", "fz"), ("theta", "tauy")] {
            if rec.has(f) && !rec.has(c) {
                return Err(Error::MissingColumn {
                    path: rec.path().to_path_buf(),
                    column: c.into(),
                    why: format!(
                        "the recording has force {f} but no position {c}; estimating without it would ignore that force"
                    ),
                    found: rec.names().join(","),
                });
            }
        }
    }
    if coords.is_empty() {
        let mut k = 1;
        while rec.has(&format!("q{k}")) {
            let f = format!("tau{k}");
            rec.require(&f, &format!("torque paired with joint angle q{k}"))?;
            coords.push(format!("q{k}"));
            forces.push(f);
            k += 1;
        }
    }
    if coords.is_empty() {
        return Err(Error::MissingColumn {
            path: rec.path().to_path_buf(),
            column: "x".into(),
            why:
                "positions x,y[,z] with forces fx,fy[,fz], or joint angles q1.. with torques tau1.."
                    .into(),
            found: rec.names().join(","),
        });
    }
    Ok((coords, forces))
}

/// Prepare a recording for estimation: every window's signals, concatenated.
pub fn prepare(rec: &Recording, params: &PrepareParams) -> Result<Prepared> {
    plan(rec, params)?.materialise()
}

/// A preparation whose windows are found, but whose signals are computed
/// only when asked, one window at a time ([`Plan::fill_window`]). An
/// estimator that reduces each window as it goes (the linear fit's QR,
/// issue 16) never holds the prepared signals of the whole recording.
#[derive(Debug, Clone)]
pub struct Plan<'r> {
    /// Everything of the prepared data but its signals: `disp`, `vel`,
    /// `acc` and `force` are empty, [`Plan::len`] gives the sample count.
    pub meta: Prepared,
    rec: Cow<'r, Recording>,
    /// Source windows, in the order of `meta.windows`.
    windows: Vec<Window>,
    lowpass: LowPass,
    derivative: Derivative,
    sign: f64,
    end_trim: usize,
    sg_window: usize,
    samples: usize,
}

/// Find the windows of a recording and everything about them that needs no
/// filtering (rest offsets, references, lengths); see [`Plan`].
pub fn plan<'r>(rec: &'r Recording, params: &PrepareParams) -> Result<Plan<'r>> {
    if params.min_rest_s.is_nan() || params.min_rest_s <= 0.0 {
        return Err(Error::invalid("minimum rest", "must be positive"));
    }
    let rec: Cow<'r, Recording> = match &params.transform {
        Some(tf) => {
            let mut local = rec.clone();
            tf.apply(&mut local)?;
            Cow::Owned(local)
        }
        None => Cow::Borrowed(rec),
    };
    let (coords, force_cols) = choose_coordinates(&rec)?;
    let (rec, measured_rate) = at_measured_rate(rec, &coords)?;
    let fs = rec.sample_rate();
    let cutoff = params.cutoff_hz.unwrap_or_else(|| default_cutoff(fs));
    let lowpass = LowPass::butterworth(params.filter_order, cutoff, fs)?;
    // a closed-loop rig: the motion the commanded references drive (issue 79)
    let (rec, closed_loop) =
        crate::closed_loop::instrumented(rec, &coords, (params.open_loop, Some(&lowpass)))?;
    let pos = columns(&rec, &coords);
    let frc = columns(&rec, &force_cols);
    // a coordinate that never moves: its filtered copy varies by rounding
    // alone, which once gave K 4.6e22 ± 3.6e22 (issue 56)
    if let Some((c, x)) = coords
        .iter()
        .zip(&pos)
        .find(|(_, x)| x.iter().all(|v| *v == x[0]))
    {
        return Err(Error::Format {
            path: rec.path().to_path_buf(),
            message: format!(
                "column {c} holds {} in every sample: that coordinate never moves, so its impedance cannot be estimated; leave the column out (1-, 2- and 3-D recordings are read)",
                limpid_core::error::Num(x[0])
            ),
        });
    }
    let sign = if params.negate_force { -1.0 } else { 1.0 };
    let min_rest = ((params.min_rest_s * fs).round() as usize).max(3);

    let mode = resolved_windowing(&rec, params);
    // the noise of every signal onset detection needs, signals in parallel;
    // positions at their measured rate: a held or interpolated stream has
    // zero second differences, which would read as no noise at all (issue 56)
    let trials = matches!(mode, Windowing::Trials);
    // (one join: six signals on the cores at once, not three then three)
    let forces_for_onsets: Vec<&[f64]> = frc.iter().filter(|_| trials).copied().collect();
    let ((position_noise, resampled), force_noise): ((Vec<f64>, Vec<_>), Vec<f64>) = rayon::join(
        || pos.par_iter().map(|c| native_noise_sigma(c)).unzip(),
        || {
            forces_for_onsets
                .par_iter()
                .map(|c| noise_sigma(c))
                .collect()
        },
    );
    let mut windows = make_windows(
        &rec,
        mode,
        &params.trial_column,
        (&pos, &frc),
        (&position_noise, &force_noise),
        min_rest,
    )?;
    if let Some(level) = params.level {
        keep_level(&rec, &mut windows, level)?;
    }
    let continuous = windows.iter().all(|w| w.onset.is_none());

    let Trims {
        trim,
        end_trim,
        sg_window,
    } = trims(params.derivative, fs, cutoff, continuous);
    let dt = 1.0 / fs;
    let n = coords.len();
    let need = (trim + end_trim + 1)
        .max(lowpass.padlen() + 1)
        .max(sg_window);
    refuse_short_windows(&rec, &windows, need)?;
    let gains = noise_gains(params.derivative, &lowpass, sg_window, dt)?;
    let regressor_noise_var = position_noise
        .iter()
        .map(|s| std::array::from_fn(|i| s * s * gains[i]))
        .collect();
    let (prepared_windows, samples) =
        prepared_windows(&windows, (&pos, &frc), sign, (trim, end_trim));
    let reference = (0..n)
        .map(|k| {
            prepared_windows.iter().map(|w| w.reference[k]).sum::<f64>()
                / prepared_windows.len() as f64
        })
        .collect();
    let position_range = pos.iter().map(|c| crate::units::range(c)).collect();
    let meta = Prepared {
        path: rec.path().to_path_buf(),
        coordinates: coords,
        force_columns: force_cols,
        fs,
        disp: vec![Vec::new(); n],
        vel: vec![Vec::new(); n],
        acc: vec![Vec::new(); n],
        force: vec![Vec::new(); n],
        // several continuous windows (the holds of a continuous perturbation) each get their own offset
        demeaned: if continuous {
            windows.len() > 1
        } else {
            fits_offsets(params.offsets, &windows, fs)
        },
        windows: prepared_windows,
        continuous,
        cutoff_hz: cutoff,
        filter_order: params.filter_order,
        derivative: params.derivative,
        trim,
        reference,
        position_range,
        position_noise,
        resampled,
        measured_rate,
        closed_loop,
        regressor_noise_var,
    };
    Ok(Plan {
        meta,
        rec,
        windows,
        lowpass,
        derivative: params.derivative,
        sign,
        end_trim,
        sg_window,
        samples,
    })
}

/// Samples cut from each window's ends: the filter's and differences' edge
/// effects (`trim`), one cut-off period more at a perturbation window's end
/// (see END_TRIM_PERIODS), and the Savitzky-Golay window (0 for central differences).
struct Trims {
    trim: usize,
    end_trim: usize,
    sg_window: usize,
}

fn trims(derivative: Derivative, fs: f64, cutoff: f64, continuous: bool) -> Trims {
    let (trim, sg_window) = match derivative {
        Derivative::Central => (((TRIM_PERIODS * fs / cutoff).ceil() as usize).max(2), 0),
        Derivative::Savgol => {
            let w = savgol_window(fs, cutoff);
            (w / 2, w)
        }
    };
    let end_trim_extra = if continuous || derivative == Derivative::Savgol {
        0
    } else {
        ((END_TRIM_PERIODS * fs / cutoff).round() as usize).max(1)
    };
    Trims {
        trim,
        end_trim: trim + end_trim_extra,
        sg_window,
    }
}

/// Refuse a window shorter than filtering and differences need, naming its rows.
fn refuse_short_windows(rec: &Recording, windows: &[Window], need: usize) -> Result<()> {
    match windows.iter().find(|w| w.range.len() < need) {
        Some(w) => Err(Error::TooFewSamples {
            path: rec.path().to_path_buf(),
            what: format!(
                "trial {} (rows {}-{}) with zero-phase filtering and differences",
                w.id,
                rec.row_of(w.range.start),
                rec.row_of(w.range.end - 1)
            ),
            needed: need,
            found: w.range.len(),
        }),
        None => Ok(()),
    }
}

/// Each window's place in the concatenated samples, its rows after trimming,
/// and its rest offsets (force, sign applied) and reference position; with
/// the total number of samples.
fn prepared_windows(
    windows: &[Window],
    (pos, frc): (&[&[f64]], &[&[f64]]),
    sign: f64,
    (trim, end_trim): (usize, usize),
) -> (Vec<PreparedWindow>, usize) {
    let mut start = 0;
    let prepared = windows
        .iter()
        .map(|w| {
            let r = &w.range;
            let rest = match w.onset {
                Some(onset) => r.start..onset,
                None => r.clone(),
            };
            let len = r.len() - trim - end_trim;
            let out = PreparedWindow {
                id: w.id,
                samples: start..start + len,
                rows: r.start + trim..r.end - end_trim,
                rest_samples: w.rest_len(),
                force_offset: frc
                    .iter()
                    .map(|f| match w.onset {
                        Some(_) => sign * mean(&f[rest.clone()]),
                        None => 0.0,
                    })
                    .collect(),
                reference: pos.iter().map(|p| mean(&p[rest.clone()])).collect(),
            };
            start += len;
            out
        })
        .collect();
    (prepared, start)
}

/// The named columns of `rec` (chosen before: an absent one reads as empty).
/// Positions logged faster than they were measured and cut back to the
/// samples the sensor gave.
#[derive(Debug, Clone, PartialEq)]
pub struct MeasuredRate {
    /// How they were logged (held or interpolated, the factor, the phase).
    pub resampled: Resampled,
    /// The logging's rate (Hz); the recording now runs at this / factor.
    pub logged_hz: f64,
    /// The position columns.
    pub columns: Vec<String>,
}

impl MeasuredRate {
    /// The warning that says what was done.
    pub fn warning(&self) -> Warning {
        let r = &self.resampled;
        let kept = if r.irregular {
            "estimated from one sample in every second measured interval, at about"
        } else {
            "estimated from the measured samples only, at"
        };
        Warning::new(
            WarningCode::ResampledSignal,
            format!(
                "positions logged faster than they were measured: {} ({}); {kept} {} Hz (one sample in {} of the {} Hz log, from its sample {}), since holding delays a signal and interpolation puts noise measured at the slower rate on a faster clock; record at the sensor's own rate",
                self.columns.join(", "),
                r.describe(),
                limpid_core::short_number(self.logged_hz / r.stride() as f64),
                r.stride(),
                limpid_core::short_number(self.logged_hz),
                r.phase
            ),
        )
    }
}

/// The recording at the rate its positions were measured (issue 58): when
/// every position column was held or interpolated alike (the same factor
/// and phase, [`resampling`]), only the samples the sensor gave are kept
/// (all columns, at those rows). A held stream is late by half a
/// measurement interval and its velocity steps; an interpolated one carries
/// noise measured at the slower rate, whose density below that rate's
/// Nyquist the preparation for the logging rate misreads (held 4x on a
/// 500 Hz centre-out recording: B 11 % low at 3 SE; interpolated 4x, or
/// held and put back on the full clock by straight lines, and estimated at
/// the logging rate: about half the truth). Positions resampled unlike each
/// other are left as they are (the linear method then calls damping and
/// inertia not identifiable).
pub fn at_measured_rate<'r>(
    rec: Cow<'r, Recording>,
    positions: &[String],
) -> Result<(Cow<'r, Recording>, Option<MeasuredRate>)> {
    let found: Vec<Option<Resampled>> = positions
        .par_iter()
        .map(|c| rec.column(c).and_then(resampling))
        .collect();
    let Some(Some(first)) = found.first().copied() else {
        return Ok((rec, None));
    };
    let alike = |r: &Option<Resampled>| {
        r.is_some_and(|r| (r.factor, r.phase) == (first.factor, first.phase))
    };
    if !found.iter().all(alike) {
        return Ok((rec, None));
    }
    let kept = rec.every(first.phase, first.stride())?;
    let measured = MeasuredRate {
        resampled: first,
        logged_hz: rec.sample_rate(),
        columns: positions.to_vec(),
    };
    Ok((Cow::Owned(kept), Some(measured)))
}

pub(crate) fn columns<'a>(rec: &'a Recording, names: &[String]) -> Vec<&'a [f64]> {
    names.iter().map(|c| rec.column(c).unwrap_or(&[])).collect()
}

impl Plan<'_> {
    /// Samples the prepared signals will have (all windows).
    pub fn len(&self) -> usize {
        self.samples
    }

    /// True when no sample is used.
    pub fn is_empty(&self) -> bool {
        self.samples == 0
    }

    /// Window `i`'s trimmed signals into `dest`, kind-major: the n
    /// displacements, then velocities, accelerations and forces, each as
    /// long as the window's `samples` range.
    pub fn fill_window(&self, i: usize, dest: &mut [&mut [f64]]) -> Result<()> {
        let w = &self.windows[i];
        let prepared = &self.meta.windows[i];
        let pos = columns(&self.rec, &self.meta.coordinates);
        let frc = columns(&self.rec, &self.meta.force_columns);
        let (fs, dt) = (self.meta.fs, 1.0 / self.meta.fs);
        let cutoff = self.lowpass.cutoff_hz();
        let r = w.range.clone();
        // one extension per window end, shared by every signal so that the model holds across coordinates
        let edge_samples = ((fs / cutoff).round() as usize).max(3);
        let (left, right) = edge_kinds(&pos, r.clone(), edge_samples, dt);
        let extra = ((3.0 * fs / cutoff).round() as usize).min(r.len() - 1);
        let n = pos.len();
        let mut shifted: Vec<Vec<f64>> = Vec::with_capacity(2 * n);
        for (p, reference) in pos.iter().zip(&prepared.reference) {
            shifted.push(p[r.clone()].iter().map(|v| v - reference).collect());
        }
        for (f, offset) in frc.iter().zip(&prepared.force_offset) {
            let sign = self.sign;
            shifted.push(f[r.clone()].iter().map(|v| sign * v - offset).collect());
        }
        let keep = self.meta.trim..r.len() - self.end_trim;
        if self.derivative == Derivative::Central && keep.start >= 1 && keep.end < r.len() {
            return self.fill_central(&shifted, (left, right, extra), keep, dest);
        }
        let signals = filter_and_differentiate(
            &shifted,
            self.derivative,
            &self.lowpass,
            (left, right, extra),
            self.sg_window,
            dt,
        )?;
        for (k, per_coordinate) in signals.iter().enumerate() {
            for (kind, src) in per_coordinate.iter().enumerate() {
                let part = &src[keep.clone()];
                let m = if self.meta.demeaned { mean(part) } else { 0.0 };
                for (o, v) in dest[kind * n + k].iter_mut().zip(part) {
                    *o = v - m;
                }
            }
        }
        Ok(())
    }

    /// [`Plan::fill_window`] with central differences, when the kept samples
    /// have a neighbour on each side: the filtered signals go straight into
    /// `dest` and the derivatives are taken over the kept samples only (the
    /// same arithmetic as `central_first` and `central_second` there, without
    /// four window-long vectors per coordinate, issue 82).
    fn fill_central(
        &self,
        shifted: &[Vec<f64>],
        (left, right, extra): (limpid_dsp::Edge, limpid_dsp::Edge, usize),
        keep: Range<usize>,
        dest: &mut [&mut [f64]],
    ) -> Result<()> {
        let n = shifted.len() / 2;
        let dt = 1.0 / self.meta.fs;
        let (two_dt, h2) = (2.0 * dt, dt * dt);
        let refs: Vec<&[f64]> = shifted.iter().map(Vec::as_slice).collect();
        let filtered = self
            .lowpass
            .filtfilt_edges_many(&refs, left, right, extra)?;
        for k in 0..n {
            let x = &filtered[k];
            let out = |kind: usize| kind * n + k;
            for (o, i) in dest[out(0)].iter_mut().zip(keep.clone()) {
                *o = x[i];
            }
            for (o, i) in dest[out(1)].iter_mut().zip(keep.clone()) {
                *o = (x[i + 1] - x[i - 1]) / two_dt;
            }
            for (o, i) in dest[out(2)].iter_mut().zip(keep.clone()) {
                *o = (x[i + 1] - 2.0 * x[i] + x[i - 1]) / h2;
            }
            dest[out(3)].copy_from_slice(&filtered[n + k][keep.clone()]);
        }
        if self.meta.demeaned {
            for column in dest.iter_mut().take(4 * n) {
                let m = mean(column);
                column.iter_mut().for_each(|v| *v -= m);
            }
        }
        Ok(())
    }

    /// Every window's signals, concatenated: the [`Prepared`] data.
    pub fn materialise(&self) -> Result<Prepared> {
        let n = self.meta.dims();
        let total = self.samples;
        // every window writes its signals straight into its own part of the
        // output columns, windows in parallel (no per-window copies, and the
        // fresh pages are first touched by the threads that fill them)
        let mut columns: Vec<Vec<f64>> = (0..4 * n).map(|_| vec![0.0; total]).collect();
        let mut destinations: Vec<Vec<&mut [f64]>> = (0..self.windows.len())
            .map(|_| Vec::with_capacity(4 * n))
            .collect();
        for column in columns.iter_mut() {
            let mut rest: &mut [f64] = column;
            for (dest, w) in destinations.iter_mut().zip(&self.meta.windows) {
                let (head, tail) = std::mem::take(&mut rest).split_at_mut(w.samples.len());
                dest.push(head);
                rest = tail;
            }
        }
        destinations
            .into_par_iter()
            .enumerate()
            .try_for_each(|(i, mut dest)| self.fill_window(i, &mut dest))?;
        let mut out = self.meta.clone();
        let mut columns = columns.into_iter();
        for kind in [&mut out.disp, &mut out.vel, &mut out.acc, &mut out.force] {
            *kind = columns.by_ref().take(n).collect();
        }
        Ok(out)
    }
}

fn mean(x: &[f64]) -> f64 {
    x.iter().sum::<f64>() / x.len().max(1) as f64
}
