"""Perturbation rejection (paper §VII, Fig. 9): push a regulated object and watch the error recover.

    ccopt study perturbation [--forces 5,10,14] [--duration 0.15] [--object paper-triangle]

For each regulation (:func:`regulations`), push direction (``+x``, ``−x``) and push size, one
closed-loop run holds a coordinate at its value while an external horizontal force
(:class:`ccopt.closed_loop.Perturbation`) acts on the object's centroid for ``--duration`` s from
``--push-at`` s. The schedule is a single step of the coordinate's motion — a pivot for ``θ_o``, a
hand slide for ``s_h``, a ground slide for ``s_g``, each slide held once in the positive and once in
the negative direction — whose increment (±1e-9 rad or m) and tolerance (1e-12) are far below the
sensor noise, so the step never ends and the controller regulates the coordinate at its value when
the run began, under that contact mode.

The default sizes (5, 10, 14 N for 0.15 s) are chosen for the paper triangle: a horizontal push at its
centroid pivots it and slips the hand; only above ≈ 13 N does the ground contact slide as well (the
object then slides in ``+x``; a ``−x`` push of these sizes never slides it), and from ≈ 15 N the push
knocks it out of the hand in some modes.

Scored against truth: the error of the regulated coordinate, its true value minus its value just
before the push (deg, mm); it *recovers* when it is back within ``0.5°`` / ``1 mm`` and stays there
to the end of the run (``--window`` s after the push starts); the recovery time is counted from the
push's start (0 when the push never moved it out of tolerance: ``perturbed`` false).

Which pushes cannot recover, and why (the ``why`` column):

* ``held mode``: a held slide lets the contact move only in its direction, so an error left the
  same way cannot be removed (the paper: ground sliding regulation "can only correct perturbations
  in one direction"); ``back allowed`` says whether the held mode allows the motion that would remove
  the error left at the end (elastic excursions during the push return by themselves either way);
* ``hand, not object``: before the kinematics are estimated the closed loop measures progress on the
  hand's own motion (``θ_h``, ``−r_h·e_t``, ``x_h``; see :mod:`ccopt.closed_loop`). That equals the
  coordinate only while the commanded configuration holds; a push that makes the hand slip on the
  object moves the object without the hand, and the controller returns the hand, not the object.
  The ``measured final`` column is the error the controller saw at the end;
* ``contact lost``: the push knocked the object out of the hand;
* ``not settled``: none of the above, still outside tolerance at the end.

``held mode`` and ``hand, not object`` can both apply (joined by ``;``).

Outputs in ``<out>``: ``results.json`` (traces included), ``results.csv`` (flat, no traces) and
``perturbation.png`` (error traces per regulation and push direction, grey during the push, like Fig. 9).
"""

from __future__ import annotations

import argparse
import itertools
import sys
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from ccopt import closed_loop, metrics, modes
from ccopt.cliutil import fail, print_table
from ccopt.closed_loop import LoopParams, Perturbation
from ccopt.objects import OBJECT_NAMES, make_object
from ccopt.schedule import Schedule, Step
from studies import runner
from studies.runner import cell, finished

TOLERANCE = (np.deg2rad(0.5), 1e-3, 1e-3)
"""Recovered means back within this of the pre-push value, rad, m, m."""
SCALE = (float(np.rad2deg(1.0)), 1e3, 1e3)
UNIT = ("deg", "mm", "mm")
VANISHING = 1e-9
"""Increment of the regulation step, rad or m: a set point, not a motion."""
BEFORE = 0.25
"""The stored traces start this long before the push, s."""


@dataclass(frozen=True)
class Push:
    """One run: regulate ``coordinate`` holding the slide in direction ``held`` (±1; +1 for ``θ_o``),
    push the object's centroid with ``force`` N along ``direction`` × x for ``duration`` s from
    ``push_at`` s; the run ends ``window`` s after the push starts. ``seed`` seeds the sensor noise."""

    coordinate: str
    held: int
    direction: int
    force: float
    duration: float
    push_at: float
    window: float
    object: str
    plant: str
    seed: int


def regulations(coordinates: Sequence[str]) -> list[tuple[str, int]]:
    """``(coordinate, held slide direction)`` to study: ``θ_o`` once, each slide both ways."""
    return [(c, held) for c in coordinates for held in ((1,) if c == "theta_o" else (1, -1))]


def regulation_label(coordinate: str, held: int) -> str:
    """``θ_o (pivot)``, ``s_g (slide_ground+)``, ..."""
    sign = "" if coordinate == "theta_o" else ("+" if held > 0 else "−")
    return f"{coordinate} ({modes.driving_kind(coordinate)}{sign})"


def regulation_schedule(coordinate: str, held: int, seconds: float) -> Schedule:
    """One step that holds ``coordinate`` at its starting value for ``seconds`` (see the docstring)."""
    step = Step(modes.driving_kind(coordinate), held * VANISHING, 1e-3 * VANISHING, seconds)
    return Schedule(f"regulate-{coordinate}", (step,))


def signed_peak(values: np.ndarray) -> float:
    """The value of largest magnitude (NaN ignored; 0 for no values)."""
    finite = values[np.isfinite(values)]
    return float(finite[np.argmax(np.abs(finite))]) if finite.size else 0.0


def measured_coordinates(samples: Mapping[str, np.ndarray], use_estimate: bool) -> np.ndarray:
    """What the controller measured progress on: the estimate, or the hand proxy of the measured pose."""
    if use_estimate:
        return samples["est_coordinates"]
    return np.array([closed_loop.hand_proxy(pose) for pose in samples["hand_pose"]])


def perturbation_trial(spec: Push) -> dict:
    """Regulate, push, and score the error of the regulated coordinate (deg or mm in the result)."""
    k = modes.COORDINATES.index(spec.coordinate)
    push = Perturbation(spec.push_at, (spec.direction * spec.force, 0.0), spec.duration)
    params = LoopParams(plant=spec.plant, perturbations=(push,))
    schedule = regulation_schedule(spec.coordinate, spec.held, spec.push_at + spec.window)
    result = finished(closed_loop.run(make_object(spec.object), schedule, params, seed=spec.seed))
    samples = result.samples
    time = samples["time"] - spec.push_at
    before = max(int(np.searchsorted(time, 0.0)) - 1, 0)
    start = min(int(np.searchsorted(samples["time"], result.steps[0].start_time)), len(time) - 1)
    use_estimate = bool(samples["est_kinematics_valid"][start])
    truth = metrics.coordinate_changes(samples["true_coordinates"], samples["true_coordinates"][before])
    seen = measured_coordinates(samples, use_estimate)
    measured = metrics.coordinate_changes(seen, seen[before])
    after = time >= 0.0
    rejoined = metrics.recovery_time(time, truth[:, k], TOLERANCE[k])
    contact_kept = bool(np.all(samples["true_contacts"][after]))
    shown = time >= -BEFORE
    slid_hand, slid_ground = metrics.slip_distance(time[after], samples["true_slip_rates"][after])
    peaks = {
        f"peak_{name}_{UNIT[j]}": signed_peak(truth[after, j]) * SCALE[j]
        for j, name in enumerate(modes.COORDINATES)
    }
    return {
        "unit": UNIT[k],
        "tolerance": TOLERANCE[k] * SCALE[k],
        "peak_error": peaks[f"peak_{spec.coordinate}_{UNIT[k]}"],
        "final_error": float(truth[-1, k]) * SCALE[k],
        "perturbed": bool(np.nanmax(np.abs(truth[after, k])) > TOLERANCE[k]),
        "recovered": contact_kept and rejoined is not None,
        "recovery_time_s": rejoined if contact_kept else None,
        "back_allowed": spec.coordinate == "theta_o" or spec.held * float(truth[-1, k]) <= 0.0,
        "measured_final_error": float(measured[-1, k]) * SCALE[k],
        "progress_source": "estimate" if use_estimate else "hand",
        "contact_kept": contact_kept,
        "slid_hand_mm": float(slid_hand) * 1e3,
        "slid_ground_mm": float(slid_ground) * 1e3,
        **peaks,
        "trace_time": time[shown].round(4).tolist(),
        "trace_error": (truth[shown, k] * SCALE[k]).tolist(),
        "trace_measured": (measured[shown, k] * SCALE[k]).tolist(),
    }


def why_not_recovered(result: Mapping[str, object]) -> str | None:
    """Why a perturbed coordinate did not recover (see the module docstring; several reasons are
    joined by ``;``), else None."""
    if "error" in result:
        return "run error"
    if result["recovered"]:
        return None
    if not result["contact_kept"]:
        return "contact lost"
    reasons = [] if result["back_allowed"] else ["held mode"]
    if abs(result["measured_final_error"]) <= result["tolerance"]:
        reasons.append("hand, not object" if result["progress_source"] == "hand" else "estimate, not truth")
    return "; ".join(reasons) or "not settled"


# --- output ---------------------------------------------------------------------------------------


def push_label(spec: Push) -> str:
    return f"{'+' if spec.direction > 0 else '−'}x {spec.force:g} N {spec.duration:g} s"


def summarise(specs: Sequence[Push], results: Sequence[dict]) -> dict:
    """Counts of perturbed and recovered pushes, and why each of the others did not recover."""
    ran = [r for r in results if "error" not in r]
    return {
        "pushes": len(results),
        "perturbed": sum(r["perturbed"] for r in ran),
        "recovered": sum(r["recovered"] for r in ran if r["perturbed"]),
        "not_recovered": [
            {
                "regulation": regulation_label(s.coordinate, s.held),
                "push": push_label(s),
                "why": why_not_recovered(r),
            }
            for s, r in zip(specs, results, strict=True)
            if why_not_recovered(r) is not None
        ],
        "errors": dict(runner.failures(results)),
    }


def table_rows(specs: Sequence[Push], results: Sequence[dict]) -> list[tuple[str, ...]]:
    rows = []
    for spec, r in zip(specs, results, strict=True):
        if "error" in r:
            rows.append(
                (
                    regulation_label(spec.coordinate, spec.held),
                    push_label(spec),
                    "ERROR",
                    *[""] * 7,
                    r["error"],
                )
            )
            continue
        recovered = "yes" if r["recovered"] else "no"
        rows.append(
            (
                regulation_label(spec.coordinate, spec.held),
                push_label(spec),
                f"{cell(r['peak_error'])} {r['unit']}",
                cell(r["final_error"]),
                recovered if r["perturbed"] else f"{recovered} (not perturbed)",
                cell(r["recovery_time_s"]),
                ("yes" if r["back_allowed"] else "no") if r["perturbed"] else "-",
                cell(r["measured_final_error"]),
                f"{cell(r['slid_hand_mm'], 1)} / {cell(r['slid_ground_mm'], 1)}",
                " / ".join(
                    cell(r[f"peak_{name}_{unit}"]) for name, unit in zip(modes.COORDINATES, UNIT, strict=True)
                ),
                why_not_recovered(r) or "-",
            )
        )
    return rows


HEADER = (
    "regulated",
    "push",
    "peak",
    "final",
    "recovered",
    "t_rec (s)",
    "back allowed",
    "measured final",
    "slid h/g (mm)",
    "true peaks θ/s_h/s_g",
    "why",
)


def _trace(values: list) -> np.ndarray:
    return np.array([np.nan if v is None else v for v in values], dtype=float)


def _draw_panel(ax, runs: Sequence[tuple[Push, dict]], tolerance: float, styles: dict[float, str]) -> None:
    """One regulation and push direction: a line per push size, the push interval and the tolerance."""
    limit = 3.0 * tolerance
    for spec, r in runs:
        time, error = np.array(r["trace_time"]), _trace(r["trace_error"])
        pushed = (time >= 0.0) & (time <= spec.duration)
        style = styles[spec.force]
        ax.plot(time, error, color="black", ls=style, lw=1.2, label=f"{spec.force:g} N")
        ax.plot(time[pushed], error[pushed], color="0.6", ls=style, lw=2.0)
        ax.plot(time, _trace(r["trace_measured"]), color="tab:blue", ls=style, lw=0.8, alpha=0.7)
        ax.axvspan(0.0, spec.duration, color="0.92", zorder=0)
        if r["contact_kept"]:
            limit = max(limit, 1.2 * float(np.nanmax(np.abs(error))))
    for level in (-tolerance, tolerance):
        ax.axhline(level, color="0.5", ls=":", lw=0.8)
    ax.set_ylim(-min(limit, 20.0 * tolerance), min(limit, 20.0 * tolerance))
    if runs:
        ax.legend(loc="upper right", fontsize="small")


def write_figure(path: Path, specs: Sequence[Push], results: Sequence[dict]) -> None:
    """Truth error (black, grey while pushed) and the error the controller measured (blue) per
    regulation and push direction; line style by push size; dotted: the tolerance (Fig. 9)."""
    from matplotlib.figure import Figure

    rows = list(dict.fromkeys((s.coordinate, s.held) for s in specs))
    styles = dict(
        zip(sorted({s.force for s in specs}), itertools.cycle(("-", "--", ":", "-.")), strict=False)
    )
    figure = Figure(figsize=(10, 2.3 * len(rows) + 0.6), layout="constrained")
    axes = figure.subplots(len(rows), 2, sharex=True, squeeze=False)
    for (coordinate, held), pair in zip(rows, axes, strict=True):
        k = modes.COORDINATES.index(coordinate)
        for direction, ax in zip((1, -1), pair, strict=True):
            runs = [
                (s, r)
                for s, r in zip(specs, results, strict=True)
                if (s.coordinate, s.held, s.direction) == (coordinate, held, direction) and "error" not in r
            ]
            _draw_panel(ax, runs, TOLERANCE[k] * SCALE[k], styles)
            ax.set_title(f"{regulation_label(coordinate, held)}, push {'+' if direction > 0 else '−'}x")
            ax.set_ylabel(f"error ({UNIT[k]})")
    for ax in axes[-1]:
        ax.set_xlabel("time from push start (s)")
    figure.suptitle(
        "Fig. 9: true error of the regulated coordinate (black; grey: pushed) and measured (blue)"
    )
    figure.savefig(path, dpi=110)


# --- command line ---------------------------------------------------------------------------------


def positive_float(value: str) -> float:
    """argparse type: a finite number > 0."""
    try:
        number = float(value)
    except ValueError:
        raise argparse.ArgumentTypeError(f"{value!r} is not a number") from None
    if not (np.isfinite(number) and number > 0.0):
        raise argparse.ArgumentTypeError(f"{value!r} must be a positive number")
    return number


def force_list(value: str) -> tuple[float, ...]:
    """argparse type: ``a,b,c`` positive forces, N."""
    return tuple(positive_float(v) for v in value.split(","))


def coordinate_list(value: str) -> tuple[str, ...]:
    """argparse type: a comma-separated subset of :data:`modes.COORDINATES`."""
    names = tuple(v.strip() for v in value.split(","))
    unknown = [n for n in names if n not in modes.COORDINATES]
    if unknown:
        raise argparse.ArgumentTypeError(
            f"unknown coordinate {unknown[0]!r}; expected {', '.join(modes.COORDINATES)}"
        )
    return names


FULL = {"coordinates": modes.COORDINATES, "forces": (5.0, 10.0, 14.0), "window": 4.0}
QUICK = {"coordinates": ("theta_o",), "forces": (5.0,), "window": 1.5}
"""The regulated coordinates, push sizes (N) and window (s) a study runs by default, and with ``--quick``."""


def make_parser() -> argparse.ArgumentParser:
    parser = runner.study_parser(
        "perturbation",
        __doc__.split("\n")[0],
        "θ_o regulated against one 5 N push each way, 1.5 s after it (unless given otherwise)",
    )
    parser.add_argument("--object", default="paper-triangle", help="library object (default: paper-triangle)")
    parser.add_argument("--plant", choices=("planar", "panda"), default="planar", help="default: planar")
    parser.add_argument(
        "--coordinates",
        type=coordinate_list,
        metavar="LIST",
        help="regulated coordinates (default: theta_o,s_h,s_g)",
    )
    parser.add_argument(
        "--forces",
        type=force_list,
        metavar="LIST",
        help="push sizes, N (default: 5,10,14)",
    )
    parser.add_argument(
        "--duration", type=positive_float, default=0.15, metavar="S", help="push duration, s (default: 0.15)"
    )
    parser.add_argument(
        "--push-at", type=positive_float, default=1.0, metavar="S", help="push start, s (default: 1)"
    )
    parser.add_argument(
        "--window",
        type=positive_float,
        metavar="S",
        help="run on after the push starts, s (default: 4)",
    )
    return parser


def main(argv: Sequence[str] | None = None) -> int:
    parser = make_parser()
    args = parser.parse_args(argv)
    for name, value in (QUICK if args.quick else FULL).items():
        if getattr(args, name) is None:
            setattr(args, name, value)
    if args.object not in OBJECT_NAMES:
        fail(parser.prog, f"unknown object {args.object!r}; valid names: {', '.join(OBJECT_NAMES)}")
    if args.duration >= args.window:
        fail(
            parser.prog, f"--duration ({args.duration:g} s) must be shorter than --window ({args.window:g} s)"
        )
    specs = [
        Push(c, held, d, f, args.duration, args.push_at, args.window, args.object, args.plant, args.seed)
        for c, held in regulations(args.coordinates)
        for d in (1, -1)
        for f in args.forces
    ]
    options = runner.RunOptions.from_args(args)
    results = runner.run_study(parser.prog, perturbation_trial, specs, options)
    summary = summarise(specs, results)
    runner.write_results(options.out, specs, results, summary)
    write_figure(options.out / "perturbation.png", specs, results)
    print_table(table_rows(specs, results), HEADER)
    print(
        f"{summary['recovered']}/{summary['perturbed']} perturbed pushes recovered; results in {options.out}"
    )
    return 0 if not runner.failures(results) else 1


if __name__ == "__main__":
    sys.exit(main())
