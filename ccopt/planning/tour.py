"""A long schedule of possible steps on a known object: the experimenter's tool for closed-loop tests.

:func:`possible_tour` walks the :class:`~ccopt.planning.graph.ConfigurationGraph` of the object's *true*
statics from where a run starts: pivots both ways first (the kinematics need them), then, in turn, the
nearest hand slide and the nearest ground slide of the way not done last (reached through pivots and
hand slides the statics allow with margin), pivots in between, until the schedule is long enough. A
kind of slide the object allows nowhere in reach is left out, and :class:`Tour` says so. Every step of
the result is possible with margin by construction (the oracle of :func:`ccopt.statics.schedule_feasibility`
agrees up to its own margin).
"""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass, field
from typing import TYPE_CHECKING

import numpy as np

from ccopt import geometry, statics
from ccopt.estimation import face
from ccopt.modes import Motion
from ccopt.objects import PlanarObject
from ccopt.planning.graph import ConfigurationGraph, Edge, GraphParams, Node
from ccopt.plant import placement
from ccopt.plant.base import StartConfig
from ccopt.schedule import Schedule, Step, exploration, hold

if TYPE_CHECKING:
    from ccopt.closed_loop import LoopParams

SLIDE_KINDS = ("slide_hand", "slide_ground")
_DETOUR = 1000.0
"""Route cost of a hand slide on the way to another slide, in pivots: any number of pivots first."""


@dataclass(frozen=True)
class Tour:
    """A schedule of possible steps and what the object allowed.

    Attributes:
        schedule: the steps.
        allowed: per slide kind and sign, how many distinct edges of it the graph reachable from the
            start holds (``{"slide_hand": {1: n, -1: m}, ...}``).
        counts: the number of steps of each kind in the schedule.
        edges: the graph's edges the schedule's motions follow (with their margins).
    """

    schedule: Schedule
    allowed: dict[str, dict[int, int]]
    counts: dict[str, int] = field(default_factory=dict)
    edges: tuple[Edge, ...] = ()


def reachable_nodes(graph: ConfigurationGraph, source: Node, limit: int = 2000) -> set[Node]:
    """Every node reachable from ``source`` through pivots and hand slides (breadth first)."""
    seen, queue = {source}, [source]
    while queue and len(seen) < limit:
        node = queue.pop()
        for edge in graph.edges(node):
            if edge.target not in seen:
                seen.add(edge.target)
                queue.append(edge.target)
    return seen


def allowed_slides(graph: ConfigurationGraph, nodes: set[Node]) -> dict[str, dict[int, int]]:
    """How many distinct slide edges of each kind and sign the nodes hold."""
    found: dict[str, dict[int, int]] = {kind: {1: 0, -1: 0} for kind in SLIDE_KINDS}
    for node in nodes:
        for edge in graph.edges(node):
            if edge.kind in SLIDE_KINDS:
                found[edge.kind][int(math.copysign(1, edge.delta))] += 1
    return found


def _as_step(edge: Edge, timeout: float) -> Step:
    tolerance = math.radians(0.5) if edge.kind == "pivot" else 0.0015
    return Step(edge.kind, edge.delta, tolerance, timeout)


def possible_tour(
    graph: ConfigurationGraph,
    steps: int = 32,
    slides: int = 4,
    name: str = "possible-tour",
    timeout: float = 10.0,
    ground_span: float = 0.05,
) -> Tour:
    """At least ``steps`` possible steps from the graph's start with up to ``slides`` hand slides and
    ``slides`` ground slides (alternating their way where both ways exist), or as many as the object
    allows; ``s_g`` is kept within ``±ground_span`` (m) of its start."""
    node = Node(0, 0)
    reach = reachable_nodes(graph, node)
    allowed = allowed_slides(graph, reach)
    edges: list[Edge] = []
    done = {kind: 0 for kind in SLIDE_KINDS}
    way = {kind: 1 for kind in SLIDE_KINDS}
    s_g = 0.0
    stuck = 0

    def wanting() -> bool:
        return len(edges) < steps or any(done[k] < slides and sum(allowed[k].values()) for k in SLIDE_KINDS)

    while wanting() and stuck < 4:
        progressed = False
        for kind in SLIDE_KINDS:
            if done[kind] >= slides or not sum(allowed[kind].values()):
                continue
            for sign in (way[kind], -way[kind]):
                if kind == "slide_ground" and abs(s_g + sign * graph.params.ground_slide) > ground_span:
                    continue
                hand_way = way["slide_hand"] if done["slide_hand"] < slides else 0
                route = _route_to_slide(graph, node, kind, sign, hand_way)
                if route is None:
                    continue
                edges.extend(route)
                node = route[-1].target
                if kind == "slide_ground":
                    s_g += route[-1].delta
                for edge in route[:-1]:  # a hand slide on the way counts as one of the tour's
                    if edge.kind == "slide_hand":
                        done["slide_hand"] += 1
                        way["slide_hand"] = -way["slide_hand"]
                done[kind] += 1
                way[kind] = -sign
                progressed = True
                break
        if len(edges) < steps:
            pivot = next((e for e in graph.edges(node) if e.kind == "pivot"), None)
            if pivot is not None:
                edges.append(pivot)
                node = pivot.target
                progressed = True
        stuck = 0 if progressed else stuck + 1
    explore = exploration() if _explorable(graph) else ()
    steps = (hold(0.5), *explore, *(_as_step(edge, timeout) for edge in edges), hold(0.5))
    schedule = Schedule(name, steps)
    counts = {kind: sum(edge.kind == kind for edge in edges) for kind in ("pivot", *SLIDE_KINDS)}
    return Tour(schedule, allowed, counts, tuple(edges))


def _explorable(graph: ConfigurationGraph) -> bool:
    """Whether the exploration's pivots (:func:`ccopt.schedule.exploration`) are possible from the
    start: one pivot each way."""
    start = Node(0, 0)
    ways = {int(math.copysign(1, e.delta)) for e in graph.edges(start) if e.kind == "pivot"}
    return ways == {1, -1}


def _route_to_slide(
    graph: ConfigurationGraph, source: Node, kind: str, sign: int, hand_way: int
) -> list[Edge] | None:
    """Pivots to the nearest node with a slide of ``kind`` and ``sign``, then the slide; a hand slide
    on the way only in ``hand_way`` (0: none), and only where pivots alone do not get there."""

    def slide_from(node: Node) -> Edge | None:
        return next(
            (e for e in graph.edges(node) if e.kind == kind and math.copysign(1, e.delta) == sign), None
        )

    def cost(edge: Edge) -> float:
        if edge.kind == "pivot":
            return 1.0
        return _DETOUR if math.copysign(1, edge.delta) == hand_way else math.inf

    path = graph.shortest_path(source, lambda node: slide_from(node) is not None, cost)
    if path is None:
        return None
    end = path[-1].target if path else source
    return [*path, slide_from(end)]


def vertex_range(
    obj: PlanarObject, start: StartConfig, step: float = math.radians(0.5)
) -> tuple[float, float]:
    """The face angles ``θ_o`` (rad) over which the object keeps resting on the vertex it starts on
    (the experimenter's geometry: beyond, another vertex touches the ground)."""

    def vertex(theta: float) -> int:
        angle = geometry.object_angle_for_face(obj.face_normal(obj.face_index(start.hand_face)), theta)
        return geometry.lowest_vertex(geometry.transform_points(obj.vertices, (0.0, 0.0, angle)))

    first = vertex(start.theta_o)
    ends = []
    for sign in (-1.0, 1.0):
        theta = start.theta_o
        while abs(theta - start.theta_o) < math.pi and vertex(theta + sign * step) == first:
            theta += sign * step
        ends.append(theta)
    return ends[0], ends[1]


def plan_tour(
    obj: PlanarObject,
    params: LoopParams,
    angle_range: tuple[float, float],
    margin: float = 2.5,
    force_share: float = 0.75,
    candidates: int = 7,
    **tour_options: object,
) -> tuple[LoopParams, Tour]:
    """The experimenter's schedule for ``obj``: among start positions ``s_h`` of the hand along its
    face (``candidates`` of them, at the run's start tilt), the one whose :func:`possible_tour` holds
    the most slides (up to the number asked for of each kind), then the largest smallest margin along
    its steps (a start off the ground contact may leave pivots possible only near the least normal
    force, where the torque window ``±l_h f_n`` is a fraction of a degree of the hand's impedance),
    with the loop parameters that start there. ``angle_range`` is the robot's reach in ``θ_h``
    (rad); the object's own vertex range and ``5°`` of clearance narrow it. Every step (and the
    start) keeps ``margin`` (N) with a normal force within ``force_share`` of the hand's range and
    the estimate's torque lever: headroom for what the statics ignore (the contacts' compliance, the
    dynamics); the hand's contact patch is cut to the part of the face the run knows, under the hand
    at the start (:mod:`ccopt.estimation.face`; the run knows no more unless the centre of pressure
    goes there). Uses the true object: never for the estimator or the controller."""
    if not (math.isfinite(margin) and margin >= 0.0):
        raise ValueError(f"margin must be a non-negative number of N, got {margin!r}")
    if not 0.0 < force_share <= 1.0:
        raise ValueError(f"force_share must be in (0, 1] of the hand's force range, got {force_share!r}")
    if not angle_range[0] < angle_range[1]:
        raise ValueError(f"empty ranges: the reach {angle_range}")
    if not angle_range[0] <= params.start.theta_o <= angle_range[1]:
        low, high, start = (math.degrees(v) for v in (*angle_range, params.start.theta_o))
        raise ValueError(f"the start tilt {start:.1f}° is outside the reach [{low:.1f}°, {high:.1f}°]")
    base = dataclasses.replace(params.start, s_h=0.0)
    low, high = placement.face_s_h_range(obj, base)
    inset = params.hand.half_length + 2e-3
    if high - low < 2.0 * inset:
        raise ValueError(f"the hand does not fit on face {base.hand_face} of {obj.name}")
    tilt_low, tilt_high = vertex_range(obj, base)
    clearance = math.radians(5.0)
    theta_range = (max(angle_range[0], tilt_low + clearance), min(angle_range[1], tilt_high - clearance))
    wanted = int(tour_options.get("slides", 4))
    lever = params.estimator_params.friction.torque_margin * params.hand.half_length  # as the run knows it
    face_margin = params.estimator_params.face.margin
    f_min, f_max = params.hand.force_limits
    forces = (f_min, f_min + force_share * (f_max - f_min))  # headroom for what the model ignores
    best: tuple[tuple[int, float], LoopParams, Tour] | None = None
    for s_h in np.linspace(low + inset, high - inset, candidates):
        start = dataclasses.replace(base, s_h=float(s_h))
        trial = dataclasses.replace(params, start=start, centre_hand=False)
        truth = statics.true_statics(obj, start, params.hand)
        graph_params = GraphParams(s_h_range=truth.s_h_range, theta_range=theta_range, min_margin=margin)
        where = (truth.theta_o, truth.s_h)
        start_face = face.inside(face.hand_extent(params.hand.half_length, start.s_h), face_margin)
        known = dataclasses.replace(truth.statics, face=start_face)
        graph = ConfigurationGraph(known, where, lever, forces, graph_params)
        if graph.margin(Node(0, 0), Motion.HOLD) < margin:
            continue  # the run could not even hold its start comfortably
        tour = possible_tour(graph, **tour_options)
        slides = sum(min(tour.counts[kind], wanted) for kind in SLIDE_KINDS)
        score = (slides, min((edge.margin for edge in tour.edges), default=-math.inf))
        if best is None or score > best[0]:
            best = (score, trial, tour)
    if best is None:
        raise ValueError(f"{obj.name} cannot be held with a margin of {margin} N anywhere on its face")
    return best[1], best[2]
