"""Symbolic derivatives against central finite differences: the contact model and the QP's solution.

    ccopt study gradients [--seeds 4] [--points 20] [--instances 40]

Contact model
    For every function of :data:`ccopt.contact.CONTACT_FUNCTIONS`, at random points: the CasADi
    Jacobian of every output with respect to every input against central differences
    (step ``h = 1e-5 · max(1, |x|)``). Error of a Jacobian block: ``max |J − J_fd|`` (absolute), and
    that over ``max |J|`` of the block (relative; absolute for an all-zero block). Acceptance: relative
    error ≤ :data:`CONTACT_TOLERANCE`.

QP sensitivities
    ``z(p) = (Δx, t)``, the soft QP's solution (:mod:`ccopt.control.qp`) as a function of its packed
    parameters ``p``, is differentiable wherever the active set is locally constant and strictly
    complementary. There the KKT system of the active rows ``C z = c``,
    ``[H Cᵀ; C 0] [z; λ] = [−g; c]``, differentiated (implicit function theorem) gives
    ``[H Cᵀ; C 0] [∂z; ∂λ] = [−∂H z − ∂g − ∂Cᵀ λ; ∂c − ∂C z]``, with ``∂H, ∂g, ∂A, ∂ub`` the CasADi
    Jacobians of :func:`ccopt.control.qp.build_qp_matrices`. That is compared with central
    differences of the ``codegen`` (DAQP) solver's solution, on random realistic instances
    (:mod:`ccopt.control.instances`) whose active set is the same at ``p ± h`` for every parameter
    (others are counted as skipped). Errors are measured on the column-scaled Jacobian
    ``∂z/∂p · diag(max(|p|, 1))`` (the change of ``z`` for a relative change of each parameter), per
    component of ``z``, relative to that component's largest entry.
"""

from __future__ import annotations

import sys
from collections.abc import Sequence
from dataclasses import dataclass

import casadi as ca
import numpy as np

from ccopt import contact
from ccopt.casadi_eval import BufferedFunction
from ccopt.cliutil import print_table
from ccopt.control import qp
from ccopt.control.instances import random_instance
from studies import runner

CONTACT_TOLERANCE = 1e-6
"""Largest acceptable relative error of a contact-model Jacobian."""

QP_TOLERANCE = 1e-5
"""Largest acceptable relative error of the QP sensitivities (see the module docstring)."""

CONTACT_STEP = 1e-5
"""Relative central-difference step for the contact model (truncation ~h², rounding ~1e-16/h)."""

QP_STEP = 1e-6
"""Relative central-difference step for the QP: its solution is exact only to the solver's accuracy,
so rounding (~solver error / h) dominates; 1e-6 measured best against 1e-5 and 1e-7."""

ACTIVE_TOLERANCE = 1e-9
"""A row is active when ``A z − ub ≥ −ACTIVE_TOLERANCE (1 + |ub|)``; the same for ``t ≥ 0``."""

NEGLIGIBLE = 1e-12
"""A component of ``z`` whose scaled derivatives are all below this does not depend on ``p`` (the
slack ``t`` pinned at 0): its error is reported as absolute."""

MIN_MULTIPLIER = 1e-9
"""Active rows need a multiplier above this (strict complementarity), else the instance is skipped."""

_INPUT_SCALES = {"w_h": 10.0, "f_ground": 10.0, "f_grav": 5.0, "ground_b": 5.0}
"""Half-width of the uniform sampling range per input name (N for forces); others ``[-1, 1]``."""


@dataclass(frozen=True)
class GradientTrial:
    """One trial: ``points`` random points of contact function ``name``, or ``points`` QP instances
    when ``name`` is ``"qp"``, drawn from ``seed``."""

    name: str
    seed: int
    points: int


# --- the contact model ----------------------------------------------------------------------------


@runner.thread_cached
def _contact_functions() -> dict[str, tuple[ca.Function, ca.Function]]:
    """``name → (function, jacobians)``; ``jacobians`` returns every ``∂ vec(out_j) / ∂ vec(in_i)``,
    outputs major. Built once per thread."""
    built = {}
    for function in contact.CONTACT_FUNCTIONS:
        inputs = [ca.SX.sym(function.name_in(i), function.sparsity_in(i)) for i in range(function.n_in())]
        outputs = function.call(inputs)
        blocks = [ca.densify(ca.jacobian(ca.vec(out), ca.vec(inp))) for out in outputs for inp in inputs]
        built[function.name()] = (function, ca.Function(f"{function.name()}_jacobians", inputs, blocks))
    return built


def _as_args(function: ca.Function, flat_args: Sequence[np.ndarray]) -> list[ca.DM]:
    """Inputs given as column-major flat vectors, reshaped to ``function``'s input shapes."""
    return [ca.DM(a.reshape(function.size_in(i), order="F")) for i, a in enumerate(flat_args)]


def _evaluate(function: ca.Function, flat_args: Sequence[np.ndarray]) -> list[np.ndarray]:
    """``function`` at flat inputs; outputs flattened column-major."""
    return [
        np.asarray(ca.densify(out)).reshape(-1, order="F")
        for out in function.call(_as_args(function, flat_args))
    ]


def _random_inputs(function: ca.Function, rng: np.random.Generator) -> list[np.ndarray]:
    """Flat inputs, uniform in ``±`` :data:`_INPUT_SCALES` (``±1`` by default)."""
    return [
        rng.uniform(-1.0, 1.0, function.numel_in(i)) * _INPUT_SCALES.get(function.name_in(i), 1.0)
        for i in range(function.n_in())
    ]


def finite_difference_blocks(function: ca.Function, flat_args: Sequence[np.ndarray]) -> list[np.ndarray]:
    """Central-difference ``∂ vec(out_j) / ∂ vec(in_i)``, outputs major (like the symbolic blocks)."""
    blocks: dict[tuple[int, int], list[np.ndarray]] = {}
    for i, arg in enumerate(flat_args):
        for k in range(arg.size):
            step = CONTACT_STEP * max(1.0, abs(arg[k]))
            plus, minus = [a.copy() for a in flat_args], [a.copy() for a in flat_args]
            plus[i][k] += step
            minus[i][k] -= step
            outputs = zip(_evaluate(function, plus), _evaluate(function, minus), strict=True)
            for j, (high, low) in enumerate(outputs):
                blocks.setdefault((j, i), []).append((high - low) / (2.0 * step))
    return [np.column_stack(blocks[j, i]) for j in range(function.n_out()) for i in range(function.n_in())]


def contact_errors(name: str, seed: int, points: int) -> dict:
    """Max absolute and relative Jacobian error of contact function ``name`` over ``points`` points."""
    function, jacobians = _contact_functions()[name]
    rng = np.random.default_rng(seed)
    worst_abs = worst_rel = 0.0
    for _ in range(points):
        args = _random_inputs(function, rng)
        exact = [np.asarray(block) for block in jacobians.call(_as_args(function, args))]
        for symbolic, numeric in zip(exact, finite_difference_blocks(function, args), strict=True):
            error = float(np.max(np.abs(symbolic - numeric), initial=0.0))
            scale = float(np.max(np.abs(symbolic), initial=0.0))
            worst_abs = max(worst_abs, error)
            worst_rel = max(worst_rel, error / scale if scale > 0.0 else error)
    return {"max_abs": worst_abs, "max_rel": worst_rel, "points": points}


# --- the QP ---------------------------------------------------------------------------------------


def _build_matrix_jacobians() -> ca.Function:
    """``p → (∂vec H, ∂g, ∂vec A, ∂ub)`` with respect to ``p`` (column-major ``vec``), dense."""
    parameters = ca.SX.sym("p", qp.N_PARAMETERS)
    outputs = qp.build_qp_matrices()(parameters)
    jacobians = [ca.densify(ca.jacobian(ca.vec(out), parameters)) for out in outputs]
    return ca.Function("qp_matrix_jacobians", [parameters], jacobians)


QP_MATRICES = qp.build_qp_matrices()
QP_MATRIX_JACOBIANS = _build_matrix_jacobians()
N_Z = 4
"""``z = (Δn, Δt, Δθ, t)``."""


@runner.thread_cached
def _codegen_qp() -> BufferedFunction:
    """The ``codegen`` back end's compiled function ``p → z`` (compiled once, cached on disk)."""
    function = qp.build_qp_function()
    library, _ = qp.compile_function(function)
    return BufferedFunction(ca.external(function.name(), str(library)))


def _solve(packed: np.ndarray) -> np.ndarray:
    """The compiled solver's ``z = (Δx, t)`` for a packed parameter vector (any ``p``, not only a
    :class:`~ccopt.control.qp.QPInstance`'s)."""
    return _codegen_qp().call_flat(packed)


def active_set(packed: np.ndarray, z: np.ndarray) -> tuple[bool, ...]:
    """Which of the rows ``A z ≤ ub`` and the bound ``t ≥ 0`` (last) hold with equality at ``z``."""
    _, _, rows, upper = (np.asarray(m) for m in QP_MATRICES(packed))
    residual = rows @ z - upper.ravel()
    active = residual >= -ACTIVE_TOLERANCE * (1.0 + np.abs(upper.ravel()))
    return (*(bool(a) for a in active), bool(z[3] <= ACTIVE_TOLERANCE))


def kkt_sensitivity(packed: np.ndarray, active: Sequence[bool]) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """``(z, λ, ∂z/∂p)`` from the KKT system of the active set (implicit function theorem).

    Raises ``np.linalg.LinAlgError`` when the active rows are linearly dependent (no unique λ).
    """
    hessian, gradient, rows, upper = (np.asarray(m) for m in QP_MATRICES(packed))
    d_hessian, d_gradient, d_rows, d_upper = (np.asarray(m) for m in QP_MATRIX_JACOBIANS(packed))
    n_p = packed.size
    d_hessian = d_hessian.reshape(N_Z, N_Z, n_p, order="F")
    d_rows = d_rows.reshape(qp.MAX_ROWS, N_Z, n_p, order="F")
    bound = np.zeros((1, N_Z))
    bound[0, 3] = -1.0  # t ≥ 0 as −t ≤ 0
    all_rows = np.vstack([rows, bound])
    all_upper = np.append(upper.ravel(), 0.0)
    all_d_rows = np.concatenate([d_rows, np.zeros((1, N_Z, n_p))])
    all_d_upper = np.vstack([d_upper, np.zeros((1, n_p))])
    chosen = np.flatnonzero(active)
    c_rows, c_upper = all_rows[chosen], all_upper[chosen]
    m = chosen.size
    kkt = np.block([[hessian, c_rows.T], [c_rows, np.zeros((m, m))]])
    solution = np.linalg.solve(kkt, np.concatenate([-gradient.ravel(), c_upper]))
    z, multipliers = solution[:N_Z], solution[N_Z:]
    dc_rows, dc_upper = all_d_rows[chosen], all_d_upper[chosen]
    rhs_top = -(
        np.einsum("ijk,j->ik", d_hessian, z) + d_gradient + np.einsum("jik,j->ik", dc_rows, multipliers)
    )
    rhs_bottom = dc_upper - np.einsum("ijk,j->ik", dc_rows, z)
    derivative = np.linalg.solve(kkt, np.vstack([rhs_top, rhs_bottom]))[:N_Z]
    return z, multipliers, derivative


def finite_difference_sensitivity(packed: np.ndarray, active: Sequence[bool]) -> np.ndarray | None:
    """Central differences of the solver's ``z``; ``None`` if any ``p ± h`` changes the active set."""
    columns = []
    for k in range(packed.size):
        step = QP_STEP * max(1.0, abs(packed[k]))
        solutions = []
        for sign in (1.0, -1.0):
            shifted = packed.copy()
            shifted[k] += sign * step
            z = _solve(shifted)
            if active_set(shifted, z) != tuple(active):
                return None
            solutions.append(z)
        columns.append((solutions[0] - solutions[1]) / (2.0 * step))
    return np.column_stack(columns)


def sensitivity_errors(exact: np.ndarray, numeric: np.ndarray, packed: np.ndarray) -> tuple[float, float]:
    """``(max abs, max rel)`` error of ``∂z/∂p``; relative per component of ``z`` on the column-scaled
    Jacobian (absolute for a component that does not depend on ``p``)."""
    scale = np.maximum(np.abs(packed), 1.0)
    error = np.abs(exact - numeric) * scale
    size = np.max(np.abs(exact) * scale, axis=1)
    relative = np.max(error, axis=1) / np.where(size > NEGLIGIBLE, size, 1.0)
    return float(np.max(np.abs(exact - numeric))), float(np.max(relative))


def qp_errors(seed: int, instances: int) -> dict:
    """KKT sensitivities against finite differences on ``instances`` usable random instances.

    Instances are drawn until ``instances`` are usable or ``10 × instances`` were tried. Skipped:
    the active set changes within ``±h``, a multiplier is not strictly positive, the active rows
    are dependent, or the solver's ``z`` is not the KKT point of its own active set — which is what
    infeasible (soft, ``t > 0``) instances give, as DAQP solves those only to ~1e-6 (counted in
    ``skipped_soft``).
    """
    rng = np.random.default_rng(seed)
    worst_abs = worst_rel = 0.0
    used = skipped = skipped_soft = 0
    while used < instances and used + skipped < 10 * instances:
        packed = random_instance(rng).packed
        z = _solve(packed)
        active = active_set(packed, z)
        try:
            z_kkt, multipliers, exact = kkt_sensitivity(packed, active)
            usable = np.allclose(z_kkt, z, rtol=0.0, atol=1e-9) and np.all(multipliers > MIN_MULTIPLIER)
            numeric = finite_difference_sensitivity(packed, active) if usable else None
        except np.linalg.LinAlgError:
            numeric = None
        if numeric is None:
            skipped += 1
            skipped_soft += int(z[3] > qp.INFEASIBLE_SLACK)
            continue
        abs_error, rel_error = sensitivity_errors(exact, numeric, packed)
        worst_abs, worst_rel = max(worst_abs, abs_error), max(worst_rel, rel_error)
        used += 1
    return {
        "max_abs": worst_abs,
        "max_rel": worst_rel,
        "points": used,
        "skipped": skipped,
        "skipped_soft": skipped_soft,
    }


def gradient_trial(spec: GradientTrial) -> dict:
    """Errors of one contact function, or of the QP sensitivities (``name == "qp"``)."""
    if spec.name == "qp":
        return qp_errors(spec.seed, spec.points)
    return contact_errors(spec.name, spec.seed, spec.points)


# --- command line ---------------------------------------------------------------------------------


def make_specs(seed: int, seeds: int, points: int, instances: int) -> list[GradientTrial]:
    """``seeds`` trials per contact function and ``seeds`` QP trials, seeds derived from ``seed``."""
    names = [function.name() for function in contact.CONTACT_FUNCTIONS]
    trial_seeds = runner.trial_seeds(seed, seeds)
    specs = [GradientTrial(name, s, points) for name in names for s in trial_seeds]
    return specs + [GradientTrial("qp", s, instances) for s in trial_seeds]


def summarise(specs: Sequence[GradientTrial], results: Sequence[dict]) -> dict:
    """Worst errors per function (over its trials) and whether each meets its tolerance."""
    summary: dict[str, dict] = {}
    for spec, result in zip(specs, results, strict=True):
        entry = summary.setdefault(
            spec.name, {"max_abs": 0.0, "max_rel": 0.0, "points": 0, "skipped": 0, "skipped_soft": 0}
        )
        if "error" in result:
            entry["error"] = result["error"]
            continue
        entry["max_abs"] = max(entry["max_abs"], result["max_abs"])
        entry["max_rel"] = max(entry["max_rel"], result["max_rel"])
        entry["points"] += result["points"]
        entry["skipped"] += result.get("skipped", 0)
        entry["skipped_soft"] += result.get("skipped_soft", 0)
    for name, entry in summary.items():
        tolerance = QP_TOLERANCE if name == "qp" else CONTACT_TOLERANCE
        entry["tolerance"] = tolerance
        entry["passed"] = "error" not in entry and entry["points"] > 0 and entry["max_rel"] <= tolerance
    return summary


FULL = {"seeds": 4, "points": 20, "instances": 40}
QUICK = {"seeds": 1, "points": 5, "instances": 10}
"""Trials per function, random points and QP instances per trial, by default and with ``--quick``."""


def main(argv: Sequence[str] | None = None) -> int:
    parser = runner.study_parser(
        "gradients", __doc__.split("\n")[0], "1 trial of 5 points and 10 QP instances (unless given)"
    )
    parser.add_argument("--seeds", type=runner.positive_int, help="trials per function (default: 4)")
    parser.add_argument("--points", type=runner.positive_int, help="random points per trial (default: 20)")
    parser.add_argument("--instances", type=runner.positive_int, help="QP instances per trial (default: 40)")
    args = parser.parse_args(argv)
    sizes = QUICK if args.quick else FULL
    counts = [getattr(args, name) or sizes[name] for name in ("seeds", "points", "instances")]
    specs = make_specs(args.seed, *counts)
    options = runner.RunOptions.from_args(args)
    results = runner.run_study(parser.prog, gradient_trial, specs, options)
    summary = summarise(specs, results)
    runner.write_results(options.out, specs, results, summary)
    rows = [
        (
            name,
            f"{s['max_abs']:.1e}",
            f"{s['max_rel']:.1e}",
            f"{s['tolerance']:.0e}",
            str(s["points"]),
            str(s["skipped"]),
            "ok" if s["passed"] else s.get("error", "FAILED"),
        )
        for name, s in summary.items()
    ]
    print_table(rows, ("function", "max abs", "max rel", "tolerance", "points", "skipped", "result"))
    print(f"results in {options.out}")
    return 0 if all(s["passed"] for s in summary.values()) else 1


if __name__ == "__main__":
    sys.exit(main())
