"""Results that travel between processes, fork safety and refused options (issue 21)."""

import concurrent.futures
import copy
import multiprocessing
import pathlib
import pickle

import numpy as np
import pytest

import limpid

from conftest import examples

LINEAR = examples("cartesian_slow") / "ex_cubic.csv"


def _stiffness_of(path):
    """Worker: estimate in a child process, return the whole Result."""
    return limpid.estimate_linear(str(path))


@pytest.fixture(scope="module")
def result():
    return limpid.estimate_linear(str(LINEAR))


def test_results_pickle_and_copy_round_trip(result):
    back = pickle.loads(pickle.dumps(result))
    assert back == result
    np.testing.assert_array_equal(back.stiffness, result.stiffness)
    assert copy.copy(result) == result
    deep = copy.deepcopy(result)
    assert deep == result and deep.to_dict() is not result.to_dict()
    # to_dict is a copy: changing it leaves the result alone
    d = result.to_dict()
    d["stiffness"] = None
    assert result.stiffness is not None and result.to_dict()["stiffness"] is not None
    again = limpid.Result.from_dict(result.to_dict())
    assert again == result
    with pytest.raises(AttributeError):
        result.no_such_field
    with pytest.raises(KeyError):
        result["no_such_field"]


def test_results_come_back_from_a_process_pool(result):
    # spawn: results are pickled both ways (the fork case is the test below, which can time out)
    ctx = multiprocessing.get_context("spawn")
    with concurrent.futures.ProcessPoolExecutor(max_workers=2, mp_context=ctx) as pool:
        got = list(pool.map(_stiffness_of, [LINEAR, LINEAR]))
    for r in got:
        np.testing.assert_allclose(r.stiffness, result.stiffness, rtol=1e-12)


def _child(path, queue):
    queue.put(limpid.estimate_linear(str(path)).stiffness.tolist())


def _forked_stiffness(path):
    """The stiffness a forked child estimates from `path` (it must not hang)."""
    ctx = multiprocessing.get_context("fork")
    queue = ctx.Queue()
    child = ctx.Process(target=_child, args=(path, queue))
    child.start()
    child.join(timeout=60)
    alive = child.is_alive()
    if alive:
        child.kill()
    assert not alive, "the forked child hung"
    assert child.exitcode == 0
    return queue.get(timeout=5)


def test_a_forked_child_finishes_after_the_parent_estimated(result):
    # the parent has used the thread pool (fixture); a forked child that uses it must not hang
    np.testing.assert_allclose(_forked_stiffness(LINEAR), result.stiffness, rtol=1e-12)


def test_a_forked_child_reads_parquet_after_the_parent_did(tmp_path):
    # the Parquet reader decodes columns in parallel: in the package's pool,
    # never in rayon's global one, which a forked child inherits without threads
    import os
    import subprocess
    cli = os.environ.get("LIMPID_CLI")
    if not cli:
        pytest.skip("LIMPID_CLI is not set (scripts/test.sh sets it)")
    parquet = tmp_path / "cubic.parquet"
    subprocess.run([cli, "convert", str(LINEAR), "-o", str(parquet)], check=True,
                   stdout=subprocess.PIPE, stderr=subprocess.PIPE)
    expected = limpid.estimate_linear(str(parquet)).stiffness
    np.testing.assert_allclose(_forked_stiffness(parquet), expected, rtol=1e-12)


@pytest.mark.parametrize("kwargs", [
    {"order": 4.5}, {"order": "4"}, {"order": True}, {"order": 0},
    {"cutoff_hz": "10"}, {"cutoff_hz": float("nan")}, {"negate_force": 1},
    {"equilibrium": "yes"}, {"offsets": "mean"}, {"window": 3},
])
def test_bad_options_are_refused_with_value_error(kwargs):
    with pytest.raises(ValueError):
        limpid.estimate_linear(str(LINEAR), **kwargs)


def test_numpy_and_integral_options_are_taken(result):
    a = limpid.estimate_linear(str(LINEAR), order=np.int64(4), cutoff_hz=np.float64(30.0))
    b = limpid.estimate_linear(str(LINEAR), order=4.0, cutoff_hz=30)
    np.testing.assert_allclose(a.stiffness, b.stiffness, rtol=1e-12)
    # a different order is used, not dropped
    c = limpid.estimate_linear(str(LINEAR), order=2)
    assert not np.allclose(c.stiffness, a.stiffness, rtol=1e-9)


def test_filter_order_must_be_a_whole_number():
    x = np.sin(np.linspace(0, 20, 2000))
    with pytest.raises(ValueError):
        limpid.lowpass_filtfilt(x, 10.0, 500.0, order=4.5)
    with pytest.raises(ValueError):
        limpid.lowpass_filtfilt(x, "10", 500.0)
