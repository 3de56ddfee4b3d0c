"""Goal steps at run time: the motions a goal needs, planned one at a time on the estimated statics.

A closed loop that meets a :class:`~ccopt.schedule.Goal` hands it to a :class:`GoalSequencer`, which
answers, every time a motion ends, with the next motion or with how the goal ended:

* **explore** — while the kinematics are not yet usable the statics cannot be judged: the
  exploration of :func:`ccopt.schedule.exploration` runs first; and after a motion that ended
  ``lost`` (the estimator let go of what it could no longer tell, e.g. which contact slid) its
  pivots run again, which find the ground contact and ``s_h`` anew (at most
  :attr:`GoalSequencer.max_explorations` explorations per goal);
* **move** — :func:`ccopt.planning.planner.next_motion` on the statics the estimate knows *now*
  (:func:`ccopt.control.targets.estimated_statics`, per motion), from the estimated configuration.
  Until the hand has slid, ``μ̂_h`` is a lower bound, optimistic for a hand slide: a hand slide is
  certain only where it keeps its margin at both ``μ̂_h`` and
  :attr:`~ccopt.planning.planner.PlannerParams.hand_friction_max`. Where no plan is certain, the
  planner tries the friction midway between them, then ``μ̂_h`` alone, and such a plan's first hand
  slide is a probe. Where that finds no sequence either, it plans again with the hand friction one
  step beyond ``μ̂_h`` (the controller explores it on the way);
* a motion that explores — an uncertain hand slide (above), a motion on the hand friction one step
  beyond ``μ̂_h``, or a ground slide towards a side whose friction face is not yet known (sought
  past the sticking forces seen) — is a probe
  (``Step.explore``): it looks for a limit that may not be where it is sought, and its realised
  change is not scored as a commanded motion's;
* ``reached`` — every given coordinate is within its tolerance, by the estimate; but a goal on
  ``s_h`` or ``s_g`` ends ``failed`` instead where the moment balance contradicts the kinematics'
  ground contact (``Estimate.kinematics_doubted``): an object rocked over a ground face onto the
  next vertex, unseen, has its positions a face's length off, and the reset that settles it comes
  only after 5° of turning. ``θ_o`` is the hand's, and a goal on it alone stands. Over seeds 0–19
  of the goals study it changed six goals of 2 500 (a run goes on the same either way): four
  claimed 18–50 mm off by the truth, and two within their tolerance that the oracle does not
  reach. Where the estimator reports the hand off flush (on the face's end, so ``θ̂_o`` is not the
  face's angle and the positions taken from it are off), the goal first holds for
  :data:`SETTLE_TIME` (once, :attr:`GoalSequencer.max_settles`) and is judged again on the
  estimate the hold leaves: on the goals study a hand slide at 39° rolled an object 12° past the
  hand, which the kinematics still took as flush (they follow the commanded configuration), and
  the next ``s_g`` goal was claimed at once 14 mm off by the truth; after the hold the estimate saw
  where the object lay;
* ``unreachable`` — no sequence reaches it under the estimate, with the planner's reason;
* ``timeout`` — the goal's time ran out;
* ``failed`` — the estimate became unusable, or :attr:`GoalSequencer.max_misses` planned motions
  in a row did not do what they commanded.

A pivot that ends ``rolled`` (the hand rolled on the face: the object stopped turning, it lies on
another vertex or a face) marks the tilt where the roll was first seen, a degree short, as a limit
that way for the rest of the run (:attr:`GoalSequencer.tilt_limits`): what the estimate knows of
the object's tipping points. A goal not yet reached beyond a limit first pivots back to it
(:func:`~ccopt.planning.planner.back_within`).
A hand slide that the hand held against (it ended ``rolled`` on the
face's end or did not start: the object stayed where it was) is tried once more where it failed, then
not within half a pivot step of that tilt, and after :attr:`GoalSequencer.max_hand_slide_failures`
such failures that way not at all, for the rest of the goal (:attr:`GoalSequencer.failed_hand_slides`).
A goal the estimate then leaves no way to is ``unreachable``, its reason naming the failed slides.
A hand slide that slid the ground instead is not one of them: the object moved, and sought at other
tilts the next slides slid it further (on the goals study they tipped a quadrilateral over).
A ground slide that did not start (it ended ``rolled`` or ``timeout`` before ``ŝ_g`` moved its way by
the controller's slide onset) is tried once more where it failed, then sought half a pivot step further
that way; one ``lost`` near the vertical once the hand has slid, where the pose cannot tell it from
a hand slide, past that band (:meth:`GoalSequencer._failed_slide`).

``s_g`` goals are measured from ``s_g_origin``: the run's start ground contact as the estimate knows
it, the latest usable estimate while the ground has neither been commanded to slide nor seen moving
(``ccopt.closed_loop``'s step tracker). A slip the estimate never saw stays in it.
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from ccopt.control.targets import TargetGoal, estimated_statics, seeks_friction
from ccopt.estimation.estimator import Estimate
from ccopt.modes import HandGeometry, Motion, configuration, kind_of
from ccopt.planning.graph import Statics
from ccopt.planning.planner import (
    Plan,
    PlannerParams,
    StaticsOf,
    back_within,
    next_motion,
    past_reach,
    towards,
)
from ccopt.schedule import DEFAULT_TOLERANCE, Goal, Step, exploration, hold, probe_as_run
from ccopt.statics import ObjectStatics

GOAL_STATUSES = ("reached", "unreachable", "timeout", "failed")
"""How a goal can end (see the module docstring)."""
DOUBTED = (
    "the moment balance contradicts the kinematics' ground contact: the object may rest on another vertex"
)
"""Why a goal on ``s_h`` or ``s_g`` whose estimate is within its tolerance is not claimed
(:attr:`~ccopt.estimation.estimator.Estimate.kinematics_doubted`; see the module docstring)."""
SETTLE_TIME = 0.3
"""How long (s) a goal whose estimate is within its tolerance holds before it is claimed where the
hand is reported off flush (on a face's end, ``θ̂_o`` not the hand's)."""
HELD = ("rolled", "timeout")
"""How a slide ends when it did not start: the hand held against it (a hand slide) or the ground
did (a ground slide), and the object stayed put."""


@dataclass(frozen=True)
class GoalResult:
    """How one goal step went, by the estimate (truth is scored in :mod:`ccopt.metrics`).

    Attributes:
        index: the goal's position in the schedule.
        goal: the goal.
        start_time, end_time: simulated times, s.
        status: one of :data:`GOAL_STATUSES`.
        reason: why it ended so, one line ("" when reached).
        motions: how many motions it used (exploration included).
    """

    index: int
    goal: Goal
    start_time: float
    end_time: float
    status: str
    reason: str = ""
    motions: int = 0

    def as_dict(self) -> dict[str, object]:
        """The result as ``meta.json`` stores it (targets in degrees and millimetres, as given)."""
        theta, s_h, s_g = self.goal.targets
        return {
            "index": self.index,
            "targets": {
                "theta_deg": None if theta is None else math.degrees(theta),
                "s_h_mm": None if s_h is None else 1e3 * s_h,
                "s_g_mm": None if s_g is None else 1e3 * s_g,
            },
            "tolerance_deg": math.degrees(self.goal.angle_tolerance),
            "tolerance_mm": 1e3 * self.goal.length_tolerance,
            "start_time": self.start_time,
            "end_time": self.end_time,
            "status": self.status,
            "reason": self.reason,
            "motions": self.motions,
        }


class GoalSequencer:
    """The motions of one goal (see the module docstring).

    Args:
        index: the goal's position in the schedule.
        goal: the goal.
        start_time: when it begins, s.
        reach: the hand angles ``θ_h`` the robot reaches (rad); plans keep the face's ``θ_o``
            within them less the hand's tilt against the face when planned (see :meth:`next`).
        aim: force limits and margin of the estimated statics (:class:`~ccopt.control.targets.TargetGoal`;
            its headroom narrows the planner's force range, its friction step is the exploration).
        params: the planner's parameters.
        tilt_limits: the run's tilt limits so far (:attr:`tilt_limits`; shared by its goals).
        split_tilt: the least ``|θ_o|`` (rad) at which the estimator tells a ground slide from a
            hand slide by the pose (:attr:`~ccopt.estimation.kinematics.KinematicsParams.split_tilt`;
            0: at every tilt): see :meth:`_failed_slide`.
    """

    max_misses = 3
    max_explorations = 3
    max_hand_slide_failures = 3
    lost_slide_tries = 2
    slide_tries_per_tilt = 2
    max_settles = 1

    def __init__(
        self,
        index: int,
        goal: Goal,
        start_time: float,
        reach: tuple[float, float],
        aim: TargetGoal,
        params: PlannerParams | None = None,
        tilt_limits: dict[int, float] | None = None,
        split_tilt: float = 0.0,
    ) -> None:
        self.index = index
        self.split_tilt = split_tilt
        self.goal = goal
        self.start_time = start_time
        self.reach = reach
        self.aim = aim
        self.params = params or PlannerParams()
        self.motions = 0
        self.misses = 0
        self.tilt_limits = {} if tilt_limits is None else tilt_limits
        """Per way (``±1``), the tilt (rad) past which a pivot that way rolled the hand instead of
        turning the object (it landed on another vertex or a face): plans keep within. The run's
        goals share it (it is the object's, not the goal's)."""
        self.failed_slides: dict[int, float] = {}
        """Per way (``±1``), the tilt (rad) of the last ground slide that did not start."""
        self.held_slides: dict[int, list[float]] = {}
        """Per way (``±1``), the tilts (rad) of the ground slides that ended ``rolled`` or
        ``timeout`` (:meth:`_failed_slide`: tried once more where they failed)."""
        self.unobservable_slides: dict[int, list[float]] = {}
        """Per way (``±1``), the tilts (rad) of the ground slides lost where the pose cannot tell
        them from a hand slide (:meth:`_failed_slide`)."""
        self.failed_hand_slides: dict[int, list[float]] = {}
        """Per way (``±1``), the tilts (rad) of the hand slides the hand held against (ended
        ``rolled`` or ``timeout``): see :meth:`_barred`."""
        self._exploration: list[Step] | None = None
        self._explored_last: Step | None = None  # the exploration's last step (run or skipped)
        self.explorations = 0
        self.settles = 0
        """Holds taken before a claim where the hand was reported off flush (module docstring)."""
        self._last: tuple[Step, float] | None = None  # the last motion and the tilt it began at
        self._hand_tilt = 0.0  # θ_h − θ̂_o (rad) when the next motion was asked for

    def next(
        self,
        now: float,
        estimate: Estimate,
        s_g_origin: float | None,
        last_status: str | None = None,
        roll_tilt: float | None = None,
        held_tilts: tuple[float, float] | None = None,
        hand_angle: float | None = None,
        last_started: bool = False,
    ) -> Step | GoalResult:
        """The next motion, or how the goal ended; ``last_status`` is how the previous motion of this
        goal ended (None at the start), ``roll_tilt`` the estimated ``θ_o`` (rad) where a pivot that
        ended ``rolled`` was first seen rolling (None: unknown), ``held_tilts`` the range of
        estimated ``θ_o`` (rad) at which pivots left the object on the vertex it is on now (None:
        unknown; :meth:`_rolled`), ``hand_angle`` the measured ``θ_h`` (rad; None: taken as
        ``θ̂_o``), ``last_started`` whether the previous motion, a slide, had moved its coordinate
        its way by the controller's slide onset when it ended
        (:attr:`~ccopt.control.controller.ControllerParams.slide_onset`).

        A pivot turns the hand from ``θ_h``, and the robot's reach bounds where the hand ends, not
        the face: the hand stands tilted against the face by the pad's compliance under the torque
        (``θ_h − θ̂_o``, a few tenths of a degree), so a plan to the end of the reach in ``θ_o`` asked
        the hand past it, and the step was refused (the paper triangle on the Panda plant, whose
        reach ends at 29.7°: two pivots to 29.8° refused, ``θ_h`` 29.9° and 30.2°, and the goal
        failed)."""
        hand_tilt = hand_angle - float(estimate.theta_o) if hand_angle is not None else 0.0
        self._hand_tilt = hand_tilt if math.isfinite(hand_tilt) else 0.0
        failed = last_status not in (None, "reached") and not self._started(last_status, last_started)
        self.misses = self.misses + 1 if failed else 0
        if self._last is not None and failed:
            step, tilt = self._last
            way = 1 if step.delta > 0 else -1
            if step.kind == "slide_ground":
                self._failed_slide(tilt, way, last_status, estimate)
            if step.kind == "slide_hand" and last_status in HELD:
                self.failed_hand_slides.setdefault(way, []).append(tilt)
            if step.kind == "pivot" and last_status == "rolled":
                self._rolled(tilt, roll_tilt, way, held_tilts)
        if now - self.start_time >= self.goal.timeout:
            return self.end(now, "timeout", f"the goal's {self.goal.timeout:g} s ran out")
        if self.misses >= self.max_misses:
            return self.end(now, "failed", f"{self.misses} planned motions in a row were not reached")
        usable = _usable(estimate) and s_g_origin is not None
        if not usable and not self._exploration and self.explorations < self.max_explorations:
            if last_status == "lost":
                self._exploration = [step for step in exploration() if step.kind == "pivot"]
                self.explorations += 1
            elif self._exploration is None:
                self._exploration = list(exploration())
                self.explorations += 1
        while self._exploration:
            step = self._explored(self._exploration.pop(0), estimate)
            if step is not None:
                return self._take(step)
        if not usable:
            return self.end(now, "failed", "the kinematics are unknown after exploring")
        plan = self._plan(estimate, s_g_origin)
        if plan.status == "reached":
            if estimate.kinematics_doubted and any(target is not None for target in self.goal.targets[1:]):
                return self.end(now, "failed", DOUBTED)
            if estimate.hand_geometry != HandGeometry.FLUSH and self.settles < self.max_settles:
                self.settles += 1
                return self._take(hold(SETTLE_TIME))
            return self.end(now, "reached")
        back = back_within(float(estimate.theta_o), self._reach(), self.params)
        if back is not None:
            plan = back
        if plan.status == "unreachable":
            return self.end(now, "unreachable", plan.reason + self._failures())
        self._last = (plan.motion, float(estimate.theta_o))
        probe = plan.explores or seeks_friction(estimate, plan.motion.motion)
        return self._take(dataclasses.replace(plan.motion, explore=True) if probe else plan.motion)

    def _plan(self, estimate: Estimate, s_g_origin: float) -> Plan:
        where = (float(estimate.theta_o), float(estimate.s_h), float(estimate.s_g))
        f_min, f_max = self.aim.force_limits
        forces = (f_min, f_max - self.aim.headroom)

        estimated = _estimated_statics(estimate, self.aim.push)

        def plan_with(mu_h: float | None, hand_ceiling: float | None = None) -> Plan:
            return next_motion(
                _statics_of(estimated, mu_h, hand_ceiling),
                where,
                self.goal,
                s_g_origin,
                self._reach(),
                estimate.torque_lever,
                forces,
                self.params,
                failed_slides=self.failed_slides,
                barred=self._barred,
            )

        if estimate.hand_slid:
            return plan_with(None)
        ceiling = max(self.params.hand_friction_max, estimate.mu_h)
        sure = plan_with(None, ceiling)
        if sure.status != "unreachable":
            return sure
        likely = plan_with(None, 0.5 * (estimate.mu_h + ceiling))
        plan = likely if likely.status == "move" else plan_with(None)
        if plan.status == "move":
            guess = plan.motion.kind == "slide_hand"  # the first hand slide is a probe of μ_h
            return dataclasses.replace(plan, explores=guess)
        if self.aim.friction_step <= 0.0:
            return plan
        bolder = plan_with(estimate.mu_h + self.aim.friction_step)
        if bolder.status != "move":
            return plan
        return Plan(bolder.status, bolder.motion, bolder.reason, bolder.path, explores=True)

    def _rolled(
        self, begin: float, roll_tilt: float | None, way: int, held: tuple[float, float] | None
    ) -> None:
        """Limit the tilt ``way`` after a pivot that began at ``begin`` (rad) ended ``rolled``
        (:func:`tilt_limit`, :attr:`tilt_limits`), unless the pivot rolled before it turned the
        object (``roll_tilt`` within a pivot's tolerance of ``begin``) where pivots had left the
        object beyond that limit by more than a pivot's tolerance (``held``): the object does not
        tip where it has already stood, and the roll came from the torque the previous motion left
        at the hand's limit. A random triangle's exploration had pivoted it to 9.9° and back; its
        hand-slide probe then rolled the hand 0.8° on the face's end, the first goal's pivot down
        from 16.9° began with its torque row tight and ended ``rolled`` with the object still, and
        the limit there cut the reach to [17°, 75°] for the rest of the run (goals-study seed 1,
        trial 38: three goals below 17° reported unreachable, the oracle reaching them). A pivot
        that turned the object before it rolled sets its limit whatever was held: another random
        triangle's exploration pivot had laid it on its face at 10.2°, and a goal's pivot from
        17.2° that rolled at 12.4°, onto that face, then rolled twice more where the limit was
        skipped."""
        limit = tilt_limit(begin, roll_tilt, way)
        still = roll_tilt is None or not abs(roll_tilt - begin) > PIVOT_TOLERANCE  # NaN: unknown
        edge = None if held is None else (held[0] if way < 0 else held[1])
        if still and edge is not None and way * edge > way * limit + PIVOT_TOLERANCE:
            return
        self.tilt_limits[way] = limit

    def _failed_slide(self, tilt: float, way: int, status: str, estimate: Estimate) -> None:
        """Record a ground slide towards ``way`` that began at ``tilt`` (rad) and ended ``status``
        as failed (:attr:`failed_slides`: :func:`~ccopt.planning.planner.next_motion` seeks the next
        one at least half a pivot step further that way).

        A slide that did not start (:data:`HELD`) is tried :attr:`slide_tries_per_tilt` times in all
        within half a pivot step of where it failed (:attr:`held_slides`), as a hand slide is
        (:meth:`_barred`). A slide not yet known to be possible is sought
        past the sticking forces seen by the push (:func:`~ccopt.control.targets.estimated_statics`),
        and its own forces move that edge out: the retry pushes further. On the goals study
        (seed 7, trial 11) a pentagon's ground slides towards −s_g timed out at 2.8° and −11.4°,
        after which none was sought within the tilt limits and the goal, which the oracle reaches,
        was reported unreachable; tried again at −11.4°, the slide moved the ground 10 mm and the
        goal was reached 1.3 mm off by the truth (:mod:`tests.test_goal_recovery`). Over seeds 0–19
        of the goals study, the goals the oracle reaches that were reached went from 1 813 of 2 038
        to 1 825 of 2 036 (on seeds 0–11, 14 ``s_g`` goals gained whose slides were retried, and 7
        goals of all kinds lost where the runs went otherwise), and the goals claimed reached
        outside their tolerance from 77 to 79 (within the study's noise: on seeds 12–19 alone, 747
        reached and 37 claimed either way). The gain is the ``rolled`` slides': retried after a
        ``timeout`` only, 1 811 of 2 033 were reached and 76 claimed. It has a cost: on the
        robustness study, runs that completed without a slip went from 34 to 32 of 50 (those that
        meet the closed-loop bar from 25 to 26); in trial 34 a slide at 31° had slid the ground
        9 mm before it ended ``rolled`` with the hand's centre of pressure 25 mm out, its retry
        ended ``rolled`` too, and the next pivot rolled and slipped the ground 2.5 mm.

        A slide ``lost`` once the hand has slid, within :attr:`split_tilt` of the vertical (and a
        pivot's tolerance, within which the pivot before it ended), is one the kinematics let go
        of because the forces brought the hand to its friction limit too, and the pose cannot tell
        the ground's slide from the hand's (:func:`~ccopt.estimation.estimator.either_slides`).
        Half a pivot step further the hand needs less of its friction, and a retry there may slide
        the ground (a goals-study quadrilateral's at 9.8° slid the hand 3.9 mm, its retry at 2.2°
        the ground 9.4 mm). After :attr:`lost_slide_tries` such slides that way, the next is
        sought past the band's far edge, where the pose tells the two slides apart: on the goals
        study (seed 1) the ground slides towards ``−s_g`` of three random objects were lost at
        9.6°, 2° and −5° in turn, an exploration after each, until the goal failed. Each lost
        slide costs an exploration, so a goal has :attr:`max_explorations` (3) of them: with 2, the
        slide past the band had none left after the two losses and another triangle's goal still
        failed (seed 1, trial 27; reached with 3)."""
        if status in HELD:
            held = self.held_slides.setdefault(way, [])
            held.append(tilt)
            if self._near(held, tilt) < self.slide_tries_per_tilt:
                return
        band = self.split_tilt + PIVOT_TOLERANCE
        if status != "lost" or not estimate.hand_slid or abs(tilt) > band:
            self.failed_slides[way] = tilt
            return
        lost = self.unobservable_slides.setdefault(way, [])
        lost.append(tilt)
        edge = way * (self.split_tilt - 0.5 * self.params.pivot_step)
        jump = len(lost) >= self.lost_slide_tries and (edge - tilt) * way > 0.0
        self.failed_slides[way] = edge if jump else tilt

    def _barred(self, theta: float, motion: Motion) -> bool:
        """Whether ``motion`` failed :attr:`slide_tries_per_tilt` times within half a pivot
        step of the tilt ``theta`` (rad), or :attr:`max_hand_slide_failures` times in all.

        A hand slide that failed is evidence the estimated statics lack: until the hand slides,
        ``μ̂_h`` is a lower bound, and a slide sought at it sets the normal force for too little
        friction (the centre of pressure moves by ``d̂ Δμ_h`` as the tangential force grows: 10 mm
        on the heavy paper triangle between ``μ̂_h`` 0.41 and the true 0.5) and loads the ground
        with too little tangential force. Tried at the same tilt again and again with the estimate
        barely changed, the paper triangle's hand slides rolled or did not start three times in a
        row and its goals failed; tried at ever larger tilts, the light triangle's slid the ground
        at the third and fourth (38° and 46°). But one retry where it failed is worth it: a
        ``rolled`` slide is judged on the conservative report (a torque near the hand's limit reads
        as maybe rolling, with the true hand flush), and on the goals study the second try at the
        same tilt slid the hand where the first had rolled."""
        if kind_of(motion) != "slide_hand":
            return False
        tilts = self.failed_hand_slides.get(int(configuration(motion).hand_mode), ())
        if len(tilts) >= self.max_hand_slide_failures:
            return True
        return self._near(tilts, theta) >= self.slide_tries_per_tilt

    def _started(self, status: str | None, started: bool) -> bool:
        """Whether the last motion, a ground slide that ended held (``status`` in :data:`HELD`), had
        ``started`` all the same: moved ``ŝ_g`` its way by the controller's slide onset. It is then
        neither a failed slide (:meth:`_failed_slide`) nor a miss. A slide ends ``rolled`` on the
        conservative report (the hand's torque near its limit over the part of the face known), and
        at the end of the reach there may be no other tilt to seek it at: on the Panda plant a
        quadrilateral's slides towards +s_g at 29.8° ended ``rolled`` after sliding the ground 1.7
        and 3.6 mm, and the goal was reported unreachable; counted as started, the next slide there
        slid 9.8 mm and the goal was reached (:mod:`tests.test_goal_recovery`). Goals study on the
        Panda, seeds 0–7: 555/649 → 559/649 oracle-reachable goals reached, claimed outside
        tolerance 20 → 21 (a 2.3 mm near miss); on the planar plant, seeds 0–19: 1 822/2 035 →
        1 820/2 033, claimed 74 → 75 (within the noise); paper cases, paper study (8 of 10) and
        robustness study (32 and 26 of 50) unchanged."""
        return started and status in HELD and self._last is not None and self._last[0].kind == "slide_ground"

    def _near(self, tilts: list[float] | tuple[float, ...], theta: float) -> int:
        """How many of ``tilts`` (rad) lie within half a pivot step of ``theta`` (rad)."""
        return sum(abs(theta - tilt) < 0.5 * self.params.pivot_step for tilt in tilts)

    def _failures(self) -> str:
        """The failed hand slides and the ground slides lost where the pose cannot tell them from a
        hand slide, for an ``unreachable`` reason ("" if none)."""
        parts = []
        if self.failed_hand_slides:
            parts.append(f"hand slides tried and failed {_ways(self.failed_hand_slides, 's_h')}")
        if self.unobservable_slides:
            parts.append(
                f"ground slides lost {_ways(self.unobservable_slides, 's_g')}, where within "
                f"{math.degrees(self.split_tilt):.1f}° of the vertical the pose cannot tell them from "
                "a hand slide"
            )
        return f" ({'; '.join(parts)})" if parts else ""

    def _reach(self) -> tuple[float, float]:
        """The robot's reach in ``θ_o`` (less the hand's tilt against the face, :meth:`next`), cut at
        the tilts where a pivot rolled the hand."""
        low, high = (limit - self._hand_tilt for limit in self.reach)
        low, high = max(low, self.tilt_limits.get(-1, low)), min(high, self.tilt_limits.get(1, high))
        return min(low, high), high

    def _within_limits(self, step: Step, theta: float) -> Step:
        """An exploration's pivot from ``theta`` (rad), turned the other way if it would end past the
        reach (:meth:`_reach`) by more than its tolerance: exploring again after a pivot found the
        object's tipping point (the kinematics lost), a random quadrilateral's probes went on 15°
        past it onto another vertex, where no planned motion was possible any more."""
        if step.kind != "pivot" or not math.isfinite(theta):
            return step
        if abs(past_reach(theta + step.delta, self._reach())) <= step.tolerance:
            return step
        return dataclasses.replace(step, delta=-step.delta)

    def _explored(self, step: Step, estimate: Estimate) -> Step | None:
        """An exploration's step as it runs: a pivot within the reach (:meth:`_within_limits`), a
        probe as :func:`~ccopt.schedule.probe_as_run` has it at ``θ̂_o`` (None: skipped)."""
        theta = float(estimate.theta_o)
        run = probe_as_run(self._within_limits(step, theta), self._explored_last, theta, estimate.hand_slid)
        self._explored_last = step if run is None else run
        return run

    def _take(self, step: Step) -> Step:
        self.motions += 1
        return step

    def end(self, now: float, status: str, reason: str = "") -> GoalResult:
        """The goal's result, ending now with ``status``."""
        return GoalResult(self.index, self.goal, self.start_time, now, status, reason, self.motions)


def _ways(tilts: dict[int, list[float]], coordinate: str) -> str:
    """``towards ±coordinate at a°, b°`` for each way's tilts (rad), joined by "; "."""
    return "; ".join(
        f"{towards(way, coordinate)} at " + ", ".join(f"{math.degrees(tilt):.0f}°" for tilt in each)
        for way, each in tilts.items()
    )


PIVOT_TOLERANCE = float(DEFAULT_TOLERANCE["pivot"])
"""rad: within this of its target a pivot ends (:data:`ccopt.schedule.DEFAULT_TOLERANCE`)."""
TIPPING_CLEARANCE = math.radians(1.0)
"""rad: how far short of a tipping point a plan keeps the object (the experimenter's oracle, of the
true one: :func:`ccopt.experiment.oracle_frame`)."""
ROLL_BACKOFF = TIPPING_CLEARANCE + PIVOT_TOLERANCE
"""rad: a pivot that rolled the hand limits the tilt that way this far short of where the roll was
first seen: :data:`TIPPING_CLEARANCE` and a pivot's tolerance, so that a pivot that ends within its
tolerance of the limit stays that clearance short. The roll is seen once the object has landed and
the hand presses it into its face, which the ground's compliance lets turn on: on the paper
pentagon the roll was first seen 0.4–0.9° past its tipping point by the truth. With a degree alone,
its ground slides were tried 0.3–0.4° short of the tipping point, with the far vertex on the
ground, and did not start."""


def tilt_limit(begin: float, roll_tilt: float | None, way: int) -> float:
    """The tilt (rad) past which a pivot ``way`` (``±1``) that began at ``begin`` and ended ``rolled``
    cannot go: the object turned with the hand up to where the roll was first seen (``roll_tilt``,
    less :data:`ROLL_BACKOFF`), never less than it began at. The start alone cut the reach a whole
    pivot short: a random triangle that tips onto a face at −23.8°, whose ground slide towards
    −s_g keeps 1 N of margin below about −20° by the estimate (−18° by the truth), was left with
    −18.3° and its goal reported unreachable (:mod:`tests.test_tipping_point`)."""
    if roll_tilt is None or not math.isfinite(roll_tilt):
        return begin
    return max(begin, roll_tilt - ROLL_BACKOFF) if way > 0 else min(begin, roll_tilt + ROLL_BACKOFF)


def _usable(estimate: Estimate) -> bool:
    values = (estimate.theta_o, estimate.s_h, estimate.s_g, estimate.d)
    return bool(estimate.kinematics_valid) and all(map(math.isfinite, values))


EstimatedStatics = Callable[[float | None, Motion], ObjectStatics]
"""The statics an estimate knows for a motion, with a given hand friction (None: ``μ̂_h``)."""


def _estimated_statics(estimate: Estimate, push: float) -> EstimatedStatics:
    """The estimated statics of a motion with the hand friction ``mu_h`` (None: ``μ̂_h``), at the
    current hand angle's gravity moment where no model is estimated yet, a ground slide sought
    ``push`` (N) past the sticking forces seen where its friction face is not known
    (:func:`ccopt.control.targets.estimated_statics`); each made once for all of a plan's searches."""
    cache: dict[tuple[float | None, Motion], ObjectStatics] = {}
    angle = float(estimate.theta_o)

    def of(mu_h: float | None, motion: Motion) -> ObjectStatics:
        key = (mu_h, motion)
        if key not in cache:
            known = estimated_statics(estimate, angle, mu_h, motion, push)
            if known is None:
                raise ValueError("the estimate cannot judge the statics")
            cache[key] = known
        return cache[key]

    return of


def _statics_of(
    estimated: EstimatedStatics, mu_h: float | None, hand_ceiling: float | None = None
) -> StaticsOf:
    """The statics per motion with the hand friction ``mu_h`` (None: ``μ̂_h``); a hand slide, where
    ``hand_ceiling`` is given, under that hand friction as well (the hand friction is known only to
    lie between them)."""

    def statics_of(motion: Motion) -> Statics:
        if hand_ceiling is not None and kind_of(motion) == "slide_hand":
            return estimated(mu_h, motion), estimated(hand_ceiling, motion)
        return estimated(mu_h, motion)

    return statics_of


def s_g_from(estimate: Estimate) -> float | None:
    """The ground contact ``s_g`` of a usable estimate (m), else None."""
    return float(estimate.s_g) if _usable(estimate) and np.isfinite(estimate.s_g) else None
