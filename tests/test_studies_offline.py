"""Offline studies: feasibility against closed forms, gradient checks, the QP-region figures, the CLI."""

import itertools
import json

import numpy as np
import pytest

from ccopt.geometry import GRAVITY
from ccopt.modes import Motion
from studies import feasibility, gradients, qp_region
from studies.__main__ import main as studies_main
from studies.feasibility import FeasibilityParams, is_feasible

# --- feasibility: closed forms on a flat object (θ_o = 0, s_h = 0, centre of mass above the contact) ----
#
# At θ_o = 0 the hand pushes down (e_n = −y, e_t = +x) from r_h = (0, d); the hand force is
# (f_t, −f_n) in the world and equilibrium about the ground contact gives τ = d f_t. With
# F = f_h + f_grav = (f_t, −f_n − m g) the six rows (torque rows over l_h) are
#   μ_h f_n + f_t,  μ_h f_n − f_t,  f_n + d f_t / l_h,  f_n − d f_t / l_h,
#   μ_g (f_n + m g) − f_t,  μ_g (f_n + m g) + f_t.
# A motion fixes f_t (its removed row = 0), every kept row becomes affine in f_n, and the margin is
# max over f_n ∈ [f_min, f_max] of their minimum. Holding picks f_t = 0 (the rows come in ± pairs).


def best_of_lines(lines, f_min, f_max):
    """max over f_n ∈ [f_min, f_max] of min_i (a_i f_n + c_i): at an end or a crossing."""
    candidates = [f_min, f_max]
    for (a1, c1), (a2, c2) in itertools.combinations(lines, 2):
        if a1 != a2:
            crossing = (c2 - c1) / (a1 - a2)
            if f_min <= crossing <= f_max:
                candidates.append(crossing)
    return max(min(a * f + c for a, c in lines) for f in candidates)


def kept_lines(p, f_t_slope, f_t_offset, removed):
    """The kept rows as (slope, offset) in f_n, for f_t = f_t_slope f_n + f_t_offset."""
    weight, k = p.mass * GRAVITY, p.d / p.l_h
    rows = {
        "hand_pos": (p.mu_hand + f_t_slope, f_t_offset),
        "hand_neg": (p.mu_hand - f_t_slope, -f_t_offset),
        "pivot_pos": (1 + k * f_t_slope, k * f_t_offset),
        "pivot_neg": (1 - k * f_t_slope, -k * f_t_offset),
        "ground_pos": (p.mu_ground - f_t_slope, p.mu_ground * weight - f_t_offset),
        "ground_neg": (p.mu_ground + f_t_slope, p.mu_ground * weight + f_t_offset),
    }
    return [line for name, line in rows.items() if name != removed]


def closed_form_margin(p, motion):
    weight = p.mass * GRAVITY
    if motion in (Motion.HOLD, Motion.PIVOT):
        lines = kept_lines(p, 0.0, 0.0, None)
    elif motion is Motion.SLIDE_HAND_POS:  # μ_h f_n + f_t = 0
        lines = kept_lines(p, -p.mu_hand, 0.0, "hand_pos")
    elif motion is Motion.SLIDE_HAND_NEG:
        lines = kept_lines(p, p.mu_hand, 0.0, "hand_neg")
    elif motion is Motion.SLIDE_GROUND_POS:  # μ_g (f_n + m g) − f_t = 0
        lines = kept_lines(p, p.mu_ground, p.mu_ground * weight, "ground_pos")
    else:
        lines = kept_lines(p, -p.mu_ground, -p.mu_ground * weight, "ground_neg")
    return best_of_lines(lines, p.f_min, p.f_max)


FLAT_CASES = [
    FeasibilityParams(mu_hand=mu_h, mu_ground=mu_g, mass=mass, d=d, com_along=0.0)
    for mu_h, mu_g, mass, d in itertools.product((0.2, 0.6, 1.1), (0.3, 0.9), (0.2, 1.0), (0.04, 0.116))
]


@pytest.mark.parametrize("motion", list(Motion), ids=lambda m: m.value)
def test_flat_object_margin_matches_closed_form(motion):
    for params in FLAT_CASES:
        expected = closed_form_margin(params, motion)
        feasible, margin = is_feasible(params, motion)
        assert margin == pytest.approx(expected, rel=1e-6, abs=1e-6), params
        assert feasible == (margin >= params.min_margin)


def test_hold_on_a_flat_object_is_limited_by_the_weakest_cone_at_full_force():
    # f_t = τ = 0, f_n = f_max: margin = f_max · min(μ_h, 1, μ_g (1 + m g / f_max))
    params = FeasibilityParams(mu_hand=0.5, mu_ground=0.8, mass=0.195, com_along=0.0)
    _, margin = is_feasible(params, Motion.HOLD)
    assert margin == pytest.approx(0.5 * params.f_max, rel=1e-6)
    wrench = feasibility.best_wrench(params, Motion.HOLD)[1]
    np.testing.assert_allclose(wrench, [params.f_max, 0.0, 0.0], atol=1e-5)


def test_hand_slides_only_if_the_hand_neither_pivots_nor_drags_the_object():
    # Hand sliding needs d μ_h < l_h (else the hand pivots first) and μ_h f_n < μ_g (f_n + m g)
    # for some allowed f_n (else the object slides on the ground first).
    short, low = FeasibilityParams(mu_hand=0.3, mu_ground=0.8, d=0.08), FeasibilityParams(mu_hand=0.3, d=0.2)
    assert is_feasible(short, Motion.SLIDE_HAND_POS)[0]  # d μ_h / l_h = 0.48
    assert not is_feasible(low, Motion.SLIDE_HAND_POS)[0]  # d μ_h / l_h = 1.2: the hand pivots
    grippy = FeasibilityParams(mu_hand=0.9, mu_ground=0.3, mass=0.2, d=0.04)
    # μ_g m g / (μ_h − μ_g) = 0.98 N < f_min = 3 N: the object slides first at every allowed force
    assert not is_feasible(grippy, Motion.SLIDE_HAND_POS)[0]
    assert is_feasible(grippy, Motion.SLIDE_GROUND_POS)[0]


def test_mirror_symmetry_of_the_slides():
    for theta in (-0.3, 0.1, 0.4):
        for pos, neg in (
            (Motion.SLIDE_HAND_POS, Motion.SLIDE_HAND_NEG),
            (Motion.SLIDE_GROUND_POS, Motion.SLIDE_GROUND_NEG),
        ):
            left = is_feasible(FeasibilityParams(theta_o=theta, com_along=0.0), pos)[1]
            right = is_feasible(FeasibilityParams(theta_o=-theta, com_along=0.0), neg)[1]
            assert left == pytest.approx(right, rel=1e-6, abs=1e-6)


def test_concurrent_threads_get_the_serial_answers():
    # trials may share a Dask worker's threads: the cached LP and buffers are per thread
    from concurrent.futures import ThreadPoolExecutor

    cases = [(p, m) for p in FLAT_CASES[:8] for m in (Motion.HOLD, Motion.SLIDE_GROUND_NEG)]
    serial = [is_feasible(p, m) for p, m in cases]
    with ThreadPoolExecutor(4) as pool:
        assert list(pool.map(lambda case: is_feasible(*case), cases)) == serial


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
    assert len(contact_names) == 7
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


def test_qp_solution_lies_in_the_drawn_region():
    from ccopt.control.controller import Controller

    region = qp_region.compute_region(qp_region.RegionState(), Controller())
    step = region.output.solution.step * qp_region.PLOT_SCALE
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
        ["qp-region", "--wrench", "1,2"],
        ["qp-region", "--motion", "fly"],
        ["qp-region", "--mass", "-1"],
        ["no-such-study"],
    ],
)
def test_bad_values_give_one_line_and_exit_2(argv, capsys):
    with pytest.raises(SystemExit) as exit_info:
        studies_main(argv)
    assert exit_info.value.code == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "error" in err


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
    steps = [vars(step) for step in result.steps]
    ratios = metrics.realised_ratios(result.samples, steps)
    assert 0.85 < ratios[0] < 1.15  # the pivot
    failed_slide = ratios[1] < 0.85 or any(
        event["step"] == 2 for event in metrics.unintended_slips(result.samples, steps)
    )
    assert failed_slide, (ratios, metrics.unintended_slips(result.samples, steps))
