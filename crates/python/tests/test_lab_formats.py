"""One recording as other programs would write it — MATLAB -v7.3 (hdf5storage),
C3D (ezc3d), TDMS (npTDMS) — read back through channel maps, gives the
estimate of its CSV (issue 40). The writers are the formats' own Python
libraries, not limpid."""

import numpy as np
import pytest

import limpid
from conftest import examples

ezc3d = pytest.importorskip("ezc3d")
hdf5storage = pytest.importorskip("hdf5storage")
nptdms = pytest.importorskip("nptdms")

AXES = ["x", "y", "z"]


@pytest.fixture(scope="module")
def recording():
    path = examples("cartesian_slow") / "ex_cubic.csv"
    rec = limpid.read_recording(path)
    dt = np.diff(rec["t"])
    assert np.allclose(dt, dt[0], rtol=1e-6), "a uniformly sampled example"
    return path, rec, 1.0 / dt[0]


def _stiffness(result):
    return np.asarray(result.to_dict()["stiffness"])


def _same_estimate(csv_path, rec_dict, rtol):
    expected = _stiffness(limpid.estimate_linear(csv_path))
    got = _stiffness(limpid.estimate_linear(rec_dict))
    np.testing.assert_allclose(got, expected, rtol=rtol, atol=rtol * np.abs(expected).max())


def test_a_mat_v73_struct_gives_the_csv_estimate(recording, tmp_path):
    path, rec, _ = recording
    mat = tmp_path / "session.mat"
    rec_struct = {"Time_ms": (rec["t"] * 1e3).reshape(-1, 1), "TrialNo": rec["trial"].reshape(-1, 1)}
    rec_struct["Hand"] = {a.upper(): (rec[a] * 1e3).reshape(-1, 1) for a in AXES}
    rec_struct["Force"] = {"F" + a: rec["f" + a].reshape(-1, 1) for a in AXES}
    hdf5storage.savemat(str(mat), {"rec": rec_struct}, format="7.3", matlab_compatible=True,
                        store_python_metadata=False)
    columns = {"t": {"channel": "rec.Time_ms", "unit": "ms"}, "trial": "rec.TrialNo"}
    columns.update({a: {"channel": f"rec.Hand.{a.upper()}", "unit": "mm"} for a in AXES})
    columns.update({"f" + a: f"rec.Force.F{a}" for a in AXES})
    converted = limpid.read_recording(mat, map={"columns": columns})
    # float64 all the way: the mm -> m conversion is the only rounding
    for name in ["t"] + AXES + ["fx", "fy", "fz", "trial"]:
        np.testing.assert_allclose(converted[name], rec[name], rtol=1e-12, atol=1e-15)
    _same_estimate(path, converted, 1e-9)


def test_a_c3d_file_gives_the_csv_estimate(recording, tmp_path):
    path, rec, fs = recording
    c = ezc3d.c3d()
    c["parameters"]["POINT"]["RATE"]["value"] = [fs]
    c["parameters"]["POINT"]["LABELS"]["value"] = ["Handle"]
    c["parameters"]["POINT"]["UNITS"]["value"] = ["mm"]
    n = len(rec["t"])
    points = np.ones((4, 1, n))
    for k, a in enumerate(AXES):
        points[k, 0] = rec[a] * 1e3
    c["data"]["points"] = points
    c["parameters"]["ANALOG"]["RATE"]["value"] = [fs]
    c["parameters"]["ANALOG"]["LABELS"]["value"] = ["Fx", "Fy", "Fz", "Trial"]
    c["parameters"]["ANALOG"]["UNITS"]["value"] = ["N", "N", "N", ""]
    c["data"]["analogs"] = np.array([[rec["fx"], rec["fy"], rec["fz"], rec["trial"]]])
    c3d_path = tmp_path / "session.c3d"
    c.write(str(c3d_path))
    columns = {a: {"channel": f"Handle.{a.upper()}", "stream": "points"} for a in AXES}
    columns.update({"f" + a: f"F{a}" for a in AXES})
    columns["trial"] = "Trial"
    converted = limpid.read_recording(c3d_path, map={"time": {"stream": "points"}, "columns": columns})
    # C3D stores 32-bit floats: the estimate agrees to that precision
    for name in AXES + ["fx", "trial"]:
        np.testing.assert_allclose(converted[name], rec[name], rtol=1e-6, atol=1e-7)
    _same_estimate(path, converted, 1e-4)


def test_a_tdms_file_gives_the_csv_estimate(recording, tmp_path):
    path, rec, fs = recording
    tdms = tmp_path / "session.tdms"
    props = {"wf_increment": 1.0 / fs, "wf_start_offset": 0.0}
    with nptdms.TdmsWriter(str(tdms)) as w:
        w.write_segment([nptdms.ChannelObject("Rig", name, rec[src] * k, dict(props, unit_string=u))
                         for name, src, k, u in [("Pos X", "x", 1e3, "mm"), ("Pos Y", "y", 1e3, "mm"),
                                                 ("Pos Z", "z", 1e3, "mm"), ("Fx", "fx", 1.0, "N"),
                                                 ("Fy", "fy", 1.0, "N"), ("Fz", "fz", 1.0, "N"),
                                                 ("Trial", "trial", 1.0, "")]])
    columns = {a: f"Pos {a.upper()}" for a in AXES}
    columns.update({"f" + a: f"F{a}" for a in AXES})
    columns["trial"] = "Trial"
    converted = limpid.read_recording(tdms, map={"columns": columns})
    for name in AXES + ["fx", "trial"]:
        np.testing.assert_allclose(converted[name], rec[name], rtol=1e-12, atol=1e-15)
    _same_estimate(path, converted, 1e-9)
