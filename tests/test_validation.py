"""validation.trusted: the hot paths' objects made without __init__ equal those made with it."""

import copy
import pickle

import numpy as np
import pytest

from ccopt import validation
from ccopt.control.qp import QPSolution


def fields_of_a_solution() -> dict[str, object]:
    return {
        "step": np.array([1e-3, -2e-3, 0.01]),
        "wrench_change": np.zeros(3),
        "slack": 0.0,
        "feasible": True,
        "backend": "codegen",
    }


def test_a_trusted_instance_equals_copies_and_pickles_like_one_made_by_init():
    fields = fields_of_a_solution()
    made = QPSolution(**fields)
    trusted = validation.trusted(QPSolution, fields)
    assert type(trusted) is QPSolution
    for other in (trusted, copy.deepcopy(trusted), pickle.loads(pickle.dumps(trusted))):
        assert other.step.tolist() == made.step.tolist()
        assert (other.slack, other.feasible, other.backend) == (made.slack, made.feasible, made.backend)
    with pytest.raises(AttributeError):  # still frozen
        trusted.slack = 1.0


@pytest.mark.parametrize("change", ["missing", "extra", "misspelt"])
def test_a_trusted_instance_needs_exactly_its_fields(change):
    fields = fields_of_a_solution()
    if change == "missing":
        del fields["backend"]
    elif change == "extra":
        fields["speed"] = 1.0
    else:
        fields["backends"] = fields.pop("backend")
    with pytest.raises(TypeError, match="QPSolution needs the fields"):
        validation.trusted(QPSolution, fields)
