"""Issue 39: results in a notebook. Each kind displays as a readable table
(value ± SE rounded by the library's rule, units, verdicts, warnings),
``to_pandas()`` gives back the result's own numbers exactly, every plot
runs on the examples of its kind with units on its axes, and the tutorial
notebook executes."""

import math
import pathlib
import sys

import pytest

import limpid
from limpid import _limpid

from conftest import examples

pd = pytest.importorskip("pandas")
matplotlib = pytest.importorskip("matplotlib")
matplotlib.use("Agg")

REPO = pathlib.Path(__file__).resolve().parents[3]


def _study(tmp_path):
    c = examples("cocontraction")
    manifest = tmp_path / "study.toml"
    entries = "".join(
        f'[[recording]]\nsubject = "s1"\nconfiguration = "{n}"\nfile = "{c / f"ex_config{n}.csv"}"\n'
        f'mvc = "{c / f"ex_config{n}.mvc.csv"}"\n'
        for n in (4, 7)
    )
    manifest.write_text('[study]\nname = "two configurations"\n' + entries)
    return limpid.study_run(manifest)


@pytest.fixture(scope="module")
def results(tmp_path_factory):
    """One result of every kind, made from the limpid-made examples."""
    cart, planar, stoch = examples("cartesian_slow"), examples("planar"), examples("stochastic")
    coc = examples("cocontraction")
    return {
        "linear": limpid.estimate_linear(cart / "ex_cubic.csv"),
        "cocontraction": limpid.estimate_cocontraction(coc / "ex_config4.csv", coc / "ex_config4.mvc.csv"),
        "planar": limpid.estimate_planar(planar / "ex_joint_180.csv", link_lengths=[0.3, 0.33]),
        "window_sweep": limpid.window_sweep(planar / "ex_joint_180.csv", link_lengths=[0.3, 0.33]),
        "stochastic": limpid.estimate_stochastic(stoch / "ex_sa3.csv"),
        "reflex": limpid.estimate_reflex(examples("ankle") / "ex_ankle.csv"),
        "varying": limpid.estimate_varying(planar / "ex_joint_180.csv"),
        "study": _study(tmp_path_factory.mktemp("study")),
    }


KINDS = ["linear", "cocontraction", "planar", "window_sweep", "stochastic", "reflex", "varying", "study"]


@pytest.mark.parametrize("kind", KINDS)
def test_each_kind_displays_as_a_readable_table(results, kind):
    r = results[kind]
    assert r.kind == kind
    text = repr(r)
    assert text.startswith(f"limpid.Result(kind={kind!r}") and "NaN" not in text and len(text) < 400, text
    html = r._repr_html_()
    assert html.count("<table") >= 1 and "NaN" not in html and " nan" not in html, kind
    if kind in ("linear", "stochastic", "planar"):
        d = r.to_dict()
        k, se = d["stiffness"][0][0], d["standard_errors"]["stiffness"][0][0]
        # the diagonal as the report and the CLI print it, rounded to its SE
        assert _limpid.with_standard_error(k, se) in html
        assert d["criteria"]["verdicts"]["stiffness"].replace("_", " ") in html
        unit = "N/m" if kind != "planar" else "N m/rad"
        assert f"({unit})" in html or unit in html
        assert f"{_limpid.with_standard_error(k, se)} {unit}" in text
    if r.to_dict().get("warnings"):
        w = r.to_dict()["warnings"][0]
        assert w["code"].replace("_", " ") in html


def _exact(df, rows):
    """Every (selector, value) of `rows` is in `df` with exactly that float."""
    for sel, value in rows:
        hit = df
        for col, v in sel.items():
            hit = hit[hit[col] == v]
        assert len(hit) == 1, (sel, len(hit))
        got = hit.iloc[0]["value"] if "value" in hit.columns else None
        assert got == value or (math.isnan(value) and math.isnan(got)), (sel, got, value)


def test_to_pandas_gives_back_the_numbers_of_the_json_exactly(results):
    lin = results["linear"].to_dict()
    df = results["linear"].to_pandas()
    coords = lin["provenance"]["coordinates"]
    assert len(df) == 3 * len(coords) ** 2
    for q in ("stiffness", "damping", "inertia"):
        for i, a in enumerate(coords):
            for j, b in enumerate(coords):
                row = df[(df.quantity == q) & (df.row == a) & (df.column == b)].iloc[0]
                assert row.value == lin[q][i][j]
                assert row.se == lin["standard_errors"][q][i][j]
                assert row.verdict == lin["criteria"]["verdicts"][q]
    assert set(df.unit[df.quantity == "damping"]) == {"N s/m"}

    coc = results["cocontraction"].to_dict()
    dfc = results["cocontraction"].to_pandas()
    for lv in coc["levels"]:
        _exact(dfc, [({"level": lv["level"], "quantity": "cocontraction_index"}, lv["cocontraction_index"]),
                     ({"level": lv["level"], "quantity": "stiffness", "row": "x", "column": "y"},
                      lv["estimate"]["stiffness"][0][1])])

    sto = results["stochastic"].to_dict()
    z = results["stochastic"].to_pandas("impedance")
    k = len(sto["frequencies"]) // 2
    first = z[(z.frequency_hz == sto["frequencies"][k]) & (z.output == "x") & (z.displacement == "z")].iloc[0]
    assert first.real == sto["impedance"][k][0][1][0] and first.imag == sto["impedance"][k][0][1][1]
    coh = results["stochastic"].to_pandas("coherence")
    out0 = sto["coherence"]["outputs"][0]
    hit = coh[(coh.output == out0) & (coh.frequency_hz == sto["frequencies"][k]) & (coh.input == sto["inputs"][1])]
    assert hit.iloc[0].partial == sto["coherence"]["partial"][0][1][k]
    assert hit.iloc[0].multiple == sto["coherence"]["multiple"][0][k]
    xa = results["stochastic"].to_xarray()
    assert xa.shape == (len(sto["frequencies"]), 3, 3)
    assert complex(xa.values[k, 0, 1]) == complex(*sto["impedance"][k][0][1])

    swp = results["window_sweep"].to_dict()
    dfs = results["window_sweep"].to_pandas()
    for r in swp["rows"]:
        _exact(dfs, [({"window_ms": r["observation_window_ms"], "element": "K2,2"}, r["estimate"]["stiffness"][1][1]),
                     ({"window_ms": r["observation_window_ms"], "element": "D1,2"}, r["estimate"]["damping"][0][1])])
        assert set(dfs[dfs.window_ms == r["observation_window_ms"]].trusted) == {r["trusted"]}

    ref = results["reflex"].to_dict()
    dfr = results["reflex"].to_pandas()
    _exact(dfr, [({"quantity": "intrinsic_stiffness"}, ref["intrinsic"]["stiffness"]),
                 ({"quantity": "reflex_gain"}, ref["reflex"]["gain"])])
    assert dfr[dfr.quantity == "intrinsic_stiffness"].iloc[0].unit == "N m/rad"

    var = results["varying"].to_dict()
    dfv = results["varying"].to_pandas()
    ok = [p for p in var["points"] if p["identifiable"]]
    assert len(dfv) == sum(3 * len(var["coordinates"]) ** 2 for _ in ok)
    for p in ok:
        _exact(dfv, [({"sigma": p["sigma"], "element": "K1,1"}, p["stiffness"][0][0])])

    st = results["study"].to_dict()
    dft = results["study"].to_pandas()
    assert len(dft) == len(st["levels"])
    assert list(dft.kxx) == [lv["kxx"] for lv in st["levels"]]
    assert len(results["study"].to_pandas("rotation")) == len(st["rotation"])

    with pytest.raises(ValueError, match="impedance"):
        results["linear"].to_pandas("impedance")


def _labelled(fig):
    """Every axis that shows data names its quantity and unit (a shared x
    axis once, under the bottom panel)."""
    for ax in fig.axes:
        if not ax.has_data():
            continue
        x = ax.get_xlabel() or next(
            (o.get_xlabel() for o in ax.get_shared_x_axes().get_siblings(ax) if o.get_xlabel()), "")
        labels = [x, ax.get_ylabel()] + ([ax.get_zlabel()] if hasattr(ax, "get_zlabel") else [])
        for label in labels:
            assert label and "(" in label and label.endswith(")"), (ax.get_title(), labels)


def test_every_plot_runs_on_its_kind_with_units_on_the_axes(results, tmp_path):
    from limpid import plot

    figures = {
        "ellipsoids_linear": plot.ellipsoids(results["linear"]),
        "ellipsoids_levels": plot.ellipsoids(results["cocontraction"]),
        "ellipses": plot.ellipses(results["planar"]),
        "fit_linear": plot.fit(results["linear"]),
        "fit_reflex": plot.fit(results["reflex"]),
        "bode": plot.bode(results["stochastic"]),
        "coherence": plot.coherence(results["stochastic"]),
        "sweep": plot.sweep(results["window_sweep"]),
        "reflex": plot.reflex(results["reflex"]),
    }
    for name, fig in figures.items():
        _labelled(fig)
        path = tmp_path / f"{name}.png"
        fig.savefig(path, dpi=60)
        assert path.stat().st_size > 5000, name
    # one ellipsoid per level
    levels = len(results["cocontraction"].to_dict()["levels"])
    assert len(figures["ellipsoids_levels"].axes[0].get_legend().get_texts()) == levels
    # into given axes
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots()
    assert plot.ellipses(results["planar"], ax=ax) is fig
    # the wrong kind is a clear error
    with pytest.raises(ValueError, match="stochastic"):
        plot.bode(results["linear"])


def test_without_matplotlib_a_plot_says_how_to_get_it(results, monkeypatch):
    from limpid import plot

    monkeypatch.setitem(sys.modules, "matplotlib.pyplot", None)
    with pytest.raises(ImportError, match=r"pip install"):
        plot.sweep(results["window_sweep"])


def test_the_module_shows_its_api_only():
    names = dir(limpid)
    for inner in ("np", "json", "os", "Any", "Dict", "copy", "warnings"):
        assert inner not in names
    assert "plot" in names and "estimate_linear" in names
    assert set(limpid.__all__) == set(names)
    # the plot module too, and the installed version (issue 63, item 6)
    assert dir(limpid.plot) == sorted(limpid.plot.__all__)
    from importlib.metadata import version

    assert limpid.__version__ == version("limpid") and limpid.__version__[0].isdigit()


def test_a_result_shows_its_conversions_beside_its_fields(results):
    names = dir(results["linear"])
    for method in ("to_pandas", "to_dict", "to_xarray", "keys"):
        assert method in names
    assert "stiffness" in names and "_data" not in names


def test_the_tutorial_notebook_executes(tmp_path):
    nbformat = pytest.importorskip("nbformat")
    nbclient = pytest.importorskip("nbclient")
    path = REPO / "docs" / "notebooks" / "tutorial.ipynb"
    nb = nbformat.read(path, as_version=4)
    # its outputs are not committed
    assert all(not c.get("outputs") for c in nb.cells if c.cell_type == "code")
    client = nbclient.NotebookClient(nb, timeout=600, kernel_name="python3",
                                     resources={"metadata": {"path": str(tmp_path)}})
    client.execute()
    shown = "".join(
        o.get("data", {}).get("text/html", "") for c in nb.cells if c.cell_type == "code" for o in c.outputs
    )
    assert "limpid-result" in shown, "the tutorial shows at least one result table"
    errors = [o for c in nb.cells if c.cell_type == "code" for o in c.outputs if o.output_type == "error"]
    assert not errors


def test_a_sweeps_change_and_tissue_in_series_are_said_in_its_table(results):
    """Issue 37: the sweep's change (and, when a compliance in series explains
    it, the tissue) is said under the table, not only in each row's reasons."""
    d = results["window_sweep"].to_dict()
    assert "changes within the trials" not in results["window_sweep"]._repr_html_()
    d["impedance_change"] = {"onset_ms": 90.0, "significant_from_ms": 70.0, "stiffness_change": 0.35,
                             "damping_change": 0.2, "p_value": 1e-6, "z": 4.75}
    html = limpid.Result.from_dict(d)._repr_html_()
    assert "significantly from 70 ms" in html and "K by 35 %" in html and "not a reflex" not in html
    d["series_compliance"] = {"compliance": [[0.002, 0.0], [0.0, 0.001]], "time_constant_s": 0.01,
                              "residual_ratio": 88.0}
    html = limpid.Result.from_dict(d)._repr_html_()
    assert "88 times better" in html and "not a reflex" in html
