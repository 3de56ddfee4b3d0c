"""The flat hand plate on the Panda flange, and where the robot stands relative to the work plane.

Frames (all right-handed)
    *Flange frame*: ``panda_link8`` of the URDF, origin on the flange face, ``z`` along joint 7's
    axis pointing away from the robot.
    *Hand frame*: origin at the centre of the plate's contact face, ``thickness`` along the flange
    ``z``; the plate is rotated by ``mount_angle`` about the flange ``z`` (−45°, like the Franka hand,
    so that joint 7 sits mid-range at its usual +45°). Its axes are ``x = e_t``, ``z = e_n`` (from the
    hand into the object) and ``y = z × x``, which in the work plane is MuJoCo ``(0, −1, 0)``: the axis
    of ccopt's counter-clockwise planar angle.

Work plane
    The ccopt plane is MuJoCo's ``y = plane_y`` plane with ``(x, y)_ccopt = (x, z)_mujoco``. The robot
    base stands *in* the plane (joint 1's axis lies in it) at ccopt ``(base_x, base_height)``, facing
    ``+x``: the arm then works in its own sagittal plane (joints 1, 3, 5 near zero, joints 2, 4, 6
    perpendicular to the plane), which keeps the in-plane joints well conditioned and the out-of-plane
    directions (MuJoCo ``y``, roll and yaw of the plate) held by joints 1, 3, 5, 7. The default
    ``base_x = −0.5 m`` puts the ccopt origin, where the objects stand, 0.5 m in front of the base.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from functools import cached_property

import numpy as np

from ccopt.geometry import Array


def _read_only(array: Array) -> Array:
    array.setflags(write=False)
    return array


@dataclass(frozen=True)
class HandPlate:
    """A rigid box plate bolted to the flange; its far face is the hand's contact line.

    Attributes:
        half_length: ``l_h`` (m), half the contact face length along ``e_t``.
        half_width: half the plate width out of the plane (m).
        thickness: flange-to-contact-face distance along the flange ``z`` (m), F/T sensor included.
        mass: plate mass (kg), uniform.
        mount_angle: rotation of the plate about the flange ``z`` axis (rad).
    """

    half_length: float = 0.05
    half_width: float = 0.02
    thickness: float = 0.03
    mass: float = 0.3
    mount_angle: float = -math.pi / 4

    def __post_init__(self) -> None:
        for name in ("half_length", "half_width", "thickness", "mass"):
            value = getattr(self, name)
            if not (math.isfinite(value) and value > 0.0):
                raise ValueError(f"HandPlate.{name} must be a positive finite number, got {value!r}")
        if not math.isfinite(self.mount_angle):
            raise ValueError(f"HandPlate.mount_angle must be finite, got {self.mount_angle!r}")

    @cached_property
    def rotation(self) -> Array:
        """3×3 rotation of the hand frame in the flange frame (about the flange ``z``); read-only."""
        c, s = math.cos(self.mount_angle), math.sin(self.mount_angle)
        return _read_only(np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]]))

    @cached_property
    def face_centre(self) -> Array:
        """Contact face centre (the hand frame origin) in the flange frame (m); read-only."""
        return _read_only(np.array([0.0, 0.0, self.thickness]))

    @cached_property
    def centre_of_mass(self) -> Array:
        """Plate centre of mass in the flange frame (m); read-only."""
        return _read_only(np.array([0.0, 0.0, 0.5 * self.thickness]))

    @cached_property
    def inertia(self) -> Array:
        """3×3 rotational inertia about the centre of mass, in the flange frame (kg·m²); read-only."""
        sx, sy, sz = 2.0 * self.half_length, 2.0 * self.half_width, self.thickness
        diag = self.mass / 12.0 * np.array([sy**2 + sz**2, sx**2 + sz**2, sx**2 + sy**2])
        return _read_only(self.rotation @ np.diag(diag) @ self.rotation.T)


@dataclass(frozen=True)
class Mount:
    """Where the robot base stands, in the ccopt plane.

    Attributes:
        base_x: ccopt ``x`` (= MuJoCo ``x``) of the base origin (m).
        base_height: ccopt ``y`` (= MuJoCo ``z``) of the base origin (m); 0 = on the ground.
        plane_y: MuJoCo ``y`` of the work plane and of the base (m).
    """

    base_x: float = -0.5
    base_height: float = 0.0
    plane_y: float = 0.0

    def __post_init__(self) -> None:
        for name in ("base_x", "base_height", "plane_y"):
            value = getattr(self, name)
            if not math.isfinite(value):
                raise ValueError(f"Mount.{name} must be finite, got {value!r}")

    @property
    def base_position(self) -> Array:
        """Base origin in MuJoCo world coordinates (m); the base is not rotated."""
        return np.array([self.base_x, self.plane_y, self.base_height])
