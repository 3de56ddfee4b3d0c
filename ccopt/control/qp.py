"""The impedance-target QP of paper eqs. 17–21, in the soft form of docs/architecture.md §5.

Per control tick, find the hand-frame change of the impedance target ``Δx`` (m, m, rad; order
``(n, t, θ)``) and the wrench change ``Δw = K Δx`` that

    minimise    α₀‖Δx‖² + Σᵢ αᵢ (vᵢᵀΔx − δᵢ)²                 (δᵢ = βᵢ Δεᵢ, paper eq. 21)
    subject to  nⱼᵀ(w_meas + γⱼ K Δx) ≤ bⱼ  for every active row j.

The problem has a fixed maximum size (:data:`MAX_ROWS` rows, :data:`MAX_TERMS` tracking terms) and
an active-row mask, so that one compiled solver serves every contact configuration. It is always
solved in the soft form: one slack ``t ≥ 0`` relaxes every active row (``A Δx − t ≤ ub``) at a cost
``ρ t + ½ t²`` with ``ρ`` (:data:`SLACK_WEIGHT`) far above any multiplier. On feasible instances the
answer equals the hard QP's; otherwise the solver returns the least-violating step and reports
``feasible = False`` with the violation ``t`` (N or N·m, the row's units).

Three interchangeable back ends (:func:`make_solver`):

``codegen``
    CasADi ``conic`` with the ``daqp`` plugin, C code generated once, compiled with the system C
    compiler, cached on disk by a hash of the generated code (``$CCOPT_CACHE_DIR``, else
    ``$XDG_CACHE_HOME/ccopt``, else ``~/.cache/ccopt``), loaded with ``casadi.external`` and called
    through a ``FunctionBuffer``. Falls back to ``casadi``, with a warning, where no compiler works.
``casadi``
    The same CasADi function, evaluated in process.
``cvxpy``
    The same matrices in cvxpy, solved by Clarabel (offline studies and cross-checks). The soft
    form is solved lexicographically (minimum violation first, then the cost), its ``ρ → ∞`` limit.
"""

from __future__ import annotations

import subprocess
import warnings
from dataclasses import dataclass, field
from pathlib import Path
from typing import Literal, Protocol

import casadi as ca
import numpy as np
from numpy.typing import ArrayLike

from ccopt import validation
from ccopt.casadi_eval import BufferedFunction, compile_function

MAX_ROWS = 10
"""Maximum number of wrench rows (six cone rows, force limits, spares)."""

MAX_TERMS = 4
"""Maximum number of tracking terms ``αᵢ (vᵢᵀΔx − δᵢ)²`` in the cost."""

SLACK_WEIGHT = 1e3
"""``ρ``: linear cost of the slack; far above any multiplier of the hard problem.

The founding design suggested 1e8, but with steps in metres and rows in newtons the hard problem's
multipliers are tiny (``|∇cost| ≲ 1`` over row gradients ``γ K n ≳ 60``, so ``λ ≲ 0.02`` for tracking
weights up to ~10), and 1e8 against a unit Hessian costs DAQP's dual active set up to 30 % of the violation on
infeasible ticks through cancellation. 1e3 keeps a margin of ~5·10⁴ over the multipliers and solves
infeasible ticks to ~1e-6 relative (measured on 600 instances against an LP)."""

INFEASIBLE_SLACK = 1e-7
"""Slack (row units) above which an instance is reported infeasible."""

Backend = Literal["codegen", "casadi", "cvxpy"]
BACKENDS: tuple[Backend, ...] = ("codegen", "casadi", "cvxpy")


# --- the instance and its packing -----------------------------------------------------------------

_LAYOUT = (
    ("stiffness", (3, 3)),
    ("wrench", (3,)),
    ("rows", (MAX_ROWS, 3)),
    ("bounds", (MAX_ROWS,)),
    ("gains", (MAX_ROWS,)),
    ("active", (MAX_ROWS,)),
    ("regularization", ()),
    ("directions", (MAX_TERMS, 3)),
    ("weights", (MAX_TERMS,)),
    ("targets", (MAX_TERMS,)),
)
_SLICES: dict[str, slice] = {}
_offset = 0
for _name, _shape in _LAYOUT:
    _size = int(np.prod(_shape))
    _SLICES[_name] = slice(_offset, _offset + _size)
    _offset += _size
N_PARAMETERS = _offset
"""Length of the packed parameter vector of the compiled solver."""
_FIELDS = tuple(name for name, _ in _LAYOUT)


@dataclass(frozen=True)
class QPInstance:
    """One tick's QP, in the hand frame ``(n, t, θ)``.

    Attributes:
        stiffness: ``K`` (3×3), N/m and N·m/rad: ``Δw = K Δx``.
        wrench: measured hand wrench ``w_meas = (f_n, f_t, τ)`` (N, N, N·m).
        rows: ``nⱼ`` (m×3), ``m ≤ MAX_ROWS``; ``nⱼᵀ w ≤ bⱼ``.
        bounds: ``bⱼ`` (m,).
        gains: ``γⱼ`` (m,), scaling of the predicted wrench change per row.
        active: which rows are enforced (m,) bool.
        regularization: ``α₀ > 0``.
        directions: ``vᵢ`` (k×3), ``k ≤ MAX_TERMS``, hand-frame target directions.
        weights: ``αᵢ ≥ 0`` (k,).
        targets: ``δᵢ = βᵢ Δεᵢ`` (k,), in the units of ``θ_o``/``s_h``/``s_g`` (rad or m).
    """

    stiffness: np.ndarray
    wrench: np.ndarray
    rows: np.ndarray
    bounds: np.ndarray
    gains: np.ndarray
    active: np.ndarray
    regularization: float
    directions: np.ndarray
    weights: np.ndarray
    targets: np.ndarray
    packed: np.ndarray = field(init=False, repr=False, compare=False)

    def __post_init__(self) -> None:
        n_rows = _check_matrix("rows", self.rows, MAX_ROWS, 3)
        n_terms = _check_matrix("directions", self.directions, MAX_TERMS, 3)
        for name, length in (("bounds", n_rows), ("gains", n_rows), ("active", n_rows)):
            _check_vector(name, getattr(self, name), length)
        for name in ("weights", "targets"):
            _check_vector(name, getattr(self, name), n_terms)
        _check_vector("wrench", self.wrench, 3)
        if np.shape(self.stiffness) != (3, 3) or not np.all(np.isfinite(self.stiffness)):
            raise ValueError(f"stiffness must be a finite 3×3 matrix, got {self.stiffness!r}")
        if not (np.isfinite(self.regularization) and self.regularization > 0.0):
            raise ValueError(f"regularization must be positive, got {self.regularization!r}")
        if np.any(np.asarray(self.weights) < 0.0):
            raise ValueError(f"weights must be non-negative, got {self.weights!r}")
        object.__setattr__(self, "packed", _pack(self, n_rows, n_terms))

    @classmethod
    def unchecked(
        cls,
        stiffness: np.ndarray,
        wrench: np.ndarray,
        rows: np.ndarray,
        bounds: np.ndarray,
        gains: np.ndarray,
        active: np.ndarray,
        regularization: float,
        directions: np.ndarray,
        weights: np.ndarray,
        targets: np.ndarray,
    ) -> QPInstance:
        """The instance of these fields (NumPy arrays of the shapes above) without the constructor's
        checks: for a producer whose instances are well formed by construction, the controller once a
        tick (its inputs were checked where they entered). Anything else should use the constructor."""
        instance = object.__new__(cls)
        fields = (stiffness, wrench, rows, bounds, gains, active, regularization)
        for name, value in zip(_FIELDS, (*fields, directions, weights, targets), strict=True):
            object.__setattr__(instance, name, value)
        object.__setattr__(instance, "packed", _pack(instance, len(rows), len(directions)))
        return instance

    @classmethod
    def from_packed(cls, packed: np.ndarray, n_rows: int, n_terms: int) -> QPInstance:
        """The instance of ``n_rows`` rows and ``n_terms`` terms whose packed vector is ``packed``
        (:data:`N_PARAMETERS`,), unchecked like :meth:`unchecked`: the inverse of the packing."""
        fields = {name: np.array(packed[_SLICES[name]]) for name, _ in _LAYOUT}
        rows = fields["rows"].reshape(3, MAX_ROWS).T[:n_rows]  # column-major slots, transposed back
        directions = fields["directions"].reshape(3, MAX_TERMS).T[:n_terms]
        return cls.unchecked(
            stiffness=fields["stiffness"].reshape(3, 3).T,
            wrench=fields["wrench"],
            rows=np.ascontiguousarray(rows),
            bounds=fields["bounds"][:n_rows],
            gains=fields["gains"][:n_rows],
            active=fields["active"][:n_rows] != 0.0,
            regularization=float(fields["regularization"][0]),
            directions=np.ascontiguousarray(directions),
            weights=fields["weights"][:n_terms],
            targets=fields["targets"][:n_terms],
        )


def _check_matrix(name: str, value: ArrayLike, max_rows: int, cols: int) -> int:
    shape = np.shape(value)
    if len(shape) != 2 or shape[1] != cols or shape[0] > max_rows:
        raise ValueError(f"{name} must have shape (m ≤ {max_rows}, {cols}), got {shape}")
    if not np.all(np.isfinite(value)):
        raise ValueError(f"{name} must be finite, got {value!r}")
    return shape[0]


def _check_vector(name: str, value: ArrayLike, length: int) -> None:
    if np.shape(value) != (length,):
        raise ValueError(f"{name} must have shape ({length},), got {np.shape(value)}")
    if not np.all(np.isfinite(np.asarray(value, dtype=float))):
        raise ValueError(f"{name} must be finite, got {value!r}")


def _pack(instance: QPInstance, n_rows: int, n_terms: int) -> np.ndarray:
    """The packed parameter vector: each field in its slot of :data:`_LAYOUT`, column-major like
    CasADi, a ``(count, ...)`` block in the first ``count`` rows of its ``(MAX, ...)`` slot (zeros
    after)."""
    packed = np.zeros(N_PARAMETERS)
    # a (rows, 3) slot column-major is a (3, rows) block row-major: the transposed field fills it
    packed[_STIFFNESS].reshape(3, 3)[...] = np.asarray(instance.stiffness).T
    packed[_WRENCH] = instance.wrench
    packed[_REGULARIZATION] = instance.regularization
    packed[_ROWS].reshape(3, MAX_ROWS)[:, :n_rows] = np.asarray(instance.rows).T
    packed[_DIRECTIONS].reshape(3, MAX_TERMS)[:, :n_terms] = np.asarray(instance.directions).T
    start = _SLICES["bounds"].start
    packed[start : start + n_rows] = instance.bounds
    start = _SLICES["gains"].start
    packed[start : start + n_rows] = instance.gains
    start = _SLICES["active"].start
    packed[start : start + n_rows] = instance.active
    start = _SLICES["weights"].start
    packed[start : start + n_terms] = instance.weights
    start = _SLICES["targets"].start
    packed[start : start + n_terms] = instance.targets
    return packed


_STIFFNESS, _WRENCH, _ROWS, _DIRECTIONS, _REGULARIZATION = (
    _SLICES[name] for name in ("stiffness", "wrench", "rows", "directions", "regularization")
)


@dataclass(frozen=True)
class QPSolution:
    """The step and its diagnostics.

    Attributes:
        step: ``Δx_tar`` in the hand frame ``(Δn, Δt, Δθ)`` (m, m, rad).
        wrench_change: ``Δw = K Δx_tar`` (N, N, N·m).
        slack: violation ``t`` of the active rows that the step could not avoid (row units).
        feasible: ``slack ≤ INFEASIBLE_SLACK``.
        backend: which back end solved it.
    """

    step: np.ndarray
    wrench_change: np.ndarray
    slack: float
    feasible: bool
    backend: str


class QPSolver(Protocol):
    backend: str

    def solve(self, instance: QPInstance) -> QPSolution: ...


# --- the formulation, written once ---------------------------------------------------------------


def unpack_symbols(parameters: ca.SX) -> dict[str, ca.SX]:
    """The fields of a symbolic packed parameter vector, each shaped as its slot of :data:`_LAYOUT`
    (the inverse of :func:`pack_symbols`, padding included)."""
    out = {}
    for name, shape in _LAYOUT:
        flat = parameters[_SLICES[name]]
        out[name] = ca.reshape(flat, *shape) if len(shape) == 2 else flat
    return out


def pack_symbols(fields: dict[str, ca.SX]) -> ca.SX:
    """The packed parameter vector (:data:`N_PARAMETERS`,) of symbolic instance fields, laid out as
    :func:`_pack` lays out a :class:`QPInstance`'s: ``rows``, ``bounds``, ``gains``, ``active`` of
    ``m ≤ MAX_ROWS`` rows and ``directions``, ``weights``, ``targets`` of ``k ≤ MAX_TERMS`` terms
    (column vectors and matrices), padded with zeros to their slots."""
    slots = []
    for name, shape in _LAYOUT:
        value = ca.SX(fields[name])
        if len(shape) == 2 and value.shape != shape:  # a (m, 3) block in the first rows of its slot
            value = ca.vertcat(value, ca.SX.zeros(shape[0] - value.shape[0], shape[1]))
        elif len(shape) == 1 and value.shape[0] != shape[0]:
            value = ca.vertcat(value, ca.SX.zeros(shape[0] - value.shape[0]))
        slots.append(ca.vec(value))
    return ca.vertcat(*slots)


def build_qp_matrices() -> ca.Function:
    """``p → (H (4×4), g (4), A (MAX_ROWS×4), ub (MAX_ROWS))`` of the soft QP in ``z = (Δx, t)``.

    Cost ``½ zᵀHz + gᵀz`` (the paper's cost, expanded, plus ``ρ t + ½ t²``), rows ``A z ≤ ub``,
    ``t ≥ 0``. Inactive rows become ``0·Δx − t ≤ 1``: always slack, so interior-point solvers keep
    a strict interior (``0 ≤ 0`` rows would break Slater's condition).
    """
    parameters = ca.SX.sym("p", N_PARAMETERS)
    q = unpack_symbols(parameters)
    hessian = 2.0 * q["regularization"] * ca.SX.eye(3)
    gradient = ca.SX.zeros(3)
    for i in range(MAX_TERMS):
        direction = q["directions"][i, :].T
        hessian += 2.0 * q["weights"][i] * (direction @ direction.T)
        gradient -= 2.0 * q["weights"][i] * q["targets"][i] * direction
    mask = q["active"]
    rows = ca.diag(mask * q["gains"]) @ q["rows"] @ q["stiffness"]
    upper = mask * (q["bounds"] - q["rows"] @ q["wrench"]) + (1.0 - mask)
    return ca.Function(
        "ccopt_qp_matrices",
        [parameters],
        [
            ca.diagcat(hessian, 1.0),
            ca.vertcat(gradient, SLACK_WEIGHT),
            ca.horzcat(rows, -ca.SX.ones(MAX_ROWS)),
            upper,
        ],
        ["p"],
        ["H", "g", "A", "ub"],
    )


def build_qp_function(plugin: str = "daqp") -> ca.Function:
    """``p → z = (Δx, t)``: the soft QP solved by CasADi's ``conic`` ``plugin`` (symbolic pipeline)."""
    matrices = build_qp_matrices()
    parameters = ca.MX.sym("p", N_PARAMETERS)
    hessian, gradient, rows, upper = matrices(parameters)
    conic = ca.conic(
        "ccopt_qp_conic",
        plugin,
        {"h": ca.Sparsity.dense(4, 4), "a": ca.Sparsity.dense(MAX_ROWS, 4)},
        {"error_on_fail": False},
    )
    lower_bound = ca.DM([-ca.inf, -ca.inf, -ca.inf, 0.0])
    solution = conic(
        h=ca.densify(hessian),
        g=gradient,
        a=ca.densify(rows),
        lba=-ca.inf * ca.DM.ones(MAX_ROWS),
        uba=upper,
        lbx=lower_bound,
        ubx=ca.inf * ca.DM.ones(4),
    )
    return ca.Function("ccopt_qp", [parameters], [solution["x"]], ["p"], ["z"])


# --- back ends -------------------------------------------------------------------------------------


def _solution(z: np.ndarray, instance: QPInstance, backend: str) -> QPSolution:
    step = z[:3].copy()  # z may be a solver's reusable output buffer
    slack = max(float(z[3]), 0.0)
    return validation.trusted(  # every field, each well formed by construction
        QPSolution,
        {
            "step": step,
            "wrench_change": np.asarray(instance.stiffness) @ step,
            "slack": slack,
            "feasible": slack <= INFEASIBLE_SLACK,
            "backend": backend,
        },
    )


class CasadiQPSolver:
    """The CasADi/DAQP function evaluated in process (the ``casadi`` back end)."""

    backend = "casadi"

    def __init__(self, function: ca.Function | None = None) -> None:
        self._function = BufferedFunction(function if function is not None else build_qp_function())
        self._z = np.zeros(4)

    def solve(self, instance: QPInstance) -> QPSolution:
        z = self._function.call_flat(instance.packed, self._z)
        if self._function.failed():  # DAQP failed in generated code: no step (not the last one's)
            z = np.full(4, np.nan)
        return _solution(z, instance, self.backend)


class CodegenQPSolver(CasadiQPSolver):
    """The same function as generated C, compiled once and cached (the ``codegen`` back end).

    Attributes:
        library: path of the compiled shared library.
        cache_hit: True if the library was loaded from the cache instead of compiled.
    """

    backend = "codegen"

    def __init__(self, cache_dir: Path | None = None, compiler: str | None = None) -> None:
        function = build_qp_function()
        self.library, self.cache_hit = compile_function(function, cache_dir, compiler)
        super().__init__(ca.external(function.name(), str(self.library)))


class CvxpyQPSolver:
    """The same QP in cvxpy, solved by Clarabel (the ``cvxpy`` back end).

    The matrices come from :func:`build_qp_matrices` (the one formulation); the problem is built
    per call with a native quadratic objective (a parametrised ``sum_squares`` goes to Clarabel as
    a second-order cone and was seen to stall), in scaled variables ``y = Δx / STEP_SCALE`` with a
    unit-size Hessian, because Clarabel's tolerances are absolute and a tick's cost is tiny in SI
    units. The soft form is solved lexicographically: the hard QP first and, if it is infeasible,
    the least violation ``t*`` by an LP and then the cost under rows relaxed by ``t*``.
    """

    backend = "cvxpy"
    STEP_SCALE = 1e-3

    def __init__(self) -> None:
        import cvxpy as cp

        self._cp = cp
        self._matrices = BufferedFunction(build_qp_matrices())

    def _solve(self, problem: object) -> str:
        """Solve with tight, then looser tolerances until Clarabel decides; failures become a status."""
        status = "solver_error"
        for tolerance in (1e-10, 1e-8):
            try:
                problem.solve(
                    solver="CLARABEL", tol_gap_abs=tolerance, tol_gap_rel=tolerance, tol_feas=tolerance
                )
            except self._cp.error.SolverError:
                continue
            status = problem.status
            if status in ("optimal", "infeasible"):
                break
        return status

    def solve(self, instance: QPInstance) -> QPSolution:
        cp = self._cp
        hessian, gradient, rows, upper = self._matrices(instance.packed)
        scaled_hessian = hessian[:3, :3] * self.STEP_SCALE**2
        cost_scale = 1.0 / np.max(np.abs(scaled_hessian))
        rows = rows[:, :3] * self.STEP_SCALE
        step, slack = cp.Variable(3), cp.Variable(nonneg=True)
        cost = 0.5 * cp.quad_form(step, cp.psd_wrap(scaled_hessian * cost_scale))
        cost = cost + (gradient[:3] * self.STEP_SCALE * cost_scale) @ step
        least_violation = 0.0
        if self._solve(cp.Problem(cp.Minimize(cost), [rows @ step <= upper])) == "infeasible":
            self._solve(cp.Problem(cp.Minimize(slack), [rows @ step - slack <= upper]))
            least_violation = max(float(slack.value), 0.0)
            relaxed = upper + least_violation * (1.0 + 1e-9) + 1e-12
            self._solve(cp.Problem(cp.Minimize(cost), [rows @ step <= relaxed]))
        scaled_step = step.value if step.value is not None else np.zeros(3)
        return _solution(np.append(scaled_step * self.STEP_SCALE, least_violation), instance, self.backend)


def make_solver(backend: Backend = "codegen", **options: object) -> QPSolver:
    """The QP solver of ``backend`` (``codegen``, ``casadi`` or ``cvxpy``).

    ``codegen`` accepts ``cache_dir`` and ``compiler``; where compilation is impossible it warns
    and returns the ``casadi`` back end.
    """
    if backend == "codegen":
        try:
            return CodegenQPSolver(**options)
        except (OSError, RuntimeError, subprocess.CalledProcessError) as error:
            warnings.warn(
                f"code-generated QP unavailable ({error}); using the in-process CasADi solver",
                RuntimeWarning,
                stacklevel=2,
            )
            return CasadiQPSolver()
    if backend == "casadi":
        return CasadiQPSolver()
    if backend == "cvxpy":
        return CvxpyQPSolver()
    raise ValueError(f"unknown QP backend {backend!r}; expected one of: {', '.join(BACKENDS)}")
