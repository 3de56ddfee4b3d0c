"""Closed-loop robustness over randomised objects: success rate, error distributions, failure causes.

    ccopt study robustness [--trials 50] [--schedule paper] [--plant planar] [--workers 2]

Each trial draws, from its own seed (:func:`studies.runner.trial_seeds` of ``--seed``), one of the
five shapes (:data:`SHAPES`) with side 7–19 cm (a rectangle draws width and height in 7–19 cm),
mass 0.2–0.95 kg, ``μ_hand`` 0.3–0.7 and ``μ_ground`` 0.4–0.9 (all uniform), runs the schedule in
closed loop (no record folder) and scores it with :func:`ccopt.experiment.run_experiment`.

A trial *succeeds* when it completed (every step reached, both contacts kept) without an unintended
slip; otherwise :func:`ccopt.metrics.failure_causes` names why (several may apply): an ``impossible
step`` (the oracle's statics LP on the true object), ``loss of contact``, a slip at the ground or the
hand, a ``hand pivot``, an ``infeasible QP``, an ``estimator reset`` or a ``timeout``.

An object whose hand face is shorter than the hand is ``does not fit the hand`` (not run); with
``--schedule tour`` (each object's own tour of what its true statics allow, issue 10's scripted
runs: :func:`ccopt.experiment.experimenter_tour`), one that no start on its face holds with margin
is ``no tour`` (not run); a trial that raised is ``run error`` with its message. A trial *meets the
bar* when :func:`ccopt.metrics.misses` finds nothing (errors, ratios overall and per kind, valid
kinematics, normal force, slips). Outputs in ``<out>``: ``results.json``/``results.csv``
(one row per trial, with the drawn object) and ``robustness.png`` (error distributions, causes, and
success over size and mass).
"""

from __future__ import annotations

import argparse
import sys
from collections import Counter
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from ccopt import metrics, statics
from ccopt.cliutil import print_table
from ccopt.closed_loop import LoopParams, start_config
from ccopt.experiment import run_experiment
from ccopt.modes import Motion
from ccopt.objects import PlanarObject, make_object
from ccopt.planning.graph import GraphParams
from ccopt.plant.placement import hand_over_vertex
from studies import runner
from studies.runner import cell, slips_cell

SHAPES = ("triangle", "square", "rectangle", "pentagon", "hexagon")
SIDE = (0.07, 0.19)
"""Range of a side (and of a rectangle's width and height), m."""
MASS = (0.2, 0.95)
"""Range of the mass, kg."""
MU_HAND = (0.3, 0.7)
MU_GROUND = (0.4, 0.9)
TRIALS = 50
QUICK_TRIALS = 3
"""Random objects of a study, and of one run with ``--quick``."""
DOES_NOT_FIT = "does not fit the hand"
NO_TOUR = "no tour"
RUN_ERROR = "run error"
CAUSES = (*metrics.CAUSES, DOES_NOT_FIT, NO_TOUR, RUN_ERROR)
"""Every cause a trial can report: a run's (:func:`ccopt.metrics.failure_causes`) and the study's own."""


@dataclass(frozen=True)
class RandomObject:
    """One trial's object and run. Lengths in m (``height`` only for a rectangle), mass in kg."""

    index: int
    seed: int
    shape: str
    side: float
    height: float | None
    mass: float
    mu_hand: float
    mu_ground: float
    schedule: str
    plant: str


def draw_object(index: int, seed: int, schedule: str, plant: str) -> RandomObject:
    """The object of trial ``index``, drawn from ``seed`` (the same seed seeds the sensor noise)."""
    rng = np.random.default_rng(seed)
    shape = str(rng.choice(SHAPES))
    side = float(rng.uniform(*SIDE))
    height = float(rng.uniform(*SIDE)) if shape == "rectangle" else None
    mass, mu_hand, mu_ground = (float(rng.uniform(*span)) for span in (MASS, MU_HAND, MU_GROUND))
    return RandomObject(index, seed, shape, side, height, mass, mu_hand, mu_ground, schedule, plant)


def build_object(spec: RandomObject) -> PlanarObject:
    size = {"width": spec.side, "height": spec.height} if spec.shape == "rectangle" else {"side": spec.side}
    return make_object(spec.shape, mass=spec.mass, mu_hand=spec.mu_hand, mu_ground=spec.mu_ground, **size)


def fits_hand(obj: PlanarObject, params: LoopParams) -> bool:
    """Whether the hand fits on the start face (else the run cannot start)."""
    try:
        hand_over_vertex(obj, params.start, params.hand)
    except ValueError:
        return False
    return True


def held_at_start(obj: PlanarObject, params: LoopParams) -> bool:
    """Whether a hand wrench of the start's normal force holds ``obj`` where the run starts it, as the
    plant places it (:func:`ccopt.statics.start_target`), with the margin the oracle asks of every
    motion (:class:`ccopt.planning.graph.GraphParams`); the statics of the *true* object, the
    experimenter's check. Without it the plant released the object, which fell before the run began
    or in its first pivots: in a goals study of 40 trials, 8 such starts (margins −12 to +0.5 N, e.g.
    a triangle whose face put the hand 41 mm off its ground contact lay on a face, and the run
    explored with the hand rolling on a corner) gave 28 of the 54 goals claimed reached whose true
    error was out of tolerance."""
    start = start_config(obj, params)
    hand = params.hand
    truth = statics.true_statics(obj, start, hand)
    force = (start.normal_force, start.normal_force)
    where = (start.theta_o, start.s_h)
    result = statics.best_wrench(truth.statics, *where, Motion.HOLD, hand.half_length, force)
    return result.wrench is not None and result.margin >= GraphParams().min_margin


def robustness_trial(spec: RandomObject) -> dict:
    """Run one random object; :func:`ccopt.metrics.flat_summary` plus success and causes."""
    obj = build_object(spec)
    params = LoopParams(plant=spec.plant)
    if not fits_hand(obj, params):
        return {"fits_hand": False, "success": False, "causes": [DOES_NOT_FIT]}
    try:
        schedule, params = runner.trial_run(obj, spec.schedule, params)
    except ValueError:  # the tour's object cannot be held with margin anywhere on its face
        return {"fits_hand": False, "success": False, "causes": [NO_TOUR]}
    done = run_experiment(obj, schedule, params, seed=spec.seed)
    runner.finished(done.result)
    summary = done.summary
    causes = metrics.failure_causes(summary)
    return {
        "fits_hand": True,
        **metrics.flat_summary(summary),
        "kinematics_resets": summary["kinematics_resets"],
        "impossible_steps": summary["impossible_steps"],
        "success": not causes,
        "causes": causes,
        "misses": metrics.misses(summary),
    }


# --- output ---------------------------------------------------------------------------------------


def causes_of(result: Mapping[str, object]) -> list[str]:
    return [RUN_ERROR] if "error" in result else list(result["causes"])


ERROR_COLUMNS = ("theta_err_deg_median", "s_h_err_mm_median", "s_g_err_mm_median", "ratio_median")


def column(results: Sequence[dict], key: str) -> list[float]:
    return [r[key] for r in results if r.get(key) is not None]


def summarise(specs: Sequence[RandomObject], results: Sequence[dict]) -> dict:
    """Success rate, quartiles over trials of the per-trial medians, cause counts, the failures."""
    causes = [causes_of(r) for r in results]
    return {
        "trials": len(results),
        "successes": sum(bool(r.get("success")) for r in results),
        "success_rate": sum(bool(r.get("success")) for r in results) / len(results),
        "meet_paper_thresholds": sum(r.get("misses") == [] for r in results),
        "feasible_schedules": sum(r.get("impossible_steps") == [] for r in results),
        "successes_on_feasible_schedules": sum(
            bool(r.get("success")) and r.get("impossible_steps") == [] for r in results
        ),
        "errors_over_trials": {key: metrics.quartiles(column(results, key)) for key in ERROR_COLUMNS},
        "causes": dict(Counter(c for found in causes for c in found)),
        "primary_causes": dict(Counter(found[0] for found in causes if found)),
        "failures": [
            {"index": spec.index, "object": describe(spec), "causes": found, "error": result.get("error")}
            for spec, result, found in zip(specs, results, causes, strict=True)
            if found
        ],
    }


def describe(spec: RandomObject) -> str:
    """``shape side(×height) cm, mass kg``."""
    size = f"{100 * spec.side:.1f}" + (f"×{100 * spec.height:.1f}" if spec.height is not None else "")
    return f"{spec.shape} {size} cm {spec.mass:.2f} kg"


def write_figure(path: Path, specs: Sequence[RandomObject], results: Sequence[dict]) -> None:
    """Per-trial median errors and ratios, failure-cause counts, success over size and mass."""
    from matplotlib.figure import Figure

    figure = Figure(figsize=(12, 6.5), layout="constrained")
    axes = figure.subplots(2, 3)
    for ax, key, title in zip(
        axes[0],
        ERROR_COLUMNS[:3],
        ("median |θ_o error| (deg)", "median |s_h error| (mm)", "median |s_g error| (mm)"),
        strict=True,
    ):
        values = column(results, key)
        if values:
            ax.boxplot(values, widths=0.5)
        ax.set_title(f"{title}, {len(values)} trials (no paper figure)")
        ax.set_xticks([])
    ratios = column(results, "ratio_median")
    if ratios:
        axes[1, 0].hist(ratios, bins=20, color="0.55", edgecolor="white")
    axes[1, 0].axvline(1.0, color="tab:blue", ls="--")
    axes[1, 0].set(title="median realised / commanded per trial", xlabel="ratio", ylabel="trials")
    counts = Counter(c for r in results for c in causes_of(r))
    names = [c for c in CAUSES if counts[c]]
    axes[1, 1].barh(names, [counts[c] for c in names], color="tab:red")
    axes[1, 1].invert_yaxis()
    axes[1, 1].set(title="failure causes (a trial may have several)", xlabel="trials")
    ok = np.array([bool(r.get("success")) for r in results])
    size = np.array([100 * (s.side if s.height is None else min(s.side, s.height)) for s in specs])
    mass = np.array([s.mass for s in specs])
    axes[1, 2].scatter(size[ok], mass[ok], color="tab:green", label="success")
    axes[1, 2].scatter(size[~ok], mass[~ok], color="tab:red", marker="x", label="failure")
    axes[1, 2].set(title="outcome by object", xlabel="side (shortest, cm)", ylabel="mass (kg)")
    axes[1, 2].legend()
    figure.savefig(path, dpi=110)


def failure_rows(specs: Sequence[RandomObject], results: Sequence[dict]) -> list[tuple[str, ...]]:
    rows = []
    for spec, r in zip(specs, results, strict=True):
        if r.get("success"):
            continue
        ran = "error" not in r and r["fits_hand"]
        rows.append(
            (
                str(spec.index),
                describe(spec),
                f"{spec.mu_hand:.2f}/{spec.mu_ground:.2f}",
                f"{r['steps_done']}/{r['steps_total']}" if ran else "-",
                slips_cell(r) if ran else "-",
                f"{100 * r['infeasible_share']:.0f}" if ran else "-",
                ", ".join(causes_of(r)) + (f": {r['error']}" if "error" in r else ""),
            )
        )
    return rows


def overview_rows(summary: Mapping[str, object]) -> list[tuple[str, ...]]:
    rows = [
        ("success (completed, no slips)", f"{summary['successes']}/{summary['trials']}"),
        ("meet the closed-loop bar", f"{summary['meet_paper_thresholds']}/{summary['trials']}"),
        (
            "success where every step is possible",
            f"{summary['successes_on_feasible_schedules']}/{summary['feasible_schedules']}",
        ),
    ]
    for key, q in summary["errors_over_trials"].items():
        rows.append(
            (
                f"{key} over trials: median [q25, q75]",
                f"{cell(q['median'])} [{cell(q['q25'])}, {cell(q['q75'])}]",
            )
        )
    for cause in CAUSES:
        if cause in summary["causes"]:
            primary = summary["primary_causes"].get(cause, 0)
            rows.append((f"cause: {cause}", f"{summary['causes'][cause]} (first cause of {primary})"))
    return rows


def make_parser() -> argparse.ArgumentParser:
    parser = runner.study_parser(
        "robustness", __doc__.split("\n")[0], f"{QUICK_TRIALS} trials (unless --trials) on the smoke schedule"
    )
    runner.closed_loop_arguments(parser)
    parser.add_argument(
        "--trials", type=runner.positive_int, metavar="N", help=f"random objects (default: {TRIALS})"
    )
    return parser


def main(argv: Sequence[str] | None = None) -> int:
    parser = make_parser()
    args = parser.parse_args(argv)
    schedule = runner.checked_schedule(parser.prog, args)
    seeds = runner.trial_seeds(args.seed, args.trials or (QUICK_TRIALS if args.quick else TRIALS))
    specs = [draw_object(k, seed, schedule, args.plant) for k, seed in enumerate(seeds)]
    options = runner.RunOptions.from_args(args)
    results = runner.run_study(parser.prog, robustness_trial, specs, options)
    summary = summarise(specs, results)
    runner.write_results(options.out, specs, results, summary)
    write_figure(options.out / "robustness.png", specs, results)
    failed = failure_rows(specs, results)
    if failed:
        print_table(failed, ("k", "object", "μ_h/μ_g", "steps", "slips (g h p)", "infeasible %", "causes"))
    print_table(overview_rows(summary), ("robustness", "value"))
    print(f"results in {options.out}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
