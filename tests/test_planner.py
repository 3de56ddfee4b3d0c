"""ccopt.planning.planner (goals into motions) against independent truths.

* Every motion a plan takes keeps the margin: direct :func:`ccopt.statics.best_wrench` calls at the
  points it passes, computed here from the motion's definition.
* Reachability and plan length: breadth-first search over the reference graph of
  ``tests/test_planning.py`` (its edges from direct LP calls), built with the band and reach the
  planner's docstring states.
* Closed forms: without hand friction no hand slide is possible (the hand's tangential force must
  be zero while it slides), so no ``s_h`` goal other than the current one is reachable.
"""

from __future__ import annotations

import dataclasses
import itertools
import math

import numpy as np
import pytest

from ccopt import statics
from ccopt.closed_loop import LoopParams, start_config
from ccopt.control.targets import TargetGoal
from ccopt.estimation.estimator import Estimate, Estimator
from ccopt.modes import Motion, motion_of
from ccopt.objects import PlanarObject, from_vertices, make_object
from ccopt.planning.graph import GraphParams
from ccopt.planning.planner import PlannerParams, back_within, next_motion, oracle_plan
from ccopt.planning.sequencer import GoalSequencer, tilt_limit
from ccopt.planning.tour import vertex_range
from ccopt.plant.mujoco_planar import HAND_ANGLE_RANGE
from ccopt.schedule import Goal, Step, exploration, reach
from tests.test_planning import Reference, bfs_distances

FORCES = (2.0, 22.5)
"""N: the hand's force range less the controller's headroom, as the run's planner gets it."""


@dataclasses.dataclass(frozen=True)
class Case:
    truth: statics.TrueConfiguration
    reach: tuple[float, float]
    lever: float


def case(name: str, added_mass: float = 0.0) -> Case:
    return case_of(make_object(name, added_mass=added_mass))


def case_of(obj: PlanarObject) -> Case:
    params = LoopParams()
    start = start_config(obj, params)
    truth = statics.true_statics(obj, start, params.hand)
    low, high = vertex_range(obj, start)
    window = (max(HAND_ANGLE_RANGE[0], low), min(HAND_ANGLE_RANGE[1], high))
    lever = params.estimator_params.friction.torque_margin * params.hand.half_length
    return Case(truth, window, lever)


@pytest.fixture(scope="module")
def cases() -> dict[str, Case]:
    return {
        "triangle": case("paper-triangle"),
        "square": case("paper-square"),
        "heavy-triangle": case("paper-triangle", 0.5),
        "random-triangle": case_of(from_vertices(np.array(RANDOM_TRIANGLE), 0.719, 0.659, 0.742)),
    }


RANDOM_TRIANGLE = [[0.05064, 0.07522], [-0.06667, 0.02921], [0.04639, -0.05800]]
"""A goals-study triangle (0.72 kg, μ_h 0.66, μ_g 0.74) whose hand slide towards ``+s_h`` keeps its
margin only some 25° below the tilt it starts at."""


def start_of(c: Case) -> tuple[float, float, float]:
    return c.truth.theta_o, c.truth.s_h, 0.0


def passed_points(step: Step, where: np.ndarray, s_h_step: float) -> list[tuple[float, float]]:
    """The ``(θ_o, s_h)`` points a motion passes: a pivot its ends, a hand slide every ``s_h_step``
    and its end, a ground slide its configuration."""
    theta, s_h = where[0], where[1]
    if step.kind == "pivot":
        return [(theta, s_h), (theta + step.delta, s_h)]
    if step.kind == "slide_hand":
        count = max(1, math.ceil(abs(step.delta) / s_h_step - 1e-9))
        return [(theta, s_h + step.delta * k / count) for k in range(count + 1)]
    return [(theta, s_h)]


def assert_plan_keeps_margin(c: Case, motions: tuple[Step, ...], params: PlannerParams) -> np.ndarray:
    """Replay ``motions`` nominally from the start, checking every point with a direct LP; the end."""
    where = np.array(start_of(c))
    for step in motions:
        motion = motion_of(step.kind, step.delta)
        for theta, s_h in passed_points(step, where, params.s_h_step):
            assert c.reach[0] - 1e-9 <= theta <= c.reach[1] + 1e-9, (step, theta)
            margin = statics.best_wrench(c.truth.statics, theta, s_h, motion, c.lever, FORCES).margin
            assert margin >= params.margin - 1e-6, (step, math.degrees(theta), s_h, margin)
        where[step.coordinate] += step.delta
    return where


GOALS = {
    "tilt up": reach(theta_deg=31.6),
    "tilt down": reach(theta_deg=2.8),
    "off grid": reach(theta_deg=20.0),
    "ground +": reach(s_g_mm=10.0),
    "ground −": reach(s_g_mm=-10.0),
    "combined": reach(theta_deg=24.4, s_g_mm=10.0),
}


@pytest.mark.parametrize("name", ["triangle", "square", "heavy-triangle"])
@pytest.mark.parametrize("goal", list(GOALS))
def test_every_planned_motion_keeps_the_margin_and_a_reached_plan_ends_within_the_aim(
    cases: dict[str, Case], name: str, goal: str
) -> None:
    c, target = cases[name], GOALS[goal]
    params = PlannerParams()
    answer = oracle_plan(c.truth.statics, start_of(c), target, 0.0, c.reach, c.lever, FORCES, params,
                         face=c.truth.s_h_range)
    end = assert_plan_keeps_margin(c, answer.motions, params)
    assert np.allclose(end, answer.where)
    if answer.status == "reached":
        assert np.all(np.abs(target.errors(end, 0.0)) <= params.aim * target.tolerances + 1e-12)
    else:
        assert answer.reason


def test_the_triangle_reaches_the_papers_tilts_and_ground_slides(cases: dict[str, Case]) -> None:
    """The paper's triangle pivots 7.2° each way and slides on the ground once tilted (paper Fig. 9)."""
    c = cases["triangle"]
    for goal in (GOALS["tilt up"], GOALS["tilt down"], GOALS["ground +"], GOALS["ground −"]):
        answer = oracle_plan(c.truth.statics, start_of(c), goal, 0.0, c.reach, c.lever, FORCES,
                             face=c.truth.s_h_range)
        assert answer.status == "reached", (goal, answer.reason)
    up = oracle_plan(c.truth.statics, start_of(c), GOALS["tilt up"], 0.0, c.reach, c.lever, FORCES)
    assert [step.kind for step in up.motions] == ["pivot", "pivot"]


def reference_for(c: Case, goal_s_h: float | None, params: PlannerParams) -> Reference:
    """The graph the planner's docstring describes: ``θ_o`` within the reach, ``s_h`` within the band
    from the current to the goal's ``s_h`` widened by ``s_h_span``, cut to the face."""
    s_h = c.truth.s_h
    target = s_h if goal_s_h is None else goal_s_h
    band = (min(s_h, target) - params.s_h_span, max(s_h, target) + params.s_h_span)
    face = c.truth.s_h_range
    band = (max(band[0], min(face[0], s_h)), min(band[1], max(face[1], s_h)))
    grid = GraphParams(theta_range=c.reach, s_h_range=band, min_margin=params.margin,
                       s_h_step=params.s_h_step, hand_slide=params.hand_slide)
    return Reference(c.truth.statics, (c.truth.theta_o, s_h), c.lever, FORCES, grid)


@pytest.mark.parametrize("name", ["triangle", "square", "heavy-triangle"])
@pytest.mark.parametrize("pivots", [-3, -2, -1, 1, 2, 3])
def test_a_tilt_on_the_grid_is_reachable_exactly_where_breadth_first_search_reaches_it(
    cases: dict[str, Case], name: str, pivots: int
) -> None:
    c = cases[name]
    params = PlannerParams()
    goal = Goal(theta_o=c.truth.theta_o + pivots * params.pivot_step)
    reference = reference_for(c, None, params)
    distances = bfs_distances(reference, (0, 0))
    hits = [n for (i, j), n in distances.items() if i == pivots]
    plan = next_motion(lambda motion: c.truth.statics, start_of(c), goal, 0.0, c.reach, c.lever, FORCES,
                       params, face=c.truth.s_h_range)
    if not hits:
        assert plan.status == "unreachable" and "θ_o" in plan.reason
        return
    assert plan.status == "move"
    assert len(plan.path) >= min(hits)
    assert len(plan.path) <= min(hits) * 1.2 + 1e-9  # a hand slide costs 1.2 pivots


@pytest.mark.parametrize("sign", [1, -1])
def test_without_hand_friction_no_hand_slide_goal_is_reachable(cases: dict[str, Case], sign: int) -> None:
    c = cases["triangle"]
    frictionless = dataclasses.replace(c.truth.statics, mu_h=0.0)
    goal = Goal(s_h=c.truth.s_h + sign * 0.010)
    plan = next_motion(lambda motion: frictionless, start_of(c), goal, 0.0, c.reach, c.lever, FORCES)
    assert plan.status == "unreachable"
    way = "+" if sign > 0 else "−"
    assert f"no hand slide towards {way}s_h" in plan.reason and "μ_h 0.00" in plan.reason
    for theta in np.linspace(*c.reach, 7):
        motion = Motion.SLIDE_HAND_POS if sign > 0 else Motion.SLIDE_HAND_NEG
        margin = statics.best_wrench(frictionless, theta, c.truth.s_h, motion, c.lever, FORCES).margin
        assert not margin >= 1.0


@pytest.mark.parametrize("name", ["triangle", "square", "heavy-triangle", "random-triangle"])
@pytest.mark.parametrize("sign", [1, -1])
def test_an_s_h_goal_ends_at_whatever_tilt_its_closing_slide_keeps_the_margin(
    cases: dict[str, Case], name: str, sign: int
) -> None:
    """The goal's tilt is free. ``s_h`` 11.5 mm away: a full hand slide (two grid steps) and then a
    partial 1.5 mm one. The plan reaches it exactly where the reference graph reaches a node two
    steps along ``s_h``, at any tilt, from which that partial slide keeps the margin at both ends
    (direct LPs), and every motion keeps the margin. Before, the plan had to end within half a pivot
    of the tilt it began at: the random triangle's goal towards ``+s_h`` was unreachable."""
    c = cases[name]
    params = PlannerParams()
    closing = sign * 0.0015
    goal = Goal(s_h=c.truth.s_h + sign * 2 * params.s_h_step + closing)
    reference = reference_for(c, goal.s_h, params)
    motion = Motion.SLIDE_HAND_POS if sign > 0 else Motion.SLIDE_HAND_NEG

    def closes(i: int, j: int) -> bool:
        theta, s_h = reference.config(i, j)
        margins = [statics.best_wrench(c.truth.statics, theta, point, motion, c.lever, FORCES).margin
                   for point in (s_h, s_h + closing)]
        return min(margins) >= params.margin

    ends = [(i, j) for i, j in bfs_distances(reference, (0, 0)) if j == 2 * sign and closes(i, j)]
    answer = oracle_plan(c.truth.statics, start_of(c), goal, 0.0, c.reach, c.lever, FORCES, params,
                         face=c.truth.s_h_range)
    assert (answer.status == "reached") == bool(ends), answer.reason
    assert_plan_keeps_margin(c, answer.motions, params)
    if name == "random-triangle" and sign > 0:
        assert ends and all(i != 0 for i, _ in ends)  # the case this guards


def test_a_goal_already_within_the_aim_is_reached_at_once(cases: dict[str, Case]) -> None:
    c = cases["triangle"]
    where = start_of(c)
    goal = Goal(theta_o=where[0] + math.radians(0.4), s_g=0.0005)
    plan = next_motion(lambda motion: c.truth.statics, where, goal, 0.0, c.reach, c.lever, FORCES)
    assert plan.status == "reached" and plan.motion is None


def slide_tilt(c: Case, goal: Goal, failed: dict[int, float]) -> float | None:
    """The tilt (rad) at which the planner, its motions applied nominally, slides on the ground."""
    where = np.array(start_of(c))
    for _ in range(20):
        plan = next_motion(lambda motion: c.truth.statics, tuple(where), goal, 0.0, c.reach, c.lever,
                           FORCES, failed_slides=failed)
        if plan.status != "move":
            return None
        if plan.motion.kind == "slide_ground":
            return float(where[0])
        where[plan.motion.coordinate] += plan.motion.delta
    raise AssertionError("no ground slide within 20 motions")


def test_a_ground_slide_that_did_not_start_is_sought_further_tilted(cases: dict[str, Case]) -> None:
    """Tilting the hand's normal towards the slide is what lets the hand push the object along: at
    least half a pivot step further, also when the failed try was a little short of the current tilt
    (a retry from where exploring left the object failed as the first did)."""
    c = cases["triangle"]
    first = slide_tilt(c, GOALS["ground +"], {})
    assert first is not None
    half_step = 0.5 * GraphParams().pivot_step
    for tried in (first, first - 0.3 * half_step):
        again = slide_tilt(c, GOALS["ground +"], {1: tried})
        assert again is None or again >= tried + half_step
    assert slide_tilt(c, GOALS["ground +"], {-1: first}) == pytest.approx(first)


def test_a_ground_goal_out_of_reach_says_which_slide_and_where(cases: dict[str, Case]) -> None:
    c = cases["square"]
    narrow = (c.truth.theta_o - 0.01, c.truth.theta_o + 0.01)  # no tilt that lets the square slide
    plan = next_motion(lambda motion: c.truth.statics, start_of(c), GOALS["ground +"], 0.0, narrow,
                       c.lever, FORCES)
    assert plan.status == "unreachable"
    assert plan.reason.startswith("s_g +10 mm: no ground slide towards +s_g is possible at any tilt in")
    margin = statics.best_wrench(c.truth.statics, c.truth.theta_o, c.truth.s_h, Motion.SLIDE_GROUND_POS,
                                 c.lever, FORCES).margin
    assert not margin >= 1.0


@pytest.mark.parametrize(("goal_deg", "status"), [(31.6, "unreachable"), (30.0, "reached")])
def test_a_tilt_goal_past_the_reach_closes_at_its_end_or_is_unreachable(
    cases: dict[str, Case], goal_deg: float, status: str
) -> None:
    """A reach ending at 29.7° (the Panda's at its start): 30° is within the aim (half the 1°
    tolerance) of the reach's end and planned there; 31.6° is not, and no motion is planned past
    the end (the plan's every point is checked against the reach and with a direct LP)."""
    c = cases["triangle"]
    panda = Case(c.truth, (c.reach[0], math.radians(29.69)), c.lever)
    params = PlannerParams()
    answer = oracle_plan(panda.truth.statics, start_of(panda), reach(theta_deg=goal_deg), 0.0, panda.reach,
                         panda.lever, FORCES, params, face=panda.truth.s_h_range)
    end = assert_plan_keeps_margin(panda, answer.motions, params)
    assert answer.status == status, answer.reason
    if status == "reached":
        assert math.isclose(end[0], panda.reach[1], abs_tol=1e-9)
    else:
        assert answer.reason.startswith("θ_o 31.6°: 1.9° beyond the robot's reach"), answer.reason


def test_a_reach_closed_down_to_the_current_tilt_plans_without_pivots(cases: dict[str, Case]) -> None:
    """Tilt limits met on both sides (a one-point reach): a tilt goal is unreachable, a ground goal
    is judged at the current tilt alone, and nothing raises."""
    c = cases["triangle"]
    where = start_of(c)
    point = (where[0], where[0])
    def known(motion: Motion) -> statics.ObjectStatics:
        return c.truth.statics

    tilt = next_motion(known, where, GOALS["tilt up"], 0.0, point, c.lever, FORCES)
    assert tilt.status == "unreachable" and "θ_o 31.6°" in tilt.reason
    ground = next_motion(known, where, GOALS["ground +"], 0.0, point, c.lever, FORCES)
    margin = statics.best_wrench(
        c.truth.statics, where[0], where[1], Motion.SLIDE_GROUND_POS, c.lever, FORCES
    ).margin
    assert (ground.status == "move") == (margin >= 1.0)
    if ground.status == "move":
        assert ground.motion.kind == "slide_ground"


def test_a_goal_explores_again_after_a_motion_lost_the_kinematics_and_fails_past_the_limit() -> None:
    unknown = Estimator().update(0.0, [0.0, 0.1, 0.0], [5.0, 0.0, 0.0])  # one sample: nothing valid
    aim = TargetGoal(force_limits=(2.0, 25.0), nominal_force=8.0, margin=1.0)
    pivots = [step for step in exploration() if step.kind == "pivot"]

    sequencer = GoalSequencer(0, reach(10.0), 0.0, HAND_ANGLE_RANGE, aim)
    steps, answer = [], sequencer.next(0.0, unknown, None)
    while isinstance(answer, Step):
        steps.append(answer)
        answer = sequencer.next(1.0, unknown, None, "reached")
    assert steps == list(exploration()) and answer.status == "failed"  # unknown after exploring

    sequencer = GoalSequencer(0, reach(10.0), 0.0, HAND_ANGLE_RANGE, aim)
    sequencer.next(0.0, unknown, None)
    for _ in exploration()[1:]:
        sequencer.next(1.0, unknown, None, "reached")
    for _ in range(GoalSequencer.max_explorations - 1):
        again = sequencer.next(1.0, unknown, None, "lost")
        assert again == pivots[0]  # the pivots only: the friction was explored
        for step in pivots[1:]:
            assert sequencer.next(1.0, unknown, None, "reached") == step
    assert sequencer.next(1.0, unknown, None, "lost").status == "failed"  # no exploration left


def test_a_tilt_beyond_the_reach_pivots_back_inside_its_edge() -> None:
    """From beyond either end of the reach by more than a pivot's tolerance, one pivot aims a
    tolerance inside that end, so that wherever within its tolerance it stops it lies within the
    reach; within the tolerance (or the reach), nothing."""
    low, high = math.radians(-20.0), math.radians(30.0)
    tolerance = math.radians(0.7)
    for theta, edge, inward in ((low - math.radians(5.0), low, 1.0), (high + math.radians(3.0), high, -1.0)):
        plan = back_within(theta, (low, high), PlannerParams())
        assert plan.status == "move" and plan.motion.kind == "pivot"
        assert math.isclose(theta + plan.motion.delta, edge + inward * tolerance, abs_tol=1e-12)
        for stop in (-1.0, 1.0):
            end = theta + plan.motion.delta + stop * plan.motion.tolerance
            assert low - 1e-12 <= end <= high + 1e-12
    for theta in (low - 0.9 * tolerance, high + 0.9 * tolerance, 0.0):
        assert back_within(theta, (low, high), PlannerParams()) is None


def test_a_rolled_pivot_limits_the_tilt_short_of_where_the_roll_began() -> None:
    """Where the roll was seen past the pivot's start, the limit is a degree and a pivot's tolerance
    (1.7°) short of it that way; unknown, or not past the start, the start."""
    deg = math.radians
    assert math.isclose(tilt_limit(deg(-18.3), deg(-24.0), -1), deg(-22.3))
    assert math.isclose(tilt_limit(deg(18.3), deg(24.0), 1), deg(22.3))
    for roll in (None, math.nan, deg(-17.0), deg(-18.8)):
        assert tilt_limit(deg(-18.3), roll, -1) == deg(-18.3)


def test_a_pivot_that_rolled_before_turning_where_the_object_has_stood_beyond_sets_no_limit() -> None:
    """A pivot down from 16.9° that ends ``rolled``: where it rolled before turning the object and
    pivots had held the object at 9.9° (beyond the 16.9° limit it would set), the reach stays open;
    held only to 16.5° (within a pivot's tolerance), the limit is the pivot's start; rolled after
    turning to 12.4°, a degree and a pivot's tolerance short of there. The closed-loop case is
    ``tests/test_goal_recovery.py``."""
    from tests.test_targets import OBJECT, S_H, known_estimate

    deg = math.radians
    aim = TargetGoal(force_limits=(3.0, 25.0), nominal_force=8.0, margin=1.0)

    def limits_after(roll_tilt: float, held: tuple[float, float]) -> dict[int, float]:
        limits: dict[int, float] = {}
        sequencer = GoalSequencer(0, reach(2.8), 0.0, HAND_ANGLE_RANGE, aim, tilt_limits=limits)
        first = sequencer.next(0.0, known_estimate(OBJECT, deg(16.9), S_H), 0.0)
        assert first.kind == "pivot" and first.delta < 0.0
        sequencer.next(1.0, known_estimate(OBJECT, deg(16.9), S_H), 0.0, "rolled", roll_tilt, held)
        return limits

    assert limits_after(deg(16.9), (deg(9.9), deg(24.0))) == {}
    assert limits_after(math.nan, (deg(9.9), deg(24.0))) == {}
    assert limits_after(deg(16.9), (deg(16.5), deg(24.0))) == {-1: deg(16.9)}  # never short of the start
    rolled_on = limits_after(deg(12.4), (deg(9.9), deg(24.0)))  # a degree and a tolerance short: 14.1°
    assert rolled_on.keys() == {-1} and math.isclose(rolled_on[-1], deg(14.1))
    assert limits_after(deg(16.9), (math.inf, -math.inf)) == {-1: deg(16.9)}


def test_an_exploration_pivot_past_a_tilt_limit_turns_the_other_way() -> None:
    """Exploring at −19° with the tilt limited at −20°: a pivot that would end below −20.7° goes up
    instead; the others run as the exploration has them."""
    unknown = Estimator().update(0.0, [0.0, 0.1, 0.0], [5.0, 0.0, 0.0])
    at = dataclasses.replace(unknown, theta_o=math.radians(-19.0))
    aim = TargetGoal(force_limits=(2.0, 25.0), nominal_force=8.0, margin=1.0)
    sequencer = GoalSequencer(
        0, reach(10.0), 0.0, HAND_ANGLE_RANGE, aim, tilt_limits={-1: math.radians(-20.0)}
    )
    steps = [sequencer.next(0.0, at, None)]
    steps += [sequencer.next(1.0, at, None, "reached") for _ in exploration()[1:]]
    for step, planned in zip(steps, exploration(), strict=True):
        if planned.kind != "pivot":
            assert step.kind == planned.kind and abs(step.delta) == abs(planned.delta)
            continue
        beyond = -19.0 + math.degrees(planned.delta) < -20.0 - math.degrees(planned.tolerance)
        assert step.delta == (-planned.delta if beyond else planned.delta)
    assert any(step.delta != planned.delta for step, planned in zip(steps, exploration(), strict=True))



@pytest.mark.parametrize("tilt", [-17.0, 17.0])
def test_the_exploration_probes_the_safer_way_first_and_the_other_only_while_the_hand_has_not_slid(
    tilt: float,
) -> None:
    unknown = Estimator().update(0.0, [0.0, 0.1, 0.0], [5.0, 0.0, 0.0])
    at = dataclasses.replace(unknown, theta_o=math.radians(tilt))
    aim = TargetGoal(force_limits=(2.0, 25.0), nominal_force=8.0, margin=1.0)
    probe = next(step for step in exploration() if step.kind == "slide_hand")
    pivots = sum(step.kind == "pivot" for step in exploration())

    def probes(slid_after_first: bool) -> list[Step]:
        sequencer = GoalSequencer(0, reach(10.0), 0.0, HAND_ANGLE_RANGE, aim)
        answer, taken = sequencer.next(0.0, at, None), []
        for _ in range(pivots):
            answer = sequencer.next(1.0, at, None, "reached")
        while isinstance(answer, Step):
            taken.append(answer)
            estimate = dataclasses.replace(at, hand_slid=slid_after_first)
            answer = sequencer.next(1.0, estimate, None, "reached")
        assert answer.status == "failed"  # the kinematics stay unknown here
        return taken

    first_way = 1 if tilt > 0.0 else -1
    assert [step.delta for step in probes(False)] == [first_way * probe.delta, -first_way * probe.delta]
    assert [step.delta for step in probes(True)] == [first_way * probe.delta]

def plan_nominally(
    statics_of, c: Case, goal: Goal, params: PlannerParams, max_motions: int = 40, barred=None
) -> tuple[str, list[Step]]:
    """``next_motion`` from the start with every motion applied nominally: its last status and motions."""
    where, motions = np.array(start_of(c)), []
    for _ in range(max_motions):
        plan = next_motion(statics_of, tuple(where), goal, 0.0, c.reach, c.lever, FORCES, params,
                           face=c.truth.s_h_range, barred=barred)
        if plan.status != "move":
            return plan.status, motions
        motions.append(plan.motion)
        where[plan.motion.coordinate] += plan.motion.delta
    return "unreachable", motions


@pytest.mark.parametrize("name", ["triangle", "square", "heavy-triangle", "random-triangle"])
def test_a_hand_slide_judged_on_a_friction_interval_keeps_the_margin_at_both_ends(
    cases: dict[str, Case], name: str
) -> None:
    """A hand slide judged under two statics, the true ones and the same with μ_h 1.0 (what an
    estimate knows before the hand slides: a lower bound and a ceiling), keeps the margin under each
    (direct LPs at the points it passes), and a goal reached so is reached on the true statics alone.
    On the heavy and the random triangle the interval's plans go to other tilts than the truth's
    alone, with more motions (the case it guards): the slide the truth alone takes first would not
    keep the margin at μ_h 1.0."""
    c = cases[name]
    params = PlannerParams()
    ceiling = dataclasses.replace(c.truth.statics, mu_h=1.0)
    hand = (Motion.SLIDE_HAND_POS, Motion.SLIDE_HAND_NEG)

    def interval(motion: Motion):
        return (c.truth.statics, ceiling) if motion in hand else c.truth.statics

    stricter = []
    for sign in (1, -1):
        goal = Goal(s_h=c.truth.s_h + sign * params.hand_slide)
        status, motions = plan_nominally(interval, c, goal, params)
        alone, direct = plan_nominally(lambda motion: c.truth.statics, c, goal, params)
        assert status != "reached" or alone == "reached"
        stricter.append(len(motions) > len(direct))
        where = np.array(start_of(c))
        for step in motions:
            motion = motion_of(step.kind, step.delta)
            for known in (c.truth.statics, ceiling) if step.kind == "slide_hand" else (c.truth.statics,):
                for theta, s_h in passed_points(step, where, params.s_h_step):
                    margin = statics.best_wrench(known, theta, s_h, motion, c.lever, FORCES).margin
                    assert margin >= params.margin - 1e-6, (step, known.mu_h, margin)
            where[step.coordinate] += step.delta
    if name in ("heavy-triangle", "random-triangle"):
        assert any(stricter)


def hand_slide_tilts(c: Case, motions: list[Step]) -> list[float]:
    """The tilts (rad) at which ``motions``, applied nominally from the start, slide the hand."""
    where, tilts = np.array(start_of(c)), []
    for step in motions:
        if step.kind == "slide_hand":
            tilts.append(float(where[0]))
        where[step.coordinate] += step.delta
    return tilts


@pytest.mark.parametrize("name", ["heavy-triangle", "random-triangle"])
@pytest.mark.parametrize("sign", [1, -1])
def test_a_barred_hand_slide_is_planned_elsewhere_with_the_margin_or_not_at_all(
    cases: dict[str, Case], name: str, sign: int
) -> None:
    """A hand slide barred within half a pivot step of the tilt the plan first slides at (as the
    sequencer bars one that failed there) is planned at least half a step away, every motion keeping
    the margin (direct LPs), or the goal is unreachable; barred everywhere, unreachable."""
    c = cases[name]
    params = PlannerParams()
    goal = Goal(s_h=c.truth.s_h + sign * params.hand_slide)
    motion = Motion.SLIDE_HAND_POS if sign > 0 else Motion.SLIDE_HAND_NEG
    known = lambda motion: c.truth.statics  # noqa: E731
    status, motions = plan_nominally(known, c, goal, params)
    assert status == "reached"  # both objects slide the hand either way (the paper triangle does not)
    first = hand_slide_tilts(c, motions)[0]
    half = 0.5 * params.pivot_step

    def near_first(theta: float, barred: Motion) -> bool:
        return barred == motion and abs(theta - first) < half

    status, motions = plan_nominally(known, c, goal, params, barred=near_first)
    assert status in ("reached", "unreachable")
    if status == "reached":
        assert all(abs(tilt - first) >= half - 1e-9 for tilt in hand_slide_tilts(c, motions))
        assert_plan_keeps_margin(c, tuple(motions), params)
    status, motions = plan_nominally(known, c, goal, params, barred=lambda theta, barred: barred == motion)
    assert status == "unreachable" and not any(step.kind == "slide_hand" for step in motions)


def test_failed_hand_slides_are_tried_twice_per_tilt_three_times_in_all_then_unreachable() -> None:
    """The sequencer on a fixed object whose hand slides either way are possible by the estimate
    (μ̂_h 0.3, tests.test_targets' object): every hand slide it plans is held ('rolled' or
    'timeout'), every pivot is done. No hand slide is planned a third time within half a pivot step
    of two that failed, three are tried in all, and the goal ends unreachable naming their tilts.
    A slide that slipped the ground bars nothing: the next plan is the same slide."""
    from tests.test_targets import OBJECT, S_H, THETA_O, known_estimate

    aim = TargetGoal(force_limits=(3.0, 25.0), nominal_force=8.0, margin=3.0, friction_step=0.1)
    half = 0.5 * PlannerParams().pivot_step
    for sign in (1, -1):
        sequencer = GoalSequencer(0, reach(s_h_mm=sign * 10.0), 0.0, HAND_ANGLE_RANGE, aim)
        theta, failed, outcomes = THETA_O, [], iter(("rolled", "timeout", "rolled"))
        answer = sequencer.next(0.0, known_estimate(OBJECT, theta, S_H, mu_h=0.3), 0.1)
        for _ in range(30):
            if not isinstance(answer, Step):
                break
            status = "reached"
            if answer.kind == "slide_hand":
                assert answer.delta * sign > 0
                assert sum(abs(theta - tilt) < half for tilt in failed) < 2
                failed.append(theta)
                status = next(outcomes)
            elif answer.kind == "pivot":
                theta += answer.delta
            answer = sequencer.next(1.0, known_estimate(OBJECT, theta, S_H, mu_h=0.3), 0.1, status)
        assert len(failed) == GoalSequencer.max_hand_slide_failures == 3
        assert answer.status == "unreachable"
        way = "+" if sign > 0 else "−"
        tilts = ", ".join(f"{math.degrees(tilt):.0f}°" for tilt in failed)
        assert answer.reason.endswith(f"(hand slides tried and failed towards {way}s_h at {tilts})")
    sequencer = GoalSequencer(0, reach(s_h_mm=10.0), 0.0, HAND_ANGLE_RANGE, aim)
    at = known_estimate(OBJECT, THETA_O, S_H, mu_h=0.3)
    first = sequencer.next(0.0, at, 0.1)
    assert first.kind == "slide_hand"
    assert sequencer.next(1.0, at, 0.1, "slipped") == first
    assert sequencer.next(2.0, at, 0.1, "slipped") == first


def test_a_ground_slide_lost_where_the_pose_cannot_tell_it_from_a_hand_slide_is_sought_past_there() -> None:
    """Once the hand has slid, the kinematics let go of a ground slide within ``asin(position_noise /
    valid_std)`` (9.6°) of the vertical (:func:`~ccopt.estimation.estimator.either_slides`). On an
    object whose ground slides towards −s_g from +8° by the estimate (μ_g 0.2), every ground slide
    the sequencer plans in that band here ends ``lost``. Each next one is planned at least half a
    pivot step further, as after any failed slide; with the hand slid, the one after
    ``lost_slide_tries`` such losses past the band (before the hand has slid the band does not
    apply)."""
    from tests.test_targets import S_H, known_estimate

    kinematics = LoopParams().estimator_params.kinematics
    band = math.asin(kinematics.position_noise / kinematics.valid_std)
    slippery = statics.ObjectStatics.of_model(0.6, 0.2, 0.3, 0.03, 0.01, 0.02)
    aim = TargetGoal(force_limits=(3.0, 25.0), nominal_force=8.0, margin=1.0, friction_step=0.1)
    half = 0.5 * PlannerParams().pivot_step

    def slide_tilts(hand_slid: bool) -> list[float]:
        sequencer = GoalSequencer(
            0, reach(s_g_mm=-10.0), 0.0, HAND_ANGLE_RANGE, aim, split_tilt=kinematics.split_tilt
        )
        theta, tilts = math.radians(8.0), []

        def at(theta: float) -> Estimate:
            return dataclasses.replace(known_estimate(slippery, theta, S_H, mu_h=0.5), hand_slid=hand_slid)

        answer = sequencer.next(0.0, at(theta), 0.0)
        while isinstance(answer, Step) and len(tilts) < 6:
            status = "reached"
            if answer.kind == "pivot":
                theta += answer.delta
            elif answer.kind == "slide_ground":
                assert answer.delta < 0.0
                tilts.append(theta)
                if abs(theta) >= band:
                    return tilts
                status = "lost"
            answer = sequencer.next(1.0, at(theta), 0.0, status)
        raise AssertionError(f"no ground slide planned past the band: {answer}")

    tries = GoalSequencer.lost_slide_tries
    slid = slide_tilts(True)
    assert len(slid) == tries + 1 and all(abs(tilt) < band for tilt in slid[:-1]) and slid[-1] <= -band
    assert all(later <= earlier - half for earlier, later in itertools.pairwise(slid))
    tried = slide_tilts(False)
    assert len(tried) > tries + 1 and abs(tried[tries]) < band
    assert all(later <= earlier - half for earlier, later in itertools.pairwise(tried))


def test_a_ground_slide_possible_only_past_the_grid_is_planned_at_the_reach_end(
    cases: dict[str, Case],
) -> None:
    """A reach cut between two grid tilts (a tipping point a pivot found, a degree short): where the
    ground slide towards −s_g keeps its margin only beyond the grid's outermost tilt, the planner
    pivots the rest of the way to the reach's end and slides there. Direct LPs: no grid tilt within
    the reach has the slide's margin, the end has, and every planned motion keeps its margin."""
    c, params = cases["triangle"], PlannerParams()
    step, lever = params.pivot_step, c.lever

    def slide_margin(theta: float) -> float:
        motion = Motion.SLIDE_GROUND_NEG
        return statics.best_wrench(c.truth.statics, theta, c.truth.s_h, motion, lever, FORCES).margin

    tilts = (math.radians(-deg) for deg in np.arange(0.0, 60.0, 0.5))
    end = next(theta for theta in tilts if slide_margin(theta) >= 1.5)
    start = end + math.radians(3.0) + 2 * step  # the grid from here stops 3° short of the end
    reach = (end, c.reach[1])
    grid = [start - k * step for k in range(3)]
    assert all(slide_margin(theta) < params.margin for theta in grid)
    cut = Case(dataclasses.replace(c.truth, theta_o=start), reach, lever)
    answer = oracle_plan(c.truth.statics, start_of(cut), GOALS["ground −"], 0.0, reach, lever, FORCES, params,
                         face=c.truth.s_h_range)
    assert answer.status == "reached", answer.reason
    assert_plan_keeps_margin(cut, answer.motions, params)
    tilt = start + sum(step.delta for step in answer.motions if step.kind == "pivot")
    assert tilt == pytest.approx(end, abs=1e-9)
    assert [s.kind for s in answer.motions][-1] == "slide_ground"


def test_a_ground_slide_whose_tilts_lie_between_the_grids_nodes_is_planned_there(
    cases: dict[str, Case],
) -> None:
    """At a 7 N margin the triangle's ground slide towards +s_g keeps it only from about 32°, its
    pivots only up to about 34.5°: a window narrower than a pivot step, which the grid from most
    start tilts steps over. From every start the planner pivots into the window and slides there.
    Direct LPs every 0.1°: the window, that some starts' grid tilts all miss it, and that every
    planned motion keeps the margin."""
    c, params = cases["triangle"], PlannerParams(margin=7.0)

    def margin(theta: float, motion: Motion) -> float:
        return statics.best_wrench(c.truth.statics, theta, c.truth.s_h, motion, c.lever, FORCES).margin

    tilts = np.radians(np.arange(10.0, 50.0, 0.1))
    window = [t for t in tilts if min(margin(t, Motion.SLIDE_GROUND_POS), margin(t, Motion.PIVOT)) >= 7.0]
    assert window and window[-1] - window[0] < 0.6 * params.pivot_step
    assert all(margin(t, Motion.PIVOT) >= 7.0 for t in tilts if t <= window[0])
    missed = 0
    for start in np.radians(np.arange(10.0, 17.5, 0.5)):
        grid = start + params.pivot_step * np.arange(6)
        missed += not any(window[0] <= t <= window[-1] for t in grid)
        moved = Case(dataclasses.replace(c.truth, theta_o=float(start)), c.reach, c.lever)
        answer = oracle_plan(c.truth.statics, start_of(moved), GOALS["ground +"], 0.0, c.reach, c.lever,
                             FORCES, params, face=c.truth.s_h_range)
        assert answer.status == "reached", (math.degrees(start), answer.reason)
        assert_plan_keeps_margin(moved, answer.motions, params)
        assert "slide_ground" in [step.kind for step in answer.motions]
    assert missed >= 5
