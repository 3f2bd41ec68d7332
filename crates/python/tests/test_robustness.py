"""Issue 56 through the Python package: values that crashed the interpreter,
were silently misread, or overwrote an input are refused with a ValueError
naming what is wrong."""
import json
import math

import numpy as np
import pytest

import limpid
from conftest import examples

CUBIC = examples("cartesian_slow") / "ex_cubic.csv"


def test_a_map_dict_that_contains_itself_or_nests_deeply_is_refused():
    cyclic = {"columns": {"t": "t"}}
    cyclic["columns"]["x"] = cyclic
    with pytest.raises(ValueError, match="nested deeper than"):
        limpid.read_recording(CUBIC, map=cyclic)
    deep = {"columns": {"t": "t"}}
    inner = deep
    for _ in range(200_000):
        inner["x"] = {}
        inner = inner["x"]
    with pytest.raises(ValueError, match="nested deeper than"):
        limpid.read_recording(CUBIC, map=deep)
    # a list that contains itself, inside options
    loop = []
    loop.append(loop)
    with pytest.raises(ValueError, match="nested deeper than"):
        limpid.estimate_linear(CUBIC, level=loop)


def test_non_finite_options_are_refused_by_request_as_by_the_estimators():
    with pytest.raises(ValueError, match="window_ms"):
        limpid.request("planar", link_lengths=(0.32, 0.31), window_ms=math.inf)
    with pytest.raises(ValueError, match="step_ms"):
        limpid.request("window_sweep", link_lengths=(0.32, 0.31), step_ms=math.inf)
    with pytest.raises(ValueError, match="tolerance"):
        limpid.request("cocontraction", tolerance=math.inf)
    assert limpid.request("planar", link_lengths=(0.32, 0.31), window_ms=200.0)["window_ms"] == 200.0


def test_masked_arrays_are_refused_unless_nothing_is_masked():
    rec = limpid.read_recording(CUBIC)
    data = {k: np.asarray(v) for k, v in rec.items()}
    masked = dict(data)
    masked["x"] = np.ma.masked_array(data["x"], mask=np.arange(len(data["x"])) == 10)
    with pytest.raises(ValueError, match="masked array with 1 masked value"):
        limpid.estimate_linear(masked)
    unmasked = dict(data)
    unmasked["x"] = np.ma.masked_array(data["x"], mask=False)
    a = limpid.estimate_linear(unmasked).to_dict()
    b = limpid.estimate_linear(data).to_dict()
    assert a["stiffness"] == b["stiffness"]
    with pytest.raises(ValueError, match="masked"):
        limpid.psd(np.ma.masked_invalid([1.0, np.nan, 2.0] * 100), fs=100.0)


def test_a_ragged_result_displays_why_instead_of_raising():
    r = limpid.estimate_linear(CUBIC).to_dict()
    r["stiffness"] = [[1.0]]
    ragged = limpid.Result(r)
    html = ragged._repr_html_()
    assert "cannot be shown" in html and "do not agree" in html
    assert repr(ragged).startswith("limpid.Result(")


def test_an_ellipsoid_of_nan_says_so():
    with pytest.raises(ValueError, match="NaN or infinite"):
        limpid.ellipsoid([[math.nan] * 3] * 3)
    with pytest.raises(ValueError, match="found 4 x 4"):
        limpid.ellipsoid(np.eye(4))


def test_a_report_over_its_own_recording_is_refused(tmp_path):
    rec = tmp_path / "rec.csv"
    rec.write_bytes(CUBIC.read_bytes())
    r = limpid.estimate_linear(rec)
    with pytest.raises(ValueError, match="would replace the input"):
        limpid.report([r], rec)
    assert rec.read_bytes() == CUBIC.read_bytes()
    limpid.report([r], tmp_path / "r.html")
    assert (tmp_path / "r.html").stat().st_size > 1000


def test_a_mat_v73_field_declared_larger_than_stored_is_refused_before_decoding(tmp_path):
    h5py = pytest.importorskip("h5py")
    path = tmp_path / "huge.mat"
    with h5py.File(path, "w", userblock_size=512) as f:
        rec = f.create_group("rec")
        rec.attrs["MATLAB_class"] = np.bytes_("struct")
        # 2^28 doubles (2 GiB) declared, no chunk ever written: HDF5 fills them
        d = rec.create_dataset("x", shape=(1, 2**28), dtype="f8", chunks=(1, 2**16))
        d.attrs["MATLAB_class"] = np.bytes_("double")
        t = rec.create_dataset("t", data=np.arange(100.0).reshape(1, -1))
        t.attrs["MATLAB_class"] = np.bytes_("double")
    with open(path, "r+b") as f:
        f.write(b"MATLAB 7.3 MAT-file, Platform: GLNXA64, Created on: Mon Jan  1 00:00:00 2026 HDF5 schema 1.00 .".ljust(116))
    assert path.stat().st_size < 100_000
    with pytest.raises(ValueError, match="does not store|decodes from one MAT-file"):
        limpid.inspect(path)


def test_spectra_over_whole_periods_finds_a_static_gain_and_no_distortion(tmp_path):
    # a random-odd-like excitation: odd lines of a 2 s period at 200 Hz, every third left out
    fs, period, periods = 200.0, 2.0, 8
    n = int(fs * period)
    lines = [k for k in range(1, 80, 2) if (k // 2) % 3 != 2]
    t = np.arange(n * (periods + 1)) / fs
    rng = np.random.default_rng(4)
    phases = rng.uniform(0, 2 * np.pi, len(lines))
    u = sum(np.cos(2 * np.pi * k * t / period + p) for k, p in zip(lines, phases))
    y = 3.0 * u + 0.01 * rng.standard_normal(len(t))
    r = limpid.spectra({"t": t, "u": u, "y": y}, ["u"], ["y"], period_s=period)
    p = r.to_dict()["periodic"]
    assert p["periods"] == periods
    assert p["distortion"]["verdict"] == "linear"
    assert np.allclose(p["frf"][0]["magnitude"], 3.0, rtol=0.01)
    assert limpid.request("spectra", inputs=["u"], outputs=["y"], period_s=2.0)["period_s"] == 2.0
    with pytest.raises(ValueError, match="period_s"):
        limpid.spectra({"t": t, "u": u, "y": y}, ["u"], ["y"], period_s=2.0001)


def test_plot_periodic_draws_the_lines_and_each_pair(tmp_path):
    pytest.importorskip("matplotlib")
    import matplotlib

    matplotlib.use("Agg")
    from limpid import plot

    fs, period, periods = 200.0, 2.0, 8
    n = int(fs * period)
    lines = [k for k in range(1, 80, 2) if (k // 2) % 3 != 2]
    t = np.arange(n * (periods + 1)) / fs
    u = sum(np.cos(2 * np.pi * k * t / period + 0.3 * k) for k in lines)
    y = 3.0 * u + 0.2 * u**2 + 0.01 * np.random.default_rng(1).standard_normal(len(t))
    # columns named outside the recording format: no unit limit applies
    r = limpid.spectra({"t": t, "drive": u, "response": y}, ["drive"], ["response"], period_s=period)
    drawn = plot.periodic(r)
    assert drawn.axes.shape == (2, 1)
    labels = [h.get_label() for h in drawn.ax.get_lines()]
    assert {"excited", "even detection", "noise"} <= set(labels)
    assert "nonlinear" in drawn.ax.get_title()
    # its lines and response as tables, its verdict in the display (issue 63)
    lines = r.to_pandas("lines")
    assert {"excited", "even_detection"} <= set(lines.kind)
    frf = r.to_pandas("frf")
    assert len(frf) == sum(len(p["frequency_hz"]) for p in r.to_dict()["periodic"]["frf"])
    assert "Periodic analysis: 8 periods" in r._repr_html_()
    # a spectra result's coherences have a plot too
    assert plot.coherence(r).axes.shape == (1, 1)
    with pytest.raises(ValueError, match="no periodic analysis"):
        plot.periodic(limpid.spectra({"t": t, "drive": u, "response": y}, ["drive"], ["response"]))


def test_a_periodic_end_point_recording_gives_a_stochastic_estimate_over_whole_periods():
    """Issue 59: the end-point multisine preset simulated, estimated with
    period_s, the periodic block drawn from the stochastic result."""
    pytest.importorskip("matplotlib")
    import matplotlib

    matplotlib.use("Agg")
    from limpid import plot

    ((columns, truth),) = limpid.simulate("endpoint-multisine", seed=2)
    assert {"x", "fx", "period"} <= set(columns) and "ux" not in columns
    assert truth["method"] == "periodic"
    r = limpid.estimate_stochastic(columns, period_s=20.0, band_hz=[0.2, 6.0])
    d = r.to_dict()
    assert d["inputs"] == ["x", "y", "z"]
    assert d["periodic"]["distortion"]["verdict"] == "linear"
    k, se = np.asarray(d["stiffness"]), np.asarray(d["standard_errors"]["stiffness"])
    assert np.all(np.abs(k - np.asarray(truth["stiffness"])) < 4 * se)
    assert plot.periodic(r).axes.shape == (1 + 9, 1)


def test_the_thread_count_is_the_callers_and_changes_no_number():
    """Issue 57: a caller-chosen pool size; the estimate is the same on one
    thread as on one a core (the reductions are ordered)."""
    default = limpid.estimate_linear(CUBIC)
    try:
        limpid.set_threads(1)
        one = limpid.estimate_linear(CUBIC)
    finally:
        limpid.set_threads(None)
    np.testing.assert_allclose(one.stiffness, default.stiffness, rtol=1e-12, atol=0)
    np.testing.assert_allclose(one.damping, default.damping, rtol=1e-12, atol=0)
    with pytest.raises(ValueError, match="at least 1"):
        limpid.set_threads(0)
    with pytest.raises(ValueError, match="set_threads: expected an int or None"):
        limpid.set_threads(2.5)


def test_thread_counts_beyond_any_machine_are_refused():
    """Issue 76: set_threads(10**6) started a minute of threads, 2**63 was taken."""
    for n in (10**6, 2**63):
        with pytest.raises(ValueError, match="at most 1024"):
            limpid.set_threads(n)
    limpid.set_threads(None)


def test_a_design_duration_is_a_number_and_an_edited_design_names_its_field():
    """Issue 76: design(..., "10") took text for a duration; a design whose
    pooled list was shortened raised IndexError from to_pandas."""
    with pytest.raises(ValueError, match="duration_s: expected a number"):
        limpid.design("demo:S1", "10", limits_from="artemiadis-3d")
    _, r = limpid.design("demo:S1", 60.0, limits_from="artemiadis-3d", runs=3)
    d = r.to_dict()
    assert len(r.to_pandas()) == 3  # K, B, M of the design (no baseline given)
    d["predicted"]["pooled"]["se"] = d["predicted"]["pooled"]["se"][:1]
    with pytest.raises(ValueError, match="length"):
        limpid.Result.from_dict(d)


def test_a_2d_plot_on_3d_axes_names_the_axes_it_wants():
    """Issue 76: plot.coherence(ax=<3-D axes>) raised matplotlib's own error."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from limpid import plot

    t = np.arange(4096) / 100.0
    rng = np.random.default_rng(3)
    u = rng.standard_normal(t.size)
    y = np.convolve(u, [0.5, 0.3, 0.1], mode="same") + 0.1 * rng.standard_normal(t.size)
    r = limpid.spectra({"t": t, "u": u, "y": y}, ["u"], ["y"], nperseg=256)
    fig = plt.figure()
    ax3 = fig.add_subplot(projection="3d")
    with pytest.raises(ValueError, match="2-D Axes"):
        plot.coherence(r, ax=np.array([[ax3]]))
    plt.close(fig)
