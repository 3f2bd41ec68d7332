//! limpid-dsp: zero-phase low-pass filtering, numerical derivatives, Welch
//! spectral analysis ([`spectral`]), periodic perturbation signals
//! ([`excitation`]: PRBS, multisines) and their analysis ([`periodic`]).
//!
//! Seed 000 §II-C and seed 001 "Data Processing" low-pass and differentiate
//! positions; seed 001 eq. (1) low-passes rectified EMG with a 2nd-order
//! Butterworth at 8 Hz. Filter design and `sosfiltfilt` come from `sci-rs`
//! (checked against scipy values in `tests/scipy_fixtures.rs`); this crate
//! adds the argument checks that turn its panics into errors, and the
//! derivative schemes.
//!
//! Conventions: cut-off in Hz, sample interval in s; `filtfilt` pads with the
//! odd extension of length `3 * (2 * sections + 1)` exactly as
//! `scipy.signal.sosfiltfilt`; Savitzky-Golay edges use `mode='nearest'`.

#![warn(missing_docs)]

pub mod cross_spectra;
pub mod excitation;
pub mod periodic;
pub mod spectral;

use limpid_core::error::Num;
use limpid_core::{Error, Result};
use sci_rs::signal::filter::design::{
    butter_dyn, DigitalFilter, FilterBandType, FilterOutputType, Sos,
};

/// How a window is extended beyond its ends before zero-phase filtering.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Edge {
    /// Point reflection about the end sample (scipy's `padtype='odd'`).
    Odd,
    /// Mirror about the end sample (scipy's `padtype='even'`).
    Even,
}

/// How [`LowPass::filtfilt_into`] extends the signal before filtering
/// (scipy's `padtype`).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Pad {
    /// Point reflection about the end sample (`'odd'`, scipy's default).
    Odd,
    /// Mirror about the end sample (`'even'`).
    Even,
    /// The end sample repeated (`'constant'`).
    Constant,
    /// No extension (`padtype=None`).
    None,
}

/// A designed zero-phase low-pass filter (second-order sections).
#[derive(Debug, Clone)]
pub struct LowPass {
    sos: Vec<Sos<f64>>,
    order: usize,
    cutoff_hz: f64,
}

impl LowPass {
    /// Butterworth low-pass of `order` (1..=20) at `cutoff_hz` for sample rate `fs_hz`.
    pub fn butterworth(order: usize, cutoff_hz: f64, fs_hz: f64) -> Result<Self> {
        if !(1..=20).contains(&order) {
            return Err(Error::invalid(
                "filter order",
                format!("expected 1 to 20, found {order}"),
            ));
        }
        if !(fs_hz.is_finite() && fs_hz > 0.0) {
            return Err(Error::invalid(
                "sample rate",
                format!(
                    "expected a finite positive rate in Hz, found {}",
                    Num(fs_hz)
                ),
            ));
        }
        let nyquist = limpid_core::display_round(fs_hz / 2.0);
        if !(cutoff_hz > 0.0 && cutoff_hz < nyquist) {
            return Err(Error::invalid(
                "cutoff_hz",
                format!(
                    "expected 0 < cut-off < {} Hz (Nyquist), found {} Hz",
                    Num(nyquist),
                    Num(cutoff_hz)
                ),
            ));
        }
        // sci-rs asserts (panics) on cut-offs that underflow its pole placement
        if cutoff_hz / nyquist < 1e-6 {
            return Err(Error::invalid(
                "cutoff_hz",
                format!(
                    "{} Hz is below 1e-6 of the Nyquist frequency {} Hz: no usable filter",
                    Num(cutoff_hz),
                    Num(nyquist)
                ),
            ));
        }
        let design = std::panic::catch_unwind(|| {
            butter_dyn(
                order,
                vec![cutoff_hz],
                Some(FilterBandType::Lowpass),
                Some(false),
                Some(FilterOutputType::Sos),
                Some(fs_hz),
            )
        });
        let Ok(DigitalFilter::Sos(sos)) = design else {
            return Err(Error::invalid(
                "filter",
                format!(
                    "no Butterworth design for order {order}, {} Hz at {} Hz (sci-rs returned no second-order sections)",
                    Num(cutoff_hz),
                    Num(fs_hz)
                ),
            ));
        };
        let finite = sos
            .sos
            .iter()
            .all(|s| s.b.iter().chain(&s.a).all(|v| v.is_finite()));
        if !finite {
            return Err(Error::invalid(
                "cutoff_hz",
                format!(
                    "{} Hz at {} Hz sampling gives no usable filter (too close to 0 or to Nyquist)",
                    Num(cutoff_hz),
                    Num(fs_hz)
                ),
            ));
        }
        Ok(LowPass {
            sos: sos.sos,
            order,
            cutoff_hz,
        })
    }

    /// Filter order (per pass; zero-phase filtering doubles the effective order).
    pub fn order(&self) -> usize {
        self.order
    }
    /// Cut-off frequency in Hz (-3 dB per pass).
    pub fn cutoff_hz(&self) -> f64 {
        self.cutoff_hz
    }
    /// Number of samples of odd-extension padding (scipy's default `padlen`).
    pub fn padlen(&self) -> usize {
        let n = self.sos.len();
        let bzeros = self.sos.iter().filter(|s| s.b[2] == 0.0).count();
        let azeros = self.sos.iter().filter(|s| s.a[2] == 0.0).count();
        3 * (2 * n + 1 - bzeros.min(azeros))
    }

    /// Forward-backward (zero-phase) filtering, as `scipy.signal.sosfiltfilt`
    /// (odd extension of [`LowPass::padlen`] samples, each pass started in
    /// the steady state of its first sample, as `sosfilt_zi`). One buffer,
    /// filtered in place forward then backward, all sections per sample.
    pub fn filtfilt(&self, x: &[f64]) -> Result<Vec<f64>> {
        self.filtfilt_padded(x, Pad::Odd, self.padlen())
    }

    /// [`LowPass::filtfilt`] with scipy's `padtype` and `padlen`
    /// (`sosfiltfilt(sos, x, padtype=..., padlen=...)`). The signal must be
    /// longer than `padlen` ([`Pad::None`] pads nothing).
    pub fn filtfilt_padded(&self, x: &[f64], pad: Pad, padlen: usize) -> Result<Vec<f64>> {
        let (mut y, padlen) = self.filtered_buffer(x, pad, padlen)?;
        // the filtered signal moved to the front of its own buffer: no second allocation
        y.copy_within(padlen..padlen + x.len(), 0);
        y.truncate(x.len());
        Ok(y)
    }

    /// [`LowPass::filtfilt_padded`] written into `out` (as long as `x`).
    pub fn filtfilt_into(&self, x: &[f64], pad: Pad, padlen: usize, out: &mut [f64]) -> Result<()> {
        if out.len() != x.len() {
            return Err(Error::invalid(
                "output",
                format!("expected {} samples of room, found {}", x.len(), out.len()),
            ));
        }
        let (y, padlen) = self.filtered_buffer(x, pad, padlen)?;
        out.copy_from_slice(&y[padlen..padlen + x.len()]);
        Ok(())
    }

    /// The extended signal, filtered forward then backward (each pass started
    /// in the steady state of its first sample, as `sosfilt_zi`), and the
    /// extension length per end.
    fn filtered_buffer(&self, x: &[f64], pad: Pad, padlen: usize) -> Result<(Vec<f64>, usize)> {
        let n = x.len();
        let padlen = if pad == Pad::None { 0 } else { padlen };
        if n <= padlen {
            return Err(Error::invalid(
                "signal length",
                format!(
                    "zero-phase filtering needs more than padlen = {padlen} samples, found {n}"
                ),
            ));
        }
        let sections = self.sections();
        let zi = steady_state(&sections);
        let (first, last) = (x[0], x[n - 1]);
        let mut y = Vec::with_capacity(n + 2 * padlen);
        y.extend((1..=padlen).rev().map(|i| match pad {
            Pad::Odd => 2.0 * first - x[i],
            Pad::Even => x[i],
            Pad::Constant | Pad::None => first,
        }));
        y.extend_from_slice(x);
        y.extend((1..=padlen).map(|i| match pad {
            Pad::Odd => 2.0 * last - x[n - 1 - i],
            Pad::Even => x[n - 1 - i],
            Pad::Constant | Pad::None => last,
        }));
        let start = y[0];
        run_sections(y.iter_mut(), &sections, &zi, start);
        let end = y[y.len() - 1];
        run_sections(y.iter_mut().rev(), &sections, &zi, end);
        Ok((y, padlen))
    }

    /// Sections normalised to `a0 = 1`: `([b0, b1, b2], [a1, a2])`.
    fn sections(&self) -> Vec<([f64; 3], [f64; 2])> {
        self.sos
            .iter()
            .map(|s| {
                let a0 = s.a[0];
                (
                    [s.b[0] / a0, s.b[1] / a0, s.b[2] / a0],
                    [s.a[1] / a0, s.a[2] / a0],
                )
            })
            .collect()
    }

    /// Zero-phase filtering after extending each end by its own reflection:
    /// [`Edge::Odd`] (point reflection, keeps the slope continuous) or
    /// [`Edge::Even`] (mirror, keeps the curvature continuous). `extra` samples
    /// are added per end before scipy's own odd padding; they are removed again.
    ///
    /// Why: a linear model `f = M x'' + B x' + K x` still holds between the
    /// filtered signals only if the extensions obey it too. A mirror obeys it
    /// where the window ends at zero velocity (any acceleration), a point
    /// reflection where it ends at zero acceleration.
    pub fn filtfilt_edges(
        &self,
        x: &[f64],
        left: Edge,
        right: Edge,
        extra: usize,
    ) -> Result<Vec<f64>> {
        let n = x.len();
        if n < 2 {
            return Err(Error::invalid(
                "signal length",
                format!("need at least 2 samples, found {n}"),
            ));
        }
        let e = extra.min(n - 1);
        let mut ext = Vec::with_capacity(n + 2 * e);
        for k in (1..=e).rev() {
            ext.push(match left {
                Edge::Odd => 2.0 * x[0] - x[k],
                Edge::Even => x[k],
            });
        }
        ext.extend_from_slice(x);
        for k in 1..=e {
            ext.push(match right {
                Edge::Odd => 2.0 * x[n - 1] - x[n - 1 - k],
                Edge::Even => x[n - 1 - k],
            });
        }
        let y = self.filtfilt(&ext)?;
        Ok(y[e..e + n].to_vec())
    }

    /// [`LowPass::filtfilt_edges`] of several signals of one window at once
    /// (same length, same edges): up to six signals are interleaved and
    /// filtered together, so the recursive sections run one lane per signal
    /// instead of waiting on one signal's dependency chain. Every lane does
    /// exactly the arithmetic of the one-signal call (equal results).
    pub fn filtfilt_edges_many(
        &self,
        xs: &[&[f64]],
        left: Edge,
        right: Edge,
        extra: usize,
    ) -> Result<Vec<Vec<f64>>> {
        let n = xs.first().map_or(0, |x| x.len());
        if n < 2 {
            return Err(Error::invalid(
                "signal length",
                format!("need at least 2 samples, found {n}"),
            ));
        }
        if xs.iter().any(|x| x.len() != n) {
            return Err(Error::invalid(
                "signal length",
                "signals filtered together must have one length",
            ));
        }
        let e = extra.min(n - 1);
        let pad = self.padlen();
        if n + 2 * e <= pad {
            return Err(Error::invalid(
                "signal length",
                format!(
                    "zero-phase filtering needs more than {pad} samples, found {}",
                    n + 2 * e
                ),
            ));
        }
        let layout = Padding {
            n,
            e,
            pad,
            left,
            right,
        };
        let sections = self.sections();
        let zi = steady_state(&sections);
        let mut out = Vec::with_capacity(xs.len());
        // up to six lanes: the three positions and three forces of a 3-D
        // window in one pass (a 4 + 2 split waited twice on the same latency)
        for group in xs.chunks(6) {
            match group.len() {
                1 => lanes::<1>(group, &layout, &sections, &zi, &mut out),
                2 => lanes::<2>(group, &layout, &sections, &zi, &mut out),
                3 => lanes::<3>(group, &layout, &sections, &zi, &mut out),
                4 => lanes::<4>(group, &layout, &sections, &zi, &mut out),
                5 => lanes::<5>(group, &layout, &sections, &zi, &mut out),
                _ => lanes::<6>(group, &layout, &sections, &zi, &mut out),
            }
        }
        Ok(out)
    }

    /// One causal pass, as `scipy.signal.sosfilt` with zero initial state.
    pub fn filter_causal(&self, x: &[f64]) -> Vec<f64> {
        let mut sos = self.sos.clone();
        sci_rs::signal::filter::sosfilt_dyn(x.iter(), &mut sos)
    }

    /// The causal filter one sample at a time, started in the steady state of
    /// a constant input `x0` (as `sosfilt` with `zi = sosfilt_zi * x0`): a
    /// signal that starts at `x0` shows no start-up transient.
    pub fn streaming_from(&self, x0: f64) -> StreamingFilter {
        let sections = self.sections();
        let state = steady_state(&sections)
            .iter()
            .map(|z| [z[0] * x0, z[1] * x0])
            .collect();
        StreamingFilter { sections, state }
    }

    /// The same causal filter, one sample at a time (live use): no allocation per sample.
    pub fn streaming(&self) -> StreamingFilter {
        StreamingFilter {
            sections: self.sections(),
            state: vec![[0.0; 2]; self.sos.len()],
        }
    }
}

/// `scipy.signal.sosfilt_zi`: per-section states of the steady state for a
/// unit input (transposed direct form II; `lfilter_zi` of each section,
/// scaled by the DC gain of the sections before it).
fn steady_state(sections: &[([f64; 3], [f64; 2])]) -> Vec<[f64; 2]> {
    let mut scale = 1.0;
    sections
        .iter()
        .map(|(b, a)| {
            let (b0, b1) = (b[1] - a[0] * b[0], b[2] - a[1] * b[0]);
            let z0 = (b0 + b1) / (1.0 + a[0] + a[1]);
            let z = [scale * z0, scale * (b1 - a[1] * z0)];
            scale *= (b[0] + b[1] + b[2]) / (1.0 + a[0] + a[1]);
            z
        })
        .collect()
}

/// One second-order section in transposed direct form II (scipy's `sosfilt`
/// arithmetic, in its order): the output for `y`, the state `z0, z1` advanced.
/// Every cascade here (unrolled, looped, many lanes, streaming) takes it.
#[inline(always)]
fn section(b: &[f64; 3], a: &[f64; 2], z0: &mut f64, z1: &mut f64, y: f64) -> f64 {
    let out = b[0] * y + *z0;
    *z0 = b[1] * y - a[0] * out + *z1;
    *z1 = b[2] * y - a[1] * out;
    out
}

/// Filter the samples in place through every section (transposed direct
/// form II), starting from the steady state `zi * x0`. Dispatched on the
/// section count so the per-sample loop over sections is unrolled with its
/// state in registers.
fn run_sections<'a>(
    samples: impl Iterator<Item = &'a mut f64>,
    sections: &[([f64; 3], [f64; 2])],
    zi: &[[f64; 2]],
    x0: f64,
) {
    fn fixed<'a, const N: usize>(
        samples: impl Iterator<Item = &'a mut f64>,
        sections: &[([f64; 3], [f64; 2])],
        zi: &[[f64; 2]],
        x0: f64,
    ) {
        let sec: [([f64; 3], [f64; 2]); N] = std::array::from_fn(|i| sections[i]);
        let mut state: [[f64; 2]; N] = std::array::from_fn(|i| [zi[i][0] * x0, zi[i][1] * x0]);
        for v in samples {
            let mut y = *v;
            for i in 0..N {
                let ((b, a), [z0, z1]) = (&sec[i], &mut state[i]);
                y = section(b, a, z0, z1, y);
            }
            *v = y;
        }
    }
    // Up to four sections (Butterworth order 8; every default is 1 or 2) the
    // loop is unrolled; more take the same arithmetic with the state in a
    // vector (unrolling all ten counts cost most of this crate's build time).
    match sections.len() {
        1 => fixed::<1>(samples, sections, zi, x0),
        2 => fixed::<2>(samples, sections, zi, x0),
        3 => fixed::<3>(samples, sections, zi, x0),
        4 => fixed::<4>(samples, sections, zi, x0),
        _ => {
            // the streaming filter's loop, started from the steady state
            let mut cascade = StreamingFilter {
                sections: sections.to_vec(),
                state: zi.iter().map(|z| [z[0] * x0, z[1] * x0]).collect(),
            };
            for v in samples {
                *v = cascade.step(*v);
            }
        }
    }
}

/// Where each sample of a window's filtering buffer comes from: `e` edge
/// samples per end ([`Edge`]), then scipy's odd padding of `pad` samples.
struct Padding {
    n: usize,
    e: usize,
    pad: usize,
    left: Edge,
    right: Edge,
}

impl Padding {
    fn total(&self) -> usize {
        self.n + 2 * self.e + 2 * self.pad
    }
    /// Sample `i` of the edge-extended signal (length n + 2e).
    fn extended(&self, x: &[f64], i: usize) -> f64 {
        let (n, e) = (self.n, self.e);
        if i < e {
            let k = e - i;
            match self.left {
                Edge::Odd => 2.0 * x[0] - x[k],
                Edge::Even => x[k],
            }
        } else if i < e + n {
            x[i - e]
        } else {
            let k = i - (e + n) + 1;
            match self.right {
                Edge::Odd => 2.0 * x[n - 1] - x[n - 1 - k],
                Edge::Even => x[n - 1 - k],
            }
        }
    }
    /// Sample `i` of the padded buffer (as `filtfilt` builds it).
    fn padded(&self, x: &[f64], i: usize) -> f64 {
        let len = self.n + 2 * self.e;
        let pad = self.pad;
        if i < pad {
            2.0 * self.extended(x, 0) - self.extended(x, pad - i)
        } else if i < pad + len {
            self.extended(x, i - pad)
        } else {
            let j = i - (pad + len) + 1;
            2.0 * self.extended(x, len - 1) - self.extended(x, len - 1 - j)
        }
    }
}

/// Forward-backward filtering of `L` interleaved signals (see `filtfilt_edges_many`).
fn lanes<const L: usize>(
    group: &[&[f64]],
    layout: &Padding,
    sections: &[([f64; 3], [f64; 2])],
    zi: &[[f64; 2]],
    out: &mut Vec<Vec<f64>>,
) {
    let total = layout.total();
    let mut buf = vec![[0.0f64; L]; total];
    // the window itself is copied; only the extensions and pads are computed
    let middle = layout.pad + layout.e..layout.pad + layout.e + layout.n;
    for (l, x) in group.iter().enumerate() {
        for (v, xi) in buf[middle.clone()].iter_mut().zip(x.iter()) {
            v[l] = *xi;
        }
        for i in (0..middle.start).chain(middle.end..total) {
            buf[i][l] = layout.padded(x, i);
        }
    }
    let first = buf[0];
    run_lanes::<L>(buf.iter_mut(), sections, zi, first);
    let last = buf[total - 1];
    run_lanes::<L>(buf.iter_mut().rev(), sections, zi, last);
    let start = layout.pad + layout.e;
    for l in 0..group.len() {
        out.push(buf[start..start + layout.n].iter().map(|v| v[l]).collect());
    }
}

/// [`run_sections`] for `L` interleaved signals, dispatched on the section count.
fn run_lanes<'a, const L: usize>(
    samples: impl Iterator<Item = &'a mut [f64; L]>,
    sections: &[([f64; 3], [f64; 2])],
    zi: &[[f64; 2]],
    x0: [f64; L],
) {
    fn fixed<'a, const N: usize, const L: usize>(
        samples: impl Iterator<Item = &'a mut [f64; L]>,
        sections: &[([f64; 3], [f64; 2])],
        zi: &[[f64; 2]],
        x0: [f64; L],
    ) {
        let sec: [([f64; 3], [f64; 2]); N] = std::array::from_fn(|i| sections[i]);
        let mut z0: [[f64; L]; N] = std::array::from_fn(|i| x0.map(|x| zi[i][0] * x));
        let mut z1: [[f64; L]; N] = std::array::from_fn(|i| x0.map(|x| zi[i][1] * x));
        for v in samples {
            let mut y = *v;
            for i in 0..N {
                let (b, a) = &sec[i];
                for l in 0..L {
                    y[l] = section(b, a, &mut z0[i][l], &mut z1[i][l], y[l]);
                }
            }
            *v = y;
        }
    }
    // unrolled up to four sections, as in `run_sections`
    match sections.len() {
        1 => fixed::<1, L>(samples, sections, zi, x0),
        2 => fixed::<2, L>(samples, sections, zi, x0),
        3 => fixed::<3, L>(samples, sections, zi, x0),
        4 => fixed::<4, L>(samples, sections, zi, x0),
        _ => {
            let mut z0: Vec<[f64; L]> = zi.iter().map(|z| x0.map(|x| z[0] * x)).collect();
            let mut z1: Vec<[f64; L]> = zi.iter().map(|z| x0.map(|x| z[1] * x)).collect();
            for v in samples {
                let mut y = *v;
                for (i, (b, a)) in sections.iter().enumerate() {
                    for l in 0..L {
                        y[l] = section(b, a, &mut z0[i][l], &mut z1[i][l], y[l]);
                    }
                }
                *v = y;
            }
        }
    }
}

/// A causal cascade of second-order sections in transposed direct form II
/// (as `scipy.signal.sosfilt`), starting from rest.
#[derive(Debug, Clone)]
pub struct StreamingFilter {
    sections: Vec<([f64; 3], [f64; 2])>,
    state: Vec<[f64; 2]>,
}

impl StreamingFilter {
    /// Filter one sample.
    #[inline]
    pub fn step(&mut self, x: f64) -> f64 {
        let mut y = x;
        for ((b, a), [z0, z1]) in self.sections.iter().zip(self.state.iter_mut()) {
            y = section(b, a, z0, z1, y);
        }
        y
    }
}

/// Savitzky-Golay filter (`scipy.signal.savgol_filter(x, window, polyorder, deriv, delta, mode='nearest')`).
pub fn savgol(
    x: &[f64],
    window: usize,
    polyorder: usize,
    deriv: usize,
    delta: f64,
) -> Result<Vec<f64>> {
    if window.is_multiple_of(2) || window < polyorder + 2 {
        return Err(Error::invalid(
            "Savitzky-Golay window",
            format!(
                "expected an odd length of at least polyorder + 2 = {}, found {window}",
                polyorder + 2
            ),
        ));
    }
    if deriv > polyorder {
        return Err(Error::invalid(
            "Savitzky-Golay derivative",
            format!("derivative order {deriv} exceeds the polynomial order {polyorder}"),
        ));
    }
    if x.len() < window {
        return Err(Error::invalid(
            "signal length",
            format!(
                "Savitzky-Golay window of {window} needs at least {window} samples, found {}",
                x.len()
            ),
        ));
    }
    Ok(sci_rs::signal::filter::savgol_filter_dyn(
        x.iter(),
        window,
        polyorder,
        Some(deriv),
        Some(delta),
    ))
}

/// First derivative by central differences (second-order one-sided at the ends).
pub fn central_first(x: &[f64], dt: f64) -> Vec<f64> {
    let n = x.len();
    let mut d = vec![0.0; n];
    if n < 3 {
        if n == 2 {
            let s = (x[1] - x[0]) / dt;
            d.fill(s);
        }
        return d;
    }
    for i in 1..n - 1 {
        d[i] = (x[i + 1] - x[i - 1]) / (2.0 * dt);
    }
    d[0] = (-3.0 * x[0] + 4.0 * x[1] - x[2]) / (2.0 * dt);
    d[n - 1] = (3.0 * x[n - 1] - 4.0 * x[n - 2] + x[n - 3]) / (2.0 * dt);
    d
}

/// Second derivative by central differences (end values copied from their neighbours).
pub fn central_second(x: &[f64], dt: f64) -> Vec<f64> {
    let n = x.len();
    let mut d = vec![0.0; n];
    if n < 3 {
        return d;
    }
    let h2 = dt * dt;
    for i in 1..n - 1 {
        d[i] = (x[i + 1] - 2.0 * x[i] + x[i - 1]) / h2;
    }
    if n >= 4 {
        // second-order one-sided second derivative
        d[0] = (2.0 * x[0] - 5.0 * x[1] + 4.0 * x[2] - x[3]) / h2;
        d[n - 1] = (2.0 * x[n - 1] - 5.0 * x[n - 2] + 4.0 * x[n - 3] - x[n - 4]) / h2;
    } else {
        d[0] = d[1];
        d[n - 1] = d[n - 2];
    }
    d
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn signals_filtered_together_equal_one_at_a_time() {
        // 1-4 sections unrolled, 5 and 6 through the loop over a state vector
        for order in [2, 4, 7, 9, 12] {
            let lp = LowPass::butterworth(order, 30.0, 500.0).unwrap();
            let signals: Vec<Vec<f64>> = (0..6)
                .map(|c| {
                    (0..700)
                        .map(|i| ((i * (c + 3)) as f64 * 0.013).sin() + c as f64 * 0.5)
                        .collect()
                })
                .collect();
            let refs: Vec<&[f64]> = signals.iter().map(Vec::as_slice).collect();
            for (left, right, extra) in [
                (Edge::Odd, Edge::Even, 50),
                (Edge::Even, Edge::Odd, 0),
                (Edge::Even, Edge::Even, 5000),
            ] {
                let together = lp.filtfilt_edges_many(&refs, left, right, extra).unwrap();
                assert_eq!(together.len(), 6);
                for (x, y) in refs.iter().zip(&together) {
                    let alone = lp.filtfilt_edges(x, left, right, extra).unwrap();
                    assert_eq!(&alone, y, "order {order}");
                }
            }
        }
    }

    /// The section cascade, written out plainly: every section count (the
    /// unrolled 1-4 and the looped 5+) and every lane count give its bits.
    #[test]
    fn every_section_count_runs_the_plain_cascade() {
        let x: Vec<f64> = (0..400).map(|i| (i as f64 * 0.11).sin() + 0.3).collect();
        for count in 1..=7usize {
            let sections: Vec<([f64; 3], [f64; 2])> = (0..count)
                .map(|i| {
                    let k = i as f64;
                    (
                        [0.05 + 0.01 * k, 0.1, 0.05],
                        [-0.6 + 0.05 * k, 0.2 - 0.02 * k],
                    )
                })
                .collect();
            let zi: Vec<[f64; 2]> = (0..count).map(|i| [0.2 * i as f64, -0.1]).collect();
            let mut plain = x.clone();
            let mut state: Vec<[f64; 2]> = zi.iter().map(|z| [z[0] * x[0], z[1] * x[0]]).collect();
            for v in plain.iter_mut() {
                let mut y = *v;
                // written out, not `section`: the reference the code is held to
                for ((b, a), z) in sections.iter().zip(state.iter_mut()) {
                    let out = b[0] * y + z[0];
                    z[0] = b[1] * y - a[0] * out + z[1];
                    z[1] = b[2] * y - a[1] * out;
                    y = out;
                }
                *v = y;
            }
            let mut single = x.clone();
            run_sections(single.iter_mut(), &sections, &zi, x[0]);
            assert_eq!(single, plain, "{count} sections, one signal");
            let mut lanes: Vec<[f64; 3]> = x.iter().map(|v| [*v; 3]).collect();
            run_lanes::<3>(lanes.iter_mut(), &sections, &zi, [x[0]; 3]);
            for l in 0..3 {
                let lane: Vec<f64> = lanes.iter().map(|v| v[l]).collect();
                assert_eq!(lane, plain, "{count} sections, lane {l}");
            }
        }
    }

    #[test]
    fn streaming_filter_equals_the_causal_block_filter() {
        let lp = LowPass::butterworth(4, 8.0, 1000.0).unwrap();
        let x: Vec<f64> = (0..3000)
            .map(|i| ((i as f64) * 0.37).sin().abs() + (i % 7) as f64 * 0.1)
            .collect();
        let block = lp.filter_causal(&x);
        let mut s = lp.streaming();
        for (xi, yi) in x.iter().zip(&block) {
            assert!((s.step(*xi) - yi).abs() < 1e-12);
        }
    }
    use approx::assert_relative_eq;

    #[test]
    fn central_differences_exact_on_quadratics() {
        let dt = 0.01;
        let x: Vec<f64> = (0..50)
            .map(|i| {
                let t = i as f64 * dt;
                3.0 + 2.0 * t - 4.0 * t * t
            })
            .collect();
        let v = central_first(&x, dt);
        let a = central_second(&x, dt);
        for (i, (vi, ai)) in v.iter().zip(&a).enumerate() {
            let t = i as f64 * dt;
            assert_relative_eq!(*vi, 2.0 - 8.0 * t, epsilon = 1e-9);
            assert_relative_eq!(*ai, -8.0, epsilon = 1e-7);
        }
    }

    #[test]
    fn savgol_exact_on_cubics_inside() {
        let dt = 0.002;
        let x: Vec<f64> = (0..200)
            .map(|i| {
                let t = i as f64 * dt;
                1.0 - t + 0.5 * t * t + 2.0 * t * t * t
            })
            .collect();
        let v = savgol(&x, 11, 3, 1, dt).unwrap();
        let a = savgol(&x, 11, 3, 2, dt).unwrap();
        for i in 5..195 {
            let t = i as f64 * dt;
            assert_relative_eq!(v[i], -1.0 + t + 6.0 * t * t, epsilon = 1e-8);
            assert_relative_eq!(a[i], 1.0 + 12.0 * t, epsilon = 1e-6);
        }
    }

    #[test]
    fn bad_filter_arguments_are_errors_not_panics() {
        assert!(LowPass::butterworth(4, 300.0, 500.0).is_err());
        assert!(LowPass::butterworth(0, 10.0, 500.0).is_err());
        let f = LowPass::butterworth(4, 10.0, 500.0).unwrap();
        assert!(f.filtfilt(&[1.0; 10]).is_err());
        assert!(savgol(&[1.0; 100], 10, 3, 1, 1.0).is_err());
        assert!(savgol(&[1.0; 5], 11, 3, 1, 1.0).is_err());
    }
}
