"""Where a closed-loop tick spends its time at 1 kHz, and how fast whole runs go.

    python -m benchmarks.loop_tick [--quick] [--json PATH] [--seed N] [--plant {planar,panda}]

The paper triangle runs the ``smoke`` schedule on the planar plant (or the ``--plant`` given) with
the estimator and the controller at 1 kHz, recorded to a temporary folder as ``ccopt run`` records.
In one instrumented run every part of the tick is timed where the loop calls it (the plant's steps,
the sensors, the estimator, the statics target, the controller — QP instance, solve and checks —,
ground truth and the record, the sensor-health check; the rest is the loop's own bookkeeping). The
controller's ticks of that run are then replayed twice on the same inputs: with the code-generated
QP, and with the paper authors' solver path (mcubelab/pbal,
``src/Modelling/modular_barrier_controller.py``: cvxopt's ``solvers.qp`` with ``maxiters = 10`` and
tolerances of 1e-6, its answer taken whatever its status). Uninstrumented runs give the real-time
factors (simulated over wall time of the loop, one core): planar at 1 kHz, planar at the paper's
rates (100 Hz estimator, 30 Hz controller) and the Panda at 1 kHz; each is the median of
``--repeats`` runs (best in brackets: the machine may be shared).
"""

from __future__ import annotations

import tempfile
import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from pathlib import Path
from types import SimpleNamespace

import numpy as np

from benchmarks.qp_latency import cvxopt_solver
from ccopt import closed_loop
from ccopt.cliutil import benchmark_parser, print_table, write_json
from ccopt.closed_loop import LoopParams
from ccopt.control.controller import Command, ControlInput, Controller
from ccopt.objects import make_object
from ccopt.schedule import load_schedule

OBJECT, SCHEDULE = "paper-triangle", "smoke"
PAPER_RATES = (100.0, 30.0)
"""The paper's estimator and controller rates, Hz."""
KHZ = (1000.0, 1000.0)

_PARTS = (
    ("plant step", "plant", "step"),
    ("sensors", "sensors", "read"),
    ("estimator", "estimator", "update"),
    ("statics target", None, "_aim"),
    ("controller", "controller", "update"),
    ("truth", "plant", "truth"),
    ("record", "writer", "append"),
    ("sensor health", "health", "update"),
)
"""``(name, attribute of the loop holding the method (None: the loop itself), method)``."""


@dataclass(frozen=True)
class Timed:
    """Per-call wall times (µs) of one part of the tick."""

    name: str
    calls: np.ndarray


def _timed(times: list[float], method: Callable) -> Callable:
    def call(*args: object, **kwargs: object) -> object:
        start = time.perf_counter_ns()
        result = method(*args, **kwargs)
        times.append((time.perf_counter_ns() - start) * 1e-3)
        return result

    return call


def _params(plant: str, rates: tuple[float, float]) -> LoopParams:
    return LoopParams(plant=plant, estimator_hz=rates[0], controller_hz=rates[1])


def instrumented_run(
    seed: int, folder: Path, plant: str = "planar"
) -> tuple[list[Timed], float, int, list[tuple[ControlInput, Command]], LoopParams]:
    """One 1 kHz run on ``plant`` with every part timed where it is called: the parts, the loop's wall
    time (s), its plant steps and the controller's inputs (to replay)."""
    params = _params(plant, KHZ)
    loop = closed_loop._Loop(make_object(OBJECT), load_schedule(SCHEDULE), params, seed, folder, {}, None)
    stores: dict[str, list[float]] = {}
    for name, holder, method in _PARTS:
        owner = loop if holder is None else getattr(loop, holder)
        if hasattr(owner, method):  # the statics target is timed where the loop has it as a method
            stores[name] = []
            setattr(owner, method, _timed(stores[name], getattr(owner, method)))
    inputs: list[tuple[ControlInput, Command]] = []
    timed_update = loop.controller.update

    def capture(state: ControlInput, command: Command) -> object:
        inputs.append((state, command))
        return timed_update(state, command)

    loop.controller.update = capture
    result = loop.run()
    parts = [Timed(name, np.array(times)) for name, times in stores.items()]
    return parts, result.wall_time, len(stores["plant step"]), inputs, params


def replay(controller: Controller, inputs: Sequence[tuple[ControlInput, Command]]) -> np.ndarray:
    """Wall time (µs) of ``controller.update`` on each captured tick (one warm-up call first)."""
    controller.update(*inputs[0])
    times = np.empty(len(inputs))
    for k, (state, command) in enumerate(inputs):
        start = time.perf_counter_ns()
        controller.update(state, command)
        times[k] = (time.perf_counter_ns() - start) * 1e-3
    return times


def authors_solver() -> SimpleNamespace:
    """The QP back end of the authors' path: cvxopt ``solvers.qp``, at most 10 iterations,
    tolerances 1e-6 (as mcubelab/pbal sets them), on the same soft QP; its answer whatever its status."""
    return SimpleNamespace(backend="cvxopt", solve=cvxopt_solver(10, tolerance=1e-6, strict=False))


def real_time_factor(plant: str, rates: tuple[float, float], seed: int, repeats: int) -> tuple[float, float]:
    """``(median, best)`` real-time factor of recorded runs (simulated s over the loop's wall s)."""
    factors = []
    for _ in range(repeats):
        with tempfile.TemporaryDirectory() as folder:
            result = closed_loop.run(
                make_object(OBJECT),
                load_schedule(SCHEDULE),
                _params(plant, rates),
                seed,
                Path(folder) / "run",
            )
        factors.append(result.sim_time / result.wall_time)
    return float(np.median(factors)), float(np.max(factors))


def run(
    seed: int, repeats: int, plant: str = "planar"
) -> tuple[dict[str, float | int], list[tuple[str, ...]]]:
    """The figures and the breakdown table's rows (the breakdown's run on ``plant``)."""
    with tempfile.TemporaryDirectory() as folder:
        parts, wall, steps, inputs, params = instrumented_run(seed, Path(folder) / "run", plant)
    figures: dict[str, float | int] = {"plant_steps": steps, "loop_us_per_step": wall / steps * 1e6}
    rows = []
    accounted = 0.0
    for part in parts:
        key = part.name.replace(" ", "_")
        per_step = float(part.calls.sum()) / steps
        accounted += per_step
        figures[f"{key}_calls"] = len(part.calls)
        figures[f"{key}_median_us"] = float(np.median(part.calls))
        figures[f"{key}_p99_us"] = float(np.percentile(part.calls, 99))
        figures[f"{key}_per_step_us"] = per_step
        rows.append(
            (
                part.name,
                str(len(part.calls)),
                *(f"{figures[f'{key}_{s}_us']:.1f}" for s in ("median", "p99", "per_step")),
            )
        )
    rest = figures["loop_us_per_step"] - accounted
    rows.append(("loop bookkeeping", "", "", "", f"{rest:.1f}"))
    rows.append(("whole tick", str(steps), "", "", f"{figures['loop_us_per_step']:.1f}"))
    figures["bookkeeping_per_step_us"] = rest
    ours = replay(Controller(params.hand, params.control_period, params.controller_params), inputs)
    authors = replay(
        Controller(params.hand, params.control_period, params.controller_params, solver=authors_solver()),
        inputs,
    )
    figures["controller_replay_median_us"] = float(np.median(ours))
    figures["authors_path_median_us"] = float(np.median(authors))
    figures["authors_path_p99_us"] = float(np.percentile(authors, 99))
    figures["speedup_vs_authors_path"] = (
        figures["authors_path_median_us"] / figures["controller_replay_median_us"]
    )
    for name, plant, rates in (
        ("loop_rtf_1khz", "planar", KHZ),
        ("loop_rtf_paper_rates", "planar", PAPER_RATES),
        ("panda_rtf_1khz", "panda", KHZ),
    ):
        figures[name], figures[f"{name}_best"] = real_time_factor(plant, rates, seed, repeats)
    return figures, rows


def main(argv: Sequence[str] | None = None) -> None:
    parser = benchmark_parser(
        "loop_tick", __doc__, "one run per real-time factor instead of three", seed="run seed"
    )
    parser.add_argument(
        "--plant", choices=("planar", "panda"), default="planar", help="the plant whose tick is broken down"
    )
    args = parser.parse_args(argv)
    figures, rows = run(args.seed, 1 if args.quick else 3, args.plant)
    print(f"Closed-loop tick at 1 kHz: {OBJECT}, {SCHEDULE}, {args.plant} plant, recorded; one core, µs")
    print_table(rows, ("part", "calls", "median", "p99", "per plant step"))
    print()
    controller = [
        ("controller (code-generated QP)", f"{figures['controller_replay_median_us']:.1f}", "1.0x"),
        (
            "authors' path (cvxopt, 10 iterations)",
            f"{figures['authors_path_median_us']:.1f}",
            f"{figures['speedup_vs_authors_path']:.1f}x",
        ),
    ]
    print("The same controller ticks replayed")
    print_table(controller, ("QP path", "median µs", "vs ours"))
    print()
    speed = [
        (name, f"{figures[key]:.1f}x ({figures[f'{key}_best']:.1f}x)")
        for name, key in (
            ("planar, 1 kHz / 1 kHz", "loop_rtf_1khz"),
            ("planar, 100 Hz / 30 Hz (paper)", "loop_rtf_paper_rates"),
            ("Panda, 1 kHz / 1 kHz", "panda_rtf_1khz"),
        )
    ]
    print("Real-time factor of recorded runs (median (best))")
    print_table(speed, ("plant, estimator / controller", "RTF"))
    if args.json is not None:
        write_json(args.json, figures)


if __name__ == "__main__":
    main()
