"""Checks at ccopt's boundaries (constructors, the CLI, the API): one clear line naming the bad value.

Every check raises ``TypeError`` for a value of the wrong type and ``ValueError`` for one out of range,
with the parameter's name and the value in the message. They run where parameters enter ccopt, never
per tick in a hot loop; there, :func:`trusted` makes the objects whose values need no checks.
"""

from __future__ import annotations

import dataclasses
import functools
import math
import sys
from collections.abc import Iterable
from numbers import Real
from typing import TypeVar

import numpy as np

T = TypeVar("T")


def short(value: object, limit: int = 40) -> str:
    """``repr(value)``, cut to ``limit`` characters (a 5,000-digit number named in one line)."""
    text = repr(value)
    return text if len(text) <= limit else f"{text[: limit - 12]}... ({len(text)} characters)"


def parse_reason(error: Exception) -> str:
    """Why a JSON or YAML parser refused a file, in one line and in a user's words: Python's own
    limit on the digits of an integer is named, not its advice to raise it."""
    text = str(error)
    if "integer string conversion" in text:
        return f"a number of over {sys.get_int_max_str_digits()} digits"
    return text.splitlines()[0] if text else type(error).__name__


def as_float(name: str, value: Real) -> float:
    """``float(value)``; ``ValueError`` naming ``name`` for an integer beyond the largest float
    (a settings file may hold ``10**400``, which ``float`` refuses with ``OverflowError``)."""
    try:
        return float(value)
    except OverflowError:
        raise ValueError(f"{name} must be finite, got an integer beyond 1.8e308: {short(value)}") from None


def real(name: str, value: object) -> float:
    """``value`` as a finite float: ``TypeError`` unless a real number (not a bool), ``ValueError`` unless
    finite."""
    if isinstance(value, bool) or not isinstance(value, Real):
        raise TypeError(f"{name} must be a real number, got {type(value).__name__} {short(value)}")
    number = as_float(name, value)
    if not math.isfinite(number):
        raise ValueError(f"{name} must be finite, got {number!r}")
    return number


def positive(name: str, value: object) -> float:
    """``value`` as a finite float ``> 0`` (see :func:`real`)."""
    number = real(name, value)
    if number <= 0.0:
        raise ValueError(f"{name} must be positive, got {number!r}")
    return number


def reals(name: str, value: object, count: int) -> tuple[float, ...]:
    """``value`` as ``count`` finite floats (see :func:`real`; the items are named ``name[i]``)."""
    if isinstance(value, str) or np.ndim(value) != 1 or len(value) != count:
        raise ValueError(f"{name} must be {count} numbers, got {short(value)}")
    return tuple(real(f"{name}[{i}]", item) for i, item in enumerate(value))


def check_number(
    name: str, value: object, low: float = 0.0, high: float = math.inf, *, low_open: bool = True
) -> float:
    """``value`` as a float in ``(low, high]`` (``[low, high]`` if not ``low_open``); ``TypeError``
    unless a real number, ``ValueError`` unless finite and in range, naming ``name`` and the value."""
    if isinstance(value, bool) or not isinstance(value, Real):
        raise TypeError(f"{name} must be a real number, got {short(value)}")
    number = as_float(name, value)
    above_low = number > low if low_open else number >= low
    if not (above_low and number <= high and math.isfinite(number)):
        bracket = "(" if low_open else "["
        raise ValueError(f"{name} must be in {bracket}{low:g}, {high:g}], got {short(value)}")
    return number


def check_count(name: str, value: object, low: int = 1) -> int:
    """``value`` as an int ``≥ low``; ``TypeError``/``ValueError`` naming ``name`` and the value."""
    if isinstance(value, bool) or not isinstance(value, int | np.integer):
        raise TypeError(f"{name} must be an integer, got {short(value)}")
    if value < low:
        raise ValueError(f"{name} must be an integer ≥ {low}, got {short(value)}")
    return int(value)


def check_types(parts: Iterable[tuple[str, object, type]]) -> None:
    """``TypeError`` naming the first ``(name, value, kind)`` whose value is not a ``kind``."""
    for name, value, kind in parts:
        if not isinstance(value, kind):
            raise TypeError(f"{name} must be a {kind.__name__}, got {type(value).__name__} {value!r}")


def trusted(kind: type[T], fields: dict[str, object]) -> T:
    """An instance of the dataclass ``kind`` holding ``fields`` (every field, by name) without calling
    its ``__init__``: no defaults, no ``__post_init__``, no checks. For the few objects a hot path
    makes every tick from values that are well formed by construction (a frozen dataclass's
    ``__init__`` sets each field through ``object.__setattr__``: 8 µs for the estimator's 31 fields,
    0.6 µs this way). The instance equals, compares, copies and pickles like one made by ``kind(...)``.
    """
    if fields.keys() != _field_names(kind):
        expected = sorted(_field_names(kind))
        raise TypeError(f"{kind.__name__} needs the fields {expected}, got {sorted(fields)}")
    instance = object.__new__(kind)
    instance.__dict__.update(fields)
    return instance


@functools.cache
def _field_names(kind: type) -> frozenset[str]:
    return frozenset(field.name for field in dataclasses.fields(kind))
