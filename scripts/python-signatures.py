#!/usr/bin/env python3
"""Write limpid's estimator functions (crates/python/python/limpid/_estimators.py)
with every option in their signatures and numpydoc "Parameters" sections, from
the request types the CLI's flags are derived from (issue 63, item 6).

Each option's type and choices come from the method's JSON Schema
(``limpid._limpid.request_schema``), its description (unit, meaning, what
``None`` chooses) from the same doc comment that is the CLI flag's help, and
its default from the request with no option given (``limpid.request``). The
functions' summaries and their Returns sections are written here.

    python scripts/python-signatures.py          # rewrite the module
    python scripts/python-signatures.py --check  # exit 1 if it is out of date

It needs limpid's extension built and installed (the tests run ``--check``).
"""

from __future__ import annotations

import json
import pathlib
import sys
import textwrap
from typing import Any, Dict, List, Optional, Tuple

OUT = pathlib.Path(__file__).resolve().parents[1] / "crates/python/python/limpid/_estimators.py"

RECORDING_DOC = ("recording : str, os.PathLike, dict of arrays or pandas.DataFrame\n"
                 "    A recording in limpid's format (docs/src/format.md): a CSV, Parquet or MAT path,\n"
                 "    a dict of 1-D arrays or a DataFrame (time ``t`` as a column or its index).")

# how the recording files are read, the same for every estimator (issue 81)
READING_PARAMS = ["map: MapLike = None", "columns: Optional[Mapping[str, str]] = None"]
READING_DOCS = [
    "map : str, os.PathLike, dict or None, default None\n"
    "    Channel map (TOML) for commands that read recordings (the CLI's ``--map``): the path\n"
    "    of its file or a dict of the same shape, reading a lab file's channels as the\n"
    "    recording's columns (docs/src/reference/lab-files.md).",
    "columns : dict of str to str or None, default None\n"
    "    Name a column of the recording by its channel in the file (the CLI's ``--column``),\n"
    "    e.g. ``{\"t\": \"time_s\", \"q1\": \"angle_rad\"}``; the other columns keep their names.",
]

# name, method, positional parameters (source, doc), leading request fields they fill,
# summary, returns, the call of _estimate
FUNCTIONS: List[Dict[str, Any]] = [
    dict(
        name="estimate_linear", method="linear",
        params=[("recording: RecordingLike", RECORDING_DOC)], fixed={},
        summary="""Artemiadis et al. (2010)'s linear estimator (M, B, K with standard errors, fit,
criteria, ellipsoids), as ``limpid estimate linear``.""",
        returns="""Result
    kind ``linear``: ``inertia``, ``damping``, ``stiffness`` (rows: forces, columns:
    coordinates, in the units of ``provenance.units``), ``standard_errors``, ``symmetric``,
    ``antisymmetric``, ``ellipsoids``, ``table_ii``, ``fit`` (VAF %, r, RMSE and traces),
    ``criteria`` (condition number, identifiability, verdicts), ``warnings``.""",
        call='_estimate("linear", [recording], options)'),
    dict(
        name="estimate_planar", method="planar",
        params=[("recording: RecordingLike", RECORDING_DOC),
                ("link_lengths: Sequence[float]",
                 "link_lengths : sequence of 2 floats\n    Upper arm and forearm length (m).")],
        fixed={"link_lengths"},
        summary="""Lakatos, Petit & van der Smagt (2011)'s planar-arm estimator (joint K, D, inertial
parameters, criteria), as ``limpid estimate planar``.""",
        returns="""Result
    kind ``planar``: joint ``stiffness`` (N m/rad) and ``damping`` (N m s/rad) with standard
    errors, ``inertial_parameters`` (kg m²), ``endpoint_stiffness`` (N/m), ``criteria``,
    ``fit``, ``warnings``.""",
        call='_estimate("planar", [recording], dict(options, link_lengths=link_lengths))'),
    dict(
        name="window_sweep", method="window_sweep",
        params=[("recording: RecordingLike", RECORDING_DOC),
                ("link_lengths: Sequence[float]",
                 "link_lengths : sequence of 2 floats\n    Upper arm and forearm length (m).")],
        fixed={"link_lengths"},
        summary="""Lakatos, Petit & van der Smagt (2011)'s observation-window sweep, as ``limpid
window-sweep --json``: one planar estimate with its criteria per window, and the
shortest trustworthy window.""",
        returns="""Result
    kind ``window_sweep``: ``rows`` (``observation_window_ms``, ``estimate``, ``trusted``,
    ``reasons``), ``shortest_trusted_ms``; ``to_xarray()`` gives them over the window.""",
        call='_estimate("window_sweep", [recording], dict(options, link_lengths=link_lengths))'),
    dict(
        name="estimate_stochastic", method="stochastic",
        params=[("recording: Union[RecordingLike, Sequence[RecordingLike]]",
                 RECORDING_DOC + "\n    A list of recordings is pooled (their Welch segments averaged together).")],
        fixed={},
        summary="""Park & Chang (2011)'s stochastic MIMO estimator: Z(f) = T R^-1, coherences,
parametric fit, as ``limpid estimate stochastic``.

With ``shoulder`` the shoulder's joint impedance is estimated as Park & Chang (2011)
do: hand X, Z become flexion ``q1`` and abduction ``q2``, forces become torques
``J_h^T F`` (eq. (3)), and ``theta``/``tauy``/``utheta`` internal rotation ``q3``,
before the spectra; the posture is the operating point (the recording's mean X, Z is
the hand there); x forward, y left, z up, right arm.""",
        returns="""Result
    kind ``stochastic``: ``frequencies`` (Hz), ``impedance`` (complex, frequency x output x
    displacement), ``coherence`` (multiple and partial), the parametric ``inertia``,
    ``damping``, ``stiffness`` with ``standard_errors``, ``criteria``, ``accuracy`` (with
    ``expected``), ``warnings``.""",
        call=('_estimate("stochastic", list(recording) if isinstance(recording, (list, tuple)) '
              'else [recording], options)')),
    dict(
        name="estimate_reflex", method="reflex",
        params=[("recording: RecordingLike", RECORDING_DOC)], fixed={},
        summary="""Intrinsic and reflex joint stiffness by the parallel cascade (Kearney et al. 1997),
as ``limpid estimate reflex --json``.

The recording holds a position column (a joint angle in rad, or with
``coordinate="displacement"`` an end-point position in m) and the torque (or force)
applied to the limb, under a stochastic perturbation, with time ``t`` (s).""",
        returns="""Result
    kind ``reflex``: ``units`` (from what the position column is), ``intrinsic`` (inertia,
    damping, stiffness with standard errors, IRF per second of lag), ``reflex`` (polarity,
    gain, delay_s, delay_interval_s, IRF), ``fit`` (VAF %), ``cross_validated_vaf``,
    ``warnings``.""",
        call='_estimate("reflex", [recording], options)'),
    dict(
        name="estimate_varying", method="varying",
        params=[("recording: RecordingLike", RECORDING_DOC)], fixed={},
        positional_options=["schedule"],
        summary="""Impedance that varies, as ``limpid estimate varying --json``.

``schedule="time"``: the recording's ``trial`` repetitions of one task form an
ensemble; at each instant the deviations from the ensemble mean are regressed (M, B, K
against time since the trial's start). ``schedule="<column>"`` (e.g. an operating angle
``sv``, a ``level``): every parameter is a Chebyshev polynomial of that column, fitted
in one least-squares problem (parameter-varying). Walking: ``event`` cuts the record
into strides and puts impedance against gait phase (``schedule="gait-phase"``, the
default then, or ``"time-since-event"``), by ``gait_method`` ``"pulses"`` (perturbed
minus unperturbed strides) or ``"ensemble"`` (a perturbation on every stride).""",
        returns="""Result
    kind ``varying``: ``schedule`` (name, unit, values), ``points`` (per grid value:
    ``sigma``, ``identifiable``, ``stiffness``/``damping``/``inertia`` with ``*_se``,
    ``vaf``, ``reason`` when not identifiable), ``fit``, ``warnings``; walking adds
    ``gait`` (strides used, flawed ones by number).""",
        call='_estimate("varying", [recording], dict(options, schedule=schedule))'),
    dict(
        name="estimate_cocontraction", method="cocontraction",
        params=[("recording: RecordingLike", RECORDING_DOC),
                ("mvc: RecordingLike",
                 "mvc : str, os.PathLike, dict of arrays or pandas.DataFrame\n"
                 "    The maximum voluntary contraction recording of the same muscles.")],
        fixed={},
        summary="""Patel, O'Neill & Artemiadis (2013)'s co-contraction analysis: the co-contraction
index and the stiffness per level, as ``limpid estimate cocontraction``.""",
        returns="""Result
    kind ``cocontraction``: ``muscles``, ``levels`` (per level: ``cocontraction_index`` with
    its sd, the linear ``estimate``, the stiffness ``ellipsoid``), ``warnings``.""",
        call='_estimate("cocontraction", [recording, mvc], options)'),
    dict(
        name="spectra", method="spectra",
        params=[("recording: RecordingLike", RECORDING_DOC),
                ("inputs: Sequence[str]", "inputs : sequence of str\n    Input columns."),
                ("outputs: Sequence[str]", "outputs : sequence of str\n    Output columns.")],
        fixed={"inputs", "outputs"},
        summary="""Welch spectra of a recording's named columns and, per output, its ordinary
coherence with each input, its multiple coherence on all inputs and its partial
coherence with each input, the others removed (Park & Chang 2011), as ``limpid spectra
--json``; with ``period_s``, the periodic analysis (excited and detection lines).""",
        returns="""Result
    kind ``spectra``: ``frequencies``, ``psd[signal][frequency]`` (signals: inputs then
    outputs), ``coherence[output][input][frequency]``, ``multiple_coherence`` and
    ``partial_coherence`` (``None`` where the inputs' spectral matrix is singular),
    ``periodic`` with ``period_s``.""",
        check=('if isinstance(inputs, str) or isinstance(outputs, str):\n'
               '    raise ValueError("inputs and outputs: expected lists of column names, e.g. inputs=[\'ux\', \'uz\']")'),
        call='_estimate("spectra", [recording], dict(options, inputs=list(inputs), outputs=list(outputs)))'),
]

# a request needs these to be made; the values only fill the call for its defaults
REQUIRED = {"planar": {"link_lengths": [0.3, 0.33]}, "window_sweep": {"link_lengths": [0.3, 0.33]},
            "spectra": {"inputs": ["u"], "outputs": ["y"]}}


def resolve(schema: Dict[str, Any], node: Dict[str, Any]) -> Dict[str, Any]:
    ref = node.get("$ref")
    if ref:
        return resolve(schema, schema["$defs"][ref.split("/")[-1]])
    return node


def choices(schema: Dict[str, Any], node: Dict[str, Any]) -> Optional[List[str]]:
    node = resolve(schema, node)
    if "enum" in node:
        return [str(v) for v in node["enum"] if v is not None]
    for key in ("oneOf", "anyOf"):
        if key in node and all("const" in resolve(schema, n) or "enum" in resolve(schema, n)
                                for n in node[key] if resolve(schema, n).get("type") != "null"):
            out: List[str] = []
            for n in node[key]:
                n = resolve(schema, n)
                if "const" in n:
                    out.append(str(n["const"]))
                elif "enum" in n:
                    out.extend(str(v) for v in n["enum"] if v is not None)
            return out or None
    return None


def python_type(schema: Dict[str, Any], node: Dict[str, Any]) -> Tuple[str, str, bool]:
    """(annotation, numpydoc type, nullable) of a schema node."""
    node = resolve(schema, node)
    for key in ("anyOf", "oneOf"):
        alts = node.get(key)
        if alts and any(resolve(schema, a).get("type") == "null" for a in alts):
            rest = [a for a in alts if resolve(schema, a).get("type") != "null"]
            if len(rest) == 1:
                ann, doc, _ = python_type(schema, rest[0])
                return ann, doc, True
    t = node.get("type")
    if isinstance(t, list):
        nullable = "null" in t
        kinds = [k for k in t if k != "null"]
        if len(kinds) == 1:
            ann, doc, _ = python_type(schema, dict(node, type=kinds[0]))
            return ann, doc, nullable
    names = choices(schema, node)
    if names:
        return "Literal[" + ", ".join(repr(n) for n in names) + "]", "{" + ", ".join(repr(n) for n in names) + "}", False
    if t == "number":
        return "float", "float", False
    if t == "integer":
        return "int", "int", False
    if t == "boolean":
        return "bool", "bool", False
    if t == "string":
        return "str", "str", False
    if t == "array":
        items = node.get("items") or (node.get("prefixItems") or [{}])[0]
        inner, inner_doc, _ = python_type(schema, items) if isinstance(items, dict) else ("Any", "value", False)
        n = node.get("minItems")
        size = f"{n} " if n is not None and n == node.get("maxItems") else ""
        return f"Sequence[{inner}]", f"sequence of {size}{inner_doc}", False
    return "Any", "value", False


def extension() -> Any:
    """limpid's compiled module, loaded without the package (whose __init__
    imports the module this script writes)."""
    import importlib.machinery
    import importlib.util

    spec = importlib.util.find_spec("limpid")
    if spec is None or not spec.submodule_search_locations:
        raise SystemExit("limpid is not installed: build it first (maturin develop, or pip install the wheel)")
    for folder in spec.submodule_search_locations:
        for path in sorted(pathlib.Path(folder).glob("_limpid*.so")) + sorted(pathlib.Path(folder).glob("_limpid*.pyd")):
            loader = importlib.machinery.ExtensionFileLoader("_limpid", str(path))
            module_spec = importlib.util.spec_from_file_location("_limpid", path, loader=loader)
            assert module_spec is not None
            module = importlib.util.module_from_spec(module_spec)
            loader.exec_module(module)
            return module
    raise SystemExit("limpid's compiled module _limpid was not found")


def options_of(method: str) -> List[Dict[str, Any]]:
    """The method's options, flattened as the estimators take them, in the request's order."""
    _limpid = extension()

    schema = json.loads(_limpid.request_schema(method))
    defaults = _limpid.request(method, dict(REQUIRED.get(method, {})))
    out: List[Dict[str, Any]] = []

    def walk(props: Dict[str, Any], values: Dict[str, Any]) -> None:
        for name, node in props.items():
            target = resolve(schema, node)
            if target.get("type") == "object" and "properties" in target:
                walk(target["properties"], values.get(name) or {})
                continue
            ann, doc, nullable = python_type(schema, node)
            default = values.get(name)
            if default is None:
                nullable = True
            out.append(dict(name=name, annotation=f"Optional[{ann}]" if nullable else ann,
                            doc_type=doc + (" or None" if nullable else ""), default=default,
                            description=" ".join((node.get("description") or target.get("description")
                                                  or "").split())))

    walk(schema.get("properties") or {}, defaults)
    return out


def literal(v: Any) -> str:
    if isinstance(v, list):
        return "(" + ", ".join(literal(x) for x in v) + ("," if len(v) == 1 else "") + ")"
    return repr(v)


def function_source(spec: Dict[str, Any]) -> str:
    opts = [o for o in options_of(spec["method"]) if o["name"] not in spec["fixed"]]
    positional = spec.get("positional_options", [])
    lead = [o for name in positional for o in opts if o["name"] == name]
    rest = [o for o in opts if o["name"] not in positional]
    params = [p for p, _ in spec["params"]]
    params += [f"{o['name']}: {o['annotation']} = {literal(o['default'])}" for o in lead]
    params.append("*")
    params += [f"{o['name']}: {o['annotation']} = {literal(o['default'])}" for o in rest]
    params += READING_PARAMS
    head = f"def {spec['name']}("
    sig = head + ", ".join(params) + ") -> Result:"
    if len(sig) > 116:
        sig = head + "\n" + ",\n".join("        " + p for p in params) + ",\n) -> Result:"
    docs = [d for _, d in spec["params"]]
    for o in lead + rest:
        text = o["description"] or "(no description)"
        body = textwrap.fill(text, 88, initial_indent="    ", subsequent_indent="    ")
        docs.append(f"{o['name']} : {o['doc_type']}, default {literal(o['default'])}\n{body}")
    docs += READING_DOCS
    doc = (spec["summary"].strip() + "\n\nParameters\n----------\n" + "\n".join(docs)
           + "\n\nReturns\n-------\n" + spec["returns"].strip())
    doc = textwrap.indent(doc, "    ").replace("\\", "\\\\")
    names = [o["name"] for o in rest] + ["map", "columns"]
    lines = [sig, f'    """{doc.lstrip()}\n    """']
    if spec.get("check"):
        lines.append(textwrap.indent(spec["check"], "    "))
    lines.append("    options = {" + ", ".join(f'"{n}": {n}' for n in names) + "}")
    lines.append(f"    return {spec['call']}")
    return "\n".join(lines) + "\n"


def module_source() -> str:
    parts = ['''"""limpid's estimators: GENERATED by scripts/python-signatures.py from the request
types the CLI's flags are derived from, so their options, types, defaults and
descriptions cannot drift from the CLI's. Do not edit: change the request type's
doc comment (or the script's summaries) and run the script."""

from __future__ import annotations

from typing import Literal, Mapping, Optional, Sequence, Union

from . import MapLike, Result, RecordingLike, _estimate

__all__ = [''' + ", ".join(f'"{f["name"]}"' for f in FUNCTIONS) + "]\n"]
    for spec in FUNCTIONS:
        parts.append("\n\n" + function_source(spec))
    return "".join(parts)


def main() -> int:
    text = module_source()
    if "--check" in sys.argv[1:]:
        if not OUT.exists() or OUT.read_text() != text:
            print(f"{OUT} is out of date: run python scripts/python-signatures.py", file=sys.stderr)
            return 1
        return 0
    OUT.write_text(text)
    return 0


if __name__ == "__main__":
    sys.exit(main())
