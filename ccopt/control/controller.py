"""The object-agnostic controller (paper §V–VI): estimate + commanded motion → ``Δx_tar``.

Per control tick the controller builds one :class:`~ccopt.control.qp.QPInstance` in the hand frame
``(n, t, θ)`` and solves it with the code-generated QP:

Cost (paper eq. 26)
    ``α₀‖Δx‖² + Σᵢ αᵢ (vᵢᵀΔx − βᵢ Δεᵢ)²`` over the admissible-motion vectors ``v_θ, v_h, v_g`` of
    :func:`ccopt.contact.admissible_motions` at the estimated kinematics. The commanded coordinate's
    error drives its term; the other admissible coordinates are *held* at their values when the step
    began (their ``Δε`` is the drift since then), which the paper's cost does implicitly by keeping
    them in the sum. Before the kinematics are known the paper's naive ``v_θ`` is used: ``s_h = 0``
    and ``d = d_guess`` (paper §VI). A fourth term regulates the normal force towards a target
    (``v = e_n``, ``δ = (f_target − f_n) / k_n``), which keeps the hand pressing.
Rows (paper eq. 24)
    The estimated cone rows ``nⱼᵀ(w + γⱼ K Δx) ≤ bⱼ − marginⱼ`` minus those the commanded motion
    removes (:func:`ccopt.modes.kept_rows`), plus ``f_min ≤ f_n ≤ f_max``. Margins keep the kept
    inequalities strict, as the paper requires for sticking and flush contact. Rows the estimator
    has not estimated yet are not enforced: a cone built only from the wrenches seen so far would
    keep the wrench where it has been and never let exploration widen it (the paper's exploration
    learns each constraint by pushing towards it). The mode classifier stays conservative about
    them; the controller relies on the exploration schedule to meet them first.

The step is clipped to a maximum per tick (a target speed limit) and reported with the QP's
diagnostics; an infeasible tick still returns the least-violating step and says so.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from ccopt import contact, modes
from ccopt.contact import N_CONE_ROWS, Row
from ccopt.control.qp import QPInstance, QPSolution, QPSolver, make_solver
from ccopt.modes import Motion


@dataclass(frozen=True)
class ControllerParams:
    """Gains and limits of the controller. Units: N, m, rad, per control tick.

    Attributes:
        stiffness: hand-frame impedance ``K`` (3×3): N/m, N/m, N·m/rad.
        regularization: ``α₀``.
        weights: ``α`` for the ``θ_o``, ``s_h``, ``s_g`` terms (commanded coordinate).
        hold_weights: ``α`` for the held (not commanded) coordinates.
        convergence: ``β``: fraction of the remaining error asked for per tick.
        force_weight: ``α`` of the normal-force term.
        force_gain: fraction of the normal-force error corrected per tick (the hand and contact
            form a ~7 Hz oscillator: a dead-beat correction at 30 Hz would overshoot).
        normal_force: target normal force, N.
        force_limits: ``(f_min, f_max)`` on the predicted normal force, N.
        row_gains: ``γ`` for the cone rows (the force limits use 1).
        friction_margin: margin on the hand friction rows, as a fraction of the cone's half-width
            ``μ̂_h f_n`` (so a conservative ``μ̂_h`` is not eaten by its own margin).
        torque_margin: margin on the torque rows, as a fraction of ``l_h f_n``.
        ground_margin: margin on the ground rows, N.
        min_margin: lower bound of the hand-row margins, N (× ``l_h`` for torques).
        d_guess: ``d`` of the naive ``v_θ`` before the kinematics are known, m.
        max_step: largest ``|Δn|, |Δt|`` (m) and ``|Δθ|`` (rad) per tick.
    """

    stiffness: np.ndarray = field(default_factory=lambda: np.diag([2000.0, 2000.0, 60.0]))
    regularization: float = 0.05
    weights: tuple[float, float, float] = (1.0, 1.0, 1.0)
    hold_weights: tuple[float, float, float] = (0.3, 0.3, 0.3)
    convergence: float = 0.3
    force_weight: float = 0.5
    force_gain: float = 0.2
    normal_force: float = 10.0
    force_limits: tuple[float, float] = (3.0, 25.0)
    row_gains: float = 1.0
    friction_margin: float = 0.15
    torque_margin: float = 0.2
    ground_margin: float = 0.5
    min_margin: float = 0.2
    d_guess: float = 0.08
    max_step: tuple[float, float, float] = (0.002, 0.002, np.deg2rad(1.0))

    def __post_init__(self) -> None:
        stiffness = np.asarray(self.stiffness, dtype=float)
        if stiffness.shape != (3, 3) or not np.all(np.linalg.eigvalsh(0.5 * (stiffness + stiffness.T)) > 0):
            raise ValueError(f"stiffness must be a positive definite 3×3 matrix, got {self.stiffness!r}")
        object.__setattr__(self, "stiffness", stiffness)
        for name in ("regularization", "convergence", "d_guess", "normal_force"):
            if not getattr(self, name) > 0.0:
                raise ValueError(f"{name} must be positive, got {getattr(self, name)!r}")
        if not 0.0 < self.convergence <= 1.0:
            raise ValueError(f"convergence must be in (0, 1], got {self.convergence!r}")
        f_min, f_max = self.force_limits
        if not 0.0 <= f_min < self.normal_force < f_max:
            raise ValueError(
                f"need 0 ≤ f_min < normal_force < f_max, got {self.force_limits}, {self.normal_force}"
            )


@dataclass(frozen=True)
class ControlInput:
    """What the controller needs from an estimate, in the hand frame at the current hand angle.

    Attributes:
        wrench: measured hand wrench ``(f_n, f_t, τ)``, N, N, N·m.
        cone_rows: estimated generalized friction cone ``N`` (6×3), rows in :class:`Row` order.
        cone_bounds: its ``b`` (6,).
        row_valid: which cone rows are estimated (6,) bool; only those are enforced.
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


_REGULATED = {  # which coordinate (θ_o, s_h, s_g) each motion drives
    Motion.HOLD: None,
    Motion.PIVOT: 0,
    Motion.SLIDE_HAND_POS: 1,
    Motion.SLIDE_HAND_NEG: 1,
    Motion.SLIDE_GROUND_POS: 2,
    Motion.SLIDE_GROUND_NEG: 2,
}
_ADMISSIBLE = {  # coordinates that can change under each motion (others are fixed by sticking)
    Motion.HOLD: (0,),
    Motion.PIVOT: (0,),
    Motion.SLIDE_HAND_POS: (0, 1),
    Motion.SLIDE_HAND_NEG: (0, 1),
    Motion.SLIDE_GROUND_POS: (0, 2),
    Motion.SLIDE_GROUND_NEG: (0, 2),
}


class Controller:
    """Builds and solves the impedance-target QP each tick (one compiled solver, reused)."""

    def __init__(self, params: ControllerParams | None = None, solver: QPSolver | None = None) -> None:
        self.params = params if params is not None else ControllerParams()
        self.solver = solver if solver is not None else make_solver("codegen")
        self._row_gains = np.full(N_CONE_ROWS + 2, self.params.row_gains)
        self._row_gains[N_CONE_ROWS:] = 1.0

    def update(self, state: ControlInput, command: Command) -> ControlOutput:
        """The hand-frame change of the impedance target ``(Δn, Δt, Δθ)`` (m, m, rad) for this tick."""
        instance = self.build_instance(state, command)
        solution = self.solver.solve(instance)
        step = np.clip(solution.step, -np.asarray(self.params.max_step), self.params.max_step)
        return ControlOutput(step=step, solution=solution, instance=instance)

    def build_instance(self, state: ControlInput, command: Command) -> QPInstance:
        """The QP of this tick (exposed for studies and tests)."""
        p = self.params
        if state.kinematics_valid:
            vectors = contact.admissible_motions(state.hand_angle, state.s_h, state.d)
        else:
            vectors = contact.admissible_motions(state.hand_angle, 0.0, p.d_guess)
        errors = np.asarray(command.targets) - np.asarray(state.coordinates)
        regulated = _REGULATED[command.motion]
        directions, weights, targets = [], [], []
        for k in _ADMISSIBLE[command.motion]:
            directions.append(vectors[:, k])
            weights.append(p.weights[k] if k == regulated else p.hold_weights[k])
            targets.append(p.convergence * errors[k])
        f_n = state.wrench[0]
        k_n = p.stiffness[0, 0]
        directions.append(np.array([1.0, 0.0, 0.0]))
        weights.append(p.force_weight)
        targets.append(p.force_gain * (p.normal_force - f_n) / k_n)  # a displacement along e_n, m
        margins = self._margins(f_n, state)
        f_min, f_max = p.force_limits
        rows = np.vstack([state.cone_rows, [[1.0, 0.0, 0.0], [-1.0, 0.0, 0.0]]])
        bounds = np.concatenate([state.cone_bounds - margins, [f_max, -f_min]])
        active = np.concatenate([modes.kept_rows(command.motion) & state.row_valid, [True, True]])
        return QPInstance(
            stiffness=p.stiffness,
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
        mu_h = -state.cone_rows[Row.HAND_SLIDE_POS, 0]  # the row is (−μ̂_h, −1, 0)
        margins = np.full(N_CONE_ROWS, p.ground_margin)
        margins[[Row.HAND_SLIDE_POS, Row.HAND_SLIDE_NEG]] = max(
            p.friction_margin * mu_h * force, p.min_margin
        )
        margins[[Row.HAND_PIVOT_POS, Row.HAND_PIVOT_NEG]] = (
            max(p.torque_margin * force, p.min_margin) * state.l_h
        )
        return margins
