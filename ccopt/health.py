"""Sensor health: is the F/T sensor (and the pose) telling the truth? Pure, loop-independent.

The robot knows its own impedance: the hand is driven by ``w = K (x_tar − x_h) + D (v_tar − v_h)``
(world axes at the hand-face centre, gravity compensated, :mod:`ccopt.plant.mujoco_planar`), and with
the hand's inertia neglected (quasi-static) that is the force the hand exerts on the object, which
the wrist F/T sensor measures. :class:`SensorHealth` compares the two forces through a first-order
low-pass filter of time constant ``T``: with ``e = x_tar − x_h`` and ``ē`` its filtered value, the
filtered impedance force is ``K ē + D (e − ē)/L`` (the filter of ``ė`` is ``(e − ē)/L``, no
differentiation of noisy poses needed; ``L`` is the filter's lag of a ramp, ``T`` for a continuous
filter and ``Δt (1 − α)/α`` for the sampled one of gain ``α = 1 − exp(−Δt/T)``), and the filtered
measured force is compared with it.

On closed-loop runs of the paper schedule on the planar plant (three objects, default sensors,
estimator at 100 Hz and 1 kHz) the filtered difference stayed below 1.6 N over any 50 ms and below
5.4 N at any sample (pose noise through the damping term, sliding onsets, impacts), against forces
up to 34 N. On the Panda plant (arm inertia, a damping that couples the axes, the F/T sensor at
the flange) the model is rougher: up to 9.6 N over 50 ms on the paper schedule (the hand turning at
30°/s, before its :attr:`~ccopt.plant.base.Plant.hand_turn_rate` was capped), so a run takes its
``force_tolerance`` from the plant (:attr:`ccopt.plant.base.Plant.force_model_error`). The
torque is not compared: its prediction carries ``k_θ σ_θ`` ≈ 0.1 N·m of angle noise (and 1.4 N·m
of model error on the Panda) against torques below 1 N·m, and every fault kind shows in the forces.

Reported faults (the first one found is kept, with the time it was found):

``dead``
    the wrench reads exactly 0 for ``stuck_samples`` samples although noise is expected, or
    exactly 0 while the impedance force disagrees (below), or no finite wrench for
    ``signal_timeout``;
``stuck``
    the wrench is bitwise the same for ``stuck_samples`` samples although noise is expected;
``implausible``
    a wrench beyond the sensor's range (``max_force``, ``max_torque``), or a filtered force that
    differs from the impedance force by more than ``force_tolerance + force_ratio·|impedance
    force|`` for ``hold`` (a scaled, biased, stuck or late sensor: what the controller sees is not
    what the hand applies);
``pose_lost``
    no finite hand pose for ``signal_timeout``.

Brief dropouts are no fault; nor are spikes within the sensor's range shorter than ``hold`` (the
estimator's quantiles are built to ignore a few outliers).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike

from ccopt import clock
from ccopt.estimation.quantile import check_count, check_number

OK = "ok"
FAULT_NAMES = ("dead", "stuck", "implausible", "pose_lost")
"""The faults :class:`SensorHealth` reports, besides :data:`OK`."""
CRITICAL_DAMPING = 2.0 * math.sqrt(2000.0 * 1.0)
"""N·s/m: critical damping of the default 1 kg hand on 2000 N/m, the plants' default impedance."""


@dataclass(frozen=True)
class HealthParams:
    """What the robot knows of its impedance and sensors, and the fault thresholds.

    The defaults are the plants' default hand; :meth:`from_impedance` takes the robot's own.

    Attributes:
        stiffness: impedance ``K`` (N/m, N/m, N·m/rad), world axes at the hand-face centre.
        damping: impedance ``D`` (N·s/m, N·s/m, N·m·s/rad); only the force terms are used.
        filter_time: ``T`` of the low-pass filters, s.
        force_tolerance: filtered force disagreement always tolerated, N.
        force_ratio: further disagreement tolerated per newton of impedance force.
        hold: a disagreement must last this long to be a fault, s.
        force_noise: expected F/T force noise, N; 0 (noise-free sensors) disables the ``stuck``
            test and the ``dead`` test on repeated zeros.
        stuck_samples: identical wrenches in a row that mean ``stuck`` (or ``dead`` if all 0).
        signal_timeout: longest time without a finite wrench or pose, s.
        max_force: range of the F/T sensor's forces, N (``|f_n|`` and ``|f_t|``).
        max_torque: range of the F/T sensor's torque, N·m.
    """

    stiffness: tuple[float, float, float] = (2000.0, 2000.0, 60.0)
    damping: tuple[float, float, float] = (CRITICAL_DAMPING, CRITICAL_DAMPING, 0.3)
    filter_time: float = 0.03
    force_tolerance: float = 4.0
    force_ratio: float = 0.1
    hold: float = 0.05
    force_noise: float = 0.3
    stuck_samples: int = 5
    signal_timeout: float = 0.2
    max_force: float = 500.0
    max_torque: float = 50.0

    def __post_init__(self) -> None:
        for name in ("stiffness", "damping"):
            values = getattr(self, name)
            if isinstance(values, str) or len(values) != 3:
                raise ValueError(f"{name} must be three numbers (x, y, θ), got {values!r}")
            low_open = name == "stiffness"
            checked = tuple(check_number(f"{name}[{i}]", v, low_open=low_open) for i, v in enumerate(values))
            object.__setattr__(self, name, checked)
        for name in ("filter_time", "hold", "signal_timeout", "max_force", "max_torque"):
            object.__setattr__(self, name, check_number(name, getattr(self, name)))
        for name in ("force_tolerance", "force_ratio", "force_noise"):
            object.__setattr__(self, name, check_number(name, getattr(self, name), low_open=False))
        object.__setattr__(self, "stuck_samples", check_count("stuck_samples", self.stuck_samples, low=2))

    @classmethod
    def from_impedance(
        cls, stiffness: tuple[float, float, float], damping: tuple[float, float, float], **thresholds: float
    ) -> HealthParams:
        """The robot's own impedance ``K`` and ``D`` (the hand's or plant's, world axes) with default or
        given thresholds."""
        return cls(stiffness=tuple(stiffness), damping=tuple(damping), **thresholds)


@dataclass(frozen=True)
class Health:
    """The sensors' health.

    Attributes:
        status: :data:`OK` or one of :data:`FAULT_NAMES`.
        time: sample time at which the fault was found, s (NaN while ok).
        message: one line saying what was seen ("" while ok).
    """

    status: str
    time: float = math.nan
    message: str = ""

    @property
    def ok(self) -> bool:
        return self.status == OK


HEALTHY = Health(OK)


class SensorHealth:
    """Checks each sample against the robot's impedance (see the module docstring).

    Call :meth:`update` with every sample, in time order; the first fault found is kept.
    """

    def __init__(self, params: HealthParams | None = None) -> None:
        self.params = params if params is not None else HealthParams()
        self.health = HEALTHY
        self.residual = 0.0
        """Latest filtered disagreement between measured and impedance force, N."""
        self._wrench_seen = math.nan  # time of the last finite wrench (of the first sample before)
        self._pose_seen = math.nan
        self._previous = (math.nan, math.nan, math.nan)
        self._repeats = 0  # samples in a row equal to the previous one, this one included
        self._filter_time = math.nan  # time of the last filtered sample
        self._error = (0.0, 0.0)  # filtered x_tar − x_h (world x, y), m
        self._force = (0.0, 0.0)  # filtered measured world force, N
        self._over_since = math.nan  # start of the current disagreement

    def update(self, time: float, hand_pose: ArrayLike, hand_wrench: ArrayLike, target: ArrayLike) -> Health:
        """Check one sample: measured ``hand_pose`` ``(x_h, y_h, θ_h)`` (world, m, rad), measured
        ``hand_wrench`` ``(f_n, f_t, τ)`` (hand frame, N, N·m), the impedance ``target`` ``(x, y, θ)``
        (world, m, rad) at ``time`` (s). Returns (and keeps in :attr:`health`) the health so far."""
        if not self.health.ok:
            return self.health
        x_h, y_h, theta_h = np.asarray(hand_pose, dtype=float).tolist()
        f_n, f_t, torque = np.asarray(hand_wrench, dtype=float).tolist()
        x_tar, y_tar = np.asarray(target, dtype=float).tolist()[:2]
        if math.isnan(self._wrench_seen):
            self._wrench_seen = self._pose_seen = time
        wrench_ok = math.isfinite(f_n) and math.isfinite(f_t) and math.isfinite(torque)
        pose_ok = math.isfinite(x_h) and math.isfinite(y_h) and math.isfinite(theta_h)
        if wrench_ok:
            self._wrench_seen = time
        if pose_ok:
            self._pose_seen = time
        timeout = self.params.signal_timeout - clock.TIME_TOLERANCE
        if time - self._wrench_seen > timeout:
            return self._fault("dead", time, f"no finite wrench for {time - self._wrench_seen:.3g} s")
        if time - self._pose_seen > timeout:
            return self._fault("pose_lost", time, f"no finite hand pose for {time - self._pose_seen:.3g} s")
        if not wrench_ok:
            return self.health
        fault = self._wrench_fault(time, f_n, f_t, torque)
        if fault is not None or not (pose_ok and math.isfinite(x_tar) and math.isfinite(y_tar)):
            return self.health
        s, c = math.sin(theta_h), math.cos(theta_h)
        self._compare(time, (x_tar - x_h, y_tar - y_h), (s * f_n + c * f_t, s * f_t - c * f_n))
        return self.health

    def _wrench_fault(self, time: float, f_n: float, f_t: float, torque: float) -> Health | None:
        """Range and repetition tests of one finite wrench."""
        params = self.params
        if abs(f_n) > params.max_force or abs(f_t) > params.max_force or abs(torque) > params.max_torque:
            return self._fault(
                "implausible",
                time,
                f"wrench ({f_n:.4g} N, {f_t:.4g} N, {torque:.4g} N·m) is beyond the sensor's range "
                f"({params.max_force:g} N, {params.max_torque:g} N·m)",
            )
        wrench = (f_n, f_t, torque)
        self._repeats = self._repeats + 1 if wrench == self._previous else 1
        self._previous = wrench
        if params.force_noise > 0.0 and self._repeats >= params.stuck_samples:
            if wrench == (0.0, 0.0, 0.0):
                return self._fault("dead", time, f"the wrench reads exactly 0 for {self._repeats} samples")
            return self._fault(
                "stuck",
                time,
                f"the wrench reads ({f_n:.4g} N, {f_t:.4g} N, {torque:.4g} N·m) for {self._repeats} samples",
            )
        return None

    def _compare(self, time: float, error: tuple[float, float], force: tuple[float, float]) -> None:
        """Filter ``x_tar − x_h`` and the measured world force; a lasting disagreement is a fault."""
        params = self.params
        step = time - self._filter_time
        gain = -math.expm1(-step / params.filter_time) if step > 0.0 else 1.0  # restart if time went back
        lag = step * (1.0 - gain) / gain if gain < 1.0 else math.inf  # of a ramp, s (→ T as step → 0)
        self._filter_time = time
        (error_x, error_y), (force_x, force_y) = error, force
        (filtered_x, filtered_y), (measured_x, measured_y) = self._error, self._force
        filtered_x += gain * (error_x - filtered_x)  # per axis, written out: every sample
        filtered_y += gain * (error_y - filtered_y)
        measured_x += gain * (force_x - measured_x)
        measured_y += gain * (force_y - measured_y)
        (k_x, k_y, _), (d_x, d_y, _) = params.stiffness, params.damping
        predicted = (
            k_x * filtered_x + d_x * ((error_x - filtered_x) / lag),
            k_y * filtered_y + d_y * ((error_y - filtered_y) / lag),
        )
        self._error, self._force = (filtered_x, filtered_y), (measured_x, measured_y)
        self.residual = math.hypot(measured_x - predicted[0], measured_y - predicted[1])
        tolerance = params.force_tolerance + params.force_ratio * math.hypot(*predicted)
        if self.residual <= tolerance:
            self._over_since = math.nan
            return
        if math.isnan(self._over_since):
            self._over_since = time
        if clock.lasted(time, self._over_since, params.hold):
            dead = self._previous == (0.0, 0.0, 0.0)
            self._fault(
                "dead" if dead else "implausible",
                time,
                f"measured force ({measured_x:.1f}, {measured_y:.1f}) N differs from the impedance force "
                f"({predicted[0]:.1f}, {predicted[1]:.1f}) N by {self.residual:.1f} N for "
                f"{1e3 * (time - self._over_since):.0f} ms (tolerance {tolerance:.1f} N)",
            )

    def _fault(self, status: str, time: float, message: str) -> Health:
        self.health = Health(status, float(time), message)
        return self.health
