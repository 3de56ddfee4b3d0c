"""Contact modes, hand geometry, contact configurations and commanded motions (paper §III, §V).

Signs follow :mod:`ccopt.geometry` and the :class:`ccopt.contact.Row` table: a hand mode's sign is
the sign of ``ṡ_h``, the hand geometry's the sign of ``Δθ = θ_o − θ_h`` and the ground mode's the
sign of ``ṡ_g``. A commanded motion removes the cone rows that would block it (paper §V: "commanding
positive hand sliding removes the LHS of eq. 5") and keeps every other row, so that every other
contact keeps its mode.
"""

from __future__ import annotations

from dataclasses import dataclass
from enum import Enum, IntEnum

import numpy as np

from ccopt.contact import N_CONE_ROWS, Row


class ContactMode(IntEnum):
    """Mode of a sliding contact; the value is the sign of the sliding velocity."""

    SLIDE_NEG = -1
    STICK = 0
    SLIDE_POS = 1


class HandGeometry(IntEnum):
    """Geometry of the hand contact; the value is the sign of ``Δθ = θ_o − θ_h``."""

    PIVOT_NEG = -1
    FLUSH = 0
    PIVOT_POS = 1


@dataclass(frozen=True)
class ContactConfiguration:
    """The mode and geometry of every contact: hand (slide, geometry) and ground (slide)."""

    hand_mode: ContactMode = ContactMode.STICK
    hand_geometry: HandGeometry = HandGeometry.FLUSH
    ground_mode: ContactMode = ContactMode.STICK


class Motion(Enum):
    """A commanded admissible motion (paper Fig. 2): what changes, and in which direction."""

    HOLD = "hold"
    PIVOT = "pivot"
    SLIDE_HAND_POS = "slide_hand_pos"
    SLIDE_HAND_NEG = "slide_hand_neg"
    SLIDE_GROUND_POS = "slide_ground_pos"
    SLIDE_GROUND_NEG = "slide_ground_neg"


REMOVED_ROWS: dict[Motion, tuple[Row, ...]] = {
    Motion.HOLD: (),
    Motion.PIVOT: (),
    Motion.SLIDE_HAND_POS: (Row.HAND_SLIDE_POS,),
    Motion.SLIDE_HAND_NEG: (Row.HAND_SLIDE_NEG,),
    Motion.SLIDE_GROUND_POS: (Row.GROUND_SLIDE_POS,),
    Motion.SLIDE_GROUND_NEG: (Row.GROUND_SLIDE_NEG,),
}
"""Cone rows each commanded motion removes from the controller's QP. A pivot of the object about
the ground contact with both contacts sticking and the hand flush is admissible without removing
any row (paper Fig. 2b)."""

_CONFIGURATIONS: dict[Motion, ContactConfiguration] = {
    Motion.HOLD: ContactConfiguration(),
    Motion.PIVOT: ContactConfiguration(),
    Motion.SLIDE_HAND_POS: ContactConfiguration(hand_mode=ContactMode.SLIDE_POS),
    Motion.SLIDE_HAND_NEG: ContactConfiguration(hand_mode=ContactMode.SLIDE_NEG),
    Motion.SLIDE_GROUND_POS: ContactConfiguration(ground_mode=ContactMode.SLIDE_POS),
    Motion.SLIDE_GROUND_NEG: ContactConfiguration(ground_mode=ContactMode.SLIDE_NEG),
}


def configuration(motion: Motion) -> ContactConfiguration:
    """The contact configuration a commanded motion asks for."""
    return _CONFIGURATIONS[_as_motion(motion)]


def kept_rows(motion: Motion) -> np.ndarray:
    """Boolean mask over :class:`~ccopt.contact.Row`: the cone rows the QP keeps for ``motion``."""
    mask = np.ones(N_CONE_ROWS, dtype=bool)
    mask[list(REMOVED_ROWS[_as_motion(motion)])] = False
    return mask


def slide_hand(direction: float) -> Motion:
    """The hand-slide motion for a signed ``Δs_h`` (m); raises ``ValueError`` on zero."""
    return _signed(direction, Motion.SLIDE_HAND_POS, Motion.SLIDE_HAND_NEG, "hand slide")


def slide_ground(direction: float) -> Motion:
    """The ground-slide motion for a signed ``Δs_g`` (m); raises ``ValueError`` on zero."""
    return _signed(direction, Motion.SLIDE_GROUND_POS, Motion.SLIDE_GROUND_NEG, "ground slide")


def _signed(direction: float, positive: Motion, negative: Motion, what: str) -> Motion:
    if not np.isfinite(direction) or direction == 0.0:
        raise ValueError(f"{what} needs a finite, non-zero increment, got {direction!r}")
    return positive if direction > 0.0 else negative


def _as_motion(motion: Motion | str) -> Motion:
    if isinstance(motion, Motion):
        return motion
    try:
        return Motion(motion)
    except ValueError:
        valid = ", ".join(m.value for m in Motion)
        raise ValueError(f"unknown motion {motion!r}; expected one of: {valid}") from None
