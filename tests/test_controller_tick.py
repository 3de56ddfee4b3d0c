"""The compiled controller tick (:mod:`ccopt.control.tick`) against the reference path
(:meth:`Controller.build_instance` solved by the code-generated QP, then :meth:`Controller.update`'s
checks in NumPy), on every tick of a closed-loop run of the paper goals and on variants of them that
reach every branch: each motion, slides begun and not, force and tangential targets given or not, the
statics margin unknown, infinite or finite, the naive ``v_θ``, an anisotropic hand.

The two paths differ only in rounding (NumPy's products go through BLAS), so they agree to ~1e-15 on
the instance and, through the QP, to ~1e-10 on the step."""

from __future__ import annotations

import dataclasses
import math
from collections import Counter

import numpy as np
import pytest

from ccopt import closed_loop
from ccopt.control import tick
from ccopt.control.controller import Command, ControlInput, Controller, ControllerParams
from ccopt.control.qp import make_solver
from ccopt.hand import Hand
from ccopt.modes import Motion
from ccopt.objects import make_object
from ccopt.schedule import load_schedule

INSTANCE_RTOL = 1e-12
STEP_RTOL = 1e-9


@pytest.fixture(scope="module")
def recorded() -> tuple[closed_loop.LoopParams, list[tuple[ControlInput, Command]]]:
    """The controller's inputs on every tick of the `paper` goals on the paper triangle (planar, 30 Hz)."""
    params = closed_loop.LoopParams()
    inputs: list[tuple[ControlInput, Command]] = []
    update = Controller.update

    def capture(self: Controller, state: ControlInput, command: Command) -> object:
        inputs.append((state, command))
        return update(self, state, command)

    with pytest.MonkeyPatch.context() as patch:
        patch.setattr(Controller, "update", capture)
        closed_loop.run(make_object("paper-triangle"), load_schedule("paper"), params, seed=0)
    return params, inputs


def variants(state: ControlInput, command: Command) -> list[tuple[ControlInput, Command]]:
    """The tick and its variants along every input the compiled tick branches on."""
    replace = dataclasses.replace
    out = [(state, command)]
    out.append((replace(state, force_target=None, tangential_target=None, statics_margin=None), command))
    out.append((replace(state, force_target=12.5, tangential_target=-0.7, statics_margin=0.8), command))
    out.append((replace(state, statics_margin=math.inf), command))
    out.append((replace(state, s_h=math.nan, d=math.nan), command))
    out.append((replace(state, tangential_target=None), replace(command, wrench=state.wrench + 0.3)))
    out.append((state, replace(command, motion=Motion.HOLD)))
    out.append((state, replace(command, start=None)))
    return out


def differ(fast: np.ndarray, reference: np.ndarray) -> float:
    """The largest difference relative to the reference's largest magnitude."""
    fast, reference = np.asarray(fast, dtype=float), np.asarray(reference, dtype=float)
    scale = float(np.max(np.abs(reference)))
    return float(np.max(np.abs(fast - reference))) / scale if scale > 0.0 else float(np.max(np.abs(fast)))


def compare(fast: Controller, reference: Controller, ticks: list[tuple[ControlInput, Command]]) -> Counter:
    """Assert that both paths give the same output on each tick; count the cases seen."""
    cases: Counter = Counter()
    for state, command in ticks:
        ours, theirs = fast.update(state, command), reference.update(state, command)
        cases[command.motion, reference._slide_begun(state, command), ours.solved] += 1
        assert ours.solved == theirs.solved and ours.solution.feasible == theirs.solution.feasible
        assert differ(ours.packed, theirs.packed) <= INSTANCE_RTOL, (state, command)
        assert differ(ours.step, theirs.step) <= STEP_RTOL, (state, command)
        assert differ(ours.solution.step, theirs.solution.step) <= STEP_RTOL
        assert differ(ours.solution.wrench_change, theirs.solution.wrench_change) <= STEP_RTOL
        assert ours.solution.slack == pytest.approx(theirs.solution.slack, rel=STEP_RTOL, abs=1e-12)
    return cases


def test_the_compiled_tick_gives_the_reference_step_on_every_closed_loop_tick(recorded):
    params, inputs = recorded
    args = (params.hand, params.control_period, params.controller_params)
    fast, reference = Controller(*args), Controller(*args, solver=make_solver("codegen"))
    assert fast.solver is None and reference.solver is not None
    ticks = [variant for state, command in inputs for variant in variants(state, command)]
    cases = compare(fast, reference, ticks)
    motions = {(motion, begun) for motion, begun, _ in cases}
    assert motions == set(tick.CASES)  # every case's function, on a real tick or a variant of one


def test_an_anisotropic_hand_and_the_paper_rate_give_the_reference_step(recorded):
    """``K`` in the hand frame then turns with the hand angle: it is an input of every tick."""
    _, inputs = recorded
    hand = Hand(stiffness=(2000.0, 1400.0, 60.0))
    fast = Controller(hand, 0.001, ControllerParams())
    reference = Controller(hand, 0.001, ControllerParams(), solver=make_solver("codegen"))
    compare(fast, reference, inputs[::5])


def test_a_failed_solve_holds_the_target_like_the_reference(recorded):
    """Inputs DAQP cannot solve (forces of 1e300 N) or that are not numbers: no motion, no stale step
    of an earlier tick, infinite slack, the tick's instance kept."""
    _, inputs = recorded
    state, command = inputs[len(inputs) // 2]
    fast, reference = Controller(), Controller(solver=make_solver("codegen"))
    fast.update(state, command)  # an earlier, solved tick: its outputs must not leak into the next
    for wrench in ([1e300, 1e300, 0.0], [math.nan, 0.0, 0.0]):
        bad = dataclasses.replace(state, wrench=np.array(wrench))
        ours, theirs = fast.update(bad, command), reference.update(bad, command)
        assert not ours.solved and not theirs.solved
        np.testing.assert_array_equal(ours.step, np.zeros(3))
        assert ours.solution.slack == math.inf and not ours.solution.feasible
        np.testing.assert_allclose(ours.packed, theirs.packed, rtol=INSTANCE_RTOL)


def test_without_a_compiler_the_same_functions_run_in_process(recorded, tmp_path, monkeypatch):
    _, inputs = recorded
    with pytest.warns(RuntimeWarning, match="evaluating it in process"):
        in_process = tick.load_tick_functions(tmp_path, "no-such-cc")
    assert in_process[1] == "casadi" and set(in_process[0]) == set(tick.CASES)
    compiled = Controller()
    monkeypatch.setattr(tick, "load_tick_functions", lambda *_: in_process)
    evaluated = Controller()
    for state, command in inputs[::20]:
        ours, theirs = evaluated.update(state, command), compiled.update(state, command)
        assert ours.solution.backend == "casadi" and theirs.solution.backend == "codegen"
        assert differ(ours.step, theirs.step) <= 1e-12


def test_the_instance_unpacks_to_the_reference_instance(recorded):
    _, inputs = recorded
    controller = Controller()
    for state, command in inputs[::50]:
        built = controller.build_instance(state, command)
        assert (len(built.rows), len(built.directions)) == (tick.N_ROWS, tick.N_TERMS)
        unpacked = controller.update(state, command).instance
        for field in ("stiffness", "wrench", "rows", "bounds", "gains", "active", "directions", "weights"):
            assert differ(getattr(unpacked, field), getattr(built, field)) <= INSTANCE_RTOL, field
