"""Sensor faults: syntax, validation, each kind's effect from its start, and unchanged fault-free noise."""

from __future__ import annotations

import math

import numpy as np
import pytest

from ccopt.plant.sensors import BATCH, SPIKE_PROBABILITY, Fault, SensorParams, Sensors, parse_fault


class MovingPlant:
    """A plant whose pose and wrench are known functions of its time (advanced by the test)."""

    def __init__(self) -> None:
        self.time = 0.0

    def hand_pose(self) -> np.ndarray:
        t = self.time
        return np.array([0.01 * math.sin(t), 0.1 + 0.001 * t, 0.2 * math.cos(0.7 * t)])

    def hand_wrench(self) -> np.ndarray:
        t = self.time
        return np.array([10.0 + 5.0 * math.sin(3.0 * t), 2.0 * math.cos(2.0 * t), 0.05 * math.sin(t)])


def readings(params: SensorParams, n: int, seed: int = 5, period: float = 0.01) -> tuple[np.ndarray, ...]:
    """``(times, poses, wrenches)`` of ``n`` reads every ``period`` s."""
    plant = MovingPlant()
    sensors = Sensors(plant, params, seed)
    times, poses, wrenches = np.empty(n), np.empty((n, 3)), np.empty((n, 3))
    for k in range(n):
        plant.time = k * period
        reading = sensors.read()
        times[k], poses[k], wrenches[k] = reading.time, reading.hand_pose, reading.hand_wrench
    return times, poses, wrenches


def faulty(*faults: str, **noise: float) -> SensorParams:
    return SensorParams(**noise, faults=tuple(parse_fault(text) for text in faults))


def test_fault_free_samples_are_those_of_the_documented_noise_model() -> None:
    """Today's formula from an independently seeded generator: bias, then per batch of 1024 the
    noise of 6 channels, then the dropout draws (the order fixes every sample of a seed)."""
    params = SensorParams(dropout_probability=0.2)
    n = 2 * BATCH + 100
    times, poses, wrenches = readings(params, n, seed=11)
    rng = np.random.default_rng(11)
    bias = rng.standard_normal(3) * [params.bias_force, params.bias_force, params.bias_torque]
    p = params
    sigma = [p.sigma_position, p.sigma_position, p.sigma_angle, p.sigma_force, p.sigma_force, p.sigma_torque]
    plant = MovingPlant()
    for start in range(0, n, BATCH):
        offsets = rng.standard_normal((BATCH, 6)) * np.array(sigma)
        offsets[:, 3:] += bias
        dropped = rng.random(BATCH) < p.dropout_probability
        for k in range(start, min(start + BATCH, n)):
            plant.time = times[k]
            if dropped[k - start]:
                assert np.isnan(poses[k]).all() and np.isnan(wrenches[k]).all()
            else:
                np.testing.assert_array_equal(poses[k], plant.hand_pose() + offsets[k - start, :3])
                np.testing.assert_array_equal(wrenches[k], plant.hand_wrench() + offsets[k - start, 3:])


def test_faults_see_the_same_noise_and_act_only_from_their_start() -> None:
    _, clean_poses, clean = readings(SensorParams(), 400)
    times, poses, wrenches = readings(faulty("scale-ft:0.1@2", "bias-ft:5@2"), 400)
    before, after = times < 2.0 - 1e-9, times >= 2.0 - 1e-9
    np.testing.assert_array_equal(wrenches[before], clean[before])
    np.testing.assert_array_equal(poses, clean_poses)
    np.testing.assert_allclose(wrenches[after], clean[after] * 0.1 + [5.0, 5.0, 0.0], rtol=0, atol=1e-12)
    # in the order given: bias then scale is another fault
    _, _, swapped = readings(faulty("bias-ft:5@2", "scale-ft:0.1@2"), 400)
    np.testing.assert_allclose(swapped[after], (clean[after] + [5.0, 5.0, 0.0]) * 0.1, rtol=0, atol=1e-12)


def test_dead_and_stuck_force_sensors() -> None:
    _, _, clean = readings(SensorParams(), 300)
    times, _, dead = readings(faulty("dead-ft@1.5"), 300)
    after = times >= 1.5 - 1e-9
    assert np.all(dead[after] == 0.0) and np.array_equal(dead[~after], clean[~after])
    _, _, stuck = readings(faulty("stuck-ft@1.5"), 300)
    first = np.argmax(after)
    np.testing.assert_array_equal(stuck[after], np.tile(clean[first], (after.sum(), 1)))
    np.testing.assert_array_equal(stuck[~after], clean[~after])


def test_dead_pose_and_dropouts() -> None:
    _, clean_poses, clean = readings(SensorParams(), 3000)
    times, poses, wrenches = readings(faulty("dead-pose@10"), 3000)
    after = times >= 10.0 - 1e-9
    assert np.isnan(poses[after]).all() and np.array_equal(poses[~after], clean_poses[~after])
    np.testing.assert_array_equal(wrenches, clean)
    times, poses, wrenches = readings(faulty("dropout:0.3@10"), 3000)
    dropped = np.isnan(wrenches).all(axis=1)
    assert np.array_equal(dropped, np.isnan(poses).all(axis=1)) and not dropped[~after].any()
    assert dropped[after].mean() == pytest.approx(0.3, abs=0.04)
    np.testing.assert_array_equal(wrenches[~dropped], clean[~dropped])
    _, _, again = readings(faulty("dropout:0.3@10"), 3000)
    _, _, other_seed = readings(faulty("dropout:0.3@10"), 3000, seed=6)
    np.testing.assert_array_equal(np.isnan(again), np.isnan(wrenches))
    assert not np.array_equal(np.isnan(other_seed), np.isnan(wrenches))


def test_spikes_are_rare_seeded_and_of_the_given_size() -> None:
    n = 20000
    _, _, clean = readings(SensorParams(), n)
    _, _, spiky = readings(faulty("spikes-ft:50"), n)
    jump = spiky - clean
    hit = np.any(jump != 0.0, axis=1)
    np.testing.assert_allclose(np.abs(jump[hit, :2]), 50.0, rtol=1e-12)
    assert np.all(jump[:, 2] == 0.0)
    expected, spread = n * SPIKE_PROBABILITY, math.sqrt(n * SPIKE_PROBABILITY)
    assert abs(hit.sum() - expected) < 4.0 * spread
    assert np.array_equal(readings(faulty("spikes-ft:50"), n)[2], spiky)


@pytest.mark.parametrize("period", [0.01, 0.001])
def test_a_delay_reports_the_sample_taken_that_much_earlier(period: float) -> None:
    n = round(3.0 / period)
    times, clean_poses, clean = readings(SensorParams(), n, period=period)
    _, poses, wrenches = readings(faulty("delay:0.25@1"), n, period=period)
    lag = round(0.25 / period)
    after = np.flatnonzero(times >= 1.0 - 1e-9)
    np.testing.assert_array_equal(wrenches[after], clean[after - lag])
    np.testing.assert_array_equal(poses[after], clean_poses[after - lag])
    np.testing.assert_array_equal(wrenches[: after[0]], clean[: after[0]])
    # from the start of the run there is nothing that old yet: NaN until there is
    _, _, late = readings(faulty("delay:0.25"), n, period=period)
    assert np.isnan(late[:lag]).all()
    np.testing.assert_array_equal(late[lag:], clean[:-lag])


@pytest.mark.parametrize(
    ("text", "fault"),
    [
        ("dropout:0.3", Fault("dropout", 0.3)),
        ("dead-ft", Fault("dead-ft")),
        ("  stuck-ft@2.5 ", Fault("stuck-ft", None, 2.5)),
        ("scale-ft:0.1@1", Fault("scale-ft", 0.1, 1.0)),
        ("scale-ft:-1", Fault("scale-ft", -1.0)),
        ("bias-ft:5", Fault("bias-ft", 5.0)),
        ("spikes-ft:50@0", Fault("spikes-ft", 50.0)),
        ("delay:0.05", Fault("delay", 0.05)),
        ("delay:10", Fault("delay", 10.0)),
        ("dead-pose@1e1", Fault("dead-pose", None, 10.0)),
    ],
)
def test_the_fault_syntax(text: str, fault: Fault) -> None:
    assert parse_fault(text) == fault
    assert parse_fault(str(fault)) == fault


@pytest.mark.parametrize(
    ("text", "message"),
    [
        ("", "is not KIND"),
        ("dropout:0.3:1", "must be numbers"),
        ("frozen-ft", "unknown sensor fault 'frozen-ft'"),
        ("dropout", "needs a value"),
        ("dropout:", "must be numbers"),
        ("dead-ft:3", "takes no value"),
        ("dropout:1.5", r"dropout probability must be in \[0, 1\], got 1.5"),
        ("dropout:nan", "must be finite"),
        ("scale-ft:inf", "must be finite"),
        ("scale-ft:1e999", "must be finite"),
        ("bias-ft:x", "must be numbers"),
        ("delay:-0.1", r"delay must be in \[0, 10\] s"),
        ("delay:11", r"delay must be in \[0, 10\] s"),
        ("dead-ft@-1", "start must be at least 0"),
        ("dead-ft@nan", "must be finite"),
        ("dead-ft@", "must be numbers"),
    ],
)
def test_bad_faults_are_one_line_naming_the_text(text: str, message: str) -> None:
    with pytest.raises(ValueError, match=message) as error:
        parse_fault(text)
    assert repr(text) in str(error.value) and "\n" not in str(error.value)


def test_faults_are_validated_where_they_are_made() -> None:
    with pytest.raises(TypeError, match="real number"):
        Fault("bias-ft", True)
    with pytest.raises(TypeError, match="real number"):
        Fault("dead-ft", None, "1")
    with pytest.raises(TypeError, match="sequence of Fault"):
        SensorParams(faults="dead-ft")
    with pytest.raises(TypeError, match="sequence of Fault"):
        SensorParams(faults=(Fault("dead-ft"), "stuck-ft"))
    params = SensorParams(faults=[Fault("dead-ft")])
    assert params.faults == (Fault("dead-ft"),) and hash(params)
    assert Fault("delay", 1).value == 1.0 and isinstance(Fault("delay", 1).value, float)
