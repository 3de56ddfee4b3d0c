"""Planar conventions of ccopt: the one place where frames, signs and polygons are defined.

World plane
    ``x`` horizontal (the paper's I), ``y`` vertical up (the paper's J), gravity along ``-y``.
    Angles are counter-clockwise positive, in radians. Units are SI throughout.

Hand pose ``x_h = (x_h, y_h, θ_h)``
    The centre of the hand's contact face and its orientation. At ``θ_h = 0`` the hand lies
    horizontally *above* the object and pushes down.

Hand contact frame
    ``e_n`` is the unit normal from the hand into the object, ``e_t`` is ``e_n`` rotated by +90°::

        e_t(θ) = ( cos θ, sin θ)        e_n(θ) = ( sin θ, -cos θ)

    Hand-frame vectors are ordered ``(n, t, θ)``: a hand wrench is ``w_h = (f_n, f_t, τ)`` — the
    wrench the hand exerts on the object, ``f_n > 0`` when pushing, ``τ`` about the centre of the
    hand face (CCW positive) — and a hand-frame pose increment is ``(Δn, Δt, Δθ)``.

Kinematics (paper eqs. 14–16)
    ``r_h = r_o − s_h e_t − d e_n`` while the hand is flush (``θ_o = θ_h``), with ``r_o = (x_o, y_o)``
    the ground contact, ``s_g = x_o``, ``s_h = (r_o − r_h)·e_t`` and ``d = (r_o − r_h)·e_n``.

Centre of pressure and positions on the face
    A hand wrench acts at ``c e_t`` from the hand face's centre, ``c = −τ/f_n`` (a push ``f_n e_n`` at
    ``c e_t`` has the moment ``τ = −c f_n`` about the centre): :func:`centre_of_pressure`. A point of
    the object's face at hand position ``c`` lies ``u = c − s_h`` along ``e_t`` from the foot of the
    ground contact on the face's line; ``u`` is fixed in the object while the hand slides and the
    object turns (:func:`face_position`).

In MuJoCo the plane is x–z: ``(x, y)_ccopt = (x, z)_mujoco``; hinge joints use axis ``(0, -1, 0)``
so that ``qpos`` equals the CCW planar angle.
"""

from __future__ import annotations

import math

import casadi as ca
import numpy as np
from numpy.typing import ArrayLike, NDArray

GRAVITY = 9.81
"""Magnitude of gravity, m/s², acting along ``-y``."""

WORLD_UP = (0.0, 1.0)
"""The world's up ``+y`` (against gravity), as the robot knows it from gravity."""

Array = NDArray[np.float64]


def rotation(theta: float) -> Array:
    """2×2 rotation matrix of a CCW angle ``theta`` (rad)."""
    c, s = math.cos(theta), math.sin(theta)
    return np.array(((c, -s), (s, c)))


def wrap_angle(theta: ArrayLike) -> Array | float:
    """Angle(s) wrapped to ``[-π, π)``."""
    if isinstance(theta, float):  # Python's float remainder is NumPy's: the same value, cheaper
        return (theta + math.pi) % (2.0 * math.pi) - math.pi
    wrapped = (np.asarray(theta, dtype=float) + np.pi) % (2.0 * np.pi) - np.pi
    return float(wrapped) if np.ndim(wrapped) == 0 else wrapped


def _is_symbolic(value: object) -> bool:
    return isinstance(value, ca.SX | ca.MX)


def hand_normal(theta_h: float | ca.SX | ca.MX) -> Array | ca.SX | ca.MX:
    """``e_n``: unit normal from the hand into the object, world frame, for hand angle ``θ_h``.

    Accepts a float (returns a NumPy vector) or a CasADi symbol (returns a CasADi column).
    """
    if isinstance(theta_h, float):  # math's sine and cosine: NumPy's values, without its overhead
        return np.array((math.sin(theta_h), -math.cos(theta_h)))
    if _is_symbolic(theta_h):
        return ca.vertcat(ca.sin(theta_h), -ca.cos(theta_h))
    return np.array([np.sin(theta_h), -np.cos(theta_h)])


def hand_tangent(theta_h: float | ca.SX | ca.MX) -> Array | ca.SX | ca.MX:
    """``e_t``: ``e_n`` rotated by +90°, world frame (NumPy or CasADi, like :func:`hand_normal`)."""
    if isinstance(theta_h, float):
        return np.array((math.cos(theta_h), math.sin(theta_h)))
    if _is_symbolic(theta_h):
        return ca.vertcat(ca.cos(theta_h), ca.sin(theta_h))
    return np.array([np.cos(theta_h), np.sin(theta_h)])


def hand_axes(theta_h: float) -> Axes:
    """``(e_n, e_t)`` of :func:`hand_normal` and :func:`hand_tangent` as plain floats (the same values),
    for code that runs every sample."""
    s, c = math.sin(theta_h), math.cos(theta_h)
    return (s, -c), (c, s)


Axes = tuple[tuple[float, float], tuple[float, float]]
"""``(e_n, e_t)`` as plain floats (:func:`hand_axes`)."""


def hand_to_world(axes: Axes, n: float, t: float) -> tuple[float, float]:
    """The world vector ``n e_n + t e_t`` of hand-frame components ``(n, t)``, with ``axes`` from
    :func:`hand_axes` (plain floats; the values of :func:`hand_force_to_world`)."""
    (nx, ny), (tx, ty) = axes
    return n * nx + t * tx, n * ny + t * ty


def world_to_hand(axes: Axes, x: float, y: float) -> tuple[float, float]:
    """The hand-frame components ``(e_n·v, e_t·v)`` of the world vector ``v = (x, y)``, with ``axes``
    from :func:`hand_axes` (plain floats; the inverse of :func:`hand_to_world`)."""
    (nx, ny), (tx, ty) = axes
    return x * nx + y * ny, x * tx + y * ty


def hand_frame(theta_h: float | ca.SX | ca.MX) -> Array | ca.SX | ca.MX:
    """2×2 matrix whose columns are ``e_n`` and ``e_t``: maps hand-frame ``(n, t)`` to world ``(x, y)``."""
    if _is_symbolic(theta_h):
        return ca.horzcat(hand_normal(theta_h), hand_tangent(theta_h))
    return np.column_stack((hand_normal(theta_h), hand_tangent(theta_h)))


def planar_hand_to_world(theta_h: float) -> Array:
    """3×3 map of hand-frame ``(n, t, θ)`` vectors (forces/torque or displacements) to world ``(x, y, θ)``."""
    (nx, ny), (tx, ty) = hand_axes(theta_h)
    return np.array((nx, tx, 0.0, ny, ty, 0.0, 0.0, 0.0, 1.0)).reshape(3, 3)


def wrench_hand_to_world(theta_h: float, wrench_hand: ArrayLike) -> Array:
    """Hand wrench ``(f_n, f_t, τ)`` to world ``(f_x, f_y, τ)``; the torque stays about the hand centre."""
    return planar_hand_to_world(theta_h) @ np.asarray(wrench_hand, dtype=float)


def wrench_world_to_hand(theta_h: float, wrench_world: ArrayLike) -> Array:
    """World ``(f_x, f_y, τ)`` (torque about the hand centre) to hand-frame ``(f_n, f_t, τ)``.

    Written out (``f_n = e_n·f``, ``f_t = e_t·f``) because plants and sensors call it every tick.
    """
    s, c = math.sin(theta_h), math.cos(theta_h)
    f_x, f_y, torque = np.asarray(wrench_world, dtype=float).tolist()
    return np.array([s * f_x - c * f_y, c * f_x + s * f_y, torque])


def hand_force_to_world(theta_h: float, f_n: float, f_t: float) -> Array:
    """Hand-frame force ``(f_n, f_t)`` (N) to the world force ``f_n e_n + f_t e_t`` (N)."""
    return f_n * hand_normal(theta_h) + f_t * hand_tangent(theta_h)


def twist_hand_to_world(theta_h: float, twist_hand: ArrayLike) -> Array:
    """Hand-frame increment ``(Δn, Δt, Δθ)`` of the hand pose to the world increment ``(Δx, Δy, Δθ)``.

    In floats (:func:`hand_to_world`, ``Δr = Δn e_n + Δt e_t``) because the loop calls it every
    control tick.
    """
    dn, dt, dtheta = np.asarray(twist_hand, dtype=float).tolist()
    return np.array((*hand_to_world(hand_axes(theta_h), dn, dt), dtheta))


def twist_world_to_hand(theta_h: float, twist_world: ArrayLike) -> Array:
    """World increment ``(Δx, Δy, Δθ)`` of the hand pose to the hand frame ``(Δn, Δt, Δθ)``
    (``Δn = e_n·Δr``, ``Δt = e_t·Δr``)."""
    dx, dy, dtheta = np.asarray(twist_world, dtype=float).tolist()
    return np.array((*world_to_hand(hand_axes(theta_h), dx, dy), dtheta))


def shift_torque(wrench_world: ArrayLike, from_point: ArrayLike, to_point: ArrayLike) -> Array:
    """Re-express a planar world wrench's torque about ``to_point`` instead of ``from_point`` (m)."""
    fx, fy, tau = np.asarray(wrench_world, dtype=float).tolist()
    rx, ry = (np.asarray(from_point, dtype=float) - np.asarray(to_point, dtype=float)).tolist()
    return np.array((fx, fy, tau + rx * fy - ry * fx))


def hand_pose_from_contact(theta_o: float, s_h: float, d: float, r_o: ArrayLike) -> Array:
    """World hand pose ``(x_h, y_h, θ_h)`` of a flush hand (``θ_h = θ_o``), paper eq. 14.

    ``s_h`` and ``d`` in m, ``r_o = (x_o, y_o)`` the ground contact (m), ``theta_o`` (rad).
    Works on floats or CasADi symbols (then ``r_o`` is a 2-vector symbol).
    """
    if _is_symbolic(theta_o):
        r_h = r_o - s_h * hand_tangent(theta_o) - d * hand_normal(theta_o)
        return ca.vertcat(r_h, theta_o)
    r_h = np.asarray(r_o, dtype=float) - s_h * hand_tangent(theta_o) - d * hand_normal(theta_o)
    return np.array([r_h[0], r_h[1], theta_o])


def contact_coordinates(hand_pose: ArrayLike, r_o: ArrayLike) -> tuple[float, float]:
    """``(s_h, d)`` of the ground contact ``r_o`` seen from the hand pose (paper eqs. 14, 16), m."""
    pose = np.asarray(hand_pose, dtype=float)
    rel = np.asarray(r_o, dtype=float) - pose[:2]
    theta_h = pose.item(2)
    return float(rel @ hand_tangent(theta_h)), float(rel @ hand_normal(theta_h))


def centre_of_pressure(f_n: float, torque: float) -> float:
    """Where the hand wrench acts along ``e_t`` from the hand face's centre, ``c = −τ/f_n`` (m; N, N·m)."""
    return -torque / f_n


def face_position(hand_position: float, s_h: float) -> float:
    """The position ``u = c − s_h`` (m) along ``e_t``, from the ground contact's foot on the face's
    line, of the face point at hand position ``c`` (m) (module docstring)."""
    return hand_position - s_h


def ground_contact(hand_pose: ArrayLike, s_h: ArrayLike, d: ArrayLike) -> Array:
    """The ground contact ``r_o = r_h + s_h e_t + d e_n`` (m) of a flush hand (paper eq. 14 solved
    for ``r_o``); ``hand_pose`` ``(3,)`` or ``(N, 3)`` with ``s_h``, ``d`` scalars or ``(N,)``."""
    pose = np.asarray(hand_pose, dtype=float)
    theta = pose[..., 2]
    s_h, d = np.asarray(s_h, dtype=float)[..., None], np.asarray(d, dtype=float)[..., None]
    e_t, e_n = np.moveaxis(hand_tangent(theta), 0, -1), np.moveaxis(hand_normal(theta), 0, -1)
    return pose[..., :2] + s_h * e_t + d * e_n


def face_angle(outward_normal: ArrayLike, object_angle: float) -> float:
    """World orientation ``θ`` (rad) of an object face whose outward normal is ``outward_normal`` in the
    object's body frame, for the object at ``object_angle``: the face's outward normal is ``−e_n(θ)``,
    so that a hand at ``θ_h = θ`` lies flush on it."""
    normal = np.asarray(outward_normal, dtype=float)
    return object_angle + math.atan2(normal[1], normal[0]) - 0.5 * math.pi


def object_angle_for_face(outward_normal: ArrayLike, theta_o: float) -> float:
    """The object angle (rad) that turns a face with body-frame ``outward_normal`` to ``θ_o``
    (the inverse of :func:`face_angle`)."""
    normal = np.asarray(outward_normal, dtype=float)
    return theta_o + 0.5 * math.pi - math.atan2(normal[1], normal[0])


# --- polygons -----------------------------------------------------------------------------------


def as_polygon(vertices: ArrayLike) -> Array:
    """Vertices as an ``(n, 2)`` float array; raises ``ValueError`` unless ``n ≥ 3`` and all finite."""
    poly = np.asarray(vertices, dtype=float)
    if poly.ndim != 2 or poly.shape[1] != 2:
        raise ValueError(f"polygon vertices must have shape (n, 2), got {poly.shape}")
    if poly.shape[0] < 3:
        raise ValueError(f"a polygon needs at least 3 vertices, got {poly.shape[0]}")
    if not np.all(np.isfinite(poly)):
        raise ValueError("polygon vertices must be finite numbers")
    return poly


def signed_area(vertices: ArrayLike) -> float:
    """Signed area (m²), positive for counter-clockwise vertex order (shoelace formula)."""
    poly = as_polygon(vertices)
    x, y = poly[:, 0], poly[:, 1]
    return 0.5 * float(np.dot(x, np.roll(y, -1)) - np.dot(np.roll(x, -1), y))


def centroid(vertices: ArrayLike) -> Array:
    """Area centroid of a simple polygon (m)."""
    poly = as_polygon(vertices)
    x, y = poly[:, 0], poly[:, 1]
    xn, yn = np.roll(x, -1), np.roll(y, -1)
    cross = x * yn - xn * y
    area = 0.5 * cross.sum()
    if abs(area) < 1e-15:
        raise ValueError("degenerate polygon: zero area")
    return np.array([((x + xn) * cross).sum(), ((y + yn) * cross).sum()]) / (6.0 * area)


def is_convex(vertices: ArrayLike, tol: float = 1e-12) -> bool:
    """True if the polygon is strictly convex and simple, in either orientation."""
    poly = as_polygon(vertices)
    edges = np.roll(poly, -1, axis=0) - poly
    turns = edges[:, 0] * np.roll(edges[:, 1], -1) - edges[:, 1] * np.roll(edges[:, 0], -1)
    if not (np.all(turns > tol) or np.all(turns < -tol)):
        return False
    # Strict, same-sign turns with a total winding of exactly one turn rule out star polygons.
    headings = np.arctan2(edges[:, 1], edges[:, 0])
    winding = np.sum(wrap_angle(np.roll(headings, -1) - headings))
    return bool(abs(abs(winding) - 2.0 * np.pi) < 1e-6)


def lamina_inertia(vertices: ArrayLike, mass: float) -> float:
    """Polar moment of inertia (kg·m²) of a uniform lamina about its centroid, out-of-plane axis."""
    poly = as_polygon(vertices) - centroid(vertices)
    x, y = poly[:, 0], poly[:, 1]
    xn, yn = np.roll(x, -1), np.roll(y, -1)
    cross = x * yn - xn * y
    area = 0.5 * cross.sum()
    second_moment = (cross * (x * x + x * xn + xn * xn + y * y + y * yn + yn * yn)).sum() / 12.0
    return float(mass * second_moment / area)


def face_normal(vertices: ArrayLike, face: int) -> Array:
    """Outward unit normal of face ``face`` (from vertex ``face`` to ``face + 1``) of a CCW polygon."""
    poly = as_polygon(vertices)
    edge = poly[(face + 1) % len(poly)] - poly[face % len(poly)]
    return np.array([edge[1], -edge[0]]) / np.linalg.norm(edge)


LOWEST_TIE = 1e-4
"""Vertices within this height (m) of the lowest one tie for the ground contact."""


def lowest_vertex(world_vertices: ArrayLike) -> int:
    """Index of the ground-contact vertex of a polygon in world coordinates: the lowest, ties
    (:data:`LOWEST_TIE`) to the left-most (:func:`lowest_of`)."""
    xs, ys = np.asarray(world_vertices, dtype=float).T.tolist()
    return lowest_of(xs, ys)


def lowest_of(xs: list[float], ys: list[float]) -> int:
    """:func:`lowest_vertex` of the vertices ``(xs[k], ys[k])`` (m), in floats: the first of the
    left-most among those within :data:`LOWEST_TIE` of the lowest (the ground truth reads it every
    record sample)."""
    top = min(ys) + LOWEST_TIE
    vertex = -1
    for k, (x, y) in enumerate(zip(xs, ys, strict=True)):
        if y <= top and (vertex < 0 or x < xs[vertex]):
            vertex = k
    return vertex


def transform_points(points: ArrayLike, pose: ArrayLike) -> Array:
    """Points given in a body frame, mapped to the world by the body pose ``(x, y, θ)``."""
    x, y, theta = np.asarray(pose, dtype=float).tolist()
    return np.asarray(points, dtype=float) @ rotation(theta).T + np.array((x, y))
