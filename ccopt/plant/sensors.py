"""Simulated sensors: the only way the estimator sees the world.

A wrist F/T sensor reports the hand wrench ``(f_n, f_t, τ)`` (hand frame, N and N·m, ``τ`` about
the hand face centre) with white Gaussian noise and a constant bias drawn once per run;
proprioception reports the hand pose ``(x_h, y_h, θ_h)`` (world, m and rad) with white Gaussian
noise. A dropout replaces a whole sample (pose and wrench) with NaN.

Sensor faults (:class:`Fault`, written ``KIND[:VALUE][@START_S]`` on the command line, see
:func:`parse_fault`) act on those noisy samples from their start time on, in the order given, each
on what the previous ones produced; the plain dropouts of :attr:`SensorParams.dropout_probability`
come last. Faults draw their random numbers from their own generator (spawned from the same seed),
so a run with faults sees the same noise as the run without them.
"""

from __future__ import annotations

import math
import re
from collections import deque
from dataclasses import dataclass
from numbers import Real

import numpy as np

from ccopt.clock import TIME_TOLERANCE
from ccopt.plant.base import Plant

FAULT_KINDS = {
    "dropout": "each sample (pose and wrench) is NaN with probability VALUE",
    "dead-ft": "the wrench reads exactly 0",
    "stuck-ft": "the wrench stays at its value at the start",
    "scale-ft": "the wrench is multiplied by VALUE",
    "bias-ft": "VALUE newtons are added to f_n and f_t",
    "spikes-ft": "a spike of ±VALUE newtons on f_n and f_t (random signs) in 1 % of the samples",
    "delay": "every sample is the one taken VALUE seconds earlier (NaN before there is one)",
    "dead-pose": "the pose reads NaN",
}
"""Every fault kind and what it does from its start time on."""
_VALUED = frozenset({"dropout", "scale-ft", "bias-ft", "spikes-ft", "delay"})
SPIKE_PROBABILITY = 0.01
"""Probability that a sample carries a spike (``spikes-ft``)."""
MAX_DELAY = 10.0
"""Longest ``delay`` (s): the sensors keep that much history."""
Sample = tuple[np.ndarray, np.ndarray]
"""A measured ``(hand pose, hand wrench)``."""
_FAULT_SYNTAX = re.compile(r"(?P<kind>[a-z-]+)(?::(?P<value>[^@]*))?(?:@(?P<start>.*))?")


@dataclass(frozen=True)
class Fault:
    """A sensor fault (see :data:`FAULT_KINDS`).

    Attributes:
        kind: one of :data:`FAULT_KINDS`.
        value: the kind's number — probability (``dropout``, in [0, 1]), factor (``scale-ft``),
            N (``bias-ft``, ``spikes-ft``), s (``delay``, in [0, :data:`MAX_DELAY`]) — or None for
            the kinds without one.
        start: simulated time from which the fault acts, s (≥ 0).

    Raises:
        TypeError: a number is not a real number.
        ValueError: unknown kind, a missing, superfluous, non-finite or out-of-range number.
    """

    kind: str
    value: float | None = None
    start: float = 0.0

    def __post_init__(self) -> None:
        if self.kind not in FAULT_KINDS:
            raise ValueError(f"unknown sensor fault {self.kind!r}; expected one of {', '.join(FAULT_KINDS)}")
        start = _finite(f"{self.kind} start", self.start)
        if start < 0.0:
            raise ValueError(f"{self.kind} start must be at least 0 s, got {self.start!r}")
        object.__setattr__(self, "start", start)
        if self.kind not in _VALUED:
            if self.value is not None:
                raise ValueError(f"sensor fault {self.kind} takes no value, got {self.value!r}")
            return
        if self.value is None:
            raise ValueError(f"sensor fault {self.kind} needs a value ({FAULT_KINDS[self.kind]})")
        value = _finite(f"{self.kind} value", self.value)
        if self.kind == "dropout" and not 0.0 <= value <= 1.0:
            raise ValueError(f"dropout probability must be in [0, 1], got {self.value!r}")
        if self.kind == "delay" and not 0.0 <= value <= MAX_DELAY:
            raise ValueError(f"delay must be in [0, {MAX_DELAY:g}] s, got {self.value!r}")
        object.__setattr__(self, "value", value)

    def __str__(self) -> str:
        """The command-line form ``KIND[:VALUE][@START_S]`` (:func:`parse_fault` reads it back)."""
        value = "" if self.value is None else f":{self.value!r}"
        start = f"@{self.start!r}" if self.start else ""
        return f"{self.kind}{value}{start}"


def _finite(name: str, value: object) -> float:
    """``value`` as a finite float; ``TypeError``/``ValueError`` naming ``name`` and the value."""
    if isinstance(value, bool) or not isinstance(value, Real):
        raise TypeError(f"{name} must be a real number, got {type(value).__name__} {value!r}")
    number = float(value)
    if not math.isfinite(number):
        raise ValueError(f"{name} must be finite, got {value!r}")
    return number


def parse_fault(text: str) -> Fault:
    """A :class:`Fault` from ``KIND[:VALUE][@START_S]``, e.g. ``dropout:0.3``, ``dead-ft@2.5``,
    ``scale-ft:0.1@1``; ``ValueError`` naming ``text`` and what is wrong otherwise."""
    match = _FAULT_SYNTAX.fullmatch(text.strip()) if isinstance(text, str) else None
    if match is None:
        raise ValueError(f"sensor fault {text!r} is not KIND[:VALUE][@START_S], e.g. dropout:0.3@2")
    try:
        value = None if match["value"] is None else float(match["value"])
        start = 0.0 if match["start"] is None else float(match["start"])
    except ValueError:
        raise ValueError(f"sensor fault {text!r}: VALUE and START_S must be numbers") from None
    try:
        return Fault(match["kind"], value, start)
    except ValueError as error:
        raise ValueError(f"sensor fault {text!r}: {error}") from None


@dataclass(frozen=True)
class SensorParams:
    """Noise model and faults.

    Attributes:
        sigma_force: F/T force noise standard deviation, N (both ``f_n`` and ``f_t``).
        sigma_torque: F/T torque noise standard deviation, N·m.
        bias_force: standard deviation of the constant force bias drawn once per run, N.
        bias_torque: standard deviation of the constant torque bias drawn once per run, N·m.
        sigma_position: hand position noise standard deviation, m (each axis).
        sigma_angle: hand angle noise standard deviation, rad.
        dropout_probability: probability that a sample is all NaN.
        faults: sensor faults (:class:`Fault`), applied in this order.
    """

    sigma_force: float = 0.3
    sigma_torque: float = 0.005
    bias_force: float = 0.1
    bias_torque: float = 0.002
    sigma_position: float = 2e-4
    sigma_angle: float = math.radians(0.1)
    dropout_probability: float = 0.0
    faults: tuple[Fault, ...] = ()

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
        if isinstance(self.faults, str | Fault) or not all(isinstance(f, Fault) for f in self.faults):
            raise TypeError(f"faults must be a sequence of Fault, got {self.faults!r}")
        object.__setattr__(self, "faults", tuple(self.faults))

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
    """Noisy, biased, possibly faulty, seeded view of a :class:`~ccopt.plant.base.Plant`.

    Args:
        plant: the simulated system.
        params: noise model and faults.
        seed: seed of the ``numpy.random.Generator``; the same seed gives the same samples.
    """

    def __init__(self, plant: Plant, params: SensorParams | None = None, seed: int | None = 0) -> None:
        self.plant = plant
        self.params = params or SensorParams()
        sequence = np.random.SeedSequence(seed)
        self._rng = np.random.default_rng(sequence)  # the same stream as default_rng(seed)
        p = self.params
        self._sigma = np.array(
            [p.sigma_position, p.sigma_position, p.sigma_angle, p.sigma_force, p.sigma_force, p.sigma_torque]
        )
        self.bias = self._rng.standard_normal(3) * np.array([p.bias_force, p.bias_force, p.bias_torque])
        """The constant F/T bias of this run, hand frame ``(f_n, f_t, τ)``."""
        self._faults = [_FAULT_STAGES[fault.kind](fault) for fault in p.faults]
        self._fault_rng = np.random.default_rng(sequence.spawn(1)[0])
        self._pose_offsets: list[list[float]] = []  # of the batch's samples, as floats
        self._wrench_offsets: list[list[float]] = []
        self._dropped: list[bool] = []
        self._cursor = 0

    def _refill(self) -> None:
        """Draw the next :data:`BATCH` samples' noise (plus bias), dropouts and fault draws at once
        (kept as floats: a read adds its sample's in floats, the values NumPy's sums would have)."""
        offsets = self._rng.standard_normal((BATCH, 6)) * self._sigma
        offsets[:, 3:] += self.bias
        self._pose_offsets, self._wrench_offsets = offsets[:, :3].tolist(), offsets[:, 3:].tolist()
        self._dropped = (self._rng.random(BATCH) < self.params.dropout_probability).tolist()
        for stage in self._faults:
            stage.refill(self._fault_rng)
        self._cursor = 0

    def read(self) -> Measurement:
        """Sample the sensors now."""
        if self._cursor == len(self._dropped):
            self._refill()
        k = self._cursor
        self._cursor += 1
        if self._faults:
            return self._read_faulty(k)
        if self._dropped[k]:
            return Measurement(self.plant.time, np.full(3, np.nan), np.full(3, np.nan))
        pose = _plus(self.plant.hand_pose(), self._pose_offsets[k])
        return Measurement(self.plant.time, pose, _plus(self.plant.hand_wrench(), self._wrench_offsets[k]))

    def _read_faulty(self, k: int) -> Measurement:
        """:meth:`read` through the faults: sample ``k`` of the batch, the faults, then the dropouts."""
        time = self.plant.time
        pose = _plus(self.plant.hand_pose(), self._pose_offsets[k])
        wrench = _plus(self.plant.hand_wrench(), self._wrench_offsets[k])
        for stage in self._faults:
            if time >= stage.start - TIME_TOLERANCE:
                pose, wrench = stage.apply(time, k, pose, wrench)
            else:
                stage.observe(time, pose, wrench)
        if self._dropped[k]:
            return Measurement(time, np.full(3, np.nan), np.full(3, np.nan))
        return Measurement(time, pose, wrench)


def _plus(values: np.ndarray, offsets: list[float]) -> np.ndarray:
    """``values + offsets`` of three numbers, added in floats (no NumPy operation per read)."""
    a, b, c = values.tolist()
    d, e, f = offsets
    return np.array((a + d, b + e, c + f))


class _FaultStage:
    """One active fault: :meth:`apply` from its start time, :meth:`observe` before it."""

    def __init__(self, fault: Fault) -> None:
        self.start = fault.start
        self.value = fault.value

    def refill(self, rng: np.random.Generator) -> None:
        """Draw this fault's random numbers for the next :data:`BATCH` samples (none by default)."""

    def observe(self, time: float, pose: np.ndarray, wrench: np.ndarray) -> None:
        """See a sample before the fault starts (nothing to remember by default)."""

    def apply(self, time: float, k: int, pose: np.ndarray, wrench: np.ndarray) -> Sample:
        """The faulty ``(pose, wrench)`` of sample ``k`` of the batch, taken at ``time``."""
        raise NotImplementedError


class _Dropout(_FaultStage):
    def refill(self, rng: np.random.Generator) -> None:
        self._dropped = rng.random(BATCH) < self.value

    def apply(self, time: float, k: int, pose: np.ndarray, wrench: np.ndarray) -> Sample:
        if self._dropped[k]:
            return np.full(3, np.nan), np.full(3, np.nan)
        return pose, wrench


class _DeadFT(_FaultStage):
    def apply(self, time: float, k: int, pose: np.ndarray, wrench: np.ndarray) -> Sample:
        return pose, np.zeros(3)


class _StuckFT(_FaultStage):
    _held: np.ndarray | None = None

    def apply(self, time: float, k: int, pose: np.ndarray, wrench: np.ndarray) -> Sample:
        if self._held is None:
            self._held = wrench.copy()
        return pose, self._held.copy()


class _ScaleFT(_FaultStage):
    def apply(self, time: float, k: int, pose: np.ndarray, wrench: np.ndarray) -> Sample:
        return pose, wrench * self.value


class _BiasFT(_FaultStage):
    def apply(self, time: float, k: int, pose: np.ndarray, wrench: np.ndarray) -> Sample:
        return pose, wrench + np.array([self.value, self.value, 0.0])


class _SpikesFT(_FaultStage):
    def refill(self, rng: np.random.Generator) -> None:
        hits = rng.random(BATCH) < SPIKE_PROBABILITY
        signs = rng.choice([-1.0, 1.0], size=(BATCH, 2))
        self._spikes = np.zeros((BATCH, 3))
        self._spikes[:, :2] = hits[:, None] * signs * self.value
        self._hits = hits

    def apply(self, time: float, k: int, pose: np.ndarray, wrench: np.ndarray) -> Sample:
        return (pose, wrench + self._spikes[k]) if self._hits[k] else (pose, wrench)


class _Delay(_FaultStage):
    def __init__(self, fault: Fault) -> None:
        super().__init__(fault)
        self._history: deque[tuple[float, np.ndarray, np.ndarray]] = deque()

    def observe(self, time: float, pose: np.ndarray, wrench: np.ndarray) -> None:
        """Keep the samples still needed: the newest one at least ``value`` old, and all later."""
        history = self._history
        history.append((time, pose, wrench))
        due = time - self.value + TIME_TOLERANCE
        while len(history) > 1 and history[1][0] <= due:
            history.popleft()

    def apply(self, time: float, k: int, pose: np.ndarray, wrench: np.ndarray) -> Sample:
        self.observe(time, pose, wrench)
        taken, old_pose, old_wrench = self._history[0]
        if taken > time - self.value + TIME_TOLERANCE:
            return np.full(3, np.nan), np.full(3, np.nan)
        return old_pose.copy(), old_wrench.copy()


class _DeadPose(_FaultStage):
    def apply(self, time: float, k: int, pose: np.ndarray, wrench: np.ndarray) -> Sample:
        return np.full(3, np.nan), wrench


_FAULT_STAGES: dict[str, type[_FaultStage]] = {
    "dropout": _Dropout,
    "dead-ft": _DeadFT,
    "stuck-ft": _StuckFT,
    "scale-ft": _ScaleFT,
    "bias-ft": _BiasFT,
    "spikes-ft": _SpikesFT,
    "delay": _Delay,
    "dead-pose": _DeadPose,
}
