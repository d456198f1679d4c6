"""Checks for constructor arguments.

A bad value raises ``ValueError`` naming the key and what is valid.
"""

from __future__ import annotations

import math
from collections.abc import Iterable, Sequence


def check_number(
    key: str,
    value: float,
    low: float = -math.inf,
    high: float = math.inf,
    *,
    low_open: bool = False,
    integer: bool = False,
) -> float:
    """Return ``value`` if it is a finite number in the range, else raise a ``ValueError``.

    ``low_open`` excludes ``low`` itself (for strictly positive quantities such as a timestep).
    """
    kind = "an integer" if integer else "a number"
    bracket = "(" if low_open else "["
    valid = f"{kind} in {bracket}{low}, {high}]"
    if isinstance(value, bool) or not isinstance(value, (int, float)):
        raise ValueError(f"{key}={value!r} is not valid: expected {valid}")
    if integer and not float(value).is_integer():
        raise ValueError(f"{key}={value!r} is not valid: expected {valid}")
    too_low = value <= low if low_open else value < low
    if not math.isfinite(value) or too_low or value > high:
        raise ValueError(f"{key}={value!r} is out of range: expected {valid}")
    return int(value) if integer else float(value)


def check_choice(key: str, value: str, choices: Iterable[str]) -> str:
    """Return ``value`` if it is one of ``choices``, else raise a ``ValueError`` listing them."""
    choices = tuple(choices)
    if value not in choices:
        raise ValueError(f"{key}={value!r} is not valid: choose one of {', '.join(choices)}")
    return value


def check_vector(
    key: str, value: Sequence[float], length: int, low: float, high: float
) -> tuple[float, ...]:
    """Return ``value`` as a tuple if it has ``length`` finite numbers in [low, high]."""
    try:
        items = tuple(value)
    except TypeError:
        items = ()
    if len(items) != length:
        raise ValueError(
            f"{key}={value!r} is not valid: expected {length} numbers in [{low}, {high}]"
        )
    return tuple(check_number(f"{key}[{i}]", v, low, high) for i, v in enumerate(items))
