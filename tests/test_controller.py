"""One controller tick against the contact model: it moves along the right direction, inside the cone."""

import numpy as np
import pytest

from ccopt import contact
from ccopt.contact import Row
from ccopt.control.controller import Command, ControlInput, Controller, ControllerParams
from ccopt.hand import Hand
from ccopt.modes import Motion

THETA, S_H, S_G, D = 0.1, 0.01, 0.0, 0.08
MU_H, MU_G, L_H, MASS = 0.5, 0.8, 0.05, 0.3


@pytest.fixture(scope="module")
def controller():
    return Controller(params=ControllerParams())


def state(wrench=(10.0, 0.5, 0.0), valid=True):
    rows, bounds = contact.model_friction_cone(THETA, MU_H, MU_G, L_H, MASS)
    return ControlInput(
        wrench=np.array(wrench),
        cone_rows=rows,
        cone_bounds=bounds,
        row_valid=np.ones(6, dtype=bool),
        mu_h=MU_H,
        l_h=L_H,
        hand_angle=THETA,
        s_h=S_H,
        d=D,
        kinematics_valid=valid,
        coordinates=np.array([THETA, S_H, S_G]),
    )


def predicted_margins(output, current):
    rows, bounds = contact.model_friction_cone(THETA, MU_H, MU_G, L_H, MASS)
    return bounds - rows @ (current.wrench + output.solution.wrench_change)


@pytest.mark.parametrize("sign", [1.0, -1.0])
def test_pivot_moves_the_target_along_v_theta_and_keeps_sticking(controller, sign):
    current = state()
    goal = np.array([THETA + sign * np.deg2rad(7.2), S_H, S_G])
    output = controller.update(current, Command(Motion.PIVOT, goal))
    v_theta = contact.admissible_motions(THETA, S_H, D)[:, 0]
    assert output.solution.feasible
    assert np.sign(output.step @ v_theta) == sign
    assert np.all(predicted_margins(output, current) > 0.0)  # every contact keeps its mode


def test_hand_slide_drives_the_wrench_through_its_friction_face(controller):
    current = state(wrench=(10.0, -4.0, 0.0))  # already leaning on the slide-positive face
    goal = np.array([THETA, S_H + 0.01, S_G])
    output = controller.update(current, Command(Motion.SLIDE_HAND_POS, goal))
    margins = predicted_margins(output, current)
    v_h = contact.admissible_motions(THETA, S_H, D)[:, 1]
    assert output.step @ v_h > 0.0
    assert margins[Row.HAND_SLIDE_POS] < 0.0  # the removed row is crossed: the hand slides
    assert np.all(np.delete(margins, Row.HAND_SLIDE_POS) > 0.0)  # the ground keeps sticking


def test_normal_force_is_regulated_towards_its_target(controller):
    light = controller.update(
        state(wrench=(4.0, 0.0, 0.0)), Command(Motion.HOLD, np.array([THETA, S_H, S_G]))
    )
    heavy = controller.update(
        state(wrench=(20.0, 0.0, 0.0)), Command(Motion.HOLD, np.array([THETA, S_H, S_G]))
    )
    assert light.solution.wrench_change[0] > 0.0 > heavy.solution.wrench_change[0]


def test_naive_v_theta_before_the_kinematics_are_known(controller):
    current = state(valid=False)
    goal = np.array([THETA + 0.1, S_H, S_G])
    instance = controller.build_instance(current, Command(Motion.PIVOT, goal))
    naive = contact.admissible_motions(THETA, 0.0, controller.params.d_guess)[:, 0]
    np.testing.assert_allclose(instance.directions[0], naive)


def test_bad_parameters_raise():
    with pytest.raises(ValueError, match="convergence_rate"):
        ControllerParams(convergence_rate=-1.0)
    with pytest.raises(ValueError, match="max_speed"):
        ControllerParams(max_speed=(0.1, 0.1))
    with pytest.raises(ValueError, match="force limits"):
        Controller(Hand(force_limits=(15.0, 25.0)), params=ControllerParams(normal_force=10.0))
    with pytest.raises(ValueError, match="period"):
        Controller(period=0.0)
