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
import time as wallclock
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING, Literal

import numpy as np

from ccopt import geometry, validation
from ccopt.control.controller import Command, ControlInput, Controller, ControllerParams
from ccopt.control.targets import UNJUDGED, StaticsTarget, statics_target
from ccopt.estimation.estimator import Estimate, Estimator, EstimatorParams
from ccopt.hand import Hand
from ccopt.modes import MOTION_CODES
from ccopt.objects import PlanarObject
from ccopt.plant.base import Plant, PlantParams, StartConfig
from ccopt.plant.placement import hand_over_vertex
from ccopt.plant.sensors import SensorParams, Sensors
from ccopt.record import RecordWriter
from ccopt.schedule import Schedule, Step

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
    ``panda`` holds the Panda plant's own settings (None: its defaults). Rates in Hz.
    """

    plant: PlantKind = "planar"
    estimator_hz: float = 100.0
    controller_hz: float = 30.0
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
        for name in ("estimator_hz", "controller_hz"):
            rate = getattr(self, name)
            if not (np.isfinite(rate) and 0.0 < rate <= top):
                raise ValueError(f"{name} must be in (0, {top:g}] Hz, got {rate!r}")
        self.controller_params.check_hand(self.hand)

    def ticks(self, rate: float) -> int:
        """Plant steps per period of a loop running at ``rate`` Hz (at least 1)."""
        return max(1, round(1.0 / (rate * self.plant_params.timestep)))

    @property
    def control_period(self) -> float:
        """The controller's actual period, s (a whole number of plant steps)."""
        return self.ticks(self.controller_hz) * self.plant_params.timestep


STEP_STATUSES = ("reached", "timeout", "infeasible")
"""How a step can end: its coordinate settled within tolerance (by the estimate), its time ran out,
or the estimated statics ruled it out."""


@dataclass(frozen=True)
class StepResult:
    """How one schedule step went, by the estimate (truth is scored in :mod:`ccopt.metrics`)."""

    index: int
    kind: str
    delta: float
    start_time: float
    end_time: float
    status: str

    @property
    def reached(self) -> bool:
        return self.status == "reached"

    def as_dict(self) -> dict[str, object]:
        """The result as ``meta.json`` stores it (with ``reached``)."""
        return {**dataclasses.asdict(self), "reached": self.reached}


@dataclass(frozen=True)
class RunResult:
    """What a run returns; the full time series is in the record folder (or ``samples``)."""

    steps: tuple[StepResult, ...]
    samples: dict[str, np.ndarray]
    sim_time: float
    wall_time: float
    interrupted: bool
    folder: Path | None


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


_FROM_ESTIMATE = ("wrench", "cone_rows", "cone_bounds", "row_valid", "mu_h", "s_h", "d")
"""The fields a :class:`ControlInput` takes from the :class:`Estimate` as they are."""


def control_input(
    estimate: Estimate, hand_pose: np.ndarray, coordinates: np.ndarray, target: StaticsTarget = UNJUDGED
) -> ControlInput:
    """What the controller reads from an estimate, the measured hand pose, the progress source and the
    estimated statics' target."""
    return ControlInput(
        **{name: getattr(estimate, name) for name in _FROM_ESTIMATE},
        l_h=estimate.torque_lever,
        hand_angle=float(hand_pose[2]),
        kinematics_valid=kinematics_usable(estimate),
        coordinates=coordinates,
        force_target=target.force,
        tangential_target=target.tangential,
        statics_margin=target.margin if target.force is not None else None,
    )


def kinematics_usable(estimate: Estimate) -> bool:
    """Valid and finite: an estimate flagged valid with NaN coordinates is treated as unknown."""
    values = (estimate.theta_o, estimate.s_h, estimate.s_g, estimate.d)
    return bool(estimate.kinematics_valid) and all(np.isfinite(values))


def hand_proxy(hand_pose: np.ndarray) -> np.ndarray:
    """Coordinates that change like ``(θ_o, s_h, s_g)`` while the commanded configuration holds."""
    x_h, y_h, theta_h = hand_pose
    return np.array([theta_h, -np.dot([x_h, y_h], geometry.hand_tangent(theta_h)), x_h])


class _StepTracker:
    """Walks the schedule: the current command, its progress source, completion and timeout.

    Targets chain from the *nominal* configuration: after a reached step the next one starts from
    where the previous one was commanded to end, not from where it stopped inside its tolerance, so
    that small shortfalls do not add up; after a step that was not reached, or when the source of
    progress changes (hand proxy → estimate), the nominal configuration is re-read. A step is reached
    once its coordinate has stayed within tolerance for ``settle_time``; never on an unusable estimate.
    """

    def __init__(self, schedule: Schedule, settle_time: float) -> None:
        self.steps = schedule.steps
        self.settle_time = settle_time
        self.index = -1
        self.results: list[StepResult] = []
        self.use_estimate = False
        self.command: Command | None = None
        self.start_time = 0.0
        self._nominal: np.ndarray | None = None
        self._within_since: float | None = None

    @property
    def step(self) -> Step:
        return self.steps[self.index]

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

    def advance(self, now: float, estimate: Estimate, hand_pose: np.ndarray, status: str) -> None:
        if self.index >= 0:
            self.results.append(
                StepResult(self.index, self.step.kind, self.step.delta, self.start_time, now, status)
            )
        self.index += 1
        if self.done:
            return
        use_estimate = kinematics_usable(estimate)
        if use_estimate != self.use_estimate or status != "reached":
            self._nominal = None
        self.use_estimate = use_estimate
        current = self.coordinates(estimate, hand_pose)
        if self._nominal is None:
            self._nominal = current.copy()
        targets = self._nominal.copy()
        if self.step.coordinate is not None:
            targets[self.step.coordinate] += self.step.delta
        self._nominal = targets.copy()
        self.command = Command(self.step.motion, targets, start=current, wrench=np.array(estimate.wrench))
        self.start_time = now
        self._within_since = None

    def update(self, now: float, estimate: Estimate, hand_pose: np.ndarray) -> None:
        """Move to the next step when this one is reached or timed out."""
        if self.index < 0:
            self.advance(now, estimate, hand_pose, "reached")
            return
        elapsed = now - self.start_time
        if self.step.kind == "hold":
            if elapsed >= self.step.timeout:
                self.advance(now, estimate, hand_pose, "reached")
            return
        k = self.step.coordinate
        coordinates = self.coordinates(estimate, hand_pose)
        tolerance = self.step.tolerance
        within = coordinates is not None and abs(self.command.targets[k] - coordinates[k]) <= tolerance
        if not within:
            self._within_since = None
        elif self._within_since is None:
            self._within_since = now
        if within and now - self._within_since >= self.settle_time - 1e-9:
            self.advance(now, estimate, hand_pose, "reached")
        elif elapsed >= self.step.timeout:
            self.advance(now, estimate, hand_pose, "timeout")


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
    Ctrl-C ends the run early: the record is closed with status ``interrupted`` and the result says so.
    """
    params = params or LoopParams()
    plant = make_plant(obj, params)
    sensors = Sensors(plant, params.sensor_params, seed)
    estimator = Estimator(params.hand, params.estimator_params)
    controller = Controller(params.hand, params.control_period, params.controller_params)
    writer = RecordWriter(out, meta or {}) if out is not None else None
    samples: dict[str, list[np.ndarray]] = {}
    tracker = _StepTracker(schedule, params.settle_time)
    dt = plant.timestep
    estimator_every = params.ticks(params.estimator_hz)
    controller_every = params.ticks(params.controller_hz)
    target = np.array(plant.target(), dtype=float)
    velocity = np.zeros(3)
    pending = list(params.perturbations)
    last_slack, last_feasible = 0.0, True
    estimate: Estimate | None = None
    start_wall = wallclock.perf_counter()
    interrupted = False
    tick = 0
    try:
        while not tracker.done:
            tick += 1
            target = target + velocity * dt
            plant.set_target(target, velocity)
            while pending and plant.time >= pending[0].time:
                push = pending.pop(0)
                plant.push_object(push.force, push.duration)
            plant.step(1)
            if tick % estimator_every == 0 or estimate is None:
                measurement = sensors.read()
                estimate = estimator.update(measurement.time, measurement.hand_pose, measurement.hand_wrench)
                hand_pose = measurement.hand_pose if np.all(np.isfinite(measurement.hand_pose)) else None
                sample = _sample(plant, measurement, estimate, target, tracker, last_slack, last_feasible)
                if writer is not None:
                    writer.append(sample)
                else:
                    for key, value in sample.items():
                        samples.setdefault(key, []).append(np.asarray(value))
            if tick % controller_every == 0 and hand_pose is not None:
                tracker.update(plant.time, estimate, hand_pose)
                if tracker.done:
                    break
                coordinates = tracker.coordinates(estimate, hand_pose)
                if coordinates is None:  # the estimate is unusable: hold where the command says
                    coordinates = tracker.command.targets
                p = params.controller_params
                aim = statics_target(
                    estimate, float(hand_pose[2]), tracker.command.motion, params.hand.force_limits,
                    p.normal_force, p.statics_margin,
                )
                state = control_input(estimate, hand_pose, coordinates, aim)
                output = controller.update(state, tracker.command)
                last_slack, last_feasible = output.solution.slack, output.solution.feasible
                velocity = geometry.twist_hand_to_world(hand_pose[2], output.step) / controller.period
                if on_tick is not None:
                    on_tick(plant.time, tracker.index, len(schedule.steps))
    except KeyboardInterrupt:
        interrupted = True
    wall = wallclock.perf_counter() - start_wall
    result = RunResult(
        steps=tuple(tracker.results),
        samples={key: np.stack(values) for key, values in samples.items()},
        sim_time=plant.time,
        wall_time=wall,
        interrupted=interrupted,
        folder=Path(out) if out is not None else None,
    )
    if writer is not None:
        writer.meta["steps"] = [step.as_dict() for step in result.steps]
        writer.close(status="interrupted" if interrupted else "completed")
    return result


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
