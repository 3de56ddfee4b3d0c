"""MJCF building blocks shared by the MuJoCo plants: options, object, ground and contact pairs.

The ccopt plane ``(x, y)`` is MuJoCo's ``(x, z)``; planar hinges use axis ``(0, −1, 0)`` so that
``qpos`` is the counter-clockwise planar angle (docs/architecture.md §3). Geoms are created with
``contype = conaffinity = 0``: only the explicit ``<contact><pair>`` elements collide, each with its
own friction, ``condim = 3`` and ``solref`` (docs/architecture.md §6).

:func:`pair_wrench` reads the planar wrench one geom exerts on another from the solved contacts.

A plant assembles a model from these strings, e.g.::

    f"<mujoco model='m'>{option_xml(params)}<asset>{object_asset_xml(obj, params)}</asset>"
    f"<worldbody>{ground_xml()}{object_body_xml(obj)}{hand_body}</worldbody>"
    f"{contact_pairs_xml(obj, params, hand_geom='hand')}<actuator>...</actuator></mujoco>"
"""

from __future__ import annotations

from collections.abc import Iterable

import mujoco
import numpy as np

from ccopt.objects import PlanarObject
from ccopt.plant.base import PlantParams

OBJECT_BODY = "object"
OBJECT_GEOM = "object"
OBJECT_MESH = "object_prism"
OBJECT_JOINTS = ("object_x", "object_z", "object_theta")
"""Object joints in ``qpos`` order: centroid x, centroid y (MuJoCo z), CCW angle."""
GROUND_GEOM = "ground"
PLANAR_HINGE_AXIS = "0 -1 0"


def _numbers(values: Iterable[float]) -> str:
    return " ".join(f"{float(v):.12g}" for v in values)


def option_xml(params: PlantParams) -> str:
    """``<compiler>`` and ``<option>``: docs/architecture.md §6 settings (``impratio`` from ``params``)."""
    return (
        '<compiler angle="radian" autolimits="true"/>'
        f'<option timestep="{params.timestep:.12g}" integrator="implicitfast" solver="Newton" '
        f'cone="elliptic" impratio="{params.impratio:.12g}" gravity="0 0 -9.81"/>'
    )


def prism_vertices(obj: PlanarObject, depth: float) -> np.ndarray:
    """``(2n, 3)`` MuJoCo-frame vertices of the object extruded by ``depth`` (m) along MuJoCo y."""
    x, z = obj.vertices[:, 0], obj.vertices[:, 1]
    half = np.full_like(x, 0.5 * depth)
    front = np.column_stack((x, -half, z))
    back = np.column_stack((x, half, z))
    return np.vstack((front, back))


def object_asset_xml(obj: PlanarObject, params: PlantParams) -> str:
    """``<mesh>`` asset of the object prism (goes inside ``<asset>``)."""
    vertices = _numbers(prism_vertices(obj, params.depth).ravel())
    return f'<mesh name="{OBJECT_MESH}" vertex="{vertices}"/>'


def planar_joints_xml(prefix: str) -> str:
    """Three planar joints named ``{prefix}_x``, ``{prefix}_z``, ``{prefix}_theta``."""
    return (
        f'<joint name="{prefix}_x" type="slide" axis="1 0 0" damping="0"/>'
        f'<joint name="{prefix}_z" type="slide" axis="0 0 1" damping="0"/>'
        f'<joint name="{prefix}_theta" type="hinge" axis="{PLANAR_HINGE_AXIS}" damping="0"/>'
    )


def object_body_xml(obj: PlanarObject) -> str:
    """The object body: planar joints, lamina inertia about its centroid (the body origin), mesh geom.

    The out-of-plane inertia (MuJoCo y axis) is the lamina's; the two in-plane ones only need to be
    valid because the planar joints never excite them.
    """
    in_plane = 0.6 * obj.inertia
    inertia = _numbers((in_plane, obj.inertia, in_plane))
    return (
        f'<body name="{OBJECT_BODY}">'
        f"{planar_joints_xml('object')}"
        f'<inertial pos="0 0 0" mass="{obj.mass:.12g}" diaginertia="{inertia}"/>'
        f'<geom name="{OBJECT_GEOM}" type="mesh" mesh="{OBJECT_MESH}" contype="0" conaffinity="0" '
        'rgba="0.85 0.55 0.2 1"/>'
        "</body>"
    )


def ground_xml() -> str:
    """The ground: an infinite plane through the origin with normal +z (ccopt ``+y``)."""
    return (
        f'<geom name="{GROUND_GEOM}" type="plane" size="0 0 1" contype="0" conaffinity="0" '
        'rgba="0.6 0.6 0.6 1"/>'
    )


def pair_xml(geom1: str, geom2: str, mu: float, params: PlantParams) -> str:
    """One contact pair: Coulomb friction ``mu``, ``condim = 3``, ``solref = (timeconst, 1)``,
    ``solimp = (d_min, d_max, width, 0.5, 2)``.

    ``mu`` below MuJoCo's minimum friction (1e-5) is raised to it.
    """
    mu = max(float(mu), 1e-5)
    return (
        f'<pair geom1="{geom1}" geom2="{geom2}" condim="3" '
        f'friction="{mu:.12g} {mu:.12g} 0.001 0.0001 0.0001" '
        f'solref="{params.contact_timeconst:.12g} 1" solimp="{_numbers(params.solimp)} 0.5 2"/>'
    )


def contact_pairs_xml(obj: PlanarObject, params: PlantParams, hand_geom: str) -> str:
    """``<contact>`` block: hand–object (``mu_hand``) and object–ground (``mu_ground``) pairs."""
    return (
        "<contact>"
        f"{pair_xml(hand_geom, OBJECT_GEOM, obj.mu_hand, params)}"
        f"{pair_xml(OBJECT_GEOM, GROUND_GEOM, obj.mu_ground, params)}"
        "</contact>"
    )


def pair_wrench(data: mujoco.MjData, geom_a: int, geom_b: int, about: np.ndarray) -> np.ndarray:
    """Planar world wrench ``(f_x, f_y, τ)`` that geom ``geom_a`` exerts on geom ``geom_b``.

    ``τ`` is about the ccopt-plane point ``about`` (m). Sums the contacts between the two geoms; each
    contact force is read, like ``mujoco.mj_contactForce`` does for elliptic cones, from
    ``efc_force`` in the contact frame (normal from ``geom[0]`` to ``geom[1]``). Requires the
    elliptic cones of :func:`option_xml` and ``condim = 3`` pairs (:func:`pair_xml`).
    """
    forces, contacts = _pair_forces(data, geom_a, geom_b)
    if not forces:
        return np.zeros(3)
    world = np.array(forces)  # rows (f_x, 0, f_y): the sums and dot products see strided columns
    fx, fy = world[:, 0], world[:, 2]
    positions = data.contact.pos.tolist()
    x_about, y_about = float(about[0]), float(about[1])
    px = np.array([positions[k][0] - x_about for k in contacts])
    py = np.array([positions[k][2] - y_about for k in contacts])
    return np.array([fx.sum(), fy.sum(), float(px @ fy - py @ fx)])


def pair_force(data: mujoco.MjData, geom_a: int, geom_b: int) -> tuple[float, float]:
    """World force ``(f_x, f_y)`` (N) that geom ``geom_a`` exerts on geom ``geom_b``: the force of
    :func:`pair_wrench`, without its torque."""
    forces, _ = _pair_forces(data, geom_a, geom_b)
    if not forces:
        return 0.0, 0.0
    world = np.array(forces)
    return float(world[:, 0].sum()), float(world[:, 2].sum())


def _pair_forces(data: mujoco.MjData, geom_a: int, geom_b: int) -> tuple[list[list[float]], list[int]]:
    """The world force ``(f_x, 0, f_y)`` (N) of ``geom_a`` on ``geom_b`` at each of their contacts
    that has one, and those contacts' indices, in contact order. Plain floats: a handful of
    contacts costs less in Python than in NumPy calls."""
    if data.ncon == 0:
        return [], []
    contact = data.contact
    efc_force, frames = data.efc_force, contact.frame.tolist()
    forces, contacts = [], []
    pairs = zip(contact.geom.tolist(), contact.efc_address.tolist(), strict=True)
    for k, ((geom_0, geom_1), address) in enumerate(pairs):
        backward = geom_0 == geom_b and geom_1 == geom_a
        if address < 0 or not (backward or (geom_0 == geom_a and geom_1 == geom_b)):
            continue
        normal, tangent_1, tangent_2 = efc_force[address : address + 3].tolist()
        frame = frames[k]  # rows: normal, tangent 1, tangent 2 (world); np.einsum's products and sums
        f_x = normal * frame[0] + tangent_1 * frame[3] + tangent_2 * frame[6]
        f_y = normal * frame[2] + tangent_1 * frame[5] + tangent_2 * frame[8]
        forces.append([-f_x, 0.0, -f_y] if backward else [f_x, 0.0, f_y])
        contacts.append(k)
    return forces, contacts
