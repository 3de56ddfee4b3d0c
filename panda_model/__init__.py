"""The Franka Panda of example-robot-data with a flat hand plate, seen from the ccopt work plane.

Pinocchio kinematics and dynamics of the 7-DoF arm (:mod:`panda_model.model`), the plate and the
robot's mount (:mod:`panda_model.hand`), the mapping between joint-space, Cartesian and planar
impedance (:mod:`panda_model.impedance`) and the wrist F/T reading mapped to the hand wrench
(:mod:`panda_model.wrench`). Conventions are those of :mod:`ccopt.geometry`.
"""

from panda_model.hand import HandPlate, Mount
from panda_model.impedance import (
    OUT_OF_PLANE_STIFFNESS,
    ImpedanceGains,
    cartesian_stiffness,
    critical_damping,
    hand_stiffness_to_world,
    impedance_gains,
    joint_stiffness,
    planar_stiffness,
    task_inertia,
)
from panda_model.model import (
    HAND_FRAME,
    NEUTRAL,
    TASK_AXES,
    Panda,
    hand_jacobian,
    hand_placement,
    hand_pose,
    hand_rotation,
    inverse_kinematics,
    load_panda,
    planar_jacobian,
    planar_pose,
    task_error,
    task_jacobian,
)
from panda_model.urdf import ARM_JOINTS, FLANGE_LINK, arm_urdf, panda_description_dir
from panda_model.wrench import hand_wrench

__all__ = [
    "ARM_JOINTS",
    "FLANGE_LINK",
    "HAND_FRAME",
    "NEUTRAL",
    "OUT_OF_PLANE_STIFFNESS",
    "TASK_AXES",
    "HandPlate",
    "ImpedanceGains",
    "Mount",
    "Panda",
    "arm_urdf",
    "cartesian_stiffness",
    "critical_damping",
    "hand_jacobian",
    "hand_placement",
    "hand_pose",
    "hand_rotation",
    "hand_stiffness_to_world",
    "hand_wrench",
    "impedance_gains",
    "inverse_kinematics",
    "joint_stiffness",
    "load_panda",
    "panda_description_dir",
    "planar_jacobian",
    "planar_pose",
    "planar_stiffness",
    "task_error",
    "task_inertia",
    "task_jacobian",
]
