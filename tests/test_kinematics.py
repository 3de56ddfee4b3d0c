"""Kinematic estimator on hand poses of a known object (ccopt.geometry.hand_pose_from_contact)."""

from __future__ import annotations

import math

import numpy as np
import pytest

from ccopt import geometry
from ccopt.estimation.kinematics import KinematicEstimator, KinematicsParams, pivot_contact
from ccopt.modes import ContactConfiguration, ContactMode, HandGeometry

D, R_O, S_H, L_H = 0.06, np.array([0.12, 0.01]), 0.015, 0.05
POSE_NOISE = np.array([2e-4, 2e-4, math.radians(0.1)])  # m, m, rad
TORQUE_NOISE = 0.005  # N·m
COMPLIANCE = 0.04  # rad/(N·m): θ_h − θ_o = c τ
STICK = ContactConfiguration()
HAND_SLIDES = ContactConfiguration(hand_mode=ContactMode.SLIDE_POS)
GROUND_SLIDES = ContactConfiguration(ground_mode=ContactMode.SLIDE_POS)
INDETERMINATE = ContactConfiguration(hand_geometry=HandGeometry.PIVOT_POS, ground_mode=ContactMode.SLIDE_POS)
"""The ground slides while the hand pivots: nothing in eqs. 14-16 holds."""


def measured(pose: np.ndarray, rng: np.random.Generator) -> np.ndarray:
    return pose + rng.normal(0.0, POSE_NOISE)


def step(
    estimator: KinematicEstimator,
    pose: np.ndarray,
    modes: ContactConfiguration = STICK,
    in_contact: bool = True,
    ground_may_slide: bool = False,
    **options,
):
    theta = float(pose[2])
    normal, tangent = geometry.hand_normal(theta).tolist(), geometry.hand_tangent(theta).tolist()
    return estimator.update(pose, normal, tangent, modes, in_contact, ground_may_slide, **options)


def pivot_about_ground(estimator: KinematicEstimator, rng: np.random.Generator, span_deg: float = 15.0):
    """Rotate the object (and the sticking, flush hand) about the ground contact by ±``span_deg``."""
    angles = np.radians(span_deg) * np.sin(np.linspace(0.0, 2.0 * np.pi, 1200))
    for theta in angles:
        estimate = step(estimator, measured(geometry.hand_pose_from_contact(theta, S_H, D, R_O), rng))
    return estimate


@pytest.mark.parametrize("seed", range(4))
def test_a_rigid_rotation_about_the_ground_contact_gives_d_and_r_o_within_a_millimetre(seed):
    estimate = pivot_about_ground(KinematicEstimator(L_H), np.random.default_rng(seed))
    assert estimate.contact_valid and estimate.s_h_valid and estimate.theta_o_valid
    assert abs(estimate.d - D) < 1e-3
    assert np.all(np.abs(estimate.r_o - R_O) < 1e-3)
    assert estimate.s_g == estimate.r_o[0]
    assert abs(estimate.s_h - S_H) < 1e-3


def rotate_with_torque(estimator: KinematicEstimator, rng: np.random.Generator):
    """Rotate the object about the ground contact by ±15° while the hand presses with a torque that
    mostly follows the angle (as gravity's moment does) plus a part of its own, the hand tilted by
    ``COMPLIANCE · τ`` against the face. Returns the last estimate, true angle and torque."""
    count = 1200
    angles = np.radians(15.0) * np.sin(np.linspace(0.0, 2.0 * np.pi, count))
    torques = -1.5 * angles + 0.15 * np.sin(2.0 * np.pi * np.arange(count) / 74.0)
    for theta, torque in zip(angles, torques, strict=True):
        pose = geometry.hand_pose_from_contact(theta, S_H, D, R_O) + np.array([0.0, 0.0, COMPLIANCE * torque])
        measured_torque = torque + rng.normal(0.0, TORQUE_NOISE)
        estimate = step(estimator, measured(pose, rng), torque=measured_torque)
    return estimate, theta, torque


@pytest.mark.parametrize("seed", range(2))
def test_the_contact_compliance_is_estimated_and_removed_from_the_kinematics(seed):
    estimate, theta, torque = rotate_with_torque(KinematicEstimator(L_H), np.random.default_rng(seed))
    assert abs(estimate.compliance - COMPLIANCE) < max(3.0 * estimate.compliance_std, 0.004)
    assert estimate.compliance_std < 0.01
    assert abs(estimate.d - D) < 1e-3 and np.all(np.abs(estimate.r_o - R_O) < 1e-3)
    assert abs(estimate.theta_o - theta) < math.radians(0.15)
    tilt = COMPLIANCE * torque  # s_h is reported in the hand frame, like the plant's truth
    assert abs(estimate.s_h - (S_H * math.cos(tilt) - D * math.sin(tilt))) < 1e-3
    rigid = KinematicEstimator(L_H, KinematicsParams(compliance_std=0.0))
    assert abs(rotate_with_torque(rigid, np.random.default_rng(seed))[0].d - D) > 3e-3  # what it fixes


def rotate_with_torque_steps(estimators, compliance: float, seed: int):
    """:func:`rotate_with_torque` with the hand tilted by ``compliance · τ``, the same samples fed to
    each estimator in turn; yields after each sample."""
    rng = np.random.default_rng(seed)
    count = 1200
    angles = np.radians(15.0) * np.sin(np.linspace(0.0, 2.0 * np.pi, count))
    torques = -1.5 * angles + 0.15 * np.sin(2.0 * np.pi * np.arange(count) / 74.0)
    for theta, torque in zip(angles, torques, strict=True):
        pose = geometry.hand_pose_from_contact(theta, S_H, D, R_O) + np.array([0.0, 0.0, compliance * torque])
        sample = measured(pose, rng)
        measured_torque = torque + rng.normal(0.0, TORQUE_NOISE)
        yield [step(estimator, sample, torque=measured_torque) for estimator in estimators]


UNCONSTRAINED = KinematicsParams(compliance_min=-1.0)


def test_a_hand_that_tilts_against_its_torque_is_not_taken_for_a_negative_compliance():
    """A pad tilts with the torque: a stream whose hand tilts against it (what a model error looks
    like to the filter) leaves the unconstrained estimate at the negative slope, the default one at 0."""
    bounded, free = KinematicEstimator(L_H), KinematicEstimator(L_H, UNCONSTRAINED)
    for estimates in rotate_with_torque_steps((bounded, free), -COMPLIANCE, 0):
        assert estimates[0].compliance >= 0.0
    assert abs(estimates[1].compliance + COMPLIANCE) < 0.004  # the stream does push it below 0
    assert estimates[0].compliance == 0.0


def test_the_bound_projects_the_state_along_its_covariance():
    """At the first sample where the unconstrained update crosses ``c = 0``, the bounded state is its
    covariance-weighted projection ``x − P e_c c / P_cc`` (closed form, NumPy), ``P`` the same."""
    bounded, free = KinematicEstimator(L_H), KinematicEstimator(L_H, UNCONSTRAINED)
    for _ in rotate_with_torque_steps((bounded, free), -COMPLIANCE, 1):
        state, cov = np.array(free._state), np.array(free._cov)
        if state[4] < 0.0:
            break
        np.testing.assert_array_equal(bounded._state, state)  # the bound inactive: the same filter
    else:
        pytest.fail("the unconstrained compliance never went below 0")
    projected = state - cov[:, 4] / cov[4, 4] * state[4]
    np.testing.assert_allclose(bounded._state, projected, rtol=0.0, atol=1e-15)
    assert bounded._state[4] == 0.0
    np.testing.assert_array_equal(np.array(bounded._cov), cov)


def test_a_compliance_prior_below_the_bound_is_refused():
    with pytest.raises(ValueError, match="compliance_prior"):
        KinematicsParams(compliance_prior=-0.01)
    assert KinematicsParams(compliance_prior=-0.01, compliance_min=-0.1).compliance_prior == -0.01


NORMAL_COMPLIANCE = 1e-4  # m/N: the face sinks towards the ground contact by k f_n


def rotate_with_varying_force(estimator: KinematicEstimator, rng: np.random.Generator):
    """Rotate the object about the ground contact by ±15° while the normal force varies between 5
    and 25 N, the hand sunk by ``NORMAL_COMPLIANCE · f_n`` along its normal (a rigid contact in
    rotation). Returns the last estimate."""
    count = 1200
    angles = np.radians(15.0) * np.sin(np.linspace(0.0, 2.0 * np.pi, count))
    forces = 15.0 + 10.0 * np.sin(2.0 * np.pi * np.arange(count) / 97.0)
    for theta, force in zip(angles, forces, strict=True):
        sunk = D - NORMAL_COMPLIANCE * force
        pose = geometry.hand_pose_from_contact(theta, S_H, sunk, R_O)
        estimate = step(estimator, measured(pose, rng), normal_force=force + rng.normal(0.0, 0.1))
    return estimate


@pytest.mark.parametrize("seed", range(2))
def test_the_normal_compliance_is_estimated_and_d_is_reported_at_the_reference_force(seed):
    params = KinematicsParams(compliance_std=0.0)
    estimate = rotate_with_varying_force(KinematicEstimator(L_H, params), np.random.default_rng(seed))
    assert abs(estimate.normal_compliance - NORMAL_COMPLIANCE) < 1.5e-5
    assert abs(estimate.d - (D - NORMAL_COMPLIANCE * params.reference_force)) < 5e-4
    assert np.all(np.abs(estimate.r_o - R_O) < 5e-4) and abs(estimate.s_h - S_H) < 5e-4


def test_the_regression_sample_is_not_selected_by_its_own_angle_noise():
    """A rigid contact (c = 0) turning to and fro with the torque following the direction of
    turning. The sample whose measured angle crosses the excitation threshold has its noise biased
    along the motion, so along τ: regressing it would show a compliance that is not there."""
    compliances = []
    for seed in range(4):
        rng, estimator = np.random.default_rng(seed), KinematicEstimator(L_H)
        angles = np.radians(15.0) * np.sin(np.linspace(0.0, 4.0 * np.pi, 4000))
        for theta, rate in zip(angles, np.gradient(angles), strict=True):
            pose = measured(geometry.hand_pose_from_contact(theta, S_H, D, R_O), rng)
            estimate = step(estimator, pose, torque=0.3 * math.copysign(1.0, rate))
        compliances.append(estimate.compliance)
    assert abs(np.mean(compliances)) < 0.0015  # 0.004 when the crossing sample is regressed


def test_rough_means_come_before_validity_and_are_the_estimates_after():
    estimator, rng = KinematicEstimator(L_H), np.random.default_rng(15)
    assert np.isnan(
        step(estimator, measured(geometry.hand_pose_from_contact(0.0, S_H, D, R_O), rng)).rough
    ).all()
    for theta in np.radians(np.linspace(0.0, 4.0, 400)):
        estimate = step(estimator, measured(geometry.hand_pose_from_contact(theta, S_H, D, R_O), rng))
    assert not estimate.contact_valid
    truth = (D, *R_O, S_H)
    for mean, deviation, value in zip(estimate.rough, estimate.std, truth, strict=True):
        assert deviation <= estimator.params.rough_std and abs(mean - value) < 3.0 * deviation
    estimate = pivot_about_ground(estimator, rng)
    assert estimate.contact_valid and estimate.s_h_valid
    assert estimate.rough == (estimate.d, *estimate.r_o, estimate.s_h)
    away = step(estimator, measured(geometry.hand_pose_from_contact(0.0, S_H, D, R_O), rng), in_contact=False)
    assert math.isnan(away.rough[3]) and away.rough[:3] == (away.d, *away.r_o)  # s_h undefined out of contact


def test_estimates_are_invalid_until_the_hand_has_rotated_enough():
    estimator, rng = KinematicEstimator(L_H), np.random.default_rng(5)
    for theta in np.radians(np.linspace(0.0, 1.0, 200)):
        estimate = step(estimator, measured(geometry.hand_pose_from_contact(theta, S_H, D, R_O), rng))
    assert estimate.theta_o_valid and estimate.theta_o == pytest.approx(math.radians(1.0), abs=0.01)
    assert not estimate.contact_valid and not estimate.s_h_valid
    assert math.isnan(estimate.d) and np.isnan(estimate.r_o).all()


def test_the_papers_regression_alone_works_while_the_hand_slides():
    estimator, rng = KinematicEstimator(L_H), np.random.default_rng(6)
    angles = np.radians(30.0) * np.sin(np.linspace(0.0, 2.0 * np.pi, 3000))
    positions = S_H + 0.02 * np.sin(np.linspace(0.0, 6.0 * np.pi, 3000))
    for theta, s_h in zip(angles, positions, strict=True):
        pose = measured(geometry.hand_pose_from_contact(theta, s_h, D, R_O), rng)
        estimate = step(estimator, pose, HAND_SLIDES)
    assert estimate.contact_valid
    assert abs(estimate.d - D) < 2e-3 and np.all(np.abs(estimate.r_o - R_O) < 2e-3)
    assert abs(estimate.s_h - positions[-1]) < 2e-3


def test_s_h_follows_a_hand_slide():
    estimator, rng = KinematicEstimator(L_H), np.random.default_rng(7)
    pivot_about_ground(estimator, rng)
    errors = []
    for s_h in np.linspace(S_H, S_H + 0.03, 300):
        pose = measured(geometry.hand_pose_from_contact(0.05, s_h, D, R_O), rng)
        estimate = step(estimator, pose, HAND_SLIDES)
        assert estimate.s_h_valid
        errors.append(estimate.s_h - s_h)
    assert np.mean(np.abs(errors)) < 5e-4 and np.max(np.abs(errors)) < 1.5e-3  # eq. 16, sample by sample
    estimate = step(estimator, measured(geometry.hand_pose_from_contact(0.05, S_H + 0.03, D, R_O), rng))
    assert abs(estimate.s_h - (S_H + 0.03)) < 1e-3
    assert np.all(np.abs(estimate.r_o - R_O) < 1e-3)


def test_a_ground_slide_moves_r_o_rigidly_with_the_hand():
    estimator, rng = KinematicEstimator(L_H), np.random.default_rng(8)
    pivot_about_ground(estimator, rng)
    for x_o in np.linspace(R_O[0], R_O[0] + 0.03, 300):
        r_o = np.array([x_o, R_O[1]])
        estimate = step(
            estimator, measured(geometry.hand_pose_from_contact(0.1, S_H, D, r_o), rng), GROUND_SLIDES
        )
        assert estimate.contact_valid and np.all(np.abs(estimate.r_o - r_o) < 1e-3)
    assert abs(estimate.s_h - S_H) < 1e-3 and abs(estimate.d - D) < 1e-3


def hand_pivoting_on_its_end(theta_o: float, theta_h: float, sign: int, s_h: float = S_H) -> np.ndarray:
    """Hand pose touching the object face (angle ``theta_o``) only with its ``sign`` end, whose
    flush-hand equivalent is at ``s_h``."""
    contact_point = geometry.hand_pose_from_contact(theta_o, s_h, D, R_O)[:2]
    contact_point = contact_point + sign * L_H * geometry.hand_tangent(theta_o)
    return np.array([*(contact_point - sign * L_H * geometry.hand_tangent(theta_h)), theta_h])


@pytest.mark.parametrize("sign", [1, -1])
def test_pivot_contact_inverts_the_pivoting_geometry(sign):
    theta_o, theta_h = 0.2, 0.2 - sign * 0.08
    pose = hand_pivoting_on_its_end(theta_o, theta_h, sign)
    theta, s_h = pivot_contact(pose, sign, L_H, D, R_O, theta_h)
    assert theta == pytest.approx(theta_o, abs=1e-12) and s_h == pytest.approx(S_H, abs=1e-12)


def test_a_pivoting_hand_still_gives_theta_o_and_s_h():
    # θ_o is only as good as the lever from the ground contact to the hand end: 0.3 mm / 90 mm ≈ 0.2°
    estimator, rng = KinematicEstimator(L_H), np.random.default_rng(9)
    pivot_about_ground(estimator, rng)
    pivoting = ContactConfiguration(hand_geometry=HandGeometry.PIVOT_POS)  # Δθ = θ_o − θ_h > 0
    s_h = -0.04
    for theta_o in np.radians(np.linspace(0.0, 6.0, 100)):
        estimate = step(estimator, measured(hand_pivoting_on_its_end(theta_o, 0.0, 1, s_h), rng), pivoting)
        assert estimate.theta_o_valid and abs(estimate.theta_o - theta_o) < math.radians(1.0)
        assert estimate.s_h_valid and abs(estimate.s_h - s_h) < 1.5e-3


def test_resets_and_moves_of_the_ground_contact_are_counted():
    estimator, rng = KinematicEstimator(L_H), np.random.default_rng(16)
    estimate = pivot_about_ground(estimator, rng)
    assert estimate.ground_fixed and estimate.resets == 0
    anchor = estimate.anchor
    pose = measured(geometry.hand_pose_from_contact(0.1, S_H, D, R_O), rng)
    sliding = step(estimator, pose, GROUND_SLIDES)
    assert not sliding.ground_fixed and sliding.anchor > anchor and sliding.resets == 0
    reset = step(estimator, pose, INDETERMINATE)
    assert reset.resets == 1 and reset.anchor > sliding.anchor
    assert reset.compliance == sliding.compliance  # a property of the contact: kept


def test_indeterminate_motion_resets_and_lost_contact_keeps_the_ground_contact():
    estimator, rng = KinematicEstimator(L_H), np.random.default_rng(10)
    pivot_about_ground(estimator, rng)
    pose = measured(geometry.hand_pose_from_contact(0.0, S_H, D, R_O), rng)
    away = step(estimator, pose, in_contact=False)
    assert away.contact_valid and not away.s_h_valid
    reset = step(estimator, pose, INDETERMINATE)
    assert not reset.contact_valid and not reset.s_h_valid and not reset.theta_o_valid
    assert max(reset.std) == pytest.approx(estimator.params.prior_std)


@pytest.mark.parametrize("theta_deg", [3.0, 10.0, 25.0])
def test_both_contacts_sliding_release_only_x_o_and_s_h_as_well_as_the_pose_tells_them(theta_deg):
    # Both contacts may slide: the object keeps d and y_o; the moved x_o and s_h come from the sample's
    # eqs. 15-16 alone. With d and y_o known, eq. 15 gives x_o through I·e_n = sin θ (up to sign): its
    # standard deviation is the position noise over |sin θ|, so it is valid only at a tilt.
    estimator, rng = KinematicEstimator(L_H), np.random.default_rng(11)
    before = pivot_about_ground(estimator, rng)
    theta, moved_s_h, moved_r_o = math.radians(theta_deg), S_H + 0.004, R_O + np.array([-0.006, 0.0])
    both_slide = ContactConfiguration(hand_mode=ContactMode.SLIDE_POS, ground_mode=ContactMode.SLIDE_NEG)
    pose = measured(geometry.hand_pose_from_contact(theta, moved_s_h, D, moved_r_o), rng)
    after = step(estimator, pose, both_slide)
    assert after.resets == 0 and after.anchor > before.anchor
    assert after.rough[0] == pytest.approx(before.d, abs=1e-4) and after.std[0] <= 1.01 * before.std[0]
    noise = estimator.params.position_noise
    assert after.std[1] == pytest.approx(noise / math.sin(theta), rel=0.2)
    assert after.contact_valid == (noise / math.sin(theta) <= estimator.params.valid_std)
    if after.contact_valid:
        assert abs(after.s_g - moved_r_o[0]) <= 4.0 * after.std[1]
        assert abs(after.s_h - moved_s_h) <= 4.0 * after.std[3]


@pytest.mark.parametrize(
    ("field", "value", "error"),
    [
        ("excitation_angle", -0.1, ValueError),
        ("position_noise", math.nan, ValueError),
        ("prior_std", 0.0, ValueError),
        ("valid_std", "1e-3", TypeError),
        ("compliance_prior", math.inf, ValueError),
        ("compliance_std", -0.1, ValueError),
        ("rough_std", 1e-3, ValueError),  # below valid_std
        ("hand_slip_gate", 0.0, ValueError),
    ],
)
def test_bad_parameters_raise_naming_the_field(field, value, error):
    with pytest.raises(error, match=field):
        KinematicsParams(**{field: value})


@pytest.mark.parametrize("reported", [False, True])
def test_an_unreported_hand_slide_is_caught_by_the_innovation_gate(reported):
    """The modes say sticking, the hand really slides: eq. 16's innovations re-estimate ``s_h``. If
    it was reported sliding (a report not acted on, the command keeping the hand sticking), the
    tighter ``hand_slip_gate`` catches it sooner."""
    estimator, rng = KinematicEstimator(L_H), np.random.default_rng(11)
    pivot_about_ground(estimator, rng)
    positions = np.linspace(S_H, S_H + 0.02, 200)
    for s_h in positions:
        pose = measured(geometry.hand_pose_from_contact(0.05, s_h, D, R_O), rng)
        estimate = step(estimator, pose, hand_may_slide=reported)
    # s_h lags until the innovation crosses the gate: `gate` predicted standard deviations, which just
    # after a re-estimate are √2 × the measurement noise, plus the slide of one sample
    params = KinematicsParams()
    gate = params.hand_slip_gate if reported else params.gate
    lag_bound = gate * math.sqrt(2.0) * params.position_noise + (positions[1] - positions[0])
    assert estimate.s_h_valid and abs(estimate.s_h - positions[-1]) < lag_bound  # 4.3/2.9 mm; 20 if missed
    assert abs(estimate.d - D) < 1e-3 and np.all(np.abs(estimate.r_o - R_O) < 1e-3)


def test_an_unreported_move_of_the_ground_contact_resets_instead_of_keeping_a_wrong_one():
    """The modes say sticking, but the object has rolled onto a vertex 5 mm higher: eq. 15 cannot
    explain it, and after ``slip_samples`` rejections the estimate resets rather than report the old
    ``r_o`` as valid. (A move along ``e_t`` alone is kinematically a hand slide: see the docstring.)"""
    estimator, rng = KinematicEstimator(L_H), np.random.default_rng(12)
    pivot_about_ground(estimator, rng)
    moved = R_O + np.array([0.0, 0.005])
    outcomes = []
    for theta in np.radians(np.linspace(0.0, 10.0, 200)):
        estimate = step(estimator, measured(geometry.hand_pose_from_contact(theta, S_H, D, moved), rng))
        outcomes.append(estimate.contact_valid)
        if estimate.contact_valid:
            assert np.all(np.abs(estimate.r_o - R_O) < 1e-3) or np.all(np.abs(estimate.r_o - moved) < 1e-3)
    assert not all(outcomes)  # it noticed
    assert not estimate.contact_valid or np.all(np.abs(estimate.r_o - moved) < 1e-3)


@pytest.mark.parametrize("theta", [0.0, 0.3])
def test_a_ground_reported_sliding_with_a_sticking_hand_moves_r_o_not_s_h(theta):
    """The ground "may slide" (a report the kinematics do not act on) and really slides 10 mm along
    world x, the hand sticks: at θ = 0 that is a motion along ``e_t``, kinematically a hand slide,
    but the sticking-hand report decides — ``r_o`` follows, ``s_h`` stays."""
    estimator, rng = KinematicEstimator(L_H), np.random.default_rng(13)
    pivot_about_ground(estimator, rng)
    params = KinematicsParams()
    for x_o in np.linspace(R_O[0], R_O[0] + 0.01, 200):
        r_o = np.array([x_o, R_O[1]])
        pose = measured(geometry.hand_pose_from_contact(theta, S_H, D, r_o), rng)
        estimate = step(estimator, pose, ground_may_slide=True)
        # caught once the innovation crosses `slip_gate` (√2 × the noise after a re-anchoring)
        assert abs(estimate.s_g - x_o) < params.slip_gate * math.sqrt(2.0) * params.position_noise + 1e-4
    assert abs(estimate.s_h - S_H) < 1e-3 and abs(estimate.d - D) < 1e-3
    assert abs(estimate.s_g - x_o) < 1e-3


def test_a_ground_slip_while_the_hand_slides_too_gives_both_from_the_tilted_hand():
    """Both contacts "may slide" and both do (the object 8 mm along x, the hand 6 mm along the
    face) with the hand tilted 0.35 rad: eq. 15 sees the ground's share, eq. 16 the rest."""
    estimator, rng = KinematicEstimator(L_H), np.random.default_rng(14)
    pivot_about_ground(estimator, rng)
    theta = 0.35
    for fraction in np.linspace(0.0, 1.0, 400):
        r_o = R_O + np.array([0.008 * fraction, 0.0])
        pose = measured(geometry.hand_pose_from_contact(theta, S_H + 0.006 * fraction, D, r_o), rng)
        estimate = step(estimator, pose, HAND_SLIDES, ground_may_slide=True)
    assert estimate.contact_valid and estimate.s_h_valid
    assert abs(estimate.s_g - r_o[0]) < 2e-3 and abs(estimate.s_h - (S_H + 0.006)) < 2e-3


@pytest.mark.parametrize("theta_deg", [-20.0, -10.0, 10.0, 25.0])
def test_a_hand_that_slides_in_a_commanded_ground_slide_is_told_by_the_face_tilt(theta_deg):
    """The ground is commanded to slide (the kinematics follow it rigidly) but the hand slides
    10 mm along the face instead, the ground contact stays: by truth, ``ŝ_g`` and ``r̂_o`` stay within
    a millimetre and ``ŝ_h`` follows the hand, from once ``ŷ_o`` would have moved by
    ``hand_slide_height`` and by ``hand_slide_travel sin θ`` on."""
    estimator, rng = KinematicEstimator(L_H), np.random.default_rng(15)
    pivot_about_ground(estimator, rng)
    theta, slide = math.radians(theta_deg), 0.01
    params = KinematicsParams()
    caught = max(params.hand_slide_height / abs(math.sin(theta)), params.hand_slide_travel)  # hand travel, m
    for s_h in np.linspace(S_H, S_H + slide, 400):
        pose = measured(geometry.hand_pose_from_contact(theta, s_h, D, R_O), rng)
        estimate = step(estimator, pose, GROUND_SLIDES)
        if s_h - S_H > caught + 1e-3:
            assert abs(estimate.s_g - R_O[0]) < 1e-3 and abs(estimate.s_h - s_h) < 1e-3
    assert estimate.contact_valid and np.all(np.abs(estimate.r_o - R_O) < 1e-3)
    assert abs(estimate.s_h - (S_H + slide)) < 1e-3


@pytest.mark.parametrize("theta_deg", [-17.6, 17.6])
def test_a_hand_that_slides_while_the_ground_report_flickers_is_still_caught(theta_deg):
    """As above, but the classifier's ground report flickers (as it did on a goals-study triangle at
    17.6°, low normal force): every fourth sample the kinematics are told the ground sticks, though it
    still may slide. The following's start is kept through the flicker, so ``ŷ_o``'s drift adds up
    and the hand slide is caught; by truth ``ŝ_g`` stays within a millimetre (restarting the start
    at each flicker, the 10 mm hand slide was read as 5.8 mm of ground slide)."""
    estimator, rng = KinematicEstimator(L_H), np.random.default_rng(17)
    pivot_about_ground(estimator, rng)
    theta, slide = math.radians(theta_deg), 0.01
    params = KinematicsParams()
    caught = max(params.hand_slide_height / abs(math.sin(theta)), params.hand_slide_travel)
    for k, s_h in enumerate(np.linspace(S_H, S_H + slide, 400)):
        pose = measured(geometry.hand_pose_from_contact(theta, s_h, D, R_O), rng)
        modes = STICK if k % 4 == 3 else GROUND_SLIDES
        estimate = step(estimator, pose, modes, ground_may_slide=True)
        if s_h - S_H > caught + 2e-3:
            assert abs(estimate.s_g - R_O[0]) < 1e-3
    assert estimate.contact_valid and abs(estimate.s_h - (S_H + slide)) < 1e-3


@pytest.mark.parametrize("theta_deg", [-25.0, 10.0, 30.0])
def test_a_ground_slide_whose_hand_sticks_is_not_taken_for_a_hand_slide(theta_deg):
    """The control case: the ground slides 10 mm and the hand sticks. ``ŷ_o`` keeps its height, so
    the motion stays the ground's (by truth, within a millimetre) and ``ŝ_h`` stays."""
    estimator, rng = KinematicEstimator(L_H), np.random.default_rng(16)
    pivot_about_ground(estimator, rng)
    theta = math.radians(theta_deg)
    for x_o in np.linspace(R_O[0], R_O[0] - 0.01, 400):
        r_o = np.array([x_o, R_O[1]])
        pose = measured(geometry.hand_pose_from_contact(theta, S_H, D, r_o), rng)
        estimate = step(estimator, pose, GROUND_SLIDES)
        assert abs(estimate.s_g - x_o) < 1e-3
    assert abs(estimate.s_h - S_H) < 1e-3


def pivot_from(
    estimator: KinematicEstimator, rng, theta: float, s_h: float, r_o: np.ndarray, span_deg: float
):
    """Pivot the object (hand sticking, flush) about ``r_o`` from ``theta`` by ``span_deg`` and back."""
    for angle in theta + np.radians(span_deg) * np.sin(np.linspace(0.0, np.pi, 400)):
        estimate = step(estimator, measured(geometry.hand_pose_from_contact(angle, s_h, D, r_o), rng))
    return estimate


@pytest.mark.parametrize("hand_slid", [True, False])
@pytest.mark.parametrize("theta_deg", [-5.0, 4.0])
def test_a_ground_slide_near_the_vertical_whose_hand_may_have_slid_is_settled_by_the_next_pivot(
    theta_deg, hand_slid
):
    """Within ``split_tilt`` of the vertical a commanded ground slide and a hand slide along the face
    move the hand alike (their difference, ``Δ sin θ``, is under the pose noise), and while the hand
    is at its friction limit either may be the one that moved. The kinematics follow the ground (the
    command) but afterwards hold the other reading one standard deviation away: they are not valid
    until a pivot, which rotates the two readings apart, tells them; by truth ``ŝ_g`` and ``ŝ_h``
    then stand within a millimetre, whichever contact slid."""
    estimator, rng = KinematicEstimator(L_H), np.random.default_rng(21)
    pivot_about_ground(estimator, rng)
    theta, travel = math.radians(theta_deg), 0.008
    r_o, s_h = R_O.copy(), S_H
    for fraction in np.linspace(0.0, 1.0, 300):
        if hand_slid:
            s_h = S_H + travel * fraction
        else:
            r_o = R_O - np.array([travel * fraction, 0.0])
        pose = measured(geometry.hand_pose_from_contact(theta, s_h, D, r_o), rng)
        step(estimator, pose, GROUND_SLIDES, hand_may_slide=True)
    after = step(estimator, measured(geometry.hand_pose_from_contact(theta, s_h, D, r_o), rng))
    assert not after.contact_valid
    estimate = pivot_from(estimator, rng, theta, s_h, r_o, span_deg=-7.2 if theta_deg > 0 else 7.2)
    assert estimate.contact_valid and estimate.s_h_valid
    assert abs(estimate.s_g - r_o[0]) < 1e-3 and abs(estimate.s_h - s_h) < 1e-3


def test_a_ground_slide_near_the_vertical_whose_hand_stayed_inside_its_friction_stays_valid():
    """The control case: the hand was never at its friction limit, so it stuck (``μ̂_h`` is a lower
    bound) and the slide was the ground's: the kinematics stay valid, by truth within a millimetre."""
    estimator, rng = KinematicEstimator(L_H), np.random.default_rng(22)
    pivot_about_ground(estimator, rng)
    theta = math.radians(-5.0)
    for x_o in np.linspace(R_O[0], R_O[0] - 0.008, 300):
        r_o = np.array([x_o, R_O[1]])
        step(estimator, measured(geometry.hand_pose_from_contact(theta, S_H, D, r_o), rng), GROUND_SLIDES)
    estimate = step(estimator, measured(geometry.hand_pose_from_contact(theta, S_H, D, r_o), rng))
    assert estimate.contact_valid and abs(estimate.s_g - r_o[0]) < 1e-3 and abs(estimate.s_h - S_H) < 1e-3
