"""A hand that gives in a goal's ground slide, in closed loop, against the simulator's truth.

A goals-study quadrilateral (trial 20: μ_h 0.61, μ_g 0.51, 0.55 kg): its first ground slide towards
−s_g, tried at a 9.6° tilt, slides the hand 7–10 mm along the face instead. Taken as the ground's
slide (the rigid following), it moved ŝ_g 9.7 mm while the ground stayed, and the goal was claimed
reached 10 mm off (:class:`~ccopt.estimation.kinematics.KinematicsParams` ``hand_slide_height``).
"""

from __future__ import annotations

import numpy as np
import pytest

from ccopt.closed_loop import LoopParams
from ccopt.experiment import run_experiment
from ccopt.objects import from_vertices
from ccopt.schedule import Schedule, exploration, reach

QUADRILATERAL = dict(
    vertices=np.array(
        [
            [0.06092450841862059, 0.017956036744612703],
            [-0.054390586401792375, 0.02238871025425533],
            [-0.041529000312690106, -0.04263493914781402],
            [0.048413748457623536, -0.03672457489295697],
        ]
    ),
    mass=0.5524306686894425,
    mu_hand=0.61482827730131,
    mu_ground=0.5062465194007363,
)


@pytest.fixture(scope="module")
def run():
    schedule = Schedule("hand-gives", (*exploration(), reach(s_g_mm=-10.0)))
    obj = from_vertices(**QUADRILATERAL)
    return run_experiment(obj, schedule, LoopParams(plant="planar"), seed=2613302452)


def test_a_ground_slide_whose_hand_slides_instead_ends_slipped_and_the_estimate_follows_the_hand(run):
    result = run.result
    slipped = [step for step in result.steps if step.kind == "slide_ground" and step.status == "slipped"]
    assert slipped and slipped[0].reason == "the hand slid instead of the ground"
    data = result.samples
    time = np.asarray(data["time"])
    step = slipped[0]
    start, end = np.searchsorted(time, step.start_time), np.searchsorted(time, step.end_time)
    true = np.asarray(data["true_coordinates"])[end] - np.asarray(data["true_coordinates"])[start]
    estimated = np.asarray(data["est_coordinates"])[end] - np.asarray(data["est_coordinates"])[start]
    assert abs(true[1]) > 5e-3 and abs(true[2]) < 1e-3  # by truth: the hand slid, the ground stayed
    assert abs(estimated[1] - true[1]) < 1.5e-3 and abs(estimated[2] - true[2]) < 1.5e-3
    assert bool(np.asarray(data["est_kinematics_valid"])[end])
