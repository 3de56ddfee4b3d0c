"""A run's settings as one mapping: what ``ccopt run --config FILE`` reads and ``meta.json`` records.

The same form serves a hand-written YAML/JSON file and a run's own ``meta.json``, so that
``ccopt run --config RUN_DIR/meta.json`` repeats that run (same seed, same samples). SI units (m, rad, kg,
N, s; rates in Hz and 1/s) except in ``schedule``, whose file form says its units in its keys
(``delta_deg``, ``delta_mm``, :mod:`ccopt.schedule`)::

    object: paper-triangle   # a library name, or {name, vertices (m), mass, added_mass, mu_hand, mu_ground}
    schedule: paper          # a built-in name, a .yaml/.json file, or the file form itself
    seed: 0
    params:
      plant: planar          # or panda
      estimator_hz: 100.0
      controller_hz: 30.0
      centre_hand: true      # start with the hand over the ground contact (start.s_h ignored)
      max_sim_s: null        # a time limit (s of simulated time), null: by the schedule
      hand: {half_length: 0.03, stiffness: [2000, 2000, 60], force_limits: [3, 25]}  # hand.Hand
      start: {hand_face: 0, theta_o: 0.3, s_h: 0.0, normal_force: 10.0}  # plant.base.StartConfig
      sensors: {sigma_force: 0.3, sigma_angle: 0.0017, faults: ["dropout:0.3@2"]}  # SensorParams
      controller: {convergence_rate: 10.7, force_rate: 6.7, normal_force: 10.0}  # ControllerParams
      perturbations: [{time: 1.0, force: [5.0, 0.0], duration: 0.15}]  # pushes on the object

Every key is optional (the defaults of :class:`~ccopt.closed_loop.LoopParams` and its parts apply).
The keys a run adds to ``meta.json`` (:data:`RECORD_KEYS`) are ignored. Every bad value is reported,
one line each naming it (:class:`ConfigError`); nothing is run with a value that was not checked.
"""

from __future__ import annotations

import dataclasses
import json
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING

import yaml

from ccopt import objects, validation
from ccopt.cliutil import MAX_SEED
from ccopt.objects import PlanarObject
from ccopt.plant.base import MIN_RATE, PlantParams
from ccopt.schedule import BUILTIN, Schedule, load_schedule, schedule_from_dict

if TYPE_CHECKING:
    from ccopt.closed_loop import LoopParams

TOP_KEYS = ("object", "schedule", "seed", "params")
PARAMS_KEYS = (
    "plant",
    "estimator_hz",
    "controller_hz",
    "centre_hand",
    "max_sim_s",
    "hand",
    "start",
    "sensors",
    "controller",
    "perturbations",
)
RECORD_KEYS = frozenset(
    {
        "feasibility", "steps", "goals", "status", "message", "samples", "versions", "run_id", "units",
        "record_units",
    }
)
"""Keys of ``meta.json`` that a run writes about itself: not settings, ignored when read back."""
OBJECT_KEYS = ("name", "vertices", "mass", "added_mass", "mu_hand", "mu_ground")
POLYGON_MASS = 0.3
"""Mass (kg) of an object given by its vertices without a mass."""
UNITS = "SI (m, rad, kg, N, s; rates in Hz) unless a key names its unit (_deg, _mm, _s, _n)"
"""What ``meta.json``, ``summary.json`` and the studies' files say of their units."""


class ConfigError(ValueError):
    """Settings that cannot be run: one line per bad value (``lines``), each naming it."""

    def __init__(self, lines: Sequence[str]) -> None:
        super().__init__("\n".join(lines))
        self.lines = tuple(lines)


@dataclass(frozen=True)
class RunConfig:
    """Everything a run is made of: the object (never shown to the estimator or the controller),
    the schedule, the loop's parameters and the seed of the sensor noise."""

    obj: PlanarObject
    schedule: Schedule
    params: LoopParams
    seed: int


def read_file(path: str | Path) -> dict[str, object]:
    """The mapping in a ``.yaml``/``.yml``/``.json`` settings file (a run's ``meta.json`` too);
    ``ValueError`` in one line naming the file otherwise."""
    text = str(path)
    try:
        raw = Path(text).read_text(encoding="utf-8")
    except OSError as error:
        raise ValueError(f"cannot read settings file {text!r}: {error.strerror}") from None
    except UnicodeDecodeError:
        raise ValueError(f"settings file {text!r} is not a text file (UTF-8)") from None
    try:
        content = json.loads(raw) if text.lower().endswith(".json") else yaml.safe_load(raw)
    except (ValueError, RecursionError, yaml.YAMLError) as error:
        reason = validation.parse_reason(error)
        raise ValueError(f"settings file {text!r} is malformed: {reason}") from None
    if not isinstance(content, dict):
        raise ValueError(f"settings file {text!r} must hold a mapping, got {type(content).__name__}")
    return content


def merge(base: Mapping[str, object], override: Mapping[str, object]) -> dict[str, object]:
    """``base`` with ``override``'s keys put in, mappings merged key by key (recursively)."""
    merged = dict(base)
    for key, value in override.items():
        if isinstance(value, Mapping) and isinstance(merged.get(key), Mapping):
            merged[key] = merge(merged[key], value)
        else:
            merged[key] = value
    return merged


Labels = Mapping[tuple[str, ...], str]
"""What to call a setting in a message, by its key path (e.g. a command-line flag); else its path."""


class _Checker:
    """Collects the bad values of a settings mapping, one line each."""

    def __init__(self, labels: Labels | None) -> None:
        self.labels = labels or {}
        self.errors: list[str] = []

    def name(self, path: tuple[str, ...]) -> str:
        return self.labels.get(path) or ".".join(path)

    def bad(self, path: tuple[str, ...], message: str) -> None:
        self.errors.append(f"{self.name(path)}: {message}")

    def mapping(self, path: tuple[str, ...], value: object, allowed: Sequence[str]) -> dict[str, object]:
        """``value`` as a mapping whose unknown keys are each reported ({} if it is not one)."""
        if value is None:
            return {}
        if not isinstance(value, Mapping):
            self.bad(path, f"must be a mapping, got {type(value).__name__} {value!r}")
            return {}
        known = {}
        for key, item in value.items():
            if key in allowed:
                known[key] = item
            elif not (path == () and key in RECORD_KEYS):
                self.bad((*path, str(key)), f"unknown key; expected one of: {', '.join(allowed)}")
        return known

    def call(self, path: tuple[str, ...], build: Callable[[], object]) -> object | None:
        """``build()``, or None with its ``ValueError``/``TypeError`` reported under ``path``."""
        try:
            return build()
        except (ValueError, TypeError) as error:
            self.bad(path, str(error).splitlines()[0])
            return None

    def fields(
        self,
        path: tuple[str, ...],
        base: object,
        value: object,
        convert: Mapping[str, Callable] | None = None,
    ) -> object | None:
        """The dataclass ``base`` with the fields of the mapping ``value`` put in: each field checked on
        its own first (a number where the default is one, as many numbers as the default's tuple, the
        dataclass's own checks), so that every bad field gets its line."""
        names = [f.name for f in dataclasses.fields(base)]
        given = self.mapping(path, value, names)
        good = {}
        for key, item in given.items():
            where = (*path, key)
            default = getattr(base, key)
            checked = self.call(
                where, lambda key=key, item=item, default=default: _field(key, item, default, convert)
            )
            if checked is not None and self.call(
                where, lambda key=key, checked=checked: dataclasses.replace(base, **{key: checked})
            ):
                good[key] = checked
        if len(good) < len(given):
            return None
        return self.call(path, lambda: dataclasses.replace(base, **good))


def _field(
    name: str, value: object, default: object, convert: Mapping[str, Callable] | None = None
) -> object:
    """``value`` checked against the type of its ``default``: a real number, a bool, an integer or a
    tuple of as many real numbers; ``convert[name]`` turns it instead where given."""
    if convert and name in convert:
        return convert[name](value)
    if isinstance(default, bool):
        if not isinstance(value, bool):
            raise TypeError(f"must be true or false, got {validation.short(value)}")
        return value
    if isinstance(default, int):
        if isinstance(value, bool) or not isinstance(value, int):
            raise TypeError(f"must be an integer, got {validation.short(value)}")
        return value
    if isinstance(default, float):
        return validation.real(name, value)
    if isinstance(default, tuple) and all(isinstance(v, float) for v in default):
        return validation.reals(name, value, len(default))
    return value


def _faults(value: object) -> tuple:
    """Sensor faults as ``KIND[:VALUE][@START_S]`` strings (:func:`ccopt.plant.sensors.parse_fault`)."""
    from ccopt.plant.sensors import parse_fault

    if isinstance(value, str) or not isinstance(value, Sequence):
        raise TypeError(f"faults must be a list of 'KIND[:VALUE][@START_S]', got {value!r}")
    return tuple(parse_fault(item) if isinstance(item, str) else _bad_fault(item) for item in value)


def _bad_fault(item: object) -> None:
    raise TypeError(f"a fault must be a string 'KIND[:VALUE][@START_S]', got {item!r}")


def build(settings: Mapping[str, object], labels: Labels | None = None) -> RunConfig:
    """A :class:`RunConfig` from a settings mapping (module docstring); :class:`ConfigError` with one
    line per bad value, each named by ``labels`` or its key path. The hand must fit on the start face."""
    from ccopt.closed_loop import LoopParams, Perturbation, Supervision, start_config

    check = _Checker(labels)
    top = check.mapping((), settings, TOP_KEYS)
    obj = _object(check, top.get("object", "paper-triangle"))
    schedule = check.call(("schedule",), lambda: _schedule(top.get("schedule", "paper")))
    seed = check.call(("seed",), lambda: _seed(top.get("seed", 0)))
    p = check.mapping(("params",), top.get("params"), PARAMS_KEYS)
    parts: dict[str, object] = {}
    if "plant" in p:
        parts["plant"] = check.call(("params", "plant"), lambda: _plant(p["plant"]))
    top_rate = 1.0 / PlantParams().timestep
    for name in ("estimator_hz", "controller_hz"):
        if name in p:
            parts[name] = check.call(("params", name), lambda name=name: _rate(p[name], top_rate))
    if "centre_hand" in p:
        parts["centre_hand"] = check.call(
            ("params", "centre_hand"), lambda: _field("centre_hand", p["centre_hand"], True)
        )
    defaults = LoopParams()
    kinds = (
        ("hand", "hand", {}),
        ("start", "start", {}),
        ("sensors", "sensor_params", {"faults": _faults}),
        ("controller", "controller_params", {}),
    )
    for key, field, convert in kinds:
        if key in p:
            parts[field] = check.fields(("params", key), getattr(defaults, field), p[key], convert)
    if p.get("max_sim_s") is not None:
        parts["supervision"] = check.call(
            ("params", "max_sim_s"), lambda: Supervision(max_time=p["max_sim_s"])
        )
    if "perturbations" in p:
        parts["perturbations"] = check.call(
            ("params", "perturbations"), lambda: _pushes(p["perturbations"], Perturbation)
        )
    if check.errors or any(value is None for value in (obj, schedule, seed, *parts.values())):
        raise ConfigError(check.errors)
    params = check.call(("params",), lambda: LoopParams(**parts))
    if params is not None:
        check.call(("params", "start"), lambda: start_config(obj, params))  # the hand must fit on the face
    if check.errors:
        raise ConfigError(check.errors)
    return RunConfig(obj, schedule, params, seed)


def _object(check: _Checker, value: object) -> PlanarObject | None:
    """The object of a library name or a mapping (:data:`OBJECT_KEYS`)."""
    spec = {"name": value} if isinstance(value, str) else check.mapping(("object",), value, OBJECT_KEYS)
    if not spec:
        if not isinstance(value, str):
            check.bad(("object",), "needs a name or vertices")
        return None
    before = len(check.errors)
    numbers = {}
    for key in ("mass", "added_mass", "mu_hand", "mu_ground"):
        if spec.get(key) is not None:
            numbers[key] = check.call(("object", key), lambda key=key: _object_number(key, spec[key]))
    if len(check.errors) > before:
        return None
    friction = {key: numbers[key] for key in ("mu_hand", "mu_ground") if key in numbers}
    added = numbers.get("added_mass", 0.0)
    if "vertices" in spec:
        mass = numbers.get("mass", POLYGON_MASS) + added
        name = str(spec.get("name", "polygon"))
        return check.call(
            ("object",), lambda: objects.from_vertices(spec["vertices"], mass, name=name, **friction)
        )
    name = spec.get("name", "paper-triangle")
    return check.call(
        ("object",), lambda: objects.make_object(name, mass=numbers.get("mass"), added_mass=added, **friction)
    )


def _object_number(key: str, value: object) -> float:
    """A mass (kg, > 0), an added mass (kg, ≥ 0) or a friction coefficient (> 0: a run needs friction at
    both contacts, to push the object sideways and to pivot it on the ground)."""
    number = validation.real(key, value)
    if key == "added_mass" and number < 0.0:
        raise ValueError(f"must be a non-negative number of kg, got {value!r}")
    if key != "added_mass" and number <= 0.0:
        what = (
            "a positive number of kg" if key == "mass" else "positive (a run needs friction at both contacts)"
        )
        raise ValueError(f"must be {what}, got {value!r}")
    return number


def _schedule(value: object) -> Schedule:
    if isinstance(value, Mapping):
        name = str(value.get("name", "custom"))
        if name in BUILTIN and BUILTIN[name]().to_dict() == dict(value):
            return BUILTIN[name]()
        return schedule_from_dict(dict(value))
    if isinstance(value, str):
        return load_schedule(value)
    raise TypeError(f"must be a built-in name, a file or a mapping with 'steps', got {value!r}")


def _seed(value: object) -> int:
    if isinstance(value, bool) or not isinstance(value, int) or not 0 <= value < MAX_SEED:
        raise ValueError(f"must be an integer in [0, 2**64), got {validation.short(value)}")
    return value


def _plant(value: object) -> str:
    if value not in ("planar", "panda"):
        raise ValueError(f"must be 'planar' or 'panda', got {validation.short(value)}")
    return value


def _rate(value: object, top: float) -> float:
    rate = validation.real("rate", value)
    if not MIN_RATE <= rate <= top:
        raise ValueError(f"must be in [{MIN_RATE:g}, {top:g}] Hz (the plant's rate), got {value!r}")
    return rate


def _pushes(value: object, kind: type) -> tuple:
    """Pushes on the object: ``time`` (s, ≥ 0), ``force`` (two N, world), ``duration`` (s, > 0)."""
    if isinstance(value, str) or not isinstance(value, Sequence):
        raise TypeError(f"must be a list of {{time, force, duration}}, got {value!r}")
    pushes = []
    for k, item in enumerate(value):
        if not isinstance(item, Mapping) or set(item) != {"time", "force", "duration"}:
            raise ValueError(f"push {k + 1} must have exactly time, force and duration, got {item!r}")
        time = validation.real(f"push {k + 1} time", item["time"])
        if time < 0.0:
            raise ValueError(f"push {k + 1} time must be at least 0 s, got {time!r}")
        force = validation.reals(f"push {k + 1} force", item["force"], 2)
        pushes.append(kind(time, force, validation.positive(f"push {k + 1} duration", item["duration"])))
    return tuple(sorted(pushes, key=lambda push: push.time))


def settings_of(obj: PlanarObject, schedule: Schedule, params: LoopParams, seed: int) -> dict[str, object]:
    """The settings mapping of a run (:func:`build` of it gives the same run): what ``meta.json``
    records. ``start`` is where the run starts (``s_h`` over the ground contact with ``centre_hand``)."""
    from ccopt.closed_loop import start_config

    sensors = dataclasses.asdict(params.sensor_params)
    sensors["faults"] = [str(fault) for fault in params.sensor_params.faults]
    return {
        "object": object_settings(obj),
        "schedule": schedule.to_dict(),
        "seed": seed,
        "params": {
            "plant": params.plant,
            "estimator_hz": params.estimator_hz,
            "controller_hz": params.controller_hz,
            "centre_hand": params.centre_hand,
            "max_sim_s": params.supervision.max_time,
            "hand": dataclasses.asdict(params.hand),
            "start": dataclasses.asdict(start_config(obj, params)),
            "sensors": sensors,
            "controller": dataclasses.asdict(params.controller_params),
            "perturbations": [dataclasses.asdict(push) for push in params.perturbations],
        },
    }


def object_settings(obj: PlanarObject) -> dict[str, object]:
    """The object as settings and ``meta.json`` hold it (what :mod:`ccopt.plots` rebuilds it from). SI."""
    return {
        "name": obj.name,
        "vertices": obj.vertices.tolist(),
        "mass": obj.mass,
        "mu_hand": obj.mu_hand,
        "mu_ground": obj.mu_ground,
    }
