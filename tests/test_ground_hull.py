"""The compiled ground hull fit against its Python reference, bit for bit."""

from __future__ import annotations

import copy
import dataclasses
import pickle

import numpy as np
import pytest

from benchmarks.estimator_speed import synthetic_stream
from ccopt.casadi_eval import compile_source
from ccopt.estimation import Estimator, ground_hull
from ccopt.estimation.ground_cone import (
    GroundConeEstimator,
    GroundConeParams,
    compiled_hull,
    fit_ground_cone,
    half_plane_polygon,
)

PARAMS = GroundConeParams()
DIRECTIONS = GroundConeEstimator(PARAMS).directions


def cone_bytes(cone) -> tuple:
    """Every field of a ground cone, exactly (NaN and signed zeros included)."""
    return tuple(
        np.asarray(getattr(cone, field.name), dtype=float).tobytes() for field in dataclasses.fields(cone)
    )


def support_values(rng: np.random.Generator) -> np.ndarray:
    """Support values of a random hull: the largest projections of a cloud of forces in the cone's
    region (some clouds thin, some a single force, some with a ragged margin added, as a quantile's
    support values have)."""
    count = int(rng.integers(1, 60))
    scale = rng.uniform(0.05, 30.0)
    forces = rng.normal(0.0, 1.0, (count, 2)) * scale * rng.uniform(0.05, 1.0, 2) + (0.0, -rng.uniform(0, 20))
    support = (DIRECTIONS @ forces.T).max(axis=1)
    if rng.uniform() < 0.5:
        support += rng.uniform(0.0, 0.05 * scale, support.shape)
    return support


def special_support_values() -> list[np.ndarray]:
    """Degenerate hulls: a point, circles (every pair of edges as long), a segment (zero width),
    non-finite values and corners that overflow."""
    angles = np.arctan2(DIRECTIONS[:, 1], DIRECTIONS[:, 0])
    segment = np.abs(5.0 * DIRECTIONS[:, 0])
    values = [np.zeros(64), np.full(64, 3.0), np.full(64, 100.0), segment, np.full(64, 1.797e308)]
    values.append(np.abs(np.cos(angles)) * 1e307)
    for bad in (np.nan, np.inf, -np.inf):
        broken = np.full(64, 3.0)
        broken[17] = bad
        values.append(broken)
    return values


@pytest.fixture(scope="module")
def hull():
    found = compiled_hull(DIRECTIONS, PARAMS)
    assert found is not None, "no C compiler: the compiled hull is not tested"
    return found


def test_the_compiled_fit_is_the_python_fit_bit_for_bit(hull):
    rng = np.random.default_rng(3)
    cases = [support_values(rng) for _ in range(3000)] + special_support_values()
    fitted = 0
    for support in cases:
        for count in (1, PARAMS.min_samples):
            reference = fit_ground_cone(DIRECTIONS, support, PARAMS, count)
            ours = fit_ground_cone(DIRECTIONS, support, PARAMS, count, hull)
            assert cone_bytes(ours) == cone_bytes(reference)
            fitted += sum(reference.fitted)
        if np.isfinite(support).all() and hull.faces(support) is not None:
            assert hull.polygon() == half_plane_polygon(DIRECTIONS, support)
    assert fitted > 1000  # the faces themselves are compared, not only the prior rows


def test_an_estimator_with_the_compiled_fit_estimates_as_one_fitting_in_python():
    """A stream that explores both cones, pivots and slides: every field of every estimate equal."""
    times, poses, wrenches, _ = synthetic_stream(6000, seed=2)
    compiled, python = Estimator(), Estimator()
    python.ground._hull = None
    assert compiled.ground._hull is not None
    for time, pose, wrench in zip(times, poses, wrenches, strict=True):
        ours, theirs = compiled.update(time, pose, wrench), python.update(time, pose, wrench)
        for field in dataclasses.fields(ours):
            a, b = getattr(ours, field.name), getattr(theirs, field.name)
            assert pickle.dumps(a) == pickle.dumps(b), (time, field.name)
    assert ours.row_valid.all() and all(ours.ground_fitted)


@pytest.mark.parametrize("duplicate", [copy.deepcopy, lambda owner: pickle.loads(pickle.dumps(owner))])
def test_a_copied_ground_hull_fits_with_buffers_of_its_own(duplicate):
    """The original and its copy, fed different forces in turn, each fit as an estimator fitting in
    Python fed the same history: neither reads the other's support values."""
    rng = np.random.default_rng(5)
    original, in_python = GroundConeEstimator(), GroundConeEstimator()
    in_python._hull = None
    for k in range(300):
        force = rng.normal((0.0, -10.0), 3.0)
        original.update(k * PARAMS.sample_interval, force)
        in_python.update(k * PARAMS.sample_interval, force)
    twin, twin_in_python = duplicate(original), copy.deepcopy(in_python)
    assert twin._hull is not None and twin._hull is not original._hull
    for k in range(300, 500):
        time = k * PARAMS.sample_interval
        ours, theirs = rng.normal((2.0, -10.0), 3.0), rng.normal((-2.0, -12.0), 4.0)
        original.update(time, ours)
        in_python.update(time, ours)
        twin.update(time, theirs)
        twin_in_python.update(time, theirs)
        assert cone_bytes(original.cone) == cone_bytes(in_python.cone)
        assert cone_bytes(twin.cone) == cone_bytes(twin_in_python.cone)
    assert cone_bytes(twin.cone) != cone_bytes(original.cone)


def test_without_a_compiler_the_hull_is_fitted_in_python_with_a_warning(tmp_path):
    with pytest.warns(RuntimeWarning, match="fitting it in Python"):
        assert ground_hull._function(tmp_path, "no-such-cc") is None


def test_a_source_that_does_not_compile_raises_naming_it(tmp_path):
    with pytest.raises(RuntimeError, match="compiling broken failed"):
        compile_source("broken", "int f( {", tmp_path)
    library, hit = compile_source("fine", "int f(void) { return 1; }", tmp_path)
    assert library.exists() and not hit
    assert compile_source("fine", "int f(void) { return 1; }", tmp_path) == (library, True)
