"""Figures of limpid results with matplotlib (``pip install limpid[plot]``).

Every function takes a :class:`limpid.Result` (or its dict) and one keyword
for where to draw, ``ax=``, as matplotlib, pandas and python-control do:

- ``ax=None`` (default): a new figure, laid out once (no ``tight_layout`` on
  every call: a 6 x 3 Bode grid draws in well under 0.5 s);
- a single ``Axes`` for the one-panel plots (``ellipsoids`` needs a 3-D one);
- an array of ``Axes`` of the plot's shape for the multi-panel plots, e.g.
  ``fig, ax = plt.subplots(6, 3); plot.bode(r, ax=ax)``; anything else is a
  ``ValueError`` naming the shape wanted. The caller's figure keeps its layout.

Each returns a :class:`Plot`: ``.figure`` and ``.axes`` (a rows x columns
array, also for one panel), and ``.savefig(...)``. Every axis carries its
quantity and unit; log axes read as plain numbers (0.5, 1, 2, 5, 10).

- :func:`ellipsoids` — stiffness (or damping) ellipsoids in 3-D: the
  principal axes of the symmetric part, each as long as its eigenvalue
  (Patel et al. 2013's convention; Artemiadis et al. 2010 draw 1/sqrt(λ));
  one per level of a co-contraction result.
- :func:`ellipses` — the planar arm's end-point stiffness ellipse
  (Lakatos et al. 2011), or any 2-D result's.
- :func:`fit` — measured against predicted force or torque.
- :func:`bode` — |Z(f)| and phase per element with the parametric model
  (Park & Chang 2011), the fit band shaded; the measured phase is drawn on
  the fit's branch (whole turns added point by point), so +179° and -181°
  do not look like a failed fit.
- :func:`coherence` — multiple and partial coherences against frequency.
- :func:`periodic` — a periodic analysis: excited and detection lines, noise,
  |G| with ±2 SE.
- :func:`sweep` — K and D against the observation window with ±1 SE bands,
  trusted windows marked (Lakatos et al. 2011 §IV).
- :func:`reflex` — intrinsic and reflex impulse responses (per second, against
  lag in ms) and the reflex pathway's static nonlinearity (parallel cascade).
- :func:`varying` — K, B and I against time, an operating point or gait
  phase with ±2 SE bands; walking adds the stance | swing boundary and the
  perturbations (or strides) behind each point.
- :func:`design` — a designed perturbation, its spectrum against the limits
  and the predicted standard errors.
- :func:`study` — a co-contraction study's stiffness against the
  co-contraction index per configuration.
"""

from __future__ import annotations

import math
from typing import Any, Dict, List, Optional, Tuple

import numpy as np

from . import _display

__all__ = ["Plot", "ellipsoids", "ellipses", "fit", "bode", "coherence", "periodic", "sweep", "reflex", "design",
           "varying", "study"]


def __dir__() -> List[str]:
    """The plot functions only (not the modules and typing names used inside)."""
    return sorted(__all__)


class Plot:
    """What a plot function drew: ``figure`` (a matplotlib Figure) and ``axes``
    (a rows x columns numpy array of its Axes, also for a single panel)."""

    __slots__ = ("figure", "axes")

    def __init__(self, figure: Any, axes: Any) -> None:
        self.figure = figure
        self.axes = axes

    @property
    def ax(self) -> Any:
        """The first (for one-panel plots: the only) Axes."""
        return self.axes.flat[0]

    def savefig(self, *args: Any, **kwargs: Any) -> None:
        """The figure's ``savefig``."""
        self.figure.savefig(*args, **kwargs)

    def __repr__(self) -> str:
        rows, cols = self.axes.shape
        return f"limpid.plot.Plot({rows} x {cols} axes: {self.axes.flat[0].get_title() or 'untitled'!r})"


def _plt() -> Any:
    try:
        import matplotlib.pyplot as plt
    except ImportError:
        raise ImportError("limpid.plot needs matplotlib: pip install 'limpid[plot]' (or pip install matplotlib)") from None
    return plt


def _data(result: Any) -> Dict[str, Any]:
    if hasattr(result, "to_dict"):
        d: Dict[str, Any] = result.to_dict()
        return d
    if isinstance(result, dict):
        return result
    raise ValueError("expected a limpid.Result or its dict")


def _kind(d: Dict[str, Any], *kinds: str) -> str:
    k = str(d.get("kind"))
    if k not in kinds:
        raise ValueError(f"this plot is for {', '.join(kinds)} results, this one is {k!r}")
    return k


def _panels(ax: Any, rows: int, cols: int, what: str, panel: Tuple[float, float] = (3.2, 2.4),
            sharex: bool = False, projection: Optional[str] = None) -> Tuple[Any, Any, bool]:
    """The figure and a rows x cols array of Axes to draw `what` into: the
    caller's (`ax`, checked) or a new figure's; the flag says whether it is new."""
    plt = _plt()
    if ax is None:
        width, height = panel
        # margins and gaps in inches, so labels fit without tight_layout (1-3 s on a 6 x 3 grid)
        left, right, bottom, top, wgap, hgap = 0.85, 0.2, 0.55, 0.4, 0.8, 0.5 if sharex else 0.75
        fw = left + right + cols * width + (cols - 1) * wgap
        fh = bottom + top + rows * height + (rows - 1) * hgap
        fig, a = plt.subplots(rows, cols, squeeze=False, figsize=(fw, fh), sharex=sharex,
                              subplot_kw={"projection": projection} if projection else None)
        fig.subplots_adjust(left=left / fw, right=1 - right / fw, bottom=bottom / fh, top=1 - top / fh,
                            wspace=wgap / width, hspace=hgap / height)
        return fig, a, True
    shape = f"{rows} x {cols}"
    wanted = "a single Axes" if rows * cols == 1 else f"an array of {shape} Axes, e.g. plt.subplots({rows}, {cols})[1]"
    a = np.asarray(ax, dtype=object)
    if a.size != rows * cols or (a.ndim == 2 and a.shape != (rows, cols)):
        got = "one Axes" if a.ndim == 0 else f"{'x'.join(map(str, a.shape))} of them"
        raise ValueError(f"{what} draws {shape} panels: ax= takes {wanted}; got {got}")
    a = a.reshape(rows, cols)
    for x in a.flat:
        if not (hasattr(x, "figure") and hasattr(x, "plot")):
            raise ValueError(f"{what}: ax= takes matplotlib Axes, got {type(x).__name__}")
        if projection == "3d" and not hasattr(x, "get_zlim"):
            raise ValueError(f"{what} needs a 3-D Axes: fig.add_subplot(projection='3d')")
        if projection is None and hasattr(x, "get_zlim"):
            # a 3-D Axes draws a 2-D figure only with matplotlib's own error
            raise ValueError(f"{what} draws on 2-D Axes: ax= takes plt.subplots(...)[1], not a 3-D Axes")
    return a.flat[0].figure, a, False


def _plain(v: float, _pos: Any = None) -> str:
    return f"{v:g}"


def _log_ticks(axis: Any, values: Any) -> None:
    """Plain numbers on a log axis (0.5, 1, 2, 5 rather than 1.35×10⁰): 1-2-5
    steps when `values` span less than two decades, decades beyond. `axis`
    is ``ax.xaxis`` or ``ax.yaxis``; the span comes from the data, which is
    cheaper than asking matplotlib for the limits (an autoscale per call)."""
    from matplotlib.ticker import FuncFormatter, LogLocator, NullFormatter, NullLocator

    v = np.asarray(values, dtype=float)
    v = v[np.isfinite(v) & (v > 0)]
    decades = math.log10(float(v.max()) / float(v.min())) if v.size else 3.0
    axis.set_major_formatter(FuncFormatter(_plain))
    if decades < 2:
        # 1-2-5 majors say the scale; minor ticks would only cost drawing time
        axis.set_major_locator(LogLocator(base=10, subs=(1.0, 2.0, 5.0)))
        axis.set_minor_locator(NullLocator())
    else:
        axis.set_major_locator(LogLocator(base=10))
        axis.set_minor_formatter(NullFormatter())


# ---------------------------------------------------------------- ellipsoids


def _ellipsoid_list(d: Dict[str, Any], matrix: str) -> List[Any]:
    kind = _kind(d, "linear", "cocontraction", "demo")
    if kind == "linear":
        return [("", d["ellipsoids"].get(matrix))]
    if kind == "demo":
        return [(p["start_point"], p["estimate"]["ellipsoids"].get(matrix)) for p in d["points"]]
    if matrix != "stiffness":
        return [(f"level {lv['level']:g}", lv["estimate"]["ellipsoids"].get(matrix)) for lv in d["levels"]]
    return [(f"level {lv['level']:g}", lv.get("ellipsoid")) for lv in d["levels"]]


def ellipsoids(result: Any, ax: Any = None, matrix: str = "stiffness") -> Plot:
    """3-D ellipsoids of a linear, co-contraction (one per level) or demo
    (one per start point) result: axes along the principal directions of the
    symmetric part, lengths |λ| in the matrix's unit. A matrix that is not
    positive definite is drawn with |λ| and says so in the legend.
    ``ax``: one 3-D Axes (``fig.add_subplot(projection='3d')``) or None."""
    d = _data(result)
    items = [(label, e) for label, e in _ellipsoid_list(d, matrix) if e is not None and len(e["axes"]) == 3]
    if not items:
        raise ValueError(f"this result has no 3-D {matrix} ellipsoid (2-D or 1-D data: use plot.ellipses)")
    fig, a, _ = _panels(ax, 1, 1, "plot.ellipsoids", panel=(4.5, 3.6), projection="3d")
    ax = a[0, 0]
    unit = _display._unit(matrix, "x", "x")
    u, v = np.meshgrid(np.linspace(0, 2 * np.pi, 36), np.linspace(0, np.pi, 18))
    sphere = np.stack([np.cos(u) * np.sin(v), np.sin(u) * np.sin(v), np.cos(v)])
    colors = ["#0072B2", "#D55E00", "#009E73", "#CC79A7", "#E69F00", "#56B4E9", "#000000"]
    reach = 0.0
    for n, (label, e) in enumerate(items):
        axes = np.asarray(e["axes"], dtype=float)
        lam = np.asarray(e["radii_proportional"], dtype=float)
        pts = axes @ (np.abs(lam)[:, None, None] * sphere).reshape(3, -1)
        x, y, z = (pts[i].reshape(u.shape) for i in range(3))
        c = colors[n % len(colors)]
        note = "" if np.all(lam > 0) else " (not positive definite: |λ|)"
        ax.plot_wireframe(x, y, z, color=c, linewidth=0.5, alpha=0.7, label=(label or matrix) + note)
        reach = max(reach, float(np.abs(lam).max()))
    lim = reach * 1.05 or 1.0
    for setter in (ax.set_xlim, ax.set_ylim, ax.set_zlim):
        setter(-lim, lim)
    ax.set_xlabel(f"x ({unit})")
    ax.set_ylabel(f"y ({unit})")
    ax.set_zlabel(f"z ({unit})")
    ax.set_title(f"{matrix.capitalize()} ellipsoid" + ("s" if len(items) > 1 else ""))
    ax.legend(loc="upper left", fontsize="small")
    return Plot(fig, a)


def ellipses(result: Any, ax: Any = None, matrix: Optional[str] = None) -> Plot:
    """The end-point stiffness ellipse of a planar result (or the 2-D
    stiffness of a linear result): principal axes with lengths |λ| (N/m),
    centred at the origin. ``ax``: one Axes or None."""
    from . import ellipsoid as _ellipsoid

    d = _data(result)
    kind = _kind(d, "planar", "linear")
    if kind == "planar":
        m = d["endpoint_stiffness"] if matrix in (None, "endpoint_stiffness") else d[matrix]
        coords = ["x", "y"] if matrix in (None, "endpoint_stiffness") else ["q1", "q2"]
        name = "end-point stiffness" if matrix in (None, "endpoint_stiffness") else matrix
        qty = "stiffness" if matrix in (None, "endpoint_stiffness", "stiffness") else "damping"
    else:
        m = d[matrix or "stiffness"]
        coords = d["provenance"]["coordinates"]
        name = qty = matrix or "stiffness"
        if len(coords) != 2:
            raise ValueError("ellipses are for 2-D results; 3-D ones: plot.ellipsoids")
    e = _ellipsoid(m)
    axes = np.asarray(e.axes, dtype=float)
    lam = np.asarray(e.radii_proportional, dtype=float)
    t = np.linspace(0, 2 * np.pi, 200)
    pts = axes @ (np.abs(lam)[:, None] * np.stack([np.cos(t), np.sin(t)]))
    fig, a, _ = _panels(ax, 1, 1, "plot.ellipses", panel=(4.0, 3.6))
    ax = a[0, 0]
    unit = _display._unit(qty, coords[0], coords[0])
    ax.plot(pts[0], pts[1], color="#0072B2",
            label=name + ("" if np.all(lam > 0) else " (not positive definite: |λ|)"))
    for k in range(2):
        ax.plot([0, axes[0, k] * abs(lam[k])], [0, axes[1, k] * abs(lam[k])], color="#0072B2", linewidth=0.8)
    ax.set_aspect("equal", adjustable="datalim")
    ax.set_xlabel(f"{coords[0]} ({unit})")
    ax.set_ylabel(f"{coords[1]} ({unit})")
    ax.set_title(f"{name.capitalize()} ellipse")
    ax.legend(fontsize="small")
    return Plot(fig, a)


# ---------------------------------------------------------------- fit


def fit(result: Any, ax: Any = None) -> Plot:
    """Measured against predicted force (or torque) per coordinate: linear,
    planar (joint torques) and reflex (total torque with the intrinsic and
    reflex parts). ``ax``: one Axes per coordinate (n x 1; reflex: one) or None."""
    d = _data(result)
    kind = _kind(d, "linear", "planar", "reflex")
    if kind == "reflex":
        tr = d["traces"]
        fig, a, _ = _panels(ax, 1, 1, "plot.fit of a reflex result", panel=(6.5, 2.6))
        axx = a[0, 0]
        unit = _display._force_unit(d, d["position"])
        axx.plot(tr["t_s"], tr["measured"], color="#000000", linewidth=1, label="measured")
        axx.plot(tr["t_s"], np.add(tr["intrinsic"], tr["reflex"]), color="#0072B2", linestyle="--",
                 label="predicted")
        axx.plot(tr["t_s"], tr["reflex"], color="#D55E00", linewidth=0.8, label="reflex part")
        axx.set_xlabel("time (s)")
        axx.set_ylabel(f"torque {d['torque']} ({unit})")
        axx.set_title(f"Parallel-cascade fit (VAF {d['fit']['vaf_total']:.1f} %)")
        axx.legend(fontsize="small")
        return Plot(fig, a)
    if kind == "linear":
        tr = d["fit"]["traces"]
        coords = d["provenance"]["coordinates"]
        names = d["provenance"].get("force_columns") or coords
        vaf = d["fit"]["vaf"]
    else:
        tr = d.get("traces")
        if not tr:
            raise ValueError("this planar result carries no fit traces")
        coords = ["q1", "q2"]
        names = ["tau1", "tau2"]
        vaf = d["fit"]["vaf"]
    n = len(tr["measured"])
    fig, a, _ = _panels(ax, n, 1, f"plot.fit of a {kind} result", panel=(6.5, 1.8), sharex=True)
    for i in range(n):
        axx = a[i, 0]
        unit = _display._force_unit(d, coords[i])
        axx.plot(tr["time"], tr["measured"][i], color="#000000", linewidth=1, label="measured")
        axx.plot(tr["time"], tr["predicted"][i], color="#0072B2", linestyle="--", label="predicted")
        axx.set_ylabel(f"{names[i]} ({unit})")
        axx.set_title(f"{names[i]}: VAF {vaf[i]:.1f} %", fontsize="medium")
    a[-1, 0].set_xlabel("time (s)")
    a[0, 0].legend(fontsize="small")
    return Plot(fig, a)


# ---------------------------------------------------------------- frequency domain


def _on_branch(reference: Any, trace: Any) -> Any:
    """Phases (rad) of `trace` moved, point by point, by whole turns to lie
    within half a turn of the unwrapped `reference` at the same frequency:
    an estimate at +179° and its fit at -181° are drawn as the same phase."""
    ref = np.unwrap(reference)
    return trace - 2 * np.pi * np.round((trace - ref) / (2 * np.pi))


def bode(result: Any, ax: Any = None) -> Plot:
    """|Z(f)| (log-log) and phase per element of a stochastic result, with
    the fitted K - (2πf)² M + j 2πf B dashed and the fit band shaded. The
    measured phase is drawn on the fit's branch. ``ax``: 2n x n Axes
    (magnitude above phase for each element) or None."""
    d = _data(result)
    _kind(d, "stochastic")
    f = np.asarray(d["frequencies"], dtype=float)
    z = np.asarray(d["impedance"], dtype=float)
    z = z[..., 0] + 1j * z[..., 1]
    coords = d["coordinates"]
    n = len(coords)
    k, b, m = (np.asarray(d[q], dtype=float) for q in ("stiffness", "damping", "inertia"))
    w = 2 * np.pi * f
    model = k[None] - (w**2)[:, None, None] * m[None] + 1j * w[:, None, None] * b[None]
    lo, hi = d["criteria"]["band_hz"]
    fig, a, _ = _panels(ax, 2 * n, n, "plot.bode", panel=(2.9, 1.55), sharex=True)
    ok = f > 0
    fo = f[ok]
    for i in range(n):
        for j in range(n):
            unit = _display._unit("stiffness", coords[i], coords[j])
            mag, ph = a[2 * i, j], a[2 * i + 1, j]
            fit_phase = np.unwrap(np.angle(model[ok, i, j]))
            zm, mm = np.abs(z[ok, i, j]), np.abs(model[ok, i, j])
            for axx in (mag, ph):
                axx.set_xscale("log")
                axx.axvspan(lo, hi, color="#f0f0f0", zorder=0)
            mag.set_yscale("log")
            mag.plot(fo, zm, color="#000000", linewidth=1, label="Z(f)")
            mag.plot(fo, mm, color="#0072B2", linestyle="--", label="fit")
            ph.plot(fo, np.degrees(_on_branch(fit_phase, np.angle(z[ok, i, j]))), color="#000000", linewidth=1)
            ph.plot(fo, np.degrees(fit_phase), color="#0072B2", linestyle="--")
            _log_ticks(mag.yaxis, np.concatenate([zm, mm]))
            mag.set_title(f"Z {coords[i]},{coords[j]}", fontsize="medium")
            mag.set_ylabel(f"|Z| ({unit})")
            ph.set_ylabel("phase (deg)")
            if i == n - 1:
                ph.set_xlabel("frequency (Hz)")
    _log_ticks(a[0, 0].xaxis, fo)
    a[0, 0].legend(fontsize="small")
    return Plot(fig, a)


def coherence(result: Any, ax: Any = None) -> Plot:
    """Multiple coherence of each output and partial coherence on each input
    of a stochastic or spectra result, against frequency (Park & Chang 2011); coherence
    is a ratio, its axes carry no unit. ``ax``: one Axes per output (n x 1) or None."""
    d = _data(result)
    kind = _kind(d, "stochastic", "spectra")
    f = np.asarray(d["frequencies"], dtype=float)
    if kind == "stochastic":
        coh = d["coherence"]
        outs, ins = coh["outputs"], d["inputs"]
        mult = np.asarray(coh["multiple"], dtype=float)  # [output][frequency]
        part = np.asarray(coh["partial"], dtype=float)  # [output][input][frequency]
    else:
        # spectra: None where the inputs' spectral matrix is singular, drawn as gaps
        outs, ins = d["outputs"], d["inputs"]
        mult = np.asarray([[math.nan if v is None else v for v in row] for row in d["multiple_coherence"]],
                          dtype=float)
        part = np.asarray([[[math.nan if v is None else v for v in r] for r in o] for o in d["partial_coherence"]],
                          dtype=float)
    n = len(outs)
    fig, a, _ = _panels(ax, n, 1, "plot.coherence", panel=(5.5, 1.3), sharex=True)
    ok = f > 0
    for i in range(n):
        axx = a[i, 0]
        axx.semilogx(f[ok], mult[i][ok], color="#000000", linewidth=1.4, label="multiple")
        for j, name in enumerate(ins):
            axx.semilogx(f[ok], part[i, j][ok], linewidth=0.9, linestyle="--", label=f"partial on {name}")
        axx.set_ylim(0, 1.05)
        axx.set_ylabel(f"coherence of {outs[i]}")
        _log_ticks(axx.xaxis, f[ok])
    a[-1, 0].set_xlabel("frequency (Hz)")
    a[0, 0].legend(fontsize="small", ncol=2)
    return Plot(fig, a)


def periodic(result: Any, ax: Any = None) -> Plot:
    """A periodic analysis (``limpid.spectra(..., period_s=...)`` or
    ``limpid.estimate_stochastic(..., period_s=...)``): the output at the
    excited, odd-detection and even-detection lines as distinct marks and
    the noise of the period average (dB relative to the excited lines),
    then |G| of each input-output pair at its excited lines with ±2 SE.
    ``ax``: 1 + pairs Axes in a column, or None."""
    d = _data(result)
    _kind(d, "spectra", "stochastic")
    p = d.get("periodic")
    if not p:
        raise ValueError(f"this {d.get('kind')} result has no periodic analysis: use period_s=")
    frf = p["frf"]
    fig, a, _ = _panels(ax, 1 + len(frf), 1, "plot.periodic", panel=(5.5, 2.1))
    axx = a[0, 0]
    lines = p["lines"]
    for kind, color, marker, label in (("excited", "#0072B2", "o", "excited"),
                                       ("odd_detection", "#D55E00", "^", "odd detection"),
                                       ("even_detection", "#009E73", "s", "even detection")):
        at = [ln["frequency_hz"] for ln in lines if ln["kind"] == kind]
        level = [ln["output_level"] for ln in lines if ln["kind"] == kind]
        if at:
            axx.semilogx(at, level, linestyle="none", marker=marker, markersize=3.5, color=color, label=label)
    axx.semilogx([ln["frequency_hz"] for ln in lines], [ln["noise_level"] for ln in lines],
                 color="#999999", linestyle="--", linewidth=1.0, label="noise")
    axx.set_ylabel("output (dB re excited)")
    axx.set_xlabel("frequency (Hz)")
    verdict = (p.get("distortion") or {}).get("verdict", "no detection line")
    axx.set_title(f"{p['periods']} periods of {p['period_s']:g} s: {verdict}", fontsize="medium")
    axx.legend(fontsize="small", ncol=2)
    _log_ticks(axx.xaxis, [ln["frequency_hz"] for ln in lines])
    for n, pair in enumerate(frf, start=1):
        axx = a[n, 0]
        f = np.asarray(pair["frequency_hz"], dtype=float)
        m = np.asarray(pair["magnitude"], dtype=float)
        se = np.asarray(pair["magnitude_se"], dtype=float)
        axx.loglog(f, m, linestyle="none", marker="o", markersize=3, color="#0072B2", label="|G|")
        axx.fill_between(f, np.clip(m - 2 * se, m * 1e-3, None), m + 2 * se, color="#0072B2", alpha=0.2,
                         label="±2 SE")
        axx.set_ylabel(f"|{pair['output']} / {pair['input']}|")
        axx.set_xlabel("frequency (Hz)")
        axx.legend(fontsize="small")
        _log_ticks(axx.xaxis, f)
        _log_ticks(axx.yaxis, m)
    return Plot(fig, a)


# ---------------------------------------------------------------- planar sweep


def sweep(result: Any, ax: Any = None) -> Plot:
    """The diagonal of K and D against the observation window T_obs with
    ±1 SE bands; trusted windows filled, the shortest trusted one marked.
    ``ax``: 2 x 1 Axes or None."""
    d = _data(result)
    _kind(d, "window_sweep")
    t = np.asarray([r["observation_window_ms"] for r in d["rows"]], dtype=float)
    trusted = np.asarray([bool(r["trusted"]) for r in d["rows"]])
    fig, a, _ = _panels(ax, 2, 1, "plot.sweep", panel=(5.5, 2.0), sharex=True)
    for row, (q, sym) in enumerate((("stiffness", "K"), ("damping", "D"))):
        axx = a[row, 0]
        for i, c in enumerate(("#0072B2", "#D55E00")):
            v = np.asarray([r["estimate"][q][i][i] for r in d["rows"]], dtype=float)
            s = np.asarray([r["estimate"]["standard_errors"][q][i][i] for r in d["rows"]], dtype=float)
            axx.fill_between(t, v - s, v + s, color=c, alpha=0.2, linewidth=0)
            axx.plot(t, v, color=c, linewidth=1, label=f"{sym}{i + 1}{i + 1}")
            axx.plot(t[trusted], v[trusted], "o", color=c, markersize=4)
            axx.plot(t[~trusted], v[~trusted], "o", color=c, markersize=4, markerfacecolor="white")
        unit = _display._unit(q, "q1", "q1")
        axx.set_ylabel(f"{q} {sym} ({unit})")
        short = d.get("shortest_trusted_ms")
        if short is not None:
            axx.axvline(short, color="#444444", linestyle=":", linewidth=1)
        axx.legend(fontsize="small", title="filled: trusted", title_fontsize="small")
    a[-1, 0].set_xlabel("observation window T_obs (ms)")
    return Plot(fig, a)


# ---------------------------------------------------------------- reflex


def reflex(result: Any, ax: Any = None) -> Plot:
    """Parallel cascade: the intrinsic IRF (position to torque), the reflex
    IRF (rectified velocity to torque), both per second of lag (the result's
    own values) against lag in ms, and the reflex pathway's static curve (estimated, with
    its ±2 SE band; older results: the half-wave rectifier times the gain), and, when the
    result has it, the joint's |Z| from position to torque with ±2 SE and the intrinsic
    I-B-K model over it. ``ax``: 1 x 4 Axes (1 x 3 without the |Z| panel) or None."""
    d = _data(result)
    _kind(d, "reflex")
    z: Dict[str, Any] = d.get("frequency_response") or {}
    # the frequency response as a fourth panel when the result has one (and ax= asks for 4)
    panels = 4 if z and (ax is None or np.asarray(ax, dtype=object).size != 3) else 3
    fig, a, _ = _panels(ax, 1, panels, "plot.reflex", panel=(3.0, 2.6))
    tu = _display._force_unit(d, d["position"])
    pu = _display._position_unit(d, d["position"])
    ii, ri = d["intrinsic"]["irf"], d["reflex"]["irf"]

    def in_ms(irf: Dict[str, Any]) -> Tuple[Any, Any]:
        # the result's IRFs are per second of lag already (the weights over the sampling interval)
        return 1e3 * np.asarray(irf["lags_s"], dtype=float), np.asarray(irf["values"], dtype=float)

    lag, h = in_ms(ii)
    a[0, 0].plot(lag, h, color="#000000", linewidth=1, marker="o" if lag.size < 30 else None, markersize=3)
    a[0, 0].set_xlabel("lag (ms)")
    a[0, 0].set_ylabel(f"intrinsic IRF ({tu}/{pu}/s)")
    for panel in (a[0, 0], a[0, 1]):
        # IRF weights run to 1e4: short tick labels, so the axis label stays in the figure
        panel.ticklabel_format(axis="y", style="sci", scilimits=(-3, 3))
    a[0, 0].set_title("Intrinsic pathway", fontsize="medium")
    lag, h = in_ms(ri)
    a[0, 1].plot(lag, h, color="#D55E00", linewidth=1)
    a[0, 1].set_xlabel("lag (ms)")
    a[0, 1].set_ylabel(f"reflex IRF ({tu} s/{pu}/s)")
    a[0, 1].set_title("Reflex pathway (linear part)", fontsize="medium")
    r = d["reflex"]
    curve = r.get("curve")
    if curve:
        # the estimated static curve (issue 78) with its ±2 SE band
        v = np.asarray(curve["velocity_rad_s"], dtype=float)
        f = np.asarray(curve["torque"], dtype=float)
        se = np.asarray(curve["torque_se"], dtype=float)
        a[0, 2].fill_between(v, f - 2 * se, f + 2 * se, color="#D55E00", alpha=0.25, linewidth=0)
        a[0, 2].plot(v, f, color="#D55E00", linewidth=1.2)
        shape = curve["structure"].replace("_", "-")
        title = f"static curve: {shape}"
    else:
        v = np.linspace(-1.0, 1.0, 201)
        sign = 1.0 if r.get("polarity") == "positive" else -1.0
        a[0, 2].plot(v, r["gain"] * np.maximum(sign * v, 0.0), color="#D55E00", linewidth=1.2)
        title = f"{r.get('polarity', '?')} half-wave, gain {r['gain']:.3g}"
    a[0, 2].set_xlabel(f"velocity ({pu}/s)")
    a[0, 2].set_ylabel(f"reflex torque at DC ({tu})")
    a[0, 2].set_title(title, fontsize="medium")
    if panels == 4:
        f = np.asarray(z["frequency_hz"], dtype=float)
        m = np.asarray(z["magnitude"], dtype=float)
        se = np.asarray(z["magnitude_se"], dtype=float)
        a[0, 3].fill_between(f, np.maximum(m - 2 * se, m * 1e-3), m + 2 * se, color="#000000", alpha=0.2,
                             linewidth=0, label="measured ±2 SE")
        a[0, 3].loglog(f, m, color="#000000", linewidth=1)
        a[0, 3].loglog(f, np.asarray(z["intrinsic_model_magnitude"], dtype=float), color="#0072B2",
                       linewidth=1.2, label="intrinsic I-B-K")
        _log_ticks(a[0, 3].xaxis, f)
        _log_ticks(a[0, 3].yaxis, np.r_[m, z["intrinsic_model_magnitude"]])
        a[0, 3].set_xlabel("frequency (Hz)")
        a[0, 3].set_ylabel(f"|Z| ({tu}/{pu})")
        a[0, 3].set_title("position to torque", fontsize="medium")
        a[0, 3].legend(fontsize="small", frameon=False)
    return Plot(fig, a)


def varying(result: Any, ax: Any = None) -> Plot:
    """Impedance that varies: the diagonal of K, B and I (M) against the schedule with
    ±2 SE bands; points not identifiable are gaps. Walking results (``gait``) add
    the stance | swing boundary and a fourth panel with the perturbations (pulses) or
    strides (ensemble) behind each point. ``ax``: 1 x 3 Axes (walking: 1 x 4) or None."""
    d = _data(result)
    _kind(d, "varying")
    gait = d.get("gait")
    panels = 4 if gait else 3
    fig, a, new = _panels(ax, 1, panels, "plot.varying" + (" of a walking result" if gait else ""),
                          panel=(3.0, 2.6))
    coords = d["coordinates"]
    units = [_display._unit(q, coords[0], coords[0]) for q in ("stiffness", "damping", "inertia")]
    angular = _display._is_angular(d, coords[0])
    sched = d["schedule"]
    xlabel = f"{sched['name']} ({sched['unit']})" if sched.get("unit") else sched["name"]
    if sched.get("unit") == "fraction of the stride":
        # "gait phase (from heel_strike) (fraction of the stride)" does not fit under a panel
        xlabel = "gait phase"
        if new:
            fig.suptitle(f"{sched['name']}: 0 at the event, 1 at the next", fontsize="medium")
    x = np.asarray([p["sigma"] for p in d["points"]], dtype=float)
    n = len(coords)
    for col, (key, symbol, word) in enumerate([("stiffness", "K", "Stiffness"), ("damping", "B", "Damping"),
                                               ("inertia", "I" if angular else "M", "Inertia")]):
        axx = a[0, col]
        for i in range(n):
            def el(p: Dict[str, Any], k: str) -> float:
                m = p.get(k)
                return float(m[i][i]) if (p["identifiable"] and m is not None) else math.nan
            v = np.asarray([el(p, key) for p in d["points"]])
            se = np.asarray([el(p, key + "_se") for p in d["points"]])
            label = symbol if n == 1 else f"{symbol}{i + 1}{i + 1}"
            line = axx.plot(x, v, marker="o", markersize=2.5, linewidth=1.2, label=label)[0]
            axx.fill_between(x, v - 2 * se, v + 2 * se, color=line.get_color(), alpha=0.2, linewidth=0)
        axx.set_xlabel(xlabel)
        axx.set_ylabel(f"{symbol} ({units[col]})")
        axx.set_title(f"{word} (±2 SE shaded)", fontsize="medium")
        if n > 1:
            axx.legend(fontsize="small")
    if gait:
        axx = a[0, 3]
        axx.bar(x, [p["support"] for p in d["points"]], width=0.8 * (x[1] - x[0]) if len(x) > 1 else 0.02,
                color="#999999")
        axx.set_xlabel(xlabel)
        what = "perturbations" if d.get("method") == "pulses" else "strides"
        axx.set_ylabel(f"{what} behind each point")
        axx.set_title(f"{gait['strides_used']} of {gait['strides_found']} strides used", fontsize="medium")
        if sched.get("unit") == "fraction of the stride":
            for axx in a[0, :]:
                axx.axvline(gait["stance_end"], color="#777777", linestyle=":", linewidth=1)
                axx.text(gait["stance_end"], 1.0, " swing", transform=axx.get_xaxis_transform(),
                         va="top", fontsize="x-small", color="#555555")
    return Plot(fig, a)


def study(result: Any, ax: Any = None) -> Plot:
    """A co-contraction study (``limpid.study_run``): the diagonal stiffness
    Kxx, Kyy, Kzz against the co-contraction index, one line per
    configuration, mean over subjects with ±1 sd where there are several
    (Patel, O'Neill & Artemiadis 2013). ``ax``: 1 x 3 Axes or None."""
    d = _data(result)
    _kind(d, "study")
    fig, a, _ = _panels(ax, 1, 3, "plot.study", panel=(3.0, 2.6))
    configs = list(dict.fromkeys(r["configuration"] for r in d["levels"]))
    unit = _display._unit("stiffness", "x", "x")
    for col, key in enumerate(("kxx", "kyy", "kzz")):
        axx = a[0, col]
        for c in configs:
            rows = sorted((r for r in d["levels"] if r["configuration"] == c and r.get(key) is not None),
                          key=lambda r: float(r["cocontraction_index"]))
            x = [float(r["cocontraction_index"]) for r in rows]
            y = [float(r[key]) for r in rows]
            sd = [float((r.get("sd") or {}).get(key) or 0.0) for r in rows]
            axx.errorbar(x, y, yerr=sd if any(sd) else None, marker="o", markersize=3, linewidth=1,
                         capsize=2, label=f"configuration {c}")
        axx.set_xlabel("co-contraction index")
        axx.set_ylabel(f"K{key[1:]} ({unit})")
        axx.set_title(f"K{key[1:]} against co-contraction", fontsize="medium")
    a[0, 0].legend(fontsize="small")
    return Plot(fig, a)


def design(result: Any, ax: Any = None) -> Plot:
    """A designed protocol (``limpid.design``): one perturbation's (a
    multisine's: one period of x) displacement, velocity and acceleration, its
    amplitude by frequency (a multisine's: at each excited line)
    (2|X(f)|/T) against the largest sine the limits allow (and the baseline's,
    when given), and the predicted relative standard errors of K, B and M for
    the design and the baseline (a planar design: one recorded trial in joint
    angles, K, D and ξ). A reflex design (a PRBS): the start of one
    period, the amplitude of each line of a period (the design's and the
    baseline's) against the limits, and the predicted spread of the reflex
    gain. ``ax``: 1 x 3 Axes or None."""
    d = _data(result)
    kind = _kind(d, "design", "reflex_design", "planar_design")
    if kind == "reflex_design":
        return _reflex_design(d, ax)
    # a planar design's command and spectrum are joint angles; its groups K, D and ξ
    planar = kind == "planar_design"
    unit = "rad" if planar else "m"
    fig, a, _ = _panels(ax, 1, 3, "plot.design", panel=(3.6, 2.8))
    _command_traces(a[0, 0], d["command"],
                    (("rad", "rad"), ("rad_s", "rad/s"), ("rad_s2", "rad/s²")) if planar
                    else (("m", "m"), ("m_s", "m/s"), ("m_s2", "m/s²")))
    periodic = d.get("family") == "multisine"
    a[0, 0].set_xlabel("time from the period's start (s), x" if periodic else "time from the trial's start (s)")
    a[0, 0].set_ylabel("share of the peak")
    a[0, 0].legend(fontsize="small")
    sp = d["spectrum"]
    f = np.asarray(sp["frequency_hz"], dtype=float)
    # a multisine's spectrum is its excited lines: drawn as points
    a[0, 1].loglog(f, np.asarray(sp[f"designed_{unit}"], dtype=float), "." if periodic else "-", label="design")
    if sp.get(f"baseline_{unit}") is not None:
        a[0, 1].loglog(f, np.asarray(sp[f"baseline_{unit}"], dtype=float), label="baseline")
    a[0, 1].loglog(f, np.asarray(sp[f"limit_{unit}"], dtype=float), "k--", label="limits")
    a[0, 1].set_xlabel("frequency (Hz)")
    a[0, 1].set_ylabel(f"amplitude ({unit})")
    a[0, 1].legend(fontsize="small")
    _log_ticks(a[0, 1].xaxis, f)
    _log_ticks(a[0, 1].yaxis, np.concatenate([np.asarray(sp[k], dtype=float)
                                              for k in (f"designed_{unit}", f"limit_{unit}")]))
    names = ["K", "D", "ξ"] if planar else ["K", "B", "M"]
    x = np.arange(3)
    base = d.get("baseline")
    width = 0.4 if base is not None else 0.6

    # a spread of estimates mostly called not identifiable is the estimator's prior: faint, "n/i"
    def bars(offset: float, p: Dict[str, Any], label: str) -> None:
        se = np.asarray(p["pooled"]["se_percent"], dtype=float)
        ok = np.asarray(p["identifiable_share"], dtype=float) >= 0.5
        drawn = a[0, 2].bar(x + offset, se, width, label=label)
        for rect, identified, v in zip(drawn, ok, se):
            rect.set_alpha(1.0 if identified else 0.3)
            a[0, 2].annotate(f"{v:.1f}" + ("" if identified else " n/i"), (rect.get_x() + rect.get_width() / 2, v),
                             ha="center", va="bottom", fontsize="small")

    bars(-(width / 2) if base is not None else 0.0, d["predicted"], "design")
    if base is not None:
        bars(width / 2, base, "baseline")
    a[0, 2].set_xticks(x, names)
    a[0, 2].set_yscale("log")
    a[0, 2].set_ylabel("predicted SE (% of the RMS element)")
    a[0, 2].legend(fontsize="small")
    _log_ticks(a[0, 2].yaxis, np.concatenate([np.asarray(p["pooled"]["se_percent"], dtype=float)
                                              for p in (d["predicted"], base) if p is not None]))
    return Plot(fig, a)


def _command_traces(axis: Any, cmd: Dict[str, Any], units: Tuple[Tuple[str, str], ...]) -> None:
    """A designed command's displacement, velocity and acceleration, each
    relative to its peak; `units`: each key's suffix and the unit shown."""
    t = np.asarray(cmd["t_s"], dtype=float)
    for name, style, (suffix, unit) in zip(("displacement", "velocity", "acceleration"), ("-", "--", ":"), units):
        y = np.asarray(cmd[f"{name}_{suffix}"], dtype=float)
        peak = float(np.max(np.abs(y))) if y.size else 0.0
        axis.plot(t, y / peak if peak > 0 else y, style, label=f"{name} (peak {peak:.3g} {unit})")


def _reflex_design(d: Dict[str, Any], ax: Any) -> Plot:
    """`design` for a PRBS designed for the reflex gain (joint units)."""
    fig, a, _ = _panels(ax, 1, 3, "plot.design", panel=(3.6, 2.8))
    cmd = d.get("command")
    if cmd is not None:
        _command_traces(a[0, 0], cmd, (("rad", "rad"), ("rad_s", "rad/s"), ("rad_s2", "rad/s²")))
        a[0, 0].set_xlabel("time from the period's start (s)")
        a[0, 0].set_ylabel("share of the peak")
        a[0, 0].legend(fontsize="small")
    sp = d.get("spectrum")
    if sp is not None:
        f = np.asarray(sp["frequency_hz"], dtype=float)
        a[0, 1].loglog(f, np.asarray(sp["designed_rad"], dtype=float), ".", label="design")
        if sp.get("baseline_rad") is not None:
            a[0, 1].loglog(np.asarray(sp["baseline_frequency_hz"], dtype=float),
                           np.asarray(sp["baseline_rad"], dtype=float), ".", label="baseline")
        a[0, 1].loglog(f, np.asarray(sp["limit_rad"], dtype=float), "k--", label="limits")
        a[0, 1].set_xlabel("frequency (Hz)")
        a[0, 1].set_ylabel("amplitude per line (rad)")
        a[0, 1].legend(fontsize="small")
    rows = [("design", d["predicted"])] + ([("baseline", d["baseline"])] if d.get("baseline") else [])
    sds = [float(p["gain_sd"]) for _, p in rows]
    drawn = a[0, 2].bar([label for label, _ in rows], sds, 0.6)
    for rect, v in zip(drawn, sds):
        a[0, 2].annotate(f"{v:.3g}", (rect.get_x() + rect.get_width() / 2, v), ha="center", va="bottom",
                         fontsize="small")
    a[0, 2].set_ylabel("predicted reflex gain s.d. (N m s/rad)")
    return Plot(fig, a)
