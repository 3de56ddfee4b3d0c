"""What the object allows: the statics of a flush hand and a point ground contact, per commanded motion.

With the hand flush on a face and the object on one vertex, a hand wrench ``w = (f_n, f_t, τ)`` (hand
frame, :mod:`ccopt.geometry`) holds the object in static equilibrium (paper eq. 1) exactly when the
ground force ``f_g = −f_h − f_grav`` lies in the ground friction cone and the moments about the
ground contact ``r_o`` balance::

    τ − d f_t + s_h f_n + M(θ_o) = 0,          M(θ_o) = a cos θ_o + b sin θ_o,

where ``M`` is the moment of the object's weight about ``r_o`` (CCW positive; body-fixed centre of
mass, so ``M`` is linear in ``cos θ_o, sin θ_o``: :class:`GravityMoment`). The ground rows of the
generalized friction cone (:data:`ccopt.contact.cone_rows`) are written on the hand force with the
weight inside their bounds, so the ground force never appears.

For one configuration ``(θ_o, s_h)`` and one commanded motion (:class:`ccopt.modes.Motion`), a linear
program over ``(f_n, f_t, τ, t)``

* keeps every cone row the motion keeps (:func:`ccopt.modes.kept_rows`) with a margin ``≥ t``
  (torque rows divided by ``l_h`` so that every margin is a force, N);
* puts the contact at its limit in the commanded direction: the removed row's LHS is exactly 0
  (e.g. ``μ_h f_n + f_t = 0`` for ``SLIDE_HAND_POS``);
* balances the moments (above) and presses with ``f_min ≤ f_n ≤ f_max``;

and maximises ``t``, the **margin**: the motion is possible, with every other contact keeping its
mode, where the margin is at least :data:`MIN_MARGIN`. The best wrench includes the normal force: a
hand slide, for one, needs ``|±d μ_h − s_h − M/f_n| ≤ l_h``, which gravity's moment helps only at low
normal force. ``HOLD`` and ``PIVOT`` keep every row and share their answer.

The statics take **parameters**, not an object (:class:`ObjectStatics`): the true ones — the
experimenter's oracle (:meth:`ObjectStatics.of_model`, :func:`true_statics`, :func:`schedule_feasibility`)
— or the estimated ones (``μ̂_h``, the estimated ground rows, ``d̂``, an estimated ``M``) for the
controller and the planner. The LP is written once in CasADi (:func:`build_statics_lp`, the contact
model's own rows and equilibrium) and solved by DAQP (:data:`LP_PROXIMAL_WEIGHT`), about 10 µs a
solve; a cvxpy + Clarabel twin checks it in the tests.
"""

from __future__ import annotations

import dataclasses
import functools
import itertools
import math
from collections.abc import Iterable
from dataclasses import dataclass

import casadi as ca
import numpy as np

from ccopt import contact, geometry, modes
from ccopt.casadi_eval import BufferedFunction
from ccopt.contact import N_CONE_ROWS, Row
from ccopt.hand import Hand
from ccopt.modes import Motion
from ccopt.objects import PlanarObject
from ccopt.plant.base import StartConfig
from ccopt.plant.placement import face_s_h_range, start_poses
from ccopt.schedule import Step

MIN_MARGIN = 0.3
"""Margin (N) every kept row needs for a configuration to count as held, by default."""

_TORQUE_ROWS = (Row.HAND_PIVOT_POS, Row.HAND_PIVOT_NEG)
_N_PARAMETERS = 14  # θ_o, s_h, d, M, μ_h, l_h, vec(A) (4, column-major), b (2), face (2)
_N_ROWS = N_CONE_ROWS + 3  # cone rows, moment balance, |f_n − f_nom| ≤ u
_N_UNKNOWNS = 5  # f_n, f_t, τ, t, u
_BIG = 1e6
"""Bound on ``|f_t|``, ``|τ|`` and ``|t|`` of the LP (N, N·m): far beyond any wrench considered."""
_FACE_FAR = 1e3
"""The face's ends are clipped to ``±`` this (m) for the LP: an unbounded face cuts nothing from the
hand, an empty one ``(inf, −inf)`` leaves an empty patch, and the LP's matrix stays finite."""
LP_PROXIMAL_WEIGHT = 1e-6
"""DAQP's proximal-point weight, which lets its QP method solve an LP (no Hessian). The answers agree
with Clarabel's to ~2e-6 N over random configurations (a test holds the two against each other).
HiGHS, the other LP solver CasADi ships, is not used: SciPy bundles another HiGHS, and the two in one
process crash."""
_FEASIBILITY_TOLERANCE = 1e-6
"""A returned solution that misses an equality or a force limit by more than this (N, N·m) means the
LP was infeasible."""


@dataclass(frozen=True)
class GravityMoment:
    """``M(θ_o) = a cos θ_o + b sin θ_o``: the moment (N·m, CCW) of the object's weight about the ground
    contact, for a centre of mass fixed in the object.

    Attributes:
        cos_coefficient: ``a``, N·m; ``−m g`` times the centre of mass's offset along the hand face.
        sin_coefficient: ``b``, N·m; ``m g`` times its offset from the ground contact towards the face.
    """

    cos_coefficient: float
    sin_coefficient: float

    def __call__(self, theta_o: float) -> float:
        """The moment at face angle ``θ_o`` (rad), N·m."""
        return self.cos_coefficient * math.cos(theta_o) + self.sin_coefficient * math.sin(theta_o)

    @classmethod
    def of_centre_of_mass(cls, mass: float, com_along: float, com_height: float) -> GravityMoment:
        """The moment of ``mass`` kg centred at ``r_o + com_along e_t(θ_o) − com_height e_n(θ_o)`` (m)."""
        weight = mass * geometry.GRAVITY
        return cls(-weight * com_along, weight * com_height)


WHOLE_HAND = (-math.inf, math.inf)
"""A face that covers the whole hand, wherever it is (:attr:`ObjectStatics.face`)."""


@dataclass(frozen=True)
class ObjectStatics:
    """What the statics need to know of the object, true or estimated (SI units).

    Attributes:
        mu_h: hand friction coefficient.
        ground_rows: ``A`` (2×2), the ground friction rows ``A f_h ≤ b`` on the world hand force,
            rows ``GROUND_SLIDE_POS, GROUND_SLIDE_NEG`` (:data:`ccopt.contact.ground_rows_world`).
        ground_bounds: ``b`` (2,), N (the weight is inside them).
        d: distance from the ground contact to the hand face along ``e_n``, m.
        gravity: the weight's moment about the ground contact.
        ground_known: per ground row, whether it is known (an estimate's row fitted to a friction
            face; a conservative row at the extent of the data is not): unknown rows bind nothing,
            and a slide whose boundary is unknown cannot be judged (its margin is NaN).
        face: ``(u_low, u_high)``, where the hand's face of the object is (known) to be, m along
            ``e_t`` from the ground contact's foot (:func:`ccopt.geometry.face_position`); the hand's
            contact patch is the hand cut to it (:data:`ccopt.contact.patch_torque_rows`). Unbounded
            by default: the whole hand is on the face; empty (``u_low > u_high``): no wrench is known
            to be held, every margin is negative.
    """

    mu_h: float
    ground_rows: np.ndarray
    ground_bounds: np.ndarray
    d: float
    gravity: GravityMoment
    ground_known: tuple[bool, bool] = (True, True)
    face: tuple[float, float] = WHOLE_HAND

    def __post_init__(self) -> None:
        rows = np.array(self.ground_rows, dtype=float)
        bounds = np.array(self.ground_bounds, dtype=float)
        if rows.shape != (2, 2) or bounds.shape != (2,):
            raise ValueError(f"ground rows must be 2×2 with 2 bounds, got {rows.shape} and {bounds.shape}")
        values = (self.mu_h, self.d, self.gravity.cos_coefficient, self.gravity.sin_coefficient)
        finite = all(map(math.isfinite, (*rows.ravel().tolist(), *bounds.tolist(), *values)))
        if not finite:
            raise ValueError("object statics must be finite")
        if self.mu_h < 0.0:
            raise ValueError(f"mu_h must be non-negative, got {self.mu_h!r}")
        face = tuple(float(end) for end in self.face)
        if len(face) != 2 or any(map(math.isnan, face)):
            raise ValueError(f"face must be two numbers (m, ±inf allowed), got {self.face!r}")
        object.__setattr__(self, "face", face)
        rows.flags.writeable = False
        bounds.flags.writeable = False
        object.__setattr__(self, "ground_rows", rows)
        object.__setattr__(self, "ground_bounds", bounds)

    @classmethod
    def of_model(
        cls, mu_h: float, mu_g: float, mass: float, d: float, com_along: float, com_height: float
    ) -> ObjectStatics:
        """The statics of a known object on a horizontal ground (friction, mass, centre of mass)."""
        rows, bounds = contact.model_ground_rows(mu_g, mass)
        return cls(mu_h, rows, bounds, d, GravityMoment.of_centre_of_mass(mass, com_along, com_height))


@dataclass(frozen=True)
class StaticsResult:
    """The best wrench for one motion at one configuration.

    Attributes:
        margin: the largest smallest kept-row margin (N); ``-inf`` where no wrench satisfies the
            equilibrium, the force limits and the motion's sliding limit at all; NaN where the
            motion's boundary is unknown (:attr:`ObjectStatics.ground_known`).
        wrench: the hand wrench ``(f_n, f_t, τ)`` achieving it (N, N, N·m), None where none exists.
    """

    margin: float
    wrench: np.ndarray | None

    def feasible(self, min_margin: float = MIN_MARGIN) -> bool:
        """Whether the motion is possible with at least ``min_margin`` (N) on every kept row."""
        return self.margin >= min_margin


def build_statics_lp() -> ca.Function:
    """``(p, keep, g, lba, uba, lbx, ubx) → (x, rows)``: the LPs of the module docstring, by DAQP.

    ``p = (θ_o, s_h, d, M, μ_h, l_h, vec(A), b, face)``; ``x = (f_n, f_t, τ, t, u)``; the objective is
    ``gᵀx`` (minimised). The rows are the six cone rows ``s_j (b_j − n_jᵀw) − k_j t`` (``s_j = 1/l_h``
    on torque rows, ``k_j = 1`` on kept rows; the torque rows those of the hand cut to the face,
    :data:`ccopt.contact.patch_torque_rows`), the moment balance, and ``u − f_n``, ``u + f_n`` (so
    that ``u ≥ |f_n − f_nom|`` with ``−f_nom``, ``f_nom`` as their lower bounds); ``lba``/``uba`` (9)
    select kept (``[0, ∞)``), removed (``[0, 0]``) and ignored rows, and the moment balance is
    ``[0, 0]``; ``f_n`` is bounded by the force limits and ``t`` by a required margin through ``lbx``.
    """
    p = ca.SX.sym("p", _N_PARAMETERS)
    theta, s_h, d, moment, mu_h, l_h = (p[i] for i in range(6))
    ground_a, ground_b, face = ca.reshape(p[6:10], 2, 2), p[10:12], p[12:14]
    keep = ca.SX.sym("keep", N_CONE_ROWS)
    x = ca.SX.sym("x", _N_UNKNOWNS)
    wrench, margin, spread = x[:3], x[3], x[4]
    rows, bounds = contact.cone_rows(theta, mu_h, l_h, ground_a, ground_b)
    rows[_TORQUE_ROWS[0] : _TORQUE_ROWS[1] + 1, :] = contact.patch_torque_rows(l_h, s_h, face)
    scale = ca.vertcat(1, 1, 1 / l_h, 1 / l_h, 1, 1)
    slack = scale * (bounds - rows @ wrench) - keep * margin
    hand_pose = contact.hand_pose_kinematics(theta, s_h, 0.0, d, 0.0)
    zero = ca.SX.zeros(2)
    balance = contact.equilibrium_residual(hand_pose, wrench, zero, zero, zero, zero)[2] + moment
    constraints = ca.vertcat(slack, balance, spread - wrench[0], spread + wrench[0])
    matrices = ca.Function(
        "statics_lp_matrices",
        [p, keep],
        [ca.jacobian(constraints, x), ca.substitute(constraints, x, ca.SX.zeros(_N_UNKNOWNS))],
    )
    lp = ca.conic(
        "statics_lp_daqp",
        "daqp",
        {"a": ca.Sparsity.dense(_N_ROWS, _N_UNKNOWNS)},
        {"error_on_fail": False, "daqp": {"eps_prox": LP_PROXIMAL_WEIGHT}},
    )
    p_in, keep_in = ca.MX.sym("p", _N_PARAMETERS), ca.MX.sym("keep", N_CONE_ROWS)
    objective = ca.MX.sym("g", _N_UNKNOWNS)
    lba, uba = ca.MX.sym("lba", _N_ROWS), ca.MX.sym("uba", _N_ROWS)
    lbx, ubx = ca.MX.sym("lbx", _N_UNKNOWNS), ca.MX.sym("ubx", _N_UNKNOWNS)
    a, offset = matrices(p_in, keep_in)
    solution = lp(g=objective, a=ca.densify(a), lba=lba - offset, uba=uba - offset, lbx=lbx, ubx=ubx)
    residual = a @ solution["x"] + offset
    return ca.Function(
        "statics_lp",
        [p_in, keep_in, objective, lba, uba, lbx, ubx],
        [solution["x"], residual],
        ["p", "keep", "g", "lba", "uba", "lbx", "ubx"],
        ["x", "rows"],
    )


_INPUT_SIZES = (_N_PARAMETERS, N_CONE_ROWS, _N_UNKNOWNS, _N_ROWS, _N_ROWS, _N_UNKNOWNS, _N_UNKNOWNS)
"""Sizes of the LP's inputs ``(p, keep, g, lba, uba, lbx, ubx)``, in order."""


def build_answer_checks() -> ca.Function:
    """``(x, rows, keep, lba, uba, lbx, ubx) → (margin, ok)``: what the LP's answer is worth.

    DAQP's proximal iterations can stop with a kept row short of the margin ``t`` by a few hundredths
    of a newton (~0.3 % of random configurations): the wrench is sound, only its margin is not, and
    calling it infeasible would rule out a possible motion. ``margin``: ``t``, or the least slack
    ``s_j + t`` of the kept rows where that is below ``t`` (the answer is then taken at that margin,
    its rows' slack at it). ``ok``: that answer is finite and meets every bound to within
    :data:`_FEASIBILITY_TOLERANCE`; else the LP was infeasible.
    """
    x, rows, keep = ca.SX.sym("x", _N_UNKNOWNS), ca.SX.sym("rows", _N_ROWS), ca.SX.sym("keep", N_CONE_ROWS)
    lba, uba = ca.SX.sym("lba", _N_ROWS), ca.SX.sym("uba", _N_ROWS)
    lbx, ubx = ca.SX.sym("lbx", _N_UNKNOWNS), ca.SX.sym("ubx", _N_UNKNOWNS)
    margin = x[3]
    slack = rows[:N_CONE_ROWS] + keep * margin
    least = ca.SX(ca.inf)
    for row in range(N_CONE_ROWS):
        least = ca.fmin(least, ca.if_else(keep[row] > 0.0, slack[row], ca.inf))
    honest = ca.logic_not(least >= margin)
    answer = ca.vertcat(x[:3], ca.if_else(honest, least, margin), x[4:])
    answer_rows = ca.vertcat(ca.if_else(honest, slack - keep * least, rows[:N_CONE_ROWS]), rows[N_CONE_ROWS:])
    tolerance = _FEASIBILITY_TOLERANCE
    tests = (
        *ca.vertsplit(ca.fabs(answer) < ca.inf),
        *ca.vertsplit(lba - tolerance <= answer_rows),
        *ca.vertsplit(answer_rows <= uba + tolerance),
        *ca.vertsplit(lbx - tolerance <= answer),
        *ca.vertsplit(answer <= ubx + tolerance),
    )
    ok = functools.reduce(ca.logic_and, tests)
    inputs, names = [x, rows, keep, lba, uba, lbx, ubx], ["x", "rows", "keep", "lba", "uba", "lbx", "ubx"]
    return ca.Function("statics_lp_checks", inputs, [ca.vertcat(answer[3], ok)], names, ["checks"])


@functools.cache
def _solver() -> BufferedFunction:
    """The LP of :func:`build_statics_lp` on its inputs concatenated into one vector, giving ``x``,
    the rows and their :func:`build_answer_checks` as one vector (a solve fills one buffer and reads
    one), built on first use (each thread evaluates it through its own buffers)."""
    lp, checks = build_statics_lp(), build_answer_checks()
    packed = ca.MX.sym("packed", sum(_INPUT_SIZES))
    inputs = ca.vertsplit(packed, list(itertools.accumulate(_INPUT_SIZES, initial=0)))
    _, keep, _, lba, uba, lbx, ubx = inputs
    x, rows = lp(*inputs)
    answer = ca.vertcat(x, rows, checks(x, rows, keep, lba, uba, lbx, ubx))
    return BufferedFunction(ca.Function("statics_lp_packed", [packed], [answer]))


def _row_bounds(motion: Motion) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """``(keep, lba, uba)`` of the LP's rows for ``motion`` (the two ``|f_n − f_nom|`` rows' lower
    bounds are set per call)."""
    kept = modes.kept_rows(motion)
    removed = np.zeros(N_CONE_ROWS, dtype=bool)
    removed[list(modes.REMOVED_ROWS[motion])] = True
    lower = np.where(kept | removed, 0.0, -np.inf)
    upper = np.where(removed, 0.0, np.inf)
    return kept.astype(float), np.append(lower, [0.0, 0.0, 0.0]), np.append(upper, [0.0, np.inf, np.inf])


@functools.cache
def _rows_of(motion: Motion, known: tuple[bool, bool]) -> tuple[list[float], list[float], list[float]] | None:
    """``(keep, lba, uba)`` of ``motion`` with the ground rows not ``known`` ignored (as lists, built
    once per case); None where a row the motion removes is unknown (its margin cannot be judged)."""
    unknown = [int(row) for row, is_known in zip(contact.GROUND_ROWS, known, strict=True) if not is_known]
    if any(row in modes.REMOVED_ROWS[motion] for row in unknown):
        return None
    keep, lba, uba = (array.tolist() for array in _row_bounds(motion))
    for row in unknown:
        keep[row], lba[row], uba[row] = 0.0, -math.inf, math.inf
    return keep, lba, uba


def parameters(statics: ObjectStatics, theta_o: float, s_h: float, l_h: float) -> list[float]:
    """The LP's parameter vector ``p`` (see :func:`build_statics_lp`)."""
    return [
        theta_o,
        s_h,
        statics.d,
        statics.gravity(theta_o),
        statics.mu_h,
        l_h,
        *statics.ground_rows.ravel(order="F").tolist(),
        *statics.ground_bounds.tolist(),
        *(min(max(end, -_FACE_FAR), _FACE_FAR) for end in statics.face),
    ]


_MAXIMISE_MARGIN = (0.0, 0.0, 0.0, -1.0, 0.0)
_NEAREST_FORCE = (0.0, 0.0, 0.0, -0.01, 1.0)
"""Minimise ``|f_n − f_nom|``, ties broken towards a larger margin (a newton of force off the nominal costs
100 times a newton of margin, so the force stays as near as it can and the rest of the wrench is
centred in the cone)."""
_UPPER_X = (_BIG,) * _N_UNKNOWNS


class _Problem:
    """The LPs of one motion at one configuration: the inputs of :func:`build_statics_lp` they share
    (``head``: ``p`` and ``keep``; ``lba`` but the two ``|f_n − f_nom|`` rows'; ``uba``; the force
    limits), and their solve."""

    def __init__(
        self, head: list[float], lba: list[float], uba: list[float], force_limits: tuple[float, float]
    ) -> None:
        self.head, self.lba, self.uba = head, lba, uba
        self.lower_force, self.upper_force = force_limits

    @classmethod
    def of(
        cls,
        statics: ObjectStatics,
        configuration: tuple[float, float],
        motion: Motion,
        l_h: float,
        force_limits: tuple[float, float],
    ) -> _Problem | None:
        """The LPs of ``motion`` at ``configuration`` ``(θ_o, s_h)`` (:func:`best_wrench`'s arguments);
        None where a row the motion removes is unknown."""
        rows_of = _rows_of(motion, statics.ground_known)
        if rows_of is None:
            return None
        keep, lba, uba = rows_of
        lba = lba[:-2]  # the |f_n − f_nom| rows' lower bounds are set per solve
        theta_o, s_h = configuration
        return cls([*parameters(statics, theta_o, s_h, l_h), *keep], lba, uba, force_limits)

    def solve(self, objective: tuple[float, ...], least_margin: float, nominal_force: float) -> StaticsResult:
        """The LP minimising ``objective`` with a margin of at least ``least_margin`` and the normal
        force's distance from ``nominal_force``."""
        lba = [*self.lba, -nominal_force, nominal_force]
        lbx = (self.lower_force, -_BIG, -_BIG, least_margin, -_BIG)
        ubx = (self.upper_force, *_UPPER_X[1:])
        binding = _solver().buffers()  # filled in place: the LP is called twice a control tick
        binding.flat_inputs[0][:] = [*self.head, *objective, *lba, *self.uba, *lbx, *ubx]
        binding.evaluate()
        solution = binding.flat_outputs[0].tolist()
        x, (margin, ok) = solution[:_N_UNKNOWNS], solution[-2:]
        if not ok:
            return StaticsResult(-math.inf, None)
        return StaticsResult(margin, np.array(x[:3]))


def best_wrench(
    statics: ObjectStatics,
    theta_o: float,
    s_h: float,
    motion: Motion | str,
    l_h: float,
    force_limits: tuple[float, float],
) -> StaticsResult:
    """The largest margin (N) of ``motion`` at ``(θ_o, s_h)`` (rad, m) and the hand wrench achieving it.

    ``l_h`` is the torque rows' lever (m; the hand's half-length, or its estimate's effective one)
    and ``force_limits`` the normal force's ``(f_min, f_max)`` (N).
    """
    problem = _Problem.of(statics, (theta_o, s_h), Motion(motion), l_h, force_limits)
    if problem is None:
        return StaticsResult(math.nan, None)
    return problem.solve(_MAXIMISE_MARGIN, -_BIG, 0.0)


def regulation_wrench(
    statics: ObjectStatics,
    theta_o: float,
    s_h: float,
    motion: Motion | str,
    l_h: float,
    force_limits: tuple[float, float],
    nominal_force: float,
    margin_goal: float,
) -> StaticsResult:
    """The wrench a controller should hold for ``motion`` at ``(θ_o, s_h)``: the normal force nearest
    ``nominal_force`` (N) among the wrenches whose margin is at least ``min(best, margin_goal)`` (N).

    The largest margin alone presses as hard as the limits allow (every row grows with ``f_n``);
    this keeps the margin the motion needs and no more force than that. The result's ``margin`` is
    the margin required (``-inf`` where the motion is impossible at any force).
    """
    problem = _Problem.of(statics, (theta_o, s_h), Motion(motion), l_h, force_limits)
    if problem is None:
        return StaticsResult(math.nan, None)
    best = problem.solve(_MAXIMISE_MARGIN, -_BIG, 0.0)
    if best.wrench is None:
        return best
    least = min(best.margin, margin_goal) - _FEASIBILITY_TOLERANCE
    found = problem.solve(_NEAREST_FORCE, least, nominal_force)
    return StaticsResult(least, found.wrench) if found.wrench is not None else best


# --- the experimenter's oracle: a known object as a run starts it ---------------------------------


@dataclass(frozen=True)
class TrueConfiguration:
    """A known object as a run starts it: its statics, its start ``(θ_o, s_h)`` and the range of
    ``s_h`` over which the whole hand stays on the face (rad, m)."""

    statics: ObjectStatics
    theta_o: float
    s_h: float
    s_h_range: tuple[float, float]


def true_statics(obj: PlanarObject, start: StartConfig, hand: Hand) -> TrueConfiguration:
    """The true statics of ``obj`` started at ``start`` with ``hand`` (the experimenter's oracle: the
    estimator and the controller never see this)."""
    object_pose, hand_pose, _ = start_poses(obj, start, hand)
    r_o = np.array([start.x_o, 0.0])
    _, d = geometry.contact_coordinates(hand_pose, r_o)
    com = object_pose[:2] - r_o
    model = ObjectStatics.of_model(
        obj.mu_hand,
        obj.mu_ground,
        obj.mass,
        d,
        com_along=float(com @ geometry.hand_tangent(start.theta_o)),
        com_height=float(-(com @ geometry.hand_normal(start.theta_o))),
    )
    low, high = face_s_h_range(obj, start)  # the hand's centre on the face's ends
    face = (geometry.face_position(0.0, high), geometry.face_position(0.0, low))
    statics = dataclasses.replace(model, face=face)
    s_h_range = (low + hand.half_length, high - hand.half_length)
    return TrueConfiguration(statics, start.theta_o, start.s_h, s_h_range)


def start_target(obj: PlanarObject, start: StartConfig, hand: Hand) -> np.ndarray:
    """The hand's impedance target that holds ``start`` in equilibrium, world ``(x, y, θ)``: the hand
    pose displaced by ``K⁻¹ w`` for the hold wrench ``w`` of the largest margin at
    ``start.normal_force`` (the experimenter's tool, placing the plant: a pure normal push off the
    ground contact is a moment ``f_n s_h`` the object may not hold, and a robot arm settling from its
    inverse kinematics lets it fall). An object lying on a face, whose ground contact takes any
    moment, and one no wrench holds get the pure normal push."""
    object_pose, hand_pose, push = start_poses(obj, start, hand)
    heights = geometry.transform_points(obj.vertices, object_pose)[:, 1]
    if np.count_nonzero(heights <= heights.min() + geometry.LOWEST_TIE) > 1:
        return push
    truth = true_statics(obj, start, hand)
    force = (start.normal_force, start.normal_force)
    result = best_wrench(truth.statics, start.theta_o, start.s_h, Motion.HOLD, hand.half_length, force)
    if result.wrench is None:
        return push
    f_n, f_t, torque = result.wrench
    world = geometry.hand_force_to_world(start.theta_o, f_n, f_t)
    return hand_pose + np.array([*world, torque]) / np.asarray(hand.stiffness)


@dataclass(frozen=True)
class StepFeasibility:
    """Whether one schedule step is physically possible at its nominal configuration.

    The nominal configuration is where the step starts and ends if every earlier step did exactly what
    it commanded: ``θ_o`` moved by the pivots, ``s_h`` by the hand slides (``d`` and the centre of mass
    are fixed in the face frame). Angles in rad, lengths in m, margins in N (see :func:`best_wrench`).

    Attributes:
        index: position of the step in the schedule.
        kind: the step's kind (``pivot``, ``slide_hand``, ``slide_ground``, ``hold``).
        delta: its increment (rad or m).
        theta_o: nominal ``θ_o`` at the start and at the end of the step.
        s_h: nominal ``s_h`` at the start and at the end of the step.
        on_face: the whole hand stays on the face over the step.
        margin: the smaller LP margin of the step's two ends.
        feasible: ``on_face`` and ``margin ≥ min_margin``.
        explore: the step is an exploration probe (:func:`ccopt.schedule.exploration`): it looks for
            a limit and ends by itself, so its being impossible is no fault of the schedule.
    """

    index: int
    kind: str
    delta: float
    theta_o: tuple[float, float]
    s_h: tuple[float, float]
    on_face: bool
    margin: float
    feasible: bool
    explore: bool = False

    def describe(self) -> str:
        """One line in degrees and millimetres, e.g. for a warning."""
        unit, scale = ("deg", math.degrees(1.0)) if self.kind == "pivot" else ("mm", 1e3)
        why = "the hand leaves the face" if not self.on_face else f"LP margin {self.margin:.2f} N"
        return (
            f"step {self.index} ({self.kind} {self.delta * scale:+.1f} {unit}) at θ_o "
            f"{math.degrees(self.theta_o[0]):.1f}→{math.degrees(self.theta_o[1]):.1f} deg, s_h "
            f"{1e3 * self.s_h[0]:.1f}→{1e3 * self.s_h[1]:.1f} mm: {why}"
        )


def schedule_feasibility(
    obj: PlanarObject, steps: Iterable[Step], start: StartConfig, hand: Hand, min_margin: float = MIN_MARGIN
) -> tuple[StepFeasibility, ...]:
    """Check every step of a schedule (its ``steps``) on the known ``obj``, started at ``start`` with
    ``hand``.

    This is the experimenter's check, not the controller's: it uses the true object (polygon, mass,
    friction), which ccopt's estimator and controller never see. A step that is infeasible here
    cannot be done by any controller with a flush hand and a point ground contact; a step that is
    feasible may still fail (the reduced model ignores dynamics, and the object may roll onto
    another vertex at large angles). Goal steps are not checked, nor anything after the first:
    where a goal leaves the object is the planner's choice (:func:`ccopt.planning.planner.oracle_plan`
    judges goals).
    """
    truth = true_statics(obj, start, hand)
    low, high = truth.s_h_range
    theta, s_h = truth.theta_o, truth.s_h
    checks = []
    for index, step in enumerate(steps):
        if not isinstance(step, Step):
            break
        end_theta = theta + (step.delta if step.kind == "pivot" else 0.0)
        end_s_h = s_h + (step.delta if step.kind == "slide_hand" else 0.0)
        on_face = all(low - 1e-9 <= s <= high + 1e-9 for s in (s_h, end_s_h))
        margin = min(
            best_wrench(truth.statics, t, s, step.motion, hand.half_length, hand.force_limits).margin
            for t, s in ((theta, s_h), (end_theta, end_s_h))
        )
        feasible = on_face and margin >= min_margin
        ends = ((theta, end_theta), (s_h, end_s_h))
        checks.append(
            StepFeasibility(index, step.kind, step.delta, *ends, on_face, margin, feasible, step.explore)
        )
        theta, s_h = end_theta, end_s_h
    return tuple(checks)


def impossible_steps(checks: tuple[StepFeasibility, ...]) -> list[int]:
    """Indices of the steps that :func:`schedule_feasibility` finds impossible (exploration probes
    aside: they look for the limits)."""
    return [check.index for check in checks if not (check.feasible or check.explore)]

