"""The statics LP (ccopt.statics) against closed forms, a second solver (cvxpy + Clarabel) and itself
mirrored; the oracle on a known object."""

import dataclasses
import itertools
import math
from concurrent.futures import ThreadPoolExecutor
from typing import NamedTuple

import cvxpy as cp
import numpy as np
import pytest

from ccopt import contact, modes, statics
from ccopt.geometry import GRAVITY
from ccopt.modes import Motion

F_MIN, F_MAX = 3.0, 25.0


class Flat(NamedTuple):
    """A configuration of the reduced model (SI units): the hand flush at ``θ_o``, ``s_h``."""

    mu_hand: float = 0.5
    mu_ground: float = 0.8
    mass: float = 0.195
    d: float = 0.116
    theta_o: float = 0.0
    s_h: float = 0.0
    com_along: float = 0.0
    com_height: float = 0.077
    l_h: float = 0.05
    face: tuple[float, float] = statics.WHOLE_HAND

    def margin(self, motion: Motion) -> statics.StaticsResult:
        known = statics.ObjectStatics.of_model(
            self.mu_hand, self.mu_ground, self.mass, self.d, self.com_along, self.com_height
        )
        known = dataclasses.replace(known, face=self.face)
        return statics.best_wrench(known, self.theta_o, self.s_h, motion, self.l_h, (F_MIN, F_MAX))


# --- closed forms on a flat object (θ_o = 0, s_h = 0, centre of mass above the contact) ------------
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
    return best_of_lines(lines, F_MIN, F_MAX)


FLAT_CASES = [
    Flat(mu_hand=mu_h, mu_ground=mu_g, mass=mass, d=d)
    for mu_h, mu_g, mass, d in itertools.product((0.2, 0.6, 1.1), (0.3, 0.9), (0.2, 1.0), (0.04, 0.116))
]


@pytest.mark.parametrize("motion", list(Motion), ids=lambda m: m.value)
def test_flat_object_margin_matches_closed_form(motion):
    for params in FLAT_CASES:
        result = params.margin(motion)
        assert result.margin == pytest.approx(closed_form_margin(params, motion), rel=1e-6, abs=1e-6), params
        assert result.feasible() == (result.margin >= statics.MIN_MARGIN)


def test_hold_on_a_flat_object_is_limited_by_the_weakest_cone_at_full_force():
    # f_t = τ = 0, f_n = f_max: margin = f_max · min(μ_h, 1, μ_g (1 + m g / f_max))
    result = Flat(mu_hand=0.5, mu_ground=0.8, mass=0.195).margin(Motion.HOLD)
    assert result.margin == pytest.approx(0.5 * F_MAX, rel=1e-6)
    np.testing.assert_allclose(result.wrench, [F_MAX, 0.0, 0.0], atol=1e-5)


def test_hand_slides_only_if_the_hand_neither_pivots_nor_drags_the_object():
    # Hand sliding needs d μ_h < l_h (else the hand pivots first) and μ_h f_n < μ_g (f_n + m g)
    # for some allowed f_n (else the object slides on the ground first).
    assert Flat(mu_hand=0.3, mu_ground=0.8, d=0.08).margin(Motion.SLIDE_HAND_POS).feasible()  # 0.48
    assert not Flat(mu_hand=0.3, d=0.2).margin(Motion.SLIDE_HAND_POS).feasible()  # 1.2: the hand pivots
    grippy = Flat(mu_hand=0.9, mu_ground=0.3, mass=0.2, d=0.04)
    # μ_g m g / (μ_h − μ_g) = 0.98 N < f_min = 3 N: the object slides first at every allowed force
    assert not grippy.margin(Motion.SLIDE_HAND_POS).feasible()
    assert grippy.margin(Motion.SLIDE_GROUND_POS).feasible()


def test_gravity_moment_is_the_weight_s_moment_about_the_ground_contact():
    mass, along, height = 0.3, 0.02, 0.05
    moment = statics.GravityMoment.of_centre_of_mass(mass, along, height)
    for theta in (-0.6, 0.0, 0.35, 1.0):
        e_t, e_n = np.array([math.cos(theta), math.sin(theta)]), np.array([math.sin(theta), -math.cos(theta)])
        arm = along * e_t - height * e_n  # centre of mass relative to the ground contact
        assert moment(theta) == pytest.approx(arm[0] * -mass * GRAVITY, rel=1e-12)


def test_mirror_symmetry_of_the_slides():
    for theta in (-0.3, 0.1, 0.4):
        for pos, neg in (
            (Motion.SLIDE_HAND_POS, Motion.SLIDE_HAND_NEG),
            (Motion.SLIDE_GROUND_POS, Motion.SLIDE_GROUND_NEG),
        ):
            left = Flat(theta_o=theta).margin(pos).margin
            right = Flat(theta_o=-theta).margin(neg).margin
            assert left == pytest.approx(right, rel=1e-6, abs=1e-6)


def clarabel_margin(p: Flat, motion: Motion) -> float:
    """The same LP written independently in cvxpy (hand wrench and ground force, full equilibrium)."""
    rows, bounds = contact.model_friction_cone(p.theta_o, p.mu_hand, p.mu_ground, p.l_h, p.mass)
    # the patch: the centre of pressure −τ/f_n between the hand's and the face's ends nearer its centre
    low, high = max(-p.l_h, p.face[0] + p.s_h), min(p.l_h, p.face[1] + p.s_h)
    rows[2:4] = [[-high, 0.0, -1.0], [low, 0.0, 1.0]]
    scale = np.array([1.0, 1.0, 1.0 / p.l_h, 1.0 / p.l_h, 1.0, 1.0])
    rows, bounds = rows * scale[:, None], bounds * scale
    wrench, ground, margin = cp.Variable(3), cp.Variable(2), cp.Variable()
    e_n = np.array([math.sin(p.theta_o), -math.cos(p.theta_o)])
    e_t = np.array([math.cos(p.theta_o), math.sin(p.theta_o)])
    r_h = -p.s_h * e_t - p.d * e_n  # ground contact at the origin
    r_com = p.com_along * e_t - p.com_height * e_n
    weight = np.array([0.0, -p.mass * GRAVITY])
    force = wrench[0] * e_n + wrench[1] * e_t
    kept = np.flatnonzero(modes.kept_rows(motion))
    removed = list(modes.REMOVED_ROWS[motion])
    constraints = [
        force + ground + weight == 0,
        wrench[2] + r_h[0] * force[1] - r_h[1] * force[0] + r_com[0] * weight[1] - r_com[1] * weight[0] == 0,
        bounds[kept] - rows[kept] @ wrench >= margin,
        wrench[0] >= F_MIN,
        wrench[0] <= F_MAX,
    ]
    if removed:
        constraints.append(bounds[removed] - rows[removed] @ wrench == 0)
    problem = cp.Problem(cp.Maximize(margin), constraints)
    problem.solve(solver="CLARABEL")
    return float(margin.value) if problem.status == "optimal" else -math.inf


def test_daqp_agrees_with_clarabel_on_random_configurations():
    rng = np.random.default_rng(7)
    for _ in range(60):
        p = Flat(
            mu_hand=rng.uniform(0.1, 1.0),
            mu_ground=rng.uniform(0.3, 1.0),
            mass=rng.uniform(0.1, 1.0),
            d=rng.uniform(0.03, 0.15),
            theta_o=rng.uniform(-0.7, 0.8),
            s_h=rng.uniform(-0.04, 0.04),
            com_along=rng.uniform(-0.05, 0.05),
            com_height=rng.uniform(0.01, 0.1),
            l_h=rng.uniform(0.02, 0.05),
        )
        motion = list(Motion)[int(rng.integers(len(Motion)))]
        assert p.margin(motion).margin == pytest.approx(clarabel_margin(p, motion), abs=2e-5), (p, motion)


def test_a_face_shorter_than_the_hand_cuts_the_patch_as_clarabel_does():
    """Random faces whose ends fall inside the hand (or leave it empty): DAQP on the cut torque rows of
    :data:`ccopt.contact.patch_torque_rows` against the centre-of-pressure bounds written here."""
    rng = np.random.default_rng(11)
    cut = 0
    for _ in range(60):
        l_h, s_h = rng.uniform(0.02, 0.05), rng.uniform(-0.04, 0.04)
        low = rng.uniform(-l_h, 0.5 * l_h) - s_h
        p = Flat(
            mu_hand=rng.uniform(0.1, 1.0),
            mass=rng.uniform(0.1, 1.0),
            d=rng.uniform(0.03, 0.15),
            theta_o=rng.uniform(-0.7, 0.8),
            s_h=s_h,
            com_along=rng.uniform(-0.05, 0.05),
            l_h=l_h,
            face=(low, low + rng.uniform(0.005, 2.0 * l_h)),
        )
        motion = list(Motion)[int(rng.integers(len(Motion)))]
        ours, theirs = p.margin(motion).margin, clarabel_margin(p, motion)
        assert ours == pytest.approx(theirs, abs=2e-5), (p, motion)
        cut += ours < p._replace(face=statics.WHOLE_HAND).margin(motion).margin - 1e-3
    assert cut >= 20  # the faces bind in most cases


def test_an_empty_face_holds_nothing_and_one_beyond_the_hand_cuts_nothing():
    """An empty face is a patch whose torque rows cannot both hold: every margin is negative, by
    ``f_n`` times the gap over ``l_h`` at least (an unknown face, ``(inf, −inf)``, by far more)."""
    p = Flat(theta_o=0.3, s_h=0.01)
    for motion in Motion:
        assert p._replace(face=(0.01, -0.01)).margin(motion).margin <= -0.5 * F_MIN * 0.02 / p.l_h
        assert p._replace(face=(math.inf, -math.inf)).margin(motion).margin < -1e3
        assert p._replace(face=(-1.0, 1.0)).margin(motion).margin == p.margin(motion).margin


def test_the_best_wrench_holds_the_object():
    """The returned wrench meets every row it claims, the removed row exactly, and the moments."""
    p = Flat(theta_o=0.4, s_h=0.01, com_along=0.01)
    for motion in Motion:
        result = p.margin(motion)
        rows, bounds = contact.model_friction_cone(p.theta_o, p.mu_hand, p.mu_ground, p.l_h, p.mass)
        slack = (bounds - rows @ result.wrench) * np.array([1, 1, 1 / p.l_h, 1 / p.l_h, 1, 1])
        kept = modes.kept_rows(motion)
        assert np.all(slack[kept] >= result.margin - 1e-6)
        assert np.allclose(slack[~kept], 0.0, atol=1e-6)
        moment = statics.GravityMoment.of_centre_of_mass(p.mass, p.com_along, p.com_height)(p.theta_o)
        f_n, f_t, tau = result.wrench
        assert tau - p.d * f_t + p.s_h * f_n + moment == pytest.approx(0.0, abs=1e-6)


def test_concurrent_threads_get_the_serial_answers():
    # trials may share a Dask worker's threads: the LP's buffers are per thread
    cases = [(p, m) for p in FLAT_CASES[:8] for m in (Motion.HOLD, Motion.SLIDE_GROUND_NEG)]
    serial = [p.margin(m).margin for p, m in cases]
    with ThreadPoolExecutor(4) as pool:
        assert list(pool.map(lambda case: case[0].margin(case[1]).margin, cases)) == serial


def test_bad_statics_raise():
    with pytest.raises(ValueError, match="finite"):
        statics.ObjectStatics(0.5, np.eye(2), np.array([1.0, np.nan]), 0.1, statics.GravityMoment(0.0, 0.0))
    with pytest.raises(ValueError, match="2×2"):
        statics.ObjectStatics(0.5, np.eye(3), np.zeros(2), 0.1, statics.GravityMoment(0.0, 0.0))


def _answer_checks(x, rows, keep, lba=None, uba=None, lbx=None, ubx=None) -> tuple[float, bool]:
    """``(margin, ok)`` of :func:`statics.build_answer_checks` on an LP answer (unbounded by default)."""
    n_rows, n_x = len(rows), len(x)
    lba = [-math.inf] * n_rows if lba is None else lba
    uba = [math.inf] * n_rows if uba is None else uba
    lbx = [-math.inf] * n_x if lbx is None else lbx
    ubx = [math.inf] * n_x if ubx is None else ubx
    margin, ok = np.array(statics.build_answer_checks()(x, rows, keep, lba, uba, lbx, ubx)).ravel()
    return float(margin), bool(ok)


def test_the_answer_checks_lower_an_overstated_margin_and_refuse_what_misses_its_bounds():
    keep = [1.0, 1.0, 0.0, 0.0, 0.0, 0.0]
    x = [10.0, 1.0, 0.0, 2.0, 0.0]  # margin t = 2 N; a row is its slack less k_j t
    rows = [0.5, 1.0, 7.0, 7.0, 7.0, 7.0, 0.0, 0.0, 0.0]  # the kept rows' slack 2.5 and 3 N: at least t
    assert _answer_checks(x, rows, keep) == (2.0, True)
    short = [-2.5, *rows[1:]]  # row 0's slack −0.5 N: the margin is −0.5 N, the row 0 there
    cone_lower = [0.0] * 6 + [-math.inf] * 3
    assert _answer_checks(x, short, keep, lba=cone_lower) == (-0.5, True)
    assert not _answer_checks(x, [*short[:2], -0.1, *short[3:]], keep, lba=cone_lower)[1]  # a free row below
    assert not _answer_checks([10.0, 1.0, 0.0, math.nan, 0.0], rows, keep)[1]
    assert not _answer_checks(x, rows, keep, ubx=[9.0, *[math.inf] * 4])[1]
    assert _answer_checks(x, rows, keep, ubx=[10.0 - 1e-7, *[math.inf] * 4])[1]  # within the tolerance
