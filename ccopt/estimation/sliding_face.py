"""The ground's friction face fitted to the hand forces of its own slides.

While the ground slides, quasi-statically, its force lies on its friction face, so the world hand
force ``f`` lies on ``s f_x = μ_g (m g − f_y)`` (``s = ±1`` the way it slides, world "up" along
``y``; :mod:`.ground_cone`): a straight line through the weight reversed ``(0, m g)``, the cone's
apex. On a flat ground both faces are mirror images about "up", so the forces of slides either way,
mirrored onto one side (``x = s f_x``), lie on the one line ``x = μ_g (a − y)`` with ``a = m g``.

The convex hull of every force seen (:mod:`.ground_cone`) cannot tell that line: a slide at one
normal force leaves a short cluster on it, and the hull's straight edges next to the cluster are the
sticking forces of other motions. Here only forces the ground slid under count: those between two
confirmations of a slide (the contact's estimated position moved another ``slid_distance`` the way
it is meant to slide, :class:`~.estimator.SlideEvidence`), the first stretch of each slide left out
(it holds the ramp up to the face, sticking forces inside it). A stretch that took longer than
``max_stretch_time`` is left out too: the slide stalled within it. Within a stretch, a force
farther than ``max_deviation`` from the stretch's median (componentwise) is a transient, not
quasi-static: on a robustness-study run of a 0.93 kg pentagon slid at a 46° tilt, the hand
bounced off the object for a few milliseconds at a time (the force fell from (13, −6) to (5.5, −1)
N while the ground kept sliding, coasting), and a line through both clusters had μ_g 1.39 against
the true 0.78.

The line is the total least squares fit of the mirrored forces (their noise is in both
components), from running sums. Its slope is *determined* once the forces spread along it by
``min_spread`` (standard deviation, N) and the standard error of its angle, ``scatter / (spread
√m)`` with ``m`` the stretches fitted (the forces within a stretch are far from independent: taken
one by one, a cluster of a hundred forces would pin any slope), is at most ``max_slope_error``. One
cluster at one normal force spreads too little to tell a slope: on goals-study runs, fits to
forces spread 0.5–0.8 N along the line turned between μ_g 0.35 and 0.69 as stretches came in
(true 0.43); slides at several normal forces or both ways do. At the end of the goals study's
runs where it was determined, the faces' tangential limit at 5 and 15 N of pressing was within a
median 0.10 N of the truth (largest 0.72 N); ``μ̂_g`` itself tends low by up to 0.1 with the apex
high by up to 2 N (a line right where the forces are, less so beyond them). A fit whose apex falls
below the origin (no weight does) or whose slope is not a friction face's (``μ_g ≤ 0``) is not
determined either. Until it is, the hull's faces stand.
"""

from __future__ import annotations

import math
import statistics
from dataclasses import dataclass
from typing import NamedTuple

from ccopt.clock import interval_passed
from ccopt.estimation.ground_cone import friction_face_normal
from ccopt.geometry import WORLD_UP
from ccopt.validation import check_number


@dataclass(frozen=True)
class SlidingFaceParams:
    """Parameters of the sliding-force fit.

    Attributes:
        sample_interval: shortest time between two forces kept (s); neighbouring 1 kHz samples are
            nearly equal.
        max_stretch_time: longest stretch between two confirmations whose forces count (s). The
            controller slides at 20 mm/s (``ControllerParams.slide_speed``), so the 2 mm between
            confirmations take 0.1 s: on goals-study runs every stretch within 0.13 s slid
            throughout (the truth's slip rate), those of 0.2–0.4 s 33–65 % of the time (stalls).
        max_deviation: largest distance of a force from its stretch's median, per component (N).
        min_spread: standard deviation of the forces along the fitted line from which its slope
            may count as determined (N).
        max_slope_error: largest standard error of the line's angle (rad) at which its slope
            counts as determined (0.1 rad is ±0.12 in ``μ_g`` at 0.5).
    """

    sample_interval: float = 0.004
    max_stretch_time: float = 0.15
    max_deviation: float = 2.0
    min_spread: float = 1.0
    max_slope_error: float = 0.1

    def __post_init__(self) -> None:
        check_number("sample_interval", self.sample_interval, low_open=False)
        check_number("max_stretch_time", self.max_stretch_time)
        check_number("max_deviation", self.max_deviation)
        check_number("min_spread", self.min_spread)
        check_number("max_slope_error", self.max_slope_error)


@dataclass(frozen=True)
class SlidingFace:
    """The ground friction face fitted to sliding forces.

    Attributes:
        determined: whether the fit's slope is determined (module docstring). Only then are the
            faces a friction estimate; before, ``mu_g`` and ``apex`` are the fit so far (NaN
            where it is not a face).
        mu_g: ground friction coefficient, the face's slope about world "up".
        apex: the faces' apex along world "up" (N): the object's weight ``m g``.
        spread, scatter: standard deviations of the forces along and across the line (N).
        count: forces fitted.
        stretches: stretches of sliding they came from.
    """

    determined: bool
    mu_g: float
    apex: float
    spread: float
    scatter: float
    count: int
    stretches: int

    def rows(self) -> tuple[tuple[tuple[float, float], float], tuple[tuple[float, float], float]]:
        """The two faces as ground rows ``(unit normal (world), offset (N))``, in ``GROUND_ROWS``
        order (right face ``GROUND_SLIDE_POS`` first)."""
        offset = self.mu_g * self.apex / math.hypot(1.0, self.mu_g)
        right, left = (friction_face_normal(WORLD_UP, self.mu_g, side) for side in (1.0, -1.0))
        return (right, offset), (left, offset)


UNDETERMINED = SlidingFace(False, math.nan, math.nan, math.nan, math.nan, 0, 0)
"""The fit before any slide determined it."""


class FitSnapshot(NamedTuple):
    """A :class:`SlidingFaceFit` as it stood (:meth:`SlidingFaceFit.snapshot`)."""

    sums: list[float]
    stretches: int
    face: SlidingFace


class SlidingFaceFit:
    """Running total least squares fit of the ground's sliding forces (module docstring)."""

    def __init__(self, params: SlidingFaceParams | None = None) -> None:
        self.params = params if params is not None else SlidingFaceParams()
        self.face = UNDETERMINED
        self._sums = [0.0] * 6  # n, Σx, Σy, Σxx, Σxy, Σyy of the mirrored forces
        self._stretches = 0
        self._stretch: list[tuple[float, float]] = []  # mirrored forces since the last confirmation
        self._stretch_start = math.nan
        self._confirmed = 0  # confirmations of the current slide counted so far
        self._last_sample = -math.inf

    def update(
        self, time: float, force_world: tuple[float, float], way: int | None, confirmed: int
    ) -> SlidingFace:
        """Offer the world hand force (N) at ``time`` (s), the way the ground is meant to slide
        (``±1``; 0 or None: no commanded slide) and how many times the current slide was confirmed
        (:attr:`~.estimator.SlideEvidence.confirmed`); the fit."""
        if way not in (1, -1) or confirmed < self._confirmed:  # no slide, or a new one
            self._stretch.clear()
            self._confirmed = 0
            if way not in (1, -1):
                return self.face
        if confirmed > self._confirmed:
            if self._confirmed > 0 and time - self._stretch_start <= self.params.max_stretch_time:
                self._add(self._stretch)
            self._stretch.clear()
            self._confirmed = confirmed
        if not self._stretch:
            self._stretch_start = time
        if interval_passed(time, self._last_sample, self.params.sample_interval):
            self._last_sample = time
            (up_x, up_y), (f_x, f_y) = WORLD_UP, force_world
            outward = way * (f_x * up_y - f_y * up_x)  # along the side's horizontal direction
            self._stretch.append((outward, f_x * up_x + f_y * up_y))
        return self.face

    def snapshot(self) -> FitSnapshot:
        """The fit as it stands (for :meth:`restore`)."""
        return FitSnapshot(list(self._sums), self._stretches, self.face)

    def restore(self, state: FitSnapshot) -> None:
        """Go back to a :meth:`snapshot`, dropping every force fitted since and the current stretch:
        the slide they came from was not the ground's."""
        self._sums, self._stretches, self.face = list(state.sums), state.stretches, state.face
        self._stretch.clear()
        self._confirmed = 0

    def _add(self, forces: list[tuple[float, float]]) -> None:
        if not forces:
            return
        sums, limit = self._sums, self.params.max_deviation
        self._stretches += 1
        median_x, median_y = statistics.median(x for x, _ in forces), statistics.median(y for _, y in forces)
        for x, y in forces:
            if abs(x - median_x) > limit or abs(y - median_y) > limit:
                continue
            sums[0] += 1.0
            sums[1] += x
            sums[2] += y
            sums[3] += x * x
            sums[4] += x * y
            sums[5] += y * y
        self.face = fit_sliding_face(sums, self._stretches, self.params)


def fit_sliding_face(sums: list[float], stretches: int, params: SlidingFaceParams) -> SlidingFace:
    """The face ``x = μ_g (a − y)`` fitted by total least squares to mirrored forces given by their
    sums ``n, Σx, Σy, Σx², Σxy, Σy²``, from ``stretches`` stretches of sliding (module docstring)."""
    n, sx, sy, sxx, sxy, syy = sums
    if n < 3.0:
        return UNDETERMINED
    mean_x, mean_y = sx / n, sy / n
    cxx, cxy, cyy = sxx / n - mean_x * mean_x, sxy / n - mean_x * mean_y, syy / n - mean_y * mean_y
    half_trace, half_gap = 0.5 * (cxx + cyy), math.hypot(0.5 * (cxx - cyy), cxy)
    along, across = half_trace + half_gap, max(half_trace - half_gap, 0.0)
    normal = _minor_axis(cxx, cxy, cyy, across)
    p, q = normal if normal[0] >= 0.0 else (-normal[0], -normal[1])  # outward: along +x
    offset = p * mean_x + q * mean_y
    spread, scatter = math.sqrt(along), math.sqrt(across)
    determined = (
        p > 0.0
        and q > 0.0
        and offset >= 0.0
        and spread >= params.min_spread
        and scatter <= params.max_slope_error * spread * math.sqrt(stretches)
    )
    mu_g, apex = (q / p, offset / q) if p > 0.0 and q > 0.0 else (math.nan, math.nan)
    return SlidingFace(determined, mu_g, apex, spread, scatter, int(n), stretches)


def _minor_axis(cxx: float, cxy: float, cyy: float, minor: float) -> tuple[float, float]:
    """The unit eigenvector of the covariance ``[[cxx, cxy], [cxy, cyy]]`` for its eigenvalue ``minor``."""
    a, b = (cxy, minor - cxx) if abs(cxx - minor) >= abs(cyy - minor) else (minor - cyy, cxy)
    norm = math.hypot(a, b)
    return (a / norm, b / norm) if norm > 0.0 else (1.0, 0.0)

