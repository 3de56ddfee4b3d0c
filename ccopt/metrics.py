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
* success: every step reached and both contacts kept throughout.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence

import numpy as np

from ccopt.geometry import wrap_angle

SLIP_DISTANCE = 1e-3
"""An unintended slip moves a contact that should stick by more than this (m) within one step."""
SLIP_ANGLE = np.deg2rad(2.0)
"""An unintended pivot turns a hand that should stay flush by more than this (rad) within one step.

Not 0: the simulated contact is soft, and a flush hand rolls elastically against the object by up to
~1° at two thirds of its torque limit (6 cm hand, measured); only rotation beyond that band is the
hand losing its line contact."""
CONTACT_SHARE = 0.99
"""Share of the samples in which both contacts must exist for a run to count as completed."""

# which true modes (hand slide, hand geometry, ground slide) must stay 0 for each kind of step
_MUST_STICK = {
    "hold": (True, True, True),
    "pivot": (True, True, True),
    "slide_hand": (False, True, True),
    "slide_ground": (True, True, False),
}
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


def _at(data: Mapping[str, np.ndarray], moment: float) -> int:
    return int(np.clip(np.searchsorted(data["time"], moment), 0, len(data["time"]) - 1))


def realised_ratios(data: Mapping[str, np.ndarray], steps: Sequence[Mapping[str, object]]) -> np.ndarray:
    """True change of the commanded coordinate over each (non-hold) step, over the commanded change."""
    coordinate = {"pivot": 0, "slide_hand": 1, "slide_ground": 2}
    ratios = []
    for step in steps:
        if step["kind"] == "hold":
            continue
        k = coordinate[step["kind"]]
        start, end = _at(data, step["start_time"]), _at(data, step["end_time"])
        change = data["true_coordinates"][end, k] - data["true_coordinates"][start, k]
        if k == 0:
            change = wrap_angle(change)
        ratios.append(change / step["delta"])
    return np.asarray(ratios, dtype=float)


def unintended_slips(
    data: Mapping[str, np.ndarray], steps: Sequence[Mapping[str, object]]
) -> list[dict[str, object]]:
    """Steps in which a contact that had to stick truly slid, or a hand that had to stay flush pivoted.

    Slip is the integral of the true tangential slip speed at the contact over the step (m), which
    elastic rolling of the hand does not produce; pivoting is the excursion of ``θ_o − θ_h`` (rad).
    """
    events = []
    time = np.asarray(data["time"])
    intervals = np.diff(time, prepend=time[0])
    slid = np.cumsum(np.abs(data["true_slip_rates"]) * intervals[:, None], axis=0)
    relative_angle = wrap_angle(data["true_coordinates"][:, 0] - data["true_hand_pose"][:, 2])
    for step in steps:
        start, end = _at(data, step["start_time"]), _at(data, step["end_time"])
        if end <= start:
            continue
        hand_stick, hand_flush, ground_stick = _MUST_STICK[step["kind"]]
        segment = relative_angle[start : end + 1]
        measures = (
            ("hand_slide", hand_stick, slid[end, 0] - slid[start, 0], SLIP_DISTANCE),
            ("hand_pivot", hand_flush, float(np.max(np.abs(segment - segment[0]))), SLIP_ANGLE),
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


def summarize(
    data: Mapping[str, np.ndarray],
    steps: Sequence[Mapping[str, object]],
    steps_total: int,
    sim_time: float,
    wall_time: float,
) -> dict[str, object]:
    """The ``summary.json`` of a run (DESIGN.md §8 and the closed-loop issue's keys)."""
    ratios = realised_ratios(data, steps)
    slips = unintended_slips(data, steps)
    contacts = np.asarray(data["true_contacts"], dtype=bool)
    kept_contact = bool(np.mean(contacts.all(axis=1)) >= CONTACT_SHARE) if contacts.size else False
    steps_done = sum(bool(step["reached"]) for step in steps)
    return {
        "completed": bool(steps_done == steps_total and kept_contact),
        "steps_done": steps_done,
        "steps_total": steps_total,
        "contact_kept": kept_contact,
        **estimation_errors(data),
        "ratio_realised_commanded": {
            "median": float(np.median(ratios)) if ratios.size else None,
            "q25": float(np.percentile(ratios, 25)) if ratios.size else None,
            "q75": float(np.percentile(ratios, 75)) if ratios.size else None,
        },
        "unintended_slips": len(slips),
        "slip_events": slips,
        "mode_confusion": mode_confusion(data),
        "infeasible_ticks_share": float(1.0 - np.mean(data["qp_feasible"])),
        "sim_time_s": float(sim_time),
        "wall_time_s": float(wall_time),
    }
