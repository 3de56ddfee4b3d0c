"""Times on the simulated clock, and how they are compared.

A sample's time is a sum of plant timesteps, so two times meant to be one instant (or a duration
meant to equal an interval) differ by rounding. Every comparison of a time or a duration with a
bound allows :data:`TIME_TOLERANCE`; this module is the one place that says so.
"""

from __future__ import annotations

import numpy as np

TIME_TOLERANCE = 1e-9
"""s: times this close are one instant (the rounding of sums of timesteps is far below it)."""


def lasted(now: float, since: float, duration: float) -> bool:
    """Whether ``duration`` has passed from ``since`` to ``now`` (s), within rounding."""
    return now - since >= duration - TIME_TOLERANCE


def interval_passed(time: float, last: float, interval: float) -> bool:
    """Whether ``interval`` (s) has passed from ``last`` to ``time`` (within rounding), or time went
    back (a new recording): when a streaming estimate takes its next sample."""
    return time - last >= interval - TIME_TOLERANCE or time < last


def latest_samples(times: np.ndarray, moments: np.ndarray) -> np.ndarray:
    """The index of the last of the increasing sample ``times`` at or before each of ``moments``
    (s, within rounding; the first sample for a moment before it)."""
    found = np.searchsorted(times, np.asarray(moments) + TIME_TOLERANCE, side="right") - 1
    return np.clip(found, 0, len(times) - 1)
