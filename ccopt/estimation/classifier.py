"""Contact modes and hand geometry from the measured wrench and the estimated cone (paper §IV-A).

By complementarity (:mod:`ccopt.contact`), a contact may slide (or the hand pivot) only where the
cone row blocking that motion is tight. With the margins ``b − N w`` of the estimated rows (hand
frame, order :class:`~ccopt.contact.Row`), each contact is reported

* sliding (pivoting) towards the row with the smaller margin when that margin is at most the
  contact's margin parameter (N for force rows, N·m for torque rows), or when its rows are not
  estimated yet ("may be sliding": conservative);
* sticking (flush) otherwise, unless it was reported sliding within the last ``hold_time``: a
  sliding report is latched so that brief dips inside the margin do not read as sticking.

Signs follow :mod:`ccopt.modes`: ``HAND_SLIDE_POS`` tight → ``ṡ_h > 0``; ``HAND_PIVOT_POS`` tight →
``Δθ = θ_o − θ_h > 0``; ``GROUND_SLIDE_POS`` tight → ``ṡ_g > 0``. The classifier is deliberately
conservative: sliding is almost never reported as sticking, the reverse is common near the
boundaries of the estimated cone.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

from ccopt.contact import Row
from ccopt.estimation.quantile import check_number
from ccopt.modes import ContactConfiguration, ContactMode, HandGeometry


@dataclass(frozen=True)
class ModeParams:
    """Margins and latch of the mode classifier.

    Attributes:
        slide_margin: hand friction rows count as tight within this margin (N).
        pivot_margin: hand torque rows count as tight within this margin (N·m).
        ground_margin: ground rows (unit normals) count as tight within this distance (N).
        hold_time: a sliding/pivoting report is held this long after the last tight sample (s).
    """

    slide_margin: float = 1.5
    pivot_margin: float = 0.01
    ground_margin: float = 1.5
    hold_time: float = 0.15

    def __post_init__(self) -> None:
        check_number("slide_margin", self.slide_margin, low_open=False)
        check_number("pivot_margin", self.pivot_margin, low_open=False)
        check_number("ground_margin", self.ground_margin, low_open=False)
        check_number("hold_time", self.hold_time, low_open=False)


def tight_direction(margin_pos: float, margin_neg: float, threshold: float, estimated: bool) -> int:
    """+1/−1 for the motion whose blocking row is tight (the smaller margin), 0 if neither is.

    Rows that are not ``estimated`` count as tight. Margins and threshold in the rows' units.
    """
    if estimated and min(margin_pos, margin_neg) > threshold:
        return 0
    return 1 if margin_pos <= margin_neg else -1


_CONTACT_ROWS = (
    (Row.HAND_SLIDE_POS, Row.HAND_SLIDE_NEG),
    (Row.HAND_PIVOT_POS, Row.HAND_PIVOT_NEG),
    (Row.GROUND_SLIDE_POS, Row.GROUND_SLIDE_NEG),
)
"""The rows blocking the positive and negative motion of the hand slide, hand pivot, ground slide."""
_ROW_PAIRS = tuple((int(pos), int(neg)) for pos, neg in _CONTACT_ROWS)
_CONFIGURATIONS = {
    (hand, pivot, ground): ContactConfiguration(ContactMode(hand), HandGeometry(pivot), ContactMode(ground))
    for hand in (-1, 0, 1)
    for pivot in (-1, 0, 1)
    for ground in (-1, 0, 1)
}
"""Every configuration by its ``(hand mode, hand geometry, ground mode)`` signs (they are immutable)."""


class ModeClassifier:
    """Latched contact mode/geometry classification (see the module docstring)."""

    def __init__(self, params: ModeParams | None = None) -> None:
        self.params = params if params is not None else ModeParams()
        thresholds = (self.params.slide_margin, self.params.pivot_margin, self.params.ground_margin)
        self._contacts = tuple(
            (contact, threshold, pos, neg)
            for contact, threshold, (pos, neg) in zip(range(3), thresholds, _ROW_PAIRS, strict=True)
        )
        self._hold_time = self.params.hold_time
        self._values = [0, 0, 0]  # the latched reports of the hand slide, hand pivot, ground slide
        self._until = [-math.inf] * 3  # the time each report is held until

    def update(
        self, time: float, margins: Sequence[float], estimated: Sequence[bool]
    ) -> ContactConfiguration:
        """Classify one sample.

        Args:
            time: sample time (s), non-decreasing.
            margins: ``b − N w`` of the estimated cone (6 values), order :class:`~ccopt.contact.Row`.
            estimated: per row, whether the row is estimated (6 values).
        """
        values, until, hold_time = self._values, self._until, self._hold_time
        for contact, threshold, pos, neg in self._contacts:  # tight_direction written out: a call costs more
            margin_pos, margin_neg = margins[pos], margins[neg]
            smaller = margin_neg if margin_neg < margin_pos else margin_pos  # min(margin_pos, margin_neg)
            if estimated[pos] and estimated[neg] and smaller > threshold:
                if time >= until[contact]:  # nothing tight: a report is held for hold_time
                    values[contact] = 0
            else:
                values[contact], until[contact] = 1 if margin_pos <= margin_neg else -1, time + hold_time
        return _CONFIGURATIONS[values[0], values[1], values[2]]
