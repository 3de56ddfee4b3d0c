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
sample each per step (e.g. support values in many directions), with the same results, in C
(:mod:`ccopt.estimation.p2_step`).
"""

from __future__ import annotations

import functools
import math
from collections.abc import Callable

import numpy as np

from ccopt.estimation.p2_step import N_MARKERS, p2_bank_step
from ccopt.validation import check_count, check_number


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
    for ``p = 0.99``), which was as accurate or more on every distribution tested.
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
        _step(heights, self._positions, self._levels, float(sample))


def _step(heights: list[float], positions: list[float], levels: list[float], sample: float) -> None:
    """One finite sample past the first five, in place on the markers' heights and positions."""
    if sample < heights[0]:
        heights[0] = sample
        cell = 0
    elif sample >= heights[4]:
        heights[4] = sample
        cell = 3
    elif sample < heights[1]:
        cell = 0
    elif sample < heights[2]:
        cell = 1
    elif sample < heights[3]:
        cell = 2
    else:
        cell = 3
    if cell < 1:  # the markers above the sample's cell move up: cell + 1 .. 4, unrolled
        positions[1] += 1.0
    if cell < 2:
        positions[2] += 1.0
    if cell < 3:
        positions[3] += 1.0
    positions[4] += 1.0
    top = positions[4]
    for marker in (1, 2, 3):
        lag = top * levels[marker] - positions[marker]
        if lag >= 1.0 or lag <= -1.0:  # most samples move no marker: no call
            _adjust_marker(heights, positions, marker, lag)


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

    The same algorithm as :class:`P2Quantile`, stream by stream, with the same results: the first
    five samples here, then one call of C per sample for every stream (:mod:`ccopt.estimation.p2_step`;
    in Python, stream by stream, where no C compiler works).

    Args:
        level: the quantile level ``p ∈ (0, 1)``.
        size: the number of streams.
    """

    def __init__(self, level: float, size: int) -> None:
        self.level = check_level(level)
        self.size = check_count("size", size)
        self._count = 0
        self._heights = np.zeros((self.size, N_MARKERS))  # stream by stream
        self._positions = np.zeros((self.size, N_MARKERS))
        self._samples = np.zeros(self.size)
        self._levels = np.array(marker_levels(self.level))
        self._advance = self._bind()

    def _bind(self) -> Callable[[], int]:
        """The step of every stream on this bank's arrays with the samples in ``_samples`` (their
        addresses bound once: a copy or a pickle has arrays of its own and binds anew); it returns 1,
        or 0 having changed nothing where a sample is not finite."""
        step = p2_bank_step()
        if step is None:
            return self._python_step
        addresses = (a.ctypes.data for a in (self._heights, self._positions, self._samples, self._levels))
        return functools.partial(step, self.size, *addresses)

    def _python_step(self) -> int:
        """:func:`_step` stream by stream in Python (what the C does)."""
        levels, samples = self._levels.tolist(), self._samples.tolist()
        if not all(math.isfinite(sample) for sample in samples):
            return 0
        for heights, positions, sample in zip(self._heights, self._positions, samples, strict=True):
            values, places = heights.tolist(), positions.tolist()
            _step(values, places, levels, sample)
            heights[:], positions[:] = values, places
        return 1

    def __getstate__(self) -> dict[str, object]:
        state = dict(self.__dict__)
        del state["_advance"]  # bound to this bank's arrays: bound anew
        return state

    def __setstate__(self, state: dict[str, object]) -> None:
        self.__dict__.update(state)
        self._advance = self._bind()

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
            rows = np.sort(self._heights[:, : self._count], axis=1).tolist()
            return np.array([exact_quantile(row, self.level) for row in rows])
        return self._heights[:, 2].copy()

    def add(self, samples: np.ndarray) -> None:
        """Feed one sample per stream (float array of shape ``(size,)``); skipped if any is non-finite
        (checked by the step itself past the first five samples)."""
        self._samples[:] = samples
        if self._count >= N_MARKERS:
            self._count += self._advance()
            return
        if not np.isfinite(self._samples).all():
            return
        self._count += 1
        self._heights[:, self._count - 1] = self._samples
        if self._count == N_MARKERS:
            self._heights.sort(axis=1)
            self._positions[:] = np.arange(float(N_MARKERS))
