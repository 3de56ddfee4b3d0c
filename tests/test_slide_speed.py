"""A heavy object's slides are quasi-static: the ground slides of the experimenter's tour of the paper
triangle with 0.5 kg added (planar plant) keep the true normal force within the hand's limit plus
2 N (issue 10's bar), slide as commanded and slip nowhere else.

Driven at ``max_speed`` (60 mm/s) these ground slides broke away and slid at 50–90 mm/s, and the
ground contact chattered: the true normal force jumped between 8 and 29 N every few milliseconds
(``ControllerParams.slide_speed``). The second test holds that cause: the same tour with the slide
speed raised to ``max_speed`` again exceeds the bar, so the first does not pass by luck of the seed.
"""

from __future__ import annotations

import dataclasses

import pytest

from ccopt import closed_loop, experiment
from ccopt.objects import make_object

BAR = 2.0
"""Issue 10: the largest true normal force may exceed the hand's limit by this much (N)."""


def _tour_run(slide_speed: float | None) -> tuple[dict, float]:
    obj = make_object("paper-triangle", added_mass=0.5)
    params, tour = experiment.experimenter_tour(obj, closed_loop.LoopParams(plant="planar"))
    if slide_speed is not None:
        controller = dataclasses.replace(params.controller_params, slide_speed=slide_speed)
        params = dataclasses.replace(params, controller_params=controller)
    summary = experiment.run_experiment(obj, tour.schedule, params, seed=0).summary
    return summary, params.hand.force_limits[1]


@pytest.fixture(scope="module")
def default_run() -> tuple[dict, float]:
    return _tour_run(None)


def test_a_heavy_triangles_ground_slides_keep_the_normal_force_within_the_bar(default_run):
    summary, f_max = default_run
    assert summary["status"] == "completed"
    slides = summary["ratio_by_kind"]["slide_ground"]
    assert slides["n"] >= 4 and 0.9 <= slides["median"] <= 1.1
    assert summary["unintended_slips"] == 0
    assert summary["normal_force_n"]["max"] <= f_max + BAR


def test_the_same_slides_driven_at_max_speed_exceed_the_bar(default_run):
    fast = closed_loop.LoopParams().controller_params.max_speed[0]
    summary, f_max = _tour_run(fast)
    assert summary["normal_force_n"]["max"] > f_max + BAR >= default_run[0]["normal_force_n"]["max"]
