"""The controller's tick as one generated C function: QP instance, solve and speed limit in one call.

:meth:`ccopt.control.controller.Controller.build_instance`, the code-generated QP of
:mod:`ccopt.control.qp` and the checks of :meth:`~ccopt.control.controller.Controller.update` (a step
that is not finite holds the target; a step beyond the speed limit is scaled down to it, its wrench
change and slack evaluated again), written once more in CasADi symbols and generated into one C
library, compiled and cached on disk by :func:`ccopt.casadi_eval.compile_function`. There is one
function per contact case (:data:`CASES`: the commanded motion, and for a slide whether it has begun),
because the case sets the shape of the model (one free direction or two) and which terms and rows
the QP has. ``build_instance`` stays the readable reference; the tests hold this path to it.

Each function takes the tick's raw numbers (:data:`INPUTS`, hand frame, SI units) and the
controller's constants (:data:`PARAMETERS`, written with every call, so one library serves every
controller and thread), and returns one vector (:data:`OUTPUTS`): the step ``Δx`` (m, m, rad), the
QP's solution in its own units (the step ``y``, the wrench change, the slack), whether the solver gave
a finite step, and the instance's packed parameters. Where no C compiler works the same functions are
evaluated in process, with a warning.
"""

from __future__ import annotations

import functools
import math
import subprocess
import warnings
from pathlib import Path

import casadi as ca
import numpy as np

from ccopt import contact, modes
from ccopt.casadi_eval import Binding, BufferedFunction, compile_function
from ccopt.contact import N_CONE_ROWS
from ccopt.control import qp
from ccopt.modes import Motion

Case = tuple[Motion, bool]
"""A contact case: the commanded motion and whether its slide has begun (False for hold and pivot)."""

CASES: tuple[Case, ...] = tuple(
    (motion, begun)
    for motion in Motion
    for begun in ((False, True) if motion in modes.SLIDES else (False,))
)

N_ROWS = N_CONE_ROWS + 2
"""Rows of every tick's instance: the six cone rows, then ``f_n ≤ f_max − headroom`` and ``−f_n ≤ −f_min``."""
N_TERMS = 3
"""Terms of every tick's instance: the free coordinates' (one or two), the normal force's, and the
tangential force's (hold, pivot) or the push past the removed row (a slide not yet begun)."""

PARAMETERS: tuple[tuple[str, int], ...] = (
    ("regularization", 1),
    ("weights", 3),
    ("hold_weights", 3),
    ("convergence", 1),
    ("force_gain", 1),
    ("force_weight", 1),
    ("push_weight", 1),
    ("push_force", 1),
    ("friction_margin", 1),
    ("torque_margin", 1),
    ("ground_margin", 1),
    ("min_margin", 1),
    ("statics_margin_share", 1),
    ("units", 3),
    ("force_unit", 1),
    ("row_gains", N_ROWS),
    ("force_bounds", 2),
    ("max_step", 3),
    ("slide_max_step", 3),
)
"""The controller's constants, in the order of the ``parameters`` input: the
:class:`~ccopt.control.controller.ControllerParams` of the same names, and ``convergence``,
``force_gain`` (fractions per tick), ``units`` (the step's, m, m, rad), ``row_gains``, ``force_bounds``
(N), ``max_step`` and ``slide_max_step`` (m, m, rad per tick; the latter while a slide is commanded)
as the controller derives them."""

SCALARS = (
    "hand_angle",
    "s_h",
    "d",
    "mu_h",
    "l_h",
    "force_target",
    "tangential_target",
    "statics_margin",
    "statics_known",
)
"""The tick's numbers, in the order of the ``scalars`` input: ``θ_h`` (rad), ``s_h`` and ``d`` of
``v_θ`` (m, finite), ``μ̂_h``, ``l_h`` (m), the normal and tangential force targets (N, resolved),
the statics margin (N) and whether it is known (1 or 0)."""

INPUTS: tuple[tuple[str, tuple[int, int]], ...] = (
    ("parameters", (sum(size for _, size in PARAMETERS), 1)),
    ("stiffness", (3, 3)),
    ("scalars", (len(SCALARS), 1)),
    ("wrench", (3, 1)),
    ("coordinates", (3, 1)),
    ("targets", (3, 1)),
    ("cone_rows", (N_CONE_ROWS, 3)),
    ("cone_bounds", (N_CONE_ROWS, 1)),
    ("row_valid", (N_CONE_ROWS, 1)),
)
"""Inputs of every case's function: the constants, the hand-frame stiffness ``K`` (3×3), the
scalars, the measured wrench, the progress coordinates and the command's targets ``(θ_o, s_h, s_g)``,
the estimated cone rows and bounds and which rows are estimated (1 or 0)."""

OUTPUTS: dict[str, slice] = {
    "step": slice(0, 3),
    "solution_step": slice(3, 6),
    "wrench_change": slice(6, 9),
    "slack": slice(9, 10),
    "solved": slice(10, 11),
    "packed": slice(11, 11 + qp.N_PARAMETERS),
}
"""Slices of the output vector."""

_SOLVED = OUTPUTS["solved"].start
_FORCE_ROWS = ca.DM([[1.0, 0.0, 0.0], [-1.0, 0.0, 0.0]])


def _split(vector: ca.SX, layout: tuple[tuple[str, int], ...]) -> dict[str, ca.SX]:
    out, offset = {}, 0
    for name, size in layout:
        out[name] = vector[offset : offset + size]
        offset += size
    return out


def _py_max(a: ca.SX, b: ca.SX) -> ca.SX:
    """Python's ``max(a, b)``: ``b`` if ``b > a``, else ``a`` (NaNs as Python treats them)."""
    return ca.if_else(b > a, b, a)


def _py_min(a: ca.SX, b: ca.SX) -> ca.SX:
    """Python's ``min(a, b)``."""
    return ca.if_else(b < a, b, a)


def _solve_2x2(matrix: ca.SX, rhs: ca.SX) -> ca.SX:
    """``matrix⁻¹ rhs`` (2×2, 2×n) by Gaussian elimination with partial pivoting, as LAPACK's ``gesv``."""
    swap = ca.fabs(matrix[1, 0]) > ca.fabs(matrix[0, 0])
    top = ca.if_else(swap, ca.horzcat(matrix[1, :], rhs[1, :]), ca.horzcat(matrix[0, :], rhs[0, :]))
    bottom = ca.if_else(swap, ca.horzcat(matrix[0, :], rhs[0, :]), ca.horzcat(matrix[1, :], rhs[1, :]))
    factor = bottom[0] * (1.0 / top[0])
    pivot = bottom[1] - factor * top[1]
    second = (bottom[2:] - factor * top[2:]) / pivot
    first = (top[2:] - top[1] * second) / top[0]
    return ca.vertcat(first, second)


def _quasi_static_maps(stiffness: ca.SX, free: ca.SX, balance: ca.SX) -> tuple[ca.SX, ca.SX]:
    """:func:`ccopt.control.controller.quasi_static_maps` in symbols: ``(A, P)``."""
    coupling = balance @ stiffness
    reduced = coupling @ free
    motion_map = coupling * (1.0 / reduced) if reduced.shape == (1, 1) else _solve_2x2(reduced, coupling)
    return motion_map, stiffness @ (ca.DM.eye(3) - free @ motion_map)


def _margins(f_n: ca.SX, s: dict[str, ca.SX], q: dict[str, ca.SX]) -> ca.SX:
    """:meth:`ccopt.control.controller.Controller._margins` in symbols (6,)."""
    force = _py_max(f_n, 0.0)
    slide = _py_max(q["friction_margin"] * s["mu_h"] * force, q["min_margin"])
    pivot = _py_max(q["torque_margin"] * force, q["min_margin"]) * s["l_h"]
    ground = q["ground_margin"]
    share = q["statics_margin_share"] * s["statics_margin"]
    known = s["statics_known"]
    slide = ca.if_else(known, _py_max(_py_min(slide, share), 0.5 * slide), slide)
    pivot = ca.if_else(known, _py_max(_py_min(pivot, share * s["l_h"]), 0.5 * pivot), pivot)
    ground = ca.if_else(known, _py_max(_py_min(ground, share), 0.5 * ground), ground)
    return ca.vertcat(slide, slide, pivot, pivot, ground, ground)


def _model(case: Case, vectors: ca.SX, cone_rows: ca.SX) -> tuple[list[int], ca.SX]:
    """``Controller._model`` in symbols: the free coordinates and their equilibrium rows ``E``."""
    motion, begun = case
    if begun:
        removed = modes.REMOVED_ROWS[motion][0]
        balance = ca.vertcat(vectors[:, modes.THETA_O].T, cone_rows[removed, :])
        return [modes.THETA_O, modes.driven_coordinate(motion)], balance
    return [modes.THETA_O], vectors[:, modes.THETA_O].T


def _terms(
    case: Case, free: list[int], maps: tuple[ca.SX, ca.SX], x: dict[str, ca.SX], s: dict[str, ca.SX]
) -> tuple[ca.SX, ca.SX, ca.SX]:
    """``build_instance``'s tracking terms in symbols: their directions in the QP's units (k×3),
    weights (k) and targets (k)."""
    motion, begun = case
    q, (motion_map, wrench_map), wrench = _split(x["parameters"], PARAMETERS), maps, x["wrench"]
    units, driven, removed = q["units"], modes.driven_coordinate(motion), modes.REMOVED_ROWS[motion]
    errors = x["targets"] - x["coordinates"]
    directions, weights, targets = [], [], []
    for row, k in enumerate(free):
        unit = units[2] if k == modes.THETA_O else units[0]
        directions.append(motion_map[row, :] / unit)
        weights.append(q["weights"][k] if k == driven else q["hold_weights"][k])
        targets.append(q["convergence"] * errors[k] / unit)
    force_unit, gain = q["force_unit"], q["force_gain"]
    directions.append(wrench_map[0, :] / force_unit)
    weights.append(q["force_weight"])
    targets.append(gain * (s["force_target"] - wrench[0]) / force_unit)
    if not removed:  # hold the tangential force at its target
        directions.append(wrench_map[1, :] / force_unit)
        weights.append(q["force_weight"])
        targets.append(gain * (s["tangential_target"] - wrench[1]) / force_unit)
    elif not begun:  # push the removed row past its bound
        row = x["cone_rows"][removed[0], :]
        scale = force_unit * ca.sqrt(ca.dot(row, row))
        excess = x["cone_bounds"][removed[0]] + q["push_force"] - row @ wrench
        directions.append((row @ wrench_map) / scale)
        weights.append(q["push_weight"])
        targets.append(gain * excess / scale)
    in_units = ca.vertcat(*directions) * ca.repmat(units.T, len(directions), 1)
    return in_units, ca.vertcat(*weights), ca.vertcat(*targets)


def _instance(case: Case, x: dict[str, ca.SX]) -> dict[str, ca.SX]:
    """The fields of the tick's :class:`~ccopt.control.qp.QPInstance`, as ``build_instance`` makes them."""
    q, s = _split(x["parameters"], PARAMETERS), dict(zip(SCALARS, ca.vertsplit(x["scalars"]), strict=True))
    stiffness, cone_rows = x["stiffness"], x["cone_rows"]
    vectors = contact.motion_vectors(s["hand_angle"], s["s_h"], s["d"])
    free, balance = _model(case, vectors, cone_rows)
    maps = _quasi_static_maps(stiffness, ca.horzcat(*(vectors[:, k] for k in free)), balance)
    directions, weights, targets = _terms(case, free, maps, x, s)
    kept = modes.kept_rows(case[0])
    valid = [x["row_valid"][i] if kept[i] else ca.SX(0.0) for i in range(N_CONE_ROWS)]
    return {
        "stiffness": maps[1] * ca.repmat(q["units"].T, 3, 1),
        "wrench": x["wrench"],
        "rows": ca.vertcat(cone_rows, _FORCE_ROWS),
        "bounds": ca.vertcat(x["cone_bounds"] - _margins(x["wrench"][0], s, q), q["force_bounds"]),
        "gains": q["row_gains"],
        "active": ca.vertcat(*valid, 1.0, 1.0),
        "regularization": q["regularization"],
        "directions": directions,
        "weights": weights,
        "targets": targets,
    }


def _finish(packed: ca.SX, z: ca.SX, parameters: ca.SX, max_step: ca.SX) -> ca.SX:
    """The output vector from the instance and the QP's ``z = (y, t)``: ``Controller.update``'s checks.

    A step that is not finite gives no step, no wrench change, infinite slack and ``solved = 0``; a
    step beyond the speed limit ``max_step`` (the case's, m, m, rad per tick) is scaled down to it,
    and its wrench change and its slack on the active rows are evaluated again (``_scaled``)."""
    q, instance = _split(parameters, PARAMETERS), qp.unpack_symbols(packed)
    y = z[:3]
    step = q["units"] * y
    solved = ca.logic_and(
        ca.logic_and(ca.fabs(step[0]) < ca.inf, ca.fabs(step[1]) < ca.inf), ca.fabs(step[2]) < ca.inf
    )
    excess = _py_max(
        _py_max(ca.fabs(step[0]) / max_step[0], ca.fabs(step[1]) / max_step[1]),
        ca.fabs(step[2]) / max_step[2],
    )
    scaled_y = y * (1.0 / excess)
    scaled_change = instance["stiffness"] @ scaled_y
    rows = instance["rows"]
    row_excess = instance["gains"] * (rows @ scaled_change) - (instance["bounds"] - rows @ instance["wrench"])
    active_excess = ca.if_else(instance["active"], row_excess, 0.0)
    scaled_slack = _py_max(0.0, ca.mmax(active_excess))
    scale = excess > 1.0
    kept = ca.vertcat(
        ca.if_else(scale, step / excess, step),
        ca.if_else(scale, scaled_y, y),
        ca.if_else(scale, scaled_change, instance["stiffness"] @ y),
        ca.if_else(scale, scaled_slack, _py_max(z[3], 0.0)),
    )
    failed = ca.vertcat(ca.SX.zeros(9), ca.inf)
    return ca.vertcat(ca.if_else(solved, kept, failed), solved, packed)


def _case_name(case: Case) -> str:
    motion, begun = case
    return f"ccopt_tick_{motion.value}{'_begun' if begun else ''}"


@functools.cache
def build_tick_functions() -> dict[Case, ca.Function]:
    """The symbolic function of every case (built once per process), sharing one QP function."""
    solve = qp.build_qp_function()
    symbols = {name: ca.SX.sym(name, *shape) for name, shape in INPUTS}
    parameters, packed_in, z_in = (
        symbols["parameters"],
        ca.SX.sym("packed", qp.N_PARAMETERS),
        ca.SX.sym("z", 4),
    )
    max_step_in = ca.SX.sym("max_step", 3)
    finish = ca.Function(
        "ccopt_tick_finish",
        [packed_in, z_in, parameters, max_step_in],
        [_finish(packed_in, z_in, parameters, max_step_in)],
    )
    functions = {}
    for case in CASES:
        name = _case_name(case)
        instance = ca.Function(
            f"{name}_instance", list(symbols.values()), [qp.pack_symbols(_instance(case, symbols))]
        )
        arguments = [ca.MX.sym(argument, *shape) for argument, shape in INPUTS]
        packed = instance(*arguments)
        limit = "slide_max_step" if case[0] in modes.SLIDES else "max_step"  # a slide's is slower
        output = finish(packed, solve(packed), arguments[0], _split(arguments[0], PARAMETERS)[limit])
        functions[case] = ca.Function(
            name, arguments, [output], [argument for argument, _ in INPUTS], ["out"]
        )
    return functions


@functools.cache
def load_tick_functions(
    cache_dir: Path | None = None, compiler: str | None = None
) -> tuple[dict[Case, ca.Function], str]:
    """``(functions by case, backend)``: the cases compiled into one library and loaded (``codegen``),
    or, where that fails, the symbolic functions to evaluate in process (``casadi``, with a warning).
    Once per process and cache."""
    functions = build_tick_functions()
    try:
        library, _ = compile_function(list(functions.values()), cache_dir, compiler, name="ccopt_tick")
    except (OSError, RuntimeError, subprocess.CalledProcessError) as error:
        warnings.warn(
            f"code-generated controller tick unavailable ({error}); evaluating it in process",
            RuntimeWarning,
            stacklevel=2,
        )
        return functions, "casadi"
    return {case: ca.external(f.name(), str(library)) for case, f in functions.items()}, "codegen"


class Tick:
    """One controller's tick functions: its constants written into each thread's buffers once.

    Args:
        parameters: the controller's constants (:data:`PARAMETERS`).
        stiffness: ``K`` in the hand frame (3×3) where it does not depend on the hand angle, else
            None (then given with every call).
        cache_dir, compiler: where the library is cached and what compiles it (:func:`load_tick_functions`).

    Attributes:
        backend: ``codegen`` (generated C) or ``casadi`` (in process, where no compiler works).
    """

    def __init__(
        self,
        parameters: np.ndarray,
        stiffness: np.ndarray | None,
        cache_dir: Path | None = None,
        compiler: str | None = None,
    ) -> None:
        functions, self.backend = load_tick_functions(cache_dir, compiler)
        self._parameters = np.array(parameters, dtype=float)
        self._stiffness = None if stiffness is None else np.array(stiffness, dtype=float)
        self._functions = {case: BufferedFunction(f, self._prepare) for case, f in functions.items()}

    def _prepare(self, binding: Binding) -> None:
        binding.flat_inputs[0][:] = self._parameters
        if self._stiffness is not None:
            binding.inputs[1][...] = self._stiffness

    def __call__(
        self,
        case: Case,
        stiffness: np.ndarray | None,
        scalars: tuple[float, ...],
        wrench: np.ndarray,
        coordinates: np.ndarray,
        targets: np.ndarray,
        cone_rows: np.ndarray,
        cone_bounds: np.ndarray,
        row_valid: np.ndarray,
    ) -> np.ndarray:
        """The output vector (:data:`OUTPUTS`, a fresh array) of ``case`` on this tick's inputs
        (:data:`INPUTS`; ``stiffness`` None where it was given at construction; shapes not checked),
        or None where the generated code failed (DAQP's failure: the outputs were not written)."""
        binding = self._functions[case].buffers()
        flat, shaped = binding.flat_inputs, binding.inputs
        if stiffness is not None:
            shaped[1][...] = stiffness
        flat[2][:] = scalars
        flat[3][:] = wrench
        flat[4][:] = coordinates
        flat[5][:] = targets
        shaped[6][...] = cone_rows
        flat[7][:] = cone_bounds
        flat[8][:] = row_valid
        out = binding.flat_outputs[0]
        out[_SOLVED] = np.nan  # a sentinel: the function writes its whole output once it succeeds
        binding.evaluate()
        return None if math.isnan(out[_SOLVED]) else out.copy()
