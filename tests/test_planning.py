"""ccopt.planning (the configuration graph, possible tours, the experimenter's tour plan) against
independent truths.

* Margins and edges: direct calls of :func:`ccopt.statics.best_wrench` at configurations computed
  here (:class:`Reference`, an edge model written in the test from the module docstring's rules).
* Paths: breadth-first search and Bellman–Ford over the reference's adjacency.
* Tours: the experimenter's oracle :func:`ccopt.statics.schedule_feasibility`, started where the loop
  starts (:func:`ccopt.closed_loop.start_config` of the returned ``LoopParams``).
* Vertex ranges: :func:`ccopt.geometry.lowest_vertex` and the polygon's face normals.
"""

from __future__ import annotations

import dataclasses
import itertools
import math
from collections import deque
from collections.abc import Callable, Iterable, Sequence
from dataclasses import dataclass, field

import numpy as np
import pytest

from ccopt import geometry, statics
from ccopt.closed_loop import LoopParams, start_config
from ccopt.hand import Hand
from ccopt.modes import Motion
from ccopt.objects import PlanarObject, make_object
from ccopt.planning import ConfigurationGraph, Edge, GraphParams, Node
from ccopt.planning.tour import (
    SLIDE_KINDS,
    Tour,
    allowed_slides,
    plan_tour,
    possible_tour,
    reachable_nodes,
    vertex_range,
)
from ccopt.plant import placement
from ccopt.plant.base import StartConfig
from ccopt.plant.mujoco_planar import HAND_ANGLE_RANGE
from ccopt.schedule import PIVOT_STEP, SLIDE_STEP, Step, exploration

LP_TOLERANCE = 1e-5
"""N. Two LPs over nested feasible sets are compared up to the solver's accuracy (DAQP with proximal
point agrees with Clarabel to ~2e-6 N: :data:`ccopt.statics.LP_PROXIMAL_WEIGHT`)."""
PLAN_MARGIN = 2.5
"""N, :func:`plan_tour`'s default margin."""
PLAN_FORCE_SHARE = 0.75
""":func:`plan_tour`'s default share of the hand's force range."""
CLEARANCE = math.radians(5.0)
"""The clearance :func:`plan_tour` keeps from the ends of the object's vertex range."""
MOTIONS = tuple(Motion)
KINDS_PER_SIGN = {
    "pivot": (Motion.PIVOT, Motion.PIVOT),
    "slide_hand": (Motion.SLIDE_HAND_POS, Motion.SLIDE_HAND_NEG),
    "slide_ground": (Motion.SLIDE_GROUND_POS, Motion.SLIDE_GROUND_NEG),
}

Key = tuple[str, int, tuple[int, int]]
"""An edge as the reference names it: kind, sign of its increment, target ``(i, j)``."""


# --- the reference: what the graph's edges must be, from direct LP calls ---------------------------


@dataclass
class Reference:
    """The edges the graph's docstring promises, built from direct :func:`statics.best_wrench` calls:
    a motion is an edge where every grid point it passes (a pivot: its two ends; a hand slide: every
    ``s_h_step`` point; a ground slide: its node) lies within the ranges and the caller's reach and
    has a margin of at least ``min_margin``."""

    known: statics.ObjectStatics
    start: tuple[float, float]
    lever: float
    forces: tuple[float, float]
    params: GraphParams
    reach: Callable[[float, float], bool] | None = None
    _lp: dict[tuple[int, int, Motion], float] = field(default_factory=dict)

    def config(self, i: int, j: int) -> tuple[float, float]:
        return self.start[0] + i * self.params.pivot_step, self.start[1] + j * self.params.s_h_step

    def inside(self, i: int, j: int) -> bool:
        theta, s_h = self.config(i, j)
        (t_lo, t_hi), (s_lo, s_hi) = self.params.theta_range, self.params.s_h_range
        within = t_lo - 1e-9 <= theta <= t_hi + 1e-9 and s_lo - 1e-9 <= s_h <= s_hi + 1e-9
        return within and (self.reach is None or self.reach(theta, s_h))

    def margin(self, i: int, j: int, motion: Motion) -> float:
        key = (i, j, motion)
        if key not in self._lp:
            theta, s_h = self.config(i, j)
            self._lp[key] = statics.best_wrench(
                self.known, theta, s_h, motion, self.lever, self.forces
            ).margin
        return self._lp[key]

    def path(self, i: int, j: int, kind: str, sign: int) -> list[tuple[int, int]]:
        """The grid points a motion from ``(i, j)`` passes, its start first."""
        if kind == "pivot":
            return [(i, j), (i + sign, j)]
        if kind == "slide_hand":
            stride = round(self.params.hand_slide / self.params.s_h_step)
            return [(i, j + sign * k) for k in range(stride + 1)]
        return [(i, j)]

    def edges(self, i: int, j: int) -> dict[Key, float]:
        """Every edge from ``(i, j)`` with its margin (the smallest along its path)."""
        found = {}
        for kind, motions in KINDS_PER_SIGN.items():
            for sign, motion in zip((1, -1), motions, strict=True):
                points = self.path(i, j, kind, sign)
                if not all(self.inside(*point) for point in points):
                    continue
                margin = min(self.margin(*point, motion) for point in points)
                if margin >= self.params.min_margin:
                    found[(kind, sign, points[-1])] = margin
        return found

    def index_range(self) -> tuple[range, range]:
        """The grid indices within the ranges (the reach callback aside)."""
        p = self.params

        def indices(low: float, high: float, origin: float, step: float) -> range:
            first = math.ceil((low - origin) / step - 1e-6)
            return range(first, math.floor((high - origin) / step + 1e-6) + 1)

        return (
            indices(*p.theta_range, self.start[0], p.pivot_step),
            indices(*p.s_h_range, self.start[1], p.s_h_step),
        )

    def nodes(self) -> list[tuple[int, int]]:
        rows, columns = self.index_range()
        return [(i, j) for i in rows for j in columns if self.inside(i, j)]

    def ring(self) -> list[tuple[int, int]]:
        """The grid points just outside the ranges."""
        rows, columns = self.index_range()
        i_lo, i_hi, j_lo, j_hi = rows[0] - 1, rows[-1] + 1, columns[0] - 1, columns[-1] + 1
        return [
            (i, j)
            for i in range(i_lo, i_hi + 1)
            for j in range(j_lo, j_hi + 1)
            if i in (i_lo, i_hi) or j in (j_lo, j_hi)
        ]

    def moves(self, node: tuple[int, int]) -> dict[Key, float]:
        """The edges that move a node (pivots and hand slides)."""
        return {key: m for key, m in self.edges(*node).items() if key[0] != "slide_ground"}

    def closure(self, source: tuple[int, int]) -> set[tuple[int, int]]:
        """Every node reachable from ``source`` through pivots and hand slides."""
        return set(bfs_distances(self, source))


def reference_lp(reference: Reference, point: tuple[int, int], motion: Motion) -> float:
    """A fresh LP (no cache) at a grid point of the reference."""
    theta, s_h = reference.config(*point)
    return statics.best_wrench(reference.known, theta, s_h, motion, reference.lever, reference.forces).margin


def key_of(edge: Edge) -> Key:
    return edge.kind, int(math.copysign(1, edge.delta)), (edge.target.i, edge.target.j)


def graph_edges(graph: ConfigurationGraph, i: int, j: int) -> dict[Key, float]:
    found = {}
    for edge in graph.edges(Node(i, j)):
        assert key_of(edge) not in found, f"duplicate edge {edge}"
        found[key_of(edge)] = edge.margin
    return found


def assert_same_edges(actual: dict[Key, float], expected: dict[Key, float], where: object) -> None:
    assert actual.keys() == expected.keys(), f"at {where}: {sorted(actual)} != {sorted(expected)}"
    for key, margin in expected.items():
        assert actual[key] == pytest.approx(margin, rel=1e-9, abs=1e-9), (where, key)


def bfs_distances(reference: Reference, source: tuple[int, int]) -> dict[tuple[int, int], int]:
    """Unit-cost distances from ``source`` over the reference's moving edges (breadth first)."""
    distance, queue = {source: 0}, deque([source])
    while queue:
        node = queue.popleft()
        for _, _, target in reference.moves(node):
            if target not in distance:
                distance[target] = distance[node] + 1
                queue.append(target)
    return distance


def bellman_ford(
    reference: Reference, source: tuple[int, int], cost: Callable[[str, float], float]
) -> dict[tuple[int, int], float]:
    """Cheapest costs from ``source`` (relaxing every edge until nothing changes)."""
    nodes = reference.nodes()
    best = {source: 0.0}
    for _ in range(len(nodes) + 1):
        changed = False
        for node in nodes:
            if node not in best:
                continue
            for (kind, _, target), margin in reference.moves(node).items():
                total = best[node] + cost(kind, margin)
                if total < best.get(target, math.inf) - 1e-12:
                    best[target], changed = total, True
        if not changed:
            return best
    raise AssertionError("Bellman-Ford did not converge")


def assert_valid_path(graph: ConfigurationGraph, source: Node, path: Sequence[Edge]) -> None:
    """A path is a chain of the graph's own moving edges from ``source``."""
    node = source
    for edge in path:
        assert edge.source == node
        assert edge.kind != "slide_ground"
        assert edge in set(graph.edges(node))
        node = edge.target


# --- objects, plans and their graphs ----------------------------------------------------------------


OBJECTS = {
    "triangle": ("paper-triangle", 0.5),
    "square": ("paper-square", 0.0),
    "rectangle": ("paper-rectangle", 0.0),
    "pentagon": ("paper-pentagon", 0.5),
    "pentagon-light": ("paper-pentagon", 0.0),
    "hexagon": ("paper-hexagon", 0.0),
}


def build(label: str) -> PlanarObject:
    name, added = OBJECTS[label]
    return make_object(name, added_mass=added)


@dataclass(frozen=True)
class Setup:
    """A graph as :func:`plan_tour` builds it for one start ``s_h``, and its reference."""

    truth: statics.TrueConfiguration
    graph: ConfigurationGraph
    reference: Reference


def plan_setup(
    obj: PlanarObject,
    params: LoopParams,
    s_h: float,
    angle_range: tuple[float, float] = HAND_ANGLE_RANGE,
    margin: float = PLAN_MARGIN,
    force_share: float = PLAN_FORCE_SHARE,
) -> Setup:
    """The graph of ``plan_tour``'s docstring at ``s_h``: the true statics, ``θ_o`` within the reach and
    the vertex range less 5°, the hand on the face, the estimate's torque lever, the share of the
    force range, the patch cut to the face under the hand at the start (the estimate's margin in)."""
    start = dataclasses.replace(params.start, s_h=s_h)
    truth = statics.true_statics(obj, start, params.hand)
    half, inset = params.hand.half_length, params.estimator_params.face.margin
    known = dataclasses.replace(truth.statics, face=(-half - s_h + inset, half - s_h - inset))
    truth = dataclasses.replace(truth, statics=known)
    tilt_low, tilt_high = vertex_range(obj, dataclasses.replace(start, s_h=0.0))
    theta_range = (max(angle_range[0], tilt_low + CLEARANCE), min(angle_range[1], tilt_high - CLEARANCE))
    lever = params.estimator_params.friction.torque_margin * params.hand.half_length
    f_min, f_max = params.hand.force_limits
    forces = (f_min, f_min + force_share * (f_max - f_min))
    graph_params = GraphParams(s_h_range=truth.s_h_range, theta_range=theta_range, min_margin=margin)
    where = (truth.theta_o, truth.s_h)
    graph = ConfigurationGraph(truth.statics, where, lever, forces, graph_params)
    return Setup(truth, graph, Reference(truth.statics, where, lever, forces, graph_params))


@dataclass(frozen=True)
class Planned:
    obj: PlanarObject
    params: LoopParams
    tour: Tour
    setup: Setup


@pytest.fixture(scope="module")
def loop_params() -> LoopParams:
    return LoopParams()


@pytest.fixture(scope="module")
def planned(loop_params: LoopParams) -> dict[str, Planned]:
    """plan_tour on every object, with the graph rebuilt at the start it chose."""
    plans = {}
    for label in OBJECTS:
        obj = build(label)
        params, tour = plan_tour(obj, loop_params, HAND_ANGLE_RANGE)
        plans[label] = Planned(obj, params, tour, plan_setup(obj, loop_params, params.start.s_h))
    return plans


def candidate_s_h(obj: PlanarObject, params: LoopParams, candidates: int = 7) -> np.ndarray:
    """The start positions plan_tour's docstring names: evenly along the face, the whole hand on it
    with 2 mm to spare (the face's ends from the start geometry)."""
    low, high = placement.face_s_h_range(obj, dataclasses.replace(params.start, s_h=0.0))
    inset = params.hand.half_length + 2e-3
    return np.linspace(low + inset, high - inset, candidates)


@dataclass(frozen=True)
class Candidate:
    s_h: float
    setup: Setup
    hold_margin: float
    tour: Tour | None


def candidates_of(label: str, params: LoopParams) -> list[Candidate]:
    """Every start plan_tour considers on an object, each with its hold margin (direct LP) and its
    possible tour where it holds with margin."""
    obj = build(label)
    found = []
    for s_h in candidate_s_h(obj, params):
        setup = plan_setup(obj, params, float(s_h))
        known, lever, forces = setup.reference.known, setup.reference.lever, setup.reference.forces
        hold = statics.best_wrench(known, setup.truth.theta_o, float(s_h), Motion.HOLD, lever, forces).margin
        tour = possible_tour(setup.graph) if hold >= PLAN_MARGIN else None
        found.append(Candidate(float(s_h), setup, hold, tour))
    return found


@pytest.fixture(scope="module")
def triangle_candidates(loop_params: LoopParams) -> list[Candidate]:
    return candidates_of("triangle", loop_params)


def small_grid(
    label: str,
    s_h: float,
    half_width: float,
    min_margin: float,
    reach: Callable[[float, float], bool] | None = None,
) -> Setup:
    """A 7-pivot × ``2·half_width`` grid around a start of ``label`` (true statics, plan_tour's
    lever and forces): small enough for exhaustive checks."""
    params = LoopParams()
    obj = build(label)
    truth = statics.true_statics(obj, dataclasses.replace(params.start, s_h=s_h), params.hand)
    pivot = math.radians(7.2)
    graph_params = GraphParams(
        theta_range=(truth.theta_o - 3 * pivot, truth.theta_o + 3 * pivot),
        s_h_range=(s_h - half_width, s_h + half_width),
        min_margin=min_margin,
    )
    lever = params.estimator_params.friction.torque_margin * params.hand.half_length
    f_min, f_max = params.hand.force_limits
    forces = (f_min, f_min + PLAN_FORCE_SHARE * (f_max - f_min))
    where = (truth.theta_o, s_h)
    graph = ConfigurationGraph(truth.statics, where, lever, forces, graph_params, reach)
    return Setup(truth, graph, Reference(truth.statics, where, lever, forces, graph_params, reach))


@pytest.fixture(scope="module")
def square_grid() -> Setup:
    """The square with the hand 50 mm off its ground contact: one-way hand slides, pivots missing in
    a corner (a directed graph with unreachable nodes)."""
    return small_grid("square", -0.05, 0.015, PLAN_MARGIN)


@pytest.fixture(scope="module")
def triangle_grid() -> Setup:
    """The triangle: hand slides one way, ground slides at a few nodes."""
    return small_grid("triangle", -0.0107, 0.015, PLAN_MARGIN)


GRIDS = ("square_grid", "triangle_grid")


# --- GraphParams ----------------------------------------------------------------------------------


def test_graph_params_default_increments_are_the_papers() -> None:
    """The default grid moves by the paper's increments (7.2°, 10 mm, 10 mm: ccopt.schedule) and the
    hand slide is a whole number of s_h steps."""
    params = GraphParams()
    assert params.pivot_step == pytest.approx(PIVOT_STEP, abs=1e-15)
    assert params.hand_slide == pytest.approx(SLIDE_STEP, abs=1e-15)
    assert params.ground_slide == pytest.approx(SLIDE_STEP, abs=1e-15)
    ratio = params.hand_slide / params.s_h_step
    assert ratio == pytest.approx(round(ratio), abs=1e-12) and round(ratio) >= 1


@pytest.mark.parametrize(
    ("options", "message"),
    [
        ({"pivot_step": 0.0}, "steps must be positive"),
        ({"pivot_step": -0.1}, "steps must be positive"),
        ({"pivot_step": math.nan}, "steps must be positive"),
        ({"s_h_step": -0.005}, "steps must be positive"),
        ({"s_h_step": math.nan}, "steps must be positive"),
        ({"ground_slide": 0.0}, "steps must be positive"),
        ({"ground_slide": -0.01}, "steps must be positive"),
        ({"hand_slide": 0.007}, "hand_slide must be a multiple of s_h_step"),
        ({"hand_slide": 0.0}, "hand_slide must be a multiple of s_h_step"),
        ({"hand_slide": -0.01}, "hand_slide must be a multiple of s_h_step"),
        ({"theta_range": (1.0, 0.0)}, "empty ranges"),
        ({"theta_range": (math.nan, 1.0)}, "empty ranges"),
        ({"s_h_range": (0.01, -0.01)}, "empty ranges"),
        ({"s_h_range": (math.nan, 0.0)}, "empty ranges"),
    ],
)
def test_graph_params_reject_bad_steps_and_ranges(options: dict[str, object], message: str) -> None:
    """Non-positive or NaN steps, a hand slide that is not a multiple of the grid step and empty
    ranges raise ValueError saying what is wrong."""
    with pytest.raises(ValueError, match=message):
        GraphParams(**options)


def test_graph_params_accept_a_single_s_h_and_equal_steps() -> None:
    """A one-point ``s_h`` range (the hand cannot slide), a one-point ``θ_o`` range (the object may
    not pivot: its tilt limits met) and a hand slide of one grid step are valid."""
    params = GraphParams(s_h_range=(0.0, 0.0), s_h_step=0.01, hand_slide=0.01, theta_range=(0.2, 0.2))
    assert params.s_h_range == (0.0, 0.0) and params.theta_range == (0.2, 0.2)


@pytest.mark.parametrize(
    ("options", "name"),
    [
        ({"s_h_step": 0.0}, "s_h_step"),
        ({"hand_slide": math.inf}, "hand_slide"),
        ({"hand_slide": math.nan}, "hand_slide"),
        ({"pivot_step": math.inf}, "pivot_step"),
        ({"ground_slide": math.inf}, "ground_slide"),
        ({"min_margin": math.nan}, "min_margin"),
        ({"pivot_step": 0.0}, "pivot_step"),
        ({"ground_slide": -0.01}, "ground_slide"),
        ({"end_pivot": -0.01}, "end_pivot"),
        ({"end_pivot": math.nan}, "end_pivot"),
    ],
)
def test_graph_params_errors_name_the_bad_field(options: dict[str, float], name: str) -> None:
    """Every bad value raises ValueError naming its field (the project's boundary-check convention):
    a zero or infinite step, a NaN margin (an infinite pivot step would put the start node at
    θ = 0·∞ = NaN)."""
    with pytest.raises(ValueError, match=name):
        GraphParams(**options)


# --- nodes -------------------------------------------------------------------------------------------


def test_node_configuration_is_the_start_plus_whole_steps() -> None:
    """``configuration(Node(i, j)) = (θ_start + i·pivot_step, s_h_start + j·s_h_step)`` and node_of
    returns the nearest node: its configuration lies within half a step of the point asked."""
    params = GraphParams(pivot_step=0.1, s_h_step=0.004, hand_slide=0.012)
    start = (0.25, -0.003)
    graph = ConfigurationGraph(None, start, 0.03, (3.0, 25.0), params)  # type: ignore[arg-type]
    for i in range(-4, 5):
        for j in range(-4, 5):
            theta, s_h = graph.configuration(Node(i, j))
            assert theta == pytest.approx(0.25 + 0.1 * i, abs=1e-12)
            assert s_h == pytest.approx(-0.003 + 0.004 * j, abs=1e-12)
            assert graph.node_of(theta, s_h) == Node(i, j)
    rng = np.random.default_rng(3)
    for theta, s_h in zip(rng.uniform(-1.0, 1.0, 200), rng.uniform(-0.05, 0.05, 200), strict=True):
        near_theta, near_s_h = graph.configuration(graph.node_of(theta, s_h))
        assert abs(near_theta - theta) <= 0.05 + 1e-12
        assert abs(near_s_h - s_h) <= 0.002 + 1e-12


@pytest.mark.parametrize("end_pivot", [math.radians(0.7), math.radians(2.5)])
def test_end_nodes_are_the_range_ends_one_partial_pivot_beyond_the_grid(end_pivot: float) -> None:
    """With ``end_pivot``, each end of the ``θ_o`` range further than ``end_pivot`` beyond the grid's
    outermost node is a node of its own, one index on: its configuration is the end itself, nothing
    lies beyond it, and the pivot to it is the partial increment with the margin of direct LPs at both
    of its ends. An end closer to the grid than ``end_pivot`` adds no node; without ``end_pivot``, the
    plain grid."""
    setup = small_grid("triangle", -0.0107, 0.015, PLAN_MARGIN)
    step = setup.graph.params.pivot_step
    theta_0, s_h_0 = setup.graph.start
    low, high = theta_0 - 2 * step - math.radians(2.0), theta_0 + step + math.radians(5.0)
    params = dataclasses.replace(setup.graph.params, theta_range=(low, high), end_pivot=end_pivot)
    known, lever, forces = setup.reference.known, setup.graph.lever, setup.graph.force_limits
    graph = ConfigurationGraph(known, setup.graph.start, lever, forces, params)
    plain = ConfigurationGraph(
        known, setup.graph.start, lever, forces, dataclasses.replace(params, end_pivot=None)
    )
    for i in range(-2, 2):  # the grid within the range: the start plus whole steps
        assert graph.configuration(Node(i, 0)) == pytest.approx((theta_0 + i * step, s_h_0), abs=1e-12)
    assert graph.configuration(Node(2, 0)) == (high, s_h_0)  # 5° beyond 1 step: always a node
    assert graph.inside(Node(2, 0)) and not graph.inside(Node(3, 0)) and not plain.inside(Node(2, 0))
    assert graph.inside(Node(-3, 0)) == (end_pivot < math.radians(2.0))  # 2° beyond 2 steps
    if graph.inside(Node(-3, 0)):
        assert graph.configuration(Node(-3, 0)) == (low, s_h_0)
    assert not graph.inside(Node(-4, 0))
    direct = [
        statics.best_wrench(known, theta, s_h_0, Motion.PIVOT, lever, forces).margin
        for theta in (theta_0 + step, high)
    ]
    pivots = [edge for edge in graph.edges(Node(1, 0)) if edge.kind == "pivot" and edge.delta > 0.0]
    assert min(direct) >= params.min_margin  # the triangle pivots there
    (edge,) = pivots
    assert edge.target == Node(2, 0)
    assert edge.delta == pytest.approx(high - theta_0 - step, abs=1e-12)
    assert edge.margin == pytest.approx(min(direct), rel=1e-9, abs=1e-9)


# --- margins and edges ------------------------------------------------------------------------------


@pytest.mark.parametrize("grid", GRIDS)
def test_cached_margins_equal_direct_lp_calls(grid: str, request: pytest.FixtureRequest) -> None:
    """``graph.margin(node, motion)`` is the LP's margin at the node's configuration, for every node
    of the grid and every motion (including nodes whose margins were cached by edges())."""
    setup: Setup = request.getfixturevalue(grid)
    reference = setup.reference
    for i, j in reference.nodes() + reference.ring():
        list(setup.graph.edges(Node(i, j)))  # fill the cache the way the search does
        for motion in MOTIONS:
            direct = reference_lp(reference, (i, j), motion)
            assert setup.graph.margin(Node(i, j), motion) == pytest.approx(direct, rel=1e-9, abs=1e-9)


def test_margins_are_cached(monkeypatch: pytest.MonkeyPatch) -> None:
    """A margin is solved once per node and motion: asking again calls no LP."""
    setup = small_grid("square", -0.05, 0.015, PLAN_MARGIN)
    calls: list[tuple[float, float, Motion]] = []
    solve = statics.best_wrench

    def counted(known, theta, s_h, motion, lever, forces):  # type: ignore[no-untyped-def]
        calls.append((theta, s_h, Motion(motion)))
        return solve(known, theta, s_h, motion, lever, forces)

    monkeypatch.setattr(statics, "best_wrench", counted)
    first = [setup.graph.margin(Node(0, 0), motion) for motion in MOTIONS]
    assert len(calls) == len(MOTIONS)
    assert [setup.graph.margin(Node(0, 0), motion) for motion in MOTIONS] == first
    list(setup.graph.edges(Node(0, 0)))
    later = calls[len(MOTIONS) :]  # only the neighbours' margins are new
    assert {motion for *_, motion in later} <= {Motion.PIVOT, Motion.SLIDE_HAND_POS, Motion.SLIDE_HAND_NEG}
    assert all((theta, s_h) != setup.reference.config(0, 0) for theta, s_h, _ in later)


@pytest.mark.parametrize("grid", GRIDS)
def test_edges_are_exactly_the_motions_with_margin_along_their_path(
    grid: str, request: pytest.FixtureRequest
) -> None:
    """At every node (and just outside the ranges) the graph's edges are the reference's: a motion
    whose LP margin is at least min_margin at both ends and at every grid point in between, within
    the ranges; each edge's margin is the smallest along its path."""
    setup: Setup = request.getfixturevalue(grid)
    for i, j in setup.reference.nodes() + setup.reference.ring():
        assert_same_edges(graph_edges(setup.graph, i, j), setup.reference.edges(i, j), (i, j))


@pytest.mark.parametrize("grid", GRIDS)
def test_every_edge_keeps_the_margin_along_its_path(grid: str, request: pytest.FixtureRequest) -> None:
    """Each edge's increment is the grid's (pivot_step, hand_slide, ground_slide, signed), its target
    is the node that increment reaches, and the LP margin of its motion at every grid point it passes
    is at least min_margin and at least the edge's margin."""
    setup: Setup = request.getfixturevalue(grid)
    p, reference = setup.graph.params, setup.reference
    stride = round(p.hand_slide / p.s_h_step)
    count = 0
    for i, j in reference.nodes():
        for edge in setup.graph.edges(Node(i, j)):
            sign = 1 if edge.delta > 0 else -1
            step = {"pivot": p.pivot_step, "slide_hand": p.hand_slide, "slide_ground": p.ground_slide}
            assert edge.delta == pytest.approx(sign * step[edge.kind], abs=1e-15)
            moved = {"pivot": (sign, 0), "slide_hand": (0, sign * stride), "slide_ground": (0, 0)}
            assert (edge.target.i - i, edge.target.j - j) == moved[edge.kind]
            motion = KINDS_PER_SIGN[edge.kind][0 if sign > 0 else 1]
            for point in reference.path(i, j, edge.kind, sign):
                direct = reference_lp(reference, point, motion)
                assert direct >= p.min_margin
                assert direct >= edge.margin - 1e-12
            count += 1
    assert count > 0


@pytest.mark.parametrize("grid", GRIDS)
def test_no_edge_leaves_the_ranges(grid: str, request: pytest.FixtureRequest) -> None:
    """No edge starts or ends outside ``theta_range`` × ``s_h_range``; nodes just outside have none."""
    setup: Setup = request.getfixturevalue(grid)
    (t_lo, t_hi), (s_lo, s_hi) = setup.graph.params.theta_range, setup.graph.params.s_h_range
    for i, j in setup.reference.ring():
        assert list(setup.graph.edges(Node(i, j))) == []
    for i, j in setup.reference.nodes():
        for edge in setup.graph.edges(Node(i, j)):
            theta, s_h = setup.reference.config(edge.target.i, edge.target.j)
            assert t_lo - 1e-9 <= theta <= t_hi + 1e-9 and s_lo - 1e-9 <= s_h <= s_hi + 1e-9


def test_ground_slides_are_self_loops(triangle_grid: Setup) -> None:
    """A ground slide returns to its node with ``±ground_slide`` and the LP margin of that ground slide
    at the node; it exists exactly where that margin is at least min_margin (some nodes have one)."""
    reference, graph = triangle_grid.reference, triangle_grid.graph
    seen = 0
    for i, j in reference.nodes():
        slides = [e for e in graph.edges(Node(i, j)) if e.kind == "slide_ground"]
        for sign, motion in ((1, Motion.SLIDE_GROUND_POS), (-1, Motion.SLIDE_GROUND_NEG)):
            direct = reference_lp(reference, (i, j), motion)
            mine = [e for e in slides if e.delta * sign > 0]
            assert len(mine) == (1 if direct >= graph.params.min_margin else 0), (i, j, sign)
            for edge in mine:
                seen += 1
                assert edge.source == edge.target == Node(i, j)
                assert edge.delta == pytest.approx(sign * graph.params.ground_slide, abs=1e-15)
                assert edge.margin == pytest.approx(direct, rel=1e-9, abs=1e-9)
    assert seen > 0, "the fixture should hold ground slides"


def test_reach_callback_limits_nodes_and_paths() -> None:
    """With a ``reachable(θ, s_h)`` callback, edges touch only nodes it accepts, at every point they
    pass (a hand slide across a refused node is no edge even if both its ends are accepted), and the
    rest are the reference's. The callback is asked about grid configurations only."""
    asked: list[tuple[float, float]] = []
    base = small_grid("square", -0.05, 0.015, PLAN_MARGIN)
    theta_0, s_h_0 = base.reference.start
    step = base.graph.params.s_h_step

    def reach(theta: float, s_h: float) -> bool:
        asked.append((theta, s_h))
        return not (abs(s_h - (s_h_0 + step)) < 1e-9 and theta > theta_0 - 1e-9)  # a refused row segment

    setup = small_grid("square", -0.05, 0.015, PLAN_MARGIN, reach)
    reference = setup.reference
    for i, j in reference.nodes() + reference.ring():
        assert_same_edges(graph_edges(setup.graph, i, j), reference.edges(i, j), (i, j))
    refused = {(i, 1) for i in range(4)}
    assert refused <= set(base.reference.nodes()) and not refused & set(reference.nodes())
    for i, j in base.reference.nodes():
        for edge in setup.graph.edges(Node(i, j)):
            sign = 1 if edge.delta > 0 else -1
            assert not set(reference.path(i, j, edge.kind, sign)) & refused, edge
    # The refusal matters: without it the hand slides from row 0 to row 2, across the refused row,
    # between two accepted ends.
    crossing = [i for i in range(4) if ("slide_hand", 1, (i, 2)) in base.reference.edges(i, 0)]
    assert crossing, "the fixture should have hand slides across the refused row"
    for theta, s_h in asked:
        i, j = (theta - theta_0) / base.graph.params.pivot_step, (s_h - s_h_0) / step
        assert abs(i - round(i)) < 1e-9 and abs(j - round(j)) < 1e-9


# --- shortest paths ---------------------------------------------------------------------------------


SOURCES = ((0, 0), (0, 3), (-3, -3), (3, 0))


@pytest.mark.parametrize("source", SOURCES)
def test_shortest_path_is_as_short_as_breadth_first_search(
    square_grid: Setup, source: tuple[int, int]
) -> None:
    """For every node of the grid as goal, shortest_path returns a chain of the graph's own edges from
    the source to the goal with as many motions as breadth-first search over the reference needs, and
    None where the search cannot reach the goal (the fixture has such nodes)."""
    graph, reference = square_grid.graph, square_grid.reference
    distance = bfs_distances(reference, source)
    unreachable = 0
    for target in reference.nodes():
        path = graph.shortest_path(Node(*source), lambda node, t=target: (node.i, node.j) == t)
        if target not in distance:
            assert path is None, (source, target)
            unreachable += 1
            continue
        assert path is not None, (source, target)
        assert len(path) == distance[target], (source, target)
        assert_valid_path(graph, Node(*source), path)
        end = path[-1].target if path else Node(*source)
        assert (end.i, end.j) == target
    if source == (0, 3):
        assert unreachable > 0, "the fixture should leave nodes unreachable from the top row"


def test_shortest_path_to_a_set_of_goals(triangle_grid: Setup) -> None:
    """With a goal that holds at several nodes (here: where a ground slide is possible, by direct LP),
    the path ends at one of them after as few motions as the nearest one needs, or is None where
    breadth-first search reaches none of them (both happen on this grid)."""
    graph, reference = triangle_grid.graph, triangle_grid.reference
    goals = {n for n in reference.nodes() if any(k[0] == "slide_ground" for k in reference.edges(*n))}
    assert goals
    outcomes = set()
    for source in reference.nodes():
        distance = bfs_distances(reference, source)
        nearest = min((distance[g] for g in goals if g in distance), default=None)
        path = graph.shortest_path(Node(*source), lambda node: (node.i, node.j) in goals)
        outcomes.add(nearest is None)
        if nearest is None:
            assert path is None, source
            continue
        assert path is not None and len(path) == nearest, source
        assert_valid_path(graph, Node(*source), path)
        end = path[-1].target if path else Node(*source)
        assert (end.i, end.j) in goals
    assert outcomes == {True, False}


PRICES: dict[str, Callable[[str, float], float]] = {
    "per-kind": lambda kind, margin: {"pivot": 1.0, "slide_hand": 3.5}[kind],
    "per-margin": lambda kind, margin: 1.0 + 20.0 / margin,  # prefer the safer motions
}


@pytest.mark.parametrize("price", PRICES)
@pytest.mark.parametrize("source", SOURCES)
@pytest.mark.parametrize("grid", GRIDS)
def test_shortest_path_with_costs_matches_bellman_ford(
    grid: str, source: tuple[int, int], price: str, request: pytest.FixtureRequest
) -> None:
    """With a cost per edge (a hand slide dearer than a pivot; or dearer the smaller the edge's
    margin), the path's total cost is the least cost Bellman–Ford finds over the reference."""
    setup: Setup = request.getfixturevalue(grid)
    graph, reference = setup.graph, setup.reference
    cost = PRICES[price]
    best = bellman_ford(reference, source, cost)
    for target in reference.nodes():
        path = graph.shortest_path(
            Node(*source), lambda node, t=target: (node.i, node.j) == t, lambda e: cost(e.kind, e.margin)
        )
        if target not in best:
            assert path is None
            continue
        assert path is not None
        assert_valid_path(graph, Node(*source), path)
        total = sum(cost(edge.kind, edge.margin) for edge in path)
        assert total == pytest.approx(best[target], rel=1e-9, abs=1e-9), target


def test_shortest_path_trivial_and_impossible_goals(square_grid: Setup) -> None:
    """The source itself as goal gives an empty path; a goal that holds nowhere, or only outside the
    ranges, gives None; a path never contains a ground slide."""
    graph = square_grid.graph
    assert graph.shortest_path(Node(0, 0), lambda node: node == Node(0, 0)) == []
    assert graph.shortest_path(Node(0, 0), lambda node: False) is None
    assert graph.shortest_path(Node(0, 0), lambda node: node.i > 3) is None


# --- reachable nodes and allowed slides ------------------------------------------------------------


@pytest.mark.parametrize("source", SOURCES)
def test_reachable_nodes_are_the_closure_of_the_reference(
    square_grid: Setup, source: tuple[int, int]
) -> None:
    """reachable_nodes is the set of nodes breadth-first search over the reference reaches through
    pivots and hand slides."""
    found = reachable_nodes(square_grid.graph, Node(*source))
    assert {(n.i, n.j) for n in found} == square_grid.reference.closure(source)


def test_reachable_nodes_limit(square_grid: Setup) -> None:
    """With a limit the search stops early: a subset of the closure holding the source and at least
    ``limit`` nodes (when the closure has that many)."""
    full = square_grid.reference.closure((0, 0))
    assert len(full) > 5
    partial = {(n.i, n.j) for n in reachable_nodes(square_grid.graph, Node(0, 0), limit=5)}
    assert (0, 0) in partial and partial <= full and len(partial) >= 5


@pytest.mark.parametrize("grid", GRIDS)
def test_allowed_slides_count_the_reference_slides(grid: str, request: pytest.FixtureRequest) -> None:
    """allowed_slides counts, per slide kind and sign, the slide edges the reference finds at the
    given nodes."""
    setup: Setup = request.getfixturevalue(grid)
    nodes = setup.reference.closure((0, 0))
    expected = {kind: {1: 0, -1: 0} for kind in SLIDE_KINDS}
    for node in nodes:
        for kind, sign, _ in setup.reference.edges(*node):
            if kind in SLIDE_KINDS:
                expected[kind][sign] += 1
    assert allowed_slides(setup.graph, {Node(*n) for n in nodes}) == expected


# --- possible tours ----------------------------------------------------------------------------------


def manipulation(tour: Tour) -> list[Step]:
    """The tour's steps after its opening hold and exploration, before its closing hold."""
    steps = list(tour.schedule.steps)
    return [step for step in steps[1:-1] if not step.explore]


def slide_signs(edges: Iterable[Edge], kind: str) -> list[int]:
    return [1 if edge.delta > 0 else -1 for edge in edges if edge.kind == kind]


def nominal_thetas(params: LoopParams, steps: Iterable[Step]) -> list[float]:
    """θ_o at the start and after every step, from the start tilt and the pivots."""
    thetas = [params.start.theta_o]
    for step in steps:
        thetas.append(thetas[-1] + (step.delta if step.kind == "pivot" else 0.0))
    return thetas


@pytest.mark.parametrize("label", OBJECTS)
def test_tour_steps_are_feasible_on_the_true_object(planned: dict[str, Planned], label: str) -> None:
    """The oracle, started where the loop starts (start_config of the returned parameters) with the
    run's hand, finds every step of the tour possible with plan_tour's margin (its full force range
    and lever only widen the planner's LP), and each motion's margin at least the graph edge's; the
    exploration's hand-slide probes are exempt (they end by themselves, slid or not)."""
    plan = planned[label]
    start = start_config(plan.obj, plan.params)
    steps = plan.tour.schedule.steps
    checks = statics.schedule_feasibility(plan.obj, steps, start, plan.params.hand, PLAN_MARGIN)
    assert len(checks) == len(plan.tour.schedule.steps)
    probes = {i for i, s in enumerate(plan.tour.schedule.steps) if s.explore and s.kind == "slide_hand"}
    for check in checks:
        if check.index not in probes:
            assert check.on_face, check.describe()
            assert check.margin >= PLAN_MARGIN - LP_TOLERANCE, check.describe()
    motions = [c for c, s in zip(checks, steps, strict=True) if s.kind != "hold" and not s.explore]
    assert len(motions) == len(plan.tour.edges)
    for check, edge in zip(motions, plan.tour.edges, strict=True):
        assert (check.kind, check.delta) == (edge.kind, edge.delta)
        assert check.margin >= edge.margin - LP_TOLERANCE, check.describe()


@pytest.mark.parametrize("label", OBJECTS)
def test_tour_follows_graph_edges_from_the_start(planned: dict[str, Planned], label: str) -> None:
    """The tour's edges chain from the start node, each one of the reference's edges at its source
    with the reference's margin (direct LP), never below the margin asked."""
    plan = planned[label]
    node = Node(0, 0)
    for edge in plan.tour.edges:
        assert edge.source == node
        expected = plan.setup.reference.edges(node.i, node.j)
        assert key_of(edge) in expected, edge
        assert edge.margin == pytest.approx(expected[key_of(edge)], rel=1e-9, abs=1e-9)
        assert edge.margin >= PLAN_MARGIN
        node = edge.target


@pytest.mark.parametrize("label", OBJECTS)
def test_tour_schedule_and_counts_match_its_edges(planned: dict[str, Planned], label: str) -> None:
    """The schedule is a hold, the exploration (exactly when the reference pivots both ways from the
    start), one step per edge with its kind and increment, and a hold; ``counts`` are the schedule's
    numbers of steps of each kind."""
    plan = planned[label]
    steps = plan.tour.schedule.steps
    assert steps[0].kind == steps[-1].kind == "hold"
    pivots = {sign for kind, sign, _ in plan.setup.reference.edges(0, 0) if kind == "pivot"}
    explore = exploration() if pivots == {1, -1} else ()
    assert tuple(steps[1 : 1 + len(explore)]) == explore
    body = list(steps[1 + len(explore) : -1])
    assert [(s.kind, s.delta) for s in body] == [(e.kind, e.delta) for e in plan.tour.edges]
    assert all(s.tolerance > 0 and not s.explore for s in body)
    for kind in ("pivot", *SLIDE_KINDS):
        assert plan.tour.counts[kind] == sum(step.kind == kind for step in body)


@pytest.mark.parametrize("label", OBJECTS)
def test_tour_leaves_out_the_slides_the_object_never_allows(planned: dict[str, Planned], label: str) -> None:
    """``allowed`` counts the slide edges of the reference reachable from the start; a kind with none
    (e.g. both kinds on the light pentagon, ground slides on the heavy one) is absent from the
    schedule, a kind with some is in it."""
    plan = planned[label]
    reference = plan.setup.reference
    expected = {kind: {1: 0, -1: 0} for kind in SLIDE_KINDS}
    for node in reference.closure((0, 0)):
        for kind, sign, _ in reference.edges(*node):
            if kind in SLIDE_KINDS:
                expected[kind][sign] += 1
    assert plan.tour.allowed == expected
    for kind in SLIDE_KINDS:
        if sum(expected[kind].values()) == 0:
            assert plan.tour.counts[kind] == 0, kind
        else:
            assert plan.tour.counts[kind] > 0, kind


def test_light_pentagon_tour_has_no_slides(planned: dict[str, Planned]) -> None:
    """The paper's pentagon without its added mass allows no slide of either kind anywhere in reach
    with plan_tour's margin and force share (found by direct LPs over the reference's closure); its
    tour holds pivots only, and still as many steps as asked."""
    plan = planned["pentagon-light"]
    reference = plan.setup.reference
    slides = [k for n in reference.closure((0, 0)) for k in reference.edges(*n) if k[0] in SLIDE_KINDS]
    assert slides == []
    assert plan.tour.counts == {"pivot": len(plan.tour.edges), "slide_hand": 0, "slide_ground": 0}
    assert len(plan.tour.edges) >= 32


@pytest.mark.parametrize("label", OBJECTS)
def test_tour_is_as_long_as_asked_where_pivots_never_run_out(planned: dict[str, Planned], label: str) -> None:
    """Where every node in reach has a pivot (reference), the tour holds at least ``steps`` (32)
    motions, and never more ground slides than asked."""
    plan = planned[label]
    reference = plan.setup.reference
    if all(any(k[0] == "pivot" for k in reference.edges(*n)) for n in reference.closure((0, 0))):
        assert len(plan.tour.edges) >= 32
    assert plan.tour.counts["slide_ground"] <= 4


@pytest.mark.parametrize("label", OBJECTS)
def test_tour_keeps_s_g_within_the_ground_span(planned: dict[str, Planned], label: str) -> None:
    """The ground slides' running sum stays within ±ground_span (5 cm by default)."""
    s_g = np.cumsum([0.0, *(e.delta for e in planned[label].tour.edges if e.kind == "slide_ground")])
    assert np.all(np.abs(s_g) <= 0.05 + 1e-12)


@pytest.mark.parametrize("span", [0.005, 0.025, 0.035])
def test_one_way_ground_slides_fill_the_span(planned: dict[str, Planned], span: float) -> None:
    """On the hexagon (ground slides one way only, by the reference), a tour slides the ground as
    often as the span allows: ``min(slides, ⌊span / ground_slide⌋)`` times, all the same way, its
    running ``s_g`` within the span."""
    plan = planned["hexagon"]
    reference = plan.setup.reference
    signs = {k[1] for n in reference.closure((0, 0)) for k in reference.edges(*n) if k[0] == "slide_ground"}
    assert len(signs) == 1
    graph = plan_setup(plan.obj, LoopParams(), plan.params.start.s_h).graph
    tour = possible_tour(graph, steps=12, slides=3, ground_span=span)
    ground = [e.delta for e in tour.edges if e.kind == "slide_ground"]
    assert len(ground) == min(3, math.floor(span / graph.params.ground_slide + 1e-9))
    assert all(math.copysign(1, d) in signs for d in ground)
    assert np.all(np.abs(np.cumsum([0.0, *ground])) <= span + 1e-12)
    assert len(tour.edges) >= 12


@pytest.mark.parametrize("label", OBJECTS)
def test_tour_alternates_ground_slide_directions(planned: dict[str, Planned], label: str) -> None:
    """Where ground slides both ways are in reach (reference), successive ground slides alternate."""
    plan = planned[label]
    reference = plan.setup.reference
    signs = {k[1] for n in reference.closure((0, 0)) for k in reference.edges(*n) if k[0] == "slide_ground"}
    ground = slide_signs(plan.tour.edges, "slide_ground")
    if signs == {1, -1}:
        assert len(ground) >= 2
        assert all(a != b for a, b in itertools.pairwise(ground)), ground


def test_tour_hand_slides_up_to_slides_and_alternating(triangle_candidates: list[Candidate]) -> None:
    """possible_tour's docstring: up to ``slides`` (4) hand slides, alternating their way where both
    ways exist. On every candidate start of the triangle (both ways in reach) the tour's hand slides
    should number at most 4 and alternate. The third candidate (s_h = −10.67 mm) routes through extra
    hand slides: 9 of them, signs − + + − − + + − −."""
    for candidate in triangle_candidates:
        assert candidate.tour is not None
        hand = slide_signs(candidate.tour.edges, "slide_hand")
        assert len(hand) <= 4, (candidate.s_h, hand)
        assert all(a != b for a, b in itertools.pairwise(hand)), (candidate.s_h, hand)


def test_tour_without_both_pivots_has_no_exploration(loop_params: LoopParams) -> None:
    """With the reach ending at the start tilt there is no pivot up from the start (reference): the
    schedule has no exploration, yet every step of it is still one of the reference's edges."""
    obj = build("triangle")
    s_h = candidate_s_h(obj, loop_params)[3]
    theta = loop_params.start.theta_o
    setup = plan_setup(obj, loop_params, float(s_h), angle_range=(HAND_ANGLE_RANGE[0], theta))
    assert {k[1] for k in setup.reference.edges(0, 0) if k[0] == "pivot"} == {-1}
    tour = possible_tour(setup.graph, steps=8)
    assert not any(step.explore for step in tour.schedule.steps)
    assert [(s.kind, s.delta) for s in tour.schedule.steps[1:-1]] == [(e.kind, e.delta) for e in tour.edges]
    node = Node(0, 0)
    for edge in tour.edges:
        assert key_of(edge) in setup.reference.edges(node.i, node.j)
        node = edge.target


# --- plan_tour ----------------------------------------------------------------------------------------


@pytest.mark.parametrize("label", OBJECTS)
def test_plan_tour_starts_the_loop_at_the_chosen_s_h(
    planned: dict[str, Planned], loop_params: LoopParams, label: str
) -> None:
    """The returned parameters start the loop (start_config) at one of the candidate ``s_h`` along
    the face, the rest of the start unchanged; the whole hand lies on the face with 2 mm to spare
    (start geometry), and the start holds with the margin (direct LP with plan_tour's lever and
    forces)."""
    plan = planned[label]
    start = start_config(plan.obj, plan.params)
    assert start == plan.params.start
    assert dataclasses.replace(start, s_h=0.0) == dataclasses.replace(loop_params.start, s_h=0.0)
    assert np.min(np.abs(candidate_s_h(plan.obj, loop_params) - start.s_h)) < 1e-12
    low, high = placement.face_s_h_range(plan.obj, start)
    half = plan.params.hand.half_length
    assert low + half + 2e-3 - 1e-12 <= start.s_h <= high - half - 2e-3 + 1e-12
    placement.start_poses(plan.obj, start, plan.params.hand)  # raises if the hand is off the face
    reference = plan.setup.reference
    hold = statics.best_wrench(
        reference.known, start.theta_o, start.s_h, Motion.HOLD, reference.lever, reference.forces
    )
    assert hold.margin >= PLAN_MARGIN


@pytest.mark.parametrize("label", ["triangle", "hexagon"])
def test_plan_tour_maximises_slides_then_smallest_margin(
    loop_params: LoopParams, triangle_candidates: list[Candidate], label: str
) -> None:
    """plan_tour picks a candidate start of largest (slides counted up to 4 of each kind, smallest
    edge margin) among those whose start holds with the margin (direct LP), and returns that
    candidate's tour. Recomputed here for every candidate (the triangle: distinct scores; the
    hexagon: its scores tie on slides)."""
    found = triangle_candidates if label == "triangle" else candidates_of(label, loop_params)
    scores = []
    for candidate in found:
        if candidate.tour is None:
            continue
        edges = candidate.tour.edges
        slides = sum(min(sum(e.kind == kind for e in edges), 4) for kind in SLIDE_KINDS)
        scores.append(((slides, min((e.margin for e in edges), default=math.inf)), candidate))
    assert len(scores) >= 2
    params, tour = plan_tour(build(label), loop_params, HAND_ANGLE_RANGE)
    chosen = [(score, c) for score, c in scores if abs(c.s_h - params.start.s_h) < 1e-12]
    assert len(chosen) == 1, "the start must be one of the candidates that hold"
    score, candidate = chosen[0]
    assert score == max(score for score, _ in scores)
    assert tour.edges == candidate.tour.edges
    assert tour.schedule == candidate.tour.schedule


@pytest.mark.parametrize("label", OBJECTS)
def test_plan_tour_keeps_to_the_reach_and_off_the_next_vertex(
    planned: dict[str, Planned], label: str
) -> None:
    """Every nominal θ_o of the tour lies within the planar plant's reach, and 5° either side of it the
    object still rests on its start vertex (geometry: lowest vertex), up to the tie band."""
    plan = planned[label]
    face = plan.params.start.hand_face
    first = lowest_vertex_at(plan.obj, face, plan.params.start.theta_o)
    clearance = CLEARANCE - tie_angle(plan.obj)
    for theta in nominal_thetas(plan.params, plan.tour.schedule.steps):
        assert HAND_ANGLE_RANGE[0] <= theta <= HAND_ANGLE_RANGE[1]
        for side in (-1.0, 1.0):
            assert lowest_vertex_at(plan.obj, face, theta + side * clearance) == first, math.degrees(theta)


def test_plan_tour_keeps_to_a_narrower_reach(loop_params: LoopParams) -> None:
    """With a reach narrower than the object's vertex range, every nominal θ_o stays in it and the
    oracle still finds every motion possible with the margin."""
    obj = build("triangle")
    reach = (0.1, 0.6)
    params, tour = plan_tour(obj, loop_params, reach)
    thetas = nominal_thetas(params, tour.schedule.steps)
    assert all(reach[0] - 1e-9 <= theta <= reach[1] + 1e-9 for theta in thetas)
    assert min(thetas) < params.start.theta_o < max(thetas)
    checks = statics.schedule_feasibility(obj, tour.schedule.steps, start_config(obj, params), params.hand)
    for check, step in zip(checks, tour.schedule.steps, strict=True):
        if not (step.explore and step.kind == "slide_hand"):
            assert check.margin >= PLAN_MARGIN - LP_TOLERANCE, check.describe()


@pytest.mark.parametrize(
    ("label", "hand", "options", "message"),
    [
        ("pentagon", Hand(half_length=0.05), {}, "does not fit"),
        ("hexagon", Hand(half_length=0.04), {}, "does not fit"),
        ("pentagon", Hand(), {"margin": 1e3}, "cannot be held"),
        ("triangle", Hand(), {"force_share": 0.0}, "force_share must be in"),
        ("triangle", Hand(), {"angle_range": (0.5, -0.5)}, "empty ranges"),
        ("triangle", Hand(), {"angle_range": (1.5, 1.6)}, "outside the reach"),
    ],
)
def test_plan_tour_rejects_absurd_requests(
    label: str, hand: Hand, options: dict[str, object], message: str
) -> None:
    """A hand longer than the face (geometry: face length < 2·(l_h + 2 mm)), a margin no start can
    hold, no force range to press with, or an empty reach raise ValueError saying so."""
    obj = build(label)
    if message == "does not fit":
        assert obj.face_length(0) < 2 * (hand.half_length + 2e-3)
    options = dict(options)
    angle_range = options.pop("angle_range", HAND_ANGLE_RANGE)
    with pytest.raises(ValueError, match=message):
        plan_tour(obj, LoopParams(hand=hand), angle_range, **options)  # type: ignore[arg-type]


@pytest.mark.parametrize("options", [{"force_share": -1.0}, {"margin": math.nan}], ids=["share", "margin"])
def test_plan_tour_rejects_meaningless_options(loop_params: LoopParams, options: dict[str, float]) -> None:
    """A negative force share (today: a CasADi RuntimeError, f_max < f_min in the LP) or a NaN margin
    (today: accepted, every comparison false, a tour of two holds) raise ValueError."""
    with pytest.raises(ValueError):
        plan_tour(build("triangle"), loop_params, HAND_ANGLE_RANGE, **options)


def test_plan_tour_force_share_beyond_the_hand(loop_params: LoopParams) -> None:
    """A force share above 1 asks for more than the hand's largest force: plan_tour should refuse it,
    or at least plan only steps the oracle (the hand's real limits) finds possible with the margin.
    On the square at share 1.5 it plans pivots the oracle gives 2.25 N < 2.5 N."""
    obj = build("square")
    try:
        params, tour = plan_tour(obj, loop_params, HAND_ANGLE_RANGE, force_share=1.5)
    except ValueError:
        return
    checks = statics.schedule_feasibility(obj, tour.schedule.steps, start_config(obj, params), params.hand)
    for check, step in zip(checks, tour.schedule.steps, strict=True):
        if not (step.explore and step.kind == "slide_hand"):
            assert check.margin >= PLAN_MARGIN - LP_TOLERANCE, check.describe()


def test_plan_tour_rejects_a_start_outside_the_reach(loop_params: LoopParams) -> None:
    """A reach that excludes the run's start tilt (0.3 rad) leaves nothing to plan: ValueError, not a
    schedule of two holds."""
    with pytest.raises(ValueError):
        plan_tour(build("pentagon"), loop_params, (0.4, 0.5))


# --- vertex ranges ------------------------------------------------------------------------------------


def lowest_vertex_at(obj: PlanarObject, face: int, theta_o: float) -> int:
    """The ground-contact vertex with face ``face`` at angle ``θ_o`` (geometry)."""
    angle = geometry.object_angle_for_face(obj.face_normal(face), theta_o)
    return geometry.lowest_vertex(geometry.transform_points(obj.vertices, (0.0, 0.0, angle)))


def tie_angle(obj: PlanarObject) -> float:
    """The largest tilt (rad) at which a face still counts as flat: its far vertex lies within
    LOWEST_TIE of the lowest."""
    return math.asin(geometry.LOWEST_TIE / min(obj.face_length(k) for k in range(obj.n_faces)))


def normal_cone_range(obj: PlanarObject, face: int, theta_o: float) -> tuple[int, float, float]:
    """The vertex under the object at ``θ_o`` and the face angles between which it stays there, from
    the face normals alone: vertex ``v`` is lowest while straight down lies between the outward
    normals of faces ``v − 1`` and ``v``, i.e. ``θ ∈ [α_f − α_v − π, α_f − α_{v−1} − π]`` (``α`` the
    normals' body-frame angles, ``f`` the hand's face)."""
    alpha = [math.atan2(*reversed(obj.face_normal(k))) for k in range(obj.n_faces)]
    for v in range(obj.n_faces):
        exterior = (alpha[v] - alpha[v - 1]) % (2 * math.pi)
        low = alpha[face] - alpha[v] - math.pi
        low += 2 * math.pi * math.floor((theta_o - low) / (2 * math.pi))
        if theta_o - low < exterior:
            return v, low, low + exterior
    raise AssertionError("no vertex under the object")


TILTS = (0.3, -0.2, 0.55)


@pytest.mark.parametrize("label", ["triangle", "square", "rectangle", "pentagon", "hexagon"])
@pytest.mark.parametrize("tilt", TILTS)
def test_vertex_range_ends_where_another_vertex_is_lowest(label: str, tilt: float) -> None:
    """At both ends of vertex_range the start vertex is still the lowest; one step beyond, another
    vertex is (geometry.lowest_vertex)."""
    obj = build(label)
    start = StartConfig(theta_o=tilt)
    step = math.radians(0.5)
    low, high = vertex_range(obj, start, step)
    first = lowest_vertex_at(obj, 0, tilt)
    assert low <= tilt <= high
    assert lowest_vertex_at(obj, 0, low) == first and lowest_vertex_at(obj, 0, high) == first
    assert lowest_vertex_at(obj, 0, low - step) != first
    assert lowest_vertex_at(obj, 0, high + step) != first


@pytest.mark.parametrize("label", ["triangle", "square", "rectangle", "pentagon", "hexagon"])
@pytest.mark.parametrize("tilt", TILTS)
@pytest.mark.parametrize("step_deg", [0.5, 0.05])
def test_vertex_range_matches_the_face_normals(label: str, tilt: float, step_deg: float) -> None:
    """The ends lie within one step (plus the tie band) inside the angles at which a face next to the
    start vertex lies flat, computed from the face normals; the start vertex agrees with geometry."""
    obj = build(label)
    step = math.radians(step_deg)
    vertex, low, high = normal_cone_range(obj, 0, tilt)
    assert vertex == lowest_vertex_at(obj, 0, tilt)
    found_low, found_high = vertex_range(obj, StartConfig(theta_o=tilt), step)
    slack = tie_angle(obj) + 1e-9
    assert low - slack <= found_low <= low + step + slack
    assert high - step - slack <= found_high <= high + slack


def test_vertex_range_does_not_depend_on_s_h() -> None:
    """The range is geometry of the object alone: the hand's position along the face changes nothing."""
    obj = build("triangle")
    ranges = {vertex_range(obj, StartConfig(theta_o=0.3, s_h=s_h)) for s_h in (-0.02, 0.0, 0.03)}
    assert len(ranges) == 1
