"""Goals that a misread motion used to cost for good, judged in closed loop by the simulator's truth
and the experimenter's oracle (the planner on the true object). Goals-study objects:

* **A roll before the pivot turned anything.** The exploration pivots the object to 9.8° and back;
  its hand-slide probe rolls the hand 0.8° on the face's end, and the first goal's pivot down from
  17.1° begins with its torque row tight and ends ``rolled`` with the object still. Taken as a
  tipping point there, it cut the reach to [17°, 75°] for the rest of the run, and the later goals
  below 17° were reported unreachable, though the oracle reaches them
  (:meth:`ccopt.planning.sequencer.GoalSequencer._rolled`; seed 1, trial 38, run with noise seed 1:
  the trial's own noise seed no longer makes the case).
* **Ground slides lost near the vertical.** Once the hand has slid, within 9.6° of the vertical
  the estimator cannot tell a ground slide from the hand's where the hand is at its limit too, and
  lets go of both positions. The goal ``s_g`` −10 mm lost its slides at 9.6°, 2.1° and −5.1°, an
  exploration after each, and failed; the oracle reaches it
  (:meth:`~ccopt.planning.sequencer.GoalSequencer._failed_slide`; seed 1).
* **An object turned onto another vertex, unseen, that left the kinematics on a wrong ground
  contact.** In the exploration's pivot down from 16.8°, at 14.8°, a pentagon turned onto its
  neighbouring vertex (``d`` 121 → 134 mm, the ground contact 43 mm along the ground); the
  kinematics stayed on the first contact, and drifting between the two (``ŝ_g`` 21 mm at the goal's
  start) they gave the ``s_g`` goal its origin: claimed reached 16 mm off. The moment balance about
  that contact disagreed with ``M̂`` 0.11 s after the turn
  (:meth:`ccopt.estimation.estimator.Estimator._check_moment`; seed 2, trial 1, run with noise
  seed 0). Before the exploration's pivots about the naive lever were paced, a flat triangle (seed 4)
  slid 6 mm under the hand in the exploration's second pivot, to the same effect; it no longer
  slides so (30 noise seeds: its four goals reached within tolerance with the check or without).
* **A ground slide that slid the hand, read as the ground's.** At 2.4° a heavy quadrilateral's
  ground slide towards −s_g moved the hand 11.6 mm along the face instead, and the kinematics,
  which cannot tell the two apart by the pose so near the vertical, moved the ground contact: the
  goal ``s_g`` −10 mm was claimed with the object where it began. The moment balance gives the
  hand's position on the face (:meth:`ccopt.estimation.estimator.Estimator._check_hand_give`;
  seed 7, trial 35, run with noise seed 0).
* **A hand's slide taken for the ground's friction.** A ground slide at 10° slid the hand 4.8 mm
  along the face in 2.7 s, the ground not at all; before the kinematics were let go, ``ŝ_g`` had
  moved, and the ground counted as seen sliding towards −s_g: the hand's friction limit became the
  ground's friction face there (``μ̂_g`` 0.37 against 0.69), and the goal was reported unreachable
  (:meth:`ccopt.estimation.estimator.Estimator._drop_unfounded_slide`; seed 6, trial 34, run with
  noise seed 10: since the exploration's pivots about the naive lever were paced, the trial's own
  noise seed no longer makes the case, and of noise seeds 0–39 only 10 does).
* **Ground slides that did not start, given up too soon.** A pentagon's ground slides towards
  −s_g timed out at 2.8° and at −11.4°; each failure moved the next slide half a pivot step on, and
  after the second no tilt was left within the limits: the goal was reported unreachable, though
  the oracle reaches it. A slide sought past the sticking forces seen moves their edge out, so a
  second try where it failed pushes further; at −11.4° it slid the ground 10 mm
  (:meth:`~ccopt.planning.sequencer.GoalSequencer._failed_slide`; seed 7, trial 11). Not a cure:
  on noise seeds 0–11 the goal is reached on 7 with the retry or without, and on the other 5 the
  retry times out too and the goal ends ``failed`` instead of ``unreachable``.
* **An object rocking over a ground face, unseen.** Pivots across a pentagon's ground face near 0°
  rock it onto the next vertex and back (the true ground contact jumps 34 mm each way); the
  kinematics stay on the first vertex, and the moment check, which resets them only after 5° of
  turning, was too slow: an ``s_h`` goal was claimed 30 mm off by the truth. Doubted over 2°
  (``Estimate.kinematics_doubted``), the goal is not claimed (seed 6, trial 1).
* **A pivot to the end of the robot's reach.** On the Panda plant, whose hand reaches up to 29.7°,
  the paper triangle's ground slide towards +s_g rolled at 24.1° and the planner pivoted to the end
  of the reach in ``θ_o``; the hand, tilted 0.26° against the face by the pad's compliance, would
  have ended past it, so both pivots were refused and the goal failed
  (:meth:`ccopt.planning.sequencer.GoalSequencer.next`; the paper goals' third goal).
* **Ground slides that ended held, having slid.** On the Panda plant a quadrilateral's ground
  slides towards +s_g at the end of the reach (29.8°) ended ``rolled`` after sliding the ground
  1.7 mm and 3.6 mm; counted as slides that did not start, they barred the only tilt within reach,
  and the goal was reported unreachable, though the oracle reaches it
  (:meth:`ccopt.planning.sequencer.GoalSequencer._started`; goals-study seed 0 on the Panda, trial 12).
* **A roll over the face's end, unseen.** A sliver's ground slides with the hand 9 mm past the
  ground contact moved the centre of pressure to the face's end, well inside the hand, and the
  object turned 17° under the hand with the hand's torque rows far from tight
  (:func:`ccopt.estimation.estimator.patch_margins`; seed 0).
"""

from __future__ import annotations

import itertools
import math

import numpy as np
import pytest

from ccopt.closed_loop import LoopParams
from ccopt.control.controller import ControllerParams
from ccopt.estimation.estimator import Estimator, EstimatorParams
from ccopt.estimation.kinematics import KinematicsParams
from ccopt.experiment import Experiment, run_experiment
from ccopt.metrics import sample_at
from ccopt.objects import from_vertices, make_object
from ccopt.planning.planner import PlannerParams
from ccopt.planning.sequencer import DOUBTED, HELD, GoalSequencer
from ccopt.schedule import DEFAULT_TOLERANCE, GOAL_TOLERANCE, Schedule, exploration, reach

LOW_GOAL_DEG = 2.788733853924695
PIVOT_TOLERANCE_DEG = math.degrees(DEFAULT_TOLERANCE["pivot"])


def run(vertices, mass, mu_hand, mu_ground, goals, seed, params: LoopParams | None = None) -> Experiment:
    obj = from_vertices(np.array(vertices), mass, mu_hand, mu_ground)
    schedule = Schedule("recovery", (*exploration(), *goals))
    return run_experiment(obj, schedule, params or LoopParams(), seed=seed)


@pytest.fixture(scope="module")
def rolled_early() -> Experiment:
    vertices = [[-0.01616214370390999, 0.07494277258999732], [-0.06745684652252526, -0.021110137622774774],
                [0.04480139537426041, -0.06575319221187154]]
    goals = (reach(s_h_mm=-10.0), reach(theta_deg=LOW_GOAL_DEG), reach(theta_deg=LOW_GOAL_DEG))
    return run(vertices, 0.5808597565229205, 0.619501255473099, 0.7561156066309858, goals, 1)


@pytest.fixture(scope="module")
def lost_near_vertical() -> Experiment:
    vertices = [[-0.015208748117611576, 0.03319277491184496], [0.013545368313401727, -0.034586219727736255],
                [0.04335329910817251, -0.0021558683727751766]]
    goals = (reach(theta_deg=24.388733853924695), reach(s_g_mm=10.0), reach(s_g_mm=-10.0))
    return run(vertices, 0.2889686299481784, 0.3833548766755788, 0.382349545387647, goals, 3734005922)


def test_a_pivot_that_rolled_before_turning_the_object_leaves_the_tilts_below_reachable(rolled_early) -> None:
    """The case: a goal pivot ended ``rolled`` within a pivot's tolerance of where it began, by the
    truth above the lowest tilt the exploration had held the object at. The later goals at 2.8°,
    below it, which the oracle reaches, are reached within their tolerance by the truth."""
    result, summary = rolled_early.result, rolled_early.summary
    data = result.samples
    theta = np.degrees(np.asarray(data["true_coordinates"])[:, 0])
    held_low = theta[: sample_at(data, result.steps[7].end_time)].min()  # the exploration's 8 steps

    def turned(step) -> float:
        return abs(theta[sample_at(data, step.end_time)] - theta[sample_at(data, step.start_time)])

    early = [
        s for s in result.steps
        if s.goal is not None and s.kind == "pivot" and s.status == "rolled"
        and turned(s) < PIVOT_TOLERANCE_DEG
    ]
    assert early and theta[sample_at(data, early[0].start_time)] > held_low + 5.0
    for goal in summary["goals"][1:]:
        assert goal["oracle"]["reachable"]
        assert goal["status"] == "reached" and goal["within_tolerance"], goal


def test_ground_slides_lost_near_the_vertical_are_sought_past_it_and_the_goal_reached(
    lost_near_vertical,
) -> None:
    """The case: at least two of the goal's ground slides ended ``lost`` within the band where the
    pose cannot tell them from a hand slide, by the truth's tilt. The goal, which the oracle
    reaches, is reached within its tolerance by the truth."""
    result, summary = lost_near_vertical.result, lost_near_vertical.summary
    kinematics = KinematicsParams()
    band = math.degrees(math.asin(kinematics.position_noise / kinematics.valid_std)) + PIVOT_TOLERANCE_DEG
    theta = np.degrees(np.asarray(result.samples["true_coordinates"])[:, 0])
    goal = summary["goals"][2]
    lost = [
        s for s in result.steps
        if s.goal == goal["index"] and s.kind == "slide_ground" and s.status == "lost"
        and abs(theta[sample_at(result.samples, s.start_time)]) < band
    ]
    assert len(lost) >= 2
    assert goal["oracle"]["reachable"]
    assert goal["status"] == "reached" and goal["within_tolerance"], goal


@pytest.fixture(scope="module")
def held_slides() -> Experiment:
    vertices = [[0.0685777615177403, 0.03425512571803571], [-0.07604556949807133, -0.010776546402522114],
                [-0.03093288287362771, -0.06748630862908002], [0.005215231645633909, -0.072497318074799],
                [0.05750978997588445, -0.04162022777628418]]
    goals = (reach(theta_deg=LOW_GOAL_DEG, s_g_mm=-10.0),)
    return run(vertices, 0.24250409362792477, 0.37361688972255136, 0.45147704590538706, goals, 199829066)


def test_a_ground_slide_that_did_not_start_is_tried_again_where_it_failed(held_slides) -> None:
    """The case: a goal's ground slide ended ``timeout`` and the next one, within half a pivot step
    of the same tilt by the truth, moved the ground by most of its command. The goal, which the
    oracle reaches, is reached within its tolerance by the truth."""
    result, summary = held_slides.result, held_slides.summary
    theta = np.degrees(np.asarray(result.samples["true_coordinates"])[:, 0])
    s_g = np.asarray(result.samples["true_coordinates"])[:, 2]
    slides = [s for s in result.steps if s.goal is not None and s.kind == "slide_ground"]
    half_step = 0.5 * math.degrees(PlannerParams().pivot_step)

    def at(time: float) -> int:
        return sample_at(result.samples, time)

    retried = [
        (failed, again) for failed, again in itertools.pairwise(slides)
        if failed.status == "timeout"
        and abs(theta[at(again.start_time)] - theta[at(failed.start_time)]) <= half_step
        and abs(s_g[at(again.end_time)] - s_g[at(again.start_time)]) >= 0.5 * abs(again.delta)
    ]
    assert retried
    goal = summary["goals"][0]
    assert goal["oracle"]["reachable"]
    assert goal["status"] == "reached" and goal["within_tolerance"], goal


@pytest.fixture(scope="module")
def rolled_over_the_face_end() -> Experiment:
    vertices = [[0.032486014959909715, 0.011555802769146526], [-0.03497957493910002, 0.020580763226844913],
                [-0.034678190839134766, -0.015371360201069077]]
    back = reach(theta_deg=LOW_GOAL_DEG, s_g_mm=-10.0)
    goals = (reach(s_h_mm=10.0), reach(s_g_mm=10.0), back, reach(s_h_mm=10.0))
    return run(vertices, 0.5044341144894605, 0.6660641607038036, 0.7916952920361116, goals, 691998362)


def test_a_hand_rolling_over_the_face_end_is_seen_before_the_object_turns(rolled_over_the_face_end) -> None:
    """A sliver (seed 0, trial 21) whose ground slides, with the hand 9 mm past the ground contact,
    move the centre of pressure to the face's end, well inside the hand. The case: a ground slide of
    the ``s_g`` goal ends ``rolled``. By the truth the hand never turns more than 2° against the
    object in the whole run (it rolled 17° unseen, the slide reported reached with ``s_g`` 10 mm
    off), and every goal reported reached is within its tolerance; the ``s_g`` goal, which the
    oracle reaches, is reached."""
    result, summary = rolled_over_the_face_end.result, rolled_over_the_face_end.summary
    data = result.samples
    truth = np.asarray(data["true_coordinates"])[:, 0] - np.asarray(data["true_hand_pose"])[:, 2]
    goal = summary["goals"][1]
    slides = [s for s in result.steps if s.goal == goal["index"] and s.kind == "slide_ground"]
    assert any(s.status == "rolled" for s in slides)
    assert np.degrees(np.ptp(truth[sample_at(data, result.steps[0].end_time):])) < 2.0
    assert goal["oracle"]["reachable"] and goal["status"] == "reached"
    for each in summary["goals"]:
        assert each["status"] != "reached" or each["within_tolerance"], each



TURNED_PENTAGON = (
    ((0.07494520905827287, 0.01778118341607554), (0.010004903726227437, 0.06778821064578597),
     (-0.075518827753112, -0.02039044202417651), (-0.04998874309681562, -0.05516542804161837),
     (0.04649655312036692, -0.05477076814101207)),
    0.5570918211954209, 0.5480853304907123, 0.7505909397241208,
)
PENTAGON_GOALS = (reach(s_g_mm=-10.0),)


@pytest.mark.parametrize("checked", [True, False], ids=["moment checked", "unchecked"])
def test_kinematics_the_moment_balance_contradicts_are_learned_anew(checked: bool) -> None:
    """The case (goals seed 2, trial 1, noise seed 0): unchecked (the check's sample count out of
    reach), the wrong kinematics do not reach the ``s_g`` goal: they claimed it 16.3 mm off by the
    truth, and since a ground slide that did not start is tried again where it failed, the goal
    fails 52 mm off. Checked, they are reset and learned again by exploring, and every goal is
    reached within its tolerance by the truth (0.9 mm off)."""
    estimator = EstimatorParams() if checked else EstimatorParams(moment_mismatch_samples=10**9)
    params = LoopParams(estimator_params=estimator)
    summary = run(*TURNED_PENTAGON, PENTAGON_GOALS, 0, params).summary
    goals = summary["goals"]
    if checked:
        assert all(g["status"] == "reached" and g["within_tolerance"] for g in goals), goals
    else:
        assert not any(g["status"] == "reached" and g["within_tolerance"] for g in goals), goals


ROCKING_PENTAGON = (
    ((0.04489352415840628, 0.02161674190387873), (-0.028277780412668416, 0.045248196596133314),
     (-0.052373656318454025, 0.01038432047364983), (-0.0454304814998695, -0.04194200352361469),
     (-0.01277777739196946, -0.050537663871827315)),
    0.6708027861111525, 0.4884627090484549, 0.8946395170384869,
)
ROCKING_GOALS = (
    reach(theta_deg=31.588733853924694, s_g_mm=10.0), reach(theta_deg=9.988733853924696),
    reach(s_g_mm=-10.0), reach(s_h_mm=-10.0),
)


@pytest.mark.parametrize("doubting", [True, False], ids=["doubted", "undoubted"])
def test_positions_the_moment_balance_contradicts_are_not_claimed(doubting: bool) -> None:
    """The case (goals seed 6, trial 1): the ``s_h`` goal, reached by the estimate after a pivot
    that rocked the pentagon onto its next vertex. Undoubted (``moment_doubt_tilt`` at the reset's
    tilt, so the kinematics are never doubted short of a reset), it is claimed reached, off by the
    truth by more than its tolerance. Doubted, it ends ``failed``, the balance named, and by the
    truth it is indeed outside its tolerance. (On noise seeds 0–7 the four goals end alike either
    way but on seed 6, where the doubt stops another claim outside the tolerance.)"""
    tilt = EstimatorParams().moment_mismatch_tilt
    estimator = EstimatorParams() if doubting else EstimatorParams(moment_doubt_tilt=tilt)
    params = LoopParams(estimator_params=estimator)
    goal = run(*ROCKING_PENTAGON, ROCKING_GOALS, 4186225163, params).summary["goals"][3]
    assert abs(goal["true_error"]["s_h_mm"]) > 1e3 * GOAL_TOLERANCE[1], goal
    if doubting:
        assert goal["status"] == "failed" and goal["reason"] == DOUBTED, goal
    else:
        assert goal["status"] == "reached", goal


HEAVY_QUADRILATERAL = (
    ((-0.07660948746343185, 0.01646614556716727), (-0.05721918098666484, -0.04807479072850895),
     (-0.03106459129264579, -0.0705663770531922), (0.07440625081234442, -0.02066080967942695)),
    0.9879824995790261, 0.4294748284150718, 0.507245110721929,
)
QUADRILATERAL_GOALS = (
    reach(theta_deg=24.388733853924695), reach(s_g_mm=-10.0), reach(s_g_mm=-10.0), reach(s_h_mm=10.0),
)


@pytest.mark.parametrize(
    ("checked", "settled"),
    [(True, True), (False, True), (False, False)],
    ids=["checked", "settled", "unchecked"],
)
def test_a_ground_slide_that_slid_the_hand_is_not_taken_for_the_grounds(
    checked: bool, settled: bool, monkeypatch: pytest.MonkeyPatch
) -> None:
    """The case (goals seed 7, trial 35, noise seed 0): with neither the departure out of reach
    checked nor the hold before a claim where the hand is reported off flush, an ``s_g`` goal was
    claimed reached outside its tolerance by the truth (9.9 mm off, the object where it began).
    Checked, every goal claimed reached is within its tolerance by the truth, and the two ``s_g``
    goals are reached (1.0 mm off); with the hold alone, every goal claimed is within its tolerance
    too (1.7 mm off)."""
    estimator = EstimatorParams() if checked else EstimatorParams(hand_give=1.0)
    if not settled:
        monkeypatch.setattr(GoalSequencer, "max_settles", 0)
    params = LoopParams(estimator_params=estimator)
    goals = run(*HEAVY_QUADRILATERAL, QUADRILATERAL_GOALS, 0, params).summary["goals"]
    claimed = [g for g in goals if g["status"] == "reached"]
    if checked:
        assert all(g["within_tolerance"] for g in claimed), goals
        assert all(g["status"] == "reached" for g in goals[1:3]), goals
    elif settled:
        assert claimed and all(g["within_tolerance"] for g in claimed), goals
    else:
        assert any(not g["within_tolerance"] and g["targets"]["s_g_mm"] is not None for g in claimed), goals


HAND_GAVE_TRIANGLE = (
    ((0.06830254659072219, 0.05404367711953298), (-0.07274439515226586, 0.05077839230979951),
     (-0.0704341208080029, -0.025318491176577907)),
    0.4643631313027823, 0.5894393882394463, 0.6913196117345117,
)


@pytest.mark.parametrize("dropped", [True, False], ids=["lost slide dropped", "kept"])
def test_a_lost_ground_slide_that_slid_the_hand_teaches_nothing_of_the_ground(
    dropped: bool, monkeypatch: pytest.MonkeyPatch
) -> None:
    """The case: a ground slide of the ``s_g`` goal ended ``lost`` with the hand moved 3 mm or more
    along the face by the truth and the ground less than 1 mm (at 10°: 4.8 mm and 0.0 mm). Kept (the
    evidence of that slide left as it was), the goal, which the oracle reaches, was reported
    unreachable; dropped, it is reached within its tolerance by the truth (at −12.8°, 0.2 mm off)."""
    if not dropped:
        keep = lambda self, commanded, kinematics, slid: slid  # noqa: E731
        monkeypatch.setattr(Estimator, "_drop_unfounded_slide", keep)
    goals = (reach(theta_deg=31.588733853924694), reach(s_g_mm=-10.0))
    done = run(*HAND_GAVE_TRIANGLE, goals, 10)
    data, goal = done.result.samples, done.summary["goals"][1]
    truth = np.asarray(data["true_coordinates"])

    def moved(step, coordinate: int) -> float:
        begin, end = sample_at(data, step.start_time), sample_at(data, step.end_time)
        return abs(truth[end, coordinate] - truth[begin, coordinate])

    lost = [
        s for s in done.result.steps
        if s.goal == goal["index"] and s.kind == "slide_ground" and s.status == "lost"
    ]
    assert any(moved(s, 1) >= 0.003 and moved(s, 2) < 0.001 for s in lost)
    assert goal["oracle"]["reachable"]
    if dropped:
        assert goal["status"] == "reached" and goal["within_tolerance"], goal
    else:
        assert goal["status"] == "unreachable", goal


def test_a_pivot_planned_to_the_end_of_the_robots_reach_is_not_refused() -> None:
    """The case: a goal's pivot ends within a pivot's tolerance of the reach's upper end by the
    truth's hand angle, and inside it. No step is refused as beyond the reach, and the ``s_g`` goal,
    which the oracle reaches, is reached within its tolerance by the truth."""
    goals = (reach(theta_deg=24.4), reach(s_g_mm=10.0))
    schedule = Schedule("reach-end", (*exploration(), *goals))
    done = run_experiment(make_object("paper-triangle"), schedule, LoopParams(plant="panda"), seed=0)
    high = done.result.hand_angle_range[1]
    hand = np.asarray(done.result.samples["true_hand_pose"])[:, 2]
    ends = [
        hand[sample_at(done.result.samples, s.end_time)] for s in done.result.steps
        if s.goal is not None and s.kind == "pivot" and s.status == "reached"
    ]
    assert any(0.0 <= high - end < DEFAULT_TOLERANCE["pivot"] for end in ends), np.degrees([*ends, high])
    assert not any("reach" in s.reason for s in done.result.steps)
    goal = done.summary["goals"][1]
    assert goal["oracle"]["reachable"] and goal["status"] == "reached" and goal["within_tolerance"], goal


GAINING_QUADRILATERAL = (
    ((0.06731941353370191, 0.024362626759020494), (-0.017627378461874548, 0.060760976940620263),
     (-0.0127194496787761, -0.06279273401745744), (0.06180741522155921, -0.04253991804802296)),
    0.9144946078380651, 0.6135427852052732, 0.5871181746873616,
)


def test_a_ground_slide_that_ended_held_after_sliding_is_no_failure() -> None:
    """The case: two of the ``s_g`` goal's ground slides ended ``rolled`` or ``timeout`` having moved
    the ground their way by the controller's slide onset or more, by the truth. The goal, which the
    oracle reaches, is reached within its tolerance by the truth."""
    there = reach(theta_deg=24.388733853924695, s_g_mm=-10.0)
    back = reach(theta_deg=9.988733853924696, s_g_mm=10.0)
    done = run(*GAINING_QUADRILATERAL, (there, back), 2090914255, LoopParams(plant="panda"))
    data, goal = done.result.samples, done.summary["goals"][1]
    s_g = np.asarray(data["true_coordinates"])[:, 2]

    def gained(step) -> float:
        moved = s_g[sample_at(data, step.end_time)] - s_g[sample_at(data, step.start_time)]
        return moved * np.sign(step.delta)

    slides = [s for s in done.result.steps if s.goal == goal["index"] and s.kind == "slide_ground"]
    onset = ControllerParams().slide_onset
    assert sum(s.status in HELD and gained(s) >= onset for s in slides) >= 2
    assert goal["oracle"]["reachable"] and goal["status"] == "reached" and goal["within_tolerance"], goal


ROLLED_OFF_QUADRILATERAL = (
    ((0.03278367120308789, 0.04699662785480027), (-0.048335085294915855, -0.03210511674809434),
     (0.04700474099207254, -0.04561082400571682), (0.05387731286775125, -0.007584980281050989)),
    0.8580681852302388, 0.4214008510751398, 0.3563405495253575,
)


def test_a_goal_is_not_claimed_on_an_estimate_taken_with_the_hand_off_the_face() -> None:
    """The case: a hand slide at 39° rolled the object 12° further than the hand, which ends on the
    face's end (by the truth, hand and face more than 5° apart), and the estimate, taken as flush,
    puts ``s_g`` within the next goal's tolerance. No goal is claimed reached outside its tolerance
    by the truth."""
    goals = (reach(theta_deg=24.388733853924695), reach(s_h_mm=-10.0), reach(s_g_mm=10.0))
    done = run(*ROLLED_OFF_QUADRILATERAL, goals, 3452956581)
    data = done.result.samples
    slid = done.summary["goals"][1]
    at = sample_at(data, slid["end_time"])
    apart = np.asarray(data["true_hand_pose"])[at, 2] - np.asarray(data["true_coordinates"])[at, 0]
    assert abs(np.degrees(apart)) > 5.0, np.degrees(apart)
    claimed = [g for g in done.summary["goals"] if g["status"] == "reached"]
    assert claimed and all(g["within_tolerance"] for g in claimed), done.summary["goals"]
