"""Every public function, given a value of the wrong kind or size for one
argument, raises ValueError (OSError for files, KeyError for a missing field)
with a message: never TypeError, OverflowError, IndexError or a Rust panic."""
import warnings
from pathlib import Path

import numpy as np
import pytest

import limpid

from conftest import EXAMPLES as S
VALUES = [None, 0, -1, 2**70, 1e400, float("nan"), "x", True, 1.5, [], np.array([]), np.ones((2, 2)), {}, b"x"]
CALLS = {
    "psd fs": lambda v: limpid.psd(np.ones(100), fs=v),
    "psd nperseg": lambda v: limpid.psd(np.ones(100), nperseg=v),
    "psd x": lambda v: limpid.psd(v),
    "csd y": lambda v: limpid.csd(np.ones(100), v),
    "coherence window": lambda v: limpid.coherence(np.ones(100), np.ones(100), window=v),
    "lowpass fs": lambda v: limpid.lowpass_filtfilt(np.ones(100), 10, v),
    "lowpass x": lambda v: limpid.lowpass_filtfilt(v, 10, 100),
    "linear cutoff": lambda v: limpid.estimate_linear(S / "cartesian_slow" / "ex_cubic.csv", cutoff_hz=v),
    "linear recording": lambda v: limpid.estimate_linear(v),
    "stochastic band": lambda v: limpid.estimate_stochastic(S / "stochastic" / "ex_sa3.csv", band_hz=(v, 10)),
    "stochastic shoulder": lambda v: limpid.estimate_stochastic(S / "stochastic" / "ex_sa3.csv", shoulder=v),
    "stochastic shoulder angle": lambda v: limpid.estimate_stochastic(S / "stochastic" / "ex_sa3.csv",
                                                                      shoulder=(0.3, 0.35, 90, 30, v, 0)),
    "planar links": lambda v: limpid.estimate_planar(S / "planar" / "ex_joint_180.csv", (v, 0.3)),
    "ellipsoid": lambda v: limpid.ellipsoid(v),
    "simulate seed": lambda v: limpid.simulate("artemiadis-3d", seed=v),
    "study_entries": lambda v: limpid.study_entries(v),
    "study_process": lambda v: limpid.study_process(v),
    "study_combine": lambda v: limpid.study_combine(v),
    "protocol_preset": lambda v: limpid.protocol_preset(v),
    "protocol_check": lambda v: limpid.protocol_check(v),
    "frequency_response": lambda v: limpid.frequency_response([v], [np.ones(100)]),
}


@pytest.mark.parametrize("name", sorted(CALLS))
def test_bad_values_are_value_errors(name):
    for v in VALUES:
        try:
            with warnings.catch_warnings():
                warnings.simplefilter("ignore")
                CALLS[name](v)
        except (ValueError, OSError, KeyError) as e:
            assert str(e), f"{name}({v!r}): empty message"
        # anything else (TypeError, OverflowError, PanicException) fails the test


def test_a_wrong_call_signature_stays_a_type_error():
    with pytest.raises(TypeError):
        limpid.psd()
    with pytest.raises(TypeError):
        limpid.psd(np.ones(10), bogus=1)


def test_an_unknown_option_names_the_nearest_and_lists_the_options():
    # issue 63, item 7: the options as the estimator takes them, not the request's groups
    path = S / "cartesian_slow" / "ex_cubic.csv"
    with pytest.raises(TypeError) as e:
        limpid.estimate_linear(path, cuttoff_hz=10)
    message = str(e.value)
    assert "estimate_linear() got an unexpected keyword argument 'cuttoff_hz'" in message
    assert "did you mean 'cutoff_hz'?" in message
    assert "order" in message and "prepare" not in message
    # a method whose request needs a field the call gives (planar's link lengths)
    with pytest.raises(TypeError, match=r"did you mean 'window_ms'"):
        limpid.estimate_planar(S / "planar" / "ex_joint_180.csv", (0.3, 0.3), windw_ms=200)


def test_a_number_given_as_text_names_the_option_and_the_type():
    path = S / "cartesian_slow" / "ex_cubic.csv"
    with pytest.raises(ValueError, match=r"estimate_linear: cutoff_hz = '10': a number is expected, not str"):
        limpid.estimate_linear(path, cutoff_hz="10")


def test_a_dataframe_with_time_as_its_index():
    pd = pytest.importorskip("pandas")
    rec = limpid.read_recording(S / "cartesian_slow" / "ex_cubic.csv")
    frame = pd.DataFrame(rec).set_index("t")
    # an index named t is the time
    expected = limpid.estimate_linear(S / "cartesian_slow" / "ex_cubic.csv").to_dict()["stiffness"]
    assert limpid.estimate_linear(frame).to_dict()["stiffness"] == expected
    # another name: said, with the fix
    with pytest.raises(ValueError, match=r"no column t .*its index is 'time'.*reset_index"):
        limpid.estimate_linear(frame.rename_axis("time"))


def test_units_come_from_what_the_column_is_not_its_name():
    # issue 63, item 2: the ankle with its columns renamed reports the canonical names' units
    pd = pytest.importorskip("pandas")
    rec = limpid.read_recording(S / "ankle" / "ex_ankle.csv")
    canonical = limpid.estimate_reflex(rec)
    renamed = limpid.estimate_reflex({"t": rec["t"], "angle": rec["q1"], "torque": rec["tau1"]},
                                     position="angle", torque="torque")
    a, b = canonical.to_pandas(), renamed.to_pandas()
    assert list(a.unit) == list(b.unit) and "N m/rad" in set(a.unit) and "N m s/rad" in set(a.unit)
    assert renamed.to_dict()["units"] == canonical.to_dict()["units"]
    assert renamed.to_dict()["intrinsic"]["stiffness"] == pytest.approx(canonical.to_dict()["intrinsic"]["stiffness"])
    # the assumption is said; saying what the column is removes it and can change it
    codes = lambda r: [w["code"] for w in r.to_dict()["warnings"]]  # noqa: E731
    assert "units_assumed" in codes(renamed) and "units_assumed" not in codes(canonical)
    said = limpid.estimate_reflex({"t": rec["t"], "angle": rec["q1"], "torque": rec["tau1"]},
                                  position="angle", torque="torque", coordinate="angle")
    assert "units_assumed" not in codes(said)
    metres = limpid.estimate_reflex({"t": rec["t"], "hand": rec["q1"], "push": rec["tau1"]},
                                    position="hand", torque="push", coordinate="displacement")
    assert {"N/m", "N s/m", "kg"} <= set(metres.to_pandas().unit)
    with pytest.raises(ValueError, match="coordinate"):
        limpid.estimate_reflex(rec, coordinate="radians")


def test_positions_in_centimetres_are_called_implausible():
    # issue 63, item 2: a hand moving metres is a unit error the fit cannot see
    rec = limpid.read_recording(S / "cartesian_slow" / "ex_cubic.csv")
    cm = dict(rec)
    for c in ("x", "y", "z"):
        cm[c] = np.asarray(rec[c]) * 100.0
    r = limpid.estimate_linear(cm).to_dict()
    said = [w["message"] for w in r["warnings"] if w["code"] == "implausible_units"]
    assert said and "centimetres" in said[0], r["warnings"]
    assert not [w for w in limpid.estimate_linear(rec).to_dict()["warnings"] if w["code"] == "implausible_units"]
