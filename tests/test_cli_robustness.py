"""``ccopt run`` and ``ccopt plot`` on bad input, reused folders, faults and time limits: one line
naming the value, exit status 2 and no folder left behind; an ended run says how in its exit status."""

import json
import math
import shutil
import subprocess
import sys

import numpy as np
import pytest

from ccopt import cli, closed_loop, plots, record
from ccopt.estimation.estimator import Estimator
from studies import __main__ as studies_main

QUICK = ["--schedule", "smoke", "--no-figures", "--no-progress"]


def heptagon_mm(side: float) -> str:
    """A regular heptagon with faces of ``side`` mm, as ``--vertices`` takes it."""
    radius = side / (2.0 * math.sin(math.pi / 7))
    angles = [2 * math.pi * k / 7 for k in range(7)]
    return ";".join(f"{radius * math.cos(a):.4f},{radius * math.sin(a):.4f}" for a in angles)


def one_line_exit_2(capsys, call, *named):
    with pytest.raises(SystemExit) as ended:
        call()
    assert ended.value.code == 2
    captured = capsys.readouterr()
    lines = captured.err.strip().splitlines()
    assert len(lines) == 1 and "Traceback" not in captured.err, captured.err
    for name in named:
        assert name in lines[0], lines[0]
    return lines[0]


TRIANGLE = "0,0;100,0;0,100"


@pytest.mark.parametrize(
    ("args", "named"),
    [
        (["--mu-hand", "0"], ("--mu-hand", "positive", "0.0")),
        (["--mu-ground", "0"], ("--mu-ground", "0.0")),
        (["--mu-hand", "1e300"], ("mu_hand", "1e+300")),
        (["--seed", "-1"], ("--seed", "'-1'")),
        (["--seed", "1.5"], ("--seed", "'1.5'")),
        (["--estimator-hz", "1e-310"], ("--estimator-hz", "1e-310")),
        (["--estimator-hz", "5000"], ("--estimator-hz", "5000")),
        (["--controller-hz", "nan"], ("--controller-hz", "nan")),
        (["--vertices", "0,0;1e300,0;0,1e300"], ("1 cm to 1 m", "1.41e+297 m")),
        (["--vertices", "0,0;5,0;0,5"], ("1 cm to 1 m", "0.005 m")),
        (["--vertices", heptagon_mm(55.0)], ("0.055 m", "shorter than the hand", "no face of", "fits")),
        (["--vertices", "0,0;50,0;100,50;0,100"], ("face 0 of", "shorter", "faces 1, 2, 3 fit")),
        (["--vertices", TRIANGLE, "--added-mass", "-0.5"], ("--added-mass", "-0.5")),
        (["--added-mass", "inf"], ("--added-mass", "inf")),
        (["--mass", "nan"], ("--mass", "nan")),
        (["--mass", "1e300"], ("mass", "1e+300")),
        (["--max-sim-s", "nan"], ("--max-sim-s", "nan")),
        (["--max-sim-s", "-1"], ("--max-sim-s", "-1")),
        (["--max-sim-s", "1e300"], ("--max-sim-s", "1e+300")),
        (["--fault", "warp"], ("--fault", "'warp'")),
        (["--fault", "scale-ft:inf"], ("--fault", "inf")),
        (["--fault", "dropout:2"], ("--fault", "dropout:2")),
        (["--fault", "dead-ft@-1"], ("--fault", "dead-ft@-1")),
        (["--fault", "dead-ft:3"], ("--fault", "takes no value")),
    ],
)
def test_bad_values_are_one_line_exit_2_and_leave_no_folder(tmp_path, capsys, args, named):
    out = tmp_path / "new" / "run"
    one_line_exit_2(capsys, lambda: cli.main(["run", *QUICK, *args, "--out", str(out)]), *named)
    assert not (tmp_path / "new").exists()


@pytest.mark.parametrize(
    ("name", "content", "named"),
    [
        ("huge.yaml", f"steps: [{{motion: pivot, delta_deg: {10**400}}}]", "beyond 1.8e308"),
        ("digits.json", '{"steps": [{"motion": "pivot", "delta_deg": ' + "9" * 5000 + "}]}", "4300 digits"),
        ("digits.yaml", "steps: [{motion: pivot, delta_deg: " + "9" * 5000 + "}]", "over 4300 digits"),
        ("big.json", '{"steps": [{"motion": "pivot", "delta_deg": 1e200}]}', "at most 3.142 rad"),
        ("hold.json", '{"steps": [{"motion": "hold", "duration_s": 1e300}]}', "(0, 3600] s"),
        ("nan.json", '{"steps": [{"motion": "hold", "duration_s": NaN}]}', "finite"),
        ("mixed.yaml", "1: one\nsteps: [{motion: hold}]\n", "unknown schedule key(s): 1"),
        ("mixed_step.yaml", "steps: [{motion: hold, 2: x, speed: 1}]\n", "unknown key(s) 2, speed"),
        ("binary.yaml", bytes(range(256)), "not a text file"),
        ("long.yaml", f"steps: [{{motion: {'x' * 5000}}}]", "unknown motion 'xxx"),
        ("long_value.yaml", f"steps: [{{motion: hold, duration_s: {'9' * 4000}x}}]", "duration_s"),
    ],
)
def test_bad_schedule_files_name_the_file(tmp_path, capsys, name, content, named):
    path = tmp_path / name
    path.write_bytes(content if isinstance(content, bytes) else content.encode())
    out = tmp_path / "run"
    argv = ["run", "--no-figures", "--no-progress", "--schedule", str(path), "--out", str(out)]
    line = one_line_exit_2(capsys, lambda: cli.main(argv), named, str(path))
    assert len(line) < 300
    assert not out.exists()


@pytest.mark.parametrize(
    ("argv", "named"),
    [
        (["robustness", "--seed", "-1"], "'-1'"),
        (["paper", "--seed", str(2**64)], str(2**64)),
    ],
)
def test_studies_refuse_negative_seeds(tmp_path, capsys, argv, named):
    one_line_exit_2(capsys, lambda: studies_main.main([*argv, "--out", str(tmp_path / "s")]), "--seed", named)
    assert not (tmp_path / "s").exists()


def test_benchmarks_refuse_negative_seeds():
    result = subprocess.run(
        [sys.executable, "-m", "ccopt.cli", "bench", "qp_latency", "--quick", "--seed", "-3"],
        capture_output=True,
        text=True,
        timeout=120,
    )
    assert result.returncode == 2 and "Traceback" not in result.stderr
    assert result.stderr.count("\n") == 1 and "--seed" in result.stderr and "'-3'" in result.stderr


# --- folders --------------------------------------------------------------------------------------


def short_run(out, *args):
    """A run of 0.3 s of simulated time (status timeout, exit 3)."""
    return cli.main(["run", *QUICK, "--max-sim-s", "0.3", "--out", str(out), *args])


def test_a_used_folder_is_refused_unless_overwritten(tmp_path, capsys):
    out = tmp_path / "run"
    assert short_run(out) == 3
    first = record.load_record(out)
    capsys.readouterr()
    one_line_exit_2(capsys, lambda: short_run(out), str(out), "not empty")
    assert record.load_record(out).meta["run_id"] == first.meta["run_id"]
    assert short_run(out, "--seed", "7", "--overwrite") == 3
    second = record.load_record(out)
    assert second.meta["run_id"] != first.meta["run_id"] and second.meta["seed"] == 7
    assert len(second["time"]) == len(first["time"])  # the new run only, not both
    capsys.readouterr()
    (out / "notes.txt").write_text("mine")
    one_line_exit_2(capsys, lambda: short_run(out, "--overwrite"), "notes.txt", "not written by a run")
    assert (out / "notes.txt").read_text() == "mine" and (out / "meta.json").is_file()


@pytest.mark.parametrize("out", ["", "."])
def test_the_current_directory_is_no_run_folder(tmp_path, capsys, monkeypatch, out):
    monkeypatch.chdir(tmp_path)
    one_line_exit_2(capsys, lambda: short_run(out), f"output folder {out!r} is the current directory")
    assert list(tmp_path.iterdir()) == []


# --- faults and time limits -----------------------------------------------------------------------


def test_a_run_that_ends_without_reaching_its_steps_exits_3(tmp_path, capsys):
    """Issue 12's exit status: 3 when the run ended early, goals or steps not reached too. A pivot
    of 30° given 0.3 s ends 'timeout' (the loop's own verdict); the same schedule with the time to
    do it exits 0, so the check can tell them apart."""
    short, enough = tmp_path / "short.yaml", tmp_path / "enough.yaml"
    short.write_text("steps: [{motion: pivot, delta_deg: 30, timeout_s: 0.3}]\n")
    enough.write_text("steps: [{motion: pivot, delta_deg: 7.2, timeout_s: 8}]\n")
    common = ["run", "--no-figures", "--no-progress", "--schedule"]
    assert cli.main([*common, str(short), "--out", str(tmp_path / "a")]) == 3
    err = [line for line in capsys.readouterr().err.splitlines() if not line.startswith("warning:")]
    assert err == ["ccopt run: not done: 1 of 1 motion steps not reached (step 1 timeout)"]
    assert record.load_record(tmp_path / "a").meta["status"] == "completed"
    assert cli.main([*common, str(enough), "--out", str(tmp_path / "b")]) == 0
    assert "not done" not in capsys.readouterr().err


def test_a_fault_from_the_command_line_ends_the_run_as_a_sensor_fault(tmp_path, capsys):
    out = tmp_path / "run"
    code = cli.main(["run", *QUICK, "--fault", "dead-ft@0.5", "--fault", "spikes-ft:5", "--out", str(out)])
    err = capsys.readouterr().err
    assert code == 3 and "ccopt run: sensor_fault: " in err
    loaded = record.load_record(out)
    assert loaded.meta["status"] == "sensor_fault" and loaded.summary["status"] == "sensor_fault"
    assert 0.5 < loaded["time"][-1] < 1.0  # found within half a second of the fault's start
    measured = loaded["hand_wrench"]
    assert np.all(measured[loaded["time"] >= 0.5] == 0.0)  # the fault acted from 0.5 s on
    assert np.any(measured[loaded["time"] < 0.5] != 0.0)


def test_max_sim_s_ends_the_run_as_a_timeout(tmp_path, capsys):
    out = tmp_path / "run"
    assert short_run(out) == 3
    assert "ccopt run: timeout: " in capsys.readouterr().err
    loaded = record.load_record(out)
    assert loaded.meta["status"] == "timeout" and loaded["time"][-1] == pytest.approx(0.3, abs=0.011)


ERROR_RUN = """
import sys
from ccopt import cli
from ccopt.control.controller import Controller

def broken(self, *args, **kwargs):
    raise FloatingPointError("the solver returned NaN")

Controller.update = broken
sys.exit(cli.main(sys.argv[1:]))
"""


def test_an_exception_in_the_run_is_one_line_and_exit_1(tmp_path):
    out = tmp_path / "run"
    result = subprocess.run(
        [sys.executable, "-c", ERROR_RUN, "run", *QUICK, "--out", str(out)],
        capture_output=True,
        text=True,
        timeout=120,
    )
    assert result.returncode == 1 and "Traceback" not in result.stderr, result.stderr
    lines = [line for line in result.stderr.splitlines() if not line.startswith("warning:")]
    assert lines == ["ccopt run: error: FloatingPointError: the solver returned NaN"]
    meta = json.loads((out / "meta.json").read_text())
    assert meta["status"] == "error" and meta["message"] == "FloatingPointError: the solver returned NaN"


def test_an_exception_before_the_first_sample_keeps_the_record(tmp_path, capsys, monkeypatch):
    """The loop closes its record as ``error``, scored with nothing measured: one line, exit 1."""

    def broken(self, *args, **kwargs):
        raise FloatingPointError("the estimator overflowed")

    monkeypatch.setattr(Estimator, "update", broken)
    out = tmp_path / "run"
    assert cli.main(["run", *QUICK, "--out", str(out)]) == 1
    err = [line for line in capsys.readouterr().err.splitlines() if not line.startswith("warning:")]
    assert err == ["ccopt run: error: FloatingPointError: the estimator overflowed"]
    assert record.load_record(out).meta["status"] == "error"
    summary = json.loads((out / "summary.json").read_text())
    assert summary["status"] == "error" and summary["steps_done"] == 0


@pytest.mark.parametrize(
    ("error", "code"), [(ValueError("target pose must be finite"), 2), (RuntimeError("no C compiler"), 1)]
)
def test_a_run_that_cannot_start_leaves_no_folder(tmp_path, capsys, monkeypatch, error, code):
    def refuse(obj, params):
        raise error

    monkeypatch.setattr(closed_loop, "make_plant", refuse)
    out = tmp_path / "new" / "run"
    try:
        status = cli.main(["run", *QUICK, "--out", str(out)])
    except SystemExit as ended:  # bad input
        status = ended.code
    assert status == code
    err = [line for line in capsys.readouterr().err.splitlines() if not line.startswith("warning:")]
    assert len(err) == 1 and str(error) in err[0]
    assert not (tmp_path / "new").exists()


# --- plot -----------------------------------------------------------------------------------------


@pytest.fixture(scope="module")
def finished_folder(tmp_path_factory):
    out = tmp_path_factory.mktemp("plot") / "run"
    assert short_run(out) == 3
    return out


def damage(folder, how):
    if how == "truncated record":
        data = (folder / "record.npz").read_bytes()
        (folder / "record.npz").write_bytes(data[: len(data) // 2])
    elif how == "meta a list":
        (folder / "meta.json").write_text("[1, 2]")
    elif how == "truncated meta":
        text = (folder / "meta.json").read_text()
        (folder / "meta.json").write_text(text[: len(text) // 2])
    elif how == "a partial chunk only":
        (folder / "record.npz").unlink()
        (folder / record.CHUNKS / "chunk_00001.partial.npz").write_bytes(b"PK\x03\x04 half")
    elif how == "one key cut short":
        with np.load(folder / "record.npz") as archive:
            arrays = {key: archive[key] for key in archive.files}
        arrays["hand_pose"] = arrays["hand_pose"][:5]
        np.savez(folder / "record.npz", **arrays)


@pytest.mark.parametrize(
    ("how", "named"),
    [
        ("truncated record", "record.npz' is truncated"),
        ("meta a list", "holds a list"),
        ("truncated meta", "meta.json' is not readable JSON"),
        ("a partial chunk only", "holds no sample"),
        ("one key cut short", "'hand_pose' has 5 rows"),
    ],
)
def test_plot_of_a_damaged_folder_is_one_line_exit_2(tmp_path, capsys, finished_folder, how, named):
    folder = tmp_path / "run"
    shutil.copytree(finished_folder, folder)
    damage(folder, how)
    one_line_exit_2(capsys, lambda: cli.main(["plot", str(folder)]), named)
    assert not list(folder.glob("*.png")) and not list(folder.glob("*.gif"))


def test_a_figure_that_cannot_be_drawn_is_one_line_and_leaves_none(
    tmp_path, capsys, monkeypatch, finished_folder
):
    def broken(loaded):
        raise ValueError("Axis limits cannot be NaN or Inf")

    monkeypatch.setitem(plots.FIGURES, "control.png", broken)
    folder = tmp_path / "run"
    shutil.copytree(finished_folder, folder)
    assert cli.main(["plot", str(folder)]) == 1
    why = "ValueError: Axis limits cannot be NaN or Inf"
    line = f"ccopt plot: cannot draw the figures of {str(folder)!r}: {why}"
    assert capsys.readouterr().err.splitlines() == [line]
    assert not list(folder.glob("*.png")) and not list(folder.glob("*.gif"))
    out = tmp_path / "again"
    run = ["run", "--schedule", "smoke", "--no-progress", "--max-sim-s", "0.3", "--out", str(out)]
    assert cli.main(run) == 3  # the run's own exit status
    timeout, cannot = capsys.readouterr().err.splitlines()
    assert timeout.startswith("ccopt run: timeout: ")
    assert cannot.startswith("ccopt run: cannot draw the figures")
    assert record.load_record(out).meta["status"] == "timeout"
