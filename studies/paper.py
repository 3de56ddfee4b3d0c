"""The paper's §VII experiment: ten closed-loop trials over the five paper objects, scored against truth.

    python -m studies paper [--schedule paper] [--plant planar] [--trials 10] [--workers 2]

The ten trials (:data:`TRIALS`): each of the five ``paper-*`` objects; the triangle and the pentagon
with 0.5 kg added (as in the paper); and a second run of the triangle, the square and the hexagon.
Every trial gets its own seed from ``--seed`` (:func:`studies.runner.trial_seeds`), so the repeated
objects differ in their sensor noise. ``μ_hand = 0.5``, ``μ_ground = 0.8``, the ``paper`` schedule by
default (``--schedule`` takes a built-in name or a file).

Each trial is recorded to ``<out>/trials/<k>/`` (overwritten; ``ccopt plot`` draws its figures) and
scored by :func:`ccopt.metrics.summarize`. Outputs in ``<out>``: ``results.json``/``results.csv`` (one
row per trial), ``estimation_error_boxes.png`` (Fig. 7b, pooled over the trials),
``realised_histogram.png`` (Fig. 9b), and the friction cones (Fig. 8), estimation traces (Fig. 7a)
and control errors (Fig. 9a) of the first trial that finished (a trial whose run raised is an error
row, its partial record left out of the figures).

A trial *meets the closed-loop thresholds* (:class:`Thresholds`) when it completed, its median
estimation errors are at most 1° (``θ_o``) and 3 mm (``s_h``, ``s_g``), its median realised/commanded
ratio is in [0.85, 1.15] and it had no unintended slip. A median that does not exist (the kinematics
were never estimated) misses its threshold. The ``misses`` column names the thresholds a trial misses;
``impossible steps`` counts the schedule's steps that no controller could do on the trial's object
(:func:`studies.feasibility.infeasible_steps`, the statics LP on the true object), which explains
most misses of the ``paper`` schedule (see the README).
"""

from __future__ import annotations

import argparse
import shutil
import sys
from collections.abc import Mapping, Sequence
from dataclasses import asdict, dataclass
from pathlib import Path

from ccopt import closed_loop, metrics
from ccopt.cliutil import fail, print_table
from ccopt.closed_loop import LoopParams, RunResult
from ccopt.objects import PlanarObject, make_object
from ccopt.record import Record, load_record, write_summary
from ccopt.schedule import Schedule, load_schedule
from studies import feasibility, runner

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
class Thresholds:
    """What a closed-loop trial must achieve: error medians in deg and mm, the ratio band, no slips."""

    theta_err_deg: float = 1.0
    s_h_err_mm: float = 3.0
    s_g_err_mm: float = 3.0
    ratio_low: float = 0.85
    ratio_high: float = 1.15


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


# --- shared by the closed-loop studies ------------------------------------------------------------


def object_meta(obj: PlanarObject) -> dict[str, object]:
    """The object as ``meta.json`` stores it (what :mod:`ccopt.plots` rebuilds it from)."""
    return {
        "name": obj.name,
        "vertices": obj.vertices.tolist(),
        "mass": obj.mass,
        "mu_hand": obj.mu_hand,
        "mu_ground": obj.mu_ground,
    }


def run_meta(obj: PlanarObject, schedule: Schedule, seed: int, params: LoopParams) -> dict[str, object]:
    """``meta.json`` of a recorded run, as ``ccopt run`` writes it."""
    return {
        "object": object_meta(obj),
        "schedule": schedule.to_dict(),
        "seed": seed,
        "params": {
            "plant": params.plant,
            "estimator_hz": params.estimator_hz,
            "controller_hz": params.controller_hz,
            "l_h": params.plant_params.l_h,
            "start": asdict(params.start),
        },
    }


def finished(result: RunResult) -> RunResult:
    """``result``, or ``KeyboardInterrupt`` again if Ctrl-C ended the run (the study must stop too)."""
    if result.interrupted:
        raise KeyboardInterrupt
    return result


def flat_summary(summary: Mapping[str, object]) -> dict[str, object]:
    """The scalar columns of a :func:`ccopt.metrics.summarize` summary (errors in deg and mm)."""
    slips = [event["contact"] for event in summary["slip_events"]]
    ratio = summary["ratio_realised_commanded"]
    return {
        "completed": summary["completed"],
        "steps_done": summary["steps_done"],
        "steps_total": summary["steps_total"],
        "contact_kept": summary["contact_kept"],
        **{
            f"{key}_{stat}": summary[key][stat]
            for key in ("theta_err_deg", "s_h_err_mm", "s_g_err_mm")
            for stat in ("median", "p95")
        },
        "ratio_median": ratio["median"],
        "ratio_q25": ratio["q25"],
        "ratio_q75": ratio["q75"],
        "unintended_slips": summary["unintended_slips"],
        **{f"slips_{name}": slips.count(name) for name in metrics.CONTACT_NAMES},
        "infeasible_share": summary["infeasible_ticks_share"],
        "sim_time_s": summary["sim_time_s"],
        "wall_time_s": summary["wall_time_s"],
    }


def _at_most(value: float | None, limit: float) -> bool:
    return value is not None and value <= limit


def misses(summary: Mapping[str, object], thresholds: Thresholds = Thresholds()) -> list[str]:
    """The thresholds a run misses: ``completed``, ``theta_err``, ``s_h_err``, ``s_g_err``, ``ratio``,
    ``slips`` (an absent median misses)."""
    ratio = summary["ratio_realised_commanded"]["median"]
    checks = {
        "completed": bool(summary["completed"]),
        "theta_err": _at_most(summary["theta_err_deg"]["median"], thresholds.theta_err_deg),
        "s_h_err": _at_most(summary["s_h_err_mm"]["median"], thresholds.s_h_err_mm),
        "s_g_err": _at_most(summary["s_g_err_mm"]["median"], thresholds.s_g_err_mm),
        "ratio": ratio is not None and thresholds.ratio_low <= ratio <= thresholds.ratio_high,
        "slips": summary["unintended_slips"] == 0,
    }
    return [name for name, met in checks.items() if not met]


def cell(value: object, digits: int = 2) -> str:
    """A table cell: numbers rounded, ``None`` as ``n/a``."""
    if value is None:
        return "n/a"
    if isinstance(value, float):
        return f"{value:.{digits}f}"
    return str(value)


def slips_cell(row: Mapping[str, object]) -> str:
    """``total (g ground slides, h hand slides, p hand pivots)``."""
    parts = " ".join(
        f"{tag}{row[f'slips_{name}']}"
        for tag, name in (("g", "ground_slide"), ("h", "hand_slide"), ("p", "hand_pivot"))
    )
    return f"{row['unintended_slips']} ({parts})"


def closed_loop_arguments(parser: argparse.ArgumentParser) -> None:
    """``--schedule`` and ``--plant``, shared by the closed-loop studies."""
    parser.add_argument(
        "--schedule", default="paper", help="built-in (paper, smoke) or a .yaml/.json file (default: paper)"
    )
    parser.add_argument(
        "--plant", choices=("planar", "panda"), default="planar", help="simulated robot (default: planar)"
    )


def checked_schedule(prog: str, name: str) -> Schedule:
    """The schedule ``name``, or one line and exit 2."""
    try:
        return load_schedule(name)
    except ValueError as error:
        fail(prog, str(error))


# --- the trial ------------------------------------------------------------------------------------


def paper_trial(spec: PaperTrial) -> dict:
    """Run, record and score one trial; the row of :func:`flat_summary` plus ``misses``."""
    obj = make_object(spec.object, added_mass=spec.added_mass, mu_hand=spec.mu_hand, mu_ground=spec.mu_ground)
    schedule = load_schedule(spec.schedule)
    params = LoopParams(plant=spec.plant)
    folder = Path(spec.folder)
    shutil.rmtree(folder, ignore_errors=True)
    meta = run_meta(obj, schedule, spec.seed, params)
    result = finished(closed_loop.run(obj, schedule, params, seed=spec.seed, out=folder, meta=meta))
    recorded = load_record(folder)
    summary = metrics.summarize(
        recorded.data, recorded.meta["steps"], len(schedule.steps), result.sim_time, result.wall_time
    )
    write_summary(folder, summary)
    infeasible = feasibility.infeasible_steps(obj, schedule, params)
    return {**flat_summary(summary), "infeasible_steps": infeasible, "misses": misses(summary)}


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
        "thresholds": asdict(Thresholds()),
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
                str(len(r["infeasible_steps"])),
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
    parser = runner.study_parser("paper", __doc__.split("\n")[0])
    closed_loop_arguments(parser)
    parser.add_argument(
        "--trials",
        type=runner.positive_int,
        default=len(TRIALS),
        metavar="K",
        help=f"run only the first K of the {len(TRIALS)} trials (default: {len(TRIALS)})",
    )
    return parser


def main(argv: Sequence[str] | None = None) -> int:
    parser = make_parser()
    args = parser.parse_args(argv)
    if args.trials > len(TRIALS):
        fail(parser.prog, f"--trials must be at most {len(TRIALS)}, got {args.trials}")
    checked_schedule(parser.prog, args.schedule)
    options = runner.RunOptions.from_args(args)
    specs = make_specs(args.seed, args.trials, args.schedule, args.plant, options.out)
    results = runner.run_study(parser.prog, paper_trial, specs, options)
    summary = summarise(specs, results)
    summary["figures"] = [str(path) for path in write_figures(options.out, specs, results)]
    runner.write_results(options.out, specs, results, summary)
    print_table(table_rows(specs, results), HEADER)
    print(
        f"{summary['meet_thresholds']}/{summary['trials']} trials meet the closed-loop thresholds "
        "(completed; median errors θ ≤ 1°, s_h and s_g ≤ 3 mm; median ratio in [0.85, 1.15]; no slips)"
    )
    print(f"results in {options.out}")
    return 0 if not runner.failures(results) else 1


if __name__ == "__main__":
    sys.exit(main())
