"""The weight's moment about the ground contact, ``M(θ_o) = a cos θ_o + b sin θ_o`` (docs/architecture.md §7).

``M`` is the moment (N·m, CCW) of the unknown weight about the ground contact ``r_o``; the statics
need it (:class:`ccopt.statics.GravityMoment` with ``a``, ``b`` its cos and sin coefficients). With
the hand in contact, the object in quasi-static equilibrium and the ground contact a point (its
force passes through ``r_o``), moment balance about ``r_o`` gives, per sample,

    M(θ_o) = −τ − (r_h − r_o) × f        (= −(τ + s_h f_n − d f_t) while the hand is flush),

with ``f`` the hand force in world axes, ``τ`` the measured torque about the hand face centre
``r_h`` (measured) and ``×`` the planar cross product. Only ``r_o`` of the kinematics enters, and
linearly: ``M_i = m_i + x_o f_y,i − y_o f_x,i`` with ``m_i = −τ_i − r_h,i × f_i``. So the
least-squares ``(a, b)`` over the samples of one *segment* (one ground contact position) is

    (a, b) = S (η₀ + (u + x_o g_y − y_o g_x)/σ²),    S = (Λ₀ + A/σ²)⁻¹,

from the sums ``A = Σ φφᵀ``, ``u = Σ φ m``, ``g_x = Σ φ f_x``, ``g_y = Σ φ f_y`` with
``φ = (cos θ_o, sin θ_o)``, evaluated with the *current* ``r̂_o``: a sample does not keep the error
of the ``r̂_o`` of its time, so samples are summed from the first flush, sticking one on and the
estimate improves as ``r̂_o`` does. ``(Λ₀, η₀)`` (information form) carry earlier segments: a ground
slide moves ``r_o`` but not the centre of mass relative to it, so a segment that ends is folded in
as a Gaussian prior; a reset of the kinematics (the object may rest on another vertex) forgets all.

Covariance of ``(a, b)``: ``S`` (white noise, ``moment_noise`` per sample, from the force, torque
and pose noise) ``+ S G Σ_ro Gᵀ S / σ⁴`` (the current ``r̂_o`` uncertainty, common to every sample of
the segment, ``G = [g_y, −g_x]``) ``+ β² S k kᵀ S / σ⁴`` (a constant moment bias ``β =
moment_bias``, e.g. the force/torque sensor's, common to every sample, ``k = Σ φ``). The estimate
is *valid* when the kinematics are and the standard deviation of ``M̂`` at the current ``θ_o`` is at
most ``valid_std``; the covariance gives ``M̂`` and its uncertainty at any ``θ``
(:meth:`GravityEstimate.moment`, :meth:`GravityEstimate.moment_std`), which grows away from the
angles visited.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

from ccopt.estimation.kinematics import KinematicEstimate
from ccopt.estimation.quantile import check_number

_GroundContact = tuple[float, float, float, float, float]
"""``(x_o, y_o, var x_o, cov(x_o, y_o), var y_o)`` (m, m²)."""


@dataclass(frozen=True)
class GravityParams:
    """Parameters of :class:`GravityEstimator`.

    Attributes:
        moment_noise: standard deviation of one sample's moment ``−τ − (r_h − r_o) × f`` (N·m):
            the torque noise, the force noise times the lever ``|r_h − r_o|`` and the position
            noise times ``|f|`` (0.005 N·m, 0.3 N × 0.1 m, 15 N × 0.2 mm ≈ 0.03 N·m).
        moment_bias: standard deviation of a moment error common to every sample (N·m), e.g. the
            sensor bias (0.002 N·m of torque, 0.1 N of force at 6 cm).
        prior_std: standard deviation of ``a`` and ``b`` before any data (N·m).
        valid_std: the estimate is valid once the standard deviation of ``M̂(θ_o)`` is at most
            this (N·m).
    """

    moment_noise: float = 0.04
    moment_bias: float = 0.005
    prior_std: float = 1.0
    valid_std: float = 0.02

    def __post_init__(self) -> None:
        check_number("moment_noise", self.moment_noise)
        check_number("moment_bias", self.moment_bias, low_open=False)
        check_number("prior_std", self.prior_std)
        check_number("valid_std", self.valid_std)


@dataclass(frozen=True)
class GravityEstimate:
    """``M(θ) = a cos θ + b sin θ``, the weight's moment about the ground contact (N·m, CCW).

    Attributes:
        a, b: the cos and sin coefficients (N·m; :class:`ccopt.statics.GravityMoment`); NaN while
            the ground contact is unknown.
        covariance: ``(var a, cov(a, b), var b)`` (N²·m²).
        valid: whether ``M̂`` at the current ``θ_o`` is known within ``valid_std`` and the kinematics
            are valid.
    """

    a: float = math.nan
    b: float = math.nan
    covariance: tuple[float, float, float] = (math.nan,) * 3
    valid: bool = False

    def moment(self, theta: float) -> float:
        """``M̂(θ)`` (N·m) at face angle ``θ`` (rad)."""
        return self.a * math.cos(theta) + self.b * math.sin(theta)

    def moment_std(self, theta: float) -> float:
        """The standard deviation of ``M̂(θ)`` (N·m) at face angle ``θ`` (rad)."""
        return math.sqrt(_quadratic(self.covariance, math.cos(theta), math.sin(theta)))


UNKNOWN = GravityEstimate()
"""The estimate before any usable sample."""


class GravityEstimator:
    """Least squares of ``(a, b)`` with the ground contact applied last (see the module docstring).

    Plain floats: a sample costs a few microseconds.
    """

    def __init__(self, params: GravityParams | None = None) -> None:
        self.params = params if params is not None else GravityParams()
        self._weight = 1.0 / self.params.moment_noise**2
        self._epoch = (0, 0)  # the kinematics' (resets, anchor) of the current segment
        self._contact: _GroundContact = (0.0,) * 5  # its last ground contact estimate
        self.reset()

    def update(
        self,
        theta_o: float,
        hand_pose: list[float],
        hand_wrench: list[float],
        kinematics: KinematicEstimate,
        contact: _GroundContact,
    ) -> GravityEstimate:
        """One sample (see :meth:`add`), used if the kinematics regressed it on a fixed ground
        contact; ``contact`` is their ground contact estimate. A reset of the kinematics forgets
        everything; a move of the ground contact (a new ``anchor``) ends the segment."""
        epoch = (kinematics.resets, kinematics.anchor)
        if epoch[0] != self._epoch[0]:
            self.reset()
        elif epoch[1] != self._epoch[1]:
            self.end_segment(self._contact)
        self._epoch, self._contact = epoch, contact
        if kinematics.ground_fixed and math.isfinite(theta_o):
            self.add(theta_o, hand_pose, hand_wrench)
        known = math.isfinite(kinematics.rough[1]) and math.isfinite(kinematics.rough[2])  # r_o
        return self.estimate(theta_o, contact if known else None, kinematics.contact_valid)

    def reset(self) -> None:
        """Forget everything (the object may rest on another vertex)."""
        info = 1.0 / self.params.prior_std**2
        self._prior = (info, 0.0, info, 0.0, 0.0)  # Λ₀ (upper triangle), η₀
        self._informed = False
        self._clear_segment()

    def end_segment(self, contact: _GroundContact) -> None:
        """The ground contact moves (a ground slide): fold this segment, with ``contact`` the last
        estimate of its ground contact, into the prior."""
        if self._samples:
            (a, b), (paa, pab, pbb) = self._solve(contact)
            det = paa * pbb - pab * pab
            laa, lab, lbb = pbb / det, -pab / det, paa / det
            self._prior = (laa, lab, lbb, laa * a + lab * b, lab * a + lbb * b)
        self._clear_segment()

    def add(self, theta_o: float, hand_pose: list[float], hand_wrench: list[float]) -> None:
        """One sample: face angle ``θ_o`` (rad), measured ``(x_h, y_h, θ_h)`` (world, m/rad) and
        ``(f_n, f_t, τ)`` (hand frame, N/N·m), the object in equilibrium on a fixed ground contact."""
        x_h, y_h, theta_h = hand_pose
        f_n, f_t, torque = hand_wrench
        sin_h, cos_h = math.sin(theta_h), math.cos(theta_h)
        f_x, f_y = f_n * sin_h + f_t * cos_h, -f_n * cos_h + f_t * sin_h  # f_n e_n + f_t e_t
        moment = -torque - (x_h * f_y - y_h * f_x)
        c, s = math.cos(theta_o), math.sin(theta_o)
        values = (c * c, c * s, s * s, c * moment, s * moment, c * f_x, s * f_x, c * f_y, s * f_y, c, s)
        self._sums = [total + value for total, value in zip(self._sums, values, strict=True)]
        self._samples += 1
        self._informed = True

    def estimate(
        self, theta_o: float, contact: _GroundContact | None, kinematics_valid: bool
    ) -> GravityEstimate:
        """The estimate with ``contact`` the current ground contact estimate (None: unknown)."""
        if contact is None or not self._informed:
            return UNKNOWN
        (a, b), covariance = self._solve(contact)
        valid = kinematics_valid and math.isfinite(theta_o)
        if valid:
            std = math.sqrt(_quadratic(covariance, math.cos(theta_o), math.sin(theta_o)))
            valid = std <= self.params.valid_std
        return GravityEstimate(a, b, covariance, valid)

    def _clear_segment(self) -> None:
        self._sums = [0.0] * 11  # Σ φφᵀ (3), Σ φ m (2), Σ φ f_x (2), Σ φ f_y (2), Σ φ (2)
        self._samples = 0

    def _solve(self, contact: _GroundContact) -> tuple[tuple[float, float], tuple[float, float, float]]:
        """``((a, b), (var a, cov, var b))`` with the ground contact ``(x_o, y_o, Σ_ro)``."""
        x_o, y_o, vxx, vxy, vyy = contact
        w = self._weight
        aa, ab, bb, mc, ms, xc, xs, yc, ys, kc, ks = self._sums
        laa, lab, lbb, ea, eb = self._prior
        laa, lab, lbb = laa + w * aa, lab + w * ab, lbb + w * bb
        det = laa * lbb - lab * lab
        saa, sab, sbb = lbb / det, -lab / det, laa / det  # S = Λ⁻¹
        ra = ea + w * (mc + x_o * yc - y_o * xc)
        rb = eb + w * (ms + x_o * ys - y_o * xs)
        a, b = saa * ra + sab * rb, sab * ra + sbb * rb
        # sensitivities of (a, b) to x_o, y_o and to a common moment bias: S G w, S k w
        gxa, gxb = w * (saa * yc + sab * ys), w * (sab * yc + sbb * ys)
        gya, gyb = -w * (saa * xc + sab * xs), -w * (sab * xc + sbb * xs)
        ka, kb = w * (saa * kc + sab * ks), w * (sab * kc + sbb * ks)
        bias = self.params.moment_bias**2
        paa = saa + gxa * gxa * vxx + 2.0 * gxa * gya * vxy + gya * gya * vyy + bias * ka * ka
        pbb = sbb + gxb * gxb * vxx + 2.0 * gxb * gyb * vxy + gyb * gyb * vyy + bias * kb * kb
        pab = sab + gxa * gxb * vxx + (gxa * gyb + gya * gxb) * vxy + gya * gyb * vyy + bias * ka * kb
        return (a, b), (paa, pab, pbb)


def _quadratic(covariance: tuple[float, float, float], c: float, s: float) -> float:
    """``(c, s) P (c, s)ᵀ`` of ``P = (var a, cov, var b)``, at least 0."""
    paa, pab, pbb = covariance
    return max(c * c * paa + 2.0 * c * s * pab + s * s * pbb, 0.0)
