"""Mode/geometry classifier against wrenches of known mode from the contact model."""

from __future__ import annotations

import math

import numpy as np
import pytest

from ccopt import contact
from ccopt.contact import N_CONE_ROWS, Row
from ccopt.estimation.classifier import ModeClassifier, ModeParams, tight_direction
from ccopt.modes import ContactConfiguration, ContactMode, HandGeometry

MU_H, MU_G, L_H, MASS = 0.5, 0.8, 0.05, 0.3
NOISE = np.array([0.3, 0.3, 0.005])  # N, N, N·m
ALL_ESTIMATED = [True] * N_CONE_ROWS
MOTION = {  # the configuration each tight row admits (signs as in ccopt.modes)
    Row.HAND_SLIDE_POS: ContactConfiguration(hand_mode=ContactMode.SLIDE_POS),
    Row.HAND_SLIDE_NEG: ContactConfiguration(hand_mode=ContactMode.SLIDE_NEG),
    Row.HAND_PIVOT_POS: ContactConfiguration(hand_geometry=HandGeometry.PIVOT_POS),
    Row.HAND_PIVOT_NEG: ContactConfiguration(hand_geometry=HandGeometry.PIVOT_NEG),
    Row.GROUND_SLIDE_POS: ContactConfiguration(ground_mode=ContactMode.SLIDE_POS),
    Row.GROUND_SLIDE_NEG: ContactConfiguration(ground_mode=ContactMode.SLIDE_NEG),
}


def hand_angle(row: Row) -> float:
    """A hand angle (rad) at which the face of ``row`` can be reached inside the hand's cone: the
    hand leans into the ground slide it drives."""
    return {Row.GROUND_SLIDE_POS: 0.6, Row.GROUND_SLIDE_NEG: -0.6}.get(row, 0.1)


def interior_wrench(theta: float, rng: np.random.Generator) -> np.ndarray:
    """A wrench strictly inside the true cone (rejection sampling on the model's margins)."""
    for _ in range(10_000):
        f_n = rng.uniform(3.0, 25.0)
        wrench = np.array([f_n, rng.uniform(-MU_H, MU_H) * f_n, rng.uniform(-L_H, L_H) * f_n])
        if np.all(contact.complementarity_margins(wrench, theta, MU_H, MU_G, L_H, MASS) > 0.0):
            return wrench
    raise AssertionError("no interior wrench found")


def face_wrench(row: Row, rng: np.random.Generator) -> np.ndarray:
    """A wrench on the true face of ``row``: an interior wrench moved along the row's normal (hand
    frame, :func:`ccopt.contact.model_friction_cone`) until the row is tight, if no other row is crossed."""
    theta = hand_angle(row)
    n_rows, b = contact.model_friction_cone(theta, MU_H, MU_G, L_H, MASS)
    normal = n_rows[row] / np.linalg.norm(n_rows[row])
    for _ in range(10_000):
        wrench = interior_wrench(theta, rng)
        moved = wrench + (b[row] - n_rows[row] @ wrench) / (n_rows[row] @ normal) * normal
        margins = contact.complementarity_margins(moved, theta, MU_H, MU_G, L_H, MASS)
        if abs(margins[row]) < 1e-9 and np.all(np.delete(margins, row) > 0.0) and moved[0] > 3.0:
            return moved
    raise AssertionError(f"no wrench on the face of {row!r} found")


def estimated_cone(theta: float, mu_scale: float, ground_shift: float) -> tuple[np.ndarray, np.ndarray]:
    """The true cone with estimation errors: ``μ_h`` scaled, the torque arm at 0.85 ``l_h``, the ground
    rows (unit normals) moved by ``ground_shift`` N."""
    n_rows, b = contact.model_friction_cone(theta, MU_H * mu_scale, MU_G, 0.85 * L_H, MASS)
    ground = list(contact.GROUND_ROWS)
    norms = np.linalg.norm(n_rows[ground], axis=1)
    n_rows[ground] /= norms[:, None]
    b[ground] = b[ground] / norms + ground_shift
    return n_rows, b


def classify(wrenches: np.ndarray, n_rows: np.ndarray, b: np.ndarray) -> list[ContactConfiguration]:
    classifier = ModeClassifier(ModeParams(hold_time=0.0))
    return [
        classifier.update(0.001 * k, (b - n_rows @ wrench).tolist(), ALL_ESTIMATED)
        for k, wrench in enumerate(wrenches)
    ]


def test_tight_direction_picks_the_smaller_margin_within_the_threshold():
    assert tight_direction(5.0, 4.0, 1.0, True) == 0
    assert tight_direction(0.5, 4.0, 1.0, True) == 1
    assert tight_direction(4.0, -0.2, 1.0, True) == -1
    assert tight_direction(5.0, 4.0, 1.0, False) == -1  # not estimated: may be sliding
    assert tight_direction(3.0, 4.0, 1.0, False) == 1


@pytest.mark.parametrize("row", list(Row))
def test_each_tight_row_reports_the_motion_it_blocks(row):
    wrench, theta = face_wrench(row, np.random.default_rng(int(row))), hand_angle(row)
    margins = contact.complementarity_margins(wrench, theta, MU_H, MU_G, L_H, MASS)
    n_rows, b = contact.model_friction_cone(theta, MU_H, MU_G, L_H, MASS)
    np.testing.assert_allclose(b - n_rows @ wrench, margins, atol=1e-9)
    params = ModeParams(slide_margin=1e-6, pivot_margin=1e-6, ground_margin=1e-6)
    assert ModeClassifier(params).update(0.0, margins.tolist(), ALL_ESTIMATED) == MOTION[row]


@pytest.mark.parametrize(("mu_scale", "ground_shift"), [(1.0, 0.0), (1.05, 0.5), (0.95, -0.5), (1.03, 0.3)])
def test_sliding_is_almost_never_reported_as_sticking(mu_scale, ground_shift):
    rng = np.random.default_rng(int(100 * mu_scale))
    for row in Row:
        n_rows, b = estimated_cone(hand_angle(row), mu_scale, ground_shift)
        clean = np.array([face_wrench(row, rng) for _ in range(150)])
        noisy = clean + rng.normal(0.0, NOISE, clean.shape)
        expected = getattr(MOTION[row], _field(row))
        missed = np.mean([getattr(modes, _field(row)) != expected for modes in classify(noisy, n_rows, b)])
        assert missed < 0.02, (row, missed)


def test_the_latch_holds_a_sliding_report_for_the_hold_time():
    classifier = ModeClassifier(ModeParams(hold_time=0.1))
    sliding = [0.0, 5.0, 5.0, 5.0, 5.0, 5.0]
    sticking = [5.0] * N_CONE_ROWS
    assert classifier.update(0.0, sliding, ALL_ESTIMATED).hand_mode == ContactMode.SLIDE_POS
    assert classifier.update(0.05, sticking, ALL_ESTIMATED).hand_mode == ContactMode.SLIDE_POS
    assert classifier.update(0.0999, sticking, ALL_ESTIMATED).hand_mode == ContactMode.SLIDE_POS
    assert classifier.update(0.1, sticking, ALL_ESTIMATED).hand_mode == ContactMode.STICK
    other_way = [5.0, 0.0, 5.0, 5.0, 5.0, 5.0]
    assert classifier.update(0.11, other_way, ALL_ESTIMATED).hand_mode == ContactMode.SLIDE_NEG


def test_rows_not_yet_estimated_count_as_may_be_sliding():
    classifier = ModeClassifier()
    sticking = [5.0, 6.0, 1.0, 1.0, 7.0, 3.0]
    modes = classifier.update(0.0, sticking, [False, False, True, True, False, False])
    assert modes.hand_mode == ContactMode.SLIDE_POS
    assert modes.hand_geometry == HandGeometry.FLUSH
    assert modes.ground_mode == ContactMode.SLIDE_NEG


@pytest.mark.parametrize(
    ("field", "value", "error"),
    [
        ("slide_margin", -1.0, ValueError),
        ("pivot_margin", math.nan, ValueError),
        ("ground_margin", math.inf, ValueError),
        ("hold_time", -0.1, ValueError),
        ("hold_time", None, TypeError),
    ],
)
def test_bad_parameters_raise_naming_the_field(field, value, error):
    with pytest.raises(error, match=field):
        ModeParams(**{field: value})


def _field(row: Row) -> str:
    return {0: "hand_mode", 1: "hand_mode", 2: "hand_geometry", 3: "hand_geometry"}.get(
        int(row), "ground_mode"
    )
