"""Pinocchio model of the Panda with the hand plate: forward kinematics, Jacobians, inverse kinematics.

The model's world frame *is* MuJoCo's world frame: the robot base offset of :class:`~panda_model.hand.Mount`
is folded into the placement of joint 1, so every placement and Jacobian below is in world
coordinates. Planar quantities follow :mod:`ccopt.geometry`: ``(x, y)_ccopt = (x, z)_mujoco`` and the
CCW planar angle is a rotation about MuJoCo ``(0, −1, 0)``.

Task coordinates
    The controller and the impedance mapping use a 6-vector ordered *planar first*::

        (x, y, θ | y_out, roll, yaw) = (v_x, v_z, −ω_y | v_y, ω_x, ω_z)   (MuJoCo world components)

    of the hand frame (linear velocity of the contact face centre, angular velocity of the plate).
    ``TASK_AXES`` maps MuJoCo's ``(v, ω)`` to it; the first three rows are the planar ``(ẋ, ẏ, θ̇)``.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np
import pinocchio as pin
from numpy.typing import ArrayLike

from ccopt.geometry import Array, hand_normal, hand_tangent
from panda_model.hand import HandPlate, Mount
from panda_model.urdf import FLANGE_LINK, arm_urdf

HAND_FRAME = "hand"
"""Name of the operational frame at the contact face centre (axes ``e_t``, out-of-plane, ``e_n``)."""

TASK_AXES = np.array(
    [
        [1.0, 0.0, 0.0, 0.0, 0.0, 0.0],
        [0.0, 0.0, 1.0, 0.0, 0.0, 0.0],
        [0.0, 0.0, 0.0, 0.0, -1.0, 0.0],
        [0.0, 1.0, 0.0, 0.0, 0.0, 0.0],
        [0.0, 0.0, 0.0, 1.0, 0.0, 0.0],
        [0.0, 0.0, 0.0, 0.0, 0.0, 1.0],
    ]
)
"""Signed permutation (orthogonal) from world ``(v, ω)`` to task ``(x, y, θ, y_out, roll, yaw)``."""

NEUTRAL = np.array([0.0, -0.3, 0.0, -2.2, 0.0, 1.9, math.pi / 4])
"""An elbow-up configuration in the work plane, plate facing down: the default IK seed (rad)."""


@dataclass(frozen=True, eq=False)
class Panda:
    """The Pinocchio Panda with the hand plate appended to joint 7.

    Attributes:
        model: kinematics and inertia (plate included), world = MuJoCo world.
        data: scratch workspace; every function of this module overwrites it.
        hand_frame: frame id of :data:`HAND_FRAME`.
        flange_frame: frame id of the flange ``panda_link8``.
        hand: the plate geometry and mass.
        mount: where the base stands.
    """

    model: pin.Model
    data: pin.Data = field(repr=False)
    hand_frame: int
    flange_frame: int
    hand: HandPlate
    mount: Mount

    @property
    def nq(self) -> int:
        """Number of joints (7)."""
        return self.model.nq


def load_panda(hand: HandPlate | None = None, mount: Mount | None = None, armature: float = 0.0) -> Panda:
    """Build the 7-DoF Panda of example-robot-data with the hand plate on the flange.

    ``hand`` and ``mount`` default to :class:`HandPlate` and :class:`Mount` with their defaults.

    ``armature`` (kg·m²) is the reflected rotor inertia added to every joint; it enters the mass
    matrix only, never gravity or Coriolis terms.
    """
    if not (math.isfinite(armature) and armature >= 0.0):
        raise ValueError(f"armature must be a non-negative finite number (kg·m²), got {armature!r}")
    hand, mount = hand or HandPlate(), mount or Mount()
    model = pin.buildModelFromXML(arm_urdf())
    model.jointPlacements[1] = pin.SE3(np.eye(3), mount.base_position) * model.jointPlacements[1]
    model.armature[:] = armature
    flange = model.getFrameId(FLANGE_LINK)
    joint = model.frames[flange].parentJoint
    flange_in_joint = model.frames[flange].placement
    plate = pin.Inertia(hand.mass, hand.centre_of_mass, hand.inertia)
    model.addFrame(pin.Frame("hand_plate", joint, flange, flange_in_joint, pin.FrameType.BODY, plate), True)
    face = pin.SE3(hand.rotation, hand.face_centre)
    hand_id = model.addFrame(
        pin.Frame(HAND_FRAME, joint, flange, flange_in_joint * face, pin.FrameType.OP_FRAME)
    )
    return Panda(model, model.createData(), hand_id, flange, hand, mount)


def hand_rotation(theta: float) -> Array:
    """3×3 world rotation of the hand frame at planar angle ``theta`` (rad), plate in the work plane.

    Columns: ``e_t``, the out-of-plane axis MuJoCo ``(0, −1, 0)``, and ``e_n``, each from
    :mod:`ccopt.geometry` lifted to MuJoCo ``(x, y, z)``.
    """
    e_t, e_n = hand_tangent(theta), hand_normal(theta)
    return np.array([[e_t[0], 0.0, e_n[0]], [0.0, -1.0, 0.0], [e_t[1], 0.0, e_n[1]]])


def planar_pose(position: ArrayLike, rotation: ArrayLike) -> Array:
    """Planar ``(x, y, θ)`` (m, m, rad) of a hand frame at world ``position`` and 3×3 ``rotation``.

    The position is projected on the work plane; ``θ`` is the direction of the frame's ``x = e_t``.
    """
    p, rot = np.asarray(position, dtype=float), np.asarray(rotation, dtype=float)
    return np.array([p[0], p[2], math.atan2(rot[2, 0], rot[0, 0])])


def hand_placement(panda: Panda, q: ArrayLike) -> pin.SE3:
    """World placement of the hand frame at joint angles ``q`` (rad)."""
    pin.framesForwardKinematics(panda.model, panda.data, np.asarray(q, dtype=float))
    return panda.data.oMf[panda.hand_frame].copy()


def hand_pose(panda: Panda, q: ArrayLike) -> Array:
    """Planar hand pose ``(x_h, y_h, θ_h)`` (m, m, rad) at joint angles ``q``."""
    placement = hand_placement(panda, q)
    return planar_pose(placement.translation, placement.rotation)


def hand_jacobian(panda: Panda, q: ArrayLike) -> Array:
    """6×7 Jacobian of the hand frame, world-aligned: rows ``(v, ω)`` of the face centre, MuJoCo axes."""
    return pin.computeFrameJacobian(
        panda.model, panda.data, np.asarray(q, dtype=float), panda.hand_frame, pin.LOCAL_WORLD_ALIGNED
    )


def task_jacobian(jacobian: ArrayLike) -> Array:
    """6×7 task Jacobian ``(x, y, θ, y_out, roll, yaw)`` from a world-aligned hand Jacobian."""
    return TASK_AXES @ np.asarray(jacobian, dtype=float)


def planar_jacobian(panda: Panda, q: ArrayLike) -> Array:
    """3×7 ``J_p``: rows ``(ẋ_h, ẏ_h, θ̇_h)`` in the ccopt plane per unit joint velocity."""
    return task_jacobian(hand_jacobian(panda, q))[:3]


def task_error(placement: pin.SE3, target: ArrayLike, plane_y: float) -> Array:
    """Task-coordinate error ``target − current`` (m, rad) of a hand placement.

    The target is the planar pose ``(x, y, θ)`` with the plate in the plane ``y = plane_y``;
    rotations are compared through the world-frame log map ``log(R_target Rᵀ)``.
    """
    x, y, theta = np.asarray(target, dtype=float)
    spatial = np.empty(6)
    spatial[:3] = np.array([x, plane_y, y]) - placement.translation
    spatial[3:] = pin.log3(hand_rotation(theta) @ placement.rotation.T)
    return TASK_AXES @ spatial


def inverse_kinematics(
    panda: Panda,
    pose: ArrayLike,
    seed: ArrayLike = NEUTRAL,
    tolerance: float = 1e-7,
    max_iterations: int = 500,
    damping: float = 1e-4,
) -> Array:
    """Joint angles (rad) putting the hand at planar ``pose = (x, y, θ)`` with the plate in the plane.

    Damped least squares on the 6-D task error (planar pose plus out-of-plane position, roll and
    yaw held at zero), starting from ``seed`` and clipped to the joint limits; the remaining
    redundancy is pulled towards ``seed``. Raises ``ValueError`` if the pose is not reached to
    ``tolerance`` (norm of the task error, m and rad) within ``max_iterations``.
    """
    target = np.asarray(pose, dtype=float)
    if target.shape != (3,) or not np.all(np.isfinite(target)):
        raise ValueError(f"pose must be a finite (x, y, theta), got {pose!r}")
    q = np.asarray(seed, dtype=float).copy()
    if q.shape != (panda.nq,):
        raise ValueError(f"seed must have {panda.nq} joint angles, got shape {q.shape}")
    lower, upper = panda.model.lowerPositionLimit, panda.model.upperPositionLimit
    posture = q.copy()
    for _ in range(max_iterations):
        error = task_error(hand_placement(panda, q), target, panda.mount.plane_y)
        if np.linalg.norm(error) < tolerance:
            return q
        jac = task_jacobian(hand_jacobian(panda, q))
        step = jac.T @ np.linalg.solve(jac @ jac.T + damping * np.eye(6), error)
        null = np.eye(panda.nq) - np.linalg.pinv(jac) @ jac
        step += 0.1 * null @ (posture - q)
        q = np.clip(q + step, lower, upper)
    raise ValueError(
        f"inverse kinematics did not reach the hand pose {target.tolist()} "
        f"(residual {np.linalg.norm(error):.2e}); it is probably outside the Panda's workspace"
    )
