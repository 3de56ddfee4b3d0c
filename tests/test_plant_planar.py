"""Planar MuJoCo plant against physics: Coulomb friction, quasi-static pivots, sliding, statics.

Loads are applied through the hand impedance: every step the target is put at
``x_h + K⁻¹ w`` so that the hand pushes with the world wrench ``w`` while its damping resists
motion (a damped force source). Objects lie flat or stand on one vertex; friction values are
chosen per test so that only the contact under test can slip.
"""

from __future__ import annotations

import math

import mujoco
import numpy as np
import pytest

from ccopt import geometry
from ccopt.hand import Hand
from ccopt.objects import PAPER_OBJECT_NAMES, PlanarObject, make_object
from ccopt.plant import scene
from ccopt.plant.base import Plant, PlantParams, StartConfig
from ccopt.plant.mujoco_planar import PlanarPlant

F_N = 8.0
"""Normal force the hand presses with in the motion tests, N."""


HAND = Hand(half_length=0.05)
"""The plant tests' hand: 10 cm long (docs/architecture.md §6), as on the faces these tests press."""


def flat_rectangle(mu_hand: float, mu_ground: float, s_h: float = -0.09, f_n: float = 10.0) -> PlanarPlant:
    """Paper rectangle lying on a long face, the hand on top (θ_o = 0) pressing with ``f_n``."""
    obj = make_object("paper-rectangle", mu_hand=mu_hand, mu_ground=mu_ground)
    return PlanarPlant(obj, hand=HAND, start=StartConfig(hand_face=0, theta_o=0.0, s_h=s_h, normal_force=f_n))


def push_with(plant: PlanarPlant, wrench_hand: np.ndarray) -> None:
    """One step with the hand exerting ``wrench_hand`` (hand frame) through a damped impedance."""
    pose = plant.hand_pose()
    offset = geometry.wrench_hand_to_world(pose[2], wrench_hand) / np.array(plant.hand.stiffness)
    plant.set_target(pose + offset)
    plant.step()


def hand_on_face(plant: PlanarPlant, face: int) -> float:
    """Position of the hand-face centre along object face ``face``, object frame, m (slip gauge)."""
    a, b = plant.obj.faces[face]
    pose = plant.object_pose()
    rel = geometry.rotation(pose[2]).T @ (plant.hand_pose()[:2] - pose[:2])
    return float((rel - a) @ (b - a) / np.linalg.norm(b - a))


def vertex_world(plant: PlanarPlant, index: int) -> np.ndarray:
    """World position of object vertex ``index`` (a material point), m."""
    return geometry.transform_points(plant.obj.vertices, plant.object_pose())[index]


def slip_rate(contact: str, load: float) -> float:
    """Signed slip speed (m/s) of ``contact`` under a static tangential load ``load`` × its limit.

    Hand: ``μ_h = 0.3``, ``μ_g = 1.0`` so the ground holds; the hand pushes with
    ``f_t = load μ_h f_n``. Ground: ``μ_h = 1.0``, ``μ_g = 0.3`` so the hand holds; the hand pushes
    with ``f_t = load μ_g (f_n + m g)``, the ground's friction limit. The rectangle (18 × 11 cm)
    cannot tip under either load. Slip is measured over 1 s after 0.3 s of loading.
    """
    f_n = 10.0
    plant = flat_rectangle(0.3, 1.0) if contact == "hand" else flat_rectangle(1.0, 0.3)
    weight = plant.obj.mass * geometry.GRAVITY
    limit = plant.obj.mu_hand * f_n if contact == "hand" else plant.obj.mu_ground * (f_n + weight)
    wrench = np.array([f_n, load * limit, 0.0])

    def gauge() -> float:
        return hand_on_face(plant, 0) if contact == "hand" else float(plant.object_pose()[0])

    for _ in range(300):
        push_with(plant, wrench)
    start, t0 = gauge(), plant.time
    for _ in range(1000):
        push_with(plant, wrench)
    return (gauge() - start) / (plant.time - t0)


@pytest.mark.parametrize("contact", ["hand", "ground"])
def test_static_friction_holds_below_and_slips_above_the_coulomb_limit(contact: str) -> None:
    assert abs(slip_rate(contact, 0.90)) < 0.05e-3
    assert abs(slip_rate(contact, 1.05)) > 0.5e-3


# --- quasi-static pivot about the ground vertex ------------------------------------------------

PIVOTS = {
    # object: (hand face, start θ_o in degrees); every pivot turns the object by +25° about its
    # lowest vertex. Triangle and pentagon stand on a vertex under the hand (centroid over the
    # pivot at θ_o = 0); the others are lifted about their left vertex from a 5° tilt.
    "paper-triangle": (0, -12.5),
    "paper-square": (0, 5.0),
    "paper-rectangle": (1, 5.0),
    "paper-pentagon": (0, -12.5),
    "paper-hexagon": (0, 5.0),
}


def centred_start(obj: PlanarObject, face: int, theta_o: float) -> StartConfig:
    """Start with the hand centred on ``face`` at orientation ``theta_o``."""
    normal = obj.face_normal(face)
    angle = theta_o + 0.5 * math.pi - math.atan2(normal[1], normal[0])
    world = geometry.transform_points(obj.vertices, (0.0, 0.0, angle))
    world -= world[geometry.lowest_vertex(world)]
    middle = 0.5 * (world[face] + world[(face + 1) % obj.n_faces])
    s_h = float(-middle @ geometry.hand_tangent(theta_o))
    return StartConfig(hand_face=face, theta_o=theta_o, s_h=s_h, normal_force=F_N)


def min_jerk(u: float) -> tuple[float, float]:
    """Minimum-jerk profile on ``[0, 1]`` and its derivative."""
    u = min(max(u, 0.0), 1.0)
    return u**3 * (10.0 - 15.0 * u + 6.0 * u * u), 30.0 * u * u * (1.0 - u) ** 2


def static_hand_wrench(
    obj: PlanarObject, theta: float, s_h: float, d: float, centroid: np.ndarray, l_eff: float
) -> np.ndarray:
    """Hand wrench ``(f_n, f_t, τ)`` that holds the object still about its ground vertex.

    Moments about the vertex: ``τ + s_h f_n − d f_t = c_x m g`` (``c_x`` the centroid's horizontal
    offset from the vertex). The moment not carried by ``f_n`` is split between ``f_t`` and ``τ`` so
    that both use the same fraction of their limits ``μ_h f_n`` and ``l_eff f_n``.
    """
    moment = centroid[0] * obj.mass * geometry.GRAVITY - s_h * F_N
    share = moment / (l_eff + d * obj.mu_hand)
    return np.array([F_N, -share * obj.mu_hand, share * l_eff])


@pytest.mark.parametrize("name", PAPER_OBJECT_NAMES)
def test_open_loop_pivot_sticks_at_both_contacts(name: str) -> None:
    obj = make_object(name)
    face, start_deg = PIVOTS[name]
    theta0, turn, duration = math.radians(start_deg), math.radians(25.0), 1.0
    plant = PlanarPlant(obj, hand=HAND, start=centred_start(obj, face, theta0))
    truth = plant.truth()
    r_o, s_h, d = truth.r_o.copy(), truth.s_h, truth.d
    pivot = geometry.lowest_vertex(geometry.transform_points(obj.vertices, plant.object_pose()))
    centroid0 = plant.object_pose()[:2] - r_o
    l_eff = min(plant.hand.half_length, 0.5 * obj.face_length(face))
    stiffness = np.array(plant.hand.stiffness)
    hand0, vertex0 = hand_on_face(plant, face), vertex_world(plant, pivot)

    ramp_steps, move_steps, hold_steps = 200, round(duration / plant.timestep), 300
    for k in range(ramp_steps + move_steps + hold_steps):
        u, du = min_jerk((k + 1 - ramp_steps) / move_steps)
        theta, omega = theta0 + turn * u, turn * du / duration
        pose = geometry.hand_pose_from_contact(theta, s_h, d, r_o)
        velocity = np.array([-omega * (pose[1] - r_o[1]), omega * (pose[0] - r_o[0]), omega])
        centroid = geometry.rotation(theta - theta0) @ centroid0
        wrench = static_hand_wrench(obj, theta, s_h, d, centroid, l_eff)
        wrench[1:] *= min_jerk((k + 1) / ramp_steps)[0]
        offset = geometry.wrench_hand_to_world(theta, wrench) / stiffness
        plant.set_target(pose + offset, velocity)
        plant.step()
        if k % 5 == 0:
            truth = plant.truth()
            assert (truth.hand_mode, truth.ground_mode, truth.hand_geometry) == (0, 0, 0), (
                k,
                truth,
            )
            assert truth.in_contact_hand and truth.in_contact_ground

    truth = plant.truth()
    assert abs(truth.theta_o - (theta0 + turn)) < math.radians(0.5)
    assert abs(hand_on_face(plant, face) - hand0) < 1e-3
    assert np.linalg.norm(vertex_world(plant, pivot) - vertex0) < 1e-3


# --- sliding -----------------------------------------------------------------------------------


def slide(plant: PlanarPlant, velocity: np.ndarray, seconds: float = 1.2, settle: float = 0.3):
    """Move the target at ``velocity`` (world) while pressing with ``F_N``; sample after ``settle``."""
    press = np.array([0.0, -F_N / plant.hand.stiffness[1], 0.0])
    start = plant.hand_pose() + press
    samples = []
    for k in range(round(seconds / plant.timestep)):
        t = (k + 1) * plant.timestep
        plant.set_target(start + velocity * t, velocity)
        plant.step()
        if t > settle and k % 5 == 0:
            samples.append((plant.truth(), plant.hand_wrench(), plant.hand_wrench_world()))
    return samples


@pytest.mark.parametrize("direction", [1.0, -1.0])
def test_hand_slides_along_the_face_at_the_friction_limit(direction: float) -> None:
    plant = flat_rectangle(mu_hand=0.5, mu_ground=0.8, s_h=-0.09, f_n=F_N)
    e_t = geometry.hand_tangent(0.0)
    samples = slide(plant, direction * 0.02 * np.array([e_t[0], e_t[1], 0.0]))
    # Moving the hand along +e_t decreases s_h = (r_o − r_h)·e_t: mode −1.
    assert {(t.hand_mode, t.ground_mode, t.hand_geometry) for t, _, _ in samples} == {(-int(direction), 0, 0)}
    ratios = np.array([w[1] / w[0] for _, w, _ in samples])
    assert np.all(np.sign(ratios) == direction)  # the hand drags the object along its motion
    assert np.mean(np.abs(ratios)) == pytest.approx(0.5, rel=0.10)


@pytest.mark.parametrize("direction", [1.0, -1.0])
def test_object_slides_on_the_ground_at_the_friction_limit(direction: float) -> None:
    plant = flat_rectangle(mu_hand=0.8, mu_ground=0.3, s_h=-0.09, f_n=F_N)
    samples = slide(plant, direction * np.array([0.02, 0.0, 0.0]))
    assert {(t.hand_mode, t.ground_mode, t.hand_geometry) for t, _, _ in samples} == {(0, int(direction), 0)}
    weight = plant.obj.mass * geometry.GRAVITY
    # Quasi-static: the ground force is −(hand force + weight); its ratio is μ_g while sliding.
    ratios = np.array([-w[0] / (w[1] - weight) for _, _, w in samples])
    assert np.all(np.sign(ratios) == direction)
    assert np.mean(np.abs(ratios)) == pytest.approx(0.3, rel=0.10)


def test_hand_pivots_on_a_face_edge_under_a_large_torque() -> None:
    plant = flat_rectangle(mu_hand=0.8, mu_ground=0.8, s_h=-0.09, f_n=F_N)
    target = plant.target()
    plant.set_target(target + np.array([0.0, 0.0, math.radians(3.0)]))
    plant.step(500)
    truth = plant.truth()
    # θ_o − θ_h < 0: the hand turned CCW and rests on its −e_t end, so τ = +l_h f_n.
    assert truth.hand_geometry == -1
    assert plant.hand_wrench()[2] == pytest.approx(plant.hand.half_length * plant.hand_wrench()[0], rel=0.05)


# --- statics, start configuration, pushes, API -------------------------------------------------


def test_hand_wrench_balances_the_impedance_and_the_ground_carries_the_rest() -> None:
    obj = make_object("paper-pentagon")
    plant = PlanarPlant(obj, hand=HAND, start=centred_start(obj, 0, math.radians(-8.0)))
    plant.step(500)
    world = plant.hand_wrench_world()
    impedance = np.array(plant.hand.stiffness) * (plant.target() - plant.hand_pose())
    np.testing.assert_allclose(world, impedance, atol=0.02)
    np.testing.assert_allclose(
        plant.hand_wrench(), geometry.wrench_world_to_hand(plant.hand_pose()[2], world)
    )
    ground = plant.ground_wrench()
    np.testing.assert_allclose(ground[:2] + world[:2], [0.0, obj.mass * geometry.GRAVITY], atol=0.02)


def test_hand_wrench_agrees_with_mujoco_contact_forces() -> None:
    plant = flat_rectangle(mu_hand=0.5, mu_ground=0.8, f_n=6.0)
    model, data = plant.model, plant.data
    total = np.zeros(2)
    force = np.zeros(6)
    hand, obj = model.geom("hand").id, model.geom("object").id
    for i in range(data.ncon):
        if {int(g) for g in data.contact.geom[i]} == {hand, obj}:
            mujoco.mj_contactForce(model, data, i, force)
            world = force[:3] @ data.contact.frame[i].reshape(3, 3)
            total += (world[0], world[2]) if data.contact.geom[i][0] == hand else (-world[0], -world[2])
    np.testing.assert_allclose(plant.hand_wrench_world()[:2], total)
    pair = scene.pair_wrench(data, hand, obj, plant.hand_pose()[:2])
    np.testing.assert_allclose(plant.hand_wrench_world(), pair, atol=1e-9)
    ground = scene.pair_wrench(data, model.geom("ground").id, obj, plant.object_pose()[:2])
    np.testing.assert_allclose(plant.ground_wrench(), ground, atol=1e-9)
    assert plant.hand_wrench()[0] == pytest.approx(6.0, rel=0.02)


def test_start_configuration_is_reached() -> None:
    obj = make_object("paper-hexagon")
    start = StartConfig(hand_face=2, theta_o=math.radians(20.0), s_h=-0.03, normal_force=5.0, x_o=0.1)
    truth = PlanarPlant(obj, hand=HAND, start=start).truth()
    plant = PlanarPlant(obj, hand=HAND, start=start)
    truth = plant.truth()
    # The start target only presses: the object settles slightly towards its statics.
    assert truth.theta_o == pytest.approx(start.theta_o, abs=math.radians(0.5))
    assert truth.s_h == pytest.approx(start.s_h, abs=1e-3)
    assert truth.s_g == pytest.approx(start.x_o, abs=1e-3)
    assert plant.hand_wrench()[0] == pytest.approx(start.normal_force, rel=0.05)


def test_push_moves_the_object_only_while_it_lasts() -> None:
    plant = flat_rectangle(mu_hand=0.5, mu_ground=0.3, f_n=1.0)
    plant.set_target(plant.hand_pose() + np.array([0.0, 0.05, 0.0]))  # lift the hand off
    plant.step(300)
    x0 = plant.object_pose()[0]
    weight = plant.obj.mass * geometry.GRAVITY
    plant.push_object([0.6 * weight, 0.0], duration=0.2)
    plant.step(200)
    moved = plant.object_pose()[0] - x0
    assert moved > 1e-3
    assert not np.any(plant.data.xfrc_applied)
    plant.step(500)
    assert np.linalg.norm(plant.object_velocity()) < 1e-3


def test_planar_plant_implements_the_plant_protocol() -> None:
    plant = flat_rectangle(0.5, 0.8)
    assert isinstance(plant, Plant)
    assert plant.time == 0.0 and plant.timestep == 1e-3
    plant.step(10)
    assert plant.time == pytest.approx(0.01)
    plant.set_target([0.1, 0.2, 0.3], [0.0, 0.0, 0.1])
    np.testing.assert_array_equal(plant.target(), [0.1, 0.2, 0.3])
    checked = plant.data.ctrl.copy()
    plant.set_target(np.zeros(3))
    plant.set_target(np.array([0.1, 0.2, 0.3]), np.array([0.0, 0.0, 0.1]), check=False)  # the loop's
    np.testing.assert_array_equal(plant.data.ctrl, checked)


@pytest.mark.parametrize(
    ("kwargs", "message"),
    [
        ({"timestep": 0.1}, "timestep must be at most 0.01 s, got 0.1"),
        ({"contact_timeconst": 0.001}, "contact_timeconst must be at least twice"),
        ({"solimp": (0.9, 0.5, 0.01)}, "solimp must satisfy"),
    ],
)
def test_bad_plant_parameters_raise_clear_errors(kwargs: dict, message: str) -> None:
    with pytest.raises(ValueError, match=message):
        PlantParams(**kwargs)


@pytest.mark.parametrize(
    ("kwargs", "message"),
    [
        ({"half_length": 0.0}, "half_length must be positive, got 0.0"),
        ({"stiffness": (2000.0, -1.0, 60.0)}, "stiffness must be positive"),
        ({"stiffness": (2000.0, 60.0)}, "stiffness must be 3 numbers"),
        ({"damping_ratio": -0.5}, "damping_ratio must be non-negative, got -0.5"),
        ({"mass": math.nan}, r"hand mass must be finite, got nan"),
        ({"force_limits": (10.0, 5.0)}, "force_limits must satisfy"),
    ],
)
def test_bad_hand_parameters_raise_clear_errors(kwargs: dict, message: str) -> None:
    with pytest.raises(ValueError, match=message):
        Hand(**kwargs)


def test_bad_start_and_commands_raise_clear_errors() -> None:
    obj = make_object("paper-square")
    with pytest.raises(ValueError, match=r"face must be in \[0, 3\].*got 7"):
        PlanarPlant(obj, hand=HAND, start=StartConfig(hand_face=7))
    with pytest.raises(ValueError, match=r"s_h = 0\.2 m puts the hand centre off face 0"):
        PlanarPlant(obj, hand=HAND, start=StartConfig(s_h=0.2))
    with pytest.raises(ValueError, match=r"normal_force must be positive, got -1\.0"):
        StartConfig(normal_force=-1.0)
    with pytest.raises(TypeError, match="hand_face must be an integer"):
        StartConfig(hand_face=1.5)
    plant = flat_rectangle(0.5, 0.8)
    with pytest.raises(ValueError, match="target pose must be 3 finite numbers"):
        plant.set_target([0.0, np.nan, 0.0])
    with pytest.raises(ValueError, match="force must be 2 finite numbers"):
        plant.push_object([1.0, 2.0, 3.0], 0.1)
    with pytest.raises(ValueError, match="n_steps must be a non-negative integer, got -1"):
        plant.step(-1)


@pytest.mark.parametrize(
    ("arguments", "name"),
    [
        (("square",), "obj"),
        ((None,), "obj"),
        ((make_object("paper-square"), "x"), "params"),
        ((make_object("paper-square"), None, {}), "start"),
    ],
)
def test_wrong_argument_types_raise_a_type_error_naming_them(arguments, name):
    with pytest.raises(TypeError, match=f"^{name} must be a"):
        PlanarPlant(*arguments)
