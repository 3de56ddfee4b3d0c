"""Streaming P² quantiles against numpy.quantile (the independent truth)."""

from __future__ import annotations

import copy
import math
import pickle

import numpy as np
import pytest

from ccopt.estimation import p2_step, quantile
from ccopt.estimation.quantile import P2Quantile, P2QuantileBank, marker_levels

SAMPLES = 100_000


def _stream(name: str, rng: np.random.Generator) -> np.ndarray:
    return {
        "normal": lambda: rng.normal(3.0, 2.0, SAMPLES),
        "exponential": lambda: rng.exponential(1.5, SAMPLES),
        "uniform": lambda: rng.uniform(-1.0, 4.0, SAMPLES),
        "lognormal": lambda: rng.lognormal(0.0, 1.0, SAMPLES),
        "student_t3": lambda: rng.standard_t(3, SAMPLES),
    }[name]()


def _estimate(samples: np.ndarray, level: float) -> float:
    quantile = P2Quantile(level)
    for sample in samples.tolist():
        quantile.add(sample)
    return quantile.value


@pytest.mark.parametrize("name", ["normal", "exponential", "uniform", "lognormal", "student_t3"])
def test_p2_matches_numpy_within_one_percent(name):
    rng = np.random.default_rng(11)
    samples = _stream(name, rng)
    scale = float(np.subtract(*np.quantile(samples, [0.75, 0.25])))
    for level in (0.1, 0.5, 0.9, 0.99):
        estimate, truth = _estimate(samples, level), float(np.quantile(samples, level))
        # 1 % of the value, or of the interquartile range where the quantile is near zero
        assert abs(estimate - truth) <= 0.01 * max(abs(truth), scale), (name, level, estimate, truth)
        assert abs(np.mean(samples <= estimate) - level) <= 0.01, (name, level)


def test_p2_rank_error_stays_small_on_infinite_variance_tails():
    samples = np.random.default_rng(12).standard_t(2, SAMPLES)
    for level in (0.01, 0.5, 0.995):
        assert abs(np.mean(samples <= _estimate(samples, level)) - level) <= 0.005


@pytest.mark.parametrize("level", [0.05, 0.5, 0.9, 0.99])
def test_p2_is_exact_for_the_first_five_samples(level):
    samples = np.random.default_rng(1).normal(size=5)
    quantile = P2Quantile(level)
    assert math.isnan(quantile.value)
    for count, sample in enumerate(samples, start=1):
        quantile.add(float(sample))
        assert quantile.value == pytest.approx(np.quantile(samples[:count], level), abs=1e-15)
        assert quantile.count == count


def test_p2_ignores_non_finite_samples():
    quantile = P2Quantile(0.9)
    for sample in (1.0, math.nan, 2.0, math.inf, -math.inf, 3.0):
        quantile.add(sample)
    assert quantile.count == 3
    assert quantile.value == pytest.approx(np.quantile([1.0, 2.0, 3.0], 0.9))


def test_bank_equals_one_p2_per_stream_including_ties():
    rng = np.random.default_rng(2)
    for level in (0.1, 0.5, 0.99):
        samples = np.round(rng.standard_t(3, (4000, 6)), 1)  # rounding makes many ties
        bank, scalars = P2QuantileBank(level, 6), [P2Quantile(level) for _ in range(6)]
        for row in samples:
            bank.add(row)
            for scalar, sample in zip(scalars, row.tolist(), strict=True):
                scalar.add(sample)
            if bank.count in (1, 3, 5, 6, 50):
                assert bank.values == pytest.approx([s.value for s in scalars], rel=1e-12, abs=1e-12)
        assert bank.values.tolist() == [s.value for s in scalars]


def test_bank_matches_numpy_and_skips_non_finite_rows():
    rng = np.random.default_rng(3)
    samples = rng.normal(size=(20_000, 8)) * np.arange(1, 9)
    bank = P2QuantileBank(0.99, 8)
    assert np.isnan(bank.values).all()
    for row in samples:
        bank.add(row)
    bank.add(np.full(8, np.nan))
    assert bank.count == len(samples)
    truth = np.quantile(samples, 0.99, axis=0)
    assert np.all(np.abs(bank.values - truth) <= 0.01 * np.abs(truth))


@pytest.mark.parametrize("copy_bank", [copy.deepcopy, lambda bank: pickle.loads(pickle.dumps(bank))])
def test_a_copied_bank_goes_on_like_the_original(copy_bank):
    """A copy (e.g. an estimator's pickled state) steps its own arrays, to the bit as the original."""
    rng = np.random.default_rng(5)
    bank = P2QuantileBank(0.9, 70)
    for _ in range(20):
        bank.add(rng.normal(size=70))
    copied = copy_bank(bank)
    for _ in range(50):
        row = rng.normal(size=70)
        bank.add(row)
        copied.add(row)
    assert copied.values.tobytes() == bank.values.tobytes()
    assert copied.count == bank.count


def test_marker_levels_are_classic_in_the_middle_and_close_in_the_tails():
    assert marker_levels(0.5) == pytest.approx([0.0, 0.25, 0.5, 0.75, 1.0])
    assert marker_levels(0.99) == pytest.approx([0.0, 0.98, 0.99, 0.995, 1.0])
    assert marker_levels(0.02) == pytest.approx([0.0, 0.01, 0.02, 0.04, 1.0])


@pytest.mark.parametrize("level", [0.0, 1.0, -0.5, 1.5, math.nan])
def test_bad_level_raises_value_error_naming_it(level):
    with pytest.raises(ValueError, match="level"):
        P2Quantile(level)
    with pytest.raises(ValueError, match="level"):
        P2QuantileBank(level, 3)


def test_bad_types_raise_type_error():
    with pytest.raises(TypeError, match="level"):
        P2Quantile("0.5")
    with pytest.raises(TypeError, match="size"):
        P2QuantileBank(0.5, 2.0)
    with pytest.raises(ValueError, match="size"):
        P2QuantileBank(0.5, 0)


def test_bank_equals_p2_bit_for_bit_with_ties_and_signed_zeros():
    """70 streams stepped in C against one P2Quantile per stream, every value and its sign: samples
    rounded to a tenth give ties and −0.0."""
    rng = np.random.default_rng(7)
    samples = np.round(rng.standard_t(3, (1500, 70)) * 0.3, 1)
    bank, scalars = P2QuantileBank(0.985, 70), [P2Quantile(0.985) for _ in range(70)]
    for row in samples:
        bank.add(row)
        for scalar, sample in zip(scalars, row.tolist(), strict=True):
            scalar.add(sample)
    expected = np.array([s.value for s in scalars])
    assert np.array_equal(bank.values, expected) and np.array_equal(
        np.signbit(bank.values), np.signbit(expected)
    )
    assert np.any((samples == 0.0) & np.signbit(samples))  # −0.0 among the samples


def test_a_bank_without_a_compiler_steps_in_python_with_the_same_result(tmp_path, monkeypatch):
    with pytest.warns(RuntimeWarning, match="stepping the streams in Python"):
        assert p2_step.p2_bank_step(tmp_path, "no-such-cc") is None
    compiled = P2QuantileBank(0.9, 40)
    monkeypatch.setattr(quantile, "p2_bank_step", lambda: None)
    in_python = P2QuantileBank(0.9, 40)
    rng = np.random.default_rng(8)
    for row in np.round(rng.standard_t(3, (600, 40)), 1):
        compiled.add(row)
        in_python.add(row)
    assert compiled.values.tobytes() == in_python.values.tobytes()
    assert compiled._positions.tobytes() == in_python._positions.tobytes()


def test_bank_equals_p2_bit_for_bit_where_the_markers_differences_overflow():
    """Samples spanning most of the float range, so the markers' differences overflow and the
    steps fall back to their convex combinations."""
    rng = np.random.default_rng(9)
    samples = rng.choice([-1.0, 1.0], (800, 12)) * 1.7e308 * rng.uniform(0.5, 1.0, (800, 12))
    samples[rng.uniform(size=samples.shape) < 0.3] = 0.5
    bank, scalars = P2QuantileBank(0.6, 12), [P2Quantile(0.6) for _ in range(12)]
    for row in samples:
        bank.add(row)
        for scalar, sample in zip(scalars, row.tolist(), strict=True):
            scalar.add(sample)
    assert np.isfinite(bank.values).all()
    assert bank.values.tobytes() == np.array([s.value for s in scalars]).tobytes()


@pytest.mark.parametrize("compiled", [True, False])
@pytest.mark.parametrize("at", [2, 5, 40])
def test_a_row_with_one_non_finite_sample_changes_nothing(compiled, at, monkeypatch):
    """A row with one NaN or infinity among finite samples is skipped whole, in the first five samples
    and past them (where the compiled step checks it), with C and in Python: the bank then goes on
    as one that never saw the row, to the bit."""
    if not compiled:
        monkeypatch.setattr(quantile, "p2_bank_step", lambda: None)
    rng = np.random.default_rng(at)
    rows = rng.normal(size=(60, 9))
    bank, clean = P2QuantileBank(0.9, 9), P2QuantileBank(0.9, 9)
    for k, row in enumerate(rows):
        if k == at:
            for bad in (math.nan, math.inf, -math.inf):
                spoiled = row.copy()
                spoiled[k % 9] = bad
                bank.add(spoiled)
                assert bank.count == clean.count
        bank.add(row)
        clean.add(row)
    assert bank.count == clean.count == len(rows)
    assert bank.values.tobytes() == clean.values.tobytes()
    assert bank._positions.tobytes() == clean._positions.tobytes()
