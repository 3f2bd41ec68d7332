"""Issue 39: results in a notebook. Each kind displays as a readable table
(value ± SE rounded by the library's rule, units, verdicts, warnings),
``to_pandas()`` gives back the result's own numbers exactly, every plot
runs on the examples of its kind with units on its axes, and the tutorial
notebook executes."""

import math
import pathlib
import sys

import numpy as np

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


#: Axis labels of ratios, which have no unit (coherence, a share of the peak).
UNITLESS = ("coherence of", "share of the peak", "co-contraction index")


def _labelled(drawn):
    """Every axis that shows data names its quantity and unit (a shared x
    axis once, under the bottom panel); ratios name their quantity only."""
    for ax in drawn.figure.axes:
        if not ax.has_data():
            continue
        x = ax.get_xlabel() or next(
            (o.get_xlabel() for o in ax.get_shared_x_axes().get_siblings(ax) if o.get_xlabel()), "")
        labels = [x, ax.get_ylabel()] + ([ax.get_zlabel()] if hasattr(ax, "get_zlabel") else [])
        for label in labels:
            if label.startswith(UNITLESS):
                assert "(1)" not in label and "(" not in label, label
                continue
            assert label and "(" in label and label.endswith(")"), (ax.get_title(), labels)


def _inside(drawn, name):
    """No text leaves the figure (issue 81: plot.reflex cut its own y-label to "ntrinsic IRF"):
    each Axes' tight box (the tick labels drawn, axis labels, title, legend) lies in the figure."""
    figure = drawn.figure
    if any(hasattr(ax, "get_zlim") for ax in figure.axes):
        return  # a 3-D Axes' tick texts report extents in their own projection
    figure.canvas.draw()
    renderer = figure.canvas.get_renderer()
    box = figure.bbox
    for ax in figure.axes:
        b = ax.get_tightbbox(renderer)
        assert b.x0 >= box.x0 - 1 and b.y0 >= box.y0 - 1 and b.x1 <= box.x1 + 1 and b.y1 <= box.y1 + 1, \
            (name, ax.get_title(), ax.get_ylabel(), b, box.bounds)


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
        _inside(fig, name)
        path = tmp_path / f"{name}.png"
        fig.savefig(path, dpi=60)
        assert path.stat().st_size > 5000, name
    # one ellipsoid per level
    levels = len(results["cocontraction"].to_dict()["levels"])
    assert len(figures["ellipsoids_levels"].ax.get_legend().get_texts()) == levels
    # into given axes
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots()
    drawn = plot.ellipses(results["planar"], ax=ax)
    assert drawn.figure is fig and drawn.ax is ax
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


def _plain_tick_labels(drawn):
    """Log axes read as plain numbers: no "10^" or "×10" in any tick label."""
    drawn.figure.canvas.draw()
    for ax in drawn.figure.axes:
        for axis in (ax.xaxis, ax.yaxis):
            if axis.get_scale() == "log":
                for t in axis.get_ticklabels(which="both"):
                    assert "10^" not in t.get_text() and "×" not in t.get_text() and "\\times" not in t.get_text(), \
                        t.get_text()


# (function, result kind, panels: rows, cols); the one ax= convention, issue 63 item 5
PLOTS = [("ellipsoids", "linear", 1, 1), ("ellipses", "planar", 1, 1), ("fit", "linear", 3, 1),
         ("fit", "reflex", 1, 1), ("bode", "stochastic", 6, 3), ("coherence", "stochastic", 6, 1),
         ("sweep", "window_sweep", 2, 1), ("reflex", "reflex", 1, 4), ("varying", "varying", 1, 3),
         ("study", "study", 1, 3)]


@pytest.mark.parametrize("name,kind,rows,cols", PLOTS)
def test_every_plot_takes_ax_as_one_axes_or_a_grid_of_its_shape(results, name, kind, rows, cols):
    import matplotlib.pyplot as plt
    from limpid import plot

    draw = getattr(plot, name)
    import inspect

    params = inspect.signature(draw).parameters
    assert "ax" in params and "axes" not in params
    r = results[kind]
    new = draw(r)
    assert new.axes.shape == (rows, cols) and new.figure is new.ax.figure
    _labelled(new)
    _plain_tick_labels(new)
    kw = {"projection": "3d"} if name == "ellipsoids" else {}
    fig, given = plt.subplots(rows, cols, squeeze=False, subplot_kw=kw)
    target = given[0, 0] if rows * cols == 1 else given
    drawn = draw(r, ax=target)
    assert drawn.figure is fig and drawn.axes.shape == (rows, cols)
    assert all(a is b for a, b in zip(drawn.axes.flat, given.flat))
    assert all(a.has_data() for a in drawn.axes.flat)
    # the wrong shape says which one is wanted
    fig, wrong = plt.subplots(rows + 1, cols, squeeze=False, subplot_kw=kw)
    with pytest.raises(ValueError, match=rf"{rows} x {cols} panels: ax= takes"):
        draw(r, ax=wrong)
    if rows * cols > 1:
        with pytest.raises(ValueError, match="got one Axes"):
            draw(r, ax=wrong[0, 0])
    plt.close("all")


def test_the_measured_phase_is_drawn_on_the_fits_branch(results):
    # issue 63, item 1: where the estimate agrees with its fit, the drawn phases agree too
    from limpid import plot

    drawn = plot.bode(results["stochastic"])
    n = drawn.axes.shape[1]
    compared = 0
    for i in range(n):
        for j in range(n):
            mag, ph = drawn.axes[2 * i, j], drawn.axes[2 * i + 1, j]
            zm, fm = (np.asarray(line.get_ydata()) for line in mag.get_lines()[:2])
            zp, fp = (np.asarray(line.get_ydata()) for line in ph.get_lines()[:2])
            # within 10 % as complex numbers: the phases are then within 6° on one branch
            z, fit = zm * np.exp(1j * np.radians(zp)), fm * np.exp(1j * np.radians(fp))
            close = np.abs(z / fit - 1) < 0.1
            assert np.all(np.abs(zp - fp)[close] < 10.0), (i, j, np.abs(zp - fp)[close].max())
            compared += int(close.sum())
            if i == j:
                # the well-measured diagonal: equal magnitudes mean equal phases
                agree = np.abs(zm / fm - 1) < 0.1
                assert np.all(np.abs(zp - fp)[agree] < 10.0), (i, np.abs(zp - fp)[agree].max())
    assert compared > 50
    # the same phases, mod 360°, as the result's own impedance
    d = results["stochastic"].to_dict()
    f = np.asarray(d["frequencies"])
    z = np.asarray(d["impedance"])[f > 0, 0, 1]
    drawn_phase = drawn.axes[1, 1].get_lines()[0].get_ydata()
    wrapped = (np.asarray(drawn_phase) - np.degrees(np.arctan2(z[:, 1], z[:, 0])) + 180) % 360 - 180
    assert np.allclose(wrapped, 0, atol=1e-9)


def test_a_part_of_a_result_shows_its_fields_with_units(results):
    # issue 63, item 4: r.fit, r.standard_errors, r.criteria display what they hold
    import pickle

    lin = results["linear"]
    fit = repr(lin.fit)
    assert fit.startswith("limpid.Result(fit of a linear result") and "vaf = " in fit and " %" in fit
    se = lin.standard_errors._repr_html_()
    assert se.count("<table") == 3 and "stiffness (N/m)" in se and "damping (N s/m)" in se
    d = lin.to_dict()
    assert f"{d['standard_errors']['stiffness'][0][0]:.4g}" in se
    verdicts = repr(lin.criteria.verdicts)
    assert "criteria.verdicts of a linear result" in verdicts and "stiffness = trusted" in verdicts
    assert "trusted N/m" not in verdicts  # words carry no unit
    crit = lin.criteria._repr_html_()
    assert "condition number" in crit and "kind='?'" not in crit
    # mixed coordinates: a unit per element
    sto = results["stochastic"].standard_errors._repr_html_()
    assert "N/rad" in sto and "N m/m" in sto
    # the reflex result's own units reach its parts
    ref = repr(results["reflex"].intrinsic)
    assert "stiffness = " in ref and "N m/rad" in ref
    # a part pickles with where it came from
    back = pickle.loads(pickle.dumps(lin.fit))
    assert repr(back) == fit and back.to_dict() == d["fit"]


def test_a_result_shows_what_it_was_made_from_collapsed(results):
    # issue 63, item 9: recording, samples, rate, duration, options used
    html = results["linear"]._repr_html_()
    assert "<details><summary>made from ex_cubic.csv," in html
    run = results["linear"].to_dict()["run"]
    f = run["inputs"][0]
    assert f["samples"] > 1000 and f["sample_rate_hz"] == pytest.approx(500.0)
    assert f["duration_s"] == pytest.approx(f["samples"] / f["sample_rate_hz"])
    assert f"{f['samples']} samples at 500 Hz" in html
    assert "Options used" in html and "prepare.order" in html
    # arrays have no file: said so
    rec = limpid.read_recording(examples("ankle") / "ex_ankle.csv")
    arrays = limpid.estimate_reflex(rec)._repr_html_()
    assert "made from &lt;arrays&gt;" in arrays and "samples at 1000 Hz" in arrays


def test_every_result_over_an_axis_becomes_an_xarray_with_units(results):
    # issue 63, item 3: a sweep over the window, spectra over frequency, Z(f) with a unit on f
    xr = pytest.importorskip("xarray")
    sw = results["window_sweep"]
    ds = sw.to_xarray()
    rows = sw.to_dict()["rows"]
    assert isinstance(ds, xr.Dataset) and ds.sizes["window"] == len(rows)
    assert ds["window"].attrs["units"] == "ms" and ds["stiffness"].attrs["units"] == "N m/rad"
    assert float(ds["stiffness"][3, 0, 1]) == rows[3]["estimate"]["stiffness"][0][1]
    assert list(ds["trusted"].values) == [r["trusted"] for r in rows]
    z = results["stochastic"].to_xarray()
    assert z["frequency"].attrs["units"] == "Hz"
    t = np.arange(4000) / 200.0
    u = np.random.default_rng(1).standard_normal(4000)
    sp = limpid.spectra({"t": t, "drive": u, "response": 2 * u}, ["drive"], ["response"])
    dsp = sp.to_xarray()
    assert dsp["coherence"].attrs["units"] == "1" and dsp["frequency"].attrs["units"] == "Hz"
    assert float(dsp["psd"].sel(signal="response")[10]) == pytest.approx(4 * float(dsp["psd"].sel(signal="drive")[10]))
    with pytest.raises(ValueError, match="frequency, schedule or window"):
        results["linear"].to_xarray()
