"""``ccopt``: run, plot and benchmark from the command line.

    ccopt run   --object paper-triangle --schedule paper --plant planar --seed 0 --out runs/tri
    ccopt plot  runs/tri
    ccopt study feasibility --workers 2
    ccopt bench qp_latency --quick

Degrees and millimetres at the command line (vertices in mm), SI inside. Bad input gets one line
naming the bad value and exit status 2; Ctrl-C during a run keeps the record written so far.
"""

from __future__ import annotations

import argparse
import runpy
import sys
from collections.abc import Sequence
from pathlib import Path

import numpy as np

from ccopt import __version__, objects, record
from ccopt.cliutil import OneLineParser, fail, print_table
from ccopt.objects import PlanarObject
from ccopt.schedule import load_schedule

BENCHMARKS = ("qp_latency", "plant_speed", "estimator_speed")


def parse_vertices(text: str) -> np.ndarray:
    """``"x,y;x,y;..."`` in millimetres to an ``(n, 2)`` array in metres."""
    try:
        points = [[float(v) for v in pair.split(",")] for pair in text.split(";") if pair.strip()]
        vertices = np.array(points, dtype=float)
    except ValueError:
        raise ValueError(f"--vertices {text!r} is not of the form 'x,y;x,y;...' (mm)") from None
    if vertices.ndim != 2 or vertices.shape[1] != 2:
        raise ValueError(f"--vertices {text!r} is not of the form 'x,y;x,y;...' (mm)")
    return vertices * 1e-3


def build_object(args: argparse.Namespace) -> PlanarObject:
    """The object the user asked for (the controller is never told any of it)."""
    friction = {"mu_hand": args.mu_hand, "mu_ground": args.mu_ground}
    if args.vertices is not None:
        mass = args.mass if args.mass is not None else 0.3
        return objects.from_vertices(parse_vertices(args.vertices), mass + args.added_mass, **friction)
    return objects.make_object(args.object, mass=args.mass, added_mass=args.added_mass, **friction)


def _run_parser(commands: argparse._SubParsersAction) -> None:
    run = commands.add_parser("run", help="manipulate an unknown object through a schedule")
    shape = run.add_mutually_exclusive_group()
    shape.add_argument("--object", default="paper-triangle", help="library object name")
    shape.add_argument("--vertices", help="convex polygon 'x,y;x,y;...' in mm, counter-clockwise")
    run.add_argument("--mass", type=float, help="object mass, kg (default: the object's)")
    run.add_argument("--added-mass", type=float, default=0.0, help="mass added to the object, kg")
    run.add_argument("--mu-hand", type=float, default=0.5, help="hand/object friction coefficient")
    run.add_argument("--mu-ground", type=float, default=0.8, help="object/ground friction coefficient")
    run.add_argument("--plant", choices=("planar", "panda"), default="planar")
    run.add_argument("--schedule", default="paper", help="built-in name (paper, smoke) or a .yaml/.json file")
    run.add_argument("--seed", type=int, default=0)
    run.add_argument("--estimator-hz", type=float, default=100.0)
    run.add_argument("--controller-hz", type=float, default=30.0)
    run.add_argument("--out", default="runs/latest", help="run folder (created)")
    run.add_argument("--no-figures", action="store_true", help="skip the figures and the GIF")
    run.add_argument("--no-progress", action="store_true", help="no progress bar")


def _command_run(args: argparse.Namespace, prog: str) -> int:
    from ccopt import closed_loop, experiment

    try:
        obj = build_object(args)
        schedule = load_schedule(args.schedule)
        params = closed_loop.LoopParams(
            plant=args.plant, estimator_hz=args.estimator_hz, controller_hz=args.controller_hz
        )
        folder = record.prepare_folder(args.out)
    except (ValueError, TypeError) as error:
        fail(prog, str(error))
    done = run_with_progress(experiment, obj, schedule, params, args, folder)
    print_summary(done.summary, folder)
    loaded = record.load_record(folder)
    if not args.no_figures and loaded.data:
        from ccopt import plots

        paths = plots.write_figures(loaded, folder)
        print("figures: " + ", ".join(str(p) for p in paths))
    return EXIT_CODES[done.result.status]


def run_with_progress(experiment, obj, schedule, params, args, folder):
    """Run the experiment with a tqdm bar over the schedule's steps (unless ``--no-progress``); the
    oracle's warnings about impossible steps go to stderr first."""
    from tqdm import tqdm

    bar = tqdm(total=len(schedule.steps), unit="step", disable=args.no_progress, leave=False, mininterval=0.5)
    with bar:

        def on_tick(sim_time: float, index: int, total: int) -> None:
            bar.set_postfix(sim=f"{sim_time:.1f}s", refresh=False)
            bar.update(min(index, total) - bar.n)  # redraws at most every mininterval

        def warn(line: str) -> None:
            print(f"warning: {line}", file=sys.stderr)

        return experiment.run_experiment(
            obj, schedule, params, seed=args.seed, folder=folder, on_tick=on_tick, warn=warn
        )


EXIT_CODES = {
    "completed": 0,
    "contact_lost": 3,
    "sensor_fault": 3,
    "timeout": 3,
    "error": 1,
    "interrupted": 130,
}
"""How ``ccopt run`` exits, by how the run ended (bad input exits 2 before any run)."""


def print_summary(summary: dict, folder: Path) -> None:
    def stat(value: float | None, digits: int = 2) -> str:
        return "n/a" if value is None else f"{value:.{digits}f}"

    def spread(entry: dict) -> str:
        return f"{stat(entry['median'])} [{stat(entry['q25'])}, {stat(entry['q75'])}]"

    def errors(key: str) -> str:
        return f"{stat(summary[key]['median'])} / {stat(summary[key]['p95'])}"

    force = summary["normal_force_n"]
    rows = [
        ("status", summary["status"] + (f" ({summary['message']})" if summary.get("message") else "")),
        ("steps reached", f"{summary['steps_done']}/{summary['steps_total']}"),
        ("kinematics valid share", stat(summary["kinematics_valid_share"])),
        ("θ_o error median / p95 (deg)", errors("theta_err_deg")),
        ("s_h error median / p95 (mm)", errors("s_h_err_mm")),
        ("s_g error median / p95 (mm)", errors("s_g_err_mm")),
        *(
            (f"realised/commanded {kind} median [q25, q75] (n)", f"{spread(entry)} ({entry['n']})")
            for kind, entry in summary["ratio_by_kind"].items()
        ),
        ("normal force median / p99 / max (N)", " / ".join(stat(force[k], 1) for k in force)),
        ("unintended slips", str(summary["unintended_slips"])),
        ("steps the estimate ruled out", str(summary["infeasible_steps"])),
        ("steps impossible on the true object (oracle)", str(summary.get("impossible_steps", "not checked"))),
        ("sim / wall time (s)", f"{summary['sim_time_s']:.1f} / {summary['wall_time_s']:.1f}"),
    ]
    print_table(rows, ("metric", "value"))
    print(f"record: {folder}")


def _command_plot(args: argparse.Namespace, prog: str) -> int:
    try:
        loaded = record.load_record(args.record)
    except ValueError as error:
        fail(prog, str(error))
    from ccopt import plots

    paths = plots.write_figures(loaded, Path(args.record))
    print("figures: " + ", ".join(str(p) for p in paths))
    return 0


def _command_bench(args: argparse.Namespace, prog: str) -> int:
    if args.name not in BENCHMARKS:
        fail(prog, f"unknown benchmark {args.name!r}; expected one of: {', '.join(BENCHMARKS)}")
    sys.argv = [f"benchmarks.{args.name}", *args.rest]
    runpy.run_module(f"benchmarks.{args.name}", run_name="__main__")
    return 0


def _command_study(args: argparse.Namespace, prog: str) -> int:
    """Hand over to ``python -m studies`` (the library does not depend on its studies)."""
    sys.argv = ["studies", args.name, *args.rest]
    try:
        runpy.run_module("studies", run_name="__main__")
    except SystemExit as done:
        return done.code if isinstance(done.code, int) else (0 if done.code is None else 1)
    return 0


def make_parser() -> OneLineParser:
    parser = OneLineParser(prog="ccopt", description="Manipulate unknown objects through contact.")
    parser.add_argument("--version", action="version", version=f"ccopt {__version__}")
    commands = parser.add_subparsers(dest="command", required=True, parser_class=OneLineParser)
    _run_parser(commands)
    plot = commands.add_parser("plot", help="(re)draw the figures of a run folder")
    plot.add_argument("record", help="run folder")
    study = commands.add_parser("study", help="run a scripted study (see studies/)")
    study.add_argument("name", help="feasibility, qp-region, gradients, ...")
    study.add_argument("rest", nargs=argparse.REMAINDER, help="arguments for the study")
    bench = commands.add_parser("bench", help="run a speed benchmark (see benchmarks/)")
    bench.add_argument("name", help=", ".join(BENCHMARKS))
    bench.add_argument("rest", nargs=argparse.REMAINDER, help="arguments for the benchmark")
    return parser


def main(argv: Sequence[str] | None = None) -> int:
    args = make_parser().parse_args(argv)
    prog = f"ccopt {args.command}"
    handlers = {"run": _command_run, "plot": _command_plot, "study": _command_study, "bench": _command_bench}
    return handlers[args.command](args, prog)


if __name__ == "__main__":
    sys.exit(main())
