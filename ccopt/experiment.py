"""One scored run: object + schedule + parameters + seed (+ folder) → record, meta and summary.

This is what ``ccopt run``, the paper study and the robustness study all do, with one set of
metadata keys:

1. the experimenter's check of the schedule on the *true* object (:func:`ccopt.statics.schedule_feasibility`:
   which steps no controller could do; the estimator and the controller never see it);
2. the closed loop (:func:`ccopt.closed_loop.run`), recorded to ``folder`` if one is given;
3. the score against the simulator's truth (:func:`ccopt.metrics.summarize`), with the steps the
   oracle found impossible (``impossible_steps``) and how often the kinematics were lost
   (``kinematics_resets``), written to ``summary.json``.

``meta.json`` holds the run's settings (``object``, ``schedule``, ``seed``, ``params``: the form
:mod:`ccopt.config` reads, so ``ccopt run --config RUN_DIR/meta.json`` repeats the run), ``units``,
``record_units`` (every array of ``record.npz``: its unit and frame) and ``feasibility`` (the oracle's
check of every step); the loop adds ``steps`` and ``status``.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import asdict, dataclass
from pathlib import Path

import numpy as np

from ccopt import closed_loop, config, feasibility_map, metrics, statics
from ccopt.closed_loop import LoopParams, RunResult
from ccopt.feasibility_map import FeasibilityMap
from ccopt.objects import PlanarObject
from ccopt.planning.planner import PlannerParams, oracle_plan
from ccopt.planning.sequencer import TIPPING_CLEARANCE, GoalResult
from ccopt.planning.tour import Tour, plan_tour, vertex_range
from ccopt.plant.base import StartConfig
from ccopt.record import load_record, write_summary
from ccopt.schedule import Schedule
from ccopt.stops import stops_held


@dataclass(frozen=True)
class Experiment:
    """A scored run.

    Attributes:
        result: what the closed loop returned (its samples are empty when recorded to a folder).
        meta: the run's ``meta.json`` content as written before the run.
        summary: the run's ``summary.json`` content.
        feasibility: the oracle's check of every step (:class:`ccopt.statics.StepFeasibility`).
        folder: the run folder, None for an in-memory run.
        feasibility_map: the run's feasibility maps (:mod:`ccopt.feasibility_map`), computed for a
            run recorded to a folder (``feasibility_map.npz``), else None.
    """

    result: RunResult
    meta: dict[str, object]
    summary: dict[str, object]
    feasibility: tuple[statics.StepFeasibility, ...]
    folder: Path | None
    feasibility_map: FeasibilityMap | None = None


RECORD_UNITS = {
    "time": "s",
    "hand_pose": "measured hand pose (x_h, y_h, θ_h): m, m, rad, world",
    "hand_wrench": "measured hand wrench (f_n, f_t, τ) on the object: N, N, N·m, hand frame",
    "target": "impedance target (x, y, θ): m, m, rad, world",
    "est_coordinates": "estimated (θ_o, s_h, s_g): rad, m, m",
    "est_d": "estimated d (ground contact to hand face along e_n): m",
    "est_kinematics_valid": "bool: the kinematics are estimated",
    "est_mu_h": "estimated hand friction coefficient (NaN: not yet)",
    "est_face": "known face (u_low, u_high): m along e_t from the ground contact's foot (NaN: not yet)",
    "est_ground_rows": "estimated ground cone rows A (2×2), world hand force (f_x, f_y): A f ≤ b",
    "est_ground_bounds": "estimated ground cone bounds b (2): N",
    "est_modes": "estimated (hand slide, hand pivot, ground slide): −1/0/+1, 0 sticking",
    "step_index": "schedule step (−1 before the first)",
    "motion": "commanded motion: 0 hold, 1 pivot, 2 slide_hand, 3 slide_ground",
    "command_targets": "commanded (θ_o, s_h, s_g): rad, m, m (NaN: no command)",
    "qp_slack": "the QP's slack (0: feasible): scaled units",
    "qp_feasible": "bool: the QP was feasible",
    "true_coordinates": "true (θ_o, s_h, s_g): rad, m, m",
    "true_d": "true d: m",
    "true_modes": "true (hand slide, hand pivot, ground slide): −1/0/+1",
    "true_contacts": "bool (hand, ground): the contact exists",
    "true_slip_rates": "true slip speed (hand, ground): m/s",
    "true_hand_pose": "true hand pose: m, m, rad, world",
    "true_hand_wrench": "true hand wrench (f_n, f_t, τ): N, N, N·m, hand frame",
}
"""Unit and frame of every array of ``record.npz`` (one row per estimator sample), as ``meta.json``
records them (``record_units``); hand frame and signs as in :mod:`ccopt.geometry`."""
SUMMARY_UNITS = (
    f"{config.UNITS}; slip_events excursion in m (hand_slide, ground_slide) or rad (hand_pivot); "
    "ratios and shares unitless"
)


def run_meta(obj: PlanarObject, schedule: Schedule, seed: int, params: LoopParams) -> dict[str, object]:
    """``meta.json`` of a run before it starts: its settings (:func:`ccopt.config.settings_of`) and
    their units (the loop adds ``steps`` and ``status``)."""
    settings = config.settings_of(obj, schedule, params, seed)
    return {**settings, "units": config.UNITS, "record_units": RECORD_UNITS}


def check_schedule(
    obj: PlanarObject, schedule: Schedule, params: LoopParams
) -> tuple[statics.StepFeasibility, ...]:
    """The oracle's check of every step of ``schedule`` on the true ``obj`` as ``params`` start it."""
    start = closed_loop.start_config(obj, params)
    return statics.schedule_feasibility(obj, schedule.steps, start, params.hand)


TOUR_SCHEDULE = "tour"
"""The schedule name with which a study runs each object's :func:`experimenter_tour`."""


def experimenter_tour(obj: PlanarObject, params: LoopParams) -> tuple[LoopParams, Tour]:
    """The experimenter's schedule for ``obj`` (issue 10's scripted runs): the tour of pivots, hand
    slides and ground slides that the statics on the *true* object allow with margin
    (:func:`ccopt.planning.tour.plan_tour`), within the hand angles the plant of ``params`` reaches
    (the Panda's are probed), with the loop parameters that start it. A study's tool: the estimator
    and the controller never see what it knows."""
    reach = closed_loop.make_plant(obj, params).hand_angle_range
    return plan_tour(obj, params, tuple(reach))


@dataclass(frozen=True)
class OracleFrame:
    """What the experimenter's oracle judges a run with: the true statics as the run starts the
    object, the robot's reach narrowed to the object's start vertex, the planner's force range and
    lever (rad, N, m)."""

    start: StartConfig
    truth: statics.TrueConfiguration
    reach: tuple[float, float]
    vertex_range: tuple[float, float]
    forces: tuple[float, float]
    lever: float


def oracle_frame(
    obj: PlanarObject,
    params: LoopParams,
    hand_angle_range: tuple[float, float],
    force_headroom: float | None = None,
) -> OracleFrame:
    """The oracle's frame of a run of ``obj`` with ``params`` on a robot reaching ``hand_angle_range``,
    whose normal force stays ``force_headroom`` (N) below the hand's largest (None: the controller
    parameters' headroom; a run's :attr:`~ccopt.closed_loop.RunResult.force_headroom` is its plant's).

    Its reach keeps the object on its start vertex a degree short of each tipping point
    (:data:`~ccopt.planning.sequencer.TIPPING_CLEARANCE`): the planner goes to the ends of its reach
    (partial pivots, :attr:`~ccopt.planning.graph.GraphParams.end_pivot`), and a pivot ends within its
    tolerance (0.7°) of its target, so a plan to the tipping point itself is not one a run could
    follow. The estimate, which finds a tipping point only as a pivot rolls past it, keeps further
    back (:data:`~ccopt.planning.sequencer.ROLL_BACKOFF`); the oracle's reach is not narrowed with
    it."""
    start = closed_loop.start_config(obj, params)
    truth = statics.true_statics(obj, start, params.hand)
    low, high = vertex_range(obj, start)  # the object stays on its start vertex
    reach = (
        max(hand_angle_range[0], low + TIPPING_CLEARANCE),
        min(hand_angle_range[1], high - TIPPING_CLEARANCE),
    )
    f_min, f_max = params.hand.force_limits
    headroom = params.controller_params.force_headroom if force_headroom is None else force_headroom
    forces = (f_min, f_max - headroom)
    lever = params.estimator_params.friction.torque_margin * params.hand.half_length
    return OracleFrame(start, truth, reach, (low, high), forces, lever)


def goal_oracle(frame: OracleFrame, data: dict[str, np.ndarray], goal: GoalResult) -> dict[str, object]:
    """The experimenter's answer for a goal: the planner on the *true* statics from the true
    configuration when the goal began (:func:`ccopt.planning.planner.oracle_plan`), within the
    robot's reach and the object's start vertex: ``reachable`` or not, why, and with how many
    motions."""
    begin = np.asarray(data["true_coordinates"])[metrics.sample_at(data, goal.start_time)]
    origin = float(np.asarray(data["true_coordinates"])[0, 2])
    truth = frame.truth
    answer = oracle_plan(
        truth.statics, tuple(begin), goal.goal, origin, frame.reach, frame.lever, frame.forces,
        face=truth.s_h_range,
    )
    return {"reachable": answer.status == "reached", "reason": answer.reason, "motions": len(answer.motions)}


def run_feasibility_map(
    obj: PlanarObject, params: LoopParams, result: RunResult, frame: OracleFrame
) -> feasibility_map.FeasibilityMap:
    """The run's feasibility maps (:mod:`ccopt.feasibility_map`): estimated at its last usable
    estimate, true on ``obj``, over the robot's reach."""
    return feasibility_map.of_run(
        obj,
        frame.start,
        params.hand,
        result.last_usable,
        result.hand_angle_range,
        frame.lever,
        frame.forces,
        PlannerParams().margin,
        frame.vertex_range,
        params.controller_params.slide_beyond,
    )


def run_experiment(
    obj: PlanarObject,
    schedule: Schedule,
    params: LoopParams | None = None,
    seed: int = 0,
    folder: str | Path | None = None,
    on_tick: Callable[[float, int, int], None] | None = None,
    warn: Callable[[str], None] | None = None,
) -> Experiment:
    """Check, run and score ``schedule`` on ``obj`` (see the module docstring).

    ``warn`` receives one line per step the oracle finds impossible, before the run starts;
    ``on_tick`` is passed to :func:`ccopt.closed_loop.run`. Ctrl-C ends the run early: the result
    says ``interrupted`` and the summary scores what was run. Ctrl-C while the schedule is checked
    waits, as during the loop's set-up, and then raises ``KeyboardInterrupt`` before the run starts;
    so does Ctrl-C before the loop's first sample (:func:`ccopt.closed_loop.run`).
    """
    params = params or LoopParams()
    with stops_held():  # set-up, as the loop's own (see closed_loop.run)
        checks = check_schedule(obj, schedule, params)
        if warn is not None:
            impossible = statics.impossible_steps(checks)
            for check in checks:
                if check.index in impossible:
                    warn(f"not physically possible for this object: {check.describe()}")
        meta = run_meta(obj, schedule, seed, params)
        meta["feasibility"] = [asdict(check) for check in checks]
    result = closed_loop.run(obj, schedule, params, seed=seed, out=folder, meta=meta, on_tick=on_tick)
    data = load_record(folder).data if folder is not None else result.samples
    steps = [step.as_dict() for step in result.steps]
    goals = [goal.as_dict() for goal in result.goals]
    summary = metrics.summarize(
        data,
        steps,
        len(schedule.motions),
        result.sim_time,
        result.wall_time,
        result.status,
        goals,
        len(schedule.goals),
    )
    frame = oracle_frame(obj, params, result.hand_angle_range, result.force_headroom)
    for entry, goal in zip(summary["goals"], result.goals, strict=True):
        entry["oracle"] = goal_oracle(frame, data, goal)
    summary["message"] = result.message
    summary["units"] = SUMMARY_UNITS
    summary["impossible_steps"] = statics.impossible_steps(checks)
    summary["target_at_reach_s"] = result.target_at_reach
    summary["kinematics_resets"] = metrics.kinematics_resets(data["est_kinematics_valid"]) if data else 0
    maps = None
    if folder is not None:
        write_summary(folder, summary)
        maps = run_feasibility_map(obj, params, result, frame)
        maps.save(folder)
    return Experiment(result, meta, summary, checks, Path(folder) if folder is not None else None, maps)
