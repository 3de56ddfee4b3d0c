"""Pinocchio Panda with the hand plate: kinematics against MuJoCo, Jacobians, impedance mapping."""

from __future__ import annotations

import math

import mujoco
import numpy as np
import pinocchio as pin
import pytest

from panda_model import (
    ARM_JOINTS,
    FLANGE_LINK,
    NEUTRAL,
    HandPlate,
    Mount,
    arm_urdf,
    cartesian_stiffness,
    critical_damping,
    hand_jacobian,
    hand_placement,
    hand_pose,
    hand_rotation,
    hand_stiffness_to_world,
    hand_wrench,
    inverse_kinematics,
    joint_stiffness,
    load_panda,
    planar_jacobian,
    planar_stiffness,
    task_inertia,
    task_jacobian,
)


@pytest.fixture(scope="module")
def panda():
    return load_panda()


def random_configurations(panda, count: int, seed: int = 0) -> np.ndarray:
    rng = np.random.default_rng(seed)
    lower, upper = panda.model.lowerPositionLimit, panda.model.upperPositionLimit
    return rng.uniform(lower, upper, size=(count, panda.nq))


def test_arm_urdf_is_the_seven_joint_arm_with_absolute_meshes():
    model = pin.buildModelFromXML(arm_urdf())
    assert model.nq == 7
    assert [model.names[i] for i in range(1, 8)] == list(ARM_JOINTS)
    assert "package://" not in arm_urdf()
    assert "finger" not in arm_urdf() and "panda_hand" not in arm_urdf()


def test_flange_kinematics_match_mujoco_at_random_configurations():
    # MuJoCo compiles the same URDF with its own kinematics; both worlds coincide at a zero mount.
    panda = load_panda(mount=Mount(base_x=0.0, base_height=0.0, plane_y=0.0))
    spec = mujoco.MjSpec.from_string(arm_urdf())
    spec.compiler.fusestatic = False
    model = spec.compile()
    data = mujoco.MjData(model)
    qpos = [model.jnt_qposadr[model.joint(name).id] for name in ARM_JOINTS]
    for q in random_configurations(panda, 20):
        data.qpos[qpos] = q
        mujoco.mj_kinematics(model, data)
        pin.framesForwardKinematics(panda.model, panda.data, q)
        flange = panda.data.oMf[panda.flange_frame]
        np.testing.assert_allclose(flange.translation, data.body(FLANGE_LINK).xpos, atol=1e-9)
        np.testing.assert_allclose(flange.rotation, data.body(FLANGE_LINK).xmat.reshape(3, 3), atol=1e-9)


def test_hand_frame_is_the_plate_face_on_the_flange(panda):
    q = random_configurations(panda, 1, seed=2)[0]
    hand = hand_placement(panda, q)
    flange = panda.data.oMf[panda.flange_frame]
    plate = panda.hand
    np.testing.assert_allclose(
        hand.translation, flange.act(np.array([0.0, 0.0, plate.thickness])), atol=1e-12
    )
    np.testing.assert_allclose(hand.rotation[:, 2], flange.rotation[:, 2], atol=1e-12)  # e_n along flange z


def test_hand_frame_axes_follow_the_planar_conventions(panda):
    q = inverse_kinematics(panda, (0.0, 0.15, 0.0))
    rot = hand_placement(panda, q).rotation
    np.testing.assert_allclose(rot[:, 2], [0.0, 0.0, -1.0], atol=1e-6)  # e_n points down at θ = 0
    np.testing.assert_allclose(rot[:, 0], [1.0, 0.0, 0.0], atol=1e-6)  # e_t along +x
    # A CCW planar rotation is a rotation about MuJoCo (0, -1, 0): the hinge axis of docs/architecture.md §3.
    tilted = hand_rotation(0.3)
    np.testing.assert_allclose(tilted, pin.exp3(np.array([0.0, -0.3, 0.0])) @ hand_rotation(0.0), atol=1e-12)


def finite_difference_columns(function, q: np.ndarray, step: float = 1e-6):
    """Central differences of ``function`` along every joint: yields (joint, plus, minus)."""
    for i in range(len(q)):
        dq = np.zeros(len(q))
        dq[i] = step
        yield i, function(q + dq), function(q - dq)


def test_jacobian_matches_finite_differences_of_forward_kinematics(panda):
    step = 1e-6
    for q in random_configurations(panda, 5, seed=1):
        jac = hand_jacobian(panda, q)
        for i, plus, minus in finite_difference_columns(lambda x: hand_placement(panda, x), q, step):
            linear = (plus.translation - minus.translation) / (2 * step)
            angular = pin.log3(plus.rotation @ minus.rotation.T) / (2 * step)
            np.testing.assert_allclose(jac[:3, i], linear, atol=1e-6)
            np.testing.assert_allclose(jac[3:, i], angular, atol=1e-6)


@pytest.mark.parametrize("pose", [(0.0, 0.1, 0.0), (0.1, 0.05, 0.4), (-0.15, 0.3, -0.9)])
def test_planar_jacobian_matches_finite_differences_of_the_planar_pose(panda, pose):
    # J_p is the derivative of the planar pose wherever the plate lies in the work plane.
    step = 1e-6
    q = inverse_kinematics(panda, pose)
    planar = planar_jacobian(panda, q)
    for i, plus, minus in finite_difference_columns(lambda x: hand_pose(panda, x), q, step):
        np.testing.assert_allclose(planar[:, i], (plus - minus) / (2 * step), atol=1e-6)


@pytest.mark.parametrize("pose", [(0.0, 0.1, 0.0), (0.08, 0.06, 0.3), (-0.1, 0.25, -0.6)])
def test_inverse_kinematics_reaches_planar_poses_in_the_plane(panda, pose):
    q = inverse_kinematics(panda, pose)
    np.testing.assert_allclose(hand_pose(panda, q), pose, atol=1e-7)
    placement = hand_placement(panda, q)
    assert abs(placement.translation[1] - panda.mount.plane_y) < 1e-7
    np.testing.assert_allclose(placement.rotation, hand_rotation(pose[2]), atol=1e-7)
    assert np.all(q >= panda.model.lowerPositionLimit) and np.all(q <= panda.model.upperPositionLimit)


def test_cartesian_gains_realise_the_requested_planar_stiffness_through_the_arm(panda):
    requested = hand_stiffness_to_world(np.diag([2500.0, 1500.0, 60.0]), 0.4)
    stiffness = cartesian_stiffness(requested)
    for q in [inverse_kinematics(panda, (0.05, 0.12, 0.4)), NEUTRAL]:
        jac = task_jacobian(hand_jacobian(panda, q))
        realised = planar_stiffness(jac[:3], joint_stiffness(jac, stiffness, null_stiffness=5.0))
        np.testing.assert_allclose(realised, requested, rtol=1e-8, atol=1e-8)


def test_planar_stiffness_of_a_joint_stiffness_is_the_inverse_planar_compliance(panda):
    # A wrench w at the hand deflects the joints by K_q⁻¹ J_pᵀ w and the hand by J_p K_q⁻¹ J_pᵀ w.
    q = inverse_kinematics(panda, (0.0, 0.15, -0.2))
    jac = planar_jacobian(panda, q)
    k_q = np.diag([300.0, 250.0, 200.0, 150.0, 40.0, 30.0, 10.0])
    wrench = np.array([3.0, -2.0, 0.1])
    deflection = jac @ np.linalg.solve(k_q, jac.T @ wrench)
    np.testing.assert_allclose(planar_stiffness(jac, k_q) @ deflection, wrench, rtol=1e-10)


def test_critical_damping_gives_unit_damping_ratio_per_mode(panda):
    q = inverse_kinematics(panda, (0.0, 0.15, 0.0))
    inertia, stiffness = task_inertia(panda, q), cartesian_stiffness(np.diag([2000.0, 2000.0, 60.0]))
    damping = critical_damping(stiffness, inertia, ratio=1.0)
    # Λẍ + Dẋ + Kx = 0 is critically damped: every eigenvalue of its state matrix is real, double.
    state = np.block(
        [
            [np.zeros((6, 6)), np.eye(6)],
            [-np.linalg.solve(inertia, stiffness), -np.linalg.solve(inertia, damping)],
        ]
    )
    eigenvalues = np.linalg.eigvals(state)
    assert np.abs(eigenvalues.imag).max() < 1e-3 * np.abs(eigenvalues).max()


def test_hand_wrench_of_a_free_plate_is_zero_at_any_orientation():
    plate = HandPlate(mass=0.7, thickness=0.03)
    rng = np.random.default_rng(3)
    for _ in range(5):
        rot = pin.exp3(rng.normal(size=3))
        weight_in_flange = rot.T @ np.array([0.0, 0.0, -plate.mass * 9.81])
        sensed = np.concatenate((-weight_in_flange, -np.cross(plate.centre_of_mass, weight_in_flange)))
        np.testing.assert_allclose(hand_wrench(sensed, rot, plate), 0.0, atol=1e-12)


@pytest.mark.parametrize(
    ("build", "message"),
    [
        (lambda: HandPlate(mass=-1.0), "mass"),
        (lambda: HandPlate(half_length=0.0), "half_length"),
        (lambda: HandPlate(mount_angle=math.nan), "mount_angle"),
        (lambda: Mount(base_x=math.inf), "base_x"),
        (lambda: load_panda(armature=-0.1), "armature"),
        (lambda: cartesian_stiffness(np.diag([2000.0, -1.0, 60.0])), "positive definite"),
        (lambda: cartesian_stiffness(np.eye(2)), "3×3"),
        (lambda: cartesian_stiffness(np.eye(3), out_of_plane=(1.0, 0.0, 1.0)), "out_of_plane"),
        (lambda: cartesian_stiffness([[1.0, 2.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]]), "symmetric"),
        (lambda: critical_damping(np.eye(6), np.eye(6), ratio=-1.0), "ratio"),
        (lambda: planar_stiffness(np.ones((2, 7)), np.eye(7)), "J_p"),
        (lambda: hand_wrench(np.zeros(3), np.eye(3), HandPlate()), "6-vector"),
    ],
)
def test_bad_parameters_raise_clear_value_errors(build, message):
    with pytest.raises(ValueError, match=message):
        build()


def test_inverse_kinematics_rejects_unreachable_and_malformed_poses(panda):
    with pytest.raises(ValueError, match="workspace"):
        inverse_kinematics(panda, (1.5, 0.1, 0.0), max_iterations=50)
    with pytest.raises(ValueError, match="pose"):
        inverse_kinematics(panda, (0.0, 0.1))
    with pytest.raises(ValueError, match="seed"):
        inverse_kinematics(panda, (0.0, 0.1, 0.0), seed=np.zeros(6))
