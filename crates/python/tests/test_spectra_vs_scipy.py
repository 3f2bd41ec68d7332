"""limpid.psd/csd/coherence against scipy.signal on random data, in the
settings scipy's own tests do not cover together: N-D broadcasting, windows
by tuple, zero padding, median of complex cross-spectra, dead channels."""
import warnings

import numpy as np
import pytest
from scipy import signal

import limpid


def test_the_cross_spectral_matrix_of_nine_channels_in_one_call():
    rng = np.random.default_rng(5)
    s = rng.standard_normal((9, 4000)).cumsum(axis=1)
    f, m = limpid.csd(s[:, None, :], s[None, :, :], fs=500.0, nperseg=512, window=("tukey", 0.25))
    fs, ms = signal.csd(s[:, None, :], s[None, :, :], fs=500.0, nperseg=512, window=("tukey", 0.25))
    assert m.shape == ms.shape == (9, 9, 257)
    np.testing.assert_allclose(f, fs)
    np.testing.assert_allclose(m, ms, rtol=1e-10, atol=1e-12 * np.abs(ms).max())
    # Hermitian, as a spectral matrix must be
    np.testing.assert_allclose(m, np.conj(np.swapaxes(m, 0, 1)), rtol=1e-12, atol=1e-14 * np.abs(m).max())


@pytest.mark.parametrize("kw", [
    dict(nperseg=100, nfft=256, detrend="linear"),
    dict(nperseg=128, noverlap=100, average="median", scaling="spectrum"),
    dict(nperseg=64, return_onesided=False, window="blackmanharris"),
    dict(nperseg=77, detrend=False, window=("kaiser", 8.0), axis=0),
])
def test_csd_and_psd_equal_scipy(kw):
    rng = np.random.default_rng(7)
    x = rng.standard_normal((3000, 2))
    y = 0.5 * x + rng.standard_normal((3000, 2))
    axis = kw.pop("axis", -1)
    if axis == -1:
        x, y = x.T, y.T
    for ours, theirs in [(limpid.csd(x, y, 200.0, axis=axis, **kw), signal.csd(x, y, 200.0, axis=axis, **kw)),
                         (limpid.psd(x, 200.0, axis=axis, **kw), signal.welch(x, 200.0, axis=axis, **kw))]:
        np.testing.assert_allclose(ours[0], theirs[0])
        assert ours[1].shape == theirs[1].shape and ours[1].dtype == theirs[1].dtype
        np.testing.assert_allclose(ours[1], theirs[1], rtol=1e-9, atol=1e-12 * np.abs(theirs[1]).max())


def test_complex_median_and_float32_as_scipy():
    rng = np.random.default_rng(9)
    z = (rng.standard_normal(2048) + 1j * rng.standard_normal(2048)).astype(np.complex64)
    w = np.roll(z, 3)
    ours = limpid.csd(z, w, nperseg=128, average="median")
    theirs = signal.csd(z, w, nperseg=128, average="median")
    assert ours[1].dtype == theirs[1].dtype == np.complex64
    np.testing.assert_allclose(ours[0], theirs[0])
    np.testing.assert_allclose(ours[1], theirs[1], rtol=2e-5, atol=1e-6 * np.abs(theirs[1]).max())


def test_a_dead_channel_has_nan_coherence_as_scipy():
    rng = np.random.default_rng(3)
    x = rng.standard_normal(1000)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", RuntimeWarning)
        _, c = limpid.coherence(x, np.zeros(1000), nperseg=100)
        _, cs = signal.coherence(x, np.zeros(1000), nperseg=100)
    assert np.isnan(c).all() and np.isnan(cs).all()
    _, c = limpid.coherence(x, 2 * x + 1, nperseg=100)
    np.testing.assert_allclose(c, 1.0, rtol=1e-12)


def test_bad_arguments_are_value_errors():
    x = np.ones(100)
    for kw in [dict(nperseg=4.5), dict(nperseg="8"), dict(nfft=7.0, nperseg=8), dict(noverlap=-1, nperseg=8),
               dict(fs=0.0), dict(fs="x"), dict(axis=1.5), dict(axis=3), dict(detrend="cubic"), dict(detrend=True),
               dict(window=np.ones((2, 3))), dict(window=np.ones(4) * 1j), dict(average="max"),
               dict(nfft=2**70), dict(nfft=2**40), dict(nperseg=-3), dict(fs=1e400), dict(fs=np.nan)]:
        with pytest.raises(ValueError):
            limpid.psd(x, **kw)
    with pytest.raises(ValueError, match="cannot be broadcast"):
        limpid.csd(np.ones((2, 8)), np.ones((3, 8)))
    with pytest.raises(ValueError):
        limpid.psd(np.array(["a", "b"]))


@pytest.mark.parametrize("kw", [
    dict(axis=1), dict(axis=-2, padtype="even", padlen=50), dict(axis=1, padtype="constant"),
    dict(axis=1, padtype=None), dict(axis=2, padlen=2), dict(axis=1, padlen=0), dict(axis=0, padlen=2, order=2),
])
def test_lowpass_filtfilt_with_padding_and_axis_equals_sosfiltfilt(kw):
    rng = np.random.default_rng(1)
    x = rng.standard_normal((3, 500, 4)).cumsum(axis=1)
    order = kw.pop("order", 4)
    sos = signal.butter(order, 10, fs=500, output="sos")
    ours = limpid.lowpass_filtfilt(x, 10, 500, order=order, **kw)
    theirs = signal.sosfiltfilt(sos, x, **kw)
    assert ours.shape == theirs.shape and ours.dtype == theirs.dtype
    np.testing.assert_allclose(ours, theirs, rtol=1e-10, atol=1e-10 * np.abs(theirs).max())


def test_lowpass_filtfilt_of_complex_and_float32_input_as_sosfiltfilt():
    rng = np.random.default_rng(2)
    z = rng.standard_normal(300) + 1j * rng.standard_normal(300)
    sos = signal.butter(4, 20, fs=250, output="sos")
    np.testing.assert_allclose(limpid.lowpass_filtfilt(z, 20, 250), signal.sosfiltfilt(sos, z), rtol=1e-10, atol=1e-12)
    f = z.real.astype(np.float32)
    ours, theirs = limpid.lowpass_filtfilt(f, 20, 250), signal.sosfiltfilt(sos, f)
    assert ours.dtype == theirs.dtype == np.float64
    # scipy extends float32 input in float32 before filtering in float64
    np.testing.assert_allclose(ours, theirs, rtol=1e-6, atol=1e-6)


def test_lowpass_filtfilt_refuses_what_sosfiltfilt_refuses():
    x = np.ones(20)
    for kw in [dict(padlen=20), dict(padtype="mirror")]:
        with pytest.raises(ValueError):
            limpid.lowpass_filtfilt(x, 10, 100, **kw)
        with pytest.raises(ValueError):
            signal.sosfiltfilt(signal.butter(4, 10, fs=100, output="sos"), x, **kw)
    # stricter than scipy (which runs padlen=-1 and raises IndexError for the axis)
    for kw in [dict(padlen=-1), dict(padlen=3.5), dict(axis=1), dict(padlen=2**70), dict(order=2**70),
               dict(order=0)]:
        with pytest.raises(ValueError):
            limpid.lowpass_filtfilt(x, 10, 100, **kw)
    for cutoff in (1e400, float("nan"), "10", 60.0):
        with pytest.raises(ValueError):
            limpid.lowpass_filtfilt(x, cutoff, 100)
    # padtype=None pads nothing, so any length above zero works, as in scipy
    np.testing.assert_allclose(limpid.lowpass_filtfilt(np.arange(5.0), 10, 100, padtype=None),
                               signal.sosfiltfilt(signal.butter(4, 10, fs=100, output="sos"), np.arange(5.0), padtype=None),
                               rtol=1e-10)
