"""Per-solve latency of the impedance-target QP, as a user calls it from Python.

    python -m benchmarks.qp_latency [--quick] [--json PATH] [--seed N]

Back ends, on the same random realistic instances (:mod:`ccopt.control.instances`), in one run:
``codegen`` (generated C + DAQP through a FunctionBuffer), ``casadi`` (the same in process),
``cvxpy`` (Clarabel, the reference answer) and, as the original authors' baseline, cvxopt's
``solvers.qp`` with ``maxiters=10`` on the same soft QP. A solve *fails* when it flags a feasible
instance infeasible or its step differs from the reference by more than 1e-5 (relative); the
failures are split into *unsolved* (the solver returned no step: cvxopt stopped short of its
tolerance within ``maxiters``) and *inaccurate* (a step, but the wrong one or the wrong feasibility).
"""

from __future__ import annotations

import time
import warnings
from collections.abc import Callable, Sequence

import numpy as np

from ccopt.casadi_eval import BufferedFunction
from ccopt.cliutil import benchmark_parser, print_table, write_json
from ccopt.control import qp
from ccopt.control.instances import random_instances

TOLERANCE = 1e-5


def cvxopt_solver(
    max_iterations: int = 10, tolerance: float | None = None, strict: bool = True
) -> Callable[[qp.QPInstance], qp.QPSolution]:
    """cvxopt's interior-point ``solvers.qp`` on the soft QP in ``z = (Δx, t)``, at most
    ``max_iterations`` iterations; ``tolerance`` sets its ``abstol``, ``reltol`` and ``feastol``
    (None: cvxopt's defaults). ``strict``: a status other than optimal gives no step (NaN), else the
    answer is taken as it is, as the paper authors' controller takes it."""
    import cvxopt

    options: dict[str, object] = {"maxiters": max_iterations, "show_progress": False}
    if tolerance is not None:
        options.update(abstol=tolerance, reltol=tolerance, feastol=tolerance)
    matrices = BufferedFunction(qp.build_qp_matrices())
    bound = np.zeros((1, 4))
    bound[0, 3] = -1.0

    def solve(instance: qp.QPInstance) -> qp.QPSolution:
        hessian, gradient, rows, upper = matrices(instance.packed)
        result = cvxopt.solvers.qp(
            cvxopt.matrix(hessian),
            cvxopt.matrix(gradient),
            cvxopt.matrix(np.vstack([rows, bound])),
            cvxopt.matrix(np.append(upper, 0.0)),
            options=options,
        )
        z = np.array(result["x"]).ravel()
        if strict and result["status"] != "optimal":
            z = np.full(4, np.nan)
        slack = float(z[3]) if np.isfinite(z[3]) else np.inf
        return qp.QPSolution(z[:3], instance.stiffness @ z[:3], slack, slack <= qp.INFEASIBLE_SLACK, "cvxopt")

    return solve


def time_solves(solve: Callable, instances: Sequence[qp.QPInstance]) -> tuple[np.ndarray, list]:
    """Wall time of each call (µs) and the solutions; one warm-up call first."""
    solve(instances[0])
    times, solutions = np.empty(len(instances)), []
    for k, instance in enumerate(instances):
        start = time.perf_counter_ns()
        solutions.append(solve(instance))
        times[k] = (time.perf_counter_ns() - start) * 1e-3
    return times, solutions


def count_failures(solutions: list[qp.QPSolution], references: list[qp.QPSolution]) -> tuple[int, int]:
    """``(unsolved, inaccurate)`` against the references (see the module docstring)."""
    unsolved = inaccurate = 0
    for solution, reference in zip(solutions, references, strict=True):
        if not np.all(np.isfinite(solution.step)):
            unsolved += 1
        elif reference.feasible:
            scale = max(np.linalg.norm(reference.step), 1e-6)
            wrong = np.linalg.norm(solution.step - reference.step) / scale > TOLERANCE
            inaccurate += int(wrong or not solution.feasible)
        else:
            inaccurate += int(solution.feasible)
    return unsolved, inaccurate


def run(count: int, seed: int) -> dict[str, float | int]:
    instances = random_instances(seed, count)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", UserWarning)
        reference_times, references = time_solves(qp.make_solver("cvxpy").solve, instances)
    figures: dict[str, float | int] = {
        "instances": count,
        "infeasible_instances": sum(not r.feasible for r in references),
        "cvxpy_median_us": float(np.median(reference_times)),
        "cvxpy_p99_us": float(np.percentile(reference_times, 99)),
    }
    candidates = {
        "codegen": qp.make_solver("codegen").solve,
        "casadi": qp.make_solver("casadi").solve,
        "cvxopt": cvxopt_solver(),
    }
    for name, solve in candidates.items():
        times, solutions = time_solves(solve, instances)
        figures[f"{name}_median_us"] = float(np.median(times))
        figures[f"{name}_p99_us"] = float(np.percentile(times, 99))
        unsolved, inaccurate = count_failures(solutions, references)
        figures[f"{name}_failures"] = unsolved + inaccurate
        figures[f"{name}_unsolved"] = unsolved
        figures[f"{name}_inaccurate"] = inaccurate
    figures["speedup_vs_cvxopt"] = figures["cvxopt_median_us"] / figures["codegen_median_us"]
    figures["speedup_vs_casadi"] = figures["casadi_median_us"] / figures["codegen_median_us"]
    figures["speedup_vs_cvxpy"] = figures["cvxpy_median_us"] / figures["codegen_median_us"]
    return figures


def failures_cell(figures: dict[str, float | int], name: str) -> str:
    if f"{name}_failures" not in figures:
        return "reference"
    return f"{figures[f'{name}_failures']} ({figures[f'{name}_unsolved']} + {figures[f'{name}_inaccurate']})"


def main(argv: Sequence[str] | None = None) -> None:
    quick = "300 instances instead of 3000"
    parser = benchmark_parser("qp_latency", __doc__, quick, seed="instance generator seed")
    args = parser.parse_args(argv)
    figures = run(300 if args.quick else 3000, args.seed)
    rows = [
        (
            name,
            f"{figures[f'{name}_median_us']:.1f}",
            f"{figures[f'{name}_p99_us']:.1f}",
            f"{figures[f'{name}_median_us'] / figures['codegen_median_us']:.1f}x",
            failures_cell(figures, name),
        )
        for name in ("codegen", "casadi", "cvxpy", "cvxopt")
    ]
    print(
        f"QP latency, {figures['instances']} instances "
        f"({figures['infeasible_instances']} infeasible), one core, from Python"
    )
    print_table(rows, ("backend", "median µs", "p99 µs", "vs codegen", "failures (unsolved + inaccurate)"))
    if args.json is not None:
        write_json(args.json, figures)


if __name__ == "__main__":
    main()
