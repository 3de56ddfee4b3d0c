"""The object-agnostic controller (paper §V–VI): estimate + commanded motion → ``Δx_tar``.

Per control tick the controller builds one :class:`~ccopt.control.qp.QPInstance` in the hand frame
``(n, t, θ)`` and solves it with the code-generated QP:

Cost (paper eq. 21)
    ``α₀‖Δx‖² + Σᵢ αᵢ (vᵢᵀΔx − βᵢ Δεᵢ)²`` over the admissible-motion vectors ``v_θ, v_h, v_g`` of
    :func:`ccopt.contact.admissible_motions` at the estimated kinematics. The commanded coordinate's
    error drives its term; the other admissible coordinates are *held* at their values when the step
    began (their ``Δε`` is the drift since then), which the paper's cost does implicitly by keeping
    them in the sum. Before the kinematics are known the paper's naive ``v_θ`` is used: ``s_h = 0``
    and ``d = d_guess`` (paper §VI). A fourth term regulates the normal force towards a target
    (``v = e_n``, ``δ = (f_target − f_n) / k_n``), which keeps the hand pressing.
Rows (paper eq. 19)
    The estimated cone rows ``nⱼᵀ(w + γⱼ K Δx) ≤ bⱼ − marginⱼ`` minus those the commanded motion
    removes (:func:`ccopt.modes.kept_rows`), plus ``f_min ≤ f_n ≤ f_max``. Margins keep the kept
    inequalities strict, as the paper requires for sticking and flush contact. Rows the estimator
    has not estimated yet are not enforced: a cone built only from the wrenches seen so far would
    keep the wrench where it has been and never let exploration widen it (the paper's exploration
    learns each constraint by pushing towards it). The mode classifier stays conservative about
    them; the controller relies on the exploration schedule to meet them first.

The step is clipped to a maximum per tick (a target speed limit, :attr:`ControllerParams.max_speed`
times the control period) and reported with the QP's
diagnostics; an infeasible tick still returns the least-violating step and says so.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ccopt import contact, modes, validation
from ccopt.contact import N_CONE_ROWS, Row
from ccopt.control.qp import QPInstance, QPSolution, QPSolver, make_solver
from ccopt.hand import Hand
from ccopt.modes import Motion

PAPER_PERIOD = 0.033
"""Control period (s) of the loop at the paper's 30 Hz on a 1 ms plant (33 plant steps), at which
the default gains below were tuned as fractions per tick; they are stated per second so that the
same physical behaviour holds at any rate."""


def _per_second(fraction_per_tick: float) -> float:
    """The rate (1/s) that corrects ``fraction_per_tick`` of an error per :data:`PAPER_PERIOD`."""
    return -math.log(1.0 - fraction_per_tick) / PAPER_PERIOD


@dataclass(frozen=True)
class ControllerParams:
    """Gains and limits of the controller, in SI units per second (independent of the control rate).

    Attributes:
        regularization: ``α₀``.
        weights: ``α`` for the ``θ_o``, ``s_h``, ``s_g`` terms (commanded coordinate).
        hold_weights: ``α`` for the held (not commanded) coordinates.
        convergence_rate: ``β`` as a rate (1/s): each tick asks for ``1 − exp(−rate · period)`` of the
            remaining error (30 % per tick at the paper's 30 Hz).
        force_weight: ``α`` of the normal-force term.
        force_rate: rate (1/s) at which the normal-force error is corrected (20 % per tick at 30 Hz:
            the hand and contact form a ~7 Hz oscillator, a dead-beat correction would overshoot).
        normal_force: target normal force, N (inside the hand's force limits).
        row_gains: ``γ`` for the cone rows (the force limits use 1).
        friction_margin: margin on the hand friction rows, as a fraction of the cone's half-width
            ``μ̂_h f_n`` (so a conservative ``μ̂_h`` is not eaten by its own margin).
        torque_margin: margin on the torque rows, as a fraction of ``l_h f_n``.
        ground_margin: margin on the ground rows, N.
        min_margin: lower bound of the hand-row margins, N (× ``l_h`` for torques).
        d_guess: ``d`` of the naive ``v_θ`` before the kinematics are known, m.
        max_speed: largest impedance-target speed ``|Δn|, |Δt|`` (m/s) and ``|Δθ|`` (rad/s).
    """

    regularization: float = 0.05
    weights: tuple[float, float, float] = (1.0, 1.0, 1.0)
    hold_weights: tuple[float, float, float] = (0.3, 0.3, 0.3)
    convergence_rate: float = _per_second(0.3)
    force_weight: float = 0.5
    force_rate: float = _per_second(0.2)
    normal_force: float = 10.0
    row_gains: float = 1.0
    friction_margin: float = 0.15
    torque_margin: float = 0.2
    ground_margin: float = 0.5
    min_margin: float = 0.2
    d_guess: float = 0.08
    max_speed: tuple[float, float, float] = (
        0.002 / PAPER_PERIOD,
        0.002 / PAPER_PERIOD,
        math.radians(1.0) / PAPER_PERIOD,
    )

    def __post_init__(self) -> None:
        for name in ("regularization", "convergence_rate", "force_rate", "d_guess", "normal_force"):
            value = getattr(self, name)
            if not (math.isfinite(value) and value > 0.0):
                raise ValueError(f"{name} must be positive, got {value!r}")
        if len(self.max_speed) != 3 or not all(math.isfinite(v) and v > 0.0 for v in self.max_speed):
            raise ValueError(f"max_speed must be three positive speeds, got {self.max_speed!r}")

    def check_hand(self, hand: Hand) -> None:
        """``ValueError`` unless the target normal force lies inside the hand's force limits."""
        f_min, f_max = hand.force_limits
        if not f_min < self.normal_force < f_max:
            raise ValueError(
                f"normal_force {self.normal_force} N must lie inside the hand's force limits "
                f"{hand.force_limits}"
            )


@dataclass(frozen=True)
class ControlInput:
    """What the controller needs from an estimate, in the hand frame at the current hand angle.

    Attributes:
        wrench: measured hand wrench ``(f_n, f_t, τ)``, N, N, N·m.
        cone_rows: estimated generalized friction cone ``N`` (6×3), rows in :class:`Row` order.
        cone_bounds: its ``b`` (6,).
        row_valid: which cone rows are estimated (6,) bool; only those are enforced.
        mu_h: estimated hand friction coefficient ``μ̂_h`` (scales the friction margin).
        l_h: torque-row lever used by the estimate (m): scales the torque margin.
        hand_angle: measured ``θ_h`` (rad): the hand frame in which ``Δx_tar`` is expressed.
        s_h: estimated ``s_h`` (m), shapes ``v_θ`` once the kinematics are valid.
        d: estimated distance ``d`` from the ground contact to the hand face (m), likewise.
        kinematics_valid: whether ``s_h`` and ``d`` are estimated yet (else the naive ``v_θ``).
        coordinates: the ``(θ_o, s_h, s_g)`` that progress is measured on (rad, m, m), the same
            source as the command's targets.
    """

    wrench: np.ndarray
    cone_rows: np.ndarray
    cone_bounds: np.ndarray
    row_valid: np.ndarray
    mu_h: float
    l_h: float
    hand_angle: float
    s_h: float
    d: float
    kinematics_valid: bool
    coordinates: np.ndarray


@dataclass(frozen=True)
class Command:
    """A commanded motion with its target coordinates ``(θ_o, s_h, s_g)`` (rad, m, m).

    ``targets`` holds the commanded coordinate's goal and the held coordinates' values at the start
    of the step.
    """

    motion: Motion
    targets: np.ndarray


@dataclass(frozen=True)
class ControlOutput:
    """One tick's result: the hand-frame target change and the QP's diagnostics."""

    step: np.ndarray
    solution: QPSolution
    instance: QPInstance


class Controller:
    """Builds and solves the impedance-target QP each tick (one compiled solver, reused).

    Args:
        hand: the robot's hand (its impedance ``K`` and normal-force limits).
        period: control period, s (the per-second gains become per-tick fractions).
        params: gains and limits.
        solver: the QP back end (the code-generated one by default).
    """

    def __init__(
        self,
        hand: Hand | None = None,
        period: float = PAPER_PERIOD,
        params: ControllerParams | None = None,
        solver: QPSolver | None = None,
    ) -> None:
        self.hand = hand if hand is not None else Hand()
        self.params = params if params is not None else ControllerParams()
        validation.check_types((("hand", self.hand, Hand), ("params", self.params, ControllerParams)))
        self.period = validation.positive("control period", period)
        self.params.check_hand(self.hand)
        self.solver = solver if solver is not None else make_solver("codegen")
        self._convergence = 1.0 - math.exp(-self.params.convergence_rate * self.period)
        self._force_gain = 1.0 - math.exp(-self.params.force_rate * self.period)
        self._max_step = np.asarray(self.params.max_speed) * self.period
        self._row_gains = np.full(N_CONE_ROWS + 2, self.params.row_gains)
        self._row_gains[N_CONE_ROWS:] = 1.0

    def update(self, state: ControlInput, command: Command) -> ControlOutput:
        """The hand-frame change of the impedance target ``(Δn, Δt, Δθ)`` (m, m, rad) for this tick."""
        instance = self.build_instance(state, command)
        solution = self.solver.solve(instance)
        step = np.clip(solution.step, -self._max_step, self._max_step)
        return ControlOutput(step=step, solution=solution, instance=instance)

    def build_instance(self, state: ControlInput, command: Command) -> QPInstance:
        """The QP of this tick (exposed for studies and tests)."""
        p = self.params
        if state.kinematics_valid:
            vectors = contact.admissible_motions(state.hand_angle, state.s_h, state.d)
        else:
            vectors = contact.admissible_motions(state.hand_angle, 0.0, p.d_guess)
        errors = np.asarray(command.targets) - np.asarray(state.coordinates)
        regulated = modes.driven_coordinate(command.motion)
        directions, weights, targets = [], [], []
        for k in modes.admitted_coordinates(command.motion):
            directions.append(vectors[:, k])
            weights.append(p.weights[k] if k == regulated else p.hold_weights[k])
            targets.append(self._convergence * errors[k])
        f_n = state.wrench[0]
        stiffness = self.hand.stiffness_in_hand_frame(state.hand_angle)
        k_n = stiffness[0, 0]
        directions.append(np.array([1.0, 0.0, 0.0]))
        weights.append(p.force_weight)
        targets.append(self._force_gain * (p.normal_force - f_n) / k_n)  # a displacement along e_n, m
        margins = self._margins(f_n, state)
        f_min, f_max = self.hand.force_limits
        rows = np.vstack([state.cone_rows, [[1.0, 0.0, 0.0], [-1.0, 0.0, 0.0]]])
        bounds = np.concatenate([state.cone_bounds - margins, [f_max, -f_min]])
        active = np.concatenate([modes.kept_rows(command.motion) & state.row_valid, [True, True]])
        return QPInstance(
            stiffness=stiffness,
            wrench=np.asarray(state.wrench, dtype=float),
            rows=rows,
            bounds=bounds,
            gains=self._row_gains,
            active=active,
            regularization=p.regularization,
            directions=np.asarray(directions),
            weights=np.asarray(weights),
            targets=np.asarray(targets),
        )

    def _margins(self, f_n: float, state: ControlInput) -> np.ndarray:
        """Per-row margins ``b − margin``: strict inequalities for the rows the command keeps."""
        p = self.params
        force = max(f_n, 0.0)
        mu_h = state.mu_h
        margins = np.full(N_CONE_ROWS, p.ground_margin)
        margins[[Row.HAND_SLIDE_POS, Row.HAND_SLIDE_NEG]] = max(
            p.friction_margin * mu_h * force, p.min_margin
        )
        margins[[Row.HAND_PIVOT_POS, Row.HAND_PIVOT_NEG]] = (
            max(p.torque_margin * force, p.min_margin) * state.l_h
        )
        return margins
