"""Which contact configurations can be held — and which motions allowed — for which objects (offline).

    ccopt study feasibility [--mu-hand 0.1:1.0:10] [--theta=-30:30:13] [--mu-ground 0.4,0.8] ...

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


# --- trials ---------------------------------------------------------------------------------------


@dataclass(frozen=True)
class FeasibilityChunk:
    """One trial: the ``μ_h × θ_o`` grid (and every motion) for one set of the other parameters.

    Angles in rad, lengths in m, forces in N. Deterministic: no seed.

    Attributes:
        mu_hand: the hand friction coefficients ``μ_h`` of the grid.
        theta_o: the orientations of the hand face of the grid, rad (hand flush: ``θ_h = θ_o``).
        mu_ground: object/ground friction coefficient ``μ_g``.
        mass: object mass, kg.
        d: distance from the ground contact to the hand face along ``e_n``, m.
        s_h: position of the hand centre along the face, ``(r_o − r_h)·e_t``, m.
        com_along: centre of mass along the face (``e_t``) from the ground contact, m.
        com_height: centre of mass from the ground contact towards the face (``−e_n``), m.
        l_h: half-length of the hand, m (torque rows ``|τ| ≤ l_h f_n``).
        force_limits: the normal force's ``(f_min, f_max)``, N.
        min_margin: margin (N) every kept row must have for the configuration to count as held.
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
    force_limits: tuple[float, float]
    min_margin: float

    def margin(self, mu_hand: float, theta_o: float, motion: Motion) -> float:
        """The statics LP's margin (N) of ``motion`` at one grid point (:func:`ccopt.statics.best_wrench`)."""
        known = statics.ObjectStatics.of_model(
            mu_hand, self.mu_ground, self.mass, self.d, self.com_along, self.com_height
        )
        return statics.best_wrench(known, theta_o, self.s_h, motion, self.l_h, self.force_limits).margin


def feasibility_trial(chunk: FeasibilityChunk) -> dict:
    """Margins over ``motion × μ_h × θ_o`` (C order), flattened; ``None`` where nothing exists."""
    margins = [
        chunk.margin(mu, theta, motion)
        for motion, mu, theta in itertools.product(MOTIONS, chunk.mu_hand, chunk.theta_o)
    ]
    feasible = [m >= chunk.min_margin for m in margins]
    return {"margin": margins, "n_points": len(margins), "n_feasible": int(sum(feasible))}


def make_chunks(grid: dict[str, tuple[float, ...]], fixed: dict[str, object]) -> list[FeasibilityChunk]:
    """One chunk per combination of the ``mu_ground, mass, d, s_h`` values in ``grid``; ``fixed`` holds
    the other fields."""
    chunks = []
    for mu_g, mass, d, s_h in itertools.product(grid["mu_ground"], grid["mass"], grid["d"], grid["s_h"]):
        values = {**fixed, "mu_ground": mu_g, "mass": mass, "d": d, "s_h": s_h}
        chunks.append(FeasibilityChunk(mu_hand=grid["mu_hand"], theta_o=grid["theta_o"], **values))
    return chunks


def margin_grid(chunk: FeasibilityChunk, result: dict) -> np.ndarray:
    """A trial's margins as ``(motion, μ_h, θ_o)``; NaN where no wrench exists."""
    values = [np.nan if m is None else m for m in result["margin"]]
    return np.asarray(values, dtype=float).reshape(len(MOTIONS), len(chunk.mu_hand), len(chunk.theta_o))


# --- output ---------------------------------------------------------------------------------------


def write_points(path: Path, chunks: Sequence[FeasibilityChunk], results: Sequence[dict]) -> None:
    """One CSV row per configuration and motion: the parameters, ``feasible`` (0/1) and ``margin``."""
    names = [f.name for f in fields(FeasibilityChunk) if f.name != "force_limits"]
    with open(path, "w", newline="") as stream:
        writer = csv.writer(stream)
        writer.writerow([*names, "f_min", "f_max", "motion", "feasible", "margin"])
        for chunk, result in zip(chunks, results, strict=True):
            if "error" in result:
                continue
            grid = margin_grid(chunk, result)
            for (i, motion), (j, mu), (k, theta) in itertools.product(
                enumerate(MOTIONS), enumerate(chunk.mu_hand), enumerate(chunk.theta_o)
            ):
                point = {**{n: getattr(chunk, n) for n in names}, "mu_hand": mu, "theta_o": theta}
                margin = grid[i, j, k]
                feasible = int(bool(margin >= chunk.min_margin))
                limits = chunk.force_limits
                writer.writerow([*(point[n] for n in names), *limits, motion.value, feasible, margin])


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
        f"statics margin (no paper figure): μ_g={chunk.mu_ground:g}  m={chunk.mass:g} kg  "
        f"d={chunk.d * 1e3:g} mm  s_h={chunk.s_h * 1e3:g} mm  "
        f"f_n∈[{chunk.force_limits[0]:g}, {chunk.force_limits[1]:g}] N"
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


GRID_FLAGS = {
    "--mu-hand": "μ_h values",
    "--theta": "θ_o values, deg",
    "--mu-ground": "μ_g values",
    "--mass": "object masses, kg",
    "--d": "ground contact to hand face, mm",
    "--s-hand": "hand position along the face s_h, mm",
    "--force-limits": "f_min,f_max, N",
}
FULL = {
    "--mu-hand": "0.1:1.0:10",
    "--theta": "-30:30:13",
    "--mu-ground": "0.4,0.8",
    "--mass": "0.195,0.695",
    "--d": "116",
    "--s-hand": "0",
    "--force-limits": "3,25",
}
QUICK = {**FULL, "--mu-hand": "0.3,0.7", "--theta": "-20,0,20", "--mu-ground": "0.8", "--mass": "0.195"}
"""The grid flags' values by default and with ``--quick``."""


def make_parser() -> argparse.ArgumentParser:
    description = (
        __doc__.split("\n")[0] + " LIST is a,b,c or start:stop:count (write --theta=-30:30:13 for a"
        " leading minus). Deterministic: --seed has no effect."
    )
    parser = runner.study_parser(
        "feasibility", description, "a 2 × 3 grid of μ_h × θ_o at one μ_g and one mass (unless given)"
    )

    def grid(flag: str, default: str, what: str) -> None:
        parser.add_argument(flag, type=grid_values, metavar="LIST", help=f"{what} (default: {default})")

    def number(flag: str, default: float, what: str) -> None:
        parser.add_argument(
            flag, type=float, default=default, metavar="X", help=f"{what} (default: {default:g})"
        )

    for flag, what in GRID_FLAGS.items():
        grid(flag, FULL[flag], what)
    number("--com-along", 0.0, "centre of mass along the face, mm")
    number("--com-height", 77.0, "centre of mass from the ground contact towards the face, mm")
    number("--l-hand", 50.0, "hand half-length l_h, mm")
    number("--min-margin", 0.3, "margin every kept row needs for a configuration to count as held, N")
    return parser


def _fixed(args: argparse.Namespace, prog: str) -> dict[str, object]:
    """The chunk fields that do not vary over the grid, checked (one line and exit 2 on a bad value)."""
    for flag, values in (("--mu-hand", args.mu_hand), ("--mu-ground", args.mu_ground), ("--mass", args.mass)):
        if min(values) <= 0.0:
            fail(prog, f"{flag} values must be positive, got {min(values):g}")
    if len(args.force_limits) != 2 or not 0.0 <= args.force_limits[0] <= args.force_limits[1]:
        fail(prog, f"--force-limits needs two values 0 ≤ f_min ≤ f_max, got {args.force_limits}")
    if not args.l_hand > 0.0:
        fail(prog, f"--l-hand must be positive, got {args.l_hand:g}")
    return {
        "com_along": args.com_along * 1e-3,
        "com_height": args.com_height * 1e-3,
        "l_h": args.l_hand * 1e-3,
        "force_limits": tuple(args.force_limits),
        "min_margin": args.min_margin,
    }


def main(argv: Sequence[str] | None = None) -> int:
    parser = make_parser()
    args = parser.parse_args(argv)
    for flag, value in (QUICK if args.quick else FULL).items():
        name = flag[2:].replace("-", "_")
        if getattr(args, name) is None:
            setattr(args, name, grid_values(value))
    fixed = _fixed(args, parser.prog)
    grid = {
        "mu_hand": args.mu_hand,
        "theta_o": tuple(float(np.deg2rad(v)) for v in args.theta),
        "mu_ground": args.mu_ground,
        "mass": args.mass,
        "d": tuple(v * 1e-3 for v in args.d),
        "s_h": tuple(v * 1e-3 for v in args.s_hand),
    }
    chunks = make_chunks(grid, fixed)
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
