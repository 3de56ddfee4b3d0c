"""Real-time factor of the simulated plants with the sensors on and a 1 kHz Python callback.

    python -m benchmarks.plant_speed [--quick] [--json PATH]

Each plant starts with the paper square under the hand; every simulated millisecond a callback reads
the sensors and sets the impedance target (a slow ±2 mm sweep along the face), as the closed loop
does. The real-time factor is simulated time over wall time, one core, construction and settling
excluded; the best RTF is that of the fastest chunk of 250 steps (the speed without contention from
other processes). ``--json`` writes ``{"planar_rtf": ..., "panda_rtf": ...}`` and the details
(``null`` for a plant that is not available, with a note).
"""

from __future__ import annotations

import importlib
import math
import time
from collections.abc import Sequence

import numpy as np

from ccopt import geometry
from ccopt.cliutil import benchmark_parser, print_table, write_json
from ccopt.objects import make_object
from ccopt.plant.base import Plant, StartConfig
from ccopt.plant.mujoco_planar import PlanarPlant
from ccopt.plant.sensors import Sensors

START = StartConfig(hand_face=0, theta_o=math.radians(5.0), s_h=-0.05, normal_force=5.0)
SWEEP_AMPLITUDE = 2e-3
"""Amplitude of the target sweep along the face, m."""
SWEEP_PERIOD = 2.0
"""Period of the target sweep, s."""
CHUNK = 250
"""Steps timed together; the best chunk shows the speed without contention from other processes."""


def run_loop(plant: Plant, seconds: float, seed: int = 0) -> np.ndarray:
    """Simulate ``seconds`` with a sensor read and a target update every step.

    Returns the wall time (s) of each chunk of :data:`CHUNK` steps.
    """
    sensors = Sensors(plant, seed=seed)
    centre = plant.target()
    along = np.array([*geometry.hand_tangent(centre[2]), 0.0])
    omega = 2.0 * math.pi / SWEEP_PERIOD
    chunks = max(1, round(seconds / plant.timestep / CHUNK))
    walls = np.empty(chunks)
    for chunk in range(chunks):
        start = time.perf_counter()
        for _ in range(CHUNK):
            sensors.read()
            phase = omega * plant.time
            plant.set_target(
                centre + SWEEP_AMPLITUDE * math.sin(phase) * along,
                SWEEP_AMPLITUDE * omega * math.cos(phase) * along,
            )
            plant.step()
        walls[chunk] = time.perf_counter() - start
    return walls


def panda_class() -> type | None:
    """``ccopt.plant.mujoco_panda.PandaPlant``, or ``None`` if that module does not exist yet."""
    try:
        module = importlib.import_module("ccopt.plant.mujoco_panda")
    except ModuleNotFoundError as error:
        if error.name != "ccopt.plant.mujoco_panda":
            raise
        return None
    return module.PandaPlant


def run(seconds: float) -> tuple[dict[str, float | str | None], list[tuple[str, ...]]]:
    """Figures and table rows for both plants."""
    obj = make_object("paper-square")
    figures: dict[str, float | str | None] = {"simulated_seconds": seconds}
    rows = []
    for name, factory in (("planar", PlanarPlant), ("panda", panda_class())):
        if factory is None:
            figures[f"{name}_rtf"] = None
            figures[f"{name}_note"] = "ccopt.plant.mujoco_panda does not exist yet"
            rows.append((name, "-", "-", "-", "-", "-", "not available"))
            continue
        built = time.perf_counter()
        plant = factory(obj, start=START)
        build = time.perf_counter() - built
        walls = run_loop(plant, seconds)
        chunk_seconds = CHUNK * plant.timestep
        figures[f"{name}_rtf"] = chunk_seconds * len(walls) / walls.sum()
        figures[f"{name}_rtf_best"] = chunk_seconds / walls.min()
        figures[f"{name}_step_us"] = walls.sum() / (CHUNK * len(walls)) * 1e6
        figures[f"{name}_build_s"] = build
        rows.append(
            (
                name,
                f"{chunk_seconds * len(walls):.1f}",
                f"{walls.sum():.2f}",
                f"{figures[f'{name}_rtf']:.1f}x",
                f"{figures[f'{name}_rtf_best']:.1f}x",
                f"{figures[f'{name}_step_us']:.1f}",
                f"{build:.2f}",
            )
        )
    return figures, rows


def main(argv: Sequence[str] | None = None) -> None:
    parser = benchmark_parser("plant_speed", __doc__, "2 simulated seconds per plant instead of 10")
    args = parser.parse_args(argv)
    figures, rows = run(2.0 if args.quick else 10.0)
    print("Plant speed: sensors + 1 kHz target callback, one core (real-time factor = sim s / wall s)")
    print_table(rows, ("plant", "sim s", "wall s", "RTF", "best RTF", "µs/step", "build+settle s"))
    if args.json is not None:
        write_json(args.json, figures)


if __name__ == "__main__":
    main()
