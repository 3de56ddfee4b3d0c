"""A run as the figures and the viewer read it: its record, and the scene of each sample in the world.

:func:`as_record` takes what a run gives back — a run folder, a :class:`~ccopt.record.Record`, the
:class:`~ccopt.closed_loop.RunResult` of :func:`ccopt.closed_loop.run` or the
:class:`~ccopt.experiment.Experiment` of :func:`ccopt.experiment.run_experiment`, recorded to a folder
or kept in memory — and returns the record. :func:`scene` rebuilds, per sample, what the scene holds
(m, world frame of :mod:`ccopt.geometry`): the true object polygon from the true configuration and the
object model of ``meta.json``, the true hand, the true and estimated ground contact and hand contact,
the estimated and true friction cones, the measured and true hand forces. Only plots and the viewer
read the truth this way.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from ccopt import geometry
from ccopt.hand import Hand
from ccopt.objects import PlanarObject
from ccopt.plant.base import StartConfig
from ccopt.record import Record, load_record


def as_record(run: object) -> Record:
    """The record of ``run``: a :class:`Record` as it is, a run folder (``str`` or ``Path``) loaded, a
    ``RunResult`` or ``Experiment`` loaded from its folder or, run in memory, wrapped (its samples, its
    steps and, for an ``Experiment``, its metadata and summary). ``TypeError`` for anything else."""
    if isinstance(run, Record):
        return run
    if isinstance(run, str | Path):
        return load_record(run)
    from ccopt.closed_loop import RunResult
    from ccopt.experiment import Experiment

    if isinstance(run, Experiment):
        if run.folder is not None:
            return load_record(run.folder)
        steps = [step.as_dict() for step in run.result.steps]
        return Record(None, dict(run.result.samples), {**run.meta, "steps": steps}, run.summary)
    if isinstance(run, RunResult):
        if run.folder is not None:
            return load_record(run.folder)
        return Record(None, dict(run.samples), {"steps": [step.as_dict() for step in run.steps]}, None)
    raise TypeError(
        f"expected a run folder, a Record, a RunResult or an Experiment, got {type(run).__name__}"
    )


def has(record: Record, *keys: str) -> bool:
    """True if every key is present with at least one sample."""
    return all(key in record.data and len(record.data[key]) > 0 for key in keys)


def valid(record: Record) -> np.ndarray:
    """Samples where the estimator reports valid, finite kinematics."""
    estimate = record.data["est_coordinates"]
    return record.data["est_kinematics_valid"].astype(bool) & np.isfinite(estimate).all(axis=1)


def half_length(record: Record) -> float:
    """The hand's ``l_h`` (m) of a run's ``meta.json`` (the default hand's if the run did not say)."""
    params = record.meta.get("params", {})
    hand = params.get("hand", {}) if isinstance(params, dict) else {}
    value = hand.get("half_length") if isinstance(hand, dict) else None
    return float(value) if isinstance(value, int | float) else Hand().half_length


def true_object(record: Record) -> PlanarObject | None:
    """The object of ``meta.json`` (SI), or None if the run did not record a valid one."""
    spec = record.meta.get("object")
    try:
        return PlanarObject(spec["name"], spec["vertices"], spec["mass"], spec["mu_hand"], spec["mu_ground"])
    except (KeyError, TypeError, ValueError):
        return None


def _object_offset(record: Record, obj: PlanarObject) -> float | None:
    """The angle (rad) to add to the angle of the hand's face to get the object's body angle."""
    start = record.meta.get("params", {}).get("start", {})
    try:
        face = start.get("hand_face", StartConfig().hand_face)
        return -geometry.face_angle(obj.face_normal(face), 0.0)
    except (AttributeError, TypeError, ValueError):
        return None


def polygon(vertices: np.ndarray, offset: float, theta_o: float, r_o: np.ndarray) -> np.ndarray:
    """World vertices of the object at angle ``θ_o + offset`` whose lowest vertex is at ``r_o`` (m)."""
    turned = geometry.transform_points(vertices, (0.0, 0.0, theta_o + offset))
    return turned - turned[geometry.lowest_vertex(turned)] + r_o


def upward(row: np.ndarray) -> np.ndarray:
    """The direction along the line ``a·f = b`` of a ground row ``a`` that points up (+y)."""
    along = np.array([-row[1], row[0]])
    return along if along[1] >= 0.0 else -along


def wedge(apex: np.ndarray, directions: Sequence[np.ndarray], length: float) -> np.ndarray:
    """Polygon of ``apex`` and ``apex + length·u`` for the unit vector ``u`` of each direction."""
    units = (np.asarray(u, dtype=float) / np.linalg.norm(u) for u in directions)
    return np.vstack([apex, *(apex + length * u for u in units)])


@dataclass(frozen=True)
class Frame:
    """The scene at one sample, m, world frame; None where unknown.

    Attributes:
        time: simulated time, s.
        object: the true object polygon (``(n, 2)``), from the true configuration and the object model.
        hand: the true hand's contact face, its two ends (``(2, 2)``).
        r_o, r_o_est: the true and the estimated ground contact.
        r_h_est: the measured hand centre where the kinematics are estimated.
        chain, chain_est: ``r_o → r_o − d e_n → r_h`` (``(3, 2)``), true and estimated: the contact
            geometry ``d`` and ``s_h`` drawn from the ground contact to the hand.
        hand_cone, hand_cone_true: the estimated (``μ̂_h``, at the measured hand) and the true
            (``μ_h``, at the true hand) hand friction cone, a wedge ``apex, edge, edge``.
        ground_cone, ground_cone_true: the estimated ground cone (the directions of its rows' lines,
            at the estimated ground contact) and the true one (``|f_x| ≤ μ_g f_y`` of the ground's
            force, at the true ground contact), as wedges.
        force, force_true: the measured and the true force of the hand on the object, N (world).
    """

    time: float
    object: np.ndarray | None
    hand: np.ndarray
    r_o: np.ndarray
    r_o_est: np.ndarray | None
    r_h_est: np.ndarray | None
    chain: np.ndarray
    chain_est: np.ndarray | None
    hand_cone: np.ndarray | None
    hand_cone_true: np.ndarray | None
    ground_cone: np.ndarray | None
    ground_cone_true: np.ndarray | None
    force: np.ndarray | None
    force_true: np.ndarray


SCENE_KEYS = (
    "time",
    "hand_pose",
    "hand_wrench",
    "true_hand_pose",
    "true_hand_wrench",
    "true_coordinates",
    "true_d",
    "est_coordinates",
    "est_d",
    "est_kinematics_valid",
    "est_mu_h",
    "est_ground_rows",
)
"""Series :func:`scene` needs."""


def _chain(r_o: np.ndarray, d: float, theta: float, r_h: np.ndarray) -> np.ndarray:
    return np.vstack([r_o, r_o - d * geometry.hand_normal(theta), r_h])


def scene(record: Record, frames: np.ndarray) -> list[Frame]:
    """The :class:`Frame` of each sample index in ``frames`` (the record must hold :data:`SCENE_KEYS`).
    The cones are drawn ``2 l_h`` long."""
    data = record.data
    l_h = half_length(record)
    length = 2.0 * l_h
    true_pose, pose = data["true_hand_pose"][frames], data["hand_pose"][frames]
    true_c, est_c = data["true_coordinates"][frames], data["est_coordinates"][frames]
    r_o = geometry.ground_contact(true_pose, true_c[:, 1], data["true_d"][frames])
    r_est = geometry.ground_contact(pose, est_c[:, 1], data["est_d"][frames])
    usable = valid(record)[frames] & np.isfinite(pose).all(axis=1)
    obj = true_object(record)
    offset = _object_offset(record, obj) if obj is not None else None
    out = []
    for j, i in enumerate(frames):
        mu, rows = data["est_mu_h"][i], data["est_ground_rows"][i]
        theta, true_theta = pose[j, 2], true_pose[j, 2]
        e_t, e_n = geometry.hand_tangent(theta), geometry.hand_normal(theta)
        measured = bool(np.isfinite(pose[j]).all())
        t_t, t_n = geometry.hand_tangent(true_theta), geometry.hand_normal(true_theta)
        hand_cone = None
        if measured and np.isfinite(mu):
            hand_cone = wedge(pose[j, :2], (e_n + mu * e_t, e_n - mu * e_t), length)
        ground_ok = usable[j] and np.isfinite(rows).all()
        force = geometry.wrench_hand_to_world(theta, data["hand_wrench"][i])[:2] if measured else None
        out.append(
            Frame(
                time=float(data["time"][i]),
                object=polygon(obj.vertices, offset, true_c[j, 0], r_o[j]) if offset is not None else None,
                hand=true_pose[j, :2] + np.outer([-l_h, l_h], t_t),
                r_o=r_o[j],
                r_o_est=r_est[j] if usable[j] else None,
                r_h_est=pose[j, :2] if usable[j] else None,
                chain=_chain(r_o[j], float(data["true_d"][i]), true_theta, true_pose[j, :2]),
                chain_est=_chain(r_est[j], float(data["est_d"][i]), theta, pose[j, :2])
                if usable[j]
                else None,
                hand_cone=hand_cone,
                hand_cone_true=wedge(
                    true_pose[j, :2], (t_n + obj.mu_hand * t_t, t_n - obj.mu_hand * t_t), length
                )
                if obj is not None
                else None,
                ground_cone=wedge(r_est[j], [upward(a) for a in rows], length) if ground_ok else None,
                ground_cone_true=wedge(r_o[j], [(obj.mu_ground, 1.0), (-obj.mu_ground, 1.0)], length)
                if obj is not None
                else None,
                force=force if force is not None and np.isfinite(force).all() else None,
                force_true=geometry.wrench_hand_to_world(true_theta, data["true_hand_wrench"][i])[:2],
            )
        )
    return out
