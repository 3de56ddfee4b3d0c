"""The QP's constraints and feasible region for one estimate (paper Fig. 4b–c).

    ccopt study qp_region [--theta 10] [--s-hand 10] [--wrench 12,1.5,0.1] [--motion pivot] ...

The estimate is exact here: the cone is the true one of the given object
(:func:`ccopt.contact.model_friction_cone`), the kinematics are known, and the controller
(:class:`ccopt.control.controller.Controller`, default gains) builds the tick's QP for the commanded
motion and change. Two figures, in the hand frame:

``constraints.png`` (Fig. 4b)
    Top, the ``(f_t, f_n)`` plane: the hand friction cone (dashed blue), the ground friction cone
    rotated into the hand frame (dashed purple) and the normal-force limits (dotted grey), the region
    they leave shaded. Bottom, the ``(τ, f_n)`` plane: the hand torque cone (solid red). Rows the motion
    removes are drawn faded. The measured wrench is a black dot, the wrench the QP's step predicts
    (``w + K Δx``) an orange star. The QP's own rows carry the controller's margins; these are the
    cone's boundaries.
``region.png`` (Fig. 4c)
    The polytope ``{Δx : A Δx ≤ ub}`` of the QP's active rows (:func:`ccopt.control.qp.build_qp_matrices`)
    in ``(Δn, Δt, Δθ)`` (mm, mm, deg) in grey, the target direction of the commanded coordinate
    (``v_θ``, ``v_h`` or ``v_g``) in black, the set minimising that term — the plane ``vᵀΔx = δ``
    (``δ = β Δε``) cut by the region — in orange, and the QP's solution (red).
"""

from __future__ import annotations

import argparse
import sys
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path

import numpy as np
from scipy.optimize import linprog
from scipy.spatial import ConvexHull, HalfspaceIntersection

from ccopt import contact, modes
from ccopt.cliutil import fail, print_table, write_json
from ccopt.contact import Row
from ccopt.control.controller import Command, ControlInput, Controller, ControlOutput
from ccopt.control.qp import build_qp_matrices, make_solver
from ccopt.modes import Motion
from studies import runner

PLOT_SCALE = np.array([1e3, 1e3, np.rad2deg(1.0)])
"""``Δx`` (m, m, rad) to plotting units (mm, mm, deg)."""

QP_MATRICES = build_qp_matrices()
"""The controller's QP as matrices (one formulation): ``p → (H, g, A, ub)``."""

BOX = np.array([50.0, 50.0, 30.0])
"""Half-widths (mm, mm, deg) of a box that bounds the drawn region should the QP's be unbounded."""

_DEFAULT_CHANGE = {Motion.HOLD: 0.0, Motion.PIVOT: 2.0} | {
    m: 1.0 for m in Motion if m not in (Motion.HOLD, Motion.PIVOT)
}
"""Default commanded changes at the command line (deg), else 1 mm: one the tick can achieve, so that
the minimising plane cuts the region as in the paper's figure (7.2°, the paper's whole increment,
asks for more than one tick allows and the plane misses the region)."""


def _commanded(motion: Motion) -> int:
    """The column of the admissible-motion vectors ``(v_θ, v_h, v_g)`` a motion's cost drives (a hold
    draws the pivot's)."""
    driven = modes.driven_coordinate(motion)
    return modes.THETA_O if driven is None else driven


@dataclass(frozen=True)
class RegionState:
    """The estimate and the command. SI units; the wrench in the hand frame ``(f_n, f_t, τ)``.

    Attributes:
        theta_o: object (and hand) orientation, rad.
        s_h: hand position along the face, m.
        d: ground contact to hand face, m.
        mu_hand, mu_ground: friction coefficients.
        mass: object mass, kg.
        l_h: hand half-length, m.
        wrench: measured hand wrench, N, N, N·m.
        motion: the commanded motion.
        change: commanded change of the motion's coordinate (rad for ``θ_o``, m for ``s_h``, ``s_g``).
    """

    theta_o: float = np.deg2rad(10.0)
    s_h: float = 0.01
    d: float = 0.116
    mu_hand: float = 0.5
    mu_ground: float = 0.8
    mass: float = 0.195
    l_h: float = 0.05
    wrench: tuple[float, float, float] = (12.0, 1.5, 0.1)
    motion: Motion = Motion.PIVOT
    change: float = np.deg2rad(2.0)


@dataclass(frozen=True)
class Region:
    """The QP of one tick, its solution, and the geometry to draw (``Δx`` in plotting units).

    Attributes:
        output: the controller's output (instance, solution).
        scale: the QP variable's units in plotting units (the solution ``y`` plots as ``y · scale``).
        rows: ``A`` of the active rows (k×3), in plotting units.
        upper: their ``ub`` (k,).
        vertices: vertices of the feasible polytope (plotting units), ``None`` if empty.
        direction: the commanded coordinate's target direction ``v`` (hand frame, SI).
        target: ``δ`` of that term (rad or m).
        plane: vertices of the plane ``vᵀΔx = δ`` inside the region (plotting units), ``None`` if
            the plane misses it.
            clipped: whether the drawing box cuts the region (the QP's region is unbounded).
        force_limits: the controller's ``(f_min, f_max)``, N.
    """

    output: ControlOutput
    scale: np.ndarray
    rows: np.ndarray
    upper: np.ndarray
    vertices: np.ndarray | None
    direction: np.ndarray
    target: float
    plane: np.ndarray | None
    clipped: bool
    force_limits: tuple[float, float]


def control_input(state: RegionState) -> ControlInput:
    """An exact estimate of ``state``: the true cone (every row valid), known kinematics, a flush
    hand (``θ_h = θ_o``), ``s_g = 0``."""
    rows, bounds = contact.model_friction_cone(
        state.theta_o, state.mu_hand, state.mu_ground, state.l_h, state.mass
    )
    exact = {"cone_rows": rows, "cone_bounds": bounds, "row_valid": np.ones(contact.N_CONE_ROWS, dtype=bool)}
    return ControlInput(
        wrench=np.asarray(state.wrench, dtype=float),
        **exact,
        mu_h=state.mu_hand,
        l_h=state.l_h,
        hand_angle=state.theta_o,
        s_h=state.s_h,
        d=state.d,
        kinematics_valid=True,
        coordinates=np.array([state.theta_o, state.s_h, 0.0]),
    )


def command(state: RegionState) -> Command:
    """The commanded targets: the motion's coordinate moved by ``change``, the others held."""
    targets = np.array([state.theta_o, state.s_h, 0.0])
    targets[_commanded(state.motion)] += state.change
    return Command(motion=state.motion, targets=targets)


def halfspace_vertices(rows: np.ndarray, upper: np.ndarray) -> np.ndarray | None:
    """Vertices of the bounded polytope ``{x : rows x ≤ upper}`` (any dimension); ``None`` if it has
    no interior (found by the Chebyshev centre, an LP)."""
    norms = np.linalg.norm(rows, axis=1)
    dimension = rows.shape[1]
    cost = np.zeros(dimension + 1)
    cost[-1] = -1.0
    centre = linprog(
        cost,
        A_ub=np.column_stack([rows, norms]),
        b_ub=upper,
        bounds=[(None, None)] * dimension + [(0.0, None)],
        method="highs",
    )
    if centre.status != 0 or centre.x[-1] <= 1e-9:
        return None
    return HalfspaceIntersection(np.column_stack([rows, -upper]), centre.x[:dimension]).intersections


def _box_rows(half_widths: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """``|x_i| ≤ half_widths_i`` as rows ``A x ≤ b``."""
    eye = np.eye(half_widths.size)
    return np.vstack([eye, -eye]), np.concatenate([half_widths, half_widths])


def plane_section(
    rows: np.ndarray, upper: np.ndarray, normal: np.ndarray, offset: float
) -> np.ndarray | None:
    """Vertices (3-D, in polygon order) of ``{x : rows x ≤ upper, normalᵀx = offset}``; ``None`` if
    the plane misses the polytope's interior."""
    unit = normal / np.linalg.norm(normal)
    origin = unit * offset / np.linalg.norm(normal)
    basis = np.linalg.svd(unit[None, :])[2][1:].T  # 3×2, orthonormal, ⊥ normal
    section = halfspace_vertices(rows @ basis, upper - rows @ origin)
    if section is None:
        return None
    return origin + section[ConvexHull(section).vertices] @ basis.T


def polytope_faces(rows: np.ndarray, vertices: np.ndarray) -> list[np.ndarray]:
    """The faces of a 3-D polytope as vertex loops: for each bounding plane (a row of ``rows``,
    normalised, tight on three or more vertices), its vertices in polygon order."""
    faces = []
    normals = rows / np.linalg.norm(rows, axis=1, keepdims=True)
    support = np.max(vertices @ normals.T, axis=0)
    tolerance = 1e-7 * max(1.0, float(np.max(np.abs(vertices))))
    for normal, level in zip(normals, support, strict=True):
        on_face = vertices[np.abs(vertices @ normal - level) <= tolerance]
        if len(on_face) < 3:
            continue
        basis = np.linalg.svd(normal[None, :])[2][1:].T
        flat = (on_face - on_face.mean(axis=0)) @ basis
        faces.append(on_face[np.argsort(np.arctan2(flat[:, 1], flat[:, 0]))])
    return faces


def compute_region(state: RegionState, controller: Controller) -> Region:
    """The tick's QP for ``state`` and the geometry of Fig. 4c."""
    output = controller.update(control_input(state), command(state))
    instance = output.instance
    _, _, rows, upper = (np.asarray(m) for m in QP_MATRICES(instance.packed))
    upper = upper.ravel()
    used = np.linalg.norm(rows[:, :3], axis=1) > 0.0  # inactive rows are 0·Δx − t ≤ 1
    scale = PLOT_SCALE * controller.step_units  # the QP's variable to the plot's mm, mm, deg
    rows_plot, upper_plot = rows[used, :3] / scale, upper[used]
    box_rows, box_upper = _box_rows(BOX)
    all_rows, all_upper = np.vstack([rows_plot, box_rows]), np.concatenate([upper_plot, box_upper])
    vertices = halfspace_vertices(all_rows, all_upper)
    clipped = vertices is not None and bool(np.any(np.isclose(np.abs(vertices), BOX, rtol=1e-9)))
    vectors = contact.admissible_motions(state.theta_o, state.s_h, state.d)
    direction = vectors[:, _commanded(state.motion)]
    aligned = np.abs(instance.directions @ (direction / controller.step_units))
    term = int(np.argmax(aligned / np.linalg.norm(instance.directions, axis=1)))  # the motion's term
    target = float(instance.targets[term])
    plane = plane_section(all_rows, all_upper, instance.directions[term] / scale, target)
    return Region(
        output,
        scale,
        rows_plot,
        upper_plot,
        vertices,
        direction,
        target,
        plane,
        clipped,
        controller.hand.force_limits,
    )


# --- figures --------------------------------------------------------------------------------------


_PLANES = (  # (wrench components drawn as (x, y), cone rows in that plane as (rows, colour, style, label))
    (
        (1, 0),
        (
            ((Row.HAND_SLIDE_POS, Row.HAND_SLIDE_NEG), "tab:blue", "--", "hand friction"),
            ((Row.GROUND_SLIDE_POS, Row.GROUND_SLIDE_NEG), "tab:purple", "--", "ground friction"),
        ),
    ),
    ((2, 0), (((Row.HAND_PIVOT_POS, Row.HAND_PIVOT_NEG), "tab:red", "-", "hand torque"),)),
)
"""Fig. 4b's two planes: ``(f_t, f_n)`` and ``(τ, f_n)``; each row drawn has a zero third component."""


def _boundary(ax, normal: np.ndarray, bound: float, x_span: np.ndarray, **style) -> None:
    """The line ``normal · (x, y) = bound`` across ``x_span`` (vertical if it does not involve ``y``)."""
    a, b = normal
    if abs(b) > 1e-12:
        ax.plot(x_span, (bound - a * x_span) / b, **style)
    else:
        ax.axvline(bound / a, **style)


def constraints_figure(path: Path, state: RegionState, region: Region) -> None:
    """Fig. 4b: the cone rows in the ``(f_t, f_n)`` and ``(τ, f_n)`` planes with the wrenches."""
    from matplotlib.figure import Figure

    cone, bounds = contact.model_friction_cone(
        state.theta_o, state.mu_hand, state.mu_ground, state.l_h, state.mass
    )
    kept = modes.kept_rows(state.motion)
    f_min, f_max = region.force_limits
    wrench = np.asarray(state.wrench)
    predicted = wrench + region.output.solution.wrench_change
    figure = Figure(figsize=(6, 8), layout="constrained")
    x_limits = (1.2 * state.mu_hand * f_max + 5.0, 1.5 * state.l_h * f_max)
    for ax, ((i, j), groups), x_limit in zip(figure.subplots(2, 1), _PLANES, x_limits, strict=True):
        x_span = np.array([-2.0, 2.0]) * x_limit
        drawn = []
        for rows, colour, style, label in groups:
            for row in rows:
                alpha = 1.0 if kept[row] else 0.25  # removed by the motion: faded
                _boundary(ax, cone[row, [i, j]], bounds[row], x_span, color=colour, ls=style, alpha=alpha)
            ax.plot([], [], color=colour, linestyle=style, label=label)
            drawn += [row for row in rows if kept[row]]
        polygon = halfspace_vertices(
            np.vstack([cone[drawn][:, [i, j]], [[0.0, 1.0], [0.0, -1.0]]]),
            np.concatenate([bounds[drawn], [f_max, -f_min]]),
        )
        if polygon is not None:
            ax.fill(*polygon[ConvexHull(polygon).vertices].T, color="0.88", zorder=0, label="allowed")
        for limit in (f_min, f_max):
            ax.axhline(limit, color="0.5", linestyle=":")
        ax.plot(wrench[i], wrench[j], "ko", label="measured")
        ax.plot(predicted[i], predicted[j], "*", color="tab:orange", markersize=12, label="predicted")
        ax.set_xlim(-x_limit, x_limit)
        ax.set_ylim(0.0, 1.2 * f_max)
        ax.set_xlabel(("f_t (N)", "τ (N·m)")[i - 1])
        ax.set_ylabel("f_n (N)")
        ax.legend(loc="lower right", fontsize=8)
    figure.suptitle(f"Fig. 4b: {state.motion.value} at θ_o = {np.rad2deg(state.theta_o):.1f}°, hand frame")
    figure.savefig(path, dpi=120)


def region_figure(path: Path, state: RegionState, region: Region) -> None:
    """Fig. 4c: the feasible polytope, the target direction, the minimising plane and the solution."""
    from matplotlib.figure import Figure
    from mpl_toolkits.mplot3d.art3d import Poly3DCollection

    figure = Figure(figsize=(7, 6), layout="constrained")
    ax = figure.add_subplot(projection="3d")
    solution = region.output.solution.step * region.scale
    extent = 1.0
    if region.vertices is not None:
        faces = polytope_faces(np.vstack([region.rows, _box_rows(BOX)[0]]), region.vertices)
        ax.add_collection3d(
            Poly3DCollection(faces, facecolor="0.6", alpha=0.3, edgecolor="0.3", linewidth=0.6)
        )
        extent = float(np.max(np.abs(region.vertices)))
        ax.auto_scale_xyz(*region.vertices.T)
    if region.plane is not None:
        ax.add_collection3d(Poly3DCollection([region.plane], facecolor="tab:orange", alpha=0.8))
    arrow = region.direction * PLOT_SCALE
    arrow = arrow / np.linalg.norm(arrow) * 0.8 * extent
    ax.quiver(0, 0, 0, *arrow, color="k", linewidth=2)
    ax.text(*arrow, "v", color="k")
    ax.scatter(*solution, color="tab:red", s=40, depthshade=False, label="QP solution")
    ax.scatter(0, 0, 0, color="k", s=10, label="Δx = 0")
    ax.set_xlabel("Δn (mm)")
    ax.set_ylabel("Δt (mm)")
    ax.set_zlabel("Δθ (deg)")
    notes = []
    if region.vertices is None:
        notes.append("feasible region empty")
    if region.plane is None:
        notes.append("minimising plane misses the region")
    if region.clipped:
        notes.append("region cut by the drawing box")
    ax.set_title(
        f"Fig. 4c: {state.motion.value}, the QP's feasible region"
        + (f" ({'; '.join(notes)})" if notes else "")
    )
    ax.legend(loc="upper left", fontsize=8)
    figure.savefig(path, dpi=120)


# --- command line ---------------------------------------------------------------------------------


def wrench_triple(value: str) -> tuple[float, float, float]:
    """argparse type: ``f_n,f_t,τ`` (N, N, N·m), finite."""
    try:
        numbers = tuple(float(v) for v in value.split(","))
    except ValueError:
        numbers = ()
    if len(numbers) != 3 or not np.all(np.isfinite(numbers)):
        raise argparse.ArgumentTypeError(f"{value!r} is not three numbers f_n,f_t,τ")
    return numbers


def finite(value: str) -> float:
    """argparse type: a finite float."""
    try:
        number = float(value)
    except ValueError:
        number = float("nan")
    if not np.isfinite(number):
        raise argparse.ArgumentTypeError(f"{value!r} is not a finite number")
    return number


def positive(value: str) -> float:
    """argparse type: a finite float > 0."""
    number = finite(value)
    if number <= 0.0:
        raise argparse.ArgumentTypeError(f"{value!r} must be positive")
    return number


def make_parser() -> argparse.ArgumentParser:
    parser = runner.study_parser(
        "qp_region", __doc__.split("\n")[0], "no effect: the study is one QP solve (about 2 s)", trials=False
    )
    add = parser.add_argument
    add("--theta", type=finite, default=10.0, help="θ_o, deg")
    add("--s-hand", type=finite, default=10.0, help="s_h, mm")
    add("--d", type=positive, default=116.0, help="ground contact to hand face, mm")
    add("--mu-hand", type=positive, default=0.5, help="μ_h")
    add("--mu-ground", type=positive, default=0.8, help="μ_g")
    add("--mass", type=positive, default=0.195, help="object mass, kg")
    add("--l-hand", type=positive, default=50.0, help="hand half-length l_h, mm")
    add("--wrench", type=wrench_triple, default=(12.0, 1.5, 0.1), help="measured f_n,f_t,τ (N, N, N·m)")
    add("--motion", choices=[m.value for m in Motion], default=Motion.PIVOT.value, help="commanded motion")
    add(
        "--change",
        type=finite,
        help="commanded change of θ_o (deg; pivot default 2, hold 0: a drift to undo) or s_h, s_g (mm; 1)",
    )
    return parser


def state_from_args(args: argparse.Namespace) -> RegionState:
    motion = Motion(args.motion)
    angular = _commanded(motion) == 0
    change = args.change if args.change is not None else _DEFAULT_CHANGE[motion]
    return RegionState(
        theta_o=float(np.deg2rad(args.theta)),
        s_h=args.s_hand * 1e-3,
        d=args.d * 1e-3,
        mu_hand=args.mu_hand,
        mu_ground=args.mu_ground,
        mass=args.mass,
        l_h=args.l_hand * 1e-3,
        wrench=args.wrench,
        motion=motion,
        change=float(np.deg2rad(change)) if angular else change * 1e-3,
    )


RESULT_UNITS = (
    "SI: state (rad, m, kg, N), step and region/plane vertices (Δn, Δt, Δθ) in m, m, rad in the hand "
    "frame; slack and target_qp_units in the QP's scaled units (mm, deg, N)"
)
"""What ``results.json`` says of its units."""


def main(argv: Sequence[str] | None = None) -> int:
    parser = make_parser()
    args = parser.parse_args(argv)
    state = state_from_args(args)
    try:
        args.out.mkdir(parents=True, exist_ok=True)
    except OSError as error:
        fail(parser.prog, runner.error_line(error))
    region = compute_region(state, Controller(solver=make_solver("codegen")))
    constraints_figure(args.out / "constraints.png", state, region)
    region_figure(args.out / "region.png", state, region)
    solution = region.output.solution
    summary = {
        "units": RESULT_UNITS,
        "state": runner.spec_dict(state),
        "step": solution.step * region.scale / PLOT_SCALE,
        "slack": solution.slack,
        "feasible": solution.feasible,
        "region_vertices": None if region.vertices is None else region.vertices / PLOT_SCALE,
        "region_empty": region.vertices is None,
        "plane_vertices": None if region.plane is None else region.plane / PLOT_SCALE,
        "direction": region.direction,
        "target_qp_units": region.target,
        "clipped": region.clipped,
    }
    write_json(args.out / "results.json", runner.json_ready(summary))
    step = solution.step * region.scale
    rows = [
        ("QP feasible", str(solution.feasible)),
        ("step Δn, Δt, Δθ", f"{step[0]:.3f} mm, {step[1]:.3f} mm, {step[2]:.3f}°"),
        ("region vertices", "empty" if region.vertices is None else str(len(region.vertices))),
        ("minimising plane", "misses the region" if region.plane is None else "meets the region"),
    ]
    print_table(rows, ("", state.motion.value))
    print(f"figures in {args.out}: constraints.png, region.png")
    return 0


if __name__ == "__main__":
    sys.exit(main())
