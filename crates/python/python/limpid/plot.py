"""Figures of limpid results with matplotlib (``pip install limpid[plot]``).

Each function takes a :class:`limpid.Result` (or its dict), draws into the
axes given (``ax=``/``axes=``) or into a new figure, and returns the
``matplotlib.figure.Figure``. Every axis carries its quantity and unit.

- :func:`ellipsoids` — stiffness (or damping) ellipsoids in 3-D: the
  principal axes of the symmetric part, each as long as its eigenvalue
  (Patel et al. 2013's convention; Artemiadis et al. 2010 draw 1/sqrt(λ));
  one per level of a co-contraction result.
- :func:`ellipses` — the planar arm's end-point stiffness ellipse
  (Lakatos et al. 2011), or any 2-D result's.
- :func:`fit` — measured against predicted force or torque.
- :func:`bode` — |Z(f)| and phase per element with the parametric model
  (Park & Chang 2011), the fit band shaded.
- :func:`coherence` — multiple and partial coherences against frequency.
- :func:`sweep` — K and D against the observation window with ±1 SE bands,
  trusted windows marked (Lakatos et al. 2011 §IV).
- :func:`reflex` — intrinsic and reflex impulse responses and the reflex
  pathway's static nonlinearity (parallel cascade).
- :func:`varying` — K, B and I against time, an operating point or gait
  phase with ±2 SE bands; walking adds the stance | swing boundary and the
  perturbations (or strides) behind each point.
"""

from __future__ import annotations

import math
from typing import Any, Dict, List, Optional, Sequence

import numpy as np

from . import _display

__all__ = ["ellipsoids", "ellipses", "fit", "bode", "coherence", "periodic", "sweep", "reflex", "design", "varying"]


def __dir__() -> List[str]:
    """The plot functions only (not the modules and typing names used inside)."""
    return sorted(__all__)


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


def _figure(ax: Any, projection: Optional[str] = None) -> Any:
    plt = _plt()
    if ax is not None:
        return ax.figure, ax
    fig = plt.figure(figsize=(5.5, 4.5))
    return fig, fig.add_subplot(111, projection=projection)


def _grid(axes: Any, rows: int, cols: int, **kw: Any) -> Any:
    plt = _plt()
    if axes is not None:
        a = np.asarray(axes, dtype=object).reshape(rows, cols)
        return a.flat[0].figure, a
    fig, a = plt.subplots(rows, cols, squeeze=False, **kw)
    return fig, a


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


def ellipsoids(result: Any, ax: Any = None, matrix: str = "stiffness") -> Any:
    """3-D ellipsoids of a linear, co-contraction (one per level) or demo
    (one per start point) result: axes along the principal directions of the
    symmetric part, lengths |λ| in the matrix's unit. A matrix that is not
    positive definite is drawn with |λ| and says so in the legend."""
    d = _data(result)
    items = [(label, e) for label, e in _ellipsoid_list(d, matrix) if e is not None and len(e["axes"]) == 3]
    if not items:
        raise ValueError(f"this result has no 3-D {matrix} ellipsoid (2-D or 1-D data: use plot.ellipses)")
    fig, ax = _figure(ax, "3d")
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
    for setter, name in ((ax.set_xlim, "x"), (ax.set_ylim, "y"), (ax.set_zlim, "z")):
        setter(-lim, lim)
    ax.set_xlabel(f"x ({unit})")
    ax.set_ylabel(f"y ({unit})")
    ax.set_zlabel(f"z ({unit})")
    ax.set_title(f"{matrix.capitalize()} ellipsoid" + ("s" if len(items) > 1 else ""))
    ax.legend(loc="upper left", fontsize="small")
    return fig


def ellipses(result: Any, ax: Any = None, matrix: Optional[str] = None) -> Any:
    """The end-point stiffness ellipse of a planar result (or the 2-D
    stiffness of a linear result): principal axes with lengths |λ| (N/m),
    centred at the origin."""
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
    fig, ax = _figure(ax)
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
    return fig


# ---------------------------------------------------------------- fit


def fit(result: Any, axes: Any = None) -> Any:
    """Measured against predicted force (or torque) per coordinate: linear,
    planar (joint torques) and reflex (total torque with the intrinsic and
    reflex parts)."""
    d = _data(result)
    kind = _kind(d, "linear", "planar", "reflex")
    if kind == "reflex":
        tr = d["traces"]
        fig, a = _grid(axes, 1, 1, figsize=(7, 3.2))
        ax = a[0, 0]
        unit = "N m" if d["position"] == "theta" or d["position"].startswith("q") else "N"
        ax.plot(tr["t_s"], tr["measured"], color="#000000", linewidth=1, label="measured")
        ax.plot(tr["t_s"], np.add(tr["intrinsic"], tr["reflex"]), color="#0072B2", linestyle="--", label="predicted")
        ax.plot(tr["t_s"], tr["reflex"], color="#D55E00", linewidth=0.8, label="reflex part")
        ax.set_xlabel("time (s)")
        ax.set_ylabel(f"torque {d['torque']} ({unit})")
        ax.set_title(f"Parallel-cascade fit (VAF {d['fit']['vaf_total']:.1f} %)")
        ax.legend(fontsize="small")
        fig.tight_layout()
        return fig
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
    fig, a = _grid(axes, n, 1, figsize=(7, 2.2 * n), sharex=True)
    for i in range(n):
        ax = a[i, 0]
        angular = coords[i] == "theta" or coords[i].startswith("q")
        unit = "N m" if angular else "N"
        ax.plot(tr["time"], tr["measured"][i], color="#000000", linewidth=1, label="measured")
        ax.plot(tr["time"], tr["predicted"][i], color="#0072B2", linestyle="--", label="predicted")
        ax.set_ylabel(f"{names[i]} ({unit})")
        ax.set_title(f"{names[i]}: VAF {vaf[i]:.1f} %", fontsize="medium")
    a[-1, 0].set_xlabel("time (s)")
    a[0, 0].legend(fontsize="small")
    fig.tight_layout()
    return fig


# ---------------------------------------------------------------- frequency domain


def bode(result: Any, axes: Any = None) -> Any:
    """|Z(f)| (log-log) and phase per element of a stochastic result, with
    the fitted K - (2πf)² M + j 2πf B dashed and the fit band shaded."""
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
    fig, a = _grid(axes, 2 * n, n, figsize=(3.2 * n, 2.4 * 2 * n), sharex=True)
    ok = f > 0
    for i in range(n):
        for j in range(n):
            unit = _display._unit("stiffness", coords[i], coords[j])
            mag, ph = a[2 * i, j], a[2 * i + 1, j]
            mag.loglog(f[ok], np.abs(z[ok, i, j]), color="#000000", linewidth=1, label="Z(f)")
            mag.loglog(f[ok], np.abs(model[ok, i, j]), color="#0072B2", linestyle="--", label="fit")
            # unwrapped, so that a phase near ±180° does not jump across the panel
            ph.semilogx(f[ok], np.degrees(np.unwrap(np.angle(z[ok, i, j]))), color="#000000", linewidth=1)
            ph.semilogx(f[ok], np.degrees(np.unwrap(np.angle(model[ok, i, j]))), color="#0072B2", linestyle="--")
            for axx in (mag, ph):
                axx.axvspan(lo, hi, color="#f0f0f0", zorder=0)
            mag.set_title(f"Z {coords[i]},{coords[j]}", fontsize="medium")
            mag.set_ylabel(f"|Z| ({unit})")
            ph.set_ylabel("phase (deg)")
            if i == n - 1:
                ph.set_xlabel("frequency (Hz)")
    a[0, 0].legend(fontsize="small")
    fig.tight_layout()
    return fig


def coherence(result: Any, axes: Any = None) -> Any:
    """Multiple coherence of each output and partial coherence on each input
    of a stochastic result, against frequency (Park & Chang 2011)."""
    d = _data(result)
    _kind(d, "stochastic")
    f = np.asarray(d["frequencies"], dtype=float)
    coh = d["coherence"]
    outs, ins = coh["outputs"], d["inputs"]
    mult = np.asarray(coh["multiple"], dtype=float)  # [output][frequency]
    part = np.asarray(coh["partial"], dtype=float)  # [output][input][frequency]
    n = len(outs)
    fig, a = _grid(axes, n, 1, figsize=(6, 1.9 * n), sharex=True)
    ok = f > 0
    for i in range(n):
        ax = a[i, 0]
        ax.semilogx(f[ok], mult[i][ok], color="#000000", linewidth=1.4, label="multiple")
        for j, name in enumerate(ins):
            ax.semilogx(f[ok], part[i, j][ok], linewidth=0.9, linestyle="--", label=f"partial on {name}")
        ax.set_ylim(0, 1.05)
        ax.set_ylabel(f"coherence of {outs[i]} (1)")
    a[-1, 0].set_xlabel("frequency (Hz)")
    a[0, 0].legend(fontsize="small", ncol=2)
    fig.tight_layout()
    return fig


def periodic(result: Any, axes: Any = None) -> Any:
    """A periodic analysis (``limpid.spectra(..., period_s=...)``): the output
    at the excited, odd-detection and even-detection lines as distinct marks
    and the noise of the period average (dB relative to the excited lines),
    then |G| of each input-output pair at its excited lines with ±2 SE."""
    d = _data(result)
    _kind(d, "spectra")
    p = d.get("periodic")
    if not p:
        raise ValueError("this spectra result has no periodic analysis: use period_s=")
    frf = p["frf"]
    fig, a = _grid(axes, 1 + len(frf), 1, figsize=(6, 2.6 * (1 + len(frf))))
    ax = a[0, 0]
    lines = p["lines"]
    for kind, color, marker, label in (("excited", "#0072B2", "o", "excited"),
                                       ("odd_detection", "#D55E00", "^", "odd detection"),
                                       ("even_detection", "#009E73", "s", "even detection")):
        at = [ln["frequency_hz"] for ln in lines if ln["kind"] == kind]
        level = [ln["output_level"] for ln in lines if ln["kind"] == kind]
        if at:
            ax.semilogx(at, level, linestyle="none", marker=marker, markersize=3.5, color=color, label=label)
    ax.semilogx([ln["frequency_hz"] for ln in lines], [ln["noise_level"] for ln in lines],
                color="#999999", linestyle="--", linewidth=1.0, label="noise")
    ax.set_ylabel("output (dB re excited)")
    verdict = (p.get("distortion") or {}).get("verdict", "no detection line")
    ax.set_title(f"{p['periods']} periods of {p['period_s']:g} s: {verdict}", fontsize="medium")
    ax.legend(fontsize="small", ncol=2)
    for n, pair in enumerate(frf, start=1):
        ax = a[n, 0]
        f = np.asarray(pair["frequency_hz"], dtype=float)
        m = np.asarray(pair["magnitude"], dtype=float)
        se = np.asarray(pair["magnitude_se"], dtype=float)
        ax.loglog(f, m, linestyle="none", marker="o", markersize=3, color="#0072B2", label="|G|")
        ax.fill_between(f, np.clip(m - 2 * se, m * 1e-3, None), m + 2 * se, color="#0072B2", alpha=0.2, label="±2 SE")
        ax.set_ylabel(f"|{pair['output']} / {pair['input']}|")
        ax.legend(fontsize="small")
    a[-1, 0].set_xlabel("frequency (Hz)")
    fig.tight_layout()
    return fig


# ---------------------------------------------------------------- planar sweep


def sweep(result: Any, axes: Any = None) -> Any:
    """The diagonal of K and D against the observation window T_obs with
    ±1 SE bands; trusted windows filled, the shortest trusted one marked."""
    d = _data(result)
    _kind(d, "window_sweep")
    t = np.asarray([r["observation_window_ms"] for r in d["rows"]], dtype=float)
    trusted = np.asarray([bool(r["trusted"]) for r in d["rows"]])
    fig, a = _grid(axes, 2, 1, figsize=(6, 5), sharex=True)
    for row, (q, sym) in enumerate((("stiffness", "K"), ("damping", "D"))):
        ax = a[row, 0]
        for i, c in enumerate(("#0072B2", "#D55E00")):
            v = np.asarray([r["estimate"][q][i][i] for r in d["rows"]], dtype=float)
            s = np.asarray([r["estimate"]["standard_errors"][q][i][i] for r in d["rows"]], dtype=float)
            ax.fill_between(t, v - s, v + s, color=c, alpha=0.2, linewidth=0)
            ax.plot(t, v, color=c, linewidth=1, label=f"{sym}{i + 1}{i + 1}")
            ax.plot(t[trusted], v[trusted], "o", color=c, markersize=4)
            ax.plot(t[~trusted], v[~trusted], "o", color=c, markersize=4, markerfacecolor="white")
        unit = _display._unit(q, "q1", "q1")
        ax.set_ylabel(f"{q} {sym} ({unit})")
        short = d.get("shortest_trusted_ms")
        if short is not None:
            ax.axvline(short, color="#444444", linestyle=":", linewidth=1)
        ax.legend(fontsize="small", title="filled: trusted", title_fontsize="small")
    a[-1, 0].set_xlabel("observation window T_obs (ms)")
    fig.tight_layout()
    return fig


# ---------------------------------------------------------------- reflex


def reflex(result: Any, axes: Any = None) -> Any:
    """Parallel cascade: the intrinsic IRF (position to torque), the reflex
    IRF (rectified velocity to torque) and the reflex pathway's static
    nonlinearity (half-wave rectifier times the gain)."""
    d = _data(result)
    _kind(d, "reflex")
    fig, a = _grid(axes, 1, 3, figsize=(11, 3.2))
    angular = d["position"] == "theta" or d["position"].startswith("q")
    pu, tu = ("rad", "N m") if angular else ("m", "N")
    ii, ri = d["intrinsic"]["irf"], d["reflex"]["irf"]
    a[0, 0].plot(ii["lags_s"], ii["values"], color="#000000", linewidth=1)
    a[0, 0].set_xlabel("lag (s)")
    a[0, 0].set_ylabel(f"intrinsic IRF ({tu}/{pu} per sample)")
    a[0, 0].set_title("Intrinsic pathway", fontsize="medium")
    a[0, 1].plot(ri["lags_s"], ri["values"], color="#D55E00", linewidth=1)
    a[0, 1].set_xlabel("lag (s)")
    a[0, 1].set_ylabel(f"reflex IRF ({tu} s/{pu} per sample)")
    a[0, 1].set_title("Reflex pathway (linear part)", fontsize="medium")
    r = d["reflex"]
    v = np.linspace(-1.0, 1.0, 201)
    sign = 1.0 if r.get("polarity") == "positive" else -1.0
    a[0, 2].plot(v, r["gain"] * np.maximum(sign * v, 0.0), color="#D55E00", linewidth=1.2)
    a[0, 2].set_xlabel(f"velocity ({pu}/s)")
    a[0, 2].set_ylabel(f"reflex torque at DC ({tu})")
    a[0, 2].set_title(f"Nonlinearity: {r.get('polarity', '?')} half-wave, gain {r['gain']:.3g}", fontsize="medium")
    fig.tight_layout()
    return fig


def varying(result: Any, axes: Any = None) -> Any:
    """Impedance that varies: the diagonal of K, B and I (M) against the schedule with
    ±2 SE bands; points not identifiable are gaps. Walking results (``gait``) add
    the stance | swing boundary and a fourth panel with the perturbations (pulses) or
    strides (ensemble) behind each point."""
    d = _data(result)
    _kind(d, "varying")
    gait = d.get("gait")
    panels = 4 if gait else 3
    fig, a = _grid(axes, 1, panels, figsize=(3.6 * panels, 3.2))
    angular = all(c == "theta" or c.startswith("q") for c in d["coordinates"])
    units = ("N m/rad", "N m s/rad", "kg m²") if angular else ("N/m", "N s/m", "kg")
    sched = d["schedule"]
    xlabel = f"{sched['name']} ({sched['unit']})" if sched.get("unit") else sched["name"]
    if sched.get("unit") == "fraction of the stride":
        # "gait phase (from heel_strike) (fraction of the stride)" does not fit under a panel
        xlabel = "gait phase"
        fig.suptitle(f"{sched['name']}: 0 at the event, 1 at the next", fontsize="medium")
    x = np.asarray([p["sigma"] for p in d["points"]], dtype=float)
    n = len(d["coordinates"])
    for col, (key, symbol, word) in enumerate([("stiffness", "K", "Stiffness"), ("damping", "B", "Damping"),
                                               ("inertia", "I" if angular else "M", "Inertia")]):
        ax = a[0, col]
        for i in range(n):
            def el(p: Dict[str, Any], k: str) -> float:
                m = p.get(k)
                return float(m[i][i]) if (p["identifiable"] and m is not None) else math.nan
            v = np.asarray([el(p, key) for p in d["points"]])
            se = np.asarray([el(p, key + "_se") for p in d["points"]])
            label = symbol if n == 1 else f"{symbol}{i + 1}{i + 1}"
            line = ax.plot(x, v, marker="o", markersize=2.5, linewidth=1.2, label=label)[0]
            ax.fill_between(x, v - 2 * se, v + 2 * se, color=line.get_color(), alpha=0.2, linewidth=0)
        ax.set_xlabel(xlabel)
        ax.set_ylabel(f"{symbol} ({units[col]})")
        ax.set_title(f"{word} (±2 SE shaded)", fontsize="medium")
        if n > 1:
            ax.legend(fontsize="small")
    if gait:
        ax = a[0, 3]
        ax.bar(x, [p["support"] for p in d["points"]], width=0.8 * (x[1] - x[0]) if len(x) > 1 else 0.02,
               color="#999999")
        ax.set_xlabel(xlabel)
        what = "perturbations" if d.get("method") == "pulses" else "strides"
        ax.set_ylabel(f"{what} behind each point")
        ax.set_title(f"{gait['strides_used']} of {gait['strides_found']} strides used", fontsize="medium")
        if sched.get("unit") == "fraction of the stride":
            for ax in a[0, :]:
                ax.axvline(gait["stance_end"], color="#777777", linestyle=":", linewidth=1)
                ax.text(gait["stance_end"], 1.0, " swing", transform=ax.get_xaxis_transform(),
                        va="top", fontsize="x-small", color="#555555")
    fig.tight_layout()
    return fig


def design(result: Any, axes: Any = None) -> Any:
    """A designed protocol (``limpid.design``): one perturbation's
    displacement, velocity and acceleration, its amplitude by frequency
    (2|X(f)|/T) against the largest sine the limits allow (and the baseline's,
    when given), and the predicted relative standard errors of K, B and M for
    the design and the baseline."""
    d = _data(result)
    _kind(d, "design")
    fig, a = _grid(axes, 1, 3, figsize=(13, 3.4))
    cmd = d["command"]
    t = np.asarray(cmd["t_s"], dtype=float)
    for key, label, style, unit in (
        ("displacement_m", "displacement", "-", "m"),
        ("velocity_m_s", "velocity", "--", "m/s"),
        ("acceleration_m_s2", "acceleration", ":", "m/s²"),
    ):
        y = np.asarray(cmd[key], dtype=float)
        peak = float(np.max(np.abs(y))) if y.size else 0.0
        a[0, 0].plot(t, y / peak if peak > 0 else y, style, label=f"{label} (peak {peak:.3g} {unit})")
    a[0, 0].set_xlabel("time from the trial's start (s)")
    a[0, 0].set_ylabel("share of the peak (1)")
    a[0, 0].legend(fontsize="small")
    sp = d["spectrum"]
    f = np.asarray(sp["frequency_hz"], dtype=float)
    a[0, 1].loglog(f, np.asarray(sp["designed_m"], dtype=float), label="design")
    if sp.get("baseline_m") is not None:
        a[0, 1].loglog(f, np.asarray(sp["baseline_m"], dtype=float), label="baseline")
    a[0, 1].loglog(f, np.asarray(sp["limit_m"], dtype=float), "k--", label="limits")
    a[0, 1].set_xlabel("frequency (Hz)")
    a[0, 1].set_ylabel("amplitude (m)")
    a[0, 1].legend(fontsize="small")
    names = ["K", "B", "M"]
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
    fig.tight_layout()
    return fig
