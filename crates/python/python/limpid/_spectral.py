"""Welch spectra with the arguments, defaults, shapes and dtypes of
``scipy.signal.welch``, ``csd`` and ``coherence`` (scipy 1.17).

The numbers come from the Rust kernel ``limpid._limpid.cross_spectra``
(crate ``limpid-dsp``, module ``cross_spectra``); this module only turns
N-D arguments into rows and index pairs, and the result back into scipy's
shape. Choices where scipy is silent or differs are listed in docs/src/python.md
("Python: spectra as scipy").
"""

from __future__ import annotations

import importlib
import operator
import warnings
from typing import Any, Callable, Optional, Sequence, Tuple, Union

import numpy as np

from . import _limpid

# one FFT of 2^28 complex bins is 4 GiB: beyond that, refuse instead of running out of memory
MAX_NFFT = 1 << 28

WindowLike = Union[str, Tuple[Any, ...], Sequence[float], np.ndarray]
DetrendLike = Union[str, bool, None, Callable[[np.ndarray], np.ndarray]]

# windows computed without scipy, exactly as scipy.signal.get_window computes
# them (periodic, DFT-even): general cosine windows of M + 1 points, truncated
_COSINE_WINDOWS = {
    "hann": (0.5, 0.5),
    "hann_periodic": (0.5, 0.5),
    "hanning": (0.5, 0.5),
    "hamming": (0.54, 0.46),
    "hamming_periodic": (0.54, 0.46),
    "boxcar": (1.0,),
    "boxcar_periodic": (1.0,),
    "rectangular": (1.0,),
    "ones": (1.0,),
}


def _window(window: Union[str, Tuple[Any, ...]], n: int) -> np.ndarray:
    """Window samples of a name or a (name, parameter...) tuple: scipy's
    ``get_window`` when scipy is installed, else the built-in cosine windows."""
    try:
        get_window = importlib.import_module("scipy.signal").get_window
    except ImportError:
        a = _COSINE_WINDOWS.get(window) if isinstance(window, str) else None
        if a is None:
            raise ValueError(
                f"window {window!r}: without scipy, limpid knows {', '.join(sorted(_COSINE_WINDOWS))}; "
                "install scipy for every scipy.signal.get_window window, or pass the window's samples"
            ) from None
        if n <= 1:
            return np.ones(n)
        fac = np.linspace(-np.pi, np.pi, n + 1)
        w = np.zeros(n + 1)
        for k, ak in enumerate(a):
            w += ak * np.cos(k * fac)
        return w[:-1]
    return np.asarray(get_window(window, n), dtype=float)


def _whole(name: str, value: Any) -> int:
    """An integer argument (numpy integers too); floats and strings are ValueErrors."""
    if isinstance(value, (bool, np.bool_)):
        raise ValueError(f"{name}: expected an integer, found {value!r}")
    try:
        return operator.index(value)
    except TypeError:
        raise ValueError(f"{name}: expected an integer, found {value!r}") from None


def _rate(fs: Any) -> float:
    try:
        v = float(fs)
    except (TypeError, ValueError):
        raise ValueError(f"fs: expected a positive sample rate, found {fs!r}") from None
    if not (np.isfinite(v) and v > 0):
        raise ValueError(f"fs: expected a positive sample rate, found {fs!r}")
    return v


def _signal(a: Any, name: str) -> np.ndarray:
    # a masked array's mask would be ignored by asarray (issue 56): refused when it masks anything
    if np.ma.isMaskedArray(a):
        masked = int(np.asarray(getattr(a, "mask"), dtype=bool).sum())
        if masked:
            raise ValueError(f"{name}: a masked array with {masked} masked value(s); "
                             "limpid does not guess them: fill them or drop those samples first")
        a = np.asarray(getattr(a, "data"))
    arr = np.asarray(a)
    if arr.dtype.kind not in "biufc":
        try:
            arr = arr.astype(float)
        except (TypeError, ValueError):
            raise ValueError(f"{name}: expected numbers, found dtype {arr.dtype}") from None
    if arr.ndim == 0:
        raise ValueError(f"{name}: expected an array of samples, found a scalar")
    return arr


def _axis(axis: Any, ndim: int, name: str) -> int:
    a = _whole("axis", axis)
    if not -ndim <= a < ndim:
        raise ValueError(f"axis {a} is out of bounds for {name} with {ndim} dimension(s)")
    return a % ndim


def _rows(a: np.ndarray, ax: int, n: int) -> Tuple[np.ndarray, Tuple[int, ...]]:
    """Samples along ``ax`` as C-contiguous rows of ``n`` (zero-padded), and the outer shape."""
    a = np.moveaxis(a, ax, -1)
    outer = a.shape[:-1]
    dtype = np.complex128 if np.iscomplexobj(a) else np.float64
    a = a.astype(dtype, copy=False)
    if a.shape[-1] < n:
        a = np.concatenate((a, np.zeros(outer + (n - a.shape[-1],), dtype)), axis=-1)
    return np.ascontiguousarray(a.reshape(-1, n)), outer


def _detrended_segments(rows: np.ndarray, outer: Tuple[int, ...], detrend: Callable[[np.ndarray], np.ndarray],
                        nperseg: int, hop: int) -> np.ndarray:
    """scipy's callable detrend: called once per segment with the outer
    dimensions kept (samples on the last axis); segments laid end to end."""
    n = rows.shape[-1]
    nseg = (n - nperseg) // hop + 1
    full = rows.reshape(outer + (n,))
    parts = []
    for k in range(nseg):
        seg = full[..., k * hop:k * hop + nperseg]
        d = np.asarray(detrend(seg))
        if d.shape != seg.shape:
            raise ValueError(f"detrend returned shape {d.shape} for a segment of shape {seg.shape}")
        parts.append(d)
    out = np.concatenate(parts, axis=-1).reshape(-1, nseg * nperseg)
    dtype = np.complex128 if np.iscomplexobj(out) else np.float64
    return np.ascontiguousarray(out.astype(dtype, copy=False))


def spectra(x: Any, y: Any, kind: str, fs: Any, window: WindowLike, nperseg: Any, noverlap: Any, nfft: Any,
            detrend: DetrendLike, return_onesided: Any, scaling: str, axis: Any,
            average: str) -> Tuple[np.ndarray, np.ndarray]:
    """``kind``: 'psd' (y is None or x itself), 'csd' or 'coherence'."""
    same = y is None or y is x
    x = _signal(x, "x")
    ax = _axis(axis, x.ndim, "x")
    if same:
        if x.size == 0:
            return np.empty(x.shape), np.empty(x.shape)
        out_dtype = np.result_type(x, np.complex64)
        n = x.shape[ax]
        ay = ax
    else:
        y = _signal(y, "y")
        ay = _axis(axis, y.ndim, "y")
        xo = x.shape[:ax] + x.shape[ax + 1:]
        yo = y.shape[:ay] + y.shape[ay + 1:]
        try:
            outer = np.broadcast_shapes(xo, yo)
        except ValueError as e:
            raise ValueError(f"x and y cannot be broadcast together: outer shapes {xo} and {yo}") from e
        if x.size == 0 or y.size == 0:
            empty = np.moveaxis(np.empty(outer + (min(x.shape[ax], y.shape[ay]),)), -1, axis)
            return empty, empty
        out_dtype = np.result_type(x, y, np.complex64)
        n = max(x.shape[ax], y.shape[ay])

    if isinstance(window, (str, tuple)):
        nperseg = 256 if nperseg is None else _whole("nperseg", nperseg)
        if nperseg < 1:
            raise ValueError(f"Parameter nperseg={nperseg} is not a positive integer!")
        if n < nperseg:
            warnings.warn(f"nperseg={nperseg} is greater than signal length max(len(x), len(y)) = {n}, "
                          f"using nperseg = {n}", UserWarning, stacklevel=4)
            nperseg = n
        win = _window(window, nperseg)
    else:
        win = np.asarray(window)
        if win.ndim != 1:
            raise ValueError(f"window must be 1-D, found {win.ndim} dimensions")
        if np.iscomplexobj(win):
            raise ValueError("window must be real")
        win = win.astype(float)
        nperseg = len(win) if nperseg is None else _whole("nperseg", nperseg)
        if nperseg != len(win):
            raise ValueError(f"nperseg={nperseg} does not equal len(win)={len(win)}")
        if len(win) > n:
            raise ValueError(f"window is longer than input signal ({len(win)} > {n} samples)")
        if len(win) == 0:
            raise ValueError("window must have at least one sample")
    nfft = nperseg if nfft is None else _whole("nfft", nfft)
    if nfft < nperseg:
        raise ValueError(f"nfft={nfft} must be greater than or equal to nperseg={nperseg}!")
    if nfft > MAX_NFFT:
        raise ValueError(f"nfft={nfft} is larger than limpid's limit of {MAX_NFFT} (2^28) bins")
    noverlap = nperseg // 2 if noverlap is None else _whole("noverlap", noverlap)
    if noverlap >= nperseg:
        raise ValueError(f"noverlap={noverlap} must be less than nperseg={nperseg}!")
    if noverlap < 0:
        raise ValueError(f"noverlap={noverlap} must not be negative")
    fs = _rate(fs)
    if scaling not in ("density", "spectrum"):
        raise ValueError(f"Parameter scaling={scaling!r} not in ('density', 'spectrum')!")
    if average not in ("mean", "median"):
        raise ValueError(f"Parameter average={average!r} must be 'median' or 'mean'!")
    onesided = bool(return_onesided) and not np.iscomplexobj(x) and (same or not np.iscomplexobj(y))
    if detrend is False or detrend is None:
        mode: Optional[str] = "none"
    elif isinstance(detrend, str):
        mode = {"constant": "constant", "c": "constant", "linear": "linear", "l": "linear"}.get(detrend)
        if mode is None:
            raise ValueError(f"detrend={detrend!r}: expected 'constant', 'linear', False, None or a function")
    elif callable(detrend):
        mode = None
    else:
        raise ValueError(f"detrend={detrend!r}: expected 'constant', 'linear', False, None or a function")

    hop = nperseg - noverlap
    xr, xo = _rows(x, ax, n)
    sources = [xr]
    if not same:
        yr, yo = _rows(y, ay, n)
        sources.append(yr)
    if mode is None:
        sources = [_detrended_segments(r, o, detrend, nperseg, hop)  # type: ignore[arg-type]
                   for r, o in zip(sources, [xo] + ([] if same else [yo]))]
        hop, mode = nperseg, "none"

    def run(a: np.ndarray, b: np.ndarray) -> np.ndarray:
        return _limpid.cross_spectra(sources, np.ascontiguousarray(a, np.int64), np.ascontiguousarray(b, np.int64),
                                     np.ascontiguousarray(win), hop, nfft, onesided, mode, scaling, fs, average)

    freqs = np.fft.rfftfreq(nfft, 1 / fs) if onesided else np.fft.fftfreq(nfft, 1 / fs)
    real_dtype = np.empty(0, out_dtype).real.dtype

    def shaped(v: np.ndarray, outer: Tuple[int, ...]) -> np.ndarray:
        v = v.reshape(outer + (v.shape[-1],))
        return np.moveaxis(v, -1, axis if -v.ndim <= operator.index(axis) < v.ndim else -1)

    if same:
        idx = np.arange(xr.shape[0])
        p = shaped(run(idx, idx), xo).astype(out_dtype).real
        return freqs, p
    nx = xr.shape[0]
    ix = np.broadcast_to(np.arange(nx).reshape(xo), outer).ravel()
    iy = np.broadcast_to(np.arange(nx, nx + yr.shape[0]).reshape(yo), outer).ravel()
    if kind == "csd":
        return freqs, shaped(run(ix, iy), outer).astype(out_dtype)
    # coherence: the cross-spectra, and each row's auto-spectrum once
    rows_all = np.arange(nx + yr.shape[0])
    m = len(ix)
    both = run(np.concatenate((ix, rows_all)), np.concatenate((iy, rows_all)))
    pxy = both[:m].astype(out_dtype)
    auto = both[m:].real.astype(real_dtype)
    with np.errstate(divide="warn", invalid="warn"):
        c = np.abs(pxy) ** 2 / auto[ix] / auto[iy]
    return freqs, shaped(c, outer)


# ---------------------------------------------------------------- the public functions


_WELCH_PARAMETERS = """
    fs : float, default 1.0
        Sample rate of the signal (Hz); frequencies are returned in Hz.
    window : str, tuple or array_like, default 'hann'
        A name or ``(name, parameter, ...)`` tuple as accepted by
        ``scipy.signal.get_window`` (periodic), or the window's samples (then
        ``nperseg`` defaults to their count). Without scipy installed, the
        names hann, hamming and boxcar are built in.
    nperseg : int, optional
        Samples per segment; default 256 for a named window, shortened with a
        ``UserWarning`` to the signal length when longer.
    noverlap : int, optional
        Samples shared by neighbouring segments; default ``nperseg // 2``.
    nfft : int, optional
        FFT length (zero padding); default ``nperseg``.
    detrend : {'constant', 'linear', False, None} or callable, default 'constant'
        Trend removed from each segment before windowing. A callable is called
        once per segment with the samples on the last axis.
"""


def psd(x: Any, fs: float = 1.0, window: WindowLike = "hann", nperseg: Optional[int] = None,
        noverlap: Optional[int] = None, nfft: Optional[int] = None,
        detrend: DetrendLike = "constant", return_onesided: bool = True,
        scaling: str = "density", axis: int = -1, average: str = "mean") -> Tuple[np.ndarray, np.ndarray]:
    """Welch power spectral density, as ``scipy.signal.welch``.

    Parameters
    ----------
    x : array_like
        Signal(s), real or complex, any number of dimensions; samples along ``axis``.
    {params}    return_onesided : bool, default True
        One-sided spectrum (doubled except at 0 Hz and Nyquist); complex
        input always gives the two-sided spectrum.
    scaling : {{'density', 'spectrum'}}, default 'density'
        Power spectral density (unit^2/Hz) or power spectrum (unit^2).
    axis : int, default -1
        Axis of the samples.
    average : {{'mean', 'median'}}, default 'mean'
        Mean of the segments' periodograms, or their median divided by the
        median's bias.

    Returns
    -------
    f : ndarray
        Frequencies (Hz).
    Pxx : ndarray
        Spectral density or spectrum, with the frequencies along ``axis``;
        float32 for float32 or complex64 input, else float64.
    """
    return spectra(x, None, "psd", fs, window, nperseg, noverlap, nfft, detrend, return_onesided,
                             scaling, axis, average)


def csd(x: Any, y: Any, fs: float = 1.0, window: WindowLike = "hann", nperseg: Optional[int] = None,
        noverlap: Optional[int] = None, nfft: Optional[int] = None,
        detrend: DetrendLike = "constant", return_onesided: bool = True,
        scaling: str = "density", axis: int = -1, average: str = "mean") -> Tuple[np.ndarray, np.ndarray]:
    """Welch cross spectral density ``P_xy = avg conj(X) Y``, as ``scipy.signal.csd``.

    ``x`` and ``y`` broadcast against each other outside ``axis`` (so
    ``csd(s[:, None, :], s[None, :, :])`` is the full cross-spectral matrix of
    the channels of ``s``, each channel's FFT computed once per segment); the
    shorter is zero-padded along ``axis`` to the longer.

    Parameters
    ----------
    x, y : array_like
        Signals, real or complex; samples along ``axis``.
    {params}    return_onesided : bool, default True
        One-sided spectrum; complex input gives the two-sided one.
    scaling : {{'density', 'spectrum'}}, default 'density'
        Cross spectral density (unit_x unit_y/Hz) or cross spectrum.
    axis : int, default -1
        Axis of the samples.
    average : {{'mean', 'median'}}, default 'mean'
        Mean over segments, or the bias-corrected median of the real and
        imaginary parts.

    Returns
    -------
    f : ndarray
        Frequencies (Hz).
    Pxy : ndarray
        Complex cross-spectral density (real when ``y is x``), complex64 for
        single-precision input.
    """
    return spectra(x, y, "csd", fs, window, nperseg, noverlap, nfft, detrend, return_onesided,
                             scaling, axis, average)


def coherence(x: Any, y: Any, fs: float = 1.0, window: WindowLike = "hann",
              nperseg: Optional[int] = None, noverlap: Optional[int] = None, nfft: Optional[int] = None,
              detrend: DetrendLike = "constant", axis: int = -1) -> Tuple[np.ndarray, np.ndarray]:
    """Magnitude-squared coherence ``|P_xy|^2 / (P_xx P_yy)``, as ``scipy.signal.coherence``.

    Parameters
    ----------
    x, y : array_like
        Signals; broadcast outside ``axis`` as in :func:`csd`.
    {params}    axis : int, default -1
        Axis of the samples.

    Returns
    -------
    f : ndarray
        Frequencies (Hz).
    Cxy : ndarray
        Coherence in [0, 1]; NaN (with numpy's RuntimeWarning) where a
        signal has no power, as scipy.
    """
    return spectra(x, y, "coherence", fs, window, nperseg, noverlap, nfft, detrend, True,
                             "density", axis, "mean")


for _f in (psd, csd, coherence):
    _f.__doc__ = (_f.__doc__ or "").replace("{params}", _WELCH_PARAMETERS.strip() + "\n").replace("{{", "{").replace("}}", "}")
