"""A constant-rate Kalman filter of a measured angle (for ``θ_o`` from the hand angle while flush).

The state is the angle and its rate; the rate is driven by white angular acceleration of standard
deviation ``acceleration`` (rad/s²) and each measurement carries white noise of standard deviation
``noise`` (rad). Unlike a low-pass filter it follows a steady rotation without lag, so it can average
the sensor noise during a pivot: on a plant recording with 0.1° of angle noise, ``acceleration = 3``
brought the largest ``θ_o`` error from 0.60° to 0.37° at 1 kHz and to 0.44° at 100 Hz. Samples may
come at any interval; the first one after :meth:`AngleFilter.reset` (or after time went back)
starts the filter at the measured angle, at rest with a rate uncertainty of ``rate_std``; so does a
measurement beyond ``restart_gate`` predicted standard deviations (a turn faster than the model
allows is followed at once, unfiltered, rather than with a lag), and one whose prediction overflows
(a gap of astronomical length). Innovations are wrapped to
(−π, π]; the output is continuous from a start on (it is not wrapped).
Plain floats: a step costs about a microsecond.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

from ccopt.estimation.quantile import check_number


@dataclass(frozen=True)
class AngleFilterParams:
    """Noise model of :class:`AngleFilter`.

    Attributes:
        noise: standard deviation of a measured angle (rad).
        acceleration: standard deviation of the angular acceleration (rad/s²).
        rate_std: standard deviation of the rate when the filter starts (rad/s).
        restart_gate: a measurement this many predicted standard deviations away restarts the filter.
    """

    noise: float = math.radians(0.1)
    acceleration: float = 3.0
    rate_std: float = 1.0
    restart_gate: float = 5.0

    def __post_init__(self) -> None:
        check_number("noise", self.noise)
        check_number("acceleration", self.acceleration)
        check_number("rate_std", self.rate_std)
        check_number("restart_gate", self.restart_gate)


class AngleFilter:
    """Constant-rate Kalman filter of an angle (see the module docstring)."""

    def __init__(self, params: AngleFilterParams | None = None) -> None:
        self.params = params if params is not None else AngleFilterParams()
        self._noise_variance = self.params.noise**2
        self._acceleration_variance = self.params.acceleration**2
        self._restart_gate_squared = self.params.restart_gate**2
        self.reset()

    def reset(self) -> None:
        """Forget the angle: the next :meth:`update` starts afresh."""
        self._time = math.nan

    def update(self, time: float, angle: float) -> float:
        """Filter the angle (rad) measured at ``time`` (s); returns the filtered angle (rad)."""
        if not time >= self._time:  # first sample, or time went back
            return self._start(time, angle)
        dt = time - self._time
        p00, p01, p11 = self._p00, self._p01, self._p11
        q = self._acceleration_variance
        dt2 = dt * dt
        p00 += dt * (2.0 * p01 + dt * p11) + q * dt2 * dt2 / 4.0
        p01 += dt * p11 + q * dt2 * dt / 2.0
        p11 += q * dt2
        predicted = self._angle + self._rate * dt
        variance = p00 + self._noise_variance
        difference = angle - predicted
        if not (math.isfinite(difference) and math.isfinite(variance)):  # a gap beyond floating point
            return self._start(time, angle)
        innovation = math.remainder(difference, math.tau)
        if innovation * innovation > self._restart_gate_squared * variance:
            return self._start(time, angle)
        self._time = time
        gain_angle, gain_rate = p00 / variance, p01 / variance
        self._angle = predicted + gain_angle * innovation
        self._rate += gain_rate * innovation
        self._p00, self._p01, self._p11 = (
            p00 - gain_angle * p00,
            p01 - gain_angle * p01,
            p11 - gain_rate * p01,
        )
        return self._angle

    def _start(self, time: float, angle: float) -> float:
        self._time, self._angle, self._rate = time, angle, 0.0
        self._p00, self._p01, self._p11 = self._noise_variance, 0.0, self.params.rate_std**2  # covariance
        return angle
