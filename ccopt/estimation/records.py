"""The estimator's per-sample frozen dataclasses, made at the cost of one dict.

:func:`ccopt.validation.trusted` makes an instance without its ``__init__`` and checks that the
fields given are every field, by their key set: 0.3-0.5 µs for the estimate's 34 fields, more than
making the instance itself (replaying a smoke run, about 1 µs a sample over the estimate, the
kinematics' estimate and the ground cone). These are made from dict literals that name every
field, so the check cannot fail at run time; :func:`record` leaves it out
(``tests/test_estimation_records.py`` holds the literals to their dataclasses instead). Only for
such literals: anywhere else, :func:`~ccopt.validation.trusted`.
"""

from __future__ import annotations

from typing import TypeVar

T = TypeVar("T")

_new = object.__new__
_set = object.__setattr__


def record(kind: type[T], fields: dict[str, object]) -> T:
    """An instance of the frozen dataclass ``kind`` whose ``__dict__`` is ``fields`` (every field,
    by name; not checked, not copied: the caller gives it up)."""
    instance = _new(kind)
    _set(instance, "__dict__", fields)
    return instance
