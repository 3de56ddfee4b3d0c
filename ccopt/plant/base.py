"""What every simulated plant offers: its parameters, its start configuration and its interface.

Frames and signs are those of :mod:`ccopt.geometry`: world ``(x, y, θ)`` with ``y`` up, hand pose
at the centre of the hand's contact face, hand wrench ``(f_n, f_t, τ)`` exerted by the hand on the
object in the hand contact frame, ``τ`` about the face centre.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Protocol, runtime_checkable

import numpy as np
from numpy.typing import ArrayLike

from ccopt import validation
from ccopt.hand import Hand
from ccopt.objects import PlanarObject
from ccopt.plant.truth import Truth


def planar_vector(name: str, value: ArrayLike) -> np.ndarray:
    """``value`` as 3 finite floats ``(x, y, θ)``; ``ValueError`` naming ``name`` otherwise."""
    vector = np.asarray(value, dtype=float)
    if vector.shape != (3,) or not math.isfinite(sum(vector.tolist())):  # a NaN or an inf: not finite
        raise ValueError(f"{name} must be 3 finite numbers (x, y, θ), got {value!r}")
    return vector


MIN_RATE = 1.0
"""Slowest rate at which a loop may read a plant's sensors or command it, Hz."""


@dataclass(frozen=True)
class PlantParams:
    """Numerical parameters of a simulated plant (the hand's own are in :class:`~ccopt.hand.Hand`).

    Attributes:
        timestep: simulation step, s.
        depth: out-of-plane extent of the object prism (the hand is 1.5× deeper), m.
        contact_timeconst: MuJoCo ``solref`` time constant of every contact pair, s.
        solimp: MuJoCo ``solimp`` ``(d_min, d_max, width)`` of every contact pair (width in m).
            The soft start (``d_min = 0.5``) keeps sliding contacts from chattering: with
            MuJoCo's default ``(0.9, 0.95, 0.001)`` a contact sliding at 5–20 mm/s bounces
            (normal force ±25–50 %, intermittent loss of contact).
        impratio: MuJoCo ratio of frictional to normal constraint impedance. 1000 keeps creep
            under a static load at 90 % of the friction limit below 0.01 mm/s with the soft
            ``solimp`` above.

    Raises:
        TypeError: a field is not a real number.
        ValueError: a field is non-finite or out of range (the message names it).
    """

    timestep: float = 1e-3
    depth: float = 0.04
    contact_timeconst: float = 0.005
    solimp: tuple[float, float, float] = (0.5, 0.95, 0.01)
    impratio: float = 1000.0

    def __post_init__(self) -> None:
        for name in ("depth", "impratio"):
            object.__setattr__(self, name, validation.positive(name, getattr(self, name)))
        timestep = validation.positive("timestep", self.timestep)
        if timestep > 0.01:
            raise ValueError(f"timestep must be at most 0.01 s, got {timestep!r}")
        object.__setattr__(self, "timestep", timestep)
        timeconst = validation.positive("contact_timeconst", self.contact_timeconst)
        if timeconst < 2.0 * timestep:
            raise ValueError(
                f"contact_timeconst must be at least twice the timestep ({2.0 * timestep} s), "
                f"got {timeconst!r}"
            )
        object.__setattr__(self, "contact_timeconst", timeconst)
        if isinstance(self.solimp, str) or np.ndim(self.solimp) != 1 or len(self.solimp) != 3:
            raise ValueError(f"solimp must be three numbers (d_min, d_max, width), got {self.solimp!r}")
        d_min, d_max, width = (validation.real(f"solimp[{i}]", v) for i, v in enumerate(self.solimp))
        if not 0.0 < d_min <= d_max < 1.0 or width <= 0.0:
            raise ValueError(f"solimp must satisfy 0 < d_min <= d_max < 1 and width > 0, got {self.solimp!r}")
        object.__setattr__(self, "solimp", (d_min, d_max, width))


@dataclass(frozen=True)
class StartConfig:
    """Where a run starts: the hand flush on one object face, pressing, the object on one vertex.

    Attributes:
        hand_face: index of the object face the hand is flush on (see :mod:`ccopt.objects`).
        theta_o: orientation of that face, rad (equals ``θ_h`` while flush; 0 = hand on top).
        s_h: hand sliding position ``(r_o − r_h)·e_t``, m.
        normal_force: hand normal force the start target is set to press with, N.
        x_o: ground-contact x (the object's lowest vertex), m.
        settle_time: simulated time to settle before the run starts, s.
    """

    hand_face: int = 0
    theta_o: float = 0.0
    s_h: float = 0.0
    normal_force: float = 5.0
    x_o: float = 0.0
    settle_time: float = 0.5

    def __post_init__(self) -> None:
        face = self.hand_face
        if isinstance(face, bool) or not isinstance(face, int | np.integer):
            got = f"{type(face).__name__} {validation.short(face)}"
            raise TypeError(f"hand_face must be an integer, got {got}")
        if face < 0:
            raise ValueError(f"hand_face must be non-negative, got {validation.short(face)}")
        object.__setattr__(self, "hand_face", int(face))
        for name in ("theta_o", "s_h", "x_o"):
            object.__setattr__(self, name, validation.real(name, getattr(self, name)))
        object.__setattr__(self, "normal_force", validation.positive("normal_force", self.normal_force))
        settle = validation.real("settle_time", self.settle_time)
        if settle < 0.0:
            raise ValueError(f"settle_time must be non-negative, got {settle!r}")
        object.__setattr__(self, "settle_time", settle)


def plant_inputs(
    obj: object, params: object, start: object, hand: object
) -> tuple[PlanarObject, PlantParams, StartConfig, Hand]:
    """A plant's constructor arguments with defaults filled in; ``TypeError`` naming a wrong one."""
    params = PlantParams() if params is None else params
    start = StartConfig() if start is None else start
    hand = Hand() if hand is None else hand
    parts = (("obj", PlanarObject), ("params", PlantParams), ("start", StartConfig), ("hand", Hand))
    values = {"obj": obj, "params": params, "start": start, "hand": hand}
    validation.check_types((name, values[name], kind) for name, kind in parts)
    return obj, params, start, hand


@runtime_checkable
class Plant(Protocol):
    """A simulated hand–object–ground system driven by a planar hand impedance."""

    time: float
    """Simulated time, s."""
    timestep: float
    """Simulation step, s."""
    params: PlantParams
    hand: Hand
    hand_angle_range: tuple[float, float]
    """The hand angles ``θ_h`` (rad) the robot reaches; a motion planned or scripted to end outside
    is refused."""
    target_angle_range: tuple[float, float]
    """The impedance target's angles (rad) the robot may be driven to: :attr:`hand_angle_range` and
    the room a motion at its end needs (the regulation's torque turns the target on, and a slide
    may turn the object on); the loop holds the target within it."""
    force_model_error: float
    """N: how far the hand force may differ from the impedance model ``K e + D ė`` (filtered, for as
    long as a sensor fault must last, :mod:`ccopt.health`) in fault-free runs of this plant: its
    inertia, and on an arm the coupling of its axes. The sensor-health check tolerates this much."""
    force_headroom: float
    """N: the least headroom the controller's predicted normal force and the statics' force targets
    keep below the hand's largest force on this plant (:attr:`ControllerParams.force_headroom
    <ccopt.control.controller.ControllerParams.force_headroom>` where larger): how far the measured
    force runs above the impedance model in a push, so that it stays within the limit by about the
    sensor noise."""
    hand_turn_rate: float
    """rad/s: the fastest the impedance target may turn the hand (``math.inf``: as fast as the
    controller's own limit). A turning hand lags its target and runs on past it when the target
    stops; a pivot that lands the object on a face, unforeseeable from the estimate, is stopped
    when the hand is seen rolling, and the hand rolls against the object by what it lagged and ran
    on. The loop caps the controller's angular speed at this rate."""

    def set_target(self, pose: ArrayLike, velocity: ArrayLike | None = None, *, check: bool = True) -> None:
        """Hand impedance target, world ``(x, y, θ)`` (m, rad), with optional velocity feed-forward.
        ``ValueError`` unless each is 3 finite numbers; ``check=False`` skips the check (a caller
        whose values are so by construction: the closed loop's every step)."""

    def target(self) -> np.ndarray:
        """Current impedance target, world ``(x, y, θ)``."""

    def step(self, n_steps: int = 1) -> None:
        """Advance the simulation by ``n_steps`` timesteps."""

    def hand_pose(self) -> np.ndarray:
        """True world ``(x_h, y_h, θ_h)`` of the hand contact-face centre."""

    def hand_wrench(self) -> np.ndarray:
        """True wrench the hand exerts on the object, hand frame ``(f_n, f_t, τ)``, ``τ`` about the
        face centre: what an ideal, gravity-compensated wrist F/T sensor reports."""

    def truth(self) -> Truth:
        """Ground truth of the contact configuration."""

    def push_object(self, force: ArrayLike, duration: float) -> None:
        """Apply world force ``(f_x, f_y)`` (N) at the object's centroid for ``duration`` s from now."""
