"""Simulated sensors: the only way the estimator sees the world.

A wrist F/T sensor reports the hand wrench ``(f_n, f_t, τ)`` (hand frame, N and N·m, ``τ`` about
the hand face centre) with white Gaussian noise and a constant bias drawn once per run;
proprioception reports the hand pose ``(x_h, y_h, θ_h)`` (world, m and rad) with white Gaussian
noise. A dropout replaces a whole sample (pose and wrench) with NaN.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from numbers import Real

import numpy as np

from ccopt.plant.base import Plant


@dataclass(frozen=True)
class SensorParams:
    """Noise model.

    Attributes:
        sigma_force: F/T force noise standard deviation, N (both ``f_n`` and ``f_t``).
        sigma_torque: F/T torque noise standard deviation, N·m.
        bias_force: standard deviation of the constant force bias drawn once per run, N.
        bias_torque: standard deviation of the constant torque bias drawn once per run, N·m.
        sigma_position: hand position noise standard deviation, m (each axis).
        sigma_angle: hand angle noise standard deviation, rad.
        dropout_probability: probability that a sample is all NaN.
    """

    sigma_force: float = 0.3
    sigma_torque: float = 0.005
    bias_force: float = 0.1
    bias_torque: float = 0.002
    sigma_position: float = 2e-4
    sigma_angle: float = math.radians(0.1)
    dropout_probability: float = 0.0

    def __post_init__(self) -> None:
        for name in (
            "sigma_force",
            "sigma_torque",
            "bias_force",
            "bias_torque",
            "sigma_position",
            "sigma_angle",
            "dropout_probability",
        ):
            value = getattr(self, name)
            if isinstance(value, bool) or not isinstance(value, Real):
                raise TypeError(f"{name} must be a real number, got {type(value).__name__} {value!r}")
            if not math.isfinite(value) or value < 0.0:
                raise ValueError(f"{name} must be finite and non-negative, got {value!r}")
            object.__setattr__(self, name, float(value))
        if self.dropout_probability > 1.0:
            raise ValueError(f"dropout_probability must be at most 1, got {self.dropout_probability!r}")

    @classmethod
    def ideal(cls) -> SensorParams:
        """No noise, no bias, no dropouts."""
        return cls(0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0)


@dataclass(frozen=True)
class Measurement:
    """One sensor sample.

    Attributes:
        time: s.
        hand_pose: measured world ``(x_h, y_h, θ_h)``, m and rad (NaN on dropout).
        hand_wrench: measured hand-frame ``(f_n, f_t, τ)``, N and N·m (NaN on dropout).
    """

    time: float
    hand_pose: np.ndarray
    hand_wrench: np.ndarray


BATCH = 1024
"""Samples of noise drawn at once (one generator call per batch keeps a read cheap)."""


class Sensors:
    """Noisy, biased, seeded view of a :class:`~ccopt.plant.base.Plant`.

    Args:
        plant: the simulated system.
        params: noise model.
        seed: seed of the ``numpy.random.Generator``; the same seed gives the same samples.
    """

    def __init__(self, plant: Plant, params: SensorParams | None = None, seed: int | None = 0) -> None:
        self.plant = plant
        self.params = params or SensorParams()
        self._rng = np.random.default_rng(seed)
        p = self.params
        self._sigma = np.array(
            [p.sigma_position, p.sigma_position, p.sigma_angle, p.sigma_force, p.sigma_force, p.sigma_torque]
        )
        self.bias = self._rng.standard_normal(3) * np.array([p.bias_force, p.bias_force, p.bias_torque])
        """The constant F/T bias of this run, hand frame ``(f_n, f_t, τ)``."""
        self._offsets = np.empty((0, 6))
        self._dropped = np.empty(0, dtype=bool)
        self._cursor = 0

    def _refill(self) -> None:
        """Draw the next :data:`BATCH` samples' noise (plus bias) and dropouts at once."""
        self._offsets = self._rng.standard_normal((BATCH, 6)) * self._sigma
        self._offsets[:, 3:] += self.bias
        self._dropped = self._rng.random(BATCH) < self.params.dropout_probability
        self._cursor = 0

    def read(self) -> Measurement:
        """Sample the sensors now."""
        if self._cursor == len(self._dropped):
            self._refill()
        k = self._cursor
        self._cursor += 1
        if self._dropped[k]:
            return Measurement(self.plant.time, np.full(3, np.nan), np.full(3, np.nan))
        offsets = self._offsets[k]
        return Measurement(
            self.plant.time, self.plant.hand_pose() + offsets[:3], self.plant.hand_wrench() + offsets[3:]
        )
