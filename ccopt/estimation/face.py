"""Where the object's face under the hand is known to be: the part of it the hand has pressed on.

The estimator does not know where the face touching the hand ends, and a statics judged with the
whole hand as the contact patch (``|τ| ≤ l_h f_n``) allows wrenches whose centre of pressure lies
past the face's end: the object then turns about that end instead of doing what was commanded (on a
goals-study quadrilateral, a hand slide back from 13 mm past the start asked for its centre of
pressure 12 mm beyond the face and the object rolled 4° under the hand, unseen). The face is fixed
in the object, so its points are fixed positions ``u`` along ``e_t`` from the ground contact's foot
(:func:`ccopt.geometry.face_position`), whatever the hand's slide and the object's tilt.

Two kinds of evidence tell where the face is, conservatively (the interval lies inside the face):

* **the start**: a run starts with the hand flush on the face over its whole length (the plant
  places it so, DESIGN §1): where the kinematics become valid before the hand is first commanded to
  slide, the face covers ``[−l_h − ŝ_h, l_h − ŝ_h]``, with ``ŝ_h`` the latest estimate before that
  first slide (the hand has not moved on the face until then, and the estimate only improves);
* **the centre of pressure**: every sample with the hand flush, pressing with at least
  ``min_normal_force`` and the kinematics valid has its centre of pressure ``c = −τ/f_n`` on the
  face, at ``u = c − ŝ_h``.

While no slide is commanded the hand does not move on the face, so a change of ``ŝ_h`` then is the
estimate improving (or, found again, the object on another vertex): the evidence stays where it is
on the hand (``u`` moves by the change of ``ŝ_h``). While a slide is commanded the evidence is held
fixed in ``u``: a hand slide moves the hand on the face, and a ground slide may too (a heavy
quadrilateral's ground slide near the vertical slid the hand 10 mm along the face instead). Kept in
``u`` throughout (measured before exploration pivots held their target while the hand rolled), the
centres of pressure a paper hexagon's kinematics saw just after they were found again, with
``ŝ_h`` 41 mm off (the object had rocked over its bottom face, onto its other vertex and back),
stayed 30 mm off the hand once ``ŝ_h`` converged: the known face cut the hand 11 mm from its
centre, 34 mm inside the true face's end, and a ground slide with the hand flush ended `rolled`.

The interval reported is their hull shrunk by ``margin`` at each end (the error of ``ŝ_h``) and each
centre of pressure also by ``torque_noise / f_n`` (the torque's noise). While the kinematics are lost
the face is not reported. When they are found again and no slide was commanded meanwhile, the
face is where it was on the hand (``u`` moves by the change of ``ŝ_h``), whatever
the vertex: the object may have rolled onto another vertex under the same face, or the estimate,
found again, may differ. A paper hexagon rocking over its bottom face (parallel to the hand's face,
so both its vertices have the same ``d``) was found again at 2° with ``ŝ_h`` 51 mm off; kept in
``u`` because ``d̂`` had not changed, the known face reached 53 mm past the hand's end. If a slide was
commanded while they were lost, the face is kept in ``u`` when ``d̂`` is the same
(within ``same_vertex``: the same vertex, the hand may have slid on the face), and forgotten
otherwise (from then on only centres of pressure tell it); on an object with a ground face parallel
to the hand's face, a rock over it during such a slide is taken for the same vertex.

Only commanded slides count: the classifier reports the hand sliding whenever its friction is not
yet estimated, which is most of the start. A replay without commands takes no slide as commanded,
so its evidence stays on the hand through any slide: there the face is only as good as the
recording's hand slides are few.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

from ccopt import geometry
from ccopt.validation import check_number

UNKNOWN_FACE = (math.nan, math.nan)
"""The face while the kinematics are not valid: not estimated."""
NO_FACE = (math.inf, -math.inf)
"""The face while the kinematics are valid but nothing shows where it is (an empty interval)."""


def hand_extent(half_length: float, s_h: float) -> tuple[float, float]:
    """Where the face points under the whole hand lie, ``(u_low, u_high)`` (m): the hand's ends
    ``∓l_h`` at ``ŝ_h`` (:func:`ccopt.geometry.face_position`)."""
    return geometry.face_position(-half_length, s_h), geometry.face_position(half_length, s_h)


def inside(evidence: tuple[float, float], margin: float) -> tuple[float, float]:
    """The known face from the evidence's hull ``(low, high)`` (m): ``margin`` (m) inside each end;
    :data:`NO_FACE` where there is no hull."""
    low, high = evidence
    return (low + margin, high - margin) if low <= high else NO_FACE


@dataclass(frozen=True)
class FaceParams:
    """Parameters of the face estimate (m, N, N·m).

    Attributes:
        start_on_face: the run starts with the whole hand on the face (module docstring).
        margin: each end of the known face is taken this far inside the evidence (m).
        min_normal_force: centres of pressure count at this normal force or above (N).
        torque_noise: a centre of pressure is taken ``torque_noise / f_n`` inside where it was
            measured (N·m; about twice the default sensors' torque noise).
        same_vertex: kinematics found again, after a slide was commanded, with ``d̂``
            within this (m) of the last are on the same ground contact.
    """

    start_on_face: bool = True
    margin: float = 3e-3
    min_normal_force: float = 3.0
    torque_noise: float = 0.01
    same_vertex: float = 3e-3

    def __post_init__(self) -> None:
        if not isinstance(self.start_on_face, bool):
            raise TypeError(f"start_on_face must be a bool, got {self.start_on_face!r}")
        check_number("margin", self.margin, low_open=False)
        check_number("min_normal_force", self.min_normal_force)
        check_number("torque_noise", self.torque_noise, low_open=False)
        check_number("same_vertex", self.same_vertex, low_open=False)


class FaceEstimator:
    """The known part of the face (module docstring).

    Args:
        half_length: ``l_h``, half the length of the hand's contact face (m).
        params: estimator parameters.
    """

    def __init__(self, half_length: float, params: FaceParams | None = None) -> None:
        self.half_length = check_number("half_length", half_length)
        self.params = params if params is not None else FaceParams()
        self.face = UNKNOWN_FACE
        """``(u_low, u_high)`` (m): :data:`UNKNOWN_FACE` while the kinematics are not valid; empty
        (``u_low > u_high``) where too little is known (:data:`NO_FACE`, or a centre of pressure or
        two)."""
        self._low, self._high = NO_FACE  # the hull of the evidence but the start's
        self._start = NO_FACE  # the start's evidence
        self._at_start = self.params.start_on_face  # the hand lies where the run started it
        self._valid = False
        self._d = self._s_h = math.nan  # d̂ and ŝ_h when the kinematics were last valid
        self._slid = False  # a slide was commanded since they were

    def update(
        self,
        valid: bool,
        s_h: float,
        d: float,
        flush: bool,
        f_n: float,
        torque: float,
        slides: bool,
    ) -> tuple[float, float]:
        """One sample: whether the kinematics are ``valid``, ``ŝ_h`` and ``d̂`` (m), whether the hand
        is ``flush``, the wrench's ``f_n`` (N) and ``τ`` (N·m), whether a slide (of either contact)
        is commanded. Returns :attr:`face`."""
        if slides:  # the hand may move on the face: the start's evidence is as last estimated
            self._at_start = False
            self._slid = not valid
        if not valid:
            if self._valid:  # lost: the hand may have slid unseen, the start's evidence stays
                self._valid, self._at_start, self.face = False, False, UNKNOWN_FACE
            return self.face
        changed = False
        if not self._valid:
            self._found(s_h, d)
        elif not slides and s_h != self._s_h:  # the face stays where it is on the hand
            self._shift(self._s_h - s_h)
            changed = True
        self._d, self._s_h = d, s_h
        if self._at_start:
            self._start, changed = hand_extent(self.half_length, s_h), True
        params = self.params
        if flush and f_n >= params.min_normal_force:
            u = geometry.face_position(geometry.centre_of_pressure(f_n, torque), s_h)
            noise = params.torque_noise / f_n
            if u + noise < self._low or u - noise > self._high:
                self._low, self._high, changed = min(u + noise, self._low), max(u - noise, self._high), True
        if changed:
            self._report()
        return self.face

    def _found(self, s_h: float, d: float) -> None:
        """The kinematics became valid (module docstring)."""
        self._valid = True
        shift = self._s_h - s_h
        if not self._slid and math.isfinite(shift):  # the face stays where it was on the hand
            self._shift(shift)
        elif not abs(d - self._d) <= self.params.same_vertex:  # slid onto another vertex (or the first)
            (self._low, self._high), self._start = NO_FACE, NO_FACE
        self._slid = False
        self._report()

    def _shift(self, shift: float) -> None:
        """Move the evidence by ``shift`` (m) in ``u``: the face stays where it was on the hand while
        ``ŝ_h`` changed by ``−shift``."""
        self._low, self._high = self._low + shift, self._high + shift
        self._start = (self._start[0] + shift, self._start[1] + shift)

    def _report(self) -> None:
        """The face from the evidence: its hull, ``margin`` inside."""
        (low, high), (start_low, start_high) = (self._low, self._high), self._start
        hull = (  # min(low, start_low), max(high, start_high), written out: a call costs more
            start_low if start_low < low else low,
            start_high if start_high > high else high,
        )
        self.face = inside(hull, self.params.margin)
