#!/usr/bin/env bash
# The tests: the Rust workspace, then the Python package built as a wheel and
# tested in a fresh virtual environment (maturin, numpy, scipy, pytest from PyPI).
set -euo pipefail
cd "$(dirname "$0")/.."
# prerequisites first: one line on what to install, not a build failure 20 minutes in
missing=""
command -v cargo >/dev/null 2>&1 || missing="$missing cargo(rustup)"
command -v cmake >/dev/null 2>&1 || missing="$missing cmake"
command -v c++ >/dev/null 2>&1 || missing="$missing g++"
command -v chromium >/dev/null 2>&1 || command -v chromium-browser >/dev/null 2>&1 || missing="$missing chromium"
[ -e /usr/share/fonts/truetype/dejavu/DejaVuSans.ttf ] || [ -e /usr/share/fonts/truetype/liberation/LiberationSans-Regular.ttf ] || missing="$missing fonts-dejavu-core"
python3 -c "import venv, ensurepip" >/dev/null 2>&1 || missing="$missing python3-venv"
if [ -n "$missing" ]; then
  echo "scripts/test.sh: missing:$missing; install them first (Debian: apt-get install cmake g++ chromium fonts-dejavu-core python3-venv; Rust from rustup), or run .ci/run, which installs the Debian ones" >&2
  exit 2
fi
cargo test --workspace --release
# Lab Streaming Layer inlets (cargo feature lsl) on loopback: liblsl is built
# from source with cmake; its vendored boost needs the define with glibc >= 2.34
# (LSLAPICFG: resolve on this machine only, without multicast or IPv6)
CXXFLAGS="-DPTHREAD_STACK_MIN=16384 ${CXXFLAGS:-}" LSLAPICFG="$PWD/crates/live/tests/lsl_api.cfg" \
  cargo test --release -p limpid-live --features lsl --test lsl
venv=target/venv-test
python3 -m venv --clear "$venv"
"$venv/bin/pip" install -q --disable-pip-version-check maturin numpy scipy pytest mypy "dask[distributed]"
rm -rf target/wheels
"$venv/bin/maturin" build --release -q -m crates/python/Cargo.toml -o target/wheels
"$venv/bin/pip" install -q --disable-pip-version-check --no-deps target/wheels/limpid-*.whl
LIMPID_REQUIRE_DASK=1 "$venv/bin/python" -m pytest -q crates/python/tests
