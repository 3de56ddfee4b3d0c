"""The unintended-pivot measure (ccopt.metrics.turn_from_flush, unintended_slips) against closed forms:
a hand's turn against the object counts only away from flush and from where the step began."""

import math

import numpy as np
import pytest

from ccopt.metrics import SLIP_ANGLE, turn_from_flush, unintended_slips


@pytest.mark.parametrize(
    ("degrees", "expected"),
    [
        ([1.52, 0.5, -0.48], 0.48),  # back to flush from a roll the step began with, past it elastically
        ([0.0, 1.0, 2.5], 2.5),  # away from flush
        ([1.0, 2.0, 3.0], 2.0),  # further from a roll it began with
        ([1.0, -1.5], 1.5),  # through flush to the other side
        ([-1.0, 0.5, -2.0], 1.0),  # the larger of both sides
        ([0.3], 0.0),
    ],
)
def test_turn_from_flush_is_the_distance_from_the_span_between_flush_and_the_start(degrees, expected):
    assert math.degrees(turn_from_flush(np.radians(degrees))) == pytest.approx(expected)


def _pivot_run(relative_deg: list[float]) -> tuple[dict, list[dict]]:
    n = len(relative_deg)
    data = {
        "time": np.linspace(0.0, 1.0, n),
        "true_slip_rates": np.zeros((n, 2)),
        "true_coordinates": np.column_stack([np.radians(relative_deg), np.zeros(n), np.zeros(n)]),
        "true_hand_pose": np.zeros((n, 3)),
    }
    return data, [{"index": 0, "kind": "pivot", "start_time": 0.0, "end_time": 1.0, "delta": 0.1}]


def test_a_hand_coming_back_flush_is_no_slip_and_one_rolling_away_is():
    back = _pivot_run([1.6, 1.0, 0.0, -0.5])  # 2.1° from its start
    assert unintended_slips(*back) == []
    away = _pivot_run([0.0, 1.0, 2.0, 2.5])
    (event,) = unintended_slips(*away)
    assert event["contact"] == "hand_pivot" and event["excursion"] == pytest.approx(math.radians(2.5))
    assert event["excursion"] > SLIP_ANGLE
