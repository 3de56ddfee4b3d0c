"""The contact model against finite differences, closed forms and hand-made wrenches."""

import casadi as ca
import numpy as np
import pytest

from ccopt import contact, geometry
from ccopt.contact import Row

MU_H, MU_G, L_H, MASS = 0.5, 0.8, 0.05, 0.3
WEIGHT = MASS * geometry.GRAVITY


@pytest.mark.parametrize("theta_o", [-0.6, 0.0, 0.35, 1.1])
@pytest.mark.parametrize(("s_h", "d"), [(0.0, 0.08), (0.03, 0.05), (-0.04, 0.12)])
def test_admissible_motions_are_finite_differences_of_the_kinematics(theta_o, s_h, d):
    y_o, s_g, h = 0.0, 0.2, 1e-6

    def pose(theta, slide_h, slide_g):
        return geometry.hand_pose_from_contact(theta, slide_h, d, [slide_g, y_o])

    columns = []
    for k in range(3):
        step = np.zeros(3)
        step[k] = h
        args_plus = np.array([theta_o, s_h, s_g]) + step
        args_minus = np.array([theta_o, s_h, s_g]) - step
        world = (pose(*args_plus) - pose(*args_minus)) / (2 * h)
        columns.append(geometry.twist_world_to_hand(theta_o, world))
    np.testing.assert_allclose(
        contact.admissible_motions(theta_o, s_h, d), np.column_stack(columns), atol=1e-8
    )


def test_admissible_motions_match_the_paper():
    """v_θ = [−d, s_h, 1] and v_h = [−1, 0, 0] in the paper's (t, n, θ) order; v_g = world x."""
    theta, s_h, d = 0.3, 0.02, 0.07
    v = contact.admissible_motions(theta, s_h, d)
    t_n_theta = [1, 0, 2]
    np.testing.assert_allclose(v[t_n_theta, 0], [-d, s_h, 1.0], atol=1e-12)
    np.testing.assert_allclose(v[t_n_theta, 1], [-1.0, 0.0, 0.0], atol=1e-12)
    np.testing.assert_allclose(geometry.twist_hand_to_world(theta, v[:, 2]), [1.0, 0.0, 0.0], atol=1e-12)


def margins(wrench, theta=0.0):
    return contact.complementarity_margins(wrench, theta, MU_H, MU_G, L_H, MASS)


def test_wrench_inside_the_cone_has_positive_margins():
    assert np.all(margins([10.0, 1.0, 0.05]) > 0.0)


@pytest.mark.parametrize(
    ("wrench", "tight"),
    [
        # Friction pointing −e_t on the object: the object slides +e_t relative to the hand, ṡ_h > 0.
        ([10.0, -MU_H * 10.0, 0.0], Row.HAND_SLIDE_POS),
        ([10.0, MU_H * 10.0, 0.0], Row.HAND_SLIDE_NEG),
        # All force at the +e_t end (τ = −l f_n): the object turns CCW about that end, Δθ > 0.
        ([10.0, 0.0, -L_H * 10.0], Row.HAND_PIVOT_POS),
        ([10.0, 0.0, L_H * 10.0], Row.HAND_PIVOT_NEG),
    ],
)
def test_hand_faces(wrench, tight):
    lhs = margins(wrench)
    assert lhs[tight] == pytest.approx(0.0, abs=1e-12)
    assert np.all(np.delete(lhs, tight) > 0.0)


@pytest.mark.parametrize("direction", [1, -1])
def test_ground_faces(direction):
    """A hand force that makes the ground reaction lie on its friction cone edge, pushing ±x."""
    push_down = 20.0
    ground_normal = push_down + WEIGHT  # ground reaction, vertical component
    f_world = np.array([direction * MU_G * ground_normal, -push_down])  # net horizontal push ±x
    wrench = geometry.wrench_world_to_hand(0.0, [*f_world, 0.0])
    lhs = margins(wrench)
    blocked = Row.GROUND_SLIDE_POS if direction > 0 else Row.GROUND_SLIDE_NEG
    other = Row.GROUND_SLIDE_NEG if direction > 0 else Row.GROUND_SLIDE_POS
    assert lhs[blocked] == pytest.approx(0.0, abs=1e-9)
    assert lhs[other] > 0.0


def test_ground_rows_rotate_with_the_hand():
    """A world-frame force has the same ground margins whatever the hand angle it is measured at."""
    f_world = np.array([3.0, -15.0])
    for theta in (-0.5, 0.2, 0.9):
        wrench = geometry.wrench_world_to_hand(theta, [*f_world, 0.0])
        np.testing.assert_allclose(margins(wrench, theta)[4:], margins([15.0, 3.0, 0.0])[4:], atol=1e-9)


def test_equilibrium_residual_of_a_static_square():
    """A square of side a resting on a vertex pushed by a known wrench: forces and torques balance."""
    side, theta = 0.1, 0.3
    r_o = np.array([0.0, 0.0])
    rot = geometry.rotation(theta)
    square = np.array([[0, 0], [side, 0], [side, side], [0, side]]) @ rot.T
    r_com = square.mean(axis=0)
    hand_pose = np.array([*square[[2, 3]].mean(axis=0), theta])
    f_grav = contact.weight(MASS)
    # choose f_n; solve the torque balance about r_o for the tangential force
    f_n = 10.0
    e_n, e_t = geometry.hand_normal(theta), geometry.hand_tangent(theta)
    arm = hand_pose[:2] - r_o

    def moment(r, f):
        return r[0] * f[1] - r[1] * f[0]

    f_t = -(moment(arm, f_n * e_n) + moment(r_com - r_o, f_grav)) / moment(arm, e_t)
    f_hand = f_n * e_n + f_t * e_t
    f_ground = -(f_hand + f_grav)
    residual = contact.equilibrium_residual(hand_pose, [f_n, f_t, 0.0], f_ground, r_o, r_com, f_grav)
    np.testing.assert_allclose(np.array(residual).ravel(), 0.0, atol=1e-12)


@pytest.mark.parametrize("function", contact.CONTACT_FUNCTIONS, ids=lambda f: f.name())
def test_symbolic_jacobians_match_central_differences(function):
    rng = np.random.default_rng(7)
    inputs = [ca.MX.sym(function.name_in(i), *function.size_in(i)) for i in range(function.n_in())]
    flat = ca.vertcat(*[ca.vec(x) for x in inputs])
    outputs = ca.vertcat(*[ca.vec(y) for y in function.call(inputs)])
    unflat = ca.Function("flat", [flat], [outputs, ca.jacobian(outputs, flat)])
    for _ in range(5):
        point = rng.uniform(-1.0, 1.0, flat.shape[0])
        _, jacobian = (np.array(v) for v in unflat(point))
        h = 1e-6
        finite = np.column_stack(
            [
                (np.array(unflat(point + h * e)[0]) - np.array(unflat(point - h * e)[0])).ravel() / (2 * h)
                for e in np.eye(len(point))
            ]
        )
        np.testing.assert_allclose(jacobian, finite, rtol=1e-6, atol=1e-8)


def test_numeric_wrappers_give_each_thread_its_own_buffers():
    # the module-level wrappers are shared by the threads of a Dask worker
    from concurrent.futures import ThreadPoolExecutor

    masses = np.linspace(0.1, 2.0, 64)

    def cone(mass: float) -> np.ndarray:
        rows, bounds = contact.model_friction_cone(0.2, 0.5, 0.8, 0.03, mass)
        return np.column_stack([rows, bounds])

    serial = [cone(mass) for mass in masses]
    for _ in range(20):
        with ThreadPoolExecutor(4) as pool:
            for threaded, expected in zip(pool.map(cone, masses), serial, strict=True):
                np.testing.assert_array_equal(threaded, expected)


def test_patch_torque_margins_are_the_cut_rows_margins():
    """The plain-float margins of a patch against :data:`ccopt.contact.patch_torque_rows` (CasADi),
    with the patch's ends on the hand ``(u_low + s_h, u_high + s_h)`` inside the hand, and their sign
    against the centre of pressure ``c = −τ/f_n`` lying in the patch."""
    rng = np.random.default_rng(3)
    for _ in range(200):
        s_h, f_n, c = rng.uniform(-0.03, 0.03), rng.uniform(1.0, 30.0), rng.uniform(-0.05, 0.05)
        face = np.sort(rng.uniform(-0.04, 0.04, 2) - s_h)
        low, high = face + s_h  # inside the hand [−L_H, L_H]: the hand's own rows cut nothing
        wrench = np.array([f_n, rng.uniform(-5.0, 5.0), -c * f_n])
        rows = np.array(contact.patch_torque_rows(L_H, s_h, face))
        margins = contact.patch_torque_margins(f_n, wrench[2], low, high)
        np.testing.assert_allclose(margins, -rows @ wrench, rtol=1e-12, atol=1e-12)
        assert (margins[0] > 0) == (c < high) and (margins[1] > 0) == (c > low)
