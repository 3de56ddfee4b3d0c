"""Offline studies: feasibility against closed forms, gradient checks, the QP-region figures, the CLI."""

import json

import numpy as np
import pytest

from ccopt import contact
from ccopt.modes import Motion
from studies import feasibility, gradients, qp_region
from studies.__main__ import main as studies_main


def test_feasibility_study_writes_points_and_heat_maps(tmp_path):
    argv = ["--out", str(tmp_path), "--workers", "1", "--no-progress", "--mu-hand", "0.3,0.7"]
    argv += ["--theta=-10:10:3", "--mu-ground", "0.8", "--mass", "0.2"]
    assert feasibility.main(argv) == 0
    lines = (tmp_path / "points.csv").read_text().splitlines()
    assert len(lines) == 1 + 2 * 3 * len(Motion)
    assert (tmp_path / "margin_000.png").stat().st_size > 10_000
    summary = json.loads((tmp_path / "results.json").read_text())["summary"]
    assert summary["motions"]["hold"]["points"] == 6 and summary["failed_trials"] == 0


# --- gradients ------------------------------------------------------------------------------------


def test_gradient_study_meets_its_tolerances(tmp_path):
    argv = ["--out", str(tmp_path), "--workers", "1", "--no-progress", "--seeds", "2"]
    argv += ["--points", "3", "--instances", "6"]
    assert gradients.main(argv) == 0
    summary = json.loads((tmp_path / "results.json").read_text())["summary"]
    contact_names = [name for name in summary if name != "qp"]
    assert len(contact_names) == len(contact.CONTACT_FUNCTIONS)
    for name in contact_names:
        assert summary[name]["max_rel"] <= gradients.CONTACT_TOLERANCE == 1e-6, name
    assert summary["qp"]["points"] >= 6
    assert summary["qp"]["max_rel"] <= gradients.QP_TOLERANCE


def test_qp_sensitivity_matches_finite_differences_on_one_instance():
    result = gradients.qp_errors(seed=7, instances=3)
    assert result["points"] == 3
    assert result["max_rel"] <= gradients.QP_TOLERANCE


# --- QP region ------------------------------------------------------------------------------------


@pytest.mark.parametrize("motion", ["pivot", "slide_hand_pos"])
def test_qp_region_writes_its_figures(tmp_path, motion):
    assert qp_region.main(["--out", str(tmp_path), "--motion", motion]) == 0
    for name in ("constraints.png", "region.png"):
        assert (tmp_path / name).stat().st_size > 10_000
    result = json.loads((tmp_path / "results.json").read_text())
    assert result["feasible"] and not result["region_empty"]
    step, vertices = np.array(result["step"]), np.array(result["region_vertices"])  # one unit: SI
    assert np.all(step >= vertices.min(axis=0) - 1e-9) and np.all(step <= vertices.max(axis=0) + 1e-9)
    assert 0.0 < np.abs(step[:2]).max() < 0.005  # a tick moves the hand by millimetres, in m


def test_qp_solution_lies_in_the_drawn_region():
    from ccopt.control.controller import Controller

    region = qp_region.compute_region(qp_region.RegionState(), Controller())
    step = region.output.solution.step * region.scale
    assert np.all(region.rows @ step <= region.upper + 1e-6)
    lows, highs = region.vertices.min(axis=0), region.vertices.max(axis=0)
    assert np.all(step >= lows - 1e-6) and np.all(step <= highs + 1e-6)
    assert region.plane is not None  # the default change is one the tick can achieve


# --- command line ---------------------------------------------------------------------------------


@pytest.mark.parametrize(
    "argv",
    [
        ["feasibility", "--workers", "0"],
        ["feasibility", "--scheduler", "not an address"],
        ["feasibility", "--mu-hand", "abc"],
        ["feasibility", "--mu-hand", "-0.2,0.5"],
        ["feasibility", "--force-limits", "3"],
        ["gradients", "--points", "0"],
        ["qp_region", "--wrench", "1,2"],
        ["qp_region", "--motion", "fly"],
        ["qp_region", "--mass", "-1"],
        ["no-such-study"],
    ],
)
def test_bad_values_give_one_line_and_exit_2(argv, capsys):
    with pytest.raises(SystemExit) as exit_info:
        studies_main(argv)
    assert exit_info.value.code == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "error" in err
    assert ("unknown study" in err) == (argv[0] == "no-such-study"), err  # the study's own check said it


def test_out_must_be_a_folder(tmp_path, capsys):
    blocker = tmp_path / "file"
    blocker.write_text("")
    with pytest.raises(SystemExit) as exit_info:
        studies_main(["gradients", "--out", str(blocker)])
    assert exit_info.value.code == 2
    assert "not a folder" in capsys.readouterr().err


def test_schedule_check_agrees_with_the_simulated_closed_loop():
    """A hand slide the statics rule out on the light triangle (its friction moment about the ground
    vertex needs more torque than a flush 6 cm hand can give) is one the closed loop cannot do flush,
    while the pivot the check accepts is done as commanded; the check uses the true object, MuJoCo
    decides independently."""
    from ccopt import closed_loop, metrics
    from ccopt.closed_loop import LoopParams
    from ccopt.experiment import check_schedule
    from ccopt.objects import make_object
    from ccopt.schedule import Schedule, hold, pivot, slide_hand

    obj = make_object("paper-triangle")
    schedule = Schedule("check", (hold(0.3), pivot(7.2), slide_hand(10.0)))
    checks = check_schedule(obj, schedule, LoopParams())
    assert [c.feasible for c in checks] == [True, True, False]
    assert checks[2].on_face and checks[2].margin < 0.0
    result = closed_loop.run(obj, schedule, seed=0)
    steps = [step.as_dict() for step in result.steps]
    ratios = metrics.realised_ratios(result.samples, steps)
    assert 0.85 < ratios[0] < 1.15  # the pivot
    failed_slide = ratios[1] < 0.85 or any(
        event["step"] == 2 for event in metrics.unintended_slips(result.samples, steps)
    )
    assert failed_slide, (ratios, metrics.unintended_slips(result.samples, steps))
