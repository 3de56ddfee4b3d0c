"""Studies resume: an interrupted study run again into the same folder runs only what is missing."""

import json
from pathlib import Path

import numpy as np
import pytest

from studies import runner


def logged_trial(spec):
    """Records every call in ``spec["calls"]``; stops the study (Ctrl-C) on the trial named in the
    file ``spec["stop"]`` if it exists; fails when asked to; else draws numbers from the seed."""
    calls, stop = Path(spec["calls"]), Path(spec["stop"])
    with open(calls, "a") as stream:
        stream.write(f"{spec['k']}\n")
    if stop.exists() and stop.read_text() == str(spec["k"]):
        raise KeyboardInterrupt
    if Path(spec["fail"]).exists() and spec["k"] == 1:
        raise ValueError("asked to fail")
    rng = np.random.default_rng(spec["seed"])
    return {"k": spec["k"], "mean": float(rng.normal(size=50).mean()), "none": float("nan")}


def make_specs(tmp_path, count=5):
    common = {name: str(tmp_path / name) for name in ("calls", "stop", "fail")}
    return [{"k": k, "seed": seed, **common} for k, seed in enumerate(runner.trial_seeds(1, count))]


def calls(tmp_path):
    path = tmp_path / "calls"
    return [int(line) for line in path.read_text().split()] if path.exists() else []


def study(out, specs, fresh=False, workers=1):
    options = runner.RunOptions(out=out, workers=workers, progress=False, fresh=fresh)
    return runner.run_study("study", logged_trial, specs, options)


def expected(specs):
    """The results of every trial computed directly, as a study stores them (JSON-ready)."""
    return [runner.json_ready(logged_trial({**spec, "calls": "/dev/null"})) for spec in specs]


def test_an_interrupted_study_reruns_only_its_unfinished_trials(tmp_path, capsys):
    specs, out = make_specs(tmp_path), tmp_path / "out"
    (tmp_path / "stop").write_text("2")
    with pytest.raises(SystemExit) as stopped:
        study(out, specs)
    assert stopped.value.code == 130 and calls(tmp_path) == [0, 1, 2]
    (tmp_path / "stop").unlink()
    results = study(out, specs)
    assert calls(tmp_path) == [0, 1, 2, 2, 3, 4]  # trials 0 and 1 were not run again
    assert results == expected(specs)
    assert "resuming: 2 of 5 trials already finished" in capsys.readouterr().err
    logged = runner.read_trials(out / runner.TRIALS_LOG)
    assert sorted(record["index"] for record in logged) == list(range(5))
    assert results == study(out, specs) and calls(tmp_path)[6:] == []  # all finished: nothing runs


def test_fresh_runs_every_trial_again(tmp_path):
    specs, out = make_specs(tmp_path, 3), tmp_path / "out"
    first = study(out, specs)
    args = runner.study_parser("demo", "", "fewer trials").parse_args(
        ["--out", str(out), "--workers", "1", "--fresh"]
    )
    options = runner.RunOptions.from_args(args)
    default = runner.RunOptions.from_args(runner.study_parser("demo", "", "fewer trials").parse_args([]))
    assert options.fresh and not default.fresh
    assert runner.run_study("study", logged_trial, specs, options) == first
    assert calls(tmp_path) == [0, 1, 2, 0, 1, 2]
    assert len(runner.read_trials(out / runner.TRIALS_LOG)) == 3


def test_error_rows_a_cut_log_and_other_specs_are_run_again(tmp_path):
    """A log written by a killed study: an error row, a row of a spec no longer asked for, trials
    finished out of order (a pool), a damaged line and a partial last line."""
    specs, out = make_specs(tmp_path), tmp_path / "out"
    (tmp_path / "fail").write_text("")
    study(out, specs[:4])
    (tmp_path / "fail").unlink()
    log = out / runner.TRIALS_LOG
    rows = runner.read_trials(log)
    assert rows[1]["result"] == {"error": "ValueError: asked to fail"}
    other = {**rows[0], "spec": {**rows[0]["spec"], "seed": 12345}}
    lines = [json.dumps(row) for row in (rows[3], rows[1], other, rows[0])]
    log.write_text("\n".join([*lines, "[1, 2]", "{not json", json.dumps(rows[2])[:-9]]))
    (tmp_path / "calls").unlink()
    results = study(out, specs)
    assert calls(tmp_path) == [1, 2, 4]
    assert results == expected(specs)
    assert [r["index"] for r in runner.read_trials(log)] == [0, 3, 1, 2, 4]


def test_finished_trials_match_by_spec_not_by_position(tmp_path):
    specs = make_specs(tmp_path, 3)
    records = [
        {"index": 0, "spec": runner.spec_dict(specs[2]), "result": {"x": 2}, "seconds": 0.1},
        {"index": 1, "spec": runner.spec_dict(specs[0]), "result": {"error": "E: no"}, "seconds": 0.1},
        {"index": 2, "spec": runner.spec_dict(specs[0]), "result": {"x": 0}, "seconds": 0.2},
        {"index": 3, "spec": runner.spec_dict(specs[0]), "result": {"error": "E: later"}, "seconds": 0.1},
    ]
    found = runner.finished_trials(records, specs)
    assert sorted(found) == [0, 2]
    assert found[0] == {**records[2], "index": 0} and found[2] == {**records[0], "index": 2}


def test_a_pooled_study_resumes_too(tmp_path):
    specs, out = make_specs(tmp_path, 4), tmp_path / "out"
    study(out, specs[:2])
    assert study(out, specs, workers=2) == expected(specs)
    assert sorted(calls(tmp_path)) == [0, 1, 2, 3]
