"""One P² step of many streams in C written for it (the hot path of a ``P2QuantileBank``).

``p2_bank.c`` transcribes :meth:`ccopt.estimation.quantile.P2Quantile.add` past its first five
samples line for line, the same floating-point operations in the same order (built with
``-ffp-contract=off``), so the heights and positions are those of
:class:`~ccopt.estimation.quantile.P2Quantile` fed each stream's samples, bit for bit (signed zeros
too). Written by hand rather than generated from CasADi symbols: CasADi has no branches, so its
form evaluated every branch and selected (3.3 µs a step of 64 streams, 4.5 with its buffers'
copies, against 0.3 here). The library is compiled once and cached on disk
(:func:`ccopt.casadi_eval.load_c_function`); where no C compiler works, :func:`p2_bank_step` warns
and returns None, and the bank steps its streams in Python.
"""

from __future__ import annotations

import ctypes
import functools
from collections.abc import Callable
from pathlib import Path

from ccopt.casadi_eval import load_c_function

N_MARKERS = 5
SOURCE = Path(__file__).with_name("p2_bank.c")


@functools.cache
def p2_bank_step(cache_dir: Path | None = None, compiler: str | None = None) -> Callable | None:
    """``ccopt_p2_bank(streams, heights, positions, samples, levels)``, loaded once per process:
    heights and positions ``(streams, 5)`` C-contiguous, stepped in place, samples ``(streams,)``,
    levels the markers' (5), each passed as its address; it returns 1, or 0 having changed nothing
    where a sample is not finite. None, with a warning, where it cannot be compiled."""
    arguments = [ctypes.c_int, *[ctypes.c_void_p] * 4]
    fallback = "stepping the streams in Python"
    return load_c_function(SOURCE, "ccopt_p2_bank", arguments, fallback, cache_dir, compiler, ctypes.c_int)
