"""Simulated plants (MuJoCo), their sensors and their ground truth."""

from ccopt.plant.base import Plant, PlantParams, StartConfig
from ccopt.plant.mujoco_planar import PlanarPlant
from ccopt.plant.sensors import Measurement, SensorParams, Sensors
from ccopt.plant.truth import Truth

__all__ = [
    "Measurement",
    "PlanarPlant",
    "Plant",
    "PlantParams",
    "SensorParams",
    "Sensors",
    "StartConfig",
    "Truth",
]
