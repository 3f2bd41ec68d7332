"""Test data: the example recordings limpid's lab makes (scripts/test.sh writes
them with `cargo run -p limpid-testkit --bin limpid-test-examples -- DIR` and
sets LIMPID_TEST_EXAMPLES), and the optional real recordings (LIMPID_REAL_DATA)."""

import os
import pathlib

import pytest


def _folder(variable):
    value = os.environ.get(variable)
    return pathlib.Path(value) if value else None


EXAMPLES = _folder("LIMPID_TEST_EXAMPLES")
REAL = _folder("LIMPID_REAL_DATA")


def pytest_configure(config):
    if EXAMPLES is None or not (EXAMPLES / "cartesian_slow").is_dir():
        raise pytest.UsageError(
            "LIMPID_TEST_EXAMPLES must name the folder of limpid's example recordings: run "
            "scripts/test.sh, or `cargo run -p limpid-testkit --bin limpid-test-examples -- DIR` "
            "and set LIMPID_TEST_EXAMPLES=DIR")


def examples(family):
    """The limpid-made examples of `family` (cartesian_slow, cocontraction, planar, stochastic, ankle)."""
    return EXAMPLES / family


def real_data(sub):
    """Real recordings under LIMPID_REAL_DATA, or skip the test saying why."""
    if REAL is None:
        pytest.skip("LIMPID_REAL_DATA is not set")
    return REAL / sub
