"""Goal slides end `rolled` when the hand leaves flush contact, and a slide is reached only when the
object truly did it: the `paper` goals on the paper triangle, pentagon and hexagon (planar plant, seed 0),
judged by the simulator's truth.

The planner tries ground slides where the statics the estimate knows allow them while its hand
friction is still a lower bound; on the triangle at 2.7° the hand ended up on the face's end. Before
slides had the `rolled` ending, the hand stayed there for 2.5 s, then rolled and slid 10 mm on the
face, and the kinematics (which take the hand as flush) read that as the ground slide: `reached`,
with the true ground contact unmoved. Since the ground hull's faces are held above the origin the
triangle's ground slides all slide. Which slides of the other objects end `rolled` changes with the
smallest perturbation of a run (a change of rounding in the impedance target's step took the
pentagon's three to none and left the hexagon's two), so the `rolled` slides are checked over the
pentagon's and the hexagon's runs together.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from ccopt import closed_loop, statics
from ccopt.hand import Hand
from ccopt.objects import make_object
from ccopt.schedule import load_schedule


def paper_goals(name: str) -> closed_loop.RunResult:
    return closed_loop.run(make_object(name), load_schedule("paper"), closed_loop.LoopParams(), seed=0)


def true_face_on_hand(name: str, result: closed_loop.RunResult) -> np.ndarray:
    """``(N, 2)``: where the true face under the hand lies on the hand (hand positions, m) at each
    sample: the start's face (:func:`ccopt.statics.true_statics`) moved by the true hand slides. A
    jump of the true ``s_h`` by more than :data:`VERTEX_JUMP` in one sample is the object changing
    ground vertex (a polygon rocking over a face on the ground), which leaves the face on the hand."""
    params = closed_loop.LoopParams()
    start = closed_loop.start_config(make_object(name), params)
    face = np.asarray(statics.true_statics(make_object(name), start, params.hand).statics.face)
    s_h = np.asarray(result.samples["true_coordinates"])[:, 1]
    slid = np.diff(s_h, prepend=s_h[0])
    slid[np.abs(slid) > VERTEX_JUMP] = 0.0
    return face[None, :] + s_h[0] + np.cumsum(slid)[:, None]


VERTEX_JUMP = 0.03
"""m: more than any hand slide moves in one sample, less than a paper polygon's face."""


@pytest.fixture(scope="module")
def result() -> closed_loop.RunResult:
    return paper_goals("paper-triangle")


OTHERS = ("paper-pentagon", "paper-hexagon")


@pytest.fixture(scope="module")
def others() -> list[closed_loop.RunResult]:
    return [paper_goals(name) for name in OTHERS]


def window(result: closed_loop.RunResult, step: closed_loop.StepResult) -> slice:
    time = np.asarray(result.samples["time"])
    return slice(int(np.searchsorted(time, step.start_time)), int(np.searchsorted(time, step.end_time)) + 1)


def goal_slides(result: closed_loop.RunResult) -> list[closed_loop.StepResult]:
    return [step for step in result.steps if step.goal is not None and step.kind.startswith("slide")]


def test_every_reached_goal_slide_truly_moved_its_coordinate(result):
    """At least half the commanded length, the commanded way, by the truth."""
    reached = [step for step in goal_slides(result) if step.status == "reached"]
    assert reached
    for step in reached:
        k = 1 if step.kind == "slide_hand" else 2
        true = np.asarray(result.samples["true_coordinates"])[window(result, step), k]
        moved = (true[-1] - true[0]) * math.copysign(1.0, step.delta)
        assert moved >= 0.5 * abs(step.delta), (step, moved)


EDGE_SHARE = 0.75
"""A hand about to roll: its true centre of pressure ``|τ| / f_n`` in the outer quarter of its
half-length (the estimate calls a hand whose torque nears its limit maybe rolling)."""


def test_a_goal_slide_that_ends_rolled_truly_had_the_hand_at_or_over_its_edge(others):
    """Each `rolled` slide: by the truth, the hand was off flush or its centre of pressure was in the
    outer quarter of the hand, and the roll did not pass for the slide: the estimated coordinate
    moved no further the slide's way than the true one, to the slide's 2 mm tolerance. (A slide may
    truly happen and the hand roll at its end: the pentagon's ground slide at 35°, the tilt a pivot
    that rolled had turned it to, slid the ground 9.0 mm, 8.2 mm by the estimate, and ended `rolled`.)"""
    rolled = [(result, step) for result in others for step in goal_slides(result) if step.status == "rolled"]
    assert rolled
    for result, step in rolled:
        span = window(result, step)
        geometry = np.asarray(result.samples["true_modes"])[span, 1]
        wrench = np.asarray(result.samples["true_hand_wrench"])[span]
        centre = np.abs(wrench[:, 2]) / np.maximum(wrench[:, 0], 1e-9)
        at_edge = centre >= EDGE_SHARE * Hand().half_length
        assert np.any(geometry != 0) or np.any(at_edge), step
        k = 1 if step.kind == "slide_hand" else 2
        true = np.asarray(result.samples["true_coordinates"])[span, k]
        estimated = np.asarray(result.samples["est_coordinates"])[span, k]
        read = (estimated[-1] - estimated[0]) - (true[-1] - true[0])
        assert read * math.copysign(1.0, step.delta) < 2e-3, step


def test_the_known_face_lies_on_the_hand_where_the_true_face_does(others):
    """The estimate's known face (``est_face`` + ``ŝ_h``, hand positions) inside the true face on the
    hand, to 0.5 mm, wherever it is known. The paper hexagon rocks over its bottom face (its ground
    vertex switches back and forth near 0°). Found again at 2° with ``ŝ_h`` 51 mm off and the same
    ``d̂`` (the bottom face is parallel to the hand's), its face was kept in ``u`` and reached 53 mm
    past the hand's end. Before exploration pivots held their target while the hand rolled, its
    kinematics, found again after such a rock, took ``ŝ_h`` 41 mm off and
    corrected it by 30 mm over the next 16 s with the hand sticking; the face, kept in ``u``, ended
    up 23 mm past the true face's end on one side and 34 mm short of it on the other, where it cut
    the hand 11 mm from its centre: a ground slide ended `rolled` with the hand truly flush and its
    centre of pressure 12-13 mm from the hand's centre, 35 mm inside the true face."""
    for name, result in zip(OTHERS, others, strict=True):
        known = np.asarray(result.samples["est_face"])
        judged = np.isfinite(known).all(axis=1) & (known[:, 0] <= known[:, 1])
        assert judged.sum() > 1000, name
        on_hand = known[judged] + np.asarray(result.samples["est_coordinates"])[judged, 1:2]
        true = true_face_on_hand(name, result)[judged]
        assert np.all(on_hand[:, 0] >= true[:, 0] - 5e-4), name
        assert np.all(on_hand[:, 1] <= true[:, 1] + 5e-4), name
