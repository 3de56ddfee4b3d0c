"""Schedules: built-ins, files in degrees/millimetres, and clear errors."""

import json

import numpy as np
import pytest

from ccopt import schedule
from ccopt.modes import Motion


def test_paper_schedule_explores_then_manipulates():
    paper = schedule.load_schedule("paper")
    kinds = [step.kind for step in paper.steps]
    assert kinds[1:5] == ["slide_hand", "slide_hand", "pivot", "pivot"]
    assert {s.motion for s in paper.steps if s.kind == "slide_hand"} == {
        Motion.SLIDE_HAND_POS,
        Motion.SLIDE_HAND_NEG,
    }
    pivots = [abs(s.delta) for s in paper.steps if s.kind == "pivot"]
    assert np.allclose(pivots, np.deg2rad(7.2))
    assert all(abs(s.delta) == pytest.approx(0.010) for s in paper.steps if s.kind.startswith("slide"))


def test_smoke_schedule_pivots_both_ways():
    smoke = schedule.load_schedule("smoke")
    deltas = [s.delta for s in smoke.steps if s.kind == "pivot"]
    assert len(deltas) == 4 and sum(deltas) == pytest.approx(0.0) and min(deltas) < 0 < max(deltas)


def test_file_round_trip_in_degrees_and_millimetres(tmp_path):
    original = schedule.load_schedule("smoke")
    path = tmp_path / "s.json"
    path.write_text(json.dumps(original.to_dict()))
    loaded = schedule.load_schedule(path)
    assert loaded == schedule.Schedule("smoke", original.steps)


def test_yaml_file(tmp_path):
    path = tmp_path / "mine.yaml"
    path.write_text("steps:\n  - {motion: pivot, delta_deg: -5}\n  - {motion: slide_ground, delta_mm: 3}\n")
    loaded = schedule.load_schedule(path)
    assert loaded.name == "mine"
    assert loaded.steps[0].delta == pytest.approx(np.deg2rad(-5))
    assert loaded.steps[1].motion is Motion.SLIDE_GROUND_POS


@pytest.mark.parametrize(
    ("text", "message"),
    [
        ("steps: [{motion: twirl}]", "unknown motion 'twirl'"),
        ("steps: [{motion: pivot}]", "needs 'delta_deg'"),
        ("steps: [{motion: pivot, delta_deg: 0}]", "non-zero"),
        ("steps: [{motion: pivot, delta_deg: 5, speed: 2}]", "unknown key"),
        ("steps: [{motion: slide_hand, delta_mm: abc}]", "finite number"),
        ("steps: []", "no steps"),
        ("steps: [{motion: pivot, delta_deg: [", "malformed"),
        ("- 1\n- 2", "mapping"),
    ],
)
def test_malformed_files_name_the_problem(tmp_path, text, message):
    path = tmp_path / "bad.yaml"
    path.write_text(text)
    with pytest.raises(ValueError, match=message):
        schedule.load_schedule(path)


def test_unknown_names_and_missing_files():
    with pytest.raises(ValueError, match="not a built-in"):
        schedule.load_schedule("fancy")
    with pytest.raises(ValueError, match="cannot read"):
        schedule.load_schedule("/no/such/file.yaml")


def test_an_explore_step_expands_into_pivots_both_ways_and_friction_probes():
    explore = {"motion": "explore", "pivot_deg": 5.0, "probe_mm": 2.0}
    explored = schedule.schedule_from_dict({"steps": [explore]})
    kinds = [(step.kind, round(float(np.sign(step.delta)))) for step in explored.steps]
    pivots = [("pivot", 1), ("pivot", -1), ("pivot", 1), ("pivot", -1), ("pivot", -1), ("pivot", 1)]
    assert kinds == [*pivots, ("slide_hand", 1), ("slide_hand", -1)]
    turns = [abs(step.delta) for step in explored.steps if step.kind == "pivot"]
    assert turns[2:] == pytest.approx([np.deg2rad(5.0)] * 4)  # first a third of the way, then the whole
    assert turns[:2] == pytest.approx([np.deg2rad(5.0) / 3.0] * 2)
    assert all(step.explore for step in explored.steps)
    assert sum(step.delta for step in explored.steps if step.kind == "pivot") == pytest.approx(0.0)
    assert schedule.schedule_from_dict(explored.to_dict()).steps == explored.steps  # the file keeps the flag


def test_exploration_steps_are_not_scored():
    from ccopt import metrics

    data = {"time": np.array([0.0, 1.0]), "true_coordinates": np.array([[0.0, 0.0, 0.0], [0.0, 0.0, 0.0]])}
    probe = {"kind": "slide_hand", "delta": 0.003, "start_time": 0.0, "end_time": 1.0, "explore": True}
    assert metrics.realised_ratios(data, [probe]).size == 0
