"""One P² step of a block of streams as generated C (the hot path of a ``P2QuantileBank``).

:meth:`ccopt.estimation.quantile.P2Quantile.add` past its first five samples, written in CasADi
symbols for :data:`BLOCK` streams at once, every branch evaluated and selected, so that the same
operations happen in the same order on the same floats: the heights and positions are those of
:class:`~ccopt.estimation.quantile.P2Quantile` fed each stream's samples, bit for bit (signed
zeros too). The function is compiled once and cached on disk
(:func:`ccopt.casadi_eval.compile_function`); where no C compiler works it is evaluated in process,
with a warning.
"""

from __future__ import annotations

import functools
import subprocess
import warnings
from pathlib import Path

import casadi as ca
import numpy as np

from ccopt.casadi_eval import BufferedFunction, compile_function

BLOCK = 64
"""Streams per call (the ground hull's directions); a bank of another size is padded to blocks."""

N_MARKERS = 5


def _finite(value: ca.SX) -> ca.SX:
    return ca.fabs(value) < ca.inf


def _select(condition: ca.SX, if_true: ca.SX, if_false: ca.SX) -> ca.SX:
    """``if_true if condition else if_false``, signed zeros kept (CasADi's ``if_else`` adds the two
    branches, each zero where not taken, and so turns a −0.0 into +0.0)."""
    sign = ca.if_else(condition, ca.copysign(1.0, if_true), ca.copysign(1.0, if_false))
    return ca.copysign(ca.if_else(condition, if_true, if_false), sign)


def _interpolate(low: ca.SX, high: ca.SX, fraction: ca.SX) -> ca.SX:
    """:func:`ccopt.estimation.quantile.interpolate` in symbols."""
    value = low + fraction * (high - low)
    return _select(_finite(value), value, (1.0 - fraction) * low + fraction * high)


def _adjust(heights: list[ca.SX], positions: list[ca.SX], marker: int, lag: ca.SX) -> None:
    """:func:`ccopt.estimation.quantile._adjust_marker` in symbols, in place on the lists."""
    gap_above = positions[marker + 1] - positions[marker]
    gap_below = positions[marker] - positions[marker - 1]
    up = ca.logic_and(lag >= 1.0, gap_above > 1.0)
    down = ca.logic_and(ca.logic_not(up), ca.logic_and(lag <= -1.0, gap_below > 1.0))
    step = ca.if_else(up, 1.0, ca.if_else(down, -1.0, 0.0))
    height, above, below = heights[marker], heights[marker + 1], heights[marker - 1]
    parabolic = height + step / (gap_above + gap_below) * (
        (gap_below + step) * (above - height) / gap_above + (gap_above - step) * (height - below) / gap_below
    )
    rising = step > 0.0
    linear = _select(rising, height + (above - height) / gap_above, height - (height - below) / gap_below)
    moved = _select(ca.logic_and(below < parabolic, parabolic < above), parabolic, linear)
    neighbour, gap = _select(rising, above, below), ca.if_else(rising, gap_above, gap_below)
    moved = _select(_finite(moved), moved, _interpolate(height, neighbour, 1.0 / gap))
    heights[marker] = _select(ca.logic_or(up, down), moved, height)
    positions[marker] = positions[marker] + step


def _step(heights: list[ca.SX], positions: list[ca.SX], sample: ca.SX, levels: ca.SX) -> None:
    """One stream's step (``P2Quantile.add`` of a finite sample after the fifth), in place."""
    lowest, highest = sample < heights[0], sample >= heights[4]
    cell = ca.if_else(
        lowest,
        0.0,
        ca.if_else(
            highest,
            3.0,
            ca.if_else(
                sample < heights[1],
                0.0,
                ca.if_else(sample < heights[2], 1.0, ca.if_else(sample < heights[3], 2.0, 3.0)),
            ),
        ),
    )
    heights[0] = _select(lowest, sample, heights[0])
    heights[4] = _select(ca.logic_and(ca.logic_not(lowest), highest), sample, heights[4])
    for marker in range(1, N_MARKERS):
        positions[marker] = positions[marker] + (cell < marker)
    top = positions[4]
    for marker in (1, 2, 3):
        _adjust(heights, positions, marker, top * levels[marker] - positions[marker])


@functools.cache
def build_p2_step() -> ca.Function:
    """``(heights, positions, samples, levels) → (heights, positions)``: one step of :data:`BLOCK`
    streams; heights and positions ``(5, BLOCK)``, a column per stream, samples ``(1, BLOCK)``,
    levels the markers' (:func:`~ccopt.estimation.quantile.marker_levels`, ``(5, 1)``). One stream's
    step mapped over the block (a loop in C)."""
    heights_in, positions_in = ca.SX.sym("heights", N_MARKERS), ca.SX.sym("positions", N_MARKERS)
    sample, levels = ca.SX.sym("sample"), ca.SX.sym("levels", N_MARKERS)
    heights, positions = ca.vertsplit(heights_in), ca.vertsplit(positions_in)
    _step(heights, positions, sample, levels)
    one = ca.Function(
        "ccopt_p2_stream",
        [heights_in, positions_in, sample, levels],
        [ca.vertcat(*heights), ca.vertcat(*positions)],
    )
    return one.map("ccopt_p2_step", "serial", BLOCK, [3], [])


@functools.cache
def p2_step(cache_dir: Path | None = None, compiler: str | None = None) -> BufferedFunction:
    """The step compiled and loaded once per process and cache (evaluated in process, with a
    warning, where no C compiler works); its buffers are per thread."""
    function = build_p2_step()
    try:
        library, _ = compile_function(function, cache_dir, compiler)
    except (OSError, RuntimeError, subprocess.CalledProcessError) as error:
        warnings.warn(
            f"code-generated P² step unavailable ({error}); evaluating it in process",
            RuntimeWarning,
            stacklevel=2,
        )
        return BufferedFunction(function)
    return BufferedFunction(ca.external(function.name(), str(library)))


def advance(heights: np.ndarray, positions: np.ndarray, samples: np.ndarray, levels: np.ndarray) -> None:
    """One step of a block, in place: ``heights`` and ``positions`` flat ``(5 BLOCK,)`` views of
    C-contiguous ``(BLOCK, 5)`` arrays (stream by stream, CasADi's column-major ``(5, BLOCK)``),
    ``samples`` ``(BLOCK,)``, ``levels`` ``(5,)``."""
    binding = p2_step().buffers()
    inputs, outputs = binding.flat_inputs, binding.flat_outputs
    inputs[0][:] = heights
    inputs[1][:] = positions
    inputs[2][:] = samples
    inputs[3][:] = levels
    binding.evaluate()
    heights[:] = outputs[0]
    positions[:] = outputs[1]
