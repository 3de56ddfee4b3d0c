"""Ground friction hull against the contact model's ground rows (horizontal and tilted ground)."""

from __future__ import annotations

import collections
import math

import numpy as np
import pytest

from ccopt import contact, geometry
from ccopt.estimation.ground_cone import (
    FACE_COSINE_RANGE,
    FACE_WINDOW_STEPS,
    GroundCone,
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
    same) or moved without moving the rows, and otherwise fits anew: either way the cone is
    ``fit_ground_cone`` of the current values."""
    params = GroundConeParams(min_samples=40)
    estimator = GroundConeEstimator(params)
    samples = forces(0.8, 0.3, 0.0, 400, (1, -1), np.random.default_rng(7))
    unmoved = kept = refitted = 0
    for k, force in enumerate(samples):
        before, values_before = estimator.cone, estimator._support.values.tobytes()
        estimator.update(k * INTERVAL, force)
        cone = estimator.refit()
        support, count = estimator._support.values, estimator.sample_count
        assert same_cone(cone, fit_ground_cone(estimator.directions, support, params, count))
        moved = support.tobytes() != values_before
        unmoved += cone is before and not moved
        kept += cone is before and moved
        refitted += cone is not before
        assert estimator.refit() is cone  # nothing changed since
    assert unmoved > 0 and kept > 0 and refitted > 0


Row2 = tuple[tuple[float, float], float, float]


def _reference_fit(
    directions: np.ndarray, support: np.ndarray, params: GroundConeParams, sample_count: int
) -> GroundCone:
    """``fit_ground_cone`` as first written (edges, candidates and prior rows per fit, each a plain
    loop over the whole polygon, on :func:`_straightforward_half_plane_polygon`): the reference of
    its optimised form, which must give the same cone bit for bit (closed-loop runs stay the same)."""
    rows, valid, fitted = _reference_prior_rows([(0.0, 0.0)], params.mu_prior), False, (False, False)
    if sample_count > 0 and np.isfinite(support).all():
        active, vertices = _straightforward_half_plane_polygon(directions, support)
        if math.isfinite(sum([x + y for x, y in vertices])):
            fit = _reference_rows(directions[active].tolist(), vertices, len(directions), params)
            if math.isfinite(sum(normal[0] + normal[1] + offset for normal, offset, _ in fit[0])):
                rows, valid, fitted = fit[0], sample_count >= params.min_samples, fit[1]
    return _reference_cone(rows, valid, fitted)


def _reference_rows(
    normals: list[list[float]], vertices: list[tuple[float, float]], count: int, params: GroundConeParams
) -> tuple[list[Row2], tuple[bool, bool]]:
    rows = _reference_prior_rows(vertices, params.mu_prior)
    starts = [vertices[-1], *vertices[:-1]]
    edges = [(nx, ny, math.dist(s, e)) for (nx, ny), s, e in zip(normals, starts, vertices, strict=True)]
    fitted = [False, False]
    for index, side in enumerate((1.0, -1.0)):
        face = _reference_face(edges, vertices, side, FACE_WINDOW_STEPS * 2.0 * math.pi / count)
        if face is not None and face[2] >= params.min_face_length:
            rows[index], fitted[index] = face, True
    return rows, (fitted[0], fitted[1])


def _reference_prior_rows(vertices: list[tuple[float, float]], mu_prior: float) -> list[Row2]:
    (up_x, up_y), scale, rows = geometry.WORLD_UP, math.hypot(1.0, mu_prior), []
    for side in (1.0, -1.0):
        normal = ((side * up_y + mu_prior * up_x) / scale, (-side * up_x + mu_prior * up_y) / scale)
        rows.append((normal, max([normal[0] * x + normal[1] * y for x, y in vertices]), 0.0))
    return rows


def _reference_face(
    edges: list[tuple[float, float, float]], vertices: list[tuple[float, float]], side: float, window: float
) -> Row2 | None:
    (up_x, up_y), (low, high) = geometry.WORLD_UP, FACE_COSINE_RANGE
    right_x, right_y = side * up_y, -side * up_x
    candidate = [
        nx * right_x + ny * right_y > 0.0 and low <= nx * up_x + ny * up_y <= high for nx, ny, _ in edges
    ]
    count, best, first = len(edges), 0.0, -1
    for index in range(count):
        following = (index + 1) % count
        if candidate[index] and candidate[following] and edges[index][2] + edges[following][2] > best:
            best, first = edges[index][2] + edges[following][2], index
    seed = _reference_chord(vertices[first - 1], vertices[(first + 1) % count]) if first >= 0 else None
    if seed is None:
        return None

    def extends(index: int) -> bool:
        nx, ny, _ = edges[index % count]
        return candidate[index % count] and nx * seed[0][0] + ny * seed[0][1] >= math.cos(window)

    start, end = first, first + 1
    while end - start < count - 1 and extends(end + 1):
        end += 1
    while end - start < count - 1 and extends(start - 1):
        start -= 1
    ends = (vertices[(start - 1) % count], vertices[end % count])
    row = _reference_chord(*ends)
    if row is not None and row[1] < 0.0:  # through the origin, about the far end
        start_point, end_point = ends
        if math.hypot(*start_point) <= math.hypot(*end_point):
            turned = _reference_chord((0.0, 0.0), end_point)
        else:
            turned = _reference_chord(start_point, (0.0, 0.0))
        row = None if turned is None else (turned[0], 0.0, math.dist(start_point, end_point))
    return row if row is not None and low <= row[0][0] * up_x + row[0][1] * up_y <= high else None


def _reference_chord(start: tuple[float, float], end: tuple[float, float]) -> Row2 | None:
    (sx, sy), (ex, ey) = start, end
    length = math.hypot(ex - sx, ey - sy)
    if length == 0.0:
        return None
    normal = ((ey - sy) / length, (sx - ex) / length)
    return normal, normal[0] * sx + normal[1] * sy, length


def _reference_cone(rows: list[Row2], valid: bool, fitted: tuple[bool, bool]) -> GroundCone:
    mu_g, apex, up = math.nan, np.full(2, np.nan), geometry.WORLD_UP
    (ax, ay), (cx, cy) = rows[0][0], rows[1][0]
    axis = math.hypot(ax + cx, ay + cy)
    half_angle = 0.5 * math.acos(max(-1.0, min(1.0, ax * cx + ay * cy)))
    if all(fitted) and axis > 0.0 and half_angle > 0.0:
        up = ((ax + cx) / axis, (ay + cy) / axis)
        mu_g = 1.0 / math.tan(half_angle)
        det = ax * cy - ay * cx
        if det != 0.0:
            (_, b_pos, _), (_, b_neg, _) = rows
            apex = np.array([(cy * b_pos - ay * b_neg) / det, (ax * b_neg - cx * b_pos) / det])
    normals, offsets = np.array([row[0] for row in rows]), np.array([row[1] for row in rows])
    return GroundCone(normals, offsets, valid, fitted, mu_g, apex, np.array(up))


def _directions(count: int, rng: np.random.Generator | None = None) -> np.ndarray:
    """``count`` directions by ascending angle: evenly spaced, or jittered by up to a third of a step."""
    steps = np.arange(count) + (rng.uniform(-1 / 3, 1 / 3, count) if rng is not None else 0.0)
    angles = 2.0 * np.pi * steps / count
    return np.column_stack((np.cos(angles), np.sin(angles)))


def _support_cases(directions: np.ndarray, rng: np.random.Generator, trials: int) -> list[np.ndarray]:
    """Support values of every kind a fit can meet: cone-like hand forces (their quantiles, as the
    estimator's: lines dropped, faces fitted), point clouds (true support functions), with noise,
    rounding (concurrent lines), loose lines, a hull with a corner at the origin or a segment through
    it (zero products), a regular polygon, huge and tiny values (corners overflow or underflow), an
    empty intersection, and NaN or infinite values."""
    cases = []
    for trial in range(trials):
        kind = trial % 9
        if kind <= 2:  # the estimator's: a high quantile of noisy hand forces with outliers
            sides = ((1, -1), (1,), (-1,))[kind]
            samples = forces(
                rng.uniform(0.3, 1.2), rng.uniform(0.1, 0.5), rng.uniform(-0.2, 0.2), 300, sides, rng
            )
            cases.append(np.quantile(samples @ directions.T, 0.985, axis=0))
            continue
        scale, shift = rng.uniform(0.1, 20.0, 2), rng.normal(0.0, 5.0, 2)
        points = rng.normal(size=(int(rng.integers(1, 40)), 2)) * scale + shift
        support = np.max(points @ directions.T, axis=0)
        if kind == 4:
            support = support + rng.normal(0.0, 0.3, len(support))
        elif kind == 5:
            support = np.round(support, 1)
        elif kind == 6:
            loose = rng.integers(len(support), size=int(rng.integers(1, 4)))
            support[loose] += rng.uniform(0.5, 1e3, len(loose))
        elif kind == 7:  # zero products: a narrow cone below the origin; a segment through it
            below = np.column_stack((0.05 * np.tanh(points[:, 0]), -1.0 - np.abs(points[:, 1])))
            support = np.max(np.vstack([[0.0, 0.0], below]) @ directions.T, axis=0)
            if trial // 9 % 3 == 1:
                support = np.abs(directions @ rng.normal(size=2))
            elif trial // 9 % 3 == 2:  # a regular polygon
                support = np.full(len(directions), rng.uniform(1.0, 9.0))
        elif kind == 8:  # corners that overflow or underflow, an empty intersection, non-finite values
            support = support * (1e306, 1e-300, -1.0, 1.0)[trial // 9 % 4] - (trial // 9 % 4 == 2)
            if trial // 9 % 4 == 3:
                support[rng.integers(len(support))] = (np.nan, np.inf, -np.inf)[trial % 3]
        cases.append(support)
    return cases


@pytest.mark.parametrize(("count", "jitter"), [(4, False), (8, False), (9, True), (64, False), (64, True)])
def test_fit_is_the_reference_fit_bit_for_bit(count, jitter):
    """Every kind of support values (:func:`_support_cases`), every sample count regime and two
    parameter sets: the same cone as the reference, bit for bit; the cases cover dropped lines,
    fitted faces on both sides, the prior before any force and the fallback of a hull beyond floats."""
    rng = np.random.default_rng(count + jitter)
    directions = _directions(count, rng if jitter else None)
    if count == 4:  # exactly parallel opposite lines
        directions = np.array([[1.0, 0.0], [0.0, 1.0], [-1.0, 0.0], [0.0, -1.0]])
    seen = collections.Counter()
    for trial, support in enumerate(_support_cases(directions, rng, 450)):
        params = GroundConeParams(min_face_length=(3.0, 0.5)[trial % 2], mu_prior=(0.1, 0.6)[trial % 3 // 2])
        sample_count = (0, 1, 199, 200, 10_000)[trial % 5]
        cone = fit_ground_cone(directions, support, params, sample_count)
        assert same_cone(cone, _reference_fit(directions, support, params, sample_count)), trial
        if np.isfinite(support).all():
            seen["dropped lines"] += len(half_plane_polygon(directions, support)[0]) < count
        seen["valid"] += cone.valid
        seen.update(side for side, fitted in zip(("right", "left"), cone.fitted, strict=True) if fitted)
    assert seen["valid"] >= 100 and (count == 4 or seen["dropped lines"] >= 100), seen
    if count == 64:  # fewer directions leave at most one edge within a side's face range
        assert seen["right"] >= 20 and seen["left"] >= 20, seen


def test_fit_of_point_cloud_support_is_the_reference_fit_bit_for_bit():
    """True support functions (every line touches the hull) of hand-force-like clouds — two straight
    faces below a weight — and of round ones: the same cone as the reference, bit for bit."""
    rng = np.random.default_rng(11)
    directions, params, fitted = _directions(64), GroundConeParams(), 0
    for trial in range(300):
        mu_g, weight, depth = rng.uniform(0.2, 1.5), rng.uniform(0.5, 5.0), rng.uniform(2.0, 30.0, 40)
        lateral = np.concatenate([[-1.0, 1.0], rng.uniform(-1.0, 1.0, 38)])
        points = np.column_stack((mu_g * depth * lateral, weight - depth))
        if trial % 3 == 2:
            points = rng.normal(size=(40, 2)) * rng.uniform(1.0, 10.0, 2)
        support = np.max(points @ directions.T, axis=0)
        cone = fit_ground_cone(directions, support, params, 1000)
        assert same_cone(cone, _reference_fit(directions, support, params, 1000)), trial
        fitted += all(cone.fitted)
    assert fitted >= 100


def test_every_refit_of_a_run_is_the_reference_fit_bit_for_bit():
    """The estimator's own support values (P² quantiles, refitted every 25 ms) over a run that slides
    the object both ways: every refit's cone is the reference fit of the values it saw."""
    params = GroundConeParams(min_samples=40)
    estimator = GroundConeEstimator(params)
    samples = forces(0.8, 0.3, 0.1, 3000, (1, -1), np.random.default_rng(5))
    fits = 0
    for k, force in enumerate(samples):
        before = estimator.cone
        estimator.update(k * INTERVAL, force)
        if estimator.cone is not before:
            support, count = estimator._support.values, estimator.sample_count
            assert same_cone(estimator.cone, _reference_fit(estimator.directions, support, params, count)), k
            fits += 1
    assert fits > 100 and all(estimator.cone.fitted)


def test_ties_between_seed_pairs_go_to_the_first_as_in_the_reference():
    """Hulls mirror-symmetric about the 45° line, on directions that the mirror maps onto each other
    exactly: the two longest pairs of right face candidates are often equally long to the bit, and
    the fit seeds on the first, as the reference does."""
    count = 32
    eighth = [(math.cos(angle), math.sin(angle)) for angle in 2.0 * np.pi * np.arange(count // 8) / count]
    diagonal = math.cos(math.pi / 4.0)
    turns = [np.array([*eighth, (diagonal, diagonal), *[(y, x) for x, y in reversed(eighth[1:])]])]
    for _ in range(3):  # quarter turns
        turns.append(np.column_stack((-turns[-1][:, 1], turns[-1][:, 0])))
    directions = np.vstack(turns)
    rng, params, ties = np.random.default_rng(2), GroundConeParams(min_face_length=0.1), 0
    low, high = FACE_COSINE_RANGE
    for trial in range(200):
        points = rng.normal(size=(6, 2)) * 5.0
        points = np.vstack([points, points[:, ::-1]])
        support = (points[:, :1] * directions[:, 0] + points[:, 1:] * directions[:, 1]).max(axis=0)
        cone = fit_ground_cone(directions, support, params, 1000)
        assert same_cone(cone, _reference_fit(directions, support, params, 1000)), trial
        active, vertices = half_plane_polygon(directions, support)
        lengths = [math.dist(vertices[i - 1], vertices[i]) for i in range(len(active))]
        right = [x > 0.0 and low <= y <= high for x, y in directions[active]]
        pairs = [lengths[i - 1] + lengths[i] for i in range(1, len(active)) if right[i - 1] and right[i]]
        ties += len(pairs) > 1 and pairs.count(max(pairs)) > 1
    assert ties >= 20
