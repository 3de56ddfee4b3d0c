"""Closed-loop studies: the paper's experiment, robustness over random objects, perturbation rejection."""

import json

import numpy as np
import pytest

from ccopt import closed_loop, metrics, statics
from ccopt.closed_loop import LoopParams
from ccopt.metrics import failure_causes, recovery_time
from ccopt.objects import make_object
from ccopt.schedule import load_schedule
from studies import paper, perturbation, robustness, runner
from studies.perturbation import Push

SMALL = ["--schedule", "smoke", "--workers", "1", "--no-progress"]


def read_results(folder):
    return json.loads((folder / "results.json").read_text())


# --- paper ----------------------------------------------------------------------------------------


@pytest.fixture(scope="module")
def paper_study(tmp_path_factory):
    out = tmp_path_factory.mktemp("paper")
    code = paper.main([*SMALL, "--trials", "2", "--seed", "5", "--out", str(out)])
    return code, out


def test_paper_study_writes_its_table_and_figures(paper_study):
    code, out = paper_study
    assert code == 0
    results = read_results(out)
    assert len(results["trials"]) == 2 and (out / "results.csv").is_file()
    assert results["summary"]["trials"] == 2
    for name in ("estimation_error_boxes.png", "realised_histogram.png", "friction_cones_trial0.png"):
        assert (out / name).stat().st_size > 0
    assert (out / "trials" / "1" / "record.npz").is_file()


def test_paper_trial_numbers_equal_a_direct_run(paper_study):
    _, out = paper_study
    trial = read_results(out)["trials"][1]
    spec, row = trial["spec"], trial["result"]
    assert (spec["object"], spec["added_mass"]) == paper.TRIALS[1]
    schedule = load_schedule("smoke")
    obj = make_object(spec["object"], mu_hand=0.5, mu_ground=0.8)
    result = closed_loop.run(obj, schedule, LoopParams(), seed=spec["seed"])
    steps = [step.as_dict() for step in result.steps]
    direct = metrics.summarize(result.samples, steps, len(schedule.steps), result.sim_time, result.wall_time)
    assert row["completed"] == direct["completed"]
    assert row["steps_done"] == direct["steps_done"]
    assert row["unintended_slips"] == direct["unintended_slips"]
    assert row["infeasible_share"] == pytest.approx(direct["infeasible_ticks_share"], abs=1e-12)
    for key, stat in (("ratio_median", "median"), ("ratio_q25", "q25"), ("ratio_q75", "q75")):
        assert row[key] == pytest.approx(direct["ratio_realised_commanded"][stat], abs=1e-12)
    for key in ("theta_err_deg", "s_h_err_mm", "s_g_err_mm"):
        assert row[f"{key}_median"] == direct[key]["median"]


def test_a_tour_trial_runs_the_objects_own_tour_that_the_oracle_finds_possible(tmp_path):
    """``--schedule tour``: each object its own tour; the oracle (the statics LP on the true object)
    finds every step possible, and the trial runs all of them with the tour's start."""
    spec = paper.PaperTrial(0, "paper-square", 0.0, 3, "tour", "planar", 0.5, 0.8, str(tmp_path / "t"))
    obj = make_object(spec.object, mu_hand=spec.mu_hand, mu_ground=spec.mu_ground)
    schedule, params = runner.trial_run(obj, "tour", LoopParams())
    assert not params.centre_hand and any(step.kind == "slide_ground" for step in schedule.steps)
    feasibility = statics.schedule_feasibility(
        obj, schedule.steps, closed_loop.start_config(obj, params), params.hand
    )
    assert statics.impossible_steps(feasibility) == []
    row = paper.paper_trial(spec)
    assert row["impossible_steps"] == [] and row["steps_total"] == len(schedule.steps)
    meta = json.loads((tmp_path / "t" / "meta.json").read_text())
    assert meta["params"]["start"]["s_h"] == pytest.approx(params.start.s_h)


def test_misses_name_each_threshold():
    """Each threshold of issue 10's bar is named when missed, at its boundary met; a kind of motion
    that did not run (median None) is not judged."""
    summary = {
        "completed": True,
        "theta_err_deg": {"median": 0.5},
        "s_h_err_mm": {"median": None},
        "s_g_err_mm": {"median": 3.5},
        "ratio_realised_commanded": {"median": 1.2},
        "ratio_by_kind": {
            "pivot": {"median": 0.89},
            "slide_hand": {"median": None},
            "slide_ground": {"median": 1.11},
        },
        "kinematics_valid_share": 0.79,
        "normal_force_n": {"max": 27.1},
        "unintended_slips": 1,
    }
    assert metrics.misses(summary) == [
        "s_h_err",
        "s_g_err",
        "ratio",
        "ratio_pivot",
        "ratio_slide_ground",
        "valid_share",
        "normal_force",
        "slips",
    ]
    summary.update(
        s_h_err_mm={"median": 1.0},
        s_g_err_mm={"median": 3.0},
        ratio_realised_commanded={"median": 1.0},
        ratio_by_kind={
            "pivot": {"median": 0.9},
            "slide_hand": {"median": None},
            "slide_ground": {"median": 1.1},
        },
        kinematics_valid_share=0.8,
        normal_force_n={"max": 27.0},
        unintended_slips=0,
    )
    assert metrics.misses(summary) == []


# --- robustness -----------------------------------------------------------------------------------


def test_robustness_study_runs_and_classifies(tmp_path):
    assert robustness.main([*SMALL, "--trials", "2", "--out", str(tmp_path)]) == 0
    results = read_results(tmp_path)
    assert len(results["trials"]) == 2 and (tmp_path / "robustness.png").is_file()
    for trial in results["trials"]:
        assert trial["result"]["success"] == (trial["result"]["causes"] == [])
    spec = results["trials"][0]["spec"]
    assert 0.07 <= spec["side"] <= 0.19 and 0.2 <= spec["mass"] <= 0.95


def summary_with(**changes):
    base = {
        "completed": True,
        "steps_done": 5,
        "steps_total": 5,
        "contact_kept": True,
        "unintended_slips": 0,
        "slip_events": [],
        "infeasible_ticks_share": 0.0,
        "kinematics_resets": 0,
    }
    return {**base, **changes}


def slip(contact):
    return {"step": 2, "contact": contact, "excursion": 0.01}


@pytest.mark.parametrize(
    ("changes", "causes"),
    [
        ({}, []),
        ({"completed": False, "steps_done": 3}, ["timeout"]),
        ({"completed": False, "contact_kept": False}, ["loss of contact"]),
        ({"unintended_slips": 1, "slip_events": [slip("ground_slide")]}, ["slip at the ground"]),
        ({"unintended_slips": 1, "slip_events": [slip("hand_slide")]}, ["slip at the hand"]),
        ({"unintended_slips": 1, "slip_events": [slip("hand_pivot")]}, ["hand pivot"]),
        ({"completed": False, "steps_done": 4, "infeasible_ticks_share": 0.5}, ["infeasible QP"]),
        ({"completed": False, "steps_done": 4, "kinematics_resets": 2}, ["estimator reset"]),
        (
            {
                "completed": False,
                "steps_done": 1,
                "unintended_slips": 2,
                "slip_events": [slip("hand_slide"), slip("ground_slide")],
                "infeasible_ticks_share": 0.3,
            },
            ["slip at the ground", "slip at the hand", "infeasible QP"],
        ),
        ({"infeasible_ticks_share": 0.5, "kinematics_resets": 1}, []),  # succeeded anyway
        (
            {"completed": False, "steps_done": 1, "impossible_steps": [1, 7]},
            ["impossible step"],
        ),
        ({"impossible_steps": [3]}, []),  # an impossible step is no failure if the run succeeded
    ],
)
def test_failure_causes_from_hand_made_summaries(changes, causes):
    assert failure_causes(summary_with(**changes)) == causes


def test_estimator_resets_count_valid_to_invalid():
    assert metrics.kinematics_resets(np.array([0, 1, 1, 0, 0, 1, 0], dtype=bool)) == 2
    assert metrics.kinematics_resets(np.array([0, 0, 1], dtype=bool)) == 0


def test_an_object_too_small_for_the_hand_does_not_fit():
    spec = robustness.RandomObject(0, 1, "hexagon", 0.05, None, 0.3, 0.5, 0.8, "smoke", "planar")
    assert robustness.robustness_trial(spec) == {
        "fits_hand": False,
        "success": False,
        "causes": ["does not fit the hand"],
    }


# --- perturbation ---------------------------------------------------------------------------------


def test_perturbation_study_writes_its_table_and_figure(tmp_path):
    argv = ["--coordinates", "theta_o", "--forces", "5", "--window", "1.5", "--workers", "1", "--no-progress"]
    assert perturbation.main([*argv, "--out", str(tmp_path)]) == 0
    trials = read_results(tmp_path)["trials"]
    assert [t["spec"]["direction"] for t in trials] == [1, -1]
    assert (tmp_path / "perturbation.png").stat().st_size > 0
    for trial in trials:
        assert trial["result"]["recovered"] and trial["result"]["recovery_time_s"] < 1.0


@pytest.mark.parametrize("direction", [1, -1])
def test_a_push_moves_the_object_the_way_it_pushes(direction):
    """A horizontal push at the centroid, which sits above the ground contact, turns the object about
    that contact the other way round (``θ_o`` falls for ``+x``), and a push strong enough to slide the
    ground contact slides it along the push."""
    turn = perturbation.perturbation_trial(
        Push("theta_o", 1, direction, 10.0, 0.15, 0.5, 1.0, "paper-triangle", "planar", 0)
    )
    assert np.sign(turn["peak_error"]) == -direction and abs(turn["peak_error"]) > 0.5
    if direction > 0:
        slide = perturbation.perturbation_trial(
            Push("s_g", 1, 1, 14.0, 0.15, 0.5, 1.0, "paper-triangle", "planar", 0)
        )
        assert slide["peak_error"] > 1e3 * metrics.SLIP_DISTANCE and slide["contact_kept"]  # it slid, mm


def test_recovery_time_on_a_synthetic_trace():
    time = np.arange(-0.5, 3.0, 0.01)
    error = np.where(time < 0.0, 0.0, 3.0 * np.exp(-time / 0.4))  # leaves tolerance 1 until 0.4 ln 3
    expected = 0.4 * np.log(3.0)
    assert recovery_time(time, error, 1.0) == pytest.approx(expected, abs=0.011)
    assert recovery_time(time, error + 2.0 * (time > 2.0), 1.0) is None  # out again at the end
    assert recovery_time(time, 0.5 * np.sin(time), 1.0) == 0.0  # never left
    bounced = error.copy()
    bounced[(time > 1.5) & (time < 1.6)] = -1.5
    assert recovery_time(time, bounced, 1.0) == pytest.approx(1.6, abs=0.011)


# --- command line ---------------------------------------------------------------------------------


@pytest.mark.parametrize(
    ("study", "argv", "message"),
    [
        (paper.main, ["--trials", "11"], "--trials must be at most 10"),
        (paper.main, ["--schedule", "nope"], "unknown schedule 'nope'"),
        (paper.main, ["--plant", "robot"], "invalid choice: 'robot'"),
        (robustness.main, ["--trials", "0"], "'0' must be at least 1"),
        (perturbation.main, ["--forces", "5,-1"], "'-1' must be a positive number"),
        (perturbation.main, ["--coordinates", "x_o"], "unknown coordinate 'x_o'"),
        (perturbation.main, ["--object", "blob"], "unknown object 'blob'"),
        (perturbation.main, ["--duration", "5"], "must be shorter than --window"),
    ],
)
def test_bad_values_exit_2_with_one_line(study, argv, message, capsys, tmp_path):
    with pytest.raises(SystemExit) as ended:
        study([*argv, "--out", str(tmp_path)])
    assert ended.value.code == 2
    err = capsys.readouterr().err
    assert message in err and err.count("\n") == 1


def pushed(**changes):
    base = {
        "recovered": False,
        "contact_kept": True,
        "back_allowed": True,
        "measured_final_error": 3.0,
        "tolerance": 1.0,
        "progress_source": "hand",
    }
    return {**base, **changes}


@pytest.mark.parametrize(
    ("result", "why"),
    [
        (pushed(recovered=True), None),
        (pushed(contact_kept=False, back_allowed=False), "contact lost"),
        (pushed(back_allowed=False), "held mode"),
        (pushed(measured_final_error=-0.4), "hand, not object"),
        (pushed(back_allowed=False, measured_final_error=0.2), "held mode; hand, not object"),
        (pushed(measured_final_error=0.2, progress_source="estimate"), "estimate, not truth"),
        (pushed(), "not settled"),
        ({"error": "ValueError: x"}, "run error"),
    ],
)
def test_why_a_push_did_not_recover(result, why):
    assert perturbation.why_not_recovered(result) == why
