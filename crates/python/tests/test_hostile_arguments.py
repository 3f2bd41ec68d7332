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
