"""The exploration probes the hand's friction the way that leans least on the ground first, and the
other way only while the hand has not slid. Judged by the simulator's truth on a goals-study
triangle (0.41 kg, μ_h 0.61, μ_g 0.78) at the paper's start tilt, 17°.

A probe towards −s_h there pushes 48° from the vertical at the hand's friction limit, towards
+s_h 14° (:func:`ccopt.schedule.safer_probe_way`). Run in the exploration's old order (+3 mm,
then −3 mm), the second probe slid the ground 3.4 mm instead of the hand; the estimate read it as
the hand's slide, and the ``s_g`` goal after it was claimed reached 3.1 mm short by the truth.
"""

from __future__ import annotations

import numpy as np
import pytest

from ccopt.closed_loop import LoopParams
from ccopt.experiment import run_experiment
from ccopt.objects import from_vertices
from ccopt.schedule import Schedule, exploration, reach, safer_probe_way

VERTICES = [
    [-0.019262418998621474, 0.0329615918004118],
    [0.006245287651377846, -0.028845261528896347],
    [0.013017131347243655, -0.004116330271515457],
]
SEED = 1454127163
GOAL = reach(s_g_mm=10.0)


@pytest.fixture(scope="module")
def done():
    obj = from_vertices(np.array(VERTICES), 0.4141700626377701, 0.6097411597896223, 0.7805224763588156)
    return run_experiment(obj, Schedule("probe-order", (*exploration(), GOAL)), LoopParams(), seed=SEED)


def true_change(done, step, coordinate: int) -> float:
    """The true change of a coordinate (m) over a step."""
    samples = done.result.samples
    time, true = np.asarray(samples["time"]), np.asarray(samples["true_coordinates"])
    start, end = np.searchsorted(time, [step.start_time, step.end_time])
    return float(true[min(end, len(time) - 1), coordinate] - true[start, coordinate])


def test_the_hand_is_probed_the_safer_way_and_the_ground_never_slides(done) -> None:
    steps = [step for step in done.result.steps if step.goal is None]
    probes = [step for step in steps if step.kind == "slide_hand"]
    theta = float(np.asarray(done.result.samples["true_coordinates"])[0, 0])
    assert safer_probe_way(theta) == 1 and probes[0].delta > 0.0
    assert true_change(done, probes[0], 1) > 2e-3  # the hand slid: μ_h measured
    assert probes[1].status == "skipped" and probes[1].end_time == probes[1].start_time
    ground = [abs(true_change(done, step, 2)) for step in steps]
    assert max(ground) < 0.5e-3


def test_the_ground_goal_after_it_is_reached_by_truth(done) -> None:
    (goal,) = done.summary["goals"]
    assert goal["status"] == "reached", goal["reason"]
    assert goal["within_tolerance"], goal["true_error"]
    assert done.summary["unintended_slips"] == 0
