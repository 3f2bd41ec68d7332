"""limpid: limb impedance identification, for notebooks.

A thin layer over the Rust library (``limpid._limpid``):

- recordings: a path (CSV/Parquet, the recording format of docs/src/format.md), a dict of 1-D arrays, or a
  pandas DataFrame;
- spectra with scipy.signal's argument names and defaults (``psd``, ``csd``,
  ``coherence``) returning ``(f, values)``;
- the estimators (``estimate_linear``, ``estimate_planar``, ``window_sweep``,
  ``estimate_stochastic``, ``estimate_reflex``, ``estimate_varying``,
  ``estimate_cocontraction``) and ``spectra`` (coherences of named columns), returning
  :class:`Result` objects whose ``to_dict()`` has the keys of the CLI's JSON;
- the virtual lab (``protocol_preset``, ``protocol_check``, ``simulate``),
  ``ellipsoid`` and ``report``;
- in a notebook, results display as tables (value ± SE rounded to the SE,
  units, verdicts, warnings), become tidy DataFrames (``to_pandas()``) and
  figures (:mod:`limpid.plot`, with matplotlib).

Bad input raises ``ValueError`` (files: ``OSError``) with the library's
one-line message; long computations release the GIL.
"""

from __future__ import annotations

import copy
import difflib
import json
import operator
import os
import re
import warnings
from typing import TYPE_CHECKING, Any, Dict, List, Mapping, Optional, Sequence, Tuple, Union

import numpy as np

from . import _display, _limpid, _spectral, plot
from ._spectral import coherence, csd, psd

try:
    from importlib.metadata import PackageNotFoundError as _NotFound
    from importlib.metadata import version as _version

    __version__: str = _version("limpid")
except _NotFound:  # run from a source tree without installing
    __version__ = "0+unknown"

__all__ = [
    "__version__",
    "Result",
    "plot",
    "read_recording",
    "inspect",
    "psd",
    "csd",
    "coherence",
    "lowpass_filtfilt",
    "frequency_response",
    "request",
    "estimate_linear",
    "estimate_planar",
    "window_sweep",
    "estimate_stochastic",
    "estimate_reflex",
    "estimate_cocontraction",
    "estimate_varying",
    "spectra",
    "ellipsoid",
    "StudyOutcome",
    "study_entries",
    "study_process",
    "study_combine",
    "study_run",
    "protocol_preset",
    "protocol_check",
    "design",
    "simulate",
    "gravity_compensate",
    "report",
    "set_threads",
]

RecordingLike = Union[str, "os.PathLike[str]", Mapping[str, Any], Any]
# a channel map: the path of its TOML file or a dict of the same shape
MapLike = Union[None, str, "os.PathLike[str]", Mapping[str, Any]]


def _arrayish(v: Any) -> Any:
    """Nested lists of numbers become numpy arrays; everything else stays."""
    if isinstance(v, list) and v and all(isinstance(x, (int, float, list)) and not isinstance(x, bool) for x in v):
        try:
            a = np.asarray(v, dtype=float)
            if a.dtype == float and a.ndim >= 1:
                return a
        except (ValueError, TypeError):
            pass
    return v


class Result:
    """An estimate: attribute access to its fields (numeric lists as numpy
    arrays, nested objects as Results); ``to_dict()`` gives a copy of the
    plain dict with the CLI's JSON keys, ``Result.from_dict`` makes one back.

    Results pickle and copy (``pickle``, ``copy.copy``, ``copy.deepcopy``), so
    they travel between processes (``concurrent.futures``, dask)."""

    __slots__ = ("_data", "_context")

    if TYPE_CHECKING:
        # the fields most results have, for type checkers (served by __getattr__;
        # which a Result has depends on its ``kind``: see ``keys()``)
        schema: str
        kind: str
        inertia: np.ndarray
        damping: np.ndarray
        stiffness: np.ndarray
        standard_errors: "Result"
        fit: "Result"
        criteria: "Result"
        warnings: List[Any]
        provenance: "Result"
        frequencies: np.ndarray
        impedance: np.ndarray
        coherence: "Result"
        levels: List[Any]
        rows: List[Any]

    def __init__(self, data: Dict[str, Any], _context: Optional[Dict[str, Any]] = None):
        if not isinstance(data, dict):
            raise ValueError(f"a Result is made from a dict, found {type(data).__name__}")
        object.__setattr__(self, "_data", data)
        # a part of a result (``r.fit``, ``r.standard_errors``) keeps where it came
        # from: its path, the whole result's kind, coordinates and units
        object.__setattr__(self, "_context", _context)

    def _part(self, name: str, v: Dict[str, Any]) -> "Result":
        return Result(v, _display.part_context(self._data, self._context, name))

    @classmethod
    def from_dict(cls, data: Mapping[str, Any]) -> "Result":
        """A Result from a plain dict (as ``to_dict()`` or the CLI's ``--json`` give); the dict is copied.
        A result document (with its ``schema`` key) is checked as ``limpid report``
        reads one: a field of the wrong type or length is a ValueError naming it."""
        d = copy.deepcopy(dict(data))
        if "schema" in d:
            try:
                text = json.dumps(d, allow_nan=False)
            except (TypeError, ValueError) as e:
                raise ValueError(f"result: not a limpid result: {e}") from None
            _limpid.check_result(text)
        return cls(d)

    def __getattr__(self, name: str) -> Any:
        # private and dunder names are never fields (pickle and copy probe them)
        if name.startswith("_"):
            raise AttributeError(name)
        try:
            v = self._data[name]
        except KeyError:
            raise AttributeError(name) from None
        if isinstance(v, dict):
            return self._part(name, v)
        if name == "impedance" and self._data.get("kind") == "stochastic":
            # Z(f) as complex numbers (frequency, output, displacement); the JSON keeps [re, im]
            z = np.asarray(v, dtype=float)
            return z[..., 0] + 1j * z[..., 1]
        return _arrayish(v)

    def __getitem__(self, name: str) -> Any:
        if name not in self._data:
            raise KeyError(name)
        v = self._data[name]
        return self._part(name, v) if isinstance(v, dict) else _arrayish(v)

    def __contains__(self, name: object) -> bool:
        return name in self._data

    def __dir__(self) -> List[str]:
        # the fields, and the methods that turn a result into tables and arrays
        methods = ["from_dict", "keys", "to_dict", "to_pandas", "to_xarray"]
        return sorted(set(self._data.keys()) | set(methods))

    def keys(self) -> List[str]:
        return list(self._data.keys())

    def to_dict(self) -> Dict[str, Any]:
        """A deep copy of the fields (changing it does not change the Result)."""
        return copy.deepcopy(self._data)

    def __eq__(self, other: object) -> bool:
        if not isinstance(other, Result):
            return NotImplemented
        return bool(self._data == other._data)

    __hash__ = None  # type: ignore[assignment]

    def __reduce__(self) -> Tuple[Any, Tuple[Dict[str, Any], Optional[Dict[str, Any]]]]:
        return (Result, (self._data, self._context))

    def __copy__(self) -> "Result":
        return Result(self._data, self._context)

    def __deepcopy__(self, memo: Dict[int, Any]) -> "Result":
        return Result(copy.deepcopy(self._data, memo), copy.deepcopy(self._context, memo))

    def __repr__(self) -> str:
        if self._context is not None:
            return _display.part_summary(self._data, self._context)
        try:
            return _display.summary(self._data)
        except (IndexError, KeyError, TypeError, ValueError, AttributeError) as e:
            return f"limpid.Result(kind={self._data.get('kind', '?')!r}; cannot be summarised: {_display.why(e)})"

    def _repr_html_(self) -> str:
        """A notebook's view: value ± SE per matrix element with units,
        rounded to the SE, the verdict per matrix, fit quality, warnings.
        A hand-made result whose fields disagree says so instead of raising.
        A part of a result (``r.fit``) shows its fields with units."""
        if self._context is not None:
            return _display.part_html(self._data, self._context)
        try:
            return _display.to_html(self._data)
        except (IndexError, KeyError, TypeError, ValueError, AttributeError) as e:
            import html

            return (f"<p><b>limpid {html.escape(str(self._data.get('kind', '?')))} result</b>: "
                    f"cannot be shown: {html.escape(_display.why(e))}</p>")

    def to_pandas(self, table: str = "parameters") -> Any:
        """A tidy ``pandas.DataFrame`` of the result (pandas must be installed).

        ``table="parameters"`` (default): one row per matrix element (and per
        level, window or schedule point, as the kind has them) with columns
        ``quantity, element, row, column, value, se, unit, verdict``; reflex:
        one row per pathway parameter; study: the seed 001 tables (one row per
        configuration and level, ``*_sd`` columns). ``table="impedance"``
        (stochastic): one row per frequency and element of Z(f) (real,
        imaginary, magnitude, phase, unit); ``table="coherence"``
        (stochastic, spectra): multiple and partial (spectra: also ordinary)
        coherence per frequency, output and input; ``table="psd"`` (spectra):
        the power spectral density per frequency and signal. ``table="rotation"`` (study): the ellipsoid rotations.
        ``table="flawed"`` (walking): the strides left out or joined, by number, with start, row, duration and why.
        The values are the result's own floats; absent ones are NaN."""
        try:
            import importlib

            pd = importlib.import_module("pandas")  # optional: no stubs needed to type-check limpid
        except ImportError:
            raise ImportError("Result.to_pandas needs pandas: pip install pandas") from None
        recs = _display.records(self._data, table)
        # a field some rows lack is None in all of them (not NaN in one table and None in another)
        keys = list(dict.fromkeys(k for r in recs for k in r))
        return pd.DataFrame.from_records([{k: r.get(k) for k in keys} for r in recs], columns=keys)

    def to_xarray(self) -> Any:
        """The result over its axis, with units (xarray must be installed).

        Stochastic: Z(f) as an ``xarray.DataArray`` (complex, dims ``frequency,
        output, displacement``). Varying (and walking): an ``xarray.Dataset``
        over the schedule (``sigma``: time, the operating point or gait phase)
        with ``stiffness``, ``damping``, ``inertia`` and their ``*_se`` (dims
        ``sigma, output, coordinate``; NaN where a point is not identifiable),
        ``identifiable`` and ``support``. Window sweep: a Dataset over the
        observation window (``window``, ms) with the planar ``stiffness``,
        ``damping``, their ``*_se`` and ``trusted``. Spectra: a Dataset over
        ``frequency`` with ``psd`` (per signal), ``coherence``,
        ``multiple_coherence`` and ``partial_coherence``. Every variable
        carries ``units`` ("1" for ratios)."""
        kind = self._data.get("kind")
        if kind not in ("stochastic", "varying", "window_sweep", "spectra"):
            raise ValueError("to_xarray is for results over a frequency, schedule or window axis (stochastic, "
                             f"spectra, varying, window_sweep), this one is {kind!r}")
        try:
            import xarray as xr
        except ImportError:
            raise ImportError("Result.to_xarray needs xarray: pip install xarray") from None
        if kind == "varying":
            return _varying_dataset(xr, self._data)
        if kind == "window_sweep":
            return _sweep_dataset(xr, self._data)
        if kind == "spectra":
            return _spectra_dataset(xr, self._data)
        coords = self._data["coordinates"]
        z = np.asarray(self._data["impedance"], dtype=float)
        return xr.DataArray(z[..., 0] + 1j * z[..., 1], dims=("frequency", "output", "displacement"),
                            coords={"frequency": ("frequency", self._data["frequencies"], {"units": "Hz"}),
                                    "output": coords, "displacement": coords},
                            name="impedance", attrs={"units": "N/m, N/rad, N m/m or N m/rad by element",
                                                     "frequency_units": "Hz"})


def _varying_dataset(xr: Any, d: Dict[str, Any]) -> Any:
    """A varying result as an xarray Dataset over its schedule."""
    coords = d["coordinates"]
    n = len(coords)
    points = d["points"]
    sched = d["schedule"]
    data: Dict[str, Any] = {}
    for q in ("stiffness", "damping", "inertia"):
        unit = _display._unit(q, coords[0], coords[0]) if n == 1 else "by element (see to_pandas)"
        for name in (q, q + "_se"):
            a = np.full((len(points), n, n), np.nan)
            for k, p in enumerate(points):
                if p["identifiable"] and p.get(name) is not None:
                    a[k] = np.asarray(p[name], dtype=float)
            data[name] = (("sigma", "output", "coordinate"), a, {"units": unit})
    data["identifiable"] = (("sigma",), np.asarray([bool(p["identifiable"]) for p in points]))
    data["support"] = (("sigma",), np.asarray([float(p["support"]) for p in points]),
                       {"units": "perturbations" if d.get("method") == "pulses"
                        else ("strides" if d.get("gait") else "repetitions or s")})
    ds = xr.Dataset(data, coords={"sigma": ("sigma", [p["sigma"] for p in points],
                                            {"long_name": sched["name"], "units": sched.get("unit", "")}),
                                  "output": coords, "coordinate": coords},
                    attrs={"method": d.get("method", ""), "resolution": d.get("resolution_note", "")})
    return ds


def _sweep_dataset(xr: Any, d: Dict[str, Any]) -> Any:
    """A window sweep as an xarray Dataset over the observation window."""
    rows = d["rows"]
    joints = ["q1", "q2"]
    data: Dict[str, Any] = {}
    for q in ("stiffness", "damping"):
        unit = _display._unit(q, "q1", "q1")
        data[q] = (("window", "output", "coordinate"),
                   np.asarray([r["estimate"][q] for r in rows], dtype=float), {"units": unit})
        data[q + "_se"] = (("window", "output", "coordinate"),
                           np.asarray([r["estimate"]["standard_errors"][q] for r in rows], dtype=float),
                           {"units": unit})
    data["trusted"] = (("window",), np.asarray([bool(r["trusted"]) for r in rows]))
    return xr.Dataset(data, coords={"window": ("window", [r["observation_window_ms"] for r in rows],
                                               {"long_name": "observation window T_obs", "units": "ms"}),
                                    "output": joints, "coordinate": joints},
                      attrs={"shortest_trusted_ms": d.get("shortest_trusted_ms") or float("nan")})


def _spectra_dataset(xr: Any, d: Dict[str, Any]) -> Any:
    """Spectra as an xarray Dataset over frequency. The signals' units are
    the columns' own (limpid does not guess them from names)."""
    f = ("frequency", d["frequencies"], {"units": "Hz"})
    ratio = {"units": "1"}
    data = {
        "psd": (("signal", "frequency"), np.asarray(d["psd"], dtype=float),
                {"units": "(signal unit)²/Hz", "long_name": "power spectral density (one-sided, Welch)"}),
        "coherence": (("output", "input", "frequency"), np.asarray(d["coherence"], dtype=float),
                      dict(ratio, long_name="ordinary coherence")),
        "multiple_coherence": (("output", "frequency"), np.asarray(d["multiple_coherence"], dtype=float),
                               dict(ratio, long_name="multiple coherence on all inputs")),
        "partial_coherence": (("output", "input", "frequency"), np.asarray(d["partial_coherence"], dtype=float),
                              dict(ratio, long_name="partial coherence")),
    }
    return xr.Dataset(data, coords={"frequency": f, "signal": d["signals"], "output": d["outputs"],
                                    "input": d["inputs"]},
                      attrs={"segment_samples": d["segment_samples"], "overlap_samples": d["overlap_samples"]})


def _integer(name: str, value: Any, *, minimum: Optional[int] = None) -> int:
    """An integer option: int, numpy integer or an integral float; anything else is a ValueError."""
    if isinstance(value, (bool, np.bool_)):
        raise ValueError(f"{name}: expected an integer, found a boolean {value!r}")
    try:
        v = operator.index(value)
    except TypeError:
        if isinstance(value, (float, np.floating)) and float(value).is_integer():
            v = int(value)
        else:
            raise ValueError(f"{name}: expected an integer, found {value!r}") from None
    if minimum is not None and v < minimum:
        raise ValueError(f"{name}: expected at least {minimum}, found {v}")
    if v > 2**53:  # no count limpid takes is this large; the Rust side would overflow
        raise ValueError(f"{name}: {v} is too large")
    return int(v)


def _number(name: str, value: Any) -> float:
    """A real option: int, float or numpy number (not a string or boolean); finite."""
    if isinstance(value, (bool, np.bool_)) or not isinstance(value, (int, float, np.integer, np.floating)):
        raise ValueError(f"{name}: expected a number, found {value!r}")
    v = float(value)
    if not np.isfinite(v):
        raise ValueError(f"{name}: expected a finite number, found {v}")
    return v


def _choice(name: str, value: Any, choices: Sequence[str]) -> str:
    if not isinstance(value, str) or value not in choices:
        raise ValueError(f"{name}: expected one of {', '.join(choices)}, found {value!r}")
    return value


def _unmasked(name: str, values: Any) -> Any:
    """A numpy masked array's data when nothing is masked; refused when
    something is (its mask would otherwise be ignored: issue 56)."""
    if np.ma.isMaskedArray(values):
        masked = int(np.asarray(getattr(values, "mask"), dtype=bool).sum())
        if masked:
            raise ValueError(f"{name}: a masked array with {masked} masked value(s); "
                             "limpid does not guess them: fill them or drop those samples first")
        return np.asarray(getattr(values, "data"))
    return values


def _column(name: str, values: Any) -> np.ndarray:
    """One column as a contiguous float array; text or objects are refused by
    name, with the first value that is not a number (rows count from 1)."""
    values = _unmasked(f"column {name}", values)
    try:
        a = np.asarray(values, dtype=float)
    except (TypeError, ValueError):
        for row, v in enumerate(np.asarray(values, dtype=object).ravel(), start=1):
            try:
                float(v)
            except (TypeError, ValueError):
                raise ValueError(f"column {name}, row {row}: expected a number, found {v!r}") from None
        raise ValueError(f"column {name}: expected a 1-D array of numbers") from None
    return np.ascontiguousarray(a)


def _recording(rec: RecordingLike) -> Any:
    """A path stays a path; a DataFrame or mapping becomes a dict of float arrays."""
    if isinstance(rec, (str, bytes)) or hasattr(rec, "__fspath__"):
        return rec
    if hasattr(rec, "columns") and not isinstance(rec, Mapping):  # a pandas DataFrame
        columns = {str(c): _column(str(c), rec[c].to_numpy()) for c in rec.columns}
        index = getattr(rec, "index", None)
        if "t" not in columns and index is not None and getattr(index, "name", None) == "t":
            # time as the index, as pandas users keep it
            columns = {"t": _column("t", np.asarray(index)), **columns}
        elif "t" not in columns and index is not None and getattr(index, "name", None) is not None:
            raise ValueError(
                f"the DataFrame has no column t (time, s); its index is {index.name!r}: "
                f"if that is the time, rename it (df.rename_axis('t')) or pass df.reset_index()")
        return columns
    if isinstance(rec, Mapping):
        return {str(k): _column(str(k), v) for k, v in rec.items()}
    raise ValueError("a recording is a path, a dict of 1-D arrays or a pandas DataFrame")


def read_recording(path: Union[str, "os.PathLike[str]"],
                   map: MapLike = None,
                   partial: bool = False,
                   columns: Optional[Mapping[str, str]] = None) -> Dict[str, np.ndarray]:
    """Read a recording (docs/src/format.md) into a dict of arrays.

    CSV, Parquet and MAT files whose columns carry FORMAT.md's names are read
    as they are. Lab files (XDF, C3D, TDMS, MAT v7.3, MAT structs, ROS 2 bags, or a CSV
    with the lab's own names) are read through a channel map: the path of its
    TOML file, or a dict of the same shape, e.g.
    ``{"time": {"stream": "robot"}, "columns": {"x": {"channel": "EndEff.X", "unit": "mm"}}}``
    (docs/src/reference/lab-files.md). Conversion notes arrive as warnings.
    ``partial=True`` reads a file beside the main one (an MVC recording) with
    the same map, leaving out the columns it does not record. ``columns``
    names columns by the file's own channels, e.g. ``{"t": "time_s"}`` (the
    CLI's ``--column t=time_s``); the other columns keep their names.
    """
    checked_map, checked_columns = _reading(map, columns)
    try:
        return _limpid.read_recording(path, checked_map, partial, checked_columns)
    except ValueError as e:
        message = _name_the_column(str(e))
        if message != str(e):
            raise ValueError(message) from None
        raise


def inspect(path: Union[str, "os.PathLike[str]"]) -> Dict[str, Any]:
    """What a lab file holds: its streams with channels, units, rates, gaps and
    marker texts, and a proposed channel map (``proposed_map``, TOML text) where
    channel names are recognisable, as ``limpid inspect FILE --json`` prints."""
    found: Dict[str, Any] = json.loads(_limpid.inspect(path))
    return found


def _welch_args(n: int, nperseg: Optional[int], noverlap: Optional[int], nfft: Optional[int],
                return_onesided: bool, axis: int, average: str) -> Tuple[int, Optional[int]]:
    if nfft is not None and nfft != (nperseg or min(256, n)):
        raise ValueError("nfft different from nperseg is not supported")
    if not return_onesided:
        raise ValueError("only one-sided spectra are supported")
    if axis not in (-1, 0):
        raise ValueError("1-D signals only")
    if average != "mean":
        raise ValueError("only average='mean' is supported")
    seg = 256 if nperseg is None else int(nperseg)
    seg = min(seg, n)  # scipy shortens the segment to the signal (with a warning)
    return seg, noverlap


def _vector(x: Any) -> np.ndarray:
    a = np.ascontiguousarray(np.asarray(_unmasked("signal", x), dtype=float))
    if a.ndim != 1:
        raise ValueError(f"expected a 1-D signal, found {a.ndim} dimensions")
    return a


def frequency_response(inputs: Sequence[Any], outputs: Sequence[Any], fs: float = 1.0,
                       window: str = "hann", nperseg: Optional[int] = None,
                       noverlap: Optional[int] = None, detrend: Union[str, bool] = "constant"
                       ) -> Tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """MIMO H1 frequency response of ``outputs`` on ``inputs`` (lists of 1-D signals)
    with multiple and partial coherences (Welch settings as ``psd``).

    Returns ``(f, H, multiple, partial)`` with ``H[f, output, input]`` complex,
    ``multiple[f, output]`` and ``partial[f, output, input]``. At a frequency
    where the inputs' spectral matrix is singular (an input without power
    there, or two inputs fully coherent) nothing can be identified: those rows
    are NaN (mask them with ``numpy.isfinite``), and a warning says how many."""
    ins = [_vector(x) for x in inputs]
    outs = [_vector(y) for y in outputs]
    n = len(ins[0]) if ins else 0
    if any(len(s) != n for s in ins + outs):
        raise ValueError("all signals must have the same length")
    seg, ov = _welch_args(n, nperseg, noverlap, None, True, -1, "mean")
    f, h, m, p = _limpid.frequency_response(ins, outs, float(fs), window, seg, ov, str(detrend).lower())
    nf, no, ni = len(f), len(outs), len(ins)
    singular = int(np.count_nonzero(~np.isfinite(m.reshape(nf, no)[:, 0]))) if nf and no else 0
    if singular:
        warnings.warn(
            f"frequency_response: the inputs' spectral matrix is singular at {singular} of {nf} "
            "frequencies (no input power there, or inputs fully coherent); H and the coherences are NaN there",
            RuntimeWarning,
            stacklevel=3,
        )
    return f, h.reshape(nf, no, ni), m.reshape(nf, no), p.reshape(nf, no, ni)


def lowpass_filtfilt(x: Any, cutoff_hz: float, fs: float, order: int = 4, axis: int = -1,
                     padtype: Optional[str] = "odd", padlen: Optional[int] = None) -> np.ndarray:
    """Zero-phase Butterworth low-pass, as
    ``scipy.signal.sosfiltfilt(scipy.signal.butter(order, cutoff_hz, fs=fs, output='sos'), x,
    axis=axis, padtype=padtype, padlen=padlen)``.

    Parameters
    ----------
    x : array_like
        Signal(s), any number of dimensions, filtered along ``axis``; complex
        input has its real and imaginary parts filtered (the filter is real).
    cutoff_hz : float
        -3 dB frequency of each pass (Hz), below Nyquist (``fs / 2``).
    fs : float
        Sample rate (Hz).
    order : int, default 4
        Butterworth order per pass (the forward-backward result has twice
        the attenuation slope and zero phase).
    axis : int, default -1
        Axis of the samples.
    padtype : {'odd', 'even', 'constant', None}, default 'odd'
        Extension of each end before filtering, as scipy's.
    padlen : int, optional
        Samples of extension per end; default ``3 * (2 * sections + 1)``
        (scipy's, 27 for order 4). The signal must be longer.

    Returns
    -------
    ndarray
        The filtered signal, float64 (complex128 for complex input), in the shape of ``x``.
    """
    a = np.asarray(_unmasked("x", x))
    if a.dtype.kind not in "biufc":
        raise ValueError(f"x: expected numbers, found dtype {a.dtype}")
    if a.ndim == 0:
        raise ValueError("x: expected an array of samples, found a scalar")
    ax = _spectral._axis(axis, a.ndim, "x")
    if padtype not in ("odd", "even", "constant", None):
        raise ValueError(f"padtype={padtype!r}: expected 'odd', 'even', 'constant' or None")
    pl = None if padlen is None else _spectral._whole("padlen", padlen)
    if pl is not None and pl < 0:
        raise ValueError(f"padlen={pl} must not be negative")
    moved = np.moveaxis(a, ax, -1)
    if pl is not None and padtype is not None and pl >= moved.shape[-1]:
        raise ValueError(f"the signal must be longer than padlen={pl} samples, found {moved.shape[-1]}")
    if padtype is None:
        pl = 0
    args = (_number("cutoff_hz", cutoff_hz), _number("fs", fs), _integer("order", order, minimum=1), padtype, pl)

    def run(part: np.ndarray) -> np.ndarray:
        rows = np.ascontiguousarray(part.reshape(-1, moved.shape[-1]) if moved.size else
                                    np.empty((0, moved.shape[-1])), dtype=np.float64)
        return _limpid.lowpass_filtfilt(rows, *args).reshape(moved.shape)

    y = run(moved.real) + 1j * run(moved.imag) if np.iscomplexobj(moved) else run(moved)
    return np.moveaxis(y, -1, ax)


def _plain(v: Any, depth: int = 0) -> Any:
    """numpy arrays and scalars as Python lists and numbers, the values a request is made of."""
    if isinstance(v, np.ndarray):
        return v.tolist()
    if isinstance(v, np.generic):
        return _plain(v.item(), depth)
    if isinstance(v, float) and v.is_integer() and abs(v) < 2**63:
        return int(v)  # 4.0 is a fine sample count; a float field reads an int as well
    if isinstance(v, (list, tuple)):
        if depth >= 16:
            raise ValueError("options: nested deeper than 16 levels (or it contains itself)")
        return [_plain(x, depth + 1) for x in v]
    return v


def request(method: str, **options: Any) -> Dict[str, Any]:
    """The request an estimator runs with these options, as a dict (what a result's run
    block records and ``limpid rerun`` runs): ``request("reflex")`` shows every default.

    ``method`` is one of linear, cocontraction, planar, window_sweep, stochastic, reflex,
    varying, spectra;
    options are the keyword arguments of the ``estimate_*`` functions. The same request
    is what ``limpid estimate METHOD ... --print-request`` prints for the same settings."""
    r: Dict[str, Any] = _limpid.request(str(method), {k: _plain(v) for k, v in options.items()})
    return r


def _function_name(method: str) -> str:
    return method if method in ("window_sweep", "spectra") else f"estimate_{method}"


def _reading(map: Any, columns: Any) -> Tuple[Any, Optional[Dict[str, str]]]:
    """``map=`` and ``columns=`` as the extension takes them, checked."""
    if map is not None and not isinstance(map, (str, os.PathLike)):
        if not isinstance(map, Mapping):
            raise ValueError("map is the path of a channel map (TOML) or a dict like {'columns': {...}}")
        map = dict(map)
    if columns is not None:
        if not isinstance(columns, Mapping) or not all(
                isinstance(k, str) and isinstance(v, str) for k, v in columns.items()):
            raise ValueError("columns is a dict of column name to the file's channel, e.g. {'t': 'time_s'}")
        columns = dict(columns)
    return map, columns


def _name_the_column(message: str) -> str:
    """A missing column's error with the keyword that names it (the CLI says --column)."""
    missing = re.search(r"missing required column (\S+) .*found columns: ([^;,\s]+)", message)
    if not missing or "columns=" in message:
        return message
    name, first = missing.groups()
    return (message.split("; name it with --column")[0]
            + f"; name it with columns={{{name!r}: {first!r}}} (a column of the file), "
              f"or pass map= (limpid.inspect(path)['proposed_map'] proposes one)")


def _estimate(method: str, recordings: Sequence[RecordingLike], options: Mapping[str, Any]) -> Result:
    options = dict(options)
    map, columns = _reading(options.pop("map", None), options.pop("columns", None))
    opts = {k: _plain(v) for k, v in options.items()}
    try:
        return Result(json.loads(_limpid.estimate(method, [_recording(r) for r in recordings], opts,
                                                  map, columns)))
    except ValueError as e:
        message = _name_the_column(str(e))
        if message != str(e):
            raise ValueError(message) from None
        wrong = re.match(r"invalid (\w+): TypeError: (.*)", message)
        if wrong and wrong.group(1) in opts:
            value = opts[wrong.group(1)]
            raise ValueError(
                f"{_function_name(method)}: {wrong.group(1)} = {value!r}: a number is expected, "
                f"not {type(value).__name__}") from None
        if re.search(r"\brow \d+", message) and not all(
                isinstance(r, (str, bytes)) or hasattr(r, "__fspath__") for r in recordings):
            # a DataFrame's rows count from 0; the library's from 1
            raise ValueError(message + " (rows count from 1: pandas' index from 0)") from None
        raise


class StudyOutcome:
    """One recording of a study, processed (``ok``) or failed (``error``):
    what :func:`study_process` returns and :func:`study_combine` joins.
    Picklable, so it can come back from another process or machine."""

    __slots__ = ("subject", "configuration", "file", "ok", "error", "_json")

    def __init__(self, text: str) -> None:
        d = json.loads(text)
        body = d.get("Ok") or d.get("Err") or {}
        self.ok: bool = "Ok" in d
        self.subject: str = body.get("subject", "")
        self.configuration: str = body.get("configuration", "")
        self.file: str = body.get("file", "")
        self.error: Optional[str] = None if self.ok else body.get("error")
        self._json = text

    def result(self) -> "Result":
        """The recording's co-contraction result (``ValueError`` if it failed)."""
        if not self.ok:
            raise ValueError(f"subject {self.subject}, configuration {self.configuration}: {self.error}")
        return Result(json.loads(self._json)["Ok"]["result"])

    def __getstate__(self) -> str:
        return self._json

    def __setstate__(self, text: str) -> None:
        self.__init__(text)  # type: ignore[misc]

    def __repr__(self) -> str:
        state = "ok" if self.ok else f"failed: {self.error}"
        return f"StudyOutcome(subject={self.subject!r}, configuration={self.configuration!r}, {state})"


def study_entries(manifest: Union[str, "os.PathLike[str]"]) -> List[Dict[str, Any]]:
    """The recordings of a study manifest (``limpid study run``'s TOML), paths
    resolved, each a dict ready for :func:`study_process` on any worker.

    Parameters
    ----------
    manifest : path
        The study's TOML manifest (``[[recording]]`` with subject,
        configuration, file, mvc).

    Returns
    -------
    list of dict
        ``{"subject", "configuration", "file", "mvc", "request", "tolerance", "study"}`` per
        recording (``tolerance`` repeats the request's, and wins when edited);
        ``request`` is the study's co-contraction request (``[study.request]``, with
        ``study.tolerance`` folded in), as :func:`request` returns it.
    """
    m = json.loads(_limpid.study_entries(os.fspath(manifest)))
    meta = m.get("study") or {}
    options: Dict[str, Any] = dict(meta.get("request") or {})
    if meta.get("tolerance") is not None:
        options["tolerance"] = meta["tolerance"]
    study_request = request("cocontraction", **options)
    name = meta.get("name") or "study"
    return [dict(e, request=study_request, tolerance=study_request["tolerance"], study=name)
            for e in m["recording"]]


def study_process(entry: Mapping[str, Any]) -> StudyOutcome:
    """Process one study recording (one entry of :func:`study_entries`):
    Patel, O'Neill & Artemiadis (2013)'s co-contraction analysis, or the reason it failed. Never
    raises for a bad recording: the failure is kept for the study's table
    of failures, as ``limpid study run`` does."""
    e = {k: os.fspath(entry[k]) if k in ("file", "mvc") else str(entry[k])
         for k in ("subject", "configuration", "file", "mvc")}
    if entry.get("map") is not None:
        e["map"] = os.fspath(entry["map"])
    options = dict(entry.get("request") or {})
    if entry.get("tolerance") is not None:  # entries made before requests
        options["tolerance"] = entry["tolerance"]
    options.pop("method", None)
    return StudyOutcome(_limpid.study_process(json.dumps(e), {k: _plain(v) for k, v in options.items()}))


def study_combine(outcomes: Sequence[StudyOutcome], *, name: str = "study",
                  out: Optional[Union[str, "os.PathLike[str]"]] = None) -> Result:
    """Patel, O'Neill & Artemiadis (2013)'s Tables 1-5 from the outcomes of :func:`study_process`
    (gathered from any executor), as ``limpid study run``; the tables
    (tables.csv, rotation.csv, study.json, tables.md) are written to ``out``
    when given. ``ValueError`` when no recording could be processed."""
    texts = []
    for o in outcomes:
        if not isinstance(o, StudyOutcome):
            raise ValueError(f"study_combine takes StudyOutcome objects (from study_process), found {type(o).__name__}")
        texts.append(o._json)
    return Result(json.loads(_limpid.study_combine(str(name), texts, None if out is None else os.fspath(out))))


def study_run(manifest: Union[str, "os.PathLike[str]"], *,
              out: Optional[Union[str, "os.PathLike[str]"]] = None) -> Result:
    """``limpid study run``: every recording of the manifest processed in
    parallel on this machine, Patel, O'Neill & Artemiadis (2013)'s Tables 1-5 returned (``levels``,
    ``rotation``, ``failures``, ``recordings``) and written to ``out`` when
    given. For a study spread over processes or a cluster, use
    :func:`study_entries`, :func:`study_process` and :func:`study_combine`
    (docs/src/python.md, "Python: studies, here or on a cluster")."""
    return Result(json.loads(_limpid.study_run(os.fspath(manifest), None if out is None else os.fspath(out))))


def ellipsoid(matrix: Any) -> Result:
    """Ellipsoid of the symmetric part of a 2 x 2 or 3 x 3 matrix (Artemiadis et al. 2010, eq. 13-17)."""
    m = np.asarray(matrix, dtype=float)
    return Result(json.loads(_limpid.ellipsoid(m.tolist())))


def protocol_preset(name: str) -> str:
    """A preset protocol as TOML: artemiadis-3d, patel-cocontraction, lakatos-planar, park-stochastic."""
    return _limpid.protocol_preset(name)


def protocol_check(toml_text: str) -> Result:
    """Check a protocol (TOML text) against its limits; raises ValueError at the first breach."""
    return Result(json.loads(_limpid.protocol_check(toml_text)))


def _text_or_file(value: Union[str, "os.PathLike[str]"]) -> Tuple[str, str]:
    """(text, name): TOML text as given, or a file's text and its path."""
    if isinstance(value, str) and ("\n" in value or "=" in value):
        return value, "<text>"
    name = os.fspath(value)
    with open(name, encoding="utf-8") as f:
        return f.read(), name


def design(
    prior: Union[str, "os.PathLike[str]"],
    duration_s: float,
    *,
    limits_from: Optional[Union[str, "os.PathLike[str]"]] = None,
    objective: str = "stiffness,damping",
    baseline: Optional[Union[str, "os.PathLike[str]"]] = None,
    verify: int = 0,
    runs: int = 40,
    seed: int = 1,
    method: str = "linear",
    robust: str = "worst",
) -> Tuple[str, Result]:
    """Design a centre-out protocol for the linear method, as ``limpid
    protocol design``: (the protocol as TOML text, the result).

    ``prior`` is ``"demo:S1"`` .. ``"demo:S6"`` (the demo's realistic subject),
    TOML text or a path to a prior file (3 x 3 ``inertia``, ``damping``,
    ``stiffness``, optional ``start_m``, ``[other_end]``, ``[noise]``,
    ``[limits]``). ``limits_from`` and ``baseline`` are centre-out protocols:
    a preset name (``"artemiadis-3d"``), TOML text or a path. The result has
    ``predicted`` and ``baseline`` (pooled standard errors, errors, shares
    identifiable), ``limits`` (margins), ``chosen``, ``command`` and
    ``spectrum`` (for ``limpid.plot.design``) and, with ``verify`` > 0,
    ``verify`` (predicted against achieved spread).

    ``method="stochastic"``: an end-point multisine for ``estimate_stochastic``
    with ``period_s`` (``family`` ``multisine`` in the result); the same priors,
    ``limits_from`` an end-point periodic protocol (``"endpoint-multisine"``) or
    a centre-out one, ``baseline`` an end-point multisine.

    ``method="reflex"``: a PRBS for the stretch-reflex gain (``kind``
    ``reflex_design``); ``prior`` is ``"demo:ankle"``, an ankle's TOML text or
    file, ``limits_from`` and ``baseline`` PRBS protocols (``"ankle-prbs"``).

    ``method="planar"``: quintic joint perturbations for ``estimate_planar``
    (``kind`` ``planar_design``; predicted K, D and ξ); ``prior`` is
    ``"demo:planar"`` (seed 003's arm holding a load, with a reflex at 90 ms)
    or an arm's TOML text or file (``xi``, 2 x 2 joint ``stiffness`` and
    ``damping``, optional ``posture_rad``, ``tau0``, ``[other_end]``,
    ``[reflex]``, ``[noise]``, ``[limits]``), ``limits_from`` and
    ``baseline`` planar protocols (``"lakatos-planar"``, the default limits).

    ``robust``: over a prior's range (``[other_end]``), ``"worst"`` (the
    worse end; conservative for the subjects between) or ``"expected"`` (the
    mean over its ends and midpoint). Not for the reflex method."""

    def protocol_text(value: Optional[Union[str, "os.PathLike[str]"]]) -> Optional[str]:
        if value is None:
            return None
        if isinstance(value, str) and "\n" not in value and "=" not in value and not os.path.exists(value):
            return protocol_preset(value)
        return _text_or_file(value)[0]

    _choice("method", method, ("linear", "stochastic", "reflex", "planar"))
    _choice("robust", robust, ("worst", "expected"))
    if isinstance(prior, str) and prior.startswith("demo:"):
        prior_text, prior_name = prior, "<prior>"
    else:
        prior_text, prior_name = _text_or_file(prior)
    duration = _number("duration_s", duration_s)
    toml_text, doc = _limpid.design(
        prior_text,
        duration,
        protocol_text(limits_from),
        objective,
        protocol_text(baseline),
        _integer("verify", verify, minimum=0),
        _integer("runs", runs, minimum=0),
        _integer("seed", seed, minimum=0),
        prior_name,
        method,
        robust,
    )
    return toml_text, Result(json.loads(doc))


def simulate(
    protocol: str,
    seed: int = 1,
    subject: Optional[Union[str, "os.PathLike[str]"]] = None,
    controller: str = "ideal",
) -> List[Tuple[Dict[str, np.ndarray], Dict[str, Any]]]:
    """Simulate a protocol (TOML text or preset name), as ``limpid simulate``:
    a list of (columns, truth), one per recording (centre-out: one per start
    point).

    ``subject`` is TOML text or a path to a TOML file (the CLI's ``--subject``
    format for the protocol's kind); without it the built-in subjects are used
    (centre-out: Artemiadis et al. 2010's subject 1; planar: the Lakatos et al. 2011 arm; stochastic:
    spring set SA3; periodic: the ankle, planar arm or 3-D end point by the protocol's channels,
    each taking ``quadratic`` and ``cubic`` stiffness terms). ``controller`` (stochastic protocols) is ``ideal``,
    ``imbic`` or ``pd``: who holds the spring array."""
    text = protocol if "\n" in protocol or "=" in protocol else protocol_preset(protocol)
    subject_text = None
    subject_name = "<subject>"
    if subject is not None:
        if isinstance(subject, str) and ("\n" in subject or "=" in subject):
            subject_text = subject
        else:
            subject_name = os.fspath(subject)
            with open(subject_name, encoding="utf-8") as f:
                subject_text = f.read()
    return [
        (cols, json.loads(truth))
        for cols, truth in _limpid.simulate(text, _integer("seed", seed, minimum=0), subject_text, subject_name,
                                            _choice("controller", controller, ("ideal", "imbic", "pd")))
    ]


def gravity_compensate(recording: RecordingLike, *, bias: Optional[RecordingLike] = None,
                       calibration: Optional[RecordingLike] = None, initial_s: float = 1.0,
                       robot: Optional[str] = None,
                       robot_base: Optional[Sequence[float]] = None) -> Tuple[Dict[str, np.ndarray], List[str]]:
    """F/T sensor readings (``sensor_fx..z``, optionally ``sensor_tx..z``) to the force
    (and torque) on the limb, as ``limpid gravity-compensate``: Park & Chang (2011)'s two steps
    (``bias``: readings in a gravity-free pose; ``initial_s``: the still start of the
    test) or a ``calibration`` from still poses (weight, centre of mass, biases).
    The orientation comes from ``robot`` (``kuka-lwr4``, ``puma3`` or a URDF path,
    placed at ``robot_base``) and the ``robot_q*`` columns, else from ``theta``.
    Returns (columns with ``fx, fy, fz`` [and ``taux, tauy, tauz``], summary lines)."""
    base = [float(v) for v in robot_base] if robot_base is not None else None
    return _limpid.gravity_compensate(
        _recording(recording),
        None if bias is None else _recording(bias),
        None if calibration is None else _recording(calibration),
        float(initial_s), robot, base)


def report(results: Sequence[Union[Result, Mapping[str, Any], List[Any]]], path: Union[str, "os.PathLike[str]"]) -> None:
    """Write one self-contained HTML report of results to ``path``."""
    texts = [json.dumps(r.to_dict() if isinstance(r, Result) else r) for r in results]
    _limpid.report(texts, path)


def _value_errors(f: Any) -> Any:
    """Bad argument values raise ValueError, whatever their type: a TypeError,
    OverflowError or IndexError raised while a call's arguments are read
    becomes a ValueError naming the function (chained to the original). A
    call with the wrong arguments for the signature stays a TypeError."""
    import functools
    import inspect

    sig = inspect.signature(f)

    @functools.wraps(f)
    def checked(*args: Any, **kwargs: Any) -> Any:
        try:
            sig.bind(*args, **kwargs)
        except TypeError as e:
            unknown = re.search(r"unexpected keyword argument '(\w+)'", str(e))
            if not unknown:
                raise
            # name the nearest option and list them all (issue 63, item 7)
            names = [p.name for p in sig.parameters.values()
                     if p.kind in (p.KEYWORD_ONLY, p.POSITIONAL_OR_KEYWORD)]
            close = difflib.get_close_matches(unknown.group(1), names, n=1)
            hint = f"; did you mean {close[0]!r}?" if close else ""
            raise TypeError(f"{f.__name__}() got an unexpected keyword argument {unknown.group(1)!r}{hint} "
                            f"(its options: {', '.join(names)})") from None
        try:
            return f(*args, **kwargs)
        except (TypeError, OverflowError, IndexError) as e:
            if isinstance(e, TypeError) and "unexpected keyword argument" in str(e):
                raise
            if isinstance(e, TypeError) and "unknown field" in str(e):
                # an option the estimator does not have: a wrong call, as Python says
                raise TypeError(f"{f.__name__}() got an unexpected keyword argument: {e}") from None
            raise ValueError(f"{f.__name__}: {e}") from e

    return checked


def set_threads(threads: Optional[int] = None) -> None:
    """How many threads limpid's estimators run on: ``threads`` (at least 1),
    or ``None`` for one a core (the default). Takes effect at the next call;
    a forked worker (multiprocessing, dask) starts its own pool of this size."""
    if threads is not None and (isinstance(threads, bool) or not isinstance(threads, int)):
        # a TypeError: turned into "set_threads: ..." ValueError as every bad value
        raise TypeError(f"expected an int or None, found {type(threads).__name__}")
    _limpid.set_threads(threads)


def __dir__() -> List[str]:
    """The public API only (not the modules and typing names used inside)."""
    return sorted(__all__)


from ._estimators import (  # noqa: E402  (they use Result and _estimate above)
    estimate_cocontraction, estimate_linear, estimate_planar, estimate_reflex, estimate_stochastic,
    estimate_varying, spectra, window_sweep)

for _name in __all__:
    _obj = globals()[_name]
    if isinstance(_obj, str):
        continue
    if callable(_obj) and not isinstance(_obj, type):
        globals()[_name] = _value_errors(_obj)
del _name, _obj
