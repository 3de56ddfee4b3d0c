"""How well a run did, scored against the simulator's ground truth (the only reader of truth).

All functions take the run's time series (the arrays of ``record.npz``, see
:func:`ccopt.closed_loop._sample`) and the per-step results stored in ``meta.json``.

* estimation errors of ``θ_o`` (deg), ``s_h`` and ``s_g`` (mm) over the samples where the estimator
  reports valid kinematics (after the warm start);
* realised/commanded change of each commanded increment, from the truth at the step's start and end;
* unintended slips: a contact the command required to stick that truly slid by more than
  :data:`SLIP_DISTANCE` during one step (the true tangential slip speed at the contact, integrated),
  or a hand required flush that truly turned against the object by more than :data:`SLIP_ANGLE`;
* mode-classification confusion per contact, in particular how often true sliding was reported as
  sticking (the error the estimator must avoid) and the opposite error;
* success: every step reached and both contacts kept throughout;
* the verdicts the studies give a run: the closed-loop thresholds (:class:`Thresholds`,
  :func:`misses`), the causes of a failure (:func:`failure_causes`), the kinematics lost
  (:func:`kinematics_resets`), and for a pushed run the recovery of a coordinate
  (:func:`recovery_time`, :func:`coordinate_changes`, :func:`slip_distance`).
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np

from ccopt import modes
from ccopt.geometry import wrap_angle
from ccopt.hand import Hand

if TYPE_CHECKING:
    from ccopt.closed_loop import RunResult
    from ccopt.schedule import Schedule

SLIP_DISTANCE = 1e-3
"""An unintended slip moves a contact that should stick by more than this (m) within one step."""
SLIP_ANGLE = np.deg2rad(2.0)
"""An unintended pivot turns a hand that should stay flush by more than this (rad) within one step.

Not 0: the simulated contact is soft, and a flush hand rolls elastically against the object by up to
~1° at two thirds of its torque limit (6 cm hand, measured); only rotation beyond that band is the
hand losing its line contact."""
CONTACT_SHARE = 0.99
"""Share of the samples in which both contacts must exist for a run to count as completed."""

CONTACT_NAMES = ("hand_slide", "hand_pivot", "ground_slide")


def _stats(values: np.ndarray) -> dict[str, float | None]:
    if values.size == 0:
        return {"median": None, "p95": None}
    return {"median": float(np.median(values)), "p95": float(np.percentile(values, 95))}


def estimation_errors(data: Mapping[str, np.ndarray]) -> dict[str, dict[str, float | None]]:
    """Absolute errors where the kinematics are valid: ``θ_o`` in degrees, ``s_h``/``s_g`` in mm."""
    valid = np.asarray(data["est_kinematics_valid"], dtype=bool)
    estimated, true = data["est_coordinates"][valid], data["true_coordinates"][valid]
    theta = np.rad2deg(np.abs(wrap_angle(estimated[:, 0] - true[:, 0])))
    return {
        "theta_err_deg": _stats(np.atleast_1d(theta)),
        "s_h_err_mm": _stats(1e3 * np.abs(estimated[:, 1] - true[:, 1])),
        "s_g_err_mm": _stats(1e3 * np.abs(estimated[:, 2] - true[:, 2])),
    }


def sample_at(data: Mapping[str, np.ndarray], moment: float) -> int:
    """The index of the first record sample at or after ``moment`` (s; the last sample if none)."""
    return int(np.clip(np.searchsorted(data["time"], moment), 0, len(data["time"]) - 1))


def realised_ratios(data: Mapping[str, np.ndarray], steps: Sequence[Mapping[str, object]]) -> np.ndarray:
    """True change of the commanded coordinate over each (non-hold) step, over the commanded change;
    exploration steps (which end by themselves, e.g. a friction probe) are not scored."""
    ratios = []
    for step in steps:
        k = modes.driven_coordinate(step["kind"])
        if k is None or step.get("explore"):
            continue
        start, end = sample_at(data, step["start_time"]), sample_at(data, step["end_time"])
        change = data["true_coordinates"][end, k] - data["true_coordinates"][start, k]
        if k == 0:
            change = wrap_angle(change)
        ratios.append(change / step["delta"])
    return np.asarray(ratios, dtype=float)


def turn_from_flush(relative: np.ndarray) -> float:
    """The largest turn (rad) of the hand against the object over one step's samples of
    ``θ_o − θ_h`` (rad, 0 flush): the distance of each sample from the span between flush and the
    step's first sample. A hand coming back to flush from a roll the step began with (the step
    after a landing on a face) does what a step that keeps it flush asks, and does not count: the
    paper rectangle's pivot back from its landing went from +1.52° to the elastic −0.48°, a 2.0°
    excursion from its start but 0.48° from flush."""
    if relative.size == 0:
        return 0.0
    low, high = min(0.0, relative[0]), max(0.0, relative[0])
    return float(max(low - relative.min(), relative.max() - high, 0.0))


def unintended_slips(
    data: Mapping[str, np.ndarray], steps: Sequence[Mapping[str, object]]
) -> list[dict[str, object]]:
    """Steps in which a contact that had to stick truly slid, or a hand that had to stay flush pivoted.

    Slip is the integral of the true tangential slip speed at the contact over the step (m), which
    elastic rolling of the hand does not produce; pivoting is the hand's turn against the object
    away from flush and from where the step began (:func:`turn_from_flush`, rad).
    """
    events = []
    time = np.asarray(data["time"])
    intervals = np.diff(time, prepend=time[0])
    slid = np.cumsum(np.abs(data["true_slip_rates"]) * intervals[:, None], axis=0)
    relative_angle = wrap_angle(data["true_coordinates"][:, 0] - data["true_hand_pose"][:, 2])
    for step in steps:
        start, end = sample_at(data, step["start_time"]), sample_at(data, step["end_time"])
        if end <= start:
            continue
        hand_stick, hand_flush, ground_stick = modes.kept_contacts(step["kind"])
        segment = relative_angle[start : end + 1]
        measures = (
            ("hand_slide", hand_stick, slid[end, 0] - slid[start, 0], SLIP_DISTANCE),
            ("hand_pivot", hand_flush, turn_from_flush(segment), SLIP_ANGLE),
            ("ground_slide", ground_stick, slid[end, 1] - slid[start, 1], SLIP_DISTANCE),
        )
        for name, required, excursion, limit in measures:
            if required and excursion > limit:
                events.append({"step": int(step["index"]), "contact": name, "excursion": float(excursion)})
    return events


def mode_confusion(data: Mapping[str, np.ndarray]) -> dict[str, dict[str, float | None]]:
    """Per contact: share of truly moving samples reported sticking, and of sticking reported moving."""
    out = {}
    for k, name in enumerate(CONTACT_NAMES):
        true_moving = data["true_modes"][:, k] != 0
        reported_moving = data["est_modes"][:, k] != 0
        moving, sticking = int(true_moving.sum()), int((~true_moving).sum())
        out[name] = {
            "moving_reported_sticking": float((true_moving & ~reported_moving).sum() / moving)
            if moving
            else None,
            "sticking_reported_moving": float((~true_moving & reported_moving).sum() / sticking)
            if sticking
            else None,
            "moving_samples": moving,
        }
    return out


def ratio_by_kind(
    data: Mapping[str, np.ndarray], steps: Sequence[Mapping[str, object]]
) -> dict[str, dict[str, float | int | None]]:
    """Quartiles of the realised/commanded ratio per kind of step (``pivot``, ``slide_hand``,
    ``slide_ground``), over the steps of that kind that ran (an infeasible step did not)."""
    out = {}
    for kind in modes.KINDS[1:]:
        chosen = [step for step in steps if step["kind"] == kind and step.get("status") != "infeasible"]
        values = realised_ratios(data, chosen)
        out[kind] = quartiles(values)
    return out


def quartiles(values: Sequence[float] | np.ndarray) -> dict[str, float | int | None]:
    """``{median, q25, q75, n}`` of some values (None for an empty set)."""
    values = np.asarray(values, dtype=float)
    if values.size == 0:
        return {"median": None, "q25": None, "q75": None, "n": 0}
    q25, median, q75 = np.percentile(values, [25, 50, 75])
    return {"median": float(median), "q25": float(q25), "q75": float(q75), "n": int(values.size)}


def normal_force(data: Mapping[str, np.ndarray]) -> dict[str, float | None]:
    """The true normal force of the hand on the object, N: median, 99th percentile and largest."""
    wrench = np.asarray(data.get("true_hand_wrench", np.empty((0, 3))))
    if wrench.size == 0:
        return {"median": None, "p99": None, "max": None}
    force = wrench[:, 0]
    return {
        "median": float(np.median(force)),
        "p99": float(np.percentile(force, 99)),
        "max": float(force.max()),
    }


def summarize(
    data: Mapping[str, np.ndarray] | RunResult,
    steps: Sequence[Mapping[str, object]] | Schedule,
    steps_total: int | None = None,
    sim_time: float | None = None,
    wall_time: float | None = None,
    status: str = "completed",
    goals: Sequence[Mapping[str, object]] = (),
    goals_total: int = 0,
) -> dict[str, object]:
    """The ``summary.json`` of a run (docs/architecture.md §8); ``status`` is how the run ended.

    Either a run's own result and its schedule, ``summarize(result, schedule)`` (the
    :class:`~ccopt.closed_loop.RunResult` of :func:`ccopt.closed_loop.run`, recorded or in memory), or
    its record's arrays; ``steps``, the results of every motion (a goal's planned motions carry its
    index in ``goal``), the per-step dicts of ``meta.json``; ``steps_total`` the number of the
    schedule's own motion steps; the simulated and wall time (s); the status; ``goals`` the goal
    results (:meth:`ccopt.planning.sequencer.GoalResult.as_dict`) of the ``goals_total`` goal steps.
    A run that stopped before its first sample (``data`` empty) is summarised with nothing measured:
    no step done, every statistic None.
    """
    if not isinstance(data, Mapping):
        return summarize(*_run_inputs(data, steps))
    if len(data.get("time", ())) == 0:
        return _unmeasured(steps_total, sim_time, wall_time, status, goals_total)
    ratios = realised_ratios(data, steps)
    slips = unintended_slips(data, steps)
    contacts = np.asarray(data["true_contacts"], dtype=bool)
    kept_contact = bool(np.mean(contacts.all(axis=1)) >= CONTACT_SHARE)
    own = [step for step in steps if step.get("goal") is None]
    steps_done = sum(bool(step["reached"] or step.get("explore")) for step in own)
    valid = np.asarray(data["est_kinematics_valid"], dtype=bool)
    scored = goal_scores(data, goals)
    settled = (
        all(goal["status"] in ("reached", "unreachable") for goal in scored) and len(scored) == goals_total
    )
    return {
        "status": status,
        "completed": bool(steps_done == steps_total and kept_contact and settled),
        "steps_done": steps_done,
        "steps_total": steps_total,
        "goals": scored,
        "goals_reached": sum(goal["status"] == "reached" for goal in scored),
        "goals_total": goals_total,
        "contact_kept": kept_contact,
        **estimation_errors(data),
        "kinematics_valid_share": float(valid.mean()) if valid.size else 0.0,
        "ratio_realised_commanded": quartiles(ratios),
        "ratio_by_kind": ratio_by_kind(data, steps),
        "probes": probes(steps),
        "normal_force_n": normal_force(data),
        "infeasible_steps": [int(step["index"]) for step in own if step.get("status") == "infeasible"],
        "unintended_slips": len(slips),
        "slip_events": slips,
        "mode_confusion": mode_confusion(data),
        "infeasible_ticks_share": float(1.0 - np.mean(data["qp_feasible"])),
        "sim_time_s": float(sim_time),
        "wall_time_s": float(wall_time),
    }


def probes(steps: Sequence[Mapping[str, object]]) -> dict[str, int]:
    """The exploration steps that move something (``Step.explore``: the exploration's probes, and a
    goal's motions that look for a limit, :mod:`ccopt.planning.sequencer`), which the ratios leave
    out: ``n`` of them that ran (not ``skipped``) and how many were ``reached``."""
    moving = [
        step
        for step in steps
        if step.get("explore")
        and step.get("status") != "skipped"
        and modes.driven_coordinate(step["kind"]) is not None
    ]
    return {"n": len(moving), "reached": sum(bool(step["reached"]) for step in moving)}


def goal_scores(
    data: Mapping[str, np.ndarray], goals: Sequence[Mapping[str, object]]
) -> list[dict[str, object]]:
    """Every goal's result with its ``true_error`` at its end: truth minus target, ``theta_deg``,
    ``s_h_mm``, ``s_g_mm`` (``s_g`` from the true ground contact at the run's start; None where the
    goal leaves it free), and ``within_tolerance`` (every given coordinate, by truth)."""
    if not goals:
        return []
    true = np.asarray(data["true_coordinates"])
    origin = true[0, 2]
    scored = []
    for goal in goals:
        end = true[sample_at(data, float(goal["end_time"]))]
        targets = goal["targets"]
        reached = (np.rad2deg(end[0]), 1e3 * end[1], 1e3 * (end[2] - origin))
        error = {
            key: None if targets[key] is None else float(value - targets[key])
            for key, value in zip(("theta_deg", "s_h_mm", "s_g_mm"), reached, strict=True)
        }
        limits = {
            "theta_deg": goal["tolerance_deg"],
            "s_h_mm": goal["tolerance_mm"],
            "s_g_mm": goal["tolerance_mm"],
        }
        within = all(value is None or abs(value) <= limits[key] for key, value in error.items())
        time = float(goal["end_time"]) - float(goal["start_time"])
        scored.append({**goal, "true_error": error, "within_tolerance": within, "time_s": time})
    return scored


def _unmeasured(
    steps_total: int, sim_time: float, wall_time: float, status: str, goals_total: int = 0
) -> dict[str, object]:
    """:func:`summarize` of a run without a sample: the same keys, nothing measured."""
    nothing = _stats(np.empty(0))
    return {
        "status": status,
        "completed": False,
        "steps_done": 0,
        "steps_total": steps_total,
        "goals": [],
        "goals_reached": 0,
        "goals_total": goals_total,
        "contact_kept": False,
        **{key: dict(nothing) for key in ("theta_err_deg", "s_h_err_mm", "s_g_err_mm")},
        "kinematics_valid_share": 0.0,
        "ratio_realised_commanded": quartiles(()),
        "ratio_by_kind": {kind: quartiles(()) for kind in modes.KINDS[1:]},
        "probes": probes(()),
        "normal_force_n": normal_force({}),
        "infeasible_steps": [],
        "unintended_slips": 0,
        "slip_events": [],
        "mode_confusion": {
            name: {"moving_reported_sticking": None, "sticking_reported_moving": None}
            for name in CONTACT_NAMES
        },
        "infeasible_ticks_share": None,
        "sim_time_s": float(sim_time),
        "wall_time_s": float(wall_time),
    }


def _run_inputs(result: RunResult, schedule: Schedule) -> tuple:
    """:func:`summarize`'s arguments of a run's result and its schedule."""
    from ccopt.record import load_record

    data = load_record(result.folder).data if result.folder is not None else result.samples
    steps = [step.as_dict() for step in result.steps]
    goals = [goal.as_dict() for goal in result.goals]
    motions, goals_total = len(schedule.motions), len(schedule.goals)
    return data, steps, motions, result.sim_time, result.wall_time, result.status, goals, goals_total


# --- verdicts -------------------------------------------------------------------------------------


FORCE_EXCESS = 2.0
"""N: how far past the hand's upper force limit a run's true normal force may go (issue 10: the
sensor noise and the transients of a contact change)."""


@dataclass(frozen=True)
class Thresholds:
    """What a closed-loop run must achieve (issue 10's bar): error medians in deg and mm, the
    overall ratio band, per kind of motion (where a kind ran) a median ratio band, the share of
    samples with valid kinematics, the largest true normal force (N: the default hand's upper force
    limit plus :data:`FORCE_EXCESS`) and no slips."""

    theta_err_deg: float = 1.0
    s_h_err_mm: float = 3.0
    s_g_err_mm: float = 3.0
    ratio_low: float = 0.85
    ratio_high: float = 1.15
    kind_ratio_low: float = 0.9
    kind_ratio_high: float = 1.1
    valid_share: float = 0.8
    normal_force_max: float = Hand().force_limits[1] + FORCE_EXCESS


def _at_most(value: float | None, limit: float) -> bool:
    return value is not None and value <= limit


def misses(summary: Mapping[str, object], thresholds: Thresholds = Thresholds()) -> list[str]:
    """The thresholds a run misses: ``completed``, ``theta_err``, ``s_h_err``, ``s_g_err``, ``ratio``,
    ``ratio_<kind>`` (a kind of motion that ran), ``valid_share``, ``normal_force``, ``slips`` (an
    absent median misses)."""
    ratio = summary["ratio_realised_commanded"]["median"]
    checks = {
        "completed": bool(summary["completed"]),
        "theta_err": _at_most(summary["theta_err_deg"]["median"], thresholds.theta_err_deg),
        "s_h_err": _at_most(summary["s_h_err_mm"]["median"], thresholds.s_h_err_mm),
        "s_g_err": _at_most(summary["s_g_err_mm"]["median"], thresholds.s_g_err_mm),
        "ratio": ratio is not None and thresholds.ratio_low <= ratio <= thresholds.ratio_high,
    }
    for kind, quartile in summary["ratio_by_kind"].items():
        median = quartile["median"]
        in_band = median is None or thresholds.kind_ratio_low <= median <= thresholds.kind_ratio_high
        checks[f"ratio_{kind}"] = in_band
    share = summary["kinematics_valid_share"]
    checks["valid_share"] = share is not None and share >= thresholds.valid_share
    checks["normal_force"] = _at_most(summary["normal_force_n"]["max"], thresholds.normal_force_max)
    checks["slips"] = summary["unintended_slips"] == 0
    return [name for name, met in checks.items() if not met]


def flat_summary(summary: Mapping[str, object]) -> dict[str, object]:
    """The scalar columns of a :func:`summarize` summary (errors in deg and mm), for tables and CSV."""
    slips = [event["contact"] for event in summary["slip_events"]]
    ratio = summary["ratio_realised_commanded"]
    return {
        "completed": summary["completed"],
        "steps_done": summary["steps_done"],
        "steps_total": summary["steps_total"],
        "contact_kept": summary["contact_kept"],
        **{
            f"{key}_{stat}": summary[key][stat]
            for key in ("theta_err_deg", "s_h_err_mm", "s_g_err_mm")
            for stat in ("median", "p95")
        },
        "ratio_median": ratio["median"],
        "ratio_q25": ratio["q25"],
        "ratio_q75": ratio["q75"],
        "unintended_slips": summary["unintended_slips"],
        **{f"slips_{name}": slips.count(name) for name in CONTACT_NAMES},
        "infeasible_share": summary["infeasible_ticks_share"],
        "sim_time_s": summary["sim_time_s"],
        "wall_time_s": summary["wall_time_s"],
    }


def kinematics_resets(valid: np.ndarray) -> int:
    """How often the estimated kinematics went from valid to invalid."""
    flags = np.asarray(valid, dtype=bool)
    return int(np.sum(flags[:-1] & ~flags[1:]))


INFEASIBLE_SHARE = 0.2
"""A run with more than this share of infeasible control ticks fails (also) by ``infeasible QP``."""

IMPOSSIBLE_STEP = "impossible step"
LOSS_OF_CONTACT = "loss of contact"
GROUND_SLIP = "slip at the ground"
HAND_SLIP = "slip at the hand"
HAND_PIVOT = "hand pivot"
INFEASIBLE = "infeasible QP"
ESTIMATOR_RESET = "estimator reset"
TIMEOUT = "timeout"
CAUSES = (
    IMPOSSIBLE_STEP,
    LOSS_OF_CONTACT,
    GROUND_SLIP,
    HAND_SLIP,
    HAND_PIVOT,
    INFEASIBLE,
    ESTIMATOR_RESET,
    TIMEOUT,
)
"""Why a run can fail, in the order :func:`failure_causes` lists them."""
_SLIP_CAUSES = {"ground_slide": GROUND_SLIP, "hand_slide": HAND_SLIP, "hand_pivot": HAND_PIVOT}


def failure_causes(summary: Mapping[str, object]) -> list[str]:
    """Why a run failed (empty if it completed without an unintended slip), from its summary
    (including ``impossible_steps`` and ``kinematics_resets``, see :mod:`ccopt.experiment`):

    ``impossible step``  the schedule has a step no controller can do on this object (the oracle);
    ``loss of contact``  a contact was open in more than 1 % of the samples;
    ``slip at the ground`` / ``slip at the hand`` / ``hand pivot``  a contact that had to keep its
                         mode did not;
    ``infeasible QP``    more than :data:`INFEASIBLE_SHARE` of the control ticks had no feasible step;
    ``estimator reset``  the estimated kinematics became invalid after having been valid;
    ``timeout``          a step was not reached and none of the above applies.
    """
    if summary["completed"] and summary["unintended_slips"] == 0:
        return []
    slid = {event["contact"] for event in summary["slip_events"]}
    flags = {
        IMPOSSIBLE_STEP: bool(summary.get("impossible_steps")),
        LOSS_OF_CONTACT: not summary["contact_kept"],
        **{cause: contact in slid for contact, cause in _SLIP_CAUSES.items()},
        INFEASIBLE: summary["infeasible_ticks_share"] > INFEASIBLE_SHARE,
        ESTIMATOR_RESET: summary.get("kinematics_resets", 0) > 0,
    }
    causes = [cause for cause in CAUSES if flags.get(cause)]
    return causes or [TIMEOUT]


def recovery_time(time: np.ndarray, error: np.ndarray, tolerance: float) -> float | None:
    """First time ≥ 0 (s) after which ``|error| ≤ tolerance`` to the end; 0 if it never left, None if
    it is outside (or unknown, NaN) at the last sample. ``time`` counts from a push's start."""
    after = np.asarray(time) >= 0.0
    times, errors = np.asarray(time)[after], np.abs(np.asarray(error)[after])
    outside = np.flatnonzero(~(errors <= tolerance))
    if outside.size == 0:
        return 0.0
    if outside[-1] == len(times) - 1:
        return None
    return float(times[outside[-1] + 1])


def coordinate_changes(values: np.ndarray, reference: np.ndarray) -> np.ndarray:
    """``values − reference`` per coordinate ``(θ_o, s_h, s_g)`` (rows of ``values``), the angle wrapped."""
    delta = np.asarray(values) - reference
    delta[:, 0] = wrap_angle(delta[:, 0])
    return delta


def slip_distance(time: np.ndarray, rates: np.ndarray) -> np.ndarray:
    """Distance each contact truly slid (m): ``∫ |slip speed| dt`` per column of ``rates`` (m/s)."""
    return np.sum(np.abs(rates) * np.diff(time, prepend=time[0])[:, None], axis=0)
