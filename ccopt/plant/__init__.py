"""Simulated plants (MuJoCo), their sensors and their ground truth.

Exports load on first use, so that a light submodule (e.g. :mod:`ccopt.plant.base` for the CLI's
checks) does not load MuJoCo.
"""

from __future__ import annotations

import importlib

_EXPORTS = {
    "Measurement": "ccopt.plant.sensors",
    "PlanarPlant": "ccopt.plant.mujoco_planar",
    "Plant": "ccopt.plant.base",
    "PlantParams": "ccopt.plant.base",
    "SensorParams": "ccopt.plant.sensors",
    "Sensors": "ccopt.plant.sensors",
    "StartConfig": "ccopt.plant.base",
    "Truth": "ccopt.plant.truth",
}
__all__ = sorted(_EXPORTS)


def __getattr__(name: str) -> object:
    module = _EXPORTS.get(name)
    if module is None:
        raise AttributeError(f"module 'ccopt.plant' has no attribute {name!r}")
    value = getattr(importlib.import_module(module), name)
    globals()[name] = value
    return value


def __dir__() -> list[str]:
    return sorted(__all__)
