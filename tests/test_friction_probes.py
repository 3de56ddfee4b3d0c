"""The exploration's hand-slide probes end by themselves: where the torque limit stops one before
the hand slides, it ends `rolled` instead of pushing the hand over the face's end. Judged by the
simulator's truth on a small heavy random triangle (the robustness study's trial 20: 7.2 cm, 0.89 kg,
μ_h 0.47) whose +3 mm probe needs its centre of pressure past the hand's end: before the probe had
the `rolled` ending it pushed for its whole 3 s timeout and rolled the hand 2.3° against the object.
"""

from __future__ import annotations

import dataclasses
import math

import numpy as np
import pytest

from ccopt import closed_loop
from ccopt.closed_loop import LoopParams
from studies import robustness, runner

SMALL_HEAVY_TRIANGLE = robustness.RandomObject(
    20, 2613302452, "triangle", 0.07189618215752297, None, 0.8927966767407076,
    0.46954014909519515, 0.5475116266460018, "tour", "planar",
)  # fmt: skip


@pytest.fixture(scope="module")
def result() -> closed_loop.RunResult:
    """The tour's exploration (a hold, six pivots and the two probes), nothing after it."""
    spec = SMALL_HEAVY_TRIANGLE
    obj = robustness.build_object(spec)
    schedule, params = runner.trial_run(obj, spec.schedule, LoopParams(plant=spec.plant))
    probes = [k for k, step in enumerate(schedule.steps) if step.explore and step.kind == "slide_hand"]
    exploration = dataclasses.replace(schedule, steps=schedule.steps[: probes[-1] + 1])
    return closed_loop.run(obj, exploration, params, seed=spec.seed)


def probes(result: closed_loop.RunResult) -> list[closed_loop.StepResult]:
    return [step for step in result.steps if step.explore and step.kind == "slide_hand"]


def window(result: closed_loop.RunResult, step: closed_loop.StepResult) -> slice:
    time = np.asarray(result.samples["time"])
    return slice(int(np.searchsorted(time, step.start_time)), int(np.searchsorted(time, step.end_time)) + 1)


def test_a_probe_the_torque_limit_stops_ends_rolled_with_the_hand_kept_on_the_face(result):
    """The +3 mm probe ends `rolled` within a second, and the object never turned a degree against
    the hand (truth: ``θ_o − θ_h``, the contact's compliant tilt included)."""
    first = probes(result)[0]
    assert first.delta > 0.0 and first.status == "rolled", first
    assert first.end_time - first.start_time < 1.0
    span = window(result, first)
    samples = result.samples
    turn = np.asarray(samples["true_coordinates"])[span, 0] - np.asarray(samples["hand_pose"])[span, 2]
    assert np.max(np.abs(turn)) < math.radians(1.0), math.degrees(np.max(np.abs(turn)))


def test_the_probe_the_other_way_still_slides_the_hand(result):
    """The −3 mm probe, which the object allows, still slides the hand (truth: ``s_h`` at least 1.5 mm
    the commanded way)."""
    second = probes(result)[1]
    assert second.delta < 0.0 and second.status == "reached", second
    s_h = np.asarray(result.samples["true_coordinates"])[window(result, second), 1]
    assert s_h[0] - s_h[-1] >= 1.5e-3, s_h[[0, -1]]
