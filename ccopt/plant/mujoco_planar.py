"""Planar MuJoCo plant: a flat impedance-controlled hand presses an object against the ground.

The hand is a box whose contact face (``2 l_h`` long) is centred on the hand body's origin, with
three planar joints so that the hand's ``qpos`` is its pose ``(x_h, y_h, θ_h)`` (docs/architecture.md §3).
Position actuators (``kp = K``) and velocity actuators (``kv = D``, fed the target velocity) on
those joints make the planar impedance ``w = K (x_tar − x_h) + D (v_tar − v_h)`` at the face
centre, in world axes; gravity is compensated.
"""

from __future__ import annotations

import math

import mujoco
import numpy as np
from numpy.typing import ArrayLike

from ccopt import geometry
from ccopt.hand import Hand
from ccopt.objects import PlanarObject
from ccopt.plant import scene
from ccopt.plant.base import PlantParams, planar_vector
from ccopt.plant.mujoco_base import HAND_GEOM, MujocoPlant, joint_slice
from ccopt.plant.placement import start_poses
from ccopt.statics import start_target

HAND_BODY = "hand"
HAND_JOINTS = ("hand_x", "hand_z", "hand_theta")
HAND_ANGLE_RANGE = (-math.radians(75.0), math.radians(75.0))
"""rad: the hand angles the planar hand may take (its joints have no limits; beyond, the hand lies too
close to the ground to press)."""
TARGET_ANGLE_RANGE = (-math.radians(80.0), math.radians(80.0))
"""rad: the impedance target's angles the planar hand may be driven to: :data:`HAND_ANGLE_RANGE` and
5° of room, about the Panda's (3.5–4.6° at the paper objects' starts:
:attr:`~ccopt.plant.mujoco_panda.PandaPlant.target_angle_range`)."""


def hand_body_xml(hand: Hand, params: PlantParams) -> str:
    """Gravity-compensated hand body: planar joints at the contact-face centre, box behind the face
    (``1.5 × params.depth`` deep)."""
    half_t = 0.5 * hand.thickness
    half_w = 0.75 * params.depth
    length = 2.0 * hand.half_length
    m = hand.mass
    inertia = (
        m * (4.0 * half_w**2 + 4.0 * half_t**2) / 12.0,
        m * (length**2 + 4.0 * half_t**2) / 12.0,
        m * (length**2 + 4.0 * half_w**2) / 12.0,
    )
    return (
        f'<body name="{HAND_BODY}" gravcomp="1">'
        f"{scene.planar_joints_xml('hand')}"
        f'<inertial pos="0 0 {half_t:.12g}" mass="{m:.12g}" '
        f'diaginertia="{" ".join(f"{i:.12g}" for i in inertia)}"/>'
        f'<geom name="{HAND_GEOM}" type="box" pos="0 0 {half_t:.12g}" '
        f'size="{hand.half_length:.12g} {half_w:.12g} {half_t:.12g}" contype="0" conaffinity="0" '
        'rgba="0.2 0.4 0.8 1"/>'
        "</body>"
    )


def impedance_actuators_xml(hand: Hand) -> str:
    """Position (``kp = K``) then velocity (``kv = D``) actuators on the three hand joints."""
    position = "".join(
        f'<position name="{joint}_kp" joint="{joint}" kp="{k:.12g}"/>'
        for joint, k in zip(HAND_JOINTS, hand.stiffness, strict=True)
    )
    velocity = "".join(
        f'<velocity name="{joint}_kv" joint="{joint}" kv="{d:.12g}"/>'
        for joint, d in zip(HAND_JOINTS, hand.damping, strict=True)
    )
    return f"<actuator>{position}{velocity}</actuator>"


def planar_model_xml(obj: PlanarObject, params: PlantParams, hand: Hand) -> str:
    """The complete MJCF of the planar plant."""
    return (
        f'<mujoco model="ccopt_planar_{obj.name}">'
        f"{scene.option_xml(params)}"
        f"<asset>{scene.object_asset_xml(obj, params)}</asset>"
        f"<worldbody>{scene.ground_xml()}{scene.object_body_xml(obj)}"
        f"{hand_body_xml(hand, params)}</worldbody>"
        f"{scene.contact_pairs_xml(obj, params, HAND_GEOM)}"
        f"{impedance_actuators_xml(hand)}"
        "</mujoco>"
    )


class PlanarPlant(MujocoPlant):
    """Planar hand–object–ground simulation (implements :class:`~ccopt.plant.base.Plant`).

    Args:
        obj: the object.
        params: simulation parameters.
        start: start configuration; the plant settles there for ``start.settle_time`` (pressing
            with the wrench that holds it in equilibrium at ``start.normal_force``,
            :func:`ccopt.statics.start_target`; the object held in place for the first quarter)
            and then resets its clock to 0.
        hand: the robot's hand (its length, impedance and body).
    """

    force_model_error = 6.0
    """N (:attr:`~ccopt.plant.base.Plant.force_model_error`): the hand's inertia makes the force
    and the impedance differ while it accelerates, up to 6 N for 50 ms when a steeply tilted object
    slipped on the ground (a hexagon at 55°), 1.6 N on quiet runs."""
    force_headroom = 2.5
    """N (:attr:`~ccopt.plant.base.Plant.force_headroom`): the planar hand's force runs a few
    newtons above the model in a push (3.7 N on a heavy triangle's ground slide aimed at the limit);
    over the seven paper cases' ``paper`` runs (seeds 0–2) the largest normal force was 24 N, limit
    25 N."""
    hand_turn_rate = math.inf
    """rad/s (:attr:`~ccopt.plant.base.Plant.hand_turn_rate`): the free hand follows the
    controller's 30°/s within half a degree. Slower pivots did not make its landings gentler: the
    paper rectangle's landing on its face rolled the hand 2.6° and 1.8° (seeds 0, 1) at 30°/s and
    2.1° and 2.1° at 15°/s, where the roll comes from the torque at the face's end, not the lag."""

    def _build(self) -> None:
        object_pose, hand_pose, _ = start_poses(self.obj, self.start, self.hand)
        target = start_target(self.obj, self.start, self.hand)
        self._load(planar_model_xml(self.obj, self.params, self.hand))
        m = self._model
        hand_qpos, hand_dof = joint_slice(m, HAND_JOINTS), joint_slice(m, HAND_JOINTS, velocity=True)
        self._hand_qpos = np.arange(hand_qpos.start, hand_qpos.stop)  # index arrays: reads are copies
        self._hand_dof = np.arange(hand_dof.start, hand_dof.stop)
        self._hand_angle = hand_qpos.start + 2  # θ_h's address in qpos
        self._ctrl = self._data.ctrl
        self._qpos = self._data.qpos
        self._qvel = self._data.qvel
        self._qfrc_constraint = self._data.qfrc_constraint

        self._data.qpos[self._obj_qpos] = object_pose
        self._data.qpos[self._hand_qpos] = hand_pose
        mujoco.mj_forward(m, self._data)
        self._settle(target)

    @property
    def hand_angle_range(self) -> tuple[float, float]:
        """The hand angles ``θ_h`` (rad) this plant may take (:data:`HAND_ANGLE_RANGE`)."""
        return HAND_ANGLE_RANGE

    @property
    def target_angle_range(self) -> tuple[float, float]:
        """The impedance target's angles (rad) this plant may be driven to (:data:`TARGET_ANGLE_RANGE`)."""
        return TARGET_ANGLE_RANGE

    def _settle(self, target: np.ndarray) -> None:
        """Press towards ``target`` for the settle time, the object held for its first quarter;
        correct the target once the object has settled free, so that the contacts' compliance does
        not eat into the normal force; then reset the clock."""
        steps = round(self.start.settle_time / self.timestep)
        held = steps // 4
        half = (steps - held) // 2
        self.set_target(target)
        self._advance_holding_object(held)
        self.step(half)
        if half > 0:
            error = self.start.normal_force - self.hand_wrench()[0]
            e_n = geometry.hand_normal(self.start.theta_o)
            self.set_target(target + np.array([*(error * e_n / np.asarray(self.hand.stiffness[:2])), 0.0]))
        self.step(steps - held - half)
        self._data.time = 0.0

    # --- commands --------------------------------------------------------------------------------

    def set_target(self, pose: ArrayLike, velocity: ArrayLike | None = None, *, check: bool = True) -> None:
        """Hand impedance target, world ``(x, y, θ)`` (m, rad), and its velocity (m/s, rad/s);
        ``check=False`` takes them as 3 finite numbers each without checking."""
        if check:
            pose = planar_vector("target pose", pose)
            velocity = None if velocity is None else planar_vector("target velocity", velocity)
        self._ctrl[:3] = pose
        self._ctrl[3:] = 0.0 if velocity is None else velocity

    def target(self) -> np.ndarray:
        """Current impedance target, world ``(x, y, θ)``."""
        return self._ctrl[:3].copy()

    def _advance(self, n_steps: int) -> None:
        mujoco.mj_step(self._model, self._data, n_steps)

    # --- state -----------------------------------------------------------------------------------

    def hand_pose(self) -> np.ndarray:
        """True world ``(x_h, y_h, θ_h)`` of the hand contact-face centre."""
        return self._qpos[self._hand_qpos]

    def hand_velocity(self) -> np.ndarray:
        """True world ``(ẋ_h, ẏ_h, θ̇_h)``."""
        return self._qvel[self._hand_dof]

    def hand_wrench_world(self) -> np.ndarray:
        """True world wrench ``(f_x, f_y, τ)`` of the hand on the object, τ about the face centre.

        The hand's only contacts are with the object and its joints are world x, world z and a
        hinge at the face centre, so this is minus the constraint force on the hand's joints: the
        sum of the hand–object contact forces (:func:`ccopt.plant.scene.pair_wrench`), in O(1).
        """
        return -self._qfrc_constraint[self._hand_dof]

    def hand_wrench(self) -> np.ndarray:
        """True hand-frame wrench ``(f_n, f_t, τ)`` of the hand on the object, τ about the face centre
        (:meth:`hand_wrench_world` in the hand frame, in floats: the sensors read it every sample)."""
        f_x, f_y, torque = self._qfrc_constraint[self._hand_dof].tolist()  # on the hand, by the object
        axes = geometry.hand_axes(self._qpos.item(self._hand_angle))
        return np.array((*geometry.world_to_hand(axes, -f_x, -f_y), -torque))

    def _contact_forces(self) -> tuple[tuple[float, float], tuple[float, float]]:
        """True world forces ``(f_x, f_y)`` (N) of the hand and of the ground on the object: those of
        :meth:`hand_wrench_world` and :meth:`ground_wrench`, without their torques."""
        hand = (-self._qfrc_constraint[self._hand_dof]).tolist()
        held = self._qfrc_constraint[self._obj_dof].tolist()
        return (hand[0], hand[1]), (held[0] - hand[0], held[1] - hand[1])

    def ground_wrench(self) -> np.ndarray:
        """True world wrench ``(f_x, f_y, τ)`` of the ground on the object, τ about its centroid.

        The object's constraint force less the hand's share (the object touches nothing else).
        """
        pose = self.object_pose()
        hand = geometry.shift_torque(self.hand_wrench_world(), self.hand_pose()[:2], pose[:2])
        return self._qfrc_constraint[self._obj_dof] - hand
