"""Kinematic estimator: ground contact, ``d``, hand sliding position and object angle (paper §IV-B).

While the hand is flush, paper eq. 14 (:func:`ccopt.geometry.hand_pose_from_contact`) ties the
measured hand pose to the unknowns ``(d, x_o, y_o, s_h)``:

    r_h = r_o − s_h e_t − d e_n,  i.e.
    r_h·e_n = −d + x_o (I·e_n) + y_o (J·e_n)        (eq. 15, the paper's regression)
    r_h·e_t = x_o (I·e_t) + y_o (J·e_t) − s_h        (eq. 16: s_h = (r_o − r_h)·e_t)

Both projections are linear in the unknowns, so one recursive least-squares (Kalman) estimate of
``x = (d, x_o, y_o, s_h)`` with covariance ``P`` covers every case of the paper. What the contact
modes allow to change is *released* (its row and column of ``P`` cleared, its variance set to
``prior_std²``) before the measurement update:

=================================  ==========================================================
ground sticks, hand flush          eq. 15 (and eq. 16 if the hand sticks, so ``s_h`` is constant)
                                   added when the hand has rotated ``excitation_angle`` since the
                                   last sample; while the hand slides ``s_h`` is released and
                                   eq. 16 re-estimates it every sample
ground slides, hand sticks, flush  ``r_o`` released and both rows used every sample: ``r_o`` moves
                                   rigidly with the hand with the last ``d`` and ``s_h``
ground *may* slide (reported, but  as if it sticks, until an innovation exceeds ``slip_gate``
not acted on), hand flush          standard deviations (eq. 15, and eq. 16 if the hand sticks); then,
                                   until the ground is reported sticking again, rigidly (hand
                                   sticking) or with ``x_o`` and ``s_h`` both released (hand sliding)
ground sticks, hand pivots         no update; ``r_o`` and ``d`` stay, ``θ_o`` and ``s_h`` follow from
                                   the hand end on the object face (:func:`pivot_contact`)
hand not in contact                no update; ``s_h`` released
anything else (indeterminate)      reset
=================================  ==========================================================

Using eq. 16 while the hand sticks (the paper regresses eq. 15 alone) conditions the regression far
better: for a rigid rotation about the ground contact sampled every 0.5° with 0.3 mm of noise, the
standard deviation of ``d`` and ``y_o`` after 20° of rotation drops from ~9 mm to ~0.4 mm.
``θ_o = θ_h`` while flush. Estimates are *valid* when their posterior standard deviation (with the
assumed ``position_noise``) is at most ``valid_std``.

Innovation gate: a contact the modes call sticking that really moved shows up as an innovation the
noise cannot explain (``gate`` predicted standard deviations), tested on every sample. An eq. 16
sample beyond it while the hand is reported sticking means the hand slid all the same: ``s_h`` is
released and re-estimated from that sample, as while it is reported sliding. An eq. 15 sample beyond
the gate is not used; ``slip_samples`` such samples in a row mean the ground contact moved, and the
estimate is reset (the motion was not what the modes said). Kinematics alone cannot tell a ground
slip along ``e_t`` from a hand slide (both move the hand along ``e_t``), so the reports decide: with
the hand reported sticking and the ground reported sliding (a ground-slide report the estimator does
not act on, see :func:`ccopt.estimation.estimator.kinematic_modes`), an unexplained motion is the
ground's. The classifier is conservative (sliding is almost never reported sticking), so a
sticking-hand report is the reliable one. The rigid update costs little when the ground did not
move (``r_o`` is re-anchored to within the pose noise); the slip it catches would otherwise be read
as a hand slide, leaving ``s_h`` and ``s_g`` wrong by the slip.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from ccopt import geometry
from ccopt.estimation.quantile import check_count, check_number
from ccopt.modes import ContactConfiguration, ContactMode, HandGeometry

D, X_O, Y_O, S_H = range(4)
"""Indices of the estimated state ``(d, x_o, y_o, s_h)``."""
_CONTACT = (D, X_O, Y_O)
_Prediction = tuple[tuple[float, float, float, float], float, float]
"""``(P hᵀ, innovation, innovation variance)`` of one scalar measurement."""
_PIVOT_ITERATIONS = 8


@dataclass(frozen=True)
class KinematicsParams:
    """Parameters of the kinematic estimator.

    Attributes:
        excitation_angle: hand rotation between two regression samples (rad).
        position_noise: assumed standard deviation of each measured coordinate of ``r_h`` (m),
            including the effect of the angle noise.
        prior_std: standard deviation of an unknown before any data (m).
        valid_std: estimates are valid once their standard deviation is at most this (m).
        gate: an eq. 15 innovation beyond this many predicted standard deviations is rejected; an
            eq. 16 one means the hand slid.
        slip_gate: with the ground reported sliding, an eq. 15 (or, with the hand sticking, an
            eq. 16) innovation beyond this many predicted standard deviations means the ground slid.
            Low, because a false alarm costs little (``r_o`` is re-anchored to within the noise)
            and the default ``position_noise`` is about twice the default sensors' effective noise:
            on a plant recording 3 let the first slide each way run 1.6–2.0 mm before it was
            caught, 2 about 1 mm.
        slip_samples: this many rejected eq. 15 samples in a row reset the estimate.
    """

    excitation_angle: float = math.radians(0.5)
    position_noise: float = 5e-4
    prior_std: float = 1.0
    valid_std: float = 3e-3
    gate: float = 6.0
    slip_gate: float = 2.0
    slip_samples: int = 3

    def __post_init__(self) -> None:
        check_number("excitation_angle", self.excitation_angle, low_open=False)
        check_number("position_noise", self.position_noise)
        check_number("prior_std", self.prior_std)
        check_number("valid_std", self.valid_std)
        check_number("gate", self.gate)
        check_number("slip_gate", self.slip_gate)
        check_count("slip_samples", self.slip_samples)


@dataclass(frozen=True)
class KinematicEstimate:
    """Estimated kinematics (world frame, SI units; NaN where never estimated).

    Attributes:
        theta_o: orientation of the object face touching the hand (rad).
        s_h: hand sliding position ``(r_o − r_h)·e_t`` (m; its flush-hand equivalent while pivoting).
        s_g: ground sliding position ``x_o`` (m).
        d: distance from the ground contact to the object face touching the hand (m).
        r_o: ground contact ``(x_o, y_o)`` (m).
        std: posterior standard deviations of ``(d, x_o, y_o, s_h)`` (m).
        theta_o_valid, s_h_valid: whether ``theta_o`` and ``s_h`` are estimated.
        contact_valid: whether ``d``, ``r_o`` and ``s_g`` are estimated.
    """

    theta_o: float
    s_h: float
    s_g: float
    d: float
    r_o: np.ndarray
    std: tuple[float, ...]
    theta_o_valid: bool
    s_h_valid: bool
    contact_valid: bool


class KinematicEstimator:
    """Mode-switched recursive least squares on paper eqs. 14–16 (see the module docstring).

    The state (4) and covariance (4×4) are plain Python lists: at this size that is several times
    faster than NumPy.
    """

    def __init__(self, half_length: float, params: KinematicsParams | None = None) -> None:
        check_number("half_length", half_length)
        self.half_length = float(half_length)
        """``l_h``, half the hand's contact face (m): its ends are the pivots."""
        self.params = params if params is not None else KinematicsParams()
        self._noise_variance = self.params.position_noise**2
        self._prior_variance = self.params.prior_std**2
        self._gate_squared = self.params.gate**2
        self._slip_gate_squared = self.params.slip_gate**2
        self.reset()

    def reset(self) -> None:
        """Forget everything (the motion was indeterminate)."""
        self._state = [0.0] * 4
        self._cov = [[self._prior_variance if i == j else 0.0 for j in range(4)] for i in range(4)]
        self._last_theta = math.nan  # hand angle at the last eq. 15 sample
        self._s_h_released = True
        self._theta_o = math.nan
        self._theta_o_valid = False
        self._rejected = 0  # eq. 15 samples rejected in a row by the innovation gate
        self._ground_slipping = False  # a ground slip was seen and the ground is still reported sliding

    def update(
        self,
        hand_pose: np.ndarray,
        e_n: Sequence[float],
        e_t: Sequence[float],
        modes: ContactConfiguration,
        in_contact: bool,
        ground_may_slide: bool = False,
    ) -> KinematicEstimate:
        """Advance with one measured hand pose ``(x_h, y_h, θ_h)`` (world, m/rad).

        ``e_n``, ``e_t`` are the hand frame's axes at ``θ_h`` (:func:`ccopt.geometry.hand_normal`,
        :func:`ccopt.geometry.hand_tangent`), ``modes`` the configuration to work under,
        ``in_contact`` whether the hand touches the object, ``ground_may_slide`` whether the ground
        was reported sliding although ``modes`` says it sticks (see the module docstring).
        """
        pose, normal, tangent = hand_pose.tolist(), list(e_n), list(e_t)
        flush = modes.hand_geometry == HandGeometry.FLUSH
        ground_sticks = modes.ground_mode == ContactMode.STICK
        hand_sticks = modes.hand_mode == ContactMode.STICK
        self._ground_slipping = self._ground_slipping and ground_may_slide
        pivot_ok = True
        if not in_contact:
            self._release(S_H)
        elif ground_sticks and flush:
            if ground_may_slide and self._ground_slid(pose, normal, tangent, hand_sticks):
                self._follow_ground(pose, normal, tangent, hand_sticks)
            else:
                self._regress(pose, normal, tangent, hand_sticks)
            self._theta_o, self._theta_o_valid = pose[2], True
        elif ground_sticks:
            pivot_ok = self._pivot(hand_pose, int(modes.hand_geometry))
        elif flush and hand_sticks:
            self._follow_ground(pose, normal, tangent, hand_sticks=True)
            self._theta_o, self._theta_o_valid = pose[2], True
        else:
            self.reset()
            if flush:
                self._theta_o, self._theta_o_valid = pose[2], True
        return self._estimate(in_contact and pivot_ok)

    def _regress(
        self, pose: list[float], normal: list[float], tangent: list[float], hand_sticks: bool
    ) -> None:
        """Ground sticking, hand flush: eq. 15 on excitation; eq. 16 tracks ``s_h`` (see the docstring)."""
        last = self._last_theta
        excited = (
            math.isnan(last) or abs(math.remainder(pose[2] - last, math.tau)) >= self.params.excitation_angle
        )
        if excited:
            self._measure_normal(pose, normal)
        row, value = _tangent_row(pose, tangent)
        prediction = self._predict(row, value)
        if not hand_sticks or self._s_h_released or not self._consistent(prediction):
            self._release(S_H)  # reported sliding, unknown, or slid although reported sticking
            self._scalar_update(row, value)
            self._s_h_released = False
        elif excited:
            self._apply(prediction)

    def _ground_slid(
        self, pose: list[float], normal: list[float], tangent: list[float], hand_sticks: bool
    ) -> bool:
        """Whether the ground slid since it was first reported sliding: latched, or now an innovation
        beyond ``slip_gate`` of eq. 15, or of eq. 16 if the hand sticks (else the hand explains it)."""
        if not self._ground_slipping:
            self._ground_slipping = self._beyond_slip_gate(*_normal_row(pose, normal)) or (
                hand_sticks
                and not self._s_h_released
                and self._beyond_slip_gate(*_tangent_row(pose, tangent))
            )
            if self._ground_slipping:
                self._rejected = 0
        return self._ground_slipping

    def _beyond_slip_gate(self, row: tuple[float, float, float, float], value: float) -> bool:
        _, innovation, variance = self._predict(row, value)
        return innovation * innovation > self._slip_gate_squared * variance

    def _follow_ground(
        self, pose: list[float], normal: list[float], tangent: list[float], hand_sticks: bool
    ) -> None:
        """Ground sliding, hand flush: ``r_o`` follows the hand rigidly (hand sticking, the paper's
        case), or, with the hand sliding too, ``x_o`` and ``s_h`` both change (the object keeps its
        height on a flat ground) and eqs. 15–16 give both."""
        if hand_sticks:
            self._release(X_O, Y_O)
        else:
            self._release(X_O, S_H)
        self._measure(pose, normal, tangent)

    def _pivot(self, hand_pose: np.ndarray, sign: int) -> bool:
        """Ground sticking, hand pivoting about its ``sign`` end: ``θ_o`` and ``s_h`` from geometry."""
        self._release(S_H)
        if not self._contact_valid():
            self._theta_o_valid = False
            return False
        start = self._theta_o if self._theta_o_valid else float(hand_pose[2])
        r_o = np.array(self._state[X_O : Y_O + 1])
        solution = pivot_contact(hand_pose, sign, self.half_length, self._state[D], r_o, start)
        if solution is None:
            self._theta_o_valid = False
            return False
        self._theta_o, self._state[S_H] = solution
        self._cov[S_H][S_H] = max(self._cov[index][index] for index in _CONTACT)  # inherits their accuracy
        self._theta_o_valid = True
        return True

    def _release(self, *indices: int) -> None:
        """Forget what is known about the given state components (they may have changed)."""
        cov = self._cov
        for index in indices:
            for other in range(4):
                cov[index][other] = cov[other][index] = 0.0
            cov[index][index] = self._prior_variance
        if S_H in indices:
            self._s_h_released = True

    def _measure(self, pose: list[float], normal: list[float], tangent: list[float]) -> None:
        """Kalman update with eq. 15 (gated, :meth:`_measure_normal`), then eq. 16."""
        self._measure_normal(pose, normal)
        self._scalar_update(*_tangent_row(pose, tangent))
        self._s_h_released = False

    def _measure_normal(self, pose: list[float], normal: list[float]) -> None:
        """Eq. 15 through the innovation gate; ``slip_samples`` rejections in a row reset the estimate."""
        prediction = self._predict(*_normal_row(pose, normal))
        if not self._consistent(prediction):
            self._rejected += 1
            if self._rejected >= self.params.slip_samples:
                self.reset()
            return
        self._rejected = 0
        self._apply(prediction)
        self._last_theta = pose[2]

    def _consistent(self, prediction: _Prediction) -> bool:
        """Whether the innovation is within ``gate`` predicted standard deviations."""
        _, innovation, variance = prediction
        return innovation * innovation <= self._gate_squared * variance

    def _predict(self, row: tuple[float, float, float, float], value: float) -> _Prediction:
        """``(P hᵀ, innovation, innovation variance)`` of one measurement ``row · x = value``."""
        h0, h1, h2, h3 = row
        state = self._state
        c0, c1, c2, c3 = (r[0] * h0 + r[1] * h1 + r[2] * h2 + r[3] * h3 for r in self._cov)  # P hᵀ
        variance = c0 * h0 + c1 * h1 + c2 * h2 + c3 * h3 + self._noise_variance
        innovation = value - (state[0] * h0 + state[1] * h1 + state[2] * h2 + state[3] * h3)
        return (c0, c1, c2, c3), innovation, variance

    def _apply(self, prediction: _Prediction) -> None:
        """Kalman update with a :meth:`_predict`-ed measurement (noise variance ``position_noise²``)."""
        (c0, c1, c2, c3), innovation, variance = prediction
        scale = 1.0 / variance
        state = self._state
        for i, (r, c) in enumerate(zip(self._cov, (c0, c1, c2, c3), strict=True)):
            gain = c * scale
            state[i] += gain * innovation
            r[0] -= gain * c0
            r[1] -= gain * c1
            r[2] -= gain * c2
            r[3] -= gain * c3

    def _scalar_update(self, row: tuple[float, float, float, float], value: float) -> None:
        """Kalman update with one measurement ``row · x = value``, ungated."""
        self._apply(self._predict(row, value))

    def _standard_deviations(self) -> tuple[float, ...]:
        return tuple(math.sqrt(max(self._cov[i][i], 0.0)) for i in range(4))

    def _contact_valid(self) -> bool:
        return max(self._cov[index][index] for index in _CONTACT) <= self.params.valid_std**2

    def _estimate(self, s_h_defined: bool) -> KinematicEstimate:
        state, std = self._state, self._standard_deviations()
        contact_valid = max(std[:3]) <= self.params.valid_std
        s_h_valid = s_h_defined and contact_valid and std[S_H] <= self.params.valid_std
        nan = math.nan
        return KinematicEstimate(
            theta_o=self._theta_o,
            s_h=state[S_H] if s_h_valid else nan,
            s_g=state[X_O] if contact_valid else nan,
            d=state[D] if contact_valid else nan,
            r_o=np.array(state[X_O : Y_O + 1] if contact_valid else (nan, nan)),
            std=std,
            theta_o_valid=self._theta_o_valid,
            s_h_valid=s_h_valid,
            contact_valid=contact_valid,
        )


def _normal_row(pose: list[float], normal: list[float]) -> tuple[tuple[float, float, float, float], float]:
    """Eq. 15 as ``row · (d, x_o, y_o, s_h) = value``: ``r_h·e_n = −d + r_o·e_n``."""
    return (-1.0, normal[0], normal[1], 0.0), pose[0] * normal[0] + pose[1] * normal[1]


def _tangent_row(pose: list[float], tangent: list[float]) -> tuple[tuple[float, float, float, float], float]:
    """Eq. 16 as ``row · (d, x_o, y_o, s_h) = value``: ``r_h·e_t = r_o·e_t − s_h``."""
    return (0.0, tangent[0], tangent[1], -1.0), pose[0] * tangent[0] + pose[1] * tangent[1]


def pivot_contact(
    hand_pose: np.ndarray, sign: int, half_length: float, d: float, r_o: np.ndarray, theta_start: float
) -> tuple[float, float] | None:
    """``(θ_o, s_h)`` of an object pivoting on the hand's ``sign`` end (+1: ``+e_t``, −1: ``−e_t``).

    The hand end ``p = r_h + sign·l_h e_t(θ_h)`` lies on the object face, which is at distance ``d``
    from the ground contact ``r_o`` along ``e_n(θ_o)``: ``(r_o − p)·e_n(θ_o) = d``, solved by Newton's
    method from ``theta_start`` (``d e_n/dθ = e_t``). ``s_h`` is the flush-hand equivalent:
    ``(r_o − p)·e_t(θ_o) + sign·l_h``. None if Newton does not converge.
    """
    p = hand_pose[:2] + sign * half_length * geometry.hand_tangent(float(hand_pose[2]))
    arm = r_o - p
    theta = theta_start
    for _ in range(_PIVOT_ITERATIONS):
        residual = float(arm @ geometry.hand_normal(theta)) - d
        slope = float(arm @ geometry.hand_tangent(theta))
        if slope == 0.0:
            return None
        theta -= residual / slope
        if abs(residual) < 1e-12:
            break
    if (
        not abs(float(arm @ geometry.hand_normal(theta)) - d) < 1e-9
        or abs(theta - hand_pose[2]) > 0.5 * math.pi
    ):
        return None
    return theta, float(arm @ geometry.hand_tangent(theta)) + sign * half_length
