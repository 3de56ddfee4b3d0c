"""The faults study: each fault in closed loop, measured against the simulator's truth in its record;
run again into the same folder, it runs nothing."""

import json

import numpy as np
import pytest

from ccopt import record
from ccopt.hand import Hand
from studies import faults

FAULTS = "none,dead-ft,scale-ft:3"
QUICK = ["--quick", "--faults", FAULTS, "--start", "0.8", "--workers", "1", "--no-progress"]


@pytest.fixture(scope="module")
def study(tmp_path_factory):
    out = tmp_path_factory.mktemp("faults")
    code = faults.main([*QUICK, "--out", str(out)])
    return code, out, json.loads((out / "results.json").read_text())


def test_each_fault_is_one_recorded_trial(study):
    code, out, results = study
    assert code == 0 and (out / "results.csv").is_file()
    trials = results["trials"]
    assert [t["spec"]["fault"] for t in trials] == ["none", "dead-ft", "scale-ft:3.0"]
    assert {(t["spec"]["object"], t["spec"]["start"]) for t in trials} == {(faults.OBJECTS[0], 0.8)}
    for trial in trials:
        folder = out / "trials" / str(trial["spec"]["index"])
        assert trial["spec"]["folder"] == str(folder)
        assert record.load_record(folder).meta["status"] == trial["result"]["status"]
        assert all((folder / name).is_file() for name in faults.plots.FIGURES)


def test_the_figures_are_those_of_the_record(study):
    """Status, end and forces recomputed from each record's truth."""
    _, _, results = study
    limit = Hand().force_limits[1]
    for trial in results["trials"]:
        row, loaded = trial["result"], record.load_record(trial["spec"]["folder"])
        time, normal = loaded["time"], loaded["true_hand_wrench"][:, 0]
        assert row["ended_after_s"] == pytest.approx(loaded.summary["sim_time_s"] - 0.8, abs=1e-9)
        assert time[-1] == pytest.approx(0.8 + row["ended_after_s"], abs=0.011)
        assert row["peak_force_n"] == pytest.approx(normal[time >= 0.8].max())
        assert row["loads"] and row["plots"] and row["kept_all"] and row["kept_s"] == time[-1]
        assert time[-1] == pytest.approx(loaded.summary["sim_time_s"], abs=0.011)  # kept to the end
        assert row["force_ok"] == (row["over_limit_s"] <= 0.05) and row["peak_force_n"] < 1.2 * limit
    by_fault = {t["spec"]["fault"]: t["result"] for t in results["trials"]}
    assert by_fault["none"]["status"] == "completed"
    assert by_fault["dead-ft"]["status"] == "sensor_fault" and by_fault["dead-ft"]["ended_after_s"] < 0.2
    assert by_fault["scale-ft:3.0"]["status"] == "sensor_fault"
    dead = record.load_record(results["trials"][1]["spec"]["folder"])
    assert np.all(dead["hand_wrench"][dead["time"] >= 0.8] == 0.0)  # the fault acted from t_f
    passed = {"force_ok": 3, "ended_in_time": 3, "kept_all": 3, "loads": 3, "plots": 3}
    assert results["summary"]["passed"] == passed


def test_a_second_run_resumes_and_runs_nothing(study, capsys):
    _, out, results = study
    records = sorted(out.glob("trials/*/record.npz"))
    stamps = [path.stat().st_mtime_ns for path in records]
    assert faults.main([*QUICK, "--out", str(out)]) == 0
    assert "resuming: 3 of 3 trials already finished" in capsys.readouterr().err
    assert [path.stat().st_mtime_ns for path in records] == stamps
    assert json.loads((out / "results.json").read_text())["trials"] == results["trials"]


@pytest.mark.parametrize(
    ("flags", "longest"),
    [([], 0), ([0, 0], 0), ([1], 1), ([1, 1, 0, 1, 1, 1, 0], 3), ([0, 1, 1, 0, 1], 2), ([1, 1, 1, 1], 4)],
)
def test_longest_run(flags, longest):
    assert faults.longest_run(np.array(flags, dtype=bool)) == longest


def test_a_record_cut_short_is_not_data_kept():
    """The check the table's 'data kept' column shows: a trial whose record stops before the run's
    end (as a lost chunk would leave it) reads CUT, one measured before the column existed n/a."""
    assert faults.kept_cell({"kept_s": 2.9, "kept_all": True}) == "2.90 all"
    assert faults.kept_cell({"kept_s": 1.2, "kept_all": False}) == "1.20 CUT"
    assert faults.kept_cell({}) == "n/a"


@pytest.mark.parametrize(
    ("argv", "message"),
    [
        (["--faults", "warp"], "unknown sensor fault 'warp'"),
        (["--faults", "dropout:2"], "dropout probability must be in [0, 1]"),
        (["--faults", "dead-ft,"], "comma-separated"),
        (["--start", "nan"], "finite"),
        (["--start", "-1"], "at least 0 s"),
        (["--faults", "dead-ft@2"], "--faults 'dead-ft@2': give the faults' start with --start"),
        (["--objects", "blob"], "unknown object 'blob'"),
        (["--seed", "-2"], "'-2'"),
    ],
)
def test_bad_values_exit_2_with_one_line(tmp_path, capsys, argv, message):
    with pytest.raises(SystemExit) as ended:
        faults.main([*argv, "--out", str(tmp_path / "s")])
    assert ended.value.code == 2
    err = capsys.readouterr().err
    assert message in err and err.count("\n") == 1
    assert not (tmp_path / "s").exists()
