"""The sensor-health monitor on quasi-static streams built from the impedance law, with each fault."""

from __future__ import annotations

import math

import numpy as np
import pytest

from ccopt import closed_loop, geometry
from ccopt.closed_loop import Supervision
from ccopt.hand import Hand
from ccopt.health import FAULT_NAMES, OK, HealthParams, SensorHealth
from ccopt.objects import make_object
from ccopt.plant.mujoco_panda import PandaPlant
from ccopt.plant.mujoco_planar import PlanarPlant
from ccopt.plant.sensors import SensorParams, Sensors, parse_fault
from ccopt.schedule import load_schedule

STIFFNESS = (2000.0, 2000.0)
"""N/m: the impedance of the synthetic plant (world x, y), the plants' default."""
DAMPING = (2.0 * math.sqrt(2000.0), 2.0 * math.sqrt(2000.0))
"""N·s/m: critical for a 1 kg hand."""


class PressingPlant:
    """The hand pressing an object, quasi-static: the hand's wrench on the object is exactly the
    impedance force ``K e + D ė`` (``e = x_tar − x_h``, world) for a hand that rocks and slides
    while the pressing force swings between 7 and 23 N."""

    def __init__(self) -> None:
        self.time = 0.0

    def _error(self) -> tuple[np.ndarray, np.ndarray]:
        """``e`` (m) and ``ė`` (m/s), world x and y."""
        t, (k_x, k_y) = self.time, STIFFNESS
        w_x, w_y = 2.0 * math.pi / 2.1, 2.0 * math.pi / 1.3
        error = np.array([3.0 * math.sin(w_x * t) / k_x, -(15.0 + 8.0 * math.sin(w_y * t)) / k_y])
        rate = np.array([3.0 * w_x * math.cos(w_x * t) / k_x, -8.0 * w_y * math.cos(w_y * t) / k_y])
        return error, rate

    def hand_pose(self) -> np.ndarray:
        t = self.time
        return np.array([0.02 * math.sin(0.5 * t), 0.1 + 0.005 * math.sin(0.3 * t), 0.3 * math.sin(0.7 * t)])

    def target(self) -> np.ndarray:
        return self.hand_pose() + np.array([*self._error()[0], 0.0])

    def hand_wrench(self) -> np.ndarray:
        error, rate = self._error()
        force = np.array(STIFFNESS) * error + np.array(DAMPING) * rate
        return geometry.wrench_world_to_hand(self.hand_pose()[2], [*force, 0.1 * math.sin(self.time)])


def monitor(
    faults: tuple[str, ...] = (),
    seconds: float = 10.0,
    rate: float = 100.0,
    sensors: SensorParams | None = None,
    params: HealthParams | None = None,
    seed: int = 3,
) -> tuple[SensorHealth, float]:
    """Feed ``seconds`` of the pressing plant, read through faulty sensors, to a monitor; returns it
    and the largest filtered residual (N) it saw once its filters had settled (after 0.2 s)."""
    plant = PressingPlant()
    base = sensors if sensors is not None else SensorParams()
    noisy = SensorParams(**{**vars(base), "faults": tuple(parse_fault(text) for text in faults)})
    reader, health = Sensors(plant, noisy, seed), SensorHealth(params)
    worst = 0.0
    for k in range(round(seconds * rate)):
        plant.time = k / rate
        reading = reader.read()
        health.update(reading.time, reading.hand_pose, reading.hand_wrench, plant.target())
        worst = max(worst, health.residual) if plant.time >= 0.2 else 0.0
    return health, worst


@pytest.mark.parametrize("rate", [100.0, 1000.0])
def test_no_false_alarm_on_ten_thousand_noisy_samples(rate: float) -> None:
    """Not even one sample beyond the tolerance (the ``hold`` asks for 50 ms of them): the pose noise
    through the damping term (``D σ_x / L`` ≈ 0.7 N) dominates the force noise (0.12 N filtered)."""
    health, worst = monitor(seconds=1e4 / rate, rate=rate)
    assert health.health.status == OK and worst < HealthParams().force_tolerance


def test_the_impedance_force_includes_the_damping_through_the_filter() -> None:
    """Noise-free, the filtered measured and impedance forces agree to well below the noise; without
    the damping term ``D (e − ē)/T`` they would differ by over 1 N (``D ė`` reaches 1.7 N here)."""
    ideal = SensorParams.ideal()
    _, worst = monitor(seconds=5.0, sensors=ideal, params=HealthParams(force_noise=0.0))
    _, undamped = monitor(seconds=5.0, sensors=ideal, params=HealthParams(damping=(0, 0, 0), force_noise=0.0))
    assert worst < 0.1 and undamped > 1.0


@pytest.mark.parametrize(
    ("fault", "status", "latency"),
    [
        ("dead-ft@2", "dead", 0.06),
        ("stuck-ft@2", "stuck", 0.06),
        ("scale-ft:0.1@2", "implausible", 0.1),
        ("scale-ft:0.5@2", "implausible", 1.0),
        ("scale-ft:3@2", "implausible", 0.1),
        ("scale-ft:-1@2", "implausible", 0.1),
        ("bias-ft:6@2", "implausible", 0.5),
        ("spikes-ft:1000@2", "implausible", 5.0),
        ("delay:1@2", "implausible", 1.0),
        ("delay:0.5", "dead", 0.21),
        ("dead-pose@2", "pose_lost", 0.21),
        ("dropout:1@2", "dead", 0.21),
    ],
)
def test_each_fault_is_found_soon_after_it_starts(fault: str, status: str, latency: float) -> None:
    start = parse_fault(fault).start
    health, _ = monitor((fault,), seconds=start + latency + 0.5)
    found = health.health
    assert found.status == status, found
    assert start <= found.time <= start + latency + 1e-9
    assert found.message and "\n" not in found.message


@pytest.mark.parametrize(
    "fault", ["dropout:0.3", "bias-ft:1", "spikes-ft:20", "delay:0.02@1", "scale-ft:0.9"]
)
def test_harmless_faults_are_tolerated(fault: str) -> None:
    health, _ = monitor((fault,), seconds=20.0)
    assert health.health.status == OK


def test_a_fault_is_kept_once_found() -> None:
    health = SensorHealth()
    pose, target = np.array([0.0, 0.1, 0.0]), np.array([0.0, 0.09, 0.0])  # 20 N of impedance force
    for k in range(5):
        health.update(0.01 * k, pose, [7.0, 0.5, 0.01], target)
    assert health.health.status == "stuck" and health.health.time == pytest.approx(0.04)
    fine = health.update(1.0, pose, [20.0, 0.1, 0.0], target)
    assert fine.status == "stuck" and fine is health.health


def test_noise_free_sensors_are_not_stuck_but_can_be_dead() -> None:
    quiet = HealthParams(force_noise=0.0)
    ideal = SensorParams.ideal()
    health, _ = monitor(seconds=3.0, sensors=ideal, params=quiet)
    assert health.health.status == OK
    health = SensorHealth(quiet)
    pose, target = np.array([0.0, 0.1, 0.0]), np.array([0.0, 0.1, 0.0])  # no force expected
    for k in range(50):
        health.update(0.01 * k, pose, np.zeros(3), target)
    assert health.health.status == OK
    health, _ = monitor(("dead-ft@1",), seconds=1.2, sensors=ideal, params=quiet)
    assert health.health.status == "dead" and 1.0 <= health.health.time <= 1.1


def test_the_monitor_accepts_the_plants_recorded_impedance_runs() -> None:
    """A closed-loop run of the paper schedule on the planar plant (slides both ways and pivots):
    measured pose and wrench against the loop's impedance target, no alarm."""
    result = closed_loop.run(make_object("paper-square"), load_schedule("paper"), seed=1)
    samples = result.samples
    health = SensorHealth()  # the default impedance is the loop's
    for time, pose, wrench, target in zip(
        samples["time"], samples["hand_pose"], samples["hand_wrench"], samples["target"], strict=True
    ):
        health.update(time, pose, wrench, target)
    ran = {step.kind for step in result.steps if step.status == "reached"}
    assert result.status == "completed" and {"pivot", "slide_hand", "slide_ground"} <= ran
    assert health.health.status == OK


def test_the_impedance_can_be_the_robots_own() -> None:
    params = HealthParams.from_impedance([1000, 1500, 30], (50.0, 60.0, 0.1), hold=0.1)
    assert params.stiffness == (1000.0, 1500.0, 30.0) and params.damping == (50.0, 60.0, 0.1)
    assert params.hold == 0.1 and HealthParams().damping[:2] == DAMPING


@pytest.mark.parametrize(
    ("kwargs", "message"),
    [
        ({"force_tolerance": -1.0}, "force_tolerance must be in"),
        ({"hold": 0.0}, "hold must be in"),
        ({"stuck_samples": 1}, "stuck_samples must be an integer ≥ 2"),
        ({"stiffness": (1.0, 2.0)}, "stiffness must be three numbers"),
        ({"stiffness": (1.0, 0.0, 1.0)}, r"stiffness\[1\] must be in"),
        ({"damping": (1.0, math.nan, 1.0)}, r"damping\[1\] must be in"),
    ],
)
def test_bad_health_parameters_are_refused(kwargs: dict, message: str) -> None:
    with pytest.raises(ValueError, match=message):
        HealthParams(**kwargs)
    assert set(FAULT_NAMES) == {"dead", "stuck", "implausible", "pose_lost"}


def test_a_run_tolerates_its_plants_own_force_model_error_unless_told_otherwise() -> None:
    """The Panda's force strays further from the planar impedance than the planar plant's (the F/T
    sensor at the flange, the arm's inertia): a run takes the plant's figure, or the one it is given."""
    assert PandaPlant.force_model_error > PlanarPlant.force_model_error
    hand = Hand()
    panda = PandaPlant.force_model_error
    assert Supervision().health(hand, panda).force_tolerance == panda
    assert Supervision(health_tolerance=6.0).health(hand, panda).force_tolerance == 6.0
    with pytest.raises(ValueError, match="health_tolerance"):
        Supervision(health_tolerance=-1.0)


@pytest.mark.parametrize(("fault", "status"), [(None, "completed"), ("scale-ft:0.1@1", "sensor_fault")])
def test_on_the_panda_a_sound_sensor_runs_on_and_one_reading_a_tenth_stops_the_run(fault, status) -> None:
    """With the Panda's wider tolerance the check still tells a sensor reading a tenth of the force
    (from 1 s: the run stops within a quarter of a second) from a sound one. A sensor reading half
    goes unseen there below about 20 N (the difference, 0.5 |f|, stays within 10 N + 0.1 |f|)."""
    faults = () if fault is None else (parse_fault(fault),)
    params = closed_loop.LoopParams(plant="panda", sensor_params=SensorParams(faults=faults))
    result = closed_loop.run(make_object("paper-triangle"), load_schedule("smoke"), params, seed=0)
    assert result.status == status, result.message
    if fault is not None:
        assert "differs from the impedance force" in result.message and result.sim_time < 1.3


@pytest.mark.slow
@pytest.mark.parametrize(("tolerance", "status"), [(None, "completed"), (2.0, "sensor_fault")])
def test_the_panda_triangles_paper_run_is_no_sensor_fault_at_the_panda_s_own_tolerance(tolerance, status):
    """A sound sensor's force strays from the Panda's impedance by up to 4.2 N held for 100 ms on the
    triangle's ``paper`` run (26.2 s in; 8.1 N at −38° when the Panda's hand turned at 30°/s, and the
    planar plant's 6 N then stopped the run as a sensor fault): at the Panda's own figure the run goes
    to its end, below its model error the check stops it."""
    params = closed_loop.LoopParams(plant="panda", supervision=Supervision(health_tolerance=tolerance))
    result = closed_loop.run(make_object("paper-triangle"), load_schedule("paper"), params, seed=0)
    assert result.status == status, result.message
