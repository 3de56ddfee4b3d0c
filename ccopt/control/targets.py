"""What the controller aims for, from the estimated statics: the wrench a motion needs, or that it cannot.

The object's statics (:mod:`ccopt.statics`) are evaluated on the *estimated* parameters: the hand
friction ``μ̂_h``, the estimated ground rows (the weight is inside them), the kinematics ``d̂``, ``ŝ_h``,
``θ̂_o``, the effective torque lever of the estimate and the gravity moment about the ground contact.
While no model of that moment is estimated, its value at the current configuration is read from the
measured wrench: in static equilibrium the moment of the hand wrench about the ground contact balances
it, ``M = −v_θ·w`` (:func:`ccopt.contact.admissible_motions`), which is all the statics at the current
configuration need.

:func:`statics_target` returns the regulation wrench of the commanded motion
(:func:`ccopt.statics.regulation_wrench`: the normal force nearest the nominal one at the margin the
motion needs) and that margin; before the kinematics are known nothing can be judged and the
controller keeps its nominal force.

**Exploring the hand friction.** ``μ̂_h`` is a lower bound, the largest ratio ``|f_t|/f_n`` seen
sticking (:mod:`ccopt.estimation.friction`): judged on it alone, a motion that needs a little more
(e.g. a ground slide, which the hand must push sideways) stays out of reach for good, since the
controller then never asks for a larger ratio and ``μ̂_h`` never grows. Where ``μ̂_h`` leaves a motion
that keeps the hand sticking short of its margin goal, the target is taken on ``μ̂_h + friction_step``
if that does better, and says so (:attr:`StaticsTarget.mu_h`): the controller's hand friction rows
then use it. The hand is asked for at most one step more than it was seen to hold; if it holds, the
estimate follows and the next step is taken from there; if it does not, it slides at the true
``μ_h``, which the estimate then learns. Once the hand has been seen sliding where it was
commanded to (``Estimate.hand_slid``), ``μ̂_h`` was measured at the limit and is not explored beyond.

**A goal's hand slide holds its largest margin.** A flush hand slide needs the moment balance
``|±d μ_h − s_h − M/f_n| ≤ l_h``, so its margin peaks at one normal force and falls steeply either
side; the force nearest the nominal one that keeps ``margin`` leaves only that margin (3 N), within
what the errors of ``μ̂_h``, ``M̂`` and ``ŝ_h`` move it. On the paper rectangle at 39° the hand slid
at ``f_n`` ≈ 11 N, where the true margin was 1.5–2.3 N (4.4 N at its best), and rolled halfway; on
the heavy triangle the true margin was positive only near 3 N, and the controller held 6–7 N. So
once the hand has slid (``μ̂_h`` measured), a goal's planned hand slide (``planned``: not a probe)
holds the wrench of the largest estimated margin. Paper study over three seeds, with the push
fallback of :attr:`TargetGoal.push`: trials whose hand-slide ratio is within its band 17 → 20 of
30, unintended slips 11 → 9; goals study unchanged or better. Probes keep the nominal rule (they
look for the limit), and so do scripted steps: on the robustness tours the largest margin cost
three trials (27 → 24 of 50 at the bar: slips and unfinished steps) that the nominal rule meets.
"""

from __future__ import annotations

import dataclasses
import functools
import math
from dataclasses import dataclass

import numpy as np

from ccopt import contact, modes, statics, validation
from ccopt.contact import GROUND_ROWS
from ccopt.estimation.estimator import Estimate
from ccopt.modes import REMOVED_ROWS, Motion, kept_contacts


@dataclass(frozen=True)
class StaticsTarget:
    """The estimated statics' answer for one motion at the current configuration.

    Attributes:
        force: normal force to hold, N (None: the controller's nominal force).
        tangential: tangential force of the regulation wrench, N (None: hold the current one).
        margin: the motion's estimated margin, N: ``-inf`` where the estimate rules it out, NaN where
            the estimate cannot judge yet.
        mu_h: the hand friction the target assumes where it explores beyond ``μ̂_h`` (module
            docstring), None where it takes ``μ̂_h``.
    """

    force: float | None
    tangential: float | None
    margin: float
    mu_h: float | None = None

    @property
    def judged(self) -> bool:
        """Whether the estimate could judge the motion."""
        return not math.isnan(self.margin)


UNJUDGED = StaticsTarget(None, None, math.nan)


def estimated_statics(
    estimate: Estimate,
    hand_angle: float,
    mu_h: float | None = None,
    motion: Motion | None = None,
    push: float = 0.0,
) -> statics.ObjectStatics | None:
    """The object's statics as the estimate knows them (None before the kinematics are known), with
    the hand friction ``mu_h`` instead of ``μ̂_h`` if given.

    The gravity moment is the model's where it is valid, else the measured one at the current
    configuration (module docstring). The ground rows are the friction faces as far as they are
    known (``Estimate.friction_faces``: a side the ground slid past, and the other side its mirror
    image); an unknown side is only where the sticking forces seen end, which bounds nothing a
    sticking motion may do. The row a ground slide of ``motion`` crosses, when unknown, is the
    exception: its hull estimate, inside the true face, moved out by ``push`` (N), is where that
    slide is sought (a wrench on the hull's row need not slide the object). A friction face the
    ground slid past is the slide's limit itself, and is not moved. The hand's
    contact patch is cut to the part of the face known (``Estimate.face``; the whole hand where an
    estimate has none).
    """
    values = (estimate.d, estimate.s_h, estimate.mu_h, *estimate.wrench)
    if not (estimate.kinematics_valid and all(map(math.isfinite, values))):
        return None
    gravity = _gravity(estimate, hand_angle)
    faces, face_bounds, known_faces = estimate.friction_faces
    rows, bounds = np.array(faces), np.array(face_bounds)
    known = list(known_faces)
    side = _crossed_side(motion)
    if side is not None and not known[side]:  # the crossed row from the hull
        rows[side], bounds[side] = estimate.ground_rows[side], estimate.ground_bounds[side] + push
        known[side] = True
    if not all(map(math.isfinite, (*rows.ravel().tolist(), *bounds.tolist()))):
        return None
    friction = estimate.mu_h if mu_h is None else mu_h
    face = estimate.face if not math.isnan(estimate.face[0]) else statics.WHOLE_HAND
    return statics.ObjectStatics(friction, rows, bounds, estimate.d, gravity, tuple(known), face)


def _crossed_side(motion: Motion | None) -> int | None:
    """The ground row (0 ``GROUND_SLIDE_POS``, 1 ``GROUND_SLIDE_NEG``) ``motion`` slides across, if any."""
    rows = REMOVED_ROWS[motion] if motion is not None else ()
    return next((GROUND_ROWS.index(row) for row in rows if row in GROUND_ROWS), None)


def seeks_friction(estimate: Estimate, motion: Motion) -> bool:
    """Whether ``motion`` is a ground slide across a side whose friction face the estimate does not
    know: :func:`estimated_statics` seeks it past the sticking forces seen, where the face may not be
    (a probe of the ground's friction)."""
    side = _crossed_side(motion)
    return side is not None and not estimate.friction_faces[2][side]


def _gravity(estimate: Estimate, hand_angle: float) -> statics.GravityMoment:
    """The estimated gravity moment where it is valid, else the measured one at the current
    configuration (module docstring)."""
    model = estimate.gravity
    if model.valid:
        return statics.GravityMoment(model.a, model.b)
    v_theta = contact.admissible_motions(hand_angle, estimate.s_h, estimate.d)[:, 0]
    moment = -float(v_theta @ estimate.wrench)
    return statics.GravityMoment(moment * math.cos(hand_angle), moment * math.sin(hand_angle))


@dataclass(frozen=True)
class TargetGoal:
    """What a statics target aims for.

    Attributes:
        force_limits: ``(f_min, f_max)``, the hand's normal force range (N).
        nominal_force: the normal force preferred where the statics leave a choice (N).
        margin: the margin the regulation wrench keeps where it can (N).
        friction_step: how far beyond ``μ̂_h`` the hand friction may be explored (module docstring).
        push: how far past the sticking forces seen a ground slide is sought where its friction
            face is not known (N, :func:`estimated_statics`): the hull's row there is a face of the
            forces seen, inside the true one, so a wrench on it need not slide the object; put past
            it, the normal force is chosen so that the hand still keeps its margin while pushing
            there. A friction face the ground slid past is the limit itself: no push. Where no
            wrench pushed there keeps a margin, the target is the one on the hull's row itself:
            the hull grows with the sticking forces the push shows, so the row sought moves out
            until the hand cannot push further, and the best wrench past it then asks for more
            than the hand holds (on a goals-study quadrilateral at 45°, ``f_min`` with ``f_t =
            f_min``: the hand slid 2.4 mm instead of the ground).
        headroom: the force target stays this far (N) below ``f_max``; the motion is still judged
            on the whole range (:attr:`ccopt.control.controller.ControllerParams.force_headroom`).
    """

    force_limits: tuple[float, float]
    nominal_force: float
    margin: float
    friction_step: float = 0.0
    push: float = 0.0
    headroom: float = 0.0

    @functools.cached_property
    def best_margin(self) -> TargetGoal:
        """This goal with no margin goal short of the best (a measured hand slide's, see the module),
        made once."""
        return dataclasses.replace(self, margin=math.inf)


def statics_target(
    estimate: Estimate, hand_angle: float, motion: Motion, goal: TargetGoal, planned: bool = False
) -> StaticsTarget:
    """The regulation wrench and margin of ``motion`` on the estimated statics, exploring the hand
    friction by ``goal.friction_step`` where ``μ̂_h`` falls short (see the module). ``planned``: the
    motion is a goal's planned motion, not a probe: a hand slide then holds the wrench of its
    largest margin once the hand friction is measured (see the module)."""
    kind = modes.kind_of(motion)
    if planned and kind == "slide_hand" and estimate.hand_slid:
        goal = goal.best_margin
    push = goal.push if kind == "slide_ground" else 0.0
    known = estimated_statics(estimate, hand_angle, motion=motion, push=push)
    target = _target(known, estimate, hand_angle, motion, goal)
    if push > 0.0 and target.margin < 0.0 and seeks_friction(estimate, motion):
        at_hull = estimated_statics(estimate, hand_angle, motion=motion)
        target = max(target, _target(at_hull, estimate, hand_angle, motion, goal), key=_margin_of)
    if not (goal.friction_step > 0.0 and target.judged and target.margin < goal.margin):
        return target
    if estimate.hand_slid or not kept_contacts(motion)[0]:
        return target  # measured where the hand slid; a hand slide slides at it: nothing to explore
    mu_h = estimate.mu_h + goal.friction_step
    bolder = _target(_with_hand_friction(known, mu_h), estimate, hand_angle, motion, goal)
    if bolder.judged and bolder.margin > target.margin:
        return StaticsTarget(bolder.force, bolder.tangential, bolder.margin, mu_h)
    return target


def _with_hand_friction(known: statics.ObjectStatics, mu_h: float) -> statics.ObjectStatics:
    """``known`` with the hand friction ``mu_h`` (finite, non-negative): its other fields checked
    already, made without its ``__init__`` (``dataclasses.replace`` would check and copy them again)."""
    return validation.trusted(statics.ObjectStatics, {**vars(known), "mu_h": mu_h})


def _margin_of(target: StaticsTarget) -> float:
    """A target's margin for comparison (an unjudged one is the worst)."""
    return target.margin if target.judged else -math.inf


def _target(
    known: statics.ObjectStatics | None,
    estimate: Estimate,
    hand_angle: float,
    motion: Motion,
    goal: TargetGoal,
) -> StaticsTarget:
    """The target of ``motion`` on the statics ``known`` (None: the estimate cannot judge)."""
    if known is None:
        return UNJUDGED
    result = statics.regulation_wrench(
        known,
        hand_angle,
        estimate.s_h,
        motion,
        estimate.torque_lever,
        goal.force_limits,
        goal.nominal_force,
        goal.margin,
    )
    if math.isnan(result.margin):
        return UNJUDGED
    if result.wrench is None:
        return StaticsTarget(None, None, -math.inf)
    f_n, f_t, _ = result.wrench  # short of margin, still the best there is
    cap = goal.force_limits[1] - goal.headroom
    if f_n > cap:  # the tangential force keeps its ratio to the normal force
        f_n, f_t = cap, f_t * cap / f_n
    return StaticsTarget(float(f_n), float(f_t), result.margin)
