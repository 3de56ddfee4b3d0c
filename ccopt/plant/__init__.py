"""Simulated plants (MuJoCo), their sensors and their ground truth."""

from ccopt.plant.base import Plant, PlantParams, StartConfig
from ccopt.plant.truth import Truth

__all__ = ["Plant", "PlantParams", "StartConfig", "Truth"]
