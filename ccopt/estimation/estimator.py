"""The object-agnostic estimator (paper §IV): an :class:`Estimator`, one :meth:`~Estimator.update` per sample.

Each sample ``(time, hand_pose, hand_wrench)`` — the measured hand pose ``(x_h, y_h, θ_h)`` (world,
m/rad) and hand wrench ``(f_n, f_t, τ)`` (hand frame, N and N·m, :mod:`ccopt.geometry`) — goes through

1. the hand friction estimate (:mod:`.friction`) and the ground friction hull (:mod:`.ground_cone`),
   fed while the hand is in contact (``f_n > contact_force``);
2. the generalized friction cone ``N w ≤ b`` in the hand frame (:data:`ccopt.contact.cone_rows`,
   evaluated once per sample through one flat buffer, the same function as
   :func:`ccopt.contact.friction_cone` at a fraction of its call overhead) and its margins ``b − N w``;
3. the mode classifier (:mod:`.classifier`) on those margins: the conservative reported modes, and the
   most likely ones (a tighter hand friction margin) for the kinematics. The reported modes judge the
   hand's torque on the contact patch as far as it is known, the hand cut to the known face (the
   last sample's, :func:`patch_margins`): a hand that rolls over the face's end does so with its
   centre of pressure well inside the hand;
4. the kinematic estimator (:mod:`.kinematics`) under the most likely modes, except for ground-slide
   reports the kinematics cannot act on (:func:`kinematic_modes`): the paper's warm start regresses
   the ground contact while the controller enforces sticking, and the regression's own innovation
   gate, not the conservative report, tells when the contact really moved. Given the commanded
   configuration, the kinematics take every contact it keeps as kept (:func:`commanded_modes`);
5. while the hand is flush, ``θ_o`` (the hand's angle less the contact's compliant tilt) through a
   constant-rate Kalman filter (:mod:`.angle_filter`), which averages the angle noise without
   lagging a pivot;
6. the weight's moment about the ground contact, ``M(θ_o)`` (:mod:`.gravity`), from the samples the
   kinematics regressed on a fixed ground contact; the same balance checks the kinematics: a
   disagreement over a range of tilts (:meth:`Estimator._check_moment`), or the hand's position on
   the face departing from theirs in a ground slide the pose cannot tell from a hand slide
   (:meth:`Estimator._check_hand_give`), resets them;
7. where the face under the hand is known to be (:mod:`.face`): the hand's extent at the start and
   the centres of pressure seen since.

Samples with a non-finite pose or wrench (sensor dropouts), or a value beyond what any run of this
robot can produce (:data:`SAMPLE_BOUNDS`: a glitch, not a measurement), change nothing: the previous
estimate is returned with the new time and ``skipped=True``. A recording of ``(time, hand_pose,
hand_wrench)`` can be replayed with :func:`replay`.
"""

from __future__ import annotations

import dataclasses
import functools
import math
from collections.abc import Iterable
from dataclasses import dataclass, field
from numbers import Real

import casadi as ca
import numpy as np
from numpy.typing import ArrayLike

from ccopt import contact, geometry, validation
from ccopt.casadi_eval import BufferedFunction
from ccopt.contact import N_CONE_ROWS
from ccopt.estimation.angle_filter import AngleFilter, AngleFilterParams
from ccopt.estimation.classifier import ModeClassifier, ModeParams
from ccopt.estimation.face import UNKNOWN_FACE, FaceEstimator, FaceParams
from ccopt.estimation.friction import HandFrictionEstimator, HandFrictionParams
from ccopt.estimation.gravity import UNKNOWN as UNKNOWN_GRAVITY
from ccopt.estimation.gravity import (
    GravityEstimate,
    GravityEstimator,
    GravityParams,
    flush_hand_position,
    flush_moment,
)
from ccopt.estimation.ground_cone import GroundCone, GroundConeEstimator, GroundConeParams
from ccopt.estimation.kinematics import KinematicEstimate, KinematicEstimator, KinematicsParams
from ccopt.estimation.quantile import check_number
from ccopt.estimation.records import record
from ccopt.estimation.sliding_face import (
    UNDETERMINED,
    FitSnapshot,
    SlidingFace,
    SlidingFaceFit,
    SlidingFaceParams,
)
from ccopt.hand import Hand
from ccopt.modes import ContactConfiguration, ContactMode, HandGeometry

_FLUSH = HandGeometry.FLUSH
HAND_GIVE_SETTLE = 0.05
"""s: a watched ground slide's moment is taken over this much of its start
(:meth:`Estimator._check_hand_give`)."""
_PIVOT_POS, _PIVOT_NEG = int(contact.Row.HAND_PIVOT_POS), int(contact.Row.HAND_PIVOT_NEG)
_STICK = ContactMode.STICK


def _flat_cone_rows() -> BufferedFunction:
    """:data:`ccopt.contact.cone_rows` and the margins ``b − N w`` on one flat input
    ``(θ_h, μ_h, l_h, vec(A) (column-major), b, w)`` with one flat output ``(N row by row, b, b − N w)``,
    evaluated in the calling thread's buffers (:meth:`BufferedFunction.buffers`)."""
    flat = ca.SX.sym("cone_input", 12)
    n_rows, b = contact.cone_rows(flat[0], flat[1], flat[2], ca.reshape(flat[3:7], 2, 2), flat[7:9])
    output = ca.vertcat(ca.vec(n_rows.T), b, b - n_rows @ flat[9:12])
    return BufferedFunction(ca.Function("cone_rows_flat", [flat], [output]))


_CONE_ROWS = _flat_cone_rows()
SAMPLE_BOUNDS = (1e9, 1e3, 1e3, 1e3, 1e4, 1e4, 1e3)
"""Largest magnitudes of a sample's ``(time (s), x_h, y_h (m), θ_h (rad), f_n, f_t (N), τ (N·m))``:
far beyond any run (hand within metres, forces within tens of N), yet small enough that no product
or square in the estimator overflows. A sample beyond them is skipped like a dropout."""


@dataclass(frozen=True)
class EstimatorParams:
    """Parameters of the estimator and of each of its parts.

    Attributes:
        friction: hand friction and torque limits.
        ground: ground friction hull.
        modes: mode classifier of the reported (conservative) modes, for the controller.
        kinematic_modes: mode classifier of the modes the kinematics work under. A kinematic hand
            slide releases ``s_h``, so a sticking hand reported sliding lets a ground slip pass as a
            hand slide: here the hand friction rows count as tight only within 1 N (three standard
            deviations of the margin's noise at the default sensor noise), not the conservative
            1.5 N. On a plant recording this halved the worst ``s_h``/``s_g`` errors after a ground slide
            (4.7 → 1.1 mm).
        kinematics: kinematic estimator.
        gravity: the weight's moment about the ground contact.
        theta_filter: filter of ``θ_o`` while it is the hand's angle (flush hand).
        face: where the face under the hand is known to be.
        sliding_face: the ground's friction face fitted to the forces of its slides.
        contact_force: the hand is in contact while ``f_n`` exceeds this (N).
        slid_distance: a contact's estimated position (``s_g``, ``s_h``) moving this far (m) one
            way while it is meant to slide that way shows that it slid (:class:`SlideEvidence`):
            only then is that side's hull face the ground's friction face, and ``μ̂_h`` measured.
        moment_mismatch_tilt: the kinematics are reset once the samples whose moment about their
            ground contact disagrees with ``M̂``, with none agreeing in between, span this range
            of ``θ_o`` (rad; :meth:`Estimator._check_moment`).
        moment_mismatch_samples: ... and number at least this many.
        moment_doubt_tilt: while such samples span this range of ``θ_o`` (rad) but not yet
            ``moment_mismatch_tilt``, the kinematics' ground contact is doubted
            (:attr:`Estimate.kinematics_doubted`; at or beyond ``moment_mismatch_tilt``, never:
            the reset comes first).
        hand_give: a commanded ground slide, where the pose cannot tell it from a hand slide,
            resets the kinematics once the hand position the moment balance gives departs from
            theirs by this much (m; :meth:`Estimator._check_hand_give`).
        hand_give_filter: the time constant (s) of the low-pass filter on that position.
    """

    friction: HandFrictionParams = field(default_factory=HandFrictionParams)
    ground: GroundConeParams = field(default_factory=GroundConeParams)
    modes: ModeParams = field(default_factory=ModeParams)
    kinematic_modes: ModeParams = field(default_factory=lambda: ModeParams(slide_margin=1.0))
    kinematics: KinematicsParams = field(default_factory=KinematicsParams)
    gravity: GravityParams = field(default_factory=GravityParams)
    theta_filter: AngleFilterParams = field(default_factory=AngleFilterParams)
    face: FaceParams = field(default_factory=FaceParams)
    sliding_face: SlidingFaceParams = field(default_factory=SlidingFaceParams)
    contact_force: float = 1.0
    slid_distance: float = 2e-3
    moment_mismatch_tilt: float = math.radians(5.0)
    moment_mismatch_samples: int = 10
    moment_doubt_tilt: float = math.radians(2.0)
    hand_give: float = 5.5e-3
    hand_give_filter: float = 0.1

    def __post_init__(self) -> None:
        parts = (
            ("friction", HandFrictionParams),
            ("ground", GroundConeParams),
            ("modes", ModeParams),
            ("kinematic_modes", ModeParams),
            ("kinematics", KinematicsParams),
            ("gravity", GravityParams),
            ("theta_filter", AngleFilterParams),
            ("face", FaceParams),
            ("sliding_face", SlidingFaceParams),
        )
        validation.check_types((name, getattr(self, name), kind) for name, kind in parts)
        check_number("contact_force", self.contact_force, low_open=False)
        check_number("slid_distance", self.slid_distance)
        check_number("moment_mismatch_tilt", self.moment_mismatch_tilt)
        validation.check_count("moment_mismatch_samples", self.moment_mismatch_samples)
        check_number("moment_doubt_tilt", self.moment_doubt_tilt)
        check_number("hand_give", self.hand_give)
        check_number("hand_give_filter", self.hand_give_filter)


@dataclass(frozen=True)
class Estimate:
    """Everything estimated at one sample (arrays are read-only; SI units).

    Attributes:
        time: sample time (s).
        wrench: the measured hand wrench ``(f_n, f_t, τ)`` (hand frame, N, N·m).
        cone_rows, cone_bounds: the estimated generalized friction cone ``N w ≤ b`` in the hand
            frame (6×3, 6), row order :class:`~ccopt.contact.Row`.
        margins: ``b − N w`` for the measured wrench (N or N·m; ≤ 0 on or beyond a row).
        row_valid: per row, whether it is estimated (the hand torque rows always are).
        mu_h: hand friction coefficient.
        torque_lever: ``l_h_eff`` (m), the hand torque rows are ``|τ| ≤ l_h_eff f_n``.
        ground_rows, ground_bounds: ground rows ``A f ≤ b`` on the world hand force (2×2 unit
            normals, 2 offsets in N), rows ``GROUND_SLIDE_POS``, ``GROUND_SLIDE_NEG``.
        mu_g: ground friction coefficient: the sliding forces' (``sliding_face``) once determined,
            else from the two fitted hull faces (NaN until both are fitted).
        ground_fitted: per ground row, whether it is the ground's friction face: the hull has a
            straight face on that side *and* the ground slid that way (:class:`SlideEvidence`).
            Otherwise the row is where the sticking forces seen end (a face of the data, or the
            conservative prior row): a bound the classifier respects, but not the friction limit,
            so the statics of a motion (:mod:`ccopt.control.targets`) do not count it as one.
        sliding_face: the ground's friction faces fitted to the forces of its slides
            (:mod:`.sliding_face`); where determined, they are :attr:`friction_faces`.
        hand_mode, hand_geometry, ground_mode: the classified contact configuration.
        in_contact: whether the hand touches the object (``f_n > contact_force``).
        theta_o, s_h, s_g, d, r_o: the kinematics (rad, m), NaN where not estimated.
        theta_o_valid, s_h_valid: whether ``theta_o`` and ``s_h`` are estimated.
        contact_valid: whether ``d``, ``r_o`` and ``s_g`` are estimated.
        skipped: True if this sample was not finite and nothing was updated.
        kinematics_mean: ``(θ_o, s_h, s_g, d)`` (rad, m) *before* they are valid too: each is NaN
            only while it is unknown (``θ_o`` out of contact; a position whose standard deviation
            exceeds ``KinematicsParams.rough_std``, 5 cm by default; ``s_h`` also out of contact).
            A controller may use them, weighed by ``kinematics_std``, before ``kinematics_valid``;
            once valid they equal the fields above.
        kinematics_std: standard deviations of ``kinematics_mean`` (rad, m; NaN for ``θ_o`` while it
            is unknown). ``θ_o``'s combines the angle noise (unfiltered, an upper bound) and the
            compliance's uncertainty times ``|τ|``.
        compliance, compliance_std: the estimated rotational compliance of the hand contact,
            ``θ_h − θ_o = c τ`` (rad/(N·m), :mod:`.kinematics`), and its standard deviation.
        gravity: ``M̂(θ)``, the weight's moment about the ground contact, with its covariance
            (:class:`~ccopt.estimation.gravity.GravityEstimate`).
        hand_slid: whether the hand has been seen sliding where it was commanded to
            (:class:`SlideEvidence`): ``mu_h`` was then measured at the friction limit.
        ground_anchor: changes whenever the ground contact may have moved (the kinematics'
            ``anchor``: a reset, a ground motion followed); estimates with the same value share one
            ground contact, so ``s_g`` differences between them are the ground's own slides.
        face: ``(u_low, u_high)``, where the face under the hand is known to be, m along ``e_t``
            from the ground contact's foot (:mod:`.face`): NaN while the kinematics are not valid,
            empty (``u_low > u_high``) where nothing shows it yet.
        kinematics_doubted: whether the moment balance about the kinematics' ground contact has
            disagreed with ``M̂`` over ``moment_doubt_tilt`` of ``θ_o`` (and
            ``moment_mismatch_samples`` samples), with none agreeing in between
            (:meth:`Estimator._check_moment`): the object turned while resting elsewhere than the
            kinematics say, as after a rock over a ground face onto the next vertex, which the reset
            after ``moment_mismatch_tilt`` has not settled yet. ``θ_o`` is the hand's and stands;
            ``s_h``, ``s_g``, ``d`` and ``r_o`` may be a face's length off.
    """

    time: float
    wrench: np.ndarray
    cone_rows: np.ndarray
    cone_bounds: np.ndarray
    margins: np.ndarray
    row_valid: np.ndarray
    mu_h: float
    torque_lever: float
    ground_rows: np.ndarray
    ground_bounds: np.ndarray
    mu_g: float
    ground_fitted: tuple[bool, bool]
    hand_mode: ContactMode
    hand_geometry: HandGeometry
    ground_mode: ContactMode
    in_contact: bool
    theta_o: float
    s_h: float
    s_g: float
    d: float
    r_o: np.ndarray
    theta_o_valid: bool
    s_h_valid: bool
    contact_valid: bool
    skipped: bool = False
    kinematics_mean: tuple[float, float, float, float] = (math.nan,) * 4
    kinematics_std: tuple[float, float, float, float] = (math.nan,) * 4
    compliance: float = math.nan
    compliance_std: float = math.nan
    gravity: GravityEstimate = UNKNOWN_GRAVITY
    hand_slid: bool = False
    ground_anchor: int = 0
    face: tuple[float, float] = UNKNOWN_FACE
    sliding_face: SlidingFace = UNDETERMINED
    kinematics_doubted: bool = False

    @property
    def friction_faces(self) -> tuple[np.ndarray, np.ndarray, tuple[bool, bool]]:
        """``(A, b, known)``, the ground's friction faces as far as they are known: fitted to the
        sliding forces where that fit is determined, else the hull's (:func:`ground_friction_faces`).
        What the statics of a motion and the planner judge with."""
        if self.sliding_face.determined:
            return _sliding_faces(self.sliding_face)
        return ground_friction_faces(self.ground_rows, self.ground_bounds, self.ground_fitted)

    @property
    def kinematics_valid(self) -> bool:
        """Whether ``θ_o``, ``s_h`` and ``s_g`` (and ``d``, ``r_o``) are all estimated."""
        return self.theta_o_valid and self.s_h_valid and self.contact_valid

    @property
    def configuration(self) -> ContactConfiguration:
        """The classified modes as a :class:`ccopt.modes.ContactConfiguration`."""
        return ContactConfiguration(self.hand_mode, self.hand_geometry, self.ground_mode)


class Estimator:
    """The object-agnostic estimator (see the module docstring).

    Args:
        hand: the robot's hand (the torque limits and pivot geometry need its length; nothing of
            the object is known).
        params: estimator parameters.
    """

    def __init__(self, hand: Hand | None = None, params: EstimatorParams | None = None) -> None:
        self.hand = hand if hand is not None else Hand()
        self.params = params if params is not None else EstimatorParams()
        validation.check_types((("hand", self.hand, Hand), ("params", self.params, EstimatorParams)))
        self.friction = HandFrictionEstimator(self.hand.half_length, self.params.friction)
        self.ground = GroundConeEstimator(self.params.ground)
        self.classifier = ModeClassifier(self.params.modes)
        self.kinematic_classifier = ModeClassifier(self.params.kinematic_modes)
        self.kinematics = KinematicEstimator(self.hand.half_length, self.params.kinematics)
        self.theta_filter = AngleFilter(self.params.theta_filter)
        self.gravity = GravityEstimator(self.params.gravity)
        self.face = FaceEstimator(self.hand.half_length, self.params.face)
        self.ground_slides = SlideEvidence(self.params.slid_distance)
        self.sliding_face = SlidingFaceFit(self.params.sliding_face)
        self.hand_slides = SlideEvidence(self.params.slid_distance)
        self._cone_input = np.zeros(12)
        self._contact_force = self.params.contact_force
        self._theta_noise = self.params.theta_filter.noise
        self._split_tilt = self.params.kinematics.split_tilt
        self._last_reports: tuple = (None,) * 5  # (likely, commanded, unobservable, ground or None, reports)
        self._cone_ground: GroundCone | None = None
        self._patch: tuple[float, float] | None = None  # the known face on the hand (known_patch)
        self._mismatch: tuple[int, float, float, int] | None = None  # samples, least/largest θ_o, resets
        self._give: list[float] | None = None  # start, moment sum, samples, filtered ŝ_h, last time
        self._ground_slide_start: tuple[tuple[bool, bool], FitSnapshot] | None = None  # at a slide's start
        self._last: Estimate | None = None

    def update(
        self,
        time: float,
        hand_pose: ArrayLike,
        hand_wrench: ArrayLike,
        commanded: ContactConfiguration | None = None,
    ) -> Estimate:
        """Process one sample: ``hand_pose = (x_h, y_h, θ_h)`` (world), ``hand_wrench = (f_n, f_t, τ)``.

        ``commanded`` is the configuration the controller enforces (None: unknown); the kinematics
        then trust it for every contact it keeps (:func:`commanded_modes`).

        Raises ``TypeError`` or ``ValueError`` (and changes nothing) unless ``time`` is a real
        number and the pose and wrench are three numbers each, all within the float range.
        """
        if type(time) is not float and not isinstance(time, Real):
            raise TypeError(f"time must be a real number, got {type(time).__name__} {time!r}")
        try:
            time = float(time)
            pose = np.asarray(hand_pose, dtype=float)
            wrench = np.asarray(hand_wrench, dtype=float)
        except OverflowError:  # an integer beyond the float range
            raise ValueError("time, hand_pose and hand_wrench must be within the float range") from None
        if pose.shape != (3,) or wrench.shape != (3,):
            raise ValueError(
                f"hand_pose and hand_wrench must have shape (3,), got {pose.shape} and {wrench.shape}"
            )
        pose_values, wrench_values = pose.tolist(), wrench.tolist()
        x_h, y_h, theta_h = pose_values
        f_n, f_t, torque = wrench_values
        if not _within_bounds(time, x_h, y_h, theta_h, f_n, f_t, torque):
            return self._skip(time)
        axes = geometry.hand_axes(theta_h)
        in_contact = f_n > self._contact_force
        friction = self.friction
        force_world = geometry.hand_to_world(axes, f_n, f_t)
        if in_contact:
            friction.update(f_n, f_t)
            self.ground.update(time, force_world)
        ground = self.ground.cone
        mu_h, lever = friction.mu_h, friction.l_h_eff
        cone, margins = self._cone(theta_h, mu_h, lever, ground, wrench)
        valid, row_valid = _ROW_VALID[friction.valid, ground.valid]
        modes = self.classifier.update(time, patch_margins(margins, self._patch, f_n, torque), valid)
        likely = self.kinematic_classifier.update(time, margins, valid)
        kept, ground_may_slide, hand_may_slide, both = self._reports(likely, commanded, theta_h, ground)
        kinematics = self.kinematics.update(
            pose, *axes, kept, in_contact, ground_may_slide, torque, hand_may_slide, f_n
        )
        theta_o = kinematics.theta_o
        if in_contact and kinematics.theta_o_valid and likely.hand_geometry == _FLUSH:
            theta_o = self.theta_filter.update(time, theta_o)
        else:
            self.theta_filter.reset()
        gravity = self.gravity.update(
            theta_o, pose_values, wrench_values, kinematics, self.kinematics.ground_contact(), force_world
        )
        doubted = self._check_moment(theta_o)
        self._check_hand_give(time, commanded, theta_h, likely, kinematics, f_n, f_t, torque)
        slid, ground_way = self._slid(commanded, kinematics, theta_h, both, likely)
        slid = self._drop_unfounded_slide(commanded, kinematics, slid)
        sliding_face = self.sliding_face.update(
            time, force_world, ground_way if in_contact else 0, self.ground_slides.confirmed
        )
        hand_slid = self.hand_slides.slid
        known = kinematics.theta_o_valid and kinematics.s_h_valid and kinematics.contact_valid
        flush = in_contact and likely.hand_geometry == _FLUSH
        slides = commanded is not None and commanded.slides
        face = self.face.update(known, kinematics.s_h, kinematics.d, flush, f_n, torque, slides)
        self._patch = known_patch(face, kinematics.s_h)
        self._last = _assemble(
            time,
            np.frombuffer(wrench.tobytes()),  # a read-only copy
            cone,
            row_valid,
            mu_h,
            lever,
            ground,
            modes,
            in_contact,
            theta_o,
            kinematics,
            False,
            self._rough(theta_o, kinematics),
            gravity,
            slid,
            hand_slid[0] or hand_slid[1],
            face,
            sliding_face,
            doubted,
        )
        return self._last

    def _check_moment(self, theta_o: float) -> bool:
        """Reset the kinematics once the moment balance about their ground contact has disagreed
        with ``M̂`` (:meth:`~.gravity.GravityEstimator._consistent`) on ``moment_mismatch_samples``
        samples spanning ``moment_mismatch_tilt`` of ``θ_o``, with no sample agreeing in between
        (samples the balance does not judge, a hand off flush or a ground moving, neither count nor
        break the run): the object does not rest where the kinematics say (a contact slid unseen,
        or it turned onto another vertex), and what they report is wrong however certain it looks.
        The next sample starts them afresh (a goal then explores again).

        On a goals-study pentagon (seed 2, trial 1, noise seed 0) an exploration pivot turned the
        object onto its neighbouring vertex (``d`` 121 → 134 mm, the ground contact 43 mm along the
        ground); the kinematics stayed on the first contact and, unchecked, an ``s_g`` goal was
        claimed reached 16 mm off by the truth. The balance disagreed 0.11 s after the turn; checked,
        the goal is reached 0.9 mm off (:mod:`tests.test_goal_recovery`). When the check was
        added (before the pivots about the naive lever were paced), over seeds 0–7 of the goals
        study it took the
        goals claimed reached outside their tolerance from 69 to 57 (those off by three tolerances
        or more from 31 to 18), and the goals reached of those the oracle reaches from 90.4 % to
        89.8 %: goals whose kinematics it let go of failed after three explorations.

        A range of tilts, not a time: an object that lands on a face has a second ground contact,
        whose force disagrees with the balance at the tilt where it landed for as long as it lies
        there. Reset after 0.2 s of disagreement, the goals study lost the kinematics of objects
        lying on a face with their contact still known, and 38 goals the oracle reaches failed
        where 9 had. Over 3° instead of 5°: 51 goals claimed outside their tolerance (17 by three
        or more), 88.9 % reached (and, measured again later, the paper hexagon's known face broken:
        see ``docs/architecture.md``).

        Returns whether the kinematics are doubted meanwhile (:meth:`_doubted`): short of the
        reset, a disagreement over ``moment_doubt_tilt`` already means the object turned while
        resting elsewhere (lying on a face, it does not turn), and a goal is not claimed on the
        positions (:class:`~ccopt.planning.sequencer.GoalSequencer`)."""
        agreed = self.gravity.agreed
        if agreed is None:
            return self._doubted()
        if agreed:
            self._mismatch = None
            return False
        resets = self.kinematics.resets
        count, low, high, since = self._mismatch or (0, theta_o, theta_o, resets)
        if since != resets:  # the kinematics started afresh since: so does the run
            count, low, high = 0, theta_o, theta_o
        count, low, high = count + 1, min(low, theta_o), max(high, theta_o)
        params = self.params
        if count >= params.moment_mismatch_samples and high - low >= params.moment_mismatch_tilt:
            self.kinematics.reset()
            self._mismatch = None
            return False
        self._mismatch = (count, low, high, resets)
        return self._doubted()

    def _doubted(self) -> bool:
        """Whether the disagreement under way (:meth:`_check_moment`) has lasted
        ``moment_mismatch_samples`` samples over ``moment_doubt_tilt`` of ``θ_o`` since the
        kinematics last started afresh (:attr:`Estimate.kinematics_doubted`)."""
        mismatch = self._mismatch
        if mismatch is None:
            return False
        count, low, high, since = mismatch
        params = self.params
        return (
            since == self.kinematics.resets
            and count >= params.moment_mismatch_samples
            and high - low >= params.moment_doubt_tilt
        )

    def _check_hand_give(
        self,
        time: float,
        commanded: ContactConfiguration | None,
        theta_h: float,
        likely: ContactConfiguration,
        kinematics: KinematicEstimate,
        f_n: float,
        f_t: float,
        torque: float,
    ) -> None:
        """Reset the kinematics where a commanded ground slide moved the hand instead, unseen.

        Within :attr:`~.kinematics.KinematicsParams.split_tilt` of the vertical a ground slide and
        a hand slide along the face move the hand alike, and where the hand's friction is not yet
        measured the kinematics trust the command (:func:`either_slides`). The moment balance
        tells them apart: while the hand is flush, ``s_h = (d f_t − τ − M)/f_n``
        (:func:`~.gravity.flush_hand_position`), and at the slide's tilt ``M`` holds still. So the
        moment is taken over the slide's first 50 ms from the kinematics' own ``ŝ_h`` and ``d̂``
        (:func:`~.gravity.flush_moment`), and from then on the
        ``s_h`` that moment gives, low-pass filtered (``hand_give_filter``) over the samples whose
        hand the classifier reports flush (a hand at its torque limit flickers in and out: the
        samples between are skipped), follows the hand's true position on the face; once it
        departs from ``ŝ_h`` by ``hand_give`` the hand has slid, and the kinematics start afresh
        (the step then ends ``lost``, and a goal explores again).

        Applied to the recorded goals-study trials of seeds 2 and 3, the 33 ground slides begun within
        11° of the vertical whose hand stayed within 1 mm by the truth departed by at most 4.8 mm;
        seven of the eight whose hand slid 6.8–12.8 mm, all read as the ground's, departed by
        5.7–11.3 mm (the eighth, 2.7 mm, had been ``lost`` already). Goals study seeds 0–7, against
        the moment check alone: goals claimed reached outside their tolerance 57 → 52, of them
        three tolerances or more off 18 → 11; oracle-reachable goals reached 89.8 → 89.5 %."""
        give = self._give
        watched = (
            commanded is not None
            and commanded.ground_mode != _STICK
            and commanded.hand_mode == _STICK
            and not self._split_observable(theta_h)
            and kinematics.contact_valid
            and kinematics.s_h_valid
            and f_n > self._contact_force
        )
        if not watched:
            self._give = None
            return
        if likely.hand_geometry != _FLUSH:  # the balance needs the hand flush: skipped, not ended
            return
        d, s_h = kinematics.d, kinematics.s_h
        if give is None:
            self._give = [time, flush_moment(f_n, f_t, torque, s_h, d), 1.0, math.nan, time]
            return
        start, moment_sum, count, filtered, last = give
        if time - start < HAND_GIVE_SETTLE:
            give[1], give[2], give[4] = moment_sum + flush_moment(f_n, f_t, torque, s_h, d), count + 1.0, time
            return
        position = flush_hand_position(f_n, f_t, torque, d, moment_sum / count)
        if math.isnan(filtered):
            filtered = position
        else:
            weight = 1.0 - math.exp(-(time - last) / self.params.hand_give_filter)
            filtered += (position - filtered) * weight
        if abs(filtered - s_h) >= self.params.hand_give:
            self.kinematics.reset()
            self._give = None
            return
        give[3], give[4] = filtered, time

    def _reports(
        self,
        likely: ContactConfiguration,
        commanded: ContactConfiguration | None,
        theta_h: float,
        ground: GroundCone,
    ) -> tuple[ContactConfiguration, bool, bool, bool]:
        """``(modes, ground_may_slide, hand_may_slide, both)`` for the kinematics
        (:func:`_kinematic_reports`, the modes through :func:`kinematic_modes` unless both may slide).
        The last inputs and reports are kept: the configurations and the cone are immutable, and the
        same objects for many samples in a row; the cone counts only where :func:`kinematic_modes`
        reads it (a ground-slide report), so a refit leaves the other reports as they were."""
        unobservable = self._split_unobservable(theta_h)
        last = self._last_reports
        if (
            likely is last[0]
            and commanded is last[1]
            and unobservable == last[2]
            and (last[3] is None or ground is last[3])
        ):
            return last[4]
        kept, ground_may_slide, hand_may_slide, both = _kinematic_reports(likely, commanded, unobservable)
        reports = (kept if both else kinematic_modes(kept, ground), ground_may_slide, hand_may_slide, both)
        read = not both and kept.ground_mode != _STICK
        self._last_reports = (likely, commanded, unobservable, ground if read else None, reports)
        return reports

    def _split_unobservable(self, theta_h: float) -> bool:
        """Whether a hand at its measured friction limit in a ground slide leaves the kinematics
        unable to tell which contact slid (:func:`either_slides`): the hand has slid before, so
        ``μ̂_h`` is its limit and not merely a lower bound, and the tilt is so small that the pose
        separates the two slides by less than ``valid_std`` (``position_noise / |sin θ|``)."""
        measured = self.hand_slides.slid[0] or self.hand_slides.slid[1]
        return measured and not self._split_observable(theta_h)

    def _split_observable(self, theta_h: float) -> bool:
        """Whether the tilt separates a ground slide from a hand slide along the face by at least
        ``valid_std`` in the pose (:attr:`~.kinematics.KinematicsParams.split_tilt`)."""
        return abs(theta_h) >= self._split_tilt

    def _rough(
        self, theta_o: float, kinematics: KinematicEstimate
    ) -> tuple[tuple[float, ...], tuple[float, ...]]:
        """``(kinematics_mean, kinematics_std)`` of the :class:`Estimate`."""
        d, x_o, _, s_h = kinematics.rough
        std_d, std_x, _, std_s = kinematics.std
        theta_std = math.hypot(kinematics.theta_std, self._theta_noise)
        theta = theta_o if kinematics.theta_o_valid else math.nan
        return (theta, s_h, x_o, d), (theta_std, std_s, std_x, std_d)

    def _cone(
        self, theta_h: float, mu_h: float, l_h: float, ground: GroundCone, wrench: np.ndarray
    ) -> tuple[tuple[np.ndarray, np.ndarray, np.ndarray], list[float]]:
        """Read-only ``(N (6×3), b (6), b − N w (6))`` of :data:`ccopt.contact.cone_rows` (hand frame),
        and the margins as floats."""
        flat = self._cone_input
        flat[0], flat[1], flat[2] = theta_h, mu_h, l_h
        if ground is not self._cone_ground:  # the ground rows change only when refitted
            flat[3:7] = ground.A.ravel(order="F")
            flat[7:9] = ground.b
            self._cone_ground = ground
        flat[9:12] = wrench
        binding = _CONE_ROWS.buffers()
        binding.flat_inputs[0][:] = flat
        binding.evaluate()
        out = np.frombuffer(binding.flat_outputs[0].tobytes())  # a read-only copy
        rows = 3 * N_CONE_ROWS
        margins = out[rows + N_CONE_ROWS :]
        return (out[:rows].reshape(N_CONE_ROWS, 3), out[rows : rows + N_CONE_ROWS], margins), margins.tolist()

    def _slid(
        self,
        commanded: ContactConfiguration | None,
        kinematics: KinematicEstimate,
        theta_h: float,
        either: bool,
        likely: ContactConfiguration,
    ) -> tuple[tuple[bool, bool], int | None]:
        """Update the slide evidence of both contacts; the ways the ground slid, and the way it is
        meant to slide now. Without a command the ground counts while the kinematics let it move;
        the hand does not count. While ``either`` contact may be the one sliding
        (:func:`either_slides`), the ground does not; where it slipped in a hand slide
        (:meth:`_ground_gave`), it counts either way.

        On a goals-study triangle (0.94 kg, μ_g 0.41) hand slides at 17° slid the ground instead,
        3.4–5.4 mm each, six times over two goals, while the ground rows stayed unknown and so bound
        none of them."""
        hand = commanded.hand_mode if commanded is not None else None
        ground = commanded.ground_mode if commanded is not None else None
        self.hand_slides.update(kinematics.s_h, _sliding_way(hand), theta_h, kinematics.rough[0])
        free = None if not kinematics.ground_fixed else 0
        way = 0 if either else _sliding_way(ground, free)
        if way == 0 and free is None and self._ground_gave(hand, likely, theta_h):
            way = None
        return self.ground_slides.update(kinematics.s_g, way), way

    def _drop_unfounded_slide(
        self, commanded: ContactConfiguration | None, kinematics: KinematicEstimate, slid: tuple[bool, bool]
    ) -> tuple[bool, bool]:
        """The ways the ground was seen sliding, without what a commanded ground slide added before
        its kinematics were lost (reset or released: :meth:`_check_hand_give`, :func:`either_slides`,
        a hand that gave seen by the pose); the sliding-force fit loses that slide's forces too.

        The evidence came from ``ŝ_g`` moving as the kinematics followed the ground, and the
        kinematics were let go because what moved may have been the hand: kept, the hand's friction
        limit, seen in world axes, became the ground's friction face on that side (and, mirrored,
        on the other). On a goals-study triangle (seed 6, trial 34, noise seed 10) a ground slide
        at 10° moved the hand 4.8 mm along the face in 2.7 s, the ground not at all; kept, its
        evidence gave ``μ̂_g`` 0.37 against the true 0.69 and the goal, which the oracle reaches, was
        reported unreachable; dropped, it is reached (:mod:`tests.test_goal_recovery`)."""
        if commanded is None or commanded.ground_mode == _STICK:
            self._ground_slide_start = None
            return slid
        start = self._ground_slide_start
        if start is None:
            self._ground_slide_start = (slid, self.sliding_face.snapshot())
            return slid
        slid_then, fit_then = start
        lost = not (kinematics.theta_o_valid and kinematics.s_h_valid and kinematics.contact_valid)
        if lost and (slid != slid_then or self.sliding_face.face is not fit_then.face):
            self.ground_slides.restore(slid_then)
            self.sliding_face.restore(fit_then)
            return slid_then
        return slid

    def _ground_gave(self, hand: ContactMode | None, likely: ContactConfiguration, theta_h: float) -> bool:
        """Whether a ground the kinematics follow in a commanded hand slide is the contact that gave:
        the forces keep the hand inside its friction cone (``likely``; ``μ̂_h`` is at most the true
        friction, so the hand stuck) and the tilt tells the two slides apart (:meth:`_split_observable`).
        A hand at its limit does not tell: on the paper rectangle the exploration's hand slide (+3 mm
        at 16.6°, the ground still) had the kinematics follow the ground, whose estimate wandered
        ±1 mm a sample and drifted 3 mm with the hand's own slide."""
        if hand is None or hand == _STICK or likely.hand_mode != _STICK:
            return False
        return self._split_observable(theta_h)

    def _skip(self, time: float) -> Estimate:
        if self._last is None:
            return _empty_estimate(time, self.friction, self.ground)
        return dataclasses.replace(self._last, time=float(time), skipped=True)


def _within_bounds(
    time: float, x_h: float, y_h: float, theta_h: float, f_n: float, f_t: float, torque: float
) -> bool:
    """Whether each of a sample's ``(time, x_h, y_h, θ_h, f_n, f_t, τ)`` is within its
    :data:`SAMPLE_BOUNDS` (False for NaN)."""
    b_time, b_x, b_y, b_theta, b_n, b_t, b_torque = SAMPLE_BOUNDS
    return (
        abs(time) <= b_time
        and abs(x_h) <= b_x
        and abs(y_h) <= b_y
        and abs(theta_h) <= b_theta
        and abs(f_n) <= b_n
        and abs(f_t) <= b_t
        and abs(torque) <= b_torque
    )


def _sliding_way(commanded: ContactMode | None, fallback: int | None = 0) -> int | None:
    """The way a contact is meant to slide: ``±1`` as commanded, 0 if it is meant to stick, and
    ``fallback`` without a command (None: either way). Not the reports: a hull edge the data merely
    end at is reported as a face, the kinematics then follow the ground (a cheap false alarm for
    them), and a pivot's rotation through a slightly wrong ``d`` would pass for a slide."""
    return int(commanded) if commanded is not None else fallback


def ground_friction_faces(
    rows: np.ndarray, bounds: np.ndarray, fitted: tuple[bool, bool]
) -> tuple[np.ndarray, np.ndarray, tuple[bool, bool]]:
    """``(A, b, known)``: the ground rows as friction faces. A side the ground slid past is its hull
    face; once one side is known, the other is its mirror image about world up (Coulomb friction is
    the same both ways on a flat ground, and the weight, so the cone's apex, is on the vertical
    through the origin of the force plane): far nearer the truth than the edge of the sticking
    forces seen on that side, which lies wherever the forces happened to stop (on a goal run of the
    paper triangle, ground slides planned on it were tried at four tilts before the one that works).
    Neither side known: both unknown."""
    faces, offsets = np.array(rows, dtype=float), np.array(bounds, dtype=float)
    if fitted[0] != fitted[1]:
        source, target = (0, 1) if fitted[0] else (1, 0)
        faces[target] = faces[source] * (-1.0, 1.0)
        offsets[target] = offsets[source]
        return faces, offsets, (True, True)
    return faces, offsets, fitted


@functools.lru_cache(maxsize=8)
def _sliding_faces(face: SlidingFace) -> tuple[np.ndarray, np.ndarray, tuple[bool, bool]]:
    """``(A, b, known)`` of a determined :class:`SlidingFace` (read-only; made once per fit)."""
    (normal_pos, b_pos), (normal_neg, b_neg) = face.rows()
    rows, bounds = _read_only((normal_pos, normal_neg)), _read_only((b_pos, b_neg))
    return rows, bounds, (True, True)


class SlideEvidence:
    """Which ways a contact has been seen sliding: while it is meant to slide one way
    (:func:`_sliding_way`), its estimated position (``s_g`` or ``s_h``) moved by at least
    ``distance`` (m) that way, beyond what the hand's turn since explains. The way counts: when the
    kinematics start following a sliding ground, ``ŝ_g`` first jumps by up to a millimetre either
    way. The turn counts for the hand: the kinematics take a hand meant to slide as flush, so a hand
    that rolls on the face's end by ``Δθ_h`` moves ``ŝ_h`` by about ``d̂ Δθ_h`` without sliding at
    all (on the paper triangle, 2.8 mm over a 1° roll of a hand-slide probe, which froze ``μ̂_h`` at
    0.20 against the true 0.5), while a hand that slides and rolls at once moves it further.

    Only on a side the ground slid is the hull face the ground's friction face; before, it is
    merely where the data end (e.g. the hand forces of pivots at a tilted hand lie along a straight
    edge of the hull that looks like a face). Once the hand has slid, ``μ̂_h`` was measured at its
    limit and is no longer a bound to explore beyond.
    """

    def __init__(self, distance: float) -> None:
        self.distance = check_number("distance", distance)
        self.slid = [False, False]
        """Per way: ``[+, −]`` (for the ground, rows ``GROUND_SLIDE_POS``, ``GROUND_SLIDE_NEG``)."""
        self.confirmed = 0
        """How many times the contact was seen sliding since it was last let move."""
        self._start = math.nan  # the position where the contact was last let move
        self._angle = 0.0  # the hand's angle there

    def update(
        self, position: float, way: int | None, angle: float = 0.0, lever: float = 0.0
    ) -> tuple[bool, bool]:
        """Advance with the current position estimate (m, NaN if unknown), the way the contact is
        meant to slide (``±1``, 0 not at all, None either way), the hand's angle (rad) and the lever
        (m) by which a turn of the hand moves ``position`` (NaN: unknown, nothing counts); the ways
        seen so far."""
        if way == 0 or not math.isfinite(position):
            self._start, self.confirmed = math.nan, 0
        elif math.isnan(self._start):
            self._start, self._angle = position, angle
        else:
            moved = position - self._start
            needed = self.distance + abs(lever * (angle - self._angle))
            if abs(moved) >= needed and (way is None or moved * way > 0.0):
                self.slid[0 if moved > 0.0 else 1] = True
                self._start, self._angle = position, angle
                self.confirmed += 1
        return self.slid[0], self.slid[1]

    def restore(self, slid: tuple[bool, bool]) -> None:
        """Set the ways seen sliding back to ``slid`` (``[+, −]``), as if the contact had not been
        let move since."""
        self.slid = list(slid)
        self._start, self.confirmed = math.nan, 0


@functools.cache  # 27 × 10 configurations: each case is made once
def commanded_modes(
    modes: ContactConfiguration, commanded: ContactConfiguration | None
) -> ContactConfiguration:
    """The reported ``modes`` with every contact ``commanded`` keeps (sticking, flush) kept.

    The paper's kinematic estimator relies on the controller enforcing sticking. The classifier is
    conservative (a contact near an estimated boundary "may be moving", and the hand friction prior
    is far below the truth at first), so a report of a contact the controller keeps is not acted
    on: the kinematics' innovation gates catch a contact that moved all the same. Only a contact
    the command sets moving is taken as reported. None (no command known) keeps the reports.
    """
    if commanded is None:
        return modes
    return ContactConfiguration(
        modes.hand_mode if commanded.hand_mode != ContactMode.STICK else ContactMode.STICK,
        modes.hand_geometry if commanded.hand_geometry != HandGeometry.FLUSH else HandGeometry.FLUSH,
        modes.ground_mode if commanded.ground_mode != ContactMode.STICK else ContactMode.STICK,
    )


def _unacted_reports(
    likely: ContactConfiguration, commanded: ContactConfiguration | None
) -> tuple[bool, bool]:
    """``(ground_may_slide, hand_may_slide)`` for the kinematics: a contact reported sliding that the
    kinematics still take as sticking. Without a command, a ground-slide report (the kinematics then
    follow a slip their gate sees, :func:`kinematic_modes`). With one, a ground-slide report in any
    commanded slide: in a hand slide whose hand the forces put inside its friction cone the ground is
    the contact that gives (``μ̂_h`` is a lower bound of the true friction, so the hand surely sticks;
    on goal runs the exploration's hand-slide probe at 17° slid the ground 3–5 mm instead, which
    taken as the hand's left ``ŝ_h`` and ``ŝ_g`` off by as much); and a hand-slide report while the
    command keeps the hand sticking (its eq. 16 gate is then tighter, to catch a creeping slide)."""
    if commanded is None:
        return likely.ground_mode != ContactMode.STICK, False
    slide = commanded.slides
    hand = commanded.hand_mode == ContactMode.STICK and likely.hand_mode != ContactMode.STICK
    ground = slide and likely.ground_mode != ContactMode.STICK
    return ground, hand


def either_slides(
    likely: ContactConfiguration, commanded: ContactConfiguration | None, unobservable: bool
) -> bool:
    """Whether a commanded ground slide may be the hand's slide instead: the forces put the hand at
    its friction limit too, and the split is ``unobservable`` from the pose (both move the hand
    along the face, the ground slide horizontally: their difference is ``sin θ_o`` of the motion;
    :meth:`Estimator._split_unobservable`). The kinematics then release both positions
    (:class:`~ccopt.estimation.kinematics.KinematicEstimator`: their standard deviations say the
    estimate is no longer valid) and the ground does not count as seen sliding. On goal runs of
    random objects the planner's ground slides at 3–10° where the hand gave first slid the hand
    6–8 mm; taken as the ground's, they left ``ŝ_g`` and ``ŝ_h`` off by as much and marked a ground
    friction face where the ground never slid. Where the hand has not slid yet ``μ̂_h`` is only
    the largest ratio seen, which every first ground slide reaches: releasing both there made the
    tours' ground slides noisy and slow, so the command is trusted while the slide runs, and the
    kinematics hold the other reading once it ends, until a pivot settles it
    (:meth:`~ccopt.estimation.kinematics.KinematicEstimator._doubt_following`)."""
    return (
        unobservable
        and commanded is not None
        and commanded.ground_mode != ContactMode.STICK
        and commanded.hand_mode == ContactMode.STICK
        and likely.hand_mode != ContactMode.STICK
    )


@functools.cache  # 27 × 10 × 2 cases, as commanded_modes
def _kinematic_reports(
    likely: ContactConfiguration, commanded: ContactConfiguration | None, unobservable: bool
) -> tuple[ContactConfiguration, bool, bool, bool]:
    """``(modes, ground_may_slide, hand_may_slide, both)`` for the kinematics: the most likely modes
    with every contact ``commanded`` keeps kept (:func:`commanded_modes`), :func:`_unacted_reports`,
    and whether both contacts may be sliding (:func:`either_slides`: the modes are then the hand's
    report with the commanded ground slide, taken as they are)."""
    if either_slides(likely, commanded, unobservable):
        both = ContactConfiguration(likely.hand_mode, HandGeometry.FLUSH, commanded.ground_mode)
        return both, False, False, True
    return commanded_modes(likely, commanded), *_unacted_reports(likely, commanded), False


def kinematic_modes(modes: ContactConfiguration, ground: GroundCone) -> ContactConfiguration:
    """The configuration the kinematic estimator works under.

    The classifier is conservative: it reports the ground "may be sliding" near any boundary of the
    data hull, including before a friction face was ever seen (the prior rows) and while the hull is
    still the extent of the data rather than the cone. Right for the controller and the record, but
    it would keep the regression from ever starting — a ground slide is often not even possible at
    the start (see the feasibility study). So a ground-slide report is kept only in the paper's rigid
    case (the hand reported sticking) towards a fitted face of a valid cone; otherwise the
    kinematics assume the ground sticks, and their innovation gate tells when it really moved. Both
    contacts sliding is never commanded. Hand reports go through unchanged (a reported hand slide
    releases ``s_h``).
    """
    if modes.ground_mode == ContactMode.STICK:
        return modes
    side = 0 if modes.ground_mode == ContactMode.SLIDE_POS else 1
    trusted = ground.valid and ground.fitted[side] and modes.hand_mode == ContactMode.STICK
    return modes if trusted else _GROUND_STICKING[modes.hand_mode, modes.hand_geometry]


_GROUND_STICKING = {
    (hand, geometry_sign): ContactConfiguration(ContactMode(hand), HandGeometry(geometry_sign))
    for hand in (-1, 0, 1)
    for geometry_sign in (-1, 0, 1)
}
"""Every configuration with the ground sticking, by ``(hand mode, hand geometry)`` (immutable)."""


def _read_only(values: tuple[bool | float, ...]) -> np.ndarray:
    array = np.array(values)
    array.flags.writeable = False
    return array


_ROW_VALID = {
    (hand, ground): (valid, _read_only(valid))
    for hand in (False, True)
    for ground in (False, True)
    for valid in [(hand, hand, True, True, ground, ground)]  # order: Row
}
"""Which cone rows are estimated, by whether the hand friction and the ground rows are: as a tuple
(for the classifiers) and as the read-only array of an :class:`Estimate` (shared: it is immutable)."""


def known_patch(face: tuple[float, float], s_h: float) -> tuple[float, float] | None:
    """The known face (:mod:`.face`) on the hand, ``(u_low + ŝ_h, u_high + ŝ_h)`` (m, hand positions):
    None while it is unknown (NaN) or empty."""
    low, high = face
    if not low <= high:
        return None
    return low + s_h, high + s_h


def patch_margins(
    margins: list[float], patch: tuple[float, float] | None, f_n: float, torque: float
) -> list[float]:
    """The cone's margins (order :class:`~ccopt.contact.Row`) with the hand's torque rows taken on
    the contact patch as far as it is known: the hand (``margins``) cut to the known face ``patch``
    (:func:`known_patch`; None: the whole hand), whichever margin is smaller.

    The hand rolls about the face's end once its centre of pressure reaches it, however far that is
    from the hand's own ends. On a goals-study sliver (seed 0, trial 21) a ground slide with the hand
    9 mm past the ground contact moved the centre of pressure from 19 to 4 mm from the hand's centre,
    onto the face's end, and the object turned 17° under the hand while the hand's torque rows kept
    0.3–0.5 N·m of margin: no roll was reported, and the goal was reported reached with ``s_g`` 10 mm
    off. Cut to the known face, the slide ended ``rolled`` with the hand turned 0.9°. The known face
    lies inside the true one (:mod:`.face`), so this reports a roll at least as early as it happens:
    conservative, as the reported modes are."""
    if patch is None:
        return margins
    pos, neg = contact.patch_torque_margins(f_n, torque, *patch)
    cut = list(margins)
    cut[_PIVOT_POS] = min(cut[_PIVOT_POS], pos)
    cut[_PIVOT_NEG] = min(cut[_PIVOT_NEG], neg)
    return cut


def _assemble(
    time: float,
    wrench: np.ndarray,
    cone: tuple[np.ndarray, np.ndarray, np.ndarray],
    row_valid: np.ndarray,
    mu_h: float,
    torque_lever: float,
    ground: GroundCone,
    modes: ContactConfiguration,
    in_contact: bool,
    theta_o: float,
    kinematics: KinematicEstimate,
    skipped: bool,
    rough: tuple[tuple[float, ...], tuple[float, ...]],
    gravity: GravityEstimate,
    slid: tuple[bool, bool],
    hand_slid: bool,
    face: tuple[float, float],
    sliding_face: SlidingFace,
    kinematics_doubted: bool,
) -> Estimate:
    """An :class:`Estimate` from its parts (the arrays read-only); ``rough`` is ``(kinematics_mean,
    kinematics_std)``, ``slid`` the ways the ground was seen sliding."""
    fitted = (ground.fitted[0] and slid[0], ground.fitted[1] and slid[1])
    hull_mu_g = ground.mu_g if fitted[0] and fitted[1] else math.nan
    cone_rows, cone_bounds, margins = cone
    return record(
        Estimate,
        {
            "time": time,
            "wrench": wrench,
            "cone_rows": cone_rows,
            "cone_bounds": cone_bounds,
            "margins": margins,
            "row_valid": row_valid,
            "mu_h": mu_h,
            "torque_lever": torque_lever,
            "ground_rows": ground.A,
            "ground_bounds": ground.b,
            "mu_g": sliding_face.mu_g if sliding_face.determined else hull_mu_g,
            "ground_fitted": fitted,
            "hand_mode": modes.hand_mode,
            "hand_geometry": modes.hand_geometry,
            "ground_mode": modes.ground_mode,
            "in_contact": in_contact,
            "theta_o": theta_o,
            "s_h": kinematics.s_h,
            "s_g": kinematics.s_g,
            "d": kinematics.d,
            "r_o": kinematics.r_o,
            "theta_o_valid": kinematics.theta_o_valid,
            "s_h_valid": kinematics.s_h_valid,
            "contact_valid": kinematics.contact_valid,
            "compliance": kinematics.compliance,
            "compliance_std": kinematics.compliance_std,
            "skipped": skipped,
            "kinematics_mean": rough[0],
            "kinematics_std": rough[1],
            "gravity": gravity,
            "hand_slid": hand_slid,
            "ground_anchor": kinematics.anchor,
            "face": face,
            "sliding_face": sliding_face,
            "kinematics_doubted": kinematics_doubted,
        },
    )


_UNKNOWN_KINEMATICS = KinematicEstimate(
    math.nan, math.nan, math.nan, math.nan, np.full(2, math.nan), (math.nan,) * 4, False, False, False
)


def _empty_estimate(time: float, friction: HandFrictionEstimator, ground: GroundConeEstimator) -> Estimate:
    """The estimate before any finite sample: no cone (NaN), nothing valid, not in contact."""
    nan = np.full(N_CONE_ROWS, math.nan)
    cone = (np.full((N_CONE_ROWS, 3), math.nan), nan, nan.copy())
    wrench, row_valid = _read_only((math.nan,) * 3), _read_only((False,) * N_CONE_ROWS)
    parts = (wrench, cone, row_valid, friction.mu_h, friction.l_h_eff, ground.cone)
    unknown = ((math.nan,) * 4, (math.nan,) * 4)
    return _assemble(
        time,
        *parts,
        ContactConfiguration(),
        False,
        math.nan,
        _UNKNOWN_KINEMATICS,
        True,
        unknown,
        UNKNOWN_GRAVITY,
        (False, False),
        False,
        UNKNOWN_FACE,
        UNDETERMINED,
        False,
    )


def replay(
    times: Iterable[float],
    hand_poses: Iterable[ArrayLike],
    hand_wrenches: Iterable[ArrayLike],
    hand: Hand | None = None,
    params: EstimatorParams | None = None,
) -> list[Estimate]:
    """Run a fresh :class:`Estimator` of ``hand`` over a recording; one :class:`Estimate` per sample."""
    estimator = Estimator(hand, params)
    return [
        estimator.update(time, pose, wrench)
        for time, pose, wrench in zip(times, hand_poses, hand_wrenches, strict=True)
    ]
