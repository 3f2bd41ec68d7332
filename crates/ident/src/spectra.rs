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
    for (name, x) in inputs.iter().zip(&signals) {
        if x.iter().all(|v| *v == x[0]) {
            return Err(Error::Format {
                path: rec.path().to_path_buf(),
                message: format!(
                    "column {name}: the input never varies, so it has no spectrum to divide by"
                ),
            });
        }
    }
    let s = SegmentSpectra::new(&signals, welch)?;
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
    })
}
