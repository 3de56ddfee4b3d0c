"""The motion vocabulary of ccopt: contact modes, hand geometry, configurations and commanded motions.

The one place that says, for every commanded motion (paper §III, Fig. 2, and §V):

* which contact configuration it asks for (:func:`configuration`) and so which contacts must keep
  their mode (:func:`kept_contacts`);
* which cone rows it removes from the controller's QP (:data:`REMOVED_ROWS`, :func:`kept_rows`);
* which coordinate of ``(θ_o, s_h, s_g)`` it drives (:func:`driven_coordinate`) and which it admits
  (:func:`admitted_coordinates`);
* its *kind* as schedules and records name it (``hold``, ``pivot``, ``slide_hand``,
  ``slide_ground``: :data:`KINDS`, :func:`kind_of`, :func:`motion_of`) and its integer code in a run
  record (:data:`MOTION_CODES`).

Signs follow :mod:`ccopt.geometry` and the :class:`ccopt.contact.Row` table: a hand mode's sign is
the sign of ``ṡ_h``, the hand geometry's the sign of ``Δθ = θ_o − θ_h`` and the ground mode's the
sign of ``ṡ_g``. A commanded motion removes the cone rows that would block it (paper §V: "commanding
positive hand sliding removes the LHS of eq. 5") and keeps every other row, so that every other
contact keeps its mode.
"""

from __future__ import annotations

from dataclasses import astuple, dataclass
from enum import Enum, IntEnum
from typing import Literal

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

    @property
    def slides(self) -> bool:
        """Whether a contact slides: the hand's or the ground's."""
        return self.hand_mode != ContactMode.STICK or self.ground_mode != ContactMode.STICK


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

SLIDES = frozenset(motion for motion, rows in REMOVED_ROWS.items() if rows)
"""The motions that slide a contact: each removes a friction row (:data:`REMOVED_ROWS`)."""

_CONFIGURATIONS: dict[Motion, ContactConfiguration] = {
    Motion.HOLD: ContactConfiguration(),
    Motion.PIVOT: ContactConfiguration(),
    Motion.SLIDE_HAND_POS: ContactConfiguration(hand_mode=ContactMode.SLIDE_POS),
    Motion.SLIDE_HAND_NEG: ContactConfiguration(hand_mode=ContactMode.SLIDE_NEG),
    Motion.SLIDE_GROUND_POS: ContactConfiguration(ground_mode=ContactMode.SLIDE_POS),
    Motion.SLIDE_GROUND_NEG: ContactConfiguration(ground_mode=ContactMode.SLIDE_NEG),
}


Kind = Literal["hold", "pivot", "slide_hand", "slide_ground"]
KINDS: tuple[Kind, ...] = ("hold", "pivot", "slide_hand", "slide_ground")
"""The kinds of schedule step; a kind's index is its code in a run record (:data:`MOTION_CODES`)."""
MOTION_CODES: dict[str, int] = {kind: code for code, kind in enumerate(KINDS)}
"""Integer code of each kind in a run record (``motion``): hold 0, pivot 1, slide_hand 2, slide_ground 3."""

COORDINATES = ("theta_o", "s_h", "s_g")
"""The coordinates a motion changes, in the order of every ``(θ_o, s_h, s_g)`` vector (rad, m, m)."""
THETA_O, S_H, S_G = range(3)
"""Indices into :data:`COORDINATES`."""

_KIND: dict[Motion, Kind] = {
    Motion.HOLD: "hold",
    Motion.PIVOT: "pivot",
    Motion.SLIDE_HAND_POS: "slide_hand",
    Motion.SLIDE_HAND_NEG: "slide_hand",
    Motion.SLIDE_GROUND_POS: "slide_ground",
    Motion.SLIDE_GROUND_NEG: "slide_ground",
}
_DRIVES: dict[str, int | None] = {"hold": None, "pivot": THETA_O, "slide_hand": S_H, "slide_ground": S_G}
_KEEPS: dict[str, int | None] = {"hold": None, "pivot": None, "slide_hand": S_G, "slide_ground": S_H}
_ADMITS: dict[str, tuple[int, ...]] = {
    "hold": (THETA_O,),
    "pivot": (THETA_O,),
    "slide_hand": (THETA_O, S_H),
    "slide_ground": (THETA_O, S_G),
}
"""Coordinates that can change under each kind: a sticking contact fixes its coordinate, and with both
contacts sticking and the hand flush the object can still turn about the ground contact."""


def kind_of(motion: Motion | str) -> Kind:
    """The kind (``hold``, ``pivot``, ``slide_hand``, ``slide_ground``) of a motion or of a kind."""
    if isinstance(motion, str) and motion in _DRIVES:
        return motion
    return _KIND[_as_motion(motion)]


def motion_of(kind: str, delta: float = 0.0) -> Motion:
    """The motion of a step of ``kind`` with increment ``delta`` (rad or m; its sign picks a slide's way)."""
    if kind == "slide_hand":
        return slide_hand(delta)
    if kind == "slide_ground":
        return slide_ground(delta)
    if kind in ("hold", "pivot"):
        return Motion(kind)
    raise ValueError(f"unknown step kind {kind!r}; expected one of: {', '.join(KINDS)}")


def driven_coordinate(motion: Motion | str) -> int | None:
    """Index into ``(θ_o, s_h, s_g)`` of the coordinate a motion (or kind) drives; None for a hold."""
    return _DRIVES[kind_of(motion)]


def kept_coordinate(motion: Motion | str) -> int | None:
    """Index into ``(θ_o, s_h, s_g)`` of the position of the contact a slide keeps sticking (``s_g`` in
    a hand slide, ``s_h`` in a ground slide); None for a hold or a pivot."""
    return _KEEPS[kind_of(motion)]


def driving_kind(coordinate: int | str) -> Kind:
    """The kind of step that drives a coordinate, given by index or by name (:data:`COORDINATES`)."""
    index = COORDINATES.index(coordinate) if isinstance(coordinate, str) else coordinate
    return next(kind for kind, driven in _DRIVES.items() if driven == index)


def admitted_coordinates(motion: Motion | str) -> tuple[int, ...]:
    """Indices into ``(θ_o, s_h, s_g)`` of the coordinates that can change under a motion (or kind)."""
    return _ADMITS[kind_of(motion)]


def kept_contacts(motion: Motion | str) -> tuple[bool, bool, bool]:
    """Whether the hand must stick, the hand must stay flush and the ground must stick under a motion
    (or kind): every contact the motion's configuration does not set moving keeps its mode."""
    return _KEPT_CONTACTS[kind_of(motion)]


def configuration(motion: Motion) -> ContactConfiguration:
    """The contact configuration a commanded motion asks for."""
    return _CONFIGURATIONS[_as_motion(motion)]


def kept_rows(motion: Motion) -> np.ndarray:
    """Boolean mask over :class:`~ccopt.contact.Row`: the cone rows the QP keeps for ``motion``
    (read-only)."""
    return _KEPT_ROWS[_as_motion(motion)]


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


def _kept_rows_mask(motion: Motion) -> np.ndarray:
    mask = np.ones(N_CONE_ROWS, dtype=bool)
    mask[list(REMOVED_ROWS[motion])] = False
    mask.flags.writeable = False
    return mask


_KEPT_ROWS = {motion: _kept_rows_mask(motion) for motion in Motion}
""":func:`kept_rows` of every motion, made once."""
_KEPT_CONTACTS = {
    kind: tuple(value == 0 for value in astuple(_CONFIGURATIONS[motion_of(kind, 1.0)])) for kind in KINDS
}
""":func:`kept_contacts` of every kind, made once."""
