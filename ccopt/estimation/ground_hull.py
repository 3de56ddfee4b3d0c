"""The ground hull's polygon and friction-face search compiled (the hot part of a fit of
:mod:`ccopt.estimation.ground_cone`).

A fit intersects 64 half-planes and searches the polygon for its friction faces: data-dependent
loops (a deque sweep, a longest pair, a face grown edge by edge) that take ~25 µs in Python, and
the fit is the estimator's slowest tick. ``ground_hull.c`` transcribes them line for line, the same
floating-point operations in the same order (built with ``-ffp-contract=off``, so no multiply-add is
fused), so the polygon and the faces' ends are those of the Python reference bit for bit
(:mod:`tests.test_ground_hull` holds it to that); :mod:`~ccopt.estimation.ground_cone` turns the
ends into rows as before. Written by hand, as the P² step is (:mod:`~ccopt.estimation.p2_step`),
not generated from CasADi symbols like the controller's tick: the sweep's deque has no fixed-size
branch-free form short of comparing every pair of lines, which costs more than the sweep and
rounds differently.

The library is compiled once and cached on disk (:func:`ccopt.casadi_eval.load_c_function`); where
no C compiler works, :func:`compiled_hull` warns and returns None, and the fit stays in Python.
"""

from __future__ import annotations

import ctypes
import functools
from collections.abc import Callable, Sequence
from pathlib import Path

import numpy as np

from ccopt.casadi_eval import load_c_function

SOURCE = Path(__file__).with_name("ground_hull.c")
_OUT = 14


@functools.cache
def _function(cache_dir: Path | None = None, compiler: str | None = None) -> Callable | None:
    """``ccopt_ground_hull`` of the compiled library, loaded once per process (None, with a warning,
    where it cannot be compiled)."""
    arguments = [ctypes.c_int, *[ctypes.c_void_p] * 5]
    fallback = "fitting it in Python"
    return load_c_function(SOURCE, "ccopt_ground_hull", arguments, fallback, cache_dir, compiler)


FaceEnds = tuple[tuple[float, float], tuple[float, float]]
"""A friction face's ends ``(start, end)`` on the hull's polygon (N, world)."""


class CompiledHull:
    """The polygon and face search of one set of support directions, with its own buffers (one per
    ground hull estimator: not shared between threads).

    Args:
        ux, uy: the support directions' components, by ascending angle (``K`` each).
        candidates: per side (right of world up, then left), per direction, whether its polygon
            edge may belong to that side's friction face.
        window_cosine: the cosine of the face window.
        prior_normals: the prior rows' unit normals, right then left.
        function: the compiled ``ccopt_ground_hull``.
    """

    def __init__(
        self,
        ux: Sequence[float],
        uy: Sequence[float],
        candidates: tuple[Sequence[bool], Sequence[bool]],
        window_cosine: float,
        prior_normals: tuple[tuple[float, float], tuple[float, float]],
        function: Callable,
    ) -> None:
        count = len(ux)
        self._count = count
        self._inputs = np.concatenate((ux, uy, np.zeros(count), *prior_normals, (window_cosine,)))
        self._support = self._inputs[2 * count : 3 * count]
        self._candidates = np.array([*candidates[0], *candidates[1]], dtype=np.uint8)
        self._work = np.zeros(5 * count)
        self._indices = np.zeros(2 * count, dtype=np.intc)
        self._out = np.zeros(_OUT)
        self._function = function
        self._arguments = (
            count,
            *(array.ctypes.data for array in (self._inputs, self._candidates, self._work, self._indices)),
            self._out.ctypes.data,
        )

    def faces(
        self, support: np.ndarray
    ) -> tuple[tuple[FaceEnds | None, FaceEnds | None], tuple[float, float]] | None:
        """``((right face's ends, left face's ends), (right, left) prior rows' offsets)`` of the
        polygon ``directions·f ≤ support``, a face None where none is found; None unless the support
        values and the polygon's vertices are finite."""
        self._support[:] = support
        self._function(*self._arguments)
        out = self._out.tolist()
        if not out[0]:
            return None
        right = ((out[3], out[4]), (out[5], out[6])) if out[2] else None
        left = ((out[8], out[9]), (out[10], out[11])) if out[7] else None
        return (right, left), (out[12], out[13])

    def polygon(self) -> tuple[list[int], list[tuple[float, float]]]:
        """The last :meth:`faces` call's polygon, as
        :func:`~ccopt.estimation.ground_cone.half_plane_polygon` returns it (valid where that call
        found the support values finite)."""
        count, n = self._count, int(self._out[1])
        vx, vy = self._work[3 * count : 3 * count + n], self._work[4 * count : 4 * count + n]
        return self._indices[count : count + n].tolist(), list(zip(vx.tolist(), vy.tolist(), strict=True))


def compiled_hull(
    ux: Sequence[float],
    uy: Sequence[float],
    candidates: tuple[Sequence[bool], Sequence[bool]],
    window_cosine: float,
    prior_normals: tuple[tuple[float, float], tuple[float, float]],
) -> CompiledHull | None:
    """A :class:`CompiledHull` of these directions, or None where no C compiler works."""
    function = _function()
    if function is None:
        return None
    return CompiledHull(ux, uy, candidates, window_cosine, prior_normals, function)
