"""The closed loop on the planar plant (and, for the paper's Panda cases, the Panda plant), scored
against the simulator's ground truth."""

import math

import numpy as np
import pytest

from ccopt import closed_loop, metrics, record
from ccopt.objects import PAPER_ADDED_MASS, make_object
from ccopt.plant.mujoco_planar import PlanarPlant
from ccopt.plant.sensors import SensorParams, parse_fault
from ccopt.schedule import Goal, load_schedule


@pytest.fixture(scope="module")
def smoke_run():
    schedule = load_schedule("smoke")
    result = closed_loop.run(make_object("paper-triangle"), schedule, seed=3)
    return result, metrics.summarize(result, schedule)


def test_smoke_schedule_completes_with_the_commanded_rotations(smoke_run):
    result, summary = smoke_run
    assert summary["completed"] and summary["contact_kept"]
    assert summary["steps_done"] == summary["steps_total"]
    ratios = metrics.realised_ratios(result.samples, [vars(s) for s in result.steps])
    assert len(ratios) == 4
    assert np.all((ratios > 0.85) & (ratios < 1.15)), ratios  # true θ_o change / commanded change


def test_every_other_contact_keeps_its_mode(smoke_run):
    _, summary = smoke_run
    assert summary["unintended_slips"] == 0, summary["slip_events"]


PAPER_OBJECTS = ("triangle", "square", "rectangle", "pentagon", "hexagon")
PAPER_CASES = [(name, 0.0, "planar") for name in PAPER_OBJECTS] + [
    ("triangle", PAPER_ADDED_MASS, "planar"),
    ("pentagon", PAPER_ADDED_MASS, "planar"),
    ("triangle", 0.0, "panda"),
    ("square", 0.0, "panda"),
]
FIRST_VALID_DEG = 15.0  # of pivoting, issue 10's "after the first ~15°"


@pytest.mark.parametrize(
    ("name", "added_mass", "plant"), PAPER_CASES, ids=[f"{n}+{m}kg-{p}" for n, m, p in PAPER_CASES]
)
def test_every_paper_case_has_valid_kinematics_within_15_degrees_of_pivoting(
    name: str, added_mass: float, plant: str
):
    """The smoke run estimates the kinematics within issue 10's bar on each of the seven paper cases
    on the planar plant and the two on the Panda: its pivots (about 29° of turning in all) make the
    kinematics valid before the object has turned 15° by the truth (measured over seeds 0–2:
    7.3–13.8°), they stay valid, and the estimates match the truth (metrics.estimation_errors scores
    the valid samples: θ_o 1°, s_h and s_g 3 mm, medians), with no unintended slip."""
    schedule, params = load_schedule("smoke"), closed_loop.LoopParams(plant=plant)
    result = closed_loop.run(make_object(f"paper-{name}", added_mass=added_mass), schedule, params, seed=1)
    summary = metrics.summarize(result, schedule)
    valid = np.asarray(result.samples["est_kinematics_valid"])
    theta = np.asarray(result.samples["true_coordinates"])[:, 0]
    turned = np.concatenate([[0.0], np.cumsum(np.abs(np.diff(theta)))])
    first = int(np.argmax(valid))
    assert summary["completed"] and summary["unintended_slips"] == 0, summary["slip_events"]
    assert valid.any() and turned[first] < math.radians(FIRST_VALID_DEG), math.degrees(turned[first])
    assert valid[first:].mean() > 0.95
    bar = metrics.Thresholds()
    assert summary["theta_err_deg"]["median"] <= bar.theta_err_deg
    assert summary["s_h_err_mm"]["median"] <= bar.s_h_err_mm
    assert summary["s_g_err_mm"]["median"] <= bar.s_g_err_mm


def test_the_pivots_return_the_object_to_its_start(smoke_run):
    result, _ = smoke_run
    true_theta = result.samples["true_coordinates"][:, 0]
    assert abs(true_theta[-1] - true_theta[0]) < np.deg2rad(1.0)


def test_runs_are_deterministic_for_a_seed():
    schedule = load_schedule("smoke")
    first = closed_loop.run(make_object("paper-pentagon"), schedule, seed=7)
    second = closed_loop.run(make_object("paper-pentagon"), schedule, seed=7)
    for key in ("hand_pose", "hand_wrench", "target", "true_coordinates"):
        np.testing.assert_array_equal(first.samples[key], second.samples[key])


def test_an_interrupted_run_keeps_its_record(tmp_path):
    def interrupt(sim_time, index, total):
        if sim_time > 0.8:
            raise KeyboardInterrupt

    result = closed_loop.run(
        make_object("paper-hexagon"), load_schedule("smoke"), seed=0, out=tmp_path / "run", on_tick=interrupt
    )
    assert result.interrupted
    kept = record.load_record(tmp_path / "run")
    assert kept.meta["status"] == "interrupted"
    assert 0.75 < kept["time"][-1] < 0.9
    assert len(kept["time"]) == len(kept["true_coordinates"])


def test_a_run_interrupted_before_its_first_sample_did_not_begin(tmp_path, monkeypatch):
    """Ctrl-C in the loop's first tick, before a sample is recorded (seen in CI on a loaded machine):
    the run raises ``KeyboardInterrupt`` as while starting and leaves an unstarted run's folder, which
    :func:`ccopt.record.discard_unstarted` removes (not an empty ``interrupted`` record)."""

    def interrupt(self, *args, **kwargs):
        raise KeyboardInterrupt

    monkeypatch.setattr(closed_loop.Estimator, "update", interrupt)
    out = tmp_path / "run"
    with pytest.raises(KeyboardInterrupt):
        closed_loop.run(make_object("paper-triangle"), load_schedule("smoke"), seed=0, out=out)
    assert record.load_record(out).meta["status"] == "running"
    assert record.discard_unstarted(out) and not list(out.iterdir())
    with pytest.raises(KeyboardInterrupt):
        closed_loop.run(make_object("paper-triangle"), load_schedule("smoke"), seed=0)


def test_a_run_that_ends_early_reports_every_goal_it_never_began(tmp_path):
    """Interrupted in the exploration, before its first goal: every goal step of the schedule has a
    result, in the schedule's order, ``failed`` as not begun (a study that counts the results would
    otherwise leave them out of its denominators), and the record's ``meta.json`` has them too."""
    schedule = load_schedule("paper")
    goal_indices = [k for k, item in enumerate(schedule.steps) if isinstance(item, Goal)]
    assert goal_indices and goal_indices[0] > 0

    def interrupt(sim_time, index, total):
        if sim_time > 0.5:
            raise KeyboardInterrupt

    result = closed_loop.run(
        make_object("paper-triangle"), schedule, seed=0, out=tmp_path / "run", on_tick=interrupt
    )
    assert result.interrupted
    assert [goal.index for goal in result.goals] == goal_indices
    assert all(goal.status == "failed" and goal.reason.startswith("not begun") for goal in result.goals)
    kept = record.load_record(tmp_path / "run")
    assert [goal["index"] for goal in kept.meta["goals"]] == goal_indices


def test_bad_loop_parameters_raise():
    with pytest.raises(ValueError, match="controller_hz"):
        closed_loop.LoopParams(controller_hz=0.0)
    with pytest.raises(ValueError, match=r"estimator_hz must be in \[1, 1000\] Hz"):
        closed_loop.LoopParams(estimator_hz=1e-310)  # one tick a googol of years: refused
    with pytest.raises(ValueError, match="unknown plant 'robot'"):
        closed_loop.LoopParams(plant="robot")


def test_a_run_without_a_sample_is_summarised_with_the_same_keys_and_nothing_measured(smoke_run):
    _, measured = smoke_run
    summary = metrics.summarize({}, [], 5, 0.0, 0.01, status="error")
    assert summary.keys() == measured.keys() and summary["status"] == "error"
    assert not summary["completed"] and summary["steps_done"] == 0 and summary["steps_total"] == 5
    assert summary["theta_err_deg"]["median"] is None and summary["normal_force_n"]["max"] is None
    assert summary["ratio_by_kind"].keys() == measured["ratio_by_kind"].keys()
    assert summary["mode_confusion"].keys() == measured["mode_confusion"].keys()


def test_the_target_holds_still_from_the_first_reading_a_dropout_loses():
    """A reading without a pose or a wrench stops the target at once, not at the next control tick:
    between two lost readings in a row the recorded target does not move (issue 12). Without the
    fault the target moves between most pairs of readings, so the check can fail."""
    faults = (parse_fault("dropout:0.3@0.5"),)
    params = closed_loop.LoopParams(sensor_params=SensorParams(faults=faults))
    result = closed_loop.run(make_object("paper-triangle"), load_schedule("smoke"), params, seed=1)
    samples = result.samples
    lost = ~(np.isfinite(samples["hand_pose"]).all(axis=1) & np.isfinite(samples["hand_wrench"]).all(axis=1))
    moved = np.abs(np.diff(samples["target"], axis=0)).max(axis=1) > 0.0
    in_a_row = lost[1:] & lost[:-1]
    assert in_a_row.sum() > 20 and moved[~lost[1:] & ~lost[:-1]].mean() > 0.5
    assert not moved[in_a_row].any(), samples["time"][1:][in_a_row & moved]


def failing_after(monkeypatch, start: float, until: float = np.inf) -> None:
    """The controller's compiled tick reports a failed QP solve (no output) while the plant's time
    is in [start, until)."""
    from ccopt.control import tick

    call, clock = tick.Tick.__call__, {"time": 0.0}
    advance = closed_loop._Loop._advance_plant

    def timed(self):
        advance(self)
        clock["time"] = self.plant.time

    def broken(self, *inputs):
        out = call(self, *inputs)
        return None if start <= clock["time"] < until else out

    monkeypatch.setattr(closed_loop._Loop, "_advance_plant", timed)
    monkeypatch.setattr(tick.Tick, "__call__", broken)


def test_a_solver_that_keeps_failing_ends_the_run_as_an_error(monkeypatch):
    """No finite step for ``solver_grace`` (0.2 s): status ``error`` naming the solver, the target held
    from the first failed tick (it had been moving), not a run that times out its steps (issue 12)."""
    failing_after(monkeypatch, start=0.8)
    result = closed_loop.run(make_object("paper-triangle"), load_schedule("smoke"), seed=1)
    assert result.status == "error" and "QP solver gave no finite step from t = 0.8" in result.message
    assert 1.0 <= result.sim_time <= 1.0 + 2.0 / 30.0  # 0.2 s after the first failure, within a tick
    time, target = result.samples["time"], result.samples["target"]
    failed = time > 0.8 + 1.0 / 30.0
    np.testing.assert_array_equal(target[failed], np.broadcast_to(target[failed][0], target[failed].shape))
    assert np.abs(np.diff(target[(time > 0.5) & (time < 0.8)], axis=0)).max() > 0.0


def test_a_solver_failing_briefly_holds_and_the_run_completes(monkeypatch):
    failing_after(monkeypatch, start=0.8, until=0.9)
    result = closed_loop.run(make_object("paper-triangle"), load_schedule("smoke"), seed=1)
    assert result.status == "completed"
    time = result.samples["time"]
    assert not result.samples["qp_feasible"][(time > 0.84) & (time < 0.9)].all()


def test_the_target_turns_no_further_than_the_robot_reaches(monkeypatch, smoke_run):
    """The impedance target's angle stays within the plant's ``target_angle_range``: with the reach
    cut to 3° above the start, the smoke schedule's first pivot (+7.2°, within the hand's range, so
    not refused) turns the target to that end and holds it there, the hand runs on past it by no more
    than its lag (0.2° here; the Panda's target range leaves its joints 0.03 rad, 1.7°, inside their
    limits), and the run reports the time held. The same run with the plant's own range turns the target past
    that end, so the check can fail."""
    end = 0.3 + math.radians(3.0)  # the start's θ_o (flush hand) and 3°
    free, _ = smoke_run
    assert free.target_at_reach == 0.0
    assert np.asarray(free.samples["target"])[:, 2].max() > end + math.radians(3.0)
    monkeypatch.setattr(PlanarPlant, "target_angle_range", property(lambda self: (-math.pi / 2, end)))
    result = closed_loop.run(make_object("paper-triangle"), load_schedule("smoke"), seed=3)
    target = np.asarray(result.samples["target"])[:, 2]
    hand = np.asarray(result.samples["true_hand_pose"])[:, 2]
    assert target.max() <= end and np.isclose(target.max(), end, rtol=0.0, atol=1e-12)
    assert hand.max() <= end + math.radians(0.5)
    assert result.target_at_reach > 0.1
    assert result.steps[1].status == "timeout"
