"""Where the face under the hand is known (ccopt.estimation.face): its evidence rules, and in closed
loop against the simulator's truth: the known face lies inside the true one, and a goal run on an
object whose face ends inside the hand's reach claims nothing it did not reach."""

import dataclasses
import math

import numpy as np
import pytest

from ccopt import statics
from ccopt.closed_loop import LoopParams
from ccopt.estimation.face import NO_FACE, UNKNOWN_FACE, FaceEstimator, FaceParams
from ccopt.experiment import oracle_frame, run_experiment
from ccopt.objects import from_vertices
from ccopt.schedule import Schedule, exploration, reach

L_H = 0.03
MARGIN = FaceParams().margin


def _estimator(**params) -> FaceEstimator:
    return FaceEstimator(L_H, FaceParams(**params))


def _hold(face: FaceEstimator, s_h: float, valid: bool = True, d: float = 0.08, slides: bool = False):
    """A sample that shows no centre of pressure (below the force threshold)."""
    return face.update(valid, s_h, d, True, 0.5, 0.0, slides)


def test_the_face_is_unknown_until_the_kinematics_are_valid_then_the_hand_at_the_start():
    face = _estimator()
    assert _hold(face, math.nan, valid=False) == UNKNOWN_FACE
    assert _hold(face, -0.01) == pytest.approx((-L_H + 0.01 + MARGIN, L_H + 0.01 - MARGIN))


def test_the_start_follows_the_estimate_until_the_hand_slides_then_stays():
    face = _estimator()
    _hold(face, -0.010)
    assert _hold(face, -0.012) == pytest.approx((-L_H + 0.012 + MARGIN, L_H + 0.012 - MARGIN))
    _hold(face, -0.012, slides=True)
    assert _hold(face, 0.005, slides=True) == pytest.approx((-L_H + 0.012 + MARGIN, L_H + 0.012 - MARGIN))


def test_while_the_hand_is_not_commanded_to_slide_the_face_stays_where_it_is_on_the_hand():
    """A change of ``ŝ_h`` the hand was not commanded to make is the estimate improving: the face,
    centres of pressure included, stays on the hand. (A paper hexagon's kinematics found again after
    it rocked over its bottom face took ``ŝ_h`` 41 mm off and corrected it by 30 mm over the next
    16 s; the face, kept in ``u``, cut the hand 12 mm from its centre, 34 mm inside the true face's
    end, and a ground slide ended `rolled` with the hand flush and its centre of pressure 13 mm from
    the hand's centre.)"""
    face = _estimator()
    _hold(face, 0.0)
    _hold(face, 0.0, slides=True)  # the start's evidence is no longer the hand's extent
    face.update(True, 0.0, 0.08, True, 10.0, 0.2, False)  # c = −20 mm
    known = np.array(_hold(face, 0.0))
    assert np.array(_hold(face, 0.02)) + 0.02 == pytest.approx(known)  # on the hand: as it was
    assert np.array(_hold(face, 0.03, slides=True)) == pytest.approx(known - 0.02)  # slid: fixed in u


def test_without_the_start_a_centre_of_pressure_is_all_that_is_known():
    face = _estimator(start_on_face=False)
    assert _hold(face, 0.0) == NO_FACE
    # τ = −c f_n: a push at c = +10 mm with s_h = 2 mm is at u = 8 mm, the torque noise inside it
    known = face.update(True, 0.002, 0.08, True, 10.0, -0.1, False)
    assert known[0] > known[1]  # one point is no interval
    known = face.update(True, 0.002, 0.08, True, 10.0, 0.1, False)  # c = −10 mm: u = −12 mm
    noise = FaceParams().torque_noise / 10.0
    assert known == pytest.approx((-0.012 + noise + MARGIN, 0.008 - noise - MARGIN))


def test_a_sample_not_flush_or_below_the_force_threshold_shows_nothing():
    face = _estimator(start_on_face=False)
    _hold(face, 0.0)
    assert face.update(True, 0.0, 0.08, False, 10.0, -0.2, False) == NO_FACE
    assert face.update(True, 0.0, 0.08, True, 2.0, -0.04, False) == NO_FACE


def test_found_again_on_the_same_vertex_after_a_slide_the_face_is_kept_in_u():
    face = _estimator()
    known = _hold(face, -0.01)
    assert _hold(face, math.nan, valid=False, slides=True) == UNKNOWN_FACE
    assert _hold(face, -0.02, d=0.081) == pytest.approx(known)  # the hand slid while lost: same u


def test_found_again_without_a_slide_the_face_stays_on_the_hand_whatever_d():
    """Same ``d̂``, ``ŝ_h`` 51 mm off: a paper hexagon rocking over its bottom face (parallel to the
    hand's face, so both its vertices have the same ``d``) found again mid-rock. Kept in ``u``, the
    known face reached 53 mm past the hand's end."""
    face = _estimator()
    known = np.array(_hold(face, -0.03))
    _hold(face, math.nan, valid=False)
    assert np.array(_hold(face, 0.021, d=0.08)) + 0.021 == pytest.approx(known - 0.03)


def test_on_another_vertex_the_face_moves_with_the_hand_unless_the_hand_slid():
    face = _estimator()
    start = _hold(face, -0.01)
    _hold(face, math.nan, valid=False)
    moved = _hold(face, 0.03, d=0.05)  # the object rolled: s_h jumped by 40 mm, the hand stayed
    assert moved == pytest.approx((start[0] - 0.04, start[1] - 0.04))
    _hold(face, math.nan, valid=False, slides=True)
    assert _hold(face, 0.0, d=0.08) == NO_FACE


def test_bad_parameters_raise():
    with pytest.raises(TypeError, match="start_on_face"):
        FaceParams(start_on_face=1)
    with pytest.raises(ValueError, match="margin"):
        FaceParams(margin=-1e-3)
    with pytest.raises(ValueError, match="half_length"):
        FaceEstimator(0.0)


# --- closed loop, against the truth ----------------------------------------------------------------

SHORT_FACE = dict(  # a goals-study quadrilateral: the start puts the hand 2 mm from its face's end
    vertices=np.array(
        [
            [0.05063226206373614, 0.01062594403452077],
            [-0.05185353444533505, 0.02414251727101307],
            [-0.039634155772953185, -0.05436648240001579],
            [0.03547308830328009, -0.043756841200247934],
        ]
    ),
    mass=0.8605628037822087,
    mu_hand=0.35271888933985646,
    mu_ground=0.6718765511708074,
)
GOALS = (
    (None, 10.0, None),
    (2.788733853924695, None, 10.0),
    (31.588733853924694, None, 10.0),
    (None, -10.0, None),
)


@pytest.fixture(scope="module")
def short_face_run():
    obj = from_vertices(**SHORT_FACE)
    schedule = Schedule("short-face", (*exploration(), *(reach(*goal) for goal in GOALS)))
    params = LoopParams(plant="planar")
    done = run_experiment(obj, schedule, params, seed=2078861726)
    return done, oracle_frame(obj, params, done.result.hand_angle_range)


def test_the_known_face_lies_inside_the_true_face(short_face_run):
    done, frame = short_face_run
    data = done.result.samples
    true_low, true_high = frame.truth.statics.face
    on_start_vertex = np.abs(np.asarray(data["true_d"]) - frame.truth.statics.d) < 1e-3
    known = np.asarray(data["est_face"])
    judged = on_start_vertex & np.isfinite(known).all(axis=1) & (known[:, 0] <= known[:, 1])
    assert judged.sum() > 1000
    assert np.all(known[judged, 0] >= true_low - 5e-4) and np.all(known[judged, 1] <= true_high + 5e-4)


def test_no_goal_is_claimed_that_the_truth_does_not_hold(short_face_run):
    """Before the face was known, the planner slid the hand 21 mm past the face's end; a slide back
    then needed the centre of pressure 12 mm beyond it, the object rolled 4° under the hand, and the
    next two goals were reported reached 18° and 47° off."""
    done, _ = short_face_run
    goals = done.summary["goals"]
    assert all(goal["within_tolerance"] for goal in goals if goal["status"] == "reached")
    assert sum(goal["status"] == "reached" for goal in goals) >= 2
    assert done.summary["unintended_slips"] == 0


def test_the_oracle_s_face_is_the_polygon_s_and_cuts_a_hand_past_its_end():
    """The true face (:func:`ccopt.statics.true_statics`) is as long as the polygon's face, covers the
    hand at the start, and leaves a hand slid past its end (5 mm of it on the face) a shorter patch:
    less margin to hold."""
    obj = from_vertices(**SHORT_FACE)
    frame = oracle_frame(obj, LoopParams(plant="planar"), (-1.0, 1.0))
    truth = frame.truth
    low, high = truth.statics.face
    assert high - low == pytest.approx(obj.face_length(obj.face_index(frame.start.hand_face)), abs=1e-9)
    assert low <= -L_H - truth.s_h and L_H - truth.s_h <= high
    past_end = dict(theta_o=truth.theta_o, s_h=0.025 - low, motion="hold", l_h=L_H, force_limits=(3.0, 25.0))
    cut = statics.best_wrench(truth.statics, **past_end)
    whole = statics.best_wrench(dataclasses.replace(truth.statics, face=statics.WHOLE_HAND), **past_end)
    assert cut.margin < whole.margin - 0.5
