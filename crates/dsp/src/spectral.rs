//! Welch spectral estimates: auto- and cross-spectral densities, the full
//! spectral matrix of many signals, H1 frequency-response matrices, and
//! ordinary, multiple and partial coherence (Bendat & Piersol; seed 004
//! §III-E). No maintained crate offers CSD and coherence, so this is ours,
//! written on `realfft` and checked against `scipy.signal` (tests/fixtures).
//!
//! Conventions (as `scipy.signal.csd` with `return_onesided=True`,
//! `average='mean'`, no boundary padding): segments of `nperseg` samples with
//! `noverlap` overlap, each detrended and multiplied by the window (Hann:
//! periodic, `0.5 - 0.5 cos(2 pi n / N)`); `P_xy = mean(conj(X) Y) * scale`,
//! scale `1 / (fs sum w^2)` for densities (unit²/Hz) or `1 / (sum w)^2` for
//! spectra (unit²); one-sided values doubled except at 0 Hz and Nyquist.
//! The FFT of each signal's segments is computed once and reused for every
//! pair; the plan is made once per segment length.

use std::ops::Range;
use std::sync::Arc;

use nalgebra::DMatrix;
use num_complex::Complex64;
use realfft::{RealFftPlanner, RealToComplex};

use limpid_core::{Error, Result};

/// Window applied to each segment.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Window {
    /// Periodic Hann (scipy's `'hann'` for spectral analysis).
    Hann,
    /// Periodic Hamming.
    Hamming,
    /// Rectangular.
    Boxcar,
}

/// Trend removed from each segment.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Detrend {
    /// Leave the segment as it is.
    None,
    /// Subtract the mean (scipy's default).
    Constant,
    /// Subtract the least-squares line.
    Linear,
}

/// Density (unit²/Hz) or power spectrum (unit²).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Scaling {
    /// Power spectral density (unit²/Hz).
    Density,
    /// Power spectrum (unit²).
    Spectrum,
}

/// Welch settings.
///
/// | Name | Default | Purpose | Range |
/// |---|---|---|---|
/// | `fs` | required | sample rate (Hz) | > 0 |
/// | `nperseg` | 256 | samples per segment (= FFT length) | 2..=signal length |
/// | `noverlap` | nperseg / 2 | overlap of segments | < nperseg |
/// | `window` | Hann | segment window | |
/// | `detrend` | Constant | per-segment trend removal | |
/// | `scaling` | Density | density or spectrum | |
#[derive(Debug, Clone)]
pub struct Welch {
    /// Sample rate (Hz).
    pub fs: f64,
    /// Samples per segment.
    pub nperseg: usize,
    /// Samples shared by consecutive segments; `None`: half a segment.
    pub noverlap: Option<usize>,
    /// Taper applied to each segment.
    pub window: Window,
    /// Trend removed from each segment.
    pub detrend: Detrend,
    /// Density or spectrum.
    pub scaling: Scaling,
}

impl Welch {
    /// scipy's defaults at sample rate `fs`.
    pub fn new(fs: f64) -> Self {
        Welch {
            fs,
            nperseg: 256,
            noverlap: None,
            window: Window::Hann,
            detrend: Detrend::Constant,
            scaling: Scaling::Density,
        }
    }

    fn overlap(&self) -> usize {
        self.noverlap.unwrap_or(self.nperseg / 2)
    }

    fn check(&self, n: usize) -> Result<()> {
        if !self.fs.is_finite() || self.fs <= 0.0 {
            return Err(Error::invalid(
                "sample rate",
                format!("expected a positive rate, found {}", self.fs),
            ));
        }
        if self.nperseg < 2 || self.nperseg > n {
            return Err(Error::invalid(
                "segment length",
                format!(
                    "expected 2 to {n} samples (the signal length), found {}",
                    self.nperseg
                ),
            ));
        }
        if self.overlap() >= self.nperseg {
            return Err(Error::invalid(
                "overlap",
                format!(
                    "expected fewer than nperseg = {} samples, found {}",
                    self.nperseg,
                    self.overlap()
                ),
            ));
        }
        Ok(())
    }

    /// Window samples.
    pub fn window_values(&self) -> Vec<f64> {
        let n = self.nperseg as f64;
        (0..self.nperseg)
            .map(|k| {
                let c = (2.0 * std::f64::consts::PI * k as f64 / n).cos();
                match self.window {
                    Window::Hann => 0.5 - 0.5 * c,
                    Window::Hamming => 0.54 - 0.46 * c,
                    Window::Boxcar => 1.0,
                }
            })
            .collect()
    }

    /// Frequencies (Hz) of the one-sided estimate.
    pub fn frequencies(&self) -> Vec<f64> {
        (0..self.nperseg / 2 + 1)
            .map(|k| k as f64 * self.fs / self.nperseg as f64)
            .collect()
    }
}

/// Most bytes the kept segment spectra of one estimate may take (1 GiB).
pub const MAX_SEGMENT_SPECTRA_BYTES: usize = 1 << 30;

/// Segment spectra of several equally long signals, ready to be paired.
pub struct SegmentSpectra {
    /// `spectra[signal][segment][bin]`.
    spectra: Vec<Vec<Vec<Complex64>>>,
    scale: Vec<f64>,
    /// Frequencies of the bins (Hz).
    pub frequencies: Vec<f64>,
}

impl SegmentSpectra {
    /// FFT every windowed, detrended segment of every signal (one plan, reused).
    pub fn new(signals: &[&[f64]], p: &Welch) -> Result<Self> {
        let n = signals.first().map_or(0, |s| s.len());
        if signals.iter().any(|s| s.len() != n) {
            return Err(Error::invalid(
                "signals",
                "all signals must have the same length",
            ));
        }
        p.check(n)?;
        let step = p.nperseg - p.overlap();
        let segments = (n - p.nperseg) / step + 1;
        let bins = p.nperseg / 2 + 1;
        // every segment's spectrum is kept (the jackknife regroups them):
        // bound what an overlap close to nperseg would ask for
        let bytes = (signals.len() as f64)
            * segments as f64
            * bins as f64
            * std::mem::size_of::<Complex64>() as f64;
        if bytes > MAX_SEGMENT_SPECTRA_BYTES as f64 {
            return Err(Error::invalid(
                "overlap",
                format!(
                    "{segments} segments of {} samples (overlap {}) for {} signals would hold {:.1} GB of spectra; limpid keeps at most {:.1} GB: use a smaller overlap or segment",
                    p.nperseg,
                    p.overlap(),
                    signals.len(),
                    bytes / 1e9,
                    MAX_SEGMENT_SPECTRA_BYTES as f64 / 1e9
                ),
            ));
        }
        let w = p.window_values();
        let plan: Arc<dyn RealToComplex<f64>> =
            RealFftPlanner::<f64>::new().plan_fft_forward(p.nperseg);
        let mut input = plan.make_input_vec();
        let mut scratch = plan.make_scratch_vec();
        let mut spectra = Vec::with_capacity(signals.len());
        for s in signals {
            let mut per = Vec::with_capacity(segments);
            for k in 0..segments {
                let seg = &s[k * step..k * step + p.nperseg];
                detrend_into(seg, p.detrend, &mut input);
                for (v, wk) in input.iter_mut().zip(&w) {
                    *v *= wk;
                }
                let mut out = plan.make_output_vec();
                plan.process_with_scratch(&mut input, &mut out, &mut scratch)
                    .map_err(|e| Error::invalid("fft", e.to_string()))?;
                per.push(out);
            }
            spectra.push(per);
        }
        let base = match p.scaling {
            Scaling::Density => 1.0 / (p.fs * w.iter().map(|v| v * v).sum::<f64>()),
            Scaling::Spectrum => 1.0 / w.iter().sum::<f64>().powi(2),
        };
        let scale = (0..bins)
            .map(|b| {
                let nyquist = p.nperseg.is_multiple_of(2) && b == bins - 1;
                if b == 0 || nyquist {
                    base
                } else {
                    2.0 * base
                }
            })
            .collect();
        Ok(SegmentSpectra {
            spectra,
            scale,
            frequencies: p.frequencies(),
        })
    }

    /// Cross-spectrum `P_ab = mean over segments of conj(A) B`, scaled.
    pub fn cross(&self, a: usize, b: usize) -> Vec<Complex64> {
        self.cross_without(a, b, 0..0)
    }

    /// The cross-spectrum averaged over every segment outside `skip` (for
    /// delete-a-group jackknife replicates); all segments when `skip` is empty.
    pub fn cross_without(&self, a: usize, b: usize, skip: Range<usize>) -> Vec<Complex64> {
        self.cross_below(a, b, skip, self.scale.len())
    }

    /// [`Self::cross_without`] for the first `bins` frequencies only.
    fn cross_below(&self, a: usize, b: usize, skip: Range<usize>, bins: usize) -> Vec<Complex64> {
        let sa = &self.spectra[a];
        let sb = &self.spectra[b];
        let kept = |i: &usize| !skip.contains(i);
        let m = (0..sa.len()).filter(kept).count().max(1) as f64;
        (0..bins.min(self.scale.len()))
            .map(|k| {
                let s: Complex64 = (0..sa.len())
                    .filter(kept)
                    .map(|i| sa[i][k].conj() * sb[i][k])
                    .sum();
                s / m * self.scale[k]
            })
            .collect()
    }

    /// Delete-a-group jackknife spectra: for each range of segments in
    /// `groups`, the spectral matrix of the first `bins` frequencies averaged
    /// over every segment outside it (as [`Self::matrix_below`] with that
    /// `skip`). Each segment's products are summed once, into its group; a
    /// replicate is then the total less one group, so the cost is one pass
    /// over the segments, not one per replicate.
    pub fn matrices_deleting(
        &self,
        bins: usize,
        groups: &[Range<usize>],
    ) -> Vec<Vec<DMatrix<Complex64>>> {
        let m = self.spectra.len();
        let bins = bins.min(self.scale.len());
        let segments = self.segments();
        let pairs: Vec<(usize, usize)> = (0..m).flat_map(|i| (i..m).map(move |j| (i, j))).collect();
        let mut index = vec![vec![0; m]; m];
        for (p, &(i, j)) in pairs.iter().enumerate() {
            index[i][j] = p;
        }
        // sums[group][pair][bin] of conj(S_i) S_j over the group's segments
        let sums: Vec<Vec<Vec<Complex64>>> = groups
            .iter()
            .map(|g| {
                pairs
                    .iter()
                    .map(|&(a, b)| {
                        let (sa, sb) = (&self.spectra[a], &self.spectra[b]);
                        (0..bins)
                            .map(|k| {
                                g.clone()
                                    .filter(|i| *i < segments)
                                    .map(|i| sa[i][k].conj() * sb[i][k])
                                    .sum()
                            })
                            .collect()
                    })
                    .collect()
            })
            .collect();
        // segments outside every group count in each replicate too
        let outside: Vec<usize> = (0..segments)
            .filter(|i| !groups.iter().any(|g| g.contains(i)))
            .collect();
        let total: Vec<Vec<Complex64>> = (0..pairs.len())
            .map(|p| {
                let (a, b) = pairs[p];
                (0..bins)
                    .map(|k| {
                        sums.iter().map(|g| g[p][k]).sum::<Complex64>()
                            + outside
                                .iter()
                                .map(|&i| self.spectra[a][i][k].conj() * self.spectra[b][i][k])
                                .sum::<Complex64>()
                    })
                    .collect()
            })
            .collect();
        groups
            .iter()
            .zip(&sums)
            .map(|(g, sum)| {
                let deleted = g.clone().filter(|i| *i < segments).count();
                let kept = segments.saturating_sub(deleted).max(1) as f64;
                let at = |i: usize, j: usize, k: usize| {
                    let (lo, hi, conj) = if i <= j { (i, j, false) } else { (j, i, true) };
                    let p = index[lo][hi];
                    let v = (total[p][k] - sum[p][k]) / kept * self.scale[k];
                    if conj {
                        v.conj()
                    } else {
                        v
                    }
                };
                (0..bins)
                    .map(|k| DMatrix::from_fn(m, m, |i, j| at(i, j, k)))
                    .collect()
            })
            .collect()
    }

    /// Add the segments of another recording made with the same Welch
    /// settings and signals (seed 004 averages repeated trials): the spectra
    /// then average over the segments of both.
    pub fn append(&mut self, other: SegmentSpectra) -> Result<()> {
        if other.spectra.len() != self.spectra.len() || other.scale != self.scale {
            return Err(Error::invalid(
                "recordings",
                "pooled recordings must have the same signals, sample rate and Welch settings",
            ));
        }
        for (mine, theirs) in self.spectra.iter_mut().zip(other.spectra) {
            mine.extend(theirs);
        }
        Ok(())
    }

    /// Number of averaged segments.
    pub fn segments(&self) -> usize {
        self.spectra.first().map_or(0, Vec::len)
    }

    /// The spectral matrix `S[f][i][j] = P_{s_i s_j}(f)` of all signals.
    pub fn matrix(&self) -> Vec<DMatrix<Complex64>> {
        self.matrix_without(0..0)
    }

    /// The spectral matrix averaged over every segment outside `skip`.
    pub fn matrix_without(&self, skip: Range<usize>) -> Vec<DMatrix<Complex64>> {
        self.matrix_below(self.scale.len(), skip)
    }

    /// The spectral matrix of the first `bins` frequencies (an estimator that
    /// reads only a band below 10 Hz of a 0.04 Hz grid needs 250 of 12,289
    /// bins), averaged over every segment outside `skip`.
    pub fn matrix_below(&self, bins: usize, skip: Range<usize>) -> Vec<DMatrix<Complex64>> {
        let m = self.spectra.len();
        let bins = bins.min(self.scale.len());
        // the upper triangle; the lower one is its conjugate (Hermitian matrix)
        let upper: Vec<Vec<Vec<Complex64>>> = (0..m)
            .map(|i| {
                (i..m)
                    .map(|j| self.cross_below(i, j, skip.clone(), bins))
                    .collect()
            })
            .collect();
        let at = |i: usize, j: usize, k: usize| {
            if i <= j {
                upper[i][j - i][k]
            } else {
                upper[j][i - j][k].conj()
            }
        };
        (0..bins)
            .map(|k| DMatrix::from_fn(m, m, |i, j| at(i, j, k)))
            .collect()
    }
}

fn detrend_into(seg: &[f64], d: Detrend, out: &mut [f64]) {
    out.copy_from_slice(seg);
    match d {
        Detrend::None => {}
        Detrend::Constant => {
            let mean = seg.iter().sum::<f64>() / seg.len() as f64;
            out.iter_mut().for_each(|v| *v -= mean);
        }
        Detrend::Linear => {
            let n = seg.len() as f64;
            let tm = (n - 1.0) / 2.0;
            let ym = seg.iter().sum::<f64>() / n;
            let (mut num, mut den) = (0.0, 0.0);
            for (k, y) in seg.iter().enumerate() {
                num += (k as f64 - tm) * (y - ym);
                den += (k as f64 - tm).powi(2);
            }
            let slope = if den > 0.0 { num / den } else { 0.0 };
            for (k, v) in out.iter_mut().enumerate() {
                *v -= ym + slope * (k as f64 - tm);
            }
        }
    }
}

/// `scipy.signal.csd(x, y)`: frequencies and the cross-spectral density.
pub fn csd(x: &[f64], y: &[f64], p: &Welch) -> Result<(Vec<f64>, Vec<Complex64>)> {
    let s = SegmentSpectra::new(&[x, y], p)?;
    Ok((s.frequencies.clone(), s.cross(0, 1)))
}

/// `scipy.signal.welch(x)`: frequencies and the power spectral density.
pub fn psd(x: &[f64], p: &Welch) -> Result<(Vec<f64>, Vec<f64>)> {
    let s = SegmentSpectra::new(&[x], p)?;
    Ok((
        s.frequencies.clone(),
        s.cross(0, 0).iter().map(|v| v.re).collect(),
    ))
}

/// `scipy.signal.coherence(x, y)`: magnitude-squared coherence.
pub fn coherence(x: &[f64], y: &[f64], p: &Welch) -> Result<(Vec<f64>, Vec<f64>)> {
    let s = SegmentSpectra::new(&[x, y], p)?;
    let (pxx, pyy, pxy) = (s.cross(0, 0), s.cross(1, 1), s.cross(0, 1));
    let c = (0..pxy.len())
        .map(|k| squared_coherence(pxx[k].re, pyy[k].re, pxy[k]))
        .collect();
    Ok((s.frequencies, c))
}

/// Magnitude-squared coherence |G_xy|² / (G_xx G_yy) of one bin from the
/// auto spectra and the cross spectrum; 0 where either signal has no power.
pub fn squared_coherence(gxx: f64, gyy: f64, gxy: Complex64) -> f64 {
    let d = gxx * gyy;
    if d > 0.0 {
        gxy.norm_sqr() / d
    } else {
        0.0
    }
}

/// Frequency response and coherences of outputs on inputs at one frequency.
#[derive(Debug, Clone)]
pub struct MimoPoint {
    /// H1 estimate, outputs x inputs.
    pub h: DMatrix<Complex64>,
    /// Multiple coherence of each output on all inputs.
    pub multiple: Vec<f64>,
    /// Partial coherence [output][input]: input i and output k, the other inputs removed.
    pub partial: Vec<Vec<f64>>,
}

/// H1 = G_yu G_uu^-1 with multiple and partial coherences, from a spectral
/// matrix whose first `inputs` signals are the inputs and the rest outputs.
/// `None` where G_uu is singular to working precision (reciprocal condition
/// number below 1e-12: an input without power there, or inputs fully
/// coherent), where H would be rounding noise.
pub fn mimo_point(s: &DMatrix<Complex64>, inputs: usize) -> Option<MimoPoint> {
    let m = s.nrows();
    let q = inputs;
    let guu = s.view((0, 0), (q, q)).into_owned();
    // [input][output] = E[conj(U_i) Y_k]
    let guy = s.view((0, q), (q, m - q)).into_owned();
    // G_uu is Hermitian positive semi-definite: its eigenvalues give the conditioning
    let eig = limpid_core::linalg::symmetric_eigenvalues(guu.clone())?;
    let (lo, hi) = (eig.min(), eig.max());
    if !(hi > 0.0 && lo > 1e-12 * hi) {
        return None;
    }
    let inv = guu.try_inverse()?;
    let ht = &inv * &guy; // = H^T
    let h = ht.transpose();
    let outputs = m - q;
    let mut multiple = Vec::with_capacity(outputs);
    let mut partial = vec![vec![0.0; q]; outputs];
    for k in 0..outputs {
        let gyy = s[(q + k, q + k)].re;
        let col = guy.column(k);
        let explained = (col.adjoint() * &inv * col)[(0, 0)].re;
        multiple.push(if gyy > 0.0 {
            (explained / gyy).clamp(0.0, 1.0)
        } else {
            0.0
        });
        for i in 0..q {
            // condition input i and output k on the other inputs
            let rest: Vec<usize> = (0..q).filter(|&j| j != i).collect();
            let (gii, gkk, gik) = if rest.is_empty() {
                (s[(i, i)], s[(q + k, q + k)], s[(i, q + k)])
            } else {
                let r = rest.len();
                let grr = DMatrix::from_fn(r, r, |a, b| s[(rest[a], rest[b])]);
                let grr_inv = grr.try_inverse()?;
                let g_a_r = |a: usize| DMatrix::from_fn(1, r, |_, b| s[(a, rest[b])]);
                let g_r_b = |b: usize| DMatrix::from_fn(r, 1, |a, _| s[(rest[a], b)]);
                let cond =
                    |a: usize, b: usize| s[(a, b)] - (g_a_r(a) * &grr_inv * g_r_b(b))[(0, 0)];
                (cond(i, i), cond(q + k, q + k), cond(i, q + k))
            };
            partial[k][i] = squared_coherence(gii.re, gkk.re, gik).clamp(0.0, 1.0);
        }
    }
    Some(MimoPoint {
        h,
        multiple,
        partial,
    })
}
