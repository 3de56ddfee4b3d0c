"""A goal's pivot ends `rolled` only where the object truly stopped turning with the hand: judged
by the simulator's truth on a goals-study triangle (0.72 kg, μ_h 0.66, μ_g 0.74).

Its ground slides towards −s_g need a tilt of about −33°. The planner's slides tried on the way,
at tilts the true statics rule out, leave the hand's torque at its limit; the next pivot begins
there. The estimate's classifier holds a torque-limit report for its hold time after the last tight
sample, so a pivot that touched the limit for 0.04 s read as a hand rolling over the face's end for
the whole of the tracker's roll time: it ended `rolled` at −31° with the true hand flush and the
object turning, the planner cut its reach at −26°, and the goal was reported unreachable although
the experimenter's oracle reaches it.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from ccopt.closed_loop import LoopParams
from ccopt.experiment import run_experiment
from ccopt.objects import from_vertices
from ccopt.schedule import Schedule, exploration, reach

VERTICES = [
    [0.05064102339976676, 0.07522352389747823],
    [-0.06666979899555103, 0.02921318157846884],
    [0.04639458841317214, -0.05799999380926889],
]
SEED = 3685993406
GOAL = reach(s_g_mm=-10.0)


@pytest.fixture(scope="module")
def done():
    obj = from_vertices(np.array(VERTICES), 0.7193676428312162, 0.659286294411932, 0.7416691441480894)
    return run_experiment(obj, Schedule("pivots", (*exploration(), GOAL)), LoopParams(), seed=SEED)


def test_the_goal_the_oracle_reaches_is_reached_by_truth(done) -> None:
    (goal,) = done.summary["goals"]
    assert goal["oracle"]["reachable"]
    assert goal["status"] == "reached", goal["reason"]
    assert abs(goal["true_error"]["s_g_mm"]) <= 1e3 * GOAL.length_tolerance
    assert done.summary["unintended_slips"] == 0


def test_a_rolled_pivot_truly_stopped_turning_the_object(done) -> None:
    """Every goal pivot that ends `rolled`: by the truth, over its last 0.1 s the object turned less
    than half as far as the hand (it no longer follows it), and every other goal pivot turned the
    object at least 0.9 of its command."""
    data = done.result.samples
    time = np.asarray(data["time"])
    pivots = [step for step in done.result.steps if step.goal is not None and step.kind == "pivot"]
    assert len(pivots) >= 5  # the goal pivots down to the tilt of its slide
    for step in pivots:
        begin, end = (int(np.searchsorted(time, moment)) for moment in (step.start_time, step.end_time))
        end = min(end, len(time) - 1)
        theta = np.asarray(data["true_coordinates"])[:, 0]
        if step.status == "rolled":
            late = int(np.searchsorted(time, step.end_time - 0.1))
            hand = np.asarray(data["true_hand_pose"])[:, 2]
            assert abs(theta[end] - theta[late]) < 0.5 * abs(hand[end] - hand[late]), step
        else:
            turned = theta[end] - theta[begin]
            assert turned / step.delta >= 0.9, (step, math.degrees(turned))
