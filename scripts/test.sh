#!/usr/bin/env bash
# The tests: the Rust workspace, then the Python package built as a wheel and
# tested in a fresh virtual environment (maturin, numpy, scipy, pytest from PyPI).
set -euo pipefail
cd "$(dirname "$0")/.."
cargo test --workspace --release
# Lab Streaming Layer inlets (cargo feature lsl) on loopback: liblsl is built
# from source with cmake; its vendored boost needs the define with glibc >= 2.34
# (LSLAPICFG: resolve on this machine only, without multicast or IPv6)
CXXFLAGS="-DPTHREAD_STACK_MIN=16384 ${CXXFLAGS:-}" LSLAPICFG="$PWD/crates/live/tests/lsl_api.cfg" \
  cargo test --release -p limpid-live --features lsl --test lsl
venv=target/venv-test
python3 -m venv --clear "$venv"
"$venv/bin/pip" install -q --disable-pip-version-check maturin numpy scipy pytest
rm -rf target/wheels
"$venv/bin/maturin" build --release -q -m crates/python/Cargo.toml -o target/wheels
"$venv/bin/pip" install -q --disable-pip-version-check --no-deps target/wheels/limpid-*.whl
"$venv/bin/python" -m pytest -q crates/python/tests
