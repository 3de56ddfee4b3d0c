"""Constant-rate angle filter against the angles it was fed (closed forms: ramps, steps, wrap-around)."""

from __future__ import annotations

import math

import numpy as np
import pytest

from ccopt.estimation.angle_filter import AngleFilter, AngleFilterParams

NOISE = math.radians(0.1)


def run(times: np.ndarray, angles: np.ndarray, params: AngleFilterParams | None = None) -> np.ndarray:
    angle_filter = AngleFilter(params)
    return np.array([angle_filter.update(t, a) for t, a in zip(times, angles, strict=True)])


@pytest.mark.parametrize("interval", [0.001, 0.01])
def test_a_steady_rotation_is_followed_without_lag_and_with_less_noise(interval):
    rng = np.random.default_rng(1)
    times = np.arange(0.0, 4.0, interval)
    truth = 0.2 + 0.5 * times  # rad, 0.5 rad/s
    filtered = run(times, truth + rng.normal(0.0, NOISE, times.size))
    error = (filtered - truth)[times > 1.0]
    assert abs(error.mean()) < 0.1 * NOISE  # no lag
    assert error.std() < (0.4 if interval == 0.001 else 0.7) * NOISE


def test_a_min_jerk_pivot_stays_within_a_fraction_of_the_noise():
    # 0.4 rad in 1.2 s (peak acceleration ≈ 1.6 rad/s²), as in the estimator's plant recording
    rng = np.random.default_rng(2)
    times = np.arange(0.0, 2.0, 0.001)
    u = np.clip(times / 1.2, 0.0, 1.0)
    truth = 0.4 * u**3 * (10.0 - 15.0 * u + 6.0 * u * u)
    filtered = run(times, truth + rng.normal(0.0, NOISE, times.size))
    assert np.abs(filtered - truth)[100:].max() < 2.0 * NOISE


def test_the_first_sample_and_a_reset_start_at_the_measured_angle():
    angle_filter = AngleFilter()
    assert angle_filter.update(0.0, 0.3) == 0.3
    for k in range(1, 100):
        angle_filter.update(0.001 * k, 0.3)
    angle_filter.reset()
    assert angle_filter.update(0.2, -0.1) == -0.1
    assert angle_filter.update(0.1, 0.5) == 0.5  # time went back: start afresh


def test_the_angle_wraps_around_pi():
    times = np.arange(0.0, 1.0, 0.001)
    truth = math.pi - 0.05 + 0.1 * times  # crosses π
    measured = np.remainder(truth + math.pi, 2.0 * math.pi) - math.pi
    filtered = run(times, measured)
    error = np.remainder(filtered - truth + math.pi, 2.0 * math.pi) - math.pi
    assert np.abs(error).max() < 1e-4  # the start-up transient only (the rate starts at 0); no 2π jump
    assert np.abs(np.diff(filtered)).max() < 1e-3  # continuous through π


def test_a_jump_restarts_the_filter_at_the_measurement():
    times = np.arange(0.0, 1.0, 0.001)
    angles = np.where(times < 0.5, 0.0, 0.4)  # faster than any rotation the model allows
    filtered = run(times, angles)
    assert filtered[times >= 0.5][0] == 0.4 and np.all(filtered[times >= 0.5] == 0.4)


@pytest.mark.parametrize("field", ["noise", "acceleration", "rate_std", "restart_gate"])
@pytest.mark.parametrize("value", [0.0, -1.0, math.nan])
def test_bad_parameters_raise_naming_the_field(field, value):
    with pytest.raises(ValueError, match=field):
        AngleFilterParams(**{field: value})
