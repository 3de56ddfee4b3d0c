"""Sensor faults in closed loop: does every run end safely, in time, with its record kept?

    ccopt study faults [--quick] [--faults none,dead-ft,scale-ft:3] [--objects paper-square]
                             [--start 1.0] [--schedule smoke] [--plant planar] [--workers 2]

Each trial runs one sensor fault (:data:`FAULTS`, ``KIND[:VALUE]``, see
:func:`ccopt.plant.sensors.parse_fault`) from ``--start`` s of simulated time on, or none (``none``:
the same run without a fault, measured from the same time, the baseline), on one object
(:data:`OBJECTS`), through the schedule (``smoke`` by default), recorded to ``<out>/trials/<k>/``;
every trial has its own seed (``--seed``). ``--quick`` keeps the first object only.

Measured from the record, against the simulator's truth, after the fault's start ``t_f``:

``status``, ``message``
    how the run ended (:data:`ccopt.closed_loop.RUN_STATUSES`) and why;
``ended_after_s``
    simulated time from ``t_f`` to the end of the run: for ``sensor_fault`` the time the loop took to
    detect the fault (it stops at once);
``peak_force_n``
    the largest true normal force (``true_hand_wrench``) from ``t_f`` on;
``over_limit_s``
    the longest time the true normal force stayed above :data:`OVER_LIMIT` × the hand's largest
    normal force (``Hand.force_limits[1]``) from ``t_f`` on (sample period × samples in a row);
``kept_s``, ``kept_all``
    the data kept: the time of the record's last sample (s), and whether the record holds the run to
    its end (its last sample within one record period of the run's last moment);
``loads``, ``plots``
    whether the folder loads (:func:`ccopt.record.load_record`, at least one sample) and draws (the
    still figures of :data:`ccopt.plots.FIGURES`, written into the folder; the GIF is left out, it
    reads the same data and takes seconds).

Issue 12's acceptance, checked per trial and counted in the summary: ``over_limit_s`` at most
:data:`MAX_OVER_LIMIT_S`; the run completed, or ended with a named status within :data:`MAX_END_S` of
``t_f``; the record holds the run to its end; the folder loads and plots. Outputs in ``<out>``:
``results.json``/``results.csv`` and the table printed at the end.
"""

from __future__ import annotations

import argparse
import sys
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from ccopt import plots, record
from ccopt.cliutil import fail, print_table
from ccopt.clock import TIME_TOLERANCE
from ccopt.closed_loop import LoopParams
from ccopt.experiment import run_experiment
from ccopt.objects import make_object
from ccopt.plant.sensors import SensorParams, parse_fault
from ccopt.schedule import load_schedule
from studies import runner
from studies.runner import cell

NO_FAULT = "none"
"""The baseline: the run without a fault."""
FAULTS = (
    NO_FAULT,
    "dropout:0.3",
    "dropout:1",
    "dead-ft",
    "stuck-ft",
    "scale-ft:0.1",
    "scale-ft:3",
    "bias-ft:5",
    "spikes-ft:20",
    "delay:0.1",
    "dead-pose",
)
"""The baseline, then every kind of :data:`ccopt.plant.sensors.FAULT_KINDS`: dropouts some and all, the
scale down and up."""
OBJECTS = ("paper-triangle", "paper-square", "paper-pentagon")
START = 1.0
"""When the faults start by default, s of simulated time (mid-way through the first pivot of ``smoke``)."""
OVER_LIMIT = 1.2
"""A run is over the force limit above this times the hand's largest normal force."""
MAX_OVER_LIMIT_S = 0.05
"""Longest time over the limit the acceptance allows, s."""
MAX_END_S = 2.0
"""A run that does not complete must end within this long of the fault's start, s."""


@dataclass(frozen=True)
class FaultTrial:
    """One fault (``KIND[:VALUE]`` or :data:`NO_FAULT`) from ``start`` (s) on one library object,
    recorded to ``folder``."""

    index: int
    fault: str
    start: float
    object: str
    seed: int
    schedule: str
    plant: str
    folder: str


# --- the trial ------------------------------------------------------------------------------------


def fault_trial(spec: FaultTrial) -> dict:
    """Run one fault, then measure its record (see the module docstring)."""
    faults = () if spec.fault == NO_FAULT else (parse_fault(f"{spec.fault}@{spec.start!r}"),)
    params = LoopParams(plant=spec.plant, sensor_params=SensorParams(faults=faults))
    folder = record.prepare_folder(spec.folder, overwrite=True)
    done = run_experiment(make_object(spec.object), load_schedule(spec.schedule), params, spec.seed, folder)
    runner.finished(done.result)
    status, ended_after = done.result.status, done.result.sim_time - spec.start
    loaded, kept_checks = kept(folder)
    over_limit = OVER_LIMIT * params.hand.force_limits[1]
    forces = forces_after(loaded, spec.start, over_limit) if loaded is not None else {}
    over_s = forces.get("over_limit_s")
    kept_s = float(loaded["time"][-1]) if loaded is not None else None
    record_period = params.record_stride / params.estimator_hz
    return {
        "status": status,
        "message": done.result.message,
        "ended_after_s": ended_after,
        "peak_force_n": forces.get("peak_force_n"),
        "over_limit_s": over_s,
        "kept_s": kept_s,
        "kept_all": kept_s is not None and kept_s >= done.result.sim_time - record_period - TIME_TOLERANCE,
        **kept_checks,
        "ended_in_time": status == "completed" or ended_after <= MAX_END_S + TIME_TOLERANCE,
        "force_ok": over_s is not None and over_s <= MAX_OVER_LIMIT_S + TIME_TOLERANCE,
    }


def forces_after(loaded: record.Record, start: float, over_limit: float) -> dict:
    """``peak_force_n`` and ``over_limit_s`` (the longest time above ``over_limit``, N) of the true
    normal force from ``start`` on; empty without samples then."""
    time, normal = loaded["time"], loaded["true_hand_wrench"][:, 0]
    after = time >= start
    if not after.any():
        return {}
    period = float(np.median(np.diff(time)))
    return {
        "peak_force_n": float(normal[after].max()),
        "over_limit_s": longest_run(after & (normal > over_limit)) * period,
    }


def longest_run(flags: np.ndarray) -> int:
    """The most ``True`` in a row in ``flags``."""
    edges = np.flatnonzero(np.diff(np.concatenate(([0], np.asarray(flags, dtype=np.int8), [0]))))
    return int((edges[1::2] - edges[::2]).max()) if edges.size else 0


def kept(folder: Path) -> tuple[record.Record | None, dict]:
    """The run's record if its folder loads (with samples), and whether it loads and its still
    figures draw into it, and why not."""
    try:
        loaded = record.load_record(folder)
    except ValueError as error:
        return None, {"loads": False, "plots": False, "kept_error": runner.error_line(error)}
    if not loaded.data:
        return None, {"loads": False, "plots": False, "kept_error": "no samples"}
    try:
        for name, draw in plots.FIGURES.items():
            draw(loaded).savefig(folder / name, dpi=80)
    except Exception as error:  # whatever stops a figure is what this column measures
        return loaded, {"loads": True, "plots": False, "kept_error": runner.error_line(error)}
    return loaded, {"loads": True, "plots": True, "kept_error": None}


def make_specs(
    faults: Sequence[str],
    start: float,
    objects: Sequence[str],
    seed: int,
    schedule: str,
    plant: str,
    out: Path,
) -> list[FaultTrial]:
    """Every fault on every object (faults outer), each with its own seed and record folder."""
    pairs = [(fault, name) for fault in faults for name in objects]
    seeds = runner.trial_seeds(seed, len(pairs))
    return [
        FaultTrial(k, fault, start, name, seeds[k], schedule, plant, str(out / "trials" / str(k)))
        for k, (fault, name) in enumerate(pairs)
    ]


# --- output ---------------------------------------------------------------------------------------

CHECKS = ("force_ok", "ended_in_time", "kept_all", "loads", "plots")
"""The acceptance checks of a trial (see the module docstring)."""


def summarise(specs: Sequence[FaultTrial], results: Sequence[dict]) -> dict:
    """How many trials pass each check, and which do not."""
    ran = [(spec, r) for spec, r in zip(specs, results, strict=True) if "error" not in r]
    return {
        "trials": len(results),
        "acceptance": {
            "over_limit": OVER_LIMIT,
            "max_over_limit_s": MAX_OVER_LIMIT_S,
            "max_end_s": MAX_END_S,
        },
        "passed": {check: sum(bool(r.get(check)) for _, r in ran) for check in CHECKS},
        "failed": [
            {"index": spec.index, "fault": spec.fault, "object": spec.object, "checks": missed}
            for spec, r in ran
            if (missed := [check for check in CHECKS if not r.get(check)])
        ],
        "errors": dict(runner.failures(results)),
    }


def table_rows(specs: Sequence[FaultTrial], results: Sequence[dict]) -> list[tuple[str, ...]]:
    rows = []
    for spec, r in zip(specs, results, strict=True):
        if "error" in r:
            rows.append((spec.fault, spec.object, "ERROR", "", "", "", "", "", r["error"]))
            continue
        over = r["over_limit_s"]
        rows.append(
            (
                spec.fault,
                spec.object,
                r["status"],
                cell(r["ended_after_s"]),
                cell(r["peak_force_n"], 1),
                "n/a" if over is None else f"{1e3 * over:.0f}",
                kept_cell(r),
                f"{'yes' if r['loads'] else 'NO'}/{'yes' if r['plots'] else 'NO'}",
                ", ".join(check for check in CHECKS if not r.get(check)) or "-",
            )
        )
    return rows


def kept_cell(result: dict) -> str:
    """The data kept: the record's last sample (s), and ``all`` if that is the run's end (``n/a`` in a
    trial measured before the study measured it)."""
    if result.get("kept_s") is None:
        return "n/a"
    return f"{result['kept_s']:.2f}{' all' if result['kept_all'] else ' CUT'}"


def acceptance_rows(summary: dict) -> list[tuple[str, str]]:
    """How many trials pass each check of issue 12's acceptance."""
    what = {
        "force_ok": f"true f_n over {OVER_LIMIT:g}× its limit for ≤ {1e3 * MAX_OVER_LIMIT_S:.0f} ms from t_f",
        "ended_in_time": f"completed, or ended within {MAX_END_S:g} s of t_f",
        "kept_all": "the record holds the run to its end",
        "loads": "the folder loads",
        "plots": "the folder plots (still figures)",
    }
    return [(what[check], f"{summary['passed'][check]}/{summary['trials']}") for check in CHECKS]


HEADER = (
    "fault",
    "object",
    "status",
    "ended after (s)",
    "peak f_n (N)",
    f"over {OVER_LIMIT:g}×limit (ms)",
    "data kept to (s)",
    "loads/plots",
    "fails",
)


# --- command line ---------------------------------------------------------------------------------


def names(value: str) -> list[str]:
    """argparse type: a comma-separated list of names."""
    items = [item.strip() for item in value.split(",")]
    if not all(items):
        raise argparse.ArgumentTypeError(f"{value!r} is not a comma-separated list of names")
    return items


def make_parser() -> argparse.ArgumentParser:
    parser = runner.study_parser("faults", __doc__.split("\n")[0], "the first object only")
    runner.closed_loop_arguments(parser, schedule="smoke")
    lists = (
        ("--faults", FAULTS, f"faults KIND[:VALUE] or {NO_FAULT} (no fault)"),
        ("--objects", OBJECTS, "library objects"),
    )
    for flag, default, what in lists:
        help_text = f"comma-separated {what} (default: {','.join(default)})"
        parser.add_argument(flag, type=names, default=list(default), metavar="A,B,...", help=help_text)
    parser.add_argument(
        "--start", type=float, default=START, metavar="S", help=f"when faults start, s (default: {START:g})"
    )
    return parser


def checked_faults(prog: str, faults: Sequence[str], start: float) -> list[str]:
    """Each fault as :func:`~ccopt.plant.sensors.parse_fault` writes it (without its start), checked
    with ``start``; :data:`NO_FAULT` as it is; one line and exit 2 for a bad one."""
    checked = []
    for text in faults:
        if "@" in text:
            fail(prog, f"--faults {text!r}: give the faults' start with --start, not @")
        try:
            fault = None if text == NO_FAULT else parse_fault(f"{text}@{start!r}")
        except ValueError as error:
            fail(prog, str(error))
        checked.append(NO_FAULT if fault is None else str(fault).partition("@")[0])
    return checked


def main(argv: Sequence[str] | None = None) -> int:
    parser = make_parser()
    args = parser.parse_args(argv)
    schedule = runner.checked_schedule(parser.prog, args)
    faults = checked_faults(parser.prog, args.faults, args.start)
    objects = args.objects[:1] if args.quick else args.objects
    for name in objects:
        try:
            make_object(name)
        except ValueError as error:
            fail(parser.prog, str(error))
    options = runner.RunOptions.from_args(args)
    specs = make_specs(faults, args.start, objects, args.seed, schedule, args.plant, options.out)
    results = runner.run_study(parser.prog, fault_trial, specs, options)
    summary = summarise(specs, results)
    runner.write_results(options.out, specs, results, summary)
    print_table(table_rows(specs, results), HEADER)
    print_table(acceptance_rows(summary), (f"acceptance (faults from t_f = {args.start:g} s)", "trials"))
    print(f"results in {options.out}")
    return 0 if not runner.failures(results) else 1


if __name__ == "__main__":
    sys.exit(main())
