//! Welch spectra and coherences of a recording's columns (Park & Chang 2011,
//! §III, eq. 3-6): the power spectral density of every named column, and for
//! each output its ordinary coherence with each input, its multiple coherence
//! on all inputs and its partial coherence with each input, the others
//! removed. What `limpid spectra` prints, typed for the result contract.
//!
//! Where the inputs' spectral matrix is singular to working precision (an
//! input without power at that frequency) the multiple and partial
//! coherences do not exist: they are `null` there, never NaN.

use limpid_core::{Error, Recording, Result};
use limpid_dsp::spectral::{mimo_point, squared_coherence, SegmentSpectra, Welch};
use schemars::JsonSchema;
use serde::{Deserialize, Serialize};

/// Spectra and coherences of a recording's inputs and outputs.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, JsonSchema)]
pub struct SpectraResult {
    /// The recording's path.
    pub recording: String,
    /// Input columns.
    pub inputs: Vec<String>,
    /// Output columns.
    pub outputs: Vec<String>,
    /// Inputs then outputs: the rows of `psd`.
    pub signals: Vec<String>,
    /// Frequencies (Hz), 0 to Nyquist.
    pub frequencies: Vec<f64>,
    /// Samples per segment (= FFT length).
    pub segment_samples: usize,
    /// Samples shared by consecutive segments.
    pub overlap_samples: usize,
    /// `psd[signal][frequency]`, one-sided density (unit² / Hz).
    pub psd: Vec<Vec<f64>>,
    /// `coherence[output][input][frequency]`, ordinary coherence (0-1).
    pub coherence: Vec<Vec<Vec<f64>>>,
    /// `multiple_coherence[output][frequency]` on all inputs (0-1); `null` where the inputs' spectral matrix is singular.
    pub multiple_coherence: Vec<Vec<Option<f64>>>,
    /// `partial_coherence[output][input][frequency]` (0-1); `null` where the inputs' spectral matrix is singular.
    pub partial_coherence: Vec<Vec<Vec<Option<f64>>>>,
    /// With a period (`--period`): the analysis of the periodic excitation.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub periodic: Option<PeriodicResult>,
}

/// The analysis of a periodic excitation (issue 59; `limpid_dsp::periodic`).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, JsonSchema)]
pub struct PeriodicResult {
    /// The period (s).
    pub period_s: f64,
    /// Whole periods averaged.
    pub periods: usize,
    /// How the transient was left out.
    pub transient: String,
    /// Every line from the lowest to the highest excited one.
    pub lines: Vec<PeriodicLine>,
    /// Detection-line levels and the verdict; absent when every line in the band is excited.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub distortion: Option<PeriodicDistortion>,
    /// The frequency response at each input's excited lines, per input-output pair.
    pub frf: Vec<LineFrf>,
    /// The inputs' own detection lines against their noise: where a
    /// force-driven experiment shows its nonlinear distortion (the
    /// displacement carries it); with inputs of disjoint lines only.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub input_distortion: Option<PeriodicDistortion>,
    /// M, B, K fitted to the excited lines, when the inputs are displacements
    /// (m, rad) and the outputs as many forces or torques (N, N m).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub impedance: Option<crate::periodic_fit::PeriodicImpedance>,
}

impl PeriodicResult {
    /// The outputs' or the inputs' detection lines show nonlinear distortion:
    /// a linear model is then the best linear approximation at this amplitude.
    pub fn nonlinear(&self) -> bool {
        self.distortion
            .iter()
            .chain(&self.input_distortion)
            .any(|d| d.verdict == "nonlinear")
    }

    /// The distortion reaches the excited lines, so the response there is
    /// the best linear approximation rather than the linear part: odd
    /// distortion always; even distortion only when an even line is excited
    /// (an odd or random-odd multisine keeps it on the even lines). Of the
    /// outputs or the inputs.
    pub fn distorts_excited_lines(&self) -> bool {
        let even_excited = self.lines.iter().any(|l| {
            l.kind == "excited"
                && ((l.frequency_hz * self.period_s).round() as u64).is_multiple_of(2)
        });
        self.distortion
            .iter()
            .chain(&self.input_distortion)
            .any(|d| d.odd_above_noise || (d.even_above_noise && even_excited))
    }
}

/// One line of a periodic analysis.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, JsonSchema)]
pub struct PeriodicLine {
    /// Frequency (Hz).
    pub frequency_hz: f64,
    /// `excited`, `odd_detection` or `even_detection`.
    pub kind: String,
    /// The input that excites it (excited lines).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub input: Option<String>,
    /// Output power summed over outputs (dB relative to the mean over excited lines).
    pub output_level: f64,
    /// The noise of the period average at this line (same reference, dB).
    pub noise_level: f64,
}

/// Nonlinear distortion at the detection lines against the noise.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, JsonSchema)]
pub struct PeriodicDistortion {
    /// Mean output power at the odd detection lines (dB re excited); absent without such lines (odd multisines).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub odd_db: Option<f64>,
    /// Mean output power at the even detection lines (dB re excited).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub even_db: Option<f64>,
    /// Mean noise of the period average over the analysed lines (dB re excited).
    pub noise_db: f64,
    /// `linear` or `nonlinear` (detection lines above the noise; `limpid_dsp::periodic`).
    pub verdict: String,
    /// The odd detection lines rise above the noise: odd distortion, which
    /// also falls on odd excited lines.
    #[serde(default)]
    pub odd_above_noise: bool,
    /// The even detection lines rise above the noise: even distortion, which
    /// reaches excited lines only where an even line is excited.
    #[serde(default)]
    pub even_above_noise: bool,
}

/// The frequency response of one input-output pair at the input's excited lines.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, JsonSchema)]
pub struct LineFrf {
    /// Input column.
    pub input: String,
    /// Output column.
    pub output: String,
    /// Excited lines (Hz).
    pub frequency_hz: Vec<f64>,
    /// |G| (output unit per input unit).
    pub magnitude: Vec<f64>,
    /// Its standard error.
    pub magnitude_se: Vec<f64>,
    /// Phase (deg), unwrapped along frequency.
    pub phase_deg: Vec<f64>,
    /// Its standard error (deg).
    pub phase_se_deg: Vec<f64>,
}

/// Refuse no inputs or outputs, and a column named twice (the inputs'
/// spectral matrix would be singular everywhere): checked before any data is read.
pub fn check_columns(inputs: &[String], outputs: &[String]) -> Result<()> {
    if inputs.is_empty() || outputs.is_empty() {
        return Err(Error::invalid(
            "inputs/outputs",
            "name at least one input and one output column",
        ));
    }
    let mut seen = std::collections::HashSet::new();
    for name in inputs.iter().chain(outputs) {
        if !seen.insert(name) {
            return Err(Error::invalid(
                "inputs/outputs",
                format!(
                    "column {name} is named twice; each input and output must be its own column"
                ),
            ));
        }
    }
    Ok(())
}

/// Fewest Welch segments for coherences of `inputs` inputs: an estimate
/// averaged over n segments reads about q/n for signals that share nothing,
/// and exactly 1 from one segment (issue 56: `--nfft` as long as the
/// recording printed a coherence of 1 everywhere). Twice the inputs plus
/// one, doubled, keeps that floor at or below 1/4.
pub fn min_coherence_segments(inputs: usize) -> usize {
    2 * (inputs + 1)
}

/// Refuse coherences from too few Welch segments ([`min_coherence_segments`]).
pub fn check_segments(
    rec: &Recording,
    segments: usize,
    inputs: usize,
    nperseg: usize,
) -> Result<()> {
    let needed = min_coherence_segments(inputs);
    if segments < needed {
        return Err(Error::Format {
            path: rec.path().to_path_buf(),
            message: format!(
                "{segments} Welch segment(s) of {nperseg} samples in {} samples: coherences from fewer than {needed} segments (for {inputs} input(s)) are biased towards 1 and would read as a perfect fit; use a shorter segment (--nfft) or a longer recording",
                rec.len()
            ),
        });
    }
    Ok(())
}

/// Spectra and coherences of `inputs` and `outputs` (column names) of `rec`.
/// Refuses a column named twice (the inputs' spectral matrix would be
/// singular everywhere) and an input that never varies (no spectrum to divide by).
///
/// # Example
///
/// An output that is twice its input plus independent noise of the same
/// power as the input is 4/5 explained by it (coherence S / (S + N)):
///
/// ```
/// use limpid_core::Recording;
/// use limpid_dsp::spectral::Welch;
/// use rand::{rngs::StdRng, Rng, SeedableRng};
///
/// let mut rng = StdRng::seed_from_u64(1);
/// let mut noise = || rng.random::<f64>() - 0.5;
/// let n = 40_000;
/// let u: Vec<f64> = (0..n).map(|_| noise()).collect();
/// let y: Vec<f64> = u.iter().map(|u| 2.0 * u + noise()).collect();
/// let t: Vec<f64> = (0..n).map(|i| i as f64 / 100.0).collect();
/// let rec = Recording::new("<arrays>", vec!["t".into(), "u".into(), "y".into()], vec![t, u, y], 1)?;
/// let welch = Welch { nperseg: 256, ..Welch::new(100.0) };
/// let s = limpid_ident::spectra::spectra(&rec, &["u".into()], &["y".into()], &welch)?;
/// let coherence = &s.coherence[0][0]; // output y, input u
/// let mean = coherence.iter().sum::<f64>() / coherence.len() as f64;
/// assert!((mean - 0.8).abs() < 0.02, "{mean}");
/// # Ok::<(), limpid_core::Error>(())
/// ```
pub fn spectra(
    rec: &Recording,
    inputs: &[String],
    outputs: &[String],
    welch: &Welch,
) -> Result<SpectraResult> {
    check_columns(inputs, outputs)?;
    let names: Vec<String> = inputs.iter().chain(outputs).cloned().collect();
    let mut signals: Vec<&[f64]> = Vec::with_capacity(names.len());
    for name in &names {
        signals.push(rec.require(name, "named as an input or output")?);
    }
    spectra_of(rec, inputs, outputs, &signals, welch)
}

/// [`spectra`] of the named signals (inputs first), which may be part of the recording.
fn spectra_of(
    rec: &Recording,
    inputs: &[String],
    outputs: &[String],
    signals: &[&[f64]],
    welch: &Welch,
) -> Result<SpectraResult> {
    let names: Vec<String> = inputs.iter().chain(outputs).cloned().collect();
    for (name, x) in inputs.iter().zip(signals) {
        if x.iter().all(|v| *v == x[0]) {
            return Err(Error::Format {
                path: rec.path().to_path_buf(),
                message: format!(
                    "column {name}: the input never varies, so it has no spectrum to divide by"
                ),
            });
        }
    }
    let s = SegmentSpectra::new(signals, welch)?;
    let q = inputs.len();
    check_segments(rec, s.segments(), q, welch.nperseg)?;
    let mats = s.matrix();
    let points: Vec<_> = mats.iter().map(|m| mimo_point(m, q)).collect();
    let psd = (0..names.len())
        .map(|i| mats.iter().map(|m| m[(i, i)].re).collect())
        .collect();
    let coherence = (0..outputs.len())
        .map(|o| {
            (0..q)
                .map(|i| {
                    mats.iter()
                        .map(|m| {
                            squared_coherence(m[(i, i)].re, m[(q + o, q + o)].re, m[(i, q + o)])
                        })
                        .collect()
                })
                .collect()
        })
        .collect();
    let multiple_coherence = (0..outputs.len())
        .map(|o| {
            points
                .iter()
                .map(|p| p.as_ref().map(|p| p.multiple[o]))
                .collect()
        })
        .collect();
    let partial_coherence = (0..outputs.len())
        .map(|o| {
            (0..q)
                .map(|i| {
                    points
                        .iter()
                        .map(|p| p.as_ref().map(|p| p.partial[o][i]))
                        .collect()
                })
                .collect()
        })
        .collect();
    Ok(SpectraResult {
        recording: rec.path().display().to_string(),
        inputs: inputs.to_vec(),
        outputs: outputs.to_vec(),
        signals: names,
        frequencies: s.frequencies.clone(),
        segment_samples: welch.nperseg,
        overlap_samples: welch.noverlap.unwrap_or(welch.nperseg / 2),
        psd,
        coherence,
        multiple_coherence,
        partial_coherence,
        periodic: None,
    })
}

/// The whole periods of a recording's columns after its transient, and
/// their period-averaged spectra.
pub(crate) struct Periods<'a> {
    /// Each column's samples over the whole periods used.
    pub used: Vec<&'a [f64]>,
    /// Samples per period.
    pub period: usize,
    /// Whole periods used.
    pub periods: usize,
    /// How the transient was left out, in words.
    pub transient: String,
    /// The period-averaged spectra of `used`.
    pub spectra: limpid_dsp::periodic::PeriodSpectra,
}

/// The columns `names` of `rec` cut into whole periods of `period_s`: a
/// `period` column numbers the periods (-1 the transient, left out, and a
/// fade-out after the last period); without it the first period is left
/// out. Refuses a period that is not a whole number of samples, periods
/// that are not contiguous, and fewer than two periods.
pub(crate) fn whole_periods<'a>(
    rec: &'a Recording,
    names: &[String],
    period_s: f64,
) -> Result<Periods<'a>> {
    let fs = rec.sample_rate();
    let exact = period_s * fs;
    let n = exact.round() as usize;
    if !(n >= 4 && (exact - n as f64).abs() < 1e-3) {
        return Err(Error::invalid(
            "period_s",
            format!(
                "{} s at {} Hz is {} samples: a period must be a whole number of samples (at least 4)",
                limpid_core::error::Num(period_s),
                limpid_core::error::Num(fs),
                limpid_core::error::Num(exact)
            ),
        ));
    }
    let mut end_of_periods = None;
    let (start, transient) = match rec.column("period") {
        Some(index) => {
            let first = index
                .iter()
                .position(|p| *p >= 0.0)
                .ok_or_else(|| Error::Format {
                    path: rec.path().to_path_buf(),
                    message:
                        "column period: no sample of a period (every value is -1, the transient)"
                            .into(),
                })?;
            // a fade-out after the last period (-1 to the end) is left out too
            let end = index[first..]
                .iter()
                .position(|p| *p < 0.0)
                .map_or(index.len(), |back| first + back);
            if let Some(again) = index[end..].iter().position(|p| *p >= 0.0) {
                return Err(Error::Format {
                    path: rec.path().to_path_buf(),
                    message: format!(
                        "row {}, column period: a period after a transient (-1) that followed the periods; the periods must be contiguous",
                        rec.row_of(end + again)
                    ),
                });
            }
            period_column_agrees(rec, &index[first..end], n, period_s)?;
            let left_out = index.len() - (end - first);
            end_of_periods = Some(end);
            (
                first,
                format!("{left_out} samples numbered -1 in the period column (fade-in, fade-out) left out"),
            )
        }
        None => (
            n,
            format!("the first period ({n} samples) left out as the transient"),
        ),
    };
    let mut signals: Vec<&[f64]> = Vec::with_capacity(names.len());
    for name in names {
        let x = rec.require(name, "named as an input or output")?;
        let end = end_of_periods.unwrap_or(x.len()).min(x.len());
        signals.push(&x[start.min(end)..end]);
    }
    let available = signals.iter().map(|s| s.len()).min().unwrap_or(0);
    let periods = available / n;
    let used: Vec<&[f64]> = signals.iter().map(|s| &s[..periods * n]).collect();
    for (name, x) in names.iter().zip(&used) {
        if x.len() > 1 && x.iter().all(|v| *v == x[0]) {
            return Err(Error::Format {
                path: rec.path().to_path_buf(),
                message: format!(
                    "column {name}: holds one value ({}) over the periods used: nothing varies to identify from",
                    limpid_core::error::Num(x[0])
                ),
            });
        }
    }
    if let Some(input) = used.first() {
        repeats_with_the_period(rec, &names[0], input, n, period_s)?;
    }
    let analysed =
        limpid_dsp::periodic::PeriodSpectra::new(&used, n).map_err(|e| Error::Format {
            path: rec.path().to_path_buf(),
            message: e.to_string(),
        })?;
    Ok(Periods {
        used,
        period: n,
        periods,
        transient,
        spectra: analysed,
    })
}

/// A `period` column's periods (their runs of one index) must last the
/// period given: `--period 7.9` on periods of 8 s leaked into the noise
/// floor and turned a nonlinear verdict linear (issue 76).
fn period_column_agrees(rec: &Recording, index: &[f64], n: usize, period_s: f64) -> Result<()> {
    let mut runs: Vec<usize> = Vec::new();
    let mut start = 0;
    for i in 1..=index.len() {
        if i == index.len() || index[i] != index[start] {
            runs.push(i - start);
            start = i;
        }
    }
    // the last period may be cut short by the recording's end
    let whole = &runs[..runs.len().saturating_sub(1).max(1)];
    let mut sorted = whole.to_vec();
    sorted.sort_unstable();
    let typical = sorted[sorted.len() / 2];
    if typical != n {
        let fs = rec.sample_rate();
        return Err(Error::invalid(
            "period_s",
            format!(
                "{} s is {n} samples, but the period column's periods last {typical} samples ({} s): give the period the recording was made with",
                limpid_core::error::Num(period_s),
                limpid_core::error::Num(typical as f64 / fs)
            ),
        ));
    }
    Ok(())
}

/// The first input must repeat from period to period: consecutive periods
/// that differ by more than 0.7 of its RMS are not periods of it (a wrong
/// period on a multisine differs by about 1.4).
fn repeats_with_the_period(
    rec: &Recording,
    name: &str,
    x: &[f64],
    n: usize,
    period_s: f64,
) -> Result<()> {
    let periods = x.len() / n;
    if periods < 2 {
        return Ok(());
    }
    // each period about its own mean: a slow drift of the posture moves
    // whole periods, it does not make them differ in shape
    let means: Vec<f64> = x
        .chunks_exact(n)
        .map(|p| p.iter().sum::<f64>() / n as f64)
        .collect();
    let at = |i: usize| x[i] - means[i / n];
    let power = (0..periods * n).map(|i| at(i).powi(2)).sum::<f64>() / (periods * n) as f64;
    let difference = (0..(periods - 1) * n)
        .map(|i| (at(i + n) - at(i)).powi(2))
        .sum::<f64>()
        / ((periods - 1) * n) as f64;
    if power > 0.0 && difference > 0.49 * power {
        return Err(Error::invalid(
            "period_s",
            format!(
                "{}: column {name} does not repeat every {} s: consecutive periods differ by {} % of its RMS; is the period right, and is the excitation periodic?",
                rec.path().display(),
                limpid_core::error::Num(period_s),
                limpid_core::error::Num((100.0 * (difference / power).sqrt()).round())
            ),
        ));
    }
    Ok(())
}

/// Spectra of a periodic excitation with period `period_s` (issue 59):
/// Welch over whole periods (boxcar, no overlap, one segment a period),
/// and the periodic analysis (`limpid_dsp::periodic`): the response at the
/// excited lines with standard errors from the period-to-period scatter,
/// and the output at the detection lines against the noise. A `period`
/// column numbers the periods (-1 the transient, left out); without it the
/// first period is left out.
pub fn periodic_spectra(
    rec: &Recording,
    inputs: &[String],
    outputs: &[String],
    period_s: f64,
) -> Result<SpectraResult> {
    check_columns(inputs, outputs)?;
    let fs = rec.sample_rate();
    let names: Vec<String> = inputs.iter().chain(outputs).cloned().collect();
    let Periods {
        used,
        period: n,
        periods,
        transient,
        spectra: analysed,
    } = whole_periods(rec, &names, period_s)?;
    let analysis = limpid_dsp::periodic::analyse(&analysed, inputs.len())?;
    let welch = periodic_welch(n, periods, inputs.len(), fs);
    let mut result = spectra_of(rec, inputs, outputs, &used, &welch)?;
    let mut periodic = periodic_result(&analysis, inputs, outputs, period_s, periods, transient);
    // the inputs analysed as outputs of themselves: their detection lines
    let n_in = inputs.len();
    let twice: Vec<usize> = (0..n_in).chain(0..n_in).collect();
    let input_side = limpid_dsp::periodic::analyse(&analysed.select(&twice), n_in)
        .ok()
        .and_then(|a| a.distortion);
    periodic.input_distortion = input_side.as_ref().map(distortion_of);
    if displacements_to_forces(inputs, outputs) {
        let nonlinear = periodic.distorts_excited_lines();
        periodic.impedance =
            crate::periodic_fit::fit(&analysed, &analysis, n_in, period_s, nonlinear);
    }
    result.periodic = Some(periodic);
    Ok(result)
}

/// The Welch segments beside a periodic analysis: whole periods (boxcar,
/// no overlap: no leakage) when there are enough of them for coherences
/// ([`min_coherence_segments`]); else Hann segments of a whole fraction
/// 1/m of a period with half overlap (2 m periods - 1 segments), the
/// smallest m that gives enough. The periodic analysis itself needs only
/// two periods; the coherences are an ordinary Welch estimate.
fn periodic_welch(period: usize, periods: usize, inputs: usize, fs: f64) -> Welch {
    let needed = min_coherence_segments(inputs);
    if periods >= needed {
        return Welch {
            nperseg: period,
            noverlap: Some(0),
            window: limpid_dsp::spectral::Window::Boxcar,
            ..Welch::new(fs)
        };
    }
    let m = (1..=period / 4)
        .find(|m| 2 * periods * m > needed)
        .unwrap_or(1);
    let nperseg = period / m;
    Welch {
        nperseg,
        noverlap: Some(nperseg / 2),
        window: limpid_dsp::spectral::Window::Hann,
        ..Welch::new(fs)
    }
}

/// The typed result of a periodic analysis.
pub(crate) fn periodic_result(
    a: &limpid_dsp::periodic::PeriodicAnalysis,
    inputs: &[String],
    outputs: &[String],
    period_s: f64,
    periods: usize,
    transient: String,
) -> PeriodicResult {
    let hz = |line: usize| line as f64 / period_s;
    let lines = a
        .lines
        .iter()
        .map(|l| PeriodicLine {
            frequency_hz: hz(l.line),
            kind: l.kind.name().into(),
            input: l.input.map(|i| inputs[i].clone()),
            output_level: l.output_db,
            noise_level: l.noise_db,
        })
        .collect();
    let mut frf = Vec::new();
    for (i, input) in inputs.iter().enumerate() {
        let at: Vec<&limpid_dsp::periodic::LineResponse> =
            a.responses.iter().filter(|r| r.input == i).collect();
        for (o, output) in outputs.iter().enumerate() {
            let g: Vec<num_complex::Complex64> = at.iter().map(|r| r.response[o]).collect();
            let var: Vec<f64> = at.iter().map(|r| r.variance[o]).collect();
            let magnitude: Vec<f64> = g.iter().map(|g| g.norm()).collect();
            // complex noise of variance v: |G| and arg G each carry about v / 2
            let magnitude_se = var.iter().map(|v| (v / 2.0).sqrt()).collect();
            let phase_se_deg = var
                .iter()
                .zip(&magnitude)
                .map(|(v, m)| {
                    (v / (2.0 * m * m))
                        .sqrt()
                        .min(180.0)
                        .to_degrees()
                        .min(180.0)
                })
                .collect();
            frf.push(LineFrf {
                input: input.clone(),
                output: output.clone(),
                frequency_hz: at.iter().map(|r| hz(r.line)).collect(),
                magnitude,
                magnitude_se,
                phase_deg: unwrapped_degrees(&g),
                phase_se_deg,
            });
        }
    }
    PeriodicResult {
        period_s,
        periods,
        transient,
        lines,
        distortion: a.distortion.as_ref().map(distortion_of),
        frf,
        input_distortion: None,
        impedance: None,
    }
}

pub(crate) fn distortion_of(d: &limpid_dsp::periodic::Distortion) -> PeriodicDistortion {
    PeriodicDistortion {
        odd_db: d.odd_db,
        even_db: d.even_db,
        noise_db: d.noise_db,
        verdict: if d.nonlinear() { "nonlinear" } else { "linear" }.into(),
        odd_above_noise: d.odd_rises,
        even_above_noise: d.even_rises,
    }
}

/// Inputs all displacements (m, rad) and outputs as many forces or torques
/// (N, N m), by what the columns are (FORMAT.md).
fn displacements_to_forces(inputs: &[String], outputs: &[String]) -> bool {
    let unit = |c: &String| limpid_core::recording::magnitude_limit(c).1;
    inputs.len() == outputs.len()
        && inputs.iter().all(|c| matches!(unit(c), "m" | "rad"))
        && outputs.iter().all(|c| matches!(unit(c), "N" | "N m"))
}

/// Phases in degrees on one branch along frequency: each differs from the
/// one before by less than 180 degrees, the first in (-180, 180].
fn unwrapped_degrees(g: &[num_complex::Complex64]) -> Vec<f64> {
    let mut out: Vec<f64> = Vec::with_capacity(g.len());
    for z in g {
        let mut p = z.arg().to_degrees();
        if let Some(&before) = out.last() {
            p += 360.0 * ((before - p) / 360.0).round();
        }
        out.push(p);
    }
    out
}
