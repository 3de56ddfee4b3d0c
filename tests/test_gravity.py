"""The gravity moment estimator on wrenches of a known object in equilibrium (paper eq. 1, §7 of
docs/architecture.md): ``τ + s_h f_n − d f_t + M(θ_o) = 0``."""

from __future__ import annotations

import dataclasses
import math

import numpy as np
import pytest

from ccopt import geometry
from ccopt.estimation.gravity import (
    UNKNOWN,
    GravityEstimate,
    GravityEstimator,
    GravityParams,
    flush_hand_position,
    flush_moment,
)
from ccopt.estimation.kinematics import KinematicEstimate
from ccopt.statics import GravityMoment

TRUE = GravityMoment(cos_coefficient=-0.12, sin_coefficient=0.25)  # N·m
R_O, D, S_H = np.array([0.10, 0.0]), 0.08, 0.01
POSE_NOISE = np.array([2e-4, 2e-4, math.radians(0.1)])
WRENCH_NOISE = np.array([0.3, 0.3, 0.005])
SAMPLES = 1000


def samples(rng: np.random.Generator, r_o: np.ndarray = R_O, count: int = SAMPLES):
    """``(θ_o, measured hand pose, measured wrench)`` of a flush hand pressing the object in
    equilibrium on ``r_o``, turning it through ±10° with varying normal and tangential forces."""
    for k in range(count):
        theta = math.radians(10.0) * math.sin(2.0 * math.pi * k / count)
        f_n, f_t = 14.0 + 5.0 * math.sin(k / 37.0), 3.0 * math.sin(k / 23.0)
        torque = -TRUE(theta) - S_H * f_n + D * f_t
        pose = geometry.hand_pose_from_contact(theta, S_H, D, r_o) + rng.normal(0.0, POSE_NOISE)
        wrench = np.array([f_n, f_t, torque]) + rng.normal(0.0, WRENCH_NOISE)
        yield theta, pose.tolist(), wrench.tolist()


def contact(r_o: np.ndarray = R_O, std: float = 0.0) -> tuple[float, float, float, float, float]:
    return (float(r_o[0]), float(r_o[1]), std**2, 0.0, std**2)


def add(estimator: GravityEstimator, theta: float, pose: list[float], wrench: list[float]) -> None:
    """One sample on a fixed ground contact not yet located (so not gated against ``M̂``)."""
    estimator.update(theta, pose, wrench, UNLOCATED, contact())


def fed(rng: np.random.Generator, **kwargs) -> GravityEstimator:
    estimator = GravityEstimator()
    for theta, pose, wrench in samples(rng, **kwargs):
        add(estimator, theta, pose, wrench)
    return estimator


def moment_errors(estimate: GravityEstimate) -> np.ndarray:
    """``(M̂ − M)/σ`` over the visited angles."""
    angles = np.radians(np.linspace(-10.0, 10.0, 21))
    return np.array([(estimate.moment(t) - TRUE(t)) / estimate.moment_std(t) for t in angles])


@pytest.mark.parametrize("seed", range(3))
def test_the_moment_is_recovered_with_a_consistent_uncertainty(seed):
    estimate = fed(np.random.default_rng(seed)).estimate(0.0, contact(), kinematics_valid=True)
    assert estimate.valid
    angles = np.radians(np.linspace(-10.0, 10.0, 21))
    assert max(abs(estimate.moment(t) - TRUE(t)) for t in angles) < 0.01
    assert np.all(np.abs(moment_errors(estimate)) < 3.0)
    assert estimate.moment_std(0.0) < estimate.moment_std(math.radians(60.0))  # grows away from the data


def test_the_ground_contact_applies_when_evaluated_and_its_uncertainty_counts():
    """Samples gathered before the ground contact is known give the right moment once it is; an
    error in it biases ``M̂`` as its covariance says."""
    estimator = fed(np.random.default_rng(3))
    known = estimator.estimate(0.0, contact(), kinematics_valid=True)
    assert abs(known.moment(0.0) - TRUE(0.0)) < 0.005
    shifted = estimator.estimate(0.0, contact(R_O + np.array([0.003, 0.0]), std=0.003), kinematics_valid=True)
    bias = shifted.moment(0.0) - known.moment(0.0)
    assert abs(bias) > 0.03  # about |f_y| · 3 mm
    assert abs(bias) < 2.0 * math.sqrt(shifted.moment_std(0.0) ** 2 - known.moment_std(0.0) ** 2)
    assert not shifted.valid and not estimator.estimate(0.0, contact(), kinematics_valid=False).valid
    assert estimator.estimate(0.0, None, kinematics_valid=True) is UNKNOWN


def test_a_ground_slide_folds_the_segment_and_keeps_the_moment():
    """The object slides 10 mm along the ground between two segments: each is evaluated on its own
    ground contact; pooled under the second one, the first would be off."""
    rng = np.random.default_rng(4)
    moved = R_O + np.array([0.01, 0.0])
    estimator = fed(rng, count=SAMPLES // 2)
    estimator.end_segment(contact())
    for theta, pose, wrench in samples(rng, r_o=moved, count=SAMPLES // 2):
        add(estimator, theta, pose, wrench)
    estimate = estimator.estimate(0.0, contact(moved), kinematics_valid=True)
    assert np.all(np.abs(moment_errors(estimate)) < 3.0)
    pooled = fed(np.random.default_rng(4), count=SAMPLES // 2)
    for theta, pose, wrench in samples(rng, r_o=moved, count=SAMPLES // 2):
        add(pooled, theta, pose, wrench)
    assert abs(pooled.estimate(0.0, contact(moved), True).moment(0.0) - TRUE(0.0)) > 0.05


def kinematics(resets: int, anchor: int, fixed: bool = True) -> KinematicEstimate:
    """What :meth:`GravityEstimator.update` reads of the kinematics: valid, the ground contact known."""
    return KinematicEstimate(
        theta_o=0.0,
        s_h=S_H,
        s_g=float(R_O[0]),
        d=D,
        r_o=R_O,
        std=(1e-3,) * 4,
        theta_o_valid=True,
        s_h_valid=True,
        contact_valid=True,
        rough=(D, *R_O, S_H),
        resets=resets,
        anchor=anchor,
        ground_fixed=fixed,
    )


UNLOCATED = dataclasses.replace(kinematics(0, 0), rough=(D, math.nan, math.nan, S_H))
"""Kinematics regressed on a fixed ground contact whose place is not known yet."""


def test_update_follows_the_kinematics_resets_and_fixed_ground_contact():
    rng, estimator = np.random.default_rng(5), GravityEstimator()
    for theta, pose, wrench in samples(rng):
        estimate = estimator.update(theta, pose, wrench, kinematics(0, 0), contact())
    assert estimate.valid and abs(estimate.moment(0.0) - TRUE(0.0)) < 0.01
    ignored = estimator.update(
        0.0, [0.0, 0.0, 0.0], [50.0, 0.0, 9.0], kinematics(0, 0, fixed=False), contact()
    )
    assert ignored.a == estimate.a and ignored.b == estimate.b  # not regressed on a fixed contact
    after_reset = estimator.update(
        0.0, [0.0, 0.0, 0.0], [50.0, 0.0, 9.0], kinematics(1, 1, fixed=False), contact()
    )
    assert after_reset is UNKNOWN


def lying_on_a_face(rng: np.random.Generator, count: int = 300):
    """The same samples with the object lying on a face (a second vertex on the ground): that
    contact's force adds a moment no point contact at ``r_o`` explains, here 0.4–2.0 N·m (as the paper
    pentagon's pivoted past the tilt where its face lands, measured in closed loop)."""
    for k, (theta, pose, wrench) in enumerate(samples(rng, count=count)):
        yield theta, pose, [wrench[0], wrench[1], wrench[2] - 0.4 - 1.6 * k / count]


@pytest.mark.parametrize(("gate", "kept"), [(GravityParams().gate, True), (1e6, False)])
def test_samples_that_a_point_ground_contact_cannot_balance_are_not_used(gate, kept):
    """Gated, the estimate stays on the object's moment; with the gate open it is carried off."""
    rng, estimator = np.random.default_rng(6), GravityEstimator(GravityParams(gate=gate))
    for theta, pose, wrench in samples(rng):
        estimator.update(theta, pose, wrench, kinematics(0, 0), contact())
    for theta, pose, wrench in lying_on_a_face(rng):
        estimate = estimator.update(theta, pose, wrench, kinematics(0, 0), contact())
    assert bool(np.all(np.abs(moment_errors(estimate)) < 3.0)) is kept


def test_the_gate_keeps_every_sample_of_a_balanced_object():
    """On samples the model explains (with the sensors' noise) the gated estimate recovers the moment
    and is the ungated one: no sample was turned away."""
    gated, ungated = GravityEstimator(), GravityEstimator(GravityParams(gate=1e6))
    for estimator in (gated, ungated):
        for theta, pose, wrench in samples(np.random.default_rng(7)):
            estimator.update(theta, pose, wrench, kinematics(0, 0), contact())
    estimate = gated.estimate(0.0, contact(), kinematics_valid=True)
    assert estimate.valid and np.all(np.abs(moment_errors(estimate)) < 3.0)
    open_gate = ungated.estimate(0.0, contact(), kinematics_valid=True)
    assert (estimate.a, estimate.b) == (open_gate.a, open_gate.b)


def test_an_unknown_moment_is_nan():
    assert math.isnan(UNKNOWN.moment(0.3)) and math.isnan(UNKNOWN.moment_std(0.3)) and not UNKNOWN.valid


@pytest.mark.parametrize(
    ("field", "value", "error"),
    [
        ("moment_noise", 0.0, ValueError),
        ("moment_bias", -0.1, ValueError),
        ("prior_std", math.nan, ValueError),
        ("valid_std", "0.02", TypeError),
        ("gate", 0.0, ValueError),
    ],
)
def test_bad_parameters_raise_naming_the_field(field, value, error):
    with pytest.raises(error, match=field):
        GravityParams(**{field: value})


def test_the_flush_moment_is_the_world_moment_about_the_ground_contact_and_inverts():
    """For random flush configurations the hand-frame form is the moment of the hand's force and
    torque about the ground contact written out in world axes (the torque about the hand face's
    centre plus ``(r_h − r_o) × f``, negated), and :func:`flush_hand_position` recovers ``s_h``."""
    rng = np.random.default_rng(11)
    for _ in range(200):
        theta, s_h, d = rng.uniform(-1.0, 1.0), rng.uniform(-0.05, 0.05), rng.uniform(0.01, 0.15)
        f_n, f_t, torque = rng.uniform(2.0, 25.0), rng.uniform(-8.0, 8.0), rng.uniform(-0.5, 0.5)
        r_o = rng.uniform(-0.2, 0.2, 2)
        pose = geometry.hand_pose_from_contact(theta, s_h, d, r_o)
        f_x, f_y = geometry.hand_force_to_world(theta, f_n, f_t)
        lever = pose[:2] - r_o
        world = -(torque + lever[0] * f_y - lever[1] * f_x)
        moment = flush_moment(f_n, f_t, torque, s_h, d)
        assert moment == pytest.approx(world, abs=1e-12)
        assert flush_hand_position(f_n, f_t, torque, d, moment) == pytest.approx(s_h, abs=1e-12)
