"""The estimator facade on a synthetic run of a known object, with true modes and kinematics."""

from __future__ import annotations

import dataclasses
import math

import numpy as np
import pytest

from ccopt import contact, geometry
from ccopt.estimation import (
    Estimator,
    EstimatorParams,
    HandFrictionParams,
    KinematicsParams,
    commanded_modes,
    replay,
)
from ccopt.estimation.estimator import kinematic_modes
from ccopt.estimation.ground_cone import GroundCone
from ccopt.hand import Hand
from ccopt.modes import ContactConfiguration, ContactMode, HandGeometry

MU_H, MU_G, MASS, L_H, D = 0.5, 0.8, 0.3, 0.05, 0.06
RATE = 1000.0
PHASE = 2000  # samples per phase
HOLD = 300  # samples at the start of each phase where nothing moves (as between commanded motions)
PHASES = ("explore hand", "explore ground", "pivot", "hand slide", "ground slide", "pivot")
NOISE_POSE = np.array([2e-4, 2e-4, math.radians(0.1)])
NOISE_WRENCH = np.array([0.3, 0.3, 0.005])


@dataclasses.dataclass
class Run:
    times: np.ndarray
    poses: np.ndarray
    wrenches: np.ndarray
    phase: np.ndarray  # index into PHASES
    hand_mode: np.ndarray  # true sign of ṡ_h
    ground_mode: np.ndarray  # true sign of ṡ_g
    theta_o: np.ndarray
    s_h: np.ndarray
    r_o: np.ndarray


def synthetic_run(seed: int) -> Run:
    """The cone explored by sliding both ways at each contact, then pivots and slides, at 1 kHz;
    each phase starts with a short hold.

    Sliding wrenches lie on the true cone's faces (the hand rows of :func:`ccopt.contact.hand_rows`,
    the ground rows of :func:`ccopt.contact.model_ground_rows`); sticking ones are well inside.
    """
    rng = np.random.default_rng(seed)
    count = PHASE * len(PHASES)
    run = Run(
        times=np.arange(count) / RATE,
        poses=np.empty((count, 3)),
        wrenches=np.empty((count, 3)),
        phase=np.arange(count) // PHASE,
        hand_mode=np.zeros(count, dtype=int),
        ground_mode=np.zeros(count, dtype=int),
        theta_o=np.zeros(count),
        s_h=np.zeros(count),
        r_o=np.zeros((count, 2)),
    )
    ground_a, ground_b = contact.model_ground_rows(MU_G, MASS)
    r_o, s_h = np.array([0.10, 0.0]), 0.01
    for k, t in enumerate(run.times):
        name, swing = PHASES[run.phase[k]], math.sin(2.0 * math.pi * t / 0.5)
        f_n, theta = 10.0 + 4.0 * math.sin(2.0 * math.pi * t / 0.37), 0.0
        wrench = np.array([f_n, 0.2 * MU_H * f_n * swing, 0.2 * L_H * f_n * swing])
        if k % PHASE < HOLD:
            pass  # every phase starts and ends at θ = 0: hold still, well inside the cone
        elif name in ("explore hand", "hand slide"):
            direction = 1 if swing >= 0.0 else -1
            wrench[1] = -direction * MU_H * f_n  # on the face of row HAND_SLIDE_POS (+1) or _NEG (−1)
            s_h += direction * 0.02 / RATE
            run.hand_mode[k] = direction
        elif name in ("explore ground", "ground slide"):
            push = max(-1.0, min(1.0, 3.0 * swing))
            row = 0 if push > 0.0 else 1  # GROUND_SLIDE_POS or _NEG: a·f = b on the face
            f_x = (ground_b[row] - ground_a[row, 1] * -f_n) / ground_a[row, 0] * abs(push)
            force = np.array([f_x, -f_n])
            theta = math.atan2(force[0], -force[1])  # the hand pushes along the force: f_t = 0
            wrench = geometry.wrench_world_to_hand(theta, [*force, 0.0])
            if abs(push) == 1.0:
                run.ground_mode[k] = 1 if push > 0.0 else -1
                r_o = r_o + np.array([run.ground_mode[k] * 0.02 / RATE, 0.0])
        else:
            theta = math.radians(8.0) * math.sin(2.0 * math.pi * t / 2.0)
        run.poses[k] = geometry.hand_pose_from_contact(theta, s_h, D, r_o)
        run.wrenches[k], run.theta_o[k], run.s_h[k], run.r_o[k] = wrench, theta, s_h, r_o
    run.poses += rng.normal(0.0, NOISE_POSE, run.poses.shape)
    run.wrenches += rng.normal(0.0, NOISE_WRENCH, run.wrenches.shape)
    return run


@pytest.fixture(scope="module")
def run_and_estimates():
    run = synthetic_run(0)
    return run, replay(run.times, run.poses, run.wrenches, Hand(half_length=L_H))


def test_sliding_is_almost_never_reported_as_sticking(run_and_estimates):
    run, estimates = run_and_estimates
    hand = np.array([int(e.hand_mode) for e in estimates])
    ground = np.array([int(e.ground_mode) for e in estimates])
    for truth, reported in ((run.hand_mode, hand), (run.ground_mode, ground)):
        sliding = truth != 0
        assert np.mean(reported[sliding] != truth[sliding]) < 0.02
    assert all(e.hand_geometry == HandGeometry.FLUSH for e in estimates[PHASE:])


def test_the_cone_is_learned_from_the_run(run_and_estimates):
    _, estimates = run_and_estimates
    last = estimates[-1]
    assert last.row_valid.all()
    assert last.mu_h == pytest.approx(MU_H, rel=0.05)
    assert last.mu_g == pytest.approx(MU_G, rel=0.05)
    assert last.torque_lever == pytest.approx(HandFrictionParams().torque_margin * L_H)


def test_kinematics_after_pivoting_and_through_slides(run_and_estimates):
    run, estimates = run_and_estimates
    for end in (3 * PHASE - 1, 4 * PHASE - 1, 5 * PHASE - 1, 6 * PHASE - 1):
        estimate = estimates[end]
        assert estimate.kinematics_valid, PHASES[run.phase[end]]
        assert abs(estimate.theta_o - run.theta_o[end]) < math.radians(0.5)
        assert abs(estimate.d - D) < 1e-3
        assert np.all(np.abs(estimate.r_o - run.r_o[end]) < 1e-3)
        assert abs(estimate.s_h - run.s_h[end]) < 1e-3


def test_the_cone_rows_are_the_contact_models(run_and_estimates):
    run, estimates = run_and_estimates
    for k in (10, 2500, 11_999):
        estimate = estimates[k]
        n_rows, b = contact.friction_cone(
            run.poses[k, 2],
            estimate.mu_h,
            estimate.torque_lever,
            estimate.ground_rows,
            estimate.ground_bounds,
        )
        np.testing.assert_allclose(estimate.cone_rows, n_rows, atol=1e-14)
        np.testing.assert_allclose(estimate.cone_bounds, b, atol=1e-14)
        np.testing.assert_allclose(estimate.margins, b - n_rows @ run.wrenches[k], atol=1e-12)
        np.testing.assert_array_equal(estimate.wrench, run.wrenches[k])


def test_estimates_are_immutable(run_and_estimates):
    estimate = run_and_estimates[1][-1]
    for array in (
        estimate.wrench,
        estimate.cone_rows,
        estimate.margins,
        estimate.row_valid,
        estimate.ground_rows,
    ):
        assert not array.flags.writeable
    with pytest.raises(dataclasses.FrozenInstanceError):
        estimate.mu_h = 1.0


def test_dropouts_are_skipped_without_changing_anything():
    run = synthetic_run(1)
    first, second = Estimator(), Estimator()
    for k in range(300):
        expected = first.update(run.times[k], run.poses[k], run.wrenches[k])
        if k == 150:
            dropped = second.update(run.times[k] - 0.0005, [np.nan, 0.0, 0.0], run.wrenches[k])
            assert dropped.skipped and dropped.time == run.times[k] - 0.0005
            assert dropped.margins is second.update(run.times[k], run.poses[k], [1.0, np.inf, 0.0]).margins
        estimate = second.update(run.times[k], run.poses[k], run.wrenches[k])
        assert not estimate.skipped
        np.testing.assert_array_equal(estimate.margins, expected.margins)
        assert estimate.configuration == expected.configuration
        np.testing.assert_equal(estimate.s_h, expected.s_h)


def test_a_dropout_before_any_sample_gives_an_empty_estimate():
    estimate = Estimator().update(0.0, [0.0, 0.0, 0.0], [np.nan, 0.0, 0.0])
    assert estimate.skipped and not estimate.in_contact and not estimate.row_valid.any()
    assert np.isnan(estimate.cone_rows).all() and not estimate.kinematics_valid


def test_no_contact_force_means_not_in_contact():
    estimate = Estimator().update(0.0, [0.1, 0.1, 0.0], [0.5, 0.0, 0.0])
    assert not estimate.in_contact and not estimate.s_h_valid
    assert estimate.hand_mode != ContactMode.STICK  # unestimated friction: may be sliding


def test_replay_is_the_same_as_updating_one_by_one():
    run = synthetic_run(2)
    estimator = Estimator(Hand(half_length=L_H))
    one_by_one = [
        estimator.update(*sample) for sample in zip(run.times[:200], run.poses, run.wrenches, strict=False)
    ]
    replayed = replay(run.times[:200], run.poses[:200], run.wrenches[:200], Hand(half_length=L_H))
    for a, b in zip(one_by_one, replayed, strict=True):
        np.testing.assert_array_equal(a.margins, b.margins)
        assert a.configuration == b.configuration


def test_bad_input_raises_naming_the_problem():
    with pytest.raises(ValueError, match="shape"):
        Estimator().update(0.0, [0.0, 0.0], [1.0, 0.0, 0.0])
    with pytest.raises(TypeError, match="hand"):
        Estimator(EstimatorParams())
    with pytest.raises(TypeError, match="friction"):
        EstimatorParams(friction=KinematicsParams())
    with pytest.raises(ValueError, match="contact_force"):
        EstimatorParams(contact_force=-1.0)


def test_conservative_ground_reports_do_not_stop_the_kinematics():
    """A rigid rotation about a sticking ground contact before any sliding was seen: the classifier
    says the ground "may be sliding" (no friction face yet), yet the regression converges."""
    rng = np.random.default_rng(3)
    times = np.arange(3000) / RATE
    r_o = np.array([0.10, 0.0])
    estimator = Estimator(Hand(half_length=L_H))
    reported_sliding = 0
    for t in times:
        theta = math.radians(10.0) * math.sin(2.0 * math.pi * t / 1.5)
        pose = geometry.hand_pose_from_contact(theta, 0.01, D, r_o) + rng.normal(0.0, NOISE_POSE)
        swing = math.sin(2.0 * math.pi * t / 0.7)
        world = np.array([3.0 * swing, -12.0, 0.0])  # well inside the true cone
        wrench = geometry.wrench_world_to_hand(theta, world) + rng.normal(0.0, NOISE_WRENCH)
        estimate = estimator.update(t, pose, wrench)
        reported_sliding += estimate.ground_mode != ContactMode.STICK
    assert reported_sliding > 0.2 * len(times)  # the conservative classifier does say it
    assert estimate.kinematics_valid
    assert abs(estimate.d - D) < 2e-3 and np.all(np.abs(estimate.r_o - r_o) < 2e-3)


@pytest.mark.parametrize(
    ("command", "kept"),
    [
        (ContactConfiguration(), ContactConfiguration()),
        (
            ContactConfiguration(hand_mode=ContactMode.SLIDE_NEG),
            ContactConfiguration(hand_mode=ContactMode.SLIDE_POS),
        ),
        (
            ContactConfiguration(ground_mode=ContactMode.SLIDE_POS),
            ContactConfiguration(ground_mode=ContactMode.SLIDE_NEG),
        ),
    ],
)
def test_a_command_keeps_the_contacts_it_keeps_and_takes_the_moving_one_as_reported(command, kept):
    reported = ContactConfiguration(ContactMode.SLIDE_POS, HandGeometry.PIVOT_NEG, ContactMode.SLIDE_NEG)
    assert commanded_modes(reported, command) == kept
    assert commanded_modes(reported, None) == reported


def test_a_sticking_command_lets_the_kinematics_converge_through_conservative_hand_reports():
    """A rigid rotation with the hand pressing at |f_t| = 0.3 f_n (inside the true cone, μ_h = 0.5,
    but beyond the hand friction prior): the hand "may slide" on every sample, so without the
    command ``s_h`` is released each time; with it, the regression uses eq. 16 and converges."""
    rng = np.random.default_rng(4)
    r_o, hand = np.array([0.10, 0.0]), Hand(half_length=L_H)
    told, untold = Estimator(hand), Estimator(hand)
    for t in np.arange(2000) / RATE:
        theta = math.radians(10.0) * math.sin(2.0 * math.pi * t / 1.5)
        pose = geometry.hand_pose_from_contact(theta, 0.01, D, r_o) + rng.normal(0.0, NOISE_POSE)
        wrench = np.array([12.0, 3.6, 0.0]) + rng.normal(0.0, NOISE_WRENCH)
        with_command = told.update(t, pose, wrench, ContactConfiguration())
        without = untold.update(t, pose, wrench)
    assert with_command.hand_mode != ContactMode.STICK  # the report itself is unchanged
    assert with_command.kinematics_valid and abs(with_command.d - D) < 2e-3
    assert not without.kinematics_valid
    assert np.all(np.isfinite(without.kinematics_mean))  # rough, for a controller
    assert max(without.kinematics_std[1:]) > max(with_command.kinematics_std[1:])


@pytest.mark.parametrize(
    ("field", "value", "error"),
    [
        ("moment_mismatch_tilt", 0.0, ValueError),
        ("moment_mismatch_tilt", math.nan, ValueError),
        ("moment_mismatch_tilt", True, TypeError),
        ("moment_mismatch_samples", 0, ValueError),
        ("moment_mismatch_samples", 2.5, TypeError),
        ("moment_doubt_tilt", 0.0, ValueError),
        ("moment_doubt_tilt", "0.03", TypeError),
        ("hand_give", -1e-3, ValueError),
        ("hand_give", math.inf, ValueError),
        ("hand_give_filter", 0.0, ValueError),
        ("hand_give_filter", "0.1", TypeError),
    ],
)
def test_the_moment_checks_parameters_are_refused_naming_the_field(field, value, error):
    with pytest.raises(error, match=field):
        EstimatorParams(**{field: value})


def _cone(fitted: tuple[bool, bool]) -> GroundCone:
    rows, nan = np.array([[0.8, 0.6], [-0.8, 0.6]]), np.full(2, np.nan)
    return GroundCone(rows, np.zeros(2), True, fitted, math.nan, nan, np.array(geometry.WORLD_UP))


@pytest.mark.parametrize(
    "ground_mode", [ContactMode.STICK, ContactMode.SLIDE_POS, ContactMode.SLIDE_NEG], ids=lambda m: m.name
)
def test_the_kinematics_reports_follow_a_refit_of_the_ground_rows(ground_mode):
    """The reports the kinematics work under are kept from sample to sample (the inputs are the same
    objects for long stretches) and through a refit of the ground rows where they do not read them;
    after each refit they are what :func:`kinematic_modes` makes of the new rows."""
    estimator = Estimator(Hand(half_length=L_H))
    likely = ContactConfiguration(ContactMode.STICK, HandGeometry.FLUSH, ground_mode)
    for fitted in [(False, False), (True, True), (False, False), (True, False), (False, True)]:
        cone = _cone(fitted)
        modes = estimator._reports(likely, None, 0.3, cone)[0]
        assert modes == kinematic_modes(likely, cone), (fitted, modes)
