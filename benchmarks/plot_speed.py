"""ccopt plot of a paper run against the loop of that run (issue 13: at most as long).

    python -m benchmarks.plot_speed [--quick] [--json PATH] [--rounds N]

Each round runs ``ccopt run`` as ``make demo`` does (paper-triangle, the ``paper`` schedule, planar
plant, seed 0) without figures into one temporary folder, and then ``ccopt plot`` of that folder
twice, every command a process of its own. The loop's time is the wall time the run records
(``summary.json``'s ``wall_time_s``: the loop alone); the plot's is the command's, end to end
(start-up, imports, the five figures, exit), and so is its CPU time (the process and the worker
it forks). ``plot_over_loop`` is the ratio of the medians, measured in the same session because
this machine is shared and its times move with the load: the load average before and after is
reported, and the plot's CPU time over its wall time (near 2 with two cores free: the GIF and the
feasibility map are drawn in a second process while the still figures are drawn in the first).
"""

from __future__ import annotations

import json
import os
import resource
import statistics
import subprocess
import sys
import tempfile
import time
from collections.abc import Sequence
from pathlib import Path

from ccopt.cliutil import benchmark_parser, print_table, write_json
from studies.runner import positive_int

RUN = ["--object", "paper-triangle", "--schedule", "paper", "--plant", "planar", "--seed", "0"]
"""The run of ``make demo``."""


def _children_cpu() -> float:
    """CPU time (user + system, s) of this process's finished children and theirs."""
    usage = resource.getrusage(resource.RUSAGE_CHILDREN)
    return usage.ru_utime + usage.ru_stime


def _ccopt(args: Sequence[str], accepted: tuple[int, ...] = (0,)) -> tuple[float, float]:
    """Run ``ccopt ARGS`` in a new process; its wall and CPU time (s). ``CalledProcessError`` if it
    exits otherwise than ``accepted``."""
    cpu, start = _children_cpu(), time.perf_counter()
    done = subprocess.run([sys.executable, "-m", "ccopt.cli", *args], capture_output=True, text=True)
    wall = time.perf_counter() - start
    if done.returncode not in accepted:
        raise subprocess.CalledProcessError(done.returncode, done.args, done.stdout, done.stderr)
    return wall, _children_cpu() - cpu


def run(rounds: int) -> dict[str, object]:
    """The figures of ``rounds`` rounds: a run, then two plots of it."""
    loops, plots, cpus = [], [], []
    load_before = os.getloadavg()[0]
    with tempfile.TemporaryDirectory() as scratch:
        folder = Path(scratch) / "run"
        for _ in range(rounds):
            out = ["--no-figures", "--no-progress", "--overwrite", "--out", str(folder)]
            _ccopt(["run", *RUN, *out], accepted=(0, 3))  # 3: not done (12 of the 14 goals reachable)
            loops.append(json.loads((folder / "summary.json").read_text())["wall_time_s"])
            for _ in range(2):
                wall, cpu = _ccopt(["plot", str(folder)])
                plots.append(wall)
                cpus.append(cpu)
    loop, plot = statistics.median(loops), statistics.median(plots)
    return {
        "loop_wall_s": loop,
        "plot_wall_s": plot,
        "plot_over_loop": plot / loop,
        "plot_cpu_s": statistics.median(cpus),
        "loop_walls_s": loops,
        "plot_walls_s": plots,
        "load_before": load_before,
        "load_after": os.getloadavg()[0],
        "cores": os.cpu_count() or 1,
    }


def main(argv: Sequence[str] | None = None) -> None:
    parser = benchmark_parser("plot_speed", __doc__, "1 round instead of 3")
    parser.add_argument("--rounds", type=positive_int, help="rounds of a run and two plots (default 3)")
    args = parser.parse_args(argv)
    figures = run(args.rounds or (1 if args.quick else 3))
    print(
        f"ccopt plot of a paper run against its loop ({figures['cores']} cores; load average "
        f"{figures['load_before']:.2f} before, {figures['load_after']:.2f} after)"
    )
    rows = [
        ("loop (the run's wall_time_s)", f"{figures['loop_wall_s']:.2f}", _listed(figures["loop_walls_s"])),
        ("ccopt plot, wall", f"{figures['plot_wall_s']:.2f}", _listed(figures["plot_walls_s"])),
        ("ccopt plot, CPU", f"{figures['plot_cpu_s']:.2f}", ""),
        ("plot / loop", f"{figures['plot_over_loop']:.2f}", "bar: ≤ 1"),
    ]
    print_table(rows, ("figure", "median (s)", "all"))
    if args.json is not None:
        write_json(args.json, figures)


def _listed(values: Sequence[float]) -> str:
    return " ".join(f"{value:.2f}" for value in values)


if __name__ == "__main__":
    main()
