"""Ground friction hull against the contact model's ground rows (horizontal and tilted ground)."""

from __future__ import annotations

import collections
import math

import numpy as np
import pytest

from ccopt import contact, geometry
from ccopt.estimation.ground_cone import (
    GroundConeEstimator,
    GroundConeParams,
    fit_ground_cone,
    half_plane_polygon,
)

NOISE = 0.3  # N
INTERVAL = GroundConeParams().sample_interval


def true_rows(mu_g: float, mass: float, tilt: float) -> tuple[np.ndarray, np.ndarray]:
    """Unit-normal ground rows (world) of the model: the horizontal rows, in a ground frame turned by
    ``tilt`` (the weight seen from that frame is ``R(−tilt) f_grav``)."""
    to_ground = geometry.rotation(tilt).T
    a_ground, b = contact.ground_rows_world(mu_g, to_ground @ contact.weight(mass))
    rows, b = np.array(a_ground) @ to_ground, np.array(b).ravel()
    norms = np.linalg.norm(rows, axis=1)
    return rows / norms[:, None], b / norms


def forces(
    mu_g: float, mass: float, tilt: float, count: int, sides: tuple[int, ...], rng: np.random.Generator
) -> np.ndarray:
    """World hand forces inside the true cone, 15 % on each face in ``sides`` (+1 right, −1 left),
    with noise and 1 % outliers. In the ground frame ``F = f + f_grav = (x, −t)`` with ``|x| ≤ μ_g t``."""
    to_world = geometry.rotation(tilt)
    apex = -(to_world.T @ contact.weight(mass))
    depth = rng.uniform(mass * geometry.GRAVITY + 1.0, mass * geometry.GRAVITY + 20.0, count)
    lateral = rng.uniform(-0.95, 0.95, count)
    pick = rng.uniform(size=count)
    for index, side in enumerate(sides):
        lateral[(pick >= 0.15 * index) & (pick < 0.15 * (index + 1))] = side
    clean = (apex + np.column_stack((mu_g * depth * lateral, -depth))) @ to_world.T
    rows, b = true_rows(mu_g, mass, tilt)
    assert np.all(clean @ rows.T <= b + 1e-9)
    noisy = clean + rng.normal(0.0, NOISE, clean.shape)
    outliers = rng.uniform(size=count) < 0.01
    noisy[outliers] = rng.uniform(-40.0, 40.0, (outliers.sum(), 2))
    return noisy


def run(samples: np.ndarray, params: GroundConeParams | None = None) -> GroundConeEstimator:
    estimator = GroundConeEstimator(params)
    for k, force in enumerate(samples):
        estimator.update(k * INTERVAL, force)
    estimator.refit()
    return estimator


def face_slopes(rows: np.ndarray, tilt: float) -> np.ndarray:
    """``μ`` of each row's face measured from the ground: ``(a·n_g)/|a·t_g|``."""
    tangent, normal = geometry.rotation(tilt) @ [1.0, 0.0], geometry.rotation(tilt) @ [0.0, 1.0]
    return (rows @ normal) / np.abs(rows @ tangent)


@pytest.mark.parametrize(
    ("mu_g", "mass", "tilt_deg"), [(0.8, 0.3, 0.0), (0.5, 0.45, 10.0), (0.8, 0.25, -15.0), (1.0, 0.4, 5.0)]
)
def test_faces_within_five_percent_slope_and_one_newton(mu_g, mass, tilt_deg):
    tilt = math.radians(tilt_deg)
    rng = np.random.default_rng(int(100 * mu_g + tilt_deg))
    cone = run(forces(mu_g, mass, tilt, 10_000, (1, -1), rng)).cone
    _, b = true_rows(mu_g, mass, tilt)
    assert cone.valid and cone.fitted == (True, True)
    np.testing.assert_allclose(face_slopes(cone.A, tilt), mu_g, rtol=0.05)
    np.testing.assert_allclose(cone.b, b, atol=1.0)
    np.testing.assert_allclose(np.linalg.norm(cone.A, axis=1), 1.0)
    assert cone.mu_g == pytest.approx(mu_g, rel=0.05)
    apex = -contact.weight(mass)
    assert np.linalg.norm(cone.apex - apex) < 1.0
    assert cone.up @ (geometry.rotation(tilt) @ [0.0, 1.0]) > math.cos(math.radians(3.0))


def test_an_unexplored_side_gets_a_conservative_row():
    rng = np.random.default_rng(7)
    samples = forces(0.8, 0.3, 0.0, 6000, (1,), rng)
    cone = run(samples).cone
    assert face_slopes(cone.A[:1], 0.0) == pytest.approx(0.8, rel=0.05)
    assert face_slopes(cone.A[1:], 0.0)[0] < 0.8  # the sticking data's edge: inside the true face
    assert np.mean(samples @ cone.A[1] > cone.b[1] + 3 * NOISE) < 0.01


def test_the_hulls_top_is_not_a_friction_face_after_a_slide_one_way():
    # a steady 10 N press at ±25° (the hull's flat top), then a push that slides the object to the
    # right along its true face: the data's centroid moves right, but only the right face is fitted
    mu_g, mass = 0.5, 0.15
    rng = np.random.default_rng(3)
    angle = rng.uniform(-0.44, 0.44, 3000)
    press = 10.0 * np.column_stack([np.sin(angle), -np.cos(angle)])
    depth = rng.uniform(12.0, 18.0, 1500)
    slide = -contact.weight(mass) + np.column_stack([mu_g * depth, -depth])
    samples = np.vstack([press, slide]) + rng.normal(0.0, NOISE, (4500, 2))
    cone = run(samples).cone
    assert cone.fitted == (True, False)
    assert face_slopes(cone.A[:1], 0.0)[0] == pytest.approx(mu_g, rel=0.05)
    assert cone.b[0] == pytest.approx(true_rows(mu_g, mass, 0.0)[1][0], abs=1.0)
    assert face_slopes(cone.A[1:], 0.0)[0] < mu_g  # the sticking data's edge (or the prior): inside


def test_before_enough_data_rows_are_conservative_and_invalid():
    estimator = GroundConeEstimator()
    cone = estimator.cone
    assert not cone.valid and cone.fitted == (False, False) and math.isnan(cone.mu_g)
    np.testing.assert_allclose(cone.b, 0.0)
    assert cone.A[0] @ [1.0, 0.0] > 0.0 > cone.A[1] @ [1.0, 0.0]
    samples = forces(0.8, 0.3, 0.0, 50, (), np.random.default_rng(1))
    estimator = run(samples)
    assert not estimator.cone.valid
    inside = samples @ estimator.cone.A.T <= estimator.cone.b + 1e-9
    assert inside.mean() > 0.8


def test_forces_are_taken_at_most_once_per_sample_interval():
    estimator = GroundConeEstimator(GroundConeParams(sample_interval=0.004, refit_interval=0.05))
    for k in range(1000):
        estimator.update(k * 1e-3, np.array([0.0, -5.0]))
    assert estimator.sample_count == 250
    estimator.update(0.0, np.array([np.nan, 1.0]))  # time went back: offered, but not finite
    assert estimator.sample_count == 250


def test_half_plane_polygon_of_exact_support_values_is_the_outer_hull():
    rng = np.random.default_rng(3)
    points = rng.normal(size=(40, 2)) * [3.0, 1.0]
    angles = 2.0 * np.pi * np.arange(64) / 64
    directions = np.column_stack((np.cos(angles), np.sin(angles)))
    support = np.max(points @ directions.T, axis=0)
    active, vertices = half_plane_polygon(directions, support)
    vertices = np.array(vertices)
    assert np.all(points @ directions.T <= support + 1e-12)  # points inside every half-plane
    assert np.all(vertices @ directions.T <= support + 1e-9)  # vertices inside every half-plane
    on_lines = vertices @ directions[active].T - support[active]
    np.testing.assert_allclose(np.diag(on_lines), 0.0, atol=1e-9)
    np.testing.assert_allclose(np.diag(np.roll(on_lines, -1, axis=1)), 0.0, atol=1e-9)
    hull_area = abs(geometry.signed_area(points[_hull(points)]))
    assert hull_area <= geometry.signed_area(vertices) <= 1.05 * hull_area


def test_half_plane_polygon_drops_lines_that_do_not_touch():
    angles = 2.0 * np.pi * np.arange(8) / 8
    directions = np.column_stack((np.cos(angles), np.sin(angles)))
    support = np.array([1.0, 5.0, 1.0, 5.0, 1.0, 5.0, 1.0, 5.0])  # a square; the diagonals are loose
    active, vertices = half_plane_polygon(directions, support)
    assert active == [0, 2, 4, 6]
    np.testing.assert_allclose(vertices, [[1.0, 1.0], [-1.0, 1.0], [-1.0, -1.0], [1.0, -1.0]], atol=1e-12)


def _straightforward_half_plane_polygon(
    directions: np.ndarray, support: np.ndarray
) -> tuple[list[int], list[tuple[float, float]]]:
    """The sorted-angle deque sweep as first written (a corner function, the tests in the loop
    conditions): the reference of :func:`half_plane_polygon`'s inlined sweep."""
    ux, uy, h = directions[:, 0].tolist(), directions[:, 1].tolist(), support.tolist()

    def corner(i: int, j: int) -> tuple[float, float]:
        det = ux[i] * uy[j] - uy[i] * ux[j]
        if det == 0.0:
            return math.nan, math.nan
        return (uy[j] * h[i] - uy[i] * h[j]) / det, (ux[i] * h[j] - ux[j] * h[i]) / det

    def outside(k: int, point: tuple[float, float]) -> bool:
        return ux[k] * point[0] + uy[k] * point[1] > h[k]

    lines, corners = collections.deque(), collections.deque()
    for k in range(len(h)):
        while corners and outside(k, corners[-1]):
            lines.pop()
            corners.pop()
        while corners and outside(k, corners[0]):
            lines.popleft()
            corners.popleft()
        if lines:
            corners.append(corner(lines[-1], k))
        lines.append(k)
    while len(corners) >= 2 and outside(lines[0], corners[-1]):
        lines.pop()
        corners.pop()
    while len(corners) >= 2 and outside(lines[-1], corners[0]):
        lines.popleft()
        corners.popleft()
    corners.append(corner(lines[-1], lines[0]))
    return list(lines), list(corners)


@pytest.mark.parametrize("count", [4, 8, 9, 64])
def test_half_plane_polygon_is_the_straightforward_sweep_bit_for_bit(count):
    """Random hulls and degenerate ones (a point or a segment: concurrent lines, support values
    equal to the last bit, noise on them; with exact axes, loose lines that leave parallel ones
    adjacent), the same lines and corners to the bit."""
    rng = np.random.default_rng(count)
    angles = 2.0 * np.pi * np.arange(count) / count
    directions = np.column_stack((np.cos(angles), np.sin(angles)))
    if count == 4:  # exactly parallel opposite lines
        directions = np.array([[1.0, 0.0], [0.0, 1.0], [-1.0, 0.0], [0.0, -1.0]])
    for trial in range(300):
        points = rng.normal(size=(1 + trial % 7 if trial % 3 else 30, 2)) * rng.uniform(0.1, 10.0, 2)
        support = np.max(points @ directions.T, axis=0)
        if trial % 4 == 1:
            support = support + rng.normal(0.0, 0.05, count)
        elif trial % 4 == 2:
            support = np.round(support, 1)
        elif trial % 8 == 3:
            support[rng.integers(count)] = 1e3  # a loose line
        active, vertices = half_plane_polygon(directions, support)
        expected_active, expected_vertices = _straightforward_half_plane_polygon(directions, support)
        assert active == expected_active
        assert np.array(vertices).tobytes() == np.array(expected_vertices).tobytes()


def test_fit_without_finite_support_is_the_prior():
    params = GroundConeParams(mu_prior=0.2)
    cone = fit_ground_cone(np.eye(2), np.array([np.nan, 1.0]), params, 10)
    np.testing.assert_allclose(cone.A, [[1.0, 0.2], [-1.0, 0.2]] / np.hypot(1.0, 0.2))
    assert not cone.A.flags.writeable


@pytest.mark.parametrize(
    ("field", "value", "error"),
    [
        ("directions", 4, ValueError),
        ("directions", 64.0, TypeError),
        ("level", 1.0, ValueError),
        ("min_samples", 0, ValueError),
        ("min_face_length", -1.0, ValueError),
        ("mu_prior", 0.0, ValueError),
        ("sample_interval", -0.1, ValueError),
        ("refit_interval", math.inf, ValueError),
    ],
)
def test_bad_parameters_raise_naming_the_field(field, value, error):
    with pytest.raises(error, match=field):
        GroundConeParams(**{field: value})


def _hull(points: np.ndarray) -> list[int]:
    """Indices of the convex hull of ``points``, counter-clockwise (monotone chain)."""
    order = sorted(range(len(points)), key=lambda i: (points[i][0], points[i][1]))

    def chain(indices: list[int]) -> list[int]:
        out: list[int] = []
        for i in indices:
            while len(out) >= 2:
                (ax, ay), (bx, by) = points[out[-1]] - points[out[-2]], points[i] - points[out[-2]]
                if ax * by - ay * bx > 0.0:
                    break
                out.pop()
            out.append(i)
        return out[:-1]

    return chain(order) + chain(order[::-1])


def same_cone(a, b) -> bool:
    """Whether two cones hold the same values bit for bit (NaN equal to NaN)."""
    arrays = ("A", "b", "apex", "up")
    same_arrays = all(getattr(a, name).tobytes() == getattr(b, name).tobytes() for name in arrays)
    same_mu = np.float64(a.mu_g).tobytes() == np.float64(b.mu_g).tobytes()
    return same_arrays and same_mu and (a.valid, a.fitted) == (b.valid, b.fitted)


def test_every_refit_is_the_fit_of_the_support_values_it_sees():
    """A refit keeps the last cone while the support values did not move (the fit's inputs are the
    same), and otherwise fits anew: either way the cone is ``fit_ground_cone`` of the current values."""
    params = GroundConeParams(min_samples=40)
    estimator = GroundConeEstimator(params)
    samples = forces(0.8, 0.3, 0.0, 400, (1, -1), np.random.default_rng(7))
    kept = refitted = 0
    for k, force in enumerate(samples):
        before = estimator.cone
        estimator.update(k * INTERVAL, force)
        cone = estimator.refit()
        support, count = estimator._support.values, estimator.sample_count
        assert same_cone(cone, fit_ground_cone(estimator.directions, support, params, count))
        kept += cone is before
        refitted += cone is not before
        assert estimator.refit() is cone  # nothing changed since
    assert kept > 0 and refitted > 0
