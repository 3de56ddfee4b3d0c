"""A hand that lets go of the object: the run stops, and says so, instead of going on about an object
it no longer knows (:class:`ccopt.closed_loop.Supervision`). Judged by the simulator's truth.

* **An object that fell out of the hand.** A goals-study triangle (seed 5, trial 6) slipped the
  ground 5.8 mm in a hand slide, and in the pivot after it the hand lost the object for 0.2 s: it
  fell onto another vertex (its start face turned 25°, its ground contact moved 78 mm). The hand
  found it again, the exploration ran anew, and the last goal was reported reached with the start
  face 70° and the ground contact 38 mm from its targets.
* **A knock the loop rides out.** A 13 N push on the paper triangle lifts it off the hand for
  90 ms, well within the grace; the object is back where it was.
"""

from __future__ import annotations

import math
import re

import numpy as np
import pytest

from ccopt import closed_loop
from ccopt.closed_loop import LoopParams, Perturbation, Supervision
from ccopt.experiment import Experiment, run_experiment
from ccopt.metrics import sample_at
from ccopt.objects import from_vertices, make_object
from ccopt.schedule import Schedule, Step, exploration, reach

FALLEN_DEG, FALLEN_MM = 10.0, 10.0
"""Truth of a fall: the start face turned, or the ground contact moved, at least this much."""
LONG_LOSS = 0.12
"""The case's loss of contact is at least this long (s), by the truth."""


def off_the_object(data: dict, join: float = 0.03) -> list[tuple[float, float]]:
    """``(start, end)`` times (s) of the stretches where, by the truth, the hand does not touch the
    object, stretches less than ``join`` apart counted as one."""
    time, off = np.asarray(data["time"]), ~np.asarray(data["true_contacts"])[:, 0]
    edges = np.flatnonzero(np.diff(np.concatenate([[0], off.astype(int), [0]])))
    spans: list[tuple[float, float]] = []
    for a, b in zip(edges[::2], edges[1::2], strict=True):
        start, end = float(time[a]), float(time[min(b, len(time) - 1)])
        if spans and start - spans[-1][1] < join:
            start = spans.pop()[0]
        spans.append((start, end))
    return spans


@pytest.fixture(scope="module")
def fell() -> Experiment:
    vertices = [[-0.05248672102762314, 0.0272535523881538], [-0.04025331310816739, -0.04875067230505241],
                [0.04768339939016776, -0.01100091065257134]]
    obj = from_vertices(np.array(vertices), 0.40510829428753925, 0.6578055489965325, 0.5000597302745368)
    goals = (reach(s_h_mm=10.0), reach(s_h_mm=10.0), reach(s_h_mm=10.0), reach(theta_deg=9.99, s_g_mm=-10.0))
    return run_experiment(obj, Schedule("fell", (*exploration(), *goals)), LoopParams(), seed=456984185)


def test_an_object_the_hand_let_go_of_ends_the_run(fell) -> None:
    """The case: by the truth the object fell while the hand was off it for 0.12 s or more. The
    run ends ``contact_lost`` at the end of that loss, naming it, and no goal is reported reached
    after it began."""
    result, summary = fell.result, fell.summary
    data = result.samples
    time, truth = np.asarray(data["time"]), np.asarray(data["true_coordinates"])
    long = [(a, b) for a, b in off_the_object(data) if b - a >= LONG_LOSS]
    assert long, "the hand was never off the object that long"
    start, end = long[0]
    before, after = truth[sample_at(data, start) - 1], truth[-1]
    turned, moved = math.degrees(abs(after[0] - before[0])), 1e3 * abs(after[2] - before[2])
    assert turned > FALLEN_DEG or moved > FALLEN_MM, (turned, moved)
    assert result.status == "contact_lost", result.message
    reported = float(re.search(r"t = ([0-9.]+) s", result.message).group(1))
    assert abs(reported - start) <= 0.05 and time[-1] <= end + 0.1, (reported, start, end, time[-1])
    for goal in summary["goals"]:
        assert goal["status"] != "reached" or goal["end_time"] < start, goal


def test_a_knock_shorter_than_the_grace_is_ridden_out() -> None:
    """The case: a push lifts the object off the hand for longer than a dropout (50 ms) and shorter
    than the grace. The run completes, with the object turned back within a degree of where it
    was held (truth)."""
    push = Perturbation(0.5, (13.0, 0.0), 0.15)
    hold = Step("pivot", 1e-9, 1e-12, 2.0)  # holds θ_o where it begins
    result = closed_loop.run(
        make_object("paper-triangle"), Schedule("hold", (hold,)), LoopParams(perturbations=(push,)), seed=0
    )
    data = result.samples
    truth = np.asarray(data["true_coordinates"])
    assert 0.05 <= max(b - a for a, b in off_the_object(data)) < Supervision().contact_grace
    assert result.status == "completed"
    assert math.degrees(abs(truth[-1, 0] - truth[sample_at(data, 0.5) - 1, 0])) < 1.0
