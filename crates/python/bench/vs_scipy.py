"""limpid vs. an equivalent numpy/scipy pipeline on a long recording (not a test).

    cargo run --release -p limpid-cli --example long_recording -- 60 /tmp/long.parquet
    python crates/python/bench/vs_scipy.py /tmp/long.parquet

The numpy/scipy pipeline does what `estimate linear` does at its core, per
trial window: zero-phase 4th-order Butterworth at 30 Hz on positions and forces
(scipy.signal.sosfiltfilt), derivatives by numpy.gradient, the rest-mean force
offset, then one least-squares fit of M, B, K and x_eq (numpy.linalg.lstsq).
It has no standard errors, fit statistics or criteria; limpid's time includes
them (jackknife over trials), so the ratio understates the like-for-like gain.
"""

import sys
import time

import numpy as np
import scipy.signal as ss

import limpid


def scipy_pipeline(rec):
    t = rec["t"]
    fs = 1.0 / np.median(np.diff(t))
    sos = ss.butter(4, 30.0, fs=fs, output="sos")
    trial = rec["trial"]
    edges = np.flatnonzero(np.diff(trial)) + 1
    starts = np.r_[0, edges]
    ends = np.r_[edges, len(t)]
    rows, rhs = [], []
    for s, e in zip(starts, ends):
        x = ss.sosfiltfilt(sos, np.vstack([rec["x"][s:e], rec["y"][s:e], rec["z"][s:e]]), axis=1)
        f = ss.sosfiltfilt(sos, np.vstack([rec["fx"][s:e], rec["fy"][s:e], rec["fz"][s:e]]), axis=1)
        v = np.gradient(x, 1 / fs, axis=1)
        a = np.gradient(v, 1 / fs, axis=1)
        rest = max(1, int(0.2 * fs))
        f = f - f[:, :rest].mean(axis=1, keepdims=True)
        rows.append(np.vstack([a, v, x, np.ones(e - s)]).T)
        rhs.append(f.T)
    Y = np.vstack(rows)
    F = np.vstack(rhs)
    P, *_ = np.linalg.lstsq(Y, F, rcond=None)
    return P[6:9].T  # K


def main(path):
    rec = limpid.read_recording(path)
    n = len(rec["t"])
    t0 = time.perf_counter()
    k_scipy = scipy_pipeline(rec)
    t_scipy = time.perf_counter() - t0
    t0 = time.perf_counter()
    est = limpid.estimate_linear(rec, offsets="rest")
    t_limpid = time.perf_counter() - t0
    diff = np.linalg.norm(est.stiffness - k_scipy) / np.linalg.norm(k_scipy)
    print(f"{n} samples: numpy/scipy {t_scipy:.2f} s, limpid {t_limpid:.2f} s "
          f"(ratio {t_scipy / t_limpid:.1f}x); stiffness difference {100 * diff:.2f} %")


if __name__ == "__main__":
    main(sys.argv[1])
