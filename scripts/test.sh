#!/usr/bin/env bash
# The tests: the Rust workspace, then the Python package built as a wheel and
# tested in a fresh virtual environment (maturin, numpy, scipy, pytest from PyPI).
#
# Set-up included: on Debian, the system packages the tests need are installed
# when this runs as root or with password-less sudo; otherwise one line says
# what to install. Real human recordings (another licence) are read from
# $LIMPID_REAL_DATA; the outside-generator examples from $LIMPID_EXAMPLES. Both
# are optional: the tests that need them say they were skipped when unset.
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/prerequisites.sh
# one profile for every build below (see [profile.ci] in Cargo.toml): the
# workspace tests, the LSL test and the wheel share their compiled dependencies
profile=ci
cargo test --workspace --profile "$profile"
# Lab Streaming Layer inlets (cargo feature lsl) on loopback: liblsl is built
# from source with cmake; its vendored boost needs the define with glibc >= 2.34
# (LSLAPICFG: resolve on this machine only, without multicast or IPv6)
CXXFLAGS="-DPTHREAD_STACK_MIN=16384 ${CXXFLAGS:-}" LSLAPICFG="$PWD/crates/live/tests/lsl_api.cfg" \
  cargo test --profile "$profile" -p limpid-live --features lsl --test lsl
target_dir="${CARGO_TARGET_DIR:-target}"
venv="$target_dir/venv-test"
python3 -m venv --clear "$venv"
"$venv/bin/pip" install -q --disable-pip-version-check maturin numpy scipy pytest mypy "dask[distributed]"
rm -rf "$target_dir/wheels"
"$venv/bin/maturin" build --profile "$profile" -q -m crates/python/Cargo.toml -o "$target_dir/wheels"
"$venv/bin/pip" install -q --disable-pip-version-check --no-deps "$target_dir"/wheels/limpid-*.whl
LIMPID_REQUIRE_DASK=1 "$venv/bin/python" -m pytest -q -rs crates/python/tests
