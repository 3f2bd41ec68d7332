"""Studies: limpid.study_run as `limpid study run`, and the same study spread
over processes (concurrent.futures) and over a dask LocalCluster of processes
with study_entries / study_process / study_combine — same tables."""
import concurrent.futures as cf
import importlib.util
import os
import pickle
import shutil
from pathlib import Path

import pytest

import limpid

from conftest import examples

SHARED = examples("cocontraction")
EXAMPLES = Path(__file__).resolve().parents[1] / "examples"


@pytest.fixture()
def manifest(tmp_path):
    rows = []
    for subject in ("1", "2"):
        for config in ("4", "7"):
            # each subject its own copy: a study refuses one file listed twice
            case = tmp_path / f"s{subject}_config{config}"
            shutil.copy(SHARED / f"ex_config{config}.csv", f"{case}.csv")
            shutil.copy(SHARED / f"ex_config{config}.mvc.csv", f"{case}.mvc.csv")
            rows.append(f'[[recording]]\nsubject = "{subject}"\nconfiguration = "{config}"\n'
                        f'file = "{case}.csv"\nmvc = "{case}.mvc.csv"\n')
    # a recording that is missing: listed as a failure, not an abort
    rows.append('[[recording]]\nsubject = "3"\nconfiguration = "4"\nfile = "gone.csv"\nmvc = "gone.mvc.csv"\n')
    path = tmp_path / "study.toml"
    path.write_text('[study]\nname = "two examples"\n\n' + "\n".join(rows))
    return path


def test_study_run_gives_the_tables_and_lists_the_failure(manifest, tmp_path):
    study = limpid.study_run(manifest, out=tmp_path / "tables")
    d = study.to_dict()
    assert d["kind"] == "study" and d["name"] == "two examples"
    assert len(d["recordings"]) == 4
    assert len(d["failures"]) == 1 and "gone.csv" in d["failures"][0]["file"]
    assert {row["configuration"] for row in d["levels"]} == {"4", "7"}
    # two identical subjects per configuration: the spread over subjects is zero
    row = d["levels"][0]
    assert row["subjects"] == 2 and abs(row["sd"]["kxx"]) < 1e-9 * abs(row["kxx"])
    for name in ("tables.csv", "rotation.csv", "study.json", "tables.md"):
        assert (tmp_path / "tables" / name).exists()
    # one full result per recording, none overwritten
    assert sorted(p.name for p in (tmp_path / "tables" / "recordings").iterdir()) == [
        "s1_c4.json", "s1_c7.json", "s2_c4.json", "s2_c7.json"]


def test_a_study_over_a_process_pool_equals_study_run(manifest):
    entries = limpid.study_entries(manifest)
    assert len(entries) == 5 and entries[0]["study"] == "two examples" and entries[0]["tolerance"] == 0.1
    with cf.ProcessPoolExecutor(2) as pool:
        outcomes = list(pool.map(limpid.study_process, entries))
    assert [o.ok for o in outcomes] == [True] * 4 + [False]
    assert "gone.csv" in outcomes[-1].error
    back = pickle.loads(pickle.dumps(outcomes[0]))
    assert back.ok and back.result().to_dict() == outcomes[0].result().to_dict()
    combined = limpid.study_combine(outcomes, name="two examples")
    assert combined.to_dict()["levels"] == limpid.study_run(manifest).to_dict()["levels"]
    with pytest.raises(ValueError, match="StudyOutcome"):
        limpid.study_combine([{"subject": "1"}])
    with pytest.raises(ValueError, match="no recording could be processed"):
        limpid.study_combine(outcomes[-1:])


def test_the_dask_example_on_a_local_cluster_of_processes(manifest, tmp_path):
    # scripts/test.sh (CI) installs dask and requires this test to run
    if os.environ.get("LIMPID_REQUIRE_DASK"):
        import dask.distributed as distributed
    else:
        distributed = pytest.importorskip("dask.distributed")
    spec = importlib.util.spec_from_file_location("study_dask", EXAMPLES / "study_dask.py")
    example = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(example)
    with distributed.LocalCluster(n_workers=2, threads_per_worker=1, processes=True, dashboard_address=None) as cluster, \
            distributed.Client(cluster) as client:
        study = example.run_study(str(manifest), str(tmp_path / "dask"), client)
    assert study.to_dict()["levels"] == limpid.study_run(manifest).to_dict()["levels"]
    assert len(study.to_dict()["failures"]) == 1
    assert (tmp_path / "dask" / "tables.csv").read_text() == (
        limpid.study_run(manifest, out=tmp_path / "local") and (tmp_path / "local" / "tables.csv").read_text())


def test_repeated_recordings_of_one_subject_and_configuration_keep_their_own_files(tmp_path):
    case = SHARED / "ex_config4"
    again = tmp_path / "again.csv"
    shutil.copy(f"{case}.csv", again)
    entry = '[[recording]]\nsubject = "1"\nconfiguration = "4"\nfile = "{}"\nmvc = "' + f"{case}.mvc.csv" + '"\n'
    path = tmp_path / "study.toml"
    path.write_text(entry.format(f"{case}.csv") + "\n" + entry.format(again))
    # the same file twice is refused: it would count as two recordings
    twice = tmp_path / "twice.toml"
    twice.write_text(entry.format(f"{case}.csv") + "\n" + entry.format(f"{case}.csv"))
    with pytest.raises(ValueError, match="name the same file"):
        limpid.study_run(twice)
    limpid.study_run(path, out=tmp_path / "t")
    assert sorted(p.name for p in (tmp_path / "t" / "recordings").iterdir()) == ["s1_c4.json", "s1_c4_2.json"]


def test_study_entries_carry_the_manifest_map_to_each_process(tmp_path):
    # the lab's CSV: its own column names, positions in mm
    import numpy as np
    src = limpid.read_recording(SHARED / "ex_config4.csv")
    mvc = limpid.read_recording(SHARED / "ex_config4.mvc.csv")

    def lab_csv(rec, path):
        names = {"x": "HandX_mm", "y": "HandY_mm", "z": "HandZ_mm"}
        cols = [(names.get(k, k), v * 1e3 if k in names else v) for k, v in rec.items()]
        header = ",".join(n for n, _ in cols)
        np.savetxt(path, np.column_stack([v for _, v in cols]), delimiter=",", header=header, comments="", fmt="%.17g")

    lab_csv(src, tmp_path / "s1.csv")
    lab_csv(mvc, tmp_path / "s1_mvc.csv")
    columns = "\n".join(f'{k} = {{ channel = "Hand{k.upper()}_mm", unit = "mm" }}' for k in "xyz")
    others = "\n".join(f'{k} = "{k}"' for k in src if k not in "xyz")
    (tmp_path / "rig.toml").write_text(f"[columns]\n{columns}\n{others}\n")
    path = tmp_path / "study.toml"
    path.write_text('[study]\nname = "lab csv"\nmap = "rig.toml"\n\n[[recording]]\nsubject = "1"\n'
                    'configuration = "4"\nfile = "s1.csv"\nmvc = "s1_mvc.csv"\n')
    entries = limpid.study_entries(path)
    assert entries[0]["map"] == str(tmp_path / "rig.toml")
    outcome = limpid.study_process(entries[0])
    direct = limpid.estimate_cocontraction(SHARED / "ex_config4.csv", SHARED / "ex_config4.mvc.csv").to_dict()
    assert outcome.ok, outcome.error
    levels = outcome.result().to_dict()["levels"]
    assert len(levels) == len(direct["levels"]) == 4
    for a, b in zip(levels, direct["levels"]):
        np.testing.assert_allclose(a["stiffness"], b["stiffness"], rtol=1e-9)
