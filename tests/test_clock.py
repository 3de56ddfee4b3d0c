"""The simulated clock's comparisons: a duration summed from timesteps counts as the interval it is
meant to be, and not a rounding error less."""

import numpy as np
import pytest

from ccopt.clock import TIME_TOLERANCE, interval_passed, lasted


@pytest.mark.parametrize("timestep", [0.001, 0.002, 1.0 / 3.0e3])
def test_a_sum_of_timesteps_lasts_the_interval_it_makes(timestep: float) -> None:
    """Ten steps summed one at a time fall short of ``10 · timestep`` by rounding (checked), and
    still count as having lasted it; nine steps do not."""
    sums = np.cumsum(np.full(10_000, timestep))
    short = [k for k in range(10, len(sums)) if sums[k] - sums[k - 10] < 10 * timestep]
    assert short, "rounding never made a ten-step sum short: the test would prove nothing"
    for k in short:
        assert lasted(float(sums[k]), float(sums[k - 10]), 10 * timestep)
        assert not lasted(float(sums[k - 1]), float(sums[k - 10]), 10 * timestep)


def test_interval_passed_also_when_time_went_back() -> None:
    """A new recording starts its clock again: the next sample is taken at once."""
    assert interval_passed(0.0, 5.0, 0.004)
    assert interval_passed(5.004, 5.0, 0.004)
    assert not interval_passed(5.003, 5.0, 0.004)
    assert not interval_passed(5.0 + 0.004 - 10 * TIME_TOLERANCE, 5.0, 0.004)
