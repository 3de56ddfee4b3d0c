"""Look into a run with Rerun (``ccopt view RUN_DIR [--save FILE.rrd]``; ``pip install 'ccopt[view]'``).

Everything on one timeline, ``sim_time`` (simulated s):

``scene/…`` (world, m; a 2-D view)
    ``ground``; the true ``object`` (from the record's true configuration and the object model of
    ``meta.json``) and ``hand``; the true and estimated contact geometry (``contact/true``,
    ``contact/estimated``: ``r_o → r_o − d e_n → r_h``, and the ground contacts ``r_o/true``,
    ``r_o/estimated``); the friction cones (``cones/hand/estimated|true``,
    ``cones/ground/estimated|true``); the hand force (``force/measured|true``, arrows of
    :data:`FORCE_SCALE` m per N). At most :data:`SCENE_HZ` frames a second.
``coordinates/{theta_o_deg,s_h_mm,s_g_mm,d_mm}/{estimated,true,commanded}``
    the estimates against truth and the command, every sample.
``wrench/{f_n_n,f_t_n,tau_nm}/{measured,true}``, ``friction/mu_h/{estimated,true}``
``modes/{hand_slide,hand_pivot,ground_slide}/{estimated,true}`` (−1/0/+1), ``command/{motion,step}``
    (motion codes 0 hold, 1 pivot, 2 slide_hand, 3 slide_ground), ``qp/{slack,feasible}``,
    ``kinematics/valid`` and ``log/steps`` (how each step ended).
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from ccopt import clock, replay
from ccopt.record import Record

TIMELINE = "sim_time"
SCENE_HZ = 50.0
"""Most scene frames logged per simulated second (the series are logged at every sample)."""
FORCE_SCALE = 3e-3
"""Metres drawn per newton of hand force."""
MIN_RERUN = "0.41"
"""The oldest ``rerun-sdk`` this module is written for (``pyproject.toml``'s ``view`` extra)."""
APPLICATION = "ccopt"

BLUE, BLACK, ORANGE, PURPLE, RED, GREEN, GREY = (
    (31, 119, 180),
    (0, 0, 0),
    (255, 127, 14),
    (148, 103, 189),
    (214, 39, 40),
    (44, 160, 44),
    (128, 128, 128),
)


class RerunMissing(RuntimeError):
    """``rerun-sdk`` is not installed."""


def _rerun():
    try:
        import rerun
    except ImportError:
        raise RerunMissing(f"ccopt view needs rerun-sdk >= {MIN_RERUN}: pip install 'ccopt[view]'") from None
    return rerun


def log_run(run: object, save: str | Path | None = None, spawn: bool = True) -> Path | None:
    """Log a run (a folder, a record or a run's result: :func:`ccopt.replay.as_record`) to Rerun: to
    the file ``save`` (returned), else to a viewer it starts (``spawn``) or, without one, nowhere but
    memory. :class:`RerunMissing` without ``rerun-sdk``; ``OSError`` if ``save`` cannot be written."""
    rr = _rerun()
    record = replay.as_record(run)
    run_id = record.meta.get("run_id")
    stream = rr.RecordingStream(APPLICATION, recording_id=run_id if isinstance(run_id, str) else None)
    if save is not None:
        path = Path(save)
        with open(path, "wb"):  # the folder exists and the file is writable, before any work
            pass
        stream.save(str(path))
    elif spawn:
        stream.spawn()
    _log(rr, stream, record)
    stream.flush()
    if save is not None:
        stream.disconnect()
        return path
    return None


def _log(rr, stream, record: Record) -> None:
    data = record.data
    if not replay.has(record, "time"):
        return
    time = np.asarray(data["time"], dtype=float)
    for entity, values in _series(record).items():
        finite = np.isfinite(values)
        if finite.any():
            column = rr.TimeColumn(TIMELINE, duration=time[finite])
            stream.send_columns(entity, indexes=[column], columns=rr.Scalars.columns(scalars=values[finite]))
    _log_steps(rr, stream, record)
    if replay.has(record, *replay.SCENE_KEYS):
        _log_scene(rr, stream, record)


def _series(record: Record) -> dict[str, np.ndarray]:
    """Every time series the viewer shows, by entity path, in display units (deg, mm, N)."""
    data = record.data
    deg, mm = np.rad2deg(1.0), 1e3
    series: dict[str, np.ndarray] = {}
    names = (("theta_o_deg", deg), ("s_h_mm", mm), ("s_g_mm", mm))
    valid = replay.valid(record) if replay.has(record, "est_coordinates", "est_kinematics_valid") else None
    for k, (name, scale) in enumerate(names):
        if "est_coordinates" in data and valid is not None:
            series[f"coordinates/{name}/estimated"] = (
                np.where(valid, data["est_coordinates"][:, k], np.nan) * scale
            )
        if "true_coordinates" in data:
            series[f"coordinates/{name}/true"] = data["true_coordinates"][:, k] * scale
        if "command_targets" in data:
            series[f"coordinates/{name}/commanded"] = data["command_targets"][:, k] * scale
    if "est_d" in data and valid is not None:
        series["coordinates/d_mm/estimated"] = np.where(valid, data["est_d"], np.nan) * mm
    if "true_d" in data:
        series["coordinates/d_mm/true"] = data["true_d"] * mm
    for k, name in enumerate(("f_n_n", "f_t_n", "tau_nm")):
        for key, which in (("hand_wrench", "measured"), ("true_hand_wrench", "true")):
            if key in data:
                series[f"wrench/{name}/{which}"] = data[key][:, k]
    if "est_mu_h" in data:
        series["friction/mu_h/estimated"] = data["est_mu_h"]
    obj = replay.true_object(record)
    if obj is not None:
        series["friction/mu_h/true"] = np.full(len(data["time"]), obj.mu_hand)
    for k, name in enumerate(("hand_slide", "hand_pivot", "ground_slide")):
        for key, which in (("est_modes", "estimated"), ("true_modes", "true")):
            if key in data:
                series[f"modes/{name}/{which}"] = data[key][:, k]
    for key, entity in (
        ("motion", "command/motion"),
        ("step_index", "command/step"),
        ("qp_slack", "qp/slack"),
        ("qp_feasible", "qp/feasible"),
        ("est_kinematics_valid", "kinematics/valid"),
    ):
        if key in data:
            series[entity] = data[key]
    return {entity: np.asarray(values, dtype=float) for entity, values in series.items()}


def _log_steps(rr, stream, record: Record) -> None:
    """One text line per step, at its end: kind, increment, how it ended."""
    for step in record.meta.get("steps", []):
        try:
            kind, end, status = step["kind"], float(step["end_time"]), step["status"]
        except (KeyError, TypeError, ValueError):
            continue
        stream.set_time(TIMELINE, duration=end)
        reason = f": {step['reason']}" if step.get("reason") else ""
        text = f"step {step.get('index')} {kind} {step.get('delta', 0.0):+.4g} (rad or m) {status}{reason}"
        stream.log("log/steps", rr.TextLog(text))


def _strip(points: np.ndarray | None) -> list[np.ndarray]:
    return [] if points is None else [np.asarray(points, dtype=float)]


def _closed(points: np.ndarray | None) -> np.ndarray | None:
    return None if points is None else np.vstack((points, points[:1]))


def _log_scene(rr, stream, record: Record) -> None:
    data = record.data
    time = np.asarray(data["time"], dtype=float)
    period = 1.0 / SCENE_HZ
    moments = np.arange(time[0], time[-1] + clock.TIME_TOLERANCE, period)
    frames = np.unique(clock.latest_samples(time, moments))
    scene = replay.scene(record, frames)
    extent = np.vstack([frame.hand for frame in scene] + [frame.r_o[None] for frame in scene])
    low, high = extent[:, 0].min() - 0.2, extent[:, 0].max() + 0.2
    stream.log("scene/ground", rr.LineStrips2D([[[low, 0.0], [high, 0.0]]], colors=[GREY]), static=True)
    lines = (
        ("object", lambda f: _closed(f.object), GREY),
        ("hand", lambda f: f.hand, BLACK),
        ("contact/true", lambda f: f.chain, BLACK),
        ("contact/estimated", lambda f: f.chain_est, BLUE),
        ("cones/hand/estimated", lambda f: f.hand_cone, BLUE),
        ("cones/hand/true", lambda f: f.hand_cone_true, ORANGE),
        ("cones/ground/estimated", lambda f: f.ground_cone, PURPLE),
        ("cones/ground/true", lambda f: f.ground_cone_true, RED),
    )
    for frame in scene:
        stream.set_time(TIMELINE, duration=frame.time)
        for entity, part, color in lines:
            stream.log(f"scene/{entity}", rr.LineStrips2D(_strip(part(frame)), colors=[color]))
        estimated = [] if frame.r_o_est is None else [frame.r_o_est]
        stream.log("scene/r_o/true", rr.Points2D([frame.r_o], colors=[BLACK], radii=0.002))
        stream.log("scene/r_o/estimated", rr.Points2D(estimated, colors=[BLUE], radii=0.002))
        centre = frame.hand.mean(axis=0)
        for which, force, color in (("measured", frame.force, GREEN), ("true", frame.force_true, BLACK)):
            vectors = [] if force is None else [FORCE_SCALE * force]
            origins = [] if force is None else [centre]
            stream.log(f"scene/force/{which}", rr.Arrows2D(origins=origins, vectors=vectors, colors=[color]))
