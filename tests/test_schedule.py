"""Schedules: built-ins, files in degrees/millimetres, and clear errors."""

import dataclasses
import json
import math

import numpy as np
import pytest

from ccopt import geometry, schedule
from ccopt.modes import Motion
from ccopt.schedule import exploration, probe_as_run, safer_probe_way


def test_paper_schedule_explores_then_reaches_goals_both_ways_in_the_papers_increments():
    paper = schedule.load_schedule("paper")
    assert all(step.explore for step in paper.motions)
    assert paper.steps[: len(paper.motions)] == paper.motions
    goals = paper.goals
    assert len(goals) >= 10
    start = (17.2, 0.0, 0.0)  # degrees, mm, mm: the paper's start tilt, hand and ground at their origin
    increments = (7.2, 10.0, 10.0)
    for index, (base, increment) in enumerate(zip(start, increments, strict=True)):
        scale = np.rad2deg(1.0) if index == 0 else 1e3
        given = [goal.targets[index] * scale for goal in goals if goal.targets[index] is not None]
        multiples = (np.array(given) - base) / increment
        assert np.allclose(multiples, np.round(multiples), atol=1e-9), given
        assert min(multiples) <= -1 and max(multiples) >= 1, f"coordinate {index} visited one way only"
    assert all(np.allclose(goal.tolerances, [np.deg2rad(1.0), 0.002, 0.002]) for goal in goals)


def test_paper_script_explores_then_manipulates():
    paper = schedule.load_schedule("paper-script")
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


def test_goal_steps_read_in_degrees_and_millimetres_with_free_coordinates(tmp_path):
    path = tmp_path / "goals.yaml"
    path.write_text(
        "steps:\n"
        "  - {motion: explore}\n"
        "  - {motion: reach, theta_deg: 25}\n"
        "  - {motion: reach, s_h_mm: -8}\n"
        "  - {motion: reach, s_g_mm: 20}\n"
        "  - {motion: reach, theta_deg: 10, s_h_mm: 0, s_g_mm: 0, timeout_s: 90, tolerance_deg: 2,"
        " tolerance_mm: 3}\n"
    )
    loaded = schedule.load_schedule(path)
    goals = loaded.goals
    assert len(goals) == 4 and all(step.explore for step in loaded.motions)
    assert goals[0].targets == (pytest.approx(np.deg2rad(25)), None, None)
    assert goals[1].targets == (None, pytest.approx(-0.008), None)
    assert goals[2].targets == (None, None, pytest.approx(0.020))
    assert goals[0].tolerances == pytest.approx([np.deg2rad(1.0), 0.002, 0.002])
    assert goals[3].timeout == 90.0
    assert goals[3].tolerances == pytest.approx([np.deg2rad(2.0), 0.003, 0.003])
    again = tmp_path / "again.json"
    again.write_text(json.dumps(loaded.to_dict()))
    assert schedule.load_schedule(again).steps == loaded.steps


def test_a_goal_is_reached_within_its_tolerance_of_every_given_coordinate():
    goal = schedule.Goal(theta_o=0.3, s_g=0.01)
    origin = 0.05
    at = np.array([0.3 + np.deg2rad(0.9), 0.123, origin + 0.01 - 0.0019])
    assert goal.reached(at, origin)
    assert goal.errors(at, origin)[1] == 0.0
    assert not goal.reached(at + np.array([np.deg2rad(0.2), 0.0, 0.0]), origin)
    assert not goal.reached(at, origin + 0.0002)


@pytest.mark.parametrize(
    ("entry", "message"),
    [
        ("{motion: reach}", "at least one of"),
        ("{motion: reach, theta_deg: 200}", "theta_o"),
        ("{motion: reach, s_h_mm: .nan}", "finite"),
        ("{motion: reach, s_h_mm: 5, tolerance_mm: 0}", "length_tolerance"),
        ("{motion: reach, s_h_mm: 5, timeout_s: -1}", "timeout"),
        ("{motion: reach, s_h_mm: 5, speed: 2}", "unknown key"),
    ],
)
def test_bad_goal_steps_name_the_step_and_value(tmp_path, entry, message):
    path = tmp_path / "bad.yaml"
    path.write_text(f"steps:\n  - {entry}\n")
    with pytest.raises(ValueError, match=message) as error:
        schedule.load_schedule(path)
    assert "step 1" in str(error.value) or "steps[0]" in str(error.value) or "#1" in str(error.value)


def edge_lean(theta: float, way: int, mu_h: float) -> float:
    """rad from the vertical of the hand's push at its friction limit in a slide ``way`` in ``s_h``
    (the row that blocks it, :data:`ccopt.contact.hand_rows`, at zero: ``f_t = −way μ_h f_n``)."""
    force = geometry.hand_normal(theta) - way * mu_h * geometry.hand_tangent(theta)
    return math.atan2(abs(force[0]), -force[1])


@pytest.mark.parametrize("mu_h", [0.1, 0.5, 1.0])
def test_the_first_hand_slide_probe_leans_least_from_the_vertical(mu_h: float) -> None:
    for theta in np.radians(np.linspace(-40.0, 40.0, 33)):
        way = safer_probe_way(float(theta))
        assert edge_lean(theta, way, mu_h) <= edge_lean(theta, -way, mu_h) + 1e-12



def test_a_probe_runs_the_safer_way_first_then_the_other_only_while_the_hand_has_not_slid() -> None:
    pivot, plus, minus = exploration()[-3:]
    tilt = math.radians(-17.0)
    first = probe_as_run(plus, pivot, tilt, False)
    assert first.delta == minus.delta and first.kind == "slide_hand" and first.explore
    assert probe_as_run(minus, pivot, tilt, True).delta == minus.delta  # the first runs whatever slid
    assert probe_as_run(minus, first, tilt, False).delta == plus.delta  # the other way
    assert probe_as_run(minus, first, tilt, True) is None  # μ_h measured: skipped
    assert probe_as_run(plus, pivot, math.nan, False) == plus  # the tilt unknown: as given
    scripted = dataclasses.replace(minus, explore=False)
    assert probe_as_run(scripted, first, tilt, True) == scripted  # not a probe: as given
    assert probe_as_run(pivot, first, tilt, True) == pivot
