"""The simulated clock's comparisons: a duration summed from timesteps counts as the interval it is
meant to be, and not a rounding error less."""

import numpy as np
import pytest

from ccopt.clock import TIME_TOLERANCE, interval_passed, lasted, latest_samples


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


def test_latest_samples_are_the_last_at_or_before_each_moment_within_rounding() -> None:
    """Against a scan: moments on the record's own (rounded) sample times pick that sample, moments
    between two samples the earlier, moments before the first the first. The record's times are
    sums of timesteps, and the moments products of a period: they differ by rounding (checked)."""
    times = np.cumsum(np.full(3000, 0.001)) - 0.001
    moments = 0.01 * np.arange(300)
    assert np.any(moments < times[::10][:300]), "no sample rounded past its moment: proves nothing"
    expected = [max(k for k, t in enumerate(times) if t <= m + 1e-6 * 0.001) for m in moments]
    assert latest_samples(times, moments).tolist() == expected
    assert latest_samples(times, np.array([-1.0, 0.0005, 99.0])).tolist() == [0, 0, len(times) - 1]
