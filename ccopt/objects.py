"""Object library: validated planar convex polygons with mass and friction.

An object is a uniform convex lamina (extruded into a prism by the simulators). Its vertices are
given in the object's body frame, whose origin is the area centroid, in counter-clockwise order;
face ``k`` runs from vertex ``k`` to vertex ``k + 1``. Units are SI (m, kg).

The library holds generic shapes (``triangle``, ``square``, ``rectangle``, ``pentagon``,
``hexagon``; any side) and the five objects of the paper's experiments (``paper-*``).
"""

from __future__ import annotations

import functools
import math
from collections.abc import Callable
from dataclasses import dataclass
from numbers import Real
from typing import Any

import numpy as np
from numpy.typing import ArrayLike

from ccopt import geometry
from ccopt.validation import as_float, short

MIN_EDGE = 0.01
MAX_EDGE = 1.0
"""Shortest and longest admissible face, m: ccopt handles objects from 1 cm to 1 m (a hand, a table)."""
MASS_RANGE = (1e-3, 100.0)
"""Lightest and heaviest admissible object, kg."""
MAX_FRICTION = 10.0
"""Largest admissible friction coefficient (real materials stay below about 2)."""

DEFAULT_MU_HAND = 0.5
DEFAULT_MU_GROUND = 0.8
PAPER_ADDED_MASS = 0.5
"""Mass (kg) the paper adds to its triangle and pentagon; pass ``added_mass=PAPER_ADDED_MASS``."""


def _check_real(name: str, value: object) -> float:
    if isinstance(value, bool) or not isinstance(value, Real):
        raise TypeError(f"{name} must be a real number, got {type(value).__name__} {short(value)}")
    return as_float(name, value)


def _check_friction(name: str, value: object) -> float:
    mu = _check_real(name, value)
    if not 0.0 <= mu <= MAX_FRICTION:
        raise ValueError(f"{name} must be a friction coefficient in [0, {MAX_FRICTION:g}], got {mu!r}")
    return mu


def _check_vertices(vertices: object) -> np.ndarray:
    """Validated ``(n, 2)`` CCW vertices shifted to the area centroid (read-only copy)."""
    try:
        poly = np.array(vertices, dtype=float)
    except OverflowError:  # an integer beyond the largest float, from a settings file
        beyond = f"an integer beyond 1.8e308 in {short(vertices)}"
        raise ValueError(f"vertices must be finite, got {beyond}") from None
    except (TypeError, ValueError) as exc:
        raise TypeError(f"vertices must be an (n, 2) array of numbers, got {short(vertices)}") from exc
    if poly.ndim != 2 or poly.shape[1] != 2:
        raise ValueError(f"vertices must have shape (n, 2), got shape {poly.shape}")
    if poly.shape[0] < 3:
        raise ValueError(f"an object needs at least 3 vertices, got {poly.shape[0]}")
    if not np.all(np.isfinite(poly)):
        raise ValueError(f"vertices must be finite, got {poly.tolist()}")
    edges = np.hypot(*(np.roll(poly, -1, axis=0) - poly).T)
    if not (np.all(np.isfinite(edges)) and edges.min() >= MIN_EDGE and edges.max() <= MAX_EDGE):
        worst = edges.min() if edges.min() < MIN_EDGE else edges.max()
        raise ValueError(
            f"every face must be {MIN_EDGE:g} m to {MAX_EDGE:g} m long (objects from 1 cm to 1 m), "
            f"got a face of {worst:.3g} m in vertices {poly.tolist()}"
        )
    if not geometry.is_convex(poly):
        raise ValueError(f"vertices must form a convex, simple polygon, got {poly.tolist()}")
    if geometry.signed_area(poly) < 0.0:
        poly = poly[::-1].copy()
    poly -= geometry.centroid(poly)
    poly.setflags(write=False)
    return poly


@dataclass(frozen=True)
class PlanarObject:
    """A uniform convex polygonal object.

    Attributes:
        name: label used in records and plots.
        vertices: ``(n, 2)`` vertices in the body frame (m). On construction they are validated,
            silently re-ordered counter-clockwise if given clockwise, and shifted so that the
            body-frame origin is the area centroid. The stored array is read-only.
        mass: kg, in :data:`MASS_RANGE`.
        mu_hand: hand/object Coulomb friction coefficient, in [0, :data:`MAX_FRICTION`].
        mu_ground: object/ground Coulomb friction coefficient, in [0, :data:`MAX_FRICTION`].

    Raises:
        TypeError: a field has the wrong type.
        ValueError: fewer than 3 vertices, non-finite or non-convex vertices, a face shorter
            than :data:`MIN_EDGE` or longer than :data:`MAX_EDGE`, a mass outside
            :data:`MASS_RANGE`, friction outside [0, :data:`MAX_FRICTION`] or NaN.
    """

    name: str
    vertices: np.ndarray
    mass: float
    mu_hand: float = DEFAULT_MU_HAND
    mu_ground: float = DEFAULT_MU_GROUND

    def __post_init__(self) -> None:
        if not isinstance(self.name, str):
            raise TypeError(f"name must be a string, got {type(self.name).__name__}")
        mass = _check_real("mass", self.mass)
        low, high = MASS_RANGE
        if not low <= mass <= high:
            raise ValueError(f"mass must be a positive number of kg in [{low:g}, {high:g}], got {mass!r}")
        object.__setattr__(self, "mass", mass)
        object.__setattr__(self, "mu_hand", _check_friction("mu_hand", self.mu_hand))
        object.__setattr__(self, "mu_ground", _check_friction("mu_ground", self.mu_ground))
        object.__setattr__(self, "vertices", _check_vertices(self.vertices))

    def __eq__(self, other: object) -> bool:
        if not isinstance(other, PlanarObject):
            return NotImplemented
        return self._key() == other._key()

    def __hash__(self) -> int:
        return hash(self._key())

    def _key(self) -> tuple:
        return (self.name, self.vertices.tobytes(), self.mass, self.mu_hand, self.mu_ground)

    @property
    def n_faces(self) -> int:
        """Number of faces (= number of vertices)."""
        return len(self.vertices)

    @property
    def faces(self) -> np.ndarray:
        """``(n, 2, 2)`` body-frame segments; face ``k`` is ``(vertex k, vertex k + 1)``, m."""
        return np.stack((self.vertices, np.roll(self.vertices, -1, axis=0)), axis=1)

    @property
    def area(self) -> float:
        """Area of the lamina, m²."""
        return geometry.signed_area(self.vertices)

    @property
    def inertia(self) -> float:
        """Moment of inertia about the centroid, out-of-plane axis, kg·m² (uniform lamina)."""
        return geometry.lamina_inertia(self.vertices, self.mass)

    @functools.cached_property  # the plants' ground truth reads one every record sample
    def face_normals(self) -> np.ndarray:
        """Outward unit normals of every face in the body frame (``n_faces × 2``, read-only)."""
        normals = np.array([geometry.face_normal(self.vertices, face) for face in range(self.n_faces)])
        normals.flags.writeable = False
        return normals

    def face_normal(self, face: int) -> np.ndarray:
        """Outward unit normal of ``face`` in the body frame."""
        return self.face_normals[self.face_index(face)].copy()

    def face_length(self, face: int) -> float:
        """Length of ``face``, m."""
        start, end = self.faces[self.face_index(face)]
        return float(np.linalg.norm(end - start))

    def face_index(self, face: int) -> int:
        """``face`` validated against this object (raises ``TypeError``/``ValueError``)."""
        if isinstance(face, bool) or not isinstance(face, int | np.integer):
            raise TypeError(f"face must be an integer, got {type(face).__name__} {short(face)}")
        if not 0 <= face < self.n_faces:
            raise ValueError(f"face must be in [0, {self.n_faces - 1}] for {self.name}, got {short(face)}")
        return int(face)


# --- constructors --------------------------------------------------------------------------------


def _positive_length(name: str, value: object) -> float:
    length = _check_real(name, value)
    if not math.isfinite(length) or length <= 0.0:
        raise ValueError(f"{name} must be a positive, finite length in m, got {length!r}")
    return length


def from_vertices(
    vertices: ArrayLike,
    mass: float,
    mu_hand: float = DEFAULT_MU_HAND,
    mu_ground: float = DEFAULT_MU_GROUND,
    name: str = "polygon",
) -> PlanarObject:
    """Object from vertices in any frame and either orientation (re-centred, made CCW)."""
    return PlanarObject(name, vertices, mass, mu_hand, mu_ground)


def regular_polygon(
    n_sides: int,
    side: float,
    mass: float,
    mu_hand: float = DEFAULT_MU_HAND,
    mu_ground: float = DEFAULT_MU_GROUND,
    name: str | None = None,
) -> PlanarObject:
    """Regular polygon with ``n_sides`` faces of length ``side`` (m); face 0 is horizontal, at the bottom."""
    if isinstance(n_sides, bool) or not isinstance(n_sides, int | np.integer):
        raise TypeError(f"n_sides must be an integer, got {type(n_sides).__name__} {n_sides!r}")
    if n_sides < 3:
        raise ValueError(f"n_sides must be at least 3, got {n_sides}")
    side = _positive_length("side", side)
    circumradius = side / (2.0 * math.sin(math.pi / n_sides))
    angles = -0.5 * math.pi - math.pi / n_sides + 2.0 * math.pi * np.arange(n_sides) / n_sides
    vertices = circumradius * np.column_stack((np.cos(angles), np.sin(angles)))
    return PlanarObject(name or f"{n_sides}-gon", vertices, mass, mu_hand, mu_ground)


def rectangle(
    width: float,
    height: float,
    mass: float,
    mu_hand: float = DEFAULT_MU_HAND,
    mu_ground: float = DEFAULT_MU_GROUND,
    name: str = "rectangle",
) -> PlanarObject:
    """Axis-aligned rectangle ``width`` (along x) × ``height`` (along y), m; face 0 at the bottom."""
    half_w = 0.5 * _positive_length("width", width)
    half_h = 0.5 * _positive_length("height", height)
    vertices = [(-half_w, -half_h), (half_w, -half_h), (half_w, half_h), (-half_w, half_h)]
    return PlanarObject(name, vertices, mass, mu_hand, mu_ground)


def isosceles_triangle(
    base: float,
    leg: float,
    mass: float,
    mu_hand: float = DEFAULT_MU_HAND,
    mu_ground: float = DEFAULT_MU_GROUND,
    name: str = "isosceles-triangle",
) -> PlanarObject:
    """Triangle with a horizontal ``base`` (face 0, at the bottom) and two ``leg`` faces, m."""
    base = _positive_length("base", base)
    leg = _positive_length("leg", leg)
    if leg <= 0.5 * base:
        raise ValueError(f"leg must exceed half the base ({0.5 * base} m), got {leg} m")
    height = math.sqrt(leg * leg - 0.25 * base * base)
    vertices = [(-0.5 * base, 0.0), (0.5 * base, 0.0), (0.0, height)]
    return PlanarObject(name, vertices, mass, mu_hand, mu_ground)


# --- the library ---------------------------------------------------------------------------------


def _shape(factory: Callable[..., PlanarObject], **defaults: Any) -> Callable[..., PlanarObject]:
    def build(name: str, mass: float, mu_hand: float, mu_ground: float, **overrides: Any) -> PlanarObject:
        unknown = set(overrides) - set(defaults)
        if unknown:
            allowed = sorted({*defaults, "mass", "added_mass", "mu_hand", "mu_ground"})
            raise TypeError(f"object {name!r} takes no override {sorted(unknown)}; allowed: {allowed}")
        shape = {**defaults, **overrides}
        return factory(**shape, mass=mass, mu_hand=mu_hand, mu_ground=mu_ground, name=name)

    return build


_LIBRARY: dict[str, tuple[float, Callable[..., PlanarObject]]] = {
    "triangle": (0.195, _shape(lambda side, **kw: regular_polygon(3, side, **kw), side=0.13)),
    "square": (0.244, _shape(lambda side, **kw: regular_polygon(4, side, **kw), side=0.10)),
    "rectangle": (0.445, _shape(rectangle, width=0.18, height=0.11)),
    "pentagon": (0.278, _shape(lambda side, **kw: regular_polygon(5, side, **kw), side=0.08)),
    "hexagon": (0.310, _shape(lambda side, **kw: regular_polygon(6, side, **kw), side=0.07)),
    "paper-triangle": (0.195, _shape(lambda **kw: isosceles_triangle(0.128, 0.134, **kw))),
    "paper-square": (0.244, _shape(lambda **kw: regular_polygon(4, 0.10, **kw))),
    "paper-rectangle": (0.445, _shape(lambda **kw: rectangle(0.18, 0.11, **kw))),
    "paper-pentagon": (0.278, _shape(lambda **kw: regular_polygon(5, 0.08, **kw))),
    "paper-hexagon": (0.310, _shape(lambda **kw: regular_polygon(6, 0.07, **kw))),
}

OBJECT_NAMES: tuple[str, ...] = tuple(_LIBRARY)
"""Names accepted by :func:`make_object`."""

PAPER_OBJECT_NAMES: tuple[str, ...] = tuple(n for n in OBJECT_NAMES if n.startswith("paper-"))


def make_object(
    name: str,
    *,
    mass: float | None = None,
    added_mass: float = 0.0,
    mu_hand: float = DEFAULT_MU_HAND,
    mu_ground: float = DEFAULT_MU_GROUND,
    **shape: float,
) -> PlanarObject:
    """Library object by name, with optional overrides.

    Args:
        name: one of :data:`OBJECT_NAMES`.
        mass: kg; defaults to the paper's mass for that shape.
        added_mass: kg added to ``mass`` (the paper adds 0.5 kg to its triangle and pentagon).
        mu_hand, mu_ground: friction coefficients.
        **shape: dimensions of the generic shapes, m: ``side`` (triangle, square, pentagon,
            hexagon) or ``width``/``height`` (rectangle). The ``paper-*`` objects have fixed
            dimensions: triangle 12.8 cm base and 13.4 cm legs, square 10 cm, rectangle
            18 × 11 cm, pentagon 8 cm, hexagon 7 cm.

    Raises:
        ValueError: unknown name (the message lists the valid ones) or invalid values.
        TypeError: an override the shape does not take.
    """
    if name not in _LIBRARY:
        raise ValueError(f"unknown object {name!r}; valid names: {', '.join(OBJECT_NAMES)}")
    default_mass, build = _LIBRARY[name]
    base_mass = default_mass if mass is None else _check_real("mass", mass)
    added = _check_real("added_mass", added_mass)
    if not math.isfinite(added) or added < 0.0:
        raise ValueError(f"added_mass must be a non-negative number of kg, got {added!r}")
    return build(name, base_mass + added, mu_hand, mu_ground, **shape)
