"""The estimator on a closed-loop recording of a paper object, told the commanded configuration as
the loop will tell it, scored against the simulator's truth (the estimator never reads it).

The recording: the paper triangle on the planar plant pivoted ±7.2° five times with holds in between
(the hand flush and both contacts sticking throughout, by truth). Replayed sample by sample with the
configuration each step commands (:func:`ccopt.modes.configuration`); the true gravity moment comes
from the object's model (:func:`ccopt.statics.true_statics`), the true compliance from a fit of the
true hand tilt ``θ_h − θ_o`` against the true torque.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
import pytest

from ccopt import closed_loop, modes, statics
from ccopt.estimation import Estimate, Estimator
from ccopt.objects import make_object
from ccopt.schedule import Schedule, hold, pivot
from ccopt.statics import GravityMoment

OBJECT = "paper-triangle"
SCHEDULE = Schedule(
    "pivots",
    (
        hold(0.3),
        pivot(7.2),
        hold(0.3),
        pivot(-7.2),
        pivot(-7.2),
        hold(0.3),
        pivot(7.2),
        pivot(7.2),
        hold(0.3),
    ),
)
FIRST_VALID_LIMIT = math.radians(25.0)  # of cumulative pivoting (c, d, y_o confounded: .kinematics)
THETA_LIMIT = math.radians(0.3)
POSITION_LIMIT = 2e-3
MOMENT_LIMIT = 0.02  # N·m


@dataclass
class Replay:
    samples: dict[str, np.ndarray]
    estimates: list[Estimate]
    gravity: GravityMoment
    pivoted: np.ndarray  # cumulative |Δθ_o| so far (rad)

    @property
    def valid(self) -> np.ndarray:
        return np.array([e.kinematics_valid for e in self.estimates])


def commanded(code: int) -> modes.ContactConfiguration:
    """The configuration a step of record code ``code`` commands (a slide's direction is irrelevant
    to the kinematics: only which contact may move)."""
    return modes.configuration(modes.motion_of(modes.KINDS[code], 1.0))


@pytest.fixture(scope="module")
def replay() -> Replay:
    obj, params = make_object(OBJECT), closed_loop.LoopParams()
    samples = closed_loop.run(obj, SCHEDULE, params, seed=0).samples
    estimator = Estimator(params.hand, params.estimator_params)
    estimates = [
        estimator.update(time, pose, wrench, commanded(int(code)))
        for time, pose, wrench, code in zip(
            samples["time"], samples["hand_pose"], samples["hand_wrench"], samples["motion"], strict=True
        )
    ]
    gravity = statics.true_statics(obj, closed_loop.start_config(obj, params), params.hand).statics.gravity
    angles = samples["true_coordinates"][:, 0]
    pivoted = np.concatenate([[0.0], np.cumsum(np.abs(np.diff(angles)))])
    return Replay(samples, estimates, gravity, pivoted)


def test_the_recording_keeps_both_contacts_sticking(replay):
    true_modes = replay.samples["true_modes"]
    assert np.all(true_modes[:, [0, 2]] == 0)
    assert replay.pivoted[-1] > math.radians(30.0)


def test_the_kinematics_become_valid_and_are_accurate(replay):
    valid = replay.valid
    assert valid.any() and replay.pivoted[np.argmax(valid)] < FIRST_VALID_LIMIT
    after = np.arange(len(valid)) >= np.argmax(valid)
    assert valid[after].mean() > 0.95
    estimated = np.array([(e.theta_o, e.s_h, e.s_g, e.d) for e in replay.estimates])[valid]
    true = np.column_stack([replay.samples["true_coordinates"], replay.samples["true_d"]])[valid]
    median = np.median(np.abs(estimated - true), axis=0)
    assert median[0] < THETA_LIMIT and np.all(median[1:] < POSITION_LIMIT), median


def test_rough_kinematics_come_before_validity_within_their_uncertainty(replay):
    first_valid = int(np.argmax(replay.valid))
    one_pivot = int(np.argmax(replay.pivoted > math.radians(5.0)))  # valid within the first paced 7.2°
    assert one_pivot < first_valid
    estimate = replay.estimates[one_pivot]
    mean, std = np.array(estimate.kinematics_mean), np.array(estimate.kinematics_std)
    true = np.array([*replay.samples["true_coordinates"][one_pivot], replay.samples["true_d"][one_pivot]])
    assert np.all(np.isfinite(mean)) and np.all(np.abs(mean - true) < 3.0 * std), (mean - true, std)
    last = replay.estimates[-1]
    assert last.kinematics_mean == (last.theta_o, last.s_h, last.s_g, last.d)


def test_the_compliance_matches_the_true_tilt(replay):
    samples = replay.samples
    tilt = samples["true_hand_pose"][:, 2] - samples["true_coordinates"][:, 0]
    torque = samples["true_hand_wrench"][:, 2]
    true_compliance = float(tilt @ torque / (torque @ torque))
    last = replay.estimates[-1]
    assert abs(last.compliance - true_compliance) < max(3.0 * last.compliance_std, 0.005)


def test_the_gravity_moment_matches_the_object_over_the_visited_angles(replay):
    last = replay.estimates[-1].gravity
    assert last.valid
    angles = replay.samples["true_coordinates"][:, 0]
    for theta in np.linspace(angles.min(), angles.max(), 9):
        error = abs(last.moment(theta) - replay.gravity(theta))
        assert error < MOMENT_LIMIT and error < 3.0 * last.moment_std(theta), (math.degrees(theta), error)


def test_the_command_is_what_lets_the_kinematics_converge(replay):
    """Replayed without the command, the hand reports (the hand friction prior is far below the
    truth, so the hand "may slide" on most samples) release ``s_h`` and the kinematics come later."""
    samples = replay.samples
    estimator = Estimator()
    valid = [
        estimator.update(*sample).kinematics_valid
        for sample in zip(samples["time"], samples["hand_pose"], samples["hand_wrench"], strict=True)
    ]
    first = int(np.argmax(valid)) if any(valid) else len(valid)
    assert first > int(np.argmax(replay.valid))
