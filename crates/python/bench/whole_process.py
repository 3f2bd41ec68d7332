"""Whole-process timing of `limpid estimate linear` against the numpy/scipy
pipeline as a script (scipy_pipeline.py, pyarrow reader), alternating runs,
medians (issue 16's measure; not a test).

    cargo run --release -p limpid-cli --example long_recording -- 60 /tmp/long.parquet
    cargo build --release -p limpid-cli
    python crates/python/bench/whole_process.py /tmp/long.parquet [runs]

Needs numpy, scipy and pyarrow in the running Python.
"""

import os
import statistics
import subprocess
import sys
import time

HERE = os.path.dirname(os.path.abspath(__file__))
LIMPID = os.path.join(HERE, "..", "..", "..", "target", "release", "limpid")


def main(path, runs):
    peer = [sys.executable, os.path.join(HERE, "scipy_pipeline.py"), path]
    ours = [LIMPID, "estimate", "linear", path, "--json"]
    times = {"numpy/scipy": [], "limpid": []}
    for _ in range(runs):
        for name, cmd in (("numpy/scipy", peer), ("limpid", ours)):
            t0 = time.perf_counter()
            with open(os.devnull, "w") as sink:  # write-only: read-write is refused off Linux (main.rs)
                subprocess.run(cmd, stdout=sink, check=True)
            times[name].append(time.perf_counter() - t0)
    for name, t in times.items():
        print(f"{name}: " + " ".join(f"{x:.3f}" for x in t) + f" s (median {statistics.median(t):.3f})")
    ratio = statistics.median(times["numpy/scipy"]) / statistics.median(times["limpid"])
    print(f"limpid is {ratio:.1f}x faster (medians of {runs} alternating runs)")


if __name__ == "__main__":
    main(sys.argv[1], int(sys.argv[2]) if len(sys.argv) > 2 else 7)
