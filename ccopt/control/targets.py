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
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ccopt import contact, statics
from ccopt.estimation.estimator import Estimate
from ccopt.modes import Motion


@dataclass(frozen=True)
class StaticsTarget:
    """The estimated statics' answer for one motion at the current configuration.

    Attributes:
        force: normal force to hold, N (None: the controller's nominal force).
        tangential: tangential force of the regulation wrench, N (None: hold the current one).
        margin: the motion's estimated margin, N: ``-inf`` where the estimate rules it out, NaN where
            the estimate cannot judge yet.
    """

    force: float | None
    tangential: float | None
    margin: float

    @property
    def judged(self) -> bool:
        """Whether the estimate could judge the motion."""
        return not math.isnan(self.margin)


UNJUDGED = StaticsTarget(None, None, math.nan)


def estimated_statics(estimate: Estimate, hand_angle: float) -> statics.ObjectStatics | None:
    """The object's statics as the estimate knows them (None before the kinematics are known).

    The gravity moment is the measured one at the current configuration (module docstring).
    """
    values = (estimate.d, estimate.s_h, estimate.mu_h, *estimate.wrench)
    if not (estimate.kinematics_valid and all(map(math.isfinite, values))):
        return None
    v_theta = contact.admissible_motions(hand_angle, estimate.s_h, estimate.d)[:, 0]
    moment = -float(v_theta @ estimate.wrench)
    gravity = statics.GravityMoment(moment * math.cos(hand_angle), moment * math.sin(hand_angle))
    rows, bounds = np.asarray(estimate.ground_rows), np.asarray(estimate.ground_bounds)
    if not (np.all(np.isfinite(rows)) and np.all(np.isfinite(bounds))):
        return None
    known = tuple(estimate.ground_fitted)
    return statics.ObjectStatics(estimate.mu_h, rows, bounds, estimate.d, gravity, known)


def statics_target(
    estimate: Estimate,
    hand_angle: float,
    motion: Motion,
    force_limits: tuple[float, float],
    nominal_force: float,
    margin_goal: float,
) -> StaticsTarget:
    """The regulation wrench and margin of ``motion`` on the estimated statics (see the module)."""
    known = estimated_statics(estimate, hand_angle)
    if known is None:
        return UNJUDGED
    result = statics.regulation_wrench(
        known,
        hand_angle,
        estimate.s_h,
        motion,
        estimate.torque_lever,
        force_limits,
        nominal_force,
        margin_goal,
    )
    if math.isnan(result.margin):
        return UNJUDGED
    if result.wrench is None or result.margin < 0.0:
        return StaticsTarget(None, None, result.margin if result.wrench is not None else -math.inf)
    f_n, f_t, _ = result.wrench
    return StaticsTarget(float(f_n), float(f_t), result.margin)
