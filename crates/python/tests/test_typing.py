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


def test_user_code_sees_typed_result_fields(tmp_path):
    (tmp_path / "use.py").write_text(
        "import numpy as np\nimport limpid\n"
        "r = limpid.estimate_linear('rec.csv')\n"
        "k: np.ndarray = r.stiffness\n"
        "kind: str = r.kind\n"
        "n: int = r.kind\n"  # wrong on purpose: mypy must see the field's type
    )
    r = run("mypy", "--strict", "--no-incremental", "use.py", cwd=tmp_path)
    assert r.returncode == 1 and 'Incompatible types in assignment (expression has type "str", variable has type "int")' in r.stdout, r.stdout
    assert r.stdout.count("error:") == 1, r.stdout
