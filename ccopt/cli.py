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
completed, 3 ended early (``contact_lost``, ``sensor_fault``, ``timeout``) or not done (motion steps
or goals not reached, :func:`not_done`), each with its one-line reason on stderr, 1 an error inside
the run (its one-line message), 2 bad input, 130 interrupted.
Ctrl-C, SIGTERM and SIGHUP stop a run with its record closed (status ``interrupted``, no figures);
a second one ends the program at once and quietly. Interrupted while starting, a run leaves no
folder; interrupted while drawing, no figure cut short.
"""

from __future__ import annotations

import argparse
import math
import runpy
import sys
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np

# ``ccopt plot`` imports only what drawing a run needs: the settings (ccopt.config) and the object
# library are imported by the commands that use them.
from ccopt import __version__, record
from ccopt.cliutil import (
    OneLineParser,
    fail,
    fail_lines,
    print_scripts,
    print_table,
    scripts,
    seed_value,
)
from ccopt.plant.base import MIN_RATE
from ccopt.schedule import BUILTIN
from ccopt.stops import INTERRUPTED, stop_signals, stops_held

if TYPE_CHECKING:
    from ccopt.plant.sensors import Fault


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


def fault_value(text: str) -> Fault:
    """argparse type: a sensor fault ``KIND[:VALUE][@START_S]`` (:func:`ccopt.plant.sensors.parse_fault`)."""
    from ccopt.plant.sensors import parse_fault

    try:
        return parse_fault(text)
    except ValueError as error:
        raise argparse.ArgumentTypeError(str(error)) from None


def numbers(count: int) -> Callable[[str], tuple[float, ...]]:
    """argparse type: ``count`` comma-separated numbers."""

    def parse(text: str) -> tuple[float, ...]:
        try:
            values = tuple(float(v) for v in text.split(","))
        except ValueError:
            values = ()
        if len(values) != count:
            raise argparse.ArgumentTypeError(f"{text!r} is not {count} comma-separated numbers")
        return values

    return parse


@dataclass(frozen=True)
class Flag:
    """A settings flag of ``ccopt run``: where its value goes in the settings (:mod:`ccopt.config`) and
    the factor from the flag's unit (mm, deg) to SI."""

    name: str
    path: tuple[str, ...]
    help: str
    metavar: str | None = None
    factor: float = 1.0
    type: Callable[[str], object] = float


MM, DEG = 1e-3, math.pi / 180.0
RUN_FLAGS = (
    Flag("--mass", ("object", "mass"), "object mass, kg (default: the object's)", "KG"),
    Flag("--added-mass", ("object", "added_mass"), "mass added to the object, kg (≥ 0)", "KG"),
    Flag("--mu-hand", ("object", "mu_hand"), "hand/object friction coefficient (> 0; default: 0.5)", "MU"),
    Flag(
        "--mu-ground", ("object", "mu_ground"), "object/ground friction coefficient (> 0; default: 0.8)", "MU"
    ),
    Flag("--estimator-hz", ("params", "estimator_hz"), f"Hz, at least {MIN_RATE:g} (default: 100)", "HZ"),
    Flag("--controller-hz", ("params", "controller_hz"), f"Hz, at least {MIN_RATE:g} (default: 30)", "HZ"),
    Flag(
        "--max-sim-s",
        ("params", "max_sim_s"),
        "end the run (status timeout) after S s of simulated time (default: by the schedule)",
        "S",
    ),
    Flag("--l-hand", ("params", "hand", "half_length"), "hand half-length l_h, mm (default: 30)", "MM", MM),
    Flag(
        "--stiffness",
        ("params", "hand", "stiffness"),
        "hand impedance k_x,k_y,k_θ: N/m, N/m, N·m/rad (default: 2000,2000,60)",
        "KX,KY,KTHETA",
        type=numbers(3),
    ),
    Flag(
        "--force-limits",
        ("params", "hand", "force_limits"),
        "the hand's smallest and largest normal force, N (default: 3,25)",
        "FMIN,FMAX",
        type=numbers(2),
    ),
    Flag(
        "--theta",
        ("params", "start", "theta_o"),
        "start tilt θ_o of the hand face, deg (default: 17.2)",
        "DEG",
        DEG,
    ),
    Flag(
        "--face", ("params", "start", "hand_face"), "object face the hand starts on (default: 0)", "K", 1, int
    ),
    Flag(
        "--s-hand",
        ("params", "start", "s_h"),
        "start s_h, mm (default: as close over the ground contact as the hand fits)",
        "MM",
        MM,
    ),
    Flag("--noise-force", ("params", "sensors", "sigma_force"), "F/T force noise, N (default: 0.3)", "N"),
    Flag(
        "--noise-torque",
        ("params", "sensors", "sigma_torque"),
        "F/T torque noise, N·m (default: 0.005)",
        "NM",
    ),
    Flag(
        "--noise-position",
        ("params", "sensors", "sigma_position"),
        "hand position noise, mm (default: 0.2)",
        "MM",
        MM,
    ),
    Flag(
        "--noise-angle",
        ("params", "sensors", "sigma_angle"),
        "hand angle noise, deg (default: 0.1)",
        "DEG",
        DEG,
    ),
    Flag(
        "--convergence-rate",
        ("params", "controller", "convergence_rate"),
        "controller: rate at which the commanded coordinate's error is corrected, 1/s (default: 10.7)",
        "PER_S",
    ),
    Flag(
        "--force-rate",
        ("params", "controller", "force_rate"),
        "controller: rate at which the normal-force error is corrected, 1/s (default: 6.7)",
        "PER_S",
    ),
    Flag(
        "--normal-force",
        ("params", "controller", "normal_force"),
        "controller: target normal force, N, inside --force-limits (default: 10)",
        "N",
    ),
)
"""The settings flags of ``ccopt run`` (besides ``--object``, ``--vertices``, ``--plant``, ``--schedule``,
``--seed`` and ``--fault``)."""


def _run_parser(commands: argparse._SubParsersAction) -> None:
    run = commands.add_parser(
        "run",
        help="manipulate an unknown object through a schedule",
        description="Manipulate an unknown object through a schedule. Settings come from the defaults, "
        "then --config FILE, then the flags given (degrees and mm at the command line, SI in files).",
        epilog="exit status: 0 completed, 3 ended early (contact_lost, sensor_fault, timeout) or not done "
        "(motion steps or goals not reached), 1 error in the run, 2 bad input, 130 interrupted (Ctrl-C, "
        "SIGTERM, SIGHUP)",
    )
    run.add_argument(
        "--config",
        metavar="FILE",
        help="settings file (.yaml/.json, SI; see ccopt/config.py) or a run's meta.json, which repeats it",
    )
    shape = run.add_mutually_exclusive_group()
    shape.add_argument(
        "--object", help="library object name (ccopt objects lists them; default: paper-triangle)"
    )
    shape.add_argument("--vertices", help="convex polygon 'x,y;x,y;...' in mm, counter-clockwise")
    run.add_argument("--plant", choices=("planar", "panda"), help="simulated robot (default: planar)")
    builtin = ", ".join(BUILTIN)
    run.add_argument("--schedule", help=f"built-in name ({builtin}) or a .yaml/.json file (default: paper)")
    run.add_argument("--seed", type=seed_value, help="seed of the sensor noise, in [0, 2**64) (default: 0)")
    for flag in RUN_FLAGS:
        run.add_argument(flag.name, type=flag.type, metavar=flag.metavar, help=flag.help)
    run.add_argument(
        "--fault",
        type=fault_value,
        action="append",
        default=[],
        metavar="KIND[:VALUE][@START_S]",
        help="a sensor fault from START_S on (repeatable): dropout:P, dead-ft, stuck-ft, scale-ft:K, "
        "bias-ft:N, spikes-ft:N, delay:S, dead-pose",
    )
    run.add_argument("--out", default="runs/latest", help="run folder, new or empty (created)")
    run.add_argument(
        "--overwrite", action="store_true", help="clear a previous run's files from --out first (only those)"
    )
    run.add_argument(
        "--figures",
        action=argparse.BooleanOptionalAction,
        default=True,
        help="draw the figures and the GIF after the run (default: yes)",
    )
    run.add_argument("--no-progress", action="store_true", help="no progress bar")


def run_settings(args: argparse.Namespace) -> tuple[dict[str, object], dict[tuple[str, ...], str]]:
    """The settings mapping of ``ccopt run`` (:mod:`ccopt.config`, SI): the ``--config`` file's, with the
    flags given put in; and what to call each value a flag set in a message (the flag and its text).
    ``--object`` and ``--vertices`` replace the file's object, ``--mass`` and the others change it."""
    from ccopt import config

    settings = config.read_file(args.config) if args.config is not None else {}
    labels: dict[tuple[str, ...], str] = {}
    given: dict[tuple[str, ...], object] = {}
    if args.object is not None:
        settings["object"], labels[("object",)] = {"name": args.object}, f"--object {args.object}"
    if args.vertices is not None:
        settings["object"] = {"vertices": parse_vertices(args.vertices).tolist()}
        labels[("object",)] = f"--vertices {args.vertices}"
    if isinstance(settings.get("object"), str):
        settings["object"] = {"name": settings["object"]}
    for key, value in (("schedule", args.schedule), ("seed", args.seed)):
        if value is not None:
            given[(key,)], labels[(key,)] = value, f"--{key}"
    if args.plant is not None:
        given[("params", "plant")] = args.plant
    for flag in RUN_FLAGS:
        value = getattr(args, flag.name[2:].replace("-", "_"))
        if value is not None:
            shown = ",".join(f"{v:g}" for v in value) if isinstance(value, tuple) else f"{value:g}"
            scaled = (
                tuple(v * flag.factor for v in value) if isinstance(value, tuple) else value * flag.factor
            )
            given[flag.path], labels[flag.path] = scaled, f"{flag.name} {shown}"
    if args.s_hand is not None:
        given[("params", "centre_hand")] = False
    if args.fault:
        given[("params", "sensors", "faults")] = [str(fault) for fault in args.fault]
        labels[("params", "sensors", "faults")] = "--fault"
    overrides: dict[str, object] = {}
    for path, value in given.items():
        node = overrides
        for key in path[:-1]:
            node = node.setdefault(key, {})
        node[path[-1]] = value
    return config.merge(settings, overrides), labels


def _command_run(args: argparse.Namespace, prog: str) -> int:
    with stops_held():  # an interrupted C extension's import fails with an ImportError
        from ccopt import config, experiment

    try:
        settings, labels = run_settings(args)
        chosen = config.build(settings, labels)
    except config.ConfigError as error:
        fail_lines(prog, error.lines)
    except ValueError as error:
        fail(prog, str(error))
    obj, schedule, params, seed = chosen.obj, chosen.schedule, chosen.params, chosen.seed
    folder, created = Path(args.out), record.missing_folders(args.out)
    try:
        try:
            record.prepare_folder(args.out, overwrite=args.overwrite)  # named as given
        except ValueError as error:
            fail(prog, str(error))
        done = run_with_progress(experiment, obj, schedule, params, seed, args, folder)
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
    undone = not_done(done.result.steps, done.summary) if status == "completed" else ""
    if status != "completed":
        sys.stderr.write(f"{prog}: {status}: {message}\n")
    elif undone:
        sys.stderr.write(f"{prog}: not done: {undone}\n")
    loaded = record.load_record(folder)
    if args.figures and loaded.data:
        draw_figures(loaded, folder, prog)
    return EXIT_NOT_DONE if undone else EXIT_CODES[status]


def not_done(steps: Sequence, summary: dict) -> str:
    """What a run that ran to its end left undone, by the loop's own verdicts (not the truth): the
    schedule's motion steps not reached (exploration probes aside) and the goals neither reached nor
    found unreachable, in one line; "" if nothing."""

    def listed(names: list[str]) -> str:
        return ", ".join(names[:3]) + (", …" if len(names) > 3 else "")

    parts = []
    missed = [step for step in steps if step.goal is None and not step.explore and not step.reached]
    if missed:
        names = [f"step {step.index + 1} {step.status}" for step in missed]
        parts.append(f"{len(missed)} of {summary['steps_total']} motion steps not reached ({listed(names)})")
    goals = [goal for goal in summary["goals"] if goal["status"] not in ("reached", "unreachable")]
    if goals:
        names = [f"#{goal['index']} {goal['status']}" for goal in goals]
        parts.append(f"{len(goals)} of {summary['goals_total']} goals not reached ({listed(names)})")
    return "; ".join(parts)


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

    The figures are the last work of ``ccopt run`` and ``ccopt plot``: what the process holds now is
    frozen out of the garbage collector's reach (``gc.freeze``), so that neither the worker forked to
    draw half the figures (:func:`ccopt.forked.side_by_side`) nor the interpreter's last collections
    at exit traverse it again (their copies of its pages, and 0.1–0.15 s at exit after a ``paper``
    run).
    """
    import gc

    with stops_held():  # an interrupted C extension's import fails with an ImportError
        from ccopt import plots

    gc.freeze()
    before = _figure_files(folder)
    drawn = False
    try:
        paths = plots.write_figures(loaded, folder)  # the GIF and the maps drawn in a second process
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


def run_with_progress(experiment, obj, schedule, params, seed, args, folder):
    """Run the experiment with a tqdm bar over the schedule's steps (unless ``--no-progress``); the
    oracle's warnings about impossible steps go to stderr first."""
    with stops_held():  # an import stopped inside code it runs from a string ends python -m by SIGINT
        from tqdm import tqdm

    bar = tqdm(total=len(schedule.steps), unit="step", disable=args.no_progress, leave=False, mininterval=0.5)
    with bar:

        def on_tick(sim_time: float, index: int, total: int) -> None:
            bar.set_postfix(sim=f"{sim_time:.1f}s", refresh=False)
            bar.update(min(index, total) - bar.n)  # redraws at most every mininterval

        def warn(line: str) -> None:
            print(f"warning: {line}", file=sys.stderr)

        return experiment.run_experiment(
            obj, schedule, params, seed=seed, folder=folder, on_tick=on_tick, warn=warn
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
EXIT_NOT_DONE = 3
"""Exit status of a run that ran to its end without doing all it was asked (:func:`not_done`)."""


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
        ("probes reached (not scored above)", f"{summary['probes']['reached']}/{summary['probes']['n']}"),
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


def _loaded(prog: str, folder: str) -> record.Record:
    """The run in ``folder``, or one line and exit 2 if it is not a run folder or holds no sample."""
    try:
        loaded = record.load_record(folder)
    except ValueError as error:
        fail(prog, str(error))
    if not loaded.data:
        fail(prog, f"{folder!r} holds no sample of its run (meta.json's run_id): nothing to show")
    return loaded


def _command_plot(args: argparse.Namespace, prog: str) -> int:
    return 0 if draw_figures(_loaded(prog, args.record), Path(args.record), prog) else 1


def _command_objects(args: argparse.Namespace, prog: str) -> int:
    """List the object library: faces, face lengths, size, mass and friction."""
    from ccopt import objects

    rows = []
    for name in objects.OBJECT_NAMES:
        obj = objects.make_object(name)
        lengths = [obj.face_length(k) * 1e3 for k in range(obj.n_faces)]
        size = np.ptp(obj.vertices, axis=0) * 1e3
        rows.append(
            (
                name,
                str(obj.n_faces),
                f"{min(lengths):.0f}–{max(lengths):.0f}"
                if max(lengths) - min(lengths) > 0.5
                else f"{lengths[0]:.0f}",
                f"{size[0]:.0f} × {size[1]:.0f}",
                f"{obj.mass:.3f}",
                f"{obj.mu_hand:g}",
                f"{obj.mu_ground:g}",
            )
        )
    print_table(
        rows, ("object", "faces", "face (mm)", "width × height (mm)", "mass (kg)", "μ_hand", "μ_ground")
    )
    print(
        "ccopt run --object NAME [--mass KG] [--added-mass KG] [--mu-hand MU] [--mu-ground MU]; "
        "any convex polygon: --vertices 'x,y;x,y;...' (mm)"
    )
    return 0


def _command_bench(args: argparse.Namespace, prog: str) -> int:
    benchmarks = scripts("benchmarks")
    if args.name is None:
        print_scripts("benchmarks:", benchmarks, "run one with 'ccopt bench NAME [--quick] [--json PATH]'")
        return 0
    if args.name not in benchmarks:
        fail(prog, f"unknown benchmark {args.name!r}; expected one of: {', '.join(benchmarks)}")
    sys.argv = [f"ccopt bench {args.name}", *args.rest]
    runpy.run_module(f"benchmarks.{args.name}", run_name="__main__")
    return 0


def _command_study(args: argparse.Namespace, prog: str) -> int:
    """Hand over to ``studies.__main__`` (the library does not depend on its studies)."""
    sys.argv = ["ccopt study", *([args.name] if args.name else []), *args.rest]
    try:
        runpy.run_module("studies", run_name="__main__")
    except SystemExit as done:
        return done.code if isinstance(done.code, int) else (0 if done.code is None else 1)
    return 0


def _command_view(args: argparse.Namespace, prog: str) -> int:
    """Log a run to Rerun: saved to ``--save`` or shown in a viewer it starts."""
    from ccopt import view

    loaded = _loaded(prog, args.record)
    try:
        saved = view.log_run(loaded, save=args.save)
    except view.RerunMissing as error:
        fail(prog, str(error))
    except OSError as error:
        fail(prog, f"cannot write {args.save!r}: {error.strerror or error}")
    if saved is not None:
        print(f"saved {saved} (open it with: rerun {saved})")
    return 0


COMMANDS = {
    "run": (_command_run, "manipulate an unknown object through a schedule"),
    "plot": (_command_plot, "(re)draw the figures of a run folder"),
    "view": (_command_view, "look into a run with Rerun (scene, estimates vs truth, QP) or save it as .rrd"),
    "objects": (_command_objects, "list the objects of the library"),
    "study": (_command_study, "run a scripted study; without a name, list them"),
    "bench": (_command_bench, "run a speed benchmark; without a name, list them"),
}
"""Subcommand → (handler, one line of help)."""


def make_parser() -> OneLineParser:
    parser = OneLineParser(
        prog="ccopt",
        description="Manipulate unknown objects through contact: estimate the contact configuration from "
        "the wrist wrench and the hand pose, and regulate it with a QP (Doshi, Taylor & Rodriguez).",
        epilog="start with: ccopt run --schedule smoke --out runs/first; then ccopt plot runs/first",
    )
    parser.add_argument("--version", action="version", version=f"ccopt {__version__}")
    commands = parser.add_subparsers(dest="command", parser_class=OneLineParser, metavar="COMMAND")
    _run_parser(commands)
    plot = commands.add_parser("plot", help=COMMANDS["plot"][1])
    plot.add_argument("record", help="run folder")
    view = commands.add_parser("view", help=COMMANDS["view"][1])
    view.add_argument("record", help="run folder")
    view.add_argument(
        "--save", metavar="FILE.rrd", help="write the recording here instead of opening a viewer"
    )
    commands.add_parser("objects", help=COMMANDS["objects"][1])
    study = commands.add_parser("study", help=COMMANDS["study"][1])
    study.add_argument("name", nargs="?", help="the study (ccopt study lists them)")
    study.add_argument("rest", nargs=argparse.REMAINDER, help="arguments for the study")
    bench = commands.add_parser("bench", help=COMMANDS["bench"][1])
    bench.add_argument("name", nargs="?", help="the benchmark (ccopt bench lists them)")
    bench.add_argument("rest", nargs=argparse.REMAINDER, help="arguments for the benchmark")
    return parser


def main(argv: Sequence[str] | None = None) -> int:
    parser = make_parser()
    args = parser.parse_args(argv)
    if args.command is None:
        parser.print_help()
        return 0
    prog = f"ccopt {args.command}"
    with stop_signals(prog):
        try:
            return COMMANDS[args.command][0](args, prog)
        except KeyboardInterrupt:
            sys.stderr.write(f"{prog}: interrupted\n")
            return INTERRUPTED


if __name__ == "__main__":
    sys.exit(main())
