"""Before the kinematics are valid the controller pivots about the rough estimate of the ground
contact (:func:`ccopt.closed_loop.rough_lever`), not about the hand's own centre: judged by the
simulator's truth on an exploration whose hand starts far from the ground contact.

A 13.8 cm hexagon of 0.29 kg (one of the robustness study's random objects) with the hand 57 mm
along the face from the ground contact, where an experimenter's tour started it: with the paper's
naive ``v_θ`` (``s_h = 0``, ``d = 8 cm``) the exploration's four 7.2° pivots each turned the hand
2.1–3.1° against the object, on its edge.
"""

from __future__ import annotations

import dataclasses
import math

import numpy as np
import pytest

from ccopt import closed_loop, experiment
from ccopt.estimation import Estimator
from ccopt.objects import make_object
from ccopt.plant.base import StartConfig
from ccopt.schedule import Schedule, exploration

START = StartConfig(hand_face=0, theta_o=0.3, s_h=-0.0567)


@pytest.fixture(scope="module")
def run() -> experiment.Experiment:
    obj = make_object("hexagon", side=0.138, mass=0.29, mu_hand=0.47, mu_ground=0.84)
    params = closed_loop.LoopParams(start=START, centre_hand=False)
    return experiment.run_experiment(obj, Schedule("explore", exploration()), params, seed=4)


def test_the_exploration_pivots_keep_the_hand_flush(run):
    assert run.summary["status"] == "completed"
    assert run.summary["slip_events"] == []


def test_the_kinematics_become_valid_and_right(run):
    assert run.summary["kinematics_valid_share"] > 0.5
    assert run.summary["theta_err_deg"]["median"] < 1.0
    assert run.summary["s_h_err_mm"]["median"] < 3.0


def test_the_rough_lever_is_nan_until_both_are_known_to_a_centimetre_and_the_hand_is_off_centre():
    """From the estimate's own means and standard deviations (closed form): known to 1 cm, and
    ``|ŝ_h|`` beyond two of its standard deviations (else the naive ``s_h = 0`` is as good)."""
    estimate = Estimator().update(0.0, (0.0, 0.1, 0.2), (10.0, 0.0, 0.0))
    known = dataclasses.replace(
        estimate, kinematics_mean=(0.2, -0.05, 0.0, 0.12), kinematics_std=(0.01, 0.009, 0.02, 0.01)
    )
    assert closed_loop.rough_lever(known) == (-0.05, 0.12)
    for std in ((0.01, 0.011, 0.0, 0.01), (0.01, 0.005, 0.0, math.nan), (0.01, 0.005, 0.0, 0.02)):
        loose = dataclasses.replace(known, kinematics_std=std)
        assert all(np.isnan(closed_loop.rough_lever(loose)))
    centred = dataclasses.replace(known, kinematics_mean=(0.2, -0.017, 0.0, 0.12))
    assert all(np.isnan(closed_loop.rough_lever(centred)))  # 0.017 < 2 × 0.009
    off = dataclasses.replace(known, kinematics_mean=(0.2, 0.019, 0.0, 0.12))
    assert closed_loop.rough_lever(off) == (0.019, 0.12)
