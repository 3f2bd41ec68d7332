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

import limpid
from scipy_pipeline import scipy_pipeline


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
