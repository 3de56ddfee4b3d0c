"""How the robustness study scales with local worker processes.

    python -m benchmarks.study_scaling [--quick] [--json PATH] [--seed N] [--workers N] [--trials N]

The same robustness trials (:mod:`studies.robustness`: random objects, the ``paper`` schedule,
planar plant; as many as the study runs by default, 50) run through
:func:`studies.runner.run_trials` on 1 worker (in this process, as ``--workers 1`` runs them) and on
``--workers`` spawned worker processes (2 by default), in one run; the speedup is the ratio of the
two wall times, process start-up included. Each worker's start (0.4 s of imports, 0.3 s more for its
first run) and the last trial that one worker finishes alone are paid once per study: fewer trials
scale worse (8: ~1.6×). The speedup can reach the worker count only if that many cores are free, so
the load average before and after is reported (a shared machine's other work takes its share of the
cores), and so is the CPU time each run used (this process and its workers): where the parallel run
uses no more CPU than the serial one, the study itself scales and only the cores it was given limit
the speedup (``cpu_bound_speedup``: the speedup had every worker had a core of its own, ``workers ×
serial CPU / parallel CPU``).
"""

from __future__ import annotations

import os
import resource
import time
from collections.abc import Sequence

from ccopt.cliutil import benchmark_parser, print_table, write_json
from studies import runner
from studies.robustness import TRIALS, draw_object, robustness_trial


def _cpu_seconds() -> float:
    """CPU time (user + system, s) of this process and of its finished children."""
    return sum(
        usage.ru_utime + usage.ru_stime
        for usage in (resource.getrusage(resource.RUSAGE_SELF), resource.getrusage(resource.RUSAGE_CHILDREN))
    )


def timed_study(specs: Sequence[object], workers: int) -> tuple[float, float, list[dict]]:
    """Wall time (s), CPU time (s) and results of the trials on ``workers`` local workers."""
    start, cpu = time.perf_counter(), _cpu_seconds()
    results = runner.run_trials(robustness_trial, specs, workers=workers, progress=False)
    return time.perf_counter() - start, _cpu_seconds() - cpu, results


def run(trials: int, seed: int, workers: int) -> dict[str, float | int]:
    """The figures of one comparison: wall and CPU times (s), speedups, load averages."""
    specs = [draw_object(k, s, "paper", "planar") for k, s in enumerate(runner.trial_seeds(seed, trials))]
    load_before = os.getloadavg()[0]
    serial, serial_cpu, serial_results = timed_study(specs, 1)
    parallel, parallel_cpu, parallel_results = timed_study(specs, workers)
    same = [{k: v for k, v in result.items() if k != "wall_time_s"} for result in serial_results] == [
        {k: v for k, v in result.items() if k != "wall_time_s"} for result in parallel_results
    ]
    return {
        "trials": trials,
        "workers": workers,
        "serial_s": serial,
        "parallel_s": parallel,
        "speedup": serial / parallel,
        "serial_cpu_s": serial_cpu,
        "parallel_cpu_s": parallel_cpu,
        "cpu_bound_speedup": workers * serial_cpu / parallel_cpu,
        "same_results": int(same),
        "load_before": load_before,
        "load_after": os.getloadavg()[0],
        "cores": os.cpu_count() or 1,
    }


def main(argv: Sequence[str] | None = None) -> None:
    parser = benchmark_parser(
        "study_scaling", __doc__, f"8 trials instead of {TRIALS}", seed="base seed of the trials"
    )
    parser.add_argument("--workers", type=runner.positive_int, default=2, help="workers to compare with 1")
    parser.add_argument("--trials", type=runner.positive_int, help=f"trials (default: {TRIALS}, --quick 8)")
    args = parser.parse_args(argv)
    figures = run(args.trials or (8 if args.quick else TRIALS), args.seed, args.workers)
    print(
        f"Robustness study, {figures['trials']} trials ({figures['cores']} cores; load average "
        f"{figures['load_before']:.2f} before, {figures['load_after']:.2f} after)"
    )
    rows = [
        ("1 (in process)", f"{figures['serial_s']:.1f}", f"{figures['serial_cpu_s']:.1f}", "1.00x", ""),
        (
            f"{figures['workers']} (processes)",
            f"{figures['parallel_s']:.1f}",
            f"{figures['parallel_cpu_s']:.1f}",
            f"{figures['speedup']:.2f}x",
            f"{figures['cpu_bound_speedup']:.2f}x",
        ),
    ]
    print_table(rows, ("workers", "wall s", "CPU s", "speedup", "with a core each"))
    print("results identical" if figures["same_results"] else "results differ between the two runs")
    if args.json is not None:
        write_json(args.json, figures)


if __name__ == "__main__":
    main()
