"""Ground friction constraints from an online convex hull of the hand force (paper §IV-A).

The ground rows of the generalized friction cone (:data:`ccopt.contact.ground_rows_world`) are two
half-planes ``a·f ≤ b`` on the world hand force ``f = (f_x, f_y)``: with ``F = f + f_grav`` the
object's net force, the ground blocks sliding while ``F·t_g + μ_g F·n_g ≤ 0`` and
``−F·t_g + μ_g F·n_g ≤ 0`` (``t_g``, ``n_g`` the ground tangent and upward normal). The mass is unknown,
so the rows are learned directly in force space: a cone opening downwards (towards ``−n_g``) with its
apex at ``−f_grav = (0, m g)``, whose right face (outward normal ``∝ t_g + μ_g n_g``) is the row
``GROUND_SLIDE_POS`` and left face (``∝ −t_g + μ_g n_g``) is ``GROUND_SLIDE_NEG``.

Every measured hand force satisfies both rows, so the convex hull of the measurements is a
conservative (inner) estimate of the cone. It is tracked through its support values
``h_k = quantile_p(u_k·f)`` in ``K`` fixed directions ``u_k`` (streaming P², so a few outliers do
not inflate it). A fit every ``refit_interval`` then

1. intersects the half-planes ``u_k·f ≤ h_k`` (dropping those that do not touch the polygon);
2. on each side of world "up" (against gravity, which the robot knows), finds the friction face:
   a straight face of the hull with outward normal ``ν`` is cut by the sampled directions into two
   polygon edges (those of the two directions around ``ν``), so the face is the longest pair of
   consecutive edges whose normals both point to that side, neither nearly up (the hull's top,
   where the hand force is smallest) nor down (its bottom, :data:`FACE_COSINE_RANGE`); the face
   grows over neighbouring edges of the same kind and direction, and its chord (first vertex to
   last) gives the row; a chord that crosses "up" below the origin, where no friction face can
   (the apex is the weight reversed), turns about its far end through the origin
   (:func:`_through_origin`).

World up, not a direction estimated from the data, tells the faces from the hull's top: the hull's
centroid (an earlier choice) moves towards wherever the hand has pushed most, and after a slide one
way its top then passed for a friction face (measured on a plant recording: 14 % of the ground
sliding samples reported sticking; 0 % with world up). A tilted ground turns the faces and the top
with it, so the ground's tilt must stay well inside the 15° that separate a face from the top
(tested to 15°; a ground tilted further than its friction angle cannot hold the object anyway).

The polygon and the face search, the fit's data-dependent loops, run in C written for them
(:mod:`.ground_hull`), bit for bit the Python here, which stays the reference and the fallback
where no C compiler works.

Rows are returned with unit normals ``a`` (so ``b − a·f`` is the distance to the face in N) in the
order of :data:`ccopt.contact.GROUND_ROWS`. They are *valid* once ``min_samples`` forces have been
seen. A side whose longest pair is shorter than ``min_face_length`` (no sliding seen that way yet)
gets a conservative row instead, with the prior friction slope ``μ_prior`` about "up", touching the
hull. ``μ_g`` follows from the angle between fitted faces: ``μ_g = cot(∠(a₊, a₋)/2)``, whatever
the ground's tilt, and their intersection (the apex) is the object's weight reversed.
"""

from __future__ import annotations

import functools
import itertools
import math
import struct
from bisect import bisect_left, bisect_right
from collections import deque
from dataclasses import dataclass

import numpy as np

from ccopt.clock import interval_passed
from ccopt.estimation import ground_hull
from ccopt.estimation.ground_hull import CompiledHull
from ccopt.estimation.quantile import P2QuantileBank, check_count, check_level, check_number
from ccopt.estimation.records import record
from ccopt.geometry import WORLD_UP

FACE_COSINE_RANGE = (math.sin(math.radians(3.0)), math.cos(math.radians(15.0)))
"""``up·ν`` of a friction face's outward normal ``ν``: it is ``sin(atan μ_g − α)`` on a ground tilted
by ``α`` towards that side, positive on any ground that holds the object at rest (``α < atan μ_g``):
pressing down never lets a ground contact slide sooner. Faces within 15° of "up" (μ_g > 3.7) are the
hull's top, where the force is smallest; faces within 3° of the horizontal or below it are not
friction faces but the hull's sides and bottom, where the data end (on a closed-loop recording of
the paper triangle, the edge of the hand forces of pivots at a tilted hand, ``up·ν = −0.18``, passed
for a friction face and ruled out the pivots beyond it)."""
_NO_CORNER = (math.nan, math.nan)
"""Where two parallel lines meet (:func:`half_plane_polygon`)."""
FACE_WINDOW_STEPS = 2.1
"""A face's polygon edges have normals within this many direction steps of the face's normal."""


@dataclass(frozen=True)
class GroundConeParams:
    """Parameters of the ground friction hull.

    Attributes:
        directions: number ``K`` of support directions, evenly spaced (≥ 8).
        level: quantile level of each support value. The fraction of samples above it must be
            well above the fraction of outliers beyond the hull in any direction: P² interpolates
            across the gap between data and outliers, and with 1 % outliers a level of 0.99
            occasionally put a support line several N outside the data; 0.985 never did.
        min_samples: forces seen before the rows count as estimated.
        min_face_length: shortest chord accepted as a friction face (N).
        mu_prior: friction slope of the conservative rows used before a face is seen (> 0).
        sample_interval: shortest time between two forces fed to the hull (s). The support
            quantiles need many forces, not consecutive ones: at 1 kHz neighbouring samples are
            nearly equal, and feeding one in four (4 ms) keeps the hull's cost off most updates.
        refit_interval: time between two fits of the faces (s).
    """

    directions: int = 64
    level: float = 0.985
    min_samples: int = 200
    min_face_length: float = 3.0
    mu_prior: float = 0.1
    sample_interval: float = 0.004
    refit_interval: float = 0.025

    def __post_init__(self) -> None:
        check_count("directions", self.directions, low=8)
        check_level(self.level)
        check_count("min_samples", self.min_samples)
        check_number("min_face_length", self.min_face_length)
        check_number("mu_prior", self.mu_prior)
        check_number("sample_interval", self.sample_interval, low_open=False)
        check_number("refit_interval", self.refit_interval, low_open=False)


@dataclass(frozen=True)
class GroundCone:
    """The estimated ground rows ``A f ≤ b`` on the world hand force (N), rows in ``GROUND_ROWS`` order.

    Attributes:
        A: 2×2, unit rows: ``GROUND_SLIDE_POS`` (right face), ``GROUND_SLIDE_NEG`` (left face).
        b: 2, offsets (N).
        valid: True once enough forces back the rows (both rows share it).
        fitted: per row, True if it was fitted to a long straight side of the hull — the friction
            face once the object slid that way, until then the edge of the sticking forces seen,
            which lies inside the face — and False for the conservative prior row.
        mu_g: ``cot(∠(a₊, a₋)/2)`` if both faces are fitted, else NaN (also for faces that are
            parallel or opposite: a hull of zero width tells no cone).
        apex: intersection of the two rows (N, ``(0, m g)`` for a horizontal ground) where
            ``mu_g`` is defined, else NaN.
        up: the cone's "up" direction (unit, world): the bisector of the faces' normals where
            ``mu_g`` is defined, else world up (used to tell left from right).
    """

    A: np.ndarray
    b: np.ndarray
    valid: bool
    fitted: tuple[bool, bool]
    mu_g: float
    apex: np.ndarray
    up: np.ndarray


class GroundConeEstimator:
    """Streaming ground-friction hull of the world hand force (see the module docstring)."""

    def __init__(self, params: GroundConeParams | None = None) -> None:
        self.params = params if params is not None else GroundConeParams()
        angles = 2.0 * np.pi * np.arange(self.params.directions) / self.params.directions
        self.directions = np.column_stack((np.cos(angles), np.sin(angles)))
        self._support = P2QuantileBank(self.params.level, self.params.directions)
        self._last_sample = -math.inf
        self._last_fit = -math.inf
        self._rows = _ground_rows(self.directions, np.full(self.params.directions, np.nan), self.params, 0)
        self.cone = _cone(*self._rows)
        self._fitted_to: tuple[bytes, bool, bool] | None = None  # what self.cone was fitted to
        self._hull = compiled_hull(self.directions, self.params)  # None: fitted in Python

    def __getstate__(self) -> dict:
        """The state without the compiled face search (a copy or a pickle makes its own)."""
        return {**self.__dict__, "_hull": None}

    def __setstate__(self, state: dict) -> None:
        self.__dict__.update(state)
        self._hull = compiled_hull(self.directions, self.params)

    @property
    def sample_count(self) -> int:
        """Forces accepted so far."""
        return self._support.count

    def update(self, time: float, force_world: np.ndarray) -> None:
        """Offer the world hand force ``(f_x, f_y)`` (N) measured at ``time`` (s).

        It is added if ``sample_interval`` has passed since the last force added (or time went
        back) and it is finite; the faces are refitted when ``refit_interval`` has passed.
        """
        params = self.params
        if not interval_passed(time, self._last_sample, params.sample_interval):
            return
        self._last_sample = time
        self._support.add(self.directions @ force_world)
        if interval_passed(time, self._last_fit, params.refit_interval):
            self._last_fit = time
            self.refit()

    def refit(self) -> GroundCone:
        """Fit the rows to the current support values now; returns (and stores) :attr:`cone`.

        The fit is a function of the support values and of whether any and ``min_samples`` forces
        were seen: while none of them changed (the values bit for bit: in a third to a half of the
        fits of a closed-loop run no support value moved), the last cone is the fit. Where the
        support moved but the rows did not (the values moved away from both faces: about half of
        the other fits), the last cone is kept too, the same object, so that what its users derive
        from it stays theirs (the estimator's cone rows and kinematic modes)."""
        support, count = self._support.values, self.sample_count
        fitted_to = (support.tobytes(), count > 0, count >= self.params.min_samples)
        if fitted_to != self._fitted_to:
            rows = _ground_rows(self.directions, support, self.params, count, self._hull)
            if rows != self._rows:
                self.cone, self._rows = _cone(*rows), rows
            self._fitted_to = fitted_to
        return self.cone


def fit_ground_cone(
    directions: np.ndarray,
    support: np.ndarray,
    params: GroundConeParams,
    sample_count: int,
    hull: CompiledHull | None = None,
) -> GroundCone:
    """The ground rows from support values ``support[k] = h(directions[k])`` (see the module docstring).

    Before any force, or if the hull is beyond floating point (two adjacent support lines parallel,
    a corner or a face that overflows), the rows are the conservative prior about the origin and
    not valid. ``hull``, if given (:func:`compiled_hull` of these directions and ``params``), finds the
    polygon's faces in C, bit for bit as here in Python.
    """
    return _cone(*_ground_rows(directions, support, params, sample_count, hull))


def _ground_rows(
    directions: np.ndarray,
    support: np.ndarray,
    params: GroundConeParams,
    sample_count: int,
    hull: CompiledHull | None = None,
) -> _Rows:
    """The rows of :func:`fit_ground_cone`, before they are made a :class:`GroundCone`."""
    fit = _fit_rows(directions, support, params, hull) if sample_count > 0 else None
    if fit is None:
        origin = [(0.0, 0.0)]
        right, left = (_prior_row(WORLD_UP, params.mu_prior, side, origin) for side in (1.0, -1.0))
        return (right, left), False, (False, False)
    rows, fitted = fit
    return rows, sample_count >= params.min_samples, fitted


def compiled_hull(directions: np.ndarray, params: GroundConeParams) -> CompiledHull | None:
    """The compiled face search of ``directions`` (K×2) and the prior rows of ``params``
    (:mod:`~ccopt.estimation.ground_hull`), None where no C compiler works."""
    geometry = _direction_set(directions)
    candidates = (geometry.candidates[0].of_direction, geometry.candidates[1].of_direction)
    ux, uy, cosine = geometry.ux, geometry.uy, geometry.window_cosine
    return ground_hull.compiled_hull(ux, uy, candidates, cosine, _prior_normals(params.mu_prior))


@functools.lru_cache(maxsize=8)
def _prior_normals(mu_prior: float) -> tuple[tuple[float, float], tuple[float, float]]:
    """The prior rows' normals (:func:`friction_face_normal` about world up), right then left:
    made once per ``μ_prior``, not at every fit."""
    return friction_face_normal(WORLD_UP, mu_prior, 1.0), friction_face_normal(WORLD_UP, mu_prior, -1.0)


def _fit_rows(
    directions: np.ndarray, support: np.ndarray, params: GroundConeParams, hull: CompiledHull | None
) -> tuple[tuple[Row2, Row2], tuple[bool, bool]] | None:
    """The rows (friction faces where found, else prior rows touching the hull) and which are
    faces; None unless the support values, the hull's corners and the rows are all finite."""
    normals = _prior_normals(params.mu_prior)
    found = hull.faces(support) if hull is not None else _faces(_direction_set(directions), support, normals)
    if found is None:
        return None
    (right_ends, left_ends), (right_offset, left_offset) = found
    right, right_fitted = _row(right_ends, normals[0], right_offset, params.min_face_length)
    left, left_fitted = _row(left_ends, normals[1], left_offset, params.min_face_length)
    if not math.isfinite((right[0][0] + right[0][1] + right[1]) + (left[0][0] + left[0][1] + left[1])):
        return None
    return (right, left), (right_fitted, left_fitted)


def _row(
    ends: FaceEnds | None, prior_normal: tuple[float, float], prior_offset: float, min_length: float
) -> tuple[Row2, bool]:
    """One side's row and whether it is the friction face (:func:`_face_row` of ``ends`` at least
    ``min_length`` long), else the prior row of ``prior_normal`` at ``prior_offset``."""
    face = _face_row(ends) if ends is not None else None
    if face is not None and face[2] >= min_length:
        return face, True
    return (prior_normal, prior_offset, 0.0), False


def _faces(
    geometry: _DirectionSet, support: np.ndarray, prior_normals: tuple[tuple[float, float], ...]
) -> tuple[tuple[FaceEnds | None, FaceEnds | None], tuple[float, float]] | None:
    """``((right, left) faces' ends, (right, left) offsets of the prior rows of ``prior_normals``
    touching the polygon)`` of the polygon of ``support`` (in Python what
    :meth:`CompiledHull.faces <ccopt.estimation.ground_hull.CompiledHull.faces>` does in C); None
    unless the support values and the polygon's vertices are finite."""
    if not np.isfinite(support).all():
        return None
    active, vertices = _polygon(geometry, support)
    if not math.isfinite(sum([x + y for x, y in vertices])):
        return None
    ends = tuple(_face_ends(active, vertices, geometry, candidates) for candidates in geometry.candidates)
    offsets = tuple(max([nx * x + ny * y for x, y in vertices]) for nx, ny in prior_normals)
    return (ends[0], ends[1]), (offsets[0], offsets[1])


Row2 = tuple[tuple[float, float], float, float]
"""A ground row as ``(unit normal, offset (N), face length (N))``."""
_Rows = tuple[tuple[Row2, Row2], bool, tuple[bool, bool]]
"""A fit's ``(rows (right, left), valid, fitted)``, what :func:`_cone` makes a :class:`GroundCone` of."""
FaceEnds = ground_hull.FaceEnds


@dataclass(frozen=True)
class _Candidates:
    """The directions whose polygon edges may belong to the friction face on one side of world up
    (:func:`_face_ends`): per direction, and as runs ``(first, last)`` of consecutive indices."""

    of_direction: list[bool]
    runs: list[tuple[int, int]]


@dataclass(frozen=True)
class _DirectionSet:
    """What a fit needs of its support directions alone: their components as floats, the face
    candidates right and left of world up, and the cosine of the face window."""

    ux: list[float]
    uy: list[float]
    candidates: tuple[_Candidates, _Candidates]
    window_cosine: float


def _direction_set(directions: np.ndarray) -> _DirectionSet:
    """The :class:`_DirectionSet` of ``directions`` (K×2), computed once per distinct set: a fit
    (every 25 ms in the 1 kHz estimator) then only looks it up."""
    return _direction_set_of(np.asarray(directions, dtype=float).tobytes())


@functools.lru_cache(maxsize=8)
def _direction_set_of(key: bytes) -> _DirectionSet:
    """The :class:`_DirectionSet` of the directions whose float64 bytes are ``key``."""
    ux, uy = np.frombuffer(key).reshape(-1, 2).T.tolist()
    low, high = FACE_COSINE_RANGE
    (up_x, up_y), candidates = WORLD_UP, []
    for side in (1.0, -1.0):
        right_x, right_y = side * up_y, -side * up_x
        of_direction = [
            nx * right_x + ny * right_y > 0.0 and low <= nx * up_x + ny * up_y <= high
            for nx, ny in zip(ux, uy, strict=True)
        ]
        runs: list[tuple[int, int]] = []
        for k in itertools.compress(range(len(ux)), of_direction):
            if runs and runs[-1][1] == k - 1:
                runs[-1] = (runs[-1][0], k)
            else:
                runs.append((k, k))
        candidates.append(_Candidates(of_direction, runs))
    window = FACE_WINDOW_STEPS * 2.0 * math.pi / len(ux)
    return _DirectionSet(ux, uy, (candidates[0], candidates[1]), math.cos(window))


def half_plane_polygon(
    directions: np.ndarray, support: np.ndarray
) -> tuple[list[int], list[tuple[float, float]]]:
    """Intersection of the half-planes ``directions[k]·f ≤ support[k]`` (directions by ascending angle,
    spanning the circle so that it is bounded).

    Returns the indices of the half-planes that touch the polygon, in counter-clockwise order, and
    its vertices: vertex ``i`` is where active lines ``i`` and ``i + 1`` (cyclically) meet, so edge
    ``i`` runs from vertex ``i − 1`` to vertex ``i``; NaN where they are parallel. The classic
    sorted-angle deque sweep, O(K).
    """
    return _polygon(_direction_set(directions), support)


def _polygon(geometry: _DirectionSet, support: np.ndarray) -> tuple[list[int], list[tuple[float, float]]]:
    """:func:`half_plane_polygon` of the directions of ``geometry``."""
    lines, corners = _sweep(geometry.ux, geometry.uy, support.tolist())
    return list(lines), list(corners)


def _sweep(ux: list[float], uy: list[float], h: list[float]) -> tuple[deque[int], deque[tuple[float, float]]]:
    """:func:`half_plane_polygon` on the lines ``ux[k] x + uy[k] y = h[k]``, as deques.

    Inlined for speed, and kept a sweep: on the estimator's recorded support values every fit drops
    31 or more of the 64 lines (quantiles of projections are no support function), so the pops are
    the common case and a vectorised path for hulls where every line is active would never run. The last line
    and the last corner are kept in locals: the last corner is the one pushed just before, NaN before
    the first (NaN is outside no line, as a parallel pair's corner)."""
    lines: deque[int] = deque((0,))  # active lines, by angle
    corners: deque[tuple[float, float]] = deque()  # corners[i]: lines[i] meets lines[i + 1]
    top_a, top_b, top_c = ux[0], uy[0], h[0]  # lines[-1]
    last_x = last_y = math.nan  # corners[-1]
    for k, a, b, c in zip(range(1, len(h)), ux[1:], uy[1:], h[1:], strict=True):
        if a * last_x + b * last_y > c:  # the last corner is outside line k
            lines.pop()
            corners.pop()
            while corners:
                x, y = corners[-1]
                if not a * x + b * y > c:
                    break
                lines.pop()
                corners.pop()
            top = lines[-1]
            top_a, top_b, top_c = ux[top], uy[top], h[top]
        while corners:
            x, y = corners[0]
            if not a * x + b * y > c:  # the first corner is inside line k
                break
            lines.popleft()
            corners.popleft()
        det = top_a * b - top_b * a  # corner(lines[-1], k)
        last_x, last_y = (
            ((b * top_c - top_b * c) / det, (top_a * c - a * top_c) / det) if det != 0.0 else _NO_CORNER
        )
        corners.append((last_x, last_y))
        lines.append(k)
        top_a, top_b, top_c = a, b, c
    while len(corners) >= 2 and _outside(ux, uy, h, lines[0], corners[-1]):
        lines.pop()
        corners.pop()
    while len(corners) >= 2 and _outside(ux, uy, h, lines[-1], corners[0]):
        lines.popleft()
        corners.popleft()
    corners.append(_corner(ux, uy, h, lines[-1], lines[0]))
    return lines, corners


def _corner(ux: list[float], uy: list[float], h: list[float], i: int, j: int) -> tuple[float, float]:
    """Where lines ``i`` and ``j`` meet (:func:`half_plane_polygon`)."""
    det = ux[i] * uy[j] - uy[i] * ux[j]
    if det == 0.0:  # parallel lines (a hull of zero width): no corner
        return _NO_CORNER
    return (uy[j] * h[i] - uy[i] * h[j]) / det, (ux[i] * h[j] - ux[j] * h[i]) / det


def _outside(ux: list[float], uy: list[float], h: list[float], k: int, point: tuple[float, float]) -> bool:
    """Whether ``point`` is strictly outside half-plane ``k`` (:func:`half_plane_polygon`)."""
    return ux[k] * point[0] + uy[k] * point[1] > h[k]


_CONE_VALUES = struct.Struct("10d")
"""A cone's ``A``, ``b``, ``apex`` and ``up`` as the bytes of one read-only array (:func:`_cone`)."""


def _cone(rows: tuple[Row2, Row2], valid: bool, fitted: tuple[bool, bool]) -> GroundCone:
    """The :class:`GroundCone` of a fit's rows (:func:`_ground_rows`)."""
    ((ax, ay), b_pos, _), ((cx, cy), b_neg, _) = rows
    mu_g, apex, up = math.nan, (math.nan, math.nan), WORLD_UP
    axis = math.hypot(ax + cx, ay + cy)  # of the faces' bisector, the cone's axis
    half_angle = 0.5 * math.acos(max(-1.0, min(1.0, ax * cx + ay * cy)))
    if fitted[0] and fitted[1] and axis > 0.0 and half_angle > 0.0:  # not a hull of zero width
        up = ((ax + cx) / axis, (ay + cy) / axis)
        mu_g = 1.0 / math.tan(half_angle)
        det = ax * cy - ay * cx
        if det != 0.0:
            apex = ((cy * b_pos - ay * b_neg) / det, (ax * b_neg - cx * b_pos) / det)
    values = np.frombuffer(_CONE_VALUES.pack(ax, ay, cx, cy, b_pos, b_neg, *apex, *up))  # A, b, apex, up
    return record(  # read-only, and so are its views
        GroundCone,
        {
            "A": values[:4].reshape(2, 2),
            "b": values[4:6],
            "valid": valid,
            "fitted": fitted,
            "mu_g": mu_g,
            "apex": values[6:8],
            "up": values[8:],
        },
    )


def _prior_row(
    up: tuple[float, float], mu_prior: float, side: float, vertices: list[tuple[float, float]]
) -> Row2:
    """The row of slope ``mu_prior`` about ``up`` on ``side`` (+1 right, −1 left) touching the polygon
    ``vertices``."""
    normal = friction_face_normal(up, mu_prior, side)
    nx, ny = normal
    return normal, max([nx * x + ny * y for x, y in vertices]), 0.0


def friction_face_normal(up: tuple[float, float], mu: float, side: float) -> tuple[float, float]:
    """The outward unit normal of a friction face of slope ``mu`` about ``up`` on ``side`` (+1 right,
    −1 left): along ``right + μ up``, ``right = side · (up_y, −up_x)``."""
    scale = math.hypot(1.0, mu)
    return (side * up[1] + mu * up[0]) / scale, (-side * up[0] + mu * up[1]) / scale


def _face_ends(
    active: list[int], vertices: list[tuple[float, float]], geometry: _DirectionSet, candidates: _Candidates
) -> FaceEnds | None:
    """The ends of the friction face on the side of ``candidates`` (right or left of world up), or
    None (:func:`_face_row` makes them a row).

    Polygon edge ``i`` (from vertex ``i − 1`` to ``i``) lies on line ``active[i]``, its outward
    normal that direction. Seed: the longest pair of consecutive edges whose normals point to that
    side with ``up·ν`` in :data:`FACE_COSINE_RANGE` (the candidates, found by bisection of the
    sorted ``active`` on their runs). Noise lifts the support values most where the face is seen
    head-on, so the hull bulges slightly along a face and a straight face spans a few edges: the
    face is every consecutive edge whose normal is within :data:`FACE_WINDOW_STEPS` direction steps
    of the seed chord's, and its ends are the first one's start and the last one's end.
    """
    count, candidate, ux, uy = len(active), candidates.of_direction, geometry.ux, geometry.uy
    lengths = {  # of the candidate edges, by position, ascending
        index: math.dist(vertices[index - 1], vertices[index])
        for first_k, last_k in candidates.runs
        for index in range(bisect_left(active, first_k), bisect_right(active, last_k))
    }
    best, first = 0.0, -1
    for index, length in lengths.items():
        following = lengths.get((index + 1) % count)
        if following is not None and length + following > best:
            best, first = length + following, index
    seed = _chord(vertices[first - 1], vertices[(first + 1) % count]) if first >= 0 else None
    if seed is None:
        return None
    (seed_x, seed_y), cosine = seed[0], geometry.window_cosine

    def extends(index: int) -> bool:
        k = active[index % count]
        return candidate[k] and ux[k] * seed_x + uy[k] * seed_y >= cosine

    start, end = first, first + 1
    while end - start < count - 1 and extends(end + 1):
        end += 1
    while end - start < count - 1 and extends(start - 1):
        start -= 1
    return vertices[(start - 1) % count], vertices[end % count]


@functools.lru_cache(maxsize=64)
def _face_row(ends: FaceEnds) -> Row2 | None:
    """The row of a friction face's ``ends`` (:func:`_face_ends`): their chord, turned through the
    origin where it crosses "up" below it (:func:`_through_origin`); None where the chord has no
    length or its normal is outside :data:`FACE_COSINE_RANGE`. Cached: in half the fits or more of a
    closed-loop run, a side's face ends where it did in an earlier fit."""
    (up_x, up_y), (low, high) = WORLD_UP, FACE_COSINE_RANGE
    row = _chord(*ends)
    if row is not None and row[1] < 0.0:
        row = _through_origin(ends)
    return row if row is not None and low <= row[0][0] * up_x + row[0][1] * up_y <= high else None


def _through_origin(ends: FaceEnds) -> Row2 | None:
    """The face of a chord ``ends`` that crosses "up" below the origin: the line through the origin and
    the chord's end farther from it, in the chord's direction (so outward like the chord's own
    row, :func:`_chord`) and with the chord's length; None if that end is the origin.

    A friction face crosses the vertical through the origin at the weight reversed, ``m g`` above
    it: no face crosses below. A chord that does is where the forces seen end, not the face: e.g. a
    hull whose only sliding forces lie at one end of the chord, its slope set by the sticking forces
    next to them (on a goal run of the paper triangle, ``μ_g`` 0.8, the chords after a slide each way
    had the slopes of ``μ_g`` 1.25 and 2.8 and crossed 3 and 10 N below the origin: they predicted a
    ground slide at a 2.6° tilt, 13.8 N short on the true object, which rolled the hand four times).
    The farther end is the largest force pushed on that side, where a slide was seen; the line
    through it and the origin is the face of a weightless object, which the friction of any object
    that slid there lies within by ``μ_g m g`` at most.
    """
    start, end = ends
    turned = _chord((0.0, 0.0), end) if math.hypot(*start) <= math.hypot(*end) else _chord(start, (0.0, 0.0))
    return None if turned is None else (turned[0], 0.0, math.dist(start, end))


def _chord(start: tuple[float, float], end: tuple[float, float]) -> Row2 | None:
    """The row of the line from ``start`` to ``end`` (outward normal for a counter-clockwise polygon),
    None if they coincide."""
    (sx, sy), (ex, ey) = start, end
    length = math.hypot(ex - sx, ey - sy)
    if length == 0.0:
        return None
    normal = ((ey - sy) / length, (sx - ex) / length)
    return normal, normal[0] * sx + normal[1] * sy, length
