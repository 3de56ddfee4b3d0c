"""Low-overhead numeric evaluation of CasADi functions from NumPy, and their generated C.

A plain ``casadi.Function`` call with NumPy arguments converts every argument to ``DM`` and costs
tens of microseconds. :class:`BufferedFunction` binds preallocated, contiguous NumPy arrays to a
``FunctionBuffer`` once and then evaluates through a ctypes pointer: a call is a few array copies
plus the function's own work. Each thread binds its own buffers on first use, so one instance (for
example a module-level one) can be shared by the threads of a Dask worker.

:func:`compile_function` generates C for functions, compiles it once with the system C compiler and
caches the library on disk by a hash of the source (``$CCOPT_CACHE_DIR``, else
``$XDG_CACHE_HOME/ccopt``, else ``~/.cache/ccopt``); ``casadi.external`` loads it.
:func:`compile_source` does the same for C written by hand.
"""

from __future__ import annotations

import ctypes
import hashlib
import os
import shutil
import subprocess
import tempfile
import threading
import warnings
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from pathlib import Path

import casadi as ca
import numpy as np
from numpy.typing import ArrayLike


@dataclass(frozen=True)
class Binding:
    """One thread's buffers: column-major arrays bound to a ``FunctionBuffer``, and its evaluator.

    ``flat_inputs`` and ``flat_outputs`` are 1-D views of the same memory (CasADi's order);
    ``shaped_outputs`` are views shaped as :meth:`BufferedFunction.__call__` returns them (column
    vectors 1-D, matrices 2-D)."""

    inputs: list[np.ndarray]
    outputs: list[np.ndarray]
    flat_inputs: list[np.ndarray]
    flat_outputs: list[np.ndarray]
    shaped_outputs: list[np.ndarray]
    buffer: object  # keeps the FunctionBuffer alive while ``evaluate`` points into it
    evaluate: Callable[[], None]


def _bind(function: ca.Function) -> Binding:
    inputs = [np.zeros(function.size_in(i), order="F") for i in range(function.n_in())]
    outputs = [np.zeros(function.size_out(i), order="F") for i in range(function.n_out())]
    flat_inputs = [array.reshape(-1, order="F") for array in inputs]
    flat_outputs = [array.reshape(-1, order="F") for array in outputs]
    buffer, evaluate = function.buffer()
    for i, flat in enumerate(flat_inputs):
        buffer.set_arg(i, memoryview(flat))
    for i, flat in enumerate(flat_outputs):
        buffer.set_res(i, memoryview(flat))
    shaped = [_squeeze(array) for array in outputs]
    return Binding(inputs, outputs, flat_inputs, flat_outputs, shaped, buffer, evaluate)


class BufferedFunction:
    """Evaluate ``function`` on NumPy inputs through preallocated buffers (one set per thread).

    Inputs are copied into column-major (CasADi order) buffers; outputs are returned as fresh
    arrays shaped like the function's outputs (vectors as 1-D, matrices as 2-D).
    """

    def __init__(self, function: ca.Function, prepare: Callable[[Binding], None] | None = None) -> None:
        """``prepare``, if given, is called with each thread's buffers once they are bound (to fill
        inputs that never change)."""
        self.function = _densified(function)
        self._n_in = self.function.n_in()
        self._local = threading.local()
        self._prepare = prepare

    @property
    def name(self) -> str:
        return self.function.name()

    def buffers(self) -> Binding:
        """This thread's buffers, bound on the thread's first call. Callers may fill them in place:
        write ``flat_inputs``, call ``evaluate()``, read ``flat_outputs`` (views: copy what is kept)."""
        try:
            return self._local.binding
        except AttributeError:
            binding = _bind(self.function)
            if self._prepare is not None:
                self._prepare(binding)
            self._local.binding = binding
            return binding

    def __call__(self, *args: ArrayLike) -> tuple[np.ndarray, ...]:
        if len(args) != self._n_in:
            raise TypeError(f"{self.name} takes {self._n_in} arguments, got {len(args)}")
        binding = self.buffers()
        for buffer, flat, value in zip(binding.inputs, binding.flat_inputs, args, strict=True):
            if type(value) is float and flat.shape[0] == 1:  # a Python float: no array to build
                flat[0] = value
            else:
                buffer[...] = np.reshape(value, buffer.shape, order="F")
        binding.evaluate()
        return tuple(out.copy(order="C") for out in binding.shaped_outputs)

    def call_scalars(self, *values: float) -> np.ndarray:
        """Fast path for functions of scalar inputs: output 0 (a fresh array, shaped as
        :meth:`__call__` returns it) of one number per input (not checked)."""
        binding = self.buffers()
        for flat, value in zip(binding.flat_inputs, values, strict=True):
            flat[0] = value
        binding.evaluate()
        return binding.shaped_outputs[0].copy()

    def failed(self) -> bool:
        """Whether this thread's last evaluation reported failure (generated code returns non-zero,
        e.g. where a QP solver fails, and leaves its outputs as they were: stale). Costs ~1 µs."""
        return self.buffers().buffer.ret() != 0

    def call_flat(self, flat_input: np.ndarray, out: np.ndarray | None = None) -> np.ndarray:
        """Fast path for one-input, one-output functions: copy ``flat_input`` in, return output 0.

        ``out``, when given, receives the result without allocation.
        """
        binding = self.buffers()
        binding.flat_inputs[0][:] = flat_input
        binding.evaluate()
        result = binding.flat_outputs[0]
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
    """Column vectors (a scalar too) as 1-D views, matrices unchanged."""
    rows, cols = array.shape
    if cols == 1:
        return array.reshape(rows)
    return array


# --- code generation and the on-disk cache ---------------------------------------------------------


def default_cache_dir() -> Path:
    """Where compiled functions live: ``$CCOPT_CACHE_DIR``, ``$XDG_CACHE_HOME/ccopt`` or
    ``~/.cache/ccopt``."""
    if os.environ.get("CCOPT_CACHE_DIR"):
        return Path(os.environ["CCOPT_CACHE_DIR"])
    base = os.environ.get("XDG_CACHE_HOME") or Path.home() / ".cache"
    return Path(base) / "ccopt"


def _compile_command(compiler: str, source: Path, library: Path, flags: Sequence[str]) -> list[str]:
    return [compiler, "-O3", "-shared", "-fPIC", str(source), "-o", str(library), *flags, "-lm"]


def _casadi_flags() -> list[str]:
    """The headers and the static DAQP library that CasADi's generated C needs."""
    casadi_dir = Path(ca.__file__).parent
    return [
        f"-I{casadi_dir / 'include'}",
        f"-I{casadi_dir / 'include' / 'daqp'}",
        str(casadi_dir / "libdaqpstat.a"),
    ]


def compile_function(
    function: ca.Function | Sequence[ca.Function],
    cache_dir: Path | None = None,
    compiler: str | None = None,
    name: str | None = None,
) -> tuple[Path, bool]:
    """Generate C for ``function`` (or several functions, into one library named ``name``), compile
    it once, and return ``(library path, cache hit)``; each function loads from it by its name
    (:func:`compile_source`)."""
    functions = [function] if isinstance(function, ca.Function) else list(function)
    generator = ca.CodeGenerator(f"{name or functions[0].name()}.c", {"with_header": False})
    for each in functions:
        generator.add(each)
    source = f"/* CasADi {ca.__version__} */\n{generator.dump()}"
    return compile_source(name or functions[0].name(), source, cache_dir, compiler, _casadi_flags())


def load_c_function(
    source: Path,
    symbol: str,
    argtypes: Sequence[type],
    fallback: str,
    cache_dir: Path | None = None,
    compiler: str | None = None,
    restype: type | None = None,
) -> Callable | None:
    """The function ``symbol`` of the C file ``source`` written by hand, compiled with
    ``-ffp-contract=off`` (no fused multiply-add: the rounding of the Python it transcribes) by
    :func:`compile_source` and loaded through ``ctypes``, returning ``restype`` (None: nothing).
    Where it cannot be compiled, None, with a ``RuntimeWarning`` saying so and that the caller goes
    on with ``fallback`` (e.g. "fitting it in Python")."""
    flags = ("-ffp-contract=off",)
    try:
        library, _ = compile_source(source.stem, source.read_text(), cache_dir, compiler, flags)
    except (OSError, RuntimeError, subprocess.CalledProcessError) as error:
        message = f"compiled {source.name} unavailable ({error}); {fallback}"
        warnings.warn(message, RuntimeWarning, stacklevel=3)
        return None
    function = getattr(ctypes.CDLL(str(library)), symbol)
    function.argtypes = list(argtypes)
    function.restype = restype
    return function


def compile_source(
    name: str,
    source: str,
    cache_dir: Path | None = None,
    compiler: str | None = None,
    flags: Sequence[str] = (),
) -> tuple[Path, bool]:
    """Compile the C ``source`` into a shared library once and return ``(library path, cache hit)``.

    The library is named by a hash of the source and the compile command (``flags`` included), so a
    changed source compiles anew. Compilation writes to a temporary file and renames it into place,
    so concurrent processes never load a half-written library. Raises ``RuntimeError`` if no
    compiler is found or compilation fails.
    """
    compiler = compiler or os.environ.get("CC") or "cc"
    if shutil.which(compiler) is None:
        raise RuntimeError(f"no C compiler {compiler!r} on PATH")
    cache = Path(cache_dir) if cache_dir is not None else default_cache_dir()
    command_key = " ".join(_compile_command(compiler, Path("src.c"), Path("lib.so"), flags))
    digest = hashlib.sha256(f"{command_key}\n{source}".encode()).hexdigest()[:20]
    library = cache / f"{name}_{digest}.so"
    if library.exists():
        return library, True
    cache.mkdir(parents=True, exist_ok=True)
    with tempfile.TemporaryDirectory(dir=cache) as workdir:
        source_path = Path(workdir) / f"{name}.c"
        source_path.write_text(source)
        partial = Path(workdir) / library.name
        result = subprocess.run(
            _compile_command(compiler, source_path, partial, flags), capture_output=True, text=True
        )
        if result.returncode != 0:
            raise RuntimeError(f"compiling {name} failed: {result.stderr.strip()[:500]}")
        os.replace(partial, library)
    return library, False
