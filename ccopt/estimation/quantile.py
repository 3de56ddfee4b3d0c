"""Streaming quantiles with the P² algorithm (Jain & Chlamtac 1985; the paper's "LiveStats").

P² keeps five markers per tracked quantile: the minimum, a quantile below ``p``, the ``p``
quantile, one above it and the maximum (levels: :func:`marker_levels`), each a height and an
(integer) position among the ``n`` samples seen so far. Every sample shifts the positions of the
markers above it; a marker whose position differs by one or more from its desired position
``(n − 1) p_i`` (0-based, ``p_i`` its level) moves one step, its height by a piecewise-parabolic
(P²) interpolation of its neighbours, or linearly when the parabola would break the marker order.
Memory and time per sample are O(1); the estimate is exact for the first five samples (it is then
the linear-interpolation quantile, as :func:`numpy.quantile`'s default), and non-finite samples are
ignored.

:class:`P2Quantile` tracks one quantile of a scalar stream in plain Python floats (the fastest form
for one stream); :class:`P2QuantileBank` tracks the same level of many streams that receive one
sample each per step (e.g. support values in many directions): the bookkeeping is vectorised in
NumPy and the (rare, for tail levels) marker moves run per stream.
"""

from __future__ import annotations

import math

import numpy as np

from ccopt.validation import check_count, check_number

N_MARKERS = 5


def check_level(level: object, name: str = "level") -> float:
    """``level`` as a float in ``(0, 1)``; raises ``TypeError``/``ValueError`` naming the bad value."""
    number = check_number(name, level, 0.0, 1.0)
    if number == 1.0:
        raise ValueError(f"{name} must be in (0, 1), got {level!r}")
    return number


def exact_quantile(sorted_values: list[float], level: float) -> float:
    """Linear-interpolation quantile of an ascending list (NumPy's default method); NaN if empty."""
    if not sorted_values:
        return math.nan
    position = (len(sorted_values) - 1) * level
    below = math.floor(position)
    above = min(below + 1, len(sorted_values) - 1)
    return interpolate(sorted_values[below], sorted_values[above], position - below)


def interpolate(low: float, high: float, fraction: float) -> float:
    """``low + fraction (high − low)`` for ``fraction`` in [0, 1], finite for any finite ``low`` and
    ``high`` (their difference may overflow: then the equal convex combination, which cannot)."""
    value = low + fraction * (high - low)
    return value if math.isfinite(value) else (1.0 - fraction) * low + fraction * high


def marker_levels(level: float) -> list[float]:
    """Levels of the five markers: ``0, p − min(p/2, 1 − p), p, p + min((1 − p)/2, p), 1``.

    Jain & Chlamtac place the inner markers at ``p/2`` and ``(1 + p)/2``; the placement here is the
    same for ``1/3 ≤ p ≤ 2/3`` and keeps them closer to ``p`` in the tails (e.g. 0.98, 0.99, 0.995
    for ``p = 0.99``), which was as accurate or more on every distribution tested and makes marker
    moves rare for tail levels (the bank exploits that).
    """
    return [0.0, level - min(level / 2.0, 1.0 - level), level, level + min((1.0 - level) / 2.0, level), 1.0]


class P2Quantile:
    """Streaming estimate of the ``level`` quantile of a scalar stream (P², O(1) memory).

    Args:
        level: the quantile level ``p ∈ (0, 1)``, e.g. ``0.99``.
    """

    __slots__ = ("_count", "_heights", "_levels", "_positions", "level")

    def __init__(self, level: float) -> None:
        self.level = check_level(level)
        self._count = 0
        self._heights: list[float] = []
        self._positions = [0.0, 1.0, 2.0, 3.0, 4.0]
        self._levels = marker_levels(self.level)

    @property
    def count(self) -> int:
        """Number of finite samples seen."""
        return self._count

    @property
    def value(self) -> float:
        """Current estimate of the quantile; NaN before the first finite sample."""
        if self._count <= N_MARKERS:
            return exact_quantile(sorted(self._heights), self.level)
        return self._heights[2]

    def add(self, sample: float) -> None:
        """Feed one sample; NaN and ±inf are ignored."""
        if not math.isfinite(sample):
            return
        self._count += 1
        heights = self._heights
        if self._count <= N_MARKERS:
            heights.append(float(sample))
            if self._count == N_MARKERS:
                heights.sort()
            return
        positions = self._positions
        if sample < heights[0]:
            heights[0] = float(sample)
            cell = 0
        elif sample >= heights[4]:
            heights[4] = float(sample)
            cell = 3
        elif sample < heights[1]:
            cell = 0
        elif sample < heights[2]:
            cell = 1
        elif sample < heights[3]:
            cell = 2
        else:
            cell = 3
        for marker in range(cell + 1, N_MARKERS):
            positions[marker] += 1.0
        top = positions[4]
        for marker in (1, 2, 3):
            _adjust_marker(heights, positions, marker, top * self._levels[marker] - positions[marker])


def _adjust_marker(heights: list[float], positions: list[float], marker: int, lag: float) -> None:
    """Move ``marker`` one position towards its desired one if it lags by ≥ 1 and there is room."""
    gap_above = positions[marker + 1] - positions[marker]
    gap_below = positions[marker] - positions[marker - 1]
    if lag >= 1.0 and gap_above > 1.0:
        step = 1.0
    elif lag <= -1.0 and gap_below > 1.0:
        step = -1.0
    else:
        return
    height, above, below = heights[marker], heights[marker + 1], heights[marker - 1]
    parabolic = height + step / (gap_above + gap_below) * (
        (gap_below + step) * (above - height) / gap_above + (gap_above - step) * (height - below) / gap_below
    )
    if below < parabolic < above:  # False for an overflowed (inf or NaN) parabola
        heights[marker] = parabolic
    elif step > 0.0:
        heights[marker] = height + (above - height) / gap_above
    else:
        heights[marker] = height - (height - below) / gap_below
    if not math.isfinite(heights[marker]):  # the neighbours' difference overflowed
        neighbour, gap = (above, gap_above) if step > 0.0 else (below, gap_below)
        heights[marker] = interpolate(height, neighbour, 1.0 / gap)
    positions[marker] += step


class P2QuantileBank:
    """The ``level`` quantile of ``size`` parallel streams, each fed one sample per :meth:`add`.

    The same algorithm as :class:`P2Quantile`, stream by stream (the results are identical), with
    positions kept relative to the newest sample (``n_i − (n − 1)``): a sample below a stream's
    marker 1 then changes nothing but the minimum, and marker ``i`` of such a stream can only move
    down, once its desired position ``(n − 1) p_i`` has fallen a full position behind, or up, if the
    marker above moved up in the previous step and made room. Only those streams and markers are
    visited, one by one; for tail levels they are a few percent of the streams
    (:func:`marker_levels`).

    Args:
        level: the quantile level ``p ∈ (0, 1)``.
        size: the number of streams.
    """

    def __init__(self, level: float, size: int) -> None:
        self.level = check_level(level)
        self.size = check_count("size", size)
        self._count = 0
        self._heights = np.zeros((N_MARKERS, self.size))
        self._relative = np.zeros((3, self.size))  # positions of markers 1–3 minus that of marker 4
        self._levels = marker_levels(self.level)
        self._due = np.zeros((3, 1))  # relative position at which each marker falls a position behind
        self._moved_up: list[int] = []  # streams where a marker moved up in the last step

    @property
    def count(self) -> int:
        """Number of (all-finite) samples seen."""
        return self._count

    @property
    def values(self) -> np.ndarray:
        """Current estimates, shape ``(size,)``; NaN before the first sample."""
        if self._count == 0:
            return np.full(self.size, np.nan)
        if self._count <= N_MARKERS:  # exact, as P2Quantile's
            columns = np.sort(self._heights[: self._count], axis=0).T.tolist()
            return np.array([exact_quantile(column, self.level) for column in columns])
        return self._heights[2].copy()

    def add(self, samples: np.ndarray) -> None:
        """Feed one sample per stream (float array of shape ``(size,)``); skipped if any is non-finite."""
        if not np.isfinite(samples).all():
            return
        self._count += 1
        heights, relative = self._heights, self._relative
        if self._count <= N_MARKERS:
            heights[self._count - 1] = samples
            if self._count == N_MARKERS:
                heights.sort(axis=0)
                relative[:] = np.arange(-3.0, 0.0)[:, None]
            return
        top = float(self._count - 1)  # position of marker 4 (the newest maximum)
        np.minimum(heights[0], samples, out=heights[0])
        reached = np.flatnonzero(samples >= heights[1]).tolist()
        for inner in range(3):  # lag = top p_i − n_i ≤ −1
            self._due[inner, 0] = top * (self._levels[inner + 1] - 1.0) + 1.0
        behind = np.flatnonzero(relative >= self._due).tolist()
        # A marker that moved up last step may have unblocked the one below it: revisit those streams.
        revisit = [stream for stream in self._moved_up if stream not in reached]
        moved_up = [stream for stream in reached if self._step(stream, samples.item(stream), top)]
        moved_up += [stream for stream in revisit if self._adjust_all(stream, top)]
        visited = set(reached).union(revisit)
        for flat in behind:  # marker-major: markers 1, 2, 3 of a stream in turn
            inner, stream = divmod(flat, self.size)
            if stream not in visited:
                self._adjust(inner + 1, stream, top)
        self._moved_up = moved_up

    def _step(self, stream: int, sample: float, top: float) -> bool:
        """One P² step of a stream the sample reached (``sample ≥`` its marker 1); True if a marker rose."""
        heights, relative = self._heights, self._relative
        if sample > heights.item(4, stream):
            heights[4, stream] = sample
        for marker in (1, 2, 3):
            if sample >= heights.item(marker, stream):
                relative[marker - 1, stream] -= 1.0
        return self._adjust_all(stream, top)

    def _adjust_all(self, stream: int, top: float) -> bool:
        """Markers 1, 2, 3 of ``stream`` in turn; True if one moved up."""
        moves = [self._adjust(marker, stream, top) for marker in (1, 2, 3)]
        return max(moves) > 0.0

    def _adjust(self, marker: int, stream: int, top: float) -> float:
        """:func:`_adjust_marker` on one marker of one stream; returns its move (−1, 0, +1)."""
        relative = self._relative
        position = relative.item(marker - 1, stream) + top
        lag = top * self._levels[marker] - position
        if -1.0 < lag < 1.0:
            return 0.0
        below = 0.0 if marker == 1 else relative.item(marker - 2, stream) + top
        above = top if marker == 3 else relative.item(marker, stream) + top
        local_heights = [self._heights.item(index, stream) for index in (marker - 1, marker, marker + 1)]
        local_positions = [below, position, above]
        _adjust_marker(local_heights, local_positions, 1, lag)
        self._heights[marker, stream] = local_heights[1]
        relative[marker - 1, stream] = local_positions[1] - top
        return local_positions[1] - position
