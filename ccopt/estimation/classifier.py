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


class _Latch:
    """Holds a non-zero report for ``hold_time`` after it was last seen."""

    __slots__ = ("hold_time", "until", "value")

    def __init__(self, hold_time: float) -> None:
        self.hold_time = hold_time
        self.value = 0
        self.until = -math.inf

    def update(self, time: float, raw: int) -> int:
        if raw != 0:
            self.value, self.until = raw, time + self.hold_time
        elif time >= self.until:
            self.value = 0
        return self.value


_CONTACT_ROWS = (
    (Row.HAND_SLIDE_POS, Row.HAND_SLIDE_NEG),
    (Row.HAND_PIVOT_POS, Row.HAND_PIVOT_NEG),
    (Row.GROUND_SLIDE_POS, Row.GROUND_SLIDE_NEG),
)
"""The rows blocking the positive and negative motion of the hand slide, hand pivot, ground slide."""
(_SP, _SN), (_PP, _PN), (_GP, _GN) = ((int(pos), int(neg)) for pos, neg in _CONTACT_ROWS)
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
        self._thresholds = (self.params.slide_margin, self.params.pivot_margin, self.params.ground_margin)
        self._latches = tuple(_Latch(self.params.hold_time) for _ in _CONTACT_ROWS)

    def update(
        self, time: float, margins: Sequence[float], estimated: Sequence[bool]
    ) -> ContactConfiguration:
        """Classify one sample.

        Args:
            time: sample time (s), non-decreasing.
            margins: ``b − N w`` of the estimated cone (6 values), order :class:`~ccopt.contact.Row`.
            estimated: per row, whether the row is estimated (6 values).
        """
        m, e = margins, estimated
        (slide, pivot, ground), (hand_latch, pivot_latch, ground_latch) = self._thresholds, self._latches
        return _CONFIGURATIONS[  # unrolled over the three contacts (rows in Row order): every sample
            hand_latch.update(time, tight_direction(m[_SP], m[_SN], slide, e[_SP] and e[_SN])),
            pivot_latch.update(time, tight_direction(m[_PP], m[_PN], pivot, e[_PP] and e[_PN])),
            ground_latch.update(time, tight_direction(m[_GP], m[_GN], ground, e[_GP] and e[_GN])),
        ]
