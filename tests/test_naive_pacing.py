"""Before the kinematics are known a pivot turns about the paper's naive lever, and is paced so that
the force terms keep up (:attr:`ccopt.control.controller.ControllerParams.naive_force_lag`); judged
by the simulator's truth on the exploration of a goals-study triangle (seed 1, trial 0: 0.45 kg,
μ_h 0.65, μ_g 0.73) whose ground contact lies 22 mm along the face and 55 mm below the hand, 33 mm
from the naive guess. At the full 30°/s its first 7.2° pivot built 8 N of tangential force against
12 N of normal force, and the hand slid 4.3 mm."""

from __future__ import annotations

import dataclasses
import math

import numpy as np
import pytest

from ccopt import metrics
from ccopt.closed_loop import LoopParams
from ccopt.control.controller import Controller, ControllerParams
from ccopt.experiment import run_experiment
from ccopt.objects import from_vertices
from ccopt.schedule import Schedule, exploration

TRIANGLE = dict(
    vertices=np.array(
        [
            [-0.0478652657461541, 0.010308748194149524],
            [0.02533972766962056, -0.013837873271195794],
            [0.022525538076533527, 0.003529125077046274],
        ]
    ),
    mass=0.4508482868236573,
    mu_hand=0.6457970223233103,
    mu_ground=0.7265248355418163,
)
SEED = 1641411168
PIVOTS = Schedule("pivots", tuple(step for step in exploration() if step.kind == "pivot"))


def _hand_slips(lag: float) -> list[dict[str, object]]:
    params = LoopParams(plant="planar", controller_params=ControllerParams(naive_force_lag=lag))
    done = run_experiment(from_vertices(**TRIANGLE), PIVOTS, params, seed=SEED)
    steps = [dataclasses.asdict(step) for step in done.result.steps]
    return [e for e in metrics.unintended_slips(done.result.samples, steps) if e["contact"] != "ground_slide"]


@pytest.mark.parametrize(("lag", "slips"), [(2.0, False), (1e6, True)], ids=["paced", "full speed"])
def test_the_exploration_pivots_keep_the_hand_stuck_and_flush_only_when_paced(lag, slips) -> None:
    """By the truth: paced, no exploration pivot slides or turns the hand on the object; at the full
    speed (the pace out of reach) one does."""
    assert bool(_hand_slips(lag)) is slips


def test_the_pace_is_the_force_lag_over_the_strain_per_radian() -> None:
    """Closed form: ``ω = lag · force_rate / (k · d_guess)``: 2 N, 6.76 /s, 2000 N/m and 8 cm give
    4.8°/s, whatever the control rate."""
    speeds = [Controller(period=period).naive_turn_speed for period in (0.001, 0.01, 0.033)]
    p = ControllerParams()
    expected = p.naive_force_lag * p.force_rate / (2000.0 * p.d_guess)
    assert speeds == pytest.approx([expected] * 3) and math.degrees(expected) == pytest.approx(4.84, abs=0.01)
