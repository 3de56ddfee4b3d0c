"""The paper's §VII experiment: ten closed-loop trials over the five paper objects, scored against truth.

    ccopt study paper [--schedule paper] [--plant planar] [--trials 10] [--workers 2]

The ten trials (:data:`TRIALS`): each of the five ``paper-*`` objects; the triangle and the pentagon
with 0.5 kg added (as in the paper); and a second run of the triangle, the square and the hexagon.
Every trial gets its own seed from ``--seed`` (:func:`studies.runner.trial_seeds`), so the repeated
objects differ in their sensor noise. ``μ_hand = 0.5``, ``μ_ground = 0.8``, the ``paper`` schedule by
default (``--schedule`` takes a built-in name or a file).

Each trial is recorded to ``<out>/trials/<k>/`` (overwritten; ``ccopt plot`` draws its figures) and
scored by :func:`ccopt.experiment.run_experiment`. Outputs in ``<out>``: ``results.json``/``results.csv`` (one
row per trial), ``estimation_error_boxes.png`` (Fig. 6b, pooled over the trials),
``realised_histogram.png`` (Fig. 8b), and the friction cones (Fig. 7), estimation traces (Fig. 6a)
and control errors (Fig. 8a) of the first trial that finished (a trial whose run raised is an error
row, its partial record left out of the figures).

A trial *meets the closed-loop thresholds* (:class:`ccopt.metrics.Thresholds`, issue 10's bar) when it
completed, its median estimation errors are at most 1° (``θ_o``) and 3 mm (``s_h``, ``s_g``), its median
realised/commanded ratio is in [0.85, 1.15] and that of each kind of motion that ran in [0.9, 1.1], at
least 80 % of its samples have valid kinematics, the true normal force stayed within 27 N, and it had no
unintended slip. A median that does not exist (the kinematics were never estimated) misses its threshold.
The ``misses`` column names the thresholds a trial misses; ``impossible steps`` counts the schedule's
steps that no controller could do on the trial's object (the oracle of
:func:`ccopt.statics.schedule_feasibility`, the statics LP on the true object). ``--schedule tour`` runs
each object's own tour of the motions its true statics allow (:func:`ccopt.experiment.experimenter_tour`,
issue 10's scripted runs).
"""

from __future__ import annotations

import argparse
import shutil
import sys
from collections.abc import Sequence
from dataclasses import asdict, dataclass
from pathlib import Path

from ccopt import metrics
from ccopt.cliutil import fail, print_table
from ccopt.closed_loop import LoopParams
from ccopt.experiment import run_experiment
from ccopt.objects import make_object
from ccopt.record import Record, load_record
from studies import runner
from studies.runner import cell, slips_cell

TRIALS: tuple[tuple[str, float], ...] = (
    ("paper-triangle", 0.0),
    ("paper-square", 0.0),
    ("paper-rectangle", 0.0),
    ("paper-pentagon", 0.0),
    ("paper-hexagon", 0.0),
    ("paper-triangle", 0.5),
    ("paper-pentagon", 0.5),
    ("paper-triangle", 0.0),
    ("paper-square", 0.0),
    ("paper-hexagon", 0.0),
)
"""``(object, added mass in kg)`` of the ten trials, in order."""

MU_HAND = 0.5
MU_GROUND = 0.8


@dataclass(frozen=True)
class PaperTrial:
    """One trial: ``object`` plus ``added_mass`` (kg) through ``schedule`` on ``plant``, recorded to
    ``folder``; ``seed`` seeds the sensor noise."""

    index: int
    object: str
    added_mass: float
    seed: int
    schedule: str
    plant: str
    mu_hand: float
    mu_ground: float
    folder: str


# --- the trial ------------------------------------------------------------------------------------


def paper_trial(spec: PaperTrial) -> dict:
    """Run, record and score one trial; the row of :func:`ccopt.metrics.flat_summary` plus ``misses``."""
    obj = make_object(spec.object, added_mass=spec.added_mass, mu_hand=spec.mu_hand, mu_ground=spec.mu_ground)
    schedule, params = runner.trial_run(obj, spec.schedule, LoopParams(plant=spec.plant))
    folder = Path(spec.folder)
    shutil.rmtree(folder, ignore_errors=True)
    done = run_experiment(obj, schedule, params, seed=spec.seed, folder=folder)
    runner.finished(done.result)
    summary = done.summary
    return {
        **metrics.flat_summary(summary),
        "impossible_steps": summary["impossible_steps"],
        "misses": metrics.misses(summary),
    }


def make_specs(seed: int, count: int, schedule: str, plant: str, out: Path) -> list[PaperTrial]:
    """The first ``count`` of :data:`TRIALS`, each with its own seed and record folder."""
    seeds = runner.trial_seeds(seed, len(TRIALS))
    return [
        PaperTrial(k, name, mass, seeds[k], schedule, plant, MU_HAND, MU_GROUND, str(out / "trials" / str(k)))
        for k, (name, mass) in enumerate(TRIALS[:count])
    ]


# --- output ---------------------------------------------------------------------------------------


def label(spec: PaperTrial) -> str:
    return spec.object + (f" +{spec.added_mass:g} kg" if spec.added_mass else "")


def summarise(specs: Sequence[PaperTrial], results: Sequence[dict]) -> dict:
    """How many trials meet the thresholds, and what each of the others misses."""
    missed = {k: ["error"] if "error" in r else r["misses"] for k, r in enumerate(results)}
    return {
        "trials": len(results),
        "meet_thresholds": sum(not m for m in missed.values()),
        "thresholds": asdict(metrics.Thresholds()),
        "misses": {label(specs[k]) + f" (trial {k})": m for k, m in missed.items() if m},
        "errors": dict(runner.failures(results)),
    }


def records(specs: Sequence[PaperTrial], results: Sequence[dict]) -> list[tuple[int, Record]]:
    """``(trial index, record)`` of every trial that finished (a run that raised left only part of one)."""
    return [(s.index, load_record(s.folder)) for s, r in zip(specs, results, strict=True) if "error" not in r]


def write_figures(out: Path, specs: Sequence[PaperTrial], results: Sequence[dict]) -> list[Path]:
    """The pooled error boxes and realised histogram; cones, traces and control errors of one trial."""
    from ccopt import plots

    loaded = records(specs, results)
    if not loaded:
        return []
    runs = [record for _, record in loaded]
    first, record = loaded[0]
    figures = {
        "estimation_error_boxes.png": plots.estimation_error_boxes(runs),
        "realised_histogram.png": plots.realised_histogram(runs),
        f"friction_cones_trial{first}.png": plots.friction_cones(record),
        f"estimation_trial{first}.png": plots.estimation_figure(record),
        f"control_trial{first}.png": plots.control_errors(record),
    }
    for name, figure in figures.items():
        figure.savefig(out / name, dpi=110)
    return [out / name for name in figures]


def table_rows(specs: Sequence[PaperTrial], results: Sequence[dict]) -> list[tuple[str, ...]]:
    rows = []
    for spec, r in zip(specs, results, strict=True):
        if "error" in r:
            rows.append((str(spec.index), label(spec), "ERROR", *[""] * 9, r["error"]))
            continue
        ratio = f"{cell(r['ratio_median'])} [{cell(r['ratio_q25'])}, {cell(r['ratio_q75'])}]"
        rows.append(
            (
                str(spec.index),
                label(spec),
                "yes" if r["completed"] else "no",
                f"{r['steps_done']}/{r['steps_total']}",
                cell(r["theta_err_deg_median"]),
                cell(r["s_h_err_mm_median"]),
                cell(r["s_g_err_mm_median"]),
                ratio,
                slips_cell(r),
                f"{100 * r['infeasible_share']:.0f}",
                str(len(r["impossible_steps"])),
                f"{r['wall_time_s']:.1f}",
                ", ".join(r["misses"]) or "-",
            )
        )
    return rows


HEADER = (
    "k",
    "object",
    "completed",
    "steps",
    "θ err (deg)",
    "s_h err (mm)",
    "s_g err (mm)",
    "ratio med [q25, q75]",
    "slips (g h p)",
    "infeasible %",
    "impossible steps",
    "wall (s)",
    "misses",
)


def make_parser() -> argparse.ArgumentParser:
    parser = runner.study_parser(
        "paper", __doc__.split("\n")[0], "the first trial only (unless --trials) on the smoke schedule"
    )
    runner.closed_loop_arguments(parser)
    parser.add_argument(
        "--trials",
        type=runner.positive_int,
        metavar="K",
        help=f"run only the first K of the {len(TRIALS)} trials (default: {len(TRIALS)})",
    )
    return parser


def main(argv: Sequence[str] | None = None) -> int:
    parser = make_parser()
    args = parser.parse_args(argv)
    trials = args.trials or (1 if args.quick else len(TRIALS))
    if trials > len(TRIALS):
        fail(parser.prog, f"--trials must be at most {len(TRIALS)}, got {trials}")
    schedule = runner.checked_schedule(parser.prog, args)
    options = runner.RunOptions.from_args(args)
    specs = make_specs(args.seed, trials, schedule, args.plant, options.out)
    results = runner.run_study(parser.prog, paper_trial, specs, options)
    summary = summarise(specs, results)
    summary["figures"] = [str(path) for path in write_figures(options.out, specs, results)]
    runner.write_results(options.out, specs, results, summary)
    print_table(table_rows(specs, results), HEADER)
    print(
        f"{summary['meet_thresholds']}/{summary['trials']} trials meet the closed-loop thresholds "
        "(completed; median errors θ ≤ 1°, s_h and s_g ≤ 3 mm; median ratio in [0.85, 1.15], per kind in "
        "[0.9, 1.1]; valid kinematics ≥ 80 %; normal force ≤ 27 N; no slips)"
    )
    print(f"results in {options.out}")
    return 0 if not runner.failures(results) else 1


if __name__ == "__main__":
    sys.exit(main())
