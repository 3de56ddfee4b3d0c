"""The robot's turn rate: the impedance target turns the hand no faster than the plant's hand follows
(:attr:`ccopt.plant.base.Plant.hand_turn_rate`), and on the Panda that keeps a pivot that lands the
object on a face from rolling the hand past what the metrics count as a slip."""

from __future__ import annotations

import dataclasses
import math

import numpy as np
import pytest

from ccopt import closed_loop, metrics
from ccopt.control.controller import ControllerParams
from ccopt.objects import make_object
from ccopt.plant.mujoco_panda import PandaPlant
from ccopt.plant.mujoco_planar import PlanarPlant
from ccopt.schedule import load_schedule


def _fastest_turn(plant: str) -> float:
    """The largest angular speed (rad/s) of the impedance target between record samples of the
    ``smoke`` schedule (pivots both ways) on ``plant``."""
    params = closed_loop.LoopParams(plant=plant)
    result = closed_loop.run(make_object("paper-triangle"), load_schedule("smoke"), params, seed=0)
    assert result.status == "completed", result.message
    time, target = np.asarray(result.samples["time"]), np.asarray(result.samples["target"])[:, 2]
    return float(np.max(np.abs(np.diff(target)) / np.diff(time)))


@pytest.mark.parametrize(
    ("plant", "rate"), [("planar", PlanarPlant.hand_turn_rate), ("panda", PandaPlant.hand_turn_rate)]
)
def test_a_pivot_turns_the_target_at_the_slower_of_the_controller_and_the_plant(plant, rate) -> None:
    """The pivots go at the limit (within 10 %) and never past it: the controller's own 30°/s on the
    planar plant, whose hand follows it, and the Panda's slower rate."""
    limit = min(ControllerParams().max_speed[2], rate)
    fastest = _fastest_turn(plant)
    assert 0.9 * limit <= fastest <= limit * (1.0 + 1e-9), math.degrees(fastest)


@pytest.mark.slow
def test_the_panda_square_landing_on_its_face_rolls_the_hand_less_than_a_slip() -> None:
    """The paper square's ``paper`` run on the Panda (seed 0): a goal pivot down towards θ_o = 0
    lands it on its face, which the estimate cannot foresee, and ends ``rolled``. By the truth, no
    motion turns the hand against the object by more than the metrics' slip angle (2°) nor slips a
    contact it keeps (:func:`ccopt.metrics.unintended_slips`): at the controller's 30°/s the landing
    pivot turned the hand 2.5° and slid it 2.1 mm, and the run had three unintended slips."""
    params = closed_loop.LoopParams(plant="panda")
    result = closed_loop.run(make_object("paper-square"), load_schedule("paper"), params, seed=0)
    assert result.status == "completed", result.message
    data, steps = result.samples, result.steps
    tilt = np.asarray(data["true_coordinates"])[:, 0]
    landings = [
        step
        for step in steps
        if step.goal is not None and step.kind == "pivot" and step.status == "rolled"
        and abs(tilt[metrics.sample_at(data, step.end_time)]) < math.radians(1.0)
    ]
    assert landings  # the case this test is about
    assert metrics.unintended_slips(data, [dataclasses.asdict(step) for step in steps]) == []
