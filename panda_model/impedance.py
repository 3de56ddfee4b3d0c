"""Impedance of the Panda seen at the hand: joint-space ↔ planar stiffness, and the Cartesian gains.

All Cartesian quantities are in the task coordinates of :mod:`panda_model.model`,
``(x, y, θ | y_out, roll, yaw)``: the planar block first (world ccopt axes, torque/rotation about the
contact face centre, CCW), then the out-of-plane block. Stiffness units: N/m, N/rad, N·m/m, N·m/rad.

A Cartesian impedance ``τ = Jᵀ(K e − D ė) + N (K_null (q₀ − q) − D_null q̇)`` with
``N = I − J⁺J`` has, statically and to first order about an unloaded equilibrium, the joint
stiffness ``K_q = Jᵀ K J + N K_null`` (:func:`joint_stiffness`); the stiffness it shows at the hand in
the plane is ``(J_p K_q⁻¹ J_pᵀ)⁻¹`` (:func:`planar_stiffness`), which equals the planar block of ``K``
whenever ``K`` does not couple planar and out-of-plane directions.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import pinocchio as pin
from numpy.typing import ArrayLike

from ccopt.geometry import Array, planar_hand_to_world
from panda_model.model import Panda, hand_jacobian, task_jacobian

OUT_OF_PLANE_STIFFNESS = (2000.0, 400.0, 400.0)
"""Default ``(y_out, roll, yaw)`` stiffness holding the plate in the plane: N/m, N·m/rad, N·m/rad."""


def _symmetric_positive_definite(matrix: ArrayLike, size: int, name: str, semi: bool = False) -> Array:
    """``matrix`` as a float array; ``ValueError`` unless finite, size×size, symmetric, PD (or PSD)."""
    value = np.asarray(matrix, dtype=float)
    if value.shape != (size, size) or not np.all(np.isfinite(value)):
        raise ValueError(f"{name} must be a finite {size}×{size} matrix, got shape {value.shape}")
    scale = np.abs(value).max()
    if not np.allclose(value, value.T, rtol=0.0, atol=1e-9 * scale):
        raise ValueError(f"{name} must be symmetric")
    bound = -1e-9 * scale if semi else 0.0
    lowest = np.linalg.eigvalsh(value).min()
    if lowest < bound or (not semi and lowest == 0.0):
        raise ValueError(f"{name} must be positive {'semi-' if semi else ''}definite")
    return value


def _sqrtm(matrix: Array) -> Array:
    """Square root of a symmetric positive definite matrix."""
    values, vectors = np.linalg.eigh(matrix)
    return (vectors * np.sqrt(values)) @ vectors.T


def hand_stiffness_to_world(stiffness_hand: ArrayLike, theta_h: float) -> Array:
    """3×3 planar stiffness in the hand frame ``(n, t, θ)`` expressed in world ``(x, y, θ)`` at ``θ_h``."""
    rot = planar_hand_to_world(theta_h)
    return rot @ _symmetric_positive_definite(stiffness_hand, 3, "planar stiffness") @ rot.T


def cartesian_stiffness(
    planar: ArrayLike, out_of_plane: tuple[float, float, float] = OUT_OF_PLANE_STIFFNESS
) -> Array:
    """6×6 task stiffness: ``planar`` (3×3, world ``(x, y, θ)``) and a diagonal out-of-plane block.

    The blocks are uncoupled, so the hand shows exactly ``planar`` in the plane.
    """
    stiffness = np.zeros((6, 6))
    stiffness[:3, :3] = _symmetric_positive_definite(planar, 3, "planar stiffness")
    if len(out_of_plane) != 3 or not all(np.isfinite(k) and k > 0.0 for k in out_of_plane):
        raise ValueError(f"out_of_plane stiffness must be 3 positive numbers, got {out_of_plane!r}")
    stiffness[3:, 3:] = np.diag(out_of_plane)
    return stiffness


def task_inertia(panda: Panda, q: ArrayLike) -> Array:
    """6×6 operational-space inertia ``Λ = (J M⁻¹ Jᵀ)⁻¹`` of the hand, task coordinates (kg, kg·m)."""
    q = np.asarray(q, dtype=float)
    mass = pin.crba(panda.model, panda.data, q)
    mass = np.triu(mass) + np.triu(mass, 1).T
    jac = task_jacobian(hand_jacobian(panda, q))
    return np.linalg.inv(jac @ np.linalg.solve(mass, jac.T))


def critical_damping(stiffness: ArrayLike, inertia: ArrayLike, ratio: float = 1.0) -> Array:
    """Damping ``D = 2ζ Λ½ (Λ^-½ K Λ^-½)½ Λ½``: every mode of ``Λẍ + Dẋ + Kx = 0`` has ratio ``ζ``."""
    if not (np.isfinite(ratio) and ratio >= 0.0):
        raise ValueError(f"damping ratio must be non-negative, got {ratio!r}")
    size = np.shape(stiffness)[0]
    root = _sqrtm(_symmetric_positive_definite(inertia, size, "inertia"))
    inv_root = np.linalg.inv(root)
    inner = inv_root @ _symmetric_positive_definite(stiffness, size, "stiffness") @ inv_root
    return 2.0 * ratio * root @ _sqrtm(0.5 * (inner + inner.T)) @ root


@dataclass(frozen=True, eq=False)
class ImpedanceGains:
    """Cartesian impedance of the hand in task coordinates, and the null-space posture gains.

    Attributes:
        stiffness: 6×6 ``K`` (N/m, N·m/rad).
        damping: 6×6 ``D`` (N·s/m, N·m·s/rad), symmetric positive semi-definite.
        null_stiffness: joint stiffness of the posture task in the null space (N·m/rad).
        null_damping: joint damping in the null space (N·m·s/rad).
    """

    stiffness: Array
    damping: Array
    null_stiffness: float = 5.0
    null_damping: float = 1.0

    def __post_init__(self) -> None:
        stiffness = _symmetric_positive_definite(self.stiffness, 6, "stiffness").copy()
        damping = _symmetric_positive_definite(self.damping, 6, "damping", semi=True).copy()
        stiffness.setflags(write=False)
        damping.setflags(write=False)
        object.__setattr__(self, "stiffness", stiffness)
        object.__setattr__(self, "damping", damping)
        for name in ("null_stiffness", "null_damping"):
            value = getattr(self, name)
            if not (np.isfinite(value) and value >= 0.0):
                raise ValueError(f"{name} must be a non-negative number, got {value!r}")


def impedance_gains(
    panda: Panda,
    q: ArrayLike,
    planar: ArrayLike,
    out_of_plane: tuple[float, float, float] = OUT_OF_PLANE_STIFFNESS,
    damping_ratio: float = 1.0,
    null_stiffness: float = 5.0,
    null_damping: float = 1.0,
) -> ImpedanceGains:
    """Gains realising the planar stiffness ``planar`` (world ``(x, y, θ)``) at the hand.

    The damping is ``damping_ratio`` times critical for the operational-space inertia at ``q``;
    the null-space posture gains are passed through.
    """
    stiffness = cartesian_stiffness(planar, out_of_plane)
    damping = critical_damping(stiffness, task_inertia(panda, q), damping_ratio)
    return ImpedanceGains(stiffness, damping, null_stiffness, null_damping)


def joint_stiffness(task_jac: ArrayLike, stiffness: ArrayLike, null_stiffness: float) -> Array:
    """``K_q = Jᵀ K J + N k_null`` (N·m/rad): the joint stiffness realised by the Cartesian impedance.

    ``task_jac`` is the 6×n task Jacobian, ``stiffness`` the 6×6 ``K``, ``N = I − J⁺J`` the
    null-space projector. First order, static, about an unloaded equilibrium.
    """
    jac = np.asarray(task_jac, dtype=float)
    null = np.eye(jac.shape[1]) - np.linalg.pinv(jac) @ jac
    return jac.T @ np.asarray(stiffness, dtype=float) @ jac + null_stiffness * null


def planar_stiffness(planar_jac: ArrayLike, joint_stiffness: ArrayLike) -> Array:
    """``K_planar = (J_p K_q⁻¹ J_pᵀ)⁻¹``: a joint stiffness seen at the hand in the plane (3×3).

    ``planar_jac`` is ``J_p`` (3×n, rows ``(ẋ, ẏ, θ̇)``), ``joint_stiffness`` the n×n ``K_q``
    (invertible; it need not be symmetric).
    """
    jac = np.asarray(planar_jac, dtype=float)
    stiffness = np.asarray(joint_stiffness, dtype=float)
    if jac.ndim != 2 or jac.shape[0] != 3 or stiffness.shape != (jac.shape[1], jac.shape[1]):
        raise ValueError(f"expected J_p 3×n and K_q n×n, got {jac.shape} and {stiffness.shape}")
    return np.linalg.inv(jac @ np.linalg.solve(stiffness, jac.T))
