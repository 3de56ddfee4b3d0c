"""The object-agnostic controller (paper §V–VI): estimate + commanded motion → ``Δx_tar``.

Per control tick the controller builds one :class:`~ccopt.control.qp.QPInstance` in the hand frame
``(n, t, θ)`` and solves it with the code-generated QP (paper eqs. 18–21), with one change of model
that makes the QP respect the object's statics:

What a target change does (the quasi-static prediction)
    Under the commanded configuration the hand and the object move freely along the admissible
    directions ``V`` (columns of :func:`ccopt.contact.admissible_motions`: ``v_θ`` always, and the
    commanded slide's ``v_h`` or ``v_g`` once that contact slides) until they are in equilibrium
    again. Equilibrium along ``v_θ`` is the moment balance about the ground contact
    (``v_θ·w = −M(θ_o)``, unchanged by a small step); along a sliding direction the sliding contact
    stays on its friction boundary (the removed row ``n_r·w = b_r``). With ``E`` these rows, a target
    change ``Δx`` moves the hand by ``Δq = A Δx`` along ``V`` and changes the wrench by ``Δw = P Δx``::

        A = (E K V)⁻¹ E K,        P = K (I − V A),        E P = 0.

    The paper's QP predicts ``Δw = K Δx`` and measures motion as ``vᵢᵀΔx``: a tangential push then
    carries an unbalanced moment, and a commanded hand slide turns into a roll. Here the QP predicts
    only wrenches that balance along the admissible directions, and a held coordinate is held in
    the stiffness metric (e.g. a slide's target turns by ``k d Δt / k_θ``, not ``d Δt``).
Cost (paper eq. 21)
    ``α₀‖Δx‖² + Σᵢ αᵢ (aᵢᵀΔx − βᵢ Δεᵢ)²``: a row ``aᵢ`` of ``A`` per admitted coordinate of the motion
    (:func:`ccopt.modes.admitted_coordinates`) that is free in the model; the commanded coordinate's
    error drives its term, the others are held at their values when the step began. A normal-force
    term ``(e_nᵀ P Δx − g Δf_n)²`` (scaled by ``k_n``) regulates ``f_n`` towards the force the statics
    of the motion need (``ControlInput.force_target``, from :func:`ccopt.statics.regulation_wrench` on
    the estimated parameters), else :attr:`ControllerParams.normal_force`. Before the commanded slide
    has begun (its coordinate has not moved by :attr:`ControllerParams.slide_onset`), a push term
    drives the removed row's value past its estimated bound (the true bound lies beyond the
    conservative estimate), the moment kept balanced: the contact slides where the physics lets it.
    Before the kinematics are known ``v_θ`` takes their rough estimate where it is good enough
    (:func:`ccopt.closed_loop.control_input`), else the paper's naive one (``s_h = 0``, ``d = d_guess``).
Rows (paper eq. 19)
    The estimated cone rows the commanded motion keeps (:func:`ccopt.modes.kept_rows`), with margins
    relative to each row's width, on the predicted wrench ``w + P Δx``, plus ``f_min ≤ f_n ≤ f_max``.
    Rows the estimator has not estimated yet are not enforced.

The QP's variable is the step in task units (:attr:`ControllerParams.length_unit`, ``angle_unit``), and its
terms are errors in those units and in newtons, so that a millimetre, a degree and a newton weigh alike.
The step is scaled down to a maximum per tick (a target speed limit, :attr:`ControllerParams.max_speed`
times the control period; scaled as a whole, so that it keeps the direction that balances the wrench)
and reported with the QP's diagnostics; an infeasible tick still returns the least-violating step and
says so.

The tick runs as one call of generated C (:mod:`ccopt.control.tick`: this module's instance, the QP
and the checks, in CasADi symbols); :meth:`Controller.build_instance` is the readable reference it is
tested against, and the path taken with any other QP back end.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from operator import truediv

import numpy as np

from ccopt import contact, modes, validation
from ccopt.contact import N_CONE_ROWS
from ccopt.control import tick
from ccopt.control.qp import INFEASIBLE_SLACK, QPInstance, QPSolution, QPSolver
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
        naive_force_lag: the tangential force (N) a pivot about the naive ``v_θ`` may build up before
            the normal- and tangential-force terms catch it. The naive lever is off the true one by
            up to about ``d_guess``, so each radian turned about it strains the hand's translational
            impedance ``k`` by that much; the force terms correct a ``force_rate`` share of the error
            per second, so turning at ``ω`` lags ``k d_guess ω / force_rate`` behind. A pivot about
            the naive lever is paced to ``ω = naive_force_lag · force_rate / (k · d_guess)`` (4.8°/s
            on the default hand). Turned at the full speed, the first exploration pivots of the goals
            study (seeds 0–1, 80 trials) built 5–8 N of tangential force: before the kinematics were
            valid the hand slid 18 times and rolled 12; paced, it slid 3 times and rolled 8, none of
            them in the first exploration (all in re-explorations at steep tilts, two trials).
        max_speed: largest impedance-target speed ``|Δn|, |Δt|`` (m/s) and ``|Δθ|`` (rad/s).
        slide_speed: largest impedance-target speed ``|Δn|, |Δt|`` (m/s) while a slide is commanded
            (hand or ground), below ``max_speed`` where smaller. A slide is a quasi-static motion: driven
            fast, the sliding object's inertia and the contacts' dynamics take over. Measured on the
            paper triangle with 0.5 kg added, planar plant: a ground slide whose target moved at up to
            60 mm/s broke away and slid at 50–90 mm/s, and the ground contact chattered, the hand's
            normal force jumping between 8 and 29 N every 8 ms (limit 25 N); at 20 mm/s it slid
            smoothly (largest normal force of the run 21.5 N) and realised its command as before.
        push_weight: ``α`` of the term that pushes a commanded slide's removed row past its bound.
        push_force: how far past the estimated bound the push aims, N.
        slide_onset: progress of a commanded slide (m) after which its contact counts as sliding.
        statics_margin: margin (N) the regulation wrench of a motion keeps on its rows, where the
            estimated statics allow it (:func:`ccopt.statics.regulation_wrench`).
        statics_margin_share: the share of that margin the QP's rows keep at most (the rows' own
            margins above apply where they are smaller).
        force_headroom: the QP's predicted normal force and the statics' force targets stay this far
            (N) below the hand's largest force: the measured force overshoots the prediction by a
            few newtons in a push (3.7 N on a heavy triangle's ground slide aimed at the limit).
            A closed loop keeps at least its plant's :attr:`~ccopt.plant.base.Plant.force_headroom`
            (:func:`ccopt.closed_loop.plant_controls`).
        friction_step: how far beyond ``μ̂_h`` (the largest friction ratio the hand was seen to
            hold) a motion may explore the hand friction where ``μ̂_h`` leaves it short of its
            margin (:mod:`ccopt.control.targets`); 0 never explores.
        slide_beyond: how far past the sticking forces seen the statics target puts a ground
            slide's wrench where the ground's friction face that way is not known (N): the hull's
            row there is a face of the forces seen, about a newton inside the true face (median
            0.9 N on a closed-loop tour of the paper triangle). On a friction face the ground slid
            past, pushing past it tilted the wrench onto the hand's torque limit (a random
            square's second slide at 38° judged −2.5 N instead of +6.4 N).
        infeasible_margin: a step whose estimated statics margin is below ``−infeasible_margin`` (N)
            when it starts is not forced: it ends ``infeasible`` with the reason.
        length_unit, angle_unit, force_unit: the units in which the QP weighs its terms and its
            step (m, rad, N): an error of one unit costs its weight, a step of one unit the
            regularisation. A millimetre, a degree and a newton: the scales the task is judged on.
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
    naive_force_lag: float = 2.0
    max_speed: tuple[float, float, float] = (
        0.002 / PAPER_PERIOD,
        0.002 / PAPER_PERIOD,
        math.radians(1.0) / PAPER_PERIOD,
    )
    slide_speed: float = 0.02
    push_weight: float = 0.5
    push_force: float = 4.0
    slide_onset: float = 0.001
    statics_margin: float = 3.0
    statics_margin_share: float = 0.5
    friction_step: float = 0.1
    force_headroom: float = 2.5
    slide_beyond: float = 1.5
    infeasible_margin: float = 1.0
    length_unit: float = 1e-3
    angle_unit: float = math.radians(1.0)
    force_unit: float = 1.0

    def __post_init__(self) -> None:
        positive = (
            "regularization",
            "convergence_rate",
            "force_rate",
            "d_guess",
            "normal_force",
            "naive_force_lag",
        )
        for name in positive:
            value = getattr(self, name)
            if not (math.isfinite(value) and value > 0.0):
                raise ValueError(f"{name} must be positive, got {value!r}")
        if not (math.isfinite(self.force_headroom) and self.force_headroom >= 0.0):
            raise ValueError(f"force_headroom must be a non-negative force (N), got {self.force_headroom!r}")
        if len(self.max_speed) != 3 or not all(math.isfinite(v) and v > 0.0 for v in self.max_speed):
            raise ValueError(f"max_speed must be three positive speeds, got {self.max_speed!r}")
        if not (math.isfinite(self.slide_speed) and self.slide_speed > 0.0):
            raise ValueError(f"slide_speed must be a positive speed (m/s), got {self.slide_speed!r}")

    def check_hand(self, hand: Hand) -> None:
        """``ValueError`` unless the target normal force lies inside the hand's force limits, below
        the headroom."""
        f_min, f_max = hand.force_limits
        if not f_min < self.normal_force < f_max - self.force_headroom:
            raise ValueError(
                f"normal_force {self.normal_force} N must lie inside the hand's force limits "
                f"{hand.force_limits} less the headroom {self.force_headroom} N"
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
        s_h: estimated ``s_h`` (m), shapes ``v_θ``: valid, or before that a rough estimate good
            enough for it (:func:`ccopt.closed_loop.control_input`); NaN: the naive ``v_θ``.
        d: estimated distance ``d`` from the ground contact to the hand face (m), likewise.
        kinematics_valid: whether the kinematics are valid (the progress ``coordinates`` are then
            estimated ones).
        coordinates: the ``(θ_o, s_h, s_g)`` that progress is measured on (rad, m, m), the same
            source as the command's targets.
        force_target: the normal force the motion's statics need (N), None for the default.
        tangential_target: the tangential force of the statics' wrench (N), None to hold the one at
            the start of the step.
        statics_margin: the margin the statics' wrench keeps on the rows (N, torque rows over
            ``l_h``), None where the statics are not known.
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
    force_target: float | None = None
    tangential_target: float | None = None
    statics_margin: float | None = None


@dataclass(frozen=True)
class Command:
    """A commanded motion with its target coordinates ``(θ_o, s_h, s_g)`` (rad, m, m).

    ``targets`` holds the commanded coordinate's goal and the held coordinates' values at the start
    of the step; ``start`` the coordinates when the step began (None: the targets of the held ones,
    and no slide counts as begun); ``wrench`` the measured wrench then (N, N·m; None: unknown), which
    the tangential force is held at where the statics give no target.
    """

    motion: Motion
    targets: np.ndarray
    start: np.ndarray | None = None
    wrench: np.ndarray | None = None


@dataclass(frozen=True)
class ControlOutput:
    """One tick's result: the hand-frame target change and the QP's diagnostics; ``solved`` is False
    when the solver gave no finite step (the step is then zero, the solution infeasible). ``packed``
    is the tick's QP instance in the solver's packed layout (:attr:`instance` unpacks it)."""

    step: np.ndarray
    solution: QPSolution
    packed: np.ndarray
    solved: bool = True

    @property
    def instance(self) -> QPInstance:
        """The tick's QP instance (:meth:`Controller.build_instance`'s), unpacked afresh."""
        return QPInstance.from_packed(self.packed, tick.N_ROWS, tick.N_TERMS)


def _failed(backend: str) -> QPSolution:
    """A solver's answer that is not a finite step, as the controller reports it: no step, no wrench
    change, infinite slack, infeasible."""
    return QPSolution(np.zeros(3), np.zeros(3), math.inf, False, backend)


def _scaled(solution: QPSolution, instance: QPInstance, factor: float) -> QPSolution:
    """The solution of the step ``factor`` times the solver's (the speed limit): its wrench change,
    and its slack on the instance's active rows (the QP's rows ``γ nᵀ P Δy − t ≤ b − nᵀ w``) and
    whether that is feasible, evaluated again for that step."""
    step = solution.step * factor
    change = instance.stiffness @ step
    active = instance.active
    rows = instance.rows[active]
    excess = instance.gains[active] * (rows @ change) - (instance.bounds[active] - rows @ instance.wrench)
    slack = max(0.0, float(excess.max(initial=0.0)))
    return QPSolution(step, change, slack, slack <= INFEASIBLE_SLACK, solution.backend)


def _naive(state: ControlInput) -> bool:
    """Whether ``v_θ`` is the paper's naive one (``s_h = 0``, ``d = d_guess``): the lever is not even
    roughly known."""
    return not (math.isfinite(state.s_h) and math.isfinite(state.d))


class _Terms:
    """The tracking terms ``α (dᵀΔx − δ)²`` of one QP, collected in order."""

    def __init__(self) -> None:
        self.directions: list[np.ndarray] = []
        self.weights: list[float] = []
        self.targets: list[float] = []

    def add(self, direction: np.ndarray, weight: float, target: float) -> None:
        self.directions.append(direction)
        self.weights.append(weight)
        self.targets.append(target)


def quasi_static_maps(
    stiffness: np.ndarray, free_directions: np.ndarray, balance: np.ndarray
) -> tuple[np.ndarray, np.ndarray]:
    """``(A, P)``: the motion ``Δq = A Δx`` along the free directions ``V`` (3×k, hand frame) and the
    wrench change ``Δw = P Δx`` that a target change ``Δx`` causes once the hand and the object are
    in equilibrium again, with ``E Δw = 0`` for the equilibrium rows ``E`` (k×3): ``A = (E K V)⁻¹ E K``,
    ``P = K (I − V A)`` (see the module docstring)."""
    coupling = balance @ stiffness
    reduced = coupling @ free_directions
    if reduced.shape == (1, 1):  # one free direction: LAPACK's 1×1 solve, bit for bit, without its overhead
        motion_map = coupling * (1.0 / reduced.item())
    else:
        motion_map = np.linalg.solve(reduced, coupling)
    return motion_map, stiffness @ (_IDENTITY - free_directions @ motion_map)


_IDENTITY = np.eye(3)
_IDENTITY.flags.writeable = False
_FORCE_ROWS = np.array([[1.0, 0.0, 0.0], [-1.0, 0.0, 0.0]])
"""The normal-force limits' rows ``f_n ≤ f_max``, ``−f_n ≤ −f_min`` after the cone rows."""
_FORCE_ROWS.flags.writeable = False
_FORCE_ACTIVE = np.ones(2, dtype=bool)
_FORCE_ACTIVE.flags.writeable = False


_STEP, _SOLUTION_STEP, _WRENCH_CHANGE, _PACKED = (
    tick.OUTPUTS[name] for name in ("step", "solution_step", "wrench_change", "packed")
)
_SLACK, _SOLVED = tick.OUTPUTS["slack"].start, tick.OUTPUTS["solved"].start


class Controller:
    """Builds and solves the impedance-target QP each tick.

    By default a tick is one call of generated C (:mod:`ccopt.control.tick`: the instance, the QP
    and the checks of :meth:`update`); given a ``solver``, it is :meth:`build_instance` (the readable
    reference, in NumPy) solved by that back end.

    Args:
        hand: the robot's hand (its impedance ``K`` and normal-force limits).
        period: control period, s (the per-second gains become per-tick fractions).
        params: gains and limits.
        solver: a QP back end for the reference path; None: the compiled tick.
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
        self.solver = solver
        self._convergence = 1.0 - math.exp(-self.params.convergence_rate * self.period)
        self._force_gain = 1.0 - math.exp(-self.params.force_rate * self.period)
        self._max_step = np.asarray(self.params.max_speed) * self.period
        self._slide_max_step = self._max_step.copy()
        self._slide_max_step[:2] = np.minimum(self._max_step[:2], self.params.slide_speed * self.period)
        self._max_steps = {False: self._max_step.tolist(), True: self._slide_max_step.tolist()}
        self._naive_turn_error = self.naive_turn_speed * self.period / self._convergence
        f_min, f_max = self.hand.force_limits
        self._force_bounds = np.array([f_max - self.params.force_headroom, -f_min])
        p = self.params
        self._units = np.array([p.length_unit, p.length_unit, p.angle_unit])
        self._row_gains = np.full(N_CONE_ROWS + 2, self.params.row_gains)
        self._row_gains[N_CONE_ROWS:] = 1.0
        k_x, k_y, _ = self.hand.stiffness
        self._angle_free_stiffness = k_x == k_y  # K in the hand frame is then the same at every angle
        fixed = self.hand.stiffness_in_hand_frame(0.0) if self._angle_free_stiffness else None
        self._tick = tick.Tick(self._tick_parameters(), fixed) if solver is None else None

    def _tick_parameters(self) -> np.ndarray:
        """The constants of the compiled tick (:data:`ccopt.control.tick.PARAMETERS`)."""
        p = self.params
        values = {
            "regularization": p.regularization,
            "weights": p.weights,
            "hold_weights": p.hold_weights,
            "convergence": self._convergence,
            "force_gain": self._force_gain,
            "force_weight": p.force_weight,
            "push_weight": p.push_weight,
            "push_force": p.push_force,
            "friction_margin": p.friction_margin,
            "torque_margin": p.torque_margin,
            "ground_margin": p.ground_margin,
            "min_margin": p.min_margin,
            "statics_margin_share": p.statics_margin_share,
            "units": self._units,
            "force_unit": p.force_unit,
            "row_gains": self._row_gains,
            "force_bounds": self._force_bounds,
            "max_step": self._max_step,
            "slide_max_step": self._slide_max_step,
        }
        return np.concatenate(
            [np.atleast_1d(np.asarray(values[name], dtype=float)) for name, _ in tick.PARAMETERS]
        )

    @property
    def naive_turn_speed(self) -> float:
        """How fast (rad/s) a pivot about the naive ``v_θ`` turns at most
        (:attr:`ControllerParams.naive_force_lag`)."""
        p = self.params
        return p.naive_force_lag * p.force_rate / (max(self.hand.stiffness[:2]) * p.d_guess)

    @property
    def step_units(self) -> np.ndarray:
        """The units of the QP's variable ``y`` (m, m, rad): the target change is ``Δx = step_units · y``."""
        return self._units.copy()

    def update(self, state: ControlInput, command: Command) -> ControlOutput:
        """The hand-frame change of the impedance target ``(Δn, Δt, Δθ)`` (m, m, rad) for this tick.

        A step the solver returns that is not finite gives no change (the target holds), ``solved``
        False and a solution flagged infeasible with infinite slack: never a NaN for the plant. A step
        beyond the speed limit is scaled down to it, and the solution reported is the scaled step's.
        A pivot about the naive ``v_θ`` is paced (:meth:`_paced`)."""
        if command.motion is Motion.PIVOT and _naive(state):
            command = self._paced(state, command)
        if self._tick is not None:
            return self._compiled_update(state, command)
        instance = self.build_instance(state, command)
        solution = self.solver.solve(instance)
        step = self._units * solution.step  # the QP's variable is the step in task units
        if not all(map(math.isfinite, step.tolist())):  # the solver failed: no motion this tick
            return self._held(instance, solution.backend)
        limit = self._max_steps[command.motion in modes.SLIDES]  # a slide's is slower
        excess = max(map(truediv, map(abs, step.tolist()), limit))
        if excess > 1.0:  # scaled, not clipped: the step keeps its direction, and with it the balance
            step = step / excess  # of the wrench it predicts; the solution reported is the scaled step's
            solution = _scaled(solution, instance, 1.0 / excess)
        solved = {"step": step, "solution": solution, "packed": instance.packed, "solved": True}
        return validation.trusted(ControlOutput, solved)

    def _paced(self, state: ControlInput, command: Command) -> Command:
        """``command`` with its ``θ_o`` target at most as far from ``θ_o`` as the convergence term
        turns in a tick at :attr:`naive_turn_speed`: a pivot about the naive lever turns no faster
        than its force terms keep up with (:attr:`ControllerParams.naive_force_lag`)."""
        theta = float(state.coordinates[modes.THETA_O])
        error = float(command.targets[modes.THETA_O]) - theta
        limit = self._naive_turn_error
        if abs(error) <= limit:
            return command
        targets = np.array(command.targets, dtype=float)
        targets[modes.THETA_O] = theta + math.copysign(limit, error)
        return validation.trusted(Command, {**vars(command), "targets": targets})

    @staticmethod
    def _held(instance: QPInstance, backend: str) -> ControlOutput:
        """The output of a tick whose solver gave no finite step: no motion, flagged infeasible."""
        held = {"step": np.zeros(3), "solution": _failed(backend), "packed": instance.packed, "solved": False}
        return validation.trusted(ControlOutput, held)

    def _compiled_update(self, state: ControlInput, command: Command) -> ControlOutput:
        """:meth:`update` as one call of the compiled tick: the same step, to rounding."""
        angle = state.hand_angle
        stiffness = None if self._angle_free_stiffness else self.hand.stiffness_in_hand_frame(angle)
        out = self._tick(
            (command.motion, self._slide_begun(state, command)),
            stiffness,
            self._tick_scalars(state, command),
            state.wrench,
            state.coordinates,
            command.targets,
            state.cone_rows,
            state.cone_bounds,
            state.row_valid,
        )
        if out is None:  # the solver failed: no motion this tick
            return self._held(self.build_instance(state, command), self._tick.backend)
        slack = out.item(_SLACK)
        solution = validation.trusted(
            QPSolution,
            {
                "step": out[_SOLUTION_STEP],
                "wrench_change": out[_WRENCH_CHANGE],
                "slack": slack,
                "feasible": slack <= INFEASIBLE_SLACK,
                "backend": self._tick.backend,
            },
        )
        fields = {
            "step": out[_STEP],
            "solution": solution,
            "packed": out[_PACKED],
            "solved": out.item(_SOLVED) != 0.0,
        }
        return validation.trusted(ControlOutput, fields)

    def _tick_scalars(self, state: ControlInput, command: Command) -> tuple[float, ...]:
        """The compiled tick's scalars (:data:`ccopt.control.tick.SCALARS`), resolved as
        :meth:`build_instance` resolves them: the naive ``v_θ``, the default force targets."""
        p = self.params
        s_h, d = (0.0, p.d_guess) if _naive(state) else (state.s_h, state.d)
        force_target = p.normal_force if state.force_target is None else state.force_target
        f_t_target = state.tangential_target
        if f_t_target is None:
            f_t_target = state.wrench[1] if command.wrench is None else command.wrench[1]
        margin = state.statics_margin
        known = margin is not None and math.isfinite(margin)
        margin = margin if known else 0.0
        return (state.hand_angle, s_h, d, state.mu_h, state.l_h, force_target, f_t_target, margin, known)

    def build_instance(self, state: ControlInput, command: Command) -> QPInstance:
        """The QP of this tick (exposed for studies and tests)."""
        p = self.params
        stiffness = self.hand.stiffness_in_hand_frame(state.hand_angle)
        s_h, d = (0.0, p.d_guess) if _naive(state) else (state.s_h, state.d)
        vectors = contact.admissible_motions(state.hand_angle, s_h, d)
        free, balance = self._model(state, command, vectors)
        free_directions = vectors[:, :1] if len(free) == 1 else vectors[:, free]  # θ_o is column 0
        motion_map, wrench_map = quasi_static_maps(stiffness, free_directions, balance)
        errors = np.asarray(command.targets) - np.asarray(state.coordinates)
        regulated = modes.driven_coordinate(command.motion)
        terms = _Terms()
        for row, k in enumerate(free):
            unit = p.angle_unit if k == modes.THETA_O else p.length_unit
            weight = p.weights[k] if k == regulated else p.hold_weights[k]
            terms.add(motion_map[row] / unit, weight, self._convergence * errors[k] / unit)
        f_n = float(state.wrench[0])
        force_target = p.normal_force if state.force_target is None else state.force_target
        change = self._force_gain * (force_target - f_n)
        terms.add(wrench_map[0] / p.force_unit, p.force_weight, change / p.force_unit)
        removed = modes.REMOVED_ROWS[command.motion]
        if not removed:  # hold the tangential force where the statics want it (or where it is)
            f_t_target = state.tangential_target
            if f_t_target is None:
                f_t_target = state.wrench[1] if command.wrench is None else command.wrench[1]
            change = self._force_gain * (f_t_target - state.wrench[1])
            terms.add(wrench_map[1] / p.force_unit, p.force_weight, change / p.force_unit)
        elif len(free) == 1:  # the commanded slide has not begun: push past its bound
            row = state.cone_rows[removed[0]]
            scale = p.force_unit * float(np.linalg.norm(row))
            excess = state.cone_bounds[removed[0]] + p.push_force - float(row @ state.wrench)
            terms.add((row @ wrench_map) / scale, p.push_weight, self._force_gain * excess / scale)
        margins = self._margins(f_n, state)
        rows = np.concatenate((state.cone_rows, _FORCE_ROWS))
        bounds = np.concatenate((state.cone_bounds - margins, self._force_bounds))
        active = np.concatenate((modes.kept_rows(command.motion) & state.row_valid, _FORCE_ACTIVE))
        units = self._units  # the QP's variable y is the step in task units: Δx = units · y
        return QPInstance.unchecked(  # well formed by construction: no per-tick checks
            stiffness=wrench_map * units,
            wrench=np.asarray(state.wrench, dtype=float),
            rows=rows,
            bounds=bounds,
            gains=self._row_gains,
            active=active,
            regularization=p.regularization,
            directions=np.asarray(terms.directions) * units,
            weights=np.asarray(terms.weights),
            targets=np.asarray(terms.targets),
        )

    def _model(
        self, state: ControlInput, command: Command, vectors: np.ndarray
    ) -> tuple[list[int], np.ndarray]:
        """The coordinates free in the prediction and their equilibrium rows ``E`` (hand frame).

        ``θ_o`` is always free, balanced by the moment about the ground contact (``v_θ``). A commanded
        slide's coordinate joins once the slide has begun (moved by ``slide_onset`` the commanded way
        since the step began), held on its friction boundary by the removed row.
        """
        if self._slide_begun(state, command):
            removed = modes.REMOVED_ROWS[command.motion]
            balance = np.array((vectors[:, modes.THETA_O], state.cone_rows[removed[0]]))
            return [modes.THETA_O, modes.driven_coordinate(command.motion)], balance
        return [modes.THETA_O], vectors[:, modes.THETA_O : modes.THETA_O + 1].T

    def _slide_begun(self, state: ControlInput, command: Command) -> bool:
        """Whether the commanded slide has begun: its coordinate has moved by ``slide_onset`` (m) the
        commanded way since the step began (never for a hold or a pivot, nor without a start)."""
        if command.motion not in modes.SLIDES or command.start is None:
            return False
        driven = modes.driven_coordinate(command.motion)
        delta = command.targets[driven] - command.start[driven]
        progress = (state.coordinates[driven] - command.start[driven]) * math.copysign(1.0, delta)
        return bool(progress >= self.params.slide_onset)

    def _margins(self, f_n: float, state: ControlInput) -> np.ndarray:
        """Per-row margins ``b − margin``: strict inequalities for the rows the command keeps."""
        p = self.params
        force = max(f_n, 0.0)
        slide = max(p.friction_margin * state.mu_h * force, p.min_margin)
        pivot = max(p.torque_margin * force, p.min_margin) * state.l_h
        ground = p.ground_margin
        if state.statics_margin is not None and math.isfinite(state.statics_margin):
            # the statics' wrench keeps this margin on every row (N; torque rows over l_h): keep the
            # QP's rows no stricter, so that the QP can reach it, but never below half their own
            share = p.statics_margin_share * state.statics_margin
            slide = max(min(slide, share), 0.5 * slide)
            pivot = max(min(pivot, share * state.l_h), 0.5 * pivot)
            ground = max(min(ground, share), 0.5 * ground)
        return np.array((slide, slide, pivot, pivot, ground, ground))  # Row order
