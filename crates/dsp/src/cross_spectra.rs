//! Welch cross-spectra of many signal pairs at once, in the generality of
//! `scipy.signal.csd` (scipy >= 1.17, which computes it through
//! `ShortTimeFFT.spectrogram`): any real window, zero-padded FFT length
//! `nfft >= nperseg`, one- or two-sided spectra, real or complex signals,
//! mean or bias-corrected median average (Allen et al., FINDCHIRP, App. B,
//! as scipy's `_median_bias`). The Python package's `psd`, `csd` and
//! `coherence` run on this; N-D inputs arrive as rows and index pairs.
//!
//! `P_ab[f] = avg_segments conj(A_s[f]) B_s[f] * scale`, scale
//! `1 / (fs sum w^2)` (density) or `1 / (sum w)^2` (spectrum); one-sided
//! values are doubled except at 0 Hz and, for even `nfft`, Nyquist.
//!
//! Segments are processed in parallel chunks; each segment's FFT of every
//! row is computed once and reused by every pair (a 9-channel spectral
//! matrix costs 9 FFTs per segment, not 81). Chunk sums are added in chunk
//! order, so results do not depend on scheduling.

use num_complex::Complex64;
use rayon::prelude::*;
use realfft::{RealFftPlanner, RealToComplex};
use rustfft::{Fft, FftPlanner};
use std::sync::Arc;

use crate::spectral::{Detrend, Scaling};
use limpid_core::{Error, Result};

/// Equally long signals stored row after row (`len` samples each).
#[derive(Debug, Clone, Copy)]
pub enum Rows<'a> {
    /// Real samples.
    Real(&'a [f64]),
    /// Complex samples.
    Complex(&'a [Complex64]),
}

impl Rows<'_> {
    fn total(&self) -> usize {
        match self {
            Rows::Real(v) => v.len(),
            Rows::Complex(v) => v.len(),
        }
    }
}

/// How segment estimates are averaged.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Average {
    /// Arithmetic mean (Welch).
    Mean,
    /// Median of real and imaginary parts, divided by the median's bias
    /// relative to the mean of exponentially distributed periodograms.
    Median,
}

/// Settings of [`cross_spectra`].
#[derive(Debug, Clone)]
pub struct Settings<'a> {
    /// Sample rate (Hz), for the density scale.
    pub fs: f64,
    /// Window samples; their count is the segment length `nperseg`.
    pub window: &'a [f64],
    /// Samples between segment starts (`nperseg - noverlap`).
    pub hop: usize,
    /// FFT length (>= `nperseg`; zero padding).
    pub nfft: usize,
    /// One-sided spectrum (real signals only).
    pub onesided: bool,
    /// Trend removed from each segment before windowing.
    pub detrend: Detrend,
    /// Density or spectrum.
    pub scaling: Scaling,
    /// Mean or median over segments.
    pub average: Average,
}

impl Settings<'_> {
    /// Frequency bins of the result.
    pub fn bins(&self) -> usize {
        if self.onesided {
            self.nfft / 2 + 1
        } else {
            self.nfft
        }
    }
}

/// scipy's `_median_bias(n)`: expected median / mean of `n` periodograms.
pub fn median_bias(n: usize) -> f64 {
    let half = n.saturating_sub(1) / 2;
    1.0 + (1..=half)
        .map(|i| {
            let ii = 2.0 * i as f64;
            1.0 / (ii + 1.0) - 1.0 / ii
        })
        .sum::<f64>()
}

/// Cross-spectra of `pairs` of rows. Rows are numbered through `sources` in
/// order (the first source's rows, then the next source's, ...); every row
/// has `len` samples. Returns `pairs.len() * bins` values, pair after pair.
pub fn cross_spectra(
    sources: &[Rows<'_>],
    len: usize,
    pairs: &[(usize, usize)],
    s: &Settings<'_>,
) -> Result<Vec<Complex64>> {
    let nperseg = s.window.len();
    check(sources, len, pairs, s)?;
    let bins = s.bins();
    if pairs.is_empty() {
        return Ok(Vec::new());
    }
    let segments = (len - nperseg) / s.hop + 1;
    // the rows any pair uses, in one table of slots
    let mut slot_of = vec![usize::MAX; sources.iter().map(|r| r.total() / len.max(1)).sum()];
    let mut rows: Vec<RowRef<'_>> = Vec::new();
    let mut slot_pairs = Vec::with_capacity(pairs.len());
    for &(a, b) in pairs {
        for r in [a, b] {
            if slot_of[r] == usize::MAX {
                slot_of[r] = rows.len();
                rows.push(row(sources, len, r));
            }
        }
        slot_pairs.push((slot_of[a], slot_of[b]));
    }
    let kernel = Kernel::new(s, bins);
    let chunk = segments
        .div_ceil(4 * rayon::current_num_threads().max(1))
        .clamp(1, 256);
    let chunks: Vec<std::ops::Range<usize>> = (0..segments)
        .step_by(chunk)
        .map(|c| c..(c + chunk).min(segments))
        .collect();
    let mut out = match s.average {
        Average::Mean => {
            let sums: Vec<Vec<Complex64>> = chunks
                .par_iter()
                .map(|range| {
                    let mut acc = vec![Complex64::new(0.0, 0.0); slot_pairs.len() * bins];
                    kernel.run(&rows, &slot_pairs, range.clone(), |_, p, k, v| {
                        acc[p * bins + k] += v;
                    });
                    acc
                })
                .collect();
            let mut total = vec![Complex64::new(0.0, 0.0); slot_pairs.len() * bins];
            for part in &sums {
                for (t, v) in total.iter_mut().zip(part) {
                    *t += v;
                }
            }
            let m = segments as f64;
            total.iter_mut().for_each(|v| *v /= m);
            total
        }
        Average::Median => {
            // every segment's value kept: [pair][bin][segment]
            let per: Vec<(usize, Vec<Complex64>)> = chunks
                .par_iter()
                .map(|range| {
                    let width = range.len();
                    let mut vals = vec![Complex64::new(0.0, 0.0); slot_pairs.len() * bins * width];
                    let start = range.start;
                    kernel.run(&rows, &slot_pairs, range.clone(), |seg, p, k, v| {
                        vals[(p * bins + k) * width + (seg - start)] = v;
                    });
                    (start, vals)
                })
                .collect();
            let bias = if segments > 1 {
                median_bias(segments)
            } else {
                1.0
            };
            (0..slot_pairs.len() * bins)
                .into_par_iter()
                .map_with(
                    (Vec::with_capacity(segments), Vec::with_capacity(segments)),
                    |(re, im), cell| {
                        re.clear();
                        im.clear();
                        for (_, vals) in &per {
                            let width = vals.len() / (slot_pairs.len() * bins);
                            for v in &vals[cell * width..(cell + 1) * width] {
                                re.push(v.re);
                                im.push(v.im);
                            }
                        }
                        Complex64::new(median(re), median(im)) / bias
                    },
                )
                .collect()
        }
    };
    let base = match s.scaling {
        Scaling::Density => 1.0 / (s.fs * s.window.iter().map(|w| w * w).sum::<f64>()),
        Scaling::Spectrum => 1.0 / s.window.iter().sum::<f64>().powi(2),
    };
    let doubled = if s.onesided {
        1..if s.nfft.is_multiple_of(2) {
            bins - 1
        } else {
            bins
        }
    } else {
        0..0
    };
    for p in 0..pairs.len() {
        for (k, v) in out[p * bins..(p + 1) * bins].iter_mut().enumerate() {
            *v *= if doubled.contains(&k) {
                2.0 * base
            } else {
                base
            };
        }
    }
    Ok(out)
}

fn check(
    sources: &[Rows<'_>],
    len: usize,
    pairs: &[(usize, usize)],
    s: &Settings<'_>,
) -> Result<()> {
    let nperseg = s.window.len();
    let bad = |what: &str, msg: String| Err(Error::invalid(what, msg));
    if nperseg == 0 || nperseg > len {
        return bad(
            "segment length",
            format!("expected 1 to {len} samples (the signal length), found {nperseg}"),
        );
    }
    if s.hop == 0 || s.hop > nperseg {
        return bad(
            "overlap",
            format!("the hop must be 1 to {nperseg}, found {}", s.hop),
        );
    }
    if s.nfft < nperseg {
        return bad(
            "nfft",
            format!("must be at least nperseg = {nperseg}, found {}", s.nfft),
        );
    }
    if !(s.fs.is_finite() && s.fs > 0.0) {
        return bad(
            "sample rate",
            format!("expected a positive rate, found {}", s.fs),
        );
    }
    let total: usize = sources.iter().map(|r| r.total()).sum();
    if sources.iter().any(|r| r.total() % len != 0) {
        return bad("signals", format!("rows must all have {len} samples"));
    }
    let rows = total / len;
    if let Some(&(a, b)) = pairs.iter().find(|&&(a, b)| a >= rows || b >= rows) {
        return bad(
            "pairs",
            format!("pair ({a}, {b}) names a row beyond the {rows} given"),
        );
    }
    if s.onesided && sources.iter().any(|r| matches!(r, Rows::Complex(_))) {
        return bad("sides", "a one-sided spectrum needs real signals".into());
    }
    Ok(())
}

#[derive(Clone, Copy)]
enum RowRef<'a> {
    Real(&'a [f64]),
    Complex(&'a [Complex64]),
}

fn row<'a>(sources: &[Rows<'a>], len: usize, mut r: usize) -> RowRef<'a> {
    for src in sources {
        let n = src.total() / len;
        if r < n {
            return match src {
                Rows::Real(v) => RowRef::Real(&v[r * len..(r + 1) * len]),
                Rows::Complex(v) => RowRef::Complex(&v[r * len..(r + 1) * len]),
            };
        }
        r -= n;
    }
    unreachable!("row index checked against the sources")
}

/// FFT plans and settings shared by the chunks.
struct Kernel<'s> {
    s: &'s Settings<'s>,
    bins: usize,
    real: Arc<dyn RealToComplex<f64>>,
    complex: Arc<dyn Fft<f64>>,
}

impl<'s> Kernel<'s> {
    fn new(s: &'s Settings<'s>, bins: usize) -> Self {
        Kernel {
            s,
            bins,
            real: RealFftPlanner::<f64>::new().plan_fft_forward(s.nfft),
            complex: FftPlanner::<f64>::new().plan_fft_forward(s.nfft),
        }
    }

    /// For each segment in `range`, the spectrum of every row, then
    /// `emit(segment, pair, bin, conj(A) B)` for every pair.
    fn run(
        &self,
        rows: &[RowRef<'_>],
        pairs: &[(usize, usize)],
        range: std::ops::Range<usize>,
        mut emit: impl FnMut(usize, usize, usize, Complex64),
    ) {
        let (s, bins, nfft) = (self.s, self.bins, self.s.nfft);
        let nperseg = s.window.len();
        let mut spectra = vec![Complex64::new(0.0, 0.0); rows.len() * bins];
        let mut real_in = self.real.make_input_vec();
        let mut real_out = self.real.make_output_vec();
        let mut real_scratch = self.real.make_scratch_vec();
        let mut cbuf = vec![Complex64::new(0.0, 0.0); nfft];
        let mut cscratch = vec![Complex64::new(0.0, 0.0); self.complex.get_inplace_scratch_len()];
        for seg in range {
            let at = seg * s.hop;
            for (r, row) in rows.iter().enumerate() {
                let dest = &mut spectra[r * bins..(r + 1) * bins];
                match row {
                    RowRef::Real(x) => {
                        let x = &x[at..at + nperseg];
                        let (mean, slope) = trend(x.len(), |i| x[i], s.detrend);
                        let mid = (nperseg as f64 - 1.0) / 2.0;
                        for (i, v) in real_in[..nperseg].iter_mut().enumerate() {
                            *v = (x[i] - mean - slope * (i as f64 - mid)) * s.window[i];
                        }
                        real_in[nperseg..].iter_mut().for_each(|v| *v = 0.0);
                        // realfft only errs on buffer lengths, which the plan made
                        let _ = self.real.process_with_scratch(
                            &mut real_in,
                            &mut real_out,
                            &mut real_scratch,
                        );
                        let half = real_out.len();
                        dest[..half.min(bins)].copy_from_slice(&real_out[..half.min(bins)]);
                        // two-sided spectrum of a real signal: the mirror half
                        for k in half..bins {
                            dest[k] = real_out[nfft - k].conj();
                        }
                    }
                    RowRef::Complex(x) => {
                        let x = &x[at..at + nperseg];
                        let (mr, sr) = trend(x.len(), |i| x[i].re, s.detrend);
                        let (mi, si) = trend(x.len(), |i| x[i].im, s.detrend);
                        let mid = (nperseg as f64 - 1.0) / 2.0;
                        for (i, v) in cbuf[..nperseg].iter_mut().enumerate() {
                            let t = i as f64 - mid;
                            let d = Complex64::new(x[i].re - mr - sr * t, x[i].im - mi - si * t);
                            *v = d * s.window[i];
                        }
                        cbuf[nperseg..]
                            .iter_mut()
                            .for_each(|v| *v = Complex64::new(0.0, 0.0));
                        self.complex.process_with_scratch(&mut cbuf, &mut cscratch);
                        dest.copy_from_slice(&cbuf);
                    }
                }
            }
            for (p, &(a, b)) in pairs.iter().enumerate() {
                let (sa, sb) = (
                    &spectra[a * bins..(a + 1) * bins],
                    &spectra[b * bins..(b + 1) * bins],
                );
                for k in 0..bins {
                    emit(seg, p, k, sa[k].conj() * sb[k]);
                }
            }
        }
    }
}

/// Mean and least-squares slope (about the segment's middle) to subtract.
fn trend(n: usize, x: impl Fn(usize) -> f64, d: Detrend) -> (f64, f64) {
    match d {
        Detrend::None => (0.0, 0.0),
        Detrend::Constant => ((0..n).map(&x).sum::<f64>() / n as f64, 0.0),
        Detrend::Linear => {
            let mean = (0..n).map(&x).sum::<f64>() / n as f64;
            let mid = (n as f64 - 1.0) / 2.0;
            let (mut num, mut den) = (0.0, 0.0);
            for i in 0..n {
                let t = i as f64 - mid;
                num += t * (x(i) - mean);
                den += t * t;
            }
            (mean, if den > 0.0 { num / den } else { 0.0 })
        }
    }
}

/// `numpy.median`: the middle value (mean of the two middle ones for an
/// even count); NaN if any value is NaN.
fn median(v: &mut [f64]) -> f64 {
    let n = v.len();
    if n == 0 || v.iter().any(|x| x.is_nan()) {
        return f64::NAN;
    }
    let mid = n / 2;
    let (_, &mut upper, _) = v.select_nth_unstable_by(mid, f64::total_cmp);
    if n % 2 == 1 {
        upper
    } else {
        let lower = v[..mid].iter().copied().fold(f64::NEG_INFINITY, f64::max);
        0.5 * (lower + upper)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::spectral::{self, Welch, Window};

    fn signal(n: usize, seed: u64) -> Vec<f64> {
        let mut state = seed;
        (0..n)
            .map(|i| {
                state = state
                    .wrapping_mul(6364136223846793005)
                    .wrapping_add(1442695040888963407);
                ((state >> 11) as f64 / (1u64 << 53) as f64 - 0.5) + (i as f64 * 0.01).sin()
            })
            .collect()
    }

    fn settings(window: &[f64]) -> Settings<'_> {
        Settings {
            fs: 100.0,
            window,
            hop: window.len() / 2,
            nfft: window.len(),
            onesided: true,
            detrend: Detrend::Linear,
            scaling: Scaling::Density,
            average: Average::Mean,
        }
    }

    #[test]
    fn one_pair_equals_the_single_signal_welch() {
        let (x, y) = (signal(5000, 1), signal(5000, 2));
        let p = Welch {
            nperseg: 128,
            detrend: Detrend::Linear,
            window: Window::Hann,
            ..Welch::new(100.0)
        };
        let w = p.window_values();
        let both: Vec<f64> = x.iter().chain(&y).copied().collect();
        let got =
            cross_spectra(&[Rows::Real(&both)], 5000, &[(0, 1), (1, 1)], &settings(&w)).unwrap();
        let (_, pxy) = spectral::csd(&x, &y, &p).unwrap();
        let (_, pyy) = spectral::psd(&y, &p).unwrap();
        let bins = 65;
        for k in 0..bins {
            assert!((got[k] - pxy[k]).norm() <= 1e-12 * pxy[k].norm().max(1e-300) + 1e-18);
            assert!((got[bins + k].re - pyy[k]).abs() <= 1e-12 * pyy[k]);
            assert!(got[bins + k].im.abs() <= 1e-15 * pyy[k]);
        }
    }

    #[test]
    fn a_real_signal_as_complex_gives_the_two_sided_spectrum_of_the_real_path() {
        let x = signal(3000, 3);
        let xc: Vec<Complex64> = x.iter().map(|&v| Complex64::new(v, 0.0)).collect();
        let w = vec![1.0; 100];
        let s = Settings {
            onesided: false,
            nfft: 130,
            ..settings(&w)
        };
        let real = cross_spectra(&[Rows::Real(&x)], 3000, &[(0, 0)], &s).unwrap();
        let complex = cross_spectra(&[Rows::Complex(&xc)], 3000, &[(0, 0)], &s).unwrap();
        assert_eq!(real.len(), 130);
        for (a, b) in real.iter().zip(&complex) {
            assert!((a - b).norm() <= 1e-12 * b.norm().max(1e-12));
        }
        // Parseval on a two-sided density: the sum over bins times df equals the
        // mean windowed power divided by the window's power
        let one = cross_spectra(
            &[Rows::Real(&x)],
            3000,
            &[(0, 0)],
            &Settings {
                onesided: true,
                ..s.clone()
            },
        )
        .unwrap();
        let two_sided_total: f64 = real.iter().map(|v| v.re).sum();
        let one_sided_total: f64 = one.iter().map(|v| v.re).sum();
        assert!((two_sided_total - one_sided_total).abs() <= 1e-9 * two_sided_total);
    }

    #[test]
    fn median_of_identical_segments_is_their_value_over_the_bias() {
        // a periodic signal whose period is the hop: every segment is the same
        let x: Vec<f64> = (0..64 * 9).map(|i| ((i % 64) as f64 * 0.3).sin()).collect();
        let w = vec![1.0; 128];
        let s = Settings {
            hop: 64,
            detrend: Detrend::None,
            ..settings(&w)
        };
        let mean = cross_spectra(&[Rows::Real(&x)], x.len(), &[(0, 0)], &s).unwrap();
        let med = cross_spectra(
            &[Rows::Real(&x)],
            x.len(),
            &[(0, 0)],
            &Settings {
                average: Average::Median,
                ..s.clone()
            },
        )
        .unwrap();
        let bias = median_bias(8);
        assert!(
            (bias - (1.0 - 1.0 / 2.0 + 1.0 / 3.0 - 1.0 / 4.0 + 1.0 / 5.0 - 1.0 / 6.0 + 1.0 / 7.0))
                .abs()
                < 1e-15
        );
        for (m, d) in mean.iter().zip(&med) {
            assert!((m / bias - d).norm() <= 1e-12 * m.norm().max(1e-300));
        }
    }

    #[test]
    fn bad_settings_are_errors() {
        let x = signal(100, 4);
        let w = vec![1.0; 50];
        let ok = settings(&w);
        assert!(cross_spectra(
            &[Rows::Real(&x)],
            100,
            &[(0, 0)],
            &Settings {
                nfft: 10,
                ..ok.clone()
            }
        )
        .is_err());
        assert!(cross_spectra(&[Rows::Real(&x)], 100, &[(0, 1)], &ok).is_err());
        assert!(cross_spectra(&[Rows::Real(&x)], 40, &[(0, 0)], &ok).is_err());
        assert!(cross_spectra(
            &[Rows::Real(&x)],
            100,
            &[(0, 0)],
            &Settings {
                hop: 0,
                ..ok.clone()
            }
        )
        .is_err());
        let c = vec![Complex64::new(1.0, 0.0); 100];
        assert!(cross_spectra(&[Rows::Complex(&c)], 100, &[(0, 0)], &ok).is_err());
    }
}
