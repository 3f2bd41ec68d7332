#!/usr/bin/env bash
# The dependencies whose features differ between the tests' build (the whole
# workspace with dev-dependencies) and maturin's build of the Python package
# alone. Each one makes the wheel compile part of the workspace again; the
# workspace hack in crates/python/Cargo.toml exists to keep this list empty.
set -euo pipefail
cd "$(dirname "$0")/.."
features() {
  cargo tree "$@" --prefix none --format "{p} [{f}]" 2>/dev/null | sed 's/ (\*)//; s/ (proc-macro)//' | sort -u
}
features --workspace --features limpid-live/lsl,limpid-cli/lsl -e normal,build,dev > "${TMPDIR:-/tmp}/limpid-ws-features"
features -p limpid-python -e normal,build > "${TMPDIR:-/tmp}/limpid-py-features"
python3 - "${TMPDIR:-/tmp}/limpid-ws-features" "${TMPDIR:-/tmp}/limpid-py-features" <<'PY'
import sys
def load(p):
    d = {}
    for line in open(p):
        line = line.strip()
        if "[" in line:
            d[line.split(" [")[0]] = line[line.index("[") + 1:-1]
    return d
ws, py = load(sys.argv[1]), load(sys.argv[2])
diff = [k for k, v in py.items() if k in ws and ws[k] != v]
for k in diff:
    print(f"{k}: tests [{ws[k]}], wheel [{py[k]}]")
sys.exit(1 if diff else 0)
PY
