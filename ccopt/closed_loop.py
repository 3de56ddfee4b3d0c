"""The closed loop: plant → sensors → estimator → controller → plant, at their own rates.

The plant steps at its timestep (1 ms). Every ``1/estimator_hz`` the sensors are read and the
estimator updated; every ``1/controller_hz`` the schedule is advanced and the controller computes a
hand-frame change of the impedance target, which the loop spreads evenly over the next control
period (a ramp with velocity feed-forward, so the target never jumps). Ground truth is read only to
be recorded. A run is deterministic for a given seed.

Progress along a step is measured on the estimated coordinates ``(θ_o, s_h, s_g)``. Before the
kinematics are estimated (the paper's exploration phase), a step measures its progress on the hand's
own motion instead — ``θ_h`` for a pivot, ``−r_h·e_t`` for a hand slide (the object sticks on the
ground) and ``x_h`` for a ground slide (the hand sticks on the object) — which changes exactly like
the coordinate while the commanded configuration holds. The source is fixed for the whole step.
"""

from __future__ import annotations

import dataclasses
import functools
import math
import time as wallclock
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING, Literal

import numpy as np

from ccopt import clock, contact, geometry, modes, validation
from ccopt.contact import GROUND_ROWS, Row
from ccopt.control.controller import Command, ControlInput, Controller, ControllerParams
from ccopt.control.targets import UNJUDGED, StaticsTarget, TargetGoal, statics_target
from ccopt.estimation.classifier import tight_direction
from ccopt.estimation.estimator import Estimate, Estimator, EstimatorParams
from ccopt.hand import Hand
from ccopt.health import HealthParams, SensorHealth
from ccopt.modes import MOTION_CODES, ContactConfiguration, HandGeometry
from ccopt.objects import PlanarObject
from ccopt.planning.planner import PlannerParams
from ccopt.planning.sequencer import GoalResult, GoalSequencer, s_g_from
from ccopt.plant.base import MIN_RATE, Plant, PlantParams, StartConfig
from ccopt.plant.placement import hand_over_vertex
from ccopt.plant.sensors import Measurement, SensorParams, Sensors
from ccopt.record import RecordWriter
from ccopt.schedule import Goal, Schedule, Step, probe_as_run
from ccopt.stops import stop_requested, stops_held

if TYPE_CHECKING:
    from ccopt.plant.mujoco_panda import PandaParams

PlantKind = Literal["planar", "panda"]


@dataclass(frozen=True)
class Perturbation:
    """A scripted external push on the object: world force (N) from ``time`` (s) for ``duration`` (s)."""

    time: float
    force: tuple[float, float]
    duration: float


@dataclass(frozen=True)
class LoopParams:
    """Rates and components of a closed-loop run.

    ``hand`` is the robot's hand, handed to the plant, the estimator (which is told nothing about the
    object) and the controller. ``start`` gives the object's tilt (resting on one vertex, as in the
    paper) and the push; with ``centre_hand`` the hand starts as close over the ground contact as its
    length allows (:func:`~ccopt.plant.placement.hand_over_vertex`), whatever ``start.s_h`` says.
    ``panda`` holds the Panda plant's own settings (None: its defaults). ``statics_hz`` is the
    largest rate at which the estimated statics' target (:func:`ccopt.control.targets.statics_target`,
    two or four LPs) is evaluated afresh, and at every step's start: at the paper's 30 Hz that is
    every control tick, at 1 kHz every tenth (the configuration it judges changes little in 10 ms).
    ``record_hz`` is the record's largest rate: it keeps every ``n``-th estimator sample with its
    ground truth, ``n = round(estimator_hz / record_hz)`` (at least 1; at the default rates, every
    one). Rates in Hz.
    """

    plant: PlantKind = "planar"
    estimator_hz: float = 100.0
    controller_hz: float = 30.0
    statics_hz: float = 100.0
    record_hz: float = 100.0
    hand: Hand = field(default_factory=Hand)
    start: StartConfig = field(default_factory=lambda: StartConfig(theta_o=0.3, normal_force=10.0))
    centre_hand: bool = True
    plant_params: PlantParams = field(default_factory=PlantParams)
    panda: PandaParams | None = None
    sensor_params: SensorParams = field(default_factory=SensorParams)
    controller_params: ControllerParams = field(default_factory=ControllerParams)
    estimator_params: EstimatorParams = field(default_factory=EstimatorParams)
    perturbations: tuple[Perturbation, ...] = ()
    settle_time: float = 0.2
    supervision: Supervision = field(default_factory=lambda: Supervision())

    def __post_init__(self) -> None:
        if self.plant not in ("planar", "panda"):
            raise ValueError(f"unknown plant {self.plant!r}; expected 'planar' or 'panda'")
        parts = (
            ("hand", Hand),
            ("start", StartConfig),
            ("plant_params", PlantParams),
            ("sensor_params", SensorParams),
            ("controller_params", ControllerParams),
            ("estimator_params", EstimatorParams),
        )
        validation.check_types((name, getattr(self, name), kind) for name, kind in parts)
        top = 1.0 / self.plant_params.timestep
        for name in ("estimator_hz", "controller_hz", "statics_hz", "record_hz"):
            rate = getattr(self, name)
            if not (np.isfinite(rate) and MIN_RATE <= rate <= top):
                raise ValueError(f"{name} must be in [{MIN_RATE:g}, {top:g}] Hz, got {rate!r}")
        self.controller_params.check_hand(self.hand)

    def ticks(self, rate: float) -> int:
        """Plant steps per period of a loop running at ``rate`` Hz (at least 1)."""
        return max(1, round(1.0 / (rate * self.plant_params.timestep)))

    @property
    def control_period(self) -> float:
        """The controller's actual period, s (a whole number of plant steps)."""
        return self.ticks(self.controller_hz) * self.plant_params.timestep

    @property
    def record_stride(self) -> int:
        """The record keeps every ``record_stride``-th estimator sample (at least every one)."""
        return max(1, round(self.estimator_hz / self.record_hz))


STEP_STATUSES = ("reached", "timeout", "infeasible", "rolled", "slipped", "lost", "skipped")
"""How a step can end: its coordinate settled within tolerance (by the estimate), its time ran out,
the estimated statics ruled it out, (a goal's motion or an exploration step) the hand rolled on
the face's end instead (:data:`ROLL_TIME`), (a slide) the other contact slid instead, (a goal's
motion) the kinematics became unknown (:data:`LOST_TIME`), or (an exploration's second hand-slide
probe) it was not run: :data:`SKIPPED_PROBE`."""
SKIPPED_PROBE = "the hand slid in the first probe: μ_h is measured, the same both ways"
"""The reason of a ``skipped`` probe (:func:`ccopt.schedule.probe_as_run`)."""


@dataclass(frozen=True)
class StepResult:
    """How one schedule step went, by the estimate (truth is scored in :mod:`ccopt.metrics`)."""

    index: int
    kind: str
    delta: float
    start_time: float
    end_time: float
    status: str
    reason: str = ""
    explore: bool = False
    goal: int | None = None
    """The schedule index of the goal this motion was planned for (None: a schedule step)."""

    @property
    def reached(self) -> bool:
        return self.status == "reached"

    def as_dict(self) -> dict[str, object]:
        """The result as ``meta.json`` stores it (with ``reached``)."""
        return {**dataclasses.asdict(self), "reached": self.reached}


@dataclass(frozen=True)
class RunResult:
    """What a run returns; the full time series is in the record folder (or ``samples``).

    ``status`` is how the run ended (:data:`RUN_STATUSES`), ``message`` why, in one line.
    """

    steps: tuple[StepResult, ...]
    samples: dict[str, np.ndarray]
    sim_time: float
    wall_time: float
    status: str
    message: str
    folder: Path | None
    goals: tuple[GoalResult, ...] = ()
    hand_angle_range: tuple[float, float] = (-math.pi, math.pi)
    """The hand angles the plant's robot reaches (rad)."""
    target_at_reach: float = 0.0
    """Simulated time (s) the impedance target's turn was held at the end of the robot's reach
    (:attr:`~ccopt.plant.base.Plant.target_angle_range`)."""
    force_headroom: float | None = None
    """How far below the hand's largest force (N) the run's controller and planner kept the normal
    force (:func:`plant_controls`; None: the controller parameters' own)."""
    last_usable: Estimate | None = None
    """The run's last estimate whose kinematics were valid (None if none was)."""

    @property
    def interrupted(self) -> bool:
        return self.status == "interrupted"


def make_plant(obj: PlanarObject, params: LoopParams) -> Plant:
    """The plant of a run: planar or Panda (whose module is imported only when asked for)."""
    start = start_config(obj, params)
    if params.plant == "planar":
        from ccopt.plant.mujoco_planar import PlanarPlant

        return PlanarPlant(obj, params.plant_params, start, params.hand)
    from ccopt.plant.mujoco_panda import PandaPlant

    return PandaPlant(obj, params.plant_params, start, params.hand, panda=params.panda)


def start_config(obj: PlanarObject, params: LoopParams) -> StartConfig:
    """The configuration a run of ``params`` on ``obj`` starts in (``centre_hand`` applied)."""
    if params.centre_hand:
        return hand_over_vertex(obj, params.start, params.hand)
    return params.start


def control_input(
    estimate: Estimate, hand_pose: np.ndarray, coordinates: np.ndarray, target: StaticsTarget = UNJUDGED
) -> ControlInput:
    """What the controller reads from an estimate, the measured hand pose, the progress source and the
    estimated statics' target (with the hand friction it explores, if any: :mod:`ccopt.control.targets`)."""
    cone_rows, mu_h = estimate.cone_rows, estimate.mu_h
    if target.mu_h is not None:
        cone_rows, mu_h = contact.with_hand_friction(cone_rows, target.mu_h), target.mu_h
    usable = kinematics_usable(estimate)
    s_h, d = (estimate.s_h, estimate.d) if usable else rough_lever(estimate)
    return validation.trusted(  # every field, each well formed by construction
        ControlInput,
        {
            "wrench": estimate.wrench,
            "cone_rows": cone_rows,
            "cone_bounds": estimate.cone_bounds,
            "row_valid": enforced_rows(estimate),
            "mu_h": mu_h,
            "l_h": estimate.torque_lever,
            "hand_angle": float(hand_pose[2]),
            "s_h": s_h,
            "d": d,
            "kinematics_valid": usable,
            "coordinates": coordinates,
            "force_target": target.force,
            "tangential_target": target.tangential,
            "statics_margin": target.margin if target.force is not None else None,
        },
    )


ROUGH_LEVER_STD = 0.01
"""m: before the kinematics are valid, the controller's ``v_θ`` may take the rough ``ŝ_h`` and ``d̂``
once both standard deviations are at most this (:func:`rough_lever`)."""


def rough_lever(estimate: Estimate) -> tuple[float, float]:
    """``(s_h, d)`` (m) for the controller's ``v_θ`` before the kinematics are valid: their rough
    means where both are known to :data:`ROUGH_LEVER_STD` and the hand is known to be off the
    vertical of the ground contact (``|ŝ_h|`` beyond two standard deviations); else NaN, the
    paper's naive ``v_θ`` (``s_h = 0``), which is then as good a guess. The naive one pivots the hand
    about its own centre: with the hand 6–8 cm from the ground contact (where an experimenter's tour
    may start it) the exploration's 7.2° pivots pushed the hand onto its edge and turned it 2–3°
    against the object. Taking the rough means whenever known (the hand centred too) gave the paper
    pentagons force peaks of 27–29 N and a hand pivot in every seed."""
    _, s_h, _, d = estimate.kinematics_mean
    _, std_s_h, _, std_d = estimate.kinematics_std
    known = std_s_h <= ROUGH_LEVER_STD and std_d <= ROUGH_LEVER_STD  # False for NaN
    if known and abs(s_h) > 2.0 * std_s_h:
        return s_h, d
    return math.nan, math.nan


def enforced_rows(estimate: Estimate) -> np.ndarray:
    """The cone rows the controller keeps (where its command keeps them): the estimated ones, but of
    the ground only those fitted to a friction face. A row at the extent of the data seen so far is
    no friction boundary: keeping it would hold the hand force where it has been and block every new
    tilt, while the mode classifier stays conservative about it all the same. One shared read-only
    array per case (the controller reads one every tick)."""
    return _enforced_rows(tuple(estimate.row_valid.tolist()), tuple(estimate.ground_fitted))


@functools.cache
def _enforced_rows(row_valid: tuple[bool, ...], fitted: tuple[bool, bool]) -> np.ndarray:
    """:func:`enforced_rows` of the estimated rows ``row_valid`` and the ground rows' ``fitted``."""
    rows = np.array(row_valid)
    rows[list(GROUND_ROWS)] &= fitted
    rows.flags.writeable = False
    return rows


def kinematics_usable(estimate: Estimate) -> bool:
    """Valid and finite: an estimate flagged valid with NaN coordinates is treated as unknown."""
    if not estimate.kinematics_valid:
        return False
    return all(map(math.isfinite, (estimate.theta_o, estimate.s_h, estimate.s_g, estimate.d)))


def hand_proxy(hand_pose: np.ndarray) -> np.ndarray:
    """Coordinates that change like ``(θ_o, s_h, s_g)`` while the commanded configuration holds."""
    x_h, y_h, theta_h = np.asarray(hand_pose, dtype=float).tolist()
    along = geometry.world_to_hand(geometry.hand_axes(theta_h), x_h, y_h)[1]  # r_h·e_t
    return np.array((theta_h, -along, x_h))


class _StepTracker:
    """Walks the schedule: the current command, its progress source, completion and timeout.

    Targets chain from the *nominal* configuration: after a reached step the next one starts from
    where the previous one was commanded to end, not from where it stopped inside its tolerance, so
    that small shortfalls do not add up (a slide's own coordinate excepted: it cannot move back, so
    it slides its length from where it is); after a step that was not reached, or when the source of
    progress changes (hand proxy → estimate), the nominal configuration is re-read. A step is reached
    once its coordinate has stayed within tolerance for ``settle_time``, or, a slide, once it has
    gone past its target by more than the tolerance; never on an unusable estimate.

    A goal step (:class:`~ccopt.schedule.Goal`) is run by a :class:`~ccopt.planning.sequencer.GoalSequencer`
    ``sequencer(index, goal, now)`` makes: its motions are steps like the schedule's own (their
    results carry the goal's index), each planned from the estimate when the previous one ended and
    started from where the estimate says the object is.
    """

    def __init__(
        self,
        schedule: Schedule,
        settle_time: float,
        slide_onset: float,
        pivot_margin: float,
        hand_give: float,
        sequencer: Callable[[int, Goal, float], GoalSequencer] | None = None,
    ) -> None:
        self.steps = schedule.steps
        self.settle_time = settle_time
        self.slide_onset = slide_onset
        self.pivot_margin = pivot_margin
        """The estimate's classifier counts a hand torque row tight within this margin (N·m)."""
        self.hand_give = hand_give
        """How far (m) ``ŝ_h`` may move in a ground slide, at least, before the hand counts as having
        slid instead (:meth:`_other_slid`)."""
        self.sequencer = sequencer
        self.index = -1
        self.active: Step | None = None
        """The motion under way: a schedule step or a goal's planned motion."""
        self._scripted: Step | None = None
        """The schedule's last motion step as it ran (or was skipped): what an exploration's probe follows."""
        self.goal: GoalSequencer | None = None
        self.goal_results: list[GoalResult] = []
        self.s_g_origin: float | None = None
        """The run's start ground contact (goals' ``s_g`` origin): the latest usable estimate before
        the first ground slide, when the regression has had the most data."""
        self._ground_moved = False
        self._origin_anchor: int | None = None
        self.results: list[StepResult] = []
        self.use_estimate = False
        self.command: Command | None = None
        self.configuration: ContactConfiguration | None = None
        """The contact configuration the command asks for (None before the first step)."""
        self.start_time = 0.0
        self._nominal: np.ndarray | None = None
        self._within_since: float | None = None
        self._holding = False
        """Whether a pivot's target holds still: its torque row was tight and is not yet clear of the
        noise (:data:`ROLL_RELEASE`)."""
        self._since: dict[str, float] = {}  # when each lasting condition (rolled, lost, slipped) began
        self.roll_tilt: float | None = None
        """The estimated ``θ_o`` (rad) where the torque row that ends the pivot under way ``rolled``
        (:meth:`_rolled`) last became tight: where the object stopped turning."""
        self.held_tilts = NO_TILTS
        """``(low, high)``: the estimated ``θ_o`` (rad) range of the ends of the pivots ``reached``
        since the kinematics were last unusable at a step's end (:meth:`_hold_tilts`)."""
        self.fresh = False
        """Whether the current step has not been controlled yet (the estimated statics judge it then)."""

    @property
    def step(self) -> Step:
        return self.active

    @property
    def done(self) -> bool:
        return self.index >= len(self.steps)

    def coordinates(self, estimate: Estimate, hand_pose: np.ndarray) -> np.ndarray | None:
        """The progress coordinates ``(θ_o, s_h, s_g)`` of this step's source; None if unusable."""
        if not self.use_estimate:
            return hand_proxy(hand_pose)
        if kinematics_usable(estimate):
            return np.array([estimate.theta_o, estimate.s_h, estimate.s_g])
        return None

    def advance(
        self, now: float, estimate: Estimate, hand_pose: np.ndarray, status: str, reason: str = ""
    ) -> np.ndarray | None:
        """End the motion under way with ``status`` and start the next one; its progress coordinates
        (None at the end of the schedule)."""
        self._update_origin(estimate)
        last, started = None, False
        if self.active is not None:
            step, goal = self.active, self.goal.index if self.goal is not None else None
            ended = (self.start_time, now, status, reason, step.explore, goal)
            self.results.append(StepResult(self.index, step.kind, step.delta, *ended))
            self._hold_tilts(step, status, estimate)
            last = status
            coordinates = self.coordinates(estimate, hand_pose)
            started = coordinates is not None and self._started(coordinates)
        step = self._next(now, estimate, last, float(hand_pose[2]), started)
        if step is None:
            return None
        self.active = step
        self._ground_moved = self._ground_moved or step.kind == "slide_ground"
        use_estimate = kinematics_usable(estimate)
        if use_estimate != self.use_estimate or status != "reached" or self.goal is not None:
            self._nominal = None
        self.use_estimate = use_estimate
        current = self.coordinates(estimate, hand_pose)
        if self._nominal is None:
            self._nominal = current.copy()
        targets = self._nominal.copy()
        k = self.step.coordinate
        if k is not None:
            if self.step.motion in modes.SLIDES:
                targets[k] = current[k]  # a slide cannot come back: it goes its length from here
            targets[k] += self.step.delta
        self._nominal = targets.copy()
        self.command = Command(self.step.motion, targets, start=current, wrench=np.array(estimate.wrench))
        self.configuration = modes.configuration(self.step.motion)
        self.start_time = now
        self._within_since = None
        self._since.clear()
        self._holding = False
        self.roll_tilt = None
        self.fresh = True
        return current

    def _hold_tilts(self, step: Step, status: str, estimate: Estimate) -> None:
        """Widen :attr:`held_tilts` by the end of a pivot ``reached`` with usable kinematics; forget
        them where the kinematics are unusable (the object may lie on another vertex since)."""
        if not kinematics_usable(estimate):
            self.held_tilts = NO_TILTS
        elif step.kind == "pivot" and status == "reached":
            low, high = self.held_tilts
            self.held_tilts = (min(low, estimate.theta_o), max(high, estimate.theta_o))

    def _update_origin(self, estimate: Estimate) -> None:
        """The start's ground contact, as well as it is known now: the latest usable estimate while
        the ground has neither been commanded to slide nor seen moving (its ``ground_anchor``
        unchanged since the origin was first taken: an unintended slip the kinematics followed
        would otherwise carry the origin along with the object)."""
        latest = s_g_from(estimate)
        if latest is None or self._ground_moved:
            return
        if self._origin_anchor is not None and estimate.ground_anchor != self._origin_anchor:
            self._ground_moved = True
            return
        self.s_g_origin, self._origin_anchor = latest, estimate.ground_anchor

    def _next(
        self, now: float, estimate: Estimate, last: str | None, hand_angle: float, started: bool
    ) -> Step | None:
        """The next motion: the goal under way's, else the schedule's next step (a goal's first
        motion; an exploration's probe as :func:`~ccopt.schedule.probe_as_run` has it at the
        ``hand_angle`` (rad), recorded ``skipped`` where it does not run); None at the end of the
        schedule. ``last`` is how the motion under way ended, ``started`` whether it had started
        (:meth:`_started`)."""
        if self.goal is not None:
            answer = self.goal.next(
                now, estimate, self.s_g_origin, last, self.roll_tilt, self.held_tilts, hand_angle, started
            )
            if isinstance(answer, Step):
                return answer
            self.goal_results.append(answer)
            self.goal = None
        while True:
            self.index += 1
            if self.done:
                self.active = None
                return None
            item = self.steps[self.index]
            if isinstance(item, Step):
                run = probe_as_run(item, self._scripted, hand_angle, estimate.hand_slid)
                self._scripted = item if run is None else run
                if run is not None:
                    return run
                ended = (now, now, "skipped", SKIPPED_PROBE, True, None)
                self.results.append(StepResult(self.index, item.kind, item.delta, *ended))
                continue
            if self.sequencer is None:
                raise ValueError(f"step {self.index + 1} is a goal but the loop has no planner")
            self.goal = self.sequencer(self.index, item, now)
            answer = self.goal.next(now, estimate, self.s_g_origin, hand_angle=hand_angle)
            if isinstance(answer, Step):
                return answer
            self.goal_results.append(answer)
            self.goal = None

    def update(self, now: float, estimate: Estimate, hand_pose: np.ndarray) -> np.ndarray | None:
        """Move to the next step when this one is reached or timed out; the progress coordinates of
        the step then under way (:meth:`coordinates`)."""
        if self.index < 0:
            return self.advance(now, estimate, hand_pose, "reached")
        elapsed = now - self.start_time
        if self.step.kind == "hold":
            if elapsed >= self.step.timeout:
                return self.advance(now, estimate, hand_pose, "reached")
            return self.coordinates(estimate, hand_pose)
        k = self.step.coordinate
        coordinates = self.coordinates(estimate, hand_pose)
        tolerance = self.step.tolerance
        within = coordinates is not None and abs(self.command.targets[k] - coordinates[k]) <= tolerance
        if not within:
            self._within_since = None
        elif self._within_since is None:
            self._within_since = now
        settled = within and clock.lasted(now, self._within_since, self.settle_time)
        if settled or self._overshot(coordinates):
            return self.advance(now, estimate, hand_pose, "reached")
        if self.goal is not None and self._lost(now, coordinates):
            return self.advance(now, estimate, hand_pose, "lost", "the kinematics became unknown")
        if self._other_slid(now, coordinates):
            return self.advance(now, estimate, hand_pose, "slipped", _SLIPPED_REASONS[self.step.kind])
        if elapsed >= self.step.timeout:
            return self.advance(now, estimate, hand_pose, "timeout")
        if self.goal is not None and elapsed >= SLIDE_START_TIME and not self._started(coordinates):
            reason = f"did not start within {SLIDE_START_TIME:g} s"
            return self.advance(now, estimate, hand_pose, "timeout", reason)
        if (self.goal is not None or self.step.explore) and self._rolled(now, estimate):
            return self.advance(now, estimate, hand_pose, "rolled", _ROLL_REASONS[self.step.kind])
        return coordinates

    @property
    def rolling(self) -> bool:
        """Whether the hand is seen off flush in a goal's motion or an exploration step, not yet for
        :data:`ROLL_TIME` (a pivot: until its torque row is clear of the noise, :data:`ROLL_RELEASE`)."""
        return "rolled" in self._since or self._holding

    def _rolled(self, now: float, estimate: Estimate) -> bool:
        """Whether the hand has been seen off flush for :data:`ROLL_TIME` (the estimate's hand
        geometry, the sign of ``θ_o − θ_h``). A pivot counts the sign opposite to its own: the object
        no longer turns with the hand (it lies on another vertex or a face), and pressing on would
        only roll the hand further (the other sign, the object ahead of the hand, is a hand tipping
        over the face's end while the object still turns). A slide counts either sign: it keeps the
        hand flush, so a hand on its edge is a slide becoming a roll, and the kinematics, which take
        the hand as flush, would read the roll as the slide. The classifier is conservative (a
        torque near the hand's limit reads as maybe rolling), so this ends a slide whose hand is
        about to roll as well as one that rolled. A pivot ends only once its torque row has been
        tight (within ``pivot_margin``) on every sample for :data:`ROLL_TIME`: not on the
        classifier's report, whose hold stretches every tight sample. A pivot begun with the torque
        the previous motion left at the hand's limit touches it for a few samples and turns the
        object all the same (a random triangle's pivot at −26° did, for 0.04 s, and ended `rolled`
        with the true hand flush, which cut the planner's reach short of the tilt its ground slide
        needed); and counted on the held report a pivot that landed the object on a face ended
        0.3 s after it landed, the hand rolled 5–7° against the object (the paper square, rectangle
        and pentagon pivoting down to a face). The target holds (:attr:`rolling`) from the first
        tight sample until the row's margin exceeds ``pivot_margin`` by :data:`ROLL_RELEASE`. The
        estimated tilt where the stretch of tight samples that ends the pivot began is
        :attr:`roll_tilt`."""
        if self.step.kind == "pivot":
            margins, pos, neg = estimate.margins, Row.HAND_PIVOT_POS, Row.HAND_PIVOT_NEG
            known = bool(estimate.row_valid[pos])
            raw = tight_direction(margins[pos], margins[neg], self.pivot_margin, known)
            rolled = raw == -math.copysign(1.0, self.step.delta)
            row = neg if self.step.delta > 0 else pos
            clear = not known or margins[row] > self.pivot_margin + ROLL_RELEASE
            self._holding = rolled or (self._holding and not clear)
            if rolled and "rolled" not in self._since:
                self.roll_tilt = estimate.theta_o if estimate.theta_o_valid else None
            return self._lasted("rolled", rolled, now, ROLL_TIME)
        return self._lasted("rolled", estimate.hand_geometry != HandGeometry.FLUSH, now, ROLL_TIME)

    def _lasted(self, name: str, condition: bool, now: float, duration: float) -> bool:
        """Whether ``condition`` has held since ``duration`` ago (s), without a break."""
        if not condition:
            self._since.pop(name, None)
            return False
        return clock.lasted(now, self._since.setdefault(name, now), duration)

    def _other_slid(self, now: float, coordinates: np.ndarray | None) -> bool:
        """Whether, in a slide measured on the estimate, the coordinate of the contact it keeps
        (``ŝ_g`` in a hand slide, ``ŝ_h`` in a goal's ground slide) has been further than the
        step's tolerance (``ŝ_h``: and :attr:`hand_give`) from where it began for :data:`LOST_TIME`
        (single samples jump by about a millimetre where the kinematics re-anchor the ground on a
        false alarm): the estimator saw the other contact give, and pushing on only drives it
        further. A hand-slide probe whose ground gave, its motion taken as the ground's, pushed a
        random quadrilateral 58 mm along the ground before the probe's own coordinate could be
        reached. A hand that gives in a ground slide the estimator tells by the face's tilt
        (:class:`~ccopt.estimation.kinematics.KinematicsParams` ``hand_slide_height``), at small
        tilts not at all. A hand may give a millimetre or two before the ground breaks loose, and
        ``ŝ_h`` (hand frame) moves by a few more where the object turns a little at the start of a
        steep ground slide (on random objects at −26°, 3.5 mm in 0.3 s, then the ground slid
        10 mm): a schedule's ground slide, which the truth scores, is not ended on ``ŝ_h``."""
        kept = modes.kept_coordinate(self.step.kind)
        limit = self.step.tolerance if kept != modes.S_H else max(self.step.tolerance, self.hand_give)
        moved = (
            coordinates is not None
            and self.use_estimate
            and kept is not None
            and (kept != modes.S_H or self.goal is not None)
            and abs(coordinates[kept] - self.command.start[kept]) > limit
        )
        return self._lasted("slipped", moved, now, LOST_TIME)

    def _lost(self, now: float, coordinates: np.ndarray | None) -> bool:
        """Whether the estimate this step measures its progress on has been unusable for
        :data:`LOST_TIME` (the estimator released what it could no longer tell, e.g. which contact
        slid): the step cannot be judged, so a goal's motion ends and its planner explores again."""
        return self._lasted("lost", coordinates is None and self.use_estimate, now, LOST_TIME)

    def _started(self, coordinates: np.ndarray | None) -> bool:
        """Whether a slide has moved its coordinate the commanded way by the slide onset (other
        motions count as started)."""
        step, command = self.step, self.command
        if step.motion not in modes.SLIDES or coordinates is None:
            return True
        k = step.coordinate
        return (coordinates[k] - command.start[k]) * math.copysign(1.0, step.delta) >= self.slide_onset


    def _overshot(self, coordinates: np.ndarray | None) -> bool:
        """Whether a slide has gone past its target by more than its tolerance: its command cannot
        bring it back (the row that would is kept), so the next step's must stop it. A "slide"
        shorter than the controller's slide onset never frees its coordinate: it regulates it
        (e.g. against a push) and ends at its timeout."""
        k, step = self.step.coordinate, self.step
        if coordinates is None or step.motion not in modes.SLIDES or abs(step.delta) < self.slide_onset:
            return False
        return (coordinates[k] - self.command.targets[k]) * math.copysign(1.0, step.delta) > step.tolerance


def plant_controls(params: ControllerParams, plant: Plant) -> ControllerParams:
    """``params`` as the loop runs them on ``plant``: the impedance target's angular speed capped at
    its :attr:`~ccopt.plant.base.Plant.hand_turn_rate` (rad/s; the whole step is scaled to it, so a
    pivot keeps the direction that balances its wrench) and at least its
    :attr:`~ccopt.plant.base.Plant.force_headroom` (N) below the hand's largest force."""
    normal, tangential, angular = params.max_speed
    return dataclasses.replace(
        params,
        max_speed=(normal, tangential, min(angular, plant.hand_turn_rate)),
        force_headroom=max(params.force_headroom, plant.force_headroom),
    )


NO_TILTS = (math.inf, -math.inf)
"""An empty range of tilts (:attr:`_StepTracker.held_tilts`)."""
ROLL_RELEASE = 0.02
"""N·m: a pivot's target, held from the first sample its torque row is tight (within ``pivot_margin``,
:attr:`_StepTracker.rolling`), holds until the row's margin exceeds ``pivot_margin`` by this much.
The margin ``l_h f_n ∓ τ`` of the default sensors has a noise of about 0.01 N·m (0.005 N·m of
torque, 0.3 N of force on a 0.03 m lever), as much as ``pivot_margin`` itself: where the object
lies on a face and the hand presses on, the margin hovers about zero (−0.08 to +0.01 N·m on the
paper rectangle landing from 2° after a hand slide) and single samples above ``pivot_margin``
released the target, which stepped 0.3–0.5° at each release and turned the hand 2.5° against the
object; the pivot back turned it 2.2° more and was ``reached`` 1.35° short by the truth. Released
two noise deviations clear, the landing turned it 1.8° and the pivot back 1.1°. Only the hold: the
pivot still ends ``rolled`` on a row tight on every sample for :data:`ROLL_TIME`. Counting the
samples under this release as tight as well ended pivots that were still turning their object
(random objects, the goals study: a −7.2° pivot ended ``rolled`` 1.1° short with the hand truly
flush, and the tilt limit it set cut the planner's reach at 15°). Paper goals, 7 planar cases ×
3 seeds: unintended slips 4 → 2, goals reached outside their tolerance 1 → 0, goals reached
193 → 191; goals study (seeds 0, 1): oracle-reachable goals reached 118/124 and 94/107 either way.
The Panda triangle and square (2 seeds each) run the same."""
ROLL_TIME = 0.15
"""s: a goal's motion or an exploration step whose hand the estimate sees off flush this long ends
``rolled`` (a pivot: its torque at the hand's limit the other way on every sample; a flush pivot's
hand is classified flush, while the paper square pressed flat on its face rolled the hand within
0.1 s of the tilt where it landed; a ground slide of the paper triangle
tried at 2.7° with a bold ``μ_h`` kept its hand on the face's end for 2.5 s, then rolled it and
slid it 10 mm, which the kinematics read as the ground sliding). Meanwhile the target of a slide,
and of a goal's pivot, holds still (:attr:`_StepTracker.rolling`): pushed on, a hand that rolled on
the paper pentagon's face in a hand slide ran 4.5 mm along it on its edge before the roll was
confirmed, and a goal's pivot that landed the paper square or rectangle on a face (at 30°/s) turned
the hand 5.3–5.7° against it, the pivot back within the limit as much again (with the target held:
1.5–1.9° and 0.6–1.7°, under the 2° the metrics count as a slip). Not an exploration's pivot: it
may begin with the torque at the hand's limit (the controller pivots about a guessed point until
the kinematics are known), and held there the hand kept pressing towards the target ahead of it
until the pivot ended ``rolled`` with the object still turning (random tours at the bar: 27 → 15
of 50). An exploration's hand-slide probe the torque limit stops before the hand slides ends so too
(:func:`ccopt.schedule.exploration`): without it, the probe of a small heavy random triangle pushed
for its whole 3 s timeout and rolled the hand 2.3° against the object. A schedule's other motions,
which the truth scores, do not end ``rolled``: the report is conservative (a torque near the hand's
limit reads as maybe rolling), and ending them so cut the robustness tours' successes from 30 to 15
of 50, mostly slides the truth saw through without a slip."""
_ROLL_REASONS = {
    "pivot": "the hand rolled: the object stopped pivoting",
    "slide_hand": "the hand rolled (or was about to) on the face's end instead of sliding",
    "slide_ground": "the hand rolled (or was about to) on the face's end instead of sliding the object",
}
_SLIPPED_REASONS = {
    "slide_hand": "the ground slid instead of the hand",
    "slide_ground": "the hand slid instead of the ground",
}
LOST_TIME = 0.1
"""s: a goal's motion whose progress estimate has been unusable this long ends ``lost``."""
SLIDE_START_TIME = 3.0
"""A goal's planned slide that has not started after this long (s) ends: where the estimated statics
were too hopeful (a ground row never slid past is estimated inside the true one), the planner
tries elsewhere rather than push for the motion's whole timeout."""


RUN_STATUSES = ("completed", "interrupted", "contact_lost", "sensor_fault", "timeout", "error")
"""How a run can end: its schedule ran to the end; Ctrl-C or a signal; the hand lost the object and
could not find it again; a sensor stopped telling the truth; the run's time limit; an exception."""


@dataclass(frozen=True)
class Supervision:
    """When a run stops by itself, and what it tries first. Times in s, lengths in m, forces in N.

    Attributes:
        contact_force: the hand touches the object while the measured ``f_n`` exceeds this.
        contact_grace: contact may be missing this long (a bounce, a dropout, a knock) before the
            loop acts. Held on one vertex by the hand alone, an object the hand has let go of for
            longer may have fallen, and the estimate cannot tell where it went: the loop presses to
            find it, and the run stops ``contact_lost`` once it has (or has not within
            ``recontact_distance``). Measured on 160 goals-study trials: dropouts in hand slides
            last at most 30 ms; objects that fell lost the hand for 110–530 ms, and went on being
            claimed reached 38–60 mm off. A 13 N push on the paper triangle lifts it off the hand
            for 90 ms, and the loop turns it back within a degree; a 13 N push on another noise
            seed lost it for 80 ms and turned it 19°, which the grace lets through.
        recontact_speed: speed of the target along ``e_n`` while the loop presses to find the object.
        recontact_distance: how far past the pose where contact was lost it presses before giving up.
        time_factor: a run's time limit is this times the sum of its steps' timeouts (the schedule's
            own worst case), at least ``min_time``.
        min_time: the smallest time limit.
        max_time: a time limit given outright (s of simulated time), None for the one above.
        health_tolerance, health_hold: the force disagreement (N) between the F/T sensor and the
            impedance that a run tolerates, and for how long (s), before it is a sensor fault
            (:mod:`ccopt.health`). None: the plant's own
            (:attr:`~ccopt.plant.base.Plant.force_model_error`, what its fault-free runs reach).
        solver_grace: the QP solver may give no finite step this long in a row (the target holds)
            before the run ends with status ``error``.
    """

    contact_force: float = 1.0
    contact_grace: float = 0.1
    recontact_speed: float = 0.01
    recontact_distance: float = 0.02
    time_factor: float = 1.5
    min_time: float = 10.0
    health_tolerance: float | None = None
    health_hold: float = 0.1
    solver_grace: float = 0.2
    max_time: float | None = None

    def __post_init__(self) -> None:
        names = ("contact_force", "contact_grace", "recontact_speed", "recontact_distance")
        for name in (*names, "time_factor", "min_time", "health_hold", "solver_grace"):
            validation.positive(name, getattr(self, name))
        if self.health_tolerance is not None:
            validation.positive("health_tolerance", self.health_tolerance)
        if self.max_time is not None and not 0.0 < validation.real("max_time", self.max_time) <= 1e6:
            raise ValueError(f"max_time must be in (0, 1e6] s, got {self.max_time!r}")

    def health(self, hand: Hand, force_model_error: float) -> HealthParams:
        """The sensor-health check of a run with ``hand`` on a plant whose force strays up to
        ``force_model_error`` (N) from its impedance: that impedance, and a force disagreement
        tolerated up to ``health_tolerance`` (the plant's if None) for ``health_hold`` (s)."""
        tolerance = force_model_error if self.health_tolerance is None else self.health_tolerance
        return HealthParams.from_impedance(
            hand.stiffness, hand.damping, force_tolerance=tolerance, hold=self.health_hold
        )

    def time_limit(self, schedule: Schedule) -> float:
        """The simulated time after which a run of ``schedule`` ends with status ``timeout``."""
        if self.max_time is not None:
            return self.max_time
        return max(self.min_time, self.time_factor * sum(step.timeout for step in schedule.steps))


def run(
    obj: PlanarObject,
    schedule: Schedule,
    params: LoopParams | None = None,
    seed: int = 0,
    out: str | Path | None = None,
    meta: dict[str, object] | None = None,
    on_tick: Callable[[float, int, int], None] | None = None,
) -> RunResult:
    """Run ``schedule`` on ``obj`` in closed loop; record to ``out`` if given.

    ``on_tick(sim_time, step_index, n_steps)`` is called at every control tick (progress bars).
    The run ends when the schedule does, or early with a status (:data:`RUN_STATUSES`): Ctrl-C
    (``KeyboardInterrupt``) gives ``interrupted``; a lost object the loop cannot find again gives
    ``contact_lost``, a sensor fault (:mod:`ccopt.health`) ``sensor_fault``, the run's time limit
    ``timeout`` — each with the impedance target held where the hand is — and an exception inside the
    loop ``error`` with its one-line message. The record is closed with that status in every case.
    Ctrl-C while the run is being set up waits until the set-up is done (:func:`ccopt.stops.stops_held`)
    and then raises ``KeyboardInterrupt``, before the first sample: the record is left ``running``
    with no sample (:func:`ccopt.record.discard_unstarted` removes it). So does Ctrl-C in the loop
    before its first sample is recorded: a run with nothing recorded did not begin. A stop signal
    whose interrupt CasADi dropped is acted on all the same, at the next control tick
    (:func:`ccopt.stops.stop_requested`).
    """
    with stops_held():  # building the plant loads libraries that an interrupt would break
        loop = _Loop(obj, schedule, params or LoopParams(), seed, out, meta, on_tick)
    if stop_requested():  # before the set-up, where CasADi dropped the interrupt
        raise KeyboardInterrupt
    return loop.run()


class _Loop:
    """One closed-loop run: the plant, its sensors, the estimator, the controller and the supervision."""

    def __init__(self, obj, schedule, params, seed, out, meta, on_tick) -> None:
        self.params = params
        self.schedule = schedule
        self.plant = make_plant(obj, params)
        self.sensors = Sensors(self.plant, params.sensor_params, seed)
        self.estimator = Estimator(params.hand, params.estimator_params)
        controls = plant_controls(params.controller_params, self.plant)
        self.controller = Controller(params.hand, params.control_period, controls)
        p = controls
        self.goal = TargetGoal(
            params.hand.force_limits, p.normal_force, p.statics_margin, p.friction_step, p.slide_beyond,
            p.force_headroom,
        )
        self.health = SensorHealth(params.supervision.health(params.hand, self.plant.force_model_error))
        self.writer = RecordWriter(out, meta or {}) if out is not None else None
        self.folder = Path(out) if out is not None else None
        self.on_tick = on_tick
        self.samples: dict[str, list[np.ndarray]] = {}
        self.tracker = _StepTracker(
            schedule,
            params.settle_time,
            params.controller_params.slide_onset,
            params.estimator_params.modes.pivot_margin,
            params.estimator_params.kinematics.hand_slide_travel,
            self._sequencer,
        )
        self.target = np.array(self.plant.target(), dtype=float)
        self.velocity = np.zeros(3)
        self.target_angles = tuple(self.plant.target_angle_range)
        self.target_held = 0
        """Plant steps whose target the robot's reach held (:meth:`_advance_plant`)."""
        self.timestep = self.plant.timestep
        self.now = self.plant.time
        """The plant's time after its last step, s."""
        self.pending = list(params.perturbations)
        self.last_solution: tuple[float, bool] = (0.0, True)
        self.statics_period = params.ticks(params.statics_hz) * params.plant_params.timestep
        self.last_aim: tuple[float, StaticsTarget] | None = None  # (time, target)
        self.sensed = 0  # estimator samples so far
        self.record_stride = params.record_stride
        self.estimate: Estimate | None = None
        self.last_usable: Estimate | None = None
        self.tilt_limits: dict[int, float] = {}
        """The tilts past which the goals' pivots rolled the hand (:class:`GoalSequencer`)."""
        self.hand_pose: np.ndarray | None = None
        self.lost_since: float | None = None
        self.lost_pose: np.ndarray | None = None
        self.unsolved_since: float | None = None
        """When the QP solver last began to give no finite step (None while it gives one)."""
        self.status = "completed"
        self.message = ""

    def _sequencer(self, index: int, goal: Goal, now: float) -> GoalSequencer:
        return GoalSequencer(
            index,
            goal,
            now,
            self.plant.hand_angle_range,
            self.goal,
            PlannerParams(),
            self.tilt_limits,
            self.params.estimator_params.kinematics.split_tilt,
        )

    def run(self) -> RunResult:
        start = wallclock.perf_counter()
        limit = self.params.supervision.time_limit(self.schedule)
        estimator_every = self.params.ticks(self.params.estimator_hz)
        controller_every = self.params.ticks(self.params.controller_hz)
        tick = 0
        try:
            while not self.tracker.done and self.status == "completed":
                tick += 1
                self._advance_plant()
                if tick % estimator_every == 0 or self.estimate is None:
                    self._sense()
                if self.status != "completed":
                    break
                if tick % controller_every == 0:
                    if stop_requested():  # CasADi may have dropped the signal's interrupt
                        raise KeyboardInterrupt
                    self._control()
                if self.now >= limit:
                    self._stop("timeout", f"the run's time limit of {limit:g} s (simulated) ran out")
        except KeyboardInterrupt:
            if not self._recorded():  # stopped before its first sample: as if while starting
                raise
            self.status, self.message = "interrupted", "interrupted"
        except Exception as error:
            self.status, self.message = "error", f"{type(error).__name__}: {error}".splitlines()[0]
        return self._finish(wallclock.perf_counter() - start)

    def _advance_plant(self) -> None:
        plant, dt = self.plant, self.timestep
        (x, y, theta), (v_x, v_y, v_theta) = self.target.tolist(), self.velocity.tolist()
        theta += v_theta * dt
        low, high = self.target_angles
        if not low <= theta <= high:  # the robot's reach holds the target's turn at its end
            theta = low if theta < low else high
            self.velocity[2] = 0.0
            self.target_held += 1
        self.target[:] = (x + v_x * dt, y + v_y * dt, theta)  # the ramp, in floats
        plant.set_target(self.target, self.velocity, check=False)  # finite (Controller.update's steps are)
        while self.pending and plant.time >= self.pending[0].time:
            push = self.pending.pop(0)
            plant.push_object(push.force, push.duration)
        plant.step(1)
        self.now = plant.time

    def _sense(self) -> None:
        reading = self.sensors.read()
        time, pose, wrench = reading.time, reading.hand_pose, reading.hand_wrench
        self.estimate = self.estimator.update(time, pose, wrench, self.tracker.configuration)
        if self.estimate.kinematics_valid:
            self.last_usable = self.estimate
        self.hand_pose = pose if all(map(math.isfinite, pose.tolist())) else None
        if self._lost():  # a dropout: the target holds still from this reading on, not from the next
            self.velocity[:] = 0.0  # control tick (up to a control period of ramping on the last step)
        if self.sensed % self.record_stride == 0:
            self._record(reading)
        self.sensed += 1
        health = self.health.update(time, pose, wrench, self.target)
        if not health.ok:
            self._stop("sensor_fault", health.message)

    def _recorded(self) -> bool:
        """Whether the run has recorded a sample yet (to its folder, or in memory)."""
        return self.writer.samples > 0 if self.writer is not None else bool(self.samples)

    def _lost(self) -> bool:
        """Whether the last reading was lost: no finite hand pose, or a sample the estimator skipped."""
        return self.hand_pose is None or self.estimate.skipped

    def _record(self, reading: Measurement) -> None:
        """One record sample: this reading, the estimate, the command and the truth."""
        sample = _sample(self.plant, reading, self.estimate, self.target, self.tracker, *self.last_solution)
        if self.writer is not None:
            self.writer.append(sample)
        else:
            for key, value in sample.items():
                self.samples.setdefault(key, []).append(np.asarray(value))

    def _control(self) -> None:
        if self._lost():  # a dropout: the target holds still (:meth:`_sense` stopped it)
            return
        if self._contact_lost():
            return
        tracker, estimate, hand_pose = self.tracker, self.estimate, self.hand_pose
        coordinates = tracker.update(self.now, estimate, hand_pose)
        if tracker.done:
            return
        held = tracker.step.motion in modes.SLIDES or not tracker.step.explore or tracker.use_estimate
        if tracker.rolling and held:
            self.velocity = np.zeros(3)  # pushed on, the hand would roll on (ROLL_TIME)
            return
        if coordinates is None:  # the estimate is unusable: hold where the command says
            coordinates = tracker.command.targets
        aim = self._aim(estimate, hand_pose)
        if tracker.fresh and tracker.step.kind != "hold":
            reason = self._ruled_out(aim, estimate, hand_pose)
            if reason:
                tracker.advance(self.now, estimate, hand_pose, "infeasible", reason)
                return
        tracker.fresh = False
        output = self.controller.update(control_input(estimate, hand_pose, coordinates, aim), tracker.command)
        self.last_solution = (output.solution.slack, output.solution.feasible)
        step = geometry.twist_hand_to_world(float(hand_pose[2]), output.step)
        self.velocity = step / self.controller.period
        self._check_solved(not output.solved)
        if self.on_tick is not None:
            self.on_tick(self.now, tracker.index, len(self.schedule.steps))

    def _check_solved(self, failed: bool) -> None:
        """End the run (``error``) once the QP solver has given no finite step for ``solver_grace``:
        the controller holds the target on such a tick (:meth:`Controller.update`), which would
        otherwise go on until the time limit."""
        now = self.now
        if not failed:
            self.unsolved_since = None
        elif self.unsolved_since is None:
            self.unsolved_since = now
        elif now - self.unsolved_since >= self.params.supervision.solver_grace:
            self._stop("error", f"the QP solver gave no finite step from t = {self.unsolved_since:.2f} s on")

    def _aim(self, estimate: Estimate, hand_pose: np.ndarray) -> StaticsTarget:
        """The estimated statics' target of the command: evaluated afresh at a step's start and once
        a statics period (:attr:`LoopParams.statics_hz`) has passed, else the last one."""
        now, last = self.now, self.last_aim
        if self.tracker.fresh or last is None or clock.lasted(now, last[0], self.statics_period):
            motion, tracker = self.tracker.command.motion, self.tracker
            planned = tracker.goal is not None and not tracker.step.explore
            self.last_aim = (now, statics_target(estimate, float(hand_pose[2]), motion, self.goal, planned))
        return self.last_aim[1]

    def _ruled_out(self, aim: StaticsTarget, estimate: Estimate, hand_pose: np.ndarray) -> str:
        """Why the step just begun is not to be forced ("" if it is): beyond the robot's reach, or
        ruled out by the estimated statics."""
        step, low_high = self.tracker.step, self.plant.hand_angle_range
        if step.kind == "pivot":
            end = float(hand_pose[2]) + step.delta
            if not low_high[0] <= end <= low_high[1]:
                low, high, to = (math.degrees(a) for a in (*low_high, end))
                return f"beyond the robot's reach: θ_h {to:.1f}° not in [{low:.1f}°, {high:.1f}°]"
        if aim.margin < -self.params.controller_params.infeasible_margin:
            return _ruled_out(aim, estimate)
        return ""

    def _contact_lost(self) -> bool:
        """Whether the hand has lost the object: after a grace time the target presses along ``e_n``
        to find it again, and the run stops once it has (or has not after ``recontact_distance``):
        held on one vertex by the hand alone, the object was free meanwhile (:class:`Supervision`)."""
        rules, now = self.params.supervision, self.now
        touching = self.estimate.wrench[0] > rules.contact_force
        if touching and self.lost_since is not None and now - self.lost_since >= rules.contact_grace:
            self._stop("contact_lost", f"the hand lost the object at t = {self.lost_since:.2f} s for "
                       f"{1e3 * (now - self.lost_since):.0f} ms: left free on a vertex, it may have "
                       "fallen, and the estimate no longer knows where it lies")
            return True
        if touching:
            self.lost_since = self.lost_pose = None
            return False
        if self.lost_since is None:
            self.lost_since, self.lost_pose = now, self.hand_pose.copy()
        if now - self.lost_since < rules.contact_grace:
            return False
        travelled = float(np.linalg.norm(self.hand_pose[:2] - self.lost_pose[:2]))
        if travelled > rules.recontact_distance:
            self._stop("contact_lost", f"the hand lost the object at t = {self.lost_since:.2f} s and did "
                       f"not find it again within {1e3 * rules.recontact_distance:.0f} mm")
            return True
        press = geometry.hand_normal(float(self.hand_pose[2])) * rules.recontact_speed
        self.velocity = np.array([press[0], press[1], 0.0])
        return True

    def _stop(self, status: str, message: str) -> None:
        """End the run with ``status``, the impedance target held where the hand is."""
        self.status, self.message = status, message
        self.velocity = np.zeros(3)
        if self.hand_pose is not None:
            self.target = np.array(self.hand_pose, dtype=float)
            self.plant.set_target(self.target, self.velocity)

    def _finish(self, wall: float) -> RunResult:
        tracker, now = self.tracker, self.plant.time
        why = f"the run ended: {self.status}{': ' + self.message if self.message else ''}"
        if tracker.goal is not None:  # the run ended inside a goal
            tracker.goal_results.append(tracker.goal.end(now, "failed", why))
            tracker.goal = None
        for index in range(max(tracker.index + 1, 0), len(tracker.steps)):  # goals it never began
            item = tracker.steps[index]
            if isinstance(item, Goal):
                tracker.goal_results.append(GoalResult(index, item, now, now, "failed", f"not begun: {why}"))
        result = RunResult(
            steps=tuple(self.tracker.results),
            samples={key: np.stack(values) for key, values in self.samples.items()},
            sim_time=self.plant.time,
            wall_time=wall,
            status=self.status,
            message=self.message,
            folder=self.folder,
            goals=tuple(tracker.goal_results),
            hand_angle_range=tuple(self.plant.hand_angle_range),
            target_at_reach=self.target_held * self.timestep,
            force_headroom=self.goal.headroom,
            last_usable=self.last_usable,
        )
        if self.writer is not None:
            self.writer.meta["steps"] = [step.as_dict() for step in result.steps]
            self.writer.meta["goals"] = [goal.as_dict() for goal in result.goals]
            self.writer.meta["message"] = self.message
            self.writer.close(status=self.status)
        return result


def _ruled_out(aim: StaticsTarget, estimate: Estimate) -> str:
    """Why the estimated statics rule a step out, in one line (degrees, millimetres, newtons)."""
    margin = "no wrench at all" if math.isinf(aim.margin) else f"best margin {aim.margin:.1f} N"
    return (
        f"ruled out by the estimated statics: {margin} at θ̂_o {math.degrees(estimate.theta_o):.1f}°, "
        f"ŝ_h {1e3 * estimate.s_h:.1f} mm (μ̂_h {estimate.mu_h:.2f})"
    )


def _sample(plant, measurement, estimate, target, tracker, slack, feasible) -> dict[str, np.ndarray]:
    truth = plant.truth()
    command = tracker.command
    return {
        "time": np.float64(measurement.time),
        "hand_pose": measurement.hand_pose,
        "hand_wrench": measurement.hand_wrench,
        "target": target.copy(),
        "est_coordinates": np.array([estimate.theta_o, estimate.s_h, estimate.s_g]),
        "est_d": np.float64(estimate.d),
        "est_kinematics_valid": np.bool_(estimate.kinematics_valid),
        "est_mu_h": np.float64(estimate.mu_h),
        "est_face": np.array(estimate.face),
        "est_ground_rows": estimate.ground_rows,
        "est_ground_bounds": estimate.ground_bounds,
        "est_modes": np.array([estimate.hand_mode, estimate.hand_geometry, estimate.ground_mode], np.int8),
        "step_index": np.int16(tracker.index),
        "motion": np.int8(MOTION_CODES[tracker.step.kind] if not tracker.done and tracker.index >= 0 else 0),
        "command_targets": command.targets.copy() if command is not None else np.full(3, np.nan),
        "qp_slack": np.float64(slack),
        "qp_feasible": np.bool_(feasible),
        "true_coordinates": np.array([truth.theta_o, truth.s_h, truth.s_g]),
        "true_d": np.float64(truth.d),
        "true_modes": np.array([truth.hand_mode, truth.hand_geometry, truth.ground_mode], np.int8),
        "true_contacts": np.array([truth.in_contact_hand, truth.in_contact_ground]),
        "true_slip_rates": np.array([truth.hand_slip_rate, truth.ground_slip_rate]),
        "true_hand_pose": plant.hand_pose(),
        "true_hand_wrench": plant.hand_wrench(),
    }
