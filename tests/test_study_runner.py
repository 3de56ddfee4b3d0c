"""The study runner: local processes, error rows, incremental trials.jsonl, a Dask cluster on loopback."""

import json
import threading
import time
from pathlib import Path

import numpy as np
import pytest

from studies import runner


def seeded_trial(spec):
    """A tiny deterministic trial: numbers drawn from the spec's seed."""
    if spec.get("fail"):
        raise ValueError(f"trial {spec['seed']} was asked to fail\nsecond line")
    rng = np.random.default_rng(spec["seed"])
    return {"mean": float(rng.normal(size=100).mean()), "draws": rng.integers(0, 1000, size=3).tolist()}


def waiting_trial(spec):
    """Returns at once, or once the file ``spec["wait_for"]`` exists (at most 60 s)."""
    flag = spec.get("wait_for")
    deadline = time.monotonic() + 60.0
    while flag and not Path(flag).exists() and time.monotonic() < deadline:
        time.sleep(0.02)
    return {"index": spec["index"], "waited": bool(flag)}


def counting_trial(spec):
    """How many finished trials the log already holds when this one starts."""
    log = Path(spec["log"])
    return {"seen": len(log.read_text().splitlines()) if log.exists() else 0}


SPECS = [{"seed": s} for s in runner.trial_seeds(3, 5)]


def test_seeds_are_distinct_and_reproducible():
    assert runner.trial_seeds(3, 5) == [spec["seed"] for spec in SPECS]
    assert len(set(runner.trial_seeds(3, 50))) == 50
    assert runner.trial_seeds(4, 5) != runner.trial_seeds(3, 5)


def test_one_and_two_workers_give_identical_results_in_spec_order():
    in_process = runner.run_trials(seeded_trial, SPECS, workers=1, progress=False)
    pooled = runner.run_trials(seeded_trial, SPECS, workers=2, progress=False)
    assert in_process == pooled
    assert in_process == [seeded_trial(spec) for spec in SPECS]


@pytest.mark.parametrize("workers", [1, 2])
def test_a_raising_trial_becomes_an_error_row(tmp_path, workers):
    specs = [SPECS[0], {**SPECS[1], "fail": True}, SPECS[2]]
    results = runner.run_trials(
        seeded_trial, specs, workers=workers, progress=False, log=tmp_path / "t.jsonl"
    )
    assert results[0] == seeded_trial(SPECS[0]) and results[2] == seeded_trial(SPECS[2])
    assert results[1] == {"error": f"ValueError: trial {SPECS[1]['seed']} was asked to fail second line"}
    assert runner.failures(results) == [(1, results[1]["error"])]
    logged = {record["index"]: record for record in runner.read_trials(tmp_path / "t.jsonl")}
    assert logged[1]["result"] == results[1] and logged[1]["spec"]["fail"] is True


def test_in_process_trials_are_logged_before_the_next_starts(tmp_path):
    log = tmp_path / "trials.jsonl"
    specs = [{"log": str(log), "k": k} for k in range(4)]
    results = runner.run_trials(counting_trial, specs, workers=1, progress=False, log=log)
    assert results == [{"seen": k} for k in range(4)]


def test_pooled_trials_are_logged_as_they_finish(tmp_path):
    log, flag = tmp_path / "trials.jsonl", tmp_path / "go"
    specs = [{"index": 0, "wait_for": str(flag)}, {"index": 1}]
    outcome = {}
    thread = threading.Thread(
        target=lambda: outcome.update(
            results=runner.run_trials(waiting_trial, specs, 2, progress=False, log=log)
        )
    )
    thread.start()
    try:
        deadline = time.monotonic() + 30.0
        while time.monotonic() < deadline and not (log.exists() and log.read_text().count("\n") >= 1):
            time.sleep(0.02)
        records = runner.read_trials(log)  # what an interrupted study would keep
        assert [r["index"] for r in records] == [1]
        assert records[0]["result"] == {"index": 1, "waited": False} and records[0]["seconds"] >= 0.0
        assert thread.is_alive()  # trial 0 still runs
    finally:
        flag.write_text("")
        thread.join(timeout=60.0)
    assert outcome["results"] == [{"index": 0, "waited": True}, {"index": 1, "waited": False}]
    assert sorted(r["index"] for r in runner.read_trials(log)) == [0, 1]


def test_write_results_tables_specs_and_results(tmp_path):
    specs = [{"seed": 1, "grid": (0.1, 0.2)}, {"seed": 2, "grid": (0.3,)}]
    results = [{"x": 1.5, "xs": [float("inf"), 2.0]}, {"error": "ValueError: no"}]
    runner.write_results(tmp_path, specs, results, {"total": np.float64(1.0)})
    saved = json.loads((tmp_path / "results.json").read_text())
    assert saved["summary"] == {"total": 1.0} and "SI" in saved["units"]
    assert saved["trials"][0] == {
        "spec": {"seed": 1, "grid": [0.1, 0.2]},
        "result": {"x": 1.5, "xs": [None, 2.0]},
    }
    lines = (tmp_path / "results.csv").read_text().splitlines()
    assert lines[0] == "seed,grid,x,xs,error"  # flat: a short list's items joined by ;
    assert lines[1] == "1,0.1;0.2,1.5,;2.0," and lines[2] == "2,0.3,,,ValueError: no"


def test_csv_rows_are_flat_nested_mappings_as_columns_and_long_series_left_to_the_json():
    row = {"a": {"b": 1, "c": {"d": [1, 2]}}, "trace": list(range(100)), "causes": ["x", "y"], "e": None}
    assert runner.csv_row(row) == {"a.b": 1, "a.c.d": "1;2", "causes": "x;y", "e": None}


def test_every_listed_study_imports_with_a_main_and_the_helpers_are_not_listed():
    import importlib

    from ccopt.cliutil import scripts

    found = scripts("studies")
    assert "runner" not in found and "__main__" not in found and len(found) >= 7
    for name, line in found.items():
        module = importlib.import_module(f"studies.{name}")
        assert callable(module.main) and module.__doc__.startswith(line) and line, name


def test_unreachable_scheduler_is_one_line_exit_2(tmp_path, capsys, monkeypatch):
    from studies import feasibility  # imported here: pool workers re-import this module, keep it light

    monkeypatch.setattr(runner, "SCHEDULER_TIMEOUT", "1s")
    argv = ["--out", str(tmp_path), "--mu-hand", "0.5", "--theta", "0", "--mu-ground", "0.8", "--mass", "0.2"]
    with pytest.raises(SystemExit) as exit_info:
        feasibility.main([*argv, "--no-progress", "--scheduler", "tcp://127.0.0.1:9"])
    assert exit_info.value.code == 2
    assert capsys.readouterr().err.count("\n") == 1


@pytest.fixture(scope="module")
def dask_cluster():
    """A Dask cluster on loopback: two worker processes, one thread each."""
    from distributed import LocalCluster

    with LocalCluster(
        n_workers=2, processes=True, threads_per_worker=1, host="127.0.0.1", dashboard_address=None
    ) as cluster:
        yield cluster


def test_dask_cluster_gives_the_local_numbers(tmp_path, dask_cluster):
    from studies import feasibility

    grid = ["--mu-hand", "0.3,0.8", "--theta=-10,0,10", "--mu-ground", "0.4,0.8", "--mass", "0.3"]
    common = [*grid, "--no-progress"]
    assert feasibility.main([*common, "--out", str(tmp_path / "local"), "--workers", "1"]) == 0
    scheduler = dask_cluster.scheduler_address
    assert feasibility.main([*common, "--out", str(tmp_path / "dask"), "--scheduler", scheduler]) == 0
    local, dask = (
        json.loads((tmp_path / k / "results.json").read_text())["trials"] for k in ("local", "dask")
    )
    assert len(local) == 2
    assert local == dask


def test_a_closed_loop_study_runs_on_a_dask_cluster_as_it_runs_locally(tmp_path, dask_cluster):
    """The robustness study's trials (closed-loop runs: plants, estimator, compiled QP) on the
    cluster's workers give the numbers of the same trials run in this process (the wall time aside)."""
    from studies import robustness

    common = ["--trials", "2", "--schedule", "smoke", "--seed", "3", "--no-progress"]
    assert robustness.main([*common, "--out", str(tmp_path / "local"), "--workers", "1"]) == 0
    scheduler = dask_cluster.scheduler_address
    assert robustness.main([*common, "--out", str(tmp_path / "dask"), "--scheduler", scheduler]) == 0
    local, dask = (
        [
            {**trial, "result": {k: v for k, v in trial["result"].items() if k != "wall_time_s"}}
            for trial in json.loads((tmp_path / k / "results.json").read_text())["trials"]
        ]
        for k in ("local", "dask")
    )
    assert len(local) == 2 and all(trial["result"]["fits_hand"] for trial in local)
    assert local == dask
