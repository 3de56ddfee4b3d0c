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

from ccopt import geometry
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
        gate: a sample whose moment differs from the estimate so far by more than this many
            standard deviations (its own, ``moment_noise`` scaled with the lever beyond
            :data:`NOISE_LEVER`, and ``M̂``'s at its angle) is not used
            (:meth:`GravityEstimator._consistent`).
    """

    moment_noise: float = 0.04
    moment_bias: float = 0.005
    prior_std: float = 1.0
    valid_std: float = 0.02
    gate: float = 4.0

    def __post_init__(self) -> None:
        check_number("moment_noise", self.moment_noise)
        check_number("moment_bias", self.moment_bias, low_open=False)
        check_number("prior_std", self.prior_std)
        check_number("valid_std", self.valid_std)
        check_number("gate", self.gate)


class GravityEstimate:
    """``M(θ) = a cos θ + b sin θ``, the weight's moment about the ground contact (N·m, CCW).

    Immutable. The least squares are solved when the estimate is first read (about 2 µs), not at
    every sample: a sample only copies the sums.

    Attributes:
        a, b: the cos and sin coefficients (N·m; :class:`ccopt.statics.GravityMoment`); NaN while
            the ground contact is unknown.
        covariance: ``(var a, cov(a, b), var b)`` (N²·m²).
        valid: whether ``M̂`` at the ``θ_o`` of its sample is known within ``valid_std`` and the
            kinematics are valid.
    """

    __slots__ = ("_problem", "_solution")

    def __init__(self, problem: _Problem | None = None) -> None:
        self._problem = problem
        self._solution: _Solution | None = None if problem is not None else _UNKNOWN_SOLUTION

    @property
    def a(self) -> float:
        return self._solved()[0]

    @property
    def b(self) -> float:
        return self._solved()[1]

    @property
    def covariance(self) -> tuple[float, float, float]:
        return self._solved()[2]

    @property
    def valid(self) -> bool:
        return self._solved()[3]

    def moment(self, theta: float) -> float:
        """``M̂(θ)`` (N·m) at face angle ``θ`` (rad)."""
        a, b, _, _ = self._solved()
        return a * math.cos(theta) + b * math.sin(theta)

    def moment_std(self, theta: float) -> float:
        """The standard deviation of ``M̂(θ)`` (N·m) at face angle ``θ`` (rad)."""
        return math.sqrt(_quadratic(self._solved()[2], math.cos(theta), math.sin(theta)))

    def __repr__(self) -> str:
        a, b, covariance, valid = self._solved()
        return f"GravityEstimate(a={a!r}, b={b!r}, covariance={covariance!r}, valid={valid!r})"

    def _solved(self) -> _Solution:
        if self._solution is None:
            self._solution = _solve_problem(*self._problem)
        return self._solution


_Solution = tuple[float, float, tuple[float, float, float], bool]
"""``(a, b, covariance, valid)``."""
_UNKNOWN_SOLUTION: _Solution = (math.nan, math.nan, (math.nan,) * 3, False)
UNKNOWN = GravityEstimate()
"""The estimate before any usable sample."""


_Problem = tuple[tuple[float, ...], tuple[float, ...], _GroundContact, float, bool, "GravityParams"]
"""One estimate's least squares: the sums and prior (:class:`GravityEstimator`), the ground contact,
the sample's ``θ_o``, whether the kinematics are valid, and the parameters (a plain tuple: one is
made per sample)."""


class GravityEstimator:
    """Least squares of ``(a, b)`` with the ground contact applied last (see the module docstring).

    Plain floats: a sample costs about a microsecond.
    """

    def __init__(self, params: GravityParams | None = None) -> None:
        self.params = params if params is not None else GravityParams()
        self._resets = self._anchor = 0  # the kinematics' resets and anchor of the current segment
        self._gate_squared = self.params.gate**2
        self.agreed: bool | None = None
        """Whether the last sample's moment about the known ground contact agreed with ``M̂``
        (:meth:`_consistent`); None where it was not judged (no sample, or the contact unknown)."""
        self._contact: _GroundContact = (0.0,) * 5  # its last ground contact estimate
        self.reset()

    def update(
        self,
        theta_o: float,
        hand_pose: list[float],
        hand_wrench: list[float],
        kinematics: KinematicEstimate,
        contact: _GroundContact,
        force_world: tuple[float, float] | None = None,
    ) -> GravityEstimate:
        """One sample: face angle ``θ_o`` (rad), measured ``(x_h, y_h, θ_h)`` (world, m/rad) and
        ``(f_n, f_t, τ)`` (hand frame, N/N·m). It is used if the kinematics regressed it on a fixed ground
        contact and, where that contact is known, its moment about it agrees with the estimate so
        far (:meth:`_consistent`); ``contact`` is their ground contact estimate, ``force_world`` the
        hand force in world axes where the caller has it (N; else it is made from the wrench). A
        reset of the kinematics forgets everything; a move of the ground contact (a new ``anchor``)
        ends the segment."""
        resets, anchor = kinematics.resets, kinematics.anchor
        if resets != self._resets:
            self.reset()
        elif anchor != self._anchor:
            self.end_segment(self._contact)
        self._resets, self._anchor, self._contact = resets, anchor, contact
        rough = kinematics.rough
        known = math.isfinite(rough[1]) and math.isfinite(rough[2])  # r_o
        self.agreed = None
        if kinematics.ground_fixed and math.isfinite(theta_o):
            sample = _moment_sample(theta_o, hand_pose, hand_wrench, force_world)
            if known:
                self.agreed = self._consistent(sample, hand_pose, contact)
            if not known or self.agreed:
                self._accumulate(*sample)
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
            (a, b), (paa, pab, pbb) = _solve(self._sums, self._prior, contact, self.params)
            det = paa * pbb - pab * pab
            laa, lab, lbb = pbb / det, -pab / det, paa / det
            self._prior = (laa, lab, lbb, laa * a + lab * b, lab * a + lbb * b)
        self._clear_segment()

    def _consistent(self, sample: _MomentSample, hand_pose: list[float], contact: _GroundContact) -> bool:
        """Whether a sample's moment about ``contact``, ``m + x_o f_y − y_o f_x``, lies within ``gate``
        standard deviations of ``M̂`` at its angle (the sample's noise, ``moment_noise`` scaled with
        the lever beyond :data:`NOISE_LEVER`, and ``M̂``'s, which is wide while little is known and
        away from the angles visited). Only a point ground contact at
        ``r̂_o`` balances the object as the model says: lying on a face, the object has a second
        ground contact whose force adds its own moment. On the paper pentagon pivoted past the
        tilt where its face lands (−36°), such samples were 0.4–2.0 N·m off, against at most
        0.14 N·m (median 0.025) before; taken in, they turned ``b`` from 0.19 to −0.28 N·m (true
        0.185) for the rest of the run and ruled out every later ground slide. ``M̂`` is solved
        again every :data:`_REFERENCE_SAMPLES` samples offered (not every sample: it moves little
        between two), with the ground contact of the time."""
        if self._reference is None or self._since_reference >= _REFERENCE_SAMPLES:
            (a, b), covariance = _solve(self._sums, self._prior, contact, self.params)
            self._reference, self._since_reference = (a, b, covariance), 0
        self._since_reference += 1
        a, b, covariance = self._reference
        c, s, moment, f_x, f_y = sample
        x_o, y_o = contact[0], contact[1]
        residual = moment + x_o * f_y - y_o * f_x - (a * c + b * s)
        scale = math.hypot(hand_pose[0] - x_o, hand_pose[1] - y_o) / NOISE_LEVER
        noise = self.params.moment_noise * (scale if scale > 1.0 else 1.0)  # max(1.0, scale), written out
        variance = noise * noise + _quadratic(covariance, c, s)
        return residual * residual <= self._gate_squared * variance

    def _accumulate(self, c: float, s: float, moment: float, f_x: float, f_y: float) -> None:
        aa, ab, bb, mc, ms, xc, xs, yc, ys, kc, ks = self._sums
        self._sums = (  # a tuple made anew (not 11 items stored): each estimate keeps the one of its time
            aa + c * c,
            ab + c * s,
            bb + s * s,
            mc + c * moment,
            ms + s * moment,
            xc + c * f_x,
            xs + s * f_x,
            yc + c * f_y,
            ys + s * f_y,
            kc + c,
            ks + s,
        )
        self._samples += 1
        self._informed = True

    def estimate(
        self, theta_o: float, contact: _GroundContact | None, kinematics_valid: bool
    ) -> GravityEstimate:
        """The estimate with ``contact`` the current ground contact estimate (None: unknown)."""
        if contact is None or not self._informed:
            return UNKNOWN
        return GravityEstimate((self._sums, self._prior, contact, theta_o, kinematics_valid, self.params))

    def _clear_segment(self) -> None:
        self._sums = (0.0,) * 11  # Σ φφᵀ (3), Σ φ m (2), Σ φ f_x (2), Σ φ f_y (2), Σ φ (2)
        self._samples = 0
        self._reference: tuple[float, float, tuple[float, float, float]] | None = None  # (a, b, P)
        self._since_reference = 0  # samples offered since it was solved


NOISE_LEVER = 0.1
"""m: the lever ``|r_h − r_o|`` at which ``GravityParams.moment_noise`` holds. Its largest part is the
force noise times the lever, so the gate scales it beyond: on a random pentagon with 17 cm sides
(hand 0.2–0.25 m from the ground contact) the samples were 0.06 N·m off at the median, and a gate
on the unscaled noise turned away one in ten of them while the object stood on its vertex."""
_REFERENCE_SAMPLES = 10
"""Samples offered between two solutions of the estimate the gate compares with."""
_MomentSample = tuple[float, float, float, float, float]
"""``(cos θ_o, sin θ_o, m, f_x, f_y)`` of one sample: ``m = −τ − r_h × f`` (N·m), ``f`` the world
hand force (N)."""


def flush_moment(f_n: float, f_t: float, torque: float, s_h: float, d: float) -> float:
    """The weight's moment about the ground contact (N·m, CCW) that balances a flush hand's wrench
    ``(f_n, f_t, τ)`` (hand frame, N and N·m) with the contact at ``(s_h, d)`` (m) from the hand:
    ``M = −(τ + s_h f_n − d f_t)`` (the module docstring)."""
    return -(torque + s_h * f_n - d * f_t)


def flush_hand_position(f_n: float, f_t: float, torque: float, d: float, moment: float) -> float:
    """``s_h`` (m) of :func:`flush_moment` solved for it: where the ground contact lies along the
    hand for the wrench ``(f_n, f_t, τ)``, the distance ``d`` (m) and the weight's moment (N·m)."""
    return (d * f_t - torque - moment) / f_n


def _moment_sample(
    theta_o: float,
    hand_pose: list[float],
    hand_wrench: list[float],
    force_world: tuple[float, float] | None = None,
) -> _MomentSample:
    """One sample's terms (:data:`_MomentSample`) from ``θ_o`` (rad), the hand pose ``(x_h, y_h, θ_h)``
    (world, m/rad) and wrench ``(f_n, f_t, τ)`` (hand frame, N/N·m), its force in world axes
    ``force_world`` (N) if known."""
    x_h, y_h, theta_h = hand_pose
    f_n, f_t, torque = hand_wrench
    if force_world is None:
        force_world = geometry.hand_to_world(geometry.hand_axes(theta_h), f_n, f_t)
    f_x, f_y = force_world
    return math.cos(theta_o), math.sin(theta_o), -torque - (x_h * f_y - y_h * f_x), f_x, f_y


def _solve_problem(
    sums: tuple[float, ...],
    prior: tuple[float, ...],
    contact: _GroundContact,
    theta_o: float,
    kinematics_valid: bool,
    params: GravityParams,
) -> _Solution:
    """``(a, b, covariance, valid)`` of one :data:`_Problem`."""
    (a, b), covariance = _solve(sums, prior, contact, params)
    valid = kinematics_valid and math.isfinite(theta_o)
    if valid:
        valid = _quadratic(covariance, math.cos(theta_o), math.sin(theta_o)) <= params.valid_std**2
    return a, b, covariance, valid


def _solve(
    sums: tuple[float, ...],
    prior: tuple[float, ...],
    contact: _GroundContact,
    params: GravityParams,
) -> tuple[tuple[float, float], tuple[float, float, float]]:
    """``((a, b), (var a, cov, var b))`` of the sums and prior with the ground contact
    ``(x_o, y_o, Σ_ro)``."""
    x_o, y_o, vxx, vxy, vyy = contact
    w = 1.0 / params.moment_noise**2
    aa, ab, bb, mc, ms, xc, xs, yc, ys, kc, ks = sums
    laa, lab, lbb, ea, eb = prior
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
    bias = params.moment_bias**2
    paa = saa + gxa * gxa * vxx + 2.0 * gxa * gya * vxy + gya * gya * vyy + bias * ka * ka
    pbb = sbb + gxb * gxb * vxx + 2.0 * gxb * gyb * vxy + gyb * gyb * vyy + bias * kb * kb
    pab = sab + gxa * gxb * vxx + (gxa * gyb + gya * gxb) * vxy + gya * gyb * vyy + bias * ka * kb
    return (a, b), (paa, pab, pbb)


def _quadratic(covariance: tuple[float, float, float], c: float, s: float) -> float:
    """``(c, s) P (c, s)ᵀ`` of ``P = (var a, cov, var b)``, at least 0."""
    paa, pab, pbb = covariance
    return max(c * c * paa + 2.0 * c * s * pab + s * s * pbb, 0.0)
