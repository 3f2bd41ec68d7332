//! Stochastic MIMO impedance in the frequency domain (seed 004 §II-A, §III-E).
//!
//! Random commanded perturbations `u` (columns `ux`, `uz`, `utheta`, ... one
//! per coordinate) drive the limb or rig. From Welch spectra of inputs,
//! displacements and forces, the H1 transfer-function matrices R (u -> x) and
//! T (u -> f) are estimated, and the impedance follows by analytical
//! compensation, eq. (1)-(2): `C = R T^-1`, `Z = T R^-1`. Multiple and
//! partial coherences of every output say where the linear model holds.
//!
//! The parametric fit of `Z(f) = K - w^2 M + j w B` over a band is linear
//! least squares per element, weighted by the smallest multiple coherence of
//! the outputs at each frequency: real parts give K and M, imaginary parts B.
//! Standard errors come from the weighted residuals, with the variance
//! multiplied by the window's equivalent noise bandwidth in bins (1.5 for
//! Hann), because neighbouring Welch bins are correlated.
//!
//! Accuracy against an expected model (eq. (15)-(16)): `phi_T` is the mean over
//! the band of the largest singular value of `Z - Z_model`, `phi_ij` the mean of
//! `|Z_ij - Z_model,ij|`.

use limpid_core::criteria::{judge_matrix, MatrixKind, Verdicts, VAF_FLOOR_PERCENT};
use limpid_core::{Matrix, Warning, WarningCode};
use nalgebra::{DMatrix, DVector};
use num_complex::Complex64;
use schemars::JsonSchema;
use serde::{Deserialize, Serialize};

use crate::prepare::choose_coordinates;
use limpid_core::{Error, Recording, Result};
use limpid_dsp::spectral::{mimo_point, SegmentSpectra, Welch};
use rayon::prelude::*;

/// Groups of consecutive Welch segments for the jackknife standard errors.
pub const JACKKNIFE_GROUPS: usize = 10;
/// Fewest segments (one per group) for a jackknife; below, least-squares SEs.
pub const MIN_JACKKNIFE_GROUPS: usize = 8;

/// Settings of the stochastic estimator.
///
/// | Name | Default | Purpose | Range |
/// |---|---|---|---|
/// | `welch` | Hann, `nperseg` ≈ 4 s (power of 2, at most a quarter of the data), 50 % overlap | spectral estimation | |
/// | `band_hz` | 0.5-10 Hz | band of the parametric fit and of the accuracy measures (seed 004: 10 Hz) | 0 < lo < hi < fs/2 |
#[derive(Debug, Clone)]
pub struct StochasticParams {
    /// Welch settings; `None`: [`default_welch`].
    pub welch: Option<Welch>,
    /// Band of the parametric fit and the accuracy measures (Hz).
    pub band_hz: (f64, f64),
    /// The period of a periodic command (s): whole periods are averaged
    /// instead of Welch segments ([`crate::periodic_stochastic`]).
    pub period_s: Option<f64>,
}

impl Default for StochasticParams {
    fn default() -> Self {
        StochasticParams {
            welch: None,
            band_hz: (
                crate::request::DEFAULT_BAND_HZ[0],
                crate::request::DEFAULT_BAND_HZ[1],
            ),
            period_s: None,
        }
    }
}

/// Default Welch settings for `n` samples at `fs`.
pub fn default_welch(n: usize, fs: f64) -> Welch {
    let target = (4.0 * fs).max(16.0);
    let mut nperseg = 2usize.pow(target.log2().round() as u32);
    while nperseg > n / 4 && nperseg > 16 {
        nperseg /= 2;
    }
    Welch {
        nperseg,
        ..Welch::new(fs)
    }
}

/// Coherences per frequency.
#[derive(Debug, Clone, Serialize, Deserialize, JsonSchema)]
pub struct Coherences {
    /// Output names (positions, then forces).
    pub outputs: Vec<String>,
    /// `multiple[output][frequency]`.
    pub multiple: Vec<Vec<f64>>,
    /// `partial[output][input][frequency]`.
    pub partial: Vec<Vec<Vec<f64>>>,
}

/// Non-parametric and parametric impedance with its quality.
#[derive(Debug, Clone, Serialize, Deserialize, JsonSchema)]
pub struct StochasticEstimate {
    /// Coordinates (displacement columns).
    pub coordinates: Vec<String>,
    /// Input columns (`u*`), one per coordinate.
    pub inputs: Vec<String>,
    /// Frequencies (Hz) up to the band's upper edge.
    pub frequencies: Vec<f64>,
    /// `impedance[f][i][j] = [re, im]` of Z (force per displacement).
    pub impedance: Vec<Vec<Vec<[f64; 2]>>>,
    /// Multiple and partial coherences.
    pub coherence: Coherences,
    /// Parametric fit over the band (SI).
    pub inertia: Matrix,
    /// B (SI), parametric fit over the band.
    pub damping: Matrix,
    /// K (SI), parametric fit over the band.
    pub stiffness: Matrix,
    /// Standard errors of the parametric fit.
    pub standard_errors: ParametricErrors,
    /// Quality of the spectra and of the fit.
    pub criteria: StochasticCriteria,
    /// Accuracy against an expected model (seed 004 eq. (15)-(16)), when one is given.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub accuracy: Option<Accuracy>,
    /// What the reader should know about this estimate.
    pub warnings: Vec<Warning>,
    /// With a period (`--period`): the periodic analysis (lines classified
    /// by the commands, distortion, the FRF force per command, and the fit
    /// the parametric M, B, K above come from).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub periodic: Option<crate::spectra::PeriodicResult>,
}

/// Largest magnitude of an expected-model entry (kg, N s/m, N/m or their
/// rotational forms).
pub const EXPECTED_MODEL_LIMIT: f64 = 1e9;

/// The expected model of [`Accuracy`] (e.g. the spring array's M, B, K).
#[derive(Debug, Clone, Serialize, Deserialize, JsonSchema)]
pub struct ExpectedModel {
    /// M (SI).
    pub inertia: Matrix,
    /// B (SI).
    pub damping: Matrix,
    /// K (SI).
    pub stiffness: Matrix,
}

impl ExpectedModel {
    /// `inertia`, `damping`, `stiffness` from the JSON text of a file such as
    /// a recording's `*.truth.json` (other keys are ignored); `path` names the
    /// file in errors (`limpid-app` reads it).
    pub fn from_json(path: &std::path::Path, text: &str) -> Result<Self> {
        let model: ExpectedModel = serde_json::from_str(text).map_err(|e| Error::Format {
            path: path.to_path_buf(),
            message: format!(
                "line {}, column {}: expected square matrices of numbers under inertia, damping and stiffness ({e})",
                e.line(),
                e.column()
            ),
        })?;
        for (key, m) in [
            ("inertia", &model.inertia),
            ("damping", &model.damping),
            ("stiffness", &model.stiffness),
        ] {
            if m.nrows() != m.ncols() || m.iter().any(|v| !v.is_finite()) {
                return Err(Error::Format {
                    path: path.to_path_buf(),
                    message: format!("key {key}: expected a square matrix of finite numbers"),
                });
            }
            // Far beyond any limb or spring array, and far from overflow when
            // squared by the frequency (a 1e308 entry made phi_T infinite).
            if let Some(v) = m.iter().find(|v| v.abs() > EXPECTED_MODEL_LIMIT) {
                return Err(Error::Format {
                    path: path.to_path_buf(),
                    message: format!(
                        "key {key}: implausible entry {v:e}; expected-model entries are at most {EXPECTED_MODEL_LIMIT:e} in magnitude (SI units)"
                    ),
                });
            }
        }
        Ok(model)
    }
}

/// Seed 004 eq. (15)-(16): how far the non-parametric Z is from an expected model.
#[derive(Debug, Clone, Serialize, Deserialize, JsonSchema)]
pub struct Accuracy {
    /// phi_T: mean over the band of the largest singular value of Z - Z_expected.
    pub phi_t: f64,
    /// phi_ij: mean over the band of |Z_ij - Z_expected,ij|.
    pub phi_ij: Matrix,
    /// Mean over the band of phi_T(f) / ||Z_expected(f)||_2.
    pub mean_relative_error: f64,
    /// The model compared with.
    pub expected: ExpectedModel,
}

/// Standard errors of the parametric fit: delete-a-group jackknife over the
/// Welch segments ([`JACKKNIFE_GROUPS`] groups of consecutive segments, each
/// replicate refitting Z and its parametric model without one group); with
/// fewer than [`MIN_JACKKNIFE_GROUPS`] segments, least squares over the band
/// inflated by the window's equivalent noise bandwidth.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, JsonSchema)]
pub struct ParametricErrors {
    /// How they were obtained.
    #[serde(default)]
    pub method: String,
    /// Of M.
    pub inertia: Matrix,
    /// Of B.
    pub damping: Matrix,
    /// Of K.
    pub stiffness: Matrix,
}

/// Quality of a stochastic estimate.
#[derive(Debug, Clone, Serialize, Deserialize, JsonSchema)]
pub struct StochasticCriteria {
    /// Band of the parametric fit (Hz).
    pub band_hz: [f64; 2],
    /// Welch frequency resolution (Hz).
    pub frequency_resolution_hz: f64,
    /// Welch segments averaged.
    pub segments: usize,
    /// Samples per segment.
    pub nperseg: usize,
    /// Mean over the band of the smallest multiple coherence of the outputs.
    pub mean_multiple_coherence: f64,
    /// Smallest multiple coherence in the band.
    pub min_multiple_coherence: f64,
    /// Largest ordinary coherence between two inputs in the band (seed 004
    /// asks < 0.6); periodic: the largest power of another command at a
    /// command's excited line relative to that command's (0 for zippered lines).
    pub max_input_coherence: f64,
    /// phi_T of the non-parametric Z against the parametric fit (eq. (15)).
    pub phi_t_vs_fit: f64,
    /// Weighted VAF (%) of the parametric fit of Z over the band.
    pub fit_vaf: f64,
    /// The verdict on K, B and M: the fit explains Z ([`VAF_FLOOR_PERCENT`]
    /// of it, with a mean multiple coherence of at least
    /// [`MIN_MEAN_COHERENCE`]), then the rules of [`judge_matrix`].
    pub verdicts: Verdicts,
}

/// Smallest mean multiple coherence over the band for any matrix to be trusted.
pub const MIN_MEAN_COHERENCE: f64 = 0.5;

pub(crate) fn input_name(coord: &str) -> String {
    match coord {
        "x" | "y" | "z" | "theta" => format!("u{coord}"),
        q => format!("u{}", q.trim_start_matches('q')),
    }
}

/// Estimate Z(f) and its parametric fit from a recording with `u*` columns.
pub fn estimate_stochastic(
    rec: &Recording,
    params: &StochasticParams,
) -> Result<StochasticEstimate> {
    estimate_stochastic_pooled(std::slice::from_ref(rec), params)
}

/// Estimate Z(f) from repeated trials (seed 004 §III-F: six trials per
/// configuration): the Welch segments of every recording are averaged
/// together, so the spectral densities — not the ratios Z — are averaged,
/// which keeps Z = T R^-1 unbiased where averaging the trials' Z would
/// average ratios of noisy spectra. The recordings must share coordinates,
/// sample rate and Welch settings (default settings from the first).
///
/// # Example
///
/// Park & Chang (2011)'s spring array held by an ideal impedance-controlled
/// rig in the virtual lab (its sensors' noise included):
///
/// ```
/// use limpid_core::truth::Truth;
/// use limpid_ident::stochastic::{estimate_stochastic_pooled, StochasticParams};
/// use limpid_lab::design::Design;
/// use limpid_lab::session::{simulate_design, RigController};
///
/// let design = Design::preset("park-stochastic")?;
/// let run = simulate_design(&design, None, RigController::Ideal, 1)?.remove(0);
/// let Truth::Stochastic(truth) = &run.truth else { unreachable!() };
/// let est = estimate_stochastic_pooled(&[run.recording], &StochasticParams::default())?;
/// let (k, k_true) = (est.stiffness[(0, 0)], truth.stiffness[(0, 0)]);
/// assert!((k - k_true).abs() < 0.02 * k_true, "{k} vs {k_true}");
/// # Ok::<(), limpid_core::Error>(())
/// ```
pub fn estimate_stochastic_pooled(
    recs: &[Recording],
    params: &StochasticParams,
) -> Result<StochasticEstimate> {
    let Some(rec) = recs.first() else {
        return Err(Error::invalid("recordings", "no recording given"));
    };
    if let Some(period_s) = params.period_s {
        if recs.len() > 1 {
            return Err(Error::invalid(
                "period_s",
                "a periodic analysis averages the periods of one recording: join the trials' periods into one recording",
            ));
        }
        return crate::periodic_stochastic::estimate_stochastic_periodic(
            rec,
            period_s,
            params.band_hz,
        );
    }
    let (coords, force_cols) = choose_coordinates(rec)?;
    let n = coords.len();
    let inputs: Vec<String> = coords.iter().map(|c| input_name(c)).collect();
    let fs = rec.sample_rate();
    let welch = params
        .welch
        .clone()
        .unwrap_or_else(|| default_welch(rec.len(), fs));
    let spectra = pool_spectra(recs, &inputs, &coords, &force_cols, &welch)?;
    let (lo, hi) = band_below_nyquist(params.band_hz, fs)?;
    // nonparametric reads the bins up to the first above the band
    let bins = spectra
        .frequencies
        .iter()
        .position(|f| *f > hi)
        .map_or(spectra.frequencies.len(), |k| k + 1);
    let NonParametric {
        frequencies,
        impedance,
        multiple,
        partial,
        max_input_coherence,
        singular_in_band,
    } = nonparametric(
        spectra.matrix_below(bins, 0..0),
        &spectra.frequencies,
        n,
        (lo, hi),
    );
    let in_band = bins_in_band(&frequencies, (lo, hi));
    if in_band.len() < 4 {
        return Err(Error::TooFewSamples {
            path: rec.path().to_path_buf(),
            what: format!(
                "frequencies in the {lo}-{hi} Hz band (resolution {:.3} Hz)",
                fs / welch.nperseg as f64
            ),
            needed: 4,
            found: in_band.len(),
        });
    }
    let weight = lowest_multiple_coherence(&multiple, frequencies.len());
    let enbw_bins = match welch.window {
        limpid_dsp::spectral::Window::Hann => 1.5,
        limpid_dsp::spectral::Window::Hamming => 1.36,
        limpid_dsp::spectral::Window::Boxcar => 1.0,
    };
    let Parametric {
        inertia: m,
        damping: b,
        stiffness: kk,
        standard_errors: se,
        fit_vaf,
    } = parametric_fit(&impedance, &frequencies, &in_band, &weight, enbw_bins);
    // the least-squares SE only where the jackknife cannot be formed
    let se = jackknife_errors(&spectra, bins, n, (lo, hi)).unwrap_or(se);
    let phi_t_vs_fit = distance_to_fit(&impedance, &frequencies, &in_band, [&m, &b, &kk]);
    let mean_coh = in_band.iter().map(|&k| weight[k]).sum::<f64>() / in_band.len() as f64;
    let min_coh = in_band.iter().map(|&k| weight[k]).fold(1.0, f64::min);
    let mut warnings = quality_warnings(min_coh, singular_in_band, max_input_coherence);
    for c in &coords {
        let kind = crate::units::Coordinate::of_name(c);
        if let (Some(kind), Some(values)) = (kind, rec.column(c)) {
            warnings.extend(crate::units::implausible_motion(
                c,
                kind,
                crate::units::range(values),
            ));
        }
    }
    let fit_ok = fit_vaf >= VAF_FLOOR_PERCENT && mean_coh >= MIN_MEAN_COHERENCE;
    let verdicts = Verdicts {
        stiffness: judge_matrix(MatrixKind::Stiffness, &kk, &se.stiffness, fit_ok),
        damping: judge_matrix(MatrixKind::Damping, &b, &se.damping, fit_ok),
        inertia: Some(judge_matrix(MatrixKind::Inertia, &m, &se.inertia, fit_ok)),
    };
    let outputs: Vec<String> = coords.iter().chain(&force_cols).cloned().collect();
    Ok(StochasticEstimate {
        coordinates: coords,
        inputs,
        impedance: impedance.iter().map(re_im).collect(),
        frequencies,
        coherence: Coherences {
            outputs,
            multiple,
            partial,
        },
        inertia: m,
        damping: b,
        stiffness: kk,
        standard_errors: se,
        criteria: StochasticCriteria {
            band_hz: [lo, hi],
            frequency_resolution_hz: fs / welch.nperseg as f64,
            segments: spectra.segments(),
            nperseg: welch.nperseg,
            mean_multiple_coherence: mean_coh,
            min_multiple_coherence: min_coh,
            max_input_coherence,
            phi_t_vs_fit,
            fit_vaf,
            verdicts,
        },
        accuracy: None,
        warnings,
        periodic: None,
    })
}

/// The band of the fit, refused unless 0 < low < high < Nyquist.
pub(crate) fn band_below_nyquist((lo, hi): (f64, f64), fs: f64) -> Result<(f64, f64)> {
    if !(lo > 0.0 && hi > lo && hi < fs / 2.0) {
        let nyquist = limpid_core::display_round(fs / 2.0);
        return Err(Error::invalid(
            "band_hz",
            format!("expected 0 < low < high < {nyquist} Hz, found {lo}-{hi} Hz"),
        ));
    }
    Ok((lo, hi))
}

/// phi_T of the non-parametric Z against the parametric fit `[M, B, K]`:
/// the mean over the band of the largest singular value of their difference.
pub(crate) fn distance_to_fit(
    impedance: &[DMatrix<Complex64>],
    frequencies: &[f64],
    in_band: &[usize],
    [m, b, kk]: [&Matrix; 3],
) -> f64 {
    let n = m.nrows();
    let model = |f: f64| {
        let om = 2.0 * std::f64::consts::PI * f;
        DMatrix::from_fn(n, n, |i, j| {
            Complex64::new(kk[(i, j)] - om * om * m[(i, j)], om * b[(i, j)])
        })
    };
    in_band
        .iter()
        .map(|&k| max_singular(&(&impedance[k] - model(frequencies[k]))))
        .sum::<f64>()
        / in_band.len() as f64
}

/// A complex matrix as rows of `[re, im]` (the result's JSON form).
pub(crate) fn re_im(z: &DMatrix<Complex64>) -> Vec<Vec<[f64; 2]>> {
    (0..z.nrows())
        .map(|i| {
            (0..z.ncols())
                .map(|j| [z[(i, j)].re, z[(i, j)].im])
                .collect()
        })
        .collect()
}

/// The Welch segment spectra of every recording, pooled: inputs `u*`, then
/// positions, then forces. The recordings must share the sample rate.
fn pool_spectra(
    recs: &[Recording],
    inputs: &[String],
    coords: &[String],
    force_cols: &[String],
    welch: &Welch,
) -> Result<SegmentSpectra> {
    let fs = recs[0].sample_rate();
    let n = coords.len();
    let mut pooled: Option<SegmentSpectra> = None;
    for r in recs {
        if r.sample_rate() != fs {
            return Err(Error::invalid(
                "recordings",
                format!(
                    "{}: sample rate {} Hz, the first recording's is {fs} Hz",
                    r.path().display(),
                    r.sample_rate()
                ),
            ));
        }
        let mut signals: Vec<&[f64]> = Vec::with_capacity(3 * n);
        for u in inputs {
            signals.push(r.require(
                u,
                "commanded perturbation (stochastic input) of each coordinate",
            )?);
        }
        for c in coords.iter().chain(force_cols) {
            signals.push(r.require(c, "output")?);
        }
        let spectra = SegmentSpectra::new(&signals, welch)?;
        match pooled.as_mut() {
            None => pooled = Some(spectra),
            Some(p) => p.append(spectra)?,
        }
    }
    Ok(pooled.expect("at least one recording"))
}

/// The bins whose frequency lies in the band `[lo, hi]`.
fn bins_in_band(freqs: &[f64], (lo, hi): (f64, f64)) -> Vec<usize> {
    (0..freqs.len())
        .filter(|&k| freqs[k] >= lo && freqs[k] <= hi)
        .collect()
}

/// At each bin, the lowest multiple coherence over all outputs (the fit's weight).
fn lowest_multiple_coherence(multiple: &[Vec<f64>], len: usize) -> Vec<f64> {
    (0..len)
        .map(|k| multiple.iter().map(|m| m[k]).fold(1.0, f64::min))
        .collect()
}

/// Standard errors by a delete-a-group jackknife over the Welch segments: the
/// least-squares SE over frequencies treats neighbouring bins as independent
/// and the residual as noise, which `limpid calibrate` found about twice too
/// large. `None` with too few segments or a replicate without enough band.
fn jackknife_errors(
    spectra: &SegmentSpectra,
    bins: usize,
    n: usize,
    (lo, hi): (f64, f64),
) -> Option<ParametricErrors> {
    let segments = spectra.segments();
    let groups = JACKKNIFE_GROUPS.min(segments);
    if groups < MIN_JACKKNIFE_GROUPS {
        return None;
    }
    let ranges: Vec<std::ops::Range<usize>> = (0..groups)
        .map(|g| g * segments / groups..(g + 1) * segments / groups)
        .collect();
    let replicates: Vec<[Matrix; 3]> = spectra
        .matrices_deleting(bins, &ranges)
        .into_par_iter()
        .filter_map(|matrix| {
            let np = nonparametric(matrix, &spectra.frequencies, n, (lo, hi));
            let band = bins_in_band(&np.frequencies, (lo, hi));
            (band.len() >= 4).then(|| {
                let w = lowest_multiple_coherence(&np.multiple, np.frequencies.len());
                let f = parametric_fit(&np.impedance, &np.frequencies, &band, &w, 1.0);
                [f.stiffness, f.damping, f.inertia]
            })
        })
        .collect();
    if replicates.len() == groups {
        let spread = |which: usize| {
            let g = groups as f64;
            Matrix(nalgebra::DMatrix::from_fn(n, n, |i, j| {
                let mean = replicates.iter().map(|r| r[which][(i, j)]).sum::<f64>() / g;
                let ss = replicates
                    .iter()
                    .map(|r| (r[which][(i, j)] - mean).powi(2))
                    .sum::<f64>();
                ((g - 1.0) / g * ss).sqrt()
            }))
        };
        Some(ParametricErrors {
            stiffness: spread(0),
            damping: spread(1),
            inertia: spread(2),
            method: format!("jackknife over {groups} groups of Welch segments"),
        })
    } else {
        None
    }
}

/// Warnings on the spectra's quality: low coherence, singular frequencies, correlated inputs.
pub(crate) fn quality_warnings(
    min_coh: f64,
    singular_in_band: usize,
    max_input_coherence: f64,
) -> Vec<Warning> {
    let mut warnings = Vec::new();
    if min_coh < 0.8 {
        warnings.push(Warning::new(WarningCode::LowCoherence, format!("multiple coherence falls to {min_coh:.2} in the band: the linear model does not hold everywhere there (noise, nonlinearity or unmeasured inputs)")));
    }
    if singular_in_band > 0 {
        warnings.push(Warning::new(WarningCode::SingularFrequencies, format!("{singular_in_band} frequencies in the band were left out: the input spectral matrix (or R) is singular there (an input without power, or inputs fully coherent)")));
    }
    if max_input_coherence >= 0.6 {
        warnings.push(Warning::new(WarningCode::CorrelatedInputs, format!("inputs are correlated (ordinary coherence up to {max_input_coherence:.2}, Park & Chang 2011 asks < 0.6): R and T are poorly separated")));
    }
    warnings
}

/// Z(f) = T R^-1 and the coherences at every frequency up to the band's
/// upper edge (seed 004 eq. (1)-(2), §III-E); frequencies where the input
/// spectral matrix or R is singular are left out and counted.
struct NonParametric {
    frequencies: Vec<f64>,
    impedance: Vec<DMatrix<Complex64>>,
    /// `[output][frequency]`.
    multiple: Vec<Vec<f64>>,
    /// `[output][input][frequency]`.
    partial: Vec<Vec<Vec<f64>>>,
    /// Largest ordinary coherence between two inputs in the band.
    max_input_coherence: f64,
    singular_in_band: usize,
}

fn nonparametric(
    mats: Vec<DMatrix<Complex64>>,
    freqs: &[f64],
    n: usize,
    (lo, hi): (f64, f64),
) -> NonParametric {
    let top = freqs.iter().position(|f| *f > hi).unwrap_or(freqs.len());
    let mut frequencies = Vec::new();
    let mut impedance: Vec<DMatrix<Complex64>> = Vec::new();
    let mut multiple = vec![Vec::new(); 2 * n];
    let mut partial = vec![vec![Vec::new(); n]; 2 * n];
    let mut max_input_coherence: f64 = 0.0;
    let mut singular_in_band = 0usize;
    for k in 1..top {
        let s = &mats[k];
        let in_band = freqs[k] >= lo;
        let Some(p) = mimo_point(s, n) else {
            singular_in_band += usize::from(in_band);
            continue;
        };
        let r = p.h.view((0, 0), (n, n)).into_owned();
        let t = p.h.view((n, 0), (n, n)).into_owned();
        let Some(r_inv) = r.try_inverse() else {
            singular_in_band += usize::from(in_band);
            continue;
        };
        frequencies.push(freqs[k]);
        impedance.push(t * r_inv);
        for (o, (mult, part)) in multiple.iter_mut().zip(partial.iter_mut()).enumerate() {
            mult.push(p.multiple[o]);
            for (series, value) in part.iter_mut().zip(&p.partial[o]) {
                series.push(*value);
            }
        }
        if in_band {
            for i in 0..n {
                for j in i + 1..n {
                    let c = s[(i, j)].norm_sqr() / (s[(i, i)].re * s[(j, j)].re);
                    max_input_coherence = max_input_coherence.max(c);
                }
            }
        }
    }
    NonParametric {
        frequencies,
        impedance,
        multiple,
        partial,
        max_input_coherence,
        singular_in_band,
    }
}

/// The parametric model `Z(f) = K - w^2 M + j w B` fitted per element over
/// the band by least squares weighted by the smallest multiple coherence:
/// real parts give K and M, imaginary parts B.
struct Parametric {
    inertia: Matrix,
    damping: Matrix,
    stiffness: Matrix,
    standard_errors: ParametricErrors,
    /// Weighted VAF (%) of the fit over the band.
    fit_vaf: f64,
}

fn parametric_fit(
    z_all: &[DMatrix<Complex64>],
    out_f: &[f64],
    in_band: &[usize],
    weight: &[f64],
    enbw_bins: f64,
) -> Parametric {
    let n = z_all.first().map_or(0, |z| z.nrows());
    let mut m = Matrix::zeros(n, n);
    let mut b = Matrix::zeros(n, n);
    let mut kk = Matrix::zeros(n, n);
    let mut se = ParametricErrors {
        method: "least squares over the band, variance times the window's equivalent noise bandwidth (too few Welch segments for a jackknife)".into(),
        inertia: m.clone(),
        damping: m.clone(),
        stiffness: m.clone(),
    };
    let (mut ss_res, mut ss_tot) = (0.0, 0.0);
    for i in 0..n {
        for j in 0..n {
            let rows = in_band.len();
            let mut a_re = DMatrix::<f64>::zeros(rows, 2);
            let mut y_re = DVector::<f64>::zeros(rows);
            let mut a_im = DMatrix::<f64>::zeros(rows, 1);
            let mut y_im = DVector::<f64>::zeros(rows);
            for (r, &k) in in_band.iter().enumerate() {
                let w = weight[k].max(1e-6).sqrt();
                let om = 2.0 * std::f64::consts::PI * out_f[k];
                a_re[(r, 0)] = w;
                a_re[(r, 1)] = -om * om * w;
                y_re[r] = z_all[k][(i, j)].re * w;
                a_im[(r, 0)] = om * w;
                y_im[r] = z_all[k][(i, j)].im * w;
            }
            let (th_re, se_re, res_re) = weighted_ls(&a_re, &y_re, enbw_bins);
            let (th_im, se_im, res_im) = weighted_ls(&a_im, &y_im, enbw_bins);
            kk[(i, j)] = th_re[0];
            m[(i, j)] = th_re[1];
            b[(i, j)] = th_im[0];
            se.stiffness[(i, j)] = se_re[0];
            se.inertia[(i, j)] = se_re[1];
            se.damping[(i, j)] = se_im[0];
            ss_res += res_re + res_im;
            ss_tot += y_re.norm_squared() + y_im.norm_squared();
        }
    }
    Parametric {
        inertia: m,
        damping: b,
        stiffness: kk,
        standard_errors: se,
        fit_vaf: if ss_tot > 0.0 {
            100.0 * (1.0 - ss_res / ss_tot)
        } else {
            0.0
        },
    }
}

/// Least squares with standard errors (variance times `inflation`); returns (θ, SE, RSS).
fn weighted_ls(a: &DMatrix<f64>, y: &DVector<f64>, inflation: f64) -> (Vec<f64>, Vec<f64>, f64) {
    let p = a.ncols();
    let Some(svd) = limpid_core::linalg::svd(a.clone(), true, true) else {
        return (vec![f64::NAN; p], vec![f64::NAN; p], f64::NAN);
    };
    let theta = svd.solve(y, 1e-14).unwrap_or_else(|_| DVector::zeros(p));
    let resid = y - a * &theta;
    let rss = resid.norm_squared();
    let dof = (a.nrows().saturating_sub(p)).max(1) as f64;
    let sigma2 = rss / dof * inflation;
    let inv_s2 = svd
        .singular_values
        .map(|s| if s > 0.0 { 1.0 / (s * s) } else { 0.0 });
    let v = svd
        .v_t
        .map(|vt| vt.transpose())
        .unwrap_or_else(|| DMatrix::identity(p, p));
    let cov = &v * DMatrix::from_diagonal(&inv_s2) * v.transpose() * sigma2;
    (
        theta.iter().copied().collect(),
        (0..p).map(|j| cov[(j, j)].sqrt()).collect(),
        rss,
    )
}

fn max_singular(m: &DMatrix<Complex64>) -> f64 {
    limpid_core::linalg::singular_values(m.clone()).map_or(f64::NAN, |s| s.max())
}

/// Seed 004 eq. (15)-(16): the accuracy of the estimated Z against the
/// expected model over the frequencies in `band`; the model's matrices must
/// be n x n for the estimate's n coordinates.
pub fn accuracy(
    est: &StochasticEstimate,
    expected: &ExpectedModel,
    band: (f64, f64),
) -> Result<Accuracy> {
    let n = est.coordinates.len();
    let (m, b, k) = (&expected.inertia, &expected.damping, &expected.stiffness);
    for (name, x) in [("inertia", m), ("damping", b), ("stiffness", k)] {
        if x.shape() != (n, n) {
            return Err(Error::invalid(
                "expected",
                format!(
                    "{name} is {} x {}, the estimate has {n} coordinates",
                    x.nrows(),
                    x.ncols()
                ),
            ));
        }
    }
    let mut phi_t = 0.0;
    let mut phi = DMatrix::<f64>::zeros(n, n);
    let mut rel = 0.0;
    let mut count = 0.0f64;
    for (f, z) in est.frequencies.iter().zip(&est.impedance) {
        if *f < band.0 || *f > band.1 {
            continue;
        }
        let om = 2.0 * std::f64::consts::PI * f;
        let zm = DMatrix::from_fn(n, n, |i, j| {
            Complex64::new(k[(i, j)] - om * om * m[(i, j)], om * b[(i, j)])
        });
        let ze = DMatrix::from_fn(n, n, |i, j| Complex64::new(z[i][j][0], z[i][j][1]));
        let d = &ze - &zm;
        let dn = max_singular(&d);
        phi_t += dn;
        rel += dn / max_singular(&zm);
        phi += d.map(|c| c.norm());
        count += 1.0;
    }
    let c = count.max(1.0);
    Ok(Accuracy {
        phi_t: phi_t / c,
        phi_ij: Matrix(phi / c),
        mean_relative_error: rel / c,
        expected: expected.clone(),
    })
}
