//! EMG co-contraction index (seed 001 eq. (1) and the text before it).
//!
//! Each muscle's raw EMG is full-wave rectified and low-passed (2nd-order
//! Butterworth, 8 Hz; zero-phase offline, one causal pass for live use), then
//! divided by the maximum of the same processed signal in an MVC recording.
//! The co-contraction index C is the mean of the normalised activations over
//! the muscles, sample by sample; per condition level limpid reports its
//! mean, standard deviation and the share of samples within a tolerance band
//! around the target level.

use limpid_core::{Error, Recording, Result};
use limpid_dsp::LowPass;
use serde::Serialize;

/// EMG processing settings (seed 001 defaults).
///
/// | Name | Default | Purpose | Range |
/// |---|---|---|---|
/// | `cutoff_hz` | 8 Hz | envelope low-pass | (0, fs/2) |
/// | `order` | 2 | Butterworth order | 1..=20 |
/// | `causal` | false | one causal pass (live) instead of zero-phase | |
/// | `tolerance` | 0.1 | half-width of the band around the target level | > 0 |
#[derive(Debug, Clone)]
pub struct EmgParams {
    /// Low-pass cut-off of the rectified EMG (Hz).
    pub cutoff_hz: f64,
    /// Butterworth order.
    pub order: usize,
    /// One causal pass (live) instead of zero-phase.
    pub causal: bool,
    /// Half-width of the band around the target level (fraction of MVC).
    pub tolerance: f64,
}

impl Default for EmgParams {
    fn default() -> Self {
        EmgParams {
            cutoff_hz: 8.0,
            order: 2,
            causal: false,
            tolerance: 0.1,
        }
    }
}

/// Names of the EMG columns, in file order: the raw `emg_*` columns, or
/// when there are none the envelopes `env_*` a channel map made at the EMG's
/// native rate (limpid-io `map`).
pub fn emg_columns(rec: &Recording) -> Vec<String> {
    let raw: Vec<String> = rec
        .names()
        .iter()
        .filter(|n| n.starts_with("emg_"))
        .cloned()
        .collect();
    if !raw.is_empty() {
        return raw;
    }
    rec.names()
        .iter()
        .filter(|n| n.starts_with("env_"))
        .cloned()
        .collect()
}

/// True for an envelope column made before the recording (`env_*`).
pub fn is_envelope_column(name: &str) -> bool {
    name.starts_with("env_")
}

/// The envelope of column `name`: processed here from raw EMG, or as it is
/// for an `env_` column (already rectified and low-passed at the native rate).
fn column_envelope(name: &str, values: &[f64], fs: f64, params: &EmgParams) -> Result<Vec<f64>> {
    if is_envelope_column(name) {
        Ok(values.to_vec())
    } else {
        envelope(values, fs, params)
    }
}

/// Rectified and low-passed envelope of one raw EMG signal (V).
pub fn envelope(raw: &[f64], fs: f64, params: &EmgParams) -> Result<Vec<f64>> {
    let lp = LowPass::butterworth(params.order, params.cutoff_hz, fs)?;
    let rectified: Vec<f64> = raw.iter().map(|v| v.abs()).collect();
    if params.causal {
        Ok(lp.filter_causal(&rectified))
    } else {
        lp.filtfilt(&rectified)
    }
}

/// Per-muscle normalisation factors: the maximum processed MVC envelope (V).
pub fn mvc_maxima(mvc: &Recording, muscles: &[String], params: &EmgParams) -> Result<Vec<f64>> {
    muscles
        .iter()
        .map(|m| {
            let raw = mvc.require(
                m,
                "the MVC recording must have every EMG channel of the trials",
            )?;
            let env = column_envelope(m, raw, mvc.sample_rate(), params)?;
            let max = env.iter().fold(0.0f64, |a, v| a.max(*v));
            if max > 0.0 {
                Ok(max)
            } else {
                Err(Error::Numerical {
                    path: mvc.path().to_path_buf(),
                    message: format!(
                        "column {m}: the MVC envelope is zero everywhere, nothing to normalise by"
                    ),
                })
            }
        })
        .collect()
}

/// Co-contraction index per sample: mean over muscles of envelope / MVC maximum.
pub fn cocontraction_index(
    rec: &Recording,
    muscles: &[String],
    maxima: &[f64],
    params: &EmgParams,
) -> Result<Vec<f64>> {
    cocontraction_index_and_peaks(rec, muscles, maxima, params).map(|(index, _)| index)
}

/// [`cocontraction_index`] and each muscle's peak envelope as a fraction of
/// its MVC maximum (above 1: the MVC was not maximal, or the files are swapped).
pub fn cocontraction_index_and_peaks(
    rec: &Recording,
    muscles: &[String],
    maxima: &[f64],
    params: &EmgParams,
) -> Result<(Vec<f64>, Vec<f64>)> {
    if muscles.is_empty() {
        return Err(Error::MissingColumn {
            path: rec.path().to_path_buf(),
            column: "emg_<muscle>".into(),
            why: "the co-contraction index needs at least one EMG channel".into(),
            found: rec.names().join(","),
        });
    }
    let mut index = vec![0.0; rec.len()];
    let mut peaks = Vec::with_capacity(muscles.len());
    for (m, max) in muscles.iter().zip(maxima) {
        let raw = rec.require(m, "EMG channel")?;
        let env = column_envelope(m, raw, rec.sample_rate(), params)?;
        for (c, e) in index.iter_mut().zip(&env) {
            *c += e / max;
        }
        peaks.push(env.iter().fold(0.0f64, |a, v| a.max(*v)) / max);
    }
    let k = muscles.len() as f64;
    index.iter_mut().for_each(|c| *c /= k);
    Ok((index, peaks))
}

/// Statistics of the index over the samples of one level.
#[derive(Debug, Clone, Serialize)]
pub struct LevelIndex {
    /// The level.
    pub level: f64,
    /// Mean co-contraction index (fraction of MVC).
    pub mean: f64,
    /// Standard deviation over the samples.
    pub sd: f64,
    /// Share of samples within `tolerance` of the target level (0..1).
    pub within_band: f64,
    /// Samples at this level.
    pub samples: usize,
}

/// Index statistics per distinct value of `levels`, sorted by level.
pub fn per_level(index: &[f64], levels: &[f64], tolerance: f64) -> Vec<LevelIndex> {
    let mut distinct: Vec<f64> = levels.to_vec();
    distinct.sort_by(f64::total_cmp);
    distinct.dedup();
    distinct
        .into_iter()
        .map(|level| {
            let values: Vec<f64> = index
                .iter()
                .zip(levels)
                .filter(|(_, l)| **l == level)
                .map(|(c, _)| *c)
                .collect();
            let n = values.len() as f64;
            let mean = values.iter().sum::<f64>() / n;
            let sd = (values.iter().map(|v| (v - mean).powi(2)).sum::<f64>() / (n - 1.0).max(1.0))
                .sqrt();
            let within = values
                .iter()
                .filter(|v| (*v - level).abs() <= tolerance)
                .count() as f64
                / n;
            LevelIndex {
                level,
                mean,
                sd,
                within_band: within,
                samples: values.len(),
            }
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn envelope_of_modulated_noise_follows_its_amplitude_and_normalises() {
        // carrier: a deterministic +-1 sequence, so |x| = amplitude exactly
        let fs = 1000.0;
        let n = 6000;
        let amp = |i: usize| if i < 3000 { 0.2e-3 } else { 0.8e-3 };
        let raw: Vec<f64> = (0..n)
            .map(|i| if (i * 7919) % 13 < 6 { amp(i) } else { -amp(i) })
            .collect();
        let env = envelope(&raw, fs, &EmgParams::default()).unwrap();
        // away from the step, the envelope equals the amplitude (DC gain 1)
        assert!((env[1500] - 0.2e-3).abs() < 1e-9);
        assert!((env[4500] - 0.8e-3).abs() < 1e-9);
        let names = vec!["t".into(), "emg_a".into()];
        let t: Vec<f64> = (0..n).map(|i| i as f64 / fs).collect();
        let rec = Recording::new("r.csv", names, vec![t, raw], 2).unwrap();
        let muscles = emg_columns(&rec);
        let maxima = mvc_maxima(&rec, &muscles, &EmgParams::default()).unwrap();
        // the maximum is the plateau plus the filter's overshoot at the step (a few %)
        let max = maxima[0];
        assert!(max > 0.8e-3 && max < 0.8e-3 * 1.05, "max {max}");
        let index = cocontraction_index(&rec, &muscles, &maxima, &EmgParams::default()).unwrap();
        assert!((index[1500] - 0.2e-3 / max).abs() < 1e-9);
        assert!((index[4500] - 0.8e-3 / max).abs() < 1e-9);
        let levels: Vec<f64> = (0..n).map(|i| if i < 3000 { 0.25 } else { 1.0 }).collect();
        let stats = per_level(&index, &levels, 0.05);
        assert_eq!(stats.len(), 2);
        assert!((stats[0].mean - 0.2e-3 / max).abs() < 0.01 && stats[0].within_band > 0.95);
    }
}
