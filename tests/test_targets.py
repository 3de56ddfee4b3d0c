"""Statics targets (ccopt.control.targets) and what they feed: the estimated statics of an estimate, the
regulation wrench against the true object's statics, the hand friction explored one step beyond μ̂_h,
the cone rows at that friction (ccopt.contact.with_hand_friction) and what the controller reads
(ccopt.closed_loop.control_input, enforced_rows)."""

from __future__ import annotations

import dataclasses
import functools
import itertools
import math

import numpy as np
import pytest

from ccopt import contact, geometry, objects, statics
from ccopt.closed_loop import control_input, enforced_rows
from ccopt.contact import Row
from ccopt.control.targets import (
    UNJUDGED,
    StaticsTarget,
    TargetGoal,
    estimated_statics,
    seeks_friction,
    statics_target,
)
from ccopt.estimation import Estimate, Estimator
from ccopt.estimation.gravity import UNKNOWN as UNKNOWN_GRAVITY
from ccopt.hand import Hand
from ccopt.modes import Motion
from ccopt.plant.base import StartConfig

LEVER = 0.0255  # the estimate's torque lever l_h_eff (m)
LIMITS = (3.0, 25.0)  # hand normal force limits (N)
GOAL = TargetGoal(force_limits=LIMITS, nominal_force=8.0, margin=3.0)
STEP = 0.1  # friction step of the exploring goal
EXPLORING = dataclasses.replace(GOAL, friction_step=STEP)
CROSSED = {Motion.SLIDE_GROUND_POS: 0, Motion.SLIDE_GROUND_NEG: 1}
"""The ground row (index into GROUND_ROWS) each ground slide crosses: +x blocked by the right face."""
FITTED_CASES = list(itertools.product((False, True), repeat=2))

# A known object (hand friction, ground friction, mass, d, centre of mass along the face and above the
# ground contact) and a configuration at which every motion's LP is finite (checked in a test).
OBJECT = statics.ObjectStatics.of_model(0.6, 0.5, 0.3, 0.03, 0.01, 0.02)
THETA_O, S_H = 0.15, 0.0


@dataclasses.dataclass(frozen=True)
class KnownGravity:
    """A gravity model with the attributes :func:`estimated_statics` reads of an estimate's
    :class:`~ccopt.estimation.gravity.GravityEstimate`: ``M(θ) = a cos θ + b sin θ`` (N·m)."""

    a: float
    b: float
    valid: bool = True


@functools.cache
def measured_estimate() -> Estimate:
    """A real estimate after a few samples of a hand pressing at θ_h = 0.2: no kinematics yet."""
    estimator = Estimator(Hand())
    for k in range(10):
        estimate = estimator.update(k * 1e-3, [0.1, 0.06, 0.2], [10.0, 0.5, 0.01])
    return estimate


def equilibrium_wrench(truth: statics.ObjectStatics, theta_o: float, s_h: float) -> np.ndarray:
    """A hand wrench that balances the weight's moment about the ground contact (docs §7):
    ``τ − d f_t + s_h f_n + M(θ_o) = 0``, with ``f_n = 10``, ``f_t = 1`` N."""
    f_n, f_t = 10.0, 1.0
    return np.array([f_n, f_t, truth.d * f_t - s_h * f_n - truth.gravity(theta_o)])


def known_estimate(
    truth: statics.ObjectStatics,
    theta_o: float,
    s_h: float,
    *,
    model_gravity: bool = False,
    fitted: tuple[bool, bool] = (True, True),
    mu_h: float | None = None,
) -> Estimate:
    """A real estimate with its kinematics, cone and wrench replaced by those of ``truth`` at
    ``(θ_o, s_h)`` with the hand flush (``θ_h = θ_o``): the hand wrench balances the weight, the ground
    rows are the true ones (``fitted`` as given), the hand friction is ``mu_h`` (default the true one)
    and the gravity moment is the measured one, or a valid model of the true one (``model_gravity``)."""
    mu_h = truth.mu_h if mu_h is None else mu_h
    wrench = equilibrium_wrench(truth, theta_o, s_h)
    rows, bounds = contact.friction_cone(theta_o, mu_h, LEVER, truth.ground_rows, truth.ground_bounds)
    gravity = KnownGravity(truth.gravity.cos_coefficient, truth.gravity.sin_coefficient)
    r_o = np.array([0.1, 0.0])
    return dataclasses.replace(
        measured_estimate(),
        wrench=wrench,
        cone_rows=rows,
        cone_bounds=bounds,
        margins=bounds - rows @ wrench,
        row_valid=np.ones(6, dtype=bool),
        mu_h=mu_h,
        torque_lever=LEVER,
        ground_rows=truth.ground_rows,
        ground_bounds=truth.ground_bounds,
        ground_fitted=fitted,
        theta_o=theta_o,
        s_h=s_h,
        s_g=float(r_o[0]),
        d=truth.d,
        r_o=r_o,
        theta_o_valid=True,
        s_h_valid=True,
        contact_valid=True,
        gravity=gravity if model_gravity else UNKNOWN_GRAVITY,
    )


def with_friction(truth: statics.ObjectStatics, mu_h: float) -> statics.ObjectStatics:
    """``truth`` with the hand friction ``mu_h``."""
    return dataclasses.replace(truth, mu_h=mu_h)


def regulation(
    truth: statics.ObjectStatics, theta_o: float, s_h: float, motion: Motion
) -> statics.StaticsResult:
    """The regulation wrench of ``motion`` on ``truth`` for :data:`GOAL`."""
    return statics.regulation_wrench(
        truth, theta_o, s_h, motion, LEVER, LIMITS, GOAL.nominal_force, GOAL.margin
    )


def assert_target_is(target: StaticsTarget, expected: statics.StaticsResult, abs_tol: float = 0.0) -> None:
    """The target holds the regulation wrench ``expected`` (its normal and tangential force and margin)."""
    if expected.wrench is None:
        assert (target.force, target.tangential, target.margin) == (None, None, expected.margin)
        return
    assert target.force == pytest.approx(expected.wrench[0], abs=abs_tol)
    assert target.tangential == pytest.approx(expected.wrench[1], abs=abs_tol)
    assert target.margin == pytest.approx(expected.margin, abs=abs_tol)


def wrench_margin(truth: statics.ObjectStatics, theta_o: float, motion: Motion, wrench: np.ndarray) -> float:
    """The smallest kept-row margin of ``wrench`` (torque rows over the lever), as the LP counts it."""
    rows, bounds = contact.friction_cone(theta_o, truth.mu_h, LEVER, truth.ground_rows, truth.ground_bounds)
    slack = (bounds - rows @ wrench) * np.array([1.0, 1.0, 1.0 / LEVER, 1.0 / LEVER, 1.0, 1.0])
    removed = {Motion.SLIDE_HAND_POS: 0, Motion.SLIDE_HAND_NEG: 1, **{m: 4 + i for m, i in CROSSED.items()}}
    kept = [row for row in range(6) if row != removed.get(motion)]
    return float(slack[kept].min())


# --- estimated_statics ----------------------------------------------------------------------------


def test_nothing_is_judged_before_the_kinematics_are_known():
    """A real estimate of a few samples has no kinematics: no statics, and every target is UNJUDGED
    (NaN margin, no force), exploring or not."""
    estimate = measured_estimate()
    assert not estimate.kinematics_valid
    assert estimated_statics(estimate, 0.2) is None
    for motion, goal in itertools.product(Motion, (GOAL, EXPLORING)):
        target = statics_target(estimate, 0.2, motion, goal)
        assert target.force is None and target.tangential is None and target.mu_h is None
        assert math.isnan(target.margin) and not target.judged


@pytest.mark.parametrize(
    "change",
    [{"theta_o_valid": False}, {"s_h_valid": False}, {"contact_valid": False}, {"d": math.nan}],
    ids=["theta_o", "s_h", "contact", "nan_d"],
)
def test_an_estimate_without_usable_kinematics_has_no_statics(change):
    """Any one of the kinematics missing (or flagged valid but NaN) leaves nothing to judge, where the
    same estimate with them is judged."""
    estimate = known_estimate(OBJECT, THETA_O, S_H)
    assert estimated_statics(estimate, THETA_O) is not None
    broken = dataclasses.replace(estimate, **change)
    assert estimated_statics(broken, THETA_O) is None
    assert statics_target(broken, THETA_O, Motion.PIVOT, EXPLORING) == UNJUDGED


@pytest.mark.parametrize("fitted", FITTED_CASES)
@pytest.mark.parametrize("motion", [None, *Motion], ids=lambda m: getattr(m, "value", "none"))
def test_ground_rows_are_known_where_fitted_and_where_a_ground_slide_crosses(motion, fitted):
    """``ground_known`` is ``Estimate.ground_fitted``, both sides once one is (the other is its mirror
    image about world up: the true rows are symmetric, so it is the true row), and the row the
    commanded ground slide crosses (+x: GROUND_SLIDE_POS, −x: GROUND_SLIDE_NEG) whatever the fit
    says."""
    estimate = known_estimate(OBJECT, THETA_O, S_H, fitted=fitted)
    known = estimated_statics(estimate, THETA_O, motion=motion)
    expected = [any(fitted)] * 2
    if motion in CROSSED:
        expected[CROSSED[motion]] = True
    assert known.ground_known == tuple(expected)
    np.testing.assert_array_equal(known.ground_rows, OBJECT.ground_rows)
    np.testing.assert_array_equal(known.ground_bounds, OBJECT.ground_bounds)
    assert (known.mu_h, known.d) == (OBJECT.mu_h, OBJECT.d)


@pytest.mark.parametrize("fitted", FITTED_CASES)
@pytest.mark.parametrize("motion", list(CROSSED), ids=lambda m: m.value)
def test_a_slide_is_sought_past_the_forces_seen_only_across_a_side_not_known(motion, fitted):
    """With ``push``, the row a ground slide crosses moves ``push`` N out where it is the hull of the
    sticking forces (no side fitted: a wrench on it need not slide the object), and stays where it is
    a friction face (fitted, or the mirror of one): the slide's limit itself (pushed past it, a
    random square's second slide at 38° tilted its wrench onto the hand's torque limit)."""
    estimate = known_estimate(OBJECT, THETA_O, S_H, fitted=fitted)
    push, side = 1.5, CROSSED[motion]
    known = estimated_statics(estimate, THETA_O, motion=motion, push=push)
    expected = OBJECT.ground_bounds.copy()
    if not any(fitted):
        expected[side] += push
    np.testing.assert_array_equal(known.ground_bounds, expected)
    assert seeks_friction(estimate, motion) == (not any(fitted))  # a probe of the ground's friction
    assert not seeks_friction(estimate, Motion.PIVOT)


def test_the_hand_friction_is_the_estimates_unless_given():
    estimate = known_estimate(OBJECT, THETA_O, S_H, mu_h=0.35)
    assert estimated_statics(estimate, THETA_O).mu_h == 0.35
    assert estimated_statics(estimate, THETA_O, mu_h=0.45).mu_h == 0.45


@pytest.mark.parametrize(
    "gravity", [UNKNOWN_GRAVITY, KnownGravity(0.3, -0.2, valid=False)], ids=["unknown", "invalid"]
)
def test_without_a_valid_gravity_model_the_moment_is_the_measured_wrenchs(gravity):
    """The gravity moment at the current configuration balances the measured wrench's moment about the
    ground contact: ``M = −v_θ·w`` with ``v_θ`` from ``contact.admissible_motions`` and, written out,
    ``−(s_h f_n − d f_t + τ)`` (docs §7)."""
    rng = np.random.default_rng(11)
    for _ in range(20):
        theta_h, s_h, d = rng.uniform(-0.6, 0.6), rng.uniform(-0.03, 0.03), rng.uniform(0.02, 0.12)
        wrench = np.array([rng.uniform(3.0, 25.0), rng.uniform(-5.0, 5.0), rng.uniform(-0.3, 0.3)])
        estimate = dataclasses.replace(
            known_estimate(OBJECT, theta_h, s_h), s_h=s_h, d=d, wrench=wrench, gravity=gravity
        )
        moment = estimated_statics(estimate, theta_h).gravity(theta_h)
        v_theta = contact.admissible_motions(theta_h, s_h, d)[:, 0]
        assert moment == pytest.approx(-float(v_theta @ wrench), rel=1e-12, abs=1e-15)
        f_n, f_t, tau = wrench
        assert moment == pytest.approx(-(s_h * f_n - d * f_t + tau), rel=1e-12, abs=1e-15)


def test_a_valid_gravity_model_is_used_as_it_is():
    """A valid model gives ``M(θ) = a cos θ + b sin θ`` at every angle, not the measured moment
    (which differs here)."""
    model = KnownGravity(0.12, -0.05)
    estimate = dataclasses.replace(known_estimate(OBJECT, THETA_O, S_H), gravity=model)
    measured = -float(contact.admissible_motions(THETA_O, S_H, OBJECT.d)[:, 0] @ estimate.wrench)
    gravity = estimated_statics(estimate, THETA_O).gravity
    assert abs(gravity(THETA_O) - measured) > 0.1
    for theta in (-0.5, 0.0, THETA_O, 0.9):
        assert gravity(theta) == pytest.approx(0.12 * math.cos(theta) - 0.05 * math.sin(theta), rel=1e-12)


# --- statics_target on an estimate of a known object ----------------------------------------------


def test_every_motion_has_a_finite_best_wrench_at_the_test_configuration():
    """A check of the setup the comparisons below use: at this configuration every motion has a
    wrench, some reach the goal's margin and some fall short of it (both branches of the regulation
    wrench are compared)."""
    margins = []
    for motion in Motion:
        result = statics.best_wrench(OBJECT, THETA_O, S_H, motion, LEVER, LIMITS)
        assert result.wrench is not None, motion
        margins.append(result.margin)
    assert min(margins) < GOAL.margin < max(margins)


@pytest.mark.parametrize("model_gravity", [True, False], ids=["model_gravity", "measured_gravity"])
@pytest.mark.parametrize("motion", list(Motion), ids=lambda m: m.value)
def test_the_target_is_the_regulation_wrench_of_the_true_statics(motion, model_gravity):
    """On an estimate equal to a known object (true hand friction, fitted true ground rows, true d),
    the target is ``statics.regulation_wrench`` on that object's true ``ObjectStatics``. With the
    true gravity model the LP's input is the same to the bit; the measured moment ``M`` is balanced
    up to rounding, hence the 1e-9 N."""
    estimate = known_estimate(OBJECT, THETA_O, S_H, model_gravity=model_gravity)
    target = statics_target(estimate, THETA_O, motion, GOAL)
    expected = regulation(OBJECT, THETA_O, S_H, motion)
    assert target.mu_h is None and target.judged
    assert_target_is(target, expected, abs_tol=0.0 if model_gravity else 1e-9)


@pytest.mark.parametrize("motion", list(Motion), ids=lambda m: m.value)
def test_the_target_on_the_oracles_true_statics(motion):
    """The second path: a library pentagon started tilted, its statics by ``statics.true_statics``
    (the experimenter's oracle); an estimate that knows them gets their regulation wrench."""
    hand = Hand()
    truth = statics.true_statics(objects.make_object("pentagon"), StartConfig(theta_o=0.3, s_h=0.002), hand)
    estimate = known_estimate(truth.statics, truth.theta_o, truth.s_h)
    target = statics_target(estimate, truth.theta_o, motion, GOAL)
    expected = regulation(truth.statics, truth.theta_o, truth.s_h, motion)
    assert expected.wrench is not None  # every motion has a wrench here (some short of the margin)
    assert_target_is(target, expected, abs_tol=1e-9)


@pytest.mark.parametrize(
    ("theta_o", "s_h", "motion"),
    [
        (0.15, 0.004, Motion.SLIDE_HAND_NEG),
        (0.4172418709091269, 0.015849581957032045, Motion.SLIDE_GROUND_POS),
    ],
    ids=["slide_hand_neg", "slide_ground_pos"],
)
def test_a_motion_with_a_wrench_is_never_ruled_out(theta_o, s_h, motion):
    """``-inf`` means no wrench meets the equilibrium, the force limits and the sliding limit. Here one
    does, written out (the removed row at 0, the moments balanced, f_n within the limits), so the
    target's margin is at least that wrench's smallest kept-row margin."""
    f_n = 10.0
    if motion is Motion.SLIDE_HAND_NEG:
        f_t = OBJECT.mu_h * f_n  # μ_h f_n − f_t = 0
    else:  # the right ground face: a·f = b, f = f_n e_n + f_t e_t
        a, b = OBJECT.ground_rows[0], OBJECT.ground_bounds[0]
        f_t = (b - f_n * a @ geometry.hand_normal(theta_o)) / (a @ geometry.hand_tangent(theta_o))
    wrench = np.array([f_n, f_t, OBJECT.d * f_t - s_h * f_n - OBJECT.gravity(theta_o)])
    floor = wrench_margin(OBJECT, theta_o, motion, wrench)
    goal = dataclasses.replace(GOAL, margin=100.0)  # the best margin, not one capped by the goal
    target = statics_target(known_estimate(OBJECT, theta_o, s_h), theta_o, motion, goal)
    assert target.force is not None
    assert target.margin >= floor - 1e-6


# --- a goal's hand slide once the hand has slid ---------------------------------------------------

# Heavy objects whose hand slide's margin peaks inside the force limits (flush hand at θ_o = 0).
HEAVY = statics.ObjectStatics.of_model(0.6, 0.5, 2.0, 0.03, 0.01, 0.02)
WIDE = statics.ObjectStatics.of_model(0.6, 0.5, 1.0, 0.06, -0.02, 0.02)


def hand_slide_margins(truth: statics.ObjectStatics, motion: Motion, forces: np.ndarray) -> np.ndarray:
    """A hand slide's wrench is set by ``f_n`` alone: ``f_t = ∓μ_h f_n`` on the removed row (+s_h:
    the hand pushes the object's face back, −), ``τ`` from the moment balance about the ground contact
    (:func:`equilibrium_wrench`); its margin at each force, the smallest kept-row margin."""
    sign = -1.0 if motion is Motion.SLIDE_HAND_POS else 1.0
    margins = []
    for f_n in forces:
        f_t = sign * truth.mu_h * f_n
        wrench = np.array([f_n, f_t, truth.d * f_t - truth.gravity(0.0)])
        margins.append(wrench_margin(truth, 0.0, motion, wrench))
    return np.array(margins)


@pytest.mark.parametrize(
    ("truth", "motion"),
    [(HEAVY, Motion.SLIDE_HAND_POS), (WIDE, Motion.SLIDE_HAND_NEG)],
    ids=["heavy_pos", "wide_neg"],
)
def test_a_planned_hand_slide_holds_its_largest_margin_once_the_hand_slid(truth, motion):
    """Once the hand has slid, a goal's planned hand slide holds the normal force of the largest
    margin, found here by a scan of the force (0.01 N steps, the wrench written out): inside the
    limits, away from the nominal force. A probe, or any hand slide before the hand slid, keeps the
    nominal rule: the force nearest the nominal one at the goal's margin."""
    forces = np.linspace(*LIMITS, 2201)
    margins = hand_slide_margins(truth, motion, forces)
    peak = forces[margins.argmax()]
    assert LIMITS[0] + 1.0 < peak < LIMITS[1] - 1.0 and abs(peak - GOAL.nominal_force) > 1.5
    assert margins.max() > GOAL.margin + 1.0
    slid = dataclasses.replace(known_estimate(truth, 0.0, 0.0, model_gravity=True), hand_slid=True)
    target = statics_target(slid, 0.0, motion, GOAL, planned=True)
    assert target.force == pytest.approx(peak, abs=0.011)
    held = hand_slide_margins(truth, motion, np.array([target.force]))[0]
    assert target.margin == pytest.approx(held, abs=1e-6)  # the margin of the wrench held
    assert held >= margins.max() - 1e-9  # no force of the scan does better
    for estimate, planned in ((slid, False), (dataclasses.replace(slid, hand_slid=False), True)):
        nominal = statics_target(estimate, 0.0, motion, GOAL, planned=planned)
        assert_target_is(nominal, regulation(truth, 0.0, 0.0, motion))
        assert nominal.margin == pytest.approx(GOAL.margin, abs=1e-5)


@pytest.mark.parametrize(("theta_o", "push"), [(0.0, 1.5), (0.15, 6.0), (0.4, 6.0)])
def test_a_slide_sought_past_the_forces_seen_falls_back_to_their_edge_where_the_push_has_no_margin(
    theta_o, push
):
    """A ground slide across a side not known is sought ``push`` N past the sticking forces seen;
    where no wrench there keeps a margin (the true object's LP on the pushed row, written out with
    ``statics.regulation_wrench``), the target is the regulation wrench on the edge itself (here the
    true row: the estimate's hull is the true face), with its margin; where one does, the pushed one
    (the same LPs on inputs rounded differently: 1e-6 N)."""
    motion, goal = Motion.SLIDE_GROUND_POS, dataclasses.replace(GOAL, push=push)
    estimate = known_estimate(OBJECT, theta_o, 0.0, model_gravity=True, fitted=(False, False))
    bounds = OBJECT.ground_bounds + np.array([push, 0.0])
    pushed_truth = dataclasses.replace(OBJECT, ground_bounds=bounds)
    pushed = regulation(pushed_truth, theta_o, 0.0, motion)
    target = statics_target(estimate, theta_o, motion, goal)
    if pushed.margin < 0.0:
        at_edge = regulation(OBJECT, theta_o, 0.0, motion)
        assert at_edge.margin > 0.0
        assert_target_is(target, at_edge, abs_tol=1e-6)
    else:
        assert_target_is(target, pushed, abs_tol=1e-6)


# --- exploring the hand friction ------------------------------------------------------------------

# An object a ground slide needs more hand friction than μ̂_h for: the hand pushes sideways by
# μ_g (f_n + m g), which μ̂_h = 0.45 barely holds at f_max (closed form at θ = 0: (μ_h − μ_g) f_max
# − μ_g m g = 0.07 N) and μ̂_h + 0.1 holds with 2.6 N. Holding and pivoting at μ̂_h = 0.05 are limited
# by μ̂_h f_max = 1.25 N.
SLIDER = statics.ObjectStatics.of_model(0.45, 0.4, 0.3, 0.02, 0.0, 0.01)


def best(truth: statics.ObjectStatics, motion: Motion) -> float:
    return statics.best_wrench(truth, 0.0, 0.0, motion, LEVER, LIMITS).margin


@pytest.mark.parametrize(
    ("motion", "mu_hat"),
    [
        (Motion.SLIDE_GROUND_POS, 0.45),
        (Motion.SLIDE_GROUND_NEG, 0.45),
        (Motion.HOLD, 0.05),
        (Motion.PIVOT, 0.05),
    ],
    ids=["slide_ground_pos", "slide_ground_neg", "hold", "pivot"],
)
def test_a_sticking_hand_explores_one_friction_step_where_it_falls_short(motion, mu_hat):
    """Where μ̂_h leaves the motion short of the goal's margin and μ̂_h + step does better (both by
    ``best_wrench`` on the object at those frictions), the target is the regulation wrench at
    μ̂_h + step, says so, and keeps a larger margin than the one at μ̂_h."""
    short, bolder = with_friction(SLIDER, mu_hat), with_friction(SLIDER, mu_hat + STEP)
    assert best(short, motion) < GOAL.margin
    assert best(bolder, motion) > best(short, motion) + 1.0
    estimate = known_estimate(SLIDER, 0.0, 0.0, mu_h=mu_hat, model_gravity=True)
    target = statics_target(estimate, 0.0, motion, EXPLORING)
    assert target.mu_h == mu_hat + STEP
    assert_target_is(target, regulation(bolder, 0.0, 0.0, motion))
    unexplored = regulation(short, 0.0, 0.0, motion)
    assert target.margin > unexplored.margin
    no_step = statics_target(estimate, 0.0, motion, GOAL)
    assert no_step.mu_h is None
    assert_target_is(no_step, unexplored)


@pytest.mark.parametrize("motion", [Motion.SLIDE_HAND_POS, Motion.SLIDE_HAND_NEG], ids=lambda m: m.value)
def test_a_hand_slide_never_explores(motion):
    """A hand slide short of its margin at μ̂_h = 0.05 (closed form 2 μ̂_h f_max = 2.5 N) that μ̂_h + step
    would help: the hand slides at the friction it has, so the target stays at μ̂_h."""
    short, bolder = with_friction(SLIDER, 0.05), with_friction(SLIDER, 0.05 + STEP)
    assert best(short, motion) < GOAL.margin
    assert best(bolder, motion) > best(short, motion) + 1.0
    estimate = known_estimate(SLIDER, 0.0, 0.0, mu_h=0.05, model_gravity=True)
    target = statics_target(estimate, 0.0, motion, EXPLORING)
    assert target.mu_h is None
    assert_target_is(target, regulation(short, 0.0, 0.0, motion))


def test_a_motion_that_reaches_its_margin_does_not_explore():
    """Holding at μ̂_h = 0.45 keeps far more than 3 N (closed form μ̂_h f_max = 11.25 N): no step."""
    short = with_friction(SLIDER, 0.45)
    assert best(short, Motion.HOLD) > GOAL.margin
    estimate = known_estimate(SLIDER, 0.0, 0.0, mu_h=0.45, model_gravity=True)
    target = statics_target(estimate, 0.0, Motion.HOLD, EXPLORING)
    assert target.mu_h is None
    assert_target_is(target, regulation(short, 0.0, 0.0, Motion.HOLD))


def test_a_hand_seen_sliding_is_not_explored_beyond_its_friction():
    """Once the hand has slid where it was commanded to (``Estimate.hand_slid``), μ̂_h was measured at
    the limit: a ground slide short of its margin at μ̂_h (and better at μ̂_h + step, as above) gets
    the regulation wrench at μ̂_h."""
    short = with_friction(SLIDER, 0.45)
    assert best(short, Motion.SLIDE_GROUND_POS) < GOAL.margin
    assert best(with_friction(SLIDER, 0.45 + STEP), Motion.SLIDE_GROUND_POS) > best(
        short, Motion.SLIDE_GROUND_POS
    )
    estimate = known_estimate(SLIDER, 0.0, 0.0, mu_h=0.45, model_gravity=True)
    slid = dataclasses.replace(estimate, hand_slid=True)
    target = statics_target(slid, 0.0, Motion.SLIDE_GROUND_POS, EXPLORING)
    assert target.mu_h is None
    assert_target_is(target, regulation(short, 0.0, 0.0, Motion.SLIDE_GROUND_POS))
    assert statics_target(estimate, 0.0, Motion.SLIDE_GROUND_POS, EXPLORING).mu_h == 0.45 + STEP


@pytest.mark.parametrize("goal", [GOAL, EXPLORING], ids=["no_step", "step"])
def test_no_wrench_at_all_is_a_margin_of_minus_infinity(goal):
    """A ground slide to +x on μ_g = 1 with the hand at θ_h = −45°: the hand's tangent runs along the
    right ground face (``a·e_t = 0``) and its normal force leads away from it (``a·e_n < 0 < b``), so
    no ``f_n ≥ 0`` reaches the face; ``best_wrench`` agrees. No force, margin ``-inf``, nothing
    explored."""
    truth = statics.ObjectStatics.of_model(0.5, 1.0, 0.3, 0.05, 0.0, 0.02)
    theta = -math.pi / 4
    a, b = truth.ground_rows[0], truth.ground_bounds[0]
    assert abs(a @ geometry.hand_tangent(theta)) < 1e-12
    assert a @ geometry.hand_normal(theta) < 0.0 < b
    assert statics.best_wrench(truth, theta, 0.0, Motion.SLIDE_GROUND_POS, LEVER, LIMITS).wrench is None
    target = statics_target(known_estimate(truth, theta, 0.0), theta, Motion.SLIDE_GROUND_POS, goal)
    assert (target.force, target.tangential, target.mu_h) == (None, None, None)
    assert target.margin == -math.inf and target.judged


# --- the hand friction rows and what the controller reads -----------------------------------------


@pytest.mark.parametrize(("theta", "mu_from", "mu_to"), [(0.0, 0.1, 0.5), (0.4, 0.5, 0.2), (-0.7, 0.3, 0.9)])
def test_with_hand_friction_is_the_cone_at_the_new_friction(theta, mu_from, mu_to):
    """Against ``contact.friction_cone`` built at the new μ: equal; only the μ column of the two hand
    friction rows changed; the input (read-only, as an estimate's) is left as it was."""
    ground_a, ground_b = contact.model_ground_rows(0.8, 0.3)
    rows, _ = contact.friction_cone(theta, mu_from, LEVER, ground_a, ground_b)
    rows.flags.writeable = False
    before = rows.copy()
    changed = contact.with_hand_friction(rows, mu_to)
    expected, _ = contact.friction_cone(theta, mu_to, LEVER, ground_a, ground_b)
    np.testing.assert_array_equal(changed, expected)
    where = np.zeros((6, 3), dtype=bool)
    where[[Row.HAND_SLIDE_POS, Row.HAND_SLIDE_NEG], 0] = True
    np.testing.assert_array_equal(changed != before, where)
    np.testing.assert_array_equal(rows, before)


def test_the_control_input_takes_the_explored_friction():
    """A target exploring μ: the controller's cone rows are the cone at μ̂_h + step (built by
    ``contact.friction_cone``), its ``mu_h`` that friction; bounds, force and margin as the target's."""
    estimate = known_estimate(SLIDER, 0.0, 0.0, mu_h=0.45)
    target = statics_target(estimate, 0.0, Motion.SLIDE_GROUND_POS, EXPLORING)
    assert target.mu_h is not None
    pose = geometry.hand_pose_from_contact(0.0, 0.0, SLIDER.d, estimate.r_o)
    state = control_input(estimate, pose, np.zeros(3), target)
    expected, _ = contact.friction_cone(0.0, 0.45 + STEP, LEVER, SLIDER.ground_rows, SLIDER.ground_bounds)
    np.testing.assert_allclose(state.cone_rows, expected, rtol=0.0, atol=1e-14)
    assert not np.allclose(state.cone_rows, estimate.cone_rows)
    assert state.mu_h == 0.45 + STEP
    np.testing.assert_array_equal(state.cone_bounds, estimate.cone_bounds)
    assert (state.force_target, state.tangential_target) == (target.force, target.tangential)
    assert state.statics_margin == target.margin


def test_the_control_input_of_a_target_that_does_not_explore_is_the_estimates():
    """A real estimate's cone and friction, unchanged, for a target at μ̂_h (its force and margin
    passed on) and for no target (none)."""
    estimate = measured_estimate()
    pose = np.array([0.1, 0.06, 0.2])
    for target, margin in ((StaticsTarget(8.0, 1.0, 2.0), 2.0), (UNJUDGED, None)):
        state = control_input(estimate, pose, np.zeros(3), target)
        np.testing.assert_array_equal(state.cone_rows, estimate.cone_rows)
        assert state.mu_h == estimate.mu_h
        assert (state.force_target, state.statics_margin) == (target.force, margin)


@pytest.mark.parametrize("fitted", FITTED_CASES)
def test_the_controller_enforces_ground_rows_only_where_fitted(fitted):
    """Hand rows as estimated; a ground row only if estimated *and* fitted to a friction face."""
    estimate = dataclasses.replace(
        measured_estimate(), row_valid=np.ones(6, dtype=bool), ground_fitted=fitted
    )
    expected = [True, True, True, True, fitted[0], fitted[1]]
    np.testing.assert_array_equal(enforced_rows(estimate), expected)
    state = control_input(estimate, np.array([0.1, 0.06, 0.2]), np.zeros(3))
    np.testing.assert_array_equal(state.row_valid, expected)
    unestimated = dataclasses.replace(estimate, row_valid=np.array([True] * 4 + [False] * 2))
    np.testing.assert_array_equal(enforced_rows(unestimated), [True] * 4 + [False] * 2)
