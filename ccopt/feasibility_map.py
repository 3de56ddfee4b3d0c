"""Feasibility maps: where over ``(θ_o, s_h)`` each motion is possible with margin, estimated vs true.

The paper's authors painted, by hand, the regions where their motions worked; ccopt computes them.
For each motion (:class:`ccopt.modes.Motion` but ``HOLD``) the map holds the statics margin of
:func:`ccopt.statics.best_wrench` (N: the smallest kept friction/torque row margin of the best
wrench; ``−inf`` where no wrench balances the object, NaN where the motion's boundary is unknown)
on a grid of face angles ``θ_o`` and hand positions ``s_h``, twice:

* **estimated** — on the statics the run's last usable estimate knows
  (:func:`ccopt.control.targets.estimated_statics`, per motion), what the planner judged with;
* **true** — on the object's true statics (:func:`ccopt.statics.true_statics`; the experimenter's
  oracle), with the grid points where the hand would leave the face or the object would roll onto
  another vertex marked (NaN and :attr:`FeasibilityMap.true_valid`).

A run folder keeps the maps in ``feasibility_map.npz`` (SI: rad, m, N) and draws them into
``feasibility_map.png`` (:func:`draw`). The paper has no such figure; it is the future work of its
§VIII (planning over contact configurations).
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np

from ccopt.modes import Motion

if TYPE_CHECKING:  # the statics are imported where the maps are computed, not to draw them
    from ccopt import statics
    from ccopt.estimation.estimator import Estimate
    from ccopt.hand import Hand
    from ccopt.objects import PlanarObject
    from ccopt.plant.base import StartConfig

MOTIONS = (
    Motion.PIVOT,
    Motion.SLIDE_HAND_POS,
    Motion.SLIDE_HAND_NEG,
    Motion.SLIDE_GROUND_POS,
    Motion.SLIDE_GROUND_NEG,
)
"""The motions a map is drawn for, in order (holding is possible wherever pivoting is)."""
FILE_NAME = "feasibility_map.npz"
THETA_STEP = math.radians(2.0)
"""rad: the grid's ``θ_o`` step."""
S_H_STEP = 0.002
"""m: the grid's ``s_h`` step."""
S_H_SPAN = 0.03
"""m: the grid covers ``s_h`` this far either side of the estimate's (or the start's)."""


@dataclass(frozen=True)
class FeasibilityMap:
    """Margins over a ``(θ_o, s_h)`` grid (see the module docstring). SI units.

    Attributes:
        theta_o: the grid's face angles (n,), rad.
        s_h: the grid's hand positions (m,), m.
        motions: the motions' names (:data:`MOTIONS`), one per map.
        estimated: margins on the estimated statics (k, n, m), N; all NaN if nothing was estimated.
        true: margins on the true statics (k, n, m), N; NaN off the face or the start vertex.
        true_valid: where the true configuration exists (n, m): the hand on the face, the object
            on the vertex it started on.
        min_margin: the margin a planned motion keeps (N): the maps' contour.
        estimated_at: ``(θ̂_o, ŝ_h)`` of the estimate the maps were judged at (rad, m), NaN if none.
    """

    theta_o: np.ndarray
    s_h: np.ndarray
    motions: tuple[str, ...]
    estimated: np.ndarray
    true: np.ndarray
    true_valid: np.ndarray
    min_margin: float
    estimated_at: tuple[float, float]

    def save(self, folder: str | Path) -> Path:
        """Write ``feasibility_map.npz`` into ``folder``; its path."""
        path = Path(folder) / FILE_NAME
        temporary = path.with_name(path.name + ".partial")
        arrays = {
            "theta_o": self.theta_o,
            "s_h": self.s_h,
            "motions": np.array(self.motions),
            "estimated": self.estimated,
            "true": self.true,
            "true_valid": self.true_valid,
            "min_margin": np.float64(self.min_margin),
            "estimated_at": np.array(self.estimated_at),
        }
        with temporary.open("wb") as stream:  # written whole, then renamed: never half a file
            np.savez(stream, **arrays)
        temporary.replace(path)
        return path


def load(folder: str | Path) -> FeasibilityMap | None:
    """The maps a run folder keeps, None if it keeps none (a run from before, or interrupted early).

    Raises ``ValueError`` naming the file if it is there but unreadable."""
    path = Path(folder) / FILE_NAME
    if not path.is_file():
        return None
    try:
        with np.load(path, allow_pickle=False) as data:
            return FeasibilityMap(
                data["theta_o"],
                data["s_h"],
                tuple(str(name) for name in data["motions"]),
                data["estimated"],
                data["true"],
                data["true_valid"],
                float(data["min_margin"]),
                (float(data["estimated_at"][0]), float(data["estimated_at"][1])),
            )
    except (OSError, KeyError, ValueError, IndexError) as error:
        raise ValueError(f"{path}: not a feasibility map ({error})") from None


def grid_around(theta_range: tuple[float, float], s_h: float) -> tuple[np.ndarray, np.ndarray]:
    """The grid: ``θ_o`` over ``theta_range`` (rad) and ``s_h`` within :data:`S_H_SPAN` of ``s_h``
    (m), in :data:`THETA_STEP` and :data:`S_H_STEP`."""
    low, high = theta_range
    thetas = np.arange(low, high + 0.5 * THETA_STEP, THETA_STEP)
    count = round(S_H_SPAN / S_H_STEP)
    return thetas, s_h + S_H_STEP * np.arange(-count, count + 1)


def margins(
    statics_of: Callable[[Motion], statics.ObjectStatics | None],
    thetas: np.ndarray,
    s_hs: np.ndarray,
    lever: float,
    forces: tuple[float, float],
) -> np.ndarray:
    """Margins (k, n, m) of :data:`MOTIONS` over the grid, ``statics_of(motion)`` giving the statics
    each motion is judged on (None: NaN everywhere)."""
    from ccopt import statics

    out = np.full((len(MOTIONS), len(thetas), len(s_hs)), math.nan)
    for k, motion in enumerate(MOTIONS):
        known = statics_of(motion)
        if known is None:
            continue
        for i, theta in enumerate(thetas):
            for j, s_h in enumerate(s_hs):
                out[k, i, j] = statics.best_wrench(known, theta, s_h, motion, lever, forces).margin
    return out


def of_run(
    obj: PlanarObject,
    start: StartConfig,
    hand: Hand,
    estimate: Estimate | None,
    theta_range: tuple[float, float],
    lever: float,
    forces: tuple[float, float],
    min_margin: float,
    vertex_range: tuple[float, float],
    slide_beyond: float = 0.0,
) -> FeasibilityMap:
    """The maps of a run: estimated at ``estimate`` (the last usable one; None: no estimated map),
    true on ``obj`` as ``start`` placed it, over ``theta_range`` (the robot's reach, rad) and
    ``s_h`` around the estimate's (or the start's); ``lever`` (m) and ``forces`` (N) as the planner
    judges. ``vertex_range`` is where the object stays on its start vertex (rad;
    :func:`ccopt.planning.tour.vertex_range`); an estimated ground slide whose friction face is not
    known is sought ``slide_beyond`` (N) past the sticking forces seen, as the run's planner sought
    it (:func:`ccopt.control.targets.estimated_statics`)."""
    from ccopt import statics
    from ccopt.control.targets import estimated_statics

    truth = statics.true_statics(obj, start, hand)
    usable = estimate is not None and estimate.kinematics_valid
    centre = float(estimate.s_h) if usable else truth.s_h
    thetas, s_hs = grid_around(theta_range, centre)
    if usable:
        angle = float(estimate.theta_o)
        estimated = margins(
            lambda motion: estimated_statics(estimate, angle, motion=motion, push=slide_beyond),
            thetas,
            s_hs,
            lever,
            forces,
        )
        at = (angle, centre)
    else:
        estimated, at = np.full((len(MOTIONS), len(thetas), len(s_hs)), math.nan), (math.nan, math.nan)
    on_face = (s_hs >= truth.s_h_range[0] - 1e-9) & (s_hs <= truth.s_h_range[1] + 1e-9)
    on_vertex = (thetas >= vertex_range[0] - 1e-9) & (thetas <= vertex_range[1] + 1e-9)
    valid = on_vertex[:, None] & on_face[None, :]
    true = margins(lambda motion: truth.statics, thetas, s_hs, lever, forces)
    true[:, ~valid] = math.nan
    names = tuple(motion.value for motion in MOTIONS)
    return FeasibilityMap(thetas, s_hs, names, estimated, true, valid, min_margin, at)


CLIP = 10.0
"""N: the colour scale's end (margins beyond are drawn at it)."""


def draw(fmap: FeasibilityMap, path: str | Path | None = None, title: str = "", dpi: int = 120):
    """A figure: one row per motion, the estimated map beside the true one, margin coloured (green:
    possible with margin, red: not), the planner's margin as a contour, grey where the estimate
    cannot judge or the true configuration does not exist; the estimate's configuration marked.
    Saved to ``path`` if given; returns the :class:`~matplotlib.figure.Figure`."""
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure

    from ccopt.plots import save_png

    rows = len(fmap.motions)
    figure = Figure(figsize=(8.0, 2.0 * rows + 0.8))
    FigureCanvasAgg(figure)
    # not shared: every panel has the grid's extent, and shared axes would pass each panel's limits on
    # to the nine others (a tenth of the figure's time); the inner panels' tick labels hidden instead
    axes = figure.subplots(rows, 2, squeeze=False)
    extent = (
        math.degrees(fmap.theta_o[0]), math.degrees(fmap.theta_o[-1]), 1e3 * fmap.s_h[0], 1e3 * fmap.s_h[-1]
    )
    image = None
    for k, motion in enumerate(fmap.motions):
        for column, (label, values) in enumerate((("estimated", fmap.estimated), ("true", fmap.true))):
            ax = axes[k, column]
            ax.set_facecolor("0.8")
            shown = np.clip(np.where(np.isneginf(values[k]), -CLIP, values[k]), -CLIP, CLIP)
            image = ax.imshow(
                shown.T, origin="lower", extent=extent, aspect="auto", cmap="RdYlGn", vmin=-CLIP, vmax=CLIP
            )
            if np.any(np.isfinite(shown)):
                ax.contour(
                    np.degrees(fmap.theta_o), 1e3 * fmap.s_h, np.nan_to_num(shown, nan=-CLIP).T,
                    levels=[fmap.min_margin], colors="black", linewidths=0.8,
                )
            if math.isfinite(fmap.estimated_at[0]):
                ax.plot(math.degrees(fmap.estimated_at[0]), 1e3 * fmap.estimated_at[1], "k+", markersize=8)
            # y given: where Matplotlib would place it (nothing is above a panel), without measuring
            # every panel's hidden tick labels to find out (a tenth of the figure's time)
            ax.set_title(f"{motion}, {label}", fontsize=9, y=1.0)
            ax.tick_params(labelbottom=k == rows - 1, labelleft=column == 0)
            if column == 0:
                ax.set_ylabel(r"$s_h$ (mm)")
    for ax in axes[-1]:
        ax.set_xlabel(r"$\theta_o$ (deg)")
    figure.colorbar(image, ax=axes, shrink=0.6, label="statics margin (N)")
    figure.suptitle(
        title
        or "Feasibility maps (no paper figure: the paper's future work, §VIII)\n"
        f"statics margin of each motion, estimated (left) vs true (right); black contour at the "
        f"planner's {fmap.min_margin:g} N;\n+ where the estimate was judged (the run's last usable "
        "estimate); grey: not judged (estimate) or no such configuration (true)",
        fontsize=8,
    )
    if path is not None:
        save_png(figure, path, dpi)
    return figure


FIGURE_NAME = "feasibility_map.png"


def write_figure(folder: str | Path, into: str | Path | None = None, dpi: int = 120) -> Path | None:
    """Draw the maps a run folder keeps into ``feasibility_map.png`` of ``into`` (default: the run
    folder); its path, None if the folder keeps no maps."""
    fmap = load(folder)
    if fmap is None:
        return None
    path = Path(folder if into is None else into) / FIGURE_NAME
    draw(fmap, path, dpi=dpi)
    return path
