"""The numpy/scipy pipeline limpid's speed is compared with (issue 16), as a
script: `python scipy_pipeline.py long.parquet` reads the recording with
pyarrow and prints the stiffness, as a user's own script would.

Per trial window: zero-phase 4th-order Butterworth at 30 Hz on positions and
forces (scipy.signal.sosfiltfilt), derivatives by numpy.gradient, the
rest-mean force offset, then one least-squares fit of M, B, K and x_eq
(numpy.linalg.lstsq). No standard errors, fit statistics or criteria.
"""

import sys

import numpy as np
import scipy.signal as ss


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


if __name__ == "__main__":
    import pyarrow.parquet as pq

    table = pq.read_table(sys.argv[1])
    recording = {c: table.column(c).to_numpy() for c in table.column_names}
    print(scipy_pipeline(recording))
