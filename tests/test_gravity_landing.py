"""The gravity moment estimate in closed loop, through a pivot that lays the object on a face.

The paper pentagon pivoted down from 17° lands on its face at about −36° (a second vertex touches the
ground) and is pivoted back. While it lies on the face, the second ground contact's force adds a moment
that no point ground contact explains: taken in, those samples put ``M̂`` 0.6 N·m off, with the wrong
sign, for the rest of the run (measured before the gate of :mod:`ccopt.estimation.gravity`). The truth
is the object's model (:func:`ccopt.statics.true_statics`).
"""

from __future__ import annotations

import math

import numpy as np

from ccopt import closed_loop, statics
from ccopt.objects import make_object
from ccopt.schedule import Schedule, hold, pivot

LANDING = math.radians(-36.0)
"""Below this true ``θ_o`` the pentagon lies on its face."""
MOMENT_LIMIT = 0.03
"""N·m: the moment reaches 0.11 N·m over the angles visited."""


def test_samples_of_the_object_lying_on_a_face_leave_the_moment_estimate_alone():
    obj, params = make_object("paper-pentagon"), closed_loop.LoopParams(plant="planar")
    schedule = Schedule("landing", (hold(0.3), *[pivot(-7.2)] * 8, *[pivot(7.2)] * 5, hold(0.3)))
    result = closed_loop.run(obj, schedule, params, seed=0)
    true_theta = result.samples["true_coordinates"][:, 0]
    assert result.status == "completed" and true_theta.min() < LANDING  # it did land on the face
    truth = statics.true_statics(obj, closed_loop.start_config(obj, params), params.hand).statics
    estimate = result.last_usable.gravity
    assert estimate.valid
    for theta in np.radians(np.linspace(-35.0, 15.0, 11)):
        assert abs(estimate.moment(theta) - truth.gravity(theta)) < MOMENT_LIMIT, math.degrees(theta)
