"""Goals into motions: the next admissible motion towards a goal, from what the statics allow.

The paper's sequences were scripted by a person who could see the object; its future work is a
layer that sequences contact configurations automatically. :func:`next_motion` is that layer, one
motion at a time: it builds the :class:`~ccopt.planning.graph.ConfigurationGraph` of the statics it
is given around the current configuration (``θ_o`` in the paper's 7.2° pivots, ``s_h`` on a 5 mm
grid with 10 mm hand slides; a ground slide is a loop on a node) and

1. if the goal moves the ground contact (``s_g``) by more than its tolerance, goes to the nearest
   node where a ground slide that way is possible with margin, and slides (10 mm, or what is left);
   where no node has one, pivots towards the nearest tilt between the nodes that has
   (:func:`pivot_between_nodes`);
2. else goes to the node nearest the goal's ``(θ_o, s_h)`` by the fewest motions;
3. from there, closes the rest with one partial pivot or hand slide, if the statics allow it.

Only the first motion of a path is returned: the caller executes it and asks again with the new
estimate, so every plan uses the statics as they are then known
(:func:`ccopt.control.targets.estimated_statics`: ground rows the ground was seen sliding past,
``μ̂_h``, the gravity moment). Where no sequence
reaches the goal the answer is ``unreachable``, with the coordinate that blocks and why; a caller
that may explore (the hand friction ``μ̂_h`` is a lower bound until the hand slides) asks again with
bolder statics (:attr:`Plan.explores`). The same function on the *true* statics is the
experimenter's oracle (:func:`oracle_plan`).

Coordinates: ``θ_o`` (rad) and ``s_h`` (m) as the estimator reports them; ``s_g`` (m) relative to the
ground contact at the run's start (``s_g_origin``). The planner never leaves ``reach`` (the robot's
hand angles, which are the flush face's; a goal's sequencer cuts them where a pivot found the
object's tipping point, and from a tilt beyond first pivots back within, :func:`back_within`) nor
the band of ``s_h`` between the start and the goal widened by :attr:`PlannerParams.s_h_span`;
within it, the statics cut the hand's contact patch to the part of the face the estimate knows
(``ObjectStatics.face``, :mod:`ccopt.estimation.face`).
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from ccopt.modes import Motion, motion_of
from ccopt.planning.graph import ConfigurationGraph, Edge, GraphParams, Node, Statics
from ccopt.planning.tour import reachable_nodes
from ccopt.schedule import DEFAULT_TIMEOUT, DEFAULT_TOLERANCE, PIVOT_STEP, SLIDE_STEP, Goal, Step
from ccopt.statics import ObjectStatics
from ccopt.validation import check_number

PLAN_STATUSES = ("move", "reached", "unreachable")
"""What a plan says: take :attr:`Plan.motion`; the goal is reached; no sequence reaches it."""
COORDINATE_NAMES = ("θ_o", "s_h", "s_g")

StaticsOf = Callable[[Motion], Statics]
"""The statics a motion is judged on (per motion: an estimate knows a ground row differently for a
motion that keeps the ground and for one that slides across it; and a hand slide, before the hand
has slid, at both ends of what is known of the hand friction)."""


@dataclass(frozen=True)
class PlannerParams:
    """How the planner searches. Angles in rad, lengths in m, forces in N.

    Attributes:
        margin: every planned motion keeps at least this statics margin at both ends and between.
        pivot_step: the grid's ``θ_o`` step and a full pivot (the paper's 7.2°).
        s_h_step: the grid's ``s_h`` step.
        hand_slide: a full hand slide (a multiple of ``s_h_step``; the paper's 10 mm).
        ground_slide: a full ground slide (the paper's 10 mm).
        s_h_span: how far beyond the current and the goal's ``s_h`` a plan may take the hand.
        motion_timeout: the timeout of each planned motion, s.
        aim: the share of a goal's tolerances the plan aims within: the estimate errs by up to a
            millimetre where the truth is (the ground contact after a slide, the run's start), and
            a goal is only reached if the truth is within the whole tolerance.
        hand_friction_max: the largest hand friction coefficient believed possible. Until the hand
            has slid, ``μ̂_h`` is only a lower bound (the largest ratio seen sticking): a hand slide
            is planned as certain only where it keeps the margin at both (:mod:`ccopt.planning.sequencer`).
    """

    margin: float = 1.0
    pivot_step: float = PIVOT_STEP
    s_h_step: float = 0.005
    hand_slide: float = SLIDE_STEP
    ground_slide: float = SLIDE_STEP
    s_h_span: float = 0.02
    motion_timeout: float = DEFAULT_TIMEOUT
    aim: float = 0.5
    hand_friction_max: float = 1.0

    def __post_init__(self) -> None:
        check_number("margin", self.margin, low_open=False)
        for name in ("pivot_step", "s_h_step", "hand_slide", "ground_slide", "motion_timeout"):
            check_number(name, getattr(self, name))
        check_number("s_h_span", self.s_h_span, low_open=False)
        check_number("aim", self.aim, 0.0, 1.0)
        check_number("hand_friction_max", self.hand_friction_max)


@dataclass(frozen=True)
class Plan:
    """The planner's answer.

    Attributes:
        status: one of :data:`PLAN_STATUSES`.
        motion: the motion to take now (``move``), else None.
        reason: why the goal is unreachable (one line), else "".
        path: the motions planned from here (the first is ``motion``, partial moves aside).
        explores: whether ``motion`` is a probe: the plan relies on statics bolder than the
            estimate's (the hand friction one step beyond ``μ̂_h``), or ``motion`` is a hand slide
            the estimate cannot make certain (:mod:`ccopt.planning.sequencer`).
    """

    status: str
    motion: Step | None = None
    reason: str = ""
    path: tuple[Edge, ...] = ()
    explores: bool = False


REACHED = Plan("reached")


def next_motion(
    statics_of: StaticsOf,
    where: tuple[float, float, float],
    goal: Goal,
    s_g_origin: float,
    reach: tuple[float, float],
    lever: float,
    force_limits: tuple[float, float],
    params: PlannerParams | None = None,
    face: tuple[float, float] | None = None,
    failed_slides: dict[int, float] | None = None,
    barred: Callable[[float, Motion], bool] | None = None,
) -> Plan:
    """The next motion towards ``goal`` from ``where = (θ_o, s_h, s_g)`` (see the module docstring).

    ``lever`` is the torque rows' lever (m) and ``force_limits`` the normal force range (N) the
    statics are judged with; ``reach`` the ``θ_o`` range (rad) the robot may take the object to;
    ``face`` the range of ``s_h`` (m) over which the hand lies on the face, where known (the
    experimenter's oracle: the whole hand on the face; the estimate's statics know only a part of
    it, :attr:`ccopt.statics.ObjectStatics.face`); ``failed_slides``
    the tilts ``θ_o`` (rad) at which a ground slide each way (``+1``, ``-1``) was tried and did not
    start: a slide towards ``±s_g`` is then sought only at tilts at least half a pivot step beyond,
    further that way (tilting the hand's normal towards the slide is what lets the hand push the
    object along); ``barred(θ_o, motion)`` the motions seen failing at a tilt whatever the statics
    say (:class:`~ccopt.planning.graph.ConfigurationGraph`).
    """
    params = params or PlannerParams()
    errors = goal.errors(np.asarray(where, dtype=float), s_g_origin)
    tolerances = params.aim * goal.tolerances
    if np.all(np.abs(errors) <= tolerances):
        return REACHED
    graph = _graph(statics_of, where, goal, reach, lever, force_limits, params, face, barred)
    if abs(errors[2]) > tolerances[2]:
        return _towards_ground(graph, errors[2], goal, statics_of, lever, params, failed_slides or {})
    return _towards_configuration(graph, where, errors, tolerances, goal, statics_of, lever, params)


def _graph(
    statics_of: StaticsOf,
    where: tuple[float, float, float],
    goal: Goal,
    reach: tuple[float, float],
    lever: float,
    force_limits: tuple[float, float],
    params: PlannerParams,
    face: tuple[float, float] | None,
    barred: Callable[[float, Motion], bool] | None = None,
) -> ConfigurationGraph:
    theta, s_h, _ = where
    target = s_h if goal.s_h is None else goal.s_h
    band = (min(s_h, target) - params.s_h_span, max(s_h, target) + params.s_h_span)
    if face is not None:
        band = (max(band[0], min(face[0], s_h)), min(band[1], max(face[1], s_h)))
    low, high = min(reach[0], theta), max(reach[1], theta)
    grid = GraphParams(
        pivot_step=params.pivot_step,
        s_h_step=params.s_h_step,
        hand_slide=params.hand_slide,
        ground_slide=params.ground_slide,
        theta_range=(low, high),
        s_h_range=band,
        min_margin=params.margin,
        end_pivot=DEFAULT_TOLERANCE["pivot"],
    )
    return ConfigurationGraph(statics_of, (theta, s_h), lever, force_limits, grid, barred=barred)


def back_within(theta: float, reach: tuple[float, float], params: PlannerParams) -> Plan | None:
    """A pivot back inside ``reach`` from a tilt ``theta`` (rad) beyond it by more than a pivot's
    tolerance; None within. A pivot that found the object's tipping point leaves it lying on a face
    past the reach: no statics of the vertex hold there (a ground slide tried on a random triangle
    lying on its face at −24.4° rolled the hand, and its failure then barred slides at every tilt
    the vertex allowed).

    The pivot aims a tolerance inside the edge, so that it ends within the reach wherever within
    its tolerance it stops. Aimed at the edge itself it stopped short of it, past the reach: the
    paper pentagon (seeds 0 and 1) was left 0.3–0.4° short of its tipping point by the truth, with
    its far vertex on the ground, and its ground slide there did not start
    (:mod:`tests.test_tipping_point`)."""
    beyond = past_reach(theta, reach)
    tolerance = DEFAULT_TOLERANCE["pivot"]
    if abs(beyond) <= tolerance:
        return None
    return Plan("move", _step("pivot", -beyond - math.copysign(tolerance, beyond), params))


def past_reach(theta: float, reach: tuple[float, float]) -> float:
    """How far (rad) the tilt ``theta`` lies beyond ``reach = (low, high)``: positive above ``high``,
    negative below ``low``, 0 within."""
    low, high = reach
    return theta - min(max(theta, low), high)


def _towards_ground(
    graph: ConfigurationGraph,
    error: float,
    goal: Goal,
    statics_of: StaticsOf,
    lever: float,
    params: PlannerParams,
    failed: dict[int, float],
) -> Plan:
    """Slide the ground contact ``error`` (m) closer, going first where the slide is possible; past
    a failed slide that way, only at least half a pivot step further (a retry from where exploring
    left the object, a degree on, failed as its first try did)."""
    sign = 1.0 if error > 0.0 else -1.0
    tried = failed.get(int(sign))
    beyond = 0.5 * graph.params.pivot_step

    def allowed(theta: float) -> bool:
        return tried is None or (theta - tried) * sign >= beyond

    def slides(node: Node) -> Edge | None:
        if not allowed(graph.configuration(node)[0]):
            return None
        return next((e for e in graph.edges(node) if e.kind == "slide_ground" and e.delta * sign > 0.0), None)

    path = graph.shortest_path(Node(0, 0), lambda node: slides(node) is not None, _motion_cost)
    if path is None:
        slide = Motion.SLIDE_GROUND_POS if sign > 0.0 else Motion.SLIDE_GROUND_NEG
        pivot = pivot_between_nodes(graph, slide, allowed)
        if pivot is not None:
            return Plan("move", _step("pivot", pivot, params))
        return Plan(
            "unreachable",
            reason=f"s_g {_length(goal.s_g)}: no ground slide {towards(sign, 's_g')} is possible at any tilt "
            f"in {_degrees(graph.params.theta_range)}{_limits(statics_of, lever)}",
        )
    if path:
        return _move(path[0], params, tuple(path))
    length = sign * min(abs(error), graph.params.ground_slide)
    return Plan("move", _step("slide_ground", length, params), path=(slides(Node(0, 0)),))


FINE_PIVOTS = 4
"""Points per pivot step at which :func:`pivot_between_nodes` looks between the grid's tilts."""


def pivot_between_nodes(
    graph: ConfigurationGraph, motion: Motion, allowed: Callable[[float], bool]
) -> float | None:
    """The pivot (rad, at most a grid step) towards the nearest tilt where ``motion`` keeps the
    graph's margin, looked for every ``pivot_step / FINE_PIVOTS`` from the graph's start at its
    ``s_h``, through tilts where a pivot keeps the margin too and within the graph's ranges and reach
    (:meth:`~ccopt.planning.graph.ConfigurationGraph.inside_at`); ``allowed(θ_o)`` may rule tilts
    out. None where there is no such tilt.

    Where the grid has no node with the motion, its tilts may lie between nodes: a ground slide
    against the tilt's way is possible only past a tilt, and a pivot only short of another, and the
    window between them can be narrower than a pivot step. On a goals-study triangle (μ_g 0.40)
    the estimate allowed a slide towards −s_g from about 2° down and pivots to about −4°; the grid from 38.3°
    had nodes at 2.3° (the slide's margin 0.8 N) and −4.9° (the pivot's 0.6 N), and the goal was
    reported unreachable where the oracle reached it."""
    theta, s_h = graph.start
    least, step = graph.params.min_margin, graph.params.pivot_step / FINE_PIVOTS
    if graph.margin_at(theta, s_h, Motion.PIVOT) < least:
        return None
    nearest: float | None = None
    for way in (1.0, -1.0):
        tilt = theta + way * step
        while graph.inside_at(tilt, s_h) and graph.margin_at(tilt, s_h, Motion.PIVOT) >= least:
            if allowed(tilt) and graph.margin_at(tilt, s_h, motion) >= least:
                if nearest is None or abs(tilt - theta) < abs(nearest):
                    nearest = tilt - theta
                break
            tilt += way * step
    if nearest is None:
        return None
    return math.copysign(min(abs(nearest), graph.params.pivot_step), nearest)


def _towards_configuration(
    graph: ConfigurationGraph,
    where: tuple[float, float, float],
    errors: np.ndarray,
    tolerances: np.ndarray,
    goal: Goal,
    statics_of: StaticsOf,
    lever: float,
    params: PlannerParams,
) -> Plan:
    """Go to a node within half a step of the goal's ``(θ_o, s_h)`` from where the rest closes with
    partial motions that keep the margin, by the fewest motions; then close it. A free coordinate
    may end anywhere: an ``s_h`` goal held at the tilt it began at was reported unreachable on a
    random triangle whose hand slide towards ``+s_h`` keeps its margin only 29° lower, where the
    oracle slides it."""
    grid = graph.params
    half = np.array([0.5 * grid.pivot_step, 0.5 * grid.hand_slide])
    given = np.array([goal.theta_o is not None, goal.s_h is not None])

    def left_at(node: Node) -> np.ndarray:
        theta, s_h = graph.configuration(node)
        return np.where(given, errors[:2] - (theta - where[0], s_h - where[1]), 0.0)

    def rest(node: Node) -> list[tuple[str, float]]:
        left = left_at(node)
        return [
            (kind, float(left[k]))
            for k, kind in ((0, "pivot"), (1, "slide_hand"))
            if abs(left[k]) > tolerances[k]
        ]

    def near(node: Node) -> bool:
        theta, s_h = graph.configuration(node)
        left = left_at(node)
        if np.any(np.abs(left) > half + 1e-12):
            return False
        return _closing_margin(graph, (theta, s_h), rest(node)) >= params.margin

    path = graph.shortest_path(Node(0, 0), near, _motion_cost)
    if path is None:
        return Plan("unreachable", reason=_blocked(graph, where, errors, goal, statics_of, lever))
    if path:
        return _move(path[0], params, tuple(path))
    closing = rest(Node(0, 0))
    if not closing:
        return REACHED
    kind, delta = closing[0]
    return Plan("move", _step(kind, delta, params))


def _closing_margin(
    graph: ConfigurationGraph, start: tuple[float, float], motions: list[tuple[str, float]]
) -> float:
    """The smallest margin of partial motions taken in turn from ``start`` (at both ends of each);
    −inf where one ends outside the graph's ranges. Unchecked, the closing pivot of a tilt goal
    beyond the robot's reach left it: on the Panda (reach up to 29.7°) the triangle's goal 31.6°
    was planned, by the oracle too, as a pivot to the reach's end and a +1.9° pivot past it, and
    the run's pivots stalled at the end three times before the goal was given up as ``failed``."""
    least, (theta, s_h) = math.inf, start
    for kind, delta in motions:
        motion = motion_of(kind, delta)
        end = (theta + delta, s_h) if kind == "pivot" else (theta, s_h + delta)
        if not graph.inside_at(*end):
            return -math.inf
        for point in ((theta, s_h), end):
            least = min(least, graph.margin_at(*point, motion))
        theta, s_h = end
    return least


def _move(edge: Edge, params: PlannerParams, path: tuple[Edge, ...]) -> Plan:
    return Plan("move", _step(edge.kind, edge.delta, params), path=path)


def _step(kind: str, delta: float, params: PlannerParams) -> Step:
    tolerance = min(DEFAULT_TOLERANCE[kind], 0.5 * abs(delta))
    return Step(kind, delta, tolerance, params.motion_timeout)


def _motion_cost(edge: Edge) -> float:
    """Every motion costs one; a hand slide a little more (it is the slowest and the least robust)."""
    return 1.2 if edge.kind == "slide_hand" else 1.0


def _blocked(
    graph: ConfigurationGraph,
    where: tuple[float, float, float],
    errors: np.ndarray,
    goal: Goal,
    statics_of: StaticsOf,
    lever: float,
) -> str:
    """Why no path reaches the goal's ``(θ_o, s_h)``: the coordinate that cannot get there."""
    grid = graph.params
    if goal.s_h is not None and abs(errors[1]) > goal.length_tolerance:
        sign = 1 if errors[1] > 0 else -1
        nodes = reachable_nodes(graph, Node(0, 0))
        ways = [e for n in nodes for e in graph.edges(n) if e.kind == "slide_hand" and e.delta * sign > 0]
        if not ways:
            return (
                f"s_h {_length(goal.s_h)}: no hand slide {towards(sign, 's_h')} is possible at any tilt in "
                f"{_degrees(grid.theta_range)}{_limits(statics_of, lever)}"
            )
    beyond = 0.0 if goal.theta_o is None else past_reach(goal.theta_o, grid.theta_range)
    if beyond:
        return (
            f"θ_o {math.degrees(goal.theta_o):.1f}°: {abs(math.degrees(beyond)):.1f}° beyond the "
            f"robot's reach {_degrees(grid.theta_range)}"
        )
    if goal.theta_o is not None:
        return (
            f"θ_o {math.degrees(goal.theta_o):.1f}°: no sequence of pivots and hand slides keeps "
            f"{grid.min_margin:.1f} N of margin on the way (reach {_degrees(grid.theta_range)})"
            f"{_limits(statics_of, lever)}"
        )
    return (
        f"s_h {_length(goal.s_h)}: no sequence of motions keeps {grid.min_margin:.1f} N of margin on the way"
    )


def towards(sign: float, coordinate: str) -> str:
    """How a reason names a way along a coordinate: ``towards +s_h``, ``towards −s_g``."""
    return f"towards {'+' if sign > 0 else '−'}{coordinate}"


def _limits(statics_of: StaticsOf, lever: float) -> str:
    mu_h = statics_of(Motion.HOLD).mu_h
    return f" with μ_h {mu_h:.2f}, l_h {lever * 1e3:.0f} mm"


def _degrees(interval: tuple[float, float]) -> str:
    return f"[{math.degrees(interval[0]):.0f}°, {math.degrees(interval[1]):.0f}°]"


def _length(value: float | None) -> str:
    return "free" if value is None else f"{value * 1e3:+.0f} mm"


def _amount(kind: str, delta: float) -> str:
    return f"{math.degrees(delta):+.1f}°" if kind == "pivot" else f"{delta * 1e3:+.1f} mm"


@dataclass(frozen=True)
class OracleAnswer:
    """What the planner does with the true statics, motion by motion, as if every motion did exactly
    what it commanded (the experimenter's oracle; the estimator and the controller never see it).

    Attributes:
        status: ``reached`` or ``unreachable`` (also when ``max_motions`` run out, with the reason).
        motions: the motions, in order.
        reason: why unreachable.
        where: the nominal configuration at the end ``(θ_o, s_h, s_g)`` (rad, m; ``s_g`` absolute).
    """

    status: str
    motions: tuple[Step, ...]
    reason: str
    where: tuple[float, float, float]


def oracle_plan(
    true_statics: ObjectStatics,
    where: tuple[float, float, float],
    goal: Goal,
    s_g_origin: float,
    reach: tuple[float, float],
    lever: float,
    force_limits: tuple[float, float],
    params: PlannerParams | None = None,
    face: tuple[float, float] | None = None,
    max_motions: int = 60,
) -> OracleAnswer:
    """Plan ``goal`` on the true statics from ``where``, applying each motion nominally; ``reach``
    should be narrowed to where the object stays on its vertex and ``face`` given
    (:func:`ccopt.planning.tour.vertex_range`, :func:`ccopt.statics.true_statics`)."""
    position = np.asarray(where, dtype=float)
    motions: list[Step] = []

    def statics_of(motion: Motion) -> ObjectStatics:
        return true_statics

    for _ in range(max_motions):
        plan = next_motion(
            statics_of, tuple(position), goal, s_g_origin, reach, lever, force_limits, params, face
        )
        if plan.status != "move":
            return OracleAnswer(plan.status, tuple(motions), plan.reason, tuple(position))
        motions.append(plan.motion)
        position[plan.motion.coordinate] += plan.motion.delta
    reason = f"no plan within {max_motions} motions"
    return OracleAnswer("unreachable", tuple(motions), reason, tuple(position))
