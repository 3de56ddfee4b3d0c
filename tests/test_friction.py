"""Hand friction and torque limits against a known cone (ccopt.contact.model_friction_cone)."""

from __future__ import annotations

import math

import numpy as np
import pytest

from ccopt import contact
from ccopt.contact import Row
from ccopt.estimation.friction import HandFrictionEstimator, HandFrictionParams

L_H = 0.05
NOISE = 0.3  # N


def hand_cone(mu_h: float) -> tuple[np.ndarray, np.ndarray]:
    """The true hand rows (hand frame) of a known object."""
    n_rows, b = contact.model_friction_cone(0.0, mu_h, 1.0, L_H, 0.3)
    return n_rows[: len(contact.HAND_ROWS)], b[: len(contact.HAND_ROWS)]


def wrenches(mu_h: float, count: int, face: Row | None, rng: np.random.Generator) -> np.ndarray:
    """Noise-free wrenches inside the true cone, or on the face of the row ``face`` (made tight)."""
    n_rows, b = hand_cone(mu_h)
    f_n = rng.uniform(2.0, 25.0, count)
    torque = rng.uniform(-0.5, 0.5, count) * L_H * f_n
    if face is None:
        f_t = rng.uniform(-0.95, 0.95, count) * mu_h * f_n
    else:  # solve N_k w = b_k for f_t
        row = n_rows[face]
        f_t = (b[face] - row[0] * f_n - row[2] * torque) / row[1]
    samples = np.column_stack((f_n, f_t, torque))
    assert np.all(samples @ n_rows.T <= b + 1e-9)
    return samples


def feed(estimator: HandFrictionEstimator, samples: np.ndarray, rng: np.random.Generator) -> None:
    noisy = samples + rng.normal(0.0, NOISE, samples.shape) * [1.0, 1.0, 0.0]
    for f_n, f_t, _ in noisy.tolist():
        estimator.update(f_n, f_t)


@pytest.mark.parametrize("mu_h", [0.3, 0.5, 0.8])
def test_mu_h_within_five_percent_after_sliding_both_ways(mu_h):
    rng = np.random.default_rng(int(mu_h * 100))
    estimator = HandFrictionEstimator(0.05)
    feed(estimator, wrenches(mu_h, 3000, None, rng), rng)
    assert estimator.params.mu_prior <= estimator.mu_h < mu_h  # only sticking seen: a lower bound
    mixed = np.vstack([wrenches(mu_h, 3000, None, rng), wrenches(mu_h, 300, Row.HAND_SLIDE_POS, rng)])
    feed(estimator, rng.permutation(mixed), rng)
    assert estimator.mu_h == pytest.approx(mu_h, rel=0.05)
    mixed = np.vstack([wrenches(mu_h, 3000, None, rng), wrenches(mu_h, 300, Row.HAND_SLIDE_NEG, rng)])
    feed(estimator, rng.permutation(mixed), rng)
    assert estimator.mu_h == pytest.approx(mu_h, rel=0.05)
    assert estimator.valid


def test_mu_h_never_drops_below_the_prior():
    estimator = HandFrictionEstimator(0.05, HandFrictionParams(mu_prior=0.1))
    assert estimator.mu_h == 0.1 and not estimator.valid
    for _ in range(200):
        estimator.update(10.0, 0.2)  # |f_t| below the tangential allowance: ratio 0
    assert estimator.mu_h == 0.1
    assert estimator.valid


def test_samples_without_a_clear_contact_force_or_not_finite_are_ignored():
    estimator = HandFrictionEstimator(0.05, HandFrictionParams(min_normal_force=3.0))
    for f_n, f_t in ((3.0, 3.0), (0.5, 1.0), (-5.0, 1.0), (math.nan, 1.0), (10.0, math.inf)):
        estimator.update(f_n, f_t)
    assert estimator.sample_count == 0
    estimator.update(10.0, 4.0)
    params = estimator.params
    expected = (4.0 - params.tangential_allowance) / (10.0 + params.epsilon)
    assert estimator.sample_count == 1
    assert estimator.mu_h == pytest.approx(expected)


def test_rows_are_the_contact_model_hand_rows_with_the_torque_margin():
    estimator = HandFrictionEstimator(0.06, HandFrictionParams(torque_margin=0.8))
    for _ in range(10):
        estimator.update(10.0, 5.0)
    n_rows, b = estimator.rows()
    assert estimator.l_h_eff == pytest.approx(0.048)
    expected_rows, expected_b = contact.hand_rows(estimator.mu_h, 0.048)
    np.testing.assert_allclose(n_rows, np.array(expected_rows), atol=1e-15)
    np.testing.assert_allclose(b, np.array(expected_b).ravel(), atol=1e-15)


@pytest.mark.parametrize(
    ("field", "value", "error"),
    [
        ("mu_prior", 0.0, ValueError),
        ("epsilon", -1.0, ValueError),
        ("tangential_allowance", math.nan, ValueError),
        ("min_normal_force", 0.0, ValueError),
        ("level", 1.0, ValueError),
        ("min_samples", 0, ValueError),
        ("torque_margin", 1.2, ValueError),
        ("torque_margin", "0.8", TypeError),
        ("min_samples", 10.5, TypeError),
    ],
)
def test_bad_parameters_raise_naming_the_field(field, value, error):
    with pytest.raises(error, match=field):
        HandFrictionParams(**{field: value})
