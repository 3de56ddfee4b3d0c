"""The robot's flat hand: the one owner of its length, impedance and force limits.

The robot knows its own hand. A :class:`Hand` is built once per run (``LoopParams.hand``) and handed
to the plant (the simulated hand body and its impedance), the estimator (the torque limits
``|τ| ≤ l_h f_n`` and the pivot geometry) and the controller (``Δw = K Δx_tar`` and the normal-force
limits), so that no part of ccopt carries a second default.

Units are SI. The impedance acts at the centre of the hand's contact face, in world axes
(:mod:`ccopt.geometry`): ``w = K (x_tar − x_h) + D (v_tar − v_h)`` with ``K = diag(k_x, k_y, k_θ)``.
"""

from __future__ import annotations

import functools
import math
from dataclasses import dataclass

import numpy as np

from ccopt import geometry, validation


@dataclass(frozen=True)
class Hand:
    """A flat hand: a line contact face of length ``2 l_h`` on a box, under planar impedance.

    Attributes:
        half_length: ``l_h``, half the length of the contact face, m. 3 cm by default, so that the
            hand fits on the paper's smallest faces (7 cm); the paper's own hand was 10 cm long.
        stiffness: impedance ``(k_x, k_y, k_θ)`` in world axes, N/m, N/m, N·m/rad (docs/architecture.md §5).
        damping_ratio: impedance damping as a fraction of critical damping of the free hand.
        force_limits: ``(f_min, f_max)``, the smallest and largest normal force the hand may press
            with, N.
        thickness: extent of the hand box behind its contact face, m.
        mass: mass of the moving hand, kg (gravity compensated).

    Raises:
        TypeError: a field is not a real number.
        ValueError: a field is non-finite or out of range (the message names it).
    """

    half_length: float = 0.03
    stiffness: tuple[float, float, float] = (2000.0, 2000.0, 60.0)
    damping_ratio: float = 1.0
    force_limits: tuple[float, float] = (3.0, 25.0)
    thickness: float = 0.02
    mass: float = 1.0

    def __post_init__(self) -> None:
        for name in ("half_length", "thickness", "mass"):
            object.__setattr__(self, name, validation.positive(f"hand {name}", getattr(self, name)))
        stiffness = validation.reals("hand stiffness", self.stiffness, 3)
        if min(stiffness) <= 0.0:
            raise ValueError(f"hand stiffness must be positive, got {self.stiffness!r}")
        object.__setattr__(self, "stiffness", stiffness)
        ratio = validation.real("hand damping_ratio", self.damping_ratio)
        if ratio < 0.0:
            raise ValueError(f"hand damping_ratio must be non-negative, got {ratio!r}")
        object.__setattr__(self, "damping_ratio", ratio)
        f_min, f_max = validation.reals("hand force_limits", self.force_limits, 2)
        if not 0.0 <= f_min < f_max:
            raise ValueError(f"hand force_limits must satisfy 0 ≤ f_min < f_max, got {self.force_limits!r}")
        object.__setattr__(self, "force_limits", (f_min, f_max))

    @property
    def inertia(self) -> float:
        """Moment of inertia of the hand box about the contact-face centre (out of plane), kg·m²."""
        length, thick = 2.0 * self.half_length, self.thickness
        return self.mass * ((length**2 + thick**2) / 12.0 + 0.25 * thick**2)

    @property
    def damping(self) -> tuple[float, float, float]:
        """Impedance damping ``(d_x, d_y, d_θ)``, N·s/m, N·s/m, N·m·s/rad, from ``damping_ratio``."""
        masses = (self.mass, self.mass, self.inertia)
        return tuple(
            2.0 * self.damping_ratio * math.sqrt(k * m) for k, m in zip(self.stiffness, masses, strict=True)
        )

    @functools.cached_property
    def _diagonal_stiffness(self) -> np.ndarray:
        """``diag(k_x, k_y, k_θ)``, read-only, made once (the controller reads it every tick)."""
        stiffness = np.diag(self.stiffness)
        stiffness.flags.writeable = False
        return stiffness

    def stiffness_in_hand_frame(self, theta_h: float) -> np.ndarray:
        """``K`` (3×3) acting on hand-frame ``(Δn, Δt, Δθ)`` at hand angle ``θ_h`` (N/m, N·m/rad).

        With ``k_x = k_y`` this is ``diag(k, k, k_θ)`` at every angle.
        """
        k_x, k_y, k_theta = self.stiffness
        if k_x == k_y:
            return self._diagonal_stiffness
        frame = geometry.hand_frame(theta_h)
        out = np.zeros((3, 3))
        out[:2, :2] = frame.T @ np.diag([k_x, k_y]) @ frame
        out[2, 2] = k_theta
        return out
