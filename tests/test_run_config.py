"""Run settings from flags and ``--config`` files: validated at the boundary (one line per bad value,
exit 2), written into ``meta.json``, and ``ccopt run --config RUN/meta.json`` repeats the run."""

import json

import numpy as np
import pytest

from ccopt import cli, config, record
from ccopt.closed_loop import LoopParams
from ccopt.hand import Hand

QUICK = ["--schedule", "smoke", "--max-sim-s", "1.2", "--no-figures", "--no-progress"]
CHANGED = [
    "--l-hand", "25",
    "--stiffness", "1800,1900,50",
    "--force-limits", "2,24",
    "--theta", "15",
    "--noise-force", "0.2",
    "--noise-angle", "0.05",
    "--convergence-rate", "9",
    "--normal-force", "9",
    "--seed", "7",
]  # fmt: skip


def test_flags_reach_the_run_in_si_and_a_meta_json_repeats_it_to_the_last_sample(tmp_path, capsys):
    first, again = tmp_path / "first", tmp_path / "again"
    assert cli.main(["run", *QUICK, *CHANGED, "--out", str(first)]) == 3  # the 1.2 s limit: timeout
    meta = record.load_record(first).meta
    params = meta["params"]
    assert params["hand"]["half_length"] == pytest.approx(0.025)
    assert params["hand"]["stiffness"] == [1800.0, 1900.0, 50.0]
    assert params["hand"]["force_limits"] == [2.0, 24.0]
    assert params["start"]["theta_o"] == pytest.approx(np.deg2rad(15.0))
    assert params["sensors"]["sigma_force"] == 0.2
    assert params["sensors"]["sigma_angle"] == pytest.approx(np.deg2rad(0.05))
    assert params["controller"]["convergence_rate"] == 9.0 and params["controller"]["normal_force"] == 9.0
    assert meta["seed"] == 7 and params["max_sim_s"] == 1.2 and "units" in meta
    assert cli.main(["run", "--config", str(first / "meta.json"), "--no-progress", "--out", str(again)]) == 3
    one, two = record.load_record(first), record.load_record(again)
    assert one.data.keys() == two.data.keys() and len(one.data["time"]) > 50
    for key in one.data:
        np.testing.assert_array_equal(one.data[key], two.data[key], err_msg=key)
    drop = ("wall_time_s",)
    assert {k: v for k, v in one.summary.items() if k not in drop} == {
        k: v for k, v in two.summary.items() if k not in drop
    }
    settings = {key: two.meta[key] for key in config.TOP_KEYS}
    assert settings == {key: meta[key] for key in config.TOP_KEYS}


def test_a_different_seed_gives_different_noise(tmp_path):
    a, b = tmp_path / "a", tmp_path / "b"
    cli.main(["run", *QUICK, "--max-sim-s", "0.3", "--out", str(a)])
    cli.main(["run", *QUICK, "--max-sim-s", "0.3", "--seed", "1", "--out", str(b)])
    assert not np.array_equal(record.load_record(a)["hand_wrench"], record.load_record(b)["hand_wrench"])


def test_a_settings_file_sets_what_it_names_and_flags_override_it(tmp_path):
    path = tmp_path / "run.yaml"
    path.write_text(
        "object: {name: paper-square, mass: 0.5}\n"
        "seed: 3\n"
        "params:\n"
        "  hand: {half_length: 0.02}\n"
        "  start: {hand_face: 1}\n"
        "  sensors: {faults: ['dropout:0.1@0.5']}\n"
    )
    args = cli.make_parser().parse_args(["run", "--config", str(path), "--mu-hand", "0.6", "--seed", "4"])
    run = config.build(*cli.run_settings(args))
    assert run.obj.name == "paper-square" and run.obj.mass == 0.5 and run.obj.mu_hand == 0.6
    assert run.seed == 4
    assert run.params.hand == Hand(half_length=0.02)
    default_start = LoopParams().start
    assert run.params.start.hand_face == 1 and run.params.start.theta_o == default_start.theta_o
    assert run.params.start.normal_force == default_start.normal_force
    (fault,) = run.params.sensor_params.faults
    assert (fault.kind, fault.value, fault.start) == ("dropout", 0.1, 0.5)


def test_every_bad_value_of_a_file_is_one_line_naming_it_and_exit_2(tmp_path, capsys):
    path = tmp_path / "bad.yaml"
    path.write_text(
        "object: paper-triangle\n"
        "colour: red\n"
        "params:\n"
        "  estimator_hz: 0\n"
        "  hand: {half_length: -0.01, stiffness: [1, 2]}\n"
        "  start: {theta_o: .nan, hand_face: 1.5}\n"
        "  controller: {convergence_rate: fast}\n"
        "  sensors: {sigma_force: -1, faults: [warp]}\n"
    )
    out = tmp_path / "run"
    with pytest.raises(SystemExit) as ended:
        cli.main(["run", "--config", str(path), "--no-progress", "--out", str(out)])
    assert ended.value.code == 2 and not out.exists()
    lines = capsys.readouterr().err.strip().splitlines()
    named = [
        "colour",
        "params.estimator_hz",
        "params.hand.half_length",
        "params.hand.stiffness",
        "params.start.theta_o",
        "params.start.hand_face",
        "params.sensors.sigma_force",
        "params.sensors.faults",
        "params.controller.convergence_rate",
    ]
    assert len(lines) == len(named), lines
    for name, line in zip(named, lines, strict=True):
        assert line.startswith(f"ccopt run: error: {name}: "), line


@pytest.mark.parametrize(
    ("args", "named"),
    [
        (["--l-hand", "-3"], "--l-hand -3"),
        (["--stiffness", "1,2"], "--stiffness"),
        (["--normal-force", "40"], "normal_force 40"),
        (["--face", "7"], "face"),
        (["--s-hand", "500"], "s_h"),
        (["--noise-angle", "nan"], "--noise-angle nan"),
    ],
)
def test_bad_flags_are_one_line_naming_them(tmp_path, capsys, args, named):
    with pytest.raises(SystemExit) as ended:
        cli.main(["run", *QUICK, *args, "--out", str(tmp_path / "run")])
    assert ended.value.code == 2
    lines = capsys.readouterr().err.strip().splitlines()
    assert len(lines) == 1 and named in lines[0], lines


def test_a_settings_file_that_is_not_a_mapping_is_one_line(tmp_path, capsys):
    path = tmp_path / "list.json"
    path.write_text(json.dumps([1, 2]))
    with pytest.raises(SystemExit):
        cli.main(["run", "--config", str(path), "--out", str(tmp_path / "run")])
    (line,) = capsys.readouterr().err.strip().splitlines()
    assert str(path) in line and "mapping" in line


HUGE = 10**400
"""An integer beyond the largest float (YAML and JSON read it exactly)."""


@pytest.mark.parametrize(
    ("path", "value"),
    [
        (("params", "estimator_hz"), HUGE),
        (("params", "max_sim_s"), HUGE),
        (("params", "hand", "half_length"), HUGE),
        (("params", "sensors", "sigma_force"), -HUGE),
        (("params", "controller", "normal_force"), HUGE),
        (("object", "mass"), HUGE),
        (("object", "vertices"), [[0, 0], [HUGE, 0], [0, 0.1]]),
        (("seed",), 10**4000),
    ],
    ids=lambda value: ".".join(value) if isinstance(value, tuple) else "",
)
def test_a_huge_integer_in_a_file_is_one_short_line_naming_it(tmp_path, capsys, path, value):
    """Never the ``OverflowError`` of ``float(10**400)``, nor a line of 4,000 digits (issue 12)."""
    settings: dict = {"schedule": "smoke", "object": {"name": "paper-triangle"}}
    node = settings
    for key in path[:-1]:
        node = node.setdefault(key, {})
    node[path[-1]] = value
    file = tmp_path / "huge.json"
    file.write_text(json.dumps(settings))
    out = tmp_path / "run"
    with pytest.raises(SystemExit) as ended:
        cli.main(["run", "--config", str(file), "--no-progress", "--out", str(out)])
    assert ended.value.code == 2 and not out.exists()
    captured = capsys.readouterr()
    lines = captured.err.strip().splitlines()
    assert len(lines) == 1 and "Traceback" not in captured.err, captured.err
    line = lines[0]
    assert line.startswith(f"ccopt run: error: {path[0]}") and path[-1] in line and len(line) < 300, line


@pytest.mark.parametrize("name", ["digits.yaml", "digits.json"])
def test_a_number_of_more_digits_than_python_reads_is_named_in_the_users_words(tmp_path, capsys, name):
    """Not Python's advice to call ``sys.set_int_max_str_digits()``."""
    file = tmp_path / name
    digits = "9" * 5000
    file.write_text(f"seed: {digits}" if name.endswith(".yaml") else f'{{"seed": {digits}}}')
    with pytest.raises(SystemExit) as ended:
        cli.main(["run", "--config", str(file), "--no-progress", "--out", str(tmp_path / "run")])
    assert ended.value.code == 2
    (line,) = capsys.readouterr().err.strip().splitlines()
    assert str(file) in line and "a number of over 4300 digits" in line and "sys." not in line, line
