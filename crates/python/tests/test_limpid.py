"""limpid's Python package against scipy.signal, numpy.linalg.lstsq and the
truth files of the examples limpid's lab makes (issue 8)."""

import json
import os
import pathlib

import numpy as np
import pytest
import scipy.signal as ss

import limpid

from conftest import examples, real_data
RNG = np.random.default_rng(20261123)


def rel(a, b):
    a, b = np.asarray(a, float), np.asarray(b, float)
    return np.linalg.norm(a - b) / np.linalg.norm(b)


@pytest.mark.parametrize("nperseg,noverlap,window,detrend,scaling", [
    (None, None, "hann", "constant", "density"),
    (512, 384, "hamming", "linear", "spectrum"),
    (300, 0, "boxcar", False, "density"),
])
def test_psd_csd_coherence_match_scipy(nperseg, noverlap, window, detrend, scaling):
    n = 10_000
    x = RNG.standard_normal(n)
    y = np.convolve(x, [0.5, 0.3, -0.2], mode="same") + 0.3 * RNG.standard_normal(n)
    kw = dict(fs=250.0, window=window, nperseg=nperseg, noverlap=noverlap, detrend=detrend)
    f, p = limpid.psd(x, scaling=scaling, **kw)
    fs_, ps = ss.welch(x, scaling=scaling, **kw)
    np.testing.assert_allclose(f, fs_, rtol=1e-12)
    np.testing.assert_allclose(p, ps, rtol=1e-10)
    f, c = limpid.csd(x, y, scaling=scaling, **kw)
    _, cs = ss.csd(x, y, scaling=scaling, **kw)
    np.testing.assert_allclose(c, cs, rtol=1e-10, atol=1e-12 * np.abs(cs).max())
    f, h = limpid.coherence(x, y, **kw)
    _, hs = ss.coherence(x, y, **kw)
    np.testing.assert_allclose(h, hs, rtol=1e-10, atol=1e-12)


def test_short_signal_uses_its_length_as_scipy_does():
    x = RNG.standard_normal(100)
    with pytest.warns(UserWarning):
        _, ps = ss.welch(x)
    _, p = limpid.psd(x)
    np.testing.assert_allclose(p, ps, rtol=1e-10)


@pytest.mark.parametrize("order,cutoff", [(2, 10.0), (4, 30.0), (6, 45.0)])
def test_butterworth_filtfilt_matches_scipy(order, cutoff):
    fs = 500.0
    x = np.cumsum(RNG.standard_normal(3000)) + 5 * np.sin(np.arange(3000) / 30)
    y = limpid.lowpass_filtfilt(x, cutoff, fs, order)
    ys = ss.sosfiltfilt(ss.butter(order, cutoff, fs=fs, output="sos"), x)
    np.testing.assert_allclose(y, ys, rtol=1e-10, atol=1e-10 * np.abs(ys).max())


def test_linear_estimator_matches_lstsq_on_a_noiseless_system():
    fs, n = 1000.0, 20_000
    t = np.arange(n) / fs
    M = np.array([[1.5, 0.2, 0.1], [0.2, 1.2, 0.05], [0.1, 0.05, 0.9]])
    B = np.array([[20.0, 2.0, 1.0], [1.5, 15.0, 0.5], [1.0, 0.5, 25.0]])
    K = np.array([[900.0, 40.0, 30.0], [35.0, 400.0, 20.0], [30.0, 25.0, 600.0]])
    # independent phases and frequencies per axis (a common phase pattern would
    # make the three axes span only two signals)
    x = np.zeros((3, n)); v = np.zeros((3, n)); a = np.zeros((3, n))
    for i in range(3):
        for k in range(5):
            f = (0.6 + 0.9 * k) * (1.0 + 0.13 * i)
            w, ph, amp = 2 * np.pi * f, RNG.uniform(0, 2 * np.pi), 0.004 / (k + 1)
            x[i] += amp * np.sin(w * t + ph)
            v[i] += amp * w * np.cos(w * t + ph)
            a[i] -= amp * w * w * np.sin(w * t + ph)
    F = M @ a + B @ v + K @ x
    rec = {"t": t, "x": x[0], "y": x[1], "z": x[2], "fx": F[0], "fy": F[1], "fz": F[2]}
    est = limpid.estimate_linear(rec, window="continuous")
    # numpy's least squares on the exact kinematics: F^T = [a v x 1]^T P
    Y = np.vstack([a, v, x, np.ones(n)]).T
    P, *_ = np.linalg.lstsq(Y, F.T, rcond=None)
    M_ls, B_ls, K_ls = P[0:3].T, P[3:6].T, P[6:9].T
    assert rel(K_ls, K) < 1e-9 and rel(B_ls, B) < 1e-9
    assert rel(est.stiffness, K_ls) < 1e-3
    assert rel(est.damping, B_ls) < 1e-3
    assert rel(est.inertia, M_ls) < 1e-3
    # the result carries its quality, with the CLI's JSON keys
    d = est.to_dict()
    for key in ["inertia", "damping", "stiffness", "standard_errors", "symmetric", "antisymmetric",
                "ellipsoids", "table_ii", "fit", "criteria", "warnings", "provenance"]:
        assert key in d, key
    assert est.stiffness.shape == (3, 3)
    assert min(est.fit.vaf) > 99.9


def test_recovers_the_example_truths():
    case = examples("cartesian_slow") / "ex_cubic"
    truth = json.loads(case.with_suffix(".truth.json").read_text())
    est = limpid.estimate_linear(str(case.with_suffix(".csv")))
    assert rel(est.stiffness, truth["stiffness"]) < 0.03

    case = examples("planar") / "ex_joint_180"
    truth = json.loads(case.with_suffix(".truth.json").read_text())
    est = limpid.estimate_planar(case.with_suffix(".csv"), truth["link_lengths"])
    assert rel(est.stiffness, truth["stiffness"]) < 0.03
    assert est.criteria.trusted

    case = examples("stochastic") / "ex_sa3"
    truth = json.loads(case.with_suffix(".truth.json").read_text())
    # from a dict of arrays this time
    est = limpid.estimate_stochastic(limpid.read_recording(case.with_suffix(".csv")))
    assert rel(est.stiffness, truth["stiffness"]) < 0.05
    # Z(f) as complex numbers (issue 63, item 8); the dict keeps [re, im]
    assert est.impedance.shape[1:] == (3, 3) and np.iscomplexobj(est.impedance)
    assert est.impedance[5, 0, 1] == complex(*est.to_dict()["impedance"][5][0][1])

    case = examples("cocontraction") / "ex_config4"
    truth = json.loads(case.with_suffix(".truth.json").read_text())
    res = limpid.estimate_cocontraction(case.with_suffix(".csv"), str(case) + ".mvc.csv")
    assert len(res.to_dict()["levels"]) == 4


class FakeFrame:
    """The two things limpid uses of a pandas DataFrame."""

    def __init__(self, d):
        self._d = d
        self.columns = list(d)

    def __getitem__(self, k):
        class Col:
            def __init__(self, v):
                self.v = v

            def to_numpy(self, dtype=None):
                return np.asarray(self.v, dtype=dtype)
        return Col(self._d[k])


def test_dataframes_and_errors():
    rec = limpid.read_recording(examples("cartesian_slow") / "ex_cubic.csv")
    a = limpid.estimate_linear(FakeFrame(rec))
    b = limpid.estimate_linear(rec)
    np.testing.assert_array_equal(a.stiffness, b.stiffness)
    bad = dict(rec)
    del bad["fx"]
    with pytest.raises(ValueError, match="fx"):
        limpid.estimate_linear(bad)
    bad = dict(rec)
    bad["fy"] = bad["fy"][:-1]
    with pytest.raises(ValueError, match="samples"):
        limpid.estimate_linear(bad)
    with pytest.raises(OSError, match="nope.csv"):
        limpid.read_recording("nope.csv")
    with pytest.raises(ValueError, match="window"):
        limpid.psd(np.ones(1000), window="kaiser")


def test_hostile_values_are_refused_and_suspicious_ones_warned(tmp_path):
    rec = limpid.read_recording(examples("cartesian_slow") / "ex_cubic.csv")
    bad = dict(rec)
    bad["x"] = bad["x"].copy()
    bad["x"][100] = 1e307
    with pytest.raises(ValueError, match=r"row 101, column x: implausible value 1e307"):
        limpid.estimate_linear(bad)
    p = tmp_path / "ms.csv"
    p.write_text("t,x,fx\n" + "".join(f"{2 * i},0.3,1.0\n" for i in range(100)))
    with pytest.warns(UserWarning, match="milliseconds"):
        limpid.read_recording(p)


def test_virtual_lab_ellipsoid_and_report(tmp_path):
    text = limpid.protocol_preset("artemiadis-3d")
    assert "kind = \"centre-out\"" in text
    r = limpid.protocol_check(text)
    assert r.kind == "centre-out"
    fast = text.replace("centre_out_s = 3.0", "centre_out_s = 0.2")
    with pytest.raises(ValueError, match="acceleration"):
        limpid.protocol_check(fast)
    runs = limpid.simulate("artemiadis-3d", seed=3)
    assert len(runs) == 6
    cols, truth = runs[0]
    est = limpid.estimate_linear(cols)
    assert rel(est.stiffness, truth["stiffness"]) < 0.03
    e = limpid.ellipsoid(np.diag([3.0, 2.0, 1.0]))
    np.testing.assert_allclose(e.eigenvalues, [3.0, 2.0, 1.0])
    out = tmp_path / "r.html"
    limpid.report([est], out)
    html = out.read_text()
    assert "<h2>Ellipsoids</h2>" in html and "src=" not in html


def test_frequency_response_of_a_noiseless_two_input_system():
    # y1 = 2 u1 - u2 (static), y2 = u1 delayed by one sample: H known, multiple coherence 1
    n = 20_000
    u1, u2 = RNG.standard_normal(n), RNG.standard_normal(n)
    y1 = 2 * u1 - u2
    y2 = np.r_[0.0, u1[:-1]]
    f, H, mult, part = limpid.frequency_response([u1, u2], [y1, y2], fs=100.0, nperseg=256)
    assert H.shape == (len(f), 2, 2)
    np.testing.assert_allclose(H[:, 0, 0], 2.0, atol=1e-9)
    np.testing.assert_allclose(H[:, 0, 1], -1.0, atol=1e-9)
    # a one-sample delay: exp(-j w / fs), up to the edge effects of one sample per segment
    expected = np.exp(-2j * np.pi * f / 100.0)
    assert np.abs(H[:, 1, 0] - expected).max() < 0.02
    np.testing.assert_allclose(mult[:, 0], 1.0, atol=1e-9)
    assert mult[:, 1].min() > 0.98
    # with noise on y1 the multiple coherence drops as predicted: S/(S+N) = 5 / (5 + 1)
    noisy = y1 + RNG.standard_normal(n)
    _, _, mult, _ = limpid.frequency_response([u1, u2], [noisy], fs=100.0, nperseg=256)
    assert abs(np.median(mult[:, 0]) - 5 / 6) < 0.03


def test_planar_and_stochastic_simulations_estimate_back_to_their_truth():
    (cols, truth), = limpid.simulate("lakatos-planar", seed=2)
    est = limpid.estimate_planar(cols, (0.30, 0.33))
    assert rel(est.stiffness, truth["stiffness"]) < 0.03
    (cols, truth), = limpid.simulate("park-stochastic", seed=2)
    est = limpid.estimate_stochastic(cols)
    assert rel(est.stiffness, truth["stiffness"]) < 0.05


def test_simulate_with_a_subject_file_and_the_robot_controllers(tmp_path):
    subject = tmp_path / "stiff.toml"
    subject.write_text(
        "inertia = [[1.5, 0, 0], [0, 1.8, 0], [0, 0, 2.0]]\n"
        "damping = [[12.0, 1.0, 0], [1.0, 9.0, 0], [0, 0, 7.0]]\n"
        "stiffness = [[900.0, 120.0, -60.0], [120.0, 500.0, 40.0], [-60.0, 40.0, 350.0]]\n"
    )
    runs = limpid.simulate("artemiadis-3d", seed=4, subject=subject)
    cols, truth = runs[2]
    np.testing.assert_allclose(truth["stiffness"][0], [900.0, 120.0, -60.0])
    assert rel(limpid.estimate_linear(cols).stiffness, truth["stiffness"]) < 0.03
    # the same subject as TOML text
    (_, truth_text), *_ = limpid.simulate("artemiadis-3d", subject=subject.read_text())
    assert truth_text["stiffness"] == truth["stiffness"]
    # the spring array held by the PUMA-type robot under IMBIC
    (cols, truth), = limpid.simulate("park-stochastic", controller="imbic")
    assert "IMBIC" in truth["robot"]["model"]
    assert rel(limpid.estimate_stochastic(cols).stiffness, truth["stiffness"]) < 0.05
    with pytest.raises(ValueError, match="controller"):
        limpid.simulate("park-stochastic", controller="pid")
    with pytest.raises(ValueError, match=r"stiff\.toml: line 1, column 1: unknown field `springs`"):
        subject.write_text("springs = [1.0]\n")
        limpid.simulate("artemiadis-3d", subject=subject)


def test_frequency_response_says_where_the_inputs_are_singular():
    u = RNG.standard_normal(4096)
    with pytest.warns(RuntimeWarning, match="singular"):
        f, H, mult, _ = limpid.frequency_response([u, u.copy()], [u], fs=100.0, nperseg=128)
    assert np.isnan(H[1:]).all() and np.isnan(mult[1:]).all()


def test_matlab_files_read_like_their_csv():
    fixtures = pathlib.Path(__file__).resolve().parents[2] / "io" / "tests" / "fixtures"
    csv = limpid.read_recording(fixtures / "small.csv")
    mat = limpid.read_recording(fixtures / "small_v7.mat")
    assert list(mat) == list(csv)
    for name in csv:
        np.testing.assert_array_equal(mat[name], csv[name])
    with pytest.raises(ValueError, match="complex values"):
        limpid.read_recording(fixtures / "complex.mat")


def test_lab_files_read_through_a_map_given_as_a_file_or_a_dict():
    formats = pathlib.Path(__file__).resolve().parents[2] / "io" / "tests" / "fixtures" / "formats"
    expected = json.loads((formats / "rig.tdms.expected.json").read_text())
    with pytest.warns(UserWarning):
        from_file = limpid.read_recording(formats / "rig.tdms", map=formats / "rig_tdms.toml")
    as_dict = {
        "time": {"stream": "Robot"},
        "columns": {
            "x": {"channel": "EndEffX"},
            "fx": {"channel": "Force X", "scale": -1.0},
            "q2": {"channel": "Elbow", "unit": "deg", "scale": 0.01},
            "emg_biceps": {"channel": "EMG 1", "stream": "DAQ"},
        },
    }
    with pytest.warns(UserWarning):
        from_dict = limpid.read_recording(str(formats / "rig.tdms"), map=as_dict)
    for name, values in expected.items():
        np.testing.assert_allclose(from_file[name], values, rtol=1e-9, atol=1e-12)
        np.testing.assert_array_equal(from_dict[name], from_file[name])
    found = limpid.inspect(formats / "rig.xdf")
    assert [s["name"] for s in found["streams"]] == ["robot", "emg", "markers"]
    assert "EndEff.X" in found["proposed_map"]
    with pytest.raises(ValueError, match="unknown unit"):
        limpid.read_recording(formats / "rig.tdms", map={"columns": {"x": {"channel": "EndEffX", "unit": "furlong"}}})
    with pytest.raises(ValueError, match="no channel"):
        limpid.read_recording(formats / "rig.tdms", map={"time": {"stream": "Robot"}, "columns": {"x": "EndEfX"}})
    # a file beside the main one: the same map, without the columns it lacks
    only_emg = {"time": {"stream": "Robot"}, "columns": {"x": {"channel": "EndEffX", "stream": "Arm"},
                                                         "emg_biceps": {"channel": "EMG 1", "stream": "DAQ"}}}
    with pytest.warns(UserWarning, match="left out: x"):
        emg = limpid.read_recording(formats / "rig.tdms", map=only_emg, partial=True)
    assert list(emg) == ["t", "emg_biceps"] and len(emg["t"]) == 200  # on the Robot clock, which the file has


def test_window_sweep_rows_match_single_estimates():
    case = examples("planar") / "ex_joint_180"
    truth = json.loads(case.with_suffix(".truth.json").read_text())
    rec = case.with_suffix(".csv")
    sweep = limpid.window_sweep(rec, truth["link_lengths"], from_ms=50, to_ms=400, step_ms=50)
    windows = [r["observation_window_ms"] for r in sweep.to_dict()["rows"]]
    # up to the longest window the trials allow
    assert len(windows) >= 3 and np.allclose(np.diff(windows), 50.0) and windows[0] == 50.0
    last = sweep.to_dict()["rows"][-1]["estimate"]
    single = limpid.estimate_planar(rec, truth["link_lengths"], window_ms=windows[-1])
    np.testing.assert_allclose(last["stiffness"], single.stiffness, rtol=1e-12)
    assert rel(single.stiffness, truth["stiffness"]) < 0.03
    assert sweep.min_positive_definite_ms is not None and sweep.min_positive_definite_ms <= windows[-1]
    with pytest.raises(ValueError, match="from_ms"):
        limpid.window_sweep(rec, truth["link_lengths"], from_ms=0)


def _rig_readings(theta, f_limb, tau_limb, weight, centre, bias_f, bias_t):
    """Sensor readings of seed 004's rig turned by theta about y (sensor frame)."""
    out = []
    for th, f, tau in zip(theta, f_limb, tau_limb):
        c, s = np.cos(th), np.sin(th)
        r = np.array([[c, 0, s], [0, 1, 0], [-s, 0, c]])
        g = r.T @ weight
        out.append(np.r_[g - r.T @ f + bias_f, np.cross(centre, g) - r.T @ tau + bias_t])
    out = np.array(out)
    names = ["sensor_fx", "sensor_fy", "sensor_fz", "sensor_tx", "sensor_ty", "sensor_tz"]
    return {n: out[:, i] for i, n in enumerate(names)}


def test_gravity_compensation_from_still_poses():
    weight, centre = np.array([0.0, 0.0, -6.0]), np.array([0.01, 0.0, 0.05])
    bias_f, bias_t = np.array([0.2, -0.1, 0.4]), np.array([0.03, -0.05, 0.02])
    still = np.repeat([-0.3, -0.1, 0.0, 0.15, 0.3], 20)
    zeros = np.zeros((len(still), 3))
    cal = {"t": np.arange(len(still)) / 1000.0, "theta": still,
           **_rig_readings(still, zeros, zeros, weight, centre, bias_f, bias_t)}
    t = np.arange(3000) / 1000.0
    theta = 0.1 * np.sin(3 * t)
    f_limb = np.c_[2 * np.sin(5 * t), np.zeros_like(t), -np.cos(7 * t)]
    tau_limb = np.c_[np.zeros_like(t), 0.5 * np.sin(4 * t), np.zeros_like(t)]
    rec = {"t": t, "theta": theta, **_rig_readings(theta, f_limb, tau_limb, weight, centre, bias_f, bias_t)}
    cols, summary = limpid.gravity_compensate(rec, calibration=cal)
    np.testing.assert_allclose(np.c_[cols["fx"], cols["fy"], cols["fz"]], f_limb, atol=1e-9)
    np.testing.assert_allclose(np.c_[cols["taux"], cols["tauy"], cols["tauz"]], tau_limb, atol=1e-9)
    assert any("centre of mass" in line for line in summary)
    with pytest.raises(ValueError, match="exactly one"):
        limpid.gravity_compensate(rec, bias=cal, calibration=cal)


def test_reflex_on_the_real_ankle_recording():
    real = real_data("reklab_ankle") / "pf.csv"
    est = limpid.estimate_reflex(real)
    d = est.to_dict()
    assert d["kind"] == "reflex"
    assert 85.0 < d["fit"]["vaf_total"] < 97.0
    assert 0.035 < d["reflex"]["delay_s"] < 0.065
    assert d["intrinsic"]["stiffness"] < d["reflex_free"]["parameters"]["stiffness"]


def test_five_real_ankles_table_carries_verdicts_and_nan_for_what_is_not_identifiable():
    """Issue 81, item 1: a five-recording table must not average a 0 s delay
    nobody identified, and df2's gain (about 5 +- 3) is not distinguishable from zero."""
    pd = pytest.importorskip("pandas")
    folder = real_data("reklab_ankle")
    rows = []
    for name in ("df", "df2", "df3", "pf", "pf2"):
        t = limpid.estimate_reflex(folder / f"{name}.csv").to_pandas()
        t["recording"] = name
        rows.append(t)
    table = pd.concat(rows).set_index(["recording", "quantity"])
    judged = table.drop(index="reflex_free_stiffness", level="quantity")
    assert judged["verdict"].notna().all(), judged[judged["verdict"].isna()]
    for name in ("df", "df2", "df3"):
        delay = table.loc[(name, "reflex_delay")]
        assert delay["verdict"] == "not_identifiable"
        assert np.isnan(delay["value"]) and np.isnan(delay["se"])
        assert np.isnan(table.loc[(name, "reflex_natural_frequency_hz"), "value"])
    assert table.loc[("df2", "reflex_gain"), "verdict"] == "not_distinguishable_from_zero"
    assert table.loc[("pf", "reflex_gain"), "verdict"] in ("trusted", "imprecise")
    # the mean delay over the five takes only the identified ones, if any
    delays = table.xs("reflex_delay", level="quantity")["value"]
    assert delays.notna().sum() <= 2
    k = table.xs("intrinsic_stiffness", level="quantity")
    assert (k["value"] > 2 * k["se"]).all()


def _lab_ankle(tmp_path):
    """The ankle PRBS recording with a lab's own column names, as CSV and as a MAT struct."""
    cols, _ = limpid.simulate("ankle-prbs")[0]
    lab = {"time_s": cols["t"], "angle_rad": cols["q1"], "torque_Nm": cols["tau1"]}
    csv = tmp_path / "lab.csv"
    np.savetxt(csv, np.c_[lab["time_s"], lab["angle_rad"], lab["torque_Nm"]], delimiter=",",
               header="time_s,angle_rad,torque_Nm", comments="")
    return csv, lab


def test_every_estimator_reads_a_lab_s_own_names_by_keyword(tmp_path):
    """Issue 81, item 2: map= and columns= wherever a recording is read, and a
    missing column's error that names the keyword."""
    csv, lab = _lab_ankle(tmp_path)
    with pytest.raises(ValueError, match=r"missing required column t .*columns=\{'t': 'time_s'\}"):
        limpid.estimate_reflex(csv, position="angle_rad", torque="torque_Nm")
    named = limpid.estimate_reflex(csv, columns={"t": "time_s"}, position="angle_rad", torque="torque_Nm")
    assert abs(named.intrinsic.stiffness - 80.0) < 4.0
    assert named.to_dict()["run"]["columns"] == {"t": "time_s"}
    mapped = limpid.estimate_reflex(csv, map={"columns": {"t": "time_s", "q1": "angle_rad", "tau1": "torque_Nm"}})
    assert mapped.intrinsic.stiffness == named.intrinsic.stiffness
    # inspect's proposed map, used as it is
    proposed = limpid.inspect(csv)["proposed_map"]
    (tmp_path / "rig.toml").write_text(proposed)
    again = limpid.estimate_reflex(csv, map=tmp_path / "rig.toml")
    assert again.intrinsic.stiffness == named.intrinsic.stiffness
    rec = limpid.read_recording(csv, columns={"t": "time_s"})
    assert set(rec) == {"t", "angle_rad", "torque_Nm"}
    with pytest.raises(ValueError, match="columns is a dict"):
        limpid.estimate_reflex(csv, columns=["t=time_s"])
    # a MAT struct whose fields carry the format's names is read as it is
    sio = pytest.importorskip("scipy.io")
    mat = tmp_path / "rec.mat"
    sio.savemat(mat, {"rec": {"t": lab["time_s"], "q1": lab["angle_rad"], "tau1": lab["torque_Nm"]}})
    assert limpid.estimate_reflex(mat).intrinsic.stiffness == named.intrinsic.stiffness
    sio.savemat(mat, {"rec": lab})
    with pytest.raises(ValueError, match=r"struct fields .*--column t=rec.time_s"):
        limpid.estimate_reflex(mat)
    fields = {"t": "rec.time_s", "q1": "rec.angle_rad", "tau1": "rec.torque_Nm"}
    assert limpid.estimate_reflex(mat, columns=fields).intrinsic.stiffness == named.intrinsic.stiffness
    # two structs with the format's names: which one is the user's to say
    both = {"t": lab["time_s"], "q1": lab["angle_rad"], "tau1": lab["torque_Nm"]}
    sio.savemat(mat, {"a": both, "b": both})
    with pytest.raises(ValueError, match=r"fields a.t and b.t could both be column t"):
        limpid.estimate_reflex(mat)
    fields = {"t": "b.t", "q1": "b.q1", "tau1": "b.tau1"}
    assert limpid.estimate_reflex(mat, columns=fields).intrinsic.stiffness == named.intrinsic.stiffness


def test_a_text_column_is_named_with_its_row():
    rec = FakeFrame({"t": np.arange(4) / 100, "x": [0.0, 0.1, "slip", 0.2], "fx": np.zeros(4)})
    with pytest.raises(ValueError, match=r"column x, row 3: expected a number, found 'slip'"):
        limpid.estimate_linear(rec)


def _hand(angles_rad, upper=0.3, fore=0.35, elbow_rad=np.pi / 2):
    """The arm model of limpid's shoulder (R = Ry(-flexion) Rx(-abduction) Rz(rotation)),
    written again here from its documented definition."""
    f, a, r = angles_rad

    def rot(axis, t):
        c, s = np.cos(t), np.sin(t)
        return {"x": np.array([[1, 0, 0], [0, c, -s], [0, s, c]]),
                "y": np.array([[c, 0, s], [0, 1, 0], [-s, 0, c]]),
                "z": np.array([[c, -s, 0], [s, c, 0], [0, 0, 1]])}[axis]

    arm = np.array([0, 0, -upper]) + fore * np.array([np.sin(elbow_rad), 0, -np.cos(elbow_rad)])
    return rot("y", -f) @ rot("x", -a) @ rot("z", r) @ arm


def test_stochastic_in_the_shoulders_joint_space_matches_the_mapped_truth():
    case = examples("stochastic") / "ex_sa3"
    truth = json.loads(case.with_suffix(".truth.json").read_text())
    est = limpid.estimate_stochastic(case.with_suffix(".csv"), shoulder=(0.3, 0.35, 90, 30, 45, 0))
    assert est.to_dict()["coordinates"] == ["q1", "q2", "q3"]
    # J = diag(J_h, 1), J_h = d(X, Z)/d(flexion, abduction) by central differences
    q0 = np.radians([30.0, 45.0, 0.0])
    jh = np.zeros((2, 2))
    for c in range(2):
        dq = np.zeros(3)
        dq[c] = 1e-6
        d = (_hand(q0 + dq) - _hand(q0 - dq)) / 2e-6
        jh[:, c] = d[[0, 2]]
    j = np.eye(3)
    j[:2, :2] = jh
    expected = j.T @ np.array(truth["stiffness"]) @ j
    assert rel(est.stiffness, expected) < 0.05


def test_stochastic_shoulder_needs_six_numbers_and_a_usable_posture():
    path = examples("stochastic") / "ex_sa3.csv"
    with pytest.raises(ValueError, match="expected 6 numbers"):
        limpid.estimate_stochastic(path, shoulder=(0.3, 0.35, 90, 30, 45))
    with pytest.raises(ValueError, match="do not determine the two angles"):
        limpid.estimate_stochastic(path, shoulder=(0.3, 0.35, 90, 30, 0, 0))


def test_varying_impedance_from_a_simulated_ramp_and_hold_ankle():
    (cols, truth), = limpid.simulate("ankle-ramp-and-hold", seed=3)
    assert truth["method"] == "varying" and truth["schedule"] == "sv"
    est = limpid.estimate_varying(cols, schedule="sv", reflex=True, grid_points=7).to_dict()
    assert est["kind"] == "varying" and est["schedule"]["name"] == "sv"
    assert len(est["schedule"]["values"]) == len(est["points"]) == 7
    # the truth's quadratic K(sv), evaluated at the result's grid
    sv = np.array([p["sigma"] for p in truth["points"]])
    k_true = np.array([p["stiffness"][0][0] for p in truth["points"]])
    for p in est["points"]:
        assert p["identifiable"]
        k = p["stiffness"][0][0]
        assert abs(k - np.interp(p["sigma"], sv, k_true)) < 0.05 * k
    assert est["reflex"]["detected"] and abs(est["reflex"]["delay_s"] - truth["reflex_delay_s"]) < 0.005


def test_varying_ensemble_marks_instants_without_support():
    (cols, _), = limpid.simulate("kind = 'ensemble'\nrepetitions = 5\n", seed=2)
    est = limpid.estimate_varying(cols).to_dict()
    assert all(not p["identifiable"] and p["stiffness"] is None for p in est["points"])
    with pytest.raises(ValueError, match="trial"):
        limpid.estimate_varying({"t": np.arange(2000) / 1000, "q1": np.zeros(2000), "tau1": np.zeros(2000)})


def test_spectra_of_named_columns_give_the_analytic_coherences():
    # y = 2 u1 - u2 + e, all of unit variance: the inputs explain S/(S+N) = 5/6 of y
    # (multiple coherence); u1 alone 4/6, u2 alone 1/6 (ordinary); u1 with u2 removed
    # 4/5, u2 with u1 removed 1/2 (partial)
    n = 60_000
    u1, u2, e = (RNG.standard_normal(n) for _ in range(3))
    cols = {"t": np.arange(n) / 100.0, "u1": u1, "u2": u2, "y": 2 * u1 - u2 + e}
    r = limpid.spectra(cols, ["u1", "u2"], ["y"], nperseg=256)
    d = r.to_dict()
    assert d["kind"] == "spectra" and d["segment_samples"] == 256
    assert d["run"]["request"] == limpid.request("spectra", inputs=["u1", "u2"], outputs=["y"], nperseg=256)
    med = lambda v: float(np.median([x for x in v[1:] if x is not None]))  # noqa: E731
    assert abs(med(d["multiple_coherence"][0]) - 5 / 6) < 0.03
    assert abs(med(d["coherence"][0][0]) - 4 / 6) < 0.03
    assert abs(med(d["coherence"][0][1]) - 1 / 6) < 0.03
    assert abs(med(d["partial_coherence"][0][0]) - 4 / 5) < 0.03
    assert abs(med(d["partial_coherence"][0][1]) - 1 / 2) < 0.03
    # the PSD of u1 (unit variance, 100 Hz) is 2 / 100 per Hz one-sided
    assert abs(med(d["psd"][0]) - 0.02) < 0.002
    assert "inputs u1, u2; outputs y" in repr(r)
    assert "Multiple coherence" in r._repr_html_()
    pd = pytest.importorskip("pandas")
    psd = r.to_pandas("psd")
    assert len(psd) == 3 * 129 and set(psd["signal"]) == {"u1", "u2", "y"}
    coh = r.to_pandas("coherence")
    assert list(coh.columns[-3:]) == ["coherence", "multiple", "partial"]
    assert isinstance(coh, pd.DataFrame) and len(coh) == 2 * 129
    with pytest.raises(ValueError, match="'psd' and 'coherence'"):
        r.to_pandas()
    with pytest.raises(ValueError, match="column names"):
        limpid.spectra(cols, "u1", ["y"])
    with pytest.raises(ValueError, match="named twice"):
        limpid.spectra(cols, ["u1", "u1"], ["y"])


def test_design_for_the_demo_subject_beats_the_seed_protocol_and_plots(tmp_path):
    toml_text, r = limpid.design("demo:S1", 147.2, limits_from="artemiadis-3d", baseline="artemiadis-3d", runs=6)
    assert r.kind == "design"
    # the designed protocol passes its own check and fits the budget
    report = limpid.protocol_check(toml_text)
    assert report.trials == r.chosen.trials
    assert r.chosen.duration_s <= 147.2
    # damping: the seed's slow cubic leaves it to the force fluctuation, the design does not
    assert r.predicted.pooled.se_percent[1] < 0.25 * r.baseline.pooled.se_percent[1]
    assert all(m["margin_percent"] >= 0 for m in r.limits)
    import matplotlib

    matplotlib.use("Agg")
    fig = limpid.plot.design(r)
    fig.savefig(tmp_path / "design.png")
    # displayed and tabled as every result (issue 63): predicted errors with units, the limits
    assert "M error" in repr(r) and "(not identifiable)" in repr(r)
    df = r.to_pandas()
    assert set(df.protocol) == {"design", "baseline"} and len(df) == 6
    k = df[(df.protocol == "design") & (df.element == "K")].iloc[0]
    assert k.unit == "N/m" and k.se_percent == r.predicted.pooled.se_percent[0]
    assert list(r.to_pandas("limits").quantity) == [m["quantity"] for m in r.to_dict()["limits"]]
    html = r._repr_html_()
    assert "Within the safety limits" in html and "Predicted standard errors" in html
    with pytest.raises(ValueError, match="objective"):
        limpid.design("demo:S1", 147.2, limits_from="artemiadis-3d", objective="stifness")
    with pytest.raises(ValueError, match="demo:S1 .. demo:S6"):
        limpid.design("demo:S7", 147.2, limits_from="artemiadis-3d")


def test_stochastic_design_writes_a_multisine_its_check_accepts(tmp_path):
    toml_text, r = limpid.design("demo:S1", 60.0, limits_from="endpoint-multisine", method="stochastic", runs=3)
    assert (r.kind, r.method, r.family) == ("design", "stochastic", "multisine")
    assert r.chosen.duration_s <= 60.0 and r.chosen.band_hz[0] < r.chosen.band_hz[1]
    report = limpid.protocol_check(toml_text)
    assert report.duration_s == pytest.approx(r.chosen.duration_s)
    assert all(m["margin_percent"] >= 0 for m in r.limits)
    assert "multisine" in r._repr_html_()
    import matplotlib

    matplotlib.use("Agg")
    limpid.plot.design(r).savefig(tmp_path / "design.png")
    with pytest.raises(ValueError, match="end-point multisine"):
        limpid.design("demo:S1", 60.0, limits_from="endpoint-multisine", method="stochastic", baseline="artemiadis-3d")


def test_reflex_design_writes_a_prbs_its_check_accepts(tmp_path):
    toml_text, r = limpid.design("demo:ankle", 30.0, limits_from="ankle-prbs", method="reflex", runs=3,
                                 baseline="ankle-prbs")
    assert r.kind == "reflex_design"
    assert r.chosen.duration_s <= 30.0
    report = limpid.protocol_check(toml_text)
    assert report.duration_s == pytest.approx(r.chosen.duration_s)
    # the command and its lines, drawn (issue 60: the report and limpid.plot draw the designed command)
    assert max(abs(v) for v in r.command["displacement_rad"]) == pytest.approx(r.chosen.amplitude_rad, rel=1e-6)
    assert len(r.spectrum["baseline_rad"]) == len(r.spectrum["baseline_frequency_hz"])
    import matplotlib

    matplotlib.use("Agg")
    limpid.plot.design(r).savefig(tmp_path / "reflex_design.png")
    with pytest.raises(ValueError, match="demo:ankle"):
        limpid.design("demo:S1", 30.0, limits_from="ankle-prbs", method="reflex")
    with pytest.raises(ValueError, match="method"):
        limpid.design("demo:S1", 30.0, limits_from="artemiadis-3d", method="walking")


def test_planar_design_writes_joint_perturbations_its_check_accepts(tmp_path):
    toml_text, r = limpid.design("demo:planar", 40.0, limits_from="lakatos-planar", baseline="lakatos-planar",
                                 method="planar", runs=4)
    assert r.kind == "planar_design"
    report = limpid.protocol_check(toml_text)
    assert report.trials == r.chosen.trials and r.chosen.duration_s <= 40.0
    assert all(m["margin_percent"] >= 0 for m in r.limits)
    # K and D are 2 x 2 joint matrices, ξ one row; tabled with their units
    assert len(r.predicted.stiffness_se) == 2 and len(r.predicted.inertia_se[0]) == 3
    df = r.to_pandas()
    assert list(df[df.protocol == "design"].unit) == ["N m/rad", "N m s/rad", "kg m²"]
    assert "quintic joint perturbations" in r._repr_html_()
    import matplotlib

    matplotlib.use("Agg")
    limpid.plot.design(r).savefig(tmp_path / "planar_design.png")
    with pytest.raises(ValueError, match="demo:planar"):
        limpid.design("demo:S1", 40.0, method="planar")
    with pytest.raises(ValueError, match="robust"):
        limpid.design("demo:planar", 40.0, method="planar", robust="best")


def test_walking_from_the_virtual_lab_to_the_figure(tmp_path):
    # issue 61: a walk with pulses, its strides, and the figure against gait phase
    import subprocess
    cli = os.environ.get("LIMPID_CLI")
    if not cli:
        pytest.skip("LIMPID_CLI is not set (scripts/test.sh sets it)")
    proto = tmp_path / "walk.toml"
    subprocess.run([cli, "protocol", "new", "--preset", "walking-pulses", "-o", str(proto)], check=True)
    text = proto.read_text().replace("strides = 300", "strides = 90").replace("missed_events = 0.0", "missed_events = 0.05")
    proto.write_text(text)
    subprocess.run([cli, "simulate", str(proto), "-o", str(tmp_path / "walk.csv"), "--seed", "2"], check=True,
                   capture_output=True)
    est = limpid.estimate_varying(str(tmp_path / "walk.csv"), event="heel_strike")
    d = est.to_dict() if hasattr(est, "to_dict") else est
    assert d["method"] == "pulses" and "phase" in d["schedule"]["name"]
    assert all(0.0 <= v < 1.0 for v in d["schedule"]["values"])
    assert any(f["kind"] == "missed" for f in d["gait"]["flawed"])
    truth = json.loads((tmp_path / "walk.truth.json").read_text())
    ks = {round(p["sigma"], 2): p["stiffness"][0][0] for p in truth["points"]}
    mid = [p for p in d["points"] if p["identifiable"] and 0.2 <= p["sigma"] <= 0.45]
    assert mid, "stance points identifiable"
    for p in mid:
        k = p["stiffness"][0][0]
        assert abs(k - ks[round(p["sigma"], 2)]) <= 0.25 * ks[round(p["sigma"], 2)], (p["sigma"], k)
    # the display shows K, B and I with their units, the strides and the flawed ones
    html = est._repr_html_()
    for needle in ("K (N m/rad)", "B (N m s/rad)", "I (kg m²)", "Strides with flawed events", "walking tolerances"):
        assert needle in html, needle
    assert "strides used" in repr(est)
    pd = pytest.importorskip("pandas")
    flawed = est.to_pandas("flawed")
    assert isinstance(flawed, pd.DataFrame) and (flawed["kind"] == "missed").any()
    assert {"stride", "index", "start_s", "start_row"} <= set(flawed.columns)
    xr = pytest.importorskip("xarray")
    ds = est.to_xarray()
    assert isinstance(ds, xr.Dataset) and ds["stiffness"].dims == ("sigma", "output", "coordinate")
    assert ds["stiffness"].attrs["units"] == "N m/rad" and ds["sigma"].attrs["units"] == "fraction of the stride"
    ok = ds["identifiable"].values
    assert np.isnan(ds["stiffness"].values[~ok]).all() and np.isfinite(ds["stiffness"].values[ok]).all()
    matplotlib = pytest.importorskip("matplotlib")
    matplotlib.use("Agg")
    drawn = limpid.plot.varying(est)
    assert drawn.axes.shape == (1, 4) and "gait phase" in drawn.ax.get_xlabel()


def test_a_long_varying_table_is_shortened_and_an_operating_point_has_no_empty_unit(tmp_path):
    # issue 63, item 3: a 100-row time-varying table is not shown whole; "sv ()" is not a header
    points = [{"sigma": 0.01 * i, "identifiable": True, "support": 40.0,
               "stiffness": [[100.0 + i]], "stiffness_se": [[2.0]], "damping": [[1.5]], "damping_se": [[0.1]],
               "inertia": [[0.02]], "inertia_se": [[0.001]], "vaf": 90.0} for i in range(100)]
    d = {"schema": 1, "kind": "varying", "method": "parameter_varying",
         "schedule": {"name": "sv", "unit": "", "values": [p["sigma"] for p in points]},
         "coordinates": ["q1"], "forces": ["tau1"], "sample_rate_hz": 1000.0, "cutoff_hz": 30.0,
         "resolution": 0.1, "resolution_note": "", "points": points,
         "fit": {"vaf": 90.0, "cross_validated_vaf": 89.0}, "warnings": []}
    html = limpid.Result(d)._repr_html_()
    assert "sv ()" not in html and "more rows" in html
    assert html.count("<tr>") < 25
