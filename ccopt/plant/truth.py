"""Ground truth of the contact configuration, from the simulator's state (metrics and plots only).

The estimator and controller never read this module's output. Conventions are those of
:mod:`ccopt.geometry`; :func:`compute_truth` is a pure function of poses and velocities so that
every plant reports truth the same way.

Thresholds:
    * a contact slides when its sliding speed exceeds :data:`SLIDE_SPEED` (1 mm/s). At the hand
      the sliding speed is the tangential (``e_t``) velocity of the object's material point at the
      hand-face centre relative to the hand; it equals ``ṡ_h`` while the hand is flush and, unlike
      ``ṡ_h``, ignores the small relative rotations of a compliant flush contact (the tangential
      relative velocity is the same at every point of the face line). At the ground it is
      ``ṡ_g``, the horizontal velocity of the object's material point at its lowest vertex;
    * the hand pivots when ``|θ_o − θ_h|`` exceeds :data:`PIVOT_ANGLE` (0.5°).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike

from ccopt import geometry, validation
from ccopt.objects import PlanarObject

SLIDE_SPEED = 1e-3
"""Sliding-speed threshold, m/s: slower contacts are reported as sticking."""

PIVOT_ANGLE = math.radians(0.5)
"""Hand pivoting threshold on ``|θ_o − θ_h|``, rad: smaller is reported as flush."""

GROUND_VERTEX_HYSTERESIS = 1e-3
"""m: the vertex that was the ground contact stays it while it is within this height of the lowest.
An object lying on a face touches the ground at two vertices whose heights differ by the contacts'
compliance (tenths of a millimetre): the lowest alone flips between them, and with it ``s_g`` by a
face's length, while the vertex the object pivoted about, which the coordinates mean, still
touches."""


@dataclass(frozen=True)
class Truth:
    """True contact configuration at one instant.

    Attributes:
        time: s.
        theta_o: orientation of the object face the hand is on, rad (same convention as ``θ_h``,
            unwrapped to within ±π of ``θ_h``).
        s_h: ``(r_o − r_h)·e_t`` with ``e_t`` of the hand, m.
        s_g: ``x_o``, m.
        d: ``(r_o − r_h)·e_n`` with ``e_n`` of the hand, m.
        r_o: ground contact (the object's lowest vertex), world, m.
        object_pose: object centroid and angle, world ``(x, y, φ)``, m and rad.
        hand_mode: −1 / 0 / +1 for sliding with ``ṡ_h < 0`` / sticking / ``ṡ_h > 0``.
        hand_geometry: −1 / 0 / +1 for pivoting with ``θ_o − θ_h < 0`` / flush / ``> 0``.
        ground_mode: −1 / 0 / +1 for sliding with ``ṡ_g < 0`` / sticking / ``ṡ_g > 0``.
        in_contact_hand: the hand touches the object.
        in_contact_ground: the object touches the ground.
        hand_slip_rate: object-relative-to-hand sliding velocity along ``e_t`` at the hand, m/s
            (``ṡ_h`` while flush).
        ground_slip_rate: ``ṡ_g``, m/s.
        ground_vertex: index of the object's vertex that is the ground contact.
    """

    time: float
    theta_o: float
    s_h: float
    s_g: float
    d: float
    r_o: np.ndarray
    object_pose: np.ndarray
    hand_mode: int
    hand_geometry: int
    ground_mode: int
    in_contact_hand: bool
    in_contact_ground: bool
    hand_slip_rate: float
    ground_slip_rate: float
    ground_vertex: int = 0


def _mode(rate: float, threshold: float) -> int:
    return 0 if abs(rate) <= threshold else int(math.copysign(1.0, rate))


def point_velocity(pose: ArrayLike, velocity: ArrayLike, point: ArrayLike) -> np.ndarray:
    """World velocity of a material ``point`` of a body with ``pose`` and ``velocity`` ``(ẋ, ẏ, ω)``."""
    x, y, _ = np.asarray(pose, dtype=float).tolist()
    px, py = np.asarray(point, dtype=float).tolist()
    return np.array(_point_velocity(x, y, np.asarray(velocity, dtype=float).tolist(), px, py))


def _point_velocity(x: float, y: float, velocity: list[float], px: float, py: float) -> tuple[float, float]:
    """:func:`point_velocity` of the point ``(px, py)`` of a body at ``(x, y)``, in floats."""
    vx, vy, omega = velocity
    px, py = px - x, py - y
    return vx - omega * py, vy + omega * px


def ground_vertex(xs: list[float], ys: list[float], previous: int | None) -> int:
    """The ground contact's vertex of a polygon whose world vertices are at ``(xs[k], ys[k])`` (m):
    the lowest (:func:`ccopt.geometry.lowest_of`), or ``previous`` while it is within
    :data:`GROUND_VERTEX_HYSTERESIS` of that one."""
    vertex = geometry.lowest_of(xs, ys)
    if previous is not None and ys[previous] <= ys[vertex] + GROUND_VERTEX_HYSTERESIS:
        return previous
    return vertex


def compute_truth(
    time: float,
    obj: PlanarObject,
    hand_face: int,
    object_pose: ArrayLike,
    object_velocity: ArrayLike,
    hand_pose: ArrayLike,
    hand_velocity: ArrayLike,
    in_contact_hand: bool,
    in_contact_ground: bool,
    previous_vertex: int | None = None,
) -> Truth:
    """Truth from the object pose/velocity (centroid, world ``(x, y, φ)``) and the hand pose/velocity
    (contact-face centre, world ``(x, y, θ)``); units m, rad, m/s, rad/s. The ground contact is the
    lowest vertex, or ``previous_vertex`` (the last one) while within :data:`GROUND_VERTEX_HYSTERESIS`
    of it. Worked out in floats (the values of the NumPy expressions of :mod:`ccopt.geometry`: a
    record sample reads it), the vertices but through :func:`ccopt.geometry.transform_points`."""
    object_pose = np.array(object_pose, dtype=float)
    x, y, phi = object_pose.tolist()
    x_h, y_h, theta_h = np.asarray(hand_pose, dtype=float).tolist()
    world_vertices = geometry.transform_points(obj.vertices, object_pose)
    xs, ys = world_vertices.T.tolist()
    vertex = ground_vertex(xs, ys, previous_vertex)
    r_o, x_o, y_o = world_vertices[vertex], xs[vertex], ys[vertex]
    axes = geometry.hand_axes(theta_h)
    d, s_h = geometry.world_to_hand(axes, x_o - x_h, y_o - y_h)  # geometry.contact_coordinates
    raw = geometry.face_angle(obj.face_normals[obj.face_index(hand_face)], phi)
    theta_o = theta_h + geometry.wrap_angle(raw - theta_h)
    velocity = np.asarray(object_velocity, dtype=float).tolist()
    v_x, v_y, _ = np.asarray(hand_velocity, dtype=float).tolist()
    contact_x, contact_y = _point_velocity(x, y, velocity, x_h, y_h)
    hand_slip_rate = geometry.world_to_hand(axes, contact_x - v_x, contact_y - v_y)[1]
    ground_slip_rate = _point_velocity(x, y, velocity, x_o, y_o)[0]
    delta = theta_o - theta_h
    return validation.trusted(  # every field, each well formed by construction (a record sample's)
        Truth,
        {
            "time": float(time),
            "theta_o": theta_o,
            "s_h": s_h,
            "s_g": x_o,
            "d": d,
            "r_o": r_o,
            "object_pose": object_pose,
            "hand_mode": _mode(hand_slip_rate, SLIDE_SPEED),
            "hand_geometry": _mode(delta, PIVOT_ANGLE),
            "ground_mode": _mode(ground_slip_rate, SLIDE_SPEED),
            "in_contact_hand": bool(in_contact_hand),
            "in_contact_ground": bool(in_contact_ground),
            "hand_slip_rate": hand_slip_rate,
            "ground_slip_rate": ground_slip_rate,
            "ground_vertex": vertex,
        },
    )
