"""The package's annotations and stubs hold: mypy --strict finds nothing and
stubtest finds the compiled module as its stub describes it."""
import subprocess
import sys


def run(*args, cwd):
    return subprocess.run([sys.executable, "-m", *args], cwd=cwd, capture_output=True, text=True, timeout=600)


def test_mypy_strict_is_clean(tmp_path):
    r = run("mypy", "--strict", "--no-incremental", "-p", "limpid", cwd=tmp_path)
    assert r.returncode == 0, r.stdout + r.stderr


def test_stubtest_is_clean(tmp_path):
    r = run("mypy.stubtest", "limpid", cwd=tmp_path)
    assert r.returncode == 0, r.stdout + r.stderr
