"""Figures of a run (paper §VII, Figs. 6–8) and a GIF of the scene, drawn from a run record.

Every figure function is pure: it takes a :class:`~ccopt.record.Record` (or several, where the
study aggregates trials) and returns a new :class:`~matplotlib.figure.Figure` rendered by Agg; no
pyplot state is touched. The record is SI (rad, m, N); the plots show degrees and millimetres.
A panel whose data are missing (an empty or interrupted record, no valid kinematics, no steps)
says "no data" instead of raising.

The coordinates are ``(θ_o, s_h, s_g)`` in that order, and a sample's ``motion`` code
(``ccopt.modes.MOTION_CODES``: 0 hold, 1 pivot, 2 slide_hand, 3 slide_ground) commands
coordinate ``motion − 1``.
"""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path

import numpy as np
from matplotlib.animation import PillowWriter
from matplotlib.axes import Axes
from matplotlib.backends.backend_agg import FigureCanvasAgg
from matplotlib.figure import Figure
from matplotlib.lines import Line2D
from matplotlib.patches import Polygon
from matplotlib.ticker import MaxNLocator

from ccopt import geometry, metrics
from ccopt.hand import Hand
from ccopt.objects import PlanarObject
from ccopt.plant.base import StartConfig
from ccopt.record import Record

ESTIMATE_COLOR = "tab:blue"
TRUTH_COLOR = "black"
STICKING_COLOR = "0.65"
SLIDING_COLOR = "tab:blue"
COMMANDED_SHADE = "0.88"

LABELS = (r"$\theta_o$", r"$s_h$", r"$s_g$")
UNITS = ("deg", "mm", "mm")
SCALES = (float(np.rad2deg(1.0)), 1e3, 1e3)
"""Display label, unit and SI-to-display factor of each coordinate ``(θ_o, s_h, s_g)``."""

Records = Record | Sequence[Record]


# --- helpers --------------------------------------------------------------------------------------


def _figure(width: float, height: float) -> Figure:
    fig = Figure(figsize=(width, height), layout="constrained")
    FigureCanvasAgg(fig)
    return fig


def _as_list(records: Records) -> list[Record]:
    return [records] if isinstance(records, Record) else list(records)


def _has(record: Record, *keys: str) -> bool:
    """True if every key is present with at least one sample."""
    return all(key in record.data and len(record.data[key]) > 0 for key in keys)


def _no_data(ax: Axes, message: str = "no data") -> None:
    ax.text(0.5, 0.5, message, transform=ax.transAxes, ha="center", va="center", color="0.4")


def _difference(a: np.ndarray, b: np.ndarray, k: int) -> np.ndarray:
    """``a − b`` of coordinate ``k``, wrapped to ``[−π, π)`` for the angle (SI)."""
    return np.asarray(geometry.wrap_angle(a - b)) if k == 0 else a - b


def _valid(record: Record) -> np.ndarray:
    """Samples where the estimator reports valid, finite kinematics."""
    estimate = record.data["est_coordinates"]
    return record.data["est_kinematics_valid"].astype(bool) & np.isfinite(estimate).all(axis=1)


def _command_runs(record: Record) -> list[tuple[int, int, int]]:
    """``(start, stop, coordinate)`` sample ranges of each commanded (non-hold) step."""
    if not _has(record, "motion", "step_index"):
        return []
    motion, step = record.data["motion"].astype(int), record.data["step_index"].astype(int)
    change = np.flatnonzero((np.diff(motion) != 0) | (np.diff(step) != 0)) + 1
    starts, stops = np.r_[0, change], np.r_[change, len(motion)]
    return [(int(a), int(b), int(motion[a]) - 1) for a, b in zip(starts, stops, strict=True) if motion[a] > 0]


def _last_finite(values: np.ndarray) -> np.ndarray | None:
    """The last sample of ``values`` (first axis) whose entries are all finite, or None."""
    finite = np.isfinite(values.reshape(len(values), -1)).all(axis=1)
    return values[np.flatnonzero(finite)[-1]] if finite.any() else None


def _limits(points: np.ndarray, pad: float = 0.15) -> tuple[tuple[float, float], tuple[float, float]]:
    """Padded ``(xlim, ylim)`` around 2-D points."""
    low, high = points.min(axis=0), points.max(axis=0)
    margin = pad * np.maximum(high - low, 1e-9)
    return (low[0] - margin[0], high[0] + margin[0]), (low[1] - margin[1], high[1] + margin[1])


def _label_coordinates(axes: Sequence[Axes], what: str) -> None:
    for ax, label, unit in zip(axes, LABELS, UNITS, strict=True):
        ax.set_ylabel(f"{label}{what} ({unit})")
    axes[-1].set_xlabel("time (s)")


# --- Fig. 6: estimation ---------------------------------------------------------------------------


def _draw_traces(axes: Sequence[Axes], record: Record) -> None:
    _label_coordinates(axes, "")
    if not _has(record, "time", "est_coordinates", "true_coordinates", "est_kinematics_valid"):
        for ax in axes:
            _no_data(ax)
        return
    time, valid = record.data["time"], _valid(record)
    for start, stop, k in _command_runs(record):
        axes[k].axvspan(time[start], time[min(stop, len(time) - 1)], color=COMMANDED_SHADE, lw=0)
    for k, ax in enumerate(axes):
        true = record.data["true_coordinates"][:, k] * SCALES[k]
        estimate = np.where(valid, record.data["est_coordinates"][:, k], np.nan) * SCALES[k]
        ax.plot(time, true, color=TRUTH_COLOR, lw=1.2, label="true")
        ax.plot(time, estimate, color=ESTIMATE_COLOR, lw=1.0, label="estimated")
        if not valid.any():
            _no_data(ax, "no valid estimate")
    axes[0].legend(loc="best", fontsize="small")


def estimation_traces(record: Record) -> Figure:
    """Fig. 6a: estimated (blue) and true (black) ``θ_o`` (deg), ``s_h`` and ``s_g`` (mm) over time
    (s), the estimate only where the kinematics are valid; grey where that coordinate was commanded.
    """
    fig = _figure(7.0, 5.5)
    axes = fig.subplots(3, 1, sharex=True)
    _draw_traces(axes, record)
    fig.suptitle("Estimated vs true contact configuration")
    return fig


def _abs_errors(record: Record, k: int) -> np.ndarray:
    """|estimate − truth| of coordinate ``k`` where the kinematics are valid, in deg or mm."""
    if not _has(record, "est_coordinates", "true_coordinates", "est_kinematics_valid"):
        return np.empty(0)
    valid = _valid(record)
    estimate, true = record.data["est_coordinates"][valid, k], record.data["true_coordinates"][valid, k]
    return np.abs(_difference(estimate, true, k)) * SCALES[k]


def _draw_boxes(axes: Sequence[Axes], records: list[Record]) -> None:
    for k, ax in enumerate(axes):
        errors = np.concatenate([np.empty(0), *(_abs_errors(record, k) for record in records)])
        ax.set_ylabel(f"|{LABELS[k]} error| ({UNITS[k]})")
        if errors.size:
            ax.boxplot(errors, whis=1.5, showfliers=False, widths=0.5, medianprops={"color": ESTIMATE_COLOR})
        else:
            _no_data(ax)
        ax.set_xticks([])


def estimation_error_boxes(records: Records) -> Figure:
    """Fig. 6b: box plots of the absolute estimation error of ``θ_o`` (deg), ``s_h`` and ``s_g`` (mm)
    over the samples with valid kinematics, pooled over ``records``; median blue, whiskers 1.5 × IQR,
    outliers hidden.
    """
    records = _as_list(records)
    fig = _figure(6.0, 3.0)
    _draw_boxes(fig.subplots(1, 3), records)
    fig.suptitle(f"Absolute estimation error ({len(records)} run{'s' * (len(records) != 1)})")
    return fig


def estimation_figure(record: Record) -> Figure:
    """Fig. 6 for one run: the traces (left) and the error box plots (right, one per coordinate)."""
    fig = _figure(9.0, 6.0)
    axes = fig.subplots(3, 2, width_ratios=(4, 1))
    for ax in axes[:2, 0]:
        ax.sharex(axes[2, 0])
    _draw_traces(axes[:, 0], record)
    _draw_boxes(axes[:, 1], [record])
    axes[0, 0].set_title("estimation (grey: commanded)")
    axes[0, 1].set_title("|error|")
    return fig


# --- Fig. 7: friction cones -----------------------------------------------------------------------


def _scatter_by_mode(ax: Axes, points: np.ndarray, sliding: np.ndarray) -> None:
    ax.scatter(*points[~sliding].T, s=4, color=STICKING_COLOR, lw=0, label="sticking (true)")
    ax.scatter(*points[sliding].T, s=4, color=SLIDING_COLOR, lw=0, label="sliding (true)")


def _draw_hand_cone(ax: Axes, record: Record) -> None:
    ax.set(xlabel=r"$f_n$ (N)", ylabel=r"$f_t$ (N)", title="hand")
    if not _has(record, "hand_wrench", "true_modes", "true_contacts"):
        _no_data(ax)
        return
    wrench = record.data["hand_wrench"]
    touching = record.data["true_contacts"][:, 0].astype(bool) & np.isfinite(wrench[:, :2]).all(axis=1)
    points = wrench[touching, :2]
    _scatter_by_mode(ax, points, record.data["true_modes"][touching, 0] != 0)
    mu = _last_finite(record.data["est_mu_h"]) if "est_mu_h" in record.data else None
    if mu is not None:
        f_n = np.array([0.0, 1.1 * max(float(points[:, 0].max(initial=0.0)), 1.0)])
        ax.plot(f_n, mu * f_n, color=TRUTH_COLOR, lw=1.2, label=rf"estimated $\mu_h$ = {float(mu):.2f}")
        ax.plot(f_n, -mu * f_n, color=TRUTH_COLOR, lw=1.2)
    if len(points) == 0:
        _no_data(ax)
    ax.legend(loc="best", fontsize="small")


def _world_forces(record: Record) -> np.ndarray:
    """Measured hand force in the world frame ``(f_x, f_y)``, N, one row a sample."""
    pose, wrench = record.data["hand_pose"], record.data["hand_wrench"]
    forces = [geometry.wrench_hand_to_world(p[2], w)[:2] for p, w in zip(pose, wrench, strict=True)]
    return np.reshape(forces, (-1, 2))


def _draw_boundary(ax: Axes, rows: np.ndarray, bounds: np.ndarray, limits: tuple) -> None:
    """The boundary of ``{f : A f ≤ b}``: each row's line ``a·f = b`` where the other rows hold,
    long enough to cross the (then fixed) ``limits``.
    """
    (x0, x1), (y0, y1) = limits
    centre, reach = np.array([x0 + x1, y0 + y1]) / 2, np.hypot(x1 - x0, y1 - y0)
    for i, (a, b) in enumerate(zip(rows, bounds, strict=True)):
        norm = np.linalg.norm(a)
        if norm == 0.0:
            continue
        foot, along = a * b / norm**2, np.array([-a[1], a[0]]) / norm
        half = reach + np.linalg.norm(foot - centre)
        low, high = -half, half
        for j in np.flatnonzero(np.arange(len(rows)) != i):  # a_j·(foot + t along) ≤ b_j
            rate, room = rows[j] @ along, bounds[j] - rows[j] @ foot
            if rate > 0.0:
                high = min(high, room / rate)
            elif rate < 0.0:
                low = max(low, room / rate)
            elif room < 0.0:
                high = low
        if low < high:
            ends = foot + np.outer([low, high], along)
            ax.plot(*ends.T, color=TRUTH_COLOR, lw=1.2, label="_" if ax.get_lines() else "estimated")
    ax.set(xlim=(x0, x1), ylim=(y0, y1))


def _draw_ground_cone(ax: Axes, record: Record) -> None:
    ax.set(xlabel=r"hand force $f_x$ (N)", ylabel=r"hand force $f_y$ (N)", title="ground")
    if not _has(record, "hand_pose", "hand_wrench", "true_modes", "true_contacts"):
        _no_data(ax)
        return
    forces = _world_forces(record)
    touching = record.data["true_contacts"].astype(bool).all(axis=1) & np.isfinite(forces).all(axis=1)
    points = forces[touching]  # (a sensor dropout or dead sensor reads NaN)
    if len(points) == 0:
        _no_data(ax)
        return
    _scatter_by_mode(ax, points, record.data["true_modes"][touching, 2] != 0)
    final = _final_ground_rows(record)
    if final is not None:
        _draw_boundary(ax, *final, _limits(np.vstack((points, [0.0, 0.0], *_corner(*final, points)))))
    ax.legend(loc="best", fontsize="small")


def _final_ground_rows(record: Record) -> tuple[np.ndarray, np.ndarray] | None:
    """The last finite estimate of the ground rows ``(A (2×2), b (2))``, or None."""
    if not _has(record, "est_ground_rows", "est_ground_bounds"):
        return None
    rows, bounds = record.data["est_ground_rows"], record.data["est_ground_bounds"]
    finite = np.flatnonzero(np.isfinite(rows).all(axis=(1, 2)) & np.isfinite(bounds).all(axis=1))
    return (rows[finite[-1]], bounds[finite[-1]]) if finite.size else None


def _corner(rows: np.ndarray, bounds: np.ndarray, points: np.ndarray) -> list[np.ndarray]:
    """The cone's apex (the rows' intersection, N) as a one-element list if it lies near ``points``
    (within three times their extent of their centre), so the view can include it; else empty.
    """
    if abs(np.linalg.det(rows)) < 1e-9 * np.linalg.norm(rows) ** 2:
        return []
    apex = np.linalg.solve(rows, bounds)
    centre, extent = points.mean(axis=0), max(float(np.ptp(points, axis=0).max()), 1.0)
    return [apex] if np.linalg.norm(apex - centre) <= 3.0 * extent else []


def friction_cones(record: Record) -> Figure:
    """Fig. 7: measured wrenches, grey where the contact truly sticks and blue where it truly slides,
    with the final estimated cone boundaries (black). Left: the hand, ``f_t`` against ``f_n`` (N),
    lines ``f_t = ±μ_h f_n``. Right: the world hand force ``(f_x, f_y)`` (N) and the boundary of the
    estimated ground constraint ``A f ≤ b``. Only samples with the contacts truly closed are shown.
    """
    fig = _figure(8.0, 3.8)
    hand, ground = fig.subplots(1, 2)
    _draw_hand_cone(hand, record)
    _draw_ground_cone(ground, record)
    fig.suptitle("Estimated friction cones and measured wrenches")
    return fig


# --- Fig. 8: control ------------------------------------------------------------------------------


def _draw_control_errors(axes: Sequence[Axes], record: Record) -> None:
    _label_coordinates(axes, " error")
    runs = _command_runs(record) if _has(record, "time", "command_targets", "true_coordinates") else []
    for start, stop, k in runs:
        command = record.data["command_targets"][start:stop, k]
        error = _difference(command, record.data["true_coordinates"][start:stop, k], k) * SCALES[k]
        axes[k].plot(record.data["time"][start:stop], error, color=TRUTH_COLOR, lw=1.0)
    commanded = {k for _, _, k in runs}
    for k, ax in enumerate(axes):
        if k in commanded:
            ax.axhline(0.0, color="0.6", lw=0.8, ls=":")
        else:
            _no_data(ax)


def control_errors(record: Record) -> Figure:
    """Fig. 8a: commanded − true value of the commanded coordinate, ``θ_o`` (deg), ``s_h`` and ``s_g``
    (mm), over time (s) during each step that commands it (one line per step).
    """
    fig = _figure(7.0, 5.5)
    _draw_control_errors(fig.subplots(3, 1, sharex=True), record)
    fig.suptitle("Control error during commanded motions")
    return fig


def _ratios(records: list[Record]) -> np.ndarray:
    """Realised/commanded change of every non-hold step of ``records`` (see :mod:`ccopt.metrics`)."""
    parts = [
        metrics.realised_ratios(record.data, record.meta.get("steps", []))
        for record in records
        if _has(record, "time", "true_coordinates")
    ]
    ratios = np.concatenate([np.empty(0), *parts])
    return ratios[np.isfinite(ratios)]


def _bins(ratios: np.ndarray, width: float = 0.05, most: int = 40) -> np.ndarray:
    """Bin edges of ``width`` (wider if more than ``most`` bins) centred on its multiples, covering 1."""
    low, high = min(ratios.min(), 1.0), max(ratios.max(), 1.0)
    width = max(width, (high - low) / most)
    return width * (np.arange(np.floor(low / width), np.ceil(high / width) + 1.0) - 0.5)


def _draw_histogram(ax: Axes, records: list[Record]) -> None:
    ax.set(xlabel="realised / commanded change", ylabel="steps")
    ratios = _ratios(records)
    if ratios.size == 0:
        _no_data(ax)
        return
    ax.hist(ratios, bins=_bins(ratios), color="0.55", edgecolor="white")
    ax.yaxis.set_major_locator(MaxNLocator(integer=True))
    ax.axvline(1.0, color=ESTIMATE_COLOR, ls="--", lw=1.5)


def realised_histogram(records: Records) -> Figure:
    """Fig. 8b: histogram of the true change of the commanded coordinate over each step, divided by
    the commanded change, pooled over ``records``; dashed line at 1 (fully realised).
    """
    records = _as_list(records)
    fig = _figure(4.5, 3.5)
    _draw_histogram(fig.add_subplot(), records)
    fig.suptitle(f"Realised change ({len(records)} run{'s' * (len(records) != 1)})")
    return fig


def control_figure(record: Record) -> Figure:
    """Fig. 8 for one run: the control errors (left) and the histogram of realised change (right)."""
    fig = _figure(10.0, 5.5)
    left, right = fig.subfigures(1, 2, width_ratios=(3, 2))
    _draw_control_errors(left.subplots(3, 1, sharex=True), record)
    _draw_histogram(right.add_subplot(), [record])
    left.suptitle("commanded − true")
    right.suptitle("realised / commanded")
    return fig


# --- animation ------------------------------------------------------------------------------------


def _object(record: Record) -> tuple[np.ndarray, float] | None:
    """Body-frame vertices (m) of the object of ``meta`` and the angle (rad) to add to the angle of its
    hand face to get the object angle; None if the object or the face is unknown or invalid.
    """
    spec = record.meta.get("object")
    start = record.meta.get("params", {}).get("start", {})
    try:
        obj = PlanarObject(spec["name"], spec["vertices"], spec["mass"], spec["mu_hand"], spec["mu_ground"])
        face = start.get("hand_face", StartConfig().hand_face)
        return obj.vertices, -geometry.face_angle(obj.face_normal(face), 0.0)
    except (KeyError, TypeError, ValueError):
        return None


def _polygon(vertices: np.ndarray, offset: float, theta_o: float, r_o: np.ndarray) -> np.ndarray:
    """World vertices of the object at angle ``θ_o + offset`` whose lowest vertex is at ``r_o`` (m)."""
    turned = geometry.transform_points(vertices, (0.0, 0.0, theta_o + offset))
    return turned - turned[geometry.lowest_vertex(turned)] + r_o


def _upward(row: np.ndarray) -> np.ndarray:
    """The direction along the line ``a·f = b`` of a ground row ``a`` that points up (+y)."""
    along = np.array([-row[1], row[0]])
    return along if along[1] >= 0.0 else -along


def _wedge(apex: np.ndarray, directions: Sequence[np.ndarray], length: float) -> np.ndarray:
    """Polygon of ``apex`` and ``apex + length·u`` for the unit vector ``u`` of each direction."""
    return np.vstack([apex, *(apex + length * u / np.linalg.norm(u) for u in directions)])


SCENE_KEYS = (
    "time",
    "hand_pose",
    "true_hand_pose",
    "true_coordinates",
    "true_d",
    "est_coordinates",
    "est_d",
    "est_kinematics_valid",
    "est_mu_h",
    "est_ground_rows",
)
"""Series the animation needs."""


def _half_length(record: Record) -> float:
    """The hand's ``l_h`` (m) of a run's ``meta.json`` (the default hand's if the run did not say)."""
    params = record.meta.get("params", {})
    hand = params.get("hand", {}) if isinstance(params, dict) else {}
    value = hand.get("half_length") if isinstance(hand, dict) else None
    return float(value) if isinstance(value, int | float) else Hand().half_length


def _scene(record: Record, frames: np.ndarray) -> list[dict[str, np.ndarray | None]]:
    """Per frame, in m: the object polygon (true), hand segment (true), true and estimated ``r_o``,
    the estimated hand cone at the measured hand and the estimated ground cone at the estimated ``r_o``
    (None where unknown).
    """
    data = record.data
    l_h = _half_length(record)
    true_pose, pose = data["true_hand_pose"][frames], data["hand_pose"][frames]
    r_o = geometry.ground_contact(true_pose, data["true_coordinates"][frames, 1], data["true_d"][frames])
    r_est = geometry.ground_contact(pose, data["est_coordinates"][frames, 1], data["est_d"][frames])
    valid = _valid(record)[frames]
    known = _object(record)
    scene = []
    for j, i in enumerate(frames):
        mu, rows = data["est_mu_h"][i], data["est_ground_rows"][i]
        e_t, e_n = geometry.hand_tangent(pose[j, 2]), geometry.hand_normal(pose[j, 2])
        hand_cone = _wedge(pose[j, :2], (e_n + mu * e_t, e_n - mu * e_t), l_h) if np.isfinite(mu) else None
        ground_ok = valid[j] and np.isfinite(rows).all()
        scene.append(
            {
                "object": _polygon(*known, data["true_coordinates"][i, 0], r_o[j]) if known else None,
                "hand": true_pose[j, :2] + np.outer([-l_h, l_h], geometry.hand_tangent(true_pose[j, 2])),
                "r_o": r_o[j],
                "r_o_est": r_est[j] if valid[j] else None,
                "hand_cone": hand_cone,
                "ground_cone": _wedge(r_est[j], [_upward(a) for a in rows], l_h) if ground_ok else None,
            }
        )
    return scene


MM = 1e3
"""Metres to millimetres, the unit of the animation's axes."""


def _fix_view(ax: Axes, scene: list[dict[str, np.ndarray | None]]) -> None:
    """Fixed limits (mm) holding every frame's geometry and the ground line ``y = 0``."""
    points = np.vstack([np.reshape(v, (-1, 2)) for frame in scene for v in frame.values() if v is not None])
    points = MM * points[np.isfinite(points).all(axis=1)]
    xlim, ylim = _limits(np.vstack((points, [points[0, 0], 0.0])), pad=0.1)
    ax.set(xlim=xlim, ylim=ylim, xlabel="x (mm)", ylabel="y (mm)")
    ax.set_aspect("equal", adjustable="box")


def _show_patch(patch: Polygon, xy: np.ndarray | None) -> None:
    patch.set_visible(xy is not None)
    if xy is not None:
        patch.set_xy(MM * xy)


def _show_line(line: Line2D, xy: np.ndarray | None) -> None:
    points = np.empty((0, 2)) if xy is None else MM * np.reshape(xy, (-1, 2))
    line.set_data(points[:, 0], points[:, 1])


def animation(record: Record, path: str | Path, fps: int = 20, max_frames: int = 200) -> Path:
    """Write a GIF of the run to ``path`` and return it: the true object and hand, the ground, the true
    (black ×) and estimated (blue ○, where the kinematics are valid) ground contact ``r_o``, the
    estimated hand friction cone at the measured hand and the estimated ground cone (the directions
    of the ground rows' lines, pointing up) at the estimated ``r_o``; axes in mm. At most
    ``max_frames`` evenly spaced samples are shown, ``fps`` a second. An empty record gives one
    "no data" frame.
    """
    path = Path(path)
    fig = _figure(4.0, 3.4)
    ax = fig.add_subplot()
    writer = PillowWriter(fps=fps)
    n = len(record.data["time"]) if _has(record, *SCENE_KEYS) else 0
    if n == 0:
        _no_data(ax)
        with writer.saving(fig, str(path), dpi=80):
            writer.grab_frame()
        return path
    frames = np.unique(np.linspace(0, n - 1, min(n, max_frames)).round().astype(int))
    scene = _scene(record, frames)
    _fix_view(ax, scene)
    ax.axhline(0.0, color="0.3", lw=1.5)
    body = ax.add_patch(Polygon(np.zeros((3, 2)), fc="0.85", ec="0.3"))
    cones = {
        key: ax.add_patch(Polygon(np.zeros((3, 2)), fc=ESTIMATE_COLOR, ec=ESTIMATE_COLOR, alpha=0.3))
        for key in ("hand_cone", "ground_cone")
    }
    lines = {
        "hand": ax.plot([], [], color="0.15", lw=4, solid_capstyle="butt")[0],
        "r_o": ax.plot([], [], "x", color=TRUTH_COLOR, ms=8, mew=2, label="true $r_o$")[0],
        "r_o_est": ax.plot([], [], "o", mfc="none", color=ESTIMATE_COLOR, ms=8, label="estimated $r_o$")[0],
    }
    ax.legend(loc="upper right", fontsize="x-small")
    clock = ax.text(0.02, 0.97, "", transform=ax.transAxes, va="top", fontsize="small")
    fig.canvas.draw()  # lay out once: the limits are fixed, so the layout is too
    fig.set_layout_engine("none")
    with writer.saving(fig, str(path), dpi=80):
        for i, frame in zip(frames, scene, strict=True):
            _show_patch(body, frame["object"])
            for key, patch in cones.items():
                _show_patch(patch, frame[key])
            for key, line in lines.items():
                _show_line(line, frame[key])
            clock.set_text(f"t = {record.data['time'][i]:.2f} s")
            writer.grab_frame()
    return path


# --- all figures of a run -------------------------------------------------------------------------

FIGURES = {
    "estimation.png": estimation_figure,
    "friction_cones.png": friction_cones,
    "control.png": control_figure,
}
"""The still figures of a run folder and the functions that draw them."""


def write_figures(record: Record, folder: str | Path, dpi: int = 120) -> list[Path]:
    """Write ``estimation.png``, ``friction_cones.png``, ``control.png`` and ``animation.gif`` into
    ``folder`` (created if needed) and return their paths.
    """
    folder = Path(folder)
    folder.mkdir(parents=True, exist_ok=True)
    paths = []
    for name, draw in FIGURES.items():
        draw(record).savefig(folder / name, dpi=dpi)
        paths.append(folder / name)
    paths.append(animation(record, folder / "animation.gif"))
    return paths
