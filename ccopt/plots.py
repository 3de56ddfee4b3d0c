"""Figures of a run (paper §VII, Figs. 6–8) and a GIF of the scene (cf. Fig. 5).

Every figure function is pure: it takes a run — a run folder, a :class:`~ccopt.record.Record`, or
what :func:`ccopt.closed_loop.run` or :func:`ccopt.experiment.run_experiment` returned, recorded or
in memory (:func:`ccopt.replay.as_record`) — or several, where the study pools trials, and returns
a new :class:`~matplotlib.figure.Figure` rendered by Agg; no pyplot state is touched. Each is titled
with the paper's figure it reproduces. The record is SI (rad, m, N); the plots show degrees and
millimetres. A panel whose data are missing (an empty or interrupted record, no valid kinematics, no
steps) says "no data" instead of raising.

The coordinates are ``(θ_o, s_h, s_g)`` in that order, and a sample's ``motion`` code
(``ccopt.modes.MOTION_CODES``: 0 hold, 1 pivot, 2 slide_hand, 3 slide_ground) commands
coordinate ``motion − 1``.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from pathlib import Path

import numpy as np
from matplotlib import font_manager
from matplotlib.axes import Axes
from matplotlib.backends.backend_agg import FigureCanvasAgg
from matplotlib.figure import Figure
from matplotlib.lines import Line2D
from matplotlib.patches import Patch, Polygon
from matplotlib.ticker import MaxNLocator
from PIL import Image, ImageDraw, ImageFont

from ccopt import clock, forked, geometry, metrics, replay
from ccopt.record import Record
from ccopt.replay import as_record, has

ESTIMATE_COLOR = "tab:blue"
TRUTH_COLOR = "black"
TRUE_CONE_COLOR = "tab:orange"
STICKING_COLOR = "0.65"
SLIDING_COLOR = "tab:blue"
COMMANDED_SHADE = "0.88"

LABELS = (r"$\theta_o$", r"$s_h$", r"$s_g$")
UNITS = ("deg", "mm", "mm")
SCALES = (float(np.rad2deg(1.0)), 1e3, 1e3)
"""Display label, unit and SI-to-display factor of each coordinate ``(θ_o, s_h, s_g)``."""

Run = object
"""A run folder, a :class:`Record`, a ``RunResult`` or an ``Experiment`` (:func:`ccopt.replay.as_record`)."""
Runs = Run | Sequence[Run]


# --- helpers --------------------------------------------------------------------------------------


def _figure(width: float, height: float) -> Figure:
    fig = Figure(figsize=(width, height), layout="constrained")
    FigureCanvasAgg(fig)
    return fig


def _as_list(runs: Runs) -> list[Record]:
    if isinstance(runs, Sequence) and not isinstance(runs, str):
        return [as_record(run) for run in runs]
    return [as_record(runs)]


def _no_data(ax: Axes, message: str = "no data") -> None:
    ax.text(0.5, 0.5, message, transform=ax.transAxes, ha="center", va="center", color="0.4")


def _difference(a: np.ndarray, b: np.ndarray, k: int) -> np.ndarray:
    """``a − b`` of coordinate ``k``, wrapped to ``[−π, π)`` for the angle (SI)."""
    return np.asarray(geometry.wrap_angle(a - b)) if k == 0 else a - b


def _command_runs(record: Record) -> list[tuple[int, int, int]]:
    """``(start, stop, coordinate)`` sample ranges of each commanded (non-hold) step."""
    if not has(record, "motion", "step_index"):
        return []
    motion, step = record.data["motion"].astype(int), record.data["step_index"].astype(int)
    change = np.flatnonzero((np.diff(motion) != 0) | (np.diff(step) != 0)) + 1
    starts, stops = np.r_[0, change], np.r_[change, len(motion)]
    return [(int(a), int(b), int(motion[a]) - 1) for a, b in zip(starts, stops, strict=True) if motion[a] > 0]


def _limits(points: np.ndarray, pad: float = 0.15) -> tuple[tuple[float, float], tuple[float, float]]:
    """Padded ``(xlim, ylim)`` around 2-D points."""
    low, high = points.min(axis=0), points.max(axis=0)
    margin = pad * np.maximum(high - low, 1e-9)
    return (low[0] - margin[0], high[0] + margin[0]), (low[1] - margin[1], high[1] + margin[1])


def _label_coordinates(axes: Sequence[Axes], what: str) -> None:
    for ax, label, unit in zip(axes, LABELS, UNITS, strict=True):
        ax.set_ylabel(f"{label}{what} ({unit})")
    axes[-1].set_xlabel("time (s)")


def _legend_inside(ax: Axes) -> None:
    """A small legend at the best place inside ``ax``. Kept out of the figure's layout, which has
    nothing to make room for inside the axes: the best place is then searched for once, when drawn,
    not in every pass of the layout as well (a twentieth of the still figures' time)."""
    ax.legend(loc="best", fontsize="small").set_in_layout(False)


def _name(record: Record) -> str:
    """The object and schedule of a run, for a title ("" if the run did not record them)."""
    obj, schedule = record.meta.get("object"), record.meta.get("schedule")
    parts = [
        obj.get("name") if isinstance(obj, dict) else None,
        f"schedule {schedule.get('name')}" if isinstance(schedule, dict) else None,
    ]
    return ", ".join(str(p) for p in parts if p)


def _title(fig: Figure, text: str, record: Record | None = None) -> None:
    """``text`` as the figure's title, the run's object and schedule on a second line."""
    name = _name(record) if record is not None else ""
    fig.suptitle(f"{text}\n{name}" if name else text)


# --- Fig. 6: estimation ---------------------------------------------------------------------------


def _draw_traces(axes: Sequence[Axes], record: Record) -> None:
    _label_coordinates(axes, "")
    if not has(record, "time", "est_coordinates", "true_coordinates", "est_kinematics_valid"):
        for ax in axes:
            _no_data(ax)
        return
    time, valid = record.data["time"], replay.valid(record)
    for start, stop, k in _command_runs(record):
        axes[k].axvspan(time[start], time[min(stop, len(time) - 1)], color=COMMANDED_SHADE, lw=0)
    for k, ax in enumerate(axes):
        true = record.data["true_coordinates"][:, k] * SCALES[k]
        estimate = np.where(valid, record.data["est_coordinates"][:, k], np.nan) * SCALES[k]
        ax.plot(time, true, color=TRUTH_COLOR, lw=1.2, label="true")
        ax.plot(time, estimate, color=ESTIMATE_COLOR, lw=1.0, label="estimated")
        if not valid.any():
            _no_data(ax, "no valid estimate")
    _legend_inside(axes[0])


def estimation_traces(run: Run) -> Figure:
    """Fig. 6a: estimated (blue) and true (black) ``θ_o`` (deg), ``s_h`` and ``s_g`` (mm) over time
    (s), the estimate only where the kinematics are valid; grey where that coordinate was commanded.
    """
    record = as_record(run)
    fig = _figure(7.0, 5.5)
    axes = fig.subplots(3, 1, sharex=True)
    _draw_traces(axes, record)
    _title(fig, "Fig. 6a: estimated (blue) vs true (black) contact configuration", record)
    return fig


def _abs_errors(record: Record, k: int) -> np.ndarray:
    """|estimate − truth| of coordinate ``k`` where the kinematics are valid, in deg or mm."""
    if not has(record, "est_coordinates", "true_coordinates", "est_kinematics_valid"):
        return np.empty(0)
    valid = replay.valid(record)
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


def estimation_error_boxes(runs: Runs) -> Figure:
    """Fig. 6b: box plots of the absolute estimation error of ``θ_o`` (deg), ``s_h`` and ``s_g`` (mm)
    over the samples with valid kinematics, pooled over ``runs``; median blue, whiskers 1.5 × IQR,
    outliers hidden.
    """
    records = _as_list(runs)
    fig = _figure(6.0, 3.2)
    _draw_boxes(fig.subplots(1, 3), records)
    count = f"{len(records)} run{'s' * (len(records) != 1)}"
    _title(fig, f"Fig. 6b: absolute estimation error ({count})")
    return fig


def estimation_figure(run: Run) -> Figure:
    """Fig. 6 for one run: the traces (left) and the error box plots (right, one per coordinate)."""
    record = as_record(run)
    fig = _figure(9.0, 6.0)
    axes = fig.subplots(3, 2, width_ratios=(4, 1))
    for ax in axes[:2, 0]:
        ax.sharex(axes[2, 0])
    _draw_traces(axes[:, 0], record)
    _draw_boxes(axes[:, 1], [record])
    axes[0, 0].set_title("estimated (blue) vs true (black); grey: commanded")
    axes[0, 1].set_title("|error|")
    _title(fig, "Fig. 6: estimation", record)
    return fig


# --- Fig. 7: friction cones -----------------------------------------------------------------------


def _scatter_by_mode(ax: Axes, points: np.ndarray, sliding: np.ndarray) -> None:
    ax.scatter(*points[~sliding].T, s=4, color=STICKING_COLOR, lw=0, label="sticking (true)")
    ax.scatter(*points[sliding].T, s=4, color=SLIDING_COLOR, lw=0, label="sliding (true)")


def _estimate_index(record: Record, at: float | None) -> int | None:
    """The sample whose estimate the cone figure draws: the last with a finite ``μ̂_h`` or ground cone
    at or before ``at`` (s; None: the run's end), or None if there is none."""
    if not has(record, "time"):
        return None
    finite = np.zeros(len(record.data["time"]), dtype=bool)
    if "est_mu_h" in record.data:
        finite |= np.isfinite(record.data["est_mu_h"])
    if has(record, "est_ground_rows", "est_ground_bounds"):
        rows, bounds = record.data["est_ground_rows"], record.data["est_ground_bounds"]
        finite |= np.isfinite(rows).all(axis=(1, 2)) & np.isfinite(bounds).all(axis=1)
    if at is not None:
        finite &= record.data["time"] <= at
    return int(np.flatnonzero(finite)[-1]) if finite.any() else None


def _cone_line(ax: Axes, xy: np.ndarray, color: str, style: str, label: str, gid: str) -> None:
    ax.plot(*xy.T, color=color, lw=1.4, ls=style, label=label, gid=gid)


def _draw_hand_cone(ax: Axes, record: Record, index: int | None) -> None:
    ax.set(xlabel=r"$f_n$ (N)", ylabel=r"$f_t$ (N)", title="hand")
    if not has(record, "hand_wrench", "true_modes", "true_contacts"):
        _no_data(ax)
        return
    wrench = record.data["hand_wrench"]
    touching = record.data["true_contacts"][:, 0].astype(bool) & np.isfinite(wrench[:, :2]).all(axis=1)
    points = wrench[touching, :2]
    _scatter_by_mode(ax, points, record.data["true_modes"][touching, 0] != 0)
    f_n = np.array([0.0, 1.1 * max(float(points[:, 0].max(initial=0.0)), 1.0)])
    mu = record.data["est_mu_h"][index] if index is not None and "est_mu_h" in record.data else np.nan
    if np.isfinite(mu):
        label = rf"estimated $\hat\mu_h$ = {float(mu):.2f}"
        for sign in (1.0, -1.0):
            _cone_line(ax, np.column_stack((f_n, sign * mu * f_n)), TRUTH_COLOR, "-", label, "estimated")
            label = "_"
    obj = replay.true_object(record)
    if obj is not None:
        label = rf"true $\mu_h$ = {obj.mu_hand:.2f}"
        for sign in (1.0, -1.0):
            _cone_line(
                ax, np.column_stack((f_n, sign * obj.mu_hand * f_n)), TRUE_CONE_COLOR, "--", label, "true"
            )
            label = "_"
    if len(points) == 0:
        _no_data(ax)
    _legend_inside(ax)


def _world_forces(record: Record) -> np.ndarray:
    """Measured hand force in the world frame ``(f_x, f_y)``, N, one row a sample."""
    theta, (f_n, f_t) = record.data["hand_pose"][:, 2], record.data["hand_wrench"][:, :2].T
    sin, cos = np.sin(theta), np.cos(theta)
    return np.column_stack((f_n * sin + f_t * cos, -f_n * cos + f_t * sin))


def _boundary(rows: np.ndarray, bounds: np.ndarray, limits: tuple) -> list[np.ndarray]:
    """The boundary of ``{f : A f ≤ b}``: each row's segment of ``a·f = b`` where the other rows hold,
    long enough to cross ``limits``."""
    (x0, x1), (y0, y1) = limits
    centre, reach = np.array([x0 + x1, y0 + y1]) / 2, np.hypot(x1 - x0, y1 - y0)
    segments = []
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
            segments.append(foot + np.outer([low, high], along))
    return segments


def true_ground_rows(record: Record) -> tuple[np.ndarray, np.ndarray] | None:
    """The true ground cone on the world hand force, ``A f ≤ b`` (N): with the object at rest the
    ground pushes back ``(−f_x, m g − f_y)``, which slides once ``|f_x| > μ_g (m g − f_y)``; None
    without the object in ``meta.json``."""
    obj = replay.true_object(record)
    if obj is None:
        return None
    weight = obj.mass * geometry.GRAVITY
    rows = np.array([[1.0, obj.mu_ground], [-1.0, obj.mu_ground]])
    return rows, np.full(2, obj.mu_ground * weight)


def _draw_ground_cone(ax: Axes, record: Record, index: int | None) -> None:
    ax.set(xlabel=r"hand force $f_x$ (N)", ylabel=r"hand force $f_y$ (N)", title="ground")
    if not has(record, "hand_pose", "hand_wrench", "true_modes", "true_contacts"):
        _no_data(ax)
        return
    forces = _world_forces(record)
    touching = record.data["true_contacts"].astype(bool).all(axis=1) & np.isfinite(forces).all(axis=1)
    points = forces[touching]  # (a sensor dropout or dead sensor reads NaN)
    if len(points) == 0:
        _no_data(ax)
        return
    _scatter_by_mode(ax, points, record.data["true_modes"][touching, 2] != 0)
    estimate = None
    if index is not None and has(record, "est_ground_rows", "est_ground_bounds"):
        rows, bounds = record.data["est_ground_rows"][index], record.data["est_ground_bounds"][index]
        estimate = (rows, bounds) if np.isfinite(rows).all() and np.isfinite(bounds).all() else None
    limits = _limits(np.vstack((points, [0.0, 0.0], *(_corner(*estimate, points) if estimate else []))))
    cones = ((estimate, TRUTH_COLOR, "-", "estimated", "estimated"),)
    cones += ((true_ground_rows(record), TRUE_CONE_COLOR, "--", "true", "true"),)
    for cone, color, style, label, gid in cones:
        if cone is not None:
            for k, segment in enumerate(_boundary(*cone, limits)):
                _cone_line(ax, segment, color, style, label if k == 0 else "_", gid)
    ax.set(xlim=limits[0], ylim=limits[1])
    _legend_inside(ax)


def _corner(rows: np.ndarray, bounds: np.ndarray, points: np.ndarray) -> list[np.ndarray]:
    """The cone's apex (the rows' intersection, N) as a one-element list if it lies near ``points``
    (within three times their extent of their centre), so the view can include it; else empty.
    """
    if abs(np.linalg.det(rows)) < 1e-9 * np.linalg.norm(rows) ** 2:
        return []
    apex = np.linalg.solve(rows, bounds)
    centre, extent = points.mean(axis=0), max(float(np.ptp(points, axis=0).max()), 1.0)
    return [apex] if np.linalg.norm(apex - centre) <= 3.0 * extent else []


def friction_cones(run: Run, at: float | None = None) -> Figure:
    """Fig. 7: measured wrenches, grey where the contact truly sticks and blue where it truly slides,
    the estimated cone boundaries (black) at one instant and the true ones (orange, dashed). Left: the
    hand, ``f_t`` against ``f_n`` (N), lines ``f_t = ±μ_h f_n``. Right: the world hand force
    ``(f_x, f_y)`` (N), the boundary of the estimated ground constraint ``A f ≤ b`` and of the true
    one (:func:`true_ground_rows`). Only samples with the contacts truly closed are shown. The
    estimate drawn is the last one at or before ``at`` (s; None: the run's end); the title says when.
    """
    record = as_record(run)
    fig = _figure(8.5, 4.0)
    hand, ground = fig.subplots(1, 2)
    index = _estimate_index(record, at)
    _draw_hand_cone(hand, record, index)
    _draw_ground_cone(ground, record, index)
    if index is None:
        when = "no estimate"
    else:
        last = " (the run's last)" if at is None else ""
        when = f"estimate at t = {record.data['time'][index]:.2f} s{last}"
    _title(fig, f"Fig. 7: friction cones, estimated (black) vs true (orange, dashed)\n{when}", record)
    return fig


# --- Fig. 8: control ------------------------------------------------------------------------------


def _draw_control_errors(axes: Sequence[Axes], record: Record) -> None:
    _label_coordinates(axes, " error")
    runs = _command_runs(record) if has(record, "time", "command_targets", "true_coordinates") else []
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


def control_errors(run: Run) -> Figure:
    """Fig. 8a: commanded − true value of the commanded coordinate, ``θ_o`` (deg), ``s_h`` and ``s_g``
    (mm), over time (s) during each step that commands it (one line per step).
    """
    record = as_record(run)
    fig = _figure(7.0, 5.5)
    _draw_control_errors(fig.subplots(3, 1, sharex=True), record)
    _title(fig, "Fig. 8a: control error (commanded − true) during commanded motions", record)
    return fig


def _ratios(records: list[Record]) -> np.ndarray:
    """Realised/commanded change of every non-hold step of ``records`` (see :mod:`ccopt.metrics`)."""
    parts = [
        metrics.realised_ratios(record.data, record.meta.get("steps", []))
        for record in records
        if has(record, "time", "true_coordinates")
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


def realised_histogram(runs: Runs) -> Figure:
    """Fig. 8b: histogram of the true change of the commanded coordinate over each step, divided by
    the commanded change, pooled over ``runs``; dashed line at 1 (fully realised).
    """
    records = _as_list(runs)
    fig = _figure(4.5, 3.5)
    _draw_histogram(fig.add_subplot(), records)
    count = f"{len(records)} run{'s' * (len(records) != 1)}"
    _title(fig, f"Fig. 8b: realised / commanded change ({count})")
    return fig


def control_figure(run: Run) -> Figure:
    """Fig. 8 for one run: the control errors (left) and the histogram of realised change (right)."""
    record = as_record(run)
    fig = _figure(10.0, 5.5)
    left, right = fig.subfigures(1, 2, width_ratios=(3, 2))
    _draw_control_errors(left.subplots(3, 1, sharex=True), record)
    _draw_histogram(right.add_subplot(), [record])
    left.suptitle("commanded − true (each commanded step)")
    right.suptitle("realised / commanded")
    _title(fig, "Fig. 8: control", record)
    return fig


# --- animation ------------------------------------------------------------------------------------

MM = 1e3
"""Metres to millimetres, the unit of the animation's axes."""
GIF_SIZE = (8.0, 5.0)
GIF_DPI = 80
"""The GIF's figure size (in) and resolution: 640 × 400 pixels."""
FRAME_S = 0.1
"""How long each GIF frame shows, s of playback (10 frames a second)."""
UNCHANGED = 255
"""The GIF's palette index of a pixel that did not change since the frame before (transparent)."""
NICE_SPEEDS = (1, 2, 3, 5, 10, 20, 30, 50, 100)
"""Playback speeds (× simulated time) the GIF chooses from."""
MAX_FRAMES = 60
"""The GIF's frames at most: the demo's ``paper`` run (42.5 s) plays at 10× in 43 frames, a second of
the run a frame (at 120, 5× in 86; each frame takes about 2 ms to draw and write)."""


def playback(duration: float, max_frames: int) -> tuple[float, int]:
    """``(speed, frames)``: the smallest of :data:`NICE_SPEEDS` (× simulated time) at which a run of
    ``duration`` s plays in at most ``max_frames`` frames of :data:`FRAME_S`, and the frames it takes."""
    needed = duration / (max_frames * FRAME_S)
    speed = next((s for s in NICE_SPEEDS if s >= needed), math.ceil(needed))
    return float(speed), max(1, math.floor(duration / (speed * FRAME_S) + 1e-9) + 1)


def _view(
    scene: list[replay.Frame], l_h: float, aspect: float
) -> tuple[tuple[float, float], tuple[float, float]]:
    """Fixed limits (mm) on the object: every frame's object polygon (the hand's path where the object
    is unknown) with room for the hand and the cones around it, the ground line in view, widened to
    the ``aspect`` (width / height) of the axes."""
    shapes = [frame.object for frame in scene if frame.object is not None]
    points = np.vstack(shapes or [np.vstack((frame.hand, frame.r_o)) for frame in scene])
    low, high = points.min(axis=0), points.max(axis=0)
    room = max(2.0 * l_h + 0.01, 0.15 * float(np.max(high - low)))  # the cones are 2 l_h long
    low, high = low - room, high + room
    low[1] = min(low[1] + 0.7 * room, -0.3 * room)  # a strip of ground
    centre, half = (low + high) / 2, (high - low) / 2
    half = np.maximum(half, half[::-1] * np.array([aspect, 1.0 / aspect]))
    centre[1] = low[1] + half[1]  # room added above: the ground stays near the bottom
    return tuple(MM * (centre[0] + np.array([-1, 1]) * half[0])), tuple(
        MM * (centre[1] + np.array([-1, 1]) * half[1])
    )


ARTISTS = (
    ("object", "true object"),
    ("hand", "true hand"),
    ("chain", "true contact geometry (r_o, d, s_h)"),
    ("chain_est", "estimated contact geometry"),
    ("r_o", "true ground contact r_o"),
    ("r_o_est", "estimated ground contact"),
    ("hand_cone", "estimated hand cone"),
    ("hand_cone_true", "true hand cone"),
    ("ground_cone", "estimated ground cone"),
    ("ground_cone_true", "true ground cone"),
    ("force", "measured hand force (3 mm/N)"),
)
"""What the GIF draws, in the legend's words (a :class:`~ccopt.replay.Frame` field each)."""
FORCE_SCALE = 3e-3
"""Metres drawn per newton of hand force."""


def _artists(ax: Axes) -> dict[str, object]:
    """One animated artist per :data:`ARTISTS` entry, styled, empty."""
    empty = np.zeros((3, 2))
    cone = {"closed": False, "lw": 1.5}
    artists = {
        "object": Polygon(empty, closed=True, fc="0.85", ec="0.3", lw=1.2),
        "hand": Line2D([], [], color="0.15", lw=5, solid_capstyle="butt"),
        "chain": Line2D([], [], color=TRUTH_COLOR, lw=1.0, ls=":"),
        "chain_est": Line2D([], [], color=ESTIMATE_COLOR, lw=1.0, ls=":"),
        "r_o": Line2D([], [], marker="x", ls="none", color=TRUTH_COLOR, ms=10, mew=2),
        "r_o_est": Line2D([], [], marker="o", ls="none", mfc="none", color=ESTIMATE_COLOR, ms=10, mew=1.5),
        "hand_cone": Polygon(empty, fc=ESTIMATE_COLOR, ec=ESTIMATE_COLOR, alpha=0.3),
        "hand_cone_true": Polygon(empty, fill=False, ec=TRUE_CONE_COLOR, ls="--", **cone),
        "ground_cone": Polygon(empty, fc="tab:purple", ec="tab:purple", alpha=0.3),
        "ground_cone_true": Polygon(empty, fill=False, ec="tab:red", ls="--", **cone),
        "force": Line2D([], [], color="tab:green", lw=2.0, marker=">", markevery=[-1]),
    }
    for artist in artists.values():
        if isinstance(artist, Polygon):
            ax.add_patch(artist)
        else:
            ax.add_line(artist)
        artist.set_animated(True)
    return artists


def _legend(ax: Axes, artists: dict[str, object]) -> None:
    """A legend entry for every element (ground included), proxies styled as the artists."""
    handles = [Line2D([], [], color="0.3", lw=2, label="ground")]
    for key, label in ARTISTS:
        artist = artists[key]
        if isinstance(artist, Polygon):
            proxy = Patch(
                fc=artist.get_facecolor(),
                ec=artist.get_edgecolor(),
                ls=artist.get_linestyle(),
                fill=artist.get_fill(),
                label=label,
            )
        else:
            proxy = Line2D(
                [],
                [],
                color=artist.get_color(),
                lw=min(artist.get_linewidth(), 3),
                ls=artist.get_linestyle(),
                marker=artist.get_marker(),
                mfc=artist.get_markerfacecolor(),
                label=label,
            )
        handles.append(proxy)
    ax.legend(handles=handles, loc="upper left", bbox_to_anchor=(1.01, 1.0), fontsize=9, frameon=False)


def _show(artist: object, xy: np.ndarray | None) -> None:
    artist.set_visible(xy is not None)
    if xy is None:
        return
    points = MM * np.reshape(xy, (-1, 2))
    if isinstance(artist, Polygon):
        artist.set_xy(points)
    else:
        artist.set_data(points[:, 0], points[:, 1])


def _frame_geometry(frame: replay.Frame) -> dict[str, np.ndarray | None]:
    """The points of each artist in one frame, m."""
    force = None
    if frame.force is not None:
        force = np.vstack((frame.hand.mean(axis=0), frame.hand.mean(axis=0) + FORCE_SCALE * frame.force))
    return {key: (force if key == "force" else getattr(frame, key)) for key, _ in ARTISTS}


def animation(run: Run, path: str | Path, max_frames: int = MAX_FRAMES) -> Path:
    """Write a GIF of the run to ``path`` (640 × 400 px) and return it (cf. the paper's Fig. 5). The
    true object and hand, the ground, the true (black) and estimated (blue) ground contact and contact
    geometry, the estimated hand (blue) and ground (purple) friction cones and the true ones (dashed),
    and the measured hand force, in mm, in a frame fixed on the object (the hand may leave it). Frames
    are :data:`FRAME_S` of playback apart and play at a constant multiple of simulated time
    (:func:`playback`: at most ``max_frames``), drawn by blitting the moving parts over one rendered
    background; only the part of a frame that can change (the axes and the clock) is read back and
    written. An empty record gives one "no data" frame.
    """
    record = as_record(run)
    path = Path(path)
    fig = Figure(figsize=GIF_SIZE, dpi=GIF_DPI)
    canvas = FigureCanvasAgg(fig)
    box = (0.08, 0.11, 0.58, 0.78)
    ax = fig.add_axes(box)
    n = len(record.data["time"]) if has(record, *replay.SCENE_KEYS) else 0
    if n == 0:
        _no_data(ax)
        canvas.draw()
        still = _rgb(canvas)
        _save_gif(path, still, (0, 0, still.width, still.height), [still], FRAME_S)
        return path
    time = record.data["time"]
    speed, count = playback(float(time[-1] - time[0]), max_frames)
    moments = time[0] + speed * FRAME_S * np.arange(count)
    frames = clock.latest_samples(time, moments)
    scene = replay.scene(record, frames)
    xlim, ylim = _view(scene, replay.half_length(record), box[2] * GIF_SIZE[0] / (box[3] * GIF_SIZE[1]))
    ax.set(xlim=xlim, ylim=ylim, xlabel="x (mm)", ylabel="y (mm)")
    ax.set_aspect("equal", adjustable="box")
    ax.axhline(0.0, color="0.3", lw=2)
    ax.axhspan(ylim[0], 0.0, color="0.93", lw=0)
    artists = _artists(ax)
    _legend(ax, artists)
    name = _name(record)
    fig.suptitle(f"cf. Fig. 5: a contact configuration sequence{' — ' + name if name else ''}", fontsize=12)
    canvas.draw()
    background = canvas.copy_from_bbox(fig.bbox)
    still = _rgb(canvas)
    corner = ax.transAxes.transform((0.02, 0.97))
    stamp = (round(corner[0]), round(fig.bbox.height - corner[1]))  # PIL counts rows from the top
    font = ImageFont.truetype(font_manager.findfont("DejaVu Sans"), 14)
    texts = [f"t = {moment - time[0]:.1f} s   (playback {speed:g}× simulated time)" for moment in moments]
    region = _region(ax, [_text_box(stamp, text, font) for text in texts])
    parts = []
    for text, frame in zip(texts, scene, strict=True):
        canvas.restore_region(background)
        for key, xy in _frame_geometry(frame).items():
            _show(artists[key], xy)
            ax.draw_artist(artists[key])
        part = _rgb(canvas, region)
        ImageDraw.Draw(part).text((stamp[0] - region[0], stamp[1] - region[1]), text, fill="black", font=font)
        parts.append(part)
    _save_gif(path, still, region, parts, FRAME_S)
    return path


Box = tuple[int, int, int, int]
"""A rectangle of an image's pixels, ``(left, top, right, bottom)`` from its top left (PIL's)."""


def _text_box(corner: tuple[int, int], text: str, font: ImageFont.FreeTypeFont) -> Box:
    """The pixels ``text`` covers, written by PIL with its top left at ``corner``."""
    left, top, right, bottom = font.getbbox(text)
    return corner[0] + left, corner[1] + top, corner[0] + right, corner[1] + bottom


def _region(ax: Axes, texts: list[Box]) -> Box:
    """The pixels a GIF frame may change: the axes, to which the moving artists are clipped, and the
    clock's ``texts``, a box each."""
    box = ax.bbox
    height = ax.get_figure(root=True).bbox.height
    left, top = min(box.x0, *(t[0] for t in texts)), min(height - box.y1, *(t[1] for t in texts))
    right, bottom = max(box.x1, *(t[2] for t in texts)), max(height - box.y0, *(t[3] for t in texts))
    return math.floor(left) - 1, math.floor(top) - 1, math.ceil(right) + 1, math.ceil(bottom) + 1


def _rgb(canvas: FigureCanvasAgg, region: Box | None = None) -> Image.Image:
    """The canvas as it is now, or its ``region``, an RGB image (the clock is written on it by PIL: a
    text drawn by Matplotlib costs more than the rest of a frame)."""
    image = Image.frombuffer("RGBA", canvas.get_width_height(), canvas.buffer_rgba(), "raw", "RGBA", 0, 1)
    return (image if region is None else image.crop(region)).convert("RGB")


def _save_gif(path: Path, still: Image.Image, region: Box, parts: list[Image.Image], frame_s: float) -> None:
    """Write a looping GIF of ``still`` with each of ``parts`` over its ``region`` in turn, ``frame_s``
    s each, in one palette of 255 colours made from the first, the middle and the last frame (no
    dither: flat colours stay flat). After the first, a frame keeps only the pixels that changed; the
    others are the 256th colour, transparent, which shows the frame before. Pillow's own palette
    optimisation does the same but converts every frame pair to RGBA to compare them, four times the
    cost of the rest of the writing; a pixel is mapped to the palette on its own, so only the parts
    are mapped, once each."""
    sample = [parts[0], parts[len(parts) // 2], parts[-1]]
    mosaic = Image.new("RGB", (still.width, still.height * len(sample)))
    for k, part in enumerate(sample):
        mosaic.paste(still, (0, k * still.height))
        mosaic.paste(part, (region[0], k * still.height + region[1]))
    palette = mosaic.quantize(colors=255, method=Image.Quantize.MEDIANCUT, dither=Image.Dither.NONE)
    colours = palette.getpalette()
    left, top, right, bottom = region
    whole = np.array(still.quantize(palette=palette, dither=Image.Dither.NONE))
    frames, previous = [], None
    for part in parts:
        indices = np.asarray(part.quantize(palette=palette, dither=Image.Dither.NONE))
        if previous is None:
            shown = whole.copy()
            shown[top:bottom, left:right] = indices
        else:
            shown = np.full_like(whole, UNCHANGED)
            shown[top:bottom, left:right] = np.where(indices == previous, np.uint8(UNCHANGED), indices)
        previous = indices
        frame = Image.fromarray(shown, "P")
        frame.putpalette(colours)
        frames.append(frame)
    frames[0].save(
        path,
        save_all=True,
        append_images=frames[1:],
        duration=round(1000 * frame_s),
        loop=0,
        optimize=False,
        transparency=UNCHANGED,
        disposal=1,
    )


# --- all figures of a run -------------------------------------------------------------------------

FIGURES = {
    "estimation.png": estimation_figure,
    "friction_cones.png": friction_cones,
    "control.png": control_figure,
}
"""The still figures of a run folder and the functions that draw them."""
PNG_OPTIONS = {"compress_level": 1}
"""Pillow's options for the PNG files: zlib's fastest level, which writes a figure in a third to a
half of the time of Pillow's default (6), the files 5–25 % larger; the pixels are the same."""


def save_png(fig: Figure, path: str | Path, dpi: int = 100) -> Path:
    """Write ``fig`` (on an Agg canvas) as a PNG at ``dpi``, drawn once; its path. The figure keeps
    ``dpi`` afterwards (``savefig`` restores its own).

    The same pixels as ``fig.savefig(path, dpi=dpi)`` (tested) in two thirds to four fifths of the
    time: ``savefig`` draws a figure that has a layout engine twice, a pass that lays it out and
    then the one that renders it, which lays it out again; the constrained layout of this module's
    figures is a third to a half of each draw."""
    fig.set_dpi(dpi)
    canvas = fig.canvas
    canvas.draw()
    size = canvas.get_width_height(physical=True)
    image = Image.frombuffer("RGBA", size, canvas.buffer_rgba(), "raw", "RGBA", 0, 1)
    image.save(path, format="png", **PNG_OPTIONS)
    return Path(path)


def write_stills(run: Run, folder: str | Path, dpi: int = 100) -> list[Path]:
    """Write the still figures of :data:`FIGURES` into ``folder`` (created if needed); their paths."""
    record = as_record(run)
    folder = Path(folder)
    folder.mkdir(parents=True, exist_ok=True)
    return [save_png(draw(record), folder / name, dpi) for name, draw in FIGURES.items()]


def write_moving(run: Run, folder: str | Path) -> list[Path]:
    """Write ``animation.gif`` into ``folder`` (created if needed) and, if the run's own folder keeps
    feasibility maps, ``feasibility_map.png`` (:func:`ccopt.feasibility_map.write_figure`); their
    paths."""
    from ccopt import feasibility_map

    record = as_record(run)
    folder = Path(folder)
    folder.mkdir(parents=True, exist_ok=True)
    paths = [animation(record, folder / "animation.gif")]
    maps = feasibility_map.write_figure(record.folder, folder) if record.folder is not None else None
    return paths + ([maps] if maps is not None else [])


def write_figures(run: Run, folder: str | Path, dpi: int = 100) -> list[Path]:
    """Write every figure of a run into ``folder`` (created if needed) and return their paths:
    ``estimation.png`` (Fig. 6), ``friction_cones.png`` (Fig. 7), ``control.png`` (Fig. 8),
    ``animation.gif`` and, if the run's folder keeps feasibility maps, ``feasibility_map.png``.

    The GIF and the maps are drawn in a forked worker process while this one draws the stills
    (:func:`ccopt.forked.side_by_side`): each half takes about as long as the other, and drawn one
    after the other they took 1.5–1.8 times the loop of the ``paper`` run they showed (``docs/speed.md``).
    """
    record = as_record(run)
    stills, moving = (lambda: write_stills(record, folder, dpi)), (lambda: write_moving(record, folder))
    return forked.side_by_side(stills, moving)
