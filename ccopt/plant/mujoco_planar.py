"""Planar MuJoCo plant: a flat impedance-controlled hand presses an object against the ground.

The hand is a box whose contact face (``2 l_h`` long) is centred on the hand body's origin, with
three planar joints so that the hand's ``qpos`` is its pose ``(x_h, y_h, θ_h)`` (DESIGN.md §3).
Position actuators (``kp = K``) and velocity actuators (``kv = D``, fed the target velocity) on
those joints make the planar impedance ``w = K (x_tar − x_h) + D (v_tar − v_h)`` at the face
centre, in world axes; gravity is compensated.
"""

from __future__ import annotations

import dataclasses
import math

import mujoco
import numpy as np
from numpy.typing import ArrayLike

from ccopt import geometry
from ccopt.objects import PlanarObject
from ccopt.plant import scene
from ccopt.plant.base import PlantParams, StartConfig, planar_vector, plant_inputs
from ccopt.plant.truth import Truth, compute_truth, lowest_vertex

HAND_BODY = "hand"
HAND_GEOM = "hand"
HAND_JOINTS = ("hand_x", "hand_z", "hand_theta")

CONTACT_FORCE_MIN = 1e-3
"""Normal force (N) above which a pair counts as in contact."""


def hand_body_xml(params: PlantParams) -> str:
    """Gravity-compensated hand body: planar joints at the contact-face centre, box behind the face."""
    half_t = 0.5 * params.hand_thickness
    half_w = 0.75 * params.depth
    length = 2.0 * params.l_h
    m = params.hand_mass
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
        f'size="{params.l_h:.12g} {half_w:.12g} {half_t:.12g}" contype="0" conaffinity="0" '
        'rgba="0.2 0.4 0.8 1"/>'
        "</body>"
    )


def impedance_actuators_xml(params: PlantParams) -> str:
    """Position (``kp = K``) then velocity (``kv = D``) actuators on the three hand joints."""
    position = "".join(
        f'<position name="{joint}_kp" joint="{joint}" kp="{k:.12g}"/>'
        for joint, k in zip(HAND_JOINTS, params.K, strict=True)
    )
    velocity = "".join(
        f'<velocity name="{joint}_kv" joint="{joint}" kv="{d:.12g}"/>'
        for joint, d in zip(HAND_JOINTS, params.D, strict=True)
    )
    return f"<actuator>{position}{velocity}</actuator>"


def planar_model_xml(obj: PlanarObject, params: PlantParams) -> str:
    """The complete MJCF of the planar plant."""
    return (
        f'<mujoco model="ccopt_planar_{obj.name}">'
        f"{scene.option_xml(params)}"
        f"<asset>{scene.object_asset_xml(obj, params)}</asset>"
        f"<worldbody>{scene.ground_xml()}{scene.object_body_xml(obj)}{hand_body_xml(params)}</worldbody>"
        f"{scene.contact_pairs_xml(obj, params, HAND_GEOM)}"
        f"{impedance_actuators_xml(params)}"
        "</mujoco>"
    )


def _placed_object(obj: PlanarObject, start: StartConfig) -> tuple[np.ndarray, float, np.ndarray]:
    """Object pose, ``d`` and the hand face's end points (world) of a start configuration."""
    face = obj.face_index(start.hand_face)
    normal = obj.face_normal(face)
    angle = start.theta_o + 0.5 * math.pi - math.atan2(normal[1], normal[0])
    rotated = geometry.transform_points(obj.vertices, (0.0, 0.0, angle))
    lowest = rotated[lowest_vertex(rotated)]
    centroid = np.array([start.x_o, 0.0]) - lowest
    object_pose = np.array([centroid[0], centroid[1], angle])
    r_o = np.array([start.x_o, 0.0])
    face_ends = np.array([rotated[face], rotated[(face + 1) % obj.n_faces]]) + centroid
    d = float((r_o - face_ends[0]) @ geometry.hand_normal(start.theta_o))
    return object_pose, d, face_ends


def face_s_h_range(obj: PlanarObject, start: StartConfig) -> tuple[float, float]:
    """Range of ``s_h`` (m) that keeps the hand centre on the start face (``start.s_h`` ignored)."""
    _, _, face_ends = _placed_object(obj, start)
    along = sorted(
        float((np.array([start.x_o, 0.0]) - p) @ geometry.hand_tangent(start.theta_o)) for p in face_ends
    )
    return along[0], along[1]


def hand_over_vertex(obj: PlanarObject, start: StartConfig, half_length: float) -> StartConfig:
    """``start`` with ``s_h`` as close to 0 as the whole hand allows (m).

    ``s_h = 0`` puts the hand centre straight over the ground contact along ``e_n``, where the normal
    push has no moment about the contact (the paper's Fig. 2a); the hand is kept ``half_length`` plus
    2 mm inside the face's ends, so it lies flush over its whole length.
    """
    low, high = face_s_h_range(obj, start)
    inset = half_length + 2e-3
    if high - low < 2.0 * inset:
        raise ValueError(
            f"face {obj.face_index(start.hand_face)} of {obj.name} ({high - low:.3f} m) is shorter "
            f"than the hand ({2.0 * half_length:.3f} m)"
        )
    return dataclasses.replace(start, s_h=float(np.clip(0.0, low + inset, high - inset)))


def start_poses(
    obj: PlanarObject, start: StartConfig, params: PlantParams
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Object pose, hand pose and impedance target of a start configuration, world ``(x, y, θ)``.

    The object is turned so that the outward normal of ``start.hand_face`` is ``−e_n(θ_o)``, its
    lowest vertex touches the ground at ``x_o``; the hand lies flush on that face at ``s_h``; the
    target is the hand pose pushed ``K⁻¹ f_n e_n`` into the object.

    Raises:
        ValueError: the face does not exist, the hand centre is off the face, or the hand would
            cut the ground.
    """
    object_pose, d, _ = _placed_object(obj, start)
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
        hand_pose[:2] + a * params.l_h * e_t - b * params.hand_thickness * e_n
        for a in (-1.0, 1.0)
        for b in (0.0, 1.0)
    ]
    if min(c[1] for c in corners) < 0.0:
        raise ValueError(
            f"the hand would cut the ground at theta_o = {start.theta_o} rad, s_h = {start.s_h} m "
            f"on face {obj.face_index(start.hand_face)} of {obj.name}"
        )
    offset = start.normal_force * e_n / np.asarray(params.K[:2])
    target = hand_pose + np.array([offset[0], offset[1], 0.0])
    return object_pose, hand_pose, target


class PlanarPlant:
    """Planar hand–object–ground simulation (implements :class:`~ccopt.plant.base.Plant`).

    Args:
        obj: the object.
        params: plant parameters.
        start: start configuration; the plant settles there for ``start.settle_time`` (pressing
            with ``start.normal_force``) and then resets its clock to 0.
    """

    def __init__(
        self,
        obj: PlanarObject,
        params: PlantParams | None = None,
        start: StartConfig | None = None,
    ) -> None:
        self.obj, self.params, self.start = plant_inputs(obj, params, start)
        object_pose, hand_pose, target = start_poses(obj, self.start, self.params)
        self._model = mujoco.MjModel.from_xml_string(planar_model_xml(obj, self.params))
        self._data = mujoco.MjData(self._model)
        m = self._model
        self._hand_qpos = np.array([m.jnt_qposadr[m.joint(j).id] for j in HAND_JOINTS])
        self._hand_dof = np.array([m.jnt_dofadr[m.joint(j).id] for j in HAND_JOINTS])
        self._obj_qpos = np.array([m.jnt_qposadr[m.joint(j).id] for j in scene.OBJECT_JOINTS])
        self._obj_dof = np.array([m.jnt_dofadr[m.joint(j).id] for j in scene.OBJECT_JOINTS])
        self._hand_geom = m.geom(HAND_GEOM).id
        self._object_geom = m.geom(scene.OBJECT_GEOM).id
        self._ground_geom = m.geom(scene.GROUND_GEOM).id
        self._object_body = m.body(scene.OBJECT_BODY).id
        self._push_end: float | None = None
        self._ctrl = self._data.ctrl
        self._qpos = self._data.qpos
        self._qvel = self._data.qvel
        self._qfrc_constraint = self._data.qfrc_constraint

        self._data.qpos[self._obj_qpos] = object_pose
        self._data.qpos[self._hand_qpos] = hand_pose
        mujoco.mj_forward(m, self._data)
        self._settle(target)

    def _settle(self, target: np.ndarray) -> None:
        """Press towards ``target`` for the settle time, correcting the target once halfway so that
        the contacts' compliance does not eat into the normal force; then reset the clock."""
        half = round(0.5 * self.start.settle_time / self.timestep)
        self.set_target(target)
        self.step(half)
        if half > 0:
            error = self.start.normal_force - self.hand_wrench()[0]
            e_n = geometry.hand_normal(self.start.theta_o)
            self.set_target(target + np.array([*(error * e_n / np.asarray(self.params.K[:2])), 0.0]))
            self.step(half)
        self._data.time = 0.0

    # --- simulator access (read only: do not mutate) ---------------------------------------------

    @property
    def model(self) -> mujoco.MjModel:
        """The MuJoCo model (for tests and benchmarks; do not mutate)."""
        return self._model

    @property
    def data(self) -> mujoco.MjData:
        """The MuJoCo data (for tests and benchmarks; do not mutate)."""
        return self._data

    @property
    def time(self) -> float:
        """Simulated time since the end of settling, s."""
        return float(self._data.time)

    @property
    def timestep(self) -> float:
        """Simulation step, s."""
        return float(self._model.opt.timestep)

    # --- commands --------------------------------------------------------------------------------

    def set_target(self, pose: ArrayLike, velocity: ArrayLike | None = None) -> None:
        """Hand impedance target, world ``(x, y, θ)`` (m, rad), and its velocity (m/s, rad/s)."""
        self._ctrl[:3] = planar_vector("target pose", pose)
        self._ctrl[3:] = 0.0 if velocity is None else planar_vector("target velocity", velocity)

    def target(self) -> np.ndarray:
        """Current impedance target, world ``(x, y, θ)``."""
        return self._ctrl[:3].copy()

    def push_object(self, force: ArrayLike, duration: float) -> None:
        """Apply world force ``(f_x, f_y)`` (N) at the object's centroid for ``duration`` s from now."""
        push = np.asarray(force, dtype=float)
        if push.shape != (2,) or not np.all(np.isfinite(push)):
            raise ValueError(f"force must be 2 finite numbers (f_x, f_y), got {force!r}")
        if not math.isfinite(duration) or duration < 0.0:
            raise ValueError(f"duration must be a non-negative number of s, got {duration!r}")
        self._data.xfrc_applied[self._object_body, [0, 2]] = push
        self._push_end = self.time + duration

    def step(self, n_steps: int = 1) -> None:
        """Advance by ``n_steps`` timesteps (ending any push when its duration is over)."""
        if isinstance(n_steps, bool) or not isinstance(n_steps, int | np.integer) or n_steps < 0:
            raise ValueError(f"n_steps must be a non-negative integer, got {n_steps!r}")
        remaining = int(n_steps)
        while remaining > 0:
            if self._push_end is None:
                mujoco.mj_step(self._model, self._data, remaining)
                return
            left = math.ceil((self._push_end - self.time) / self.timestep - 1e-9)
            chunk = min(remaining, max(left, 0))
            if chunk > 0:
                mujoco.mj_step(self._model, self._data, chunk)
                remaining -= chunk
            if self.time >= self._push_end - 1e-9:
                self._data.xfrc_applied[self._object_body] = 0.0
                self._push_end = None

    # --- state -----------------------------------------------------------------------------------

    def hand_pose(self) -> np.ndarray:
        """True world ``(x_h, y_h, θ_h)`` of the hand contact-face centre."""
        return self._qpos[self._hand_qpos]

    def hand_velocity(self) -> np.ndarray:
        """True world ``(ẋ_h, ẏ_h, θ̇_h)``."""
        return self._qvel[self._hand_dof]

    def object_pose(self) -> np.ndarray:
        """True world ``(x, y, φ)`` of the object's centroid frame."""
        return self._qpos[self._obj_qpos]

    def object_velocity(self) -> np.ndarray:
        """True world ``(ẋ, ẏ, φ̇)`` of the object's centroid frame."""
        return self._qvel[self._obj_dof]

    def hand_wrench_world(self) -> np.ndarray:
        """True world wrench ``(f_x, f_y, τ)`` of the hand on the object, τ about the face centre.

        The hand's only contacts are with the object and its joints are world x, world z and a
        hinge at the face centre, so this is minus the constraint force on the hand's joints: the
        sum of the hand–object contact forces (:func:`ccopt.plant.scene.pair_wrench`), in O(1).
        """
        return -self._qfrc_constraint[self._hand_dof]

    def hand_wrench(self) -> np.ndarray:
        """True hand-frame wrench ``(f_n, f_t, τ)`` of the hand on the object, τ about the face centre."""
        theta_h = float(self._qpos[self._hand_qpos[2]])
        return geometry.wrench_world_to_hand(theta_h, -self._qfrc_constraint[self._hand_dof])

    def ground_wrench(self) -> np.ndarray:
        """True world wrench ``(f_x, f_y, τ)`` of the ground on the object, τ about its centroid.

        The object's constraint force less the hand's share (the object touches nothing else).
        """
        pose = self.object_pose()
        hand = geometry.shift_torque(self.hand_wrench_world(), self.hand_pose()[:2], pose[:2])
        return self._qfrc_constraint[self._obj_dof] - hand

    def truth(self) -> Truth:
        """Ground truth of the contact configuration (see :mod:`ccopt.plant.truth`); ``θ_o`` is that
        of the start configuration's hand face."""
        return compute_truth(
            time=self.time,
            obj=self.obj,
            hand_face=self.start.hand_face,
            object_pose=self.object_pose(),
            object_velocity=self.object_velocity(),
            hand_pose=self.hand_pose(),
            hand_velocity=self.hand_velocity(),
            in_contact_hand=self.hand_wrench()[0] > CONTACT_FORCE_MIN,
            in_contact_ground=self.ground_wrench()[1] > CONTACT_FORCE_MIN,
        )
