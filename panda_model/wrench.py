"""Wrist force/torque sensing: from the flange wrench to the hand wrench ``(f_n, f_t, τ)``.

The F/T sensor sits on the flange, between the arm and the hand plate. It measures the wrench the
flange exerts on the plate: force (N) and torque (N·m) about the flange origin, flange frame. The plate
is in static balance between that wrench, its own weight and the reaction of the object, so the wrench
the hand exerts on the object is the sensed wrench plus the plate's weight (inertial forces of the
plate are neglected: quasi-static). It is then taken about the contact face centre and projected on
the hand frame of :mod:`ccopt.geometry`: ``f_n`` along ``e_n``, ``f_t`` along ``e_t``, ``τ`` CCW.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike

from ccopt.geometry import GRAVITY, Array
from panda_model.hand import HandPlate


def _cross(a: Array, b: Array) -> Array:
    """Cross product of two 3-vectors (``np.cross`` costs ten times more on 3-vectors)."""
    return np.array([a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]])


def hand_wrench(flange_wrench: ArrayLike, flange_rotation: ArrayLike, hand: HandPlate) -> Array:
    """Hand wrench ``(f_n, f_t, τ)`` (N, N, N·m) exerted on the object, from the wrist F/T reading.

    Args:
        flange_wrench: ``(f_x, f_y, f_z, m_x, m_y, m_z)``, the wrench of the flange on the plate,
            flange frame, torque about the flange origin.
        flange_rotation: 3×3 world rotation of the flange frame (world ``z`` up).
        hand: the plate, whose weight is compensated and whose face centre is the torque point.
    """
    wrench = np.asarray(flange_wrench, dtype=float)
    rot = np.asarray(flange_rotation, dtype=float)
    if wrench.shape != (6,) or rot.shape != (3, 3):
        raise ValueError(f"expected a 6-vector wrench and a 3×3 rotation, got {wrench.shape}, {rot.shape}")
    weight = rot[2] * (-hand.mass * GRAVITY)
    force = wrench[:3] + weight
    torque = wrench[3:] + _cross(hand.centre_of_mass, weight) - _cross(hand.face_centre, force)
    axes = hand.rotation  # columns: e_t, out-of-plane (CCW) axis, e_n, in the flange frame
    return np.array([axes[:, 2] @ force, axes[:, 0] @ force, axes[:, 1] @ torque])
