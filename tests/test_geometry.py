"""Conventions of ccopt.geometry against closed forms."""

import casadi as ca
import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st

from ccopt import geometry

angles = st.floats(-np.pi, np.pi, allow_nan=False)


@given(angles)
def test_tangent_is_normal_rotated_by_plus_90_degrees(theta):
    np.testing.assert_allclose(
        geometry.rotation(np.pi / 2) @ geometry.hand_normal(theta), geometry.hand_tangent(theta), atol=1e-12
    )


def test_flat_hand_pushes_down_into_the_object():
    np.testing.assert_allclose(geometry.hand_normal(0.0), [0.0, -1.0])
    world = geometry.wrench_hand_to_world(0.0, [5.0, 0.0, 0.0])
    np.testing.assert_allclose(world, [0.0, -5.0, 0.0])


@given(angles, st.lists(st.floats(-50, 50), min_size=3, max_size=3))
def test_wrench_and_twist_transforms_are_inverse(theta, vector):
    world = geometry.wrench_hand_to_world(theta, vector)
    np.testing.assert_allclose(geometry.wrench_world_to_hand(theta, world), vector, atol=1e-9)
    np.testing.assert_allclose(
        geometry.twist_world_to_hand(theta, geometry.twist_hand_to_world(theta, vector)), vector, atol=1e-9
    )


@given(angles, st.lists(st.floats(-50, 50), min_size=3, max_size=3))
def test_twists_in_floats_are_the_hand_frame_matrix(theta, vector):
    """The float transforms agree with the frame ``[e_n e_t]`` of :func:`geometry.hand_normal` and
    :func:`geometry.hand_tangent` (NumPy), not merely with each other."""
    frame = geometry.hand_frame(theta)
    dn, dt, dtheta = vector
    expected = [*(frame @ [dn, dt]), dtheta]
    np.testing.assert_allclose(geometry.twist_hand_to_world(theta, vector), expected, rtol=0, atol=1e-12)
    expected = [*(frame.T @ [dn, dt]), dtheta]
    np.testing.assert_allclose(geometry.twist_world_to_hand(theta, vector), expected, rtol=0, atol=1e-12)
    axes = geometry.hand_axes(theta)
    np.testing.assert_allclose(geometry.world_to_hand(axes, dn, dt), frame.T @ [dn, dt], rtol=0, atol=1e-12)


def test_symbolic_frame_matches_numeric():
    theta = ca.SX.sym("theta")
    frame = ca.Function("frame", [theta], [geometry.hand_frame(theta)])
    np.testing.assert_allclose(np.array(frame(0.7)), geometry.hand_frame(0.7))


def test_shift_torque_is_the_cross_product():
    wrench = np.array([3.0, -4.0, 0.5])
    a, b = np.array([0.1, 0.2]), np.array([-0.3, 0.05])
    arm = a - b
    expected = 0.5 + arm[0] * wrench[1] - arm[1] * wrench[0]
    assert geometry.shift_torque(wrench, a, b)[2] == pytest.approx(expected)


@given(angles, st.floats(-0.08, 0.08), st.floats(0.01, 0.2), st.floats(-0.5, 0.5))
def test_contact_coordinates_invert_the_kinematics(theta, s_h, d, x_o):
    r_o = np.array([x_o, 0.0])
    pose = geometry.hand_pose_from_contact(theta, s_h, d, r_o)
    assert geometry.contact_coordinates(pose, r_o) == pytest.approx((s_h, d), abs=1e-12)


def test_square_area_centroid_and_inertia():
    side, mass = 0.1, 0.3
    square = np.array([[0, 0], [side, 0], [side, side], [0, side]]) + 0.2
    assert geometry.signed_area(square) == pytest.approx(side**2)
    np.testing.assert_allclose(geometry.centroid(square), [0.25, 0.25])
    assert geometry.lamina_inertia(square, mass) == pytest.approx(mass * side**2 / 6.0)


def test_equilateral_triangle_inertia():
    side, mass = 0.13, 0.2
    triangle = np.array([[0, 0], [side, 0], [side / 2, side * np.sqrt(3) / 2]])
    assert geometry.lamina_inertia(triangle, mass) == pytest.approx(mass * side**2 / 12.0)


def test_convexity():
    square = [[0, 0], [1, 0], [1, 1], [0, 1]]
    assert geometry.is_convex(square)
    assert geometry.is_convex(square[::-1])
    assert not geometry.is_convex([[0, 0], [2, 0], [1, 0.2], [1, 1]])
    star = [[np.cos(a), np.sin(a)] for a in np.arange(5) * 4 * np.pi / 5]
    assert not geometry.is_convex(star)


def test_bad_polygons_raise():
    with pytest.raises(ValueError, match="at least 3"):
        geometry.as_polygon([[0, 0], [1, 0]])
    with pytest.raises(ValueError, match="finite"):
        geometry.as_polygon([[0, 0], [1, np.nan], [0, 1]])


def test_lowest_vertex_is_the_left_most_of_those_within_the_tie_of_the_lowest():
    """Against the rule written out on each polygon: random ones, with vertices moved onto the
    lowest's height, within the tie of it and just beyond it."""
    rng = np.random.default_rng(8)
    for _ in range(500):
        vertices = rng.uniform(-0.1, 0.1, (int(rng.integers(3, 9)), 2))
        low = vertices[:, 1].min()
        for k in rng.choice(len(vertices), 2, replace=False):
            vertices[k, 1] = low + rng.choice((0.0, 0.5, 2.0)) * geometry.LOWEST_TIE
        ties = [k for k, (_, y) in enumerate(vertices) if y <= vertices[:, 1].min() + geometry.LOWEST_TIE]
        expected = min(ties, key=lambda k: (vertices[k, 0], k))
        assert geometry.lowest_vertex(vertices) == expected
        assert geometry.lowest_of(*vertices.T.tolist()) == expected
