"""Random, realistic impedance-target QP instances, for tests, benchmarks and studies.

An instance is what the controller builds on a tick (docs/architecture.md §5): the generalized friction cone
of a plausible object (:func:`ccopt.contact.model_friction_cone`) plus normal-force limits, the
measured wrench near or inside that cone, one commanded motion's row removed, and tracking terms
along the admissible-motion vectors, with a regularisation 2–50 % of the tracking weights (as the
controller sets it). Steep tilts with low friction make a share of instances infeasible the way real
ones are: the hand's and the ground's friction cones do not intersect above the minimum push.
"""

from __future__ import annotations

import numpy as np

from ccopt import contact, modes
from ccopt.control.qp import MAX_ROWS, MAX_TERMS, QPInstance
from ccopt.hand import Hand

DEFAULT_STIFFNESS = Hand().stiffness_in_hand_frame(0.0)
"""The default hand's impedance in its own frame (docs/architecture.md §5), N/m, N/m, N·m/rad."""


def random_instance(rng: np.random.Generator, n_rows: int | None = None) -> QPInstance:
    """One realistic instance with ``n_rows`` (6–10, random if None) wrench rows."""
    n_rows = int(rng.integers(6, MAX_ROWS + 1)) if n_rows is None else n_rows
    if not 6 <= n_rows <= MAX_ROWS:
        raise ValueError(f"n_rows must be in [6, {MAX_ROWS}], got {n_rows}")
    theta = rng.uniform(-1.0, 1.0)
    mu_h, mu_g = rng.uniform(0.1, 0.8), rng.uniform(0.2, 1.0)
    l_h, mass = rng.uniform(0.035, 0.05), rng.uniform(0.2, 1.0)
    cone_n, cone_b = contact.model_friction_cone(theta, mu_h, mu_g, l_h, mass)
    f_max, f_min = rng.uniform(15.0, 30.0), rng.uniform(1.0, 4.0)
    extra_n = [[1.0, 0.0, 0.0], [-1.0, 0.0, 0.0]]
    extra_b = [f_max, -f_min]
    while len(extra_n) < n_rows - 6:  # spare rows: loose random half-planes
        direction = rng.normal(size=3)
        extra_n.append(direction / np.linalg.norm(direction))
        extra_b.append(rng.uniform(20.0, 60.0))
    rows = np.vstack([cone_n, np.reshape(extra_n[: n_rows - 6], (-1, 3))])
    bounds = np.concatenate([cone_b, extra_b[: n_rows - 6]])
    f_n = rng.uniform(2.0, 22.0)
    wrench = np.array([f_n, rng.uniform(-1.1, 1.1) * mu_h * f_n, rng.uniform(-1.1, 1.1) * 0.8 * l_h * f_n])
    motion = rng.choice(list(modes.Motion))
    active = np.ones(n_rows, dtype=bool)
    active[:6] = modes.kept_rows(motion)
    vectors = contact.admissible_motions(theta, rng.uniform(-0.05, 0.05), rng.uniform(0.03, 0.15))
    n_terms = int(rng.integers(1, MAX_TERMS + 1))
    directions = np.vstack([vectors.T, [[1.0, 0.0, 0.0]]])[:n_terms]
    weights = rng.uniform(1.0, 10.0, size=n_terms)
    targets = rng.normal(scale=0.01, size=n_terms)
    return QPInstance(
        stiffness=DEFAULT_STIFFNESS,
        wrench=wrench,
        rows=rows,
        bounds=bounds,
        gains=rng.uniform(0.5, 2.0, size=n_rows),
        active=active,
        regularization=rng.uniform(0.02, 0.5) * float(np.mean(weights)),
        directions=directions,
        weights=weights,
        targets=targets,
    )


def random_instances(seed: int, count: int) -> list[QPInstance]:
    """``count`` instances from a seeded generator."""
    rng = np.random.default_rng(seed)
    return [random_instance(rng) for _ in range(count)]
