"""The impedance-target QP: three back ends against each other and against scipy's HiGHS LP."""

import dataclasses
import warnings

import numpy as np
import pytest
from scipy.optimize import linprog

from ccopt import contact, modes
from ccopt.contact import Row
from ccopt.control import qp
from ccopt.control.instances import DEFAULT_STIFFNESS, random_instances

N_INSTANCES = 600


@pytest.fixture(scope="module")
def solvers(tmp_path_factory):
    cache = tmp_path_factory.mktemp("qp_cache")
    return {
        "codegen": qp.make_solver("codegen", cache_dir=cache),
        "casadi": qp.make_solver("casadi"),
        "cvxpy": qp.make_solver("cvxpy"),
    }


def hard_rows(instance):
    """The active rows as ``A Δx ≤ ub``, assembled independently of the CasADi formulation."""
    a = (instance.gains[:, None] * instance.rows @ instance.stiffness)[instance.active]
    ub = (instance.bounds - instance.rows @ instance.wrench)[instance.active]
    return a, ub


def min_violation(instance):
    """The smallest achievable max-violation of the active rows, by an LP (HiGHS)."""
    a, ub = hard_rows(instance)
    lp = linprog(
        [0, 0, 0, 1],
        A_ub=np.hstack([a, -np.ones((len(a), 1))]),
        b_ub=ub,
        bounds=[(None, None)] * 3 + [(0, None)],
        method="highs",
    )
    assert lp.status == 0
    return lp.fun


@pytest.fixture(scope="module")
def results(solvers):
    instances = random_instances(seed=2024, count=N_INSTANCES)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", UserWarning)  # cvxpy's "may be inaccurate" chatter
        return [(i, {name: s.solve(i) for name, s in solvers.items()}) for i in instances]


def test_instances_cover_the_problem_class(results):
    rows = [int(i.active.size) for i, _ in results]
    assert min(rows) == 6 and max(rows) == qp.MAX_ROWS
    infeasible = sum(min_violation(i) > 1e-9 for i, _ in results)
    assert 5 <= infeasible <= N_INSTANCES // 5


def test_back_ends_agree_on_feasible_instances(results):
    worst = 0.0
    for instance, by_backend in results:
        if min_violation(instance) > 1e-9:
            continue
        reference = by_backend["cvxpy"].step
        scale = max(np.linalg.norm(reference), 1e-6)
        for name in ("codegen", "casadi"):
            worst = max(worst, np.linalg.norm(by_backend[name].step - reference) / scale)
    assert worst <= 1e-5


def test_feasible_steps_satisfy_the_hard_rows(results):
    for instance, by_backend in results:
        if min_violation(instance) > 1e-9:
            continue
        a, ub = hard_rows(instance)
        for solution in by_backend.values():
            assert solution.feasible
            assert np.all(a @ solution.step <= ub + 1e-7)


def test_infeasible_instances_are_flagged_with_the_least_violation(results):
    seen = 0
    for instance, by_backend in results:
        violation = min_violation(instance)
        if violation <= 1e-6:
            continue
        seen += 1
        for solution in by_backend.values():
            assert not solution.feasible
            assert solution.slack == pytest.approx(violation, rel=1e-4, abs=1e-6)
            a, ub = hard_rows(instance)
            assert np.max(a @ solution.step - ub) == pytest.approx(violation, rel=1e-4, abs=1e-6)
    assert seen > 0


def hand_slide_instance(motion):
    """Flat hand, wrench well inside the cone, a large commanded hand slide ``Δs_h > 0``."""
    rows, bounds = contact.model_friction_cone(0.0, 0.5, 0.8, 0.045, 0.3)
    v = contact.admissible_motions(0.0, 0.0, 0.08)
    return qp.QPInstance(
        stiffness=DEFAULT_STIFFNESS,
        wrench=np.array([10.0, 0.0, 0.0]),
        rows=np.vstack([rows, [[1.0, 0.0, 0.0], [-1.0, 0.0, 0.0]]]),
        bounds=np.append(bounds, [25.0, -8.0]),
        gains=np.ones(8),
        active=np.append(modes.kept_rows(motion), [True, True]),
        regularization=1e-2,
        directions=v[:, [1]].T,
        weights=np.array([10.0]),
        targets=np.array([0.02]),
    )


@pytest.mark.parametrize("backend", qp.BACKENDS)
def test_commanded_motion_removes_its_row(solvers, backend):
    solver = solvers[backend]
    wrench_rows, bounds = contact.model_friction_cone(0.0, 0.5, 0.8, 0.045, 0.3)

    def margin(solution, instance):
        return (bounds - wrench_rows @ (instance.wrench + solution.wrench_change))[Row.HAND_SLIDE_POS]

    holding = hand_slide_instance(modes.Motion.HOLD)
    sliding = hand_slide_instance(modes.Motion.SLIDE_HAND_POS)
    held, slid = solver.solve(holding), solver.solve(sliding)
    assert held.feasible and slid.feasible
    assert margin(held, holding) >= -1e-7  # kept: the step stops at the friction face
    assert margin(slid, sliding) < -1.0  # removed: the wrench goes through it to drive the slide


def test_compiled_solver_is_reused_from_the_cache(tmp_path):
    first = qp.CodegenQPSolver(cache_dir=tmp_path)
    mtime = first.library.stat().st_mtime_ns
    second = qp.CodegenQPSolver(cache_dir=tmp_path)
    assert not first.cache_hit and second.cache_hit
    assert second.library == first.library and second.library.stat().st_mtime_ns == mtime
    instance = random_instances(seed=1, count=1)[0]
    np.testing.assert_array_equal(first.solve(instance).step, second.solve(instance).step)


def test_missing_compiler_falls_back_with_a_warning(tmp_path):
    with pytest.warns(RuntimeWarning, match="in-process CasADi"):
        solver = qp.make_solver("codegen", cache_dir=tmp_path, compiler="no-such-cc")
    assert solver.backend == "casadi"


def test_bad_instances_and_backends_raise():
    good = hand_slide_instance(modes.Motion.HOLD)
    with pytest.raises(ValueError, match="rows must have shape"):
        qp.QPInstance(**{**_fields(good), "rows": np.zeros((11, 3)), "bounds": np.zeros(11)})
    with pytest.raises(ValueError, match="regularization must be positive"):
        qp.QPInstance(**{**_fields(good), "regularization": 0.0})
    with pytest.raises(ValueError, match="wrench must be finite"):
        qp.QPInstance(**{**_fields(good), "wrench": np.array([np.nan, 0.0, 0.0])})
    with pytest.raises(ValueError, match="unknown QP backend 'osqp'"):
        qp.make_solver("osqp")


def _fields(instance):
    return {f.name: getattr(instance, f.name) for f in dataclasses.fields(instance) if f.init}
