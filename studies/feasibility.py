"""Which contact configurations can be held — and which motions allowed — for which objects (offline).

    python -m studies feasibility [--mu-hand 0.1:1.0:10] [--theta=-30:30:13] [--mu-ground 0.4,0.8] ...

For one configuration of the reduced model below and one commanded motion (:class:`ccopt.modes.Motion`),
the statics LP of :func:`ccopt.statics.best_wrench` finds the hand wrench with the largest margin (N)
on every cone row the motion keeps, the removed row at its limit, the moments balanced and
``f_min ≤ f_n ≤ f_max``. The configuration is *feasible* when the margin reaches ``min_margin``.

Reduced model (polygon-agnostic)
    The ground contact is at the origin, ``r_o = (0, 0)``; the hand is flush on a face at distance
    ``d`` from it, turned by ``θ_o``, with its centre at ``s_h`` along the face
    (:data:`ccopt.contact.hand_pose_kinematics`). The centre of mass is fixed in the object:
    ``r_com = r_o + com_along e_t(θ_o) − com_height e_n(θ_o)``, i.e. ``com_along`` along the hand face
    and ``com_height`` from the ground contact towards the face. At ``θ_o = 0`` (hand above, pushing
    down) ``com_along`` is the horizontal offset of the centre of mass from the ground contact; its
    height never enters the statics then, but it sets how the offset grows as the object turns. The
    defaults are the paper's triangle (13.4 cm sides, 0.195 kg) standing on a vertex under its top face.

Trials are chunks of the grid (one per ``μ_g × mass × d × s_h`` combination, each covering the
``μ_h × θ_o`` grid and every motion). Output: ``points.csv`` (one row per configuration and motion:
feasible, margin), the runner's ``results.json``/``results.csv``, and one heat-map of the margin over
``μ_h × θ_o`` per chunk (``margin_*.png``).
"""

from __future__ import annotations

import argparse
import csv
import itertools
import math
import sys
from collections.abc import Sequence
from dataclasses import dataclass, fields
from pathlib import Path

import numpy as np

from ccopt import statics
from ccopt.cliutil import fail, print_table
from ccopt.modes import Motion
from studies import runner

MOTIONS: tuple[Motion, ...] = tuple(Motion)


@dataclass(frozen=True)
class FeasibilityParams:
    """One configuration of the reduced model, and what counts as holding it. SI units, hand frame.

    Attributes:
        mu_hand: hand/object friction coefficient ``μ_h``.
        mu_ground: object/ground friction coefficient ``μ_g``.
        mass: object mass, kg.
        d: distance from the ground contact to the hand face along ``e_n``, m.
        theta_o: orientation of the hand face, rad (hand flush: ``θ_h = θ_o``).
        s_h: position of the hand centre along the face, ``(r_o − r_h)·e_t``, m.
        com_along: centre of mass along the face (``e_t``) from the ground contact, m.
        com_height: centre of mass from the ground contact towards the face (``−e_n``), m.
        l_h: half-length of the hand, m (torque rows ``|τ| ≤ l_h f_n``).
        f_min: smallest normal force the hand may press with, N.
        f_max: largest normal force, N.
        min_margin: margin (N) every kept row must have for the configuration to count as held.
    """

    mu_hand: float = 0.5
    mu_ground: float = 0.8
    mass: float = 0.195
    d: float = 0.116
    theta_o: float = 0.0
    s_h: float = 0.0
    com_along: float = 0.0
    com_height: float = 0.077
    l_h: float = 0.05
    f_min: float = 3.0
    f_max: float = 25.0
    min_margin: float = 0.3

    def __post_init__(self) -> None:
        for field in fields(self):
            if not math.isfinite(getattr(self, field.name)):
                raise ValueError(f"{field.name} must be finite, got {getattr(self, field.name)!r}")
        for name in ("mu_hand", "mu_ground", "mass", "l_h"):
            if getattr(self, name) <= 0.0:
                raise ValueError(f"{name} must be positive, got {getattr(self, name)!r}")
        if not 0.0 <= self.f_min <= self.f_max:
            raise ValueError(f"need 0 ≤ f_min ≤ f_max, got {self.f_min}, {self.f_max}")


# --- one grid point ------------------------------------------------------------------------------


def best_wrench(params: FeasibilityParams, motion: Motion) -> tuple[float, np.ndarray | None]:
    """The largest margin ``t`` (N) of ``motion`` at ``params`` and the hand wrench ``(f_n, f_t, τ)``
    achieving it (:func:`ccopt.statics.best_wrench`); ``(-inf, None)`` where none exists."""
    object_statics = statics.ObjectStatics.of_model(
        params.mu_hand, params.mu_ground, params.mass, params.d, params.com_along, params.com_height
    )
    result = statics.best_wrench(
        object_statics, params.theta_o, params.s_h, motion, params.l_h, (params.f_min, params.f_max)
    )
    return result.margin, result.wrench


def is_feasible(params: FeasibilityParams, motion: Motion | str) -> tuple[bool, float]:
    """``(feasible, margin)``: can a hand wrench hold ``params`` while allowing ``motion``, by how much."""
    margin, _ = best_wrench(params, Motion(motion))
    return margin >= params.min_margin, margin


# --- trials ---------------------------------------------------------------------------------------


@dataclass(frozen=True)
class FeasibilityChunk:
    """One trial: the ``μ_h × θ_o`` grid (and every motion) for one set of the other parameters.

    Angles in rad, lengths in m, forces in N. Deterministic: no seed.
    """

    mu_hand: tuple[float, ...]
    theta_o: tuple[float, ...]
    mu_ground: float
    mass: float
    d: float
    s_h: float
    com_along: float
    com_height: float
    l_h: float
    f_min: float
    f_max: float
    min_margin: float

    def params(self, mu_hand: float, theta_o: float) -> FeasibilityParams:
        shared = {f.name: getattr(self, f.name) for f in fields(self) if f.name not in ("mu_hand", "theta_o")}
        return FeasibilityParams(mu_hand=mu_hand, theta_o=theta_o, **shared)


def feasibility_trial(chunk: FeasibilityChunk) -> dict:
    """Margins over ``motion × μ_h × θ_o`` (C order), flattened; ``None`` where nothing exists."""
    margins = [
        best_wrench(chunk.params(mu, theta), motion)[0]
        for motion, mu, theta in itertools.product(MOTIONS, chunk.mu_hand, chunk.theta_o)
    ]
    feasible = [m >= chunk.min_margin for m in margins]
    return {"margin": margins, "n_points": len(margins), "n_feasible": int(sum(feasible))}


def make_chunks(grid: dict[str, tuple[float, ...]], base: FeasibilityParams) -> list[FeasibilityChunk]:
    """One chunk per combination of the ``mu_ground, mass, d, s_h`` values in ``grid``."""
    fixed = {f.name: getattr(base, f.name) for f in fields(FeasibilityParams)}
    chunks = []
    for mu_g, mass, d, s_h in itertools.product(grid["mu_ground"], grid["mass"], grid["d"], grid["s_h"]):
        values = {**fixed, "mu_ground": mu_g, "mass": mass, "d": d, "s_h": s_h}
        values.update(mu_hand=grid["mu_hand"], theta_o=grid["theta_o"])
        chunks.append(FeasibilityChunk(**values))
    return chunks


def margin_grid(chunk: FeasibilityChunk, result: dict) -> np.ndarray:
    """A trial's margins as ``(motion, μ_h, θ_o)``; NaN where no wrench exists."""
    values = [np.nan if m is None else m for m in result["margin"]]
    return np.asarray(values, dtype=float).reshape(len(MOTIONS), len(chunk.mu_hand), len(chunk.theta_o))


# --- output ---------------------------------------------------------------------------------------


def write_points(path: Path, chunks: Sequence[FeasibilityChunk], results: Sequence[dict]) -> None:
    """One CSV row per configuration and motion: the parameters, ``feasible`` (0/1) and ``margin``."""
    names = [f.name for f in fields(FeasibilityParams)]
    with open(path, "w", newline="") as stream:
        writer = csv.writer(stream)
        writer.writerow([*names, "motion", "feasible", "margin"])
        for chunk, result in zip(chunks, results, strict=True):
            if "error" in result:
                continue
            grid = margin_grid(chunk, result)
            for (i, motion), (j, mu), (k, theta) in itertools.product(
                enumerate(MOTIONS), enumerate(chunk.mu_hand), enumerate(chunk.theta_o)
            ):
                params = chunk.params(mu, theta)
                margin = grid[i, j, k]
                feasible = int(bool(margin >= chunk.min_margin))
                writer.writerow([*(getattr(params, n) for n in names), motion.value, feasible, margin])


def heat_map(path: Path, chunk: FeasibilityChunk, result: dict) -> None:
    """The margin over ``μ_h × θ_o`` for every motion, the ``min_margin`` contour in black."""
    from matplotlib.colors import TwoSlopeNorm
    from matplotlib.figure import Figure

    grid = margin_grid(chunk, result)
    finite = grid[np.isfinite(grid)]
    low = min(float(finite.min()), chunk.min_margin - 1e-3) if finite.size else chunk.min_margin - 1.0
    high = max(float(finite.max()), chunk.min_margin + 1e-3) if finite.size else chunk.min_margin + 1.0
    norm = TwoSlopeNorm(vcenter=chunk.min_margin, vmin=low, vmax=high)
    figure = Figure(figsize=(12, 7), layout="constrained")
    axes = figure.subplots(2, 3, sharex=True, sharey=True)
    theta_deg, mu = np.rad2deg(chunk.theta_o), np.asarray(chunk.mu_hand)
    for motion, margins, ax in zip(MOTIONS, grid, axes.flat, strict=True):
        image = ax.pcolormesh(theta_deg, mu, margins, shading="nearest", cmap="RdBu", norm=norm)
        if len(theta_deg) > 1 and len(mu) > 1 and np.nanmin(margins) < chunk.min_margin < np.nanmax(margins):
            ax.contour(theta_deg, mu, margins, levels=[chunk.min_margin], colors="k", linewidths=1.2)
        ax.set_title(motion.value)
    for ax in axes[-1]:
        ax.set_xlabel("θ_o (deg)")
    for ax in axes[:, 0]:
        ax.set_ylabel("μ_h")
    figure.colorbar(image, ax=axes, label=f"margin (N); feasible ≥ {chunk.min_margin:g}")
    figure.suptitle(
        f"μ_g={chunk.mu_ground:g}  m={chunk.mass:g} kg  d={chunk.d * 1e3:g} mm  s_h={chunk.s_h * 1e3:g} mm  "
        f"f_n∈[{chunk.f_min:g}, {chunk.f_max:g}] N"
    )
    figure.savefig(path, dpi=110)


def summarise(chunks: Sequence[FeasibilityChunk], results: Sequence[dict]) -> dict:
    """Share of feasible configurations and the best margin, per motion, over the whole grid."""
    grids = [margin_grid(c, r) for c, r in zip(chunks, results, strict=True) if "error" not in r]
    if not grids:
        return {"motions": {}, "failed_trials": len(results)}
    per_motion = np.concatenate([g.reshape(len(MOTIONS), -1) for g in grids], axis=1)
    min_margin = chunks[0].min_margin
    return {
        "motions": {
            motion.value: {
                "points": int(values.size),
                "feasible": int(np.sum(values >= min_margin)),
                "best_margin": float(np.nanmax(values)) if np.any(np.isfinite(values)) else None,
            }
            for motion, values in zip(MOTIONS, per_motion, strict=True)
        },
        "failed_trials": len(runner.failures(results)),
    }


# --- command line ---------------------------------------------------------------------------------


def grid_values(value: str) -> tuple[float, ...]:
    """argparse type: ``a,b,c`` or ``start:stop:count`` (inclusive, evenly spaced) → floats."""
    try:
        if ":" in value:
            start, stop, count = value.split(":")
            if int(count) < 1:
                raise ValueError
            numbers = np.linspace(float(start), float(stop), int(count))
        else:
            numbers = np.array([float(v) for v in value.split(",")])
    except ValueError:
        raise argparse.ArgumentTypeError(f"{value!r} is not 'a,b,c' or 'start:stop:count'") from None
    if numbers.size == 0 or not np.all(np.isfinite(numbers)):
        raise argparse.ArgumentTypeError(f"{value!r} must be finite numbers")
    return tuple(float(v) for v in np.round(numbers, 12))  # 0.30000000000000004 → 0.3


def make_parser() -> argparse.ArgumentParser:
    description = (
        __doc__.split("\n")[0] + " LIST is a,b,c or start:stop:count (write --theta=-30:30:13 for a"
        " leading minus). Deterministic: --seed has no effect."
    )
    parser = runner.study_parser("feasibility", description)

    def grid(flag: str, default: str, what: str) -> None:
        parser.add_argument(
            flag,
            type=grid_values,
            default=grid_values(default),
            metavar="LIST",
            help=f"{what} (default: {default})",
        )

    def number(flag: str, default: float, what: str) -> None:
        parser.add_argument(
            flag, type=float, default=default, metavar="X", help=f"{what} (default: {default:g})"
        )

    grid("--mu-hand", "0.1:1.0:10", "μ_h values")
    grid("--theta", "-30:30:13", "θ_o values, deg")
    grid("--mu-ground", "0.4,0.8", "μ_g values")
    grid("--mass", "0.195,0.695", "object masses, kg")
    grid("--d", "116", "ground contact to hand face, mm")
    grid("--s-hand", "0", "hand position along the face s_h, mm")
    grid("--force-limits", "3,25", "f_min,f_max, N")
    number("--com-along", 0.0, "centre of mass along the face, mm")
    number("--com-height", 77.0, "centre of mass from the ground contact towards the face, mm")
    number("--l-hand", 50.0, "hand half-length l_h, mm")
    number("--min-margin", 0.3, "margin every kept row needs for a configuration to count as held, N")
    return parser


def _base_params(args: argparse.Namespace, prog: str) -> FeasibilityParams:
    for flag, values in (("--mu-hand", args.mu_hand), ("--mu-ground", args.mu_ground), ("--mass", args.mass)):
        if min(values) <= 0.0:
            fail(prog, f"{flag} values must be positive, got {min(values):g}")
    if len(args.force_limits) != 2:
        fail(prog, f"--force-limits needs two values f_min,f_max, got {len(args.force_limits)}")
    try:
        return FeasibilityParams(
            com_along=args.com_along * 1e-3,
            com_height=args.com_height * 1e-3,
            l_h=args.l_hand * 1e-3,
            f_min=args.force_limits[0],
            f_max=args.force_limits[1],
            min_margin=args.min_margin,
        )
    except ValueError as error:
        fail(prog, str(error))


def main(argv: Sequence[str] | None = None) -> int:
    parser = make_parser()
    args = parser.parse_args(argv)
    base = _base_params(args, parser.prog)
    grid = {
        "mu_hand": args.mu_hand,
        "theta_o": tuple(float(np.deg2rad(v)) for v in args.theta),
        "mu_ground": args.mu_ground,
        "mass": args.mass,
        "d": tuple(v * 1e-3 for v in args.d),
        "s_h": tuple(v * 1e-3 for v in args.s_hand),
    }
    chunks = make_chunks(grid, base)
    options = runner.RunOptions.from_args(args)
    results = runner.run_study(parser.prog, feasibility_trial, chunks, options)
    summary = summarise(chunks, results)
    runner.write_results(options.out, chunks, results, summary)
    write_points(options.out / "points.csv", chunks, results)
    for k, (chunk, result) in enumerate(zip(chunks, results, strict=True)):
        if "error" not in result:
            heat_map(options.out / f"margin_{k:03d}.png", chunk, result)
    rows = [
        (
            name,
            str(s["points"]),
            str(s["feasible"]),
            "-" if s["best_margin"] is None else f"{s['best_margin']:.2f}",
        )
        for name, s in summary["motions"].items()
    ]
    print_table(rows, ("motion", "points", "feasible", "best margin (N)"))
    for k, message in runner.failures(results):
        print(f"trial {k} failed: {message}")
    print(f"results in {options.out}")
    return 0 if not runner.failures(results) else 1


if __name__ == "__main__":
    sys.exit(main())
