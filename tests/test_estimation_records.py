"""The estimator's per-sample objects, made by :func:`ccopt.estimation.records.record` without a check,
(the estimate, the kinematics' estimate, the ground cone) hold every field of their dataclasses and
equal the instances their ``__init__`` makes."""

from __future__ import annotations

import dataclasses

import pytest

from ccopt.estimation import Estimate, Estimator
from ccopt.estimation.kinematics import KinematicEstimate
from ccopt.estimation.records import record
from tests.test_estimator import synthetic_run


def _same_as_constructed(instance: object) -> None:
    kind = type(instance)
    assert set(vars(instance)) == {field.name for field in dataclasses.fields(kind)}
    assert instance == kind(**vars(instance))


def test_a_record_is_its_fields_and_frozen():
    fields = {"determined": False, "mu_g": 0.5, "apex": 3.0, "spread": 1.0, "scatter": 0.1}
    made = record(dataclasses.make_dataclass("Face", list(fields), frozen=True), fields)
    assert vars(made) == fields
    with pytest.raises(dataclasses.FrozenInstanceError):
        made.mu_g = 0.6


def test_every_estimate_kinematic_estimate_and_ground_cone_holds_every_field():
    run = synthetic_run(0)
    estimator = Estimator()
    kinematics: list[KinematicEstimate] = []
    update = estimator.kinematics.update
    estimator.kinematics.update = lambda *args: kinematics.append(update(*args)) or kinematics[-1]
    estimates = [
        estimator.update(time, pose, wrench)
        for time, pose, wrench in zip(run.times[::50], run.poses[::50], run.wrenches[::50], strict=True)
    ]
    for made in (estimates[0], estimates[-1], *kinematics[:1], *kinematics[-1:], estimator.ground.cone):
        _same_as_constructed(made)
    assert all(type(estimate) is Estimate for estimate in estimates)
