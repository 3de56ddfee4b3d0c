"""Unintended slips in closed loop: the estimate follows the contact that really moved, against the
simulator's truth.

The object is a goals-study quadrilateral (0.57 kg, μ_h 0.45, μ_g 0.37) on which a hand slide back
(−3 mm at 17°, after the exploration) slides the *ground* instead: the forces keep the hand well
inside its measured friction cone while the ground contact gives. Read as the hand's slide (the
command), that left ŝ_h and ŝ_g 4–5 mm off for the rest of the run, and goals were reported reached
on them; followed as the ground's, the slip must not move the goals' ``s_g`` origin along with the
object. (It was the exploration's own probe back until the exploration probed the other way first,
:func:`ccopt.schedule.safer_probe_way`; a scripted slide does what it says.)
"""

from __future__ import annotations

import numpy as np
import pytest

from ccopt.closed_loop import LoopParams
from ccopt.experiment import run_experiment
from ccopt.objects import from_vertices
from ccopt.schedule import DEFAULT_TOLERANCE, Schedule, Step, exploration, reach

VERTICES = [
    [-0.006005421805984263, 0.0342507347788834],
    [-0.008760224045517058, -0.03600796683552202],
    [0.012475382288050573, -0.037700620324534556],
    [0.035739095546507914, -0.011854029656970445],
]
SEED = 3521360814


GOAL = reach(s_g_mm=-10.0)
BACK = Step("slide_hand", -3e-3, DEFAULT_TOLERANCE["slide_hand"], 3.0)
BACK_STEP = len(exploration())


@pytest.fixture(scope="module")
def done():
    obj = from_vertices(np.array(VERTICES), 0.5679544847191581, 0.44639667695066065, 0.3666416532076299)
    return run_experiment(obj, Schedule("slip", (*exploration(), BACK, GOAL)), LoopParams(), seed=SEED)


def test_a_ground_slip_in_a_hand_slide_is_followed_as_the_grounds(done) -> None:
    data = done.result.samples
    truth, estimate = data["true_coordinates"], data["est_coordinates"]
    probe = np.flatnonzero(data["step_index"] == BACK_STEP)
    moved = truth[probe[-1]] - truth[probe[0]]
    assert abs(moved[2]) > 2e-3 and abs(moved[1]) < 1e-3  # the case: the ground slid, the hand did not
    end = probe[-1] + 1
    assert done.result.steps[BACK_STEP].status == "slipped"  # ended, not pushed on: the ground stops
    later = np.searchsorted(data["time"], data["time"][end] + 0.3)
    assert abs(truth[later, 2] - truth[end, 2]) < 0.5e-3 and abs(moved[2]) < 10e-3  # it ran 58 mm
    assert bool(data["est_kinematics_valid"][end])
    error = estimate[end] - truth[end]
    assert abs(error[1]) <= 1.5e-3 and abs(error[2]) <= 1.5e-3, error


def test_the_goals_s_g_is_measured_from_where_the_ground_was_at_the_start(done) -> None:
    (goal,) = done.summary["goals"]
    assert goal["status"] == "reached"
    assert abs(goal["true_error"]["s_g_mm"]) <= 1e3 * GOAL.length_tolerance
