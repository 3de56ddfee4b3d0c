"""Latency of one ``Estimator.update``, as a user calls it from Python.

    python -m benchmarks.estimator_speed [--quick] [--json PATH] [--seed N]

The stream is synthetic but walks through the estimator's code paths as a run does, at 1 kHz: the
hand slides both ways and the known object slides on the ground both ways (exploring the cone),
then it pivots about its ground contact, the hand slides and the object slides on the ground; the
measured pose and wrench carry sensor noise (0.2 mm, 0.1°, 0.3 N, 0.005 N·m). Every sample's wall
time is recorded (after a warm-up pass of another estimator over the first samples).
"""

from __future__ import annotations

import time
from collections.abc import Sequence

import numpy as np

from ccopt import contact, geometry
from ccopt.cliutil import benchmark_parser, print_table, write_json
from ccopt.estimation import Estimator

RATE = 1000.0
"""Sample rate of the synthetic stream (Hz)."""
MU_H, MU_G, MASS, D, L_H = 0.5, 0.8, 0.3, 0.06, 0.05
PHASES = ("explore hand", "explore ground", "pivot", "hand slide", "ground slide")
"""Equal parts of the stream: the cone is explored first (sliding both ways), as in a run."""


def synthetic_stream(samples: int, seed: int) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """``(times (n), hand poses (n×3), hand wrenches (n×3), phase index (n))`` of a known object."""
    rng = np.random.default_rng(seed)
    times = np.arange(samples) / RATE
    phase = np.minimum((np.arange(samples) * len(PHASES)) // samples, len(PHASES) - 1)
    weight = contact.weight(MASS)
    poses, wrenches = np.empty((samples, 3)), np.empty((samples, 3))
    r_o, s_h = np.array([0.10, 0.0]), 0.01
    for k, t in enumerate(times):
        swing = np.sin(2.0 * np.pi * t / 0.5)
        direction = 1.0 if swing >= 0.0 else -1.0
        f_n = 10.0 + 4.0 * np.sin(2.0 * np.pi * t / 0.37)
        name, theta = PHASES[phase[k]], 0.0
        wrench = np.array([f_n, 0.2 * MU_H * f_n * swing, 0.2 * L_H * f_n * swing])
        if name in ("explore hand", "hand slide"):
            s_h += direction * 0.02 / RATE
            wrench[1] = -direction * MU_H * f_n
        elif name in ("explore ground", "ground slide"):  # the hand pushes along the ground cone's face
            push = float(np.clip(3.0 * swing, -1.0, 1.0))
            r_o = r_o + np.array([0.02 / RATE * push * (abs(push) == 1.0), 0.0])
            force = np.array([MU_G * (f_n - weight[1]) * push, -f_n])
            theta = float(np.arctan2(force[0], -force[1]))  # e_n along the force: no tangential force
            wrench = geometry.wrench_world_to_hand(theta, [*force, 0.0])
        else:
            theta = np.deg2rad(8.0) * np.sin(2.0 * np.pi * t / 2.0)
        poses[k] = geometry.hand_pose_from_contact(theta, s_h, D, r_o)
        wrenches[k] = wrench
    poses += rng.normal(0.0, [2e-4, 2e-4, np.deg2rad(0.1)], poses.shape)
    wrenches += rng.normal(0.0, [0.3, 0.3, 0.005], wrenches.shape)
    return times, poses, wrenches, phase


def time_updates(times: np.ndarray, poses: np.ndarray, wrenches: np.ndarray) -> np.ndarray:
    """Wall time (µs) of each ``update`` of a fresh estimator over the stream, after a warm-up."""
    warm_up = Estimator()
    for k in range(min(200, len(times))):
        warm_up.update(times[k], poses[k], wrenches[k])
    estimator = Estimator()
    elapsed = np.empty(len(times))
    for k in range(len(times)):
        start = time.perf_counter_ns()
        estimator.update(times[k], poses[k], wrenches[k])
        elapsed[k] = (time.perf_counter_ns() - start) * 1e-3
    return elapsed


def run(samples: int, seed: int) -> dict[str, float | int]:
    times, poses, wrenches, phase = synthetic_stream(samples, seed)
    elapsed = time_updates(times, poses, wrenches)
    figures: dict[str, float | int] = {
        "samples": samples,
        "update_median_us": float(np.median(elapsed)),
        "update_p99_us": float(np.percentile(elapsed, 99)),
        "update_mean_us": float(np.mean(elapsed)),
        "update_max_us": float(np.max(elapsed)),
    }
    names = np.array(PHASES)[phase]
    for name in dict.fromkeys(PHASES):
        figures[_key(name)] = float(np.median(elapsed[names == name]))
    return figures


def _key(phase: str) -> str:
    return f"{phase.replace(' ', '_')}_median_us"


def main(argv: Sequence[str] | None = None) -> None:
    parser = benchmark_parser("estimator_speed", __doc__, "2000 samples instead of 20000", seed="noise seed")
    args = parser.parse_args(argv)
    figures = run(2000 if args.quick else 20000, args.seed)
    rows = [
        ("all", *(f"{figures[f'update_{stat}_us']:.1f}" for stat in ("median", "p99", "mean"))),
        *((name, f"{figures[_key(name)]:.1f}", "", "") for name in dict.fromkeys(PHASES)),
    ]
    print(f"Estimator.update latency, {figures['samples']} samples at {RATE:.0f} Hz, one core, from Python")
    print_table(rows, ("samples", "median µs", "p99 µs", "mean µs"))
    if args.json is not None:
        write_json(args.json, figures)


if __name__ == "__main__":
    main()
