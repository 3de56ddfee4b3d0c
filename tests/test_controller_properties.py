"""Controller hardening, by property (issue 12): any finite input gives a finite step, never an
exception other than ``ValueError``/``TypeError``; a tick the QP solver cannot solve to a finite step
moves nothing and says so (infeasible, infinite slack)."""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from ccopt import modes
from ccopt.control.controller import Command, ControlInput, Controller, ControllerParams
from ccopt.modes import Motion

EXAMPLES = settings(max_examples=2000, deadline=None, suppress_health_check=[HealthCheck.too_slow])

finite = st.one_of(
    st.floats(allow_nan=False, allow_infinity=False),
    st.sampled_from([0.0, -0.0, 5e-324, 1e-300, -1e-300, 1e300, -1e300, 1.7976931348623157e308]),
)


def vectors(size: int) -> st.SearchStrategy[np.ndarray]:
    return st.lists(finite, min_size=size, max_size=size).map(np.array)


@st.composite
def inputs(draw: st.DrawFn) -> tuple[ControlInput, Command]:
    """Any finite estimate-like input and command: values of any size, rows valid or not."""
    optional = st.none() | finite
    state = ControlInput(
        wrench=draw(vectors(3)),
        cone_rows=draw(vectors(18)).reshape(6, 3),
        cone_bounds=draw(vectors(6)),
        row_valid=np.array(draw(st.lists(st.booleans(), min_size=6, max_size=6))),
        mu_h=draw(finite),
        l_h=draw(finite),
        hand_angle=draw(finite),
        s_h=draw(finite),
        d=draw(finite),
        kinematics_valid=draw(st.booleans()),
        coordinates=draw(vectors(3)),
        force_target=draw(optional),
        tangential_target=draw(optional),
        statics_margin=draw(optional),
    )
    command = Command(draw(st.sampled_from(list(Motion))), draw(vectors(3)))
    return state, command


@pytest.fixture(scope="module")
def controller() -> Controller:
    return Controller(params=ControllerParams())


@pytest.mark.filterwarnings("ignore::RuntimeWarning")  # overflow on the way to a step it then refuses
@EXAMPLES
@given(inputs())
def test_any_finite_input_gives_a_finite_step_within_the_speed_limit(controller, case) -> None:
    state, command = case
    try:
        output = controller.update(state, command)
    except (ValueError, TypeError):
        return
    assert np.isfinite(output.step).all()
    largest = np.asarray(controller.params.max_speed) * controller.period * (1.0 + 1e-12)
    if modes.REMOVED_ROWS[command.motion]:  # a slide: no faster than the slide speed
        slide = controller.params.slide_speed * controller.period * (1.0 + 1e-12)
        largest[:2] = np.minimum(largest[:2], slide)
    assert (np.abs(output.step) <= largest).all()
    if not output.solved:  # the solver gave no finite step: nothing moves
        assert not output.solution.feasible and not output.step.any() and math.isinf(output.solution.slack)
