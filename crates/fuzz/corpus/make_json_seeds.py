"""Write the fuzzer's JSON seeds: requests (`request-*.json`, what flags and
Python keywords become) and result documents (`result-*.json`, what
`limpid report` and `limpid rerun` read back), made by the `limpid` binary
on the recording seeds. Long arrays are cut to their first 48 entries (all
alike, so paired arrays stay paired) to keep mutations fast.

    python3 crates/fuzz/corpus/make_json_seeds.py [path/to/limpid]
"""
import json
import pathlib
import subprocess
import sys

HERE = pathlib.Path(__file__).resolve().parent
SEEDS = HERE / "seeds"
LIMPID = sys.argv[1] if len(sys.argv) > 1 else "limpid"
ARM = ["--link-lengths", "0.3,0.33"]

RUNS = {
    "linear": ["estimate", "linear", "linear3d.csv", "--shoulder", "0.3,0.35,90,30,45,0"],
    "cocontraction": ["estimate", "cocontraction", "cocontraction.csv", "--mvc", "cocontraction.csv"],
    "planar": ["estimate", "planar", "joint2.csv", *ARM, "--window-ms", "250"],
    "window_sweep": ["window-sweep", "joint2.csv", *ARM, "--from", "100", "--to", "300", "--step", "50"],
    "stochastic": ["estimate", "stochastic", "stochastic.csv", "--nfft", "512", "--overlap", "256"],
    "reflex": ["estimate", "reflex", "ankle.csv"],
    "varying": ["estimate", "varying", "joint2.csv"],
    "spectra": ["spectra", "stochastic.csv", "--inputs", "ux,uz", "--outputs", "x,z", "--nfft", "512"],
}


def cut(v):
    if isinstance(v, list):
        return [cut(x) for x in v[:48]]
    if isinstance(v, dict):
        return {k: cut(x) for k, x in v.items()}
    return v


def limpid(args):
    out = subprocess.run([LIMPID, *args], cwd=SEEDS, capture_output=True, text=True)
    if out.returncode != 0:
        sys.exit(f"limpid {' '.join(args)}: {out.stderr.strip()}")
    return json.loads(out.stdout)


for method, args in RUNS.items():
    request = limpid([*args, "--print-request"])
    (SEEDS / f"request-{method}.json").write_text(json.dumps(request, indent=1) + "\n")
    result = limpid([*args, "--json"])
    result.pop("run", None)
    (SEEDS / f"result-{method}.json").write_text(json.dumps(cut(result)) + "\n")
    print(f"request-{method}.json, result-{method}.json")
