//! Periodic analysis (issue 59; Pintelon & Schoukens, *System
//! Identification: a Frequency Domain Approach*, ch. 2-4): with a periodic
//! excitation, the DFT of whole periods has no leakage, the mean over
//! periods estimates each line, and the period-to-period scatter gives its
//! noise. From that:
//!
//! - the excited lines of each input (power within 30 dB of its strongest
//!   line);
//! - the frequency response at each input's excited lines, G = Ȳ/Ū, with
//!   its variance from the sample (co)variances of Ȳ and Ū (eq. 2-31:
//!   σ²_G = |G|² (σ²_Y/|Y|² + σ²_U/|U|² - 2 Re(σ²_YU / (Y Ū))));
//!   with several inputs each line must be excited by one input only
//!   (zippered multisines), so that G_{o,i} = Ȳ_o/Ū_i there;
//! - the output power at the lines between the lowest and highest excited
//!   line that no input excites: odd and even *detection lines*, where a
//!   linear system puts only noise and a nonlinear one its distortion
//!   (odd-order at odd lines, even-order at even lines, for odd and
//!   random-odd multisines), against the noise of the period average.
//!
//! Levels are in dB relative to the mean, over excited lines, of the output
//! power summed over outputs. The verdict is "nonlinear" when the mean
//! ratio of detection-line power to its own line's noise exceeds what
//! noise alone gives (an F(2, 2(m-1)) ratio per line) by four standard
//! errors of its mean and by 1 dB.

use limpid_core::{Error, Result};
use num_complex::Complex64;
use realfft::RealFftPlanner;

/// The period-averaged spectra of several signals.
#[derive(Debug, Clone)]
pub struct PeriodSpectra {
    /// Samples per period.
    pub period: usize,
    /// Whole periods averaged.
    pub periods: usize,
    /// `mean[signal][line]`: the mean over periods of each period's DFT
    /// (scaled so that a cosine of amplitude a reads a at its line).
    pub mean: Vec<Vec<Complex64>>,
    /// `per_period[signal][period][line]`, for the (co)variances.
    per_period: Vec<Vec<Vec<Complex64>>>,
}

impl PeriodSpectra {
    /// The spectra of `signals` cut into `periods` whole periods of
    /// `period` samples (signals at least that long; the rest is left out).
    pub fn new(signals: &[&[f64]], period: usize) -> Result<Self> {
        if period < 4 {
            return Err(Error::invalid(
                "period",
                format!("a period needs at least 4 samples, found {period}"),
            ));
        }
        let shortest = signals.iter().map(|s| s.len()).min().unwrap_or(0);
        let periods = shortest / period;
        if periods < 2 {
            return Err(Error::invalid(
                "period",
                format!(
                    "{periods} whole period(s) of {period} samples in {shortest}: the noise of the period average needs at least 2"
                ),
            ));
        }
        let fft = RealFftPlanner::<f64>::new().plan_fft_forward(period);
        let scale = 2.0 / period as f64;
        let per_period: Vec<Vec<Vec<Complex64>>> = signals
            .iter()
            .map(|s| {
                (0..periods)
                    .map(|p| {
                        let mut input = s[p * period..(p + 1) * period].to_vec();
                        let mut out = fft.make_output_vec();
                        fft.process(&mut input, &mut out)
                            .expect("lengths agree with the plan");
                        out.iter_mut().for_each(|c| *c *= scale);
                        out
                    })
                    .collect()
            })
            .collect();
        let lines = period / 2 + 1;
        let mean = per_period
            .iter()
            .map(|ps| {
                (0..lines)
                    .map(|k| ps.iter().map(|p| p[k]).sum::<Complex64>() / periods as f64)
                    .collect()
            })
            .collect();
        Ok(PeriodSpectra {
            period,
            periods,
            mean,
            per_period,
        })
    }

    /// Sample covariance of the period average of signals `a` and `b` at
    /// `line`: Σ (A_p - Ā)(B_p - B̄)* / (m (m - 1)).
    pub fn covariance_of_mean(&self, a: usize, b: usize, line: usize) -> Complex64 {
        let m = self.periods as f64;
        let (ma, mb) = (self.mean[a][line], self.mean[b][line]);
        self.per_period[a]
            .iter()
            .zip(&self.per_period[b])
            .map(|(pa, pb)| (pa[line] - ma) * (pb[line] - mb).conj())
            .sum::<Complex64>()
            / (m * (m - 1.0))
    }

    /// The spectra of `signals` (indices into these), in that order; a
    /// signal may appear twice (an input analysed as an output too).
    pub fn select(&self, signals: &[usize]) -> PeriodSpectra {
        PeriodSpectra {
            period: self.period,
            periods: self.periods,
            mean: signals.iter().map(|&s| self.mean[s].clone()).collect(),
            per_period: signals
                .iter()
                .map(|&s| self.per_period[s].clone())
                .collect(),
        }
    }

    /// Variance of the period average of signal `s` at `line`.
    pub fn variance_of_mean(&self, s: usize, line: usize) -> f64 {
        self.covariance_of_mean(s, s, line).re
    }
}

/// What a line is in a periodic experiment.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum LineKind {
    /// An input excites it.
    Excited,
    /// Odd line between the excited ones that no input excites.
    OddDetection,
    /// Even line between the excited ones that no input excites.
    EvenDetection,
}

impl LineKind {
    /// `excited`, `odd_detection`, `even_detection`.
    pub fn name(self) -> &'static str {
        match self {
            LineKind::Excited => "excited",
            LineKind::OddDetection => "odd_detection",
            LineKind::EvenDetection => "even_detection",
        }
    }
}

/// One line's levels.
#[derive(Debug, Clone, PartialEq)]
pub struct LineLevel {
    /// The line (frequency = line / period).
    pub line: usize,
    /// Excited or detection.
    pub kind: LineKind,
    /// The input exciting it (excited lines).
    pub input: Option<usize>,
    /// Output power summed over outputs, dB relative to the mean over excited lines.
    pub output_db: f64,
    /// The noise of that power's period average, same reference.
    pub noise_db: f64,
    /// Output power over its own noise (a ratio; about 1 for noise alone).
    pub ratio: f64,
}

/// The frequency response at one excited line.
#[derive(Debug, Clone, PartialEq)]
pub struct LineResponse {
    /// The line.
    pub line: usize,
    /// The exciting input.
    pub input: usize,
    /// G_{o,input} for each output.
    pub response: Vec<Complex64>,
    /// Its variance (of the complex value) for each output.
    pub variance: Vec<f64>,
}

/// Levels of the detection lines against noise, and the verdict.
#[derive(Debug, Clone, PartialEq)]
pub struct Distortion {
    /// Mean odd-detection power, dB relative to the excited lines' (None without odd detection lines).
    pub odd_db: Option<f64>,
    /// Mean even-detection power, same reference.
    pub even_db: Option<f64>,
    /// Mean noise of the period average over the analysed lines, same reference.
    pub noise_db: f64,
    /// Whether the odd detection lines do: odd distortion, which also falls
    /// on odd excited lines (the best linear approximation differs from the
    /// linear part there).
    pub odd_rises: bool,
    /// Whether the even detection lines do: even distortion, which falls on
    /// even lines only and leaves the response at odd excited lines alone.
    pub even_rises: bool,
}

impl Distortion {
    /// Whether any detection lines rise above the noise (see the module docs).
    pub fn nonlinear(&self) -> bool {
        self.odd_rises || self.even_rises
    }
}

/// The periodic analysis of inputs and outputs.
#[derive(Debug, Clone, PartialEq)]
pub struct PeriodicAnalysis {
    /// Every line from the lowest to the highest excited one, classified.
    pub lines: Vec<LineLevel>,
    /// The response at each excited line.
    pub responses: Vec<LineResponse>,
    /// Detection-line levels and the verdict; None when no line is left for detection.
    pub distortion: Option<Distortion>,
}

/// Excited lines: input power within 30 dB of that input's strongest line.
const EXCITED_BELOW_PEAK: f64 = 1e-3;
/// Output power this far below the excited lines' (200 dB) is rounding, not signal.
const EXACTLY_NOTHING: f64 = 1e-20;
/// An excited line belongs to one input when the others are 30 dB below it there.
const ONE_INPUT_RATIO: f64 = 1e3;

/// Analyse `spectra` whose first `inputs` signals are the inputs and the rest the outputs.
pub fn analyse(spectra: &PeriodSpectra, inputs: usize) -> Result<PeriodicAnalysis> {
    let signals = spectra.mean.len();
    if inputs == 0 || inputs >= signals {
        return Err(Error::invalid(
            "inputs/outputs",
            "name at least one input and one output",
        ));
    }
    let lines = spectra.period / 2 + 1;
    let power = |s: usize, k: usize| spectra.mean[s][k].norm_sqr();
    // each input's excited lines (DC never counts)
    let mut owner: Vec<Option<usize>> = vec![None; lines];
    for i in 0..inputs {
        let peak = (1..lines).map(|k| power(i, k)).fold(0.0f64, f64::max);
        if peak.is_nan() || peak <= 0.0 {
            return Err(Error::invalid(
                "inputs/outputs",
                format!("input {} has no power at any line of the period", i + 1),
            ));
        }
        for (k, slot) in owner.iter_mut().enumerate().skip(1) {
            if power(i, k) >= EXCITED_BELOW_PEAK * peak {
                match slot {
                    None => *slot = Some(i),
                    Some(j) => {
                        // shared: fine only if one input dominates the line
                        let j = *j;
                        let (pi, pj) = (power(i, k), power(j, k));
                        if pi > ONE_INPUT_RATIO * pj {
                            *slot = Some(i);
                        } else if pj <= ONE_INPUT_RATIO * pi {
                            return Err(Error::invalid(
                                "inputs/outputs",
                                format!(
                                    "inputs {} and {} both excite line {k}: a multi-input response from one periodic experiment needs each line excited by one input (zippered multisines)",
                                    j + 1,
                                    i + 1
                                ),
                            ));
                        }
                    }
                }
            }
        }
    }
    let excited: Vec<usize> = (1..lines).filter(|&k| owner[k].is_some()).collect();
    let (Some(&first), Some(&last)) = (excited.first(), excited.last()) else {
        return Err(Error::invalid("inputs/outputs", "no excited line"));
    };
    let outputs: Vec<usize> = (inputs..signals).collect();
    let output_power = |k: usize| outputs.iter().map(|&o| power(o, k)).sum::<f64>();
    let noise_power = |k: usize| {
        outputs
            .iter()
            .map(|&o| spectra.variance_of_mean(o, k))
            .sum::<f64>()
    };
    let reference = excited.iter().map(|&k| output_power(k)).sum::<f64>() / excited.len() as f64;
    if reference.is_nan() || reference <= 0.0 {
        return Err(Error::invalid(
            "inputs/outputs",
            "the outputs have no power at the excited lines",
        ));
    }
    let db = |p: f64| 10.0 * (p.max(f64::MIN_POSITIVE) / reference).log10();
    let mut levels = Vec::new();
    let mut responses = Vec::new();
    for (k, &owned) in owner.iter().enumerate().take(last + 1).skip(first) {
        let kind = match owned {
            Some(_) => LineKind::Excited,
            None if k % 2 == 1 => LineKind::OddDetection,
            None => LineKind::EvenDetection,
        };
        let (p, n) = (output_power(k), noise_power(k));
        levels.push(LineLevel {
            line: k,
            kind,
            input: owned,
            output_db: db(p),
            noise_db: db(n),
            // an output 200 dB below its excited lines is exactly periodic
            // and has nothing there (a noise-free signal whose rounding
            // repeats every period): no distortion, whatever its "noise"
            ratio: if p <= EXACTLY_NOTHING * reference {
                0.0
            } else if n > 0.0 {
                p / n
            } else {
                f64::INFINITY
            },
        });
        if let Some(i) = owned {
            let u = spectra.mean[i][k];
            let su = spectra.variance_of_mean(i, k);
            let (response, variance) = outputs
                .iter()
                .map(|&o| {
                    let y = spectra.mean[o][k];
                    let g = y / u;
                    let sy = spectra.variance_of_mean(o, k);
                    let syu = spectra.covariance_of_mean(o, i, k);
                    let v = g.norm_sqr()
                        * (sy / y.norm_sqr().max(f64::MIN_POSITIVE) + su / u.norm_sqr()
                            - 2.0 * (syu / (y * u.conj())).re);
                    (g, v.max(0.0))
                })
                .unzip();
            responses.push(LineResponse {
                line: k,
                input: i,
                response,
                variance,
            });
        }
    }
    let distortion = distortion(&levels, spectra.periods, &db, &noise_power, first..=last);
    Ok(PeriodicAnalysis {
        lines: levels,
        responses,
        distortion,
    })
}

/// Detection-line levels against noise (see the module docs for the test).
fn distortion(
    levels: &[LineLevel],
    periods: usize,
    db: &dyn Fn(f64) -> f64,
    noise_power: &dyn Fn(usize) -> f64,
    range: std::ops::RangeInclusive<usize>,
) -> Option<Distortion> {
    let mean_power = |kind: LineKind| -> Option<(f64, f64, usize)> {
        let chosen: Vec<&LineLevel> = levels.iter().filter(|l| l.kind == kind).collect();
        if chosen.is_empty() {
            return None;
        }
        let n = chosen.len() as f64;
        // back from dB: the mean power relative to the reference
        let power = chosen
            .iter()
            .map(|l| 10f64.powf(l.output_db / 10.0))
            .sum::<f64>()
            / n;
        let ratio = chosen.iter().map(|l| l.ratio.min(1e12)).sum::<f64>() / n;
        Some((power, ratio, chosen.len()))
    };
    let odd = mean_power(LineKind::OddDetection);
    let even = mean_power(LineKind::EvenDetection);
    if odd.is_none() && even.is_none() {
        return None;
    }
    let all: Vec<usize> = range.collect();
    let noise = all.iter().map(|&k| noise_power(k)).sum::<f64>() / all.len() as f64;
    // per line, |Ȳ|² / σ²_Ȳ of noise alone is F(2, 2(m - 1)) distributed
    let d2 = 2.0 * (periods as f64 - 1.0);
    let (mean_f, var_f) = if d2 > 4.0 {
        (
            d2 / (d2 - 2.0),
            2.0 * d2 * d2 * d2 / (2.0 * (d2 - 2.0).powi(2) * (d2 - 4.0)),
        )
    } else {
        // too few periods for the ratio's variance: only gross distortion counts
        (d2 / (d2 - 2.0).max(0.5), 100.0)
    };
    let rises = |m: Option<(f64, f64, usize)>| {
        m.is_some_and(|(_, ratio, count)| {
            let threshold = mean_f + 4.0 * (var_f / count as f64).sqrt();
            ratio > threshold && ratio > 10f64.powf(0.1) * mean_f
        })
    };
    Some(Distortion {
        odd_db: odd.map(|m| 10.0 * m.0.log10()),
        even_db: even.map(|m| 10.0 * m.0.log10()),
        noise_db: db(noise),
        odd_rises: rises(odd),
        even_rises: rises(even),
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::excitation::{multisine, multisine_lines, optimise_phases, LineSet};

    fn noise(seed: &mut u64) -> f64 {
        // sum of 12 uniforms - 6: close to a unit Gaussian
        (0..12)
            .map(|_| {
                *seed ^= *seed << 13;
                *seed ^= *seed >> 7;
                *seed ^= *seed << 17;
                (*seed >> 11) as f64 / (1u64 << 53) as f64
            })
            .sum::<f64>()
            - 6.0
    }

    /// A first-order system y[i] = a y[i-1] + b u[i] (+ c u[i]^2 + d u[i]^3)
    /// driven by a random-odd multisine: the response at excited lines,
    /// the noise level, and the verdict.
    fn experiment(c: f64, d: f64, sigma: f64) -> (PeriodicAnalysis, Vec<usize>, f64) {
        let (fs, period_s, periods) = (200.0, 5.0, 12);
        let n = (fs * period_s) as usize;
        let lines = multisine_lines(period_s, [0.4, 30.0], LineSet::RandomOdd, 3).unwrap();
        let amplitudes = vec![1.0; lines.len()];
        let phases = optimise_phases(n, &lines, &amplitudes);
        let one = multisine(n, &lines, &amplitudes, &phases);
        let rms = (one.iter().map(|v| v * v).sum::<f64>() / n as f64).sqrt();
        let u: Vec<f64> = (0..n * (periods + 1)).map(|i| one[i % n] / rms).collect();
        let (a, b) = (0.9, 0.1);
        let mut y = vec![0.0; u.len()];
        let mut seed = 7u64;
        let mut state = 0.0;
        for i in 0..u.len() {
            state = a * state + b * u[i] + c * u[i] * u[i] + d * u[i] * u[i] * u[i];
            y[i] = state + sigma * noise(&mut seed);
        }
        // the first period is the transient
        let spectra = PeriodSpectra::new(&[&u[n..], &y[n..]], n).unwrap();
        assert_eq!(spectra.periods, periods);
        (analyse(&spectra, 1).unwrap(), lines, (a, b).1)
    }

    #[test]
    fn the_response_of_a_linear_system_is_found_within_its_standard_errors() {
        let (result, lines, _) = experiment(0.0, 0.0, 0.01);
        let excited: Vec<usize> = result.responses.iter().map(|r| r.line).collect();
        assert_eq!(excited, lines);
        let mut covered = 0;
        for r in &result.responses {
            let w = 2.0 * std::f64::consts::PI * r.line as f64 / 1000.0;
            let z = Complex64::from_polar(1.0, -w);
            let truth = 0.1 / (1.0 - 0.9 * z);
            let err = (r.response[0] - truth).norm();
            assert!(
                err < 0.03 * truth.norm(),
                "line {}: {} vs {truth}",
                r.line,
                r.response[0]
            );
            covered += usize::from(err < 2.0 * (r.variance[0]).sqrt());
        }
        assert!(
            covered * 100 >= 80 * result.responses.len(),
            "{covered} of {}",
            result.responses.len()
        );
        let d = result.distortion.unwrap();
        assert!(!d.nonlinear(), "{d:?}");
    }

    #[test]
    fn even_and_odd_nonlinearities_show_at_their_detection_lines() {
        let (quadratic, _, _) = experiment(0.02, 0.0, 0.001);
        let d = quadratic.distortion.unwrap();
        assert!(d.nonlinear(), "{d:?}");
        assert!(d.even_db.unwrap() > d.noise_db + 10.0, "{d:?}");
        let (cubic, _, _) = experiment(0.0, 0.02, 0.001);
        let d = cubic.distortion.unwrap();
        assert!(d.nonlinear(), "{d:?}");
        assert!(d.odd_db.unwrap() > d.noise_db + 10.0, "{d:?}");
        // a cubic term puts (almost) nothing on the even lines
        assert!(d.odd_db.unwrap() > d.even_db.unwrap() + 10.0, "{d:?}");
    }

    #[test]
    fn too_few_periods_or_shared_lines_are_refused() {
        let x = vec![0.0; 150];
        assert!(PeriodSpectra::new(&[&x, &x], 100).is_err());
        let n = 100;
        let u = multisine(n, &[3, 5], &[1.0, 1.0], &[0.0, 0.0]);
        let u2: Vec<f64> = u.iter().map(|v| 0.5 * v).collect();
        let rep = |s: &[f64]| -> Vec<f64> { (0..4 * n).map(|i| s[i % n]).collect() };
        let (a, b) = (rep(&u), rep(&u2));
        let s = PeriodSpectra::new(&[&a, &b, &a], n).unwrap();
        let e = analyse(&s, 2).unwrap_err().to_string();
        assert!(e.contains("zippered"), "{e}");
    }
}
