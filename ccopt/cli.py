"""``ccopt``: run, plot and benchmark from the command line.

    ccopt run   --object paper-triangle --schedule paper --plant planar --seed 0 --out runs/tri
    ccopt plot  runs/tri
    ccopt study feasibility --workers 2
    ccopt bench qp_latency --quick

Degrees and millimetres at the command line (vertices in mm), SI inside. Bad input gets one line
naming the bad value and exit status 2, and leaves no run folder behind. A run needs friction at both
contacts (``--mu-hand`` and ``--mu-ground`` positive); objects have faces of 1 cm to 1 m
(:data:`ccopt.objects.MIN_EDGE`, :data:`~ccopt.objects.MAX_EDGE`) on which the hand fits.

``ccopt run`` writes into a new or empty ``--out``; ``--overwrite`` first clears a previous run's
files from it, and only those. Its exit status says how the run ended (:data:`EXIT_CODES`): 0
completed, 3 ended early (``contact_lost``, ``sensor_fault``, ``timeout``, each with its one-line
reason on stderr), 1 an error inside the run (its one-line message), 2 bad input, 130 interrupted.
Ctrl-C, SIGTERM and SIGHUP stop a run with its record closed (status ``interrupted``, no figures);
a second one ends the program at once and quietly. Interrupted while starting, a run leaves no
folder; interrupted while drawing, no figure cut short.
"""

from __future__ import annotations

import argparse
import runpy
import sys
from collections.abc import Sequence
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np

from ccopt import __version__, objects, record, validation
from ccopt.cliutil import INTERRUPTED, OneLineParser, fail, print_table, seed_value, stop_signals
from ccopt.objects import PlanarObject
from ccopt.plant.base import MIN_RATE, PlantParams
from ccopt.schedule import Schedule, load_schedule

if TYPE_CHECKING:
    from ccopt.closed_loop import LoopParams
    from ccopt.plant.sensors import Fault

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


def check_numbers(args: argparse.Namespace) -> None:
    """The numbers of ``ccopt run``, each named by its flag in a ``ValueError``: finite, masses and
    friction in range, rates from :data:`MIN_RATE` to the plant's own rate.

    A run needs friction at both contacts (μ > 0): without it the hand cannot push the object
    sideways and the object cannot pivot on the ground, and the friction estimate has nothing to
    measure.
    """

    if args.mass is not None:
        validation.positive("--mass", args.mass)
    if not validation.real("--added-mass", args.added_mass) >= 0.0:
        raise ValueError(f"--added-mass must be a non-negative number of kg, got {args.added_mass!r}")
    for flag, mu in (("--mu-hand", args.mu_hand), ("--mu-ground", args.mu_ground)):
        if not (validation.real(flag, mu) > 0.0):
            raise ValueError(f"{flag} must be positive (a run needs friction at both contacts), got {mu!r}")
    top = 1.0 / PlantParams().timestep
    for flag, rate in (("--estimator-hz", args.estimator_hz), ("--controller-hz", args.controller_hz)):
        if not MIN_RATE <= validation.real(flag, rate) <= top:
            raise ValueError(f"{flag} must be in [{MIN_RATE:g}, {top:g}] Hz (the plant's rate), got {rate!r}")


def fault_value(text: str) -> Fault:
    """argparse type: a sensor fault ``KIND[:VALUE][@START_S]`` (:func:`ccopt.plant.sensors.parse_fault`)."""
    from ccopt.plant.sensors import parse_fault

    try:
        return parse_fault(text)
    except ValueError as error:
        raise argparse.ArgumentTypeError(str(error)) from None


def build_object(args: argparse.Namespace) -> PlanarObject:
    """The object the user asked for (the controller is never told any of it)."""
    friction = {"mu_hand": args.mu_hand, "mu_ground": args.mu_ground}
    if args.vertices is not None:
        mass = args.mass if args.mass is not None else 0.3
        return objects.from_vertices(parse_vertices(args.vertices), mass + args.added_mass, **friction)
    return objects.make_object(args.object, mass=args.mass, added_mass=args.added_mass, **friction)


def _run_parser(commands: argparse._SubParsersAction) -> None:
    run = commands.add_parser(
        "run",
        help="manipulate an unknown object through a schedule",
        epilog="exit status: 0 completed, 3 ended early (contact_lost, sensor_fault, timeout), "
        "1 error in the run, 2 bad input, 130 interrupted (Ctrl-C, SIGTERM, SIGHUP)",
    )
    shape = run.add_mutually_exclusive_group()
    shape.add_argument("--object", default="paper-triangle", help="library object name")
    shape.add_argument("--vertices", help="convex polygon 'x,y;x,y;...' in mm, counter-clockwise")
    run.add_argument("--mass", type=float, help="object mass, kg (default: the object's)")
    run.add_argument("--added-mass", type=float, default=0.0, help="mass added to the object, kg (≥ 0)")
    run.add_argument("--mu-hand", type=float, default=0.5, help="hand/object friction coefficient (> 0)")
    run.add_argument("--mu-ground", type=float, default=0.8, help="object/ground friction coefficient (> 0)")
    run.add_argument("--plant", choices=("planar", "panda"), default="planar")
    run.add_argument("--schedule", default="paper", help="built-in name (paper, smoke) or a .yaml/.json file")
    run.add_argument("--seed", type=seed_value, default=0, help="seed of the sensor noise, in [0, 2**64)")
    run.add_argument("--estimator-hz", type=float, default=100.0, help=f"Hz, at least {MIN_RATE:g}")
    run.add_argument("--controller-hz", type=float, default=30.0, help=f"Hz, at least {MIN_RATE:g}")
    run.add_argument(
        "--fault",
        type=fault_value,
        action="append",
        default=[],
        metavar="KIND[:VALUE][@START_S]",
        help="a sensor fault from START_S on (repeatable): dropout:P, dead-ft, stuck-ft, scale-ft:K, "
        "bias-ft:N, spikes-ft:N, delay:S, dead-pose",
    )
    run.add_argument(
        "--max-sim-s",
        type=float,
        metavar="S",
        help="end the run (status timeout) after S s of simulated time (default: by the schedule)",
    )
    run.add_argument("--out", default="runs/latest", help="run folder, new or empty (created)")
    run.add_argument(
        "--overwrite", action="store_true", help="clear a previous run's files from --out first (only those)"
    )
    run.add_argument("--no-figures", action="store_true", help="skip the figures and the GIF")
    run.add_argument("--no-progress", action="store_true", help="no progress bar")


def run_inputs(args: argparse.Namespace) -> tuple[PlanarObject, Schedule, LoopParams]:
    """The object, schedule and loop parameters of ``ccopt run``, every argument checked (``ValueError``
    or ``TypeError`` naming it), the hand's start on the object included: nothing is created yet."""
    from ccopt.closed_loop import LoopParams, Supervision, start_config
    from ccopt.plant.sensors import SensorParams

    check_numbers(args)
    obj = build_object(args)
    schedule = load_schedule(args.schedule)
    try:
        supervision = Supervision(max_time=args.max_sim_s)
    except (ValueError, TypeError) as error:
        raise ValueError(f"--max-sim-s: {error}") from None
    params = LoopParams(
        plant=args.plant,
        estimator_hz=args.estimator_hz,
        controller_hz=args.controller_hz,
        sensor_params=SensorParams(faults=tuple(args.fault)),
        supervision=supervision,
    )
    start_config(obj, params)  # the hand must fit on the object's face
    return obj, schedule, params


def _command_run(args: argparse.Namespace, prog: str) -> int:
    from ccopt import experiment

    try:
        obj, schedule, params = run_inputs(args)
    except (ValueError, TypeError) as error:
        fail(prog, str(error))
    folder, created = Path(args.out), record.missing_folders(args.out)
    try:
        try:
            record.prepare_folder(folder, overwrite=args.overwrite)
        except ValueError as error:
            fail(prog, str(error))
        done = run_with_progress(experiment, obj, schedule, params, args, folder)
    except KeyboardInterrupt:
        if _discard(folder, created):
            sys.stderr.write(f"{prog}: interrupted before the run started; nothing was recorded\n")
        else:
            sys.stderr.write(f"{prog}: interrupted; the record is in {folder}\n")
        return INTERRUPTED
    except Exception as error:  # the CLI's boundary: one line, never a traceback
        return _run_failed(prog, folder, created, error)
    status, message = done.result.status, done.result.message
    print_summary(done.summary, folder)
    if status == "interrupted":
        sys.stderr.write(f"{prog}: interrupted; the record so far is in {folder} (ccopt plot draws it)\n")
        return INTERRUPTED
    if status != "completed":
        sys.stderr.write(f"{prog}: {status}: {message}\n")
    loaded = record.load_record(folder)
    if not args.no_figures and loaded.data:
        draw_figures(loaded, folder, prog)
    return EXIT_CODES[status]


def _run_failed(prog: str, folder: Path, created: list[Path], error: Exception) -> int:
    """``ccopt run`` when the experiment raised instead of returning. Before the run began: input the
    plant or the controller refused is bad input (one line, exit 2), anything else an error (one line,
    exit 1), and nothing is left behind. After: one line with how the run ended, exit 1, the record
    kept."""
    reason = f"{type(error).__name__}: {error}".splitlines()[0]
    if _discard(folder, created):
        if isinstance(error, ValueError | TypeError):
            fail(prog, str(error))
        sys.stderr.write(f"{prog}: error: {reason}\n")
        return EXIT_CODES["error"]
    try:
        meta = record.load_record(folder).meta
        ended = f"the run ended {meta.get('status')!r} ({meta.get('message')}), then "
    except ValueError:
        ended = ""
    sys.stderr.write(f"{prog}: error: {ended}{reason}; the record is in {folder}\n")
    return EXIT_CODES["error"]


def _discard(folder: Path, created: list[Path]) -> bool:
    """Remove what a run that never started left (and the folders made for it); whether it did."""
    if not record.discard_unstarted(folder):
        return False
    record.remove_empty_folders(created)
    return True


def draw_figures(loaded: record.Record, folder: Path, prog: str) -> bool:
    """Write the run's figures and GIF into ``folder`` and list them; whether that worked.

    All or none: if the drawing is interrupted or fails, the figures it had written are removed, so
    none is left cut short (a GIF is written frame by frame), and a failure is one line on stderr;
    figures it had not reached yet are left as they were. ``OSError`` if ``folder`` is not writable.
    """
    from ccopt import feasibility_map, plots

    before = _figure_files(folder)
    drawn = False
    try:
        paths = plots.write_figures(loaded, folder)
        maps = feasibility_map.write_figure(folder)
        paths += [maps] if maps is not None else []
        drawn = True
    except Exception as error:  # data a figure cannot show, a full disk: not to hide how the run ended
        reason = f"{type(error).__name__}: {error}".splitlines()[0]
        sys.stderr.write(f"{prog}: cannot draw the figures of {str(folder)!r}: {reason}\n")
    finally:
        if not drawn:
            for path, identity in _figure_files(folder).items():
                if before.get(path) != identity:
                    path.unlink(missing_ok=True)
    if drawn:
        print("figures: " + ", ".join(str(p) for p in paths))
    return drawn


def _figure_files(folder: Path) -> dict[Path, tuple[int, int, int]]:
    """The figures in ``folder`` and what tells one version of a file from another (inode, size,
    modification time)."""
    found = {}
    for path in (*folder.glob("*.png"), *folder.glob("*.gif")):
        try:
            stat = path.stat()
        except FileNotFoundError:
            continue
        found[path] = (stat.st_ino, stat.st_size, stat.st_mtime_ns)
    return found


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
    if summary["goals_total"]:
        rows.insert(2, ("goals reached", f"{summary['goals_reached']}/{summary['goals_total']}"))
    print_table(rows, ("metric", "value"))
    if summary["goals"]:
        print_table(goal_rows(summary["goals"]), GOAL_HEADER)
    print(f"record: {folder}")


GOAL_HEADER = ("#", "goal", "status", "true error (°, mm, mm)", "time (s)", "motions", "oracle")


def goal_rows(goals: list[dict]) -> list[tuple[str, ...]]:
    """One row per scored goal (:func:`ccopt.metrics.goal_scores`): its targets (degrees, mm; ``·``
    where free), status, the true error at its end, its time, the motions it used and whether the
    experimenter's oracle (the planner on the true statics) reaches it."""

    def given(targets: dict, units: tuple[str, ...]) -> str:
        parts = [f"{name} {value:g}{unit}" for (name, value), unit in zip(targets.items(), units, strict=True)
                 if value is not None]
        return ", ".join(parts)

    def error(values: dict) -> str:
        return ", ".join("·" if value is None else f"{value:+.1f}" for value in values.values())

    rows = []
    for goal in goals:
        targets = {"θ": goal["targets"]["theta_deg"], "s_h": goal["targets"]["s_h_mm"],
                   "s_g": goal["targets"]["s_g_mm"]}
        oracle = goal.get("oracle")
        verdict = "n/a" if oracle is None else ("reachable" if oracle["reachable"] else "unreachable")
        off = goal["status"] == "reached" and not goal["within_tolerance"]
        rows.append(
            (
                str(goal["index"]),
                given(targets, ("°", " mm", " mm")),
                goal["status"] + (" (truth off)" if off else ""),
                error(goal["true_error"]),
                f"{goal['time_s']:.1f}",
                str(goal["motions"]),
                verdict,
            )
        )
    return rows


def _command_plot(args: argparse.Namespace, prog: str) -> int:
    try:
        loaded = record.load_record(args.record)
    except ValueError as error:
        fail(prog, str(error))
    if not loaded.data:
        fail(prog, f"{args.record!r} holds no sample of its run (meta.json's run_id): nothing to draw")
    return 0 if draw_figures(loaded, Path(args.record), prog) else 1


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
    with stop_signals(prog):
        try:
            return handlers[args.command](args, prog)
        except KeyboardInterrupt:
            sys.stderr.write(f"{prog}: interrupted\n")
            return INTERRUPTED


if __name__ == "__main__":
    sys.exit(main())
