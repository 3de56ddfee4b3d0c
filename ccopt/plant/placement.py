"""Where a run starts: the object on one vertex, the hand flush on one of its faces (start geometry).

Shared by both MuJoCo plants, the closed loop, the plots and the studies. Frames and signs are those of
:mod:`ccopt.geometry`; a start is a :class:`~ccopt.plant.base.StartConfig` (the face, its angle
``θ_o``, the hand's ``s_h``, the ground contact's ``x_o`` and the pressing force).
"""

from __future__ import annotations

import dataclasses

import numpy as np

from ccopt import geometry
from ccopt.hand import Hand
from ccopt.objects import PlanarObject
from ccopt.plant.base import StartConfig


def placed_object(obj: PlanarObject, start: StartConfig) -> tuple[np.ndarray, float, np.ndarray]:
    """Object pose, ``d`` and the hand face's end points (world) of a start configuration."""
    face = obj.face_index(start.hand_face)
    angle = geometry.object_angle_for_face(obj.face_normal(face), start.theta_o)
    rotated = geometry.transform_points(obj.vertices, (0.0, 0.0, angle))
    lowest = rotated[geometry.lowest_vertex(rotated)]
    centroid = np.array([start.x_o, 0.0]) - lowest
    object_pose = np.array([centroid[0], centroid[1], angle])
    r_o = np.array([start.x_o, 0.0])
    face_ends = np.array([rotated[face], rotated[(face + 1) % obj.n_faces]]) + centroid
    d = float((r_o - face_ends[0]) @ geometry.hand_normal(start.theta_o))
    return object_pose, d, face_ends


def face_s_h_range(obj: PlanarObject, start: StartConfig) -> tuple[float, float]:
    """Range of ``s_h`` (m) that keeps the hand centre on the start face (``start.s_h`` ignored)."""
    _, _, face_ends = placed_object(obj, start)
    along = sorted(
        float((np.array([start.x_o, 0.0]) - p) @ geometry.hand_tangent(start.theta_o)) for p in face_ends
    )
    return along[0], along[1]


def hand_over_vertex(obj: PlanarObject, start: StartConfig, hand: Hand) -> StartConfig:
    """``start`` with ``s_h`` as close to 0 as the whole hand allows (m).

    ``s_h = 0`` puts the hand centre straight over the ground contact along ``e_n``, where the normal
    push has no moment about the contact (the paper's Fig. 2a); the hand is kept its half-length plus
    2 mm inside the face's ends, so it lies flush over its whole length.
    """
    low, high = face_s_h_range(obj, start)
    inset = hand.half_length + 2e-3
    if high - low < 2.0 * inset:
        fitting = [k for k in range(obj.n_faces) if obj.face_length(k) >= 2.0 * inset]
        others = f"faces {', '.join(map(str, fitting))} fit" if fitting else f"no face of {obj.name} fits"
        raise ValueError(
            f"face {obj.face_index(start.hand_face)} of {obj.name} ({high - low:.3f} m) is shorter "
            f"than the hand ({2.0 * hand.half_length:.3f} m, {2e3 * inset:.0f} mm with its margins); {others}"
        )
    return dataclasses.replace(start, s_h=float(np.clip(0.0, low + inset, high - inset)))


def start_poses(
    obj: PlanarObject, start: StartConfig, hand: Hand
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Object pose, hand pose and impedance target of a start configuration, world ``(x, y, θ)``.

    The object is turned so that the outward normal of ``start.hand_face`` is ``−e_n(θ_o)``, its
    lowest vertex touches the ground at ``x_o``; the hand lies flush on that face at ``s_h``; the
    target is the hand pose pushed ``K⁻¹ f_n e_n`` into the object.

    Raises:
        ValueError: the face does not exist, the hand centre is off the face, or the hand would
            cut the ground.
    """
    object_pose, d, _ = placed_object(obj, start)
    r_o = np.array([start.x_o, 0.0])
    e_n = geometry.hand_normal(start.theta_o)
    e_t = geometry.hand_tangent(start.theta_o)
    hand_pose = geometry.hand_pose_from_contact(start.theta_o, start.s_h, d, r_o)
    low, high = face_s_h_range(obj, start)
    if not low - 1e-9 <= start.s_h <= high + 1e-9:
        raise ValueError(
            f"s_h = {start.s_h} m puts the hand centre off face {obj.face_index(start.hand_face)} of "
            f"{obj.name} (admissible s_h: [{low:.4f}, {high:.4f}] m)"
        )
    corners = [
        hand_pose[:2] + a * hand.half_length * e_t - b * hand.thickness * e_n
        for a in (-1.0, 1.0)
        for b in (0.0, 1.0)
    ]
    if min(c[1] for c in corners) < 0.0:
        raise ValueError(
            f"the hand would cut the ground at theta_o = {start.theta_o} rad, s_h = {start.s_h} m "
            f"on face {obj.face_index(start.hand_face)} of {obj.name}"
        )
    offset = start.normal_force * e_n / np.asarray(hand.stiffness[:2])
    target = hand_pose + np.array([offset[0], offset[1], 0.0])
    return object_pose, hand_pose, target
