#!/usr/bin/env python3
"""Every command's output on the example recordings, for before/after diffs.

    python3 scripts/example-outputs.py LIMPID_BINARY EXAMPLES_DIR... OUT_DIR

Runs each estimator (JSON and text), `spectra`, `window-sweep`, `demo` and
`simulate` on the recordings under the given example folders (the layout of
`limpid-test-examples`) and writes one file per command to OUT_DIR, with the
run block (time, command line, file dates) removed from JSON results. A
refactoring that must not change behaviour leaves `diff -r` of two such
folders empty.
"""

import json
import subprocess
import sys
from pathlib import Path


def strip_run(text):
    try:
        doc = json.loads(text)
    except ValueError:
        return text
    if isinstance(doc, dict):
        doc.pop("run", None)
    return json.dumps(doc, indent=1, sort_keys=True) + "\n"


def commands(folder):
    out = []
    for csv in sorted(folder.glob("cartesian_slow/*.csv")):
        out.append((csv.stem, ["estimate", "linear", str(csv)]))
        out.append((csv.stem + "-fit", ["estimate", "linear", str(csv), "--offsets", "fit",
                                        "--frame", "seed000"]))
        out.append((csv.stem + "-noeq", ["estimate", "linear", str(csv), "--no-equilibrium",
                                         "--shoulder", "0.3,0.3,90,20,10,0"]))
    for csv in sorted(folder.glob("cocontraction/*[0-9].csv")):
        mvc = csv.with_suffix(".mvc.csv")
        out.append((csv.stem, ["estimate", "cocontraction", str(csv), "--mvc", str(mvc)]))
        out.append((csv.stem + "-level", ["estimate", "linear", str(csv), "--level", "0"]))
    for csv in sorted(folder.glob("planar/*.csv")):
        truth = json.loads(csv.with_suffix(".truth.json").read_text())
        links = ",".join(str(v) for v in truth["link_lengths"])
        out.append((csv.stem, ["estimate", "planar", str(csv), "--link-lengths", links]))
        out.append((csv.stem + "-200", ["estimate", "planar", str(csv), "--link-lengths", links,
                                        "--window-ms", "200"]))
        xi = ",".join(str(v) for v in truth["inertial_parameters"])
        out.append((csv.stem + "-xi", ["estimate", "planar", str(csv), "--link-lengths", links,
                                       "--inertial-parameters", xi]))
        out.append((csv.stem + "-sweep", ["window-sweep", str(csv), "--link-lengths", links,
                                          "--from", "60", "--to", "300", "--step", "20"]))
    for csv in sorted(folder.glob("stochastic/*.csv")):
        out.append((csv.stem, ["estimate", "stochastic", str(csv)]))
        out.append((csv.stem + "-band", ["estimate", "stochastic", str(csv), "--band", "1,8",
                                         "--nfft", "2048", "--window", "hamming"]))
        truth = csv.with_suffix(".truth.json")
        out.append((csv.stem + "-expected", ["estimate", "stochastic", str(csv), "--expected",
                                             str(truth)]))
        out.append((csv.stem + "-spectra", ["spectra", str(csv), "--inputs", "ux,uz",
                                            "--outputs", "fx,fz"]))
    for csv in sorted(folder.glob("ankle/*.csv")):
        out.append((csv.stem, ["estimate", "reflex", str(csv)]))
        out.append((csv.stem + "-rate", ["estimate", "reflex", str(csv), "--rate", "200",
                                         "--max-delay", "0.1"]))
    return out


def main():
    if len(sys.argv) < 4:
        sys.exit(__doc__)
    binary, folders, dest = sys.argv[1], sys.argv[2:-1], Path(sys.argv[-1])
    dest.mkdir(parents=True, exist_ok=True)
    jobs = []
    for i, folder in enumerate(folders):
        for name, args in commands(Path(folder)):
            jobs.append((f"{i}-{name}", args))
    jobs.append(("demo", ["demo", "--seed", "3"]))
    for name, args in jobs:
        for mode, extra in (("json", ["--json"]), ("text", [])):
            run = subprocess.run([binary, *args, *extra], capture_output=True, text=True)
            body = strip_run(run.stdout) if mode == "json" else run.stdout
            (dest / f"{name}.{mode}").write_text(
                f"exit {run.returncode}\n{run.stderr}\n---\n{body}")


if __name__ == "__main__":
    main()
