"""Goal steps in closed loop (planar plant, the paper triangle), judged by the simulator's truth and
by the experimenter's oracle (:func:`ccopt.planning.planner.oracle_plan` on the true statics).

One run serves every test: exploration, a tilt two pivots away, a ground slide (the planner tilts
first where it must), a hand slide that the triangle never allows (unreachable, by the oracle too),
a goal back to the start, and a goal with too little time (timeout).
"""

from __future__ import annotations

import json
import math

import numpy as np
import pytest

from ccopt import closed_loop, experiment
from ccopt.objects import make_object
from ccopt.planning.sequencer import GOAL_STATUSES
from ccopt.record import load_record
from ccopt.schedule import Goal, Schedule, exploration, reach

GOALS = (
    reach(theta_deg=31.6),
    reach(s_g_mm=10.0),
    reach(s_h_mm=12.0),
    reach(theta_deg=17.2, s_g_mm=0.0),
    Goal(theta_o=math.radians(2.8), timeout=0.2),
)


@pytest.fixture(scope="module")
def run(tmp_path_factory: pytest.TempPathFactory) -> experiment.Experiment:
    schedule = Schedule("goals", (*exploration(), *GOALS))
    folder = tmp_path_factory.mktemp("goals") / "run"
    return experiment.run_experiment(
        make_object("paper-triangle"), schedule, closed_loop.LoopParams(), seed=1, folder=folder
    )


@pytest.fixture(scope="module")
def data(run: experiment.Experiment) -> dict[str, np.ndarray]:
    return load_record(run.folder)


def truth_at(data: dict[str, np.ndarray], time: float) -> np.ndarray:
    index = min(int(np.searchsorted(np.asarray(data["time"]), time)), len(data["time"]) - 1)
    return np.asarray(data["true_coordinates"])[index]


def test_every_goal_has_an_entry_in_order_with_the_summary_keys(run: experiment.Experiment) -> None:
    goals = run.summary["goals"]
    assert [goal["index"] for goal in goals] == sorted(goal["index"] for goal in goals)
    assert len(goals) == run.summary["goals_total"] == len(GOALS)
    for goal in goals:
        assert goal["status"] in GOAL_STATUSES
        assert set(goal["targets"]) == {"theta_deg", "s_h_mm", "s_g_mm"}
        assert set(goal["true_error"]) == {"theta_deg", "s_h_mm", "s_g_mm"}
        assert goal["time_s"] >= 0.0 and goal["motions"] >= 0
    assert run.summary["goals_reached"] == sum(goal["status"] == "reached" for goal in goals)


def test_reached_goals_are_within_tolerance_by_the_simulators_truth(
    run: experiment.Experiment, data: dict[str, np.ndarray]
) -> None:
    goals = run.summary["goals"]
    origin = float(np.asarray(data["true_coordinates"])[0, 2])
    reached = [goal for goal in goals if goal["status"] == "reached"]
    assert len(reached) >= 3
    for goal in reached:
        true = truth_at(data, goal["end_time"])
        targets = goal["targets"]
        if targets["theta_deg"] is not None:
            error = math.degrees(true[0]) - targets["theta_deg"]
            assert abs(error) <= goal["tolerance_deg"]
            assert error == pytest.approx(goal["true_error"]["theta_deg"], abs=1e-6)
        if targets["s_g_mm"] is not None:
            error = (true[2] - origin) * 1e3 - targets["s_g_mm"]
            assert abs(error) <= goal["tolerance_mm"]
            assert error == pytest.approx(goal["true_error"]["s_g_mm"], abs=1e-6)
        assert goal["within_tolerance"]


def test_the_tilt_and_the_ground_slide_are_reached(run: experiment.Experiment) -> None:
    tilt, ground = run.summary["goals"][:2]
    assert tilt["status"] == "reached" and tilt["oracle"]["reachable"]
    assert ground["status"] == "reached" and ground["oracle"]["reachable"]
    ground_steps = [step for step in run.result.steps if step.goal == ground["index"]]
    assert any(step.kind == "slide_ground" and step.status == "reached" for step in ground_steps)


def test_a_hand_slide_the_object_never_allows_is_unreachable_with_the_oracles_agreement(
    run: experiment.Experiment,
) -> None:
    """The paper triangle's hand slides need ``|±d μ_h − s_h + M/f_n| ≤ l_h``, which its statics
    never meet within reach (the oracle on the true statics finds no sequence either)."""
    goal = run.summary["goals"][2]
    assert goal["oracle"]["reachable"] is False, goal["oracle"]
    assert goal["status"] == "unreachable"
    assert goal["reason"].startswith("s_h +12 mm")
    assert not goal["within_tolerance"]


def test_a_goal_without_time_times_out_and_the_run_goes_on(run: experiment.Experiment) -> None:
    goals = run.summary["goals"]
    assert goals[-1]["status"] == "timeout"
    assert not run.summary["completed"]  # a goal that timed out leaves the run incomplete


def test_the_goals_motions_keep_the_other_contacts_and_the_run_is_recorded(
    run: experiment.Experiment,
) -> None:
    assert run.summary["unintended_slips"] == 0
    folder = run.folder
    summary = json.loads((folder / "summary.json").read_text())
    assert [goal["status"] for goal in summary["goals"]] == [goal["status"] for goal in run.summary["goals"]]
    meta = json.loads((folder / "meta.json").read_text())
    assert sum(step["motion"] == "reach" for step in meta["schedule"]["steps"]) == len(GOALS)


def test_a_ground_slide_is_a_probe_until_the_ground_has_truly_slid(
    run: experiment.Experiment, data: dict[str, np.ndarray]
) -> None:
    """A goal's ground slide towards a side whose friction face is not known probes for it (it is not
    scored as a commanded motion): by truth, exactly those before the ground first slid (either way:
    the other side's face is then the mirror image of the one seen)."""
    slid = False
    probes = []
    for step in run.result.steps:
        if step.kind == "slide_ground" and step.goal is not None:
            probes.append(step.explore)
            assert step.explore == (not slid), step
        moved = truth_at(data, step.end_time)[2] - truth_at(data, step.start_time)[2]
        slid = slid or abs(moved) >= 2e-3
    assert probes[:1] == [True] and False in probes  # the first slide probes, a later one does not
