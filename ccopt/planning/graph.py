"""The graph of contact configurations and the motions between them that the statics allow.

Nodes are configurations ``(θ_o, s_h)`` on a grid around a start: ``θ_o`` in steps of the paper's
pivot (7.2°), ``s_h`` in steps of :attr:`GraphParams.s_h_step` (the hand slide is a multiple of it),
and, where :attr:`GraphParams.end_pivot` says so, the ends of the ``θ_o`` range beyond the grid's
outermost nodes (a partial pivot takes the object there). The
ground slide does not change ``(θ_o, s_h)``: it is a loop on a node that moves ``s_g``, which the
statics do not depend on. An edge is a motion whose statics (:func:`ccopt.statics.best_wrench`) have a
margin of at least :attr:`GraphParams.min_margin` at both ends and in between (a hand slide and a pivot
are checked at every grid point they pass), within the limits the caller knows: the range of ``θ_o``
the robot reaches and the object stays on its vertex, and the range of ``s_h`` over which the hand lies
on the face.

Margins are cached per node and motion: a graph over a 20 × 15 grid costs a few hundred LPs (≈60 µs
each).
"""

from __future__ import annotations

import heapq
import math
from collections.abc import Callable, Iterator
from dataclasses import dataclass

from ccopt import statics
from ccopt.modes import Motion
from ccopt.statics import ObjectStatics


@dataclass(frozen=True)
class GraphParams:
    """The grid and what an edge needs. Angles in rad, lengths in m, forces in N.

    Attributes:
        pivot_step: ``θ_o`` grid step and pivot increment (the paper's 7.2°).
        s_h_step: ``s_h`` grid step.
        hand_slide: hand-slide increment, a multiple of ``s_h_step`` (the paper's 10 mm).
        ground_slide: ground-slide increment (the paper's 10 mm).
        theta_range: ``(θ_min, θ_max)`` the robot may take the object to.
        s_h_range: ``(s_h_min, s_h_max)`` over which the whole hand lies on the face.
        min_margin: margin every point of an edge needs.
        end_pivot: where an end of ``theta_range`` lies further than this (rad) beyond the grid's
            outermost node, the end is a node of its own, one partial pivot on (None: no such
            nodes). The range's ends are often where the object's tipping point cuts it, and the
            motions that need the largest tilt, a ground slide against the tilt's way, are possible
            only there: on a goals-study triangle that lands on a face at −23.8°, its slide towards
            −s_g needed a tilt below about −20° (the estimate's statics), and the grid from 10°
            stopped at −18.8°.
    """

    pivot_step: float = math.radians(7.2)
    s_h_step: float = 0.005
    hand_slide: float = 0.010
    ground_slide: float = 0.010
    theta_range: tuple[float, float] = (math.radians(-40.0), math.radians(50.0))
    s_h_range: tuple[float, float] = (-0.05, 0.05)
    min_margin: float = 1.0
    end_pivot: float | None = None

    def __post_init__(self) -> None:
        for name in ("pivot_step", "s_h_step", "ground_slide"):
            value = getattr(self, name)
            if not (math.isfinite(value) and value > 0.0):
                raise ValueError(f"graph steps must be positive and finite: {name} = {value!r}")
        ratio = self.hand_slide / self.s_h_step
        if not math.isfinite(ratio) or abs(ratio - round(ratio)) > 1e-9 or round(ratio) < 1:
            raise ValueError(f"hand_slide must be a multiple of s_h_step, got {self.hand_slide!r}")
        if not math.isfinite(self.min_margin):
            raise ValueError(f"min_margin must be a finite number of N, got {self.min_margin!r}")
        if not (self.theta_range[0] <= self.theta_range[1] and self.s_h_range[0] <= self.s_h_range[1]):
            raise ValueError(f"empty ranges: θ {self.theta_range}, s_h {self.s_h_range}")
        if self.end_pivot is not None and not (math.isfinite(self.end_pivot) and self.end_pivot >= 0.0):
            raise ValueError(f"end_pivot must be a non-negative angle in rad or None, got {self.end_pivot!r}")


@dataclass(frozen=True, order=True)
class Node:
    """A grid configuration: ``θ_o = θ_start + i · pivot_step`` (an end node: the end of the range),
    ``s_h = s_h_start + j · s_h_step``."""

    i: int
    j: int


@dataclass(frozen=True)
class Edge:
    """A motion from one node to another (a ground slide returns to its node).

    Attributes:
        kind: ``pivot``, ``slide_hand`` or ``slide_ground``.
        delta: the increment, rad or m (signed).
        source, target: the nodes.
        margin: the smallest statics margin along the motion, N.
    """

    kind: str
    delta: float
    source: Node
    target: Node
    margin: float


Statics = ObjectStatics | tuple[ObjectStatics, ...]
"""The statics a motion is judged on: one, or several that it must hold under alike (the hand
friction at both ends of what an estimate knows of it, :mod:`ccopt.planning.sequencer`)."""


def least_margin(
    known: Statics,
    theta_o: float,
    s_h: float,
    motion: Motion,
    lever: float,
    force_limits: tuple[float, float],
) -> float:
    """The smallest of the largest margins (N) of ``motion`` at ``(θ_o, s_h)`` under every statics of
    ``known`` (:func:`ccopt.statics.best_wrench`)."""
    every = known if isinstance(known, tuple) else (known,)
    return min(statics.best_wrench(k, theta_o, s_h, motion, lever, force_limits).margin for k in every)


class ConfigurationGraph:
    """The motions the statics ``known`` allow around ``(θ_start, s_h_start)``.

    Args:
        known: the object's statics (true or estimated), or per motion (an estimate knows a ground
            row differently for a motion that keeps the ground and one that slides it across), each
            one statics or several a motion must hold under alike (:data:`Statics`).
        start: ``(θ_o, s_h)`` of the grid's origin node, rad and m.
        lever: the torque rows' lever ``l_h`` (m) and ``force_limits`` ``(f_min, f_max)`` (N).
        params: grid and margin.
        reachable: optional ``(θ_o, s_h) → bool`` of further limits (e.g. the arm's reach).
        barred: optional ``(θ_o, motion) → bool``: motions seen failing at a tilt whatever the
            statics say (a hand slide the hand held against there), given no margin.
    """

    def __init__(
        self,
        known: Statics | Callable[[Motion], Statics],
        start: tuple[float, float],
        lever: float,
        force_limits: tuple[float, float],
        params: GraphParams | None = None,
        reachable: Callable[[float, float], bool] | None = None,
        barred: Callable[[float, Motion], bool] | None = None,
    ) -> None:
        self.known = known
        self.start = start
        self.lever = lever
        self.force_limits = force_limits
        self.params = params or GraphParams()
        self._reachable = reachable
        self._barred = barred
        self._stride = round(self.params.hand_slide / self.params.s_h_step)
        self._margins: dict[tuple[Node, Motion], float] = {}
        self._ends = _end_nodes(start[0], self.params)

    def configuration(self, node: Node) -> tuple[float, float]:
        """``(θ_o, s_h)`` of a node, rad and m."""
        theta = self._ends.get(node.i)
        return (
            self.start[0] + node.i * self.params.pivot_step if theta is None else theta,
            self.start[1] + node.j * self.params.s_h_step,
        )

    def node_of(self, theta_o: float, s_h: float) -> Node:
        """The nearest node to a configuration."""
        return Node(
            round((theta_o - self.start[0]) / self.params.pivot_step),
            round((s_h - self.start[1]) / self.params.s_h_step),
        )

    def inside(self, node: Node) -> bool:
        """Whether a node lies within the ranges (and the caller's reach)."""
        return self.inside_at(*self.configuration(node))

    def inside_at(self, theta: float, s_h: float) -> bool:
        """Whether any ``(θ_o, s_h)`` (rad, m) lies within the ranges (and the caller's reach)."""
        (t_lo, t_hi), (s_lo, s_hi) = self.params.theta_range, self.params.s_h_range
        if not (t_lo - 1e-9 <= theta <= t_hi + 1e-9 and s_lo - 1e-9 <= s_h <= s_hi + 1e-9):
            return False
        return self._reachable is None or self._reachable(theta, s_h)

    def margin(self, node: Node, motion: Motion) -> float:
        """The statics margin of ``motion`` at a node, N (cached: a graph lives as long as its statics)."""
        key = (node, motion)
        if key not in self._margins:
            self._margins[key] = self.margin_at(*self.configuration(node), motion)
        return self._margins[key]

    def margin_at(self, theta_o: float, s_h: float, motion: Motion) -> float:
        """The statics margin of ``motion`` at any ``(θ_o, s_h)`` (rad, m), N; −inf where barred."""
        if self._barred is not None and self._barred(theta_o, motion):
            return -math.inf
        known = self.known(motion) if callable(self.known) else self.known
        return least_margin(known, theta_o, s_h, motion, self.lever, self.force_limits)

    def edges(self, node: Node) -> Iterator[Edge]:
        """Every motion the statics allow from ``node`` (pivots, hand slides, ground slides)."""
        p = self.params
        for sign in (1, -1):
            yield from self._path_edge(node, Motion.PIVOT, "pivot", sign * p.pivot_step, (sign, 0), 1)
            hand = Motion.SLIDE_HAND_POS if sign > 0 else Motion.SLIDE_HAND_NEG
            yield from self._path_edge(node, hand, "slide_hand", sign * p.hand_slide, (0, sign), self._stride)
            ground = Motion.SLIDE_GROUND_POS if sign > 0 else Motion.SLIDE_GROUND_NEG
            margin = self.margin(node, ground) if self.inside(node) else -math.inf
            if margin >= p.min_margin:
                yield Edge("slide_ground", sign * p.ground_slide, node, node, margin)

    def _path_edge(
        self, node: Node, motion: Motion, kind: str, delta: float, step: tuple[int, int], count: int
    ) -> Iterator[Edge]:
        path = [Node(node.i + k * step[0], node.j + k * step[1]) for k in range(count + 1)]
        if not all(self.inside(n) for n in path):
            return
        margin = min(self.margin(n, motion) for n in path)
        if margin >= self.params.min_margin:
            if kind == "pivot":  # a partial pivot to or from an end node
                delta = self.configuration(path[-1])[0] - self.configuration(node)[0]
            yield Edge(kind, delta, node, path[-1], margin)

    def shortest_path(
        self, source: Node, goal: Callable[[Node], bool], cost: Callable[[Edge], float] | None = None
    ) -> list[Edge] | None:
        """The cheapest sequence of edges from ``source`` to a node where ``goal`` holds (Dijkstra;
        unit cost per motion by default); None if no such node is reachable. Ground slides are never
        on a path (they do not move a node)."""
        cost = cost or (lambda edge: 1.0)
        frontier: list[tuple[float, int, Node]] = [(0.0, 0, source)]
        came: dict[Node, tuple[Node, Edge] | None] = {source: None}
        best = {source: 0.0}
        counter = 1
        while frontier:
            spent, _, node = heapq.heappop(frontier)
            if spent > best.get(node, math.inf):
                continue
            if goal(node):
                return _unwind(came, node)
            for edge in self.edges(node):
                if edge.kind == "slide_ground":
                    continue
                total = spent + cost(edge)
                if total < best.get(edge.target, math.inf):
                    best[edge.target] = total
                    came[edge.target] = (node, edge)
                    heapq.heappush(frontier, (total, counter, edge.target))
                    counter += 1
        return None


def _end_nodes(theta_start: float, params: GraphParams) -> dict[int, float]:
    """``{i: θ}`` of the end nodes (:attr:`GraphParams.end_pivot`): the index one step beyond the
    grid's outermost node within the range, where the range's end lies further on than
    ``end_pivot``, and that end; none without ``end_pivot`` or on a range that does not hold the start."""
    low, high = params.theta_range
    if params.end_pivot is None or not low - 1e-9 <= theta_start <= high + 1e-9:
        return {}
    step, ends = params.pivot_step, {}
    for end, way in zip(params.theta_range, (-1, 1), strict=True):
        outermost = math.floor(way * (end - theta_start) / step + 1e-9) * way
        if way * (theta_start + outermost * step - end) > 1e-9:  # rounding put it past the end
            outermost -= way
        if abs(end - (theta_start + outermost * step)) > params.end_pivot:
            ends[outermost + way] = end
    return ends


def _unwind(came: dict[Node, tuple[Node, Edge] | None], node: Node) -> list[Edge]:
    path = []
    while came[node] is not None:
        previous, edge = came[node]
        path.append(edge)
        node = previous
    return path[::-1]
