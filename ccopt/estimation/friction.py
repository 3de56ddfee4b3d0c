"""Hand contact friction and torque limits (paper §IV-A, "Hand contact friction/torque constraints").

Every measured hand wrench ``(f_n, f_t, τ)`` (hand frame, see :mod:`ccopt.geometry`) lies inside the
hand friction cone ``|f_t| ≤ μ_h f_n``, so each sample with a clear contact force gives a lower bound

    μ_meas = max(|f_t| − δ, 0) / (f_n + ε)

on ``μ_h``. The paper uses ``δ = 0`` and ``ε > 0``; ``ε`` shrinks every ratio by ``f_n/(f_n + ε)``, a
relative bias of ``ε/f_n`` that stays even at high force, while ``δ`` (a tangential noise allowance,
N) cancels the upward bias that sensor noise gives the ratio at low force, which falls off like
``1/f_n`` as well. Both default to about the force noise. The streaming 0.99 quantile of ``μ_meas``
(P², robust to outliers) is the raw estimate, and the estimate used everywhere is

    μ_h = max(μ_prior, quantile)

so it never drops below the conservative prior (0.1 by default) and equals the prior until the
first sample. Lower is conservative: the estimated cone lies inside the true one, so sliding is
reported early and the controller keeps a margin. The hand cone is symmetric, so samples sliding
either way feed the same estimate.

The torque limits ``|τ| ≤ l_h f_n`` are known from the hand: the estimate uses ``l_h_eff = margin · l_h``
(a margin below 1 keeps the centre of pressure away from the hand's ends).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ccopt import contact
from ccopt.casadi_eval import BufferedFunction
from ccopt.estimation.quantile import P2Quantile, check_count, check_level, check_number

_hand_rows = BufferedFunction(contact.hand_rows)


@dataclass(frozen=True)
class HandFrictionParams:
    """Parameters of the hand friction and torque-limit estimate.

    Attributes:
        mu_prior: conservative initial value and floor of ``μ_h`` (dimensionless, > 0).
        epsilon: ``ε`` added to ``f_n`` in the ratio (N, ≥ 0).
        tangential_allowance: ``δ`` subtracted from ``|f_t|`` in the ratio (N, ≥ 0).
        min_normal_force: samples with ``f_n`` at or below this are ignored (N, > 0).
        level: quantile level of ``μ_meas`` taken as the estimate.
        min_samples: accepted samples before the friction rows count as estimated.
        torque_margin: ``l_h_eff / l_h`` in ``(0, 1]``.
    """

    mu_prior: float = 0.1
    epsilon: float = 0.3
    tangential_allowance: float = 0.3
    min_normal_force: float = 3.0
    level: float = 0.99
    min_samples: int = 100
    torque_margin: float = 0.85

    def __post_init__(self) -> None:
        check_number("mu_prior", self.mu_prior)
        check_number("epsilon", self.epsilon, low_open=False)
        check_number("tangential_allowance", self.tangential_allowance, low_open=False)
        check_number("min_normal_force", self.min_normal_force)
        check_level(self.level)
        check_count("min_samples", self.min_samples)
        check_number("torque_margin", self.torque_margin, 0.0, 1.0)


class HandFrictionEstimator:
    """Streaming estimate of ``μ_h`` and the hand torque limit (see the module docstring).

    Args:
        half_length: ``l_h``, half the length of the hand's contact face (m; the robot's
            :class:`~ccopt.hand.Hand`).
        params: estimator parameters.
    """

    def __init__(self, half_length: float, params: HandFrictionParams | None = None) -> None:
        check_number("half_length", half_length)
        self.half_length = float(half_length)
        self.params = params if params is not None else HandFrictionParams()
        self._quantile = P2Quantile(self.params.level)
        self._mu_h = self.params.mu_prior

    @property
    def mu_h(self) -> float:
        """Estimated hand friction coefficient, ``max(μ_prior, quantile)``."""
        return self._mu_h

    @property
    def l_h_eff(self) -> float:
        """Torque limit arm ``margin · l_h`` (m): ``|τ| ≤ l_h_eff f_n``."""
        return self.params.torque_margin * self.half_length

    @property
    def sample_count(self) -> int:
        """Samples accepted so far."""
        return self._quantile.count

    @property
    def valid(self) -> bool:
        """True once ``min_samples`` samples have been accepted."""
        return self._quantile.count >= self.params.min_samples

    def update(self, f_n: float, f_t: float) -> None:
        """Add one hand-frame force sample (N); ignored unless finite and ``f_n > min_normal_force``."""
        params = self.params
        if not (f_n > params.min_normal_force and math.isfinite(f_n) and math.isfinite(f_t)):
            return
        excess = abs(f_t) - params.tangential_allowance
        ratio = (0.0 if excess < 0.0 else excess) / (f_n + params.epsilon)  # max(excess, 0.0), written out
        quantile = self._quantile
        quantile.add(ratio)
        value, prior = quantile.value, params.mu_prior
        self._mu_h = value if value > prior else prior  # max(prior, value), written out

    def rows(self) -> tuple[np.ndarray, np.ndarray]:
        """Hand rows ``N w ≤ b`` (hand frame, ``N`` 4×3, ``b`` 4) from :data:`ccopt.contact.hand_rows`."""
        return _hand_rows(self._mu_h, self.l_h_eff)
