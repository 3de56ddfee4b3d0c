"""Before the hand has slid, ``μ̂_h`` is only a lower bound of the hand friction (the largest ratio
``|f_t|/f_n`` seen sticking), and a hand slide planned on it may need less friction than the hand
has. The planner judges a hand slide as certain only where it keeps its margin at both ``μ̂_h`` and
:attr:`ccopt.planning.planner.PlannerParams.hand_friction_max`; elsewhere a hand slide is a probe of
the friction (``Step.explore``), which the ratios do not score as a commanded motion.

Judged by the simulator's truth: the paper triangle (μ_h 0.5) allows no hand slide with margin at
any tilt, yet with ``μ̂_h`` about 0.2 the estimated statics kept 1.5–7 N of margin for the slides
they planned; these ran as commanded motions and rolled the hand (ratios about 0). Here no goal's
hand slide is a commanded motion unless the true statics (an LP on the true object, at the true
configuration where it began) allow it.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from ccopt import statics
from ccopt.closed_loop import LoopParams, start_config
from ccopt.experiment import oracle_frame, run_experiment
from ccopt.modes import motion_of
from ccopt.objects import make_object
from ccopt.plant.mujoco_planar import HAND_ANGLE_RANGE
from ccopt.schedule import Schedule, exploration, reach


@pytest.mark.parametrize(("name", "offset_mm"), [("paper-triangle", 10.0), ("paper-triangle", -10.0),
                                                 ("paper-pentagon", 10.0)])
def test_no_hand_slide_the_truth_rules_out_is_a_commanded_motion(name: str, offset_mm: float) -> None:
    obj, params = make_object(name), LoopParams()
    goal = reach(s_h_mm=1e3 * start_config(obj, params).s_h + offset_mm)
    done = run_experiment(obj, Schedule("s_h", (*exploration(), goal)), params, seed=0)
    frame = oracle_frame(obj, params, HAND_ANGLE_RANGE)
    time = np.asarray(done.result.samples["time"])
    truth = np.asarray(done.result.samples["true_coordinates"])
    slides = [s for s in done.result.steps if s.goal is not None and s.kind == "slide_hand"]
    assert slides  # the goal tried the hand: the case this guards
    for step in slides:
        theta, s_h, _ = truth[min(int(np.searchsorted(time, step.start_time)), len(time) - 1)]
        motion = motion_of(step.kind, step.delta)
        truth_says = statics.best_wrench(frame.truth.statics, theta, s_h, motion, frame.lever, frame.forces)
        margin = truth_says.margin
        assert step.explore or margin >= 0.0, (math.degrees(theta), 1e3 * s_h, margin)
    result = done.summary["goals"][0]
    assert result["status"] != "reached" or result["oracle"]["reachable"]
