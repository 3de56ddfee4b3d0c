"""Estimator hardening, by property: any finite input gives finite (or flagged-invalid) output and no
exception, bad input only ValueError/TypeError, and one absurd sample changes nothing afterwards."""

from __future__ import annotations

import contextlib
import dataclasses
import math
import pickle

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from benchmarks.estimator_speed import synthetic_stream
from ccopt.estimation import (
    AngleFilter,
    Estimate,
    Estimator,
    EstimatorParams,
    GroundConeEstimator,
    GroundConeParams,
    HandFrictionParams,
    P2Quantile,
    P2QuantileBank,
)
from ccopt.estimation.estimator import SAMPLE_BOUNDS

EXAMPLES = settings(max_examples=2000, deadline=None, suppress_health_check=[HealthCheck.too_slow])

QUICK = EstimatorParams(
    friction=HandFrictionParams(min_samples=3),
    ground=GroundConeParams(
        directions=16, min_samples=5, sample_interval=0.0, refit_interval=0.0, min_face_length=0.5
    ),
)
"""Parts that count as estimated after a few samples, so that short streams reach every state (and
a coarse hull: a fresh P² bank is slow while its markers settle)."""

any_finite = st.floats(allow_nan=False, allow_infinity=False)
extreme = st.one_of(
    any_finite,
    st.sampled_from([0.0, -0.0, 5e-324, -5e-324, 1e-300, 1e300, -1e300, 1.7976931348623157e308, -1e308]),
    st.sampled_from([bound * scale for bound in SAMPLE_BOUNDS for scale in (-1.0, 1.0, 1.0 + 1e-15)]),
)


def plausible_stream(seed: int, length: int) -> list[tuple[float, list[float], list[float]]]:
    """A hand pressing (0–40 N, friction up to 0.8) while it rocks and drifts, samples 0–20 ms apart."""
    rng = np.random.default_rng(seed)
    times = np.cumsum(rng.uniform(0.0, 0.02, length))
    poses = np.array([0.0, 0.1, 0.0]) + np.cumsum(rng.normal(0.0, [1e-3, 5e-4, 0.02], (length, 3)), axis=0)
    f_n = np.clip(15.0 + np.cumsum(rng.normal(0.0, 2.0, length)), -2.0, 40.0)
    f_t = f_n * np.clip(np.cumsum(rng.normal(0.0, 0.2, length)), -0.8, 0.8)
    torque = 0.05 * f_n * np.clip(np.cumsum(rng.normal(0.0, 0.3, length)), -1.0, 1.0)
    wrenches = np.column_stack((f_n, f_t, torque))
    rows = zip(times.tolist(), poses.tolist(), wrenches.tolist(), strict=True)
    return [(time, pose, wrench) for time, pose, wrench in rows]


@st.composite
def streams(draw: st.DrawFn) -> list[tuple[float, list[float], list[float]]]:
    """A plausible stream with any finite values put anywhere (times too)."""
    stream = plausible_stream(draw(st.integers(0, 2**32 - 1)), draw(st.integers(1, 16)))
    for _ in range(draw(st.integers(0, 4))):
        k, place = draw(st.integers(0, len(stream) - 1)), draw(st.integers(0, 6))
        time, pose, wrench = stream[k]
        values = [time, *pose, *wrench]
        values[place] = draw(extreme)
        stream[k] = (values[0], values[1:4], values[4:])
    return stream


def assert_valid_parts_finite(estimate: Estimate) -> None:
    rows = estimate.row_valid
    assert math.isfinite(estimate.time)
    assert np.isfinite(estimate.cone_rows[rows]).all() and np.isfinite(estimate.cone_bounds[rows]).all()
    assert np.isfinite(estimate.margins[rows]).all()
    assert math.isfinite(estimate.mu_h) and math.isfinite(estimate.torque_lever)
    if rows[4] or rows[5]:
        assert np.isfinite(estimate.ground_rows).all() and np.isfinite(estimate.ground_bounds).all()
    assert not math.isinf(estimate.mu_g)
    assert np.isfinite(estimate.wrench).all() or estimate.skipped
    if estimate.theta_o_valid:
        assert math.isfinite(estimate.theta_o)
    if estimate.s_h_valid:
        assert math.isfinite(estimate.s_h)
    if estimate.contact_valid:
        assert math.isfinite(estimate.d) and math.isfinite(estimate.s_g) and np.isfinite(estimate.r_o).all()


@EXAMPLES
@given(streams(), st.booleans())
def test_any_finite_stream_gives_finite_or_flagged_invalid_estimates(stream, quick: bool) -> None:
    estimator = Estimator(params=QUICK if quick else None)
    for time, pose, wrench in stream:
        assert_valid_parts_finite(estimator.update(time, pose, wrench))


junk = st.one_of(
    st.none(),
    st.integers(min_value=2**1024),
    st.lists(st.integers(), min_size=3, max_size=3),
    st.text(max_size=3),
    st.complex_numbers(allow_nan=False),
    st.lists(any_finite, max_size=4),
    st.lists(st.lists(any_finite, max_size=3), max_size=3),
    st.dictionaries(st.text(max_size=2), any_finite, max_size=2),
    st.just(np.zeros((3, 1))),
    st.just(object()),
)


@EXAMPLES
@given(st.one_of(any_finite, junk), st.one_of(st.lists(any_finite, min_size=3, max_size=3), junk), junk)
def test_bad_input_raises_only_value_or_type_errors(time, pose, wrench) -> None:
    estimator = Estimator(params=QUICK)
    estimator.update(0.0, [0.0, 0.1, 0.0], [10.0, 1.0, 0.0])
    for arguments in ((time, pose, wrench), (time, wrench, pose)):
        with contextlib.suppress(ValueError, TypeError):
            assert_valid_parts_finite(estimator.update(*arguments))


STREAM_RATE = 100.0
"""The closed loop's estimator rate (Hz): the poisoning test's stream is sampled at it."""


@pytest.fixture(scope="module")
def clean_run() -> tuple[list[tuple[float, np.ndarray, np.ndarray]], list[bytes], list[tuple]]:
    """A 20 s stream that explores both cones, pivots and slides (:mod:`benchmarks.estimator_speed`,
    every 10th sample), the estimator's pickled state before every sample, and every estimate's
    fingerprint."""
    times, poses, wrenches, _ = synthetic_stream(20000, seed=4)
    stream = list(zip(times[::10], poses[::10], wrenches[::10], strict=True))
    estimator, states, estimates = Estimator(), [], []
    for time, pose, wrench in stream:
        states.append(pickle.dumps(estimator))
        last = estimator.update(time, pose, wrench)
        estimates.append(fingerprint(last))
    assert last.row_valid.all() and last.kinematics_valid  # the stream reaches every estimate
    return stream, states, estimates


def fingerprint(estimate: Estimate) -> tuple:
    """Every field of an estimate, exactly (arrays by their bytes, numbers by ``repr``: NaN is NaN)."""
    return tuple(
        value.tobytes() if isinstance(value, np.ndarray) else repr(value)
        for value in (getattr(estimate, field.name) for field in dataclasses.fields(estimate))
    )


COMPARED = 1
"""Estimates compared after the absurd sample (its state is compared too, which settles the rest)."""


@settings(max_examples=2000, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(st.data())
def test_one_absurd_sample_changes_nothing_afterwards(clean_run, data) -> None:
    """Inserted anywhere in a stream, between two samples, with any value beyond its bound in any
    place: the estimator's whole state is left exactly as it was, so every later estimate is the
    same as without it."""
    stream, states, estimates = clean_run
    position = data.draw(st.integers(1, len(stream) - COMPARED))
    place = data.draw(st.integers(0, 6))  # time, x_h, y_h, θ_h, f_n, f_t, τ
    size = data.draw(st.floats(SAMPLE_BOUNDS[place], 1.7e308, exclude_min=True) | st.just(1e300))
    sign = data.draw(st.sampled_from([-1.0, 1.0]))
    time, pose, wrench = stream[position]
    values = [time - 0.5 / STREAM_RATE, *pose, *wrench]
    values[place] = sign * size
    estimator, untouched = pickle.loads(states[position]), pickle.loads(states[position])
    assert estimator.update(values[0], values[1:4], values[4:]).skipped
    assert pickle.dumps(estimator) == pickle.dumps(untouched)
    for k in range(position, position + COMPARED):
        assert fingerprint(estimator.update(*stream[k])) == estimates[k], k


@pytest.mark.filterwarnings("ignore:overflow encountered in matmul")  # projections: inf, skipped
@EXAMPLES
@given(st.lists(st.tuples(extreme, extreme), max_size=8))
def test_ground_cone_parts_take_any_finite_force(forces) -> None:
    """The hull alone (as the estimator uses it, and directly): finite rows or invalid ones."""
    hull = GroundConeEstimator(QUICK.ground)
    for k, force in enumerate(forces):
        hull.update(float(k), np.array(force))
        cone = hull.cone
        assert not cone.valid or (np.isfinite(cone.A).all() and np.isfinite(cone.b).all())
        assert not math.isinf(cone.mu_g)


@EXAMPLES
@given(st.lists(st.tuples(extreme, extreme), max_size=12))
def test_angle_filter_and_quantiles_take_any_finite_input(samples) -> None:
    angle, single, bank = AngleFilter(), P2Quantile(0.99), P2QuantileBank(0.9, 3)
    for time, value in samples:
        filtered = angle.update(time, value)
        assert math.isfinite(filtered)
        single.add(value)
        bank.add(np.array([value, -value, time]))
        assert not math.isinf(single.value) and not np.isinf(bank.values).any()
