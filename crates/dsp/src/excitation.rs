//! Periodic perturbation signals (issue 59): pseudo-random binary sequences
//! and multisines with a low crest factor, as frequency-domain system
//! identification uses them (Pintelon & Schoukens, *System Identification:
//! a Frequency Domain Approach*, ch. 5; REKLAB's ankle PRBS).
//!
//! - [`mls`]: a maximum-length sequence of register order n (period
//!   2^n - 1 chips) from a Fibonacci shift register with a primitive
//!   feedback polynomial; its levels are ±1.
//! - [`multisine_lines`]: the DFT lines of one period (frequency resolution
//!   1/period) inside a band, all of them (`full`), the odd ones (`odd`:
//!   even nonlinearities fall on the even lines, which stay empty), or the
//!   odd ones less one in each group of three chosen at random
//!   (`random-odd`: odd nonlinearities show at the odd lines left out).
//! - [`optimise_phases`]: phases that minimise the crest factor, by descent
//!   on the Lp norm of the period for p = 4, 8, ..., 512 (Guillaume et al.
//!   1991's approach to the L∞ norm), from Schroeder's phases; 196 flat lines
//!   reach a crest factor of about 1.40 (Schroeder's 1.90, random 3.2).
//! - [`multisine`]: one period of the signal, sum of cosines at the lines.
//!
//! Conventions: a line `k` is the frequency `k / period`; a period holds
//! `n` samples; amplitudes are of the cosines (a line of amplitude a adds
//! a²/2 to the mean square).

use std::f64::consts::PI;

use limpid_core::{Error, Result};
use num_complex::Complex64;
use realfft::RealFftPlanner;

/// Register orders with a primitive feedback polynomial here.
pub const MLS_ORDERS: std::ops::RangeInclusive<usize> = 2..=24;

/// Taps (1-based register positions) of a primitive polynomial per order.
fn mls_taps(order: usize) -> Option<&'static [usize]> {
    Some(match order {
        2 => &[2, 1],
        3 => &[3, 2],
        4 => &[4, 3],
        5 => &[5, 3],
        6 => &[6, 5],
        7 => &[7, 6],
        8 => &[8, 6, 5, 4],
        9 => &[9, 5],
        10 => &[10, 7],
        11 => &[11, 9],
        12 => &[12, 6, 4, 1],
        13 => &[13, 4, 3, 1],
        14 => &[14, 5, 3, 1],
        15 => &[15, 14],
        16 => &[16, 15, 13, 4],
        17 => &[17, 14],
        18 => &[18, 11],
        19 => &[19, 6, 2, 1],
        20 => &[20, 17],
        21 => &[21, 19],
        22 => &[22, 21],
        23 => &[23, 18],
        24 => &[24, 23, 22, 17],
        _ => return None,
    })
}

/// One period (2^order - 1 chips) of a maximum-length sequence, levels ±1.
pub fn mls(order: usize) -> Result<Vec<f64>> {
    let taps = mls_taps(order).ok_or_else(|| {
        Error::invalid(
            "order",
            format!(
                "a PRBS register order from {} to {}, found {order}",
                MLS_ORDERS.start(),
                MLS_ORDERS.end()
            ),
        )
    })?;
    let len = (1usize << order) - 1;
    let mut state: u32 = 1;
    let mut out = Vec::with_capacity(len);
    for _ in 0..len {
        let bit = taps
            .iter()
            // stage t of the register (1 takes the feedback) is bit order - t here
            .fold(0u32, |acc, &t| acc ^ ((state >> (order - t)) & 1));
        out.push(if state & 1 == 1 { 1.0 } else { -1.0 });
        state = (state >> 1) | (bit << (order - 1));
    }
    Ok(out)
}

/// Register orders of the ternary sequence [`prts`].
pub const PRTS_ORDERS: std::ops::RangeInclusive<usize> = 2..=12;

/// One period (3^order - 1 chips) of a maximum-length pseudo-random ternary
/// sequence (PRTS), levels -1, 0, +1: the linear recurrence over GF(3)
/// `a_k = -(c_1 a_(k-1) + ... + c_n a_(k-n)) mod 3` of a primitive
/// polynomial, with 2 read as -1. Half a period on, the sequence is its own
/// negative (α^((3^n - 1) / 2) = -1 in GF(3^n)), so its spectrum holds the
/// odd harmonics of the period only and the even lines are left for even
/// nonlinear distortion (Godfrey's inverse-repeat property). The
/// polynomial is the first primitive one in lexicographic order of
/// (c_1, ..., c_n), found by the recurrence's period.
pub fn prts(order: usize) -> Result<Vec<f64>> {
    if !PRTS_ORDERS.contains(&order) {
        return Err(Error::invalid(
            "order",
            format!(
                "a PRTS register order from {} to {}, found {order}",
                PRTS_ORDERS.start(),
                PRTS_ORDERS.end()
            ),
        ));
    }
    let len = 3usize.pow(order as u32) - 1;
    // the recurrence from the state (1, 0, ..., 0); `None` unless its period is len
    let run = |c: &[u8]| -> Option<Vec<u8>> {
        let mut state = vec![0u8; order];
        state[0] = 1;
        let start = state.clone();
        let mut out = Vec::with_capacity(len);
        for k in 0..len {
            out.push(state[0]);
            let feedback = c.iter().zip(&state).map(|(&c, &a)| c * a).sum::<u8>() % 3;
            let next = (3 - feedback) % 3;
            state.rotate_left(1);
            state[order - 1] = next;
            if state == start && k + 1 < len {
                return None;
            }
        }
        (state == start).then_some(out)
    };
    // candidates (c_1, ..., c_n) in lexicographic order, c_n != 0
    let mut c = vec![0u8; order];
    for index in 0..3usize.pow(order as u32) {
        let mut rest = index;
        for digit in c.iter_mut().rev() {
            *digit = (rest % 3) as u8;
            rest /= 3;
        }
        if c[order - 1] == 0 {
            continue;
        }
        // the state is (a_(k-n), ..., a_(k-1)): c_n pairs with the oldest
        let taps: Vec<u8> = c.iter().rev().copied().collect();
        if let Some(seq) = run(&taps) {
            return Ok(seq
                .into_iter()
                .map(|a| match a {
                    0 => 0.0,
                    1 => 1.0,
                    _ => -1.0,
                })
                .collect());
        }
    }
    Err(Error::invalid(
        "order",
        format!("no primitive polynomial of order {order} over GF(3) was found"),
    ))
}

/// Which lines of the band a multisine excites.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum LineSet {
    /// Every line in the band.
    Full,
    /// The odd lines (odd multiples of 1/period).
    Odd,
    /// The odd lines less one in each consecutive group of three, at random.
    RandomOdd,
}

impl LineSet {
    /// From the protocol's name: `full`, `odd`, `random-odd`.
    pub fn parse(name: &str) -> Result<Self> {
        match name {
            "full" => Ok(LineSet::Full),
            "odd" => Ok(LineSet::Odd),
            "random-odd" => Ok(LineSet::RandomOdd),
            other => Err(Error::invalid(
                "lines",
                format!("expected full, odd or random-odd, found {other:?}"),
            )),
        }
    }
}

/// The DFT lines of a period of `period_s` inside `band_hz` (both ends
/// included), of the set asked for; `seed` chooses the lines a random-odd
/// set leaves out.
pub fn multisine_lines(
    period_s: f64,
    band_hz: [f64; 2],
    set: LineSet,
    seed: u64,
) -> Result<Vec<usize>> {
    if !(period_s.is_finite() && period_s > 0.0) {
        return Err(Error::invalid(
            "period_s",
            format!(
                "expected a positive period in s, found {}",
                limpid_core::error::Num(period_s)
            ),
        ));
    }
    let [lo, hi] = band_hz;
    if !(lo.is_finite() && hi.is_finite() && 0.0 < lo && lo <= hi) {
        return Err(Error::invalid(
            "band_hz",
            format!(
                "expected 0 < low <= high, found {} to {} Hz",
                limpid_core::error::Num(lo),
                limpid_core::error::Num(hi)
            ),
        ));
    }
    // a line is inside when its frequency is, to rounding
    let first = (lo * period_s - 1e-9).ceil().max(1.0) as usize;
    let last = (hi * period_s + 1e-9).floor() as usize;
    let all: Vec<usize> = (first..=last).collect();
    let lines: Vec<usize> = match set {
        LineSet::Full => all,
        LineSet::Odd => all.into_iter().filter(|k| k % 2 == 1).collect(),
        LineSet::RandomOdd => {
            let odd: Vec<usize> = all.into_iter().filter(|k| k % 2 == 1).collect();
            let mut state = seed ^ 0x9e37_79b9_7f4a_7c15;
            let mut next = move || {
                // xorshift64*: a reproducible choice, no dependency
                state ^= state >> 12;
                state ^= state << 25;
                state ^= state >> 27;
                state.wrapping_mul(0x2545_f491_4f6c_dd1d)
            };
            odd.chunks(3)
                .flat_map(|group| {
                    let drop = if group.len() == 3 {
                        Some((next() % 3) as usize)
                    } else {
                        None
                    };
                    group
                        .iter()
                        .enumerate()
                        .filter(move |(i, _)| Some(*i) != drop)
                        .map(|(_, k)| *k)
                        .collect::<Vec<_>>()
                })
                .collect()
        }
    };
    if lines.is_empty() {
        return Err(Error::invalid(
            "band_hz",
            format!(
                "no line of a {} s period (resolution {} Hz) lies in {} to {} Hz",
                limpid_core::error::Num(period_s),
                limpid_core::error::Num(1.0 / period_s),
                limpid_core::error::Num(lo),
                limpid_core::error::Num(hi)
            ),
        ));
    }
    Ok(lines)
}

/// One period of `n` samples: Σ a_k cos(2π k i / n + φ_k).
pub fn multisine(n: usize, lines: &[usize], amplitudes: &[f64], phases: &[f64]) -> Vec<f64> {
    let mut spectrum = vec![Complex64::new(0.0, 0.0); n / 2 + 1];
    for ((&k, &a), &p) in lines.iter().zip(amplitudes).zip(phases) {
        if k < spectrum.len() {
            // irfft of a one-sided spectrum: x_i = (1/n) Σ X_k e^{...}, twice for k in 1..n/2
            spectrum[k] = Complex64::from_polar(a * n as f64 / 2.0, p);
        }
    }
    inverse(n, spectrum)
}

fn inverse(n: usize, mut spectrum: Vec<Complex64>) -> Vec<f64> {
    let plan = RealFftPlanner::<f64>::new().plan_fft_inverse(n);
    let mut out = vec![0.0; n];
    // DC and (for even n) Nyquist must be real for the inverse real transform
    spectrum[0].im = 0.0;
    if n.is_multiple_of(2) {
        if let Some(last) = spectrum.last_mut() {
            last.im = 0.0;
        }
    }
    plan.process(&mut spectrum, &mut out)
        .expect("lengths agree with the plan");
    let scale = 1.0 / n as f64;
    out.iter_mut().for_each(|v| *v *= scale);
    out
}

/// The DFT of one period (unscaled: a cosine of amplitude a reads a n / 2 at its line).
pub fn period_spectrum(x: &[f64]) -> Vec<Complex64> {
    let plan = RealFftPlanner::<f64>::new().plan_fft_forward(x.len());
    let mut input = x.to_vec();
    let mut out = plan.make_output_vec();
    plan.process(&mut input, &mut out)
        .expect("lengths agree with the plan");
    out
}

/// The amplitude of each line of one period, `2 |X_k| / n` (a cosine of
/// amplitude a reads a at its line; the mean reads twice itself at line 0).
pub fn line_amplitudes(period: &[f64]) -> Vec<f64> {
    let n = period.len().max(1) as f64;
    period_spectrum(period)
        .iter()
        .map(|c| 2.0 * c.norm() / n)
        .collect()
}

/// Peak over root mean square.
pub fn crest_factor(x: &[f64]) -> f64 {
    let peak = x.iter().fold(0.0f64, |m, v| m.max(v.abs()));
    let rms = (x.iter().map(|v| v * v).sum::<f64>() / x.len().max(1) as f64).sqrt();
    if rms > 0.0 {
        peak / rms
    } else {
        f64::INFINITY
    }
}

/// Schroeder's phases for a flat spectrum: φ_j = -π j (j - 1) / K.
pub fn schroeder_phases(count: usize) -> Vec<f64> {
    let k = count as f64;
    (0..count)
        .map(|j| -PI * (j as f64 + 1.0) * j as f64 / k)
        .collect()
}

/// Schroeder's phases for lines of the given amplitudes:
/// `φ_k = -2π Σ_(l<k) (k - l) p_l`, p_l the line's share of the power
/// (Schroeder 1970); equal amplitudes give [`schroeder_phases`].
pub fn schroeder_phases_for(amplitudes: &[f64]) -> Vec<f64> {
    let first = amplitudes.first().copied().unwrap_or(0.0);
    if amplitudes.iter().all(|a| *a == first) {
        return schroeder_phases(amplitudes.len());
    }
    let total: f64 = amplitudes.iter().map(|a| a * a).sum();
    let shares: Vec<f64> = amplitudes.iter().map(|a| a * a / total).collect();
    (0..amplitudes.len())
        .map(|k| {
            -2.0 * PI
                * shares[..k]
                    .iter()
                    .enumerate()
                    .map(|(l, p)| (k - l) as f64 * p)
                    .sum::<f64>()
        })
        .collect()
}

/// Phases drawn uniformly in [0, 2π) from `seed` (xorshift: reproducible, no dependency).
pub fn random_phases(count: usize, seed: u64) -> Vec<f64> {
    let mut state = seed ^ 0x5851_f42d_4c95_7f2d;
    (0..count)
        .map(|_| {
            state ^= state << 13;
            state ^= state >> 7;
            state ^= state << 17;
            2.0 * PI * (state >> 11) as f64 / (1u64 << 53) as f64
        })
        .collect()
}

/// Samples of signal the phase optimisation may compute (evaluations x
/// period): about a second or two on one core. A period of 10^7 samples
/// took 518 s and a sample rate of 65535 Hz 57 s before (issue 76); the
/// presets' periods of 10^4 samples finish well within it.
pub const PHASE_WORK_SAMPLES: usize = 200_000_000;

/// Phases of the lines that make the period's crest factor low: descent on
/// the Lp norm of the signal (normalised by its RMS) for p doubling from 4
/// to 512, from Schroeder's phases; each step along the gradient, computed
/// with one FFT of `sign(x)|x|^(p-1)`, grows after a success and halves
/// after a failure. The work is bounded ([`PHASE_WORK_SAMPLES`]): a long
/// period stops early with the best phases found (Schroeder's at worst).
pub fn optimise_phases(n: usize, lines: &[usize], amplitudes: &[f64]) -> Vec<f64> {
    let mut phases = schroeder_phases_for(amplitudes);
    if lines.len() < 2 {
        return phases;
    }
    let mut evaluations_left = PHASE_WORK_SAMPLES / n.max(1);
    let mut planner = RealFftPlanner::<f64>::new();
    let forward = planner.plan_fft_forward(n);
    let backward = planner.plan_fft_inverse(n);
    let rms = (amplitudes.iter().map(|a| a * a / 2.0).sum::<f64>()).sqrt();
    let mut spectrum = forward.make_output_vec();
    let mut x = vec![0.0; n];
    // the normalised Lp norm (p = 2^exponent) and its gradient in the phases
    let mut norm_and_gradient = |phases: &[f64], exponent: u32| -> (f64, Vec<f64>) {
        // the multisine, by one inverse FFT (as `multisine`, planned once)
        spectrum
            .iter_mut()
            .for_each(|c| *c = Complex64::new(0.0, 0.0));
        for ((&k, &a), &ph) in lines.iter().zip(amplitudes).zip(phases) {
            if k < spectrum.len() {
                spectrum[k] = Complex64::from_polar(a / (2.0 * rms), ph);
            }
        }
        spectrum[0].im = 0.0;
        if let Some(last) = spectrum.last_mut().filter(|_| n.is_multiple_of(2)) {
            last.im = 0.0;
        }
        backward
            .process(&mut spectrum, &mut x)
            .expect("lengths agree with the plan");
        // x is now u = signal / rms; |u|^p by squaring, |u|^(p-1) = |u|^p / |u|
        let mut sum = 0.0;
        for v in x.iter_mut() {
            let a = v.abs();
            let mut power = a;
            for _ in 0..exponent {
                power *= power;
            }
            sum += power;
            *v = if a > 0.0 { v.signum() * power / a } else { 0.0 };
        }
        let p = f64::from(1u32 << exponent);
        let norm = (sum / n as f64).powf(1.0 / p);
        forward
            .process(&mut x, &mut spectrum)
            .expect("lengths agree with the plan");
        // d/dφ_k Σ g_i x_i = -a_k Im(e^{jφ_k} conj(G_k))
        let gradient = lines
            .iter()
            .zip(amplitudes)
            .zip(phases)
            .map(|((&k, &a), &ph)| -a * (Complex64::from_polar(1.0, ph) * spectrum[k].conj()).im)
            .collect();
        (norm, gradient)
    };
    for exponent in 2..=9 {
        if evaluations_left == 0 {
            break;
        }
        evaluations_left -= 1;
        let (mut value, mut gradient) = norm_and_gradient(&phases, exponent);
        let mut step = 0.1;
        for _ in 0..150 {
            let length = gradient.iter().map(|g| g * g).sum::<f64>().sqrt();
            if !(length > 0.0 && length.is_finite()) {
                break;
            }
            let mut improved = false;
            while step > 1e-6 && evaluations_left > 0 {
                evaluations_left -= 1;
                let trial: Vec<f64> = phases
                    .iter()
                    .zip(&gradient)
                    .map(|(ph, g)| ph - step * g / length)
                    .collect();
                let (v, g) = norm_and_gradient(&trial, exponent);
                if v < value {
                    (phases, value, gradient) = (trial, v, g);
                    step *= 1.5;
                    improved = true;
                    break;
                }
                step *= 0.5;
            }
            if !improved {
                break;
            }
        }
    }
    phases
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_cosine_reads_its_amplitude_at_its_line() {
        let n = 200;
        let x: Vec<f64> = (0..n)
            .map(|i| 0.3 * (std::f64::consts::TAU * 5.0 * i as f64 / n as f64 + 0.4).cos())
            .collect();
        let a = line_amplitudes(&x);
        assert!((a[5] - 0.3).abs() < 1e-12, "{}", a[5]);
        assert!(a.iter().enumerate().all(|(k, v)| k == 5 || *v < 1e-12));
    }

    #[test]
    fn ternary_sequences_repeat_inverted_and_hold_odd_harmonics_only() {
        for order in PRTS_ORDERS {
            let s = prts(order).unwrap();
            let n = s.len();
            assert_eq!(n, 3usize.pow(order as u32) - 1);
            // half a period on, the negative: only odd harmonics
            for k in 0..n / 2 {
                assert_eq!(s[k + n / 2], -s[k], "order {order}, chip {k}");
            }
            // balanced: 3^(n-1) of +1 and of -1, one zero fewer
            let ones = s.iter().filter(|v| **v == 1.0).count();
            let zeros = s.iter().filter(|v| **v == 0.0).count();
            assert_eq!(ones, 3usize.pow(order as u32 - 1), "order {order}");
            assert_eq!(zeros, 3usize.pow(order as u32 - 1) - 1, "order {order}");
            if order <= 8 {
                let spectrum = period_spectrum(&s);
                let peak = spectrum.iter().map(|c| c.norm()).fold(0.0, f64::max);
                for (k, c) in spectrum.iter().enumerate() {
                    if k % 2 == 0 {
                        assert!(c.norm() < 1e-9 * peak, "order {order}: line {k}");
                    } else {
                        assert!(c.norm() > 1e-3 * peak, "order {order}: odd line {k} empty");
                    }
                }
            }
        }
        assert!(prts(13).is_err() && prts(1).is_err());
    }

    #[test]
    fn maximum_length_sequences_have_their_period_and_balance() {
        for order in 2..=16 {
            let s = mls(order).unwrap();
            let len = (1usize << order) - 1;
            assert_eq!(s.len(), len);
            // 2^(n-1) ones and 2^(n-1) - 1 minus-ones
            let ones = s.iter().filter(|v| **v > 0.0).count();
            assert_eq!(ones, 1 << (order - 1), "order {order}");
            // two-valued autocorrelation: len at lag 0, -1 at every other lag
            for lag in [1, 2, len / 3, len - 1] {
                let r: f64 = (0..len).map(|i| s[i] * s[(i + lag) % len]).sum();
                assert_eq!(r, -1.0, "order {order}, lag {lag}");
            }
        }
        assert!(mls(1).is_err() && mls(25).is_err());
    }

    #[test]
    fn line_sets_fall_in_the_band_and_leave_detection_lines() {
        let full = multisine_lines(10.0, [0.5, 20.0], LineSet::Full, 1).unwrap();
        assert_eq!((full.len(), full[0], *full.last().unwrap()), (196, 5, 200));
        let odd = multisine_lines(10.0, [0.5, 20.0], LineSet::Odd, 1).unwrap();
        assert!(odd.iter().all(|k| k % 2 == 1) && odd.len() == 98);
        let random = multisine_lines(10.0, [0.5, 20.0], LineSet::RandomOdd, 1).unwrap();
        assert!(random.iter().all(|k| k % 2 == 1));
        // one of each three odd lines left out
        assert_eq!(random.len(), 98 - 98 / 3);
        let other = multisine_lines(10.0, [0.5, 20.0], LineSet::RandomOdd, 2).unwrap();
        assert_ne!(random, other);
        assert!(multisine_lines(1.0, [0.2, 0.4], LineSet::Full, 1).is_err());
    }

    #[test]
    fn the_synthesised_period_has_its_lines_and_power() {
        let n = 1000;
        let lines = [3, 7, 11];
        let amplitudes = [1.0, 0.5, 0.25];
        let x = multisine(n, &lines, &amplitudes, &[0.3, -1.0, 2.0]);
        let direct: f64 = (0..lines.len())
            .map(|j| {
                amplitudes[j]
                    * (2.0 * PI * lines[j] as f64 * 17.0 / n as f64 + [0.3, -1.0, 2.0][j]).cos()
            })
            .sum();
        assert!((x[17] - direct).abs() < 1e-12);
        let ms: f64 = x.iter().map(|v| v * v).sum::<f64>() / n as f64;
        assert!((ms - (1.0 + 0.25 + 0.0625) / 2.0).abs() < 1e-12);
    }

    /// Issue 59: a flat 0.5-20 Hz multisine at 1 kHz with a 10 s period
    /// (196 lines) reaches a crest factor of at most 1.45 (random phases
    /// give about 3, Schroeder's about 1.9).
    #[test]
    fn optimised_phases_give_a_crest_factor_below_1_45() {
        let n = 10_000;
        let lines = multisine_lines(10.0, [0.5, 20.0], LineSet::Full, 1).unwrap();
        let amplitudes = vec![1.0; lines.len()];
        let schroeder = crest_factor(&multisine(
            n,
            &lines,
            &amplitudes,
            &schroeder_phases(lines.len()),
        ));
        assert!((1.7..2.0).contains(&schroeder), "{schroeder}");
        let phases = optimise_phases(n, &lines, &amplitudes);
        let x = multisine(n, &lines, &amplitudes, &phases);
        let cf = crest_factor(&x);
        assert!(cf <= 1.45, "crest factor {cf}");
        // the spectrum is untouched: same lines, same amplitudes
        let mut planner = RealFftPlanner::<f64>::new();
        let fft = planner.plan_fft_forward(n);
        let mut input = x.clone();
        let mut spectrum = fft.make_output_vec();
        fft.process(&mut input, &mut spectrum).unwrap();
        for (k, c) in spectrum.iter().enumerate() {
            let a = 2.0 * c.norm() / n as f64;
            let want = if lines.contains(&k) { 1.0 } else { 0.0 };
            assert!((a - want).abs() < 1e-9, "line {k}: {a}");
        }
    }
}
