"""What both MuJoCo plants share: the model and its data, the clock, pushes on the object, the object's
state and ground truth.

A plant subclasses :class:`MujocoPlant`: its :meth:`MujocoPlant._build` builds its MJCF
(:mod:`ccopt.plant.scene` for the object, ground and contact pairs), calls :meth:`MujocoPlant._load`,
places and settles the system; it implements the hand: how one batch of
timesteps is advanced (:meth:`MujocoPlant._advance`), the hand's pose, velocity and wrenches, and the
ground's wrench. Frames and signs are those of :mod:`ccopt.geometry`.
"""

from __future__ import annotations

import math

import mujoco
import numpy as np
from numpy.typing import ArrayLike

from ccopt import geometry
from ccopt.clock import TIME_TOLERANCE
from ccopt.hand import Hand
from ccopt.objects import PlanarObject
from ccopt.plant import scene
from ccopt.plant.base import PlantParams, StartConfig, plant_inputs
from ccopt.plant.truth import Truth, compute_truth

HAND_GEOM = "hand"
"""Name of the hand's contact geom in every plant."""

CONTACT_FORCE_MIN = 1e-3
"""Normal force (N) above which a pair counts as in contact."""


def joint_slice(model: mujoco.MjModel, joints: tuple[str, ...], velocity: bool = False) -> slice:
    """The contiguous ``qpos`` (or ``qvel``) slice of ``joints`` (consecutive by construction)."""
    table = model.jnt_dofadr if velocity else model.jnt_qposadr
    addresses = [int(table[model.joint(name).id]) for name in joints]
    if addresses != list(range(addresses[0], addresses[0] + len(addresses))):
        raise RuntimeError(f"expected consecutive addresses, got {addresses}")
    return slice(addresses[0], addresses[0] + len(addresses))


class MujocoPlant:
    """The common part of the MuJoCo plants (implements most of :class:`~ccopt.plant.base.Plant`).

    Args:
        obj: the object.
        params: simulation parameters.
        start: start configuration.
        hand: the robot's hand.
    """

    def __init__(
        self,
        obj: PlanarObject,
        params: PlantParams | None = None,
        start: StartConfig | None = None,
        hand: Hand | None = None,
    ) -> None:
        self.obj, self.params, self.start, self.hand = plant_inputs(obj, params, start, hand)
        self._push_end: float | None = None
        self._ground_vertex: int | None = None  # the ground contact of the last truth read
        self._build()

    def _build(self) -> None:
        """Build the model (:meth:`_load`), place the object and the hand, settle, reset the clock."""
        raise NotImplementedError

    def _load(self, xml: str) -> None:
        """Compile ``xml`` and look up the object, the ground and the hand geom."""
        self._model = mujoco.MjModel.from_xml_string(xml)
        self._data = mujoco.MjData(self._model)
        m = self._model
        self._obj_qpos = joint_slice(m, scene.OBJECT_JOINTS)
        self._obj_dof = joint_slice(m, scene.OBJECT_JOINTS, velocity=True)
        self._hand_geom = m.geom(HAND_GEOM).id
        self._object_geom = m.geom(scene.OBJECT_GEOM).id
        self._ground_geom = m.geom(scene.GROUND_GEOM).id
        self._object_body = m.body(scene.OBJECT_BODY).id

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
                self._advance(remaining)
                return
            left = math.ceil((self._push_end - self.time) / self.timestep - 1e-9)
            chunk = min(remaining, max(left, 0))
            if chunk > 0:
                self._advance(chunk)
                remaining -= chunk
            if self.time >= self._push_end - TIME_TOLERANCE:
                self._data.xfrc_applied[self._object_body] = 0.0
                self._push_end = None

    def _advance(self, n_steps: int) -> None:
        """Advance the physics (and the plant's own control) by ``n_steps ≥ 1`` timesteps."""
        raise NotImplementedError

    def _advance_holding_object(self, n_steps: int) -> None:
        """Advance ``n_steps`` timesteps with the object held where it is, as the experimenter's hand
        holds it while the robot presses on: the hand builds its force against an object that
        cannot fall away first (a robot arm settling from its inverse kinematics takes tens of
        milliseconds to press; an object its weight turns meanwhile falls)."""
        pose = self._data.qpos[self._obj_qpos].copy()
        for _ in range(n_steps):
            self._data.qpos[self._obj_qpos] = pose
            self._data.qvel[self._obj_dof] = 0.0
            self._advance(1)

    # --- state -----------------------------------------------------------------------------------

    def object_pose(self) -> np.ndarray:
        """True world ``(x, y, φ)`` of the object's centroid frame."""
        return self._data.qpos[self._obj_qpos].copy()

    def object_velocity(self) -> np.ndarray:
        """True world ``(ẋ, ẏ, φ̇)`` of the object's centroid frame."""
        return self._data.qvel[self._obj_dof].copy()

    def hand_pose(self) -> np.ndarray:
        """True world ``(x_h, y_h, θ_h)`` of the hand contact-face centre."""
        raise NotImplementedError

    def hand_velocity(self) -> np.ndarray:
        """True world ``(ẋ_h, ẏ_h, θ̇_h)`` of the hand contact-face centre."""
        raise NotImplementedError

    def hand_wrench_world(self) -> np.ndarray:
        """True world wrench ``(f_x, f_y, τ)`` of the hand on the object, ``τ`` about the face centre."""
        raise NotImplementedError

    def ground_wrench(self) -> np.ndarray:
        """True world wrench ``(f_x, f_y, τ)`` of the ground on the object, ``τ`` about its centroid."""
        raise NotImplementedError

    def _contact_forces(self) -> tuple[tuple[float, float], tuple[float, float]]:
        """True world forces ``(f_x, f_y)`` (N) of the hand and of the ground on the object: the
        forces of :meth:`hand_wrench_world` and :meth:`ground_wrench` (what :meth:`truth` reads)."""
        hand, ground = self.hand_wrench_world().tolist(), self.ground_wrench().tolist()
        return (hand[0], hand[1]), (ground[0], ground[1])

    def truth(self) -> Truth:
        """Ground truth of the contact configuration (see :mod:`ccopt.plant.truth`); ``θ_o`` is that
        of the start configuration's hand face; the ground contact is the last read's vertex while
        it stays within :data:`~ccopt.plant.truth.GROUND_VERTEX_HYSTERESIS` of the lowest."""
        pose = self.hand_pose()
        hand, ground = self._contact_forces()
        hand_force = geometry.world_to_hand(geometry.hand_axes(float(pose[2])), *hand)[0]  # f_n
        truth = compute_truth(
            time=self.time,
            obj=self.obj,
            hand_face=self.start.hand_face,
            object_pose=self.object_pose(),
            object_velocity=self.object_velocity(),
            hand_pose=pose,
            hand_velocity=self.hand_velocity(),
            in_contact_hand=hand_force > CONTACT_FORCE_MIN,
            in_contact_ground=ground[1] > CONTACT_FORCE_MIN,
            previous_vertex=self._ground_vertex,
        )
        self._ground_vertex = truth.ground_vertex
        return truth
