"""Panda MuJoCo plant: kinematics, holding, hand impedance and wrist F/T, measured in the physics."""

from __future__ import annotations

import math

import mujoco
import numpy as np
import pytest

from ccopt import geometry
from ccopt.hand import Hand
from ccopt.objects import make_object
from ccopt.plant.base import Plant, StartConfig
from ccopt.plant.mujoco_panda import HAND_BODY, HAND_SITE, TARGET_JOINT_MARGIN, PandaParams, PandaPlant
from panda_model.impedance import joint_stiffness, planar_stiffness
from panda_model.model import hand_jacobian, hand_placement, inverse_kinematics, task_jacobian

SQUARE = make_object("square")


def lifted_plant(hand: Hand | None = None, lift=(0.0, 0.08, 0.0), settle: float = 1.5):
    """A plant whose hand target is moved by ``lift`` off its start (into free space), then settled."""
    plant = PandaPlant(SQUARE, None, StartConfig(settle_time=0.0), hand)
    plant.set_target(plant.hand_pose() + np.asarray(lift))
    plant.step(round(settle / plant.timestep))
    return plant


def hold_wrench(plant: PandaPlant, wrench, duration: float) -> np.ndarray:
    """Apply world ``(f_x, f_y, τ)`` to the plate at its face centre for ``duration`` s; final pose."""
    body = plant.model.body(HAND_BODY).id
    force = np.array([wrench[0], 0.0, wrench[1]])
    torque = np.array([0.0, -wrench[2], 0.0])  # CCW planar torque is about MuJoCo (0, -1, 0)
    for _ in range(round(duration / plant.timestep)):
        lever = plant.data.site(HAND_SITE).xpos - plant.data.xipos[body]
        plant.data.xfrc_applied[body, :3] = force
        plant.data.xfrc_applied[body, 3:] = torque + np.cross(lever, force)
        plant.step(1)
    plant.data.xfrc_applied[body] = 0.0
    return plant.hand_pose()


def test_plant_hand_site_is_the_pinocchio_hand_frame():
    plant = PandaPlant(SQUARE, start=StartConfig(settle_time=0.0))
    model, data = plant.model, mujoco.MjData(plant.model)
    qpos = slice(*[model.jnt_qposadr[model.joint(name).id] for name in ("panda_joint1", "panda_joint7")])
    rng = np.random.default_rng(0)
    lower, upper = plant.panda.model.lowerPositionLimit, plant.panda.model.upperPositionLimit
    for q in rng.uniform(lower, upper, size=(10, 7)):
        data.qpos[qpos.start : qpos.stop + 1] = q
        mujoco.mj_kinematics(model, data)
        hand = hand_placement(plant.panda, q)
        np.testing.assert_allclose(hand.translation, data.site(HAND_SITE).xpos, atol=1e-6)
        np.testing.assert_allclose(hand.rotation, data.site(HAND_SITE).xmat.reshape(3, 3), atol=1e-6)


def test_start_configuration_presses_the_object_like_the_protocol_says():
    plant = PandaPlant(SQUARE)
    assert isinstance(plant, Plant)
    assert plant.time == 0.0 and plant.timestep == pytest.approx(1e-3)
    truth = plant.truth()
    assert truth.in_contact_hand and truth.in_contact_ground
    assert (truth.hand_mode, truth.ground_mode, truth.hand_geometry) == (0, 0, 0)
    # At rest the hand wrench the wrist F/T reports is the impedance law w = K (x_tar − x_h).
    pose = plant.hand_pose()
    stiffness = plant.hand.stiffness
    impedance = geometry.wrench_world_to_hand(pose[2], np.multiply(stiffness, plant.target() - pose))
    np.testing.assert_allclose(plant.hand_wrench(), impedance, atol=0.02)
    assert plant.hand_wrench()[0] > 0.7 * StartConfig().normal_force


def test_a_start_off_the_ground_contact_holds_its_tilt():
    """The paper square started with the hand 50 mm off its ground contact: a pure normal push is
    a moment its weight does not balance, and the arm presses only after tens of milliseconds; with
    the equilibrium target (by the true statics) and the object held while the arm presses, it keeps
    its tilt and both contacts."""
    start = StartConfig(theta_o=0.3, s_h=-0.05)
    truth = PandaPlant(make_object("paper-square"), start=start).truth()
    assert truth.in_contact_hand and truth.in_contact_ground
    assert abs(truth.theta_o - start.theta_o) < math.radians(1.0)


@pytest.mark.parametrize(
    ("obj", "start"),
    [(SQUARE, StartConfig()), (make_object("hexagon"), StartConfig(theta_o=-0.25, normal_force=8.0))],
)
def test_wrist_ft_hand_wrench_equals_the_contact_wrench(obj, start):
    plant = PandaPlant(obj, start=start)
    plant.step(200)
    contact = geometry.wrench_world_to_hand(plant.hand_pose()[2], plant.hand_wrench_world())
    assert contact[0] > 4.0
    np.testing.assert_allclose(plant.hand_wrench(), contact, atol=0.02)


def test_free_space_hold_within_half_a_millimetre():
    plant = lifted_plant()
    target = plant.target()
    errors, out_of_plane = [], []
    for _ in range(500):
        plant.step(1)
        errors.append(plant.hand_pose() - target)
        out_of_plane.append(plant.data.site(HAND_SITE).xpos[1] - plant.panda_params.mount.plane_y)
    errors = np.abs(np.array(errors))
    assert errors[:, :2].max() < 5e-4
    assert errors[:, 2].max() < 1e-3
    assert np.abs(out_of_plane).max() < 5e-4


@pytest.mark.parametrize("axis", [0, 1])
def test_ten_newton_push_deflects_the_hand_by_force_over_stiffness(axis):
    plant = lifted_plant()
    rest = plant.hand_pose()
    push = np.zeros(3)
    push[axis] = 10.0
    deflection = hold_wrench(plant, push, duration=1.2) - rest
    assert deflection[axis] == pytest.approx(10.0 / plant.hand.stiffness[axis], rel=0.05)
    # The wrist F/T sees the hand hold the push: the hand exerts −push on whatever pushes it.
    felt = geometry.wrench_world_to_hand(plant.hand_pose()[2], -push)
    np.testing.assert_allclose(plant.hand_wrench(), felt, atol=0.1)


def test_predicted_planar_stiffness_matches_pushes_in_mujoco():
    plant = lifted_plant(Hand(stiffness=(2500.0, 1500.0, 60.0)), lift=(0.03, 0.08, -0.35), settle=2.0)
    rest = plant.hand_pose()
    pushes = np.diag([8.0, 8.0, 0.4])
    deflections = np.column_stack([hold_wrench(plant, push, duration=1.2) - rest for push in pushes])
    deflections[2] = [math.remainder(a, 2 * math.pi) for a in deflections[2]]
    measured = np.linalg.inv(deflections @ np.linalg.inv(pushes))

    q = plant.joint_positions()
    jac = task_jacobian(hand_jacobian(plant.panda, q))
    predicted = planar_stiffness(
        jac[:3], joint_stiffness(jac, plant.gains.stiffness, plant.gains.null_stiffness)
    )
    scale = np.sqrt(np.outer(np.diag(predicted), np.diag(predicted)))
    assert np.all(np.abs(measured - predicted) <= 0.05 * scale), (measured, predicted)


def test_push_object_applies_the_force_for_its_duration():
    plant = PandaPlant(SQUARE, start=StartConfig(settle_time=0.0))
    body = plant.model.body("object").id
    plant.push_object((2.0, -1.0), 0.05)
    plant.step(20)
    np.testing.assert_allclose(plant.data.xfrc_applied[body, [0, 2]], (2.0, -1.0))
    plant.step(40)
    np.testing.assert_allclose(plant.data.xfrc_applied[body], 0.0)


@pytest.mark.parametrize(
    ("build", "message"),
    [
        (lambda: PandaParams(out_of_plane=(2000.0, 0.0, 400.0)), "out_of_plane"),
        (lambda: PandaParams(null_stiffness=-1.0), "null_stiffness"),
        (lambda: PandaParams(armature=math.nan), "armature"),
        (lambda: PandaPlant(SQUARE, start=StartConfig(x_o=1.5, settle_time=0.0)), "workspace"),
    ],
)
def test_bad_parameters_raise_clear_value_errors(build, message):
    with pytest.raises(ValueError, match=message):
        build()


def test_bad_commands_raise_clear_value_errors():
    plant = PandaPlant(SQUARE, start=StartConfig(settle_time=0.0))
    with pytest.raises(ValueError, match="target pose"):
        plant.set_target((0.0, 0.1))
    with pytest.raises(ValueError, match="target velocity"):
        plant.set_target((0.0, 0.1, 0.0), velocity=(0.0, math.inf, 0.0))
    with pytest.raises(ValueError, match="force"):
        plant.push_object((1.0, 2.0, 3.0), 0.1)
    with pytest.raises(ValueError, match="duration"):
        plant.push_object((1.0, 2.0), -0.1)
    with pytest.raises(ValueError, match="n_steps"):
        plant.step(-1)


def test_the_target_range_holds_the_hand_range_and_room_beyond_it_inside_the_joints():
    """``target_angle_range`` contains ``hand_angle_range`` and its upper end is 2.5–5° beyond it (the
    paper triangle's ground slide at the hand range's end took the target 1.7° past it). Judged by
    MuJoCo's own joint ranges: the arm holds the hand at that end with every joint at least
    ``TARGET_JOINT_MARGIN`` inside them, and 0.2° further it cannot."""
    plant = PandaPlant(make_object("paper-triangle"))
    (low, high), (target_low, target_high) = plant.hand_angle_range, plant.target_angle_range
    assert target_low <= low and math.radians(2.5) <= target_high - high <= math.radians(5.0)
    model = plant.model
    joints = [model.joint(f"panda_joint{i}") for i in range(1, 8)]
    lower, upper = (np.array([j.range[k] for j in joints]) for k in (0, 1))
    x, y, _ = plant.start_hand_pose
    q = inverse_kinematics(plant.panda, [x, y, target_high], plant._posture)
    assert np.all(q >= lower + TARGET_JOINT_MARGIN) and np.all(q <= upper - TARGET_JOINT_MARGIN)
    beyond = inverse_kinematics(plant.panda, [x, y, target_high + math.radians(0.2)], q)
    assert np.any(beyond < lower + TARGET_JOINT_MARGIN) or np.any(beyond > upper - TARGET_JOINT_MARGIN)
