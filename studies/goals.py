"""Goals on random objects: does the planner reach what the object allows, and only claim what is true?

    ccopt study goals [--trials 40] [--goals 4] [--plant planar] [--workers 2] [--quick]

Each trial draws, from its own seed, a random convex polygon (3–8 sides: vertices at sorted random
angles on a circle, radii 75–100 % of it, kept if the polygon is convex and its start face holds
the hand), 6–20 cm across, 0.15–1.0 kg, ``μ_hand`` 0.3–0.7, ``μ_ground`` 0.3–0.9 (uniform), and
``--goals`` random goals in the paper's increments from the start: a tilt of ±7.2° or ±14.4°, a hand
position of ±10 mm, a ground position of ±10 mm, or a tilt and a ground position together. The
schedule is ``explore`` then the goals; the run is scored by :func:`ccopt.experiment.run_experiment`,
each goal by the simulator's truth and by the experimenter's oracle (the planner on the true statics,
within the object's start vertex, :func:`ccopt.experiment.goal_oracle`).

The bars (issue 11): of the goals the oracle reaches, at least 95 % are ``reached``; no goal is
reported ``reached`` whose true error is outside its tolerance. A miss's cause is its status and the
first words of its reason. Outputs in ``<out>``: ``results.json``/``results.csv`` (one row per
trial, with its goals).
"""

from __future__ import annotations

import math
import sys
from collections import Counter
from collections.abc import Mapping, Sequence
from dataclasses import dataclass

import numpy as np
from scipy.spatial import ConvexHull

from ccopt.cliutil import print_table
from ccopt.closed_loop import LoopParams, start_config
from ccopt.experiment import run_experiment
from ccopt.objects import PlanarObject, from_vertices
from ccopt.schedule import Goal, Schedule, exploration, reach
from studies import runner
from studies.robustness import fits_hand, held_at_start

SIDES = (3, 8)
ACROSS = (0.06, 0.20)
"""Range of the polygon's circumscribed diameter, m."""
MASS = (0.15, 1.0)
MU_HAND = (0.3, 0.7)
MU_GROUND = (0.3, 0.9)
DRAWS = 200
"""Polygons drawn per trial before giving up on one that holds the hand and is held."""
GOAL_KINDS = ("tilt", "hand", "ground", "tilt+ground")


@dataclass(frozen=True)
class GoalTrial:
    """One trial: the polygon (vertices in m), its mass (kg) and frictions, the goals as given
    (``(theta_deg, s_h_mm, s_g_mm)``, None where free), the plant; ``draws`` polygons were drawn."""

    index: int
    seed: int
    vertices: tuple[tuple[float, float], ...]
    mass: float
    mu_hand: float
    mu_ground: float
    goals: tuple[tuple[float | None, float | None, float | None], ...]
    plant: str
    draws: int


def random_polygon(rng: np.random.Generator) -> np.ndarray:
    """A convex polygon (k × 2, m) with 3–8 vertices, 6–20 cm across."""
    while True:
        count = int(rng.integers(SIDES[0], SIDES[1] + 1))
        radius = 0.5 * rng.uniform(*ACROSS)
        angles = np.sort(rng.uniform(0.0, 2.0 * math.pi, count))
        radii = radius * rng.uniform(0.75, 1.0, count)
        points = np.column_stack([radii * np.cos(angles), radii * np.sin(angles)])
        hull = ConvexHull(points)
        if len(hull.vertices) == count and np.min(np.diff(np.r_[angles, angles[0] + 2 * math.pi])) > 0.3:
            return points[np.sort(hull.vertices)]


def random_goals(rng: np.random.Generator, count: int, start_deg: float) -> tuple:
    goals = []
    for _ in range(count):
        kind = GOAL_KINDS[int(rng.integers(len(GOAL_KINDS)))]
        tilt = start_deg + float(rng.choice([-14.4, -7.2, 7.2, 14.4]))
        slide = float(rng.choice([-10.0, 10.0]))
        goals.append(
            {
                "tilt": (tilt, None, None),
                "hand": (None, slide, None),
                "ground": (None, None, slide),
                "tilt+ground": (tilt, None, slide),
            }[kind]
        )
    return tuple(goals)


def draw_trial(index: int, seed: int, goals: int, plant: str) -> GoalTrial:
    """Trial ``index`` from ``seed``: a polygon that holds the hand, and that the hand can hold where
    the run starts it (:func:`~studies.robustness.held_at_start`), its physics, its goals."""
    rng = np.random.default_rng(seed)
    params = LoopParams(plant=plant)
    for draw in range(1, DRAWS + 1):
        vertices = random_polygon(rng)
        mass, mu_hand, mu_ground = (float(rng.uniform(*span)) for span in (MASS, MU_HAND, MU_GROUND))
        try:
            obj = from_vertices(vertices, mass, mu_hand, mu_ground)
        except ValueError:  # a face shorter than the library takes (1 cm)
            continue
        if fits_hand(obj, params) and held_at_start(obj, params):
            start = math.degrees(start_config(obj, params).theta_o)
            targets = random_goals(rng, goals, start)
            corners = tuple((float(x), float(y)) for x, y in vertices)
            return GoalTrial(index, seed, corners, mass, mu_hand, mu_ground, targets, plant, draw)
    raise ValueError(f"trial {index}: no polygon of {DRAWS} drawn holds the hand")


def build(trial: GoalTrial) -> tuple[PlanarObject, Schedule]:
    obj = from_vertices(np.array(trial.vertices), trial.mass, trial.mu_hand, trial.mu_ground)
    goals: list[Goal] = [reach(*targets) for targets in trial.goals]
    return obj, Schedule("random-goals", (*exploration(), *goals))


def goal_trial(trial: GoalTrial) -> dict:
    """Run one trial; per goal its status, truth and the oracle's verdict."""
    obj, schedule = build(trial)
    done = run_experiment(obj, schedule, LoopParams(plant=trial.plant), seed=trial.seed)
    runner.finished(done.result)
    summary = done.summary
    return {
        "status": summary["status"],
        "unintended_slips": summary["unintended_slips"],
        "goals": [
            {
                "targets": goal["targets"],
                "status": goal["status"],
                "reason": goal["reason"],
                "within_tolerance": goal["within_tolerance"],
                "true_error": goal["true_error"],
                "oracle_reachable": goal["oracle"]["reachable"],
                "oracle_reason": goal["oracle"]["reason"],
                "motions": goal["motions"],
            }
            for goal in summary["goals"]
        ],
    }


def cause(goal: Mapping[str, object]) -> str:
    """A missed goal's cause: its status and the first words of its reason."""
    reason = str(goal["reason"]).split(":")[-1].strip()
    words = " ".join(reason.split()[:6])
    return f"{goal['status']}: {words}" if words else str(goal["status"])


def summarise(results: Sequence[dict]) -> dict:
    goals = [goal for result in results if "goals" in result for goal in result["goals"]]
    reachable = [goal for goal in goals if goal["oracle_reachable"]]
    reached = [goal for goal in reachable if goal["status"] == "reached"]
    claimed = [goal for goal in goals if goal["status"] == "reached"]
    off = [goal for goal in claimed if not goal["within_tolerance"]]
    return {
        "trials": len(results),
        "errors": sum("error" in result for result in results),
        "goals": len(goals),
        "oracle_reachable": len(reachable),
        "reached_of_reachable": len(reached),
        "reached_share_of_reachable": len(reached) / len(reachable) if reachable else None,
        "reached_beyond_the_oracle": sum(not goal["oracle_reachable"] for goal in claimed),
        "reached_outside_tolerance": len(off),
        "unreachable_agreeing_with_oracle": sum(
            goal["status"] == "unreachable" and not goal["oracle_reachable"] for goal in goals
        ),
        "runs_with_slips": sum(result.get("unintended_slips", 0) > 0 for result in results),
        "miss_causes": dict(Counter(cause(goal) for goal in reachable if goal["status"] != "reached")),
    }


def overview_rows(summary: Mapping[str, object]) -> list[tuple[str, str]]:
    share = summary["reached_share_of_reachable"]
    rows = [
        ("trials (errors)", f"{summary['trials']} ({summary['errors']})"),
        ("goals", str(summary["goals"])),
        ("oracle-reachable goals reached (bar ≥ 95 %)",
         f"{summary['reached_of_reachable']}/{summary['oracle_reachable']}"
         + ("" if share is None else f" ({100 * share:.0f} %)")),
        ("reached with the true error outside tolerance (bar 0)", str(summary["reached_outside_tolerance"])),
        ("reached where the oracle finds no sequence", str(summary["reached_beyond_the_oracle"])),
        ("unreachable, as the oracle says", str(summary["unreachable_agreeing_with_oracle"])),
        ("runs with unintended slips", str(summary["runs_with_slips"])),
    ]
    rows += [(f"miss: {name}", str(count)) for name, count in sorted(summary["miss_causes"].items())]
    return rows


def main(argv: Sequence[str] | None = None) -> int:
    parser = runner.study_parser("goals", __doc__.split("\n")[0], "6 trials of 3 goals")
    parser.add_argument("--trials", type=runner.positive_int, default=40, metavar="N", help="random objects")
    parser.add_argument("--goals", type=runner.positive_int, default=4, metavar="N", help="goals per trial")
    parser.add_argument("--plant", choices=("planar", "panda"), default="planar", help="simulated robot")
    args = parser.parse_args(argv)
    trials, goals = (6, 3) if args.quick else (args.trials, args.goals)
    seeds = runner.trial_seeds(args.seed, trials)
    specs = [draw_trial(k, seed, goals, args.plant) for k, seed in enumerate(seeds)]
    options = runner.RunOptions.from_args(args)
    results = runner.run_study(parser.prog, goal_trial, specs, options)
    summary = summarise(results)
    runner.write_results(options.out, specs, results, summary)
    print_table(overview_rows(summary), ("goals on random objects", "value"))
    print(f"results in {options.out}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
