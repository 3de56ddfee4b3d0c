"""Kinematic estimator: ground contact, ``d``, hand sliding position and object angle (paper §IV-B).

While the hand is flush, paper eq. 14 (:func:`ccopt.geometry.hand_pose_from_contact`) ties the
measured hand pose to the unknowns ``(d, x_o, y_o, s_h)``:

    r_h = r_o − s_h e_t − d e_n,  i.e.
    r_h·e_n = −d + x_o (I·e_n) + y_o (J·e_n)        (eq. 15, the paper's regression)
    r_h·e_t = x_o (I·e_t) + y_o (J·e_t) − s_h        (eq. 16: s_h = (r_o − r_h)·e_t)

**Contact compliance.** A flush contact is not rigid: the hand tilts against the object face by
``δ = θ_h − θ_o = c τ`` under the torque ``τ`` it exerts (on the planar plant ``c`` ≈ 0.025–0.046
rad/(N·m) depending on the object, residual ≈ 0.06°; ``|τ|`` reaches 0.4 N·m, so ``δ`` reaches 1°,
and ``d δ`` ≈ 2 mm of position). Eq. 14 holds in the *object's* frame, ``e_n(θ_o)``, ``e_t(θ_o)``
with ``θ_o = θ_h − c τ``: taken at ``θ_h``, it biases ``d`` by up to 10 mm and its innovations fail
the gates. The compliance ``c`` is a property of the contact (hand pad and object), so it is
estimated online as a fifth unknown, from a prior of zero with standard deviation
``compliance_std``, by an extended Kalman filter on ``x = (d, x_o, y_o, s_h, c)``: eqs. 15–16 are
projected on the estimated object frame ``ê = e(θ_h − ĉ τ)``, and their linearisation in ``c``
(``∂e_n/∂θ = e_t``, ``∂e_t/∂θ = −e_n``) adds the columns ``−s_h τ`` to eq. 15 and ``d τ`` to eq. 16.
``c`` is observable because ``τ`` does not follow ``θ_o`` alone (holds and the controller's wrench
changes turn the hand without turning the object); while it is poorly known its uncertainty enters
every prediction, so the gates and the standard deviations stay honest. Where ``τ`` does follow
``θ_o`` (``τ ≈ α + β θ_o``, as gravity's moment makes it in a pivot), eq. 16 sees ``y_o + d c β``
and eq. 15 ``d + y_o``: ``c``, ``d`` and ``y_o`` are then confounded to first order, and in closed
loop the kinematics become valid only once pivots have visited about 14° of ``θ_o`` (with ``c``
known, half that). A wrench that varies at a fixed angle (e.g. the normal force, which moves ``τ``
by ``s_h Δf_n``) pins ``c`` down. ``c`` survives a reset (it belongs to the contact, not to the
configuration); only its correlations are forgotten.

``c`` is a pad's compliance: the hand tilts *with* the torque it exerts, never against it, so
``c ≥ compliance_min`` (0 by default). Where the confounding above lets a model error pass for a
negative compliance, the unconstrained filter believed it: on a goals-study triangle whose pivots
loaded the hand near its end, ``ĉ`` ran to −0.35 rad/(N·m) in about a second of pivoting (the truth
+0.035), and ``θ̂_o = θ_h − ĉ τ`` was 6° off while the kinematics reported themselves valid. An
update that leaves ``ĉ`` below the bound is projected back onto it (the estimate projection of
Simon & Chia, 2002: ``x ← x − P e_c (ĉ − c_min) / P_cc``, so the states correlated with ``c`` move
with it; ``P`` is kept, which stays conservative).

**Normal compliance.** Both contacts also give along the normal: the hand face sinks towards the
ground contact by ``k f_n`` (the penetrations of the hand and ground contacts; 0.06 mm/N on the
default plants). At a constant force that is part of ``d``; but the controller changes ``f_n`` with
the motion's statics (10 → 19 N within one pivot), and the unmodelled 0.5 mm, confounded with ``c``
and ``y_o`` as above, biased ``s_h`` and ``s_g`` by 2–3 mm on a closed-loop recording of the paper
triangle. ``k`` is a sixth state (prior ``normal_compliance_std``, kept on a reset like ``c``):
eq. 15 reads ``r_h·ê_n = −d + k (f_n − f_ref) + r_o·ê_n``, linear in ``k``, so ``d`` is the distance
at the reference force ``f_ref`` (the controller's nominal 10 N, where it is known without ``k``).

Both projections are linear in the positions, so one recursive least-squares (Kalman) estimate
with covariance ``P`` covers every case of the paper. What the contact modes allow to change is
*released* (its row and column of ``P`` cleared, its variance set to ``prior_std²``) before the
measurement update:

=================================  ==========================================================
ground sticks, hand flush          eq. 15 (and eq. 16 if the hand sticks, so ``s_h`` is constant)
                                   added when the hand has rotated ``excitation_angle`` since the
                                   last sample; while the hand slides ``s_h`` is released and
                                   eq. 16 re-estimates it every sample
ground slides, hand sticks, flush  ``x_o`` released and both rows used every sample: ``r_o`` moves
                                   rigidly with the hand (the object keeps its height); once
                                   ``ŷ_o`` has moved ``hand_slide_height`` (and what
                                   ``hand_slide_travel`` would move it), the hand slid instead:
                                   back to the start, then as the hand sliding on a sticking ground;
                                   within ``split_tilt`` of the vertical, where the hand was reported
                                   at its friction limit, the other reading is added to ``P`` as the
                                   following ends (:meth:`KinematicEstimator._doubt_following`)
ground slides, hand slides, flush  ``x_o`` and ``s_h`` released and both rows used every sample:
                                   either contact may be the one moving (the forces could not
                                   tell), and the pose tells them apart only by ``sin θ_o`` of the
                                   motion, so their standard deviations say how well
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
``θ_o = θ_h − ĉ τ`` while flush. ``d`` is reported in the object's frame (the constant distance of
the face from ``r_o``), ``s_h`` in the hand's, ``(r_o − r_h)·e_t(θ_h)`` (it differs from the
object-frame one by ``d δ``). Estimates are *valid* when their posterior standard deviation (with
the assumed ``position_noise``) is at most ``valid_std``; before that their means are reported as
*rough* values while their standard deviation is at most ``rough_std``.

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
as a hand slide, leaving ``s_h`` and ``s_g`` wrong by the slip. A hand the controller keeps sticking
but the classifier reports sliding (``hand_may_slide``: the modes given are the command's, see
:func:`ccopt.estimation.estimator.commanded_modes`) is regressed as sticking with the tighter
``hand_slip_gate`` on eq. 16, which catches a creeping slide sooner.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from ccopt.estimation.quantile import check_count, check_number
from ccopt.estimation.records import record
from ccopt.modes import ContactConfiguration, ContactMode, HandGeometry

D, X_O, Y_O, S_H, C, K = range(6)
"""Indices of the estimated state ``(d, x_o, y_o, s_h, c, k)`` (m, m, m, m, rad/(N·m), m/N)."""
_SIZE = 6
_CONTACT = (D, X_O, Y_O)
_POSITIONS = (D, X_O, Y_O, S_H)
_Row = tuple[float, float, float, float, float, float]
_Prediction = tuple[_Row, float, float]
"""``(P hᵀ, innovation, innovation variance)`` of one scalar measurement."""
_Frame = tuple[float, float, float, float, float, float]
"""The estimated object frame of one sample and its wrench: ``(ê_n, ê_t, τ, f_n − f_ref)`` flattened
(world, N·m, N)."""
_PIVOT_ITERATIONS = 8
_STICK, _FLUSH = ContactMode.STICK, HandGeometry.FLUSH


@dataclass(frozen=True)
class KinematicsParams:
    """Parameters of the kinematic estimator.

    Attributes:
        excitation_angle: hand rotation between two regression samples (rad). The sample *after*
            the one that crossed it is used: the crossing one is selected by its own angle noise
            (biased along the motion, so along ``τ``), which on a plant recording biased ``c`` by
            a factor 2.5 and ``θ_o`` by up to 0.4°.
        position_noise: assumed standard deviation of each measured coordinate of ``r_h`` (m),
            including the effect of the angle noise.
        prior_std: standard deviation of an unknown position before any data (m).
        compliance_prior: the contact's rotational compliance ``c`` before any data (rad/(N·m));
            0 (a rigid contact) unless known, e.g. from an earlier run's estimate.
        compliance_std: its standard deviation before any data (rad/(N·m)).
        compliance_min: the least compliance the estimate may take (rad/(N·m)): a passive pad
            tilts with the torque, so 0 (a large negative value leaves it unconstrained).
        normal_compliance_prior: the contacts' normal compliance ``k`` before any data (m/N): how far
            the hand face sinks towards the ground contact per newton of normal force (both contacts'
            penetration; 0.06 mm/N on the default plants).
        normal_compliance_std: its standard deviation before any data (m/N).
        reference_force: the normal force at which ``d`` is reported (N): the face sits at
            ``d − k (f_n − reference_force)``. Near the forces the controller holds, so that ``d``
            stays known while ``f_n`` does not vary and ``k`` cannot be told from it.
        valid_std: estimates are valid once their standard deviation is at most this (m).
        rough_std: means are reported (rough, not yet valid) once their standard deviation is at
            most this (m).
        gate: an eq. 15 innovation beyond this many predicted standard deviations is rejected; an
            eq. 16 one means the hand slid.
        slip_gate: with the ground reported sliding, an eq. 15 (or, with the hand sticking, an
            eq. 16) innovation beyond this many predicted standard deviations means the ground slid.
            Low, because a false alarm costs little (``r_o`` is re-anchored to within the noise)
            and the default ``position_noise`` is about twice the default sensors' effective noise:
            on a plant recording 3 let the first slide each way run 1.6–2.0 mm before it was
            caught, 2 about 1 mm.
        slip_samples: this many rejected eq. 15 samples in a row reset the estimate.
        hand_slip_gate: with the hand reported sliding but commanded (so assumed) sticking, an
            eq. 16 innovation beyond this many predicted standard deviations means it slid (a
            slow creep would pass the ``gate``).
        follow_height_noise: while the ground slides, the ground contact's height ``y_o`` may drift
            by this standard deviation a sample (m; :meth:`KinematicEstimator._follow_ground`).
        hand_slide_height, hand_slide_travel: while the ground is followed with the hand sticking,
            ``ŷ_o`` moving from where the following began by ``hand_slide_height`` (m) and by what
            ``hand_slide_travel`` (m) of the hand along the face moves it (``Δ sin θ``) means the
            hand slid instead (:meth:`KinematicEstimator._follow_ground`). A ground contact sliding
            on a flat ground keeps its height (it sinks with the normal force, which ``k``
            models). On the goals study's 40 random objects (measured before the pivots about the
            naive lever were paced) ``ŷ_o`` moved at most 0.67 mm in the
            commanded ground slides where the ground slid or nothing did, and 1.2–4.3 mm where the
            hand slid 6–16 mm instead at 9–29° (each read as the ground's slide; two claimed goals
            10 mm off). The travel keeps a hand that gives a millimetre or two before the ground
            breaks loose (random objects at 52°) from being taken for a hand slide.
    """

    excitation_angle: float = math.radians(0.25)
    position_noise: float = 5e-4
    prior_std: float = 1.0
    compliance_prior: float = 0.0
    compliance_std: float = 0.1
    compliance_min: float = 0.0
    normal_compliance_prior: float = 0.0
    normal_compliance_std: float = 1e-4
    reference_force: float = 10.0
    valid_std: float = 3e-3
    rough_std: float = 0.05
    gate: float = 6.0
    slip_gate: float = 2.0
    slip_samples: int = 3
    hand_slip_gate: float = 4.0
    follow_height_noise: float = 1e-4
    hand_slide_height: float = 1e-3
    hand_slide_travel: float = 3e-3

    def __post_init__(self) -> None:
        check_number("excitation_angle", self.excitation_angle, low_open=False)
        check_number("position_noise", self.position_noise)
        check_number("prior_std", self.prior_std)
        check_number("compliance_min", self.compliance_min, low=-math.inf)
        check_number("compliance_prior", self.compliance_prior, low=self.compliance_min, low_open=False)
        check_number("compliance_std", self.compliance_std, low_open=False)
        check_number("normal_compliance_prior", self.normal_compliance_prior, low=-math.inf)
        check_number("normal_compliance_std", self.normal_compliance_std, low_open=False)
        check_number("reference_force", self.reference_force, low_open=False)
        check_number("valid_std", self.valid_std)
        check_number("rough_std", self.rough_std, low=self.valid_std, low_open=False)
        check_number("gate", self.gate)
        check_number("slip_gate", self.slip_gate)
        check_count("slip_samples", self.slip_samples)
        check_number("hand_slip_gate", self.hand_slip_gate)
        check_number("follow_height_noise", self.follow_height_noise, low_open=False)
        check_number("hand_slide_height", self.hand_slide_height)
        check_number("hand_slide_travel", self.hand_slide_travel)

    @property
    def split_tilt(self) -> float:
        """rad: the least ``|θ|`` (up to 90°) at which the pose tells a ground slide from a hand
        slide along the face, whose difference is ``sin θ`` of the motion, by ``valid_std``:
        ``|sin θ| valid_std ≥ position_noise`` (9.6° at the defaults)."""
        return math.asin(min(1.0, self.position_noise / self.valid_std))


@dataclass(frozen=True)
class KinematicEstimate:
    """Estimated kinematics (world frame, SI units; NaN where never estimated).

    Attributes:
        theta_o: orientation of the object face touching the hand (rad).
        s_h: hand sliding position ``(r_o − r_h)·e_t(θ_h)`` (m; its flush-hand equivalent while
            pivoting); NaN unless ``s_h_valid``.
        s_g: ground sliding position ``x_o`` (m); NaN unless ``contact_valid``.
        d: distance from the ground contact to the object face touching the hand (m); NaN unless
            ``contact_valid``.
        r_o: ground contact ``(x_o, y_o)`` (m); NaN unless ``contact_valid``.
        std: posterior standard deviations of ``(d, x_o, y_o, s_h)`` (m; ``s_h`` in the hand frame).
        theta_o_valid, s_h_valid: whether ``theta_o`` and ``s_h`` are estimated.
        contact_valid: whether ``d``, ``r_o`` and ``s_g`` are estimated.
        rough: the means of ``(d, x_o, y_o, s_h)`` (m), each NaN while its standard deviation
            exceeds ``rough_std`` (``s_h`` also while it is undefined, out of contact).
        theta_std: standard deviation of ``theta_o`` from the compliance (flush) or from the
            contact (pivoting), rad; the angle noise is not included. NaN unless ``theta_o_valid``.
        compliance: the estimated compliance ``c`` of the hand contact, rad/(N·m).
        compliance_std: its standard deviation, rad/(N·m).
        normal_compliance: the estimated normal compliance ``k`` of the contacts, m/N.
        resets: how many times the estimate was reset (:meth:`KinematicEstimator.reset`).
        anchor: changes whenever the ground contact ``r_o`` may have moved (a reset, a ground
            slide followed); samples with the same ``anchor`` share one ``r_o``.
        ground_fixed: whether this sample was regressed with ``r_o`` fixed (ground sticking,
            hand flush, no slip seen).
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
    rough: tuple[float, float, float, float] = (math.nan,) * 4
    theta_std: float = math.nan
    compliance: float = math.nan
    compliance_std: float = math.nan
    normal_compliance: float = math.nan
    resets: int = 0
    anchor: int = 0
    ground_fixed: bool = False


class KinematicEstimator:
    """Mode-switched extended Kalman filter on paper eqs. 14–16 with the contact compliance (see the
    module docstring).

    The state (6) and covariance (6×6) are plain Python lists: at this size that is several times
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
        self._height_variance = self.params.follow_height_noise**2
        self._hand_slip_gate_squared = self.params.hand_slip_gate**2
        self._hand_slide_height = self.params.hand_slide_height
        self._hand_slide_travel = self.params.hand_slide_travel
        self._split_tilt = self.params.split_tilt
        params = self.params
        self._reference_force = params.reference_force
        self._excitation_angle = params.excitation_angle
        self._valid_std, self._rough_std = params.valid_std, params.rough_std
        self._compliance_min = params.compliance_min
        self._state = [0.0, 0.0, 0.0, 0.0, params.compliance_prior, params.normal_compliance_prior]
        self._cov = [[0.0] * _SIZE for _ in range(_SIZE)]
        self._cov[C][C] = params.compliance_std**2
        self._cov[K][K] = params.normal_compliance_std**2
        self.resets = -1
        """How many times the estimate was reset."""
        self.anchor = -1
        """Changes whenever ``r_o`` is released (see :class:`KinematicEstimate`)."""
        self.reset()

    def reset(self) -> None:
        """Forget the configuration (the motion was indeterminate); the compliances are kept."""
        self._state[: S_H + 1] = [0.0] * 4
        self._release(*_POSITIONS)
        self._last_theta = math.nan  # hand angle at the last eq. 15 sample
        self._excited = True  # the next sample goes into the regression
        self._theta_o = math.nan
        self._theta_o_valid = False
        self._theta_std = math.nan
        self._rejected = 0  # eq. 15 samples rejected in a row by the innovation gate
        self._ground_slipping = False  # a ground slip was seen and the ground is still reported sliding
        self._follow_start: tuple[list[float], list[list[float]]] | None = None  # state, covariance
        self._hand_gave = False  # in the following under way, the hand was seen sliding instead
        self._follow_doubt = False  # in the following under way, the hand may have slid unseen
        self.resets += 1

    def update(
        self,
        hand_pose: np.ndarray,
        e_n: Sequence[float],
        e_t: Sequence[float],
        modes: ContactConfiguration,
        in_contact: bool,
        ground_may_slide: bool = False,
        torque: float = 0.0,
        hand_may_slide: bool = False,
        normal_force: float | None = None,
    ) -> KinematicEstimate:
        """Advance with one measured hand pose ``(x_h, y_h, θ_h)`` (world, m/rad).

        ``e_n``, ``e_t`` are the hand frame's axes at ``θ_h`` (:func:`ccopt.geometry.hand_normal`,
        :func:`ccopt.geometry.hand_tangent`), ``modes`` the configuration to work under,
        ``in_contact`` whether the hand touches the object, ``ground_may_slide`` whether the ground
        was reported sliding although ``modes`` says it sticks (see the module docstring), ``torque``
        the measured ``τ`` (N·m) that tilts a flush hand against the object, ``hand_may_slide``
        whether the hand was reported sliding although ``modes`` says it sticks (its eq. 16 gate is
        then ``hand_slip_gate``), ``normal_force`` the measured ``f_n`` (N) that presses the contacts
        in (None: ``reference_force``).
        """
        pose = hand_pose.tolist()
        flush = modes.hand_geometry == _FLUSH
        ground_sticks = modes.ground_mode == _STICK
        hand_sticks = modes.hand_mode == _STICK
        force = 0.0 if normal_force is None else normal_force - self._reference_force
        tilt = self._state[C] * torque  # the hand axes turned by −ĉ τ to the object face's
        cos, sin = math.cos(tilt), math.sin(tilt)
        frame = (
            e_n[0] * cos - e_t[0] * sin,
            e_n[1] * cos - e_t[1] * sin,
            e_t[0] * cos + e_n[0] * sin,
            e_t[1] * cos + e_n[1] * sin,
            torque,
            force,
        )
        self._ground_slipping = self._ground_slipping and ground_may_slide
        pivot_ok, fixed, following = True, False, False
        if not in_contact:
            self._release(S_H)
        elif ground_sticks and flush:
            if ground_may_slide and self._ground_slid(pose, frame, hand_sticks):
                fixed, following = self._follow_ground(pose, frame, hand_sticks), True
            else:
                self._regress(pose, frame, hand_sticks, hand_may_slide)
                fixed = True
            self._flush_angle(pose[2], torque)
        elif ground_sticks:
            pivot_ok = self._pivot(hand_pose, int(modes.hand_geometry))
        elif flush:
            fixed, following = self._follow_ground(pose, frame, hand_sticks), True
            self._flush_angle(pose[2], torque)
        else:
            self.reset()
        if following and hand_sticks and hand_may_slide and abs(pose[2]) < self._split_tilt:
            self._follow_doubt = True
        if not following and not (ground_may_slide and self._start_height_known()):
            if self._follow_doubt and self._follow_start is not None and not self._hand_gave:
                self._doubt_following(pose, frame)
            self._follow_start, self._hand_gave, self._follow_doubt = None, False, False
        return self._estimate(in_contact and pivot_ok, torque if flush else 0.0, fixed)

    def _flush_angle(self, theta_h: float, torque: float) -> None:
        """``θ_o = θ_h − ĉ τ`` and its standard deviation from ``c``'s."""
        self._theta_o = theta_h - self._state[C] * torque
        self._theta_std = abs(torque) * math.sqrt(self._cov[C][C])
        self._theta_o_valid = True

    def _regress(self, pose: list[float], frame: _Frame, hand_sticks: bool, hand_may_slide: bool) -> None:
        """Ground sticking, hand flush: eq. 15 on excitation; eq. 16 tracks ``s_h`` (see the docstring)."""
        excited = self._excited
        if excited:
            self._measure_normal(pose, frame)
        last = self._last_theta
        self._excited = (
            math.isnan(last) or abs(math.remainder(pose[2] - last, math.tau)) >= self._excitation_angle
        )
        row, value = self._tangent_row(pose, frame)
        if hand_sticks and not self._s_h_released:
            prediction = self._predict(row, value)
            gate = self._hand_slip_gate_squared if hand_may_slide else self._gate_squared
            innovation = prediction[1]
            if innovation * innovation <= gate * prediction[2]:  # _within, written out
                if excited:
                    self._apply(prediction)
                return
        self._release(S_H)  # reported sliding, unknown, or slid although reported sticking
        self._scalar_update(row, value)
        self._s_h_released = False

    def _ground_slid(self, pose: list[float], frame: _Frame, hand_sticks: bool) -> bool:
        """Whether the ground slid since it was first reported sliding: latched, or now an innovation
        beyond ``slip_gate`` of eq. 15, or of eq. 16 if the hand sticks (else the hand explains it)."""
        if not self._ground_slipping:
            self._ground_slipping = self._beyond_slip_gate(*self._normal_row(pose, frame)) or (
                hand_sticks
                and not self._s_h_released
                and self._beyond_slip_gate(*self._tangent_row(pose, frame))
            )
            if self._ground_slipping:
                self._rejected = 0
        return self._ground_slipping

    def _beyond_slip_gate(self, row: _Row, value: float) -> bool:
        return not self._within(self._predict(row, value), self._slip_gate_squared)

    def _follow_ground(self, pose: list[float], frame: _Frame, hand_sticks: bool) -> bool:
        """Ground sliding, hand flush: the object keeps its height on a flat ground, so only ``x_o``
        changes (hand sticking, the paper's case: ``r_o`` follows the hand rigidly) or ``x_o`` and
        ``s_h`` both (hand sliding too); eqs. 15–16 give them. Keeping ``y_o`` also lets a sticking
        hand's ``s_h`` be found again after a moment out of contact (a slide's start can lift the
        object off the hand for 10 ms), which releasing ``y_o`` too would leave unobservable until
        the next pivots; it is let drift by ``follow_height_noise`` a sample (the ground contact
        sinks into the ground with the normal force, which a fixed ``y_o`` would put into ``x_o``:
        0.1 mm/N on a closed-loop goal run of the paper triangle).

        With the hand sticking, the pose tells this rigid motion from the hand sliding along the
        face only by the face's tilt: a hand slide ``Δ`` reads as the ground contact moving ``Δ``
        along the face, ``Δ sin θ`` up or down. Once ``ŷ_o`` has moved from where the following
        began by ``hand_slide_height`` and by what ``hand_slide_travel`` along the face would
        make, the hand is taken to have slid instead: the state goes back to that start (the
        ground contact stayed) and, until the following ends, the hand slides on a sticking ground
        (as in :meth:`_regress`). A start that knew ``ŷ_o`` to ``hand_slide_height`` is kept through
        samples on which the ground is reported sticking but may still slide (``ground_may_slide``):
        a classifier flickering between the two restarted it every few samples, and a goals-study
        triangle's 7 mm hand slide at 17.6° was read as 5.8 mm of ground slide. A start less sure of
        ``ŷ_o`` is not kept: its height still converges (a synthetic run's, taken at 3 mm, moved 1 mm
        in a ground slide with the hand sticking). Returns whether ``r_o`` was held fixed."""
        if hand_sticks and self._follow_start is None:
            self._follow_start = (self._state.copy(), [row.copy() for row in self._cov])
        if self._hand_gave:
            self._regress(pose, frame, False, False)
            return True
        if hand_sticks:
            self._release(X_O)
            self._cov[Y_O][Y_O] += self._height_variance  # the contact sinks as the force changes
        else:
            self._release(X_O, S_H)
        self._measure_normal(pose, frame)
        self._scalar_update(*self._tangent_row(pose, frame))
        self._s_h_released = False
        start = self._follow_start
        if not hand_sticks or start is None:
            return False
        height = abs(self._state[Y_O] - start[0][Y_O])
        if height < self._hand_slide_height or height < self._hand_slide_travel * abs(frame[3]):
            return False
        self._state[:] = start[0]
        for row, saved in zip(self._cov, start[1], strict=True):
            row[:] = saved
        self._hand_gave = True
        self._regress(pose, frame, False, False)
        return True

    def _doubt_following(self, pose: list[float], frame: _Frame) -> None:
        """The end of a following that the hand may have made instead, sliding along the face.

        Within ``split_tilt`` of the vertical the two readings of the pose differ by less than
        ``valid_std`` (``Δ sin θ``), and where the hand was reported at its friction limit
        (``hand_may_slide``) before that friction was measured, the forces cannot tell them apart
        either (``μ̂_h`` is only the largest ratio seen, which a first ground slide reaches). The
        following's reading (the ground slid) is kept, and the other one (the ground contact back
        where the following began, ``s_h`` from eq. 16 there) is put one standard deviation away:
        ``P += v vᵀ`` over ``(x_o, y_o, s_h)``. The kinematics are then not valid until a pivot,
        which turns the two readings apart (by ``Δ`` times the angle turned), settles which contact
        moved. On a goals-study quadrilateral (seed 5, trial 17) a ground slide at −5.4° slid the
        hand 7.7 mm and the ground not at all; read as the ground's, it left ``ŝ_g`` 6.4 mm off and
        two goals claimed 7.3 and 2.6 mm off by the truth; with the other reading held, the next
        pivot (7°) brought ``ŝ_g`` and ``ŝ_h`` within 0.8 mm and 0.3 mm of the truth and both goals
        ended within 1.2 mm. Where the ground did slide the pivot confirms it, at the cost of the
        kinematics being invalid until then."""
        start, state, cov = self._follow_start[0], self._state, self._cov
        row, value = self._tangent_row(pose, frame)
        x_0, y_0 = start[X_O], start[Y_O]
        s_h = x_0 * row[1] + y_0 * row[2] + row[4] * state[C] - value
        change = {X_O: x_0 - state[X_O], Y_O: y_0 - state[Y_O], S_H: s_h - state[S_H]}
        for i, v_i in change.items():
            for j, v_j in change.items():
                cov[i][j] += v_i * v_j

    def _start_height_known(self) -> bool:
        """Whether the following's start knew ``ŷ_o`` to ``hand_slide_height`` (:meth:`_follow_ground`)."""
        start = self._follow_start
        return start is not None and start[1][Y_O][Y_O] <= self._hand_slide_height**2

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
        contact_variance = max(self._cov[index][index] for index in _CONTACT)
        self._cov[S_H][S_H] = contact_variance  # inherits their accuracy
        self._theta_std = math.sqrt(contact_variance) / max(float(np.hypot(*(r_o - hand_pose[:2]))), 1e-3)
        self._theta_o_valid = True
        return True

    def _release(self, *indices: int) -> None:
        """Forget what is known about the given state components (they may have changed)."""
        cov = self._cov
        for index in indices:
            for other in range(_SIZE):
                cov[index][other] = cov[other][index] = 0.0
            cov[index][index] = self._prior_variance
        if S_H in indices:
            self._s_h_released = True
        if X_O in indices:
            self.anchor += 1

    def _measure_normal(self, pose: list[float], frame: _Frame) -> None:
        """Eq. 15 through the innovation gate; ``slip_samples`` rejections in a row reset the estimate."""
        prediction = self._predict(*self._normal_row(pose, frame))
        if not self._within(prediction, self._gate_squared):
            self._rejected += 1
            if self._rejected >= self.params.slip_samples:
                self.reset()
            return
        self._rejected = 0
        self._apply(prediction)
        self._last_theta = pose[2]

    def _normal_row(self, pose: list[float], frame: _Frame) -> tuple[_Row, float]:
        """Eq. 15 on the object frame, linearised in ``c``: ``row · x = value`` with
        ``r_h·ê_n = −d + k (f_n − f_ref) + r_o·ê_n`` at ``ĉ`` and ``∂/∂c = −s_h τ``."""
        slope = -self._state[S_H] * frame[4]
        value = pose[0] * frame[0] + pose[1] * frame[1] + slope * self._state[C]
        return (-1.0, frame[0], frame[1], 0.0, slope, frame[5]), value

    def _tangent_row(self, pose: list[float], frame: _Frame) -> tuple[_Row, float]:
        """Eq. 16 on the object frame, linearised in ``c``: ``row · x = value`` with
        ``r_h·ê_t = r_o·ê_t − s_h`` at ``ĉ`` and ``∂/∂c = d τ``."""
        slope = self._state[D] * frame[4]
        value = pose[0] * frame[2] + pose[1] * frame[3] + slope * self._state[C]
        return (0.0, frame[2], frame[3], -1.0, slope, 0.0), value

    @staticmethod
    def _within(prediction: _Prediction, gate_squared: float) -> bool:
        """Whether the innovation is within ``√gate_squared`` predicted standard deviations."""
        _, innovation, variance = prediction
        return innovation * innovation <= gate_squared * variance

    def _predict(self, row: _Row, value: float) -> _Prediction:
        """``(P hᵀ, innovation, innovation variance)`` of one measurement ``row · x = value``."""
        h0, h1, h2, h3, h4, h5 = row
        # P hᵀ written out, each row unpacked once: every sample runs it, and a comprehension (its own
        # frame and a list) costs 0.74 µs a call against 0.44 (an index a term costs more still)
        r0, r1, r2, r3, r4, r5 = self._cov
        p0, p1, p2, p3, p4, p5 = r0
        c0 = p0 * h0 + p1 * h1 + p2 * h2 + p3 * h3 + p4 * h4 + p5 * h5
        p0, p1, p2, p3, p4, p5 = r1
        c1 = p0 * h0 + p1 * h1 + p2 * h2 + p3 * h3 + p4 * h4 + p5 * h5
        p0, p1, p2, p3, p4, p5 = r2
        c2 = p0 * h0 + p1 * h1 + p2 * h2 + p3 * h3 + p4 * h4 + p5 * h5
        p0, p1, p2, p3, p4, p5 = r3
        c3 = p0 * h0 + p1 * h1 + p2 * h2 + p3 * h3 + p4 * h4 + p5 * h5
        p0, p1, p2, p3, p4, p5 = r4
        c4 = p0 * h0 + p1 * h1 + p2 * h2 + p3 * h3 + p4 * h4 + p5 * h5
        p0, p1, p2, p3, p4, p5 = r5
        c5 = p0 * h0 + p1 * h1 + p2 * h2 + p3 * h3 + p4 * h4 + p5 * h5
        variance = c0 * h0 + c1 * h1 + c2 * h2 + c3 * h3 + c4 * h4 + c5 * h5 + self._noise_variance
        s0, s1, s2, s3, s4, s5 = self._state
        innovation = value - (s0 * h0 + s1 * h1 + s2 * h2 + s3 * h3 + s4 * h4 + s5 * h5)
        return (c0, c1, c2, c3, c4, c5), innovation, variance

    def _apply(self, prediction: _Prediction) -> None:
        """Kalman update with a :meth:`_predict`-ed measurement (noise variance ``position_noise²``)."""
        column, innovation, variance = prediction
        c0, c1, c2, c3, c4, c5 = column
        scale = 1.0 / variance
        state = self._state
        for i, r in enumerate(self._cov):  # a row read once and written once: a quarter faster
            gain = column[i] * scale
            state[i] += gain * innovation
            p0, p1, p2, p3, p4, p5 = r
            r[:] = (
                p0 - gain * c0,
                p1 - gain * c1,
                p2 - gain * c2,
                p3 - gain * c3,
                p4 - gain * c4,
                p5 - gain * c5,
            )
        below = state[C] - self._compliance_min
        if below < 0.0:  # project onto c ≥ c_min (see the module docstring)
            variance_c = self._cov[C][C]
            for i, row in enumerate(self._cov):
                state[i] -= row[C] / variance_c * below
            state[C] = self._compliance_min

    def _scalar_update(self, row: _Row, value: float) -> None:
        """Kalman update with one measurement ``row · x = value``, ungated."""
        self._apply(self._predict(row, value))

    def _contact_valid(self) -> bool:
        return max(self._cov[index][index] for index in _CONTACT) <= self.params.valid_std**2

    def ground_contact(self) -> tuple[float, float, float, float, float]:
        """``(x_o, y_o, var x_o, cov(x_o, y_o), var y_o)``: the ground contact and its covariance (m, m²)."""
        cov = self._cov
        return self._state[X_O], self._state[Y_O], cov[X_O][X_O], cov[X_O][Y_O], cov[Y_O][Y_O]

    def _estimate(self, s_h_defined: bool, torque: float, fixed: bool) -> KinematicEstimate:
        """The estimate of the state, with ``s_h`` in the hand frame at the torque ``τ`` (N·m) that
        tilts the hand against the face by ``δ = ĉ τ``: ``s cos δ − d sin δ``, its variance to first
        order in ``(s, d, c)``."""
        d, x_o, y_o, s, compliance, normal_compliance = self._state
        cov, valid_std = self._cov, self._valid_std
        tilt = compliance * torque
        cos, sin = math.cos(tilt), math.sin(tilt)
        j_s, j_d, j_c = cos, -sin, -torque * (s * sin + d * cos)
        var_d, _, _, cov_ds, cov_dc, _ = cov[D]  # rows unpacked in state order (d, x_o, y_o, s_h, c, k)
        cov_sd, _, _, var_s, cov_sc, _ = cov[S_H]
        cov_cd, _, _, cov_cs, var_c, _ = cov[C]
        s_h_variance = (
            j_s * (j_s * var_s + j_d * cov_sd + j_c * cov_sc)
            + j_d * (j_s * cov_ds + j_d * var_d + j_c * cov_dc)
            + j_c * (j_s * cov_cs + j_d * cov_cd + j_c * var_c)
        )
        s_h = s * cos - d * sin
        sqrt, nan, rough_std = math.sqrt, math.nan, self._rough_std
        var_x, var_y = cov[X_O][X_O], cov[Y_O][Y_O]
        # sqrt(max(v, 0.0)), the max written out (a call costs more): NaN and -0.0 kept
        std_d, std_x = sqrt(0.0 if var_d < 0.0 else var_d), sqrt(0.0 if var_x < 0.0 else var_x)
        std_y, std_s = sqrt(0.0 if var_y < 0.0 else var_y), sqrt(0.0 if s_h_variance < 0.0 else s_h_variance)
        if not s_h_defined:
            s_h = nan
        largest = std_x if std_x > std_d else std_d  # max(std_d, std_x, std_y) written out, as max compares
        contact_valid = (std_y if std_y > largest else largest) <= valid_std
        s_h_valid = s_h_defined and contact_valid and std_s <= valid_std
        theta_o_valid = self._theta_o_valid
        return record(
            KinematicEstimate,
            {
                "theta_o": self._theta_o,
                "s_h": s_h if s_h_valid else nan,
                "s_g": x_o if contact_valid else nan,
                "d": d if contact_valid else nan,
                "r_o": np.array((x_o, y_o) if contact_valid else (nan, nan)),
                "std": (std_d, std_x, std_y, std_s),
                "theta_o_valid": theta_o_valid,
                "s_h_valid": s_h_valid,
                "contact_valid": contact_valid,
                "rough": (
                    d if std_d <= rough_std else nan,
                    x_o if std_x <= rough_std else nan,
                    y_o if std_y <= rough_std else nan,
                    s_h if std_s <= rough_std else nan,
                ),
                "theta_std": self._theta_std if theta_o_valid else nan,
                "compliance": compliance,
                "compliance_std": sqrt(0.0 if var_c < 0.0 else var_c),
                "normal_compliance": normal_compliance,
                "resets": self.resets,
                "anchor": self.anchor,
                "ground_fixed": fixed,
            },
        )


def pivot_contact(
    hand_pose: np.ndarray, sign: int, half_length: float, d: float, r_o: np.ndarray, theta_start: float
) -> tuple[float, float] | None:
    """``(θ_o, s_h)`` of an object pivoting on the hand's ``sign`` end (+1: ``+e_t``, −1: ``−e_t``).

    The hand end ``p = r_h + sign·l_h e_t(θ_h)`` lies on the object face, which is at distance ``d``
    from the ground contact ``r_o`` along ``e_n(θ_o)``: ``(r_o − p)·e_n(θ_o) = d``, solved by Newton's
    method from ``theta_start`` (``d e_n/dθ = e_t``). ``s_h`` is the flush-hand equivalent:
    ``(r_o − p)·e_t(θ_o) + sign·l_h``. None if Newton does not converge.
    """
    x_h, y_h, theta_h = hand_pose.tolist()
    lever = sign * half_length
    x_o, y_o = (float(value) for value in r_o)
    arm_x, arm_y = x_o - (x_h + lever * math.cos(theta_h)), y_o - (y_h + lever * math.sin(theta_h))
    theta = theta_start
    for _ in range(_PIVOT_ITERATIONS):
        residual = (arm_x * math.sin(theta) + arm_y * -math.cos(theta)) - d  # arm · e_n(θ) − d
        slope = arm_x * math.cos(theta) + arm_y * math.sin(theta)  # arm · e_t(θ)
        if slope == 0.0:
            return None
        theta -= residual / slope
        if abs(residual) < 1e-12:
            break
    if (
        not abs((arm_x * math.sin(theta) + arm_y * -math.cos(theta)) - d) < 1e-9
        or abs(theta - theta_h) > 0.5 * math.pi
    ):
        return None
    return theta, (arm_x * math.cos(theta) + arm_y * math.sin(theta)) + lever
