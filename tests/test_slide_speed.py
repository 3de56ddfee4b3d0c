"""A heavy object's slides are quasi-static: the ground slides of the experimenter's tour of the paper
triangle with 0.5 kg added (planar plant) keep the true normal force within the hand's limit plus
2 N (issue 10's bar), slide as commanded and slip nowhere else.

Driven at ``max_speed`` (60 mm/s) these ground slides broke away and slid at 50–90 mm/s, and the
ground contact chattered: the true normal force jumped between 8 and 29 N every few milliseconds
(``ControllerParams.slide_speed``). The second test holds that cause against the first run: the same
tour with the slide speed raised to ``max_speed`` slides the ground half as fast again and peaks
3 N higher, so the first does not pass by luck of the seed (measured: 112 against 57 mm/s, 27.8
against 21.5 N; a peak compared with the bar itself, 27 N, was 0.8 N from it and moved below it
with round-off changes elsewhere in the loop).
"""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from ccopt import closed_loop, experiment
from ccopt.objects import make_object

BAR = 2.0
"""Issue 10: the largest true normal force may exceed the hand's limit by this much (N)."""


def _tour_run(slide_speed: float | None) -> tuple[dict, float, float]:
    """The tour's summary, the hand's largest force (N) and the ground's peak true slip speed (m/s)."""
    obj = make_object("paper-triangle", added_mass=0.5)
    params, tour = experiment.experimenter_tour(obj, closed_loop.LoopParams(plant="planar"))
    if slide_speed is not None:
        controller = dataclasses.replace(params.controller_params, slide_speed=slide_speed)
        params = dataclasses.replace(params, controller_params=controller)
    done = experiment.run_experiment(obj, tour.schedule, params, seed=0)
    slip_speed = float(np.max(np.abs(done.result.samples["true_slip_rates"][:, 1])))
    return done.summary, params.hand.force_limits[1], slip_speed


@pytest.fixture(scope="module")
def default_run() -> tuple[dict, float, float]:
    return _tour_run(None)


def test_a_heavy_triangles_ground_slides_keep_the_normal_force_within_the_bar(default_run):
    summary, f_max, _ = default_run
    assert summary["status"] == "completed"
    slides = summary["ratio_by_kind"]["slide_ground"]
    assert slides["n"] >= 4 and 0.9 <= slides["median"] <= 1.1
    assert summary["unintended_slips"] == 0
    assert summary["normal_force_n"]["max"] <= f_max + BAR


def test_the_same_slides_driven_at_max_speed_break_away_and_peak_higher(default_run):
    summary, _, slip_speed = default_run
    fast_summary, _, fast_slip_speed = _tour_run(closed_loop.LoopParams().controller_params.max_speed[0])
    assert fast_slip_speed >= 1.5 * slip_speed
    assert fast_summary["normal_force_n"]["max"] >= summary["normal_force_n"]["max"] + 3.0
