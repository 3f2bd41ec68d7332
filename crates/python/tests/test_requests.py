"""The CLI and Python make the same request for the same settings: every
option of every method, set away from its default, and every default. The
CLI's request is what `--print-request` prints (LIMPID_CLI, set by
scripts/test.sh, names the binary)."""
import json
import os
import subprocess

import pytest

import limpid

CLI = os.environ.get("LIMPID_CLI")
SHOULDER = (0.3, 0.35, 90.0, 30.0, 45.0, 0.0)
CASES = [
    ("linear", ["estimate", "linear", "r.csv"], {}),
    ("linear",
     ["estimate", "linear", "r.csv", "--cutoff", "20", "--order", "2", "--derivative", "savgol",
      "--offsets", "fit", "--window", "trials", "--frame", "seed000",
      "--transform", "1,0,0,0,1,0,0,0,1,0.1,0,0", "--negate-force", "--robot", "kuka-lwr4",
      "--robot-base", "0.1,0.2,0.3", "--level", "1", "--no-equilibrium", "--vertical", "x",
      "--shoulder", ",".join(str(v) for v in SHOULDER), "--open-loop"],
     dict(cutoff_hz=20, order=2, derivative="savgol", offsets="fit", window="trials",
          frame="seed000", transform=[1, 0, 0, 0, 1, 0, 0, 0, 1, 0.1, 0, 0], negate_force=True,
          robot="kuka-lwr4", robot_base=(0.1, 0.2, 0.3), level=1, equilibrium=False,
          vertical="x", shoulder=SHOULDER, open_loop=True)),
    ("cocontraction", ["estimate", "cocontraction", "r.csv", "--mvc", "m.csv"], {}),
    ("cocontraction",
     ["estimate", "cocontraction", "r.csv", "--mvc", "m.csv", "--tolerance", "0.2", "--cutoff", "15",
      "--offsets", "rest"],
     dict(tolerance=0.2, cutoff_hz=15, offsets="rest")),
    ("planar", ["estimate", "planar", "r.csv", "--link-lengths", "0.3,0.35"],
     dict(link_lengths=(0.3, 0.35))),
    ("planar",
     ["estimate", "planar", "r.csv", "--link-lengths", "0.3,0.35", "--window-ms", "200",
      "--inertial-parameters", "0.3,0.1,0.1", "--elbow-negative", "--shoulder", "0.1,-0.2",
      "--cutoff", "25"],
     dict(link_lengths=(0.3, 0.35), window_ms=200, inertial_parameters=[0.3, 0.1, 0.1],
          elbow_negative=True, shoulder=(0.1, -0.2), cutoff_hz=25)),
    ("window_sweep", ["window-sweep", "r.csv", "--link-lengths", "0.3,0.35"],
     dict(link_lengths=(0.3, 0.35))),
    ("window_sweep",
     ["window-sweep", "r.csv", "--link-lengths", "0.3,0.35", "--from", "60", "--to", "300",
      "--step", "20", "--inertial-parameters", "0.3,0.1,0.1"],
     dict(link_lengths=(0.3, 0.35), from_ms=60, to_ms=300, step_ms=20,
          inertial_parameters=(0.3, 0.1, 0.1))),
    ("stochastic", ["estimate", "stochastic", "r.csv"], {}),
    ("stochastic",
     ["estimate", "stochastic", "r.csv", "--nfft", "1024", "--overlap", "256", "--window", "hamming",
      "--band", "1,8", "--expected", "t.json", "--shoulder", ",".join(str(v) for v in SHOULDER)],
     dict(nperseg=1024, noverlap=256, window="hamming", band_hz=(1, 8), expected="t.json",
          shoulder=SHOULDER)),
    ("reflex", ["estimate", "reflex", "r.csv"], {}),
    ("reflex",
     ["estimate", "reflex", "r.csv", "--position", "x", "--torque", "fx", "--rate", "200",
      "--intrinsic-lags", "0.05", "--reflex-lags", "0.8", "--max-delay", "0.1", "--rectify-after",
      "--open-loop", "--nonlinearity", "piecewise-linear"],
     dict(position="x", torque="fx", rate_hz=200, intrinsic_lags_s=0.05, reflex_lags_s=0.8,
          max_delay_s=0.1, rectify_first=False, open_loop=True, nonlinearity="piecewise_linear")),
    ("varying", ["estimate", "varying", "r.csv"], {}),
    ("varying",
     ["estimate", "varying", "r.csv", "--schedule", "sv", "--cutoff", "20", "--window-ms", "40",
      "--step", "10", "--min-repetitions", "12", "--grid", "11", "--order", "2", "--slow", "0.3",
      "--rate", "250", "--reflex", "--max-delay", "0.08", "--schedule-angle", "offset", "--open-loop"],
     dict(schedule="sv", cutoff_hz=20, window_ms=40, step_ms=10, min_repetitions=12, grid_points=11,
          basis_order=2, slow_hz=0.3, rate_hz=250, reflex=True, max_delay_s=0.08, schedule_angle="offset",
          open_loop=True)),
    ("varying",
     ["estimate", "varying", "r.csv", "--event", "fz>50", "--hysteresis", "5", "--refractory", "300",
      "--trigger", "pulse", "--method", "pulses", "--neighbours", "8", "--bin", "0.04",
      "--min-pulses", "6", "--pulse-window", "250", "--stance-end", "0.62"],
     dict(event="fz>50", hysteresis=5, refractory_ms=300, trigger="pulse", gait_method="pulses",
          neighbours=8, bin=0.04, min_pulses=6, pulse_window_ms=250, stance_end=0.62)),
    ("spectra", ["spectra", "r.csv", "--inputs", "ux", "--outputs", "x"], dict(inputs=["ux"], outputs=["x"])),
    ("spectra",
     ["spectra", "r.csv", "--inputs", "ux,uz", "--outputs", "x,z", "--nfft", "1024", "--overlap", "256",
      "--window", "boxcar"],
     dict(inputs=["ux", "uz"], outputs=["x", "z"], nperseg=1024, noverlap=256, window="boxcar")),
]
# what a method cannot run without (no default)
REQUIRED = ("link_lengths", "inputs", "outputs")


@pytest.mark.parametrize("method,args,options", CASES)
def test_cli_and_python_make_the_same_request(method, args, options):
    if not CLI:
        pytest.skip("LIMPID_CLI is not set (scripts/test.sh sets it)")
    out = subprocess.run([CLI, *args, "--print-request"], capture_output=True, text=True, timeout=60)
    assert out.returncode == 0, out.stderr
    assert json.loads(out.stdout) == limpid.request(method, **options)


def test_every_option_of_every_method_is_exercised():
    # the non-default cases above, together, set every field of their method's request
    # (varying's walking options cannot go with its parameter-varying ones: two cases)
    left: dict = {}
    for method, _, options in CASES:
        if all(k in REQUIRED for k in options):
            continue
        defaults = limpid.request(method, **{k: v for k, v in options.items() if k in REQUIRED})
        changed = limpid.request(method, **options)
        flat_default = {**defaults, **defaults.get("prepare", {}), **defaults.get("arm", {})}
        flat_changed = {**changed, **changed.get("prepare", {}), **changed.get("arm", {})}
        same = {k for k in flat_default if k not in ("prepare", "arm", "method", *REQUIRED)
                and flat_default[k] == flat_changed[k]}
        left[method] = left[method] & same if method in left else same
    for method in ("linear", "planar", "stochastic", "reflex", "varying", "spectra"):
        assert left[method] == set(), f"{method}: options left at their default: {sorted(left[method])}"


def test_bad_options_are_named():
    with pytest.raises(TypeError, match="cutof_hz"):
        limpid.estimate_linear("r.csv", cutof_hz=20)
    with pytest.raises(ValueError, match="band_hz"):
        limpid.request("stochastic", band_hz=(1,))
    with pytest.raises(ValueError, match="order"):
        limpid.request("linear", order=-1)
    with pytest.raises(ValueError, match="not a method"):
        limpid.request("fourier")
    # NaN is kept as NaN and refused by the check, not turned into a default
    with pytest.raises(ValueError, match="cutoff"):
        limpid.estimate_linear("r.csv", cutoff_hz=float("nan"))


def test_a_python_result_records_its_request_and_the_cli_reruns_it(tmp_path):
    from conftest import examples
    path = examples("ankle") / "ex_ankle.csv"
    result = limpid.estimate_reflex(path, rate_hz=200)
    d = result.to_dict()
    assert d["run"]["request"] == limpid.request("reflex", rate_hz=200)
    assert d["run"]["inputs"][0]["path"] == str(path)
    assert d["run"]["command_line"] == "Python: limpid.estimate_reflex"
    if not CLI:
        pytest.skip("LIMPID_CLI is not set (scripts/test.sh sets it)")
    saved = tmp_path / "reflex.json"
    saved.write_text(json.dumps(d))
    out = subprocess.run([CLI, "rerun", str(saved), "--json"], capture_output=True, text=True, timeout=300)
    assert out.returncode == 0, out.stderr
    again = json.loads(out.stdout)
    assert again["intrinsic"]["stiffness"] == d["intrinsic"]["stiffness"]
    assert again["run"]["request"] == d["run"]["request"]
