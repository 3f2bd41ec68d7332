//! The numerical kernels behind `limpid.psd`, `csd`, `coherence`,
//! `frequency_response` and `lowpass_filtfilt` (the Python side shapes
//! arguments and results as scipy's).

use numpy::{
    IntoPyArray, PyArray1, PyArray2, PyArrayMethods, PyReadonlyArray1, PyReadonlyArray2,
    PyUntypedArrayMethods,
};
use pyo3::prelude::*;

use limpid_dsp::spectral::{Detrend, Scaling, Welch, Window};

use super::{detached, err, value_err};

fn parse_detrend(detrend: &str) -> PyResult<Detrend> {
    match detrend {
        "constant" => Ok(Detrend::Constant),
        "linear" => Ok(Detrend::Linear),
        "none" | "false" => Ok(Detrend::None),
        other => Err(value_err(format!(
            "detrend {other:?}: constant, linear or none"
        ))),
    }
}

fn parse_scaling(scaling: &str) -> PyResult<Scaling> {
    match scaling {
        "density" => Ok(Scaling::Density),
        "spectrum" => Ok(Scaling::Spectrum),
        other => Err(value_err(format!("scaling {other:?}: density or spectrum"))),
    }
}

fn welch(
    fs: f64,
    window: &str,
    nperseg: usize,
    noverlap: Option<usize>,
    detrend: &str,
    scaling: &str,
) -> PyResult<Welch> {
    Ok(Welch {
        fs,
        nperseg,
        noverlap,
        window: match window {
            "hann" | "hanning" => Window::Hann,
            "hamming" => Window::Hamming,
            "boxcar" | "rectangular" | "ones" => Window::Boxcar,
            other => {
                return Err(value_err(format!(
                    "window {other:?}: limpid has hann, hamming, boxcar"
                )))
            }
        },
        detrend: parse_detrend(detrend)?,
        scaling: parse_scaling(scaling)?,
    })
}

/// Welch cross-spectra of row pairs (`limpid_dsp::cross_spectra`), the
/// engine of the package's `psd`, `csd` and `coherence`: `sources` are
/// C-contiguous 2-D float64 or complex128 arrays with rows of one length;
/// rows are numbered through the sources in order; returns
/// `[pair, bin]` complex128.
#[pyfunction]
#[pyo3(signature = (sources, pairs_a, pairs_b, window, hop, nfft, onesided, detrend, scaling, fs, average))]
#[allow(clippy::too_many_arguments)]
pub fn cross_spectra<'py>(
    py: Python<'py>,
    sources: Vec<Bound<'py, PyAny>>,
    pairs_a: PyReadonlyArray1<'py, i64>,
    pairs_b: PyReadonlyArray1<'py, i64>,
    window: PyReadonlyArray1<'py, f64>,
    hop: usize,
    nfft: usize,
    onesided: bool,
    detrend: &str,
    scaling: &str,
    fs: f64,
    average: &str,
) -> PyResult<Bound<'py, PyArray2<num_complex::Complex64>>> {
    use limpid_dsp::cross_spectra::{Average, Rows, Settings};
    enum Held<'py> {
        Real(PyReadonlyArray2<'py, f64>),
        Complex(PyReadonlyArray2<'py, num_complex::Complex64>),
    }
    let mut held = Vec::with_capacity(sources.len());
    let mut len = None;
    for s in &sources {
        let h = if let Ok(a) = s.extract::<PyReadonlyArray2<f64>>() {
            Held::Real(a)
        } else if let Ok(a) = s.extract::<PyReadonlyArray2<num_complex::Complex64>>() {
            Held::Complex(a)
        } else {
            return Err(value_err(
                "sources must be 2-D float64 or complex128 arrays",
            ));
        };
        let cols = match &h {
            Held::Real(a) => a.shape()[1],
            Held::Complex(a) => a.shape()[1],
        };
        if *len.get_or_insert(cols) != cols {
            return Err(value_err("all sources must have rows of one length"));
        }
        held.push(h);
    }
    let mut rows = Vec::with_capacity(held.len());
    for h in &held {
        rows.push(match h {
            Held::Real(a) => Rows::Real(
                a.as_slice()
                    .map_err(|_| value_err("sources must be C-contiguous"))?,
            ),
            Held::Complex(a) => Rows::Complex(
                a.as_slice()
                    .map_err(|_| value_err("sources must be C-contiguous"))?,
            ),
        });
    }
    let (pa, pb) = (pairs_a.as_array(), pairs_b.as_array());
    if pa.len() != pb.len() || pa.iter().chain(pb.iter()).any(|&i| i < 0) {
        return Err(value_err(
            "pairs: two index arrays of one length, no negative index",
        ));
    }
    let pairs: Vec<(usize, usize)> = pa
        .iter()
        .zip(pb.iter())
        .map(|(&a, &b)| (a as usize, b as usize))
        .collect();
    let window = window.as_array().to_vec();
    let settings = Settings {
        fs,
        window: &window,
        hop,
        nfft,
        onesided,
        detrend: parse_detrend(detrend)?,
        scaling: parse_scaling(scaling)?,
        average: match average {
            "mean" => Average::Mean,
            "median" => Average::Median,
            other => return Err(value_err(format!("average {other:?}: mean or median"))),
        },
    };
    let len = len.unwrap_or(0);
    let bins = settings.bins();
    let values = detached(py, || {
        limpid_dsp::cross_spectra::cross_spectra(&rows, len, &pairs, &settings)
    })
    .map_err(err)?;
    let array = values.into_pyarray(py);
    array.reshape([pairs.len(), bins])
}

/// MIMO H1 frequency response of outputs on inputs with multiple and partial
/// coherences (Bendat & Piersol; seed 004 §III-E). Returns
/// flat arrays (f, H[f][output][input] complex, multiple[f][output], partial[f][output][input]);
/// NaN where the input spectral matrix is singular.
#[pyfunction]
#[pyo3(signature = (inputs, outputs, fs, window, nperseg, noverlap, detrend))]
#[allow(clippy::too_many_arguments, clippy::type_complexity)]
pub fn frequency_response<'py>(
    py: Python<'py>,
    inputs: Vec<PyReadonlyArray1<'py, f64>>,
    outputs: Vec<PyReadonlyArray1<'py, f64>>,
    fs: f64,
    window: &str,
    nperseg: usize,
    noverlap: Option<usize>,
    detrend: &str,
) -> PyResult<(
    Bound<'py, PyArray1<f64>>,
    Bound<'py, PyArray1<num_complex::Complex64>>,
    Bound<'py, PyArray1<f64>>,
    Bound<'py, PyArray1<f64>>,
)> {
    let p = welch(fs, window, nperseg, noverlap, detrend, "density")?;
    let q = inputs.len();
    if q == 0 || outputs.is_empty() {
        return Err(value_err("at least one input and one output"));
    }
    let signals: Vec<Vec<f64>> = inputs
        .iter()
        .chain(&outputs)
        .map(|a| a.as_array().to_vec())
        .collect();
    let nan = num_complex::Complex64::new(f64::NAN, f64::NAN);
    let (f, h, multiple, partial) = detached(py, || -> limpid_core::Result<_> {
        let refs: Vec<&[f64]> = signals.iter().map(Vec::as_slice).collect();
        let s = limpid_dsp::spectral::SegmentSpectra::new(&refs, &p)?;
        // flat, row-major [f][output][input]; the Python side reshapes
        let (mut h, mut multiple, mut partial) = (Vec::new(), Vec::new(), Vec::new());
        let no = signals.len() - q;
        for m in s.matrix() {
            match limpid_dsp::spectral::mimo_point(&m, q) {
                Some(pt) => {
                    for o in 0..no {
                        h.extend((0..q).map(|i| pt.h[(o, i)]));
                        partial.extend_from_slice(&pt.partial[o]);
                    }
                    multiple.extend_from_slice(&pt.multiple);
                }
                None => {
                    h.extend(std::iter::repeat_n(nan, no * q));
                    partial.extend(std::iter::repeat_n(f64::NAN, no * q));
                    multiple.extend(std::iter::repeat_n(f64::NAN, no));
                }
            }
        }
        Ok((s.frequencies.clone(), h, multiple, partial))
    })
    .map_err(err)?;
    Ok((
        f.into_pyarray(py),
        h.into_pyarray(py),
        multiple.into_pyarray(py),
        partial.into_pyarray(py),
    ))
}

/// Zero-phase Butterworth low-pass (scipy: sosfiltfilt(butter(order, cutoff, fs=fs, output='sos'), x)).
#[pyfunction]
#[pyo3(signature = (x, cutoff_hz, fs, order, padtype, padlen))]
pub fn lowpass_filtfilt<'py>(
    py: Python<'py>,
    x: PyReadonlyArray2<'py, f64>,
    cutoff_hz: f64,
    fs: f64,
    order: usize,
    padtype: Option<&str>,
    padlen: Option<usize>,
) -> PyResult<Bound<'py, PyArray2<f64>>> {
    use limpid_dsp::Pad;
    use rayon::prelude::*;
    let lp = limpid_dsp::LowPass::butterworth(order, cutoff_hz, fs).map_err(err)?;
    let pad = match padtype {
        Some("odd") => Pad::Odd,
        Some("even") => Pad::Even,
        Some("constant") => Pad::Constant,
        None => Pad::None,
        Some(other) => {
            return Err(value_err(format!(
                "padtype {other:?}: expected 'odd', 'even', 'constant' or None"
            )))
        }
    };
    let padlen = padlen.unwrap_or_else(|| lp.padlen());
    let [rows, n] = [x.shape()[0], x.shape()[1]];
    let x = x
        .as_slice()
        .map_err(|_| value_err("x must be C-contiguous"))?;
    let effective = if pad == Pad::None { 0 } else { padlen };
    if n <= effective {
        return Err(value_err(format!(
            "the signal must be longer than padlen = {effective} samples, found {n}"
        )));
    }
    if rows == 1 {
        let y = detached(py, || lp.filtfilt_padded(x, pad, padlen)).map_err(err)?;
        return y.into_pyarray(py).reshape([rows, n]);
    }
    let mut out = vec![0.0; rows * n];
    detached(py, || {
        out.par_chunks_mut(n)
            .zip(x.par_chunks(n))
            .try_for_each(|(o, r)| lp.filtfilt_into(r, pad, padlen, o))
    })
    .map_err(err)?;
    out.into_pyarray(py).reshape([rows, n])
}
