"""How a result shows itself in a notebook (issue 39): tidy records (the
rows of ``Result.to_pandas()``), a short ``repr`` and an HTML table.

Numbers are the JSON result's own floats (the records copy them, never
recompute them); the text rounds each value to its standard error with the
library's rule (``_limpid.with_standard_error``, the report's and the CLI's),
and units come from the library too (``_limpid.matrix_element_unit``).
"""

from __future__ import annotations

import html as _html
import json
import math
import os
from typing import Any, Dict, Iterable, List, Optional, Sequence, Tuple

from . import _limpid

# the kinds of a designed protocol's result
DESIGN_KINDS = ("design", "reflex_design", "planar_design")
# the planar design's three groups: joint K and D, inertial parameters ξ
PLANAR_GROUPS = (("stiffness", "K", "N m/rad"), ("damping", "D", "N m s/rad"), ("inertial_parameters", "ξ", "kg m²"))
MATRICES = ("stiffness", "damping", "inertia")
SYMBOL = {"stiffness": "K", "damping": "B", "inertia": "M"}
PLANAR_SYMBOL = {"stiffness": "K", "damping": "D", "inertia": "M"}

Record = Dict[str, Any]


def _float(v: Any) -> float:
    """A JSON number as a float; None (absent) becomes NaN, pandas' missing value."""
    return float("nan") if v is None else float(v)


def _sub(coords: Sequence[str], i: int, j: int) -> str:
    """Element subscript as the report writes it: Kxx, or K1,2 for joint names."""
    if all(len(c) == 1 for c in coords):
        return f"{coords[i]}{coords[j]}"
    short = [c[1:] if c.startswith("q") else c for c in coords]
    return f"{short[i]},{short[j]}"


def _unit(kind: str, row: str, column: str) -> str:
    return _limpid.matrix_element_unit(kind, row, column)


def _is_angular(d: Dict[str, Any], coord: str) -> bool:
    """Whether `coord` is a joint angle: as the result says (its ``units``,
    from what the request said the column is), else by its recording-format
    name (theta, q1..; results of every method but reflex use those names)."""
    units = d.get("units")
    if isinstance(units, dict) and units.get("position"):
        return bool(units["position"] == "rad")
    return coord == "theta" or coord.startswith("q")  # the rule of _limpid.matrix_element_unit


def _position_unit(d: Dict[str, Any], coord: str) -> str:
    return "rad" if _is_angular(d, coord) else "m"


def _force_unit(d: Dict[str, Any], coord: str) -> str:
    return "N m" if _is_angular(d, coord) else "N"


def _scalar_unit(d: Dict[str, Any], kind: str, coord: str) -> str:
    """The unit of a one-coordinate stiffness, damping or inertia of `d`."""
    units = d.get("units")
    if isinstance(units, dict) and units.get(kind):
        return str(units[kind])
    return _unit(kind, *(("q1", "q1") if _is_angular(d, coord) else ("x", "x")))


def _matrix_records(d: Dict[str, Any], coords: Sequence[str], kinds: Iterable[str],
                    se: Optional[Dict[str, Any]], verdicts: Optional[Dict[str, Any]],
                    extra: Optional[Record] = None, se_suffix: str = "",
                    symbols: Optional[Dict[str, str]] = None) -> List[Record]:
    out: List[Record] = []
    for kind in kinds:
        m = d.get(kind)
        if m is None:
            continue
        s = None if se is None else se.get(kind + se_suffix)
        for i, ci in enumerate(coords):
            for j, cj in enumerate(coords):
                rec: Record = dict(extra or {})
                rec.update(
                    quantity=kind,
                    element=(symbols or SYMBOL)[kind] + _sub(coords, i, j),
                    row=ci,
                    column=cj,
                    value=_float(m[i][j]),
                    se=_float(None if s is None else s[i][j]),
                    unit=_unit(kind, ci, cj),
                    verdict=None if verdicts is None else verdicts.get(kind),
                )
                out.append(rec)
    return out


def _linear(d: Dict[str, Any], extra: Optional[Record] = None) -> List[Record]:
    coords = d["provenance"]["coordinates"]
    return _matrix_records(d, coords, MATRICES, d.get("standard_errors"),
                           d.get("criteria", {}).get("verdicts"), extra)


def records(d: Dict[str, Any], table: str = "parameters") -> List[Record]:
    """The tidy rows of a result document (see ``Result.to_pandas``)."""
    kind = d.get("kind")
    if table == "impedance":
        if kind != "stochastic":
            raise ValueError(f"table 'impedance' is for stochastic results, this one is {kind!r}")
        return _impedance(d)
    if table == "coherence":
        if kind == "spectra":
            return _spectra_coherence(d)
        if kind != "stochastic":
            raise ValueError(f"table 'coherence' is for stochastic and spectra results, this one is {kind!r}")
        return _coherence(d)
    if table == "psd":
        if kind != "spectra":
            raise ValueError(f"table 'psd' is for spectra results, this one is {kind!r}")
        return [dict(frequency_hz=_float(f), signal=name, psd=_float(p[k]))
                for name, p in zip(d["signals"], d["psd"]) for k, f in enumerate(d["frequencies"])]
    if table == "rotation":
        if kind != "study":
            raise ValueError(f"table 'rotation' is for study results, this one is {kind!r}")
        return [dict(r) for r in d["rotation"]]
    if table == "flawed":
        if kind != "varying" or not d.get("gait"):
            raise ValueError(f"table 'flawed' is for walking results (estimate_varying with event=), this one is {kind!r}")
        return [dict(f) for f in d["gait"]["flawed"]]
    if table == "limits":
        if kind not in DESIGN_KINDS:
            raise ValueError(f"table 'limits' is for design results, this one is {kind!r}")
        return [dict(r) for r in d["limits"]]
    if table in ("lines", "frf"):
        if kind != "spectra" or not d.get("periodic"):
            raise ValueError(f"table {table!r} is for periodic spectra (spectra with period_s=), this one is "
                             f"{kind!r}" + (" without period_s" if kind == "spectra" else ""))
        p = d["periodic"]
        if table == "lines":
            return [dict(ln) for ln in p["lines"]]
        return [dict(output=pair["output"], input=pair["input"], frequency_hz=_float(f), magnitude=_float(m),
                     magnitude_se=_float(se))
                for pair in p["frf"]
                for f, m, se in zip(pair["frequency_hz"], pair["magnitude"], pair["magnitude_se"])]
    if table != "parameters":
        raise ValueError(
            f"table: expected 'parameters', 'impedance', 'coherence', 'psd', 'rotation', 'flawed', 'limits', "
            f"'lines' or 'frf', found {table!r}")
    if kind in DESIGN_KINDS:
        return _design(d)
    if kind == "linear":
        return _linear(d)
    if kind == "cocontraction":
        out: List[Record] = []
        for lv in d["levels"]:
            extra = {"level": _float(lv["level"])}
            out.append(dict(extra, quantity="cocontraction_index", element="CCI", row=None, column=None,
                            value=_float(lv["cocontraction_index"]), se=float("nan"),
                            unit="fraction of MVC", verdict=None))
            out.extend(_linear(lv["estimate"], extra))
        return out
    if kind == "planar":
        return _planar(d)
    if kind == "window_sweep":
        out = []
        for row in d["rows"]:
            extra = {"window_ms": _float(row["observation_window_ms"]),
                     "trusted": bool(row["trusted"])}
            out.extend(_planar(row["estimate"], extra))
        return out
    if kind == "stochastic":
        c = d["criteria"]
        return _matrix_records(d, d["coordinates"], MATRICES, d["standard_errors"], c.get("verdicts"))
    if kind == "varying":
        out = []
        coords = d["coordinates"]
        sched = d["schedule"]
        for p in d["points"]:
            extra = {"sigma": _float(p["sigma"]), "identifiable": bool(p["identifiable"])}
            if not p["identifiable"]:
                continue
            out.extend(_matrix_records(p, coords, MATRICES, p, p.get("verdicts"), extra, se_suffix="_se"))
        for r in out:
            r["schedule"] = f"{sched['name']} ({sched['unit']})" if sched.get("unit") else sched["name"]
        return out
    if kind == "reflex":
        return _reflex(d)
    if kind == "study":
        out = []
        for r in d["levels"]:
            row = {k: v for k, v in r.items() if k not in ("sd", "stiffness", "ellipsoid")}
            row.update({f"{k}_sd": v for k, v in (r.get("sd") or {}).items()})
            out.append(row)
        return out
    if kind == "spectra":
        raise ValueError("spectra results have the tables 'psd' and 'coherence' (periodic ones also 'lines' and 'frf'): "
                         "to_pandas('coherence')")
    if kind == "demo":
        out = []
        for p in d["points"]:
            extra = {"start_point": p["start_point"]}
            recs = _linear(p["estimate"], extra)
            coords = p["estimate"]["provenance"]["coordinates"]
            for r in recs:
                i, j = coords.index(r["row"]), coords.index(r["column"])
                r["truth"] = _float(p["true_" + r["quantity"]][i][j])
            out.extend(recs)
        return out
    raise ValueError(f"no table for results of kind {kind!r}")


def _planar(d: Dict[str, Any], extra: Optional[Record] = None) -> List[Record]:
    coords = ["q1", "q2"]
    se = d["standard_errors"]
    # seed 003 writes the damping D
    out = _matrix_records(d, coords, ("stiffness", "damping"), se, d["criteria"].get("verdicts"), extra,
                          symbols=PLANAR_SYMBOL)
    for i, (v, s) in enumerate(zip(d["inertial_parameters"], se["inertial_parameters"])):
        out.append(dict(extra or {}, quantity="inertial_parameter", element=f"xi{i + 1}", row=None, column=None,
                        value=_float(v), se=_float(s), unit="kg m²", verdict=None))
    return out


def _design(d: Dict[str, Any]) -> List[Record]:
    """A design's predicted standard errors, per parameter, for the design and
    the baseline it was compared with (pooled: the RMS element's)."""
    out: List[Record] = []
    for which, label in (("predicted", "design"), ("baseline", "baseline")):
        p = d.get(which)
        if not p:
            continue
        if d["kind"] == "planar_design":
            pooled = p["pooled"]
            for i, (q, symbol, unit) in enumerate(PLANAR_GROUPS):
                out.append(dict(protocol=label, quantity=q, element=symbol, se=_float(pooled["se"][i]),
                                unit=unit, se_percent=_float(pooled["se_percent"][i]),
                                error_percent=_float(pooled["error_percent"][i]),
                                identifiable_share=_float(p["identifiable_share"][i]), runs=p["runs"]))
        elif d["kind"] == "design":
            pooled = p["pooled"]
            for i, q in enumerate(MATRICES):
                out.append(dict(protocol=label, quantity=q, element=SYMBOL[q], se=_float(pooled["se"][i]),
                                unit=_unit(q, "x", "x"), se_percent=_float(pooled["se_percent"][i]),
                                error_percent=_float(pooled["error_percent"][i]),
                                identifiable_share=_float(p["identifiable_share"][i]), runs=p["runs"]))
        else:
            out.append(dict(protocol=label, quantity="reflex_gain", element="reflex gain G",
                            se=_float(p["gain_sd"]), unit="N m s/rad", se_percent=float("nan"),
                            error_percent=_float(p["gain_error_percent"]), identifiable_share=float("nan"),
                            runs=p["runs"]))
    return out


def _design_html(d: Dict[str, Any]) -> List[str]:
    c = d["chosen"]
    if d["kind"] == "design" and d.get("family") == "multisine":
        what = (f"a zippered random-odd multisine at x, y, z over {c['band_hz'][0]:.3g}-{c['band_hz'][1]:.3g} Hz "
                f"({c['amplitude_shape']} amplitude), {c['period_s']:.3g} s period, {c['periods']} periods, "
                f"{1e3 * c['rms_m']:.3g} mm RMS per axis")
    elif d["kind"] == "design":
        what = (f"{c['trials']} {c['profile']} perturbations of {1e3 * c['radius_m']:.3g} mm in "
                f"{c['motion_s']:.3g} s (hold {c['hold_s']:.3g} s, rest {c['rest_s']:.3g} s)")
    elif d["kind"] == "planar_design":
        what = (f"{c['trials']} quintic joint perturbations of {c['amplitude_rad']:.3g} rad over "
                f"{1e3 * c['interpolation_s']:.3g} ms, a {c['window_ms']:.3g} ms window after each onset "
                f"(rest {1e3 * c['rest_s']:.3g} ms, waits {c['wait_s'][0]:.3g}-{c['wait_s'][1]:.3g} s)")
    else:
        what = (f"a PRBS of {c['amplitude_rad']:.3g} rad, switching every {1e3 * c['switch_interval_s']:.3g} ms, "
                f"order {c['order']}, {c['periods']} periods")
    parts = [f"<p>Chosen: {_e(what)}, {c['duration_s']:.4g} s of the {d['budget_s']:.4g} s budget.</p>"]
    recs = _design(d)
    parts.append(_list_table(["protocol", "parameter", "predicted SE", "unit", "SE (%)", "error (%)", "identifiable"],
                             [[r["protocol"], r["element"], f"{r['se']:.3g}", r["unit"],
                               "—" if math.isnan(r["se_percent"]) else f"{r['se_percent']:.2f}",
                               f"{r['error_percent']:.2f}",
                               "—" if math.isnan(r["identifiable_share"]) else f"{100 * r['identifiable_share']:.0f} %"]
                              for r in recs],
                             f"Predicted standard errors ({recs[0]['runs'] if recs else 0} virtual runs each)"))
    parts.append(_list_table(["quantity", "peak", "limit", "unit", "margin (%)"],
                             [[m["quantity"], f"{m['peak']:.4g}", f"{m['limit']:.4g}", m["unit"].replace("^2", "²"),
                               f"{m['margin_percent']:.1f}"] for m in d["limits"]],
                             "Within the safety limits"))
    return parts


def _periodic_html(d: Dict[str, Any]) -> List[str]:
    p = d["periodic"]
    dist = p.get("distortion") or {}
    line = f"{p['periods']} periods of {p['period_s']:g} s"
    if dist.get("verdict"):
        line += f": {dist['verdict']}"
    kinds: Dict[str, int] = {}
    for ln in p["lines"]:
        kinds[ln["kind"]] = kinds.get(ln["kind"], 0) + 1
    line += "; lines: " + ", ".join(f"{n} {k.replace('_', ' ')}" for k, n in kinds.items())
    return [f"<p>Periodic analysis: {_e(line)} (to_pandas('lines'), to_pandas('frf'))</p>"]


def _reflex(d: Dict[str, Any]) -> List[Record]:
    """The rows the report's table shows (``ReflexEstimate::parameters`` in
    Rust, one place): a value that is not identifiable is NaN, not its best
    guess, so that averages over recordings do not take it in silently."""
    nan = float("nan")
    rows = json.loads(_limpid.parameter_rows(json.dumps(d)))
    return [dict(quantity=r["quantity"], element=r["label"], row=None, column=None,
                 value=nan if r["value"] is None else _float(r["value"]),
                 se=nan if r["se"] is None else _float(r["se"]),
                 unit=r["unit"], verdict=r["verdict"])
            for r in rows]


def _impedance(d: Dict[str, Any]) -> List[Record]:
    coords = d["coordinates"]
    out: List[Record] = []
    for k, f in enumerate(d["frequencies"]):
        for i, ci in enumerate(coords):
            for j, cj in enumerate(coords):
                re_, im = d["impedance"][k][i][j]
                out.append(dict(frequency_hz=_float(f), output=ci, displacement=cj, real=_float(re_),
                                imag=_float(im), magnitude=math.hypot(re_, im),
                                phase_deg=math.degrees(math.atan2(im, re_)),
                                unit=_unit("stiffness", ci, cj)))
    return out


def _coherence(d: Dict[str, Any]) -> List[Record]:
    coh = d["coherence"]
    out: List[Record] = []
    for o, name in enumerate(coh["outputs"]):
        for k, f in enumerate(d["frequencies"]):
            for j, inp in enumerate(d["inputs"]):
                out.append(dict(frequency_hz=_float(f), output=name, input=inp,
                                multiple=_float(coh["multiple"][o][k]),
                                partial=_float(coh["partial"][o][j][k])))
    return out


def _spectra_coherence(d: Dict[str, Any]) -> List[Record]:
    out: List[Record] = []
    for o, name in enumerate(d["outputs"]):
        for k, f in enumerate(d["frequencies"]):
            for j, inp in enumerate(d["inputs"]):
                out.append(dict(frequency_hz=_float(f), output=name, input=inp,
                                coherence=_float(d["coherence"][o][j][k]),
                                multiple=_float(d["multiple_coherence"][o][k]),
                                partial=_float(d["partial_coherence"][o][j][k])))
    return out


def _multiple_coherence_rows(d: Dict[str, Any]) -> List[List[str]]:
    """Per output: how much of it the inputs explain, over the frequencies where that is defined."""
    rows = []
    for name, m in zip(d["outputs"], d["multiple_coherence"]):
        known = [c for f, c in zip(d["frequencies"], m) if c is not None and f > 0]
        if not known:
            rows.append([name, "—", "—", "singular inputs at every frequency"])
            continue
        high = sum(1 for c in known if c >= 0.9)
        rows.append([name, f"{sum(known) / len(known):.3f}", f"{min(known):.3f}",
                     f"{high} of {len(known)} frequencies at 0.9 or more"])
    return rows


# ---------------------------------------------------------------- text


def with_se(value: float, se: float) -> str:
    """``value ± se`` rounded to the SE; a quantity without an SE (NaN) to 4 significant digits."""
    if math.isnan(se):
        return "n/a" if math.isnan(value) else f"{value:.4g}"
    return _limpid.with_standard_error(value, se)


def _words(verdict: Optional[str]) -> str:
    return "" if verdict is None else str(verdict).replace("_", " ")


def _recording(d: Dict[str, Any]) -> Optional[str]:
    for path in (("provenance", "recording"), ("recording",)):
        v: Any = d
        for k in path:
            v = v.get(k) if isinstance(v, dict) else None
        if isinstance(v, str) and not v.startswith("<"):  # "<arrays>": made from arrays
            return v.rsplit("/", 1)[-1]
    return None


def _diagonal(recs: List[Record], quantity: str = "stiffness") -> str:
    diag = [r for r in recs if r["quantity"] == quantity and r["row"] == r["column"]]
    return ", ".join(f"{r['element']} = {with_se(r['value'], r['se'])} {r['unit']}" for r in diag)


def summary(d: Dict[str, Any]) -> str:
    """A short repr: kind, recording and the headline numbers."""
    kind = d.get("kind", "?")
    head = f"limpid.Result(kind={kind!r}"
    rec = _recording(d)
    if rec:
        head += f", recording={rec!r}"
    body = ""
    try:
        if kind in ("linear", "stochastic", "planar"):
            recs = records(d)
            v = (d.get("criteria") or {}).get("verdicts") or {}
            body = _diagonal(recs) + (f"; stiffness {_words(v.get('stiffness'))}" if v.get("stiffness") else "")
        elif kind == "cocontraction":
            body = f"{len(d['levels'])} levels, muscles {', '.join(d['muscles'])}"
        elif kind == "window_sweep":
            t = d.get("shortest_trusted_ms")
            body = f"{len(d['rows'])} windows; shortest trusted: " + ("none" if t is None else f"{t:g} ms")
        elif kind == "reflex":
            recs = records(d)
            k = next(r for r in recs if r["quantity"] == "intrinsic_stiffness")
            g = next(r for r in recs if r["quantity"] == "reflex_gain")
            dl = next(r for r in recs if r["quantity"] == "reflex_delay")
            body = (f"intrinsic K = {with_se(k['value'], k['se'])} {k['unit']} ({_words(k['verdict'])}), "
                    f"reflex gain = {with_se(g['value'], g['se'])} {g['unit']} ({_words(g['verdict'])}), "
                    + ("delay not identifiable" if math.isnan(dl["value"]) else f"delay {dl['value'] * 1e3:.0f} ms"))
            curve = d["reflex"].get("curve")
            if curve:
                body += (", static curve rectifier" if curve["structure"] == "rectifier" else
                         f", static curve {curve['structure'].replace('_', '-')} ({len(curve['knots_rad_s'])} knots)")
        elif kind == "varying":
            n = sum(1 for p in d["points"] if p["identifiable"])
            body = f"{d['method']}, {n} of {len(d['points'])} points identifiable"
            gait = d.get("gait")
            if gait:
                body += (f"; {gait['strides_used']} of {gait['strides_found']} strides used"
                         f"{', ' + str(len(gait['flawed'])) + ' flawed' if gait['flawed'] else ''}")
        elif kind == "demo":
            worst = max(p["stiffness_error_percent"] for p in d["points"])
            body = f"{len(d['points'])} start points, stiffness within {worst:.1f} % of the truth"
        elif kind == "study":
            body = f"{d.get('name')!r}: {len(d['recordings'])} recordings, {len(d['failures'])} failed"
        elif kind in DESIGN_KINDS:
            recs = _design(d)
            design = [r for r in recs if r["protocol"] == "design"]
            body = f"{d['chosen']['duration_s']:.4g} s of {d['budget_s']:.4g} s; predicted " + ", ".join(
                f"{r['element']} error {r['error_percent']:.2g} %"
                + (" (not identifiable)" if r["identifiable_share"] < 0.5 else "") for r in design)
        elif kind == "spectra":
            body = (f"inputs {', '.join(d['inputs'])}; outputs {', '.join(d['outputs'])}; "
                    f"{len(d['frequencies'])} frequencies, segments of {d['segment_samples']} samples")
    except (KeyError, IndexError, TypeError, ValueError, StopIteration):
        body = ""
    warnings_ = d.get("warnings") or []
    tail = f", {len(warnings_)} warning{'s' if len(warnings_) != 1 else ''}" if warnings_ else ""
    return head + (f": {body}" if body else "") + tail + ")"


# ---------------------------------------------------------------- HTML

_STYLE = ("<style>.limpid-result table{border-collapse:collapse;margin:0 1.2em .6em 0;display:inline-table;"
          "vertical-align:top}.limpid-result th,.limpid-result td{padding:.15em .6em;text-align:right;"
          "border-bottom:1px solid #ddd}.limpid-result caption{text-align:left;font-weight:bold}"
          ".limpid-result td{white-space:nowrap}.limpid-result td.note{white-space:normal;text-align:left;"
          "max-width:36em;font-size:90%}.limpid-result .bad{color:#b00}.limpid-result .ok{color:#070}</style>")


def _e(v: Any) -> str:
    return _html.escape(str(v))


def _verdict_html(v: Optional[str]) -> str:
    if not v:
        return ""
    cls = "ok" if v == "trusted" else "bad"
    return f' <span class="{cls}">({_e(_words(v))})</span>'


def _matrix_table(recs: List[Record], quantity: str, caption: str) -> str:
    rs = [r for r in recs if r["quantity"] == quantity]
    if not rs:
        return ""
    rows = list(dict.fromkeys(r["row"] for r in rs))
    cols = list(dict.fromkeys(r["column"] for r in rs))
    cell = {(r["row"], r["column"]): r for r in rs}
    units = sorted({r["unit"] for r in rs})
    unit = units[0] if len(units) == 1 else "SI"
    out = [f"<table><caption>{_e(caption)} ({_e(unit)}){_verdict_html(rs[0]['verdict'])}</caption>"
           "<tr><th></th>" + "".join(f"<th>{_e(c)}</th>" for c in cols) + "</tr>"]
    for r in rows:
        out.append(f"<tr><th>{_e(r)}</th>" + "".join(
            f"<td>{_e(with_se(cell[(r, c)]['value'], cell[(r, c)]['se']))}"
            + ("" if unit != "SI" else f" {_e(cell[(r, c)]['unit'])}") + "</td>" for c in cols) + "</tr>")
    out.append("</table>")
    return "".join(out)


def _rows_html(rows: Sequence[Sequence[Any]]) -> str:
    """Table rows; a long cell wraps as a note."""
    return "".join("<tr>" + "".join(
        f'<td class="note">{_e(c)}</td>' if len(str(c)) > 30 else f"<td>{_e(c)}</td>" for c in row) + "</tr>"
        for row in rows)


def _list_table(header: Sequence[str], rows: Sequence[Sequence[Any]], caption: str) -> str:
    head = f"<table><caption>{_e(caption)}</caption><tr>" + "".join(f"<th>{_e(h)}</th>" for h in header) + "</tr>"
    return head + _rows_html(rows) + "</table>"


def _fit_line(d: Dict[str, Any]) -> str:
    fit = d.get("fit") or {}
    parts = []
    vaf = fit.get("vaf")
    if isinstance(vaf, list) and vaf:
        # one VAF per coordinate's force: labelled by it (issue 63, item 8)
        coords = d.get("coordinates") or (d.get("provenance") or {}).get("coordinates") or []
        labels = [str(c) for c in coords] if len(coords) == len(vaf) else [str(i + 1) for i in range(len(vaf))]
        parts.append("VAF " + ", ".join(f"{n} {v:.1f} %" for n, v in zip(labels, vaf) if v is not None))
    elif isinstance(vaf, (int, float)):
        parts.append(f"VAF {vaf:.1f} %")
    for k, label in (("vaf_total", "VAF (both pathways)"), ("cross_validated_vaf", "cross-validated VAF")):
        v = fit.get(k, d.get(k))
        if isinstance(v, (int, float)):
            parts.append(f"{label} {v:.1f} %")
    crit = d.get("criteria") or {}
    for k, label in (("condition_number", "condition number"), ("mean_multiple_coherence", "mean multiple coherence"),
                     ("fit_vaf", "parametric fit VAF")):
        v = crit.get(k)
        if isinstance(v, (int, float)):
            parts.append(f"{label} {v:.4g}")
    line = f"<p>Fit: {_e('; '.join(parts))}</p>" if parts else ""
    acc = d.get("accuracy")
    if isinstance(acc, dict) and isinstance(acc.get("mean_relative_error"), (int, float)):
        # stochastic with expected=: Park & Chang (2011) eq. (15)-(16) against the given model
        line += (f"<p>Against the expected model: mean relative error "
                 f"{100 * acc['mean_relative_error']:.2f} % of |Z|, phi_T {acc.get('phi_t', float('nan')):.4g} "
                 "(largest singular value of Z - Z_expected, mean over the band)</p>")
    return line


def _warnings_html(d: Dict[str, Any]) -> str:
    ws = d.get("warnings") or []
    if not ws:
        return ""
    groups: Dict[str, List[str]] = {}
    for w in ws:
        code = w.get("code", "note") if isinstance(w, dict) else "note"
        msg = w.get("message", str(w)) if isinstance(w, dict) else str(w)
        groups.setdefault(code, []).append(msg)
    items = "".join(f"<li><b>{_e(code.replace('_', ' '))}</b>: " + "<br>".join(_e(m) for m in msgs) + "</li>"
                    for code, msgs in groups.items())
    return f"<details open><summary>{len(ws)} warning{'s' if len(ws) != 1 else ''}</summary><ul>{items}</ul></details>"


def _matrices(recs: List[Record], kinds: Sequence[str] = MATRICES, symbols: Optional[Dict[str, str]] = None) -> str:
    return "".join(_matrix_table(recs, k, f"{k.capitalize()} {(symbols or SYMBOL)[k]}") for k in kinds)


#: Rows of a long table shown at its head and tail (the rest summarised in one row).
HEAD_ROWS, TAIL_ROWS = 12, 4


def _shortened(rows: List[List[str]], width: int) -> List[List[str]]:
    if len(rows) <= HEAD_ROWS + TAIL_ROWS + 1:
        return rows
    hidden = len(rows) - HEAD_ROWS - TAIL_ROWS
    gap = [f"… {hidden} more rows (to_pandas() has them all)"] + [""] * (width - 1)
    return rows[:HEAD_ROWS] + [gap] + rows[-TAIL_ROWS:]


def _varying_html(d: Dict[str, Any]) -> List[str]:
    """K, B and M (I for a joint) at every point, value ± SE with units, the
    points the data do not support named with their reason; walking adds the
    strides and the flawed ones."""
    coords = d["coordinates"]
    s = d["schedule"]
    axis = f"{s['name']} ({s['unit']})" if s.get("unit") else s["name"]
    angular = all(c == "theta" or c.startswith("q") for c in coords)
    symbols = {"stiffness": "K", "damping": "B", "inertia": "I" if angular else "M"}
    header = [axis]
    for q in MATRICES:
        for i in range(len(coords)):
            sub = "" if len(coords) == 1 else _sub(coords, i, i)
            header.append(f"{symbols[q]}{sub} ({_unit(q, coords[i], coords[i]).replace('^2', '²')})")
    header += ["count" if d.get("gait") else "support", "note"]
    rows: List[List[str]] = []
    for p in d["points"]:
        row = [f"{p['sigma']:.4g}"]
        if not p["identifiable"]:
            rows.append(row + ["—"] * (len(header) - 3) + [f"{p['support']:g}", p.get("reason") or "not identifiable"])
            continue
        for q in MATRICES:
            for i in range(len(coords)):
                m, e = p.get(q), p.get(q + "_se")
                row.append("—" if m is None or e is None else with_se(m[i][i], e[i][i]))
        v = p.get("verdicts") or {}
        note = ", ".join(f"{symbols[q]} {_words(v.get(q))}" for q in ("stiffness", "damping") if v.get(q))
        rows.append(row + [f"{p['support']:g}", note])
    parts = []
    g = d.get("gait")
    if g:
        parts.append("<p>" + _e(
            f"{g['strides_used']} of {g['strides_found']} strides used (median {g['stride_s'][0]:.3g} s, "
            f"{g['stride_s'][1]:.3g} to {g['stride_s'][2]:.3g} s); baseline: {g['baseline']}; verdicts against "
            f"walking tolerances K {100 * g['tolerances'][0]:.0f} %, B {100 * g['tolerances'][1]:.0f} %") + "</p>")
    parts.append(_list_table(header, _shortened(rows, len(header)),
                             f"Impedance against {s['name']} ({d['method']}; value ± SE)"))
    if g and g.get("flawed"):
        flawed = [[f["stride"], f"{f['start_s']:.3f}", f["start_row"], f"{f['duration_s']:.3f}", f["kind"], f["note"]]
                  for f in g["flawed"]]
        parts.append(_list_table(["stride", "start (s)", "row", "duration (s)", "kind", "what was done"],
                                 _shortened(flawed, 6), f"Strides with flawed events ({len(flawed)})"))
    parts.append(_e(d.get("resolution_note", "")) and f"<p>{_e(d['resolution_note'])}</p>")
    angle = (d.get("schedule") or {}).get("angle")
    if angle:
        parts.append(f"<p>{_e(angle)}</p>")
    parts.append(_fit_line(d))
    return parts


def why(e: BaseException) -> str:
    """Why a result could not be displayed, in one line (issue 56: a ragged
    hand-made result raised IndexError from ``_repr_html_``)."""
    return (f"its fields do not agree in shape or type ({type(e).__name__}: {e}); "
            "a result made by limpid always does")


def _flat_options(request: Dict[str, Any], prefix: str = "") -> List[Tuple[str, str]]:
    """The request's fields as (name, value) rows, nested ones dotted; absent
    (None) ones are left out: they mean "chosen from the data"."""
    rows: List[Tuple[str, str]] = []
    for k, v in request.items():
        if k == "method" or v is None:
            continue
        if isinstance(v, dict):
            rows.extend(_flat_options(v, f"{prefix}{k}."))
        else:
            rows.append((prefix + k, _value_text(v) if not isinstance(v, str) else v))
    return rows


def _header_html(d: Dict[str, Any]) -> str:
    """What the result was made from, collapsed (as MNE and xarray show it):
    the recordings (samples, rate, duration), limpid's version, when, the call
    and the options it ran with."""
    run = d.get("run")
    if not isinstance(run, dict):
        return ""
    rows: List[List[str]] = []
    for f in run.get("inputs") or []:
        shape = ""
        if f.get("samples") is not None and f.get("sample_rate_hz"):
            shape = (f"{f['samples']} samples at {f['sample_rate_hz']:.6g} Hz ({f['duration_s']:.4g} s)")
        rows.append(["recording", f.get("path", "?"), shape])
    rows.append(["made by", f"limpid {run.get('limpid_version', '?')}", run.get("created_utc", "")])
    rows.append(["call", run.get("command_line", ""), ""])
    request = run.get("request")
    options = _flat_options(request) if isinstance(request, dict) else []
    table = "<table>" + _rows_html(rows) + "</table>"
    if options:
        table += _list_table(["option", "value"], [[k, v] for k, v in options], "Options used")
    first = (run.get("inputs") or [{}])[0]
    brief = os.path.basename(str(first.get("path", ""))) or "arrays"
    if first.get("samples") is not None and first.get("sample_rate_hz"):
        brief += f", {first['samples']} samples at {first['sample_rate_hz']:.6g} Hz"
    return f"<details><summary>made from {_e(brief)}; limpid {_e(run.get('limpid_version', '?'))}</summary>{table}</details>"


def to_html(d: Dict[str, Any]) -> str:
    """The result as HTML tables (``Result._repr_html_``)."""
    kind = d.get("kind", "?")
    title = f"<p><b>limpid {_e(kind)} result</b>"
    rec = _recording(d)
    if rec:
        title += f" &mdash; {_e(rec)}"
    parts = [title + "</p>", _header_html(d)]
    if kind in ("linear", "stochastic"):
        parts.append(_matrices(records(d)))
        parts.append(_fit_line(d))
    elif kind == "planar":
        recs = records(d)
        parts.append(_matrices(recs, ("stiffness", "damping"), PLANAR_SYMBOL))
        xi = [r for r in recs if r["quantity"] == "inertial_parameter"]
        parts.append(_list_table(["parameter", "value ± SE", "unit"],
                                 [[r["element"], with_se(r["value"], r["se"]), r["unit"]] for r in xi],
                                 "Base inertial parameters"))
        parts.append(_fit_line(d))
    elif kind == "cocontraction":
        recs = records(d)
        for lv in d["levels"]:
            at = [r for r in recs if r.get("level") == lv["level"]]
            parts.append(f"<p><b>level {lv['level']:g}</b>: co-contraction index "
                         f"{lv['cocontraction_index']:.3f} (sd {lv['cocontraction_sd']:.3f})</p>")
            parts.append(_matrices(at))
    elif kind == "window_sweep":
        rows = []
        for row in d["rows"]:
            e = row["estimate"]
            recs = _planar(e)
            diag = [r for r in recs if r["quantity"] in ("stiffness", "damping") and r["row"] == r["column"]]
            rows.append([f"{row['observation_window_ms']:g}"]
                        + [with_se(r["value"], r["se"]) for r in diag]
                        + ["yes" if row["trusted"] else "no: " + "; ".join(row.get("reasons") or [])])
        recs0 = _planar(d["rows"][0]["estimate"]) if d["rows"] else []
        diag0 = [r for r in recs0 if r["quantity"] in ("stiffness", "damping") and r["row"] == r["column"]]
        header = ["T_obs (ms)"] + [f"{r['element']} ({r['unit']})" for r in diag0] + ["trusted"]
        parts.append(_list_table(header, rows, "Estimates against the observation window"))
        t = d.get("shortest_trusted_ms")
        parts.append(f"<p>Shortest trusted window: {'none' if t is None else f'{t:g} ms'}</p>")
        c = d.get("impedance_change")
        if c:
            line = (f"The impedance changes within the trials, significantly from "
                    f"{c.get('significant_from_ms', c['onset_ms']):.0f} ms after the onset "
                    f"(clearest at {c['onset_ms']:.0f} ms: K by {100 * c['stiffness_change']:.0f} %, "
                    f"D by {100 * c['damping_change']:.0f} %, p = {c.get('p_value', 0.0):.1e}); "
                    "windows reaching past it are not trusted.")
            tissue = d.get("series_compliance")
            if tissue:
                line += (f" A compliance in series explains the trials {tissue['residual_ratio']:.0f} times "
                         "better than the rigid model: likely soft tissue under the cuff, not a reflex.")
            parts.append(f"<p>{_html.escape(line)}</p>")
    elif kind == "reflex":
        recs = records(d)
        parts.append(_list_table(["quantity", "value ± SE", "unit", "verdict"],
                                 [[r["element"], with_se(r["value"], r["se"]), r["unit"], _words(r["verdict"])]
                                  for r in recs], "Intrinsic and reflex pathways (parallel cascade)"))
        parts.append(_fit_line(d))
    elif kind == "varying":
        parts.extend(_varying_html(d))
    elif kind == "study":
        # the to_pandas() column names, so the display and the table read alike (issue 63, item 8)
        header = ["configuration", "level", "subjects", "cocontraction_index", "kxx (N/m)", "kyy (N/m)", "kzz (N/m)"]
        rows = [[r["configuration"], f"{r['level']:g}", r["subjects"]]
                + ["" if r.get(k) is None else f"{r[k]:.4g}" for k in ("cocontraction_index", "kxx", "kyy", "kzz")]
                for r in d["levels"]]
        parts.append(_list_table(header, rows, "Mean over subjects (stiffness in N/m)"))
    elif kind in DESIGN_KINDS:
        parts.extend(_design_html(d))
    elif kind == "spectra":
        if d.get("periodic"):
            parts.extend(_periodic_html(d))
        parts.append(f"<p>inputs {_e(', '.join(d['inputs']))}; outputs {_e(', '.join(d['outputs']))}; "
                     f"Welch segments of {d['segment_samples']} samples overlapping by {d['overlap_samples']}</p>")
        parts.append(_list_table(["output", "mean", "min", "note"], _multiple_coherence_rows(d),
                                 "Multiple coherence on all inputs (above 0 Hz)"))
    elif kind == "demo":
        rows = []
        for p in d["points"]:
            recs = _linear(p["estimate"])
            diag = [r for r in recs if r["quantity"] == "stiffness" and r["row"] == r["column"]]
            rows.append([p["start_point"]] + [with_se(r["value"], r["se"]) for r in diag]
                        + [f"{p['stiffness_error_percent']:.1f} %", f"{p['damping_error_percent']:.1f} %"])
        parts.append(_list_table(["start point", "Kxx (N/m)", "Kyy (N/m)", "Kzz (N/m)", "K error", "B error"],
                                 rows, "Estimates against the virtual subject's truth"))
    else:
        scalars = [[k.replace("_", " "), f"{v:.4g}" if isinstance(v, float) else v]
                   for k, v in d.items() if isinstance(v, (int, float, str)) and k not in ("schema", "kind")]
        parts.append(_list_table(["field", "value"], scalars, summary(d)))
    parts.append(_warnings_html(d))
    return _STYLE + '<div class="limpid-result">' + "".join(parts) + "</div>"


# ---------------------------------------------------------------- parts of a result (issue 63, item 4)


def part_context(d: Dict[str, Any], parent: Optional[Dict[str, Any]], name: str) -> Dict[str, Any]:
    """Where a part of a result comes from: its path, and the whole result's
    kind, coordinates and units (which its matrices are in)."""
    if parent is not None:
        return dict(parent, path=f"{parent['path']}.{name}")
    coords = d.get("coordinates") or (d.get("provenance") or {}).get("coordinates")
    if coords is None and d.get("kind") == "planar":
        coords = ["q1", "q2"]
    return {"path": name, "kind": d.get("kind", "?"), "coordinates": coords, "units": d.get("units")}


def _field_unit(name: str, ctx: Dict[str, Any]) -> str:
    """The unit of a field of limpid's own schema: matrices by the result's
    coordinates (or units), the rest by the schema's suffixes."""
    base = name[:-3] if name.endswith("_se") else name
    if base in MATRICES:
        units = ctx.get("units")
        if isinstance(units, dict) and units.get(base):
            return str(units[base])
        coords = ctx.get("coordinates") or []
        if coords and len({_unit(base, c, c) for c in coords}) == 1:
            return _unit(base, coords[0], coords[0])
        return "by element" if coords else ""
    if name.startswith("vaf") or name.endswith(("_vaf", "_percent")):
        return "%"
    for suffix, unit in (("_hz", "Hz"), ("_ms", "ms"), ("_s", "s"), ("_m", "m"), ("_rad", "rad")):
        if name.endswith(suffix):
            return unit
    return ""


def _numeric(v: Any) -> bool:
    """A number or a list of numbers (which a unit applies to)."""
    if isinstance(v, list):
        return bool(v) and all(_numeric(x) for x in v)
    return isinstance(v, (int, float)) and not isinstance(v, bool)


def _is_matrix(v: Any) -> bool:
    return (isinstance(v, list) and bool(v) and all(isinstance(r, list) and len(r) == len(v[0]) for r in v)
            and all(isinstance(x, (int, float)) or x is None for r in v for x in r))


def _value_text(v: Any) -> str:
    """A field's value in words: numbers to 4 digits, short lists whole,
    long ones by size and range, nested parts by their fields."""
    if v is None:
        return "—"
    if isinstance(v, bool):
        return "yes" if v else "no"
    if isinstance(v, int):
        return str(v)
    if isinstance(v, float):
        return f"{v:.4g}" if math.isfinite(v) else "not finite"
    if isinstance(v, str):
        return v.replace("_", " ")
    if isinstance(v, dict):
        return "part: " + ", ".join(sorted(v)[:8]) + (" …" if len(v) > 8 else "")
    if isinstance(v, list):
        if _is_matrix(v):
            return f"{len(v)} x {len(v[0])} matrix"
        nums = [x for x in v if isinstance(x, (int, float)) and not isinstance(x, bool)]
        if len(nums) == len(v) and v:
            if len(v) <= 6:
                return ", ".join(f"{x:.4g}" for x in nums)
            return f"{len(v)} values, {min(nums):.4g} to {max(nums):.4g}"
        return f"{len(v)} items"
    return str(v)


def part_summary(d: Dict[str, Any], ctx: Dict[str, Any]) -> str:
    """A part's repr: where it is from and its scalar fields."""
    fields = []
    for k, v in d.items():
        if isinstance(v, (int, float, str, bool)) or (isinstance(v, list) and len(v) <= 3 and not _is_matrix(v)):
            unit = _field_unit(k, ctx) if _numeric(v) else ""
            fields.append(f"{k} = {_value_text(v)}" + (f" {unit}" if unit else ""))
        else:
            fields.append(k)
    body = "; ".join(fields)
    if len(body) > 300:
        body = body[:297] + "…"
    return f"limpid.Result({ctx['path']} of a {ctx['kind']} result: {body})"


def part_html(d: Dict[str, Any], ctx: Dict[str, Any]) -> str:
    """A part as HTML: its matrices as tables with units, its other fields
    as a field | value | unit table."""
    title = f"<p><b>{_e(ctx['path'])}</b> of a limpid {_e(ctx['kind'])} result</p>"
    coords = ctx.get("coordinates") or []
    tables, rows = [], []
    for k, v in d.items():
        if _is_matrix(v) and coords and len(v) == len(coords) and len(v[0]) == len(coords):
            base = k[:-3] if k.endswith("_se") else k
            head = ["", *coords]
            # a unit in each cell only where the elements' units differ (mixed m and rad)
            per_element = base in MATRICES and not ctx.get("units") and len(
                {_unit(base, a, b) for a in coords for b in coords}) > 1
            body = [[ci, *(_value_text(v[i][j]) + (f" {_unit(base, ci, cj)}" if per_element else "")
                           for j, cj in enumerate(coords))]
                    for i, ci in enumerate(coords)]
            unit = _field_unit(k, ctx)
            tables.append(_list_table(head, body, k.replace("_", " ") + (f" ({unit})" if unit and unit != "by element"
                                                                        else "")))
        else:
            rows.append([k.replace("_", " "), _value_text(v), _field_unit(k, ctx) if _numeric(v) else ""])
    parts = [title, *tables]
    if rows:
        parts.append(_list_table(["field", "value", "unit"], rows, "fields"))
    parts.append("<p><i>to_dict() gives the numbers in full</i></p>")
    return _STYLE + '<div class="limpid-result">' + "".join(parts) + "</div>"
