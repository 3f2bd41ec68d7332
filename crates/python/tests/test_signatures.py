"""Issue 63, item 6: every estimator shows its options in its signature, with
type and default, generated from the request types the CLI's flags come from;
the generated module is up to date, its defaults are the CLI's and its
descriptions are the CLI flags' help."""

import inspect
import json
import os
import pathlib
import runpy
import subprocess
import sys

import pytest

import limpid

REPO = pathlib.Path(__file__).resolve().parents[3]
GENERATOR = REPO / "scripts" / "python-signatures.py"
CLI = os.environ.get("LIMPID_CLI")

# function, method, arguments the CLI needs besides the recording
ESTIMATORS = [("estimate_linear", "linear", ["estimate", "linear"]),
              ("estimate_planar", "planar", ["estimate", "planar", "--link-lengths", "0.3,0.33"]),
              ("window_sweep", "window_sweep", ["window-sweep", "--link-lengths", "0.3,0.33"]),
              ("estimate_stochastic", "stochastic", ["estimate", "stochastic"]),
              ("estimate_reflex", "reflex", ["estimate", "reflex"]),
              ("estimate_varying", "varying", ["estimate", "varying"]),
              ("estimate_cocontraction", "cocontraction", ["estimate", "cocontraction"])]
NEEDED = {"planar": {"link_lengths": [0.3, 0.33]}, "window_sweep": {"link_lengths": [0.3, 0.33]}}
POSITIONAL = {"link_lengths", "inputs", "outputs"}


def test_the_generated_module_is_up_to_date():
    g = runpy.run_path(str(GENERATOR), run_name="limpid_signatures")
    assert g["OUT"].read_text() == g["module_source"](), "run python scripts/python-signatures.py"


def _flat(request):
    out = {}
    for k, v in request.items():
        if k == "method":
            continue
        if isinstance(v, dict):
            out.update(_flat(v))
        else:
            out[k] = v
    return out


@pytest.mark.parametrize("name,method,_cli", ESTIMATORS)
def test_every_option_is_in_the_signature_with_its_type_and_default(name, method, _cli):
    sig = inspect.signature(getattr(limpid, name))
    request = _flat(limpid.request(method, **NEEDED.get(method, {})))
    options = {p.name: p for p in sig.parameters.values() if p.kind == p.KEYWORD_ONLY}
    options.update({p.name: p for p in sig.parameters.values()
                    if p.kind == p.POSITIONAL_OR_KEYWORD and p.name in request and p.name not in POSITIONAL})
    # the request leaves out options that are None (chosen from the data)
    assert set(request) - POSITIONAL <= set(options), (name, set(request) - set(options))
    assert all(options[k].default is None for k in set(options) - set(request)), name
    for k, p in options.items():
        default = list(p.default) if isinstance(p.default, tuple) else p.default
        assert default == request.get(k), (name, k, p.default, request.get(k))
        assert p.annotation not in (inspect.Parameter.empty, "Any"), (name, k)
    # numpydoc: a Parameters entry per option, with its type and default
    doc = getattr(limpid, name).__doc__
    assert "Parameters\n    ----------" in doc and "Returns\n    -------" in doc
    for k in options:
        assert f"\n    {k} : " in doc and "default" in doc.split(f"\n    {k} : ")[1].split("\n")[0], (name, k)


@pytest.mark.skipif(not CLI, reason="LIMPID_CLI (the limpid binary) not set")
@pytest.mark.parametrize("name,method,cli", ESTIMATORS)
def test_the_signatures_match_the_cli_flags(name, method, cli, tmp_path):
    # the CLI's request with no flag is the signature's defaults
    rec = tmp_path / "r.csv"
    rec.write_text("t,x,fx\n0,0,0\n")
    extra = [str(rec)] + (["--mvc", str(rec)] if method == "cocontraction" else [])
    out = subprocess.run([CLI, *cli, *extra, "--print-request"], capture_output=True, text=True)
    assert out.returncode == 0, out.stderr
    printed = _flat(json.loads(out.stdout))
    sig = inspect.signature(getattr(limpid, name))
    for p in sig.parameters.values():
        if p.name in printed and p.default is not inspect.Parameter.empty:
            default = list(p.default) if isinstance(p.default, tuple) else p.default
            assert default == printed[p.name], (name, p.name, p.default, printed[p.name])
    # the CLI's flags are derived from the request types (issue 57): each
    # option's description is its flag's help, the same doc comment, so its
    # first words are in --help; yes/no options are flags whose help may say
    # the other way
    help_text = " ".join(subprocess.run([CLI, *cli, "--help"], capture_output=True, text=True).stdout.split())
    lines = getattr(limpid, name).__doc__.splitlines()
    compared = 0
    for p in sig.parameters.values():
        if p.kind != p.KEYWORD_ONLY or p.annotation in ("bool", bool):
            continue
        at = lines.index(next(x for x in lines if x.startswith(f"    {p.name} : ")))
        first_words = " ".join(lines[at + 1].split()[:5]).rstrip(".")
        assert first_words in help_text, (name, p.name, first_words)
        compared += 1
    assert compared >= 3, name
