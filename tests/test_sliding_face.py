"""The ground friction face fitted to the forces of its slides (ccopt.estimation.sliding_face), against
the true cone (``contact.model_ground_rows``) and the closed-form line the forces are drawn on."""

from __future__ import annotations

import math

import numpy as np
import pytest

from ccopt import contact, geometry
from ccopt.estimation.sliding_face import SlidingFaceFit, SlidingFaceParams, fit_sliding_face

MU_G, MASS = 0.6, 0.8
WEIGHT = MASS * geometry.GRAVITY
NOISE = 0.3  # N, per force component
PERIOD = 0.001  # s, the estimator's rate


def face_force(way: int, pressing: float) -> tuple[float, float]:
    """The world hand force on the true face of a slide ``way`` (±1), pressing down with ``pressing`` N."""
    return way * MU_G * (WEIGHT + pressing), -pressing


def sums(points: np.ndarray) -> list[float]:
    """``n, Σx, Σy, Σx², Σxy, Σy²`` of mirrored forces ``points`` (N×2)."""
    x, y = points[:, 0], points[:, 1]
    return [float(len(x)), x.sum(), y.sum(), (x * x).sum(), (x * y).sum(), (y * y).sum()]


def mirrored(pressing: np.ndarray, rng: np.random.Generator) -> np.ndarray:
    return np.array([face_force(1, p) for p in pressing]) + rng.normal(0.0, NOISE, (len(pressing), 2))


def test_forces_spread_along_the_face_give_its_slope_and_apex_and_the_true_rows():
    """Slides pressing 5–20 N (twenty stretches): μ_g within 3 %, the apex (the weight) within 0.3 N,
    and the two rows those of the true cone (unit normals) within 0.01 and 0.3 N."""
    rng = np.random.default_rng(1)
    face = fit_sliding_face(sums(mirrored(rng.uniform(5.0, 20.0, 400), rng)), 20, SlidingFaceParams())
    assert face.determined
    assert face.mu_g == pytest.approx(MU_G, rel=0.03)
    assert face.apex == pytest.approx(WEIGHT, abs=0.3)
    rows, bounds = contact.model_ground_rows(MU_G, MASS)
    norms = np.linalg.norm(rows, axis=1)
    (normal_pos, b_pos), (normal_neg, b_neg) = face.rows()
    np.testing.assert_allclose([normal_pos, normal_neg], rows / norms[:, None], atol=0.01)
    np.testing.assert_allclose([b_pos, b_neg], bounds / norms, atol=0.3)


def test_one_cluster_at_one_normal_force_does_not_tell_a_slope():
    """Forces pressing 14–15 N, however many: not determined (their spread along the face is 0.5 N)."""
    rng = np.random.default_rng(2)
    face = fit_sliding_face(sums(mirrored(rng.uniform(14.0, 15.0, 2000), rng)), 50, SlidingFaceParams())
    assert not face.determined
    assert face.spread < SlidingFaceParams().min_spread


def test_the_angle_error_bar_counts_stretches_not_forces():
    """Forces spread 1.2 N along the face with 0.3 N across it: from two stretches the angle's error
    (0.18 rad) is too large, from twenty (0.056 rad) it is not."""
    rng = np.random.default_rng(3)
    points = sums(mirrored(rng.uniform(12.0, 16.0, 400), rng))
    assert not fit_sliding_face(points, 2, SlidingFaceParams()).determined
    assert fit_sliding_face(points, 20, SlidingFaceParams()).determined


def test_a_line_whose_apex_is_below_the_origin_is_no_friction_face():
    """Forces on ``x = 0.6 (−3 − y)`` (a negative weight) are not determined, however well spread."""
    rng = np.random.default_rng(4)
    pressing = rng.uniform(5.0, 20.0, 400)
    points = np.column_stack((0.6 * (pressing - 3.0), -pressing)) + rng.normal(0.0, NOISE, (400, 2))
    face = fit_sliding_face(sums(points), 20, SlidingFaceParams())
    assert face.apex < 0.0 and not face.determined


def feed(
    fit: SlidingFaceFit, stretches: list[tuple[list[tuple[float, float]], int]], way: int, time: float = 0.0
) -> float:
    """Feed ``fit`` the stretches of one slide ``way`` from ``time`` (s), each ``(forces, confirmations
    at its end)``, one force per millisecond, the confirmation count rising at each stretch's last
    force, then one sample with the slide ended; the time reached."""
    confirmed = 0
    for forces, confirmations in stretches:
        for k, force in enumerate(forces):
            time += PERIOD
            fit.update(time, force, way, confirmations if k == len(forces) - 1 else confirmed)
        confirmed = confirmations
    time += PERIOD
    fit.update(time, (0.0, -5.0), 0, 0)
    return time


def on_face(way: int, pressing: list[float], count: int = 80) -> list[tuple[float, float]]:
    """``count`` forces on the face of a slide ``way``, pressing from ``pressing[0]`` to ``pressing[1]``."""
    return [face_force(way, p) for p in np.linspace(*pressing, count)]


def test_the_first_stretch_of_each_slide_is_left_out():
    """Each slide's first stretch (the ramp up to the face) is far inside the cone: left out, the fit
    of the later stretches of slides both ways is exact; the stretches count only those kept."""
    fit = SlidingFaceFit()
    ramp = [(0.0, -p) for p in np.linspace(2.0, 6.0, 80)]
    time = feed(fit, [(ramp, 1), (on_face(1, [6.0, 9.0]), 2), (on_face(1, [9.0, 12.0]), 3)], 1)
    feed(fit, [(ramp, 1), (on_face(-1, [15.0, 18.0]), 2)], -1, time)
    assert fit.face.determined and fit.face.stretches == 3
    assert fit.face.mu_g == pytest.approx(MU_G, rel=1e-6)
    assert fit.face.apex == pytest.approx(WEIGHT, abs=1e-6)


def test_a_stretch_slower_than_the_longest_stretch_time_is_left_out():
    """A stretch of 0.2 s (a stalled slide, its forces inside the face) is left out; the 80 ms ones count."""
    fit = SlidingFaceFit()
    stalled = [(0.5 * x, y) for x, y in on_face(1, [9.0, 12.0], 200)]
    time = feed(fit, [(on_face(1, [2.0, 6.0]), 1), (on_face(1, [6.0, 9.0]), 2), (stalled, 3)], 1)
    feed(fit, [(on_face(1, [2.0, 6.0]), 1), (on_face(1, [15.0, 18.0]), 2)], 1, time)
    assert fit.face.stretches == 2
    assert fit.face.mu_g == pytest.approx(MU_G, rel=1e-6)


def test_forces_are_kept_at_most_once_per_sample_interval():
    """At 1 kHz one force in four (4 ms) is kept."""
    fit = SlidingFaceFit()
    feed(fit, [(on_face(1, [2.0, 6.0]), 1), (on_face(1, [6.0, 9.0], 80), 2)], 1)
    assert fit.face.count == 20


@pytest.mark.parametrize("field", ["sample_interval", "max_stretch_time", "min_spread", "max_slope_error"])
@pytest.mark.parametrize("value", [-1.0, math.nan, math.inf])
def test_bad_parameters_raise_naming_the_field(field, value):
    with pytest.raises(ValueError, match=field):
        SlidingFaceParams(**{field: value})


FIRST_SLIDE = [(on_face(1, [2.0, 6.0]), 1), (on_face(1, [6.0, 9.0]), 2), (on_face(1, [9.0, 12.0]), 3)]
"""Three stretches of a slide towards +x on the true face (for :func:`feed`)."""
HAND_LIMIT_SLIDE = [
    ([(0.5 * x, y) for x, y in on_face(1, span)], k) for k, span in ((1, [3.0, 6.0]), (2, [6.0, 9.0]))
]
"""Two stretches of a slide towards +x whose forces are off the face: the hand's limit, half the
tangential force (the hand slid, not the ground)."""


def test_a_restored_fit_is_the_fit_that_never_saw_the_slide():
    """Two slides' stretches, then a third slide of forces off the face (the hand's limit, half the
    tangential force) dropped by :meth:`SlidingFaceFit.restore` to the snapshot taken as it began:
    the face, and the face after one more slide, equal those of a fit fed the other slides only."""
    second = [(on_face(-1, [2.0, 6.0]), 1), (on_face(-1, [14.0, 17.0]), 2)]
    fit, clean = SlidingFaceFit(), SlidingFaceFit()
    time = feed(fit, FIRST_SLIDE, 1)
    feed(clean, FIRST_SLIDE, 1)
    state = fit.snapshot()
    time = feed(fit, HAND_LIMIT_SLIDE, 1, time)
    assert fit.face != clean.face
    fit.restore(state)
    assert fit.face == clean.face
    feed(fit, second, -1, time)
    feed(clean, second, -1, time)
    assert fit.face == clean.face and fit.face.determined
