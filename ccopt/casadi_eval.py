"""Low-overhead numeric evaluation of CasADi functions from NumPy.

A plain ``casadi.Function`` call with NumPy arguments converts every argument to ``DM`` and costs
tens of microseconds. :class:`BufferedFunction` binds preallocated, contiguous NumPy arrays to a
``FunctionBuffer`` once and then evaluates through a ctypes pointer: a call is a few array copies
plus the function's own work. One instance is not thread-safe (it owns its buffers); processes and
threads should each build their own.
"""

from __future__ import annotations

import casadi as ca
import numpy as np
from numpy.typing import ArrayLike


class BufferedFunction:
    """Evaluate ``function`` on NumPy inputs through preallocated buffers.

    Inputs are copied into column-major (CasADi order) buffers; outputs are returned as fresh
    arrays shaped like the function's outputs (vectors as 1-D, matrices as 2-D).
    """

    def __init__(self, function: ca.Function) -> None:
        function = _densified(function)
        self.function = function
        self._inputs = [np.zeros(function.size_in(i), order="F") for i in range(function.n_in())]
        self._outputs = [np.zeros(function.size_out(i), order="F") for i in range(function.n_out())]
        self._buffer, self._evaluate = function.buffer()
        for i, array in enumerate(self._inputs):
            self._buffer.set_arg(i, memoryview(array.reshape(-1, order="F")))
        for i, array in enumerate(self._outputs):
            self._buffer.set_res(i, memoryview(array.reshape(-1, order="F")))

    @property
    def name(self) -> str:
        return self.function.name()

    def __call__(self, *args: ArrayLike) -> tuple[np.ndarray, ...]:
        if len(args) != len(self._inputs):
            raise TypeError(f"{self.name} takes {len(self._inputs)} arguments, got {len(args)}")
        for buffer, value in zip(self._inputs, args, strict=True):
            buffer[...] = np.reshape(value, buffer.shape, order="F")
        self._evaluate()
        return tuple(_squeeze(out.copy(order="C")) for out in self._outputs)

    def call_flat(self, flat_input: np.ndarray, out: np.ndarray | None = None) -> np.ndarray:
        """Fast path for one-input, one-output functions: copy ``flat_input`` in, return output 0.

        ``out``, when given, receives the result without allocation.
        """
        self._inputs[0].reshape(-1, order="F")[:] = flat_input
        self._evaluate()
        result = self._outputs[0].reshape(-1, order="F")
        if out is None:
            return result.copy()
        out[:] = result
        return out


def _densified(function: ca.Function) -> ca.Function:
    """``function`` with dense inputs and outputs (a buffer transfers structural nonzeros only)."""
    dense_in = all(function.sparsity_in(i).is_dense() for i in range(function.n_in()))
    dense_out = all(function.sparsity_out(i).is_dense() for i in range(function.n_out()))
    if dense_in and dense_out:
        return function
    inputs = [ca.MX.sym(function.name_in(i), *function.size_in(i)) for i in range(function.n_in())]
    outputs = [ca.densify(out) for out in function.call(inputs)]
    return ca.Function(function.name(), inputs, outputs)


def _squeeze(array: np.ndarray) -> np.ndarray:
    """Column vectors as 1-D arrays, scalars as 0-D arrays, matrices unchanged."""
    rows, cols = array.shape
    if cols == 1:
        return array.reshape(rows)
    return array
