"""Contact-configuration sequences: the script a closed-loop run follows.

A :class:`Schedule` is a list of :class:`Step` s, each a commanded admissible motion by an increment
(pivot ``Δθ_o``, hand slide ``Δs_h``, ground slide ``Δs_g``) or a hold, with a tolerance on the
estimated coordinate and a timeout. Inside ccopt increments are SI (rad, m); schedule files, like the
CLI, use degrees and millimetres::

    name: my-sequence
    steps:
      - {motion: slide_hand, delta_mm: 10}
      - {motion: pivot, delta_deg: -7.2, tolerance_deg: 0.8, timeout_s: 6}
      - {motion: slide_ground, delta_mm: 10}
      - {motion: hold, duration_s: 1}

A step may also be a **goal** (:class:`Goal`): a configuration to reach, absolute ``θ_o`` of the
hand's face, absolute ``s_h``, ``s_g`` relative to the ground contact at the run's start; the
planner (:mod:`ccopt.planning.planner`) picks the motions from the estimated statics. Omitted
coordinates are free; tolerances default to 1° and 2 mm::

    steps:
      - {motion: explore}                  # learn what the planner needs (ends by itself)
      - {motion: reach, theta_deg: 25}
      - {motion: reach, s_h_mm: -8}
      - {motion: reach, theta_deg: 10, s_h_mm: 0, s_g_mm: 0, timeout_s: 90, tolerance_deg: 1, tolerance_mm: 2}

Built in: ``paper`` (the paper's experiment as goals: exploration, then goals in the paper's
increments of 7.2°, 10 mm and 10 mm visiting both directions of every coordinate),
``paper-script`` (the hand-scripted motions of the paper's sequences, which ask for motions the
object may not allow) and ``smoke`` (pivots both ways, for CI).
"""

from __future__ import annotations

import dataclasses
import functools
import json
import math
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path
from typing import ClassVar

import numpy as np
import yaml

from ccopt import modes
from ccopt.modes import KINDS, Kind, Motion
from ccopt.validation import parse_reason, short

PIVOT_STEP = np.deg2rad(7.2)
SLIDE_STEP = 0.010
DEFAULT_TOLERANCE = {"pivot": np.deg2rad(0.7), "slide_hand": 0.0015, "slide_ground": 0.0015, "hold": 0.0}
DEFAULT_TIMEOUT = 8.0
MAX_TIMEOUT = 3600.0
"""Longest step (a hold's duration, a step's timeout), s."""
MAX_DELTA = {"pivot": np.pi, "slide_hand": 1.0, "slide_ground": 1.0, "hold": 0.0}
"""Largest increment and tolerance of a step, rad (half a turn) or m (the longest face of an object)."""


@dataclass(frozen=True)
class Step:
    """One commanded motion.

    Attributes:
        kind: ``pivot``, ``slide_hand``, ``slide_ground`` or ``hold``.
        delta: increment of the coordinate, rad (pivot) or m (slides); 0 for a hold.
        tolerance: the step is done when the estimated error is below this (rad or m).
        timeout: the step gives up after this long, s (a hold lasts exactly this long).
        explore: the step is part of an exploration (:func:`exploration`): it ends by itself,
            reached or not, and its realised change is not scored.

    Raises ``ValueError`` naming the value: an unknown kind, a number that is not finite, a zero
    increment or tolerance, a timeout not in (0, :data:`MAX_TIMEOUT`], an increment or tolerance
    beyond :data:`MAX_DELTA`.
    """

    kind: Kind
    delta: float = 0.0
    tolerance: float = 0.0
    timeout: float = DEFAULT_TIMEOUT
    explore: bool = False

    def __post_init__(self) -> None:
        if self.kind not in KINDS:
            raise ValueError(f"unknown step kind {self.kind!r}; expected one of: {', '.join(KINDS)}")
        for name in ("delta", "tolerance", "timeout"):
            _number(getattr(self, name), f"step {name}")
        if self.kind != "hold" and self.delta == 0.0:
            raise ValueError(f"a {self.kind} step needs a non-zero increment")
        if self.kind != "hold" and self.tolerance <= 0.0:
            raise ValueError(f"step tolerance must be positive, got {self.tolerance!r}")
        if not 0.0 < self.timeout <= MAX_TIMEOUT:
            raise ValueError(f"step timeout must be in (0, {MAX_TIMEOUT:g}] s, got {self.timeout!r}")
        largest, unit = MAX_DELTA[self.kind], "rad" if self.kind == "pivot" else "m"
        for name in ("delta", "tolerance"):
            value = getattr(self, name)
            if abs(value) > largest:
                limit = f"{largest:.4g} {unit}"
                raise ValueError(f"a {self.kind} step's {name} must be at most {limit}, got {value!r}")

    @functools.cached_property  # the loop reads it every tick; a frozen step never changes
    def motion(self) -> Motion:
        """The commanded motion of :mod:`ccopt.modes`."""
        return modes.motion_of(self.kind, self.delta)

    @functools.cached_property
    def coordinate(self) -> int | None:
        """Index into ``(θ_o, s_h, s_g)`` of the coordinate this step changes (None for a hold)."""
        return modes.driven_coordinate(self.kind)


GOAL_TOLERANCE = (np.deg2rad(1.0), 0.002)
"""Default goal tolerances: angle (rad), lengths (m)."""
GOAL_TIMEOUT = 60.0
"""Default time a goal may take, s."""


@dataclass(frozen=True)
class Goal:
    """A configuration to reach: the planner (:mod:`ccopt.planning.planner`) turns it into motions.

    Attributes:
        theta_o: the angle of the hand's face ``θ_o`` to reach, rad (None: free).
        s_h: the hand's sliding position ``s_h`` to reach, m (None: free).
        s_g: the ground contact's position relative to where it was at the run's start, m
            (None: free).
        angle_tolerance: reached when ``|θ̂_o − theta_o|`` is at most this, rad.
        length_tolerance: reached when ``|ŝ_h − s_h|`` and ``|ŝ_g − s_g|`` are at most this, m.
        timeout: the goal gives up after this long, s.

    Raises ``ValueError`` naming the value: no coordinate given, a number that is not finite, a
    tolerance not positive, a timeout not in (0, :data:`MAX_TIMEOUT`], a target beyond half a turn
    or a metre.
    """

    theta_o: float | None = None
    s_h: float | None = None
    s_g: float | None = None
    angle_tolerance: float = GOAL_TOLERANCE[0]
    length_tolerance: float = GOAL_TOLERANCE[1]
    timeout: float = GOAL_TIMEOUT

    kind: ClassVar[str] = "reach"
    explore: ClassVar[bool] = False

    def __post_init__(self) -> None:
        targets = (("theta_o", np.pi), ("s_h", 1.0), ("s_g", 1.0))
        if all(getattr(self, name) is None for name, _ in targets):
            raise ValueError("a goal needs at least one of theta_o, s_h, s_g")
        for name, largest in targets:
            value = getattr(self, name)
            if value is not None and abs(_number(value, f"goal {name}")) > largest:
                raise ValueError(f"goal {name} must be at most {largest:g} in size, got {value!r}")
        for name, largest in (("angle_tolerance", np.pi), ("length_tolerance", 1.0)):
            value = _number(getattr(self, name), f"goal {name}")
            if not 0.0 < value <= largest:
                raise ValueError(f"goal {name} must be in (0, {largest:g}], got {value!r}")
        if not 0.0 < _number(self.timeout, "goal timeout") <= MAX_TIMEOUT:
            raise ValueError(f"goal timeout must be in (0, {MAX_TIMEOUT:g}] s, got {self.timeout!r}")

    @property
    def targets(self) -> tuple[float | None, float | None, float | None]:
        """``(θ_o, s_h, s_g)`` to reach (rad, m, m; None where free)."""
        return self.theta_o, self.s_h, self.s_g

    @property
    def tolerances(self) -> np.ndarray:
        """Tolerances of ``(θ_o, s_h, s_g)`` (rad, m, m)."""
        return np.array([self.angle_tolerance, self.length_tolerance, self.length_tolerance])

    def errors(self, coordinates: np.ndarray, s_g_origin: float) -> np.ndarray:
        """Target minus ``coordinates`` (``θ_o, s_h, s_g`` absolute, rad and m), 0 where free;
        ``s_g`` measured from ``s_g_origin``."""
        reference = np.array([0.0, 0.0, s_g_origin])
        return np.array(
            [0.0 if target is None else target + ref - value
             for target, ref, value in zip(self.targets, reference, coordinates, strict=True)]
        )

    def reached(self, coordinates: np.ndarray, s_g_origin: float) -> bool:
        """Whether every given coordinate is within its tolerance."""
        return bool(np.all(np.abs(self.errors(coordinates, s_g_origin)) <= self.tolerances))


def reach(
    theta_deg: float | None = None,
    s_h_mm: float | None = None,
    s_g_mm: float | None = None,
    timeout: float = GOAL_TIMEOUT,
) -> Goal:
    """A goal in degrees and millimetres (default tolerances)."""
    return Goal(
        None if theta_deg is None else float(np.deg2rad(theta_deg)),
        None if s_h_mm is None else s_h_mm * 1e-3,
        None if s_g_mm is None else s_g_mm * 1e-3,
        timeout=timeout,
    )


def pivot(degrees: float, timeout: float = DEFAULT_TIMEOUT) -> Step:
    return Step("pivot", np.deg2rad(degrees), DEFAULT_TOLERANCE["pivot"], timeout)


def slide_hand(millimetres: float, timeout: float = DEFAULT_TIMEOUT) -> Step:
    return Step("slide_hand", millimetres * 1e-3, DEFAULT_TOLERANCE["slide_hand"], timeout)


def slide_ground(millimetres: float, timeout: float = DEFAULT_TIMEOUT) -> Step:
    return Step("slide_ground", millimetres * 1e-3, DEFAULT_TOLERANCE["slide_ground"], timeout)


def hold(seconds: float) -> Step:
    return Step("hold", 0.0, 0.0, seconds)


EXPLORE_PIVOT_DEG = 7.2
EXPLORE_PROBE_MM = 3.0
EXPLORE_TIMEOUT = 3.0


def exploration(
    pivot_deg: float = EXPLORE_PIVOT_DEG, probe_mm: float = EXPLORE_PROBE_MM, timeout: float = EXPLORE_TIMEOUT
) -> tuple[Step, ...]:
    """What the estimator needs before the object can be manipulated (paper §VI), as steps.

    Pivots both ways about the ground contact (a third of ``pivot_deg`` and back, then
    ``±pivot_deg``, back to the start): the kinematics (``d``, ``r_o``, ``s_h``) and the gravity
    moment need the object turned. The first pivots are small because the controller pivots about a
    guessed point until the kinematics are known, and its error grows with the angle (on a heavy
    paper triangle with the hand 32 mm off the ground contact, a first naive 7.2° pivot unloaded the
    hand by 3 N and pushed it into sliding). Then a hand-slide probe
    each way (``±probe_mm``, at most ``timeout`` s): the tangential force is pushed past the estimated
    friction bound, moment kept balanced, until the hand slides — which gives ``μ_h`` — or the torque
    limit stops it — which still raises the (conservative) estimate to the ratio reached. The probes
    end by themselves whether or not the hand slid. As they run (:func:`probe_as_run`), the first
    goes the way that leans least on the ground, and the second only if the hand has not slid.
    """
    angle = np.deg2rad(pivot_deg)
    tolerance = DEFAULT_TOLERANCE["pivot"]
    turns = (angle / 3.0, -angle / 3.0, angle, -angle, -angle, angle)
    pivots = tuple(Step("pivot", turn, tolerance, DEFAULT_TIMEOUT, True) for turn in turns)
    probe = probe_mm * 1e-3
    tolerance = DEFAULT_TOLERANCE["slide_hand"]
    probes = tuple(Step("slide_hand", sign * probe, tolerance, timeout, True) for sign in (1, -1))
    return pivots + probes


def safer_probe_way(tilt: float) -> int:
    """The way (``±1`` in ``s_h``) to probe the hand's friction first at the hand angle ``tilt``
    (rad): the one whose friction edge lies nearer the vertical, so that the ground, whose friction
    is not known yet, is the least likely to slide under it.

    At the hand's friction limit a slide towards ``±s_h`` pushes with ``f_n (e_n ∓ μ_h e_t)``
    (:data:`ccopt.contact.hand_rows`, :mod:`ccopt.geometry`), ``|θ ∓ atan μ_h|`` from the vertical:
    towards ``sign θ`` it leans less, for every ``μ_h``. At the paper's start tilt (17°, ``μ_h`` 0.5)
    that is 10° against 44°; on the goals study the probe towards −s_h at 17° slid a random
    triangle's ground (μ_g 0.78) 3.3 mm, which read as the hand's slide."""
    return 1 if tilt >= 0.0 else -1


def probe_as_run(step: Step, previous: Step | None, tilt: float, hand_slid: bool) -> Step | None:
    """An exploration's hand-slide probe (:func:`exploration`) as it runs after ``previous`` (the
    step run before it, None at the start) at the hand angle ``tilt`` (rad, NaN: unknown): the first
    of the pair towards :func:`safer_probe_way` (as given where the tilt is unknown), the second the
    other way, and only while the hand has not slid (``hand_slid``: ``μ_h`` is the same both ways,
    so once measured a second probe only loads the ground); None: skip it. Every other step as
    given."""
    if not (step.explore and step.kind == "slide_hand"):
        return step
    if previous is not None and previous.explore and previous.kind == "slide_hand":
        if hand_slid:
            return None
        way = -1 if previous.delta > 0.0 else 1
    elif math.isfinite(tilt):
        way = safer_probe_way(tilt)
    else:
        return step
    return dataclasses.replace(step, delta=way * abs(step.delta))


@dataclass(frozen=True)
class Schedule:
    """A named sequence of steps."""

    name: str
    steps: tuple[Step | Goal, ...]

    def __post_init__(self) -> None:
        if not self.steps:
            raise ValueError(f"schedule {self.name!r} has no steps")

    @property
    def goals(self) -> tuple[Goal, ...]:
        """The goal steps, in order."""
        return tuple(step for step in self.steps if isinstance(step, Goal))

    @property
    def motions(self) -> tuple[Step, ...]:
        """The motion steps (every step that is not a goal), in order."""
        return tuple(step for step in self.steps if isinstance(step, Step))

    def to_dict(self) -> dict[str, object]:
        """The file form (degrees, millimetres), e.g. for ``meta.json``."""
        return {"name": self.name, "steps": [_step_to_dict(step) for step in self.steps]}


def _paper() -> Schedule:
    """The paper's experiment as goals (paper §VI, Fig. 9): learn, then visit both directions of every
    coordinate in the paper's increments from the start (θ_o 17.2°, the hand over the ground contact),
    some goals a single motion away, others needing the planner to tilt the object first (a ground
    slide needs a large tilt, each way its own)."""
    return Schedule(
        "paper",
        (
            *exploration(),
            reach(theta_deg=24.4),
            reach(theta_deg=31.6),
            reach(s_g_mm=10.0),
            reach(s_h_mm=10.0),
            reach(theta_deg=17.2),
            reach(theta_deg=10.0),
            reach(s_h_mm=0.0),
            reach(s_g_mm=0.0),
            reach(theta_deg=2.8),
            reach(s_h_mm=-10.0),
            reach(s_g_mm=-10.0),
            reach(theta_deg=17.2, s_h_mm=0.0),
            reach(s_g_mm=0.0),
            reach(theta_deg=17.2, s_h_mm=0.0, s_g_mm=0.0),
        ),
    )


def _paper_script() -> Schedule:
    """The paper's sequences as a fixed script of motions (paper §VI), chosen by a person who could
    see the object: on an unknown object many of its steps are impossible."""
    angle = np.rad2deg(PIVOT_STEP)
    slide = SLIDE_STEP * 1e3
    exploration = [hold(0.5), slide_hand(slide), slide_hand(-slide), pivot(angle), pivot(-angle)]
    manipulation = [
        pivot(angle),
        pivot(angle),
        slide_hand(slide),
        slide_ground(slide),
        pivot(-angle),
        slide_hand(-slide),
        pivot(-angle),
        pivot(-angle),
        slide_ground(slide),
        slide_hand(slide),
        pivot(angle),
        slide_ground(-slide),
        slide_hand(-slide),
        hold(0.5),
    ]
    return Schedule("paper-script", tuple(exploration + manipulation))


def _smoke() -> Schedule:
    """Pivots both ways about the ground contact, with holds: short, and feasible for every paper
    object (hand slides from over the ground contact are not: see the README)."""
    angle = np.rad2deg(PIVOT_STEP)
    return Schedule("smoke", (hold(0.3), pivot(angle), pivot(-angle), pivot(-angle), pivot(angle), hold(0.3)))


BUILTIN = {"paper": _paper, "paper-script": _paper_script, "smoke": _smoke}


def load_schedule(name_or_path: str | Path) -> Schedule:
    """A built-in schedule by name, or one read from a ``.json``/``.yaml``/``.yml`` file.

    Raises ``ValueError`` naming the problem: unknown name, missing or unreadable file, malformed
    content, an unknown key, a bad value.
    """
    text = str(name_or_path)
    if text in BUILTIN:
        return BUILTIN[text]()
    path = Path(text)
    if path.suffix.lower() not in (".json", ".yaml", ".yml"):
        raise ValueError(
            f"unknown schedule {text!r}: not a built-in ({', '.join(BUILTIN)}) nor a .json/.yaml file"
        )
    try:
        raw = path.read_text(encoding="utf-8")
    except OSError as error:
        raise ValueError(f"cannot read schedule file {text!r}: {error.strerror}") from None
    except UnicodeDecodeError:
        raise ValueError(f"schedule file {text!r} is not a text file (UTF-8)") from None
    try:
        content = json.loads(raw) if path.suffix.lower() == ".json" else yaml.safe_load(raw)
    except (ValueError, RecursionError, yaml.YAMLError) as error:  # ValueError: a number of 5,000 digits
        reason = parse_reason(error)
        raise ValueError(f"schedule file {text!r} is malformed: {reason}") from None
    try:
        return schedule_from_dict(content, default_name=path.stem)
    except ValueError as error:
        raise ValueError(f"schedule file {text!r}: {error}") from None


def schedule_from_dict(content: object, default_name: str = "custom") -> Schedule:
    """A schedule from its file form (degrees, millimetres, seconds)."""
    if not isinstance(content, dict) or not isinstance(content.get("steps"), list):
        raise ValueError("a schedule must be a mapping with a list under 'steps'")
    unknown = set(content) - {"name", "steps"}
    if unknown:
        raise ValueError(f"unknown schedule key(s): {_keys(unknown)}")
    entries = enumerate(content["steps"])
    steps = tuple(step for index, entry in entries for step in _steps_from_dict(index, entry))
    return Schedule(str(content.get("name", default_name)), steps)


_FIELDS = {
    "pivot": ("delta_deg", "tolerance_deg", np.deg2rad),
    "slide_hand": ("delta_mm", "tolerance_mm", lambda v: v * 1e-3),
    "slide_ground": ("delta_mm", "tolerance_mm", lambda v: v * 1e-3),
}


def _steps_from_dict(index: int, entry: object) -> tuple[Step, ...]:
    where = f"step {index + 1}"
    if not isinstance(entry, dict) or "motion" not in entry:
        raise ValueError(f"{where}: expected a mapping with a 'motion' key, got {short(entry)}")
    kind = entry["motion"]
    if kind == "explore":
        _only(entry, {"motion", "pivot_deg", "probe_mm", "timeout_s"}, where)
        options = {
            name: _number(entry[key], f"{where} {key}")
            for name, key in (("pivot_deg", "pivot_deg"), ("probe_mm", "probe_mm"), ("timeout", "timeout_s"))
            if key in entry
        }
        try:
            return exploration(**options)
        except ValueError as error:
            raise ValueError(f"{where}: {error}") from None
    if kind == Goal.kind:
        return (_goal_from_dict(where, entry),)
    if kind not in KINDS:
        choices = ", ".join((*KINDS, "explore", Goal.kind))
        raise ValueError(f"{where}: unknown motion {short(kind)}; expected one of: {choices}")
    explore = entry.get("explore", False)
    if not isinstance(explore, bool):
        raise ValueError(f"{where}: explore must be true or false, got {short(explore)}")
    step = _step_from_dict(where, kind, {key: value for key, value in entry.items() if key != "explore"})
    return (dataclasses.replace(step, explore=explore),)


def _step_from_dict(where: str, kind: str, entry: dict) -> Step:
    try:
        if kind == "hold":
            _only(entry, {"motion", "duration_s"}, where)
            return hold(_number(entry.get("duration_s", 1.0), f"{where} duration_s"))
        delta_key, tolerance_key, to_si = _FIELDS[kind]
        _only(entry, {"motion", delta_key, tolerance_key, "timeout_s"}, where)
        if delta_key not in entry:
            raise ValueError(f"{where}: a {kind} step needs {delta_key!r}")
        delta = float(to_si(_number(entry[delta_key], f"{where} {delta_key}")))
        tolerance = entry.get(tolerance_key)
        tolerance_si = (
            DEFAULT_TOLERANCE[kind]
            if tolerance is None
            else float(to_si(_number(tolerance, f"{where} {tolerance_key}")))
        )
        timeout = _number(entry.get("timeout_s", DEFAULT_TIMEOUT), f"{where} timeout_s")
        return Step(kind, delta, tolerance_si, timeout)
    except ValueError as error:
        message = str(error)
        raise ValueError(message if message.startswith(where) else f"{where}: {message}") from None


_GOAL_KEYS = ("theta_deg", "s_h_mm", "s_g_mm", "timeout_s", "tolerance_deg", "tolerance_mm")


def _goal_from_dict(where: str, entry: dict) -> Goal:
    _only(entry, {"motion", *_GOAL_KEYS}, where)

    def value(key: str, scale: float, default: float | None = None) -> float | None:
        return default if key not in entry else _number(entry[key], f"{where} {key}") * scale

    try:
        return Goal(
            value("theta_deg", math.pi / 180.0),
            value("s_h_mm", 1e-3),
            value("s_g_mm", 1e-3),
            value("tolerance_deg", math.pi / 180.0, GOAL_TOLERANCE[0]),
            value("tolerance_mm", 1e-3, GOAL_TOLERANCE[1]),
            value("timeout_s", 1.0, GOAL_TIMEOUT),
        )
    except ValueError as error:
        message = str(error)
        raise ValueError(message if message.startswith(where) else f"{where}: {message}") from None


def _only(entry: dict, allowed: set[str], where: str) -> None:
    unknown = set(entry) - allowed
    if unknown:
        raise ValueError(f"{where}: unknown key(s) {_keys(unknown)}")


def _keys(keys: set[object]) -> str:
    """Keys of any types (a YAML mapping may mix them), sorted, for a message."""
    return ", ".join(sorted(str(key) for key in keys))


def _number(value: object, name: str) -> float:
    """``value`` as a finite float; ``ValueError`` naming ``name`` and the value otherwise."""
    if isinstance(value, bool) or not isinstance(value, int | float):
        raise ValueError(f"{name} must be a finite number, got {short(value)}")
    try:
        number = float(value)
    except OverflowError:
        raise ValueError(f"{name} must be a finite number, got an integer beyond 1.8e308") from None
    if not math.isfinite(number):
        raise ValueError(f"{name} must be a finite number, got {short(value)}")
    return number


def _step_to_dict(step: Step | Goal) -> dict[str, object]:
    if isinstance(step, Goal):
        return _goal_to_dict(step)
    return {**_motion_to_dict(step), **({"explore": True} if step.explore else {})}


def _goal_to_dict(goal: Goal) -> dict[str, object]:
    theta, s_h, s_g = goal.targets
    given = {
        "theta_deg": None if theta is None else float(np.rad2deg(theta)),
        "s_h_mm": None if s_h is None else s_h * 1e3,
        "s_g_mm": None if s_g is None else s_g * 1e3,
    }
    return {
        "motion": Goal.kind,
        **{key: value for key, value in given.items() if value is not None},
        "tolerance_deg": float(np.rad2deg(goal.angle_tolerance)),
        "tolerance_mm": goal.length_tolerance * 1e3,
        "timeout_s": goal.timeout,
    }


def _motion_to_dict(step: Step) -> dict[str, object]:
    if step.kind == "hold":
        return {"motion": "hold", "duration_s": step.timeout}
    delta_key, tolerance_key, to_si = _FIELDS[step.kind]
    per_unit = float(np.rad2deg(1.0)) if step.kind == "pivot" else 1e3
    return {
        "motion": step.kind,
        delta_key: _file_value(step.delta, per_unit, to_si),
        tolerance_key: _file_value(step.tolerance, per_unit, to_si),
        "timeout_s": step.timeout,
    }


def _file_value(si: float, per_unit: float, to_si: Callable[[float], float]) -> float:
    """``si`` in the file's unit (``per_unit`` of them per SI unit): of the floats within a few ulps of
    the product, the one that ``to_si`` reads back as exactly ``si`` if any (a run's ``meta.json``
    then repeats the run to the last bit), else the product."""
    value = si * per_unit
    for direction in (np.inf, -np.inf):
        candidate = value
        for _ in range(4):
            if float(to_si(candidate)) == si:
                return float(candidate)
            candidate = float(np.nextafter(candidate, direction))
    return float(value)
