"""Sensors (noise, bias, seeding, dropouts) and ground truth (against the MJCF geometry)."""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np
import pytest

from ccopt import geometry
from ccopt.objects import make_object
from ccopt.plant.base import StartConfig
from ccopt.plant.mujoco_planar import PlanarPlant
from ccopt.plant.sensors import Measurement, SensorParams, Sensors
from ccopt.plant.truth import compute_truth


@dataclass
class FrozenPlant:
    """A plant that never moves: known pose and wrench, to isolate the sensor model."""

    pose: np.ndarray = field(default_factory=lambda: np.array([0.1, 0.2, 0.3]))
    wrench: np.ndarray = field(default_factory=lambda: np.array([5.0, -1.0, 0.02]))
    time: float = 1.5

    def hand_pose(self) -> np.ndarray:
        return self.pose.copy()

    def hand_wrench(self) -> np.ndarray:
        return self.wrench.copy()


def sample(sensors: Sensors, n: int) -> tuple[np.ndarray, np.ndarray]:
    readings = [sensors.read() for _ in range(n)]
    return np.array([r.hand_pose for r in readings]), np.array([r.hand_wrench for r in readings])


def test_noise_statistics_match_the_parameters() -> None:
    plant, params = FrozenPlant(), SensorParams()
    sensors = Sensors(plant, params, seed=3)
    poses, wrenches = sample(sensors, 20000)
    expected_pose_sigma = [params.sigma_position, params.sigma_position, params.sigma_angle]
    expected_wrench_sigma = [params.sigma_force, params.sigma_force, params.sigma_torque]
    np.testing.assert_allclose(poses.std(axis=0), expected_pose_sigma, rtol=0.03)
    np.testing.assert_allclose(wrenches.std(axis=0), expected_wrench_sigma, rtol=0.03)
    # sample means within 4 standard errors of the truth (+ bias for the wrench)
    standard_error = 4.0 / math.sqrt(len(poses))
    assert np.all(np.abs(poses.mean(axis=0) - plant.pose) < standard_error * np.array(expected_pose_sigma))
    wrench_error = np.abs(wrenches.mean(axis=0) - plant.wrench - sensors.bias)
    assert np.all(wrench_error < standard_error * np.array(expected_wrench_sigma))


def test_bias_is_constant_within_a_run_and_drawn_per_seed() -> None:
    params = SensorParams(sigma_force=0.0, sigma_torque=0.0)
    sensors = Sensors(FrozenPlant(), params, seed=1)
    _, wrenches = sample(sensors, 10)
    np.testing.assert_array_equal(wrenches, np.tile(FrozenPlant().wrench + sensors.bias, (10, 1)))
    biases = np.array([Sensors(FrozenPlant(), params, seed=s).bias for s in range(2000)])
    np.testing.assert_allclose(
        biases.std(axis=0), [params.bias_force, params.bias_force, params.bias_torque], rtol=0.06
    )


def test_the_seed_makes_readings_deterministic() -> None:
    a = sample(Sensors(FrozenPlant(), seed=7), 50)
    b = sample(Sensors(FrozenPlant(), seed=7), 50)
    c = sample(Sensors(FrozenPlant(), seed=8), 50)
    np.testing.assert_array_equal(a[0], b[0])
    np.testing.assert_array_equal(a[1], b[1])
    assert not np.array_equal(a[1], c[1])


def test_dropouts_give_nan_samples_at_the_requested_rate() -> None:
    sensors = Sensors(FrozenPlant(), SensorParams(dropout_probability=0.3), seed=0)
    poses, wrenches = sample(sensors, 5000)
    dropped = np.isnan(wrenches).all(axis=1)
    assert np.array_equal(dropped, np.isnan(poses).all(axis=1))
    assert not np.isnan(wrenches[~dropped]).any()
    assert dropped.mean() == pytest.approx(0.3, abs=0.02)


def test_ideal_sensors_report_the_plant() -> None:
    reading = Sensors(FrozenPlant(), SensorParams.ideal()).read()
    assert isinstance(reading, Measurement)
    assert reading.time == 1.5
    np.testing.assert_array_equal(reading.hand_pose, FrozenPlant().pose)
    np.testing.assert_array_equal(reading.hand_wrench, FrozenPlant().wrench)


def test_sensors_read_a_simulated_plant() -> None:
    plant = PlanarPlant(make_object("paper-square"), start=StartConfig(s_h=-0.05))
    reading = Sensors(plant, SensorParams.ideal()).read()
    np.testing.assert_array_equal(reading.hand_wrench, plant.hand_wrench())
    np.testing.assert_array_equal(reading.hand_pose, plant.hand_pose())


@pytest.mark.parametrize(
    ("kwargs", "message"),
    [
        ({"sigma_force": -0.1}, "sigma_force must be finite and non-negative, got -0.1"),
        ({"sigma_angle": math.nan}, "sigma_angle must be finite and non-negative, got nan"),
        ({"dropout_probability": 1.5}, "dropout_probability must be at most 1, got 1.5"),
    ],
)
def test_bad_sensor_parameters_raise_clear_errors(kwargs: dict, message: str) -> None:
    with pytest.raises(ValueError, match=message):
        SensorParams(**kwargs)


# --- truth ---------------------------------------------------------------------------------------


def mjcf_geometry(plant: PlanarPlant) -> tuple[np.ndarray, np.ndarray, float]:
    """Object polygon (world, from the compiled mesh), hand-face centre and hand angle, from MuJoCo."""
    model, data = plant.model, plant.data
    obj, hand = model.geom("object").id, model.geom("hand").id
    mesh = model.geom_dataid[obj]
    start, count = model.mesh_vertadr[mesh], model.mesh_vertnum[mesh]
    local = model.mesh_vert[start : start + count]
    world = local @ data.geom_xmat[obj].reshape(3, 3).T + data.geom_xpos[obj]
    polygon = world[world[:, 1] < 0.0][:, [0, 2]]  # the prism's front face
    rotation = data.geom_xmat[hand].reshape(3, 3)
    face_centre = data.geom_xpos[hand] - model.geom_size[hand][2] * rotation[:, 2]
    theta_h = math.atan2(rotation[2, 0], rotation[0, 0])
    return polygon, face_centre[[0, 2]], theta_h


@pytest.mark.parametrize(
    ("name", "start"),
    [
        (
            "paper-pentagon",
            StartConfig(hand_face=0, theta_o=math.radians(10.0), s_h=0.0, normal_force=6.0),
        ),
        (
            "paper-triangle",
            StartConfig(hand_face=1, theta_o=math.radians(-20.0), s_h=0.05, x_o=0.2),
        ),
    ],
)
def test_truth_agrees_with_the_mjcf_geometry(name: str, start: StartConfig) -> None:
    plant = PlanarPlant(make_object(name), start=start)
    truth = plant.truth()
    polygon, r_h, theta_h = mjcf_geometry(plant)
    r_o = polygon[np.argmin(polygon[:, 1])]
    e_t, e_n = (
        np.array([math.cos(theta_h), math.sin(theta_h)]),
        np.array([math.sin(theta_h), -math.cos(theta_h)]),
    )
    # the object face under the hand: the polygon edge nearest to the hand-face centre, whose
    # outward normal is −e_n of its orientation θ_o
    hull = polygon[np.argsort(np.arctan2(*(polygon - polygon.mean(axis=0)).T[::-1]))]
    edges = list(zip(hull, np.roll(hull, -1, axis=0), strict=True))

    def distance(edge: tuple[np.ndarray, np.ndarray]) -> float:
        direction = (edge[1] - edge[0]) / np.linalg.norm(edge[1] - edge[0])
        offset = r_h - edge[0]
        return abs(direction[0] * offset[1] - direction[1] * offset[0])

    a, b = min(edges, key=distance)
    theta_o = math.atan2(b[1] - a[1], b[0] - a[0]) - math.pi

    np.testing.assert_allclose(truth.r_o, r_o, atol=1e-7)
    assert truth.s_h == pytest.approx((r_o - r_h) @ e_t, abs=1e-7)
    assert truth.d == pytest.approx((r_o - r_h) @ e_n, abs=1e-7)
    assert truth.s_g == pytest.approx(r_o[0], abs=1e-7)
    assert geometry.wrap_angle(truth.theta_o - theta_o) == pytest.approx(0.0, abs=1e-7)
    assert truth.hand_geometry == 0 and truth.in_contact_hand and truth.in_contact_ground


def test_truth_modes_follow_contact_velocities() -> None:
    obj = make_object("paper-square")
    pose, hand = np.array([0.0, 0.05, math.pi]), np.array([0.0, 0.1, 0.0])
    rest = compute_truth(0.0, obj, 0, pose, np.zeros(3), hand, np.zeros(3), True, True)
    assert (rest.hand_mode, rest.ground_mode, rest.hand_geometry) == (0, 0, 0)
    # the hand moves along +e_t over a resting object: s_h decreases
    moving_hand = compute_truth(0.0, obj, 0, pose, np.zeros(3), hand, [0.01, 0.0, 0.0], True, True)
    assert (moving_hand.hand_mode, moving_hand.ground_mode) == (-1, 0)
    # hand and object move together to −x: the ground slides negatively, the hand sticks
    together = compute_truth(0.0, obj, 0, pose, [-0.01, 0.0, 0.0], hand, [-0.01, 0.0, 0.0], True, True)
    assert (together.hand_mode, together.ground_mode) == (0, -1)
    # rigid rotation of hand and object about the ground vertex: everything sticks
    r_o = rest.r_o
    omega = 0.5

    def about_vertex(point: np.ndarray) -> np.ndarray:
        return np.array([-omega * (point[1] - r_o[1]), omega * (point[0] - r_o[0]), omega])

    pivot = compute_truth(0.0, obj, 0, pose, about_vertex(pose[:2]), hand, about_vertex(hand[:2]), True, True)
    assert (pivot.hand_mode, pivot.ground_mode, pivot.hand_geometry) == (0, 0, 0)
    tilted = compute_truth(
        0.0, obj, 0, pose, np.zeros(3), hand + np.array([0.0, 0.0, 0.02]), np.zeros(3), True, True
    )
    assert tilted.hand_geometry == -1


def test_the_ground_contact_stays_the_vertex_the_object_pivoted_about_while_it_still_touches() -> None:
    # A square lying on a face touches the ground at two vertices; a tenth of a millimetre decides
    # which is lowest. The last contact is kept while within the hysteresis, and given up beyond it.
    obj = make_object("paper-square")
    hand = np.array([0.0, 0.2, 0.0])
    tilt = 3e-4 / np.ptp(obj.vertices[:, 0])  # the bottom face's ends 0.3 mm apart in height
    flat = compute_truth(0.0, obj, 0, [0.0, 0.05, 0.0], np.zeros(3), hand, np.zeros(3), True, True)
    first, flipped = flat.ground_vertex, []
    for sign in (1.0, -1.0):
        pose = [0.0, 0.05, sign * tilt]
        lowest = compute_truth(0.0, obj, 0, pose, np.zeros(3), hand, np.zeros(3), True, True)
        kept = compute_truth(0.0, obj, 0, pose, np.zeros(3), hand, np.zeros(3), True, True, first)
        assert kept.ground_vertex == first
        vertices = geometry.transform_points(obj.vertices, pose)
        np.testing.assert_allclose(kept.r_o, vertices[first])
        flipped.append(lowest.ground_vertex != first)
    assert any(flipped)  # the lowest alone would have changed vertex
    lifted = [0.0, 0.05, 0.2]  # 11°: one of the two is a centimetre up
    vertices = geometry.transform_points(obj.vertices, lifted)
    for previous in range(len(vertices)):
        truth = compute_truth(0.0, obj, 0, lifted, np.zeros(3), hand, np.zeros(3), True, True, previous)
        assert truth.ground_vertex == int(np.argmin(vertices[:, 1]))
