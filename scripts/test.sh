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
for v in LIMPID_EXAMPLES LIMPID_REAL_DATA; do
  if [ -n "${!v:-}" ]; then echo "scripts/test.sh: $v=${!v}: its tests run"
  else echo "scripts/test.sh: $v is not set: the tests that need it are skipped"; fi
done
# One profile for every build below (see [profile.ci] in Cargo.toml), and one
# cargo invocation for the whole workspace with every feature the tests use, so
# each dependency is compiled once (a `-p` selection would unify features
# differently and compile parquet, tokio, ... again). The `lsl` feature builds
# liblsl from source with cmake; its vendored boost needs the define with
# glibc >= 2.34. LSLAPICFG: the LSL test resolves on this machine only,
# without multicast or IPv6.
profile=ci
case " ${CXXFLAGS:-} " in *" -DPTHREAD_STACK_MIN=16384 "*) ;; *) export CXXFLAGS="-DPTHREAD_STACK_MIN=16384 ${CXXFLAGS:-}" ;; esac
# Twice as many test threads as cores: a fifth of the CLI tests' time is
# spent waiting on real time (live replays, the 10 kHz load, FIFOs), which
# another test's computing can fill (the CLI tests: 153 s -> 92 s on 2 cores).
start=$(date +%s)
export RUST_TEST_THREADS="${RUST_TEST_THREADS:-$(( $(nproc) * 2 ))}"
LSLAPICFG="$PWD/crates/live/tests/lsl_api.cfg" \
  cargo test --workspace --profile "$profile" --features limpid-live/lsl,limpid-cli/lsl
echo "scripts/test.sh: Rust tests done after $(( $(date +%s) - start )) s"
target_dir="${CARGO_TARGET_DIR:-target}"
case "$target_dir" in /*) ;; *) target_dir="$PWD/$target_dir" ;; esac
# the Python tests read the same limpid-made examples as the Rust tests
export LIMPID_TEST_EXAMPLES="$target_dir/test-examples"
rm -rf "$LIMPID_TEST_EXAMPLES"
# (the writer was built by the test run, for limpid-testkit's own test: a
# separate `cargo build` would resolve features without the dev-dependencies
# and compile half the workspace again)
"$target_dir/$profile/limpid-test-examples" "$LIMPID_TEST_EXAMPLES"
venv="$target_dir/venv-test"
# h5py/hdf5storage, ezc3d and npTDMS write the lab-file versions of a recording (test_lab_formats.py),
# rosbags and mcap-ros2-support its ROS 2 bags (test_lab_bags.py);
# pandas, xarray, matplotlib, nbclient/nbformat/ipykernel: results in a notebook and the tutorial (test_notebook.py)
packages=(maturin numpy scipy pytest mypy "dask[distributed]"
  h5py hdf5storage ezc3d npTDMS rosbags mcap mcap-ros2-support pandas xarray matplotlib nbclient nbformat ipykernel)
# the environment is kept between runs while the package list and Python
# are the same, for at most a week (then made anew, with current releases):
# installing it takes about 50 s of every run
stamp="$(python3 --version) ${packages[*]}"
if [ -f "$venv/.limpid-packages" ] && [ "$(cat "$venv/.limpid-packages")" = "$stamp" ] \
  && [ -z "$(find "$venv/.limpid-packages" -mtime +7)" ] && "$venv/bin/python" -c "import numpy, scipy, pytest" 2>/dev/null; then
  echo "scripts/test.sh: reusing the Python environment $venv"
else
  python3 -m venv --clear "$venv"
  "$venv/bin/pip" install -q --disable-pip-version-check "${packages[@]}"
  echo "$stamp" > "$venv/.limpid-packages"
fi
echo "scripts/test.sh: Python environment ready after $(( $(date +%s) - start )) s"
rm -rf "$target_dir/wheels"
"$venv/bin/maturin" build --profile "$profile" -q -m crates/python/Cargo.toml -o "$target_dir/wheels"
"$venv/bin/pip" install -q --disable-pip-version-check --no-deps --force-reinstall "$target_dir"/wheels/limpid-*.whl
# the CLI the workspace tests built: the Python tests compare the requests both make
export LIMPID_CLI="$target_dir/$profile/limpid"
echo "scripts/test.sh: wheel installed after $(( $(date +%s) - start )) s"
LIMPID_REQUIRE_DASK=1 "$venv/bin/python" -m pytest -q -rs crates/python/tests
