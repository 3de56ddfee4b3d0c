"""One controller tick against the contact model: it moves along the right direction, inside the cone."""

import dataclasses

import numpy as np
import pytest
from scipy.optimize import minimize_scalar

from ccopt import contact
from ccopt.contact import Row
from ccopt.control.controller import Command, ControlInput, Controller, ControllerParams, quasi_static_maps
from ccopt.control.qp import make_solver
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


def test_the_predicted_wrench_is_the_quasi_static_equilibrium():
    """``P Δx`` against a direct minimisation of the impedance's energy over the free pivot
    ``q`` (hand pose ``x_h + v_θ q``): the equilibrium of a target change."""
    stiffness = Hand().stiffness_in_hand_frame(THETA)
    v_theta = contact.admissible_motions(THETA, S_H, D)[:, :1]
    motion_map, wrench_map = quasi_static_maps(stiffness, v_theta, v_theta.T)
    rng = np.random.default_rng(3)
    for _ in range(5):
        step = rng.normal(scale=[2e-3, 2e-3, 0.02])

        def energy(q: float, step: np.ndarray = step) -> float:
            spring = step - v_theta[:, 0] * q
            return 0.5 * spring @ stiffness @ spring

        q = minimize_scalar(energy, bounds=(-1.0, 1.0), method="bounded", options={"xatol": 1e-12}).x
        np.testing.assert_allclose(motion_map @ step, [q], atol=1e-7)
        np.testing.assert_allclose(wrench_map @ step, stiffness @ (step - v_theta[:, 0] * q), atol=1e-4)


def test_a_tangential_push_turns_the_target_to_keep_the_moment_balanced(controller):
    """Before a commanded hand slide begins, the controller pushes the wrench past the friction row
    while the moment about the ground contact (``v_θ·w``) stays where it is: no roll."""
    current = state(wrench=(10.0, -4.0, -0.2))
    goal = np.array([THETA, S_H + 0.01, S_G])
    output = controller.update(current, Command(Motion.SLIDE_HAND_POS, goal, start=current.coordinates))
    v_theta = contact.admissible_motions(THETA, S_H, D)[:, 0]
    change = output.solution.wrench_change
    assert change[1] < 0.0  # more tangential force the way the hand slides (f_t < 0 for ṡ_h > 0)
    assert abs(v_theta @ change) < 1e-6 * np.linalg.norm(change)
    assert np.all(np.delete(predicted_margins(output, current), Row.HAND_SLIDE_POS) > 0.0)


def test_a_sliding_hand_moves_along_the_face_on_its_friction_boundary(controller):
    rows, _ = contact.model_friction_cone(THETA, MU_H, MU_G, L_H, MASS)
    on_face = (10.0, -MU_H * 10.0, -0.2)  # μ_h f_n + f_t = 0: sliding towards +s_h
    current = state(wrench=on_face)
    start = current.coordinates - np.array([0.0, 0.002, 0.0])  # it has slid 2 mm already
    goal = np.array([THETA, S_H + 0.008, S_G])
    output = controller.update(current, Command(Motion.SLIDE_HAND_POS, goal, start=start))
    change = output.solution.wrench_change
    assert rows[Row.HAND_SLIDE_POS] @ change == pytest.approx(0.0, abs=1e-6)  # stays on the face
    v_h = contact.admissible_motions(THETA, S_H, D)[:, 1]
    assert output.step @ v_h > 0.0


def test_normal_force_is_regulated_towards_its_target(controller):
    light = controller.update(
        state(wrench=(4.0, 0.0, 0.0)), Command(Motion.HOLD, np.array([THETA, S_H, S_G]))
    )
    heavy = controller.update(
        state(wrench=(20.0, 0.0, 0.0)), Command(Motion.HOLD, np.array([THETA, S_H, S_G]))
    )
    assert light.solution.wrench_change[0] > 0.0 > heavy.solution.wrench_change[0]


def pivot_direction(controller, s_h, d):
    """The QP's pivot term direction for ``v_θ(s_h, d)``: ``Δq = vᵀKΔx / vᵀKv`` in the QP's units."""
    v_theta = contact.admissible_motions(THETA, s_h, d)[:, 0]
    stiffness = Hand().stiffness_in_hand_frame(THETA)
    expected = stiffness @ v_theta / (v_theta @ stiffness @ v_theta)
    return expected * controller.step_units / controller.params.angle_unit  # Δx = units · y


def test_naive_v_theta_before_the_kinematics_are_even_roughly_known(controller):
    current = dataclasses.replace(state(valid=False), s_h=np.nan, d=np.nan)
    goal = np.array([THETA + 0.1, S_H, S_G])
    instance = controller.build_instance(current, Command(Motion.PIVOT, goal))
    naive = pivot_direction(controller, 0.0, controller.params.d_guess)
    np.testing.assert_allclose(instance.directions[0], naive)


def test_a_rough_estimate_shapes_v_theta_before_the_kinematics_are_valid(controller):
    """Not yet valid, but ``s_h`` and ``d`` given (the loop's rough estimate): ``v_θ`` is theirs,
    the same as once valid, and not the naive one."""
    goal = np.array([THETA + 0.1, S_H, S_G])
    rough = dataclasses.replace(state(valid=False), s_h=-0.06, d=0.12)
    valid = dataclasses.replace(rough, kinematics_valid=True)
    command = Command(Motion.PIVOT, goal)
    directions = [controller.build_instance(s, command).directions[0] for s in (rough, valid)]
    np.testing.assert_allclose(directions[0], pivot_direction(controller, -0.06, 0.12))
    np.testing.assert_allclose(directions[0], directions[1])
    assert not np.allclose(directions[0], pivot_direction(controller, 0.0, controller.params.d_guess))


def test_bad_parameters_raise():
    with pytest.raises(ValueError, match="convergence_rate"):
        ControllerParams(convergence_rate=-1.0)
    with pytest.raises(ValueError, match="max_speed"):
        ControllerParams(max_speed=(0.1, 0.1))
    for speed in (0.0, -0.01, float("nan")):
        with pytest.raises(ValueError, match="slide_speed"):
            ControllerParams(slide_speed=speed)
    with pytest.raises(ValueError, match="force limits"):
        Controller(Hand(force_limits=(15.0, 25.0)), params=ControllerParams(normal_force=10.0))
    with pytest.raises(ValueError, match="period"):
        Controller(period=0.0)


class BrokenSolver:
    """A QP back end that fails as a numerical solver can: a step of NaN or infinity."""

    backend = "broken"

    def __init__(self, value: float) -> None:
        self.value = value

    def solve(self, instance):
        from ccopt.control.qp import QPSolution

        bad = np.full(3, self.value)
        return QPSolution(bad, bad, self.value, False, self.backend)


@pytest.mark.parametrize("value", [np.nan, np.inf, -np.inf])
def test_a_step_the_solver_got_wrong_holds_the_target_and_is_flagged_infeasible(value):
    """Issue 12: the controller checks that the solver's step is finite. It returns no motion (the
    target holds) and a solution flagged infeasible, never a NaN the plant would be driven with."""
    broken = Controller(params=ControllerParams(), solver=BrokenSolver(value))
    current = state()
    output = broken.update(current, Command(Motion.PIVOT, np.array([THETA + 0.1, S_H, S_G])))
    np.testing.assert_array_equal(output.step, np.zeros(3))
    assert not output.solved and not output.solution.feasible and output.solution.slack == np.inf
    np.testing.assert_array_equal(output.solution.wrench_change, np.zeros(3))


def violation(instance, step_task):
    """The largest violation of the instance's active rows by a step in the QP's units: the QP's own
    row ``γ nᵀ P Δy − t ≤ b − nᵀ w`` solved for ``t`` (0 if none is violated)."""
    active = np.asarray(instance.active, dtype=bool)
    rows, change = instance.rows[active], instance.stiffness @ step_task
    excess = instance.gains[active] * (rows @ change) - (instance.bounds[active] - rows @ instance.wrench)
    return max(0.0, float(excess.max(initial=0.0)))


def test_a_step_scaled_to_the_speed_limit_reports_its_own_wrench_change_and_slack():
    """Issue 12: the solution reported is the one of the step returned, not of the step before the
    controller scaled it down to its speed limit. The reference is the same tick without a limit."""
    current = state(wrench=(10.0, 3.0, 0.0))
    command = Command(Motion.PIVOT, np.array([THETA + 1.0, S_H, S_G]))
    free = Controller(params=ControllerParams(max_speed=(1e9, 1e9, 1e9))).update(current, command)
    limited = Controller(params=ControllerParams())
    output = limited.update(current, command)
    excess = np.max(np.abs(free.step) / (np.asarray(limited.params.max_speed) * limited.period))
    assert excess > 1.5  # the limit scaled this step
    np.testing.assert_allclose(output.step, free.step / excess, rtol=1e-9)
    np.testing.assert_allclose(output.solution.step, free.solution.step / excess, rtol=1e-9)
    np.testing.assert_allclose(output.solution.wrench_change, free.solution.wrench_change / excess, rtol=1e-9)
    assert violation(free.instance, free.solution.step) == pytest.approx(free.solution.slack, abs=1e-6)
    assert output.solution.slack == pytest.approx(violation(output.instance, output.solution.step), abs=1e-12)
    assert output.solution.feasible == (output.solution.slack <= 1e-7)


@pytest.mark.parametrize("path", ["compiled", "reference"])
@pytest.mark.parametrize(
    ("motion", "begun"),
    [(Motion.SLIDE_GROUND_POS, False), (Motion.SLIDE_GROUND_POS, True), (Motion.SLIDE_HAND_NEG, True)],
)
def test_a_slide_is_driven_no_faster_than_the_slide_speed(path, motion, begun):
    """A commanded slide's target moves at most ``slide_speed`` (m/s) along the hand's axes; any other
    motion keeps ``max_speed``. Reference: the same tick without any limit, scaled down as a whole to
    the slide's limits (the compiled tick and the NumPy path alike)."""
    solver = None if path == "compiled" else make_solver("codegen")
    current = state(wrench=(10.0, 3.0, 0.0))
    goal = current.coordinates + np.array([0.0, -0.02, 0.03])  # far: the step is limited
    start = current.coordinates - (np.array([0.0, 0.002, 0.002]) if begun else 0.0)
    command = Command(motion, goal, start=start)
    unlimited = ControllerParams(max_speed=(1e9, 1e9, 1e9), slide_speed=1e9)
    free = Controller(params=unlimited, solver=solver).update(current, command)
    params = ControllerParams(slide_speed=0.004)
    limited = Controller(params=params, solver=solver)
    limits = np.array([params.slide_speed, params.slide_speed, params.max_speed[2]]) * limited.period
    excess = np.max(np.abs(free.step) / limits)
    assert excess > 1.5  # the slide's limit scaled this step
    output = limited.update(current, command)
    np.testing.assert_allclose(output.step, free.step / excess, rtol=1e-9, atol=1e-15)
    pivot = Command(Motion.PIVOT, current.coordinates + np.array([0.5, 0.0, 0.0]))
    assert np.abs(limited.update(current, pivot).step[:2]).max() > 1.5 * limits[0]  # max_speed's
